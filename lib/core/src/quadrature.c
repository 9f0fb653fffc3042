/* lib/core/src/quadrature.c: tables of corner and geometric quadrature rules
 * (Theorem 3.1, (24)) and the ideal reference elements. */
#include "varmesh/quadrature.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>

/* tri: the element itself */
static const vm_qnode tri_nodes[1] = {{{1, 2, 0}, {0, 0, 0}, 1.0}};
/* quad: 4 corner triangles (column 1 to the next vertex, column 2 to the
 * previous): the geometric rule for the bilinear map, m = 2, 2^2 nodes */
static const vm_qnode quad_nodes[4] = {{{1, 3, 0}, {0, 0, 0}, 0.25},
                                       {{2, 0, 0}, {1, 1, 0}, 0.25},
                                       {{3, 1, 0}, {2, 2, 0}, 0.25},
                                       {{0, 2, 0}, {3, 3, 0}, 0.25}};
static const vm_qnode tet_nodes[1] = {{{1, 2, 3}, {0, 0, 0}, 1.0}};
/* pyramid: the 4 base-corner tets (next, previous, apex) */
static const vm_qnode pyr_nodes[4] = {{{1, 3, 4}, {0, 0, 0}, 0.25},
                                      {{2, 0, 4}, {1, 1, 1}, 0.25},
                                      {{3, 1, 4}, {2, 2, 2}, 0.25},
                                      {{0, 2, 4}, {3, 3, 3}, 0.25}};
/* prism corner tets: bottom (next, previous, up), top (previous, next, down) */
static const vm_qnode prism_corner[6] = {
    {{1, 2, 3}, {0, 0, 0}, 1.0 / 6}, {{2, 0, 4}, {1, 1, 1}, 1.0 / 6},
    {{0, 1, 5}, {2, 2, 2}, 1.0 / 6}, {{5, 4, 0}, {3, 3, 3}, 1.0 / 6},
    {{3, 5, 1}, {4, 4, 4}, 1.0 / 6}, {{4, 3, 2}, {5, 5, 5}, 1.0 / 6}};
/* hex corner tets: at each corner the three edges in the xi1, xi2, xi3
 * directions, oriented along +xi (a subset of the geometric rule) */
static vm_qnode hex_corner[8];
static vm_qnode hex_geom[64];
/* the 6 Kuhn tets of the 6-tet split (0,1,2,6), (0,2,3,6), (0,3,7,6),
 * (0,7,4,6), (0,4,5,6), (0,5,1,6): det T = 1 on the unit cube each */
static const vm_qnode hex_split[6] = {
    {{1, 2, 6}, {0, 0, 0}, 1.0 / 6}, {{2, 3, 6}, {0, 0, 0}, 1.0 / 6},
    {{3, 7, 6}, {0, 0, 0}, 1.0 / 6}, {{7, 4, 6}, {0, 0, 0}, 1.0 / 6},
    {{4, 5, 6}, {0, 0, 0}, 1.0 / 6}, {{5, 1, 6}, {0, 0, 0}, 1.0 / 6}};
static vm_qnode hex_corner_split[14];
static vm_qnode hex_geom_split[70];
static vm_qnode prism_geom[12];
/* set (release) only after the tables and the rule array are complete */
static atomic_int tables_ready;

/* hex vertex of unit-cube corner (i, j, k), VTK order */
static int hexv(int i, int j, int k) {
  static const int v[2][2][2] = {{{0, 4}, {3, 7}}, {{1, 5}, {2, 6}}};
  return v[i][j][k];
}

/* dst: the n nodes of base, then the 6 of the split, each at half its weight */
static void with_split(vm_qnode *dst, const vm_qnode *base, int n) {
  for (int q = 0; q < n + 6; q++) {
    dst[q] = q < n ? base[q] : hex_split[q - n];
    dst[q].beta *= 0.5;
  }
}

static void build_tables(void) {
  /* (24) for the trilinear map: column 1 is the xi1-edge at (j, k) with
   * weight b_j(xi2) b_k(xi3); column 2 the xi2-edge at (i', k'), column 3 the
   * xi3-edge at (i'', j''). beta = prod over directions of int b_a b_b, with
   * int b_a b_b = 1/3 if a == b else 1/6. */
  int n = 0, nc = 0;
  for (int j = 0; j < 2; j++)
    for (int k = 0; k < 2; k++)
      for (int i2 = 0; i2 < 2; i2++)
        for (int k2 = 0; k2 < 2; k2++)
          for (int i3 = 0; i3 < 2; i3++)
            for (int j3 = 0; j3 < 2; j3++) {
              vm_qnode *q = &hex_geom[n++];
              q->head[0] = (signed char)hexv(1, j, k);
              q->tail[0] = (signed char)hexv(0, j, k);
              q->head[1] = (signed char)hexv(i2, 1, k2);
              q->tail[1] = (signed char)hexv(i2, 0, k2);
              q->head[2] = (signed char)hexv(i3, j3, 1);
              q->tail[2] = (signed char)hexv(i3, j3, 0);
              double b1 = i2 == i3 ? 1.0 / 3 : 1.0 / 6; /* xi1 in cols 2, 3 */
              double b2 = j == j3 ? 1.0 / 3 : 1.0 / 6;  /* xi2 in cols 1, 3 */
              double b3 = k == k2 ? 1.0 / 3 : 1.0 / 6;  /* xi3 in cols 1, 2 */
              q->beta = b1 * b2 * b3;
            }
  /* corner tets at corner (i, j, k): edges through that corner */
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++)
      for (int k = 0; k < 2; k++) {
        vm_qnode *q = &hex_corner[nc++];
        q->head[0] = (signed char)hexv(1, j, k);
        q->tail[0] = (signed char)hexv(0, j, k);
        q->head[1] = (signed char)hexv(i, 1, k);
        q->tail[1] = (signed char)hexv(i, 0, k);
        q->head[2] = (signed char)hexv(i, j, 1);
        q->tail[2] = (signed char)hexv(i, j, 0);
        q->beta = 1.0 / 8;
      }
  with_split(hex_corner_split, hex_corner, 8);
  with_split(hex_geom_split, hex_geom, 64);
  /* prism: columns 1, 2 are the base edges 0-1 and 0-2 of the bottom (weight
   * 1 - xi3) or top (xi3) triangle, column 3 a side edge (weight lambda_i);
   * beta = (1/3 same layer, 1/6 different) * 1/3 */
  n = 0;
  for (int l1 = 0; l1 < 2; l1++)
    for (int l2 = 0; l2 < 2; l2++)
      for (int s = 0; s < 3; s++) {
        vm_qnode *q = &prism_geom[n++];
        q->head[0] = (signed char)(1 + 3 * l1);
        q->tail[0] = (signed char)(0 + 3 * l1);
        q->head[1] = (signed char)(2 + 3 * l2);
        q->tail[1] = (signed char)(0 + 3 * l2);
        q->head[2] = (signed char)(s + 3);
        q->tail[2] = (signed char)s;
        q->beta = (l1 == l2 ? 1.0 / 3 : 1.0 / 6) / 3;
      }
}

const vm_qrule *vm_qrule_get(int type, int rule) {
  enum { NRULES = VM_RULE_GEOMETRIC_SPLIT + 1 };
  static vm_qrule rules[VM_NTYPES][NRULES];
  if (type < 0 || type >= VM_NTYPES || rule < VM_RULE_CORNER || rule >= NRULES) return NULL;
  if (!atomic_load_explicit(&tables_ready, memory_order_acquire)) {
#ifdef _OPENMP
#pragma omp critical(vm_qrule_init)
#endif
    {
      if (!atomic_load_explicit(&tables_ready, memory_order_relaxed)) {
        build_tables();
        rules[VM_TRI][0] = (vm_qrule){VM_TRI, VM_RULE_CORNER, 2, 1, 0.5, tri_nodes};
        rules[VM_QUAD][0] = (vm_qrule){VM_QUAD, VM_RULE_CORNER, 2, 4, 1.0, quad_nodes};
        rules[VM_TET][0] = (vm_qrule){VM_TET, VM_RULE_CORNER, 3, 1, 1.0 / 6, tet_nodes};
        rules[VM_PYRAMID][0] = (vm_qrule){VM_PYRAMID, VM_RULE_CORNER, 3, 4, 1.0 / 3, pyr_nodes};
        rules[VM_PRISM][0] = (vm_qrule){VM_PRISM, VM_RULE_CORNER, 3, 6, 0.5, prism_corner};
        rules[VM_HEX][0] = (vm_qrule){VM_HEX, VM_RULE_CORNER, 3, 8, 1.0, hex_corner};
        for (int t = 0; t < VM_NTYPES; t++)
          for (int r = 1; r < NRULES; r++) rules[t][r] = rules[t][0];
        rules[VM_PRISM][1] = (vm_qrule){VM_PRISM, VM_RULE_GEOMETRIC, 3, 12, 0.5, prism_geom};
        rules[VM_HEX][1] = (vm_qrule){VM_HEX, VM_RULE_GEOMETRIC, 3, 64, 1.0, hex_geom};
        rules[VM_HEX][2] = (vm_qrule){VM_HEX, VM_RULE_SPLIT, 3, 6, 1.0, hex_split};
        rules[VM_HEX][3] = (vm_qrule){VM_HEX, VM_RULE_CORNER_SPLIT, 3, 14, 1.0, hex_corner_split};
        rules[VM_PRISM][4] = rules[VM_PRISM][1];
        rules[VM_HEX][4] = (vm_qrule){VM_HEX, VM_RULE_GEOMETRIC_SPLIT, 3, 70, 1.0, hex_geom_split};
        atomic_store_explicit(&tables_ready, 1, memory_order_release);
      }
    }
  }
  return &rules[type][rule];
}

void vm_elem_ideal(int type, double ref[VM_MAX_ELEM_VERTS * 3]) {
  const double s3 = sqrt(3.0);
  memset(ref, 0, sizeof(double) * VM_MAX_ELEM_VERTS * 3);
  static const double tri[3][3] = {{0, 0, 0}, {1, 0, 0}, {0.5, 0, 0}};
  switch (type) {
  case VM_TRI:
    memcpy(ref, tri, sizeof tri);
    ref[7] = s3 / 2;
    break;
  case VM_QUAD: {
    static const double q[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    memcpy(ref, q, sizeof q);
    break;
  }
  case VM_TET:
    memcpy(ref, tri, sizeof tri);
    ref[7] = s3 / 2;
    ref[9] = 0.5;
    ref[10] = s3 / 6;
    ref[11] = sqrt(2.0 / 3.0);
    break;
  case VM_PYRAMID: {
    static const double q[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    memcpy(ref, q, sizeof q);
    ref[12] = 0.5;
    ref[13] = 0.5;
    ref[14] = sqrt(0.5);
    break;
  }
  case VM_PRISM:
    memcpy(ref, tri, sizeof tri);
    ref[7] = s3 / 2;
    for (int i = 0; i < 3; i++) {
      ref[9 + 3 * i] = ref[3 * i];
      ref[10 + 3 * i] = ref[3 * i + 1];
      ref[11 + 3 * i] = 1.0;
    }
    break;
  case VM_HEX: {
    static const double h[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    memcpy(ref, h, sizeof h);
    break;
  }
  default: break;
  }
}

void vm_qnode_edges(const vm_qnode *q, int d, const double *x, double *E) {
  for (int k = 0; k < d; k++)
    for (int r = 0; r < d; r++) E[r * d + k] = x[q->head[k] * 3 + r] - x[q->tail[k] * 3 + r];
}
