/* test/support/check_prism.h: checks of prism-stage results that do not
 * use the library's own predicates: surface self-intersections by brute
 * force (separating axes) and inverted corner tets of prisms. */
#ifndef VM_TEST_CHECK_PRISM_H
#define VM_TEST_CHECK_PRISM_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "varmesh/mesh.h"

static inline void chk_sub(const double *a, const double *b, double *c) {
  for (int k = 0; k < 3; k++) c[k] = a[k] - b[k];
}
static inline void chk_cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline double chk_dot(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Triangles A, B (3x3 coordinates) overlap by more than `gap` along every
 * one of the 11 candidate axes (2 normals, 9 edge cross products). */
static inline int chk_sat_overlap(double A[3][3], double B[3][3], double gap) {
  double ea[3][3], eb[3][3], ax[11][3];
  for (int i = 0; i < 3; i++) {
    chk_sub(A[(i + 1) % 3], A[i], ea[i]);
    chk_sub(B[(i + 1) % 3], B[i], eb[i]);
  }
  chk_cross(ea[0], ea[1], ax[0]);
  chk_cross(eb[0], eb[1], ax[1]);
  int na = 2;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) chk_cross(ea[i], eb[j], ax[na++]);
  for (int k = 0; k < na; k++) {
    double l = sqrt(chk_dot(ax[k], ax[k]));
    if (!(l > 1e-12)) continue;
    double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
    for (int i = 0; i < 3; i++) {
      double pa = chk_dot(A[i], ax[k]) / l, pb = chk_dot(B[i], ax[k]) / l;
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
static inline int64_t chk_count_intersections(const double *xyz, int64_t ntri, const int32_t *tri,
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
      if (chk_sat_overlap(A, B, 0)) n++;
    }
  free(box);
  return n;
}

/* Independent validity check of a prism mesh: the number of corner tets
 * (six per prism) that are not positive. */
static inline int64_t chk_corner_inverted(const vm_mesh *m) {
  static const int ct[6][4] = {{0, 1, 2, 3}, {1, 2, 0, 4}, {2, 0, 1, 5},
                               {3, 5, 4, 0}, {4, 3, 5, 1}, {5, 4, 3, 2}};
  int64_t bad = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_PRISM) continue;
    const int32_t *c = m->conn + m->eoff[e];
    for (int k = 0; k < 6; k++) {
      const double *o = m->xyz + 3 * c[ct[k][0]];
      double a[3], b[3], d[3], x[3];
      chk_sub(m->xyz + 3 * c[ct[k][1]], o, a);
      chk_sub(m->xyz + 3 * c[ct[k][2]], o, b);
      chk_sub(m->xyz + 3 * c[ct[k][3]], o, d);
      chk_cross(a, b, x);
      if (!(chk_dot(x, d) > 0)) bad++;
    }
  }
  return bad;
}

#endif
