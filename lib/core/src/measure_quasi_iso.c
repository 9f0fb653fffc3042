/* lib/core/src/measure_quasi_iso.c: the quasi-isometric measure (11)
 * W_t = (1-t) phi_theta/(det - t phi_theta), finite where det > t phi_theta. */
#include <math.h>

#include "measure_private.h"

/* With u = det - t phi and g = phi/u:
 *   g_s = det phi_s/u^2, g_d = (det phi_d - phi)/u^2,
 *   g_ss = det phi_ss/u^2 + 2 t det phi_s^2/u^3,
 *   g_sd = phi_s/u^2 - 2 det phi_s (1 - t phi_d)/u^3,
 *   g_dd = det phi_dd/u^2 - 2 (det phi_d - phi)(1 - t phi_d)/u^3. */
static int quasi_iso_scalar(const vm_measure_params *p, int d, double s, double det, int order,
                            double out[6]) {
  if ((d != 2 && d != 3) || !(det > 0) || !(s < INFINITY)) return vm_measure_outside(out);
  double t = p->t;
  vm_sd_fn phi = vm_phi_theta_fn(p->theta, d, s, det);
  double u = det - t * phi.v;
  if (!(u > 0)) return vm_measure_outside(out);
  double a = 1 - t, iu = 1 / u, iu2 = a * iu * iu, iu3 = iu2 * iu;
  out[0] = a * phi.v * iu;
  if (order < 1) return 0;
  double nd = det * phi.d - phi.v, ud = 1 - t * phi.d;
  out[1] = det * phi.s * iu2;
  out[2] = nd * iu2;
  if (order < 2) return 0;
  out[3] = det * (phi.ss * iu2 + 2 * t * phi.s * phi.s * iu3);
  out[4] = phi.s * (iu2 - 2 * det * ud * iu3);
  out[5] = det * phi.dd * iu2 - 2 * nd * ud * iu3;
  return 0;
}

const vm_measure_ops vm_measure_quasi_iso_ops = {VM_MEASURE_QUASI_ISO, "quasi-iso",
                                                 quasi_iso_scalar};
