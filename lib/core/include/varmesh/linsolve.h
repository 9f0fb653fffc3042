/* varmesh/linsolve.h: sparse symmetric positive definite systems: CSR
 * matrices, preconditioners (Jacobi, smoothed-aggregation AMG) and the
 * preconditioned conjugate gradient method used by the implicit minimizer. */
#ifndef VARMESH_LINSOLVE_H
#define VARMESH_LINSOLVE_H

#include <stdint.h>

#include "varmesh/ctx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A square sparse matrix in compressed sparse row form (plain data).
 * Row i holds col[rowptr[i] .. rowptr[i+1]) sorted ascending, the diagonal
 * included; val holds the matching values. */
typedef struct vm_csr {
  int64_t n;
  int64_t *rowptr; /* n + 1 */
  int32_t *col;    /* rowptr[n] */
  double *val;     /* rowptr[n] */
} vm_csr;

/* Allocate the arrays of an n x n matrix with room for nnz entries
 * (rowptr zeroed, col/val uninitialized). Returns VM_OK, VM_ERR_ARG or
 * VM_ERR_NOMEM. Free with vm_csr_free. */
int vm_csr_alloc(vm_ctx *ctx, vm_csr *A, int64_t n, int64_t nnz);
/* Free the arrays of A and zero it (A itself is the caller's). */
void vm_csr_free(vm_ctx *ctx, vm_csr *A);
/* y = A x, rows in parallel (bitwise the same for any thread count). */
void vm_csr_matvec(vm_ctx *ctx, const vm_csr *A, const double *x, double *y);

/* Preconditioner kinds. */
typedef enum {
  VM_PRECOND_NONE = 0,        /* identity */
  VM_PRECOND_JACOBI = 1,      /* inverse diagonal */
  VM_PRECOND_AMG = 2,         /* smoothed-aggregation algebraic multigrid V-cycle */
  VM_PRECOND_BLOCK_JACOBI = 3 /* inverse 3x3 diagonal blocks: unknowns 3i, 3i+1,
                                 3i+2 form block i (n a multiple of 3) */
} vm_precond_kind;

/* AMG parameters. strength: a_ij is a strong connection when
 * |a_ij| >= strength * max_{k != i} |a_ik|; smooth_prolongator: 1 smoothed
 * aggregation, 0 plain (piecewise constant) aggregation; sweeps: damped
 * Jacobi sweeps before and after the coarse correction (the V-cycle is
 * symmetric, so PCG stays valid); coarse_size: direct (dense Cholesky)
 * solve at or below this many unknowns; max_levels caps the hierarchy. */
typedef struct vm_amg_options {
  double strength;
  int smooth_prolongator;
  int sweeps;
  int coarse_size;
  int max_levels;
  int update_coarse; /* vm_precond_update: 1 recompute the coarse operators
                        (Galerkin), 0 keep them (only the finest smoother
                        follows the new matrix) */
  int block_size;    /* 1 (default): scalar aggregation; 3: unknowns 3i..3i+2
                        are the coordinates of one node (n a multiple of 3):
                        nodes are aggregated by the Frobenius norms of the
                        3x3 blocks and each coordinate is coarsened on its
                        own within a node aggregate ("unknown-based"), so
                        every level keeps the 3x3 block structure */
} vm_amg_options;

/* Defaults: strength 0.25, smoothed, 1 sweep, coarse_size 400, 12 levels,
 * update_coarse 1, block_size 1. */
vm_amg_options vm_amg_options_default(void);

/* A preconditioner: an opaque object with a table of operations chosen
 * by kind (Jacobi in pcg.c, AMG in amg.c). */
typedef struct vm_precond vm_precond;

/* Create a preconditioner of `kind`; amg may be NULL (defaults; ignored by
 * the other kinds). Free with vm_precond_destroy. */
int vm_precond_create(vm_ctx *ctx, vm_precond_kind kind, const vm_amg_options *amg,
                      vm_precond **out);
void vm_precond_destroy(vm_precond **p);
vm_precond_kind vm_precond_get_kind(const vm_precond *p);

/* Full setup for matrix A (symmetric, positive diagonal): for AMG builds
 * the hierarchy (aggregates, prolongators, coarse operators). A is
 * referenced, not copied: it must stay valid and unchanged while the
 * preconditioner is applied. Returns VM_OK, VM_ERR_NOMEM, VM_ERR_ARG or
 * VM_ERR_NUMERIC (non-positive diagonal). After a failed setup, apply is
 * the identity. */
int vm_precond_setup(vm_precond *p, const vm_csr *A);
/* Cheaper re-setup for a matrix with the same size and pattern as at the
 * last full setup but new values: AMG keeps its aggregates, prolongators
 * and spectral estimates and recomputes the smoother diagonals and (with
 * update_coarse) the coarse operators. Falls back to a full setup when
 * there was none or the size differs. */
int vm_precond_update(vm_precond *p, const vm_csr *A);
/* z = M^{-1} r (r and z distinct, length n of the last setup). */
void vm_precond_apply(vm_precond *p, const double *r, double *z);

/* Hierarchy description (AMG; Jacobi and identity report one level):
 * levels, unknowns on the coarsest level, and operator complexity
 * (total nonzeros over all levels / nonzeros of the finest). */
typedef struct vm_precond_info {
  int levels;
  int64_t coarse_n;
  double op_complexity;
} vm_precond_info;
void vm_precond_get_info(const vm_precond *p, vm_precond_info *info);

/* Conjugate gradients. Stops when |r|_2 <= rtol |b|_2 or after maxit
 * iterations. */
typedef struct vm_pcg_options {
  double rtol;
  int maxit;
} vm_pcg_options;

typedef struct vm_pcg_result {
  int iterations;
  double rel_residual; /* |b - A x|_2 / |b|_2 at exit (recurrence value) */
  int converged;       /* 1 if rtol was reached */
  int breakdown;       /* 1 if p^T A p <= 0 was met (x is the last good iterate) */
} vm_pcg_result;

/* Solve A x = b by preconditioned CG from the initial guess in x (M may
 * be NULL: no preconditioner). Deterministic: inner products are summed in
 * a fixed order, so the bits do not depend on the thread count.
 * Returns VM_OK (also when maxit was reached: see res), VM_ERR_NOMEM,
 * VM_ERR_NUMERIC (NaN in the iteration). */
int vm_pcg_solve(vm_ctx *ctx, const vm_csr *A, vm_precond *M, const double *b, double *x,
                 const vm_pcg_options *opt, vm_pcg_result *res);

#ifdef __cplusplus
}
#endif
#endif
