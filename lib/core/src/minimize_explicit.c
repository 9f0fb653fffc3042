/* lib/core/src/minimize_explicit.c: the explicit minimizer: H_ij = 0 for i != j
 * (34), a projected 3x3 Newton step per vertex. */
#include <math.h>
#include <string.h>

#include "linsolve_private.h"
#include "minimize_private.h"

/* Cholesky solve of the k x k system (A + mu I) a = b; 0 if positive
 * definite (pivots above tol). */
static int chol_solve(const double *A, int k, double mu, double tol, const double *b, double *a) {
  double L[9] = {0};
  for (int j = 0; j < k; j++) {
    double s = A[j * 3 + j] + mu;
    for (int p = 0; p < j; p++) s -= L[j * 3 + p] * L[j * 3 + p];
    if (!(s > tol)) return 1;
    L[j * 3 + j] = sqrt(s);
    for (int i = j + 1; i < k; i++) {
      double t = A[i * 3 + j];
      for (int p = 0; p < j; p++) t -= L[i * 3 + p] * L[j * 3 + p];
      L[i * 3 + j] = t / L[j * 3 + j];
    }
  }
  double y[3];
  for (int i = 0; i < k; i++) {
    double s = b[i];
    for (int p = 0; p < i; p++) s -= L[i * 3 + p] * y[p];
    y[i] = s / L[i * 3 + i];
  }
  for (int i = k - 1; i >= 0; i--) {
    double s = y[i];
    for (int p = i + 1; p < k; p++) s -= L[p * 3 + i] * a[p];
    a[i] = s / L[i * 3 + i];
  }
  return 0;
}

int vm_min_vertex_step(const double H[9], const double g[3], const double Q[9], int k,
                       double d[3]) {
  d[0] = d[1] = d[2] = 0;
  if (k <= 0) return 1;
  double A[9] = {0}, r[3] = {0}, HQ[9];
  /* the symmetric part of H in the basis Q: A = Q^T sym(H) Q, r = Q^T g */
  for (int j = 0; j < k; j++)
    for (int i = 0; i < 3; i++) {
      double s = 0;
      for (int c = 0; c < 3; c++) s += 0.5 * (H[i * 3 + c] + H[c * 3 + i]) * Q[3 * j + c];
      HQ[3 * j + i] = s;
    }
  double smax = 0;
  for (int i = 0; i < k; i++) {
    for (int j = 0; j < k; j++) {
      double s = 0;
      for (int c = 0; c < 3; c++) s += Q[3 * i + c] * HQ[3 * j + c];
      A[i * 3 + j] = s;
    }
    r[i] = Q[3 * i] * g[0] + Q[3 * i + 1] * g[1] + Q[3 * i + 2] * g[2];
    if (fabs(A[i * 3 + i]) > smax) smax = fabs(A[i * 3 + i]);
  }
  if (!(smax > 0) || !isfinite(smax)) return 1;
  /* guard non-positive-definite blocks by a growing multiple of I */
  static const double shifts[] = {0, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1, 10, 100, 1e4};
  double b[3] = {-r[0], -r[1], -r[2]}, a[3];
  for (size_t s = 0; s < sizeof shifts / sizeof shifts[0]; s++) {
    if (chol_solve(A, k, shifts[s] * smax, 1e-14 * smax, b, a)) continue;
    for (int j = 0; j < k; j++)
      for (int c = 0; c < 3; c++) d[c] += a[j] * Q[3 * j + c];
    return 0;
  }
  return 1;
}

static int explicit_begin(vm_minimizer *m) {
  (void)m;
  return VM_OK;
}

static int explicit_direction(vm_minimizer *m, int iter, const double *g, const double *hdiag,
                              const double *hoff, double *d, int *lin_iters) {
  (void)iter;
  (void)hoff;
  *lin_iters = 0;
  int nt = vm_nthreads(m->ctx);
  const int64_t nv = m->nv;
#pragma omp parallel for num_threads(nt) schedule(static) if (nv >= VM_PAR_MIN / 8)
  for (int64_t v = 0; v < nv; v++) {
    double Q[9];
    int k = vm_bc_basis(m->bc, v, Q);
    vm_min_vertex_step(hdiag + 9 * v, g + 3 * v, Q, k, d + 3 * v);
  }
  return VM_OK;
}

static void explicit_end(vm_minimizer *m) { (void)m; }

const vm_minimizer_ops vm_minimizer_explicit_ops = {"explicit", 0, explicit_begin,
                                                    explicit_direction, explicit_end};
