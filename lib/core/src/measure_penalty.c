/* lib/core/src/measure_penalty.c: the penalty form P_eps = phi_theta/chi_eps(det)
 * of (14), (16), finite for every det when eps > 0. */
#include <math.h>

#include "measure_private.h"

/* With q = sqrt(eps^2 + det^2): chi' = chi/q, chi'' = eps^2/(2 q^3), and
 * r = 1/chi has r' = -r/q, r'' = 2/q^3 = 2 r/q^2 (the chi'^2 part) minus
 * chi''/chi^2 (the chi'' part, dropped on request). */
static int penalty_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                          double out[6]) {
  if ((d != 2 && d != 3) || !(s < INFINITY) || !(fabs(det) < INFINITY))
    return vm_measure_outside(out);
  double q = sqrt(p->eps * p->eps + det * det);
  /* (14): chi_eps, in the conjugate form for det < 0 to avoid cancellation */
  double chi = det >= 0 ? 0.5 * (det + q) : 0.5 * p->eps * p->eps / (q - det);
  if (!(chi > 0)) return vm_measure_outside(out);
  vm_sd_fn phi = vm_phi_theta_fn(p->theta, d, s, det);
  double r = 1 / chi, rq = r / q;
  double r2 = p->drop_chi2 ? 2 * rq / q : 2 / (q * q * q);
  vm_measure_product(&phi, r, -rq, r2, order, out);
  return 0;
}

const vm_measure_ops vm_measure_penalty_ops = {VM_MEASURE_PENALTY, "penalty", penalty_scalar};
