/* test/support/check_surface.h: checks of triangle surfaces that do not use
 * the library's own code: closed, manifold, consistently oriented (every
 * directed edge once, with its twin) and the Euler characteristic; the
 * enclosed volume by the divergence theorem. */
#ifndef VM_TEST_CHECK_SURFACE_H
#define VM_TEST_CHECK_SURFACE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "varmesh/mesh.h"

static int chk_cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* closed, manifold, consistently oriented; *chi = V - E + F */
static inline int chk_closed_euler(const vm_mesh *m, int64_t *chi) {
  int64_t n = 3 * m->ne;
  uint64_t *k = malloc((size_t)(n > 0 ? n : 1) * sizeof *k),
           *t = malloc((size_t)(n > 0 ? n : 1) * sizeof *t);
  for (int64_t e = 0; e < m->ne; e++)
    for (int i = 0; i < 3; i++) {
      uint32_t a = (uint32_t)m->conn[3 * e + i], b = (uint32_t)m->conn[3 * e + (i + 1) % 3];
      k[3 * e + i] = (uint64_t)a << 32 | b;
      t[3 * e + i] = (uint64_t)b << 32 | a;
    }
  qsort(k, (size_t)n, sizeof *k, chk_cmp_u64);
  qsort(t, (size_t)n, sizeof *t, chk_cmp_u64);
  int ok = 1;
  for (int64_t i = 0; i < n; i++) {
    if (i > 0 && k[i] == k[i - 1]) ok = 0;
    if (k[i] != t[i]) ok = 0;
  }
  *chi = m->nv - n / 2 + m->ne;
  free(k);
  free(t);
  return ok;
}

/* the volume a closed triangle surface encloses (outward: positive) */
static inline double chk_volume(const vm_mesh *m) {
  double v = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e],
                 *b = m->xyz + 3 * (int64_t)m->conn[3 * e + 1],
                 *c = m->xyz + 3 * (int64_t)m->conn[3 * e + 2];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) /
         6;
  }
  return v;
}

/* Two tetrahedra sharing vertex 0: every edge manifold, vertex 0 not (its
 * triangles form two fans). 7 vertices, 8 triangles. */
static inline void chk_bowtie(vm_mesh *m) {
  static const double x[7][3] = {{0, 0, 0},  {1, 0, 0},  {0, 1, 0}, {0, 0, 1},
                                 {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  static const int32_t t[8][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},
                                  {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
  vm_mesh_set_vertices(m, 7);
  for (int v = 0; v < 7; v++)
    for (int r = 0; r < 3; r++) m->xyz[3 * v + r] = x[v][r];
  for (int i = 0; i < 8; i++) vm_mesh_add_element(m, VM_TRI, t[i]);
}

/* The surface of the unit cube as an n x n grid of squares per face, each
 * split into two triangles, oriented outwards: lattice vertex (i, j, k)
 * (on the surface) at (x(i), x(j), x(k)), x(i) = (i / n)^pw, vid[(i (n +
 * 1) + j) (n + 1) + k] its index (-1 inside; vid has (n + 1)^3 entries).
 * NULL on failure. */
static inline vm_mesh *chk_grid_cube(vm_ctx *ctx, int n, double pw, int32_t *vid) {
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m)) return NULL;
  const int n1 = n + 1;
  int64_t nv = 0;
  for (int i = 0; i <= n; i++)
    for (int j = 0; j <= n; j++)
      for (int k = 0; k <= n; k++) {
        int surf = i == 0 || j == 0 || k == 0 || i == n || j == n || k == n;
        vid[(i * n1 + j) * n1 + k] = surf ? (int32_t)nv++ : -1;
      }
  if (vm_mesh_set_vertices(m, nv)) {
    vm_mesh_destroy(&m);
    return NULL;
  }
  for (int i = 0; i <= n; i++)
    for (int j = 0; j <= n; j++)
      for (int k = 0; k <= n; k++) {
        int32_t v = vid[(i * n1 + j) * n1 + k];
        if (v < 0) continue;
        const int ijk[3] = {i, j, k};
        for (int r = 0; r < 3; r++)
          m->xyz[3 * (int64_t)v + r] = ijk[r] == n ? 1 : pow((double)ijk[r] / n, pw);
      }
  /* origin, u, v (in units of n) with u x v the outward normal */
  static const int fo[6][3] = {{0, 0, 0}, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}};
  static const int fu[6][3] = {{0, 1, 0}, {1, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 0, 1}, {0, 1, 0}};
  static const int fv[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int s = 0; s < 6; s++)
    for (int a = 0; a < n; a++)
      for (int b = 0; b < n; b++) {
        int32_t q[4];
        for (int c = 0; c < 4; c++) {
          int da = c == 1 || c == 2, db = c >= 2;
          int p[3];
          for (int r = 0; r < 3; r++)
            p[r] = n * fo[s][r] + (a + da) * fu[s][r] + (b + db) * fv[s][r];
          q[c] = vid[(p[0] * n1 + p[1]) * n1 + p[2]];
        }
        int32_t t0[3] = {q[0], q[1], q[2]}, t1[3] = {q[0], q[2], q[3]};
        vm_mesh_add_element(m, VM_TRI, t0);
        vm_mesh_add_element(m, VM_TRI, t1);
      }
  return m;
}

#endif
