/* test/measure/mtest_util.h: small dense-matrix, random-rotation and
 * Gauss-Legendre helpers shared by the measure and quadrature tests. */
#ifndef MTEST_UTIL_H
#define MTEST_UTIL_H

#include <math.h>
#include <string.h>

#include "varmesh/ctx.h"

static const double mt_pi = 3.14159265358979323846;

/* uniform in [a, b) */
static inline double mt_uniform(vm_ctx *ctx, double a, double b) {
  return a + (b - a) * vm_ctx_rand_unit(ctx);
}

static inline double mt_det(int d, const double *A) {
  if (d == 2) return A[0] * A[3] - A[1] * A[2];
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static inline double mt_trace_ctc(int d, const double *A) {
  double s = 0;
  for (int n = 0; n < d * d; n++) s += A[n] * A[n];
  return s;
}

/* C = A B (d x d, row-major); C may not alias A or B */
static inline void mt_mul(int d, const double *A, const double *B, double *C) {
  for (int i = 0; i < d; i++)
    for (int j = 0; j < d; j++) {
      double v = 0;
      for (int k = 0; k < d; k++) v += A[i * d + k] * B[k * d + j];
      C[i * d + j] = v;
    }
}

/* C = A B^T */
static inline void mt_mul_bt(int d, const double *A, const double *B, double *C) {
  for (int i = 0; i < d; i++)
    for (int j = 0; j < d; j++) {
      double v = 0;
      for (int k = 0; k < d; k++) v += A[i * d + k] * B[j * d + k];
      C[i * d + j] = v;
    }
}

/* A uniformly random rotation (det +1): an angle in 2D, Shoemake's unit
 * quaternion in 3D. */
static inline void mt_rotation(vm_ctx *ctx, int d, double *R) {
  if (d == 2) {
    double a = mt_uniform(ctx, 0, 2 * mt_pi), c = cos(a), s = sin(a);
    R[0] = c, R[1] = -s, R[2] = s, R[3] = c;
    return;
  }
  double u1 = vm_ctx_rand_unit(ctx), u2 = 2 * mt_pi * vm_ctx_rand_unit(ctx),
         u3 = 2 * mt_pi * vm_ctx_rand_unit(ctx);
  double w = sqrt(1 - u1) * sin(u2), x = sqrt(1 - u1) * cos(u2), y = sqrt(u1) * sin(u3),
         z = sqrt(u1) * cos(u3);
  R[0] = 1 - 2 * (y * y + z * z), R[1] = 2 * (x * y - z * w), R[2] = 2 * (x * z + y * w);
  R[3] = 2 * (x * y + z * w), R[4] = 1 - 2 * (x * x + z * z), R[5] = 2 * (y * z - x * w);
  R[6] = 2 * (x * z - y * w), R[7] = 2 * (y * z + x * w), R[8] = 1 - 2 * (x * x + y * y);
}

/* C = U diag(sig) V^T with random rotations U, V */
static inline void mt_from_singular(vm_ctx *ctx, int d, const double *sig, double *C) {
  double U[9], V[9], US[9];
  mt_rotation(ctx, d, U);
  mt_rotation(ctx, d, V);
  for (int i = 0; i < d; i++)
    for (int j = 0; j < d; j++) US[i * d + j] = U[i * d + j] * sig[j];
  mt_mul_bt(d, US, V, C);
}

/* |a - b| / max(1, |a|, |b|) */
static inline double mt_relerr(double a, double b) {
  double m = fmax(1.0, fmax(fabs(a), fabs(b)));
  return fabs(a - b) / m;
}

/* n-point Gauss-Legendre rule on [0, 1] (n <= 16), by Newton on P_n. */
static inline void mt_gauss(int n, double *x, double *w) {
  for (int i = 0; i < n; i++) {
    double z = cos(mt_pi * (i + 0.75) / (n + 0.5)), dp = 1;
    for (int it = 0; it < 100; it++) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; k++) {
        double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      double dz = p1 / dp;
      z -= dz;
      if (fabs(dz) < 1e-16) break;
    }
    x[i] = 0.5 * (1 - z);
    w[i] = 1.0 / ((1 - z * z) * dp * dp);
  }
}

#endif
