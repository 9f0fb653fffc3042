/* lib/core/src/measure_barrier.c: the extended barrier B_eps = phi_theta/(det + eps)
 * of (17), finite on the widened admissible set det > -eps. */
#include <math.h>

#include "measure_private.h"

static int barrier_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                          double out[6]) {
  double h = det + p->eps;
  if ((d != 2 && d != 3) || !(h > 0) || !(s < INFINITY)) return vm_measure_outside(out);
  vm_sd_fn phi = vm_phi_theta_fn(p->theta, d, s, det);
  double r = 1 / h;
  vm_measure_product(&phi, r, -r * r, 2 * r * r * r, order, out);
  return 0;
}

const vm_measure_ops vm_measure_barrier_ops = {VM_MEASURE_BARRIER, "barrier", barrier_scalar};
