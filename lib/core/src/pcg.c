/* lib/core/src/pcg.c: CSR matrices, the preconditioner interface with its
 * Jacobi member, deterministic inner products and preconditioned CG. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "linsolve_private.h"

int vm_nthreads(const vm_ctx *ctx) {
  int t = vm_ctx_threads(ctx);
  return t > 0 ? t : omp_get_max_threads();
}

#define DOT_MAX_BLOCKS 1024

double vm_dot(const vm_ctx *ctx, int64_t n, const double *a, const double *b) {
  if (n <= 0) return 0.0;
  int64_t bs = 2048;
  if ((n + bs - 1) / bs > DOT_MAX_BLOCKS) bs = (n + DOT_MAX_BLOCKS - 1) / DOT_MAX_BLOCKS;
  int64_t nb = (n + bs - 1) / bs;
  double part[DOT_MAX_BLOCKS];
  int nt = vm_nthreads(ctx);
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
  for (int64_t k = 0; k < nb; k++) {
    int64_t i0 = k * bs, i1 = i0 + bs < n ? i0 + bs : n;
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    int64_t i = i0;
    for (; i + 4 <= i1; i += 4) {
      s0 += a[i] * b[i];
      s1 += a[i + 1] * b[i + 1];
      s2 += a[i + 2] * b[i + 2];
      s3 += a[i + 3] * b[i + 3];
    }
    for (; i < i1; i++) s0 += a[i] * b[i];
    part[k] = (s0 + s1) + (s2 + s3);
  }
  double s = 0;
  for (int64_t k = 0; k < nb; k++) s += part[k];
  return s;
}

int vm_csr_alloc(vm_ctx *ctx, vm_csr *A, int64_t n, int64_t nnz) {
  if (!A || n < 0 || nnz < 0) return vm_error(ctx, VM_ERR_ARG, "vm_csr_alloc: bad size");
  memset(A, 0, sizeof *A);
  A->rowptr = vm_calloc(ctx, (size_t)n + 1, sizeof *A->rowptr);
  A->col = vm_alloc_array(ctx, nnz ? (size_t)nnz : 1, sizeof *A->col);
  A->val = vm_alloc_array(ctx, nnz ? (size_t)nnz : 1, sizeof *A->val);
  if (!A->rowptr || !A->col || !A->val) {
    vm_csr_free(ctx, A);
    return VM_ERR_NOMEM;
  }
  A->n = n;
  return VM_OK;
}

void vm_csr_free(vm_ctx *ctx, vm_csr *A) {
  if (!A) return;
  vm_free(ctx, A->rowptr);
  vm_free(ctx, A->col);
  vm_free(ctx, A->val);
  memset(A, 0, sizeof *A);
}

void vm_csr_matvec(vm_ctx *ctx, const vm_csr *A, const double *x, double *y) {
  int nt = vm_nthreads(ctx);
  const int64_t n = A->n;
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN_MV)
  for (int64_t i = 0; i < n; i++) {
    double s = 0;
    for (int64_t k = A->rowptr[i]; k < A->rowptr[i + 1]; k++) s += A->val[k] * x[A->col[k]];
    y[i] = s;
  }
}

/* Jacobi: z = D^{-1} r. */
typedef struct {
  int64_t n;
  double *dinv;
} jacobi_impl;

static void jacobi_destroy(vm_precond *p) {
  jacobi_impl *J = p->impl;
  if (!J) return;
  vm_free(p->ctx, J->dinv);
  vm_free(p->ctx, J);
  p->impl = NULL;
}

static int jacobi_setup(vm_precond *p, const vm_csr *A) {
  jacobi_impl *J = p->impl;
  if (!J || J->n != A->n) {
    jacobi_destroy(p);
    J = vm_calloc(p->ctx, 1, sizeof *J);
    if (!J) return VM_ERR_NOMEM;
    p->impl = J;
    J->dinv = vm_alloc_array(p->ctx, A->n ? (size_t)A->n : 1, sizeof *J->dinv);
    if (!J->dinv) return VM_ERR_NOMEM;
    J->n = A->n;
  }
  for (int64_t i = 0; i < A->n; i++) {
    double d = 0;
    for (int64_t k = A->rowptr[i]; k < A->rowptr[i + 1]; k++)
      if (A->col[k] == i) d = A->val[k];
    if (!(d > 0)) {
      for (int64_t k = i; k < A->n; k++) J->dinv[k] = 1.0;
      return vm_error(p->ctx, VM_ERR_NUMERIC, "jacobi: non-positive diagonal in row %lld",
                      (long long)i);
    }
    J->dinv[i] = 1.0 / d;
  }
  return VM_OK;
}

static void jacobi_apply(vm_precond *p, const double *r, double *z) {
  const jacobi_impl *J = p->impl;
  int nt = vm_nthreads(p->ctx);
  const int64_t n = J->n;
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
  for (int64_t i = 0; i < n; i++) z[i] = J->dinv[i] * r[i];
}

static void jacobi_info(const vm_precond *p, vm_precond_info *info) {
  const jacobi_impl *J = p->impl;
  info->levels = 1;
  info->coarse_n = J ? J->n : 0;
  info->op_complexity = 1.0;
}

static const vm_precond_ops jacobi_ops = {"jacobi",     jacobi_setup, jacobi_setup,
                                          jacobi_apply, jacobi_info,  jacobi_destroy};

/* Block Jacobi: z_i = D_i^{-1} r_i with D_i the 3x3 diagonal block of
 * unknowns 3i..3i+2 (inverted through its Cholesky factor; a block that is
 * not positive definite falls back to its diagonal). */
typedef struct {
  int64_t n;
  double *binv; /* 9 per block, the symmetric inverse */
} bjacobi_impl;

static void bjacobi_destroy(vm_precond *p) {
  bjacobi_impl *J = p->impl;
  if (!J) return;
  vm_free(p->ctx, J->binv);
  vm_free(p->ctx, J);
  p->impl = NULL;
}

/* Inverse of the symmetric positive definite 3x3 B into X; nonzero if B
 * is not numerically positive definite. */
static int spd3_inverse(const double *B, double *X) {
  double l00 = B[0], tol = 1e-14 * (fabs(B[0]) + fabs(B[4]) + fabs(B[8]));
  if (!(l00 > tol)) return 1;
  l00 = sqrt(l00);
  double l10 = B[3] / l00, l20 = B[6] / l00;
  double d1 = B[4] - l10 * l10;
  if (!(d1 > tol)) return 1;
  double l11 = sqrt(d1), l21 = (B[7] - l20 * l10) / l11;
  double d2 = B[8] - l20 * l20 - l21 * l21;
  if (!(d2 > tol)) return 1;
  double l22 = sqrt(d2);
  /* inverse of L (lower), then X = L^{-T} L^{-1} */
  double i00 = 1 / l00, i11 = 1 / l11, i22 = 1 / l22;
  double i10 = -l10 * i00 * i11, i21 = -l21 * i11 * i22;
  double i20 = -(l20 * i00 + l21 * i10) * i22;
  X[0] = i00 * i00 + i10 * i10 + i20 * i20;
  X[1] = X[3] = i10 * i11 + i20 * i21;
  X[2] = X[6] = i20 * i22;
  X[4] = i11 * i11 + i21 * i21;
  X[5] = X[7] = i21 * i22;
  X[8] = i22 * i22;
  return 0;
}

static int bjacobi_setup(vm_precond *p, const vm_csr *A) {
  if (A->n % 3)
    return vm_error(p->ctx, VM_ERR_ARG, "block jacobi: n = %lld is not a multiple of 3",
                    (long long)A->n);
  bjacobi_impl *J = p->impl;
  if (!J || J->n != A->n) {
    bjacobi_destroy(p);
    J = vm_calloc(p->ctx, 1, sizeof *J);
    if (!J) return VM_ERR_NOMEM;
    p->impl = J;
    J->binv = vm_alloc_array(p->ctx, A->n ? (size_t)(3 * A->n) : 1, sizeof *J->binv);
    if (!J->binv) return VM_ERR_NOMEM;
    J->n = A->n;
  }
  const int64_t nb = A->n / 3;
  int bad = 0;
  int nt = vm_nthreads(p->ctx);
#pragma omp parallel for num_threads(nt) schedule(static) if (nb >= VM_PAR_MIN / 8)                \
    reduction(|                                                                                    \
              : bad)
  for (int64_t i = 0; i < nb; i++) {
    double B[9] = {0};
    for (int r = 0; r < 3; r++) {
      int64_t row = 3 * i + r;
      for (int64_t k = A->rowptr[row]; k < A->rowptr[row + 1]; k++) {
        int64_t c = A->col[k] - 3 * i;
        if (c >= 0 && c < 3) B[3 * r + c] = A->val[k];
      }
    }
    for (int r = 0; r < 3; r++)
      for (int c = r + 1; c < 3; c++)
        B[3 * r + c] = B[3 * c + r] = 0.5 * (B[3 * r + c] + B[3 * c + r]);
    double *X = J->binv + 9 * i;
    if (spd3_inverse(B, X)) {
      for (int k = 0; k < 9; k++) X[k] = 0;
      for (int r = 0; r < 3; r++) {
        if (B[4 * r] > 0)
          X[4 * r] = 1 / B[4 * r];
        else {
          X[4 * r] = 1;
          bad = 1;
        }
      }
    }
  }
  if (bad) return vm_error(p->ctx, VM_ERR_NUMERIC, "block jacobi: non-positive diagonal");
  return VM_OK;
}

static void bjacobi_apply(vm_precond *p, const double *r, double *z) {
  const bjacobi_impl *J = p->impl;
  int nt = vm_nthreads(p->ctx);
  const int64_t nb = J->n / 3;
#pragma omp parallel for num_threads(nt) schedule(static) if (nb >= VM_PAR_MIN / 4)
  for (int64_t i = 0; i < nb; i++) {
    const double *X = J->binv + 9 * i, *ri = r + 3 * i;
    double *zi = z + 3 * i;
    zi[0] = X[0] * ri[0] + X[1] * ri[1] + X[2] * ri[2];
    zi[1] = X[3] * ri[0] + X[4] * ri[1] + X[5] * ri[2];
    zi[2] = X[6] * ri[0] + X[7] * ri[1] + X[8] * ri[2];
  }
}

static void bjacobi_info(const vm_precond *p, vm_precond_info *info) {
  const bjacobi_impl *J = p->impl;
  info->levels = 1;
  info->coarse_n = J ? J->n : 0;
  info->op_complexity = 1.0;
}

static const vm_precond_ops bjacobi_ops = {"block-jacobi", bjacobi_setup, bjacobi_setup,
                                           bjacobi_apply,  bjacobi_info,  bjacobi_destroy};

/* Identity: z = r. */
typedef struct {
  int64_t n;
} identity_impl;

static void identity_destroy(vm_precond *p) {
  vm_free(p->ctx, p->impl);
  p->impl = NULL;
}

static int identity_setup(vm_precond *p, const vm_csr *A) {
  identity_impl *I = p->impl;
  if (!I) {
    I = vm_calloc(p->ctx, 1, sizeof *I);
    if (!I) return VM_ERR_NOMEM;
    p->impl = I;
  }
  I->n = A->n;
  return VM_OK;
}

static void identity_apply(vm_precond *p, const double *r, double *z) {
  const identity_impl *I = p->impl;
  memcpy(z, r, (size_t)I->n * sizeof *z);
}

static void identity_info(const vm_precond *p, vm_precond_info *info) {
  const identity_impl *I = p->impl;
  info->levels = 1;
  info->coarse_n = I ? I->n : 0;
  info->op_complexity = 1.0;
}

static const vm_precond_ops identity_ops = {"none",         identity_setup, identity_setup,
                                            identity_apply, identity_info,  identity_destroy};

vm_amg_options vm_amg_options_default(void) {
  vm_amg_options o;
  o.strength = 0.25;
  o.smooth_prolongator = 1;
  o.sweeps = 1;
  o.coarse_size = 400;
  o.max_levels = 12;
  o.update_coarse = 1;
  o.block_size = 1;
  return o;
}

int vm_precond_create(vm_ctx *ctx, vm_precond_kind kind, const vm_amg_options *amg,
                      vm_precond **out) {
  static const vm_precond_ops *const table[] = {&identity_ops, &jacobi_ops, &vm_precond_amg_ops,
                                                &bjacobi_ops};
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_precond_create: out is NULL");
  *out = NULL;
  if ((int)kind < 0 || (int)kind >= (int)(sizeof table / sizeof table[0]))
    return vm_error(ctx, VM_ERR_ARG, "vm_precond_create: unknown kind %d", (int)kind);
  vm_precond *p = vm_calloc(ctx, 1, sizeof *p);
  if (!p) return VM_ERR_NOMEM;
  p->ctx = ctx;
  p->kind = kind;
  p->ops = table[kind];
  p->amg = amg ? *amg : vm_amg_options_default();
  *out = p;
  return VM_OK;
}

void vm_precond_destroy(vm_precond **pp) {
  if (!pp || !*pp) return;
  vm_precond *p = *pp;
  p->ops->destroy(p);
  vm_free(p->ctx, p);
  *pp = NULL;
}

vm_precond_kind vm_precond_get_kind(const vm_precond *p) { return p->kind; }

int vm_precond_setup(vm_precond *p, const vm_csr *A) {
  if (!p || !A || A->n < 0) return VM_ERR_ARG;
  return p->ops->setup(p, A);
}

int vm_precond_update(vm_precond *p, const vm_csr *A) {
  if (!p || !A || A->n < 0) return VM_ERR_ARG;
  return p->ops->update(p, A);
}

void vm_precond_apply(vm_precond *p, const double *r, double *z) { p->ops->apply(p, r, z); }

void vm_precond_get_info(const vm_precond *p, vm_precond_info *info) {
  memset(info, 0, sizeof *info);
  if (p && p->impl) p->ops->info(p, info);
}

int vm_pcg_solve(vm_ctx *ctx, const vm_csr *A, vm_precond *M, const double *b, double *x,
                 const vm_pcg_options *opt, vm_pcg_result *res) {
  vm_pcg_result rr = {0, 0.0, 0, 0};
  const int64_t n = A->n;
  double rtol = opt ? opt->rtol : 1e-8;
  int maxit = opt ? opt->maxit : 1000;
  if (res) *res = rr;
  if (n == 0) {
    if (res) res->converged = 1;
    return VM_OK;
  }
  double *r = vm_alloc_array(ctx, (size_t)n, sizeof *r);
  double *z = vm_alloc_array(ctx, (size_t)n, sizeof *z);
  double *p = vm_alloc_array(ctx, (size_t)n, sizeof *p);
  double *q = vm_alloc_array(ctx, (size_t)n, sizeof *q);
  int status = VM_OK;
  if (!r || !z || !p || !q) {
    status = VM_ERR_NOMEM;
    goto done;
  }
  int nt = vm_nthreads(ctx);
  vm_csr_matvec(ctx, A, x, q);
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
  for (int64_t i = 0; i < n; i++) r[i] = b[i] - q[i];
  double bnorm = sqrt(vm_dot(ctx, n, b, b));
  double rnorm = sqrt(vm_dot(ctx, n, r, r));
  if (bnorm == 0) bnorm = 1;
  rr.rel_residual = rnorm / bnorm;
  if (!isfinite(rnorm)) {
    status = vm_error(ctx, VM_ERR_NUMERIC, "pcg: non-finite residual");
    goto done;
  }
  if (rnorm <= rtol * bnorm) {
    rr.converged = 1;
    goto done;
  }
  if (M)
    vm_precond_apply(M, r, z);
  else
    memcpy(z, r, (size_t)n * sizeof *z);
  memcpy(p, z, (size_t)n * sizeof *p);
  double rz = vm_dot(ctx, n, r, z);
  for (int it = 1; it <= maxit; it++) {
    vm_csr_matvec(ctx, A, p, q);
    double pq = vm_dot(ctx, n, p, q);
    if (!isfinite(pq) || !isfinite(rz)) {
      status = vm_error(ctx, VM_ERR_NUMERIC, "pcg: non-finite value at iteration %d", it);
      goto done;
    }
    if (!(pq > 0) || !(rz > 0)) {
      rr.breakdown = 1;
      break;
    }
    double alpha = rz / pq;
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
    for (int64_t i = 0; i < n; i++) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
    }
    rr.iterations = it;
    rnorm = sqrt(vm_dot(ctx, n, r, r));
    rr.rel_residual = rnorm / bnorm;
    if (rnorm <= rtol * bnorm) {
      rr.converged = 1;
      break;
    }
    if (M)
      vm_precond_apply(M, r, z);
    else
      memcpy(z, r, (size_t)n * sizeof *z);
    double rz1 = vm_dot(ctx, n, r, z);
    double beta = rz1 / rz;
    rz = rz1;
#pragma omp parallel for num_threads(nt) schedule(static) if (n >= VM_PAR_MIN)
    for (int64_t i = 0; i < n; i++) p[i] = z[i] + beta * p[i];
  }
done:
  vm_free(ctx, r);
  vm_free(ctx, z);
  vm_free(ctx, p);
  vm_free(ctx, q);
  if (res) *res = rr;
  return status;
}
