/* lib/core/src/measure_balanced.c: the balanced measure (10) W = phi_theta/det. */
#include <math.h>

#include "measure_private.h"

static int balanced_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                           double out[6]) {
  return vm_balanced_scalar(p, d, s, det, order, out);
}

const vm_measure_ops vm_measure_balanced_ops = {VM_MEASURE_BALANCED, "balanced", balanced_scalar};
