/* lib/core/src/jacobian.c: certified sign of the Jacobian determinant of
 * each cell's map: Bernstein coefficients of det J, de Casteljau
 * subdivision for hexahedra and pyramids, closed form for prisms. */
#include "varmesh/jacobian.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "linsolve_private.h"
#include "vec3.h"

/* A polynomial in tensor-product Bernstein form of degree deg[a] <= 2 in
 * each of three variables, with for each coefficient a bound `mag` on the
 * magnitudes it was summed from (the rounding error of the coefficient is
 * a small multiple of DBL_EPSILON * mag). */
typedef struct {
  int deg[3];
  double c[3][3][3];
  double mag[3][3][3];
} bern3;

/* Rounding tolerance: units in the last place per coefficient at level 0,
 * and how many more each subdivision level may add (each level averages,
 * which adds at most one rounding per coefficient and axis). */
#define TOL_ULPS 64.0
#define TOL_ULPS_PER_LEVEL 8.0
#define DEFAULT_DEPTH 6
#define PART_BUDGET 4096

static const double binom[5][5] = {
    {1, 0, 0, 0, 0}, {1, 1, 0, 0, 0}, {1, 2, 1, 0, 0}, {1, 3, 3, 1, 0}, {1, 4, 6, 4, 1}};

/* Weight of B^m_i * B^n_j = w * B^{m+n}_{i+j}. */
static double bw(int m, int i, int n, int j) {
  return binom[m][i] * binom[n][j] / binom[m + n][i + j];
}

static void bern_zero(bern3 *p, int d0, int d1, int d2) {
  memset(p, 0, sizeof *p);
  p->deg[0] = d0;
  p->deg[1] = d1;
  p->deg[2] = d2;
}

/* r += sign * p * q (degrees add; r must have the sum's degrees). */
static void bern_mul_add(bern3 *r, const bern3 *p, const bern3 *q, double sign) {
  for (int i = 0; i <= p->deg[0]; i++)
    for (int j = 0; j <= p->deg[1]; j++)
      for (int k = 0; k <= p->deg[2]; k++) {
        double pc = p->c[i][j][k], pm = p->mag[i][j][k];
        for (int a = 0; a <= q->deg[0]; a++)
          for (int b = 0; b <= q->deg[1]; b++)
            for (int c = 0; c <= q->deg[2]; c++) {
              double w = bw(p->deg[0], i, q->deg[0], a) * bw(p->deg[1], j, q->deg[1], b) *
                         bw(p->deg[2], k, q->deg[2], c);
              r->c[i + a][j + b][k + c] += sign * w * pc * q->c[a][b][c];
              r->mag[i + a][j + b][k + c] += w * pm * q->mag[a][b][c];
            }
      }
}

/* det [X Y Z] = X . (Y x Z) of three vector polynomials (component r of X
 * is X[r]). */
static void bern_det3(const bern3 X[3], const bern3 Y[3], const bern3 Z[3], bern3 *det) {
  bern3 cr[3];
  for (int r = 0; r < 3; r++) {
    int s = (r + 1) % 3, t = (r + 2) % 3;
    bern_zero(&cr[r], Y[s].deg[0] + Z[t].deg[0], Y[s].deg[1] + Z[t].deg[1],
              Y[s].deg[2] + Z[t].deg[2]);
    bern_mul_add(&cr[r], &Y[s], &Z[t], 1);
    bern_mul_add(&cr[r], &Y[t], &Z[s], -1);
  }
  bern_zero(det, X[0].deg[0] + cr[0].deg[0], X[0].deg[1] + cr[0].deg[1],
            X[0].deg[2] + cr[0].deg[2]);
  for (int r = 0; r < 3; r++) bern_mul_add(det, &X[r], &cr[r], 1);
}

/* Split p at the midpoint of every axis of positive degree: 2^k children
 * into out (at most 8), their number returned. */
static int bern_split(const bern3 *p, bern3 out[8]) {
  int n = 1;
  out[0] = *p;
  for (int ax = 0; ax < 3; ax++) {
    int d = p->deg[ax];
    if (d == 0) continue;
    for (int h = 0; h < n; h++) {
      bern3 *lo = &out[h], *hi = &out[h + n];
      *hi = *lo;
      int idx[3];
      for (idx[0] = 0; idx[0] < 3; idx[0]++)
        for (idx[1] = 0; idx[1] < 3; idx[1]++)
          for (idx[2] = 0; idx[2] < 3; idx[2]++) {
            if (idx[ax] != 0) continue;
            double *L[3], *H[3], *Lm[3], *Hm[3];
            for (int t = 0; t <= d; t++) {
              int ii[3] = {idx[0], idx[1], idx[2]};
              ii[ax] = t;
              L[t] = &lo->c[ii[0]][ii[1]][ii[2]];
              H[t] = &hi->c[ii[0]][ii[1]][ii[2]];
              Lm[t] = &lo->mag[ii[0]][ii[1]][ii[2]];
              Hm[t] = &hi->mag[ii[0]][ii[1]][ii[2]];
            }
            double a = *L[0], b = *L[1], am = *Lm[0], bm = *Lm[1];
            if (d == 1) {
              *L[1] = *H[0] = 0.5 * (a + b);
              *Lm[1] = *Hm[0] = 0.5 * (am + bm);
            } else {
              double c = *L[2], cm = *Lm[2];
              double ab = 0.5 * (a + b), bc = 0.5 * (b + c), mid = 0.5 * (ab + bc);
              double abm = 0.5 * (am + bm), bcm = 0.5 * (bm + cm), midm = 0.5 * (abm + bcm);
              *L[1] = ab, *L[2] = mid, *H[0] = mid, *H[1] = bc;
              *Lm[1] = abm, *Lm[2] = midm, *Hm[0] = midm, *Hm[1] = bcm;
            }
          }
    }
    n *= 2;
  }
  return n;
}

typedef struct {
  int max_depth;
  int parts;
  double min_coef;
} decide_state;

static vm_jac_verdict bern_decide(const bern3 *p, int level, decide_state *s) {
  double tol_ulps = TOL_ULPS + TOL_ULPS_PER_LEVEL * level;
  int all_pos = 1;
  double lo = INFINITY;
  for (int i = 0; i <= p->deg[0]; i++)
    for (int j = 0; j <= p->deg[1]; j++)
      for (int k = 0; k <= p->deg[2]; k++) {
        double tol = tol_ulps * DBL_EPSILON * p->mag[i][j][k];
        double c = p->c[i][j][k];
        if (c < lo) lo = c;
        if (!(c > tol)) all_pos = 0;
        /* a corner coefficient is the value of det J there */
        int corner =
            (i == 0 || i == p->deg[0]) && (j == 0 || j == p->deg[1]) && (k == 0 || k == p->deg[2]);
        if (corner && c < -tol) return VM_JAC_INVALID;
      }
  if (all_pos) {
    if (lo < s->min_coef) s->min_coef = lo;
    return VM_JAC_VALID;
  }
  if (level >= s->max_depth || s->parts >= PART_BUDGET) return VM_JAC_UNDECIDED;
  bern3 ch[8];
  int n = bern_split(p, ch);
  s->parts += n;
  vm_jac_verdict v = VM_JAC_VALID;
  for (int h = 0; h < n; h++) {
    vm_jac_verdict vh = bern_decide(&ch[h], level + 1, s);
    if (vh == VM_JAC_INVALID) return VM_JAC_INVALID;
    if (vh == VM_JAC_UNDECIDED) v = VM_JAC_UNDECIDED;
  }
  return v;
}

/* A vector polynomial's coefficient: the difference a - b, rounded once. */
static void set_diff(bern3 V[3], int i, int j, int k, const double *a, const double *b) {
  for (int r = 0; r < 3; r++) {
    double d = a[r] - b[r];
    V[r].c[i][j][k] = d;
    V[r].mag[i][j][k] = fabs(d);
  }
}

static double longest_edge(const double *xyz, int nv) {
  double L = 0;
  for (int a = 0; a < nv; a++)
    for (int b = a + 1; b < nv; b++) {
      double d[3];
      vm_sub3(xyz + 3 * a, xyz + 3 * b, d);
      double l = vm_norm3(d);
      if (l > L) L = l;
    }
  return L;
}

static vm_jac_verdict certify_hex(const double *x, int max_depth, double *min_coef) {
  /* vertex of the corner (i, j, k) of the unit cube, VTK/Gmsh order */
  static const int node[2][2][2] = {{{0, 4}, {3, 7}}, {{1, 5}, {2, 6}}};
#define P(i, j, k) (x + 3 * node[i][j][k])
  bern3 Xu[3], Xv[3], Xw[3];
  for (int r = 0; r < 3; r++) {
    bern_zero(&Xu[r], 0, 1, 1);
    bern_zero(&Xv[r], 1, 0, 1);
    bern_zero(&Xw[r], 1, 1, 0);
  }
  for (int a = 0; a < 2; a++)
    for (int b = 0; b < 2; b++) {
      set_diff(Xu, 0, a, b, P(1, a, b), P(0, a, b));
      set_diff(Xv, a, 0, b, P(a, 1, b), P(a, 0, b));
      set_diff(Xw, a, b, 0, P(a, b, 1), P(a, b, 0));
    }
#undef P
  bern3 det;
  bern_det3(Xu, Xv, Xw, &det);
  decide_state s = {max_depth, 1, INFINITY};
  vm_jac_verdict v = bern_decide(&det, 0, &s);
  *min_coef = s.min_coef;
  return v;
}

static vm_jac_verdict certify_pyramid(const double *x, int max_depth, double *min_coef) {
  /* base corner (i, j) of the unit square: 0 (0,0), 1 (1,0), 2 (1,1), 3 (0,1) */
  static const int node[2][2] = {{0, 3}, {1, 2}};
  const double *A = x + 12;
  bern3 Qu[3], Qv[3], R[3];
  for (int r = 0; r < 3; r++) {
    bern_zero(&Qu[r], 0, 1, 0);
    bern_zero(&Qv[r], 1, 0, 0);
    bern_zero(&R[r], 1, 1, 0);
  }
  for (int a = 0; a < 2; a++) {
    set_diff(Qu, 0, a, 0, x + 3 * node[1][a], x + 3 * node[0][a]);
    set_diff(Qv, a, 0, 0, x + 3 * node[a][1], x + 3 * node[a][0]);
    for (int b = 0; b < 2; b++) set_diff(R, a, b, 0, A, x + 3 * node[a][b]);
  }
  bern3 q;
  bern_det3(R, Qu, Qv, &q); /* R . (Qu x Qv) = (Qu x Qv) . R */
  decide_state s = {max_depth, 1, INFINITY};
  vm_jac_verdict v = bern_decide(&q, 0, &s);
  *min_coef = s.min_coef;
  return v;
}

/* Is g(w) = b0 (1-w)^2 + 2 b1 w (1-w) + b2 w^2 positive on [0, 1]? With
 * t = w / (1-w): g / (1-w)^2 = b0 + 2 b1 t + b2 t^2, so iff b0, b2 > 0 and
 * (b1 >= 0 or b1^2 < b0 b2). tol: rounding tolerance of the b's. */
static vm_jac_verdict quadratic_positive(const double b[3], const double tol[3], double *lo) {
  if (b[0] < -tol[0] || b[2] < -tol[2]) return VM_JAC_INVALID;
  if (!(b[0] > tol[0]) || !(b[2] > tol[2])) return VM_JAC_UNDECIDED;
  double m = b[0] < b[2] ? b[0] : b[2];
  if (b[1] > tol[1]) {
    if (b[1] < m) m = b[1];
    if (m < *lo) *lo = m;
    return VM_JAC_VALID;
  }
  /* the minimum over t >= 0 of (b0 + 2 b1 t + b2 t^2) is b0 - b1^2 / b2 */
  double disc = b[0] * b[2] - b[1] * b[1];
  double dtol = 4 * (tol[0] * b[2] + tol[2] * b[0] + 2 * tol[1] * fabs(b[1]));
  if (disc > dtol) {
    double gmin = disc / b[2] < m ? disc / b[2] : m;
    if (gmin < *lo) *lo = gmin;
    return VM_JAC_VALID;
  }
  if (disc < -dtol) return VM_JAC_INVALID;
  return VM_JAC_UNDECIDED;
}

static vm_jac_verdict certify_prism(const double *x, double *min_coef) {
  double a0[3], a1[3], b0[3], b1[3], e[3][3];
  vm_sub3(x + 3, x, a0);      /* P1 - P0 */
  vm_sub3(x + 12, x + 9, a1); /* P4 - P3 */
  vm_sub3(x + 6, x, b0);      /* P2 - P0 */
  vm_sub3(x + 15, x + 9, b1); /* P5 - P3 */
  for (int i = 0; i < 3; i++) vm_sub3(x + 9 + 3 * i, x + 3 * i, e[i]);
  /* x_u x x_v in Bernstein form of degree 2 in w: c0, c1, c2, and for
   * each component the magnitude of the products it sums */
  double c[3][3], t0[3], t1[3], cm[3][3];
  vm_cross3(a0, b0, c[0]);
  vm_cross3(a0, b1, t0);
  vm_cross3(a1, b0, t1);
  for (int r = 0; r < 3; r++) c[1][r] = 0.5 * (t0[r] + t1[r]);
  vm_cross3(a1, b1, c[2]);
  for (int r = 0; r < 3; r++) {
    int s = (r + 1) % 3, t = (r + 2) % 3;
    cm[0][r] = fabs(a0[s] * b0[t]) + fabs(a0[t] * b0[s]);
    cm[1][r] = 0.5 * (fabs(a0[s] * b1[t]) + fabs(a0[t] * b1[s]) + fabs(a1[s] * b0[t]) +
                      fabs(a1[t] * b0[s]));
    cm[2][r] = fabs(a1[s] * b1[t]) + fabs(a1[t] * b1[s]);
  }
  vm_jac_verdict v = VM_JAC_VALID;
  double lo = INFINITY;
  for (int i = 0; i < 3; i++) {
    double b[3], tol[3];
    for (int k = 0; k < 3; k++) {
      b[k] = vm_dot3(c[k], e[i]);
      double mag = 0;
      for (int r = 0; r < 3; r++) mag += cm[k][r] * fabs(e[i][r]);
      tol[k] = TOL_ULPS * DBL_EPSILON * mag;
    }
    vm_jac_verdict vi = quadratic_positive(b, tol, &lo);
    if (vi == VM_JAC_INVALID) return VM_JAC_INVALID;
    if (vi == VM_JAC_UNDECIDED) v = VM_JAC_UNDECIDED;
  }
  *min_coef = lo;
  return v;
}

/* Sign of a number computed from terms of total magnitude mag. */
static vm_jac_verdict sign_verdict(double d, double mag, double *min_coef) {
  double tol = TOL_ULPS * DBL_EPSILON * mag;
  *min_coef = d;
  if (d > tol) return VM_JAC_VALID;
  if (d < -tol) return VM_JAC_INVALID;
  return VM_JAC_UNDECIDED;
}

static vm_jac_verdict certify_tet(const double *x, double *min_coef) {
  double a[3], b[3], c[3], bc[3];
  vm_sub3(x + 3, x, a);
  vm_sub3(x + 6, x, b);
  vm_sub3(x + 9, x, c);
  vm_cross3(b, c, bc);
  double mag = fabs(a[0]) * (fabs(b[1] * c[2]) + fabs(b[2] * c[1])) +
               fabs(a[1]) * (fabs(b[2] * c[0]) + fabs(b[0] * c[2])) +
               fabs(a[2]) * (fabs(b[0] * c[1]) + fabs(b[1] * c[0]));
  return sign_verdict(vm_dot3(a, bc), mag, min_coef);
}

/* z of (b - a) x (c - a) in the plane, and its magnitude. */
static double cross2(const double *a, const double *b, const double *c, double *mag) {
  double u0 = b[0] - a[0], u1 = b[1] - a[1], v0 = c[0] - a[0], v1 = c[1] - a[1];
  *mag = fabs(u0 * v1) + fabs(u1 * v0);
  return u0 * v1 - u1 * v0;
}

static vm_jac_verdict certify_planar(int type, const double *x, double *min_coef) {
  double mag;
  if (type == VM_TRI) {
    double d = cross2(x, x + 3, x + 6, &mag);
    return sign_verdict(d, mag, min_coef);
  }
  /* quad: det J is bilinear, its Bernstein coefficients are the corner values
   * (edge to the next corner) x (edge to the previous corner) */
  vm_jac_verdict v = VM_JAC_VALID;
  double lo = INFINITY;
  for (int k = 0; k < 4; k++) {
    double d = cross2(x + 3 * k, x + 3 * ((k + 1) % 4), x + 3 * ((k + 3) % 4), &mag), m;
    vm_jac_verdict vk = sign_verdict(d, mag, &m);
    if (m < lo) lo = m;
    if (vk == VM_JAC_INVALID) return VM_JAC_INVALID;
    if (vk == VM_JAC_UNDECIDED) v = VM_JAC_UNDECIDED;
  }
  *min_coef = lo;
  return v;
}

/* Local vertex of corner (a, b, c) of the hex, a along u, b along v, c along w. */
static int hex_vertex(int a, int b, int c) { return 4 * c + (b ? (a ? 2 : 3) : a); }

void vm_hex_bernstein(const double *xyz, double b[27], double *grad) {
  memset(b, 0, 27 * sizeof *b);
  if (grad) memset(grad, 0, 27 * 24 * sizeof *grad);
  static const double count[3] = {1, 2, 1};
  for (int n = 0; n < 64; n++) {
    /* x edge at (j, k), y edge at (i2, k2), z edge at (i3, j3) */
    int j = n & 1, k = n >> 1 & 1, i2 = n >> 2 & 1, k2 = n >> 3 & 1, i3 = n >> 4 & 1,
        j3 = n >> 5 & 1;
    int hd[3] = {hex_vertex(1, j, k), hex_vertex(i2, 1, k2), hex_vertex(i3, j3, 1)};
    int tl[3] = {hex_vertex(0, j, k), hex_vertex(i2, 0, k2), hex_vertex(i3, j3, 0)};
    double e[3][3];
    for (int l = 0; l < 3; l++)
      for (int r = 0; r < 3; r++) e[l][r] = xyz[3 * hd[l] + r] - xyz[3 * tl[l] + r];
    double cof[3][3];
    for (int l = 0; l < 3; l++) {
      const double *p = e[(l + 1) % 3], *q = e[(l + 2) % 3];
      cof[l][0] = p[1] * q[2] - p[2] * q[1];
      cof[l][1] = p[2] * q[0] - p[0] * q[2];
      cof[l][2] = p[0] * q[1] - p[1] * q[0];
    }
    int I = i2 + i3, J = j + j3, K = k + k2, c = 9 * I + 3 * J + K;
    double wgt = 1 / (count[I] * count[J] * count[K]);
    b[c] += wgt * (e[0][0] * cof[0][0] + e[0][1] * cof[0][1] + e[0][2] * cof[0][2]);
    if (!grad) continue;
    double *g = grad + 24 * c;
    for (int l = 0; l < 3; l++)
      for (int r = 0; r < 3; r++) {
        g[3 * hd[l] + r] += wgt * cof[l][r];
        g[3 * tl[l] + r] -= wgt * cof[l][r];
      }
  }
}

vm_jac_verdict vm_jacobian_certify(int type, const double *xyz, int max_depth, double *min_bound) {
  if (max_depth <= 0) max_depth = DEFAULT_DEPTH;
  double lo = INFINITY;
  vm_jac_verdict v;
  int nv = vm_elem_nverts(type), planar = 0;
  switch (type) {
  case VM_TRI:
  case VM_QUAD:
    v = certify_planar(type, xyz, &lo);
    planar = 1;
    break;
  case VM_TET: v = certify_tet(xyz, &lo); break;
  case VM_PYRAMID: v = certify_pyramid(xyz, max_depth, &lo); break;
  case VM_PRISM: v = certify_prism(xyz, &lo); break;
  case VM_HEX: v = certify_hex(xyz, max_depth, &lo); break;
  default:
    if (min_bound) *min_bound = INFINITY;
    return VM_JAC_VALID;
  }
  if (min_bound) {
    double L = longest_edge(xyz, nv);
    double scale = planar ? L * L : L * L * L;
    *min_bound = v != VM_JAC_VALID ? 0 : scale > 0 ? lo / scale : lo;
  }
  return v;
}

/* the coordinates of element e's vertices, in its order */
static void cell_coords(const vm_mesh *m, int64_t e, double *x) {
  int nv = vm_elem_nverts(m->etype[e]);
  for (int k = 0; k < nv; k++)
    memcpy(x + 3 * k, m->xyz + 3 * (int64_t)m->conn[m->eoff[e] + k], 3 * sizeof(double));
}

int vm_mesh_jacobian_certify(const vm_mesh *m, vm_jac_report *rep, uint8_t *verdict) {
  if (!m || !rep) return VM_ERR_ARG;
  int64_t counts[VM_NTYPES];
  int top = vm_mesh_count_types(m, counts);
  int cell_dim = top == 3 ? 3 : (m->dim == 2 ? 2 : 0);
  int64_t cells = 0, invalid = 0, undecided = 0, first = m->ne;
  int nt = vm_nthreads(m->ctx);
#pragma omp parallel for num_threads(nt) schedule(static) \
    reduction(+ : cells, invalid, undecided) reduction(min : first)
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    vm_jac_verdict v = VM_JAC_VALID;
    if (cell_dim && vm_elem_dim(t) == cell_dim) {
      double x[3 * 8];
      cell_coords(m, e, x);
      v = vm_jacobian_certify(t, x, 0, NULL);
      cells++;
      if (v == VM_JAC_INVALID) invalid++;
      if (v == VM_JAC_UNDECIDED) undecided++;
      if (v != VM_JAC_VALID && e < first) first = e;
    }
    if (verdict) verdict[e] = (uint8_t)v;
  }
  rep->cells = cells;
  rep->invalid = invalid;
  rep->undecided = undecided;
  rep->first_bad = first < m->ne ? first : -1;
  return VM_OK;
}

/* ---- phi and psi over the whole hexahedron ---- */

typedef struct {
  double phi, psi;
} phipsi;

static double psi_of(double d) { return 2 * d / (1 + d * d); }

/* The least psi on [a, b]: psi rises on [-1, 1] and falls outside it. */
static double psi_min_on(double a, double b) {
  if (a <= -1 && b >= -1) return -1;
  return fmin(psi_of(a), psi_of(b));
}

static void trilinear(const double *x8, double u, double v, double w, double *p) {
  for (int r = 0; r < 3; r++) {
    double s = 0;
    for (int c = 0; c < 2; c++)
      for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++)
          s +=
              (a ? u : 1 - u) * (b ? v : 1 - v) * (c ? w : 1 - w) * x8[3 * hex_vertex(a, b, c) + r];
    p[r] = s;
  }
}

/* The sub-cell of edge s at corner o of the reference cube: lo the
 * certified lower bounds of phi and psi on it, at the least phi and psi at
 * its corners (points of the cell, where the derivatives are the edges);
 * h scales det for psi (h <= 0: no psi). */
static void box_eval(const double *x8, const double *o, double s, double h, phipsi *lo,
                     phipsi *at) {
  double p[24];
  for (int c = 0; c < 2; c++)
    for (int b = 0; b < 2; b++)
      for (int a = 0; a < 2; a++)
        trilinear(x8, o[0] + a * s, o[1] + b * s, o[2] + c * s, p + 3 * hex_vertex(a, b, c));
  double bc[27], dlo = INFINITY, dhi = -INFINITY;
  vm_hex_bernstein(p, bc, NULL);
  for (int i = 0; i < 27; i++) {
    dlo = fmin(dlo, bc[i]);
    dhi = fmax(dhi, bc[i]);
  }
  /* the derivative along an axis is a convex combination of the 4 edges
   * on that axis: its squared length is at most their largest */
  double fhi = 0;
  at->phi = at->psi = INFINITY;
  double sc = h > 0 ? (s * h) * (s * h) * (s * h) : 1;
  for (int ax = 0; ax < 3; ax++) {
    double big = 0;
    for (int q = 0; q < 4; q++) {
      int t[3], hd[3];
      t[ax] = 0;
      t[(ax + 1) % 3] = q & 1;
      t[(ax + 2) % 3] = q >> 1;
      memcpy(hd, t, sizeof t);
      hd[ax] = 1;
      double d[3];
      vm_sub3(p + 3 * hex_vertex(hd[0], hd[1], hd[2]), p + 3 * hex_vertex(t[0], t[1], t[2]), d);
      big = fmax(big, vm_dot3(d, d));
    }
    fhi += big;
  }
  for (int n = 0; n < 8; n++) {
    int a = n & 1, b = n >> 1 & 1, c = n >> 2;
    /* the edges from corner n along each axis: the derivatives there */
    double e[3][3], x[3];
    vm_sub3(p + 3 * hex_vertex(1, b, c), p + 3 * hex_vertex(0, b, c), e[0]);
    vm_sub3(p + 3 * hex_vertex(a, 1, c), p + 3 * hex_vertex(a, 0, c), e[1]);
    vm_sub3(p + 3 * hex_vertex(a, b, 1), p + 3 * hex_vertex(a, b, 0), e[2]);
    double f = vm_dot3(e[0], e[0]) + vm_dot3(e[1], e[1]) + vm_dot3(e[2], e[2]);
    vm_cross3(e[1], e[2], x);
    double det = vm_dot3(e[0], x);
    at->phi = fmin(at->phi, f > 0 ? det / pow(f / 3, 1.5) : -1);
    at->psi = fmin(at->psi, psi_of(det / sc));
  }
  lo->phi = dlo > 0 && fhi > 0 ? dlo / pow(fhi / 3, 1.5) : -1;
  lo->psi = psi_min_on(dlo / sc, dhi / sc);
  if (h <= 0) lo->psi = at->psi = NAN;
}

#define BOUNDS_BUDGET 20000

/* One cell: lo and hi brackets; sub-cells split while a bound is below the
 * least value found (in the cell, or H over the mesh) less rel of it. */
static int64_t cell_bounds(const double *x8, double h, double rel, int max_depth, phipsi H,
                           const phipsi root[2], phipsi *lo, phipsi *hi) {
  struct {
    double o[3], s;
    int depth;
  } stack[8 * 16 + 8];
  int top = 0;
  int64_t parts = 0;
  stack[top].o[0] = stack[top].o[1] = stack[top].o[2] = 0;
  stack[top].s = 1;
  stack[top++].depth = 0;
  lo->phi = lo->psi = hi->phi = hi->psi = INFINITY;
  int use_psi = h > 0;
  while (top > 0) {
    top--;
    double o[3] = {stack[top].o[0], stack[top].o[1], stack[top].o[2]}, s = stack[top].s;
    int depth = stack[top].depth;
    phipsi bl, ba;
    if (parts == 0) {
      bl = root[0];
      ba = root[1];
    } else
      box_eval(x8, o, s, h, &bl, &ba);
    parts++;
    hi->phi = fmin(hi->phi, ba.phi);
    if (use_psi) hi->psi = fmin(hi->psi, ba.psi);
    double tphi = fmin(hi->phi, H.phi), tpsi = use_psi ? fmin(hi->psi, H.psi) : 0;
    tphi -= rel * fabs(tphi);
    tpsi -= rel * fabs(tpsi);
    int done = bl.phi >= tphi && (!use_psi || bl.psi >= tpsi);
    if (done || depth >= max_depth || parts + top >= BOUNDS_BUDGET) {
      lo->phi = fmin(lo->phi, bl.phi);
      if (use_psi) lo->psi = fmin(lo->psi, bl.psi);
      continue;
    }
    for (int n = 0; n < 8; n++) {
      stack[top].o[0] = o[0] + (n & 1) * s / 2;
      stack[top].o[1] = o[1] + (n >> 1 & 1) * s / 2;
      stack[top].o[2] = o[2] + (n >> 2) * s / 2;
      stack[top].s = s / 2;
      stack[top++].depth = depth + 1;
    }
  }
  if (!use_psi) lo->psi = hi->psi = NAN;
  return parts;
}

int vm_mesh_hex_bounds(const vm_mesh *m, double h, double rel, int max_depth, vm_hex_bounds *out) {
  if (!m || !out) return VM_ERR_ARG;
  if (rel <= 0) rel = 0.01;
  if (max_depth <= 0) max_depth = 8;
  if (max_depth > 16) max_depth = 16;
  int nt = vm_nthreads(m->ctx);
  /* the whole cells first: the least value attained, H; each hex's
   * evaluation kept for the second pass */
  phipsi *root = vm_alloc_array(m->ctx, (size_t)m->ne * 2 + 1, sizeof *root);
  if (!root) return VM_ERR_NOMEM;
  double hphi = INFINITY, hpsi = INFINITY;
  int64_t hexes = 0;
#pragma omp parallel for num_threads(nt) schedule(static) reduction(min : hphi, hpsi) \
    reduction(+ : hexes)
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_HEX) continue;
    double x8[24], o[3] = {0, 0, 0};
    phipsi bl, ba;
    cell_coords(m, e, x8);
    box_eval(x8, o, 1, h, &bl, &ba);
    root[2 * e] = bl;
    root[2 * e + 1] = ba;
    hphi = fmin(hphi, ba.phi);
    if (h > 0) hpsi = fmin(hpsi, ba.psi);
    hexes++;
  }
  phipsi H = {hphi, hpsi};
  double lphi = INFINITY, lpsi = INFINITY, uphi = INFINITY, upsi = INFINITY;
  int64_t refined = 0, parts = 0;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 64) \
    reduction(min : lphi, lpsi, uphi, upsi) reduction(+ : refined, parts)
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_HEX) continue;
    double x8[24];
    phipsi lo, hi;
    cell_coords(m, e, x8);
    int64_t n = cell_bounds(x8, h, rel, max_depth, H, root + 2 * e, &lo, &hi);
    parts += n;
    refined += n > 1;
    lphi = fmin(lphi, lo.phi);
    uphi = fmin(uphi, hi.phi);
    if (h > 0) {
      lpsi = fmin(lpsi, lo.psi);
      upsi = fmin(upsi, hi.psi);
    }
  }
  vm_free(m->ctx, root);
  out->hexes = hexes;
  out->refined = refined;
  out->parts = parts;
  out->phi_lo = hexes ? lphi : NAN;
  out->phi_hi = hexes ? uphi : NAN;
  out->psi_lo = hexes && h > 0 ? lpsi : NAN;
  out->psi_hi = hexes && h > 0 ? upsi : NAN;
  return VM_OK;
}
