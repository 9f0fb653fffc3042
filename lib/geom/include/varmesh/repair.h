/* varmesh/repair.h: repair of an imported surface with CGAL (orient,
 * stitch, degenerate faces, isolated vertices, self-intersections),
 * isotropic remeshing with protected features, and Hausdorff distances. */
#ifndef VARMESH_REPAIR_H
#define VARMESH_REPAIR_H

#include <stdint.h>

#include "varmesh/features.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_repair_opts {
  int require_closed;           /* refuse a surface that stays open (default 1) */
  int check_self_intersections; /* (default 1): found ones are an error if
                                   require_closed, else a warning */
  int union_overlaps;           /* (default 1; with check_self_intersections, on a
                                   closed surface) closed components that overlap
                                   (faces of two intersect) or lie inside one
                                   another are replaced by their union (CGAL
                                   corefinement), with a VM_LOG_WARN; 0: such
                                   a surface is refused as self-intersecting */
  int heal_self;                /* (default 1; with check_self_intersections, on a
                                   closed surface) a closed component that
                                   intersects itself is healed: its crossing
                                   faces removed and the holes filled (CGAL
                                   remove_self_intersections), if the result is
                                   closed, bounds a volume and lies within
                                   twice the local edge length of the input
                                   both ways (the median length of the edges
                                   at the crossing faces' vertices), with a
                                   VM_LOG_WARN; otherwise, or with 0, refused */
} vm_repair_opts;

vm_repair_opts vm_repair_opts_default(void);

/* What vm_surface_repair found and did. */
typedef struct vm_repair_report {
  int64_t nv_in, nf_in;       /* vertices and faces before */
  int64_t nv, nf;             /* after (triangles) */
  int64_t merged_vertices;    /* duplicate points merged */
  int64_t removed_polygons;   /* duplicate or invalid (repeated vertex) faces removed */
  int64_t removed_degenerate; /* zero-area faces found and removed (by edge collapses/flips) */
  int64_t removed_isolated;   /* vertices used by no face */
  int64_t reoriented;         /* faces whose orientation was reversed */
  int64_t stitched;           /* border edge pairs stitched */
  int64_t border_edges;       /* left after repair (0: closed) */
  int64_t holes;              /* border cycles */
  int64_t components;         /* connected components */
  int64_t self_intersections; /* pairs of intersecting faces left (if checked, else -1) */
  int64_t united;             /* closed components replaced by their union (0: none) */
  int64_t union_pairs;        /* the pairs of faces of different components that
                                 intersected before the union */
  int64_t healed;             /* closed components that intersected themselves,
                                 healed (heal_self; 0: none) */
  int64_t heal_pairs;         /* their pairs of intersecting faces before */
  double heal_moved;          /* the largest distance between a healed
                                 component and its input */
  double volume;              /* enclosed volume (closed surfaces; else 0) */
  int refused;                /* on a refusal, why (VM_REPAIR_*), else 0 */
} vm_repair_report;

/* Why vm_surface_repair refused a surface (vm_repair_report.refused). */
enum {
  VM_REPAIR_EMPTY = 1,       /* no face, or none left */
  VM_REPAIR_OPEN = 2,        /* border edges left (require_closed) */
  VM_REPAIR_NONMANIFOLD = 3, /* an edge on three or more faces, a pinched vertex, or a
                                surface that cannot be oriented consistently */
  VM_REPAIR_CROSSING = 4,    /* faces that intersect and that neither the union nor
                                the healing took out */
  VM_REPAIR_RANGE = 5        /* coordinates too large for double precision */
};

/* Repair the surface m in place (its 2D elements; volume elements are an
 * error): merge duplicate points, drop faces with a repeated vertex and
 * duplicate faces, orient consistently (CGAL orient_polygon_soup), stitch
 * coincident borders, remove degenerate (zero-area) faces, remove isolated
 * vertices, triangulate quads, check for self-intersections, heal the
 * closed components that intersect themselves (o->heal_self), replace the
 * closed components that overlap or nest by their union (o->union_overlaps),
 * and orient every closed component outward (orient_to_bound_a_volume). The
 * result is a triangle mesh with new vertex numbering. Attributes are kept; fields,
 * vertex flags and slip surfaces are carried over where the items came
 * through: a kept vertex is one of m's at exactly its coordinates (merged
 * copies take the first one's values), a kept triangle one of m's
 * triangles, or a triangle of one of m's quads, on kept vertices. A field
 * with any new item (made by the repair) is dropped, said with a
 * VM_LOG_WARN; a repair that changes nothing keeps every field.
 * Refused (negative status, m unchanged, one line naming what and where):
 *  - VM_ERR_FORMAT: a non-manifold edge or vertex, or a surface that cannot
 *    be oriented consistently (it would have to be cut); an open surface
 *    (border edges left) when o->require_closed; self-intersections when
 *    checked and o->require_closed; nothing left after repair;
 *  - VM_ERR_ARG, VM_ERR_NOMEM, VM_ERR_BACKEND.
 * rep may be NULL (zeros on refusal, except an open surface's
 * border_edges and holes, and `refused`, which says why); o NULL means
 * defaults. */
int vm_surface_repair(vm_mesh *m, const vm_repair_opts *o, vm_repair_report *rep);

/* What vm_surface_wrap made. */
typedef struct vm_wrap_report {
  int64_t nv_in, nf_in; /* the input's vertices and faces */
  int64_t nv, nf;       /* the wrap's (triangles) */
  double alpha, offset; /* as given */
  double elapsed;       /* seconds */
} vm_wrap_report;

/* Replace the surface m (its 2D elements, read as a triangle soup:
 * polygons split into fans; volume elements are an error) by a closed,
 * 2-manifold, consistently oriented triangle surface that contains it and
 * does not intersect itself (CGAL's 3D alpha wrapping): no ball of radius
 * alpha passes between the wrap and the input, and the wrap lies about
 * `offset` away from the input everywhere. For a model no repair can
 * close: holes, edges on three or more faces, parts that touch or cross,
 * faces inside. Attributes are kept; fields, flags and slip surfaces are
 * dropped (the caller says so). rep may be NULL. Returns VM_OK, VM_ERR_ARG
 * (volume elements, no face, alpha or offset not positive and finite),
 * VM_ERR_NOMEM, VM_ERR_BACKEND. */
int vm_surface_wrap(vm_mesh *m, double alpha, double offset, vm_wrap_report *rep);

/* Pairs of intersecting triangles of a triangle mesh m (faces sharing a
 * vertex or an edge intersect only if they overlap beyond that). Writes
 * the count to *count and, if pairs != NULL, a vm_malloc'd array of
 * 2 * count element indices, sorted (free with vm_free). */
int vm_surface_self_intersections(const vm_mesh *m, int64_t *count, int32_t **pairs);

typedef struct vm_remesh_opts {
  double target_edge_length; /* > 0 */
  int iterations;            /* (default 5) */
  int relaxation_steps;      /* tangential relaxation per iteration (default 1) */
  double keep_angle;         /* feature-line vertices where the line turns by more than
                                this (degrees, default 10) are kept like corners */
} vm_remesh_opts;

vm_remesh_opts vm_remesh_opts_default(void);

/* Isotropic remeshing (CGAL PMP::isotropic_remeshing) of the triangle mesh
 * m in place to edge length o->target_edge_length, new vertices projected
 * onto the input surface. Features in f (of m; may be NULL) are protected:
 * feature edges are constrained (split, or collapsed along their line,
 * never flipped; their vertices never move off the line) and corners, and
 * line vertices where the line turns by more than o->keep_angle, are kept
 * in place (so a line loses only vertices where it is nearly straight). On success m holds the new
 * mesh (fields and flags dropped, one VM_LOG_WARN if there were fields) and f, if given, the
 * features of the new mesh (same corners, the constrained edges, lines renumbered). Returns VM_OK,
 * VM_ERR_ARG (not a closed-or-open manifold triangle mesh, bad options), VM_ERR_NOMEM,
 * VM_ERR_BACKEND. */
int vm_surface_remesh(vm_mesh *m, vm_surface_features *f, const vm_remesh_opts *o,
                      double corner_deg);

/* Approximate one-sided Hausdorff distances between two triangle meshes:
 * the largest distance from a sample of a's surface to b (*ab) and of b's
 * to a (*ba); samples are the vertices, edge points and a regular grid of
 * spacing `spacing` on every face (<= 0: 1/100 of the bounding box
 * diagonal of a). Deterministic. Either output may be NULL. */
int vm_surface_hausdorff(const vm_mesh *a, const vm_mesh *b, double spacing, double *ab,
                         double *ba);
/* The same, and where each largest distance was found: the sample of a
 * farthest from b (ab_at) and of b farthest from a (ba_at); any output may
 * be NULL. */
/* Whether each of n points (3*n) lies inside the closed triangle/quad
 * surface surf (inside[i] = 1) or outside (0), by the parity of a ray's
 * crossings, the majority of three rays that meet no triangle within
 * rounding of its edges or vertices (up to eight directions are tried);
 * -1 for a point within distance tol of the surface, where the parity says
 * nothing, or where no three such rays were found. */
int vm_surface_inside(const vm_mesh *surf, int64_t n, const double *pts, double tol,
                      int8_t *inside);
int vm_surface_hausdorff_at(const vm_mesh *a, const vm_mesh *b, double spacing, double *ab,
                            double *ba, double ab_at[3], double ba_at[3]);

#ifdef __cplusplus
}
#endif
#endif
