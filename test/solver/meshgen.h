/* test/solver/meshgen.h: small generated meshes for the solver tests and
 * benchmark: structured hex/tet cubes, a tet ball, quad/triangle squares,
 * boundary marking and seeded jitter. */
#ifndef VM_TEST_MESHGEN_H
#define VM_TEST_MESHGEN_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/mesh.h"

/* Unit cube [0,1]^3 with n^3 hexahedra. tets = 1: 6 Kuhn tets per cell
 * along the main diagonal; tets = 2: the same with each cell's diagonal
 * starting at its corner nearest the cube's centre (mirror-symmetric, so
 * every tet has a vertex off the boundary; n even). */
static inline int gen_cube(vm_ctx *ctx, int n, int tets, vm_mesh **out) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  int n1 = n + 1;
  st = vm_mesh_set_vertices(m, (int64_t)n1 * n1 * n1);
  if (st) goto fail;
  for (int k = 0; k < n1; k++)
    for (int j = 0; j < n1; j++)
      for (int i = 0; i < n1; i++) {
        double *p = m->xyz + 3 * (i + (int64_t)n1 * (j + (int64_t)n1 * k));
        p[0] = (double)i / n;
        p[1] = (double)j / n;
        p[2] = (double)k / n;
      }
  for (int k = 0; k < n; k++)
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        int32_t c[8];
        for (int a = 0; a < 8; a++) {
          static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                        {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
          c[a] = (int32_t)((i + off[a][0]) + n1 * ((j + off[a][1]) + n1 * (k + off[a][2])));
        }
        if (!tets) {
          st = vm_mesh_add_element(m, VM_HEX, c);
          if (st) goto fail;
          continue;
        }
        static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                       {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        int32_t base = c[0];
        int32_t step[3] = {1, n1, n1 * n1};
        if (tets == 2) {
          int ijk[3] = {i, j, k};
          for (int ax = 0; ax < 3; ax++)
            if (2 * ijk[ax] >= n) {
              base += step[ax];
              step[ax] = -step[ax];
            }
        }
        for (int t = 0; t < 6; t++) {
          int32_t v[4];
          int32_t cur = base;
          v[0] = cur;
          for (int s = 0; s < 3; s++) {
            cur += step[perm[t][s]];
            v[s + 1] = cur;
          }
          const double *p0 = m->xyz + 3 * v[0], *p1 = m->xyz + 3 * v[1], *p2 = m->xyz + 3 * v[2],
                       *p3 = m->xyz + 3 * v[3];
          double a[3], b[3], cc[3];
          for (int r = 0; r < 3; r++) {
            a[r] = p1[r] - p0[r];
            b[r] = p2[r] - p0[r];
            cc[r] = p3[r] - p0[r];
          }
          double det = a[0] * (b[1] * cc[2] - b[2] * cc[1]) - a[1] * (b[0] * cc[2] - b[2] * cc[0]) +
                       a[2] * (b[0] * cc[1] - b[1] * cc[0]);
          if (det < 0) {
            int32_t tmp = v[1];
            v[1] = v[2];
            v[2] = tmp;
          }
          st = vm_mesh_add_element(m, VM_TET, v);
          if (st) goto fail;
        }
      }
  *out = m;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

/* Unit square [0,1]^2 (dim 2) with n^2 quads (tris: 2 per cell). */
static inline int gen_square(vm_ctx *ctx, int n, int tris, vm_mesh **out) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  m->dim = 2;
  int n1 = n + 1;
  st = vm_mesh_set_vertices(m, (int64_t)n1 * n1);
  if (st) goto fail;
  for (int j = 0; j < n1; j++)
    for (int i = 0; i < n1; i++) {
      double *p = m->xyz + 3 * (i + (int64_t)n1 * j);
      p[0] = (double)i / n;
      p[1] = (double)j / n;
      p[2] = 0;
    }
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      int32_t c[4] = {i + n1 * j, i + 1 + n1 * j, i + 1 + n1 * (j + 1), i + n1 * (j + 1)};
      if (!tris) {
        st = vm_mesh_add_element(m, VM_QUAD, c);
      } else {
        int32_t t0[3] = {c[0], c[1], c[2]}, t1[3] = {c[0], c[2], c[3]};
        st = vm_mesh_add_element(m, VM_TRI, t0);
        if (!st) st = vm_mesh_add_element(m, VM_TRI, t1);
      }
      if (st) goto fail;
    }
  *out = m;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

/* Is vertex coordinate p on the boundary of [0,1]^dim? */
static inline int on_unit_boundary(const double *p, int dim) {
  for (int k = 0; k < dim; k++)
    if (p[k] == 0.0 || p[k] == 1.0) return 1;
  return 0;
}

/* Mark the boundary vertices of the unit cube/square with `flag`. */
static inline void mark_boundary(vm_mesh *m, int flag, int surf) {
  int dim = m->dim == 2 ? 2 : 3;
  for (int64_t v = 0; v < m->nv; v++)
    if (on_unit_boundary(m->xyz + 3 * v, dim)) {
      m->vflag[v] = (uint8_t)flag;
      m->vsurf[v] = surf;
    }
}

/* Displace every FREE vertex by a uniform random vector of size <= amp per
 * coordinate (xy only for dim 2), from the context's seeded generator. */
static inline void jitter_free(vm_ctx *ctx, vm_mesh *m, double amp, uint64_t seed) {
  vm_ctx_seed(ctx, seed);
  int dim = m->dim == 2 ? 2 : 3;
  for (int64_t v = 0; v < m->nv; v++) {
    double r[3];
    for (int k = 0; k < 3; k++) r[k] = (2 * vm_ctx_rand_unit(ctx) - 1) * amp;
    if (m->vflag[v] != VM_VERTEX_FREE) continue;
    for (int k = 0; k < dim; k++) m->xyz[3 * v + k] += r[k];
  }
}

/* A tet ball of radius R: the mirrored Kuhn tet cube [-1,1]^3 (n cells a side, even)
 * mapped radially, x -> R x |x|_inf / |x|_2; boundary vertices SLIP on
 * surface `surf`. */
static inline int gen_ball(vm_ctx *ctx, int n, double R, int surf, vm_mesh **out) {
  int st = gen_cube(ctx, n, 2, out);
  if (st) return st;
  vm_mesh *m = *out;
  for (int64_t v = 0; v < m->nv; v++) {
    double *p = m->xyz + 3 * v;
    int bnd = on_unit_boundary(p, 3);
    double q[3], inf = 0, two = 0;
    for (int k = 0; k < 3; k++) {
      q[k] = 2 * p[k] - 1;
      if (fabs(q[k]) > inf) inf = fabs(q[k]);
      two += q[k] * q[k];
    }
    two = sqrt(two);
    for (int k = 0; k < 3; k++) p[k] = two > 0 ? R * q[k] * inf / two : 0;
    if (bnd) {
      m->vflag[v] = VM_VERTEX_SLIP;
      m->vsurf[v] = surf;
    }
  }
  return VM_OK;
}

#endif
