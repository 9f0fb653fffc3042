/* varmesh/measure.h: polyconvex distortion measures W(C) of the paper's
 * Section 2, 2D and 3D, with first and second derivatives.
 *
 * Every measure here is a function of two invariants of the d x d Jacobian C:
 *   s = tr(C^T C) and det = det C,
 * so an implementation supplies only f(s, det) and its partial derivatives;
 * vm_measure_eval applies the chain rule
 *   dW/dC = 2 f_s C + f_d cof(C),
 *   d2W/dC2 = 2 f_s I + 4 f_ss C(x)C + 2 f_sd (C(x)cof + cof(x)C) + f_dd cof(x)cof
 *             + f_d d(cof)/dC.
 * In 2D, s/2 replaces s/3 and the power 3/2 becomes 1 (see DESIGN.md). */
#ifndef VARMESH_MEASURE_H
#define VARMESH_MEASURE_H

#include "varmesh/ctx.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_MEASURE_SHAPE = 0,     /* W_s: (s/3)^{3/2}/det (3D), (s/2)/det (2D) */
  VM_MEASURE_SHAPE_ALT = 1, /* (s/3)/det^{2/3} (3D), (s/2)/det (2D) */
  VM_MEASURE_BALANCED = 2,  /* (10): phi_theta/det */
  VM_MEASURE_QUASI_ISO = 3, /* (11): (1-t) phi_theta/(det - t phi_theta) */
  VM_MEASURE_PENALTY = 4,   /* (14), (16): phi_theta/chi_eps(det) */
  VM_MEASURE_BARRIER = 5,   /* (17): phi_theta/(det + eps) */
  VM_MEASURE_COUNT = 6
} vm_measure_kind;

/* Parameters. theta: volumetric modulus of phi_theta (default 4/5);
 * t: quasi-isometry parameter of W_t in [0, 1) (alpha = 1/t);
 * eps: epsilon of the penalty and barrier forms;
 * drop_chi2: penalty only: leave the chi'' terms out of the second
 * derivatives so the diagonal Hessian blocks stay positive definite. */
typedef struct vm_measure_params {
  double theta;
  double t;
  double eps;
  int drop_chi2;
} vm_measure_params;

/* Defaults: theta 0.8, t 0, eps 0, drop_chi2 1. */
vm_measure_params vm_measure_params_default(void);

/* The scalar function f(s, det) and its derivatives, for dimension d.
 * out[0] = f, out[1] = f_s, out[2] = f_d, out[3] = f_ss, out[4] = f_sd,
 * out[5] = f_dd. `order` 0, 1 or 2 says how many are needed (0: f only;
 * 1: f, f_s, f_d; 2: all six).
 * Returns 0 when (s, det) is inside the measure's domain (f finite),
 * nonzero outside (f = +INFINITY, derivatives not written): det <= 0 for
 * the shape, balanced and quasi-isometric forms; det <= t phi for W_t;
 * det + eps <= 0 for the barrier. The penalty form is finite everywhere
 * for eps > 0. */
typedef int (*vm_measure_scalar_fn)(const vm_measure_params *p, int d, double s, double det,
                                    int order, double out[6]);

/* A measure: one function-pointer table per kind (lib/src/measure_*.c). */
typedef struct vm_measure_ops {
  vm_measure_kind kind;
  const char *name; /* "shape", "shape-alt", "balanced", "quasi-iso", "penalty", "barrier" */
  vm_measure_scalar_fn scalar;
} vm_measure_ops;

/* The table for a kind (NULL if unknown); by name (NULL if unknown). */
const vm_measure_ops *vm_measure_get(vm_measure_kind kind);
const vm_measure_ops *vm_measure_by_name(const char *name);

/* W(C) for a d x d row-major C (d = 2 or 3), with the gradient G (d*d,
 * G[i*d+j] = dW/dC_ij) if G != NULL and the Hessian H (d^4,
 * H[(i*d+j)*d*d + k*d+l] = d2W/dC_ij dC_kl) if H != NULL.
 * Returns 0 inside the domain, nonzero outside (*W = +INFINITY). */
int vm_measure_eval(const vm_measure_ops *ops, const vm_measure_params *p, int d, const double *C,
                    double *W, double *G, double *H);

/* The penalty's chi_eps(det) = (det + sqrt(eps^2 + det^2))/2 of (14). */
double vm_chi_eps(double det, double eps);
/* phi_theta(s, det) of (10): (1-theta)(s/d)^{d/2} + theta (1 + det^2)/2. */
double vm_phi_theta(double theta, int d, double s, double det);

#ifdef __cplusplus
}
#endif
#endif
