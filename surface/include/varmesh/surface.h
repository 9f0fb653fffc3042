/* varmesh/surface.h: the surface stage as one call: repair an imported
 * surface, remesh it uniformly when it needs it, compute its mean
 * curvature and adapt the mesh to it with the 2D functional (20); or any
 * of these steps alone (what vm-surface runs). */
#ifndef VARMESH_SURFACE_H
#define VARMESH_SURFACE_H

#include <stdint.h>

#include "varmesh/adapt.h"
#include "varmesh/curvature.h"
#include "varmesh/mesh.h"
#include "varmesh/repair.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_SURFACE_ALL = 0,   /* repair -> remesh (if needed) -> curvature -> adapt */
  VM_SURFACE_REPAIR,    /* repair only */
  VM_SURFACE_REMESH,    /* repair -> isotropic remeshing */
  VM_SURFACE_CURVATURE, /* the mean curvature fields only */
  VM_SURFACE_ADAPT      /* curvature -> adaptation (no remeshing) */
} vm_surface_step;

/* Whether to run an optional step. */
enum { VM_SURFACE_AUTO = 0, VM_SURFACE_YES = 1, VM_SURFACE_NO = 2 };

typedef struct vm_surface_opts {
  vm_surface_step step; /* default VM_SURFACE_ALL */
  int repair;           /* AUTO (default): if `soup`, and always for the steps
                           all, repair and remesh; the step repair always repairs */
  int soup;             /* the input came as a polygon soup (.stl .obj .off .ply) */
  int remesh;           /* in step all; AUTO (default): if the smallest angle
                           is below sliver_angle */
  double sliver_angle;  /* degrees (default 15) */
  vm_repair_opts repair_opts;
  vm_remesh_opts remesh_opts; /* target_edge_length <= 0 (default): the mean
                                 edge length of the (repaired) input */
  vm_adapt_opts adapt;        /* also the feature angles of the remeshing and the
                                 curvature filter of the step curvature */
} vm_surface_opts;

vm_surface_opts vm_surface_opts_default(void);

/* What the steps did; a step that did not run leaves its part zero. */
typedef struct vm_surface_summary {
  int repaired;
  vm_repair_report repair; /* self_intersections -1 if not repaired */
  double min_angle_input;  /* smallest angle (degrees) after the repair */
  int remeshed;
  double target_edge_length; /* of the remeshing */
  int64_t nv_before_remesh;
  int curvature; /* the step curvature ran */
  vm_curvature_stats curvature_stats;
  double threshold, cap; /* step curvature: the filter used */
  int adapted;
  vm_adapt_result adapt;
  int open; /* refused: an open surface that nothing repaired
               and opts did not accept (see the error text) */
} vm_surface_summary;

/* Run opts->step on the surface m (dim 3, triangles and/or quads) in
 * place. Progress goes to the context's log at VM_LOG_INFO, one line per
 * step ("repair: ...", "remesh: ...", "curvature: ...", "adapt: ..."),
 * and per iteration to opts->adapt.monitor. The adaptation's reference
 * surface is the repaired input before any remeshing.
 * Returns VM_OK; VM_WARN_INVERTED if an element's orientation reversed
 * during the adaptation (summary->adapt.flipped); VM_ERR_INTERRUPTED (the
 * context's interrupt flag; m holds the last iterate, or, interrupted
 * during the repair or the remeshing, which cannot stop half-way, the mesh
 * they made: the run ends after them); VM_ERR_ARG (not a
 * surface mesh, bad options), VM_ERR_FORMAT (what the repair refused, an
 * open surface the repair did not see: summary->open), VM_ERR_NOMEM,
 * VM_ERR_BACKEND, with the error text on the context. summary may be
 * NULL. */
int vm_surface_run(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *opts,
                   vm_surface_summary *summary);

const char *vm_surface_step_name(vm_surface_step step);

#ifdef __cplusplus
}
#endif
#endif
