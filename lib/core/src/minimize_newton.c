/* lib/core/src/minimize_newton.c: the Newton minimizer: the full Hessian, with
 * each quadrature node's part projected to positive semidefinite
 * (vm_problem_eval_blocks, psd), in 3x3 blocks that couple the coordinates
 * of every vertex pair, so twists of the mesh (which need x-y coupling)
 * are seen.
 *
 * System (one 3x3 block row per vertex that moves; fixed vertices and
 * vertices outside the active elements are left out):
 *   off-diagonal  L_i H_ij L_j;
 *   diagonal      L_i H_ii L_i + mu s_i L_i + s_i (I - L_i),
 *                 s_i = tr(L_i H_ii L_i) / rank L_i;
 *   right side    -L g.
 * The (I - L_i) parts decouple and solve to 0, so the step y = L y stays in
 * the tangent cone. With H PSD and mu > 0 the matrix is SPD and the CG
 * iterates from zero are descent directions. mu (Levenberg-Marquardt) is
 * lowered after full steps and raised when the line search cuts the step. */
#include <math.h>
#include <string.h>

#include "linsolve_private.h"
#include "minimize_private.h"

#define MU_INIT 1e-3
#define MU_MIN 1e-8
#define MU_MAX 1e4

typedef struct {
  int64_t nb;       /* block unknowns */
  int32_t *vidx;    /* per vertex: block index or -1 */
  int32_t *prev;    /* vidx of the current pattern */
  int32_t *bvert;   /* per block: vertex */
  int64_t *browptr; /* nb + 1: block entries of each block row */
  int64_t *bmap;    /* per block entry: vertex-graph index, -1 on the diagonal */
  vm_csr A;         /* scalar CSR: row 3i + r holds, block by block, 3 columns each */
  uint8_t *coupled; /* per vertex-graph entry: the rule couples the pair */
  double *L;        /* 9 per vertex: L = Q Q^T */
  double *s;        /* per vertex: the diagonal scale s_i */
  uint8_t *ident;   /* per vertex: L = I */
  double *b, *y;
  vm_precond *pc;
  int full_iter;
  int have_pattern;
  double mu;
} newton_state;

static void newton_end(vm_minimizer *m) {
  newton_state *S = m->impl;
  if (!S) return;
  vm_ctx *ctx = m->ctx;
  vm_free(ctx, S->vidx);
  vm_free(ctx, S->prev);
  vm_free(ctx, S->bvert);
  vm_free(ctx, S->browptr);
  vm_free(ctx, S->bmap);
  vm_csr_free(ctx, &S->A);
  vm_free(ctx, S->coupled);
  vm_free(ctx, S->L);
  vm_free(ctx, S->s);
  vm_free(ctx, S->ident);
  vm_free(ctx, S->b);
  vm_free(ctx, S->y);
  vm_precond_destroy(&S->pc);
  vm_free(ctx, S);
  m->impl = NULL;
}

static int newton_begin(vm_minimizer *m) {
  vm_ctx *ctx = m->ctx;
  newton_end(m);
  newton_state *S = vm_calloc(ctx, 1, sizeof *S);
  if (!S) return VM_ERR_NOMEM;
  m->impl = S;
  size_t nv = m->nv > 0 ? (size_t)m->nv : 1;
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(m->prob, &rp, &adj);
  S->vidx = vm_alloc_array(ctx, nv, sizeof *S->vidx);
  S->prev = vm_alloc_array(ctx, nv, sizeof *S->prev);
  S->bvert = vm_alloc_array(ctx, nv, sizeof *S->bvert);
  S->browptr = vm_alloc_array(ctx, nv + 1, sizeof *S->browptr);
  S->coupled = vm_alloc_array(ctx, rp[m->nv] > 0 ? (size_t)rp[m->nv] : 1, 1);
  S->L = vm_alloc_array(ctx, 9 * nv, sizeof *S->L);
  S->s = vm_alloc_array(ctx, nv, sizeof *S->s);
  S->ident = vm_alloc_array(ctx, nv, sizeof *S->ident);
  S->b = vm_alloc_array(ctx, 3 * nv, sizeof *S->b);
  S->y = vm_alloc_array(ctx, 3 * nv, sizeof *S->y);
  if (!S->vidx || !S->prev || !S->bvert || !S->browptr || !S->coupled || !S->L || !S->s ||
      !S->ident || !S->b || !S->y)
    return VM_ERR_NOMEM;
  int st = vm_problem_graph_coupled(m->prob, S->coupled);
  if (st) return st;
  vm_precond_kind kind =
      m->opt.precond == VM_PRECOND_JACOBI ? VM_PRECOND_BLOCK_JACOBI : m->opt.precond;
  vm_amg_options amg = m->opt.amg;
  amg.block_size = 3;
  st = vm_precond_create(ctx, kind, &amg, &S->pc);
  if (st) return st;
  S->mu = MU_INIT;
  return VM_OK;
}

/* Projectors and diagonal scales of this iteration; the unknowns. */
static void load_vertices(vm_minimizer *m, const double *hdiag) {
  newton_state *S = m->impl;
  for (int64_t v = 0; v < m->nv; v++) {
    double Q[9], *L = S->L + 9 * v;
    int k = vm_bc_basis(m->bc, v, Q);
    S->ident[v] = k == 3;
    for (int a = 0; a < 3; a++)
      for (int c = 0; c < 3; c++) {
        double t = 0;
        for (int j = 0; j < k; j++) t += Q[3 * j + a] * Q[3 * j + c];
        L[3 * a + c] = t;
      }
    const double *H = hdiag + 9 * v;
    double tr = 0;
    if (k == 3) {
      tr = H[0] + H[4] + H[8];
    } else {
      for (int a = 0; a < 3; a++)
        for (int c = 0; c < 3; c++) tr += L[3 * a + c] * H[3 * c + a]; /* tr(L H L) = tr(L H) */
    }
    int zero = 1;
    for (int e = 0; e < 9; e++)
      if (H[e] != 0) zero = 0;
    S->s[v] = k > 0 && tr > 0 && isfinite(tr) ? tr / k : 1.0;
    S->vidx[v] = k > 0 && !zero ? 0 : -1;
  }
  int64_t nb = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (S->vidx[v] >= 0) {
      S->bvert[nb] = (int32_t)v;
      S->vidx[v] = (int32_t)nb++;
    }
  S->nb = nb;
}

/* The block pattern and the scalar CSR structure, when the unknowns
 * changed. */
static int build_pattern(vm_minimizer *m) {
  newton_state *S = m->impl;
  vm_ctx *ctx = m->ctx;
  const int64_t nv = m->nv, nb = S->nb;
  if (S->have_pattern && S->A.n == 3 * nb &&
      memcmp(S->vidx, S->prev, (size_t)nv * sizeof *S->vidx) == 0)
    return VM_OK;
  memcpy(S->prev, S->vidx, (size_t)nv * sizeof *S->vidx);
  S->have_pattern = 0;
  S->full_iter = 0;
  vm_csr_free(ctx, &S->A);
  vm_free(ctx, S->bmap);
  S->bmap = NULL;
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(m->prob, &rp, &adj);
  int64_t ne = 0;
  for (int64_t i = 0; i < nb; i++) {
    int64_t v = S->bvert[i];
    ne++;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++)
      if (S->coupled[k] && S->vidx[adj[k]] >= 0) ne++;
  }
  S->bmap = vm_alloc_array(ctx, ne ? (size_t)ne : 1, sizeof *S->bmap);
  if (!S->bmap) return VM_ERR_NOMEM;
  int st = vm_csr_alloc(ctx, &S->A, 3 * nb, 9 * ne);
  if (st) return st;
  int64_t pos = 0;
  S->browptr[0] = 0;
  for (int64_t i = 0; i < nb; i++) {
    int64_t v = S->bvert[i];
    int diag_done = 0;
    int64_t e0 = pos;
    int32_t cols[1024];
    int nc = 0;
    for (int64_t k = rp[v]; k <= rp[v + 1]; k++) {
      int32_t j = k < rp[v + 1] && S->coupled[k] ? S->vidx[adj[k]] : -1;
      if (!diag_done && (k == rp[v + 1] || j > i)) {
        S->bmap[pos++] = -1;
        if (nc < 1024) cols[nc++] = (int32_t)i;
        diag_done = 1;
      }
      if (j < 0) continue;
      S->bmap[pos++] = k;
      if (nc < 1024) cols[nc++] = j;
    }
    if (pos - e0 > 1024) return vm_error(ctx, VM_ERR_UNSUPPORTED, "newton: vertex degree > 1023");
    S->browptr[i + 1] = pos;
    int64_t w = pos - e0;
    for (int r = 0; r < 3; r++) {
      int64_t base = 9 * e0 + 3 * w * r;
      S->A.rowptr[3 * i + r + 1] = base + 3 * w;
      for (int64_t e = 0; e < w; e++)
        for (int q = 0; q < 3; q++) S->A.col[base + 3 * e + q] = 3 * cols[e] + q;
    }
  }
  S->have_pattern = 1;
  return VM_OK;
}

/* out = L_a B L_b (3x3), with identity shortcuts. */
static void proj_block(const double *La, int ia, const double *B, const double *Lb, int ib,
                       double *out) {
  double T[9];
  if (ia) {
    memcpy(T, B, sizeof T);
  } else {
    for (int r = 0; r < 3; r++)
      for (int q = 0; q < 3; q++)
        T[3 * r + q] = La[3 * r] * B[q] + La[3 * r + 1] * B[3 + q] + La[3 * r + 2] * B[6 + q];
  }
  if (ib) {
    memcpy(out, T, sizeof T);
  } else {
    for (int r = 0; r < 3; r++)
      for (int q = 0; q < 3; q++)
        out[3 * r + q] = T[3 * r] * Lb[q] + T[3 * r + 1] * Lb[3 + q] + T[3 * r + 2] * Lb[6 + q];
  }
}

static void fill_values(vm_minimizer *m, const double *hdiag, const double *hblk) {
  newton_state *S = m->impl;
  const int32_t *adj;
  vm_problem_graph(m->prob, NULL, &adj);
  int nt = vm_nthreads(m->ctx);
  const int64_t nb = S->nb;
  const double mu = S->mu;
#pragma omp parallel for num_threads(nt) schedule(static) if (nb >= VM_PAR_MIN / 16)
  for (int64_t i = 0; i < nb; i++) {
    int64_t v = S->bvert[i];
    const double *Lv = S->L + 9 * v;
    int64_t e0 = S->browptr[i], w = S->browptr[i + 1] - e0;
    for (int64_t e = e0; e < e0 + w; e++) {
      int64_t k = S->bmap[e];
      double B[9];
      if (k < 0) {
        proj_block(Lv, S->ident[v], hdiag + 9 * v, Lv, S->ident[v], B);
        double sv = S->s[v];
        for (int a = 0; a < 9; a++) {
          double id = (a % 4 == 0) ? 1.0 : 0.0;
          B[a] += mu * sv * Lv[a] + sv * (id - Lv[a]);
        }
        /* exact symmetry of the diagonal block */
        for (int r = 0; r < 3; r++)
          for (int q = r + 1; q < 3; q++)
            B[3 * r + q] = B[3 * q + r] = 0.5 * (B[3 * r + q] + B[3 * q + r]);
      } else {
        int64_t u = adj[k];
        proj_block(Lv, S->ident[v], hblk + 9 * k, S->L + 9 * u, S->ident[u], B);
      }
      int64_t off = e - e0;
      for (int r = 0; r < 3; r++) {
        double *row = S->A.val + 9 * e0 + 3 * w * r + 3 * off;
        row[0] = B[3 * r];
        row[1] = B[3 * r + 1];
        row[2] = B[3 * r + 2];
      }
    }
  }
}

static int newton_direction(vm_minimizer *m, int iter, const double *g, const double *hdiag,
                            const double *hblk, double *d, int *lin_iters) {
  newton_state *S = m->impl;
  vm_ctx *ctx = m->ctx;
  const vm_minimize_options *o = &m->opt;
  *lin_iters = 0;
  /* Levenberg-Marquardt: the last line search's verdict */
  if (iter > 1) {
    if (m->last_tau >= 1.0 && m->last_infeasible == 0)
      S->mu = fmax(S->mu / 3, MU_MIN);
    else if (m->last_tau < 0.25 || m->last_infeasible > 0)
      S->mu = fmin(S->mu * 4, MU_MAX);
  }
  load_vertices(m, hdiag);
  int st = build_pattern(m);
  if (st) return st;
  memset(d, 0, (size_t)m->nv * 3 * sizeof *d);
  const int64_t nb = S->nb;
  if (nb == 0) return VM_OK;
  for (int64_t i = 0; i < nb; i++) {
    int64_t v = S->bvert[i];
    for (int c = 0; c < 3; c++) {
      S->b[3 * i + c] = -g[3 * v + c];
      S->y[3 * i + c] = 0;
    }
  }
  fill_values(m, hdiag, hblk);
  if (S->full_iter == 0 || iter - S->full_iter >= o->amg_rebuild_every) {
    st = vm_precond_setup(S->pc, &S->A);
    S->full_iter = iter;
  } else {
    st = vm_precond_update(S->pc, &S->A);
  }
  if (st) return st;
  vm_pcg_options po = {o->pcg_rtol, o->pcg_maxit};
  vm_pcg_result pr;
  st = vm_pcg_solve(ctx, &S->A, S->pc, S->b, S->y, &po, &pr);
  if (st) return st;
  *lin_iters = pr.iterations;
  for (int64_t i = 0; i < nb; i++) {
    int64_t v = S->bvert[i];
    for (int c = 0; c < 3; c++) d[3 * v + c] = S->y[3 * i + c];
  }
  vm_bc_apply(m->bc, d);
  return VM_OK;
}

const vm_minimizer_ops vm_minimizer_newton_ops = {"newton", 2, newton_begin, newton_direction,
                                                  newton_end};
