/* lib/core/src/measure_private.h: pieces shared by the distortion measure files:
 * phi_theta with its partials, the product rule for f = phi(s, det) r(det),
 * and the per-kind function tables collected by measure.c. */
#ifndef VARMESH_MEASURE_PRIVATE_H
#define VARMESH_MEASURE_PRIVATE_H

#include <math.h>

#include "varmesh/measure.h"

/* A function of (s, det) with its partials; the mixed partial is always 0
 * for the numerators used here. */
typedef struct vm_sd_fn {
  double v, s, d, ss, dd;
} vm_sd_fn;

/* The shape term (s/d)^{d/2}: (s/3)^{3/2} in 3D, s/2 in 2D. At s = 0 the
 * 3D second partial is infinite but multiplies C (x) C = 0 in the chain
 * rule, so it is returned as 0 there (the penalty form is evaluated at C = 0). */
static inline vm_sd_fn vm_shape_term(int d, double s) {
  vm_sd_fn g = {0, 0, 0, 0, 0};
  if (d == 2) {
    g.v = 0.5 * s;
    g.s = 0.5;
    return g;
  }
  double r = sqrt(s * (1.0 / 3));
  g.v = s * (1.0 / 3) * r;
  g.s = 0.5 * r;
  g.ss = r > 0 ? (1.0 / 12) / r : 0;
  return g;
}

/* (10): phi_theta = (1-theta)(s/d)^{d/2} + theta (1 + det^2)/2. */
static inline vm_sd_fn vm_phi_theta_fn(double theta, int d, double s, double det) {
  vm_sd_fn g = vm_shape_term(d, s);
  double a = 1 - theta;
  vm_sd_fn phi = {a * g.v + 0.5 * theta * (1 + det * det), a * g.s, theta * det, a * g.ss, theta};
  return phi;
}

/* f = phi(s, det) r(det) and its partials into out[0..5] (measure.h order),
 * given r, r' and r''. */
static inline void vm_measure_product(const vm_sd_fn *phi, double r, double r1, double r2,
                                      int order, double out[6]) {
  out[0] = phi->v * r;
  if (order < 1) return;
  out[1] = phi->s * r;
  out[2] = phi->d * r + phi->v * r1;
  if (order < 2) return;
  out[3] = phi->ss * r;
  out[4] = phi->s * r1;
  out[5] = phi->dd * r + 2 * phi->d * r1 + phi->v * r2;
}

/* Outside the domain: f = +inf, derivatives untouched; returns 1. */
static inline int vm_measure_outside(double out[6]) {
  out[0] = INFINITY;
  return 1;
}

/* The balanced measure (10), W = phi_theta / det, with its partials: here
 * so that the element kernels can inline it (the measure files' table
 * calls it through a pointer). */
static inline int vm_balanced_scalar(const vm_measure_params *p, int d, double s, double det,
                                     int order, double out[6]) {
  if ((d != 2 && d != 3) || !(det > 0) || !(s < INFINITY)) return vm_measure_outside(out);
  vm_sd_fn phi = vm_phi_theta_fn(p->theta, d, s, det);
  double r = 1 / det;
  vm_measure_product(&phi, r, -r * r, 2 * r * r * r, order, out);
  return 0;
}

extern const vm_measure_ops vm_measure_shape_ops;
extern const vm_measure_ops vm_measure_shape_alt_ops;
extern const vm_measure_ops vm_measure_balanced_ops;
extern const vm_measure_ops vm_measure_quasi_iso_ops;
extern const vm_measure_ops vm_measure_penalty_ops;
extern const vm_measure_ops vm_measure_barrier_ops;

#endif
