/* lib/core/src/measure_shape.c: scale-invariant shape measures W_s = (s/3)^{3/2}/det
 * and the alternative (s/3)/det^{2/3} (3D); both are (s/2)/det in 2D. */
#include <math.h>

#include "measure_private.h"

static int shape_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                        double out[6]) {
  (void)p;
  if ((d != 2 && d != 3) || !(det > 0) || !(s < INFINITY)) return vm_measure_outside(out);
  vm_sd_fn g = vm_shape_term(d, s);
  double r = 1 / det;
  vm_measure_product(&g, r, -r * r, 2 * r * r * r, order, out);
  return 0;
}

static int shape_alt_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                            double out[6]) {
  if (d == 2) return shape_scalar(p, d, s, det, order, out);
  if (d != 3 || !(det > 0) || !(s < INFINITY)) return vm_measure_outside(out);
  vm_sd_fn g = {s * (1.0 / 3), 1.0 / 3, 0, 0, 0};
  double c = cbrt(det), r = 1 / (c * c), rd = r / det;
  vm_measure_product(&g, r, (-2.0 / 3) * rd, (10.0 / 9) * rd / det, order, out);
  return 0;
}

const vm_measure_ops vm_measure_shape_ops = {VM_MEASURE_SHAPE, "shape", shape_scalar};
const vm_measure_ops vm_measure_shape_alt_ops = {VM_MEASURE_SHAPE_ALT, "shape-alt",
                                                 shape_alt_scalar};
