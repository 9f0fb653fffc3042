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
#include "varmesh/cleanup.h"
#include "varmesh/graded.h"
#include "varmesh/ortho2d.h"
#include "varmesh/repair.h"
#include "varmesh/symmetry.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_SURFACE_ALL = 0,   /* repair -> remesh (if needed) -> curvature -> adapt -> ortho relief */
  VM_SURFACE_REPAIR,    /* repair only */
  VM_SURFACE_REMESH,    /* repair -> slivers removed (size UNIFORM: isotropic remeshing first) */
  VM_SURFACE_CURVATURE, /* the mean curvature fields only */
  VM_SURFACE_ADAPT      /* curvature -> adaptation (no remeshing) */
} vm_surface_step;

/* The sizing of the remeshing step. */
enum {
  VM_SURFACE_SIZE_INPUT = 0,
  VM_SURFACE_SIZE_UNIFORM = 1,
  VM_SURFACE_SIZE_GRADED = 2,
  VM_SURFACE_SIZE_CURVATURE = 3
};

/* Whether to run an optional step. */
enum { VM_SURFACE_AUTO = 0, VM_SURFACE_YES = 1, VM_SURFACE_NO = 2 };

typedef struct vm_surface_opts {
  vm_surface_step step;         /* default VM_SURFACE_ALL */
  int repair;                   /* AUTO (default): if `soup`, and always for the steps
                                   all, repair and remesh; the step repair always repairs */
  int soup;                     /* the input came as a polygon soup (.stl .obj .off .ply) */
  int remesh;                   /* in step all; AUTO (default): if the smallest angle
                                   is below sliver_angle */
  double sliver_angle;          /* degrees (default 15) */
  double needle_angle;          /* size INPUT: where triangles under this many degrees
                                   are left after the sliver removal (needles it cannot
                                   remove without moving the surface: the stretched rows
                                   of a CAD-graded wing), the input is remeshed to sizes
                                   from the curvature instead, about its number of
                                   triangles (a message says so; default 1, 0: never) */
  int size;                     /* what "remesh" means: VM_SURFACE_SIZE_INPUT (default):
                                   the input's own vertices and grading, slivers removed
                                   by flips and collapses (vm_surface_cleanup);
                                   VM_SURFACE_SIZE_UNIFORM: isotropic remeshing to one
                                   edge length (CGAL), then the same cleanup;
                                   VM_SURFACE_SIZE_GRADED: isotropic remeshing to the
                                   input's own local size (vm_surface_remesh_graded),
                                   then the same cleanup; VM_SURFACE_SIZE_CURVATURE:
                                   the same to sizes from the curvature */
  int64_t triangles;            /* > 0: about this many triangles (GRADED, CURVATURE:
                                   graded_opts.triangles; UNIFORM: the edge length) */
  vm_graded_opts graded_opts;   /* its sizing follows size */
  vm_cleanup_opts cleanup_opts; /* its angle is sliver_angle */
  vm_repair_opts repair_opts;
  vm_remesh_opts remesh_opts; /* target_edge_length <= 0 (default): the mean
                                 edge length of the (repaired) input */
  vm_adapt_opts adapt;        /* also the feature angles of the remeshing and the
                                 curvature filter of the step curvature */
  vm_ortho2d_opts ortho;      /* step all, last: the wall's finite-volume
                                 orthogonality relief (varmesh/ortho2d.h; its feature
                                 angles are adapt's; sweeps 0: measured only) */
  double wrap;                /* > 0: before anything else the input is replaced by a
                                 closed, manifold wrap around it (vm_surface_wrap,
                                 varmesh/repair.h), alpha = wrap times the bounding
                                 box's diagonal, offset wrap_offset times alpha;
                                 < 0 (default): only a model the repair refuses as
                                 non-manifold or crossing itself, or that step all
                                 leaves with needles under needle_angle, is wrapped,
                                 at VM_SURFACE_WRAP_DEFAULT; 0: never */
  double wrap_offset;         /* how far outside the input the wrap lies, a fraction
                                 of alpha in (0, 1] (default VM_SURFACE_WRAP_OFFSET) */
  vm_symmetry_opts symmetry;  /* half models (varmesh/symmetry.h): given 0 (default):
                                 an open input whose border lies in one plane x, y or
                                 z = C (or the plane its attribute symmetry_plane
                                 names) is a half model; given 1: the plane is axis,
                                 value. A half model is never wrapped nor closed: its
                                 border stays open, in the plane bit for bit, through
                                 every step (a feature line: its vertices slide along
                                 it, its corners stay), and the result carries the
                                 attribute symmetry_plane */
} vm_surface_opts;

/* The wrap's alpha over the bounding box's diagonal where the stage wraps
 * a model on its own (opts wrap < 0). */
#define VM_SURFACE_WRAP_DEFAULT 0.005

/* The wrap's offset over its alpha. A smaller offset follows the input
 * more closely but rounds its sharp edges and the rims of its thin sheets
 * over radii so far below alpha that the wrap's triangles there are caps
 * and needles no remeshing mends (1/30, CGAL's own default ratio, left
 * 146 to 1,023 wall edges beyond 70 degrees on four public aircraft
 * models; 1/5 leaves 0 to 2, and adds about 12 % to their volume against
 * 3 %). */
#define VM_SURFACE_WRAP_OFFSET 0.2

vm_surface_opts vm_surface_opts_default(void);

/* What the steps did; a step that did not run leaves its part zero. */
typedef struct vm_surface_summary {
  int repaired;
  vm_repair_report repair; /* self_intersections -1 if not repaired */
  double min_angle_input;  /* smallest angle (degrees) after the repair */
  int remeshed;
  double target_edge_length; /* of the remeshing */
  int64_t nv_before_remesh;
  int cleaned;                 /* the sliver cleanup ran */
  vm_cleanup_report cleanup;   /* its figures */
  vm_unblind_report unblind;   /* the last step: folds taken out (cleanup.h) */
  int size_used;               /* the size the surface was remeshed to in the end
                                  (VM_SURFACE_SIZE_INPUT: the input's own vertices) */
  int64_t needles_in;          /* size INPUT: triangles under needle_angle after the sliver
                                  removal, which made the stage remesh by the curvature */
  vm_graded_report graded;     /* the graded remeshing's figures (size GRADED) */
  int64_t cones;               /* cone points kept as corners */
  int64_t remesh_lost_corners; /* corners and tips the uniform remeshing lost, */
  int64_t remesh_opposing;     /* ... or triangles it turned over against the input:
                                  it was then given up for the input's vertices */
  int64_t opposing;            /* triangles of the result turned over against the
                                  (repaired) input: checked at the end */
  int curvature;               /* the step curvature ran */
  vm_curvature_stats curvature_stats;
  double threshold, cap; /* step curvature: the filter used */
  int adapted;
  int ortho_ran;           /* the orthogonality relief ran (step all) */
  vm_ortho2d_result ortho; /* its figures */
  int wrapped;             /* the input was wrapped (opts wrap) */
  int wrap_auto;           /* ... on the stage's own (opts wrap < 0: refused by the
                              repair, or needles left) */
  vm_wrap_report wrap;     /* its figures */
  int ortho_undone;        /* 1: its result intersected itself and was undone (the
                              figures after are then those before, nothing moved) */
  vm_adapt_result adapt;
  int open; /* refused: an open surface that nothing repaired
               and opts did not accept (see the error text) */
  /* the result checked exactly (CGAL): intersecting triangle pairs left
   * (-1: not checked, the mesh has quads) */
  int64_t self_intersections;
  int64_t remesh_refused;   /* pairs of a remeshed surface given up for the
                               repaired input (0: kept or not remeshed) */
  int64_t folds_found;      /* pairs the adaptation made, before backing off */
  int64_t adapt_backed_off; /* vertices put back where the adaptation folded */
  double angle_floor;       /* the adaptation's smallest angle may not go below this:
                               min(the smallest angle before it, 20 degrees) */
  int64_t angle_restored;   /* vertices put back where it did */
  double fold_at[3];        /* a point of the first pair found */
  /* How far the result lies from the (repaired) input, locally: at every
   * input vertex its distance to the result over its local size h (the
   * mean length of its input edges), and at every result triangle's
   * centroid its distance to the input over the triangle's mean edge
   * length. Measured when the surface moved (remeshing, sliver removal or
   * adaptation); deviation_measured 0 otherwise. */
  int deviation_measured;
  double deviation_rel;         /* the largest relative distance, anywhere */
  double deviation_abs;         /* the largest distance, anywhere */
  double deviation_at[3];       /* where deviation_rel was found */
  double deviation_feature_rel; /* the largest over the input's feature vertices (corners,
                                   cone points, feature lines: o->adapt's angles) */
  double deviation_feature_abs;
  double deviation_feature_at[3];
  int64_t deviation_features; /* feature vertices measured */
  int64_t corners_moved;      /* input corners and cone points not kept bit for bit */
  /* half models: the plane found (or given) on the input, its border vertices
   * snapped onto it (vm_symmetry_detect); why not, for an open input */
  vm_symmetry_report symmetry;
  int symmetry_reoriented;    /* the half model was turned to face away from the
                                 volume it bounds with the plane */
  int64_t symmetry_border;    /* border vertices of the result (all in the plane) */
  int64_t symmetry_resnapped; /* border vertices a step left off the plane by rounding
                                 (within the tolerance), put back on it */
  double symmetry_drift;      /* the farthest of them was that far off */
  int64_t symmetry_off;       /* border vertices of the result farther off (0; a warning) */
} vm_surface_summary;

/* Run opts->step on the surface m (dim 3, triangles and/or quads) in
 * place. Progress goes to the context's log at VM_LOG_INFO, one line per
 * step ("repair: ...", "remesh: ...", "curvature: ...", "adapt: ..."),
 * and per iteration to opts->adapt.monitor. The adaptation's reference
 * surface is the repaired input before any remeshing.
 * The result is checked exactly: a remeshed surface that intersects
 * itself is given up for the repaired input (a warning); where the
 * adapted surface intersects itself or an element reversed, the vertices
 * there go back to where they were before the adaptation, with growing
 * rings of neighbours, until none is left (a warning).
 * A half model (opts->symmetry, varmesh/symmetry.h) keeps its border open
 * and in its plane bit for bit; summary->symmetry says what was found.
 * Returns VM_OK; VM_WARN_INVERTED if an element's orientation reversed
 * or triangles intersect after that (summary->adapt.flipped,
 * summary->self_intersections); VM_ERR_INTERRUPTED (the
 * context's interrupt flag; m holds the last iterate, or, interrupted
 * during the repair or the remeshing, which cannot stop half-way, the mesh
 * they made: the run ends after them); VM_ERR_ARG (not a
 * surface mesh, bad options), VM_ERR_FORMAT (what the repair refused, an
 * open surface the repair did not see: summary->open, a half model
 * vm_symmetry_detect refused), VM_ERR_NOMEM,
 * VM_ERR_BACKEND, with the error text on the context. summary may be
 * NULL. */
int vm_surface_run(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *opts,
                   vm_surface_summary *summary);

/* The exact check of a moved surface and its local back-off: m's
 * vertices moved from x0 (3 * m->nv coordinates; the same connectivity).
 * Where triangles of m intersect (CGAL's exact predicates) or an element's
 * orientation reversed against x0, the vertices of those elements go back
 * to x0 together with 1, then 2, 4 and 8 rings of neighbours, until no
 * pair and no reversed element is left; every other vertex keeps its
 * position bit for bit. Nothing is taken back if x0 itself has an
 * intersecting pair (the input's own intersections are the repair's to
 * report). Sets s->self_intersections (pairs left; -1 and nothing done if
 * m has quads), s->adapt.flipped (reversed elements left),
 * s->folds_found (pairs before), s->adapt_backed_off (vertices put back)
 * and s->fold_at, and logs a warning when something is left. Returns
 * VM_OK, VM_ERR_ARG, VM_ERR_NOMEM, VM_ERR_BACKEND. */
int vm_surface_unfold(vm_mesh *m, const double *x0, vm_surface_summary *s);

const char *vm_surface_step_name(vm_surface_step step);

#ifdef __cplusplus
}
#endif
#endif
