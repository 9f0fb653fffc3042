/* lib/core/src/assembly.c: F of (13)/(20), its gradient and Hessian blocks over
 * all quadrature nodes, parallel over an element colouring, with the same
 * bits for any number of threads; node statistics and determinants. */
#include <math.h>
#include <string.h>

#include "hessian_psd_private.h"
#include "inline.h"
#include "measure_private.h"
#include "problem_private.h"
#include "varmesh/jacobian.h"
#include "varmesh/problem.h"

/* Per-element accumulators: gradient and diagonal blocks by local vertex,
 * off-diagonal block diagonals by element pair (problem->pair), and (full
 * Hessian) the whole off-diagonal blocks H_ab of the pairs (a < b). */
typedef struct {
  double g[VM_MAX_ELEM_VERTS][3];
  double h[VM_MAX_ELEM_VERTS][6]; /* symmetric block: xx yy zz xy yz xz */
  double o[VM_MAX_PAIRS][3];
  double f[VM_MAX_PAIRS][9];
} elem_acc;

/* What one element's nodes need besides the rule. */
typedef struct {
  double x[VM_MAX_ELEM_VERTS][3];
  int t, nv, diag;
  const vm_qrule *R;
  const double *S, *wb;
  const double *nw; /* per-node weight factors or NULL */
  double w, g, dq;
  const double *G; /* tensor metric (6) or NULL */
  double n[3];     /* reference normal (2D elements) */
  int64_t n0;
  /* S and wb when they are computed at evaluation (problem.c) */
  double Sbuf[VM_QRULE_MAX_NODES * 9], wbuf[VM_QRULE_MAX_NODES];
} elem_ctx;

static void elem_setup(const vm_problem *p, int64_t i, const double *xyz, elem_ctx *ec) {
  const vm_mesh *m = p->m;
  int32_t e = p->ael[i];
  int t = m->etype[e];
  const int32_t *cv = m->conn + m->eoff[e];
  int nv = (int)(m->eoff[e + 1] - m->eoff[e]);
  ec->t = t;
  ec->nv = nv;
  ec->R = p->qr[t];
  ec->n0 = p->noff[i];
  int dd = p->tdim * p->tdim;
  if (p->wsum) {
    double fdet; /* checked when they were set (compute_targets) */
    (void)vm_problem_elem_targets(p, i, ec->Sbuf, ec->wbuf, &fdet);
    ec->S = ec->Sbuf;
    ec->wb = ec->wbuf;
  } else {
    ec->S = p->Snode ? p->Snode + dd * ec->n0 : p->Sid[t];
    ec->wb = p->wnode ? p->wnode + ec->n0 : p->wid[t];
  }
  ec->diag = p->tgt == VM_TGT_IDEAL && p->sdiag[t];
  ec->nw = p->node_w ? p->node_w + ec->n0 : NULL;
  ec->w = p->wel[i];
  ec->g = p->metric == VM_METRIC_SCALAR ? p->mg[i] : 1.0;
  ec->dq = p->metric == VM_METRIC_IDENTITY ? 1.0 : p->mdq[i];
  ec->G = p->metric == VM_METRIC_TENSOR ? p->mG + 6 * i : NULL;
  if (p->kind == VM_PK_SURF) {
    ec->n[0] = p->nrm[3 * i];
    ec->n[1] = p->nrm[3 * i + 1];
    ec->n[2] = p->nrm[3 * i + 2];
  } else {
    ec->n[0] = ec->n[1] = 0;
    ec->n[2] = 1;
  }
  for (int a = 0; a < nv; a++) {
    const double *s = xyz + 3 * (int64_t)cv[a];
    ec->x[a][0] = s[0];
    ec->x[a][1] = s[1];
    ec->x[a][2] = p->kind == VM_PK_PLANE ? 0 : s[2];
  }
}

/* y = G v for the symmetric G = (xx yy zz xy yz xz). */
VM_INLINE void symv(const double *G, const double *v, double *y) {
  y[0] = G[0] * v[0] + G[3] * v[1] + G[5] * v[2];
  y[1] = G[3] * v[0] + G[1] * v[1] + G[4] * v[2];
  y[2] = G[5] * v[0] + G[4] * v[1] + G[2] * v[2];
}

/* Invariants of one 3D node: M = E S, C = Q M, s = |C|^2 = tr(M^T G M),
 * det C = det Q det M; cof M (all of it when full, else row 0); G M. */
typedef struct {
  double M[9], cof[9], GM[9];
  double s, det;
} node3;

VM_INLINE void node3_eval(const elem_ctx *ec, const vm_qnode *q, const double *S, int diag,
                          int full, node3 *v) {
  const double *h0 = ec->x[q->head[0]], *t0 = ec->x[q->tail[0]];
  const double *h1 = ec->x[q->head[1]], *t1 = ec->x[q->tail[1]];
  const double *h2 = ec->x[q->head[2]], *t2 = ec->x[q->tail[2]];
  double E[9] = {h0[0] - t0[0], h1[0] - t1[0], h2[0] - t2[0], h0[1] - t0[1], h1[1] - t1[1],
                 h2[1] - t2[1], h0[2] - t0[2], h1[2] - t1[2], h2[2] - t2[2]};
  double *M = v->M, *c = v->cof;
  if (diag) {
    /* S diagonal (ideal hexes): the products with its zeros dropped */
    for (int r = 0; r < 3; r++) {
      M[3 * r] = E[3 * r] * S[0];
      M[3 * r + 1] = E[3 * r + 1] * S[4];
      M[3 * r + 2] = E[3 * r + 2] * S[8];
    }
  } else {
    for (int r = 0; r < 3; r++)
      for (int l = 0; l < 3; l++)
        M[3 * r + l] = E[3 * r] * S[l] + E[3 * r + 1] * S[3 + l] + E[3 * r + 2] * S[6 + l];
  }
  c[0] = M[4] * M[8] - M[5] * M[7];
  c[1] = M[5] * M[6] - M[3] * M[8];
  c[2] = M[3] * M[7] - M[4] * M[6];
  if (full) {
    c[3] = M[7] * M[2] - M[8] * M[1];
    c[4] = M[8] * M[0] - M[6] * M[2];
    c[5] = M[6] * M[1] - M[7] * M[0];
    c[6] = M[1] * M[5] - M[2] * M[4];
    c[7] = M[2] * M[3] - M[0] * M[5];
    c[8] = M[0] * M[4] - M[1] * M[3];
  }
  double s;
  if (ec->G) {
    s = 0;
    for (int l = 0; l < 3; l++) {
      double col[3] = {M[l], M[3 + l], M[6 + l]}, y[3];
      symv(ec->G, col, y);
      v->GM[l] = y[0];
      v->GM[3 + l] = y[1];
      v->GM[6 + l] = y[2];
    }
    for (int k = 0; k < 9; k++) s += M[k] * v->GM[k];
  } else {
    s = ((M[0] * M[0] + M[1] * M[1] + M[2] * M[2]) + (M[3] * M[3] + M[4] * M[4] + M[5] * M[5]) +
         (M[6] * M[6] + M[7] * M[7] + M[8] * M[8])) *
        ec->g;
  }
  v->s = s;
  v->det = ec->dq * (M[0] * c[0] + M[1] * c[1] + M[2] * c[2]);
}

/* Invariants of one 2D node: M = E S (3 x 2, columns m0, m1),
 * det = det Q n.(m0 x m1), s = tr(M^T G M); B = d det/dM (columns). */
typedef struct {
  double m[2][3], GM[2][3], B[2][3];
  double s, det;
} node2;

VM_INLINE void cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

VM_INLINE void node2_eval(const elem_ctx *ec, const vm_qnode *q, const double *S, int full,
                          node2 *v) {
  double e[2][3];
  for (int k = 0; k < 2; k++)
    for (int r = 0; r < 3; r++) e[k][r] = ec->x[q->head[k]][r] - ec->x[q->tail[k]][r];
  for (int l = 0; l < 2; l++)
    for (int r = 0; r < 3; r++) v->m[l][r] = e[0][r] * S[l] + e[1][r] * S[2 + l];
  double c[3];
  cross(v->m[0], v->m[1], c);
  const double *n = ec->n;
  double s = 0;
  if (ec->G) {
    symv(ec->G, v->m[0], v->GM[0]);
    symv(ec->G, v->m[1], v->GM[1]);
    for (int l = 0; l < 2; l++)
      for (int r = 0; r < 3; r++) s += v->m[l][r] * v->GM[l][r];
  } else {
    for (int l = 0; l < 2; l++)
      for (int r = 0; r < 3; r++) s += v->m[l][r] * v->m[l][r];
    s *= ec->g;
  }
  v->s = s;
  v->det = ec->dq * (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]);
  if (full) {
    /* d/dm0 n.(m0 x m1) = m1 x n, d/dm1 = n x m0 */
    double b0[3], b1[3];
    cross(v->m[1], n, b0);
    cross(n, v->m[0], b1);
    for (int r = 0; r < 3; r++) {
      v->B[0][r] = ec->dq * b0[r];
      v->B[1][r] = ec->dq * b1[r];
    }
  }
}

static inline const vm_measure_params *node_params(const vm_problem *p, int64_t node,
                                                   vm_measure_params *tmp) {
  if (!p->eps_node) return &p->prm;
  *tmp = p->prm;
  tmp->eps = p->eps_node[node];
  return tmp;
}

/* Hessian pieces of one node, both dimensions: for the node's local
 * vertices u, gs_u = (ds/dM) b_u and gd_u = (d det/dM) b_u with
 * b_u = S^T a_u; the d2 det/dM2 term has a zero diagonal in every block
 * H_uv and vanishes for u = v, so it never enters hdiag or hoff. */
VM_INLINE void node_hess(const vm_nodepat *pt, int d, double gs[6][3], double gd[6][3],
                         double b[6][3], const double *f, double wq, double g, const double *G,
                         int offd, elem_acc *acc) {
  double al = wq * f[3], be = wq * f[4], ga = wq * f[5], fs2 = 2 * wq * f[1];
  double Gd[6];
  if (G) {
    for (int c = 0; c < 6; c++) Gd[c] = G[c];
  } else {
    Gd[0] = Gd[1] = Gd[2] = g;
    Gd[3] = Gd[4] = Gd[5] = 0;
  }
  double u1[6][3], u2[6][3];
  for (int u = 0; u < pt->nloc; u++) {
    for (int r = 0; r < 3; r++) {
      u1[u][r] = al * gs[u][r] + be * gd[u][r];
      u2[u][r] = be * gs[u][r] + ga * gd[u][r];
    }
    double kuu = 0;
    for (int l = 0; l < d; l++) kuu += b[u][l] * b[u][l];
    kuu *= fs2;
    double *h = acc->h[pt->loc[u]];
    h[0] += u1[u][0] * gs[u][0] + u2[u][0] * gd[u][0] + kuu * Gd[0];
    h[1] += u1[u][1] * gs[u][1] + u2[u][1] * gd[u][1] + kuu * Gd[1];
    h[2] += u1[u][2] * gs[u][2] + u2[u][2] * gd[u][2] + kuu * Gd[2];
    h[3] += u1[u][0] * gs[u][1] + u2[u][0] * gd[u][1] + kuu * Gd[3];
    h[4] += u1[u][1] * gs[u][2] + u2[u][1] * gd[u][2] + kuu * Gd[4];
    h[5] += u1[u][0] * gs[u][2] + u2[u][0] * gd[u][2] + kuu * Gd[5];
  }
  if (!offd) return; /* the explicit minimizer: diagonal blocks only */
  int k = 0;
  for (int u = 0; u < pt->nloc; u++)
    for (int v = u + 1; v < pt->nloc; v++, k++) {
      double kuv = 0;
      for (int l = 0; l < d; l++) kuv += b[u][l] * b[v][l];
      kuv *= fs2;
      double *o = acc->o[pt->pidx[k]];
      for (int r = 0; r < 3; r++) o[r] += u1[u][r] * gs[v][r] + u2[u][r] * gd[v][r] + kuv * Gd[r];
    }
}

/* b_u = S^T a_u for the node's local vertices. */
VM_INLINE void node_b(const vm_nodepat *pt, int d, const double *S, double b[6][3]) {
  for (int u = 0; u < pt->nloc; u++) {
    const double *a = pt->ad[u];
    if (d == 3) {
      b[u][0] = a[0] * S[0] + a[1] * S[3] + a[2] * S[6];
      b[u][1] = a[0] * S[1] + a[1] * S[4] + a[2] * S[7];
      b[u][2] = a[0] * S[2] + a[1] * S[5] + a[2] * S[8];
    } else {
      b[u][0] = a[0] * S[0] + a[1] * S[2];
      b[u][1] = a[0] * S[1] + a[1] * S[3];
    }
  }
}

/* The full Hessian of one node (order 3): diagonal blocks into acc->h,
 * whole off-diagonal blocks into acc->f (oriented as the element pair,
 * a < b), from gs, gd, b as node_hess (b[u][2] = 0 in 2D), the metric Gm
 * (3x3), Kd for the d2 det term (H_uv gets [w]_x with w = Kd (b_u x b_v):
 * Kd = w f_d det Q M in 3D; in 2D column 2 holds w f_d det Q n and the
 * rest is 0) and nneg rank-1 PSD corrections hn[k][u] (scaled by
 * sqrt(w |lambda_k|)). */
VM_INLINE void node_hess_full(const vm_nodepat *pt, double gs[6][3], double gd[6][3],
                              double b[6][3], const double *f, double wq, const double *Gm,
                              const double *Kd, int nneg, double hn[9][6][3], elem_acc *acc) {
  double al = wq * f[3], be = wq * f[4], ga = wq * f[5], fs2 = 2 * wq * f[1];
  double u1[6][3], u2[6][3];
  for (int u = 0; u < pt->nloc; u++) {
    for (int r = 0; r < 3; r++) {
      u1[u][r] = al * gs[u][r] + be * gd[u][r];
      u2[u][r] = be * gs[u][r] + ga * gd[u][r];
    }
    double kuu = fs2 * (b[u][0] * b[u][0] + b[u][1] * b[u][1] + b[u][2] * b[u][2]);
    double H[9];
    for (int r = 0; r < 3; r++)
      for (int q = r; q < 3; q++) {
        double a = u1[u][r] * gs[u][q] + u2[u][r] * gd[u][q] + kuu * Gm[3 * r + q];
        for (int k = 0; k < nneg; k++) a += hn[k][u][r] * hn[k][u][q];
        H[3 * r + q] = a;
      }
    double *h = acc->h[pt->loc[u]];
    h[0] += H[0];
    h[1] += H[4];
    h[2] += H[8];
    h[3] += H[1];
    h[4] += H[5];
    h[5] += H[2];
  }
  int k = 0;
  for (int u = 0; u < pt->nloc; u++)
    for (int v = u + 1; v < pt->nloc; v++, k++) {
      const double *bu = b[u], *bv = b[v];
      double kuv = fs2 * (bu[0] * bv[0] + bu[1] * bv[1] + bu[2] * bv[2]);
      double c[3] = {bu[1] * bv[2] - bu[2] * bv[1], bu[2] * bv[0] - bu[0] * bv[2],
                     bu[0] * bv[1] - bu[1] * bv[0]};
      double w[3];
      for (int r = 0; r < 3; r++)
        w[r] = Kd[3 * r] * c[0] + Kd[3 * r + 1] * c[1] + Kd[3 * r + 2] * c[2];
      double K[9] = {0, w[2], -w[1], -w[2], 0, w[0], w[1], -w[0], 0};
      double H[9];
      for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) {
          double a = u1[u][r] * gs[v][q] + u2[u][r] * gd[v][q] + kuv * Gm[3 * r + q] + K[3 * r + q];
          for (int n = 0; n < nneg; n++) a += hn[n][u][r] * hn[n][v][q];
          H[3 * r + q] = a;
        }
      double *o = acc->f[pt->pidx[k]];
      if (pt->loc[u] < pt->loc[v]) {
        for (int e = 0; e < 9; e++) o[e] += H[e];
      } else {
        for (int r = 0; r < 3; r++)
          for (int q = 0; q < 3; q++) o[3 * r + q] += H[3 * q + r];
      }
    }
}

/* The metric as a full 3x3 matrix. */
static inline void metric_full(const elem_ctx *ec, double Gm[9]) {
  if (ec->G) {
    const double *G = ec->G;
    double t[9] = {G[0], G[3], G[5], G[3], G[1], G[4], G[5], G[4], G[2]};
    memcpy(Gm, t, sizeof t);
  } else {
    for (int k = 0; k < 9; k++) Gm[k] = k % 4 == 0 ? ec->g : 0;
  }
}

/* Q with Q^T Q = G_x (upper triangular: the transposed Cholesky factor;
 * sqrt(g) I for a scalar metric), so C = Q M. */
static inline void metric_root(const elem_ctx *ec, double Q[9]) {
  memset(Q, 0, 9 * sizeof *Q);
  if (ec->G) {
    const double *G = ec->G;
    double l00 = sqrt(G[0]), l10 = G[3] / l00, l20 = G[5] / l00;
    double l11 = sqrt(fmax(G[1] - l10 * l10, 0));
    double l21 = l11 > 0 ? (G[4] - l20 * l10) / l11 : 0;
    double l22 = sqrt(fmax(G[2] - l20 * l20 - l21 * l21, 0));
    Q[0] = l00;
    Q[1] = l10;
    Q[2] = l20;
    Q[4] = l11;
    Q[5] = l21;
    Q[8] = l22;
  } else {
    double r = sqrt(ec->g);
    Q[0] = Q[4] = Q[8] = r;
  }
}

/* One 3D element: F contribution into *Fe; with order >= 1 the gradient,
 * with order 2 the Hessian pieces, into acc. Nonzero if a node is outside
 * the measure's domain. `order` and `diag` are constants in each caller.
 * All nodes' invariants and measure values come first, so the latencies of
 * the measure's roots and divisions overlap; then the derivative work. */
VM_INLINE int elem3(const vm_problem *p, const elem_ctx *ec, int order, int diag, int psd, int offd,
                    double *Fe, elem_acc *acc) {
  const vm_qrule *R = ec->R;
  const vm_nodepat *pats = p->pat[ec->t];
  vm_measure_scalar_fn scalar = p->ops->scalar;
  /* the balanced measure (the prism stage's, and the default) inlined */
  int bal = p->ops == &vm_measure_balanced_ops;
  int nn = R->nnodes;
  double F = 0;
  node3 nv[VM_QRULE_MAX_NODES];
  double fv[VM_QRULE_MAX_NODES][6];
  for (int j = 0; j < nn; j++) {
    if (ec->nw && ec->nw[j] == 0) continue; /* left out */
    node3 *v = order ? &nv[j] : &nv[0];
    double *f = order ? fv[j] : fv[0];
    node3_eval(ec, &R->nodes[j], ec->S + 9 * j, diag, order > 0, v);
    vm_measure_params tmp;
    const vm_measure_params *prm = node_params(p, ec->n0 + j, &tmp);
    if (bal ? vm_balanced_scalar(prm, 3, v->s, v->det, order, f)
            : scalar(prm, 3, v->s, v->det, order, f))
      return 1;
    F += ec->w * ec->wb[j] * (ec->nw ? ec->nw[j] : 1.0) * f[0];
  }
  *Fe = F;
  if (!order) return 0;
  for (int j = 0; j < nn; j++) {
    const double *S = ec->S + 9 * j, *f = fv[j];
    if (ec->nw && ec->nw[j] == 0) continue;
    const node3 *v = &nv[j];
    double wq = ec->w * ec->wb[j] * (ec->nw ? ec->nw[j] : 1.0);
    /* dW/dM = 2 f_s G M + f_d det Q cof M; dW/dE = (dW/dM) S^T */
    const double *A = ec->G ? v->GM : v->M;
    double cs = 2 * wq * f[1] * (ec->G ? 1.0 : ec->g), cd = wq * f[2] * ec->dq;
    double P[9], Rm[9];
    for (int k = 0; k < 9; k++) P[k] = cs * A[k] + cd * v->cof[k];
    if (diag) {
      for (int r = 0; r < 3; r++) {
        Rm[3 * r] = P[3 * r] * S[0];
        Rm[3 * r + 1] = P[3 * r + 1] * S[4];
        Rm[3 * r + 2] = P[3 * r + 2] * S[8];
      }
    } else {
      for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++)
          Rm[3 * r + k] =
              P[3 * r] * S[3 * k] + P[3 * r + 1] * S[3 * k + 1] + P[3 * r + 2] * S[3 * k + 2];
    }
    /* vertex u gets sum_k a_uk (dW/dE)_k, one update per vertex */
    const vm_nodepat *pt = &pats[j];
    for (int u = 0; u < pt->nloc; u++) {
      const double *a = pt->ad[u];
      double *gu = acc->g[pt->loc[u]];
      gu[0] += a[0] * Rm[0] + a[1] * Rm[1] + a[2] * Rm[2];
      gu[1] += a[0] * Rm[3] + a[1] * Rm[4] + a[2] * Rm[5];
      gu[2] += a[0] * Rm[6] + a[1] * Rm[7] + a[2] * Rm[8];
    }
    if (order < 2) continue;
    double b[6][3], gs[6][3], gd[6][3];
    node_b(pt, 3, S, b);
    double a2 = ec->G ? 2.0 : 2.0 * ec->g;
    for (int u = 0; u < pt->nloc; u++)
      for (int r = 0; r < 3; r++) {
        gs[u][r] = a2 * (A[3 * r] * b[u][0] + A[3 * r + 1] * b[u][1] + A[3 * r + 2] * b[u][2]);
        gd[u][r] = ec->dq * (v->cof[3 * r] * b[u][0] + v->cof[3 * r + 1] * b[u][1] +
                             v->cof[3 * r + 2] * b[u][2]);
      }
    if (order < 3) {
      node_hess(pt, 3, gs, gd, b, f, wq, ec->g, ec->G, offd, acc);
      continue;
    }
    double Gm[9], Kd[9], hn[9][6][3];
    metric_full(ec, Gm);
    double kd = wq * f[2] * ec->dq;
    for (int k = 0; k < 9; k++) Kd[k] = kd * v->M[k];
    int nneg = 0;
    if (psd) {
      /* C = Q M; a negative direction D of d2W/dC2 is Q^T D in M */
      double Q[9], C[9], lam[9], D[9][9];
      int ident = !ec->G && ec->g == 1.0;
      if (ident) {
        memcpy(C, v->M, sizeof C);
      } else {
        metric_root(ec, Q);
        for (int r = 0; r < 3; r++)
          for (int l = 0; l < 3; l++)
            C[3 * r + l] =
                Q[3 * r] * v->M[l] + Q[3 * r + 1] * v->M[3 + l] + Q[3 * r + 2] * v->M[6 + l];
      }
      nneg = vm_psd_negative3(C, f, lam, D);
      for (int k = 0; k < nneg; k++) {
        double mk[9], sc = sqrt(wq * -lam[k]);
        if (ident) {
          for (int e = 0; e < 9; e++) mk[e] = sc * D[k][e];
        } else {
          for (int r = 0; r < 3; r++)
            for (int l = 0; l < 3; l++)
              mk[3 * r + l] =
                  sc * (Q[r] * D[k][l] + Q[3 + r] * D[k][3 + l] + Q[6 + r] * D[k][6 + l]);
        }
        for (int u = 0; u < pt->nloc; u++)
          for (int r = 0; r < 3; r++)
            hn[k][u][r] = mk[3 * r] * b[u][0] + mk[3 * r + 1] * b[u][1] + mk[3 * r + 2] * b[u][2];
      }
    }
    node_hess_full(pt, gs, gd, b, f, wq, Gm, Kd, nneg, hn, acc);
  }
  return 0;
}

/* One 2D element (plane or surface), as elem3. */
VM_INLINE int elem2(const vm_problem *p, const elem_ctx *ec, int order, int psd, double *Fe,
                    elem_acc *acc) {
  const vm_qrule *R = ec->R;
  const vm_nodepat *pats = p->pat[ec->t];
  int bal = p->ops == &vm_measure_balanced_ops; /* inlined, as in elem3 */
  double F = 0;
  for (int j = 0; j < R->nnodes; j++) {
    if (ec->nw && ec->nw[j] == 0) continue; /* left out */
    const vm_qnode *q = &R->nodes[j];
    const double *S = ec->S + 4 * j;
    node2 v;
    node2_eval(ec, q, S, order > 0, &v);
    vm_measure_params tmp;
    double f[6];
    const vm_measure_params *prm = node_params(p, ec->n0 + j, &tmp);
    if (bal ? vm_balanced_scalar(prm, 2, v.s, v.det, order, f)
            : p->ops->scalar(prm, 2, v.s, v.det, order, f))
      return 1;
    double wq = ec->w * ec->wb[j] * (ec->nw ? ec->nw[j] : 1.0);
    F += wq * f[0];
    if (!order) continue;
    double(*A)[3] = ec->G ? v.GM : v.m;
    double cs = 2 * wq * f[1] * (ec->G ? 1.0 : ec->g), cd = wq * f[2];
    double P[2][3];
    for (int l = 0; l < 2; l++)
      for (int r = 0; r < 3; r++) P[l][r] = cs * A[l][r] + cd * v.B[l][r];
    double Rm[2][3];
    for (int k = 0; k < 2; k++)
      for (int r = 0; r < 3; r++) Rm[k][r] = P[0][r] * S[2 * k] + P[1][r] * S[2 * k + 1];
    const vm_nodepat *pt = &pats[j];
    for (int u = 0; u < pt->nloc; u++) {
      const double *a = pt->ad[u];
      double *gu = acc->g[pt->loc[u]];
      for (int r = 0; r < 3; r++) gu[r] += a[0] * Rm[0][r] + a[1] * Rm[1][r];
    }
    if (order < 2) continue;
    double b[6][3], gs[6][3], gd[6][3];
    node_b(pt, 2, S, b);
    double a2 = ec->G ? 2.0 : 2.0 * ec->g;
    for (int u = 0; u < pt->nloc; u++)
      for (int r = 0; r < 3; r++) {
        gs[u][r] = a2 * (A[0][r] * b[u][0] + A[1][r] * b[u][1]);
        gd[u][r] = v.B[0][r] * b[u][0] + v.B[1][r] * b[u][1];
      }
    if (order < 3) {
      node_hess(pt, 2, gs, gd, b, f, wq, ec->g, ec->G, 1, acc);
      continue;
    }
    for (int u = 0; u < pt->nloc; u++) b[u][2] = 0;
    double Gm[9], Kd[9] = {0}, hn[9][6][3];
    metric_full(ec, Gm);
    double kd = wq * f[2] * ec->dq;
    for (int r = 0; r < 3; r++) Kd[3 * r + 2] = kd * ec->n[r];
    int nneg = 0;
    if (psd) {
      /* the 6x6 Hessian of W in M (index 3 l + r: column l, row r) */
      double H6[36], lam[9], D[9][9], sM[2][3];
      for (int l = 0; l < 2; l++)
        for (int r = 0; r < 3; r++) sM[l][r] = a2 * A[l][r];
      for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) {
          int l = i / 3, r = i % 3, l2 = j / 3, r2 = j % 3;
          double gsi = sM[l][r], gsj = sM[l2][r2], gdi = v.B[l][r], gdj = v.B[l2][r2];
          double h = f[3] * gsi * gsj + f[4] * (gsi * gdj + gdi * gsj) + f[5] * gdi * gdj;
          if (l == l2) h += 2 * f[1] * Gm[3 * r + r2];
          if (l != l2 && r != r2) {
            /* f_d det Q eps_{r r2 a} n_a, sign by the column order */
            int a = 3 - r - r2;
            double e = ((r2 - r + 3) % 3 == 1 ? 1.0 : -1.0) * ec->n[a] * ec->dq * f[2];
            h += l == 0 ? e : -e;
          }
          H6[6 * i + j] = h;
        }
      nneg = vm_psd_negative_dense(6, H6, lam, D);
      for (int k = 0; k < nneg; k++) {
        double sc = sqrt(wq * -lam[k]);
        for (int u = 0; u < pt->nloc; u++)
          for (int r = 0; r < 3; r++)
            hn[k][u][r] = sc * (D[k][r] * b[u][0] + D[k][3 + r] * b[u][1]);
      }
    }
    node_hess_full(pt, gs, gd, b, f, wq, Gm, Kd, nneg, hn, acc);
  }
  *Fe = F;
  return 0;
}

/* The element kernels specialized by order (and diagonal S in 3D);
 * order 3: full Hessian blocks, order 4: the same projected to PSD. */
static int elem3_o0(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return ec->diag ? elem3(p, ec, 0, 1, 0, 0, Fe, acc) : elem3(p, ec, 0, 0, 0, 0, Fe, acc);
}
static int elem3_o1(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return ec->diag ? elem3(p, ec, 1, 1, 0, 0, Fe, acc) : elem3(p, ec, 1, 0, 0, 0, Fe, acc);
}
static int elem3_o2(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem3(p, ec, 2, 0, 0, 1, Fe, acc);
}
/* order 2 without the off-diagonal entries (no hoff wanted: the explicit
 * minimizer), a third less work per node */
static int elem3_o2d(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem3(p, ec, 2, 0, 0, 0, Fe, acc);
}
static int elem3_o3(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem3(p, ec, 3, 0, 0, 1, Fe, acc);
}
static int elem3_o4(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem3(p, ec, 3, 0, 1, 1, Fe, acc);
}
static int elem2_o0(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem2(p, ec, 0, 0, Fe, acc);
}
static int elem2_o1(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem2(p, ec, 1, 0, Fe, acc);
}
static int elem2_o2(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem2(p, ec, 2, 0, Fe, acc);
}
static int elem2_o3(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem2(p, ec, 3, 0, Fe, acc);
}
static int elem2_o4(const vm_problem *p, const elem_ctx *ec, double *Fe, elem_acc *acc) {
  return elem2(p, ec, 3, 1, Fe, acc);
}

/* Element i's F into *Fe and, by order, its derivatives into acc; offd:
 * with order 2, the off-diagonal entries too (only hoff reads them). */
/* The Bernstein term of hex i (vm_problem_set_bernstein) added to *Fe and
 * acc: sum_c w / chi_eps(s b_c) (w: the element's weight times the mean
 * node weight of its rule times bern_w), its gradient, and the Gauss-Newton part
 * of its Hessian, (1/chi)'' grad b grad b^T (the part with the Hessian of
 * b, which is indefinite, is dropped). Returns 1 outside the domain (eps 0
 * and a coefficient <= 0). */
static int bern_term(const vm_problem *p, int64_t i, const elem_ctx *ec, int order, int offd,
                     double *Fe, elem_acc *acc) {
  double x[24], b[27], G[27 * 24];
  for (int a = 0; a < 8; a++)
    for (int r = 0; r < 3; r++) x[3 * a + r] = ec->x[a][r];
  vm_hex_bernstein(x, b, order ? G : NULL);
  /* each coefficient weighs what an average node of the rule does */
  double wb = 0;
  for (int j = 0; j < ec->R->nnodes; j++) wb += ec->wb[j];
  double wq = ec->w * p->bern_w[i] * wb / ec->R->nnodes, sc = p->bern_scale, F = 0;
  int np = p->npair[VM_HEX];
  /* pairs of vertices the rule does not couple (a corner rule's body
   * diagonals): their blocks are lumped onto the two diagonal blocks
   * (|u_r| sum_t |v_t| on entry r r), which keeps the sum positive
   * semidefinite */
  signed char coupled[8][8];
  memset(coupled, 0, sizeof coupled);
  for (int k = 0; k < np; k++) coupled[p->pair[VM_HEX][k][0]][p->pair[VM_HEX][k][1]] = 1;
  for (int c = 0; c < 27; c++) {
    double eps = p->bern_eps ? p->bern_eps[27 * i + c] : p->prm.eps;
    double d = sc * b[c], q = sqrt(eps * eps + d * d);
    /* (14), in the conjugate form for d < 0 */
    double chi = d >= 0 ? 0.5 * (d + q) : 0.5 * eps * eps / (q - d);
    if (!(chi > 0) || !(chi < INFINITY)) return 1;
    double r = 1 / chi;
    F += wq * r;
    if (!order) continue;
    double r1 = -wq * r / q * sc, r2 = wq * 2 / (q * q * q) * sc * sc;
    const double *g = G + 24 * c;
    for (int a = 0; a < 8; a++)
      for (int k = 0; k < 3; k++) acc->g[a][k] += r1 * g[3 * a + k];
    if (order < 2) continue;
    for (int a = 0; a < 8; a++) {
      const double *u = g + 3 * a;
      double *h = acc->h[a];
      h[0] += r2 * u[0] * u[0];
      h[1] += r2 * u[1] * u[1];
      h[2] += r2 * u[2] * u[2];
      h[3] += r2 * u[0] * u[1];
      h[4] += r2 * u[1] * u[2];
      h[5] += r2 * u[0] * u[2];
    }
    for (int a = 0; a < 8; a++)
      for (int a2 = a + 1; a2 < 8; a2++) {
        if (coupled[a][a2]) continue;
        const double *u = g + 3 * a, *v = g + 3 * a2;
        double su = fabs(u[0]) + fabs(u[1]) + fabs(u[2]), sv = fabs(v[0]) + fabs(v[1]) + fabs(v[2]);
        for (int r = 0; r < 3; r++) {
          acc->h[a][r] += r2 * fabs(u[r]) * sv;
          acc->h[a2][r] += r2 * fabs(v[r]) * su;
        }
      }
    if (order == 2 && !offd) continue;
    for (int k = 0; k < np; k++) {
      const double *u = g + 3 * p->pair[VM_HEX][k][0], *v = g + 3 * p->pair[VM_HEX][k][1];
      if (order == 2) {
        for (int r = 0; r < 3; r++) acc->o[k][r] += r2 * u[r] * v[r];
      } else {
        for (int r = 0; r < 3; r++)
          for (int t = 0; t < 3; t++) acc->f[k][3 * r + t] += r2 * u[r] * v[t];
      }
    }
  }
  *Fe += F;
  return 0;
}

static int elem_kernel(const vm_problem *p, const elem_ctx *ec, int order, int offd, double *Fe,
                       elem_acc *acc);

static int elem_eval(const vm_problem *p, int64_t i, const double *x, int order, int offd,
                     double *Fe, elem_acc *acc) {
  elem_ctx ec;
  elem_setup(p, i, x, &ec);
  if (order) {
    memset(acc->g, 0, sizeof acc->g[0] * (size_t)ec.nv);
    if (order > 1) {
      memset(acc->h, 0, sizeof acc->h[0] * (size_t)ec.nv);
      if (order == 2) {
        /* (2D elements always accumulate them) */
        if (offd || p->tdim != 3) memset(acc->o, 0, sizeof acc->o[0] * (size_t)p->npair[ec.t]);
      } else
        memset(acc->f, 0, sizeof acc->f[0] * (size_t)p->npair[ec.t]);
    }
  }
  if (elem_kernel(p, &ec, order, offd, Fe, acc)) return 1;
  if (p->bern_w && p->bern_w[i] > 0 && ec.t == VM_HEX)
    return bern_term(p, i, &ec, order, offd, Fe, acc);
  return 0;
}

/* Are all of active element i's vertices fixed (the mesh's vflag)? */
static int elem_all_fixed(const vm_problem *p, int64_t i) {
  const vm_mesh *m = p->m;
  if (!m->vflag) return 0;
  int32_t e = p->ael[i];
  for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++)
    if (m->vflag[m->conn[k]] != VM_VERTEX_FIXED) return 0;
  return 1;
}

/* The kept nodes' values dropped (the rule changed, or no memory). */
static void fix_sd_drop(vm_problem *p) {
  vm_free(p->ctx, p->fix_noff);
  vm_free(p->ctx, p->fix_sd);
  vm_free(p->ctx, p->fix_sgen);
  p->fix_noff = NULL;
  p->fix_sd = NULL;
  p->fix_sgen = NULL;
  p->fix_sd_rule = -1;
}

void vm_problem_fix_free(vm_problem *p) {
  fix_sd_drop(p);
  vm_free(p->ctx, p->fix_of);
  vm_free(p->ctx, p->fix_x);
  vm_free(p->ctx, p->fix_F);
  vm_free(p->ctx, p->fix_gen);
  p->fix_of = NULL;
  p->fix_x = p->fix_F = NULL;
  p->fix_gen = NULL;
  p->nslot = 0;
}

/* The slots of the cache of all-fixed elements' F (problem_private.h),
 * assigned once, at the first evaluation, to the elements all-fixed then;
 * without memory for them there is no cache (the same values, computed). */
static void fix_build(vm_problem *p) {
  if (p->fix_built) return;
  p->fix_built = 1;
  int64_t n = 0;
  for (int64_t i = 0; i < p->nae; i++) n += elem_all_fixed(p, i);
  if (!n) return;
  vm_ctx *ctx = p->ctx;
  p->fix_of = vm_alloc_array(ctx, (size_t)p->nae, sizeof *p->fix_of);
  p->fix_x = vm_calloc(ctx, (size_t)n * 3 * VM_MAX_ELEM_VERTS, sizeof *p->fix_x);
  p->fix_F = vm_alloc_array(ctx, (size_t)n, sizeof *p->fix_F);
  p->fix_gen = vm_calloc(ctx, (size_t)n, sizeof *p->fix_gen);
  if (!p->fix_of || !p->fix_x || !p->fix_F || !p->fix_gen) {
    vm_problem_fix_free(p);
    return;
  }
  int64_t k = 0;
  for (int64_t i = 0; i < p->nae; i++) p->fix_of[i] = elem_all_fixed(p, i) ? (int32_t)k++ : -1;
  p->nslot = n;
}

/* Are active element i's vertices (slot `slot`) where the slot's values
 * were computed, bit for bit? If not, they are recorded there and both
 * kept values dropped. */
static int fix_at(vm_problem *p, int64_t i, int32_t slot, const double *x) {
  const vm_mesh *m = p->m;
  int32_t e = p->ael[i];
  const int32_t *cv = m->conn + m->eoff[e];
  int nv = (int)(m->eoff[e + 1] - m->eoff[e]);
  double *cx = p->fix_x + (int64_t)slot * 3 * VM_MAX_ELEM_VERTS;
  int same = 1;
  for (int a = 0; a < nv && same; a++)
    same = memcmp(cx + 3 * a, x + 3 * (int64_t)cv[a], 3 * sizeof *x) == 0;
  if (same) return 1;
  for (int a = 0; a < nv; a++) memcpy(cx + 3 * a, x + 3 * (int64_t)cv[a], 3 * sizeof *x);
  p->fix_gen[slot] = 0;
  if (p->fix_sgen) p->fix_sgen[slot] = 0;
  return 0;
}

/* F of active element i, which has cache slot `slot`, at x: the cached
 * value when it is for the problem's present state and the element's
 * vertices are where they were (bit for bit), else evaluated and kept.
 * Each element is read and written by one thread only. */
static int fix_value(vm_problem *p, int64_t i, int32_t slot, const double *x, double *Fe) {
  if (fix_at(p, i, slot, x) && p->fix_gen[slot] == p->gen) {
    *Fe = p->fix_F[slot];
    return 0;
  }
  if (elem_eval(p, i, x, 0, 0, Fe, NULL)) return 1;
  p->fix_F[slot] = *Fe;
  p->fix_gen[slot] = p->gen;
  return 0;
}

/* F of active element i at x, through the cache for all-fixed elements. */
static int elem_value(vm_problem *p, int64_t i, const double *x, double *Fe) {
  int32_t slot = p->fix_of ? p->fix_of[i] : -1;
  return slot >= 0 ? fix_value(p, i, slot, x, Fe) : elem_eval(p, i, x, 0, 0, Fe, NULL);
}

static int elem_kernel(const vm_problem *p, const elem_ctx *ec, int order, int offd, double *Fe,
                       elem_acc *acc) {
  if (p->tdim == 3) {
    switch (order) {
    case 0: return elem3_o0(p, ec, Fe, acc);
    case 1: return elem3_o1(p, ec, Fe, acc);
    case 2: return offd ? elem3_o2(p, ec, Fe, acc) : elem3_o2d(p, ec, Fe, acc);
    case 3: return elem3_o3(p, ec, Fe, acc);
    default: return elem3_o4(p, ec, Fe, acc);
    }
  }
  switch (order) {
  case 0: return elem2_o0(p, ec, Fe, acc);
  case 1: return elem2_o1(p, ec, Fe, acc);
  case 2: return elem2_o2(p, ec, Fe, acc);
  case 3: return elem2_o3(p, ec, Fe, acc);
  default: return elem2_o4(p, ec, Fe, acc);
  }
}

/* Position of v in the sorted neighbour list of u. */
VM_INLINE int64_t graph_pos(const vm_problem *p, int32_t u, int32_t v) {
  const int32_t *a = p->adj + p->rowptr[u];
  int64_t n = p->rowptr[u + 1] - p->rowptr[u], lo = 0;
  while (n > 1) {
    int64_t half = n / 2;
    lo = a[lo + half] <= v ? lo + half : lo;
    n -= half;
  }
  return p->rowptr[u] + lo;
}

static void scatter(const vm_problem *p, int64_t i, const elem_acc *acc, const vm_eval *out,
                    double *hblk) {
  const vm_mesh *m = p->m;
  int32_t e = p->ael[i];
  int t = m->etype[e];
  const int32_t *cv = m->conn + m->eoff[e];
  int nv = (int)(m->eoff[e + 1] - m->eoff[e]);
  if (out->grad)
    for (int a = 0; a < nv; a++) {
      double *g = out->grad + 3 * (int64_t)cv[a];
      g[0] += acc->g[a][0];
      g[1] += acc->g[a][1];
      g[2] += acc->g[a][2];
    }
  if (out->hdiag)
    for (int a = 0; a < nv; a++) {
      double *H = out->hdiag + 9 * (int64_t)cv[a];
      const double *h = acc->h[a];
      H[0] += h[0];
      H[1] += h[3];
      H[2] += h[5];
      H[3] += h[3];
      H[4] += h[1];
      H[5] += h[4];
      H[6] += h[5];
      H[7] += h[4];
      H[8] += h[2];
    }
  const uint8_t *pp = p->ppos_stride > 0 ? p->ppos + (int64_t)p->ppos_stride * i : NULL;
  if (out->hoff)
    for (int k = 0; k < p->npair[t]; k++) {
      int32_t u = cv[p->pair[t][k][0]], v = cv[p->pair[t][k][1]];
      const double *o = acc->o[k];
      int64_t xu = pp ? p->rowptr[u] + pp[2 * k] : graph_pos(p, u, v);
      int64_t yv = pp ? p->rowptr[v] + pp[2 * k + 1] : graph_pos(p, v, u);
      double *x = out->hoff + 3 * xu;
      double *y = out->hoff + 3 * yv;
      x[0] += o[0];
      x[1] += o[1];
      x[2] += o[2];
      y[0] += o[0];
      y[1] += o[1];
      y[2] += o[2];
    }
  if (hblk)
    for (int k = 0; k < p->npair[t]; k++) {
      int32_t u = cv[p->pair[t][k][0]], v = cv[p->pair[t][k][1]];
      const double *o = acc->f[k];
      int64_t xu = pp ? p->rowptr[u] + pp[2 * k] : graph_pos(p, u, v);
      int64_t yv = pp ? p->rowptr[v] + pp[2 * k + 1] : graph_pos(p, v, u);
      double *x = hblk + 9 * xu;
      double *y = hblk + 9 * yv;
      for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) {
          x[3 * r + q] += o[3 * r + q];
          y[3 * q + r] += o[3 * r + q];
        }
    }
}

/* The hoff position table (problem->ppos), once per rule. */
static int build_ppos(vm_problem *p) {
  int64_t nv = p->m->nv;
  int stride = 0;
  for (int64_t v = 0; v < nv; v++)
    if (p->rowptr[v + 1] - p->rowptr[v] > 255) {
      p->ppos_stride = -1;
      return VM_OK;
    }
  for (int t = 0; t < VM_NTYPES; t++)
    if (vm_elem_dim(t) == p->tdim && 2 * p->npair[t] > stride) stride = 2 * p->npair[t];
  uint8_t *pp = vm_alloc_array(p->ctx, (size_t)p->nae, (size_t)(stride ? stride : 1));
  if (!pp) return VM_ERR_NOMEM;
#pragma omp parallel for schedule(static) num_threads(vm_problem_threads(p))
  for (int64_t i = 0; i < p->nae; i++) {
    int32_t e = p->ael[i];
    int t = p->m->etype[e];
    const int32_t *cv = p->m->conn + p->m->eoff[e];
    for (int k = 0; k < p->npair[t]; k++) {
      int32_t u = cv[p->pair[t][k][0]], v = cv[p->pair[t][k][1]];
      pp[stride * i + 2 * k] = (uint8_t)(graph_pos(p, u, v) - p->rowptr[u]);
      pp[stride * i + 2 * k + 1] = (uint8_t)(graph_pos(p, v, u) - p->rowptr[v]);
    }
  }
  p->ppos = pp;
  p->ppos_stride = stride;
  return VM_OK;
}

/* Sum of the per-element F values of block b, in element order. */
static double block_sum(const vm_problem *p, int64_t b) {
  int64_t i0 = b * VM_PROBLEM_FBLOCK, i1 = i0 + VM_PROBLEM_FBLOCK;
  if (i1 > p->nae) i1 = p->nae;
  double s = 0;
  for (int64_t i = i0; i < i1; i++)
    if (!p->amask || p->amask[i]) s += p->Fe[i];
  return s;
}

int vm_problem_value(vm_problem *p, const double *x, double *F) {
  if (!p || !x || !F)
    return p ? vm_error(p->ctx, VM_ERR_ARG, "vm_problem_value: NULL argument") : VM_ERR_ARG;
  fix_build(p);
  int bad = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(vm_problem_threads(p))
  for (int64_t b = 0; b < p->nblock; b++) {
    int stop;
#pragma omp atomic read
    stop = bad;
    if (stop) continue;
    int64_t i0 = b * VM_PROBLEM_FBLOCK, i1 = i0 + VM_PROBLEM_FBLOCK;
    if (i1 > p->nae) i1 = p->nae;
    double s = 0;
    for (int64_t i = i0; i < i1; i++) {
      if (p->amask && !p->amask[i]) continue;
      double fe;
      if (elem_value(p, i, x, &fe)) {
#pragma omp atomic write
        bad = 1;
        break;
      }
      s += fe;
    }
    p->part[b] = s;
  }
  if (bad) {
    *F = INFINITY;
    return VM_WARN_INVERTED;
  }
  double s = 0;
  for (int64_t b = 0; b < p->nblock; b++) s += p->part[b];
  *F = s;
  return VM_OK;
}

int vm_problem_elem_values(vm_problem *p, const double *x, double *fe) {
  if (!p || !x || !fe)
    return p ? vm_error(p->ctx, VM_ERR_ARG, "vm_problem_elem_values: NULL argument") : VM_ERR_ARG;
  int64_t ne = p->m->ne;
  memset(fe, 0, (size_t)ne * sizeof *fe);
  fix_build(p);
#pragma omp parallel for schedule(static) num_threads(vm_problem_threads(p))
  for (int64_t i = 0; i < p->nae; i++) {
    if (p->amask && !p->amask[i]) continue;
    double f = 0;
    fe[p->ael[i]] = elem_value(p, i, x, &f) ? INFINITY : f;
  }
  return VM_OK;
}

/* vm_problem_eval, and with hblk the full blocks (vm_problem_eval_blocks;
 * out->hoff must then be NULL). */
static int assemble(vm_problem *p, const double *x, const vm_eval *out, double *hblk, int psd) {
  int order = hblk ? (psd ? 4 : 3) : out->hdiag || out->hoff ? 2 : out->grad ? 1 : 0;
  if (!order) return out->F ? vm_problem_value(p, x, out->F) : VM_OK;
  int64_t nv = p->m->nv, nnz = p->rowptr[nv];
  if ((out->hoff || hblk) && !p->ppos_stride) {
    int st = build_ppos(p);
    if (st) return st;
  }
  fix_build(p);
  int bad = 0;
#pragma omp parallel num_threads(vm_problem_threads(p))
  {
    elem_acc acc;
    if (out->grad) {
#pragma omp for schedule(static) nowait
      for (int64_t k = 0; k < 3 * nv; k++) out->grad[k] = 0;
    }
    if (out->hdiag) {
#pragma omp for schedule(static) nowait
      for (int64_t k = 0; k < 9 * nv; k++) out->hdiag[k] = 0;
    }
    if (out->hoff) {
#pragma omp for schedule(static) nowait
      for (int64_t k = 0; k < 3 * nnz; k++) out->hoff[k] = 0;
    }
    if (hblk) {
#pragma omp for schedule(static) nowait
      for (int64_t k = 0; k < 9 * nnz; k++) hblk[k] = 0;
    }
#pragma omp barrier
    for (int c = 0; c < p->ncolor; c++) {
#pragma omp for schedule(dynamic, 1)
      for (int64_t k = p->coff[c]; k < p->coff[c + 1]; k++) {
        int64_t i0 = p->clist[k] * p->chunk, i1 = i0 + p->chunk;
        if (i1 > p->nae) i1 = p->nae;
        for (int64_t i = i0; i < i1; i++) {
          int stop;
#pragma omp atomic read
          stop = bad;
          if (stop) break;
          if (p->amask && !p->amask[i]) continue;
          if (p->skip_fixed && p->fix_of && p->fix_of[i] >= 0 && elem_all_fixed(p, i)) {
            /* F only: its derivatives reach fixed rows alone */
            if (fix_value(p, i, p->fix_of[i], x, &p->Fe[i])) {
#pragma omp atomic write
              bad = 1;
              break;
            }
            continue;
          }
          if (elem_eval(p, i, x, order, out->hoff != NULL, &p->Fe[i], &acc)) {
#pragma omp atomic write
            bad = 1;
            break;
          }
          scatter(p, i, &acc, out, hblk);
        }
      }
    }
    if (out->F) {
#pragma omp for schedule(static)
      for (int64_t b = 0; b < p->nblock; b++) p->part[b] = block_sum(p, b);
    }
  }
  if (bad) {
    if (out->F) *out->F = INFINITY;
    return VM_WARN_INVERTED;
  }
  if (out->F) {
    double s = 0;
    for (int64_t b = 0; b < p->nblock; b++) s += p->part[b];
    *out->F = s;
  }
  return VM_OK;
}

int vm_problem_eval(vm_problem *p, const double *x, vm_eval *out) {
  if (!p || !x || !out)
    return p ? vm_error(p->ctx, VM_ERR_ARG, "vm_problem_eval: NULL argument") : VM_ERR_ARG;
  return assemble(p, x, out, NULL, 0);
}

int vm_problem_eval_blocks(vm_problem *p, const double *x, vm_eval_blocks *out) {
  if (!p || !x || !out)
    return p ? vm_error(p->ctx, VM_ERR_ARG, "vm_problem_eval_blocks: NULL argument") : VM_ERR_ARG;
  vm_eval ev = {out->F, out->grad, out->hdiag, NULL};
  if (!out->hblk && out->hdiag) {
    /* diagonal blocks only: through the full kernel all the same, so
     * they include the PSD correction when asked */
    int64_t nnz = p->rowptr[p->m->nv];
    double *tmp = vm_alloc_array(p->ctx, nnz > 0 ? 9 * (size_t)nnz : 1, sizeof *tmp);
    if (!tmp) return VM_ERR_NOMEM;
    int st = assemble(p, x, &ev, tmp, out->psd);
    vm_free(p->ctx, tmp);
    return st;
  }
  return assemble(p, x, &ev, out->hblk, out->psd);
}

int vm_problem_graph_coupled(const vm_problem *p, uint8_t *mask) {
  if (!p || !mask) return VM_ERR_ARG;
  memset(mask, 0, (size_t)p->rowptr[p->m->nv]);
  for (int64_t i = 0; i < p->nae; i++) {
    int32_t e = p->ael[i];
    int t = p->m->etype[e];
    const int32_t *cv = p->m->conn + p->m->eoff[e];
    for (int k = 0; k < p->npair[t]; k++) {
      int32_t u = cv[p->pair[t][k][0]], v = cv[p->pair[t][k][1]];
      mask[graph_pos(p, u, v)] = 1;
      mask[graph_pos(p, v, u)] = 1;
    }
  }
  return VM_OK;
}

/* s and det C of every node of active element i into s[], det[]. */
static void elem_sd(const vm_problem *p, int64_t i, const double *x, double *s, double *det) {
  elem_ctx ec;
  elem_setup(p, i, x, &ec);
  for (int j = 0; j < ec.R->nnodes; j++) {
    if (p->tdim == 3) {
      node3 v;
      node3_eval(&ec, &ec.R->nodes[j], ec.S + 9 * j, ec.diag, 0, &v);
      s[j] = v.s;
      det[j] = v.det;
    } else {
      node2 v;
      node2_eval(&ec, &ec.R->nodes[j], ec.S + 4 * j, 0, &v);
      s[j] = v.s;
      det[j] = v.det;
    }
  }
}

/* The kept nodes' s and det C of the all-fixed elements sized for the
 * present rule (their node counts change with it); without memory, none. */
static void fix_sd_size(vm_problem *p) {
  fix_build(p);
  if (!p->fix_of || p->fix_sd_rule == p->rule) return;
  vm_ctx *ctx = p->ctx;
  fix_sd_drop(p);
  p->fix_noff = vm_alloc_array(ctx, (size_t)p->nslot + 1, sizeof *p->fix_noff);
  p->fix_sgen = vm_calloc(ctx, (size_t)p->nslot, sizeof *p->fix_sgen);
  if (p->fix_noff && p->fix_sgen) {
    int64_t n = 0;
    p->fix_noff[0] = 0;
    for (int64_t i = 0; i < p->nae; i++)
      if (p->fix_of[i] >= 0) p->fix_noff[p->fix_of[i] + 1] = n += p->noff[i + 1] - p->noff[i];
    p->fix_sd = vm_alloc_array(ctx, 2 * (size_t)(n ? n : 1), sizeof *p->fix_sd);
  }
  if (!p->fix_noff || !p->fix_sgen || !p->fix_sd) {
    fix_sd_drop(p);
    return;
  }
  p->fix_sd_rule = p->rule;
}

/* elem_sd, through the kept values for all-fixed elements. */
static void elem_sd_kept(vm_problem *p, int64_t i, const double *x, double *s, double *det) {
  int32_t slot = p->fix_sd && p->fix_of ? p->fix_of[i] : -1;
  if (slot < 0) {
    elem_sd(p, i, x, s, det);
    return;
  }
  int nn = (int)(p->noff[i + 1] - p->noff[i]);
  double *kd = p->fix_sd + 2 * p->fix_noff[slot];
  if (fix_at(p, i, slot, x) && p->fix_sgen[slot] == p->ggen) {
    for (int j = 0; j < nn; j++) {
      s[j] = kd[2 * j];
      det[j] = kd[2 * j + 1];
    }
    return;
  }
  elem_sd(p, i, x, s, det);
  for (int j = 0; j < nn; j++) {
    kd[2 * j] = s[j];
    kd[2 * j + 1] = det[j];
  }
  p->fix_sgen[slot] = p->ggen;
}

void vm_problem_nsd_free(vm_problem *p) {
  vm_free(p->ctx, p->nsd);
  vm_free(p->ctx, p->nsd_x);
  p->nsd = p->nsd_x = NULL;
  p->nsd_n = 0;
  p->nsd_nx = 0;
  p->nsd_ggen = 0;
}

/* The kept node values for x: 1 if they are for x (bit for bit) and the
 * present geometry; 0 if not, and then p->nsd, when there is room for it,
 * is where the pass about to run keeps its values (nsd_done says they are
 * complete). */
static int nsd_lookup(vm_problem *p, const double *x) {
  int64_t n = p->noff[p->nae];
  size_t nx = (size_t)p->m->nv * 3;
  int sized = p->nsd && p->nsd_n == n && p->nsd_nx == nx;
  if (sized && p->nsd_ggen == p->ggen && memcmp(p->nsd_x, x, nx * sizeof *x) == 0) return 1;
  p->nsd_ggen = 0;
  if (sized) return 0;
  vm_problem_nsd_free(p);
  if ((double)n * 2 * sizeof(double) + (double)nx * sizeof(double) > (double)VM_PROBLEM_NSD_MAX)
    return 0;
  p->nsd = vm_alloc_array(p->ctx, 2 * (size_t)(n ? n : 1), sizeof *p->nsd);
  p->nsd_x = vm_alloc_array(p->ctx, nx ? nx : 1, sizeof *p->nsd_x);
  if (!p->nsd || !p->nsd_x) {
    vm_problem_nsd_free(p);
    return 0;
  }
  p->nsd_n = n;
  p->nsd_nx = nx;
  return 0;
}

static void nsd_done(vm_problem *p, const double *x) {
  if (!p->nsd) return;
  memcpy(p->nsd_x, x, p->nsd_nx * sizeof *x);
  p->nsd_ggen = p->ggen;
}

/* s and det C of active element i's nodes at x: the kept ones (hit), else
 * computed and, when p->nsd is there, kept. */
static void elem_sd_at(vm_problem *p, int64_t i, const double *x, int hit, double *s, double *det) {
  int nn = (int)(p->noff[i + 1] - p->noff[i]);
  double *k = p->nsd ? p->nsd + 2 * p->noff[i] : NULL;
  if (hit) {
    for (int j = 0; j < nn; j++) {
      s[j] = k[2 * j];
      det[j] = k[2 * j + 1];
    }
    return;
  }
  elem_sd_kept(p, i, x, s, det);
  if (k)
    for (int j = 0; j < nn; j++) {
      k[2 * j] = s[j];
      k[2 * j + 1] = det[j];
    }
}

int vm_problem_node_stats(vm_problem *p, const double *x, vm_node_stats *st) {
  if (!p || !x)
    return p ? vm_error(p->ctx, VM_ERR_ARG, "vm_problem_node_stats: NULL argument") : VM_ERR_ARG;
  int64_t inv = 0;
  double mind = INFINITY, phimin = INFINITY, psimin = INFINITY;
  int d = p->tdim;
  fix_sd_size(p);
  int hit = nsd_lookup(p, x);
#pragma omp parallel for schedule(static) num_threads(vm_problem_threads(p)) \
    reduction(+ : inv) reduction(min : mind, phimin, psimin)
  for (int64_t i = 0; i < p->nae; i++) {
    double s[VM_QRULE_MAX_NODES], det[VM_QRULE_MAX_NODES];
    elem_sd_at(p, i, x, hit, s, det);
    int nn = (int)(p->noff[i + 1] - p->noff[i]);
    for (int j = 0; j < nn; j++) {
      if (p->node_w && p->node_w[p->noff[i] + j] == 0) continue; /* left out */
      double dt = det[j], sd = s[j] / d;
      if (dt <= 0) inv++;
      if (dt < mind) mind = dt;
      /* phi = det/(s/d)^{d/2} */
      double phi = sd > 0 ? dt / (d == 3 ? sd * sqrt(sd) : sd) : -INFINITY;
      if (phi < phimin) phimin = phi;
      double psi = 2 * dt / (1 + dt * dt);
      if (psi < psimin) psimin = psi;
    }
  }
  if (!hit) nsd_done(p, x);
  if (st) {
    st->inverted = inv;
    st->min_det = mind;
    st->phi_min = phimin;
    st->psi_min = psimin;
  }
  return VM_OK;
}

int vm_problem_node_dets(vm_problem *p, const double *x, double *det) {
  if (!p || !x || !det)
    return p ? vm_error(p->ctx, VM_ERR_ARG, "vm_problem_node_dets: NULL argument") : VM_ERR_ARG;
  fix_sd_size(p);
  int hit = nsd_lookup(p, x);
#pragma omp parallel for schedule(static) num_threads(vm_problem_threads(p))
  for (int64_t i = 0; i < p->nae; i++) {
    double s[VM_QRULE_MAX_NODES];
    elem_sd_at(p, i, x, hit, s, det + p->noff[i]);
  }
  if (!hit) nsd_done(p, x);
  return VM_OK;
}
