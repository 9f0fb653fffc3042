/* lib/core/src/measure_balanced.c: the balanced measure (10) W = phi_theta/det. */
#include <math.h>

#include "measure_private.h"

static int balanced_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                           double out[6]) {
  if ((d != 2 && d != 3) || !(det > 0) || !(s < INFINITY)) return vm_measure_outside(out);
  vm_sd_fn phi = vm_phi_theta_fn(p->theta, d, s, det);
  double r = 1 / det;
  vm_measure_product(&phi, r, -r * r, 2 * r * r * r, order, out);
  return 0;
}

const vm_measure_ops vm_measure_balanced_ops = {VM_MEASURE_BALANCED, "balanced", balanced_scalar};
