/* lib/core/src/measure.c: distortion measure interface: registry, parameters and
 * the chain rule from f(s, det) to W(C), its gradient and Hessian. */
#include "varmesh/measure.h"

#include <math.h>
#include <string.h>

#include "measure_private.h"

static const vm_measure_ops *const measure_table[VM_MEASURE_COUNT] = {
    &vm_measure_shape_ops,     &vm_measure_shape_alt_ops, &vm_measure_balanced_ops,
    &vm_measure_quasi_iso_ops, &vm_measure_penalty_ops,   &vm_measure_barrier_ops};

const vm_measure_ops *vm_measure_get(vm_measure_kind kind) {
  if ((int)kind < 0 || (int)kind >= VM_MEASURE_COUNT) return NULL;
  return measure_table[kind];
}

const vm_measure_ops *vm_measure_by_name(const char *name) {
  if (!name) return NULL;
  for (int k = 0; k < VM_MEASURE_COUNT; k++)
    if (strcmp(measure_table[k]->name, name) == 0) return measure_table[k];
  return NULL;
}

vm_measure_params vm_measure_params_default(void) {
  vm_measure_params p = {0.8, 0.0, 0.0, 1};
  return p;
}

double vm_chi_eps(double det, double eps) {
  double q = sqrt(eps * eps + det * det);
  /* for det < 0 the sum det + q cancels: use the conjugate form */
  return det >= 0 ? 0.5 * (det + q) : 0.5 * eps * eps / (q - det);
}

double vm_phi_theta(double theta, int d, double s, double det) {
  return vm_phi_theta_fn(theta, d, s, det).v;
}

/* s = tr(C^T C), det C and the cofactor matrix cof C = det C * C^{-T},
 * computed from minors so they are valid for any C. */
static double invariants(int d, const double *C, double *cof, double *s) {
  if (d == 2) {
    cof[0] = C[3];
    cof[1] = -C[2];
    cof[2] = -C[1];
    cof[3] = C[0];
    *s = C[0] * C[0] + C[1] * C[1] + C[2] * C[2] + C[3] * C[3];
    return C[0] * C[3] - C[1] * C[2];
  }
  cof[0] = C[4] * C[8] - C[5] * C[7];
  cof[1] = C[5] * C[6] - C[3] * C[8];
  cof[2] = C[3] * C[7] - C[4] * C[6];
  cof[3] = C[7] * C[2] - C[8] * C[1];
  cof[4] = C[8] * C[0] - C[6] * C[2];
  cof[5] = C[6] * C[1] - C[7] * C[0];
  cof[6] = C[1] * C[5] - C[2] * C[4];
  cof[7] = C[2] * C[3] - C[0] * C[5];
  cof[8] = C[0] * C[4] - C[1] * C[3];
  double ss = 0;
  for (int n = 0; n < 9; n++) ss += C[n] * C[n];
  *s = ss;
  return C[0] * cof[0] + C[1] * cof[1] + C[2] * cof[2];
}

/* f_d d(cof)/dC: d cof_ij / d C_kl = e_ik e_jl in 2D and
 * sum_mn e_ikm e_jln C_mn in 3D (e the Levi-Civita symbol). */
static void add_dcof(int d, const double *C, double fd, double *H) {
  if (d == 2) {
    H[0 * 4 + 3] += fd;
    H[3 * 4 + 0] += fd;
    H[1 * 4 + 2] -= fd;
    H[2 * 4 + 1] -= fd;
    return;
  }
  for (int i = 0; i < 3; i++)
    for (int k = 0; k < 3; k++) {
      if (k == i) continue;
      int m = 3 - i - k;
      double eik = (k - i + 3) % 3 == 1 ? fd : -fd;
      for (int j = 0; j < 3; j++)
        for (int l = 0; l < 3; l++) {
          if (l == j) continue;
          int n = 3 - j - l;
          double v = eik * C[m * 3 + n];
          H[(i * 3 + j) * 9 + k * 3 + l] += (l - j + 3) % 3 == 1 ? v : -v;
        }
    }
}

int vm_measure_eval(const vm_measure_ops *ops, const vm_measure_params *p, int d, const double *C,
                    double *W, double *G, double *H) {
  if (!W) return VM_ERR_ARG;
  *W = INFINITY;
  if (!ops || !ops->scalar || !p || !C || (d != 2 && d != 3)) return VM_ERR_ARG;
  double cof[9], s, f[6];
  double det = invariants(d, C, cof, &s);
  int order = H ? 2 : G ? 1 : 0;
  if (ops->scalar(p, d, s, det, order, f)) return 1;
  *W = f[0];
  int nn = d * d;
  if (G)
    for (int a = 0; a < nn; a++) G[a] = 2 * f[1] * C[a] + f[2] * cof[a];
  if (H) {
    /* one triangle mirrored, so H is exactly symmetric */
    for (int a = 0; a < nn; a++) {
      double ca = 4 * f[3] * C[a] + 2 * f[4] * cof[a];
      double ka = 2 * f[4] * C[a] + f[5] * cof[a];
      for (int b = a; b < nn; b++) H[a * nn + b] = H[b * nn + a] = ca * C[b] + ka * cof[b];
      H[a * nn + a] += 2 * f[1];
    }
    add_dcof(d, C, f[2], H);
  }
  return 0;
}
