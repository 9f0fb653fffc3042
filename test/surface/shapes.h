/* test/surface/shapes.h: generated surfaces with known curvature for the
 * surface tests and benchmarks: torus, icosphere, open cylinder, and a
 * closed "roof" shape with a sharp ridge. Header-only (static functions). */
#ifndef VARMESH_TEST_SHAPES_H
#define VARMESH_TEST_SHAPES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/mesh.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* A small deterministic generator for jitter (splitmix64). */
static inline double shp_rand(uint64_t *s) {
  uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}

/* Torus with major radius R, minor r: nu vertices around the axis (angle
 * u), nvv around the tube (angle v); point (R + r cos v) (cos u, sin u),
 * r sin v; outward normal. quads != 0: quad elements, else each cell split
 * along one diagonal (alternate != 0: diagonals alternate in a
 * checkerboard). jitter: each vertex moved by up to jitter * (grid step)
 * in u and v (random, uniform), staying on the torus. Exact H at vertex i
 * in Hex[i] (may be NULL): (R + 2 r cos v) / (2 r (R + r cos v)). */
static inline int shp_torus(vm_ctx *ctx, double R, double r, int nu, int nvv, int quads,
                            int alternate, double jitter, uint64_t seed, vm_mesh **out,
                            double **Hex) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  if ((st = vm_mesh_set_vertices(m, (int64_t)nu * nvv))) goto fail;
  double *H = Hex ? malloc(sizeof *H * (size_t)nu * nvv) : NULL;
  uint64_t s = seed;
  for (int i = 0; i < nu; i++)
    for (int j = 0; j < nvv; j++) {
      double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nvv;
      if (jitter > 0) {
        u += jitter * 2 * M_PI / nu * (2 * shp_rand(&s) - 1);
        v += jitter * 2 * M_PI / nvv * (2 * shp_rand(&s) - 1);
      }
      double *p = m->xyz + 3 * ((int64_t)i * nvv + j);
      p[0] = (R + r * cos(v)) * cos(u);
      p[1] = (R + r * cos(v)) * sin(u);
      p[2] = r * sin(v);
      if (H) H[i * nvv + j] = (R + 2 * r * cos(v)) / (2 * r * (R + r * cos(v)));
    }
  for (int i = 0; i < nu; i++)
    for (int j = 0; j < nvv; j++) {
      int32_t a = i * nvv + j, b = ((i + 1) % nu) * nvv + j, c = ((i + 1) % nu) * nvv + (j + 1) % nvv,
              d = i * nvv + (j + 1) % nvv;
      /* (a, b, c, d) is counter-clockwise seen from outside: d_u x d_v is outward */
      if (quads) {
        int32_t q[4] = {a, b, c, d};
        if ((st = vm_mesh_add_element(m, VM_QUAD, q))) goto fail;
      } else if (alternate && (i + j) % 2) {
        int32_t t1[3] = {a, b, d}, t2[3] = {b, c, d};
        if ((st = vm_mesh_add_element(m, VM_TRI, t1)) || (st = vm_mesh_add_element(m, VM_TRI, t2)))
          goto fail;
      } else {
        int32_t t1[3] = {a, b, c}, t2[3] = {a, c, d};
        if ((st = vm_mesh_add_element(m, VM_TRI, t1)) || (st = vm_mesh_add_element(m, VM_TRI, t2)))
          goto fail;
      }
    }
  *out = m;
  if (Hex) *Hex = H;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

/* Open cylinder of radius r and height h (z from 0 to h): na vertices
 * around, nz rows; outward normal; H = 1/(2r). */
static inline int shp_cylinder(vm_ctx *ctx, double r, double h, int na, int nz, double jitter,
                               uint64_t seed, vm_mesh **out) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  if ((st = vm_mesh_set_vertices(m, (int64_t)na * nz))) goto fail;
  uint64_t s = seed;
  for (int k = 0; k < nz; k++)
    for (int i = 0; i < na; i++) {
      double u = 2 * M_PI * i / na, z = h * k / (nz - 1);
      if (jitter > 0 && k > 0 && k < nz - 1) {
        u += jitter * 2 * M_PI / na * (2 * shp_rand(&s) - 1);
        z += jitter * h / (nz - 1) * (2 * shp_rand(&s) - 1);
      }
      double *p = m->xyz + 3 * ((int64_t)k * na + i);
      p[0] = r * cos(u);
      p[1] = r * sin(u);
      p[2] = z;
    }
  for (int k = 0; k + 1 < nz; k++)
    for (int i = 0; i < na; i++) {
      int32_t a = k * na + i, b = k * na + (i + 1) % na, c = (k + 1) * na + (i + 1) % na,
              d = (k + 1) * na + i;
      int32_t t1[3] = {a, b, c}, t2[3] = {a, c, d};
      if ((st = vm_mesh_add_element(m, VM_TRI, t1)) || (st = vm_mesh_add_element(m, VM_TRI, t2)))
        goto fail;
    }
  *out = m;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

/* Midpoint lookup for the icosphere: edge (a, b) -> new vertex. */
typedef struct {
  int64_t *key;
  int32_t *val;
  int64_t cap;
} shp_edge_map;

static inline int32_t shp_midpoint(vm_mesh *m, shp_edge_map *em, int32_t a, int32_t b,
                                   double radius) {
  int64_t lo = a < b ? a : b, hi = a < b ? b : a;
  int64_t key = lo * 0x100000000ll + hi;
  uint64_t h = (uint64_t)key * 0x9e3779b97f4a7c15ull;
  int64_t i = (int64_t)(h % (uint64_t)em->cap);
  while (em->key[i] != -1) {
    if (em->key[i] == key) return em->val[i];
    i = (i + 1) % em->cap;
  }
  double p[3];
  for (int k = 0; k < 3; k++) p[k] = 0.5 * (m->xyz[3 * a + k] + m->xyz[3 * b + k]);
  double l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  int64_t idx;
  if (vm_mesh_add_vertex(m, radius * p[0] / l, radius * p[1] / l, radius * p[2] / l, &idx))
    return -1;
  em->key[i] = key;
  em->val[i] = (int32_t)idx;
  return (int32_t)idx;
}

/* Icosphere of radius `radius`: the icosahedron subdivided `level` times,
 * new vertices projected onto the sphere; outward orientation; H = 1/R.
 * jitter: every vertex moved tangentially by up to jitter * (mean edge
 * length) and put back on the sphere. */
static inline int shp_icosphere(vm_ctx *ctx, double radius, int level, double jitter,
                                uint64_t seed, vm_mesh **out) {
  const double t = (1.0 + sqrt(5.0)) / 2.0;
  const double V[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  const int32_t F[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  for (int i = 0; i < 12; i++) {
    double l = sqrt(V[i][0] * V[i][0] + V[i][1] * V[i][1] + V[i][2] * V[i][2]);
    if ((st = vm_mesh_add_vertex(m, radius * V[i][0] / l, radius * V[i][1] / l,
                                 radius * V[i][2] / l, NULL)))
      goto fail;
  }
  int64_t nt = 20;
  int32_t *tri = malloc(sizeof *tri * 3 * 20);
  memcpy(tri, F, sizeof F);
  for (int lv = 0; lv < level; lv++) {
    shp_edge_map em;
    em.cap = 4 * 3 * nt + 17;
    em.key = malloc(sizeof *em.key * (size_t)em.cap);
    em.val = malloc(sizeof *em.val * (size_t)em.cap);
    for (int64_t i = 0; i < em.cap; i++) em.key[i] = -1;
    int32_t *nt4 = malloc(sizeof *nt4 * 12 * (size_t)nt);
    for (int64_t f = 0; f < nt; f++) {
      int32_t a = tri[3 * f], b = tri[3 * f + 1], c = tri[3 * f + 2];
      int32_t ab = shp_midpoint(m, &em, a, b, radius), bc = shp_midpoint(m, &em, b, c, radius),
              ca = shp_midpoint(m, &em, c, a, radius);
      int32_t q[12] = {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca};
      memcpy(nt4 + 12 * f, q, sizeof q);
    }
    free(em.key);
    free(em.val);
    free(tri);
    tri = nt4;
    nt *= 4;
  }
  if (jitter > 0) {
    double h = radius * 1.1 / (1 << level); /* about the mean edge length */
    uint64_t s = seed;
    for (int64_t v = 0; v < m->nv; v++) {
      double *p = m->xyz + 3 * v, d[3];
      for (int k = 0; k < 3; k++) d[k] = jitter * h * (2 * shp_rand(&s) - 1);
      double l;
      for (int k = 0; k < 3; k++) p[k] += d[k];
      l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int k = 0; k < 3; k++) p[k] *= radius / l;
    }
  }
  for (int64_t f = 0; f < nt; f++)
    if ((st = vm_mesh_add_element(m, VM_TRI, tri + 3 * f))) break;
  free(tri);
  if (st) goto fail;
  *out = m;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

/* Closed unit cube [0,1]^3, n x n squares per face, each split into two
 * triangles; outward orientation. */
static inline int shp_cube(vm_ctx *ctx, int n, vm_mesh **out) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  /* vertices on the surface of the (n+1)^3 lattice */
  int N = n + 1;
  int32_t *id = malloc(sizeof *id * (size_t)N * N * N);
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++)
      for (int k = 0; k < N; k++) {
        int32_t *p = id + (i * N + j) * N + k;
        *p = -1;
        if (i == 0 || j == 0 || k == 0 || i == n || j == n || k == n) {
          int64_t v;
          if ((st = vm_mesh_add_vertex(m, (double)i / n, (double)j / n, (double)k / n, &v)))
            goto fail;
          *p = (int32_t)v;
        }
      }
  /* faces: axis a fixed at side s; (u, v) the other two axes with u x v = +e_a */
  for (int a = 0; a < 3; a++)
    for (int side = 0; side < 2; side++) {
      int u = (a + 1) % 3, w = (a + 2) % 3;
      for (int p = 0; p < n; p++)
        for (int q = 0; q < n; q++) {
          int c[4][3];
          int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
          for (int r = 0; r < 4; r++) {
            c[r][a] = side * n;
            c[r][u] = p + du[r];
            c[r][w] = q + dw[r];
          }
          int32_t v[4];
          for (int r = 0; r < 4; r++) v[r] = id[(c[r][0] * N + c[r][1]) * N + c[r][2]];
          int32_t t1[3] = {v[0], v[1], v[2]}, t2[3] = {v[0], v[2], v[3]};
          if (!side) { /* normal -e_a: reverse */
            t1[1] = v[2], t1[2] = v[1];
            t2[1] = v[3], t2[2] = v[2];
          }
          if ((st = vm_mesh_add_element(m, VM_TRI, t1)) || (st = vm_mesh_add_element(m, VM_TRI, t2)))
            goto fail;
        }
    }
  free(id);
  *out = m;
  return VM_OK;
fail:
  free(id);
  vm_mesh_destroy(&m);
  return st;
}

/* Stitch ring a (na vertices from a0, angles 2 pi (i + oa) / na) to ring b
 * (outer, nb from b0) with triangles oriented along +z x radial (flip: the
 * other way), advancing on the ring whose next angle is smaller. */
static inline int shp_stitch(vm_mesh *m, int32_t a0, int na, double oa, int32_t b0, int nb,
                             double ob, int flip) {
  int i = 0, k = 0, st = 0;
  while (i < na || k < nb) {
    double an = 2 * M_PI * (i + 1 + oa) / na, bn = 2 * M_PI * (k + 1 + ob) / nb;
    int32_t A = a0 + i % na, B = b0 + k % nb, t[3];
    if (k >= nb || (i < na && an < bn)) {
      t[0] = A, t[1] = B, t[2] = a0 + (i + 1) % na;
      i++;
    } else {
      t[0] = A, t[1] = B, t[2] = b0 + (k + 1) % nb;
      k++;
    }
    if (flip) {
      int32_t s = t[1];
      t[1] = t[2];
      t[2] = s;
    }
    if ((st = vm_mesh_add_element(m, VM_TRI, t))) return st;
  }
  return VM_OK;
}

/* A lens: two spherical caps of radius R, centres (0, 0, -d) (upper cap,
 * z >= 0) and (0, 0, d) (lower), meeting at the sharp circular ridge
 * z = 0, r = sqrt(R^2 - d^2), where the normals turn by 2 asin(d/R).
 * Rings of nearly equilateral triangles of edge about h; outward. */
static inline int shp_lens(vm_ctx *ctx, double R, double d, double h, vm_mesh **out) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  double phim = acos(d / R);
  int nr = (int)ceil(R * phim / h);
  int *cnt = malloc(sizeof *cnt * (size_t)(nr + 1));
  int32_t *start = malloc(sizeof *start * (size_t)(2 * nr + 1));
  double *off = malloc(sizeof *off * (size_t)(2 * nr + 1));
  for (int j = 1; j <= nr; j++) {
    double rj = R * sin(phim * j / nr);
    cnt[j] = (int)fmax(6, round(2 * M_PI * rj / h));
  }
  /* ring index r = 0..2nr-2: upper rings j = 1..nr then lower j = nr-1..1 */
  int nring = 2 * nr - 1;
  int64_t v;
  for (int r = 0; r < nring; r++) {
    int j = r < nr ? r + 1 : 2 * nr - 1 - r;
    double sgn = r < nr ? 1 : -1;
    double phi = phim * j / nr, rr = R * sin(phi), z = j == nr ? 0.0 : sgn * (R * cos(phi) - d);
    off[r] = 0.5 * (j % 2);
    start[r] = (int32_t)m->nv;
    for (int i = 0; i < cnt[j]; i++) {
      double th = 2 * M_PI * (i + off[r]) / cnt[j];
      if ((st = vm_mesh_add_vertex(m, rr * cos(th), rr * sin(th), z, &v))) goto fail;
    }
  }
  int64_t top, bot;
  if ((st = vm_mesh_add_vertex(m, 0, 0, R - d, &top)) ||
      (st = vm_mesh_add_vertex(m, 0, 0, -(R - d), &bot)))
    goto fail;
  for (int i = 0; i < cnt[1]; i++) { /* pole fans */
    int32_t t1[3] = {(int32_t)top, start[0] + i, start[0] + (i + 1) % cnt[1]};
    int32_t t2[3] = {(int32_t)bot, start[nring - 1] + (i + 1) % cnt[1], start[nring - 1] + i};
    if ((st = vm_mesh_add_element(m, VM_TRI, t1)) || (st = vm_mesh_add_element(m, VM_TRI, t2)))
      goto fail;
  }
  for (int r = 0; r + 1 < nr; r++) { /* upper: ring r inside ring r+1 */
    int ja = r + 1, jb = r + 2;
    if ((st = shp_stitch(m, start[r], cnt[ja], off[r], start[r + 1], cnt[jb], off[r + 1], 0)))
      goto fail;
  }
  for (int r = nr; r < nring; r++) { /* lower: ring r inside ring r-1 */
    int ja = 2 * nr - 1 - r, jb = ja + 1;
    if ((st = shp_stitch(m, start[r], cnt[ja], off[r], start[r - 1], cnt[jb], off[r - 1], 1)))
      goto fail;
  }
  free(cnt);
  free(start);
  free(off);
  *out = m;
  return VM_OK;
fail:
  free(cnt);
  free(start);
  free(off);
  vm_mesh_destroy(&m);
  return st;
}

#endif
