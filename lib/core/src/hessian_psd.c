/* lib/core/src/hessian_psd.c: positive semidefinite projection of the Hessian of
 * W(C) = f(s, det), s = tr C^T C: the analytic eigensystem of Smith, de
 * Goes and Kim (2019) in 3D through the signed SVD C = U diag(sig) V^T,
 * dense Jacobi for the small 2D systems. Only the negative eigenpairs are
 * formed: H_+ = H - sum_{lam < 0} lam D D^T, so H_+ is the exact Hessian
 * wherever nothing is clamped. */
#include <math.h>
#include <string.h>

#include "hessian_psd_private.h"
#include "inline.h"
#include "varmesh/problem.h"

/* Cyclic Jacobi; inlined with a constant n for the 3x3 cases. */
VM_INLINE void sym_eig(int n, double *A, double *w, double *V) {
  for (int i = 0; i < n; i++)
    for (int k = 0; k < n; k++) V[i * n + k] = i == k;
  for (int sweep = 0; sweep < 60; sweep++) {
    double off = 0, diag = 0;
    for (int p = 0; p < n; p++) {
      diag += A[p * n + p] * A[p * n + p];
      for (int q = p + 1; q < n; q++) off += A[p * n + q] * A[p * n + q];
    }
    if (!(off > 1e-24 * diag) || !isfinite(off)) break;
    for (int p = 0; p < n; p++)
      for (int q = p + 1; q < n; q++) {
        double apq = A[p * n + q];
        if (apq == 0) continue;
        double theta = (A[q * n + q] - A[p * n + p]) / (2 * apq);
        double t = fabs(theta) > 1e150
                       ? 0.5 / theta
                       : (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
        double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; k++) {
          double akp = A[k * n + p], akq = A[k * n + q];
          A[k * n + p] = c * akp - s * akq;
          A[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; k++) {
          double apk = A[p * n + k], aqk = A[q * n + k];
          A[p * n + k] = c * apk - s * aqk;
          A[q * n + k] = s * apk + c * aqk;
        }
        A[p * n + q] = A[q * n + p] = 0;
        for (int k = 0; k < n; k++) {
          double vkp = V[k * n + p], vkq = V[k * n + q];
          V[k * n + p] = c * vkp - s * vkq;
          V[k * n + q] = s * vkp + c * vkq;
        }
      }
  }
  for (int i = 0; i < n; i++) w[i] = A[i * n + i];
}

void vm_sym_eig(int n, double *A, double *w, double *V) { sym_eig(n, A, w, V); }

static void sym_eig3(double *A, double *w, double *V) { sym_eig(3, A, w, V); }

/* Is the symmetric 3x3 A positive definite (Cholesky pivots > 0)? */
static int spd3(const double *A) {
  double d0 = A[0];
  if (!(d0 > 0)) return 0;
  double l10 = A[3] / d0, l20 = A[6] / d0;
  double d1 = A[4] - l10 * A[3];
  if (!(d1 > 0)) return 0;
  double a21 = A[7] - l20 * A[3];
  double d2 = A[8] - l20 * A[6] - a21 * a21 / d1;
  return d2 > 0;
}

/* Givens rotation on rows i, j of R (3x3) zeroing R[j][col]; U = U G^T. */
static void givens(double *R, double *U, int i, int j, int col) {
  double a = R[3 * i + col], b = R[3 * j + col];
  double r = hypot(a, b);
  if (!(r > 0)) return;
  double c = a / r, s = b / r;
  for (int k = 0; k < 3; k++) {
    double ri = R[3 * i + k], rj = R[3 * j + k];
    R[3 * i + k] = c * ri + s * rj;
    R[3 * j + k] = -s * ri + c * rj;
    double ui = U[3 * k + i], uj = U[3 * k + j];
    U[3 * k + i] = c * ui + s * uj;
    U[3 * k + j] = -s * ui + c * uj;
  }
  R[3 * j + col] = 0;
}

void vm_svd3(const double *C, double *U, double sig[3], double *V) {
  double S[9], w[3], W[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      S[3 * i + j] = C[i] * C[j] + C[3 + i] * C[3 + j] + C[6 + i] * C[6 + j];
  sym_eig3(S, w, W);
  /* columns by decreasing eigenvalue */
  int o[3] = {0, 1, 2};
  for (int a = 0; a < 3; a++)
    for (int b = a + 1; b < 3; b++)
      if (w[o[b]] > w[o[a]]) {
        int t = o[a];
        o[a] = o[b];
        o[b] = t;
      }
  for (int i = 0; i < 3; i++)
    for (int k = 0; k < 3; k++) V[3 * i + k] = W[3 * i + o[k]];
  double dv = V[0] * (V[4] * V[8] - V[5] * V[7]) - V[1] * (V[3] * V[8] - V[5] * V[6]) +
              V[2] * (V[3] * V[7] - V[4] * V[6]);
  if (dv < 0)
    for (int i = 0; i < 3; i++) V[3 * i + 2] = -V[3 * i + 2];
  double R[9];
  for (int i = 0; i < 3; i++)
    for (int k = 0; k < 3; k++)
      R[3 * i + k] = C[3 * i] * V[k] + C[3 * i + 1] * V[3 + k] + C[3 * i + 2] * V[6 + k];
  for (int k = 0; k < 9; k++) U[k] = (k % 4) == 0;
  givens(R, U, 0, 1, 0);
  givens(R, U, 0, 2, 0);
  givens(R, U, 1, 2, 1);
  sig[0] = R[0];
  sig[1] = R[4];
  sig[2] = R[8];
}

int vm_psd_negative3(const double *C, const double f[6], double lam[9], double D[9][9]) {
  double U[9], V[9], sg[3];
  vm_svd3(C, U, sg, V);
  const double fs = f[1], fd = f[2], fss = f[3], fsd = f[4], fdd = f[5];
  int nneg = 0;
  static const int pi[3] = {1, 0, 0}, pj[3] = {2, 2, 1};
  const double r2 = 0.70710678118654752440;
  for (int k = 0; k < 3; k++) {
    int i = pi[k], j = pj[k];
    double lt = 2 * fs + fd * sg[k], lf = 2 * fs - fd * sg[k];
    for (int flip = 0; flip < 2; flip++) {
      double l = flip ? lf : lt;
      if (!(l < 0)) continue;
      double sgn = flip ? 1.0 : -1.0;
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
          D[nneg][3 * a + b] =
              r2 * (U[3 * a + i] * V[3 * b + j] + sgn * U[3 * a + j] * V[3 * b + i]);
      lam[nneg++] = l;
    }
  }
  /* scaling block: 2 f_s I + 4 f_ss sig sig^T + 2 f_sd (sig c^T + c sig^T)
   * + f_dd c c^T + f_d Dm, c = (s1 s2, s0 s2, s0 s1), Dm_ij = sig_k */
  double c[3] = {sg[1] * sg[2], sg[0] * sg[2], sg[0] * sg[1]}, A[9], w[3], Y[9];
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++)
      A[3 * a + b] = 4 * fss * sg[a] * sg[b] + 2 * fsd * (sg[a] * c[b] + c[a] * sg[b]) +
                     fdd * c[a] * c[b] + (a == b ? 2 * fs : fd * sg[3 - a - b]);
  if (spd3(A)) return nneg;
  sym_eig3(A, w, Y);
  for (int k = 0; k < 3; k++) {
    if (!(w[k] < 0)) continue;
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++)
        D[nneg][3 * a + b] = U[3 * a] * Y[k] * V[3 * b] + U[3 * a + 1] * Y[3 + k] * V[3 * b + 1] +
                             U[3 * a + 2] * Y[6 + k] * V[3 * b + 2];
    lam[nneg++] = w[k];
  }
  return nneg;
}

int vm_psd_negative_dense(int n, const double *H, double lam[9], double D[9][9]) {
  double A[81], w[9], V[81];
  memcpy(A, H, (size_t)(n * n) * sizeof *A);
  vm_sym_eig(n, A, w, V);
  int nneg = 0;
  for (int k = 0; k < n; k++) {
    if (!(w[k] < 0)) continue;
    for (int i = 0; i < n; i++) D[nneg][i] = V[i * n + k];
    lam[nneg++] = w[k];
  }
  return nneg;
}

int vm_measure_hessian_psd(const vm_measure_ops *ops, const vm_measure_params *p, int d,
                           const double *C, double *W, double *G, double *H, int *nclamped) {
  if (nclamped) *nclamped = 0;
  if (!H) return VM_ERR_ARG;
  int st = vm_measure_eval(ops, p, d, C, W, G, H);
  if (st) return st;
  int nn = d * d, nneg;
  double lam[9], D[9][9];
  if (d == 3) {
    double s = 0, f[6];
    for (int k = 0; k < 9; k++) s += C[k] * C[k];
    double det = C[0] * (C[4] * C[8] - C[5] * C[7]) - C[1] * (C[3] * C[8] - C[5] * C[6]) +
                 C[2] * (C[3] * C[7] - C[4] * C[6]);
    if (ops->scalar(p, 3, s, det, 2, f)) return 1;
    nneg = vm_psd_negative3(C, f, lam, D);
  } else {
    nneg = vm_psd_negative_dense(nn, H, lam, D);
  }
  for (int k = 0; k < nneg; k++)
    for (int a = 0; a < nn; a++)
      for (int b = 0; b < nn; b++) H[a * nn + b] -= lam[k] * D[k][a] * D[k][b];
  if (nclamped) *nclamped = nneg;
  return 0;
}
