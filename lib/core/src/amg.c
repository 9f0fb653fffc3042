/* lib/core/src/amg.c: smoothed-aggregation algebraic multigrid preconditioner
 * (symmetric V-cycle with damped Jacobi smoothing, dense coarsest solve). */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "linsolve_private.h"

#define AMG_MAX_LEVELS 25
/* Dense Cholesky up to this many coarsest unknowns when coarsening stalls;
 * above it the coarsest level is approximated by smoothing sweeps. */
#define AMG_DENSE_MAX 1000
#define AMG_COARSE_SWEEPS 8
#define AMG_POWER_ITERS 10

/* Rectangular CSR (columns within a row in a fixed, not sorted, order). */
typedef struct {
  int64_t nr, nc;
  int64_t *rp;
  int32_t *ci;
  double *v;
} mat;

typedef struct {
  mat A;        /* level operator; level 0 is a view of the caller's matrix */
  double *dinv; /* omega / a_ii of the smoother */
  double rho;   /* estimate of rho(D^{-1} A) the smoother was scaled with */
  mat P, R;     /* prolongator to this level from the next, and P^T */
  double *b, *x, *r;
} level;

typedef struct {
  int nlev;
  level lev[AMG_MAX_LEVELS];
  int dense;        /* coarsest solved by dense Cholesky */
  double *chol;     /* lower factor, row-major nc x nc */
  uint8_t *cnull;   /* pivots dropped as numerically zero */
  int64_t n0, nnz0; /* finest size and pattern size at the last full setup */
} amg_impl;

static void mat_free(vm_ctx *ctx, mat *M) {
  vm_free(ctx, M->rp);
  vm_free(ctx, M->ci);
  vm_free(ctx, M->v);
  memset(M, 0, sizeof *M);
}

static int mat_alloc(vm_ctx *ctx, mat *M, int64_t nr, int64_t nc, int64_t nnz) {
  memset(M, 0, sizeof *M);
  M->rp = vm_calloc(ctx, (size_t)nr + 1, sizeof *M->rp);
  M->ci = vm_alloc_array(ctx, nnz ? (size_t)nnz : 1, sizeof *M->ci);
  M->v = vm_alloc_array(ctx, nnz ? (size_t)nnz : 1, sizeof *M->v);
  if (!M->rp || !M->ci || !M->v) {
    mat_free(ctx, M);
    return VM_ERR_NOMEM;
  }
  M->nr = nr;
  M->nc = nc;
  return VM_OK;
}

static void mat_view(mat *M, const vm_csr *A) {
  M->nr = M->nc = A->n;
  M->rp = A->rowptr;
  M->ci = A->col;
  M->v = A->val;
}

static void level_free(vm_ctx *ctx, level *L, int own_A) {
  if (own_A)
    mat_free(ctx, &L->A);
  else
    memset(&L->A, 0, sizeof L->A);
  mat_free(ctx, &L->P);
  mat_free(ctx, &L->R);
  vm_free(ctx, L->dinv);
  vm_free(ctx, L->b);
  vm_free(ctx, L->x);
  vm_free(ctx, L->r);
  memset(L, 0, sizeof *L);
}

static void amg_clear(vm_ctx *ctx, amg_impl *M) {
  for (int l = 0; l < M->nlev; l++) level_free(ctx, &M->lev[l], l > 0);
  M->nlev = 0;
  vm_free(ctx, M->chol);
  vm_free(ctx, M->cnull);
  M->chol = NULL;
  M->cnull = NULL;
  M->dense = 0;
}

/* y = M x (rows in parallel). If acc, y += M x. */
static void mat_mv(vm_ctx *ctx, const mat *M, const double *x, double *y, int acc) {
  int nt = vm_nthreads(ctx);
  const int64_t n = M->nr;
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN_MV)
  for (int64_t i = 0; i < n; i++) {
    double s = 0;
    for (int64_t k = M->rp[i]; k < M->rp[i + 1]; k++) s += M->v[k] * x[M->ci[k]];
    y[i] = acc ? y[i] + s : s;
  }
}

static double mat_diag(const mat *M, int64_t i) {
  for (int64_t k = M->rp[i]; k < M->rp[i + 1]; k++)
    if (M->ci[k] == i) return M->v[k];
  return 0.0;
}

/* C = A B, rows in parallel; each row accumulated in a fixed order (the
 * order of first appearance, not sorted: nothing downstream needs it).
 * A symbolic pass counts each row exactly, so no oversized scratch is
 * written (first touches of fresh pages are what costs most here). */
static int mat_mul(vm_ctx *ctx, const mat *A, const mat *B, mat *C) {
  int nt = vm_nthreads(ctx);
  const int64_t nr = A->nr, nc = B->nc;
  memset(C, 0, sizeof *C);
  int64_t *cnt = vm_alloc_array(ctx, (size_t)nr + 1, sizeof *cnt);
  int64_t *mark = vm_alloc_array(ctx, (size_t)nt * (size_t)(nc ? nc : 1), sizeof *mark);
  if (!cnt || !mark) {
    vm_free(ctx, cnt);
    vm_free(ctx, mark);
    return VM_ERR_NOMEM;
  }
  cnt[0] = 0;
#pragma omp parallel num_threads(nt) if (nr >= 2048)
  {
    int64_t *mk = mark + (size_t)omp_get_thread_num() * (size_t)(nc ? nc : 1);
    for (int64_t j = 0; j < nc; j++) mk[j] = -1;
#pragma omp for schedule(static)
    for (int64_t i = 0; i < nr; i++) {
      int64_t c = 0;
      for (int64_t ka = A->rp[i]; ka < A->rp[i + 1]; ka++) {
        int32_t k = A->ci[ka];
        for (int64_t kb = B->rp[k]; kb < B->rp[k + 1]; kb++) {
          int32_t j = B->ci[kb];
          if (mk[j] != i) {
            mk[j] = i;
            c++;
          }
        }
      }
      cnt[i + 1] = c;
    }
  }
  for (int64_t i = 0; i < nr; i++) cnt[i + 1] += cnt[i];
  int st = mat_alloc(ctx, C, nr, nc, cnt[nr]);
  if (st) {
    vm_free(ctx, cnt);
    vm_free(ctx, mark);
    return st;
  }
  memcpy(C->rp, cnt, ((size_t)nr + 1) * sizeof *cnt);
  vm_free(ctx, cnt);
#pragma omp parallel num_threads(nt) if (nr >= 2048)
  {
    int64_t *mk = mark + (size_t)omp_get_thread_num() * (size_t)(nc ? nc : 1);
    for (int64_t j = 0; j < nc; j++) mk[j] = -1;
#pragma omp for schedule(static)
    for (int64_t i = 0; i < nr; i++) {
      int64_t start = C->rp[i], pos = start;
      for (int64_t ka = A->rp[i]; ka < A->rp[i + 1]; ka++) {
        int32_t k = A->ci[ka];
        double a = A->v[ka];
        for (int64_t kb = B->rp[k]; kb < B->rp[k + 1]; kb++) {
          int32_t j = B->ci[kb];
          if (mk[j] < start) {
            mk[j] = pos;
            C->ci[pos] = j;
            C->v[pos++] = a * B->v[kb];
          } else {
            C->v[mk[j]] += a * B->v[kb];
          }
        }
      }
    }
  }
  vm_free(ctx, mark);
  return VM_OK;
}

/* T = M^T (counting sort: rows of T come out sorted). */
static int mat_transpose(vm_ctx *ctx, const mat *M, mat *T) {
  int64_t nnz = M->rp[M->nr];
  int st = mat_alloc(ctx, T, M->nc, M->nr, nnz);
  if (st) return st;
  for (int64_t k = 0; k < nnz; k++) T->rp[M->ci[k] + 1]++;
  for (int64_t j = 0; j < M->nc; j++) T->rp[j + 1] += T->rp[j];
  int64_t *pos = vm_alloc_array(ctx, (size_t)M->nc + 1, sizeof *pos);
  if (!pos) {
    mat_free(ctx, T);
    return VM_ERR_NOMEM;
  }
  memcpy(pos, T->rp, ((size_t)M->nc + 1) * sizeof *pos);
  for (int64_t i = 0; i < M->nr; i++)
    for (int64_t k = M->rp[i]; k < M->rp[i + 1]; k++) {
      int64_t p = pos[M->ci[k]]++;
      T->ci[p] = (int32_t)i;
      T->v[p] = M->v[k];
    }
  vm_free(ctx, pos);
  return VM_OK;
}

/* Largest eigenvalue of D^{-1} A (A symmetric, D = diag > 0) by power
 * iteration from a fixed start vector; the Rayleigh quotient in the D inner
 * product approaches it from below. */
static int spectral_radius(vm_ctx *ctx, const mat *A, const double *d, double *rho) {
  const int64_t n = A->nr;
  double *x = vm_alloc_array(ctx, (size_t)n, sizeof *x);
  double *y = vm_alloc_array(ctx, (size_t)n, sizeof *y);
  double *t = vm_alloc_array(ctx, (size_t)n, sizeof *t);
  if (!x || !y || !t) {
    vm_free(ctx, x);
    vm_free(ctx, y);
    vm_free(ctx, t);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < n; i++) x[i] = 1.0 + (double)((i * 7919) % 101) / 101.0;
  double lam = 0;
  for (int it = 0; it < AMG_POWER_ITERS; it++) {
    mat_mv(ctx, A, x, y, 0);
    for (int64_t i = 0; i < n; i++) t[i] = x[i] * d[i];
    double xAx = vm_dot(ctx, n, x, y), xDx = vm_dot(ctx, n, x, t);
    if (!(xDx > 0)) break;
    lam = xAx / xDx;
    double s = 1.0 / sqrt(xDx);
    for (int64_t i = 0; i < n; i++) x[i] = y[i] / d[i] * s;
  }
  vm_free(ctx, x);
  vm_free(ctx, y);
  vm_free(ctx, t);
  *rho = lam > 0 ? lam : 1.0;
  return VM_OK;
}

/* Smoother of a level: dinv = (4/3) / (rho(D^{-1}A) a_ii); rho is
 * estimated when `estimate`, else the level's previous estimate is kept
 * (numeric updates of a slowly changing matrix). */
static int level_smoother(vm_ctx *ctx, level *L, int lev, int estimate) {
  const int64_t n = L->A.nr;
  if (!L->dinv) {
    L->dinv = vm_alloc_array(ctx, (size_t)n ? (size_t)n : 1, sizeof *L->dinv);
    if (!L->dinv) return VM_ERR_NOMEM;
  }
  double *d = L->dinv;
  for (int64_t i = 0; i < n; i++) {
    d[i] = mat_diag(&L->A, i);
    if (!(d[i] > 0))
      return vm_error(ctx, VM_ERR_NUMERIC, "amg: non-positive diagonal %g in row %lld of level %d",
                      d[i], (long long)i, lev);
  }
  if (estimate || !(L->rho > 0)) {
    int st = spectral_radius(ctx, &L->A, d, &L->rho);
    if (st) return st;
  }
  double w = 4.0 / (3.0 * L->rho);
  for (int64_t i = 0; i < n; i++) d[i] = w / d[i];
  return VM_OK;
}

/* Filtered matrix: strong connections plus a lumped diagonal. a_ij is
 * strong when |a_ij| >= theta max_{k != i} |a_ik| (relative to the row, so
 * the 27-point stencils with small entries coarsen, and in anisotropic rows
 * only the dominant direction is strong). Weak entries are added to the
 * diagonal so that row sums (the constant near-kernel) are kept. */
static int filter_strong(vm_ctx *ctx, const mat *A, double theta, mat *F) {
  const int64_t n = A->nr;
  int st = mat_alloc(ctx, F, n, n, A->rp[n]);
  if (st) return st;
  int64_t pos = 0;
  for (int64_t i = 0; i < n; i++) {
    double rmax = 0;
    for (int64_t k = A->rp[i]; k < A->rp[i + 1]; k++)
      if (A->ci[k] != i && fabs(A->v[k]) > rmax) rmax = fabs(A->v[k]);
    double lump = 0;
    int64_t dpos = -1;
    for (int64_t k = A->rp[i]; k < A->rp[i + 1]; k++) {
      int32_t j = A->ci[k];
      if (j == i) {
        dpos = pos;
        F->ci[pos] = j;
        F->v[pos++] = A->v[k];
      } else if (A->v[k] != 0 && fabs(A->v[k]) >= theta * rmax) {
        F->ci[pos] = j;
        F->v[pos++] = A->v[k];
      } else {
        lump += A->v[k];
      }
    }
    if (dpos >= 0 && F->v[dpos] + lump > 0) F->v[dpos] += lump;
    F->rp[i + 1] = pos;
  }
  return VM_OK;
}

/* Three-phase greedy aggregation on the off-diagonal pattern of F (Vanek,
 * Mandel, Brezina): roots whose neighbourhood is free, then attach the rest
 * to a neighbouring root aggregate, then group leftovers. Isolated rows get
 * agg = -1 (no coarse unknown). Returns the number of aggregates. */
static int64_t aggregate(const mat *F, int32_t *agg) {
  const int64_t n = F->nr;
  int64_t na = 0;
  for (int64_t i = 0; i < n; i++) agg[i] = -2; /* -2: unassigned */
  for (int64_t i = 0; i < n; i++) {
    if (agg[i] != -2) continue;
    int nbr = 0, free_nbhd = 1;
    for (int64_t k = F->rp[i]; k < F->rp[i + 1]; k++) {
      int32_t j = F->ci[k];
      if (j == i) continue;
      nbr++;
      if (agg[j] != -2) free_nbhd = 0;
    }
    if (nbr == 0) {
      agg[i] = -1;
      continue;
    }
    if (!free_nbhd) continue;
    agg[i] = (int32_t)na;
    for (int64_t k = F->rp[i]; k < F->rp[i + 1]; k++) agg[F->ci[k]] = (int32_t)na;
    na++;
  }
  /* phase 2: join the aggregate of the strongest phase-1 neighbour; the
   * assignment is recorded as -3 - a so later rows cannot chain onto it */
  for (int64_t i = 0; i < n; i++) {
    if (agg[i] != -2) continue;
    double best = -1;
    int32_t a = -1;
    for (int64_t k = F->rp[i]; k < F->rp[i + 1]; k++) {
      int32_t j = F->ci[k];
      if (j != i && agg[j] >= 0 && fabs(F->v[k]) > best) {
        best = fabs(F->v[k]);
        a = agg[j];
      }
    }
    if (a >= 0) agg[i] = -3 - a;
  }
  for (int64_t i = 0; i < n; i++)
    if (agg[i] <= -3) agg[i] = -3 - agg[i];
  /* phase 3: leftovers with their unassigned neighbours */
  for (int64_t i = 0; i < n; i++) {
    if (agg[i] != -2) continue;
    agg[i] = (int32_t)na;
    for (int64_t k = F->rp[i]; k < F->rp[i + 1]; k++)
      if (agg[F->ci[k]] == -2) agg[F->ci[k]] = (int32_t)na;
    na++;
  }
  return na;
}

/* Unknown-based aggregation for 3x3 block systems (unknowns 3i..3i+2 are
 * node i): node strength from the Frobenius norms of the blocks (block IJ
 * strong when |A_IJ| >= theta max_{K != I} |A_IK|), nodes aggregated as in
 * aggregate(), and the scalar filtered matrix F: strong blocks and the
 * diagonal block kept, weak blocks added to the diagonal block (so A t is
 * kept for the translations t, the near-kernel, unless a diagonal entry
 * would become non-positive). agg (3 n_nodes, allocated here) maps unknown
 * 3i + c to coarse unknown 3 a(i) + c; *na gets the number of coarse
 * unknowns. */
static int block_aggregate(vm_ctx *ctx, const mat *A, double theta, mat *F, int32_t **agg_out,
                           int64_t *na_out) {
  const int64_t n = A->nr, nb = n / 3;
  *agg_out = NULL;
  memset(F, 0, sizeof *F);
  int64_t *mark = vm_alloc_array(ctx, (size_t)(nb ? nb : 1), sizeof *mark);
  int32_t *aggv = vm_alloc_array(ctx, (size_t)(nb ? nb : 1), sizeof *aggv);
  int32_t *agg = vm_alloc_array(ctx, (size_t)(n ? n : 1), sizeof *agg);
  int64_t *cols = vm_alloc_array(ctx, (size_t)(nb ? nb : 1), sizeof *cols);
  mat V;
  memset(&V, 0, sizeof V);
  int st = VM_OK;
  if (!mark || !aggv || !agg || !cols) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  /* node matrix of block norms (pattern: strong blocks and the diagonal) */
  int64_t nnzb = 0;
  for (int64_t I = 0; I < nb; I++) mark[I] = -1;
  for (int64_t I = 0; I < nb; I++)
    for (int r = 0; r < 3; r++)
      for (int64_t k = A->rp[3 * I + r]; k < A->rp[3 * I + r + 1]; k++) {
        int64_t J = A->ci[k] / 3;
        if (mark[J] != I) {
          mark[J] = I;
          nnzb++;
        }
      }
  st = mat_alloc(ctx, &V, nb, nb, nnzb);
  if (st) goto done;
  for (int64_t I = 0; I < nb; I++) mark[I] = -1;
  int64_t pos = 0;
  for (int64_t I = 0; I < nb; I++) {
    int64_t start = pos;
    for (int r = 0; r < 3; r++)
      for (int64_t k = A->rp[3 * I + r]; k < A->rp[3 * I + r + 1]; k++) {
        int64_t J = A->ci[k] / 3;
        if (mark[J] != I) {
          mark[J] = I;
          cols[J] = pos;
          V.ci[pos] = (int32_t)J;
          V.v[pos++] = 0;
        }
        V.v[cols[J]] += A->v[k] * A->v[k];
      }
    double rmax = 0;
    for (int64_t k = start; k < pos; k++) {
      V.v[k] = sqrt(V.v[k]);
      if (V.ci[k] != I && V.v[k] > rmax) rmax = V.v[k];
    }
    /* keep the diagonal and the strong blocks only */
    int64_t w = start;
    for (int64_t k = start; k < pos; k++)
      if (V.ci[k] == I || (V.v[k] > 0 && V.v[k] >= theta * rmax)) {
        V.ci[w] = V.ci[k];
        V.v[w++] = V.v[k];
      }
    pos = w;
    V.rp[I + 1] = pos;
  }
  int64_t na = aggregate(&V, aggv);
  /* the scalar filtered matrix */
  st = mat_alloc(ctx, F, n, n, A->rp[n]);
  if (st) goto done;
  pos = 0;
  for (int64_t I = 0; I < nb; I++) {
    /* strong block columns of node I */
    for (int64_t k = V.rp[I]; k < V.rp[I + 1]; k++) mark[V.ci[k]] = -2 - I;
    for (int r = 0; r < 3; r++) {
      int64_t i = 3 * I + r, dblk[3] = {-1, -1, -1};
      double lump[3] = {0, 0, 0};
      for (int64_t k = A->rp[i]; k < A->rp[i + 1]; k++) {
        int64_t c = A->ci[k], J = c / 3;
        if (mark[J] == -2 - I) {
          if (J == I) dblk[c - 3 * I] = pos;
          F->ci[pos] = (int32_t)c;
          F->v[pos++] = A->v[k];
        } else {
          lump[c % 3] += A->v[k];
        }
      }
      int ok = 1;
      if (dblk[r] < 0 || !(F->v[dblk[r]] + lump[r] > 0)) ok = 0;
      for (int q = 0; q < 3 && ok; q++)
        if (lump[q] != 0 && dblk[q] < 0) ok = 0;
      if (ok)
        for (int q = 0; q < 3; q++)
          if (dblk[q] >= 0) F->v[dblk[q]] += lump[q];
      F->rp[i + 1] = pos;
    }
  }
  for (int64_t I = 0; I < nb; I++)
    for (int c = 0; c < 3; c++) agg[3 * I + c] = aggv[I] < 0 ? -1 : 3 * aggv[I] + c;
  *agg_out = agg;
  agg = NULL;
  *na_out = 3 * na;
done:
  if (st) mat_free(ctx, F);
  mat_free(ctx, &V);
  vm_free(ctx, mark);
  vm_free(ctx, aggv);
  vm_free(ctx, agg);
  vm_free(ctx, cols);
  return st;
}

/* Prolongator: P = (I - w D_F^{-1} F) P0 (smoothed), or P = P0 (plain),
 * with P0 the aggregate indicator matrix. */
static int build_prolongator(vm_ctx *ctx, const mat *F, const int32_t *agg, int64_t na, int smooth,
                             mat *P) {
  const int64_t n = F->nr;
  if (!smooth) {
    int st = mat_alloc(ctx, P, n, na, n);
    if (st) return st;
    int64_t pos = 0;
    for (int64_t i = 0; i < n; i++) {
      if (agg[i] >= 0) {
        P->ci[pos] = agg[i];
        P->v[pos++] = 1.0;
      }
      P->rp[i + 1] = pos;
    }
    return VM_OK;
  }
  double *d = vm_alloc_array(ctx, (size_t)n ? (size_t)n : 1, sizeof *d);
  if (!d) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < n; i++) d[i] = mat_diag(F, i);
  double rho;
  int st = spectral_radius(ctx, F, d, &rho);
  if (st) {
    vm_free(ctx, d);
    return st;
  }
  double w = 4.0 / (3.0 * rho);
  /* each row of P touches at most the aggregates of the row of F */
  st = mat_alloc(ctx, P, n, na, F->rp[n]);
  if (st) {
    vm_free(ctx, d);
    return st;
  }
  int64_t *mark = vm_alloc_array(ctx, (size_t)na ? (size_t)na : 1, sizeof *mark);
  if (!mark) {
    vm_free(ctx, d);
    mat_free(ctx, P);
    return VM_ERR_NOMEM;
  }
  for (int64_t a = 0; a < na; a++) mark[a] = -1;
  int64_t pos = 0;
  for (int64_t i = 0; i < n; i++) {
    int64_t start = pos;
    double s = w / d[i];
    for (int64_t k = F->rp[i]; k < F->rp[i + 1]; k++) {
      int32_t j = F->ci[k];
      int32_t a = agg[j];
      if (a < 0) continue;
      double v = (j == i ? 1.0 : 0.0) - s * F->v[k];
      if (mark[a] < start) {
        mark[a] = pos;
        P->ci[pos] = a;
        P->v[pos++] = v;
      } else {
        P->v[mark[a]] += v;
      }
    }
    P->rp[i + 1] = pos;
  }
  vm_free(ctx, mark);
  vm_free(ctx, d);
  /* the bound above was the row lengths of F: P keeps what it uses */
  int32_t *ci = vm_realloc(ctx, P->ci, (size_t)(pos ? pos : 1) * sizeof *ci);
  if (ci) P->ci = ci;
  double *v = ci ? vm_realloc(ctx, P->v, (size_t)(pos ? pos : 1) * sizeof *v) : NULL;
  if (v) P->v = v;
  if (!ci || !v) {
    mat_free(ctx, P);
    return VM_ERR_NOMEM;
  }
  return VM_OK;
}

/* Galerkin coarse operator R A P. */
static int galerkin(vm_ctx *ctx, const level *L, mat *Ac) {
  mat AP;
  int st = mat_mul(ctx, &L->A, &L->P, &AP);
  if (st) return st;
  st = mat_mul(ctx, &L->R, &AP, Ac);
  mat_free(ctx, &AP);
  return st;
}

static int level_vectors(vm_ctx *ctx, level *L) {
  size_t n = L->A.nr ? (size_t)L->A.nr : 1;
  L->b = vm_alloc_array(ctx, n, sizeof *L->b);
  L->x = vm_alloc_array(ctx, n, sizeof *L->x);
  L->r = vm_alloc_array(ctx, n, sizeof *L->r);
  return (L->b && L->x && L->r) ? VM_OK : VM_ERR_NOMEM;
}

/* Dense Cholesky of the coarsest operator; pivots that are numerically
 * zero (a singular, e.g. pure Neumann, operator) are dropped. */
static int coarse_factor(vm_ctx *ctx, amg_impl *M) {
  const mat *A = &M->lev[M->nlev - 1].A;
  const int64_t n = A->nr;
  vm_free(ctx, M->chol);
  vm_free(ctx, M->cnull);
  M->chol = vm_calloc(ctx, n > 0 ? (size_t)n * (size_t)n : 1, sizeof *M->chol);
  M->cnull = vm_calloc(ctx, (size_t)(n ? n : 1), 1);
  if (!M->chol || !M->cnull) return VM_ERR_NOMEM;
  double *L = M->chol, dmax = 0;
  for (int64_t i = 0; i < n; i++)
    for (int64_t k = A->rp[i]; k < A->rp[i + 1]; k++) {
      L[i * n + A->ci[k]] = A->v[k];
      if (A->ci[k] == i && A->v[k] > dmax) dmax = A->v[k];
    }
  for (int64_t j = 0; j < n; j++) {
    double s = L[j * n + j];
    for (int64_t k = 0; k < j; k++) s -= L[j * n + k] * L[j * n + k];
    if (!(s > 1e-13 * dmax)) {
      M->cnull[j] = 1;
      for (int64_t i = j; i < n; i++) L[i * n + j] = 0;
      continue;
    }
    double ljj = sqrt(s);
    L[j * n + j] = ljj;
    for (int64_t i = j + 1; i < n; i++) {
      double t = L[i * n + j];
      for (int64_t k = 0; k < j; k++) t -= L[i * n + k] * L[j * n + k];
      L[i * n + j] = t / ljj;
    }
  }
  return VM_OK;
}

static void coarse_solve(const amg_impl *M, const double *b, double *x) {
  const int64_t n = M->lev[M->nlev - 1].A.nr;
  const double *L = M->chol;
  for (int64_t i = 0; i < n; i++) {
    if (M->cnull[i]) {
      x[i] = 0;
      continue;
    }
    double s = b[i];
    for (int64_t k = 0; k < i; k++) s -= L[i * n + k] * x[k];
    x[i] = s / L[i * n + i];
  }
  for (int64_t i = n - 1; i >= 0; i--) {
    if (M->cnull[i]) continue;
    double s = x[i];
    for (int64_t k = i + 1; k < n; k++) s -= L[k * n + i] * x[k];
    x[i] = s / L[i * n + i];
  }
}

/* x = omega D^{-1} (b - A x) + x; from_zero: x = omega D^{-1} b. */
static void jacobi_sweep(vm_ctx *ctx, level *L, const double *b, double *x, int from_zero) {
  const int64_t n = L->A.nr;
  int nt = vm_nthreads(ctx);
  if (from_zero) {
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
    for (int64_t i = 0; i < n; i++) x[i] = L->dinv[i] * b[i];
    return;
  }
  mat_mv(ctx, &L->A, x, L->r, 0);
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
  for (int64_t i = 0; i < n; i++) x[i] += L->dinv[i] * (b[i] - L->r[i]);
}

static void vcycle(vm_ctx *ctx, amg_impl *M, int sweeps, int l, const double *b, double *x) {
  level *L = &M->lev[l];
  const int64_t n = L->A.nr;
  if (l == M->nlev - 1) {
    if (M->dense) {
      coarse_solve(M, b, x);
    } else {
      jacobi_sweep(ctx, L, b, x, 1);
      for (int s = 1; s < AMG_COARSE_SWEEPS; s++) jacobi_sweep(ctx, L, b, x, 0);
    }
    return;
  }
  jacobi_sweep(ctx, L, b, x, 1);
  for (int s = 1; s < sweeps; s++) jacobi_sweep(ctx, L, b, x, 0);
  int nt = vm_nthreads(ctx);
  mat_mv(ctx, &L->A, x, L->r, 0);
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
  for (int64_t i = 0; i < n; i++) L->r[i] = b[i] - L->r[i];
  level *C = &M->lev[l + 1];
  mat_mv(ctx, &L->R, L->r, C->b, 0);
  vcycle(ctx, M, sweeps, l + 1, C->b, C->x);
  mat_mv(ctx, &L->P, C->x, x, 1);
  for (int s = 0; s < sweeps; s++) jacobi_sweep(ctx, L, b, x, 0);
}

static void amg_destroy(vm_precond *p) {
  amg_impl *M = p->impl;
  if (!M) return;
  amg_clear(p->ctx, M);
  vm_free(p->ctx, M);
  p->impl = NULL;
}

/* Smoothers of every level and the coarsest factorization. */
static int finish_levels(vm_ctx *ctx, amg_impl *M, int estimate) {
  for (int l = 0; l < M->nlev; l++) {
    int st = level_smoother(ctx, &M->lev[l], l, estimate);
    if (st) return st;
  }
  if (M->dense) return coarse_factor(ctx, M);
  return VM_OK;
}

static int amg_setup(vm_precond *p, const vm_csr *A) {
  vm_ctx *ctx = p->ctx;
  amg_impl *M = p->impl;
  if (!M) {
    M = vm_calloc(ctx, 1, sizeof *M);
    if (!M) return VM_ERR_NOMEM;
    p->impl = M;
  }
  amg_clear(ctx, M);
  const vm_amg_options *o = &p->amg;
  int maxlev = o->max_levels < 1                ? 1
               : o->max_levels > AMG_MAX_LEVELS ? AMG_MAX_LEVELS
                                                : o->max_levels;
  int64_t csize = o->coarse_size < 1 ? 1 : o->coarse_size;
  M->n0 = A->n;
  M->nnz0 = A->rowptr[A->n];
  mat_view(&M->lev[0].A, A);
  M->nlev = 1;
  int st = VM_OK;
  int32_t *agg = NULL;
  double theta = o->strength;
  for (;;) {
    level *L = &M->lev[M->nlev - 1];
    if (L->A.nr <= csize || M->nlev == maxlev) break;
    mat F;
    int64_t na;
    if (o->block_size == 3 && L->A.nr % 3 == 0) {
      st = block_aggregate(ctx, &L->A, theta, &F, &agg, &na);
      if (st) goto fail;
    } else {
      st = filter_strong(ctx, &L->A, theta, &F);
      if (st) goto fail;
      agg = vm_alloc_array(ctx, (size_t)L->A.nr, sizeof *agg);
      if (!agg) {
        mat_free(ctx, &F);
        st = VM_ERR_NOMEM;
        goto fail;
      }
      na = aggregate(&F, agg);
    }
    if (na == 0 || (double)na > 0.8 * (double)L->A.nr) {
      mat_free(ctx, &F);
      break; /* coarsening stalled: this is the coarsest level */
    }
    st = build_prolongator(ctx, &F, agg, na, o->smooth_prolongator, &L->P);
    mat_free(ctx, &F);
    vm_free(ctx, agg);
    agg = NULL;
    if (st) goto fail;
    st = mat_transpose(ctx, &L->P, &L->R);
    if (st) goto fail;
    level *C = &M->lev[M->nlev];
    st = galerkin(ctx, L, &C->A);
    if (st) goto fail;
    M->nlev++;
  }
  vm_free(ctx, agg);
  agg = NULL;
  for (int l = 0; l < M->nlev; l++) {
    if (l > 0) {
      st = level_vectors(ctx, &M->lev[l]);
      if (st) goto fail;
    } else {
      M->lev[0].r = vm_alloc_array(ctx, (size_t)(A->n ? A->n : 1), sizeof(double));
      if (!M->lev[0].r) {
        st = VM_ERR_NOMEM;
        goto fail;
      }
    }
  }
  M->dense = M->lev[M->nlev - 1].A.nr <= AMG_DENSE_MAX;
  st = finish_levels(ctx, M, 1);
  if (st) goto fail;
  return VM_OK;
fail:
  vm_free(ctx, agg);
  amg_clear(ctx, M);
  return st;
}

static int amg_update(vm_precond *p, const vm_csr *A) {
  amg_impl *M = p->impl;
  if (!M || M->nlev == 0 || M->n0 != A->n || M->nnz0 != A->rowptr[A->n]) return amg_setup(p, A);
  vm_ctx *ctx = p->ctx;
  mat_view(&M->lev[0].A, A);
  if (!p->amg.update_coarse && M->nlev > 1) {
    int st = level_smoother(ctx, &M->lev[0], 0, 0);
    if (st) amg_clear(ctx, M);
    return st;
  }
  for (int l = 0; l + 1 < M->nlev; l++) {
    mat Ac;
    int st = galerkin(ctx, &M->lev[l], &Ac);
    if (st) {
      amg_clear(ctx, M);
      return st;
    }
    mat_free(ctx, &M->lev[l + 1].A);
    M->lev[l + 1].A = Ac;
  }
  int st = finish_levels(ctx, M, 0);
  if (st) amg_clear(ctx, M);
  return st;
}

static void amg_apply(vm_precond *p, const double *r, double *z) {
  amg_impl *M = p->impl;
  if (M->nlev == 0) { /* no hierarchy after a failed setup: identity */
    memcpy(z, r, (size_t)M->n0 * sizeof *z);
    return;
  }
  int sweeps = p->amg.sweeps < 1 ? 1 : p->amg.sweeps;
  vcycle(p->ctx, M, sweeps, 0, r, z);
}

static void amg_info(const vm_precond *p, vm_precond_info *info) {
  const amg_impl *M = p->impl;
  info->levels = M->nlev;
  info->coarse_n = M->nlev ? M->lev[M->nlev - 1].A.nr : 0;
  double nnz0 = M->nlev ? (double)M->lev[0].A.rp[M->lev[0].A.nr] : 0, tot = 0;
  for (int l = 0; l < M->nlev; l++) tot += (double)M->lev[l].A.rp[M->lev[l].A.nr];
  info->op_complexity = nnz0 > 0 ? tot / nnz0 : 1.0;
}

const vm_precond_ops vm_precond_amg_ops = {"amg",     amg_setup, amg_update,
                                           amg_apply, amg_info,  amg_destroy};
