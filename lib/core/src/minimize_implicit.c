/* lib/core/src/minimize_implicit.c: the implicit minimizer: the off-diagonal
 * entries of the projected blocks L_i^T H_ij L_j are neglected, which
 * splits (32) into one sparse SPD system per coordinate m, each solved
 * inexactly by preconditioned CG.
 *
 * Entries of system m (L = I for free vertices, rank-0 or fixed vertices
 * excluded):
 *   diagonal      (L_i H_ii L_i)_mm, exact from the 3x3 block;
 *   off-diagonal  sum_a (L_i)_am (L_j)_am (H_ij)_aa, i.e. (L_i^T H_ij L_j)_mm
 *                 with the off-diagonal entries of H_ij (not assembled)
 *                 left out: exact for axis-aligned constraints (box faces
 *                 and edges, coordinate planes) and plain (H_ij)_mm between
 *                 free vertices;
 *   right side    -(L r)_m; rows with (L_i)_mm = 0 (the coordinate is normal
 *                 to the constraint) are Dirichlet rows of that system.
 * The step is d = L y (33). With A the resulting SPD operator,
 * r^T d = -(L r)^T A^{-1} (L r) < 0: a descent direction in the tangent
 * cone, which CG from zero keeps for its inexact solutions. */
#include <math.h>
#include <string.h>

#include "linsolve_private.h"
#include "minimize_private.h"

/* (L_v)_mm below this: coordinate m of v is constrained (Dirichlet). */
#define L_TOL 1e-12

/* One coordinate's system. */
typedef struct {
  int64_t nu;     /* unknowns */
  int32_t *vidx;  /* per vertex: unknown index or -1 */
  int32_t *prev;  /* vidx of the pattern in A */
  int32_t *uvert; /* per unknown: vertex */
  vm_csr A;       /* pattern and values */
  int64_t *hmap;  /* per entry of A: index into the vertex graph, -1 on the diagonal */
  int share;      /* same unknowns as coordinate 0: use its A and hmap (values are
                     refilled before each solve), saving a pattern */
  int gen;        /* pattern generation: own builds, or coordinate 0's when shared */
  vm_precond *pc;
  vm_precond *fallback; /* Jacobi, for a step whose AMG setup failed */
  int full_iter;        /* iteration of the last full preconditioner setup (0: none) */
  int have_pattern;
} coord_system;

typedef struct {
  coord_system sys[3];
  int64_t jacobi_steps; /* steps whose AMG setup failed, taken with Jacobi */
  double *L;            /* per vertex 9: the projector (slip vertices only filled) */
  uint8_t *ident;       /* per vertex: L acts as identity on the solved coordinates */
  double *b, *y;
} implicit_state;

static void implicit_end(vm_minimizer *m) {
  implicit_state *S = m->impl;
  if (!S) return;
  vm_ctx *ctx = m->ctx;
  if (S->jacobi_steps > 1)
    vm_log(ctx, VM_LOG_INFO, "implicit: %lld steps of this phase used Jacobi in all",
           (long long)S->jacobi_steps);
  for (int c = 0; c < 3; c++) {
    coord_system *cs = &S->sys[c];
    vm_free(ctx, cs->vidx);
    vm_free(ctx, cs->prev);
    vm_free(ctx, cs->uvert);
    vm_csr_free(ctx, &cs->A);
    vm_free(ctx, cs->hmap);
    vm_precond_destroy(&cs->pc);
    vm_precond_destroy(&cs->fallback);
  }
  vm_free(ctx, S->L);
  vm_free(ctx, S->ident);
  vm_free(ctx, S->b);
  vm_free(ctx, S->y);
  vm_free(ctx, S);
  m->impl = NULL;
}

static int implicit_begin(vm_minimizer *m) {
  vm_ctx *ctx = m->ctx;
  implicit_end(m);
  implicit_state *S = vm_calloc(ctx, 1, sizeof *S);
  if (!S) return VM_ERR_NOMEM;
  m->impl = S;
  size_t nv = m->nv > 0 ? (size_t)m->nv : 1;
  S->L = vm_alloc_array(ctx, 9 * nv, sizeof *S->L);
  S->ident = vm_alloc_array(ctx, nv, sizeof *S->ident);
  S->b = vm_alloc_array(ctx, nv, sizeof *S->b);
  S->y = vm_alloc_array(ctx, nv, sizeof *S->y);
  if (!S->L || !S->ident || !S->b || !S->y) return VM_ERR_NOMEM;
  for (int c = 0; c < m->sdim; c++) {
    coord_system *cs = &S->sys[c];
    cs->vidx = vm_alloc_array(ctx, nv, sizeof *cs->vidx);
    cs->prev = vm_alloc_array(ctx, nv, sizeof *cs->prev);
    cs->uvert = vm_alloc_array(ctx, nv, sizeof *cs->uvert);
    if (!cs->vidx || !cs->prev || !cs->uvert) return VM_ERR_NOMEM;
    /* scalar systems: block Jacobi is plain Jacobi here */
    vm_precond_kind kind =
        m->opt.precond == VM_PRECOND_BLOCK_JACOBI ? VM_PRECOND_JACOBI : m->opt.precond;
    vm_amg_options amg = m->opt.amg;
    amg.block_size = 1;
    int st = vm_precond_create(ctx, kind, &amg, &cs->pc);
    if (st) return st;
  }
  return VM_OK;
}

/* Projectors of this iteration: ident[v] for free vertices, L = Q Q^T for
 * slip vertices, rank 0 (fixed) marked by ident = 0 and L = 0. */
static void load_projectors(vm_minimizer *m) {
  implicit_state *S = m->impl;
  for (int64_t v = 0; v < m->nv; v++) {
    int cls = vm_bc_class(m->bc, v);
    S->ident[v] = cls == VM_VERTEX_FREE;
    if (cls == VM_VERTEX_FREE) continue;
    double Q[9], *L = S->L + 9 * v;
    int k = vm_bc_basis(m->bc, v, Q);
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++) {
        double s = 0;
        for (int j = 0; j < k; j++) s += Q[3 * j + a] * Q[3 * j + b];
        L[3 * a + b] = s;
      }
  }
}

/* The unknowns of coordinate c and, if they changed, the CSR pattern. */
static int build_pattern(vm_minimizer *m, int c, const double *hdiag) {
  implicit_state *S = m->impl;
  coord_system *cs = &S->sys[c];
  vm_ctx *ctx = m->ctx;
  const int64_t nv = m->nv;
  int64_t nu = 0;
  for (int64_t v = 0; v < nv; v++) {
    int in = S->ident[v] || S->L[9 * v + 4 * c] > L_TOL;
    double hcc = hdiag[9 * v + 4 * c];
    /* zero blocks: vertices outside the active elements */
    if (hcc == 0 && hdiag[9 * v] == 0 && hdiag[9 * v + 4] == 0 && hdiag[9 * v + 8] == 0) in = 0;
    cs->vidx[v] = -1;
    if (in) {
      cs->uvert[nu] = (int32_t)v;
      cs->vidx[v] = (int32_t)nu++;
    }
  }
  if (cs->have_pattern && nu == cs->nu &&
      memcmp(cs->vidx, cs->prev, (size_t)nv * sizeof *cs->vidx) == 0 &&
      (!cs->share || cs->gen == S->sys[0].gen))
    return VM_OK;
  memcpy(cs->prev, cs->vidx, (size_t)nv * sizeof *cs->vidx);
  cs->nu = nu;
  cs->have_pattern = 0;
  cs->full_iter = 0;
  vm_csr_free(ctx, &cs->A);
  vm_free(ctx, cs->hmap);
  cs->hmap = NULL;
  cs->share = c > 0 && S->sys[0].have_pattern && S->sys[0].nu == nu &&
              memcmp(cs->vidx, S->sys[0].vidx, (size_t)nv * sizeof *cs->vidx) == 0;
  if (cs->share) {
    cs->gen = S->sys[0].gen;
    cs->have_pattern = 1;
    return VM_OK;
  }
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(m->prob, &rp, &adj);
  int64_t nnz = 0;
  for (int64_t v = 0; v < nv; v++) {
    if (cs->vidx[v] < 0) continue;
    nnz++;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++)
      if (cs->vidx[adj[k]] >= 0) nnz++;
  }
  int st = vm_csr_alloc(ctx, &cs->A, nu, nnz);
  if (st) return st;
  cs->hmap = vm_alloc_array(ctx, nnz ? (size_t)nnz : 1, sizeof *cs->hmap);
  if (!cs->hmap) return VM_ERR_NOMEM;
  int64_t pos = 0;
  for (int64_t i = 0; i < nu; i++) {
    int64_t v = cs->uvert[i];
    int diag_done = 0;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++) {
      int32_t j = cs->vidx[adj[k]];
      if (j < 0) continue;
      if (!diag_done && j > i) {
        cs->A.col[pos] = (int32_t)i;
        cs->hmap[pos++] = -1;
        diag_done = 1;
      }
      cs->A.col[pos] = j;
      cs->hmap[pos++] = k;
    }
    if (!diag_done) {
      cs->A.col[pos] = (int32_t)i;
      cs->hmap[pos++] = -1;
    }
    cs->A.rowptr[i + 1] = pos;
  }
  cs->gen++;
  cs->have_pattern = 1;
  return VM_OK;
}

/* Values of coordinate c (see the file comment). A non-positive diagonal
 * (possible only for non-polyconvex measures) is replaced by the row's
 * absolute off-diagonal sum. */
static void fill_values(vm_minimizer *m, int c, const double *hdiag, const double *hoff) {
  implicit_state *S = m->impl;
  coord_system *cs = &S->sys[c];
  vm_csr *A = cs->share ? &S->sys[0].A : &cs->A;
  const int64_t *hmap = cs->share ? S->sys[0].hmap : cs->hmap;
  const int32_t *adj;
  vm_problem_graph(m->prob, NULL, &adj);
  int nt = vm_nthreads(m->ctx);
  const int64_t nu = cs->nu;
#pragma omp parallel for num_threads(nt) schedule(static) if (nu >= VM_PAR_MIN / 8)
  for (int64_t i = 0; i < nu; i++) {
    int64_t v = cs->uvert[i], dpos = -1;
    const double *Lv = S->L + 9 * v;
    double off = 0;
    for (int64_t k = A->rowptr[i]; k < A->rowptr[i + 1]; k++) {
      int64_t e = hmap[k];
      double a;
      if (e < 0) {
        dpos = k;
        const double *H = hdiag + 9 * v;
        if (S->ident[v]) {
          a = H[4 * c];
        } else {
          a = 0;
          for (int p = 0; p < 3; p++)
            for (int q = 0; q < 3; q++) a += Lv[3 * p + c] * H[3 * p + q] * Lv[3 * q + c];
        }
      } else {
        int64_t u = adj[e];
        const double *h = hoff + 3 * e;
        if (S->ident[v] && S->ident[u]) {
          a = h[c];
        } else {
          const double *Lu = S->L + 9 * u;
          a = 0;
          for (int p = 0; p < 3; p++) {
            double lv = S->ident[v] ? (p == c) : Lv[3 * p + c];
            double lu = S->ident[u] ? (p == c) : Lu[3 * p + c];
            a += lv * lu * h[p];
          }
        }
        off += fabs(a);
      }
      A->val[k] = a;
    }
    if (!(A->val[dpos] > 0) || !isfinite(A->val[dpos])) A->val[dpos] = off > 0 ? off : 1.0;
  }
}

static int implicit_direction(vm_minimizer *m, int iter, const double *g, const double *hdiag,
                              const double *hoff, double *d, int *lin_iters) {
  implicit_state *S = m->impl;
  vm_ctx *ctx = m->ctx;
  const vm_minimize_options *o = &m->opt;
  *lin_iters = 0;
  load_projectors(m);
  memset(d, 0, (size_t)m->nv * 3 * sizeof *d);
  vm_pcg_options po = {o->pcg_rtol, o->pcg_maxit};
  for (int c = 0; c < m->sdim; c++) {
    coord_system *cs = &S->sys[c];
    int st = build_pattern(m, c, hdiag);
    if (st) return st;
    int64_t nz = 0;
    for (int64_t i = 0; i < cs->nu; i++) {
      S->b[i] = -g[3 * cs->uvert[i] + c];
      S->y[i] = 0;
      if (S->b[i] != 0) nz++;
    }
    if (nz == 0) continue;
    fill_values(m, c, hdiag, hoff);
    const vm_csr *A = cs->share ? &S->sys[0].A : &cs->A;
    if (cs->full_iter == 0 || iter - cs->full_iter >= o->amg_rebuild_every) {
      st = vm_precond_setup(cs->pc, A);
      cs->full_iter = iter;
    } else {
      st = vm_precond_update(cs->pc, A);
    }
    vm_precond *pc = cs->pc;
    if (st == VM_ERR_NUMERIC && cs->pc && vm_precond_get_kind(cs->pc) == VM_PRECOND_AMG) {
      /* a Galerkin coarse level of an indefinite Hessian (the penalty
       * measure near folds, tiny eps) can lose its positive diagonal: this
       * step is preconditioned by Jacobi (the fine diagonal is positive,
       * fill_values) and the next one builds a new hierarchy */
      /* said once a phase; the others with -v, and their count at its end */
      S->jacobi_steps++;
      vm_log(ctx, S->jacobi_steps == 1 ? VM_LOG_INFO : VM_LOG_DEBUG,
             "implicit: %s; this step uses Jacobi", vm_ctx_error(ctx));
      if (!cs->fallback && (st = vm_precond_create(ctx, VM_PRECOND_JACOBI, NULL, &cs->fallback)))
        return st;
      if ((st = vm_precond_setup(cs->fallback, A))) return st;
      cs->full_iter = 0;
      pc = cs->fallback;
    }
    if (st) return st;
    vm_pcg_result pr;
    st = vm_pcg_solve(ctx, A, pc, S->b, S->y, &po, &pr);
    if (st) return st;
    *lin_iters += pr.iterations;
    for (int64_t i = 0; i < cs->nu; i++) d[3 * cs->uvert[i] + c] = S->y[i];
  }
  vm_bc_apply(m->bc, d);
  return VM_OK;
}

const vm_minimizer_ops vm_minimizer_implicit_ops = {"implicit", 1, implicit_begin,
                                                    implicit_direction, implicit_end};
