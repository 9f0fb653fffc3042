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

/* The plane's attribute (VM_SYMMETRY_PLANE_ATTR), its syntax
 * (vm_axis_plane_parse, vm_axis_plane_format) and a half model's mirror
 * image (vm_mesh_mirror) are in varmesh/mesh.h. */

typedef struct vm_cut_report {
  int axis;
  double value;
  int side; /* the side kept: +1 (coordinate >= value) or -1 */
  int64_t nv_in, nf_in, nv, nf;
  int64_t snapped;      /* vertices within the tolerance moved onto the plane */
  int64_t snapped_near; /* vertices moved onto it by snap_rel */
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
 * first put on it exactly, and with snap_rel > 0 (below 0.5) so is the
 * nearer end of an edge the plane would cut within snap_rel of its
 * length from it (the needle beside the cut avoided, the surface moved
 * by at most that much of the edge; triangles in their order); every edge crossing the plane gets
 * one vertex, its coordinate on the axis `value` bit for bit, the others interpolated from the
 * edge's lower-numbered end (the same point from either triangle); clipped triangles (a triangle or
 * a quadrilateral left) are triangulated, the quadrilateral along the diagonal with the larger
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
int vm_mesh_cut_plane(vm_mesh *m, int axis, double value, int side, double snap_rel,
                      vm_cut_report *r);

/* ---- an open wall's symmetry plane (the surface stage) ---- */

/* How far (a fraction of the bounding box's diagonal) a border vertex may
 * lie from the symmetry plane to be taken as in it and snapped onto it:
 * files written in single precision put a plane's vertices about 1e-7 of
 * the diagonal off it (VM_PLANE_TOL, varmesh/planar.h). */
#define VM_SYMMETRY_DETECT_TOL 1e-6

typedef struct vm_symmetry_opts {
  int given; /* 1: the plane is axis, value (else found from the border, or
                taken from m's attribute VM_SYMMETRY_PLANE_ATTR) */
  int axis;  /* 0, 1, 2 */
  double value;
  double tol_rel; /* <= 0: VM_SYMMETRY_DETECT_TOL */
} vm_symmetry_opts;

typedef struct vm_symmetry_report {
  int found; /* 1: m is a half model: its border lies in x[axis] = value */
  int given; /* 1: the plane was given (opts), 2: by m's attribute */
  int axis;
  double value;
  int side; /* the side of the plane the wall lies on: +1, -1 */
  int64_t border_edges, border_vertices, loops;
  int64_t snapped;   /* border vertices put onto the plane (they were off it) */
  double max_offset; /* the farthest a border vertex was from it */
  double tol;        /* the tolerance used (absolute) */
  char why[384];     /* found 0 and border_edges > 0: why m is not a half model */
} vm_symmetry_report;

/* The symmetry plane of the surface m (triangles, quads), if m is a half
 * model: m has border edges, every border vertex lies within the
 * tolerance of one plane x, y or z = C (found: the value most border
 * vertices have exactly, or given), some vertex off it, every vertex on
 * one side of it, no face in it, and the border loops do not cross each
 * other in it. Then every border vertex's coordinate is set to C bit for
 * bit, the attribute VM_SYMMETRY_PLANE_ATTR set, r->found = 1.
 * A border that does not make m a half model is not an error unless the
 * plane was given (opts or m's attribute): r->found = 0 and r->why says
 * what (its loops in different planes, the vertex farthest from the
 * flattest plane, the whole surface in the plane); m is unchanged.
 * Refused (VM_ERR_FORMAT, one line on the context saying what and where,
 * m unchanged): a given plane the border is not in (its farthest vertex,
 * the distance), a closed surface with a given plane, a wall on both
 * sides of the plane (its extreme points), faces in the plane, border
 * loops crossing each other (the two edges). VM_ERR_ARG, VM_ERR_NOMEM. */
int vm_symmetry_detect(vm_mesh *m, const vm_symmetry_opts *o, vm_symmetry_report *r);

/* Keep a half model's border in its plane after a step that moved or
 * remeshed it: border vertices within tol of x[axis] = value are set onto
 * it exactly (*snapped: how many were off it, bit for bit; *max_off the
 * largest distance among them), those farther are counted in *off (may be
 * NULL: none expected), *at the first (may be NULL). Any pointer but m
 * may be NULL. Returns VM_OK or VM_ERR_NOMEM. */
int vm_symmetry_keep(vm_mesh *m, int axis, double value, double tol, int64_t *snapped,
                     double *max_off, int64_t *off, double at[3]);

/* The volume between the half model m and its plane, positive if m is
 * oriented outward (the divergence theorem with the field
 * (x[axis] - value) e_axis, which vanishes on the plane). */
double vm_symmetry_half_volume(const vm_mesh *m, int axis, double value);

#ifdef __cplusplus
}
#endif
#endif
