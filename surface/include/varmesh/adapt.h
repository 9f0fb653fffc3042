/* varmesh/adapt.h: curvature-adapted r-optimization of a surface mesh with
 * the 2D functional (20): the balanced measure under the metric
 * G_x = (1 + c|H|) I, each element measured in its own tangent frame,
 * vertices sliding on the reference surface (smooth vertices), along its
 * feature lines (feature vertices), corners fixed. Connectivity unchanged. */
#ifndef VARMESH_ADAPT_H
#define VARMESH_ADAPT_H

#include <stdint.h>

#include "varmesh/curvature.h"
#include "varmesh/mesh.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Progress after every minimizer iteration. */
typedef struct vm_adapt_progress {
  int round;      /* 1 .. rounds */
  int iter;       /* iteration within the round */
  int total_iter; /* over all rounds */
  double F;
  double grad_norm;
  double tau;
  double elapsed;
} vm_adapt_progress;

typedef void (*vm_adapt_monitor_fn)(void *user, const vm_adapt_progress *p);

typedef struct vm_adapt_opts {
  /* metric G_x = (1 + c |H|) I, H the filtered mean curvature; c in units
   * of length. c < 0: relative, c = -c * h (h the mean edge length), so
   * the default -4 gives 1 + c|H| = 5 where |H| = 1/h. */
  double c;
  /* filter of |H| (curvature.h). threshold < 0 / cap < 0: automatic,
   * |threshold| / D and |cap| / h (D the bounding box diagonal, h the mean
   * edge length): the defaults -4 and -1 zero out radii of curvature above
   * D/8 and cap radii below h. */
  vm_curvature_filter filter;
  double feature_angle; /* dihedral angle of sharp edges, degrees (default 20: the
                           creases of a faceted STL model are kept exactly) */
  double corner_angle;  /* turning angle of a feature line at a corner (default 50) */
  double cone_angle;    /* angle deficit (degrees) of a cone point, a tip kept fixed like a
                           corner (vm_surface_mark_cones; default 60; >= 360: none) */
  double theta;         /* balanced measure weight (default 0.8) */
  int max_iter;         /* minimizer iterations in all (default 200) */
  int rounds;           /* the metric is re-evaluated at the moved vertices and the
                           reference normals refreshed this many times (default 5) */
  int implicit;         /* 1: the implicit minimizer, 0: the explicit one (default) */
  double time_limit;    /* seconds, <= 0: none */
  vm_adapt_monitor_fn monitor;
  void *user;
} vm_adapt_opts;

vm_adapt_opts vm_adapt_opts_default(void);

typedef struct vm_adapt_result {
  int iterations, rounds;
  double F_initial, F;
  const char *stop;         /* stop reason of the last round (static string) */
  double c, threshold, cap; /* the values used */
  int64_t nsmooth, nline_vertices, ncorner, nfixed;
  int32_t nline;
  double min_angle_before, min_angle_after; /* degrees, over all triangle corners */
  int64_t flipped;     /* elements whose orientation reversed during the adaptation
                          (normal at the end . normal at the start <= 0) */
  double max_distance; /* largest vertex distance to the reference surface */
  double elapsed;
} vm_adapt_result;

/* Adapt m (a surface: dim 3, triangles and/or quads, manifold) in place.
 * ref: the surface the vertices stay on (vm_surface_projector_create on
 * the input surface and its features); NULL: m itself as it is now, with
 * features detected by o->feature_angle. Vertex classes: features of m
 * by o->feature_angle / corner_angle (smooth: slip on the surface; on a
 * feature line: slide along the matching line of ref; corner: fixed);
 * vertices FIXED in m stay put; m's flags are restored afterwards.
 * The curvature is computed on m at the start (vm_surface_mean_curvature,
 * then the filter), carried as a field of the starting surface and
 * evaluated at the moved vertices between rounds. On return the fields
 * VM_FIELD_MEAN_CURVATURE and VM_FIELD_MEAN_CURVATURE_FILTERED hold the
 * curvature of the adapted mesh.
 * Returns VM_OK (also when stopped at the iteration limit), VM_WARN_TIME,
 * VM_ERR_INTERRUPTED (m holds the last accepted iterate), VM_ERR_ARG (not
 * a surface mesh, bad options, a degenerate element at the start),
 * VM_ERR_FORMAT (non-manifold), VM_ERR_NOMEM, VM_ERR_BACKEND.
 * o NULL: defaults; res may be NULL. */
int vm_surface_adapt(vm_mesh *m, vm_surface_projector *ref, const vm_adapt_opts *o,
                     vm_adapt_result *res);

/* Smallest corner angle (degrees) of the triangles of m (quads: of their
 * corner triangles); 180 if there are none. */
double vm_surface_min_angle(const vm_mesh *m);
/* Mean length of the sides of the 2D elements (an interior edge counts
 * twice): the h of vm_surface_adapt, vm-surface and bench_surface. */
double vm_surface_mean_edge(const vm_mesh *m);

#ifdef __cplusplus
}
#endif
#endif
