/* test/prism/shapes.h: closed, outward-oriented triangulated test walls
 * (icosphere, subdivided cube and box, torus) and an independent check of
 * surface self-intersections (brute force, separating axes). */
#ifndef PRISM_TEST_SHAPES_H
#define PRISM_TEST_SHAPES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/mesh.h"

/* Append a triangle. */
static inline int sh_tri(vm_mesh *m, int64_t a, int64_t b, int64_t c) {
  int32_t v[3] = {(int32_t)a, (int32_t)b, (int32_t)c};
  return vm_mesh_add_element(m, VM_TRI, v);
}

/* Icosphere of `level` subdivisions (20 * 4^level triangles), appended. */
static inline int sh_icosphere(vm_mesh *m, const double c[3], double R, int level) {
  const double t = (1 + sqrt(5.0)) / 2;
  double V[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                     {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  int F[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                  {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                  {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  int nf = 20, nv = 12;
  int maxf = 20 << (2 * level), maxv = maxf / 2 + 2;
  double(*P)[3] = malloc(sizeof(double[3]) * (size_t)maxv);
  int(*T)[3] = malloc(sizeof(int[3]) * (size_t)maxf);
  int(*T2)[3] = malloc(sizeof(int[3]) * (size_t)maxf);
  int *emid = malloc(sizeof(int) * (size_t)maxv * (size_t)maxv);
  memcpy(P, V, sizeof V);
  memcpy(T, F, sizeof F);
  for (int l = 0; l < level; l++) {
    for (int i = 0; i < nv * nv; i++) emid[i] = -1;
    int n2 = 0, nv0 = nv;
    for (int f = 0; f < nf; f++) {
      int mid[3];
      for (int e = 0; e < 3; e++) {
        int a = T[f][e], b = T[f][(e + 1) % 3];
        int lo = a < b ? a : b, hi = a < b ? b : a;
        int *slot = &emid[lo * nv0 + hi];
        if (*slot < 0) {
          for (int k = 0; k < 3; k++) P[nv][k] = 0.5 * (P[a][k] + P[b][k]);
          *slot = nv++;
        }
        mid[e] = *slot;
      }
      int a = T[f][0], b = T[f][1], cc = T[f][2];
      int nt[4][3] = {{a, mid[0], mid[2]}, {b, mid[1], mid[0]}, {cc, mid[2], mid[1]},
                      {mid[0], mid[1], mid[2]}};
      memcpy(T2 + n2, nt, sizeof nt);
      n2 += 4;
    }
    memcpy(T, T2, sizeof(int[3]) * (size_t)n2);
    nf = n2;
  }
  int64_t base = m->nv;
  for (int i = 0; i < nv; i++) {
    double r = sqrt(P[i][0] * P[i][0] + P[i][1] * P[i][1] + P[i][2] * P[i][2]);
    vm_mesh_add_vertex(m, c[0] + R * P[i][0] / r, c[1] + R * P[i][1] / r, c[2] + R * P[i][2] / r,
                       NULL);
  }
  int st = 0;
  for (int f = 0; f < nf && !st; f++) st = sh_tri(m, base + T[f][0], base + T[f][1], base + T[f][2]);
  free(P);
  free(T);
  free(T2);
  free(emid);
  return st;
}

/* Axis-aligned box [lo, hi] with n[k] subdivisions per direction, split
 * into triangles, outward oriented. */
static inline int sh_box(vm_mesh *m, const double lo[3], const double hi[3], const int n[3]) {
  int st = 0;
  for (int a = 0; a < 3 && !st; a++) {
    int u = (a + 1) % 3, w = (a + 2) % 3; /* e_u x e_w = e_a */
    for (int side = 0; side < 2 && !st; side++) {
      int64_t base = m->nv;
      for (int j = 0; j <= n[w]; j++)
        for (int i = 0; i <= n[u]; i++) {
          double x[3];
          x[a] = side ? hi[a] : lo[a];
          x[u] = lo[u] + (hi[u] - lo[u]) * i / n[u];
          x[w] = lo[w] + (hi[w] - lo[w]) * j / n[w];
          vm_mesh_add_vertex(m, x[0], x[1], x[2], NULL);
        }
      for (int j = 0; j < n[w] && !st; j++)
        for (int i = 0; i < n[u] && !st; i++) {
          int64_t v00 = base + j * (n[u] + 1) + i, v10 = v00 + 1, v01 = v00 + n[u] + 1,
                  v11 = v01 + 1;
          if (side) {
            st = sh_tri(m, v00, v10, v11);
            if (!st) st = sh_tri(m, v00, v11, v01);
          } else {
            st = sh_tri(m, v00, v11, v10);
            if (!st) st = sh_tri(m, v00, v01, v11);
          }
        }
    }
  }
  return st;
}

/* Merge vertices with identical coordinates (the box faces share edges). */
static inline int sh_merge(vm_mesh *m) {
  int64_t nv = m->nv;
  int32_t *map = malloc(sizeof(int32_t) * (size_t)nv);
  int64_t n = 0;
  for (int64_t v = 0; v < nv; v++) {
    map[v] = -1;
    for (int64_t u = 0; u < v; u++)
      if (map[u] == u && !memcmp(m->xyz + 3 * u, m->xyz + 3 * v, 3 * sizeof(double))) {
        map[v] = (int32_t)u;
        break;
      }
    if (map[v] < 0) map[v] = (int32_t)v;
  }
  int32_t *ren = malloc(sizeof(int32_t) * (size_t)nv);
  for (int64_t v = 0; v < nv; v++)
    if (map[v] == v) {
      ren[v] = (int32_t)n;
      memmove(m->xyz + 3 * n, m->xyz + 3 * v, 3 * sizeof(double));
      n++;
    }
  for (int64_t k = 0; k < m->eoff[m->ne]; k++) m->conn[k] = ren[map[m->conn[k]]];
  m->nv = n;
  free(map);
  free(ren);
  return 0;
}

/* Torus around z: major radius R, minor r, nu x nv quads split. */
static inline int sh_torus(vm_mesh *m, double R, double r, int nu, int nv) {
  int64_t base = m->nv;
  for (int i = 0; i < nu; i++)
    for (int j = 0; j < nv; j++) {
      double u = 2 * 3.14159265358979323846 * i / nu, v = 2 * 3.14159265358979323846 * j / nv;
      vm_mesh_add_vertex(m, (R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v),
                         NULL);
    }
  int st = 0;
  for (int i = 0; i < nu && !st; i++)
    for (int j = 0; j < nv && !st; j++) {
      int64_t a = base + i * nv + j, b = base + ((i + 1) % nu) * nv + j,
              c = base + ((i + 1) % nu) * nv + (j + 1) % nv, d = base + i * nv + (j + 1) % nv;
      st = sh_tri(m, a, b, c);
      if (!st) st = sh_tri(m, a, c, d);
    }
  return st;
}

/* ---- independent intersection check: all pairs, separating axis test ---- */

static inline void sh_sub(const double *a, const double *b, double *c) {
  for (int k = 0; k < 3; k++) c[k] = a[k] - b[k];
}
static inline void sh_cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline double sh_dot(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Triangles A, B (3x3 coordinates) overlap by more than `gap` along every
 * one of the 11 candidate axes (2 normals, 9 edge cross products). */
static inline int sh_sat_overlap(double A[3][3], double B[3][3], double gap) {
  double ea[3][3], eb[3][3], ax[11][3];
  for (int i = 0; i < 3; i++) {
    sh_sub(A[(i + 1) % 3], A[i], ea[i]);
    sh_sub(B[(i + 1) % 3], B[i], eb[i]);
  }
  sh_cross(ea[0], ea[1], ax[0]);
  sh_cross(eb[0], eb[1], ax[1]);
  int na = 2;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) sh_cross(ea[i], eb[j], ax[na++]);
  for (int k = 0; k < na; k++) {
    double l = sqrt(sh_dot(ax[k], ax[k]));
    if (!(l > 1e-12)) continue;
    double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
    for (int i = 0; i < 3; i++) {
      double pa = sh_dot(A[i], ax[k]) / l, pb = sh_dot(B[i], ax[k]) / l;
      amin = fmin(amin, pa);
      amax = fmax(amax, pa);
      bmin = fmin(bmin, pb);
      bmax = fmax(bmax, pb);
    }
    if (amax < bmin + gap || bmax < amin + gap) return 0;
  }
  return 1;
}

/* Count intersecting pairs among triangles tri[3*i..] of xyz: pairs sharing
 * vertices are shrunk towards their centroids by `shrink` (relative) first,
 * pairs sharing an edge are skipped; pairs with both in group 0 (grp != NULL)
 * are skipped. O(n^2) with a box test: for small test meshes. */
static inline int64_t sh_count_intersections(const double *xyz, int64_t ntri, const int32_t *tri,
                                      const int32_t *grp, double shrink) {
  double(*box)[6] = malloc(sizeof(double[6]) * (size_t)ntri);
  for (int64_t t = 0; t < ntri; t++) {
    for (int k = 0; k < 3; k++) {
      box[t][k] = INFINITY;
      box[t][3 + k] = -INFINITY;
    }
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) {
        double v = xyz[3 * tri[3 * t + i] + k];
        box[t][k] = fmin(box[t][k], v);
        box[t][3 + k] = fmax(box[t][3 + k], v);
      }
  }
  int64_t n = 0;
  for (int64_t a = 0; a < ntri; a++)
    for (int64_t b = a + 1; b < ntri; b++) {
      if (grp && grp[a] == 0 && grp[b] == 0) continue;
      if (box[a][0] > box[b][3] || box[b][0] > box[a][3] || box[a][1] > box[b][4] ||
          box[b][1] > box[a][4] || box[a][2] > box[b][5] || box[b][2] > box[a][5])
        continue;
      int shared = 0;
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) shared += tri[3 * a + i] == tri[3 * b + j];
      if (shared >= 2) continue;
      double A[3][3], B[3][3], ca[3] = {0, 0, 0}, cb[3] = {0, 0, 0};
      for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
          A[i][k] = xyz[3 * tri[3 * a + i] + k];
          B[i][k] = xyz[3 * tri[3 * b + i] + k];
          ca[k] += A[i][k] / 3;
          cb[k] += B[i][k] / 3;
        }
      if (shared)
        for (int i = 0; i < 3; i++)
          for (int k = 0; k < 3; k++) {
            A[i][k] += shrink * (ca[k] - A[i][k]);
            B[i][k] += shrink * (cb[k] - B[i][k]);
          }
      if (sh_sat_overlap(A, B, 0)) n++;
    }
  free(box);
  return n;
}

/* Independent validity check of a prism mesh: the number of corner tets
 * (six per prism) that are not positive. */
static inline int64_t sh_corner_inverted(const vm_mesh *m) {
  static const int ct[6][4] = {{0, 1, 2, 3}, {1, 2, 0, 4}, {2, 0, 1, 5},
                               {3, 5, 4, 0}, {4, 3, 5, 1}, {5, 4, 3, 2}};
  int64_t bad = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_PRISM) continue;
    const int32_t *c = m->conn + m->eoff[e];
    for (int k = 0; k < 6; k++) {
      const double *o = m->xyz + 3 * c[ct[k][0]];
      double a[3], b[3], d[3], x[3];
      sh_sub(m->xyz + 3 * c[ct[k][1]], o, a);
      sh_sub(m->xyz + 3 * c[ct[k][2]], o, b);
      sh_sub(m->xyz + 3 * c[ct[k][3]], o, d);
      sh_cross(a, b, x);
      if (!(sh_dot(x, d) > 0)) bad++;
    }
  }
  return bad;
}

#endif
