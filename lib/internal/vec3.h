/* lib/internal/vec3.h: 3-vector helpers on plain double[3] arrays, shared by
 * the project's libraries (not installed, not part of the public API). */
#ifndef VARMESH_INTERNAL_VEC3_H
#define VARMESH_INTERNAL_VEC3_H

#include <math.h>

static inline double vm_dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void vm_sub3(const double *a, const double *b, double *c) {
  c[0] = a[0] - b[0];
  c[1] = a[1] - b[1];
  c[2] = a[2] - b[2];
}
static inline void vm_cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline double vm_norm3(const double *a) { return sqrt(vm_dot3(a, a)); }
static inline double vm_dist3(const double *a, const double *b) {
  double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return vm_norm3(d);
}
/* Scale a to unit length and return its former length (a unchanged if 0). */
static inline double vm_normalize3(double *a) {
  double n = vm_norm3(a);
  if (n > 0)
    for (int k = 0; k < 3; k++) a[k] /= n;
  return n;
}

#endif
