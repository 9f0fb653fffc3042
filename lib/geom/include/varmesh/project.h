/* varmesh/project.h: closest-point projection onto a reference triangle
 * surface and its feature lines (CGAL AABB trees), the sliding surfaces of
 * the minimizer (vm_surface_ops of varmesh/boundary.h). */
#ifndef VARMESH_PROJECT_H
#define VARMESH_PROJECT_H

#include <stdint.h>

#include "varmesh/boundary.h"
#include "varmesh/features.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The closest-point projector onto a reference triangle mesh and its
 * feature lines, for vm_minimizer_set_surfaces: surface id 0 is the whole
 * reference surface (closest point by an AABB tree; one constraint
 * normal: the normal of the face the point lands on); id k in 1..nline is
 * feature line k of the reference features (closest point on that
 * polyline; two constraint normals orthogonal to the line's direction
 * there, so a vertex slides along it). Other ids: VM_ERR_ARG. The
 * reference mesh and features are copied. */
typedef struct vm_surface_projector vm_surface_projector;

int vm_surface_projector_create(vm_ctx *ctx, const vm_mesh *ref, const vm_surface_features *f,
                                vm_surface_projector **out);
void vm_surface_projector_destroy(vm_surface_projector **p);
vm_surface_ops vm_surface_projector_ops(vm_surface_projector *p);
/* Number of reference feature lines. */
int32_t vm_surface_projector_nlines(const vm_surface_projector *p);

/* The surface each vertex of a mesh m (with features f, lying on or near
 * the reference) slides on: vsurf[v] (m->nv values) = -1 for CORNER
 * vertices of f and for any vertex within `tol` of a reference corner
 * (they stay fixed); k >= 1 for a LINE vertex within `tol` of reference
 * line k (the nearest); 0 for SMOOTH vertices and for LINE vertices with
 * no reference feature within `tol` (they slide on the surface). */
int vm_surface_projector_assign(vm_surface_projector *p, const vm_mesh *m,
                                const vm_surface_features *f, double tol, int32_t *vsurf);

/* Distance from each of n points (3*n) to the reference surface. */
int vm_surface_projector_distance(vm_surface_projector *p, int64_t n, const double *pts,
                                  double *dist);

/* The reference element (index into ref's elements) whose surface is
 * closest to each of n points (3*n): elem[i]; -1 if the reference has no
 * non-degenerate triangle. Consecutive points near each other are found
 * fastest (the last element found bounds the next search). */
int vm_surface_projector_closest_element(vm_surface_projector *p, int64_t n, const double *pts,
                                         int64_t *elem);

/* A per-vertex field of the reference (field[v], v < ref->nv) evaluated
 * at the closest reference points of n points (3*n): linear
 * interpolation in the triangle the closest point lies in. */
int vm_surface_projector_interpolate(vm_surface_projector *p, const double *field, int64_t n,
                                     const double *pts, double *out);
/* The same at one point, with a hint as vm_surface_ops.project_hinted's
 * (-1: none; updated): the triangle found last for a nearby point makes
 * the search local. */
int vm_surface_projector_interpolate_hinted(vm_surface_projector *p, const double *field,
                                            const double pt[3], int64_t *hint, double *out);

#ifdef __cplusplus
}
#endif
#endif
