/* varmesh/symmetry.h: half models. A closed triangle surface cut by an
 * axis-aligned plane (x, y or z = c), one side kept, its new border
 * exactly in the plane; the symmetry plane of an open wall found from its
 * border (or given) and checked; the plane carried by a mesh as the string
 * attribute "symmetry_plane" for the later stages. Axis-aligned planes
 * only: their coordinate is one double, set bit for bit. */
#ifndef VARMESH_SYMMETRY_H
#define VARMESH_SYMMETRY_H

#include <stddef.h>
#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The key of the mesh attribute that names a half model's symmetry plane;
 * its value is "x=C", "y=C" or "z=C", C printed so that strtod gives the
 * same double back ("y=0", "z=-1.25"). */
#define VM_SYMMETRY_PLANE_ATTR "symmetry_plane"

/* Vertices within this fraction of the bounding box's diagonal of the
 * plane are on it (the cut snaps them; the surface stage takes a border
 * this close as planar and snaps it). */
#define VM_SYMMETRY_TOL_REL 1e-9

/* Parse an axis-aligned plane "x=C", "y=C" or "z=C" (the axis letter in
 * either case, C a finite number), with a side after it, ":+" or ":-",
 * when side is not NULL (no suffix: *side = 0). Returns VM_OK, or
 * VM_ERR_ARG with a message on ctx (ctx may be NULL). */
int vm_axis_plane_parse(vm_ctx *ctx, const char *s, int *axis, double *value, int *side);

/* "y=0" into buf (n bytes, at least 40): the shortest %g that gives the
 * same double back. Returns buf. */
char *vm_axis_plane_format(int axis, double value, char *buf, size_t n);

/* The symmetry plane m carries (its attribute VM_SYMMETRY_PLANE_ATTR):
 * 1 and *axis (0, 1, 2), *value; 0 if it has none; VM_ERR_FORMAT (with a
 * message) if the attribute is malformed. */
int vm_mesh_get_symmetry_plane(const vm_mesh *m, int *axis, double *value);
/* Set (replace) that attribute. VM_OK, VM_ERR_ARG, VM_ERR_NOMEM. */
int vm_mesh_set_symmetry_plane(vm_mesh *m, int axis, double value);

typedef struct vm_cut_report {
  int axis;
  double value;
  int side; /* the side kept: +1 (coordinate >= value) or -1 */
  int64_t nv_in, nf_in, nv, nf;
  int64_t snapped;      /* vertices within the tolerance moved onto the plane */
  int64_t split_edges;  /* edges crossing the plane: one new vertex each */
  int64_t clipped;      /* triangles cut by the plane */
  int64_t degenerate;   /* triangles of zero area left out */
  int64_t border_edges; /* border edges of the result */
  int64_t border_off;   /* ... not in the plane (an input that was not closed) */
  double tol;           /* the snapping distance used */
} vm_cut_report;

/* Cut the triangle surface m in place by the plane x[axis] = value and
 * keep the side `side` (+1: x[axis] >= value, -1: <=, 0: the side the
 * model reaches farther into; a tie keeps +1). Vertices within
 * VM_SYMMETRY_TOL_REL of the bounding box's diagonal of the plane are
 * first put on it exactly; every edge crossing the plane gets one vertex,
 * its coordinate on the axis `value` bit for bit, the others interpolated
 * from the edge's lower-numbered end (the same point from either
 * triangle); clipped triangles (a triangle or a quadrilateral left) are
 * triangulated, the quadrilateral along the diagonal with the larger
 * smallest angle; triangles lying in the plane and triangles of zero area
 * are left out. Vertices keep their order (the unused ones dropped), the
 * new ones follow in the order they were made; orientation is kept.
 * Fields: element fields are copied from the parent triangle, attributes
 * from m; F64 vertex fields interpolated along the edge, I32 vertex
 * fields, vertex flags and slip surface ids taken where both ends of the
 * edge agree (else 0, FREE, -1). A closed input gives an open surface
 * whose border edges all lie in the plane exactly. Deterministic.
 * r may be NULL. Returns VM_OK; VM_ERR_ARG (bad axis, value or side, an
 * element that is not a triangle, nothing left on the side kept: m
 * unchanged), VM_ERR_NOMEM. */
int vm_mesh_cut_plane(vm_mesh *m, int axis, double value, int side, vm_cut_report *r);

#ifdef __cplusplus
}
#endif
#endif
