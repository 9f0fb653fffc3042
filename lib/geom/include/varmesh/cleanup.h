/* varmesh/cleanup.h: sliver removal on a triangle surface without
 * remeshing it: edge flips and edge collapses, each taken only where it
 * raises the smallest angle of the triangles it touches and keeps the
 * shape within a tolerance; no vertex moves and none is added, so the
 * input's grading, its vertices (bit for bit) and its sharp features
 * stay. Also the cone points (tips) a feature detection by dihedral angle
 * does not see. */
#ifndef VARMESH_CLEANUP_H
#define VARMESH_CLEANUP_H

#include <stdint.h>

#include "varmesh/features.h"
#include "varmesh/mesh.h"
#include "varmesh/project.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_cleanup_opts {
  double angle;        /* triangles with a smaller angle (degrees) are worked on (default 15) */
  double max_dev;      /* a move may change the surface by at most this much (absolute;
                          <= 0: 2.5e-4 of the bounding-box diagonal, the default) ... */
  double max_dev_rel;  /* ... and by at most this fraction of the edge it works on
                          (default 0.05) */
  int rounds;          /* passes over the bad triangles (default 20) */
  int border_collapse; /* 1: a border vertex that is no corner may also be collapsed onto
                          its neighbour along the border, the border moving by at most the
                          tolerances (a half model, whose border lies in its symmetry
                          plane: it stays in it); default 0: border vertices stay */
} vm_cleanup_opts;

vm_cleanup_opts vm_cleanup_opts_default(void);

typedef struct vm_cleanup_report {
  int64_t nv_in, nf_in, nv, nf;
  int64_t flips, collapses;
  int64_t border_collapses; /* of the collapses, along the border (opts border_collapse) */
  int64_t below_in, below;  /* triangles with an angle below opts.angle */
  double min_angle_in, min_angle;
  /* the same, not counting the angles at corners of the features (where
   * the input's own corner angle bounds what any triangulation can do) */
  double min_angle_free_in, min_angle_free;
  double max_dev; /* the largest change of the surface the accepted moves made,
                     added up where they follow each other */
  int rounds;
} vm_cleanup_report;

/* Remove slivers (needles and caps) of the closed or open manifold
 * triangle mesh m in place. f (features of m, not NULL) is respected:
 * feature edges are never flipped and their vertices (corners, line
 * vertices) and border vertices are never removed, so the features keep
 * their shape exactly; only smooth vertices are collapsed away. A move is taken only if
 * the smallest angle of the triangles it replaces rises, no triangle
 * turns over (its normal stays within 60 degrees of the surface it
 * replaces) and the surface moves by at most the tolerances, counting
 * what the earlier moves around the same vertices changed (so a chain of
 * collapses cannot walk away from the input). Vertices
 * that stay keep their coordinates bit for bit and their order; vertex
 * fields, flags and surface ids follow them; element fields follow the
 * triangles if no flip was made, else they are dropped with a warning. On
 * return f holds the features of the new mesh. Deterministic. Returns
 * VM_OK, VM_ERR_ARG (not a triangle mesh, features of another mesh),
 * VM_ERR_NOMEM. */
int vm_surface_cleanup(vm_mesh *m, vm_surface_features *f, const vm_cleanup_opts *o,
                       vm_cleanup_report *r);

/* Smallest corner angle (degrees) of the 2D element e of m with the
 * vertex coordinates x (m->xyz or another position of m's vertices). */
double vm_surface_elem_min_angle(const vm_mesh *m, const double *x, int64_t e);

/* Area of the 2D element e of m with the vertex coordinates x (a polygon
 * as the fan of triangles from its first vertex). */
double vm_surface_elem_area(const vm_mesh *m, const double *x, int64_t e);

/* Triangles of the surface m whose normal opposes (dot <= 0) the normal of
 * the projector's reference surface at the closest point of their
 * centroid: turned over against the surface they lie on (a fold the
 * intersection test does not see). at (may be NULL): the first one's
 * centroid. A negative status on failure. */
int64_t vm_surface_count_opposing(const vm_mesh *m, vm_surface_projector *ref, double at[3]);

/* Smallest angle (degrees) of the triangles of m, and the smallest not at a
 * corner of f (f may be NULL: no corners). */
double vm_surface_min_angle_free(const vm_mesh *m, const vm_surface_features *f, double *min_all);

/* Cone points: an inner vertex that is not a corner of f and whose angle
 * deficit |360 - sum of its triangle angles| is at least `cone_deg`
 * degrees (a tip, a spinner, a tail cone: a cone of half-angle a has
 * 360 (1 - sin a); a plane, a cylinder or a ridge has 0) becomes a corner
 * of f (lines keep their numbers; a line vertex made a corner ends its
 * line there for the operations that read vclass). Returns the number of
 * vertices marked, or a negative status. */
int64_t vm_surface_mark_cones(const vm_mesh *m, vm_surface_features *f, double cone_deg);

/* vm_surface_detect_features, then vm_surface_mark_cones unless cone_deg
 * >= 360; *ncones (may be NULL): the cone points marked. On a triangle
 * mesh with int (VM_FIELD_I32) element fields, the edges between
 * triangles that differ in one of them (the borders of regions: vm-gen's
 * component, gmsh:physical) are feature edges too, so the remeshing, the
 * sliver removal and the adaptation keep every region's border as a line
 * (where a border meets another feature line, a corner). */
int vm_surface_detect_features_cones(const vm_mesh *m, double angle_deg, double corner_deg,
                                     double cone_deg, vm_surface_features *f, int64_t *ncones);

/* Where a surface folds back on itself (a triangle turned over onto its
 * neighbours, the rim of a plate of no thickness, needles folded against
 * their neighbours), no direction sees every triangle at a vertex, and no
 * column of a prism layer can stand there. vm_surface_unblind works on
 * every vertex whose margin -- the best, over unit directions e, of the
 * least n . e over its triangles' unit normals (vm_visible_direction) --
 * is below `margin`: of the edge flips and edge collapses at the vertex,
 * it takes the one that changes the surface least among those that leave
 * fewer such vertices around it and no other vertex there below
 * min(`target`, its margin before), if that change, added to what earlier
 * moves there changed, is at most `reach` times the mean length of the
 * vertex's edges. Border vertices and fixed vertices are never removed,
 * faces with different element fields never flipped; vertices that stay
 * keep their coordinates bit for bit and their order, vertex and element
 * fields follow them. With `keep_clean` the moves are all undone if they
 * leave more pairs of triangles intersecting than before (checked
 * exactly; r->undone). Deterministic. VM_OK (also if some are left: r->blind),
 * VM_ERR_ARG (not a manifold, consistently oriented triangle surface),
 * VM_ERR_NOMEM. */
typedef struct vm_unblind_opts {
  double margin;  /* worked on below this (default 1e-3: 0.06 degrees) */
  double target;  /* default 0.02 */
  double reach;   /* default 1 */
  int rounds;     /* passes over the vertices below the margin (default 8) */
  int keep_clean; /* default 1 */
  /* caps first: a triangle with an angle within cap_deg of 180 degrees
   * (default 0.1) whose apex lies within cap_dev (default 1e-3) times its
   * long edge of that edge has the edge flipped (across a crease too: the
   * crease then runs through the apex), where that raises the two
   * triangles' smallest angle and no vertex there falls below min(target,
   * its margin before) */
  double cap_deg, cap_dev;
} vm_unblind_opts;

vm_unblind_opts vm_unblind_opts_default(void);

typedef struct vm_unblind_report {
  int64_t blind_in, blind; /* vertices below the margin before and after */
  int64_t flips, collapses;
  int64_t caps_in, caps, cap_flips; /* caps before and after, their flips */
  double max_dev; /* the largest change of the surface, added up where moves follow each other */
  int rounds;
  int undone;             /* the moves made triangles intersect and were undone */
  double at_in[3], at[3]; /* the first vertex below the margin before, the first left */
} vm_unblind_report;

int vm_surface_unblind(vm_mesh *m, const vm_unblind_opts *o, vm_unblind_report *r);

/* The vertices of the triangle surface m whose margin is below thr, and
 * where the first is (at may be NULL); a negative status on failure. */
int64_t vm_surface_count_blind(const vm_mesh *m, double thr, double at[3]);

#ifdef __cplusplus
}
#endif
#endif
