/* varmesh/mesh.h: the mesh model shared by every stage: vertices, mixed
 * elements in VTK order, per-vertex flags, named fields, string attributes. */
#ifndef VARMESH_MESH_H
#define VARMESH_MESH_H

#include <stdint.h>

#include "varmesh/ctx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Element types. Vertex order is VTK's for linear cells (and Gmsh's):
 *  TRI 0-1-2 counter-clockwise seen from the normal side;
 *  QUAD 0-1-2-3 around;
 *  TET 0-1-2 base, 3 on the side where (1-0)x(2-0) points;
 *  PYRAMID 0-1-2-3 base, 4 apex on the side of (1-0)x(3-0);
 *  PRISM 0-1-2 bottom, 3-4-5 top above 0-1-2, (1-0)x(2-0) pointing to the top
 *    (Gmsh's prism and VTK's wedge as VTK computes it: its parametric
 *    coordinates put 3-4-5 at +z; the vtkWedge header comment says otherwise);
 *  HEX 0-1-2-3 bottom, 4-5-6-7 top (VTK_HEXAHEDRON). */
typedef enum {
  VM_TRI = 0,
  VM_QUAD = 1,
  VM_TET = 2,
  VM_PYRAMID = 3,
  VM_PRISM = 4,
  VM_HEX = 5,
  VM_NTYPES = 6
} vm_elem_type;

#define VM_MAX_ELEM_VERTS 8

/* Number of vertices of a type (0 for an unknown type). */
int vm_elem_nverts(int type);
/* Topological dimension: 2 for TRI/QUAD, 3 for the others, 0 if unknown. */
int vm_elem_dim(int type);
/* Lower-case name ("tri", "quad", "tet", "pyramid", "prism", "hex"). */
const char *vm_elem_name(int type);
/* VTK cell type id (5, 9, 10, 14, 13, 12) and back (-1 if not linear). */
int vm_elem_to_vtk(int type);
int vm_elem_from_vtk(int vtk_type);
/* Local vertex j of an element in VTK's order (VTK, VTU, SU2) is local
 * vertex vm_elem_vtk_node(type, j) in varmesh's: the identity except for
 * prisms, whose base (0,1,2) VTK orders with its normal pointing away from
 * the top (3,4,5) and varmesh, like Gmsh and CGNS, towards it. The map is
 * its own inverse. */
int vm_elem_vtk_node(int type, int j);

/* Faces of a 3D element (for boundary extraction): returns the number of
 * faces; faces[f][0..3] are local vertex indices, nfv[f] 3 or 4, ordered so
 * the face normal by the right-hand rule points out of the element. For 2D
 * elements the "faces" are the edges (nfv 2). */
int vm_elem_faces(int type, int faces[6][4], int nfv[6]);

/* Per-vertex flags. */
enum { VM_VERTEX_FREE = 0, VM_VERTEX_FIXED = 1, VM_VERTEX_SLIP = 2 };

enum { VM_FIELD_VERTEX = 0, VM_FIELD_ELEMENT = 1 };
enum { VM_FIELD_F64 = 0, VM_FIELD_I32 = 1 };

/* A named field: `ncomp` values per vertex or per element, row-major
 * (value c of item i at data[i*ncomp + c]). */
typedef struct vm_field {
  char *name;
  int location; /* VM_FIELD_VERTEX or VM_FIELD_ELEMENT */
  int type;     /* VM_FIELD_F64 or VM_FIELD_I32 */
  int ncomp;    /* >= 1 */
  void *data;   /* double* or int32_t* */
} vm_field;

/* A string attribute (key -> value), e.g. "gmsh:physical_name:2:7" -> "wall". */
typedef struct vm_attr {
  char *key;
  char *value;
} vm_attr;

/* The mesh. Plain data with these invariants (vm_mesh_check verifies them):
 *  - xyz has 3*nv finite doubles (2D meshes have z = 0 and dim = 2);
 *  - etype[e] < VM_NTYPES; eoff[0] = 0, eoff[e+1] = eoff[e] + nverts(etype[e]);
 *  - 0 <= conn[k] < nv;
 *  - vflag[v] in {FREE, FIXED, SLIP}; vsurf[v] is the slip surface id (or -1);
 *  - field names are unique per location.
 * Arrays are owned by the mesh and allocated with the mesh's context. */
typedef struct vm_mesh {
  vm_ctx *ctx;
  int dim; /* 2 or 3: dimension of the embedding space of the geometry */
  int64_t nv;
  double *xyz;
  uint8_t *vflag;
  int32_t *vsurf;
  int64_t ne;
  uint8_t *etype;
  int64_t *eoff;
  int32_t *conn;
  int nfield;
  vm_field *fields;
  int nattr;
  vm_attr *attrs;
  /* storage capacities (internal: maintained by the vm_mesh_* functions) */
  int64_t vcap, ecap, ccap;
} vm_mesh;

/* Create an empty 3D mesh bound to ctx. Free with vm_mesh_destroy. */
int vm_mesh_create(vm_ctx *ctx, vm_mesh **out);
void vm_mesh_destroy(vm_mesh **p);

/* Allocate nv vertices (coordinates zeroed, flags FREE, vsurf -1),
 * discarding any previous vertices. */
int vm_mesh_set_vertices(vm_mesh *m, int64_t nv);
/* Allocate ne elements with `nconn` connectivity entries in total: the
 * caller fills etype, eoff and conn (eoff[0] is set to 0). */
int vm_mesh_set_elements(vm_mesh *m, int64_t ne, int64_t nconn);
/* Convenience for building meshes element by element: appends one element
 * (amortized growth). nverts taken from the type. */
int vm_mesh_add_element(vm_mesh *m, int type, const int32_t *verts);
/* Append one vertex; returns its index in *index (may be NULL). */
int vm_mesh_add_vertex(vm_mesh *m, double x, double y, double z, int64_t *index);

/* The first vertex element e uses at two of its corners (a collapsed
 * element), or -1. */
int32_t vm_mesh_repeated_vertex(const vm_mesh *m, int64_t e);

/* Verify the invariants above; on failure records a one-line message naming
 * the first offending vertex/element and returns VM_ERR_FORMAT. */
int vm_mesh_check(const vm_mesh *m);

/* Fields. Add a zero-filled field (replaces one with the same name and
 * location). The field's item count is nv or ne at the time of the call. */
int vm_mesh_add_field(vm_mesh *m, const char *name, int location, int type, int ncomp,
                      vm_field **out);
vm_field *vm_mesh_find_field(const vm_mesh *m, const char *name, int location);
int vm_mesh_remove_field(vm_mesh *m, const char *name, int location);
/* Items of a field: m->nv or m->ne. */
int64_t vm_field_count(const vm_mesh *m, const vm_field *f);

/* ---- half models: a symmetry plane x, y or z = C ---- */
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

/* Attributes. set replaces an existing key; get returns NULL if absent. */
int vm_mesh_set_attr(vm_mesh *m, const char *key, const char *value);
const char *vm_mesh_get_attr(const vm_mesh *m, const char *key);

/* A half model (attribute VM_SYMMETRY_PLANE_ATTR) and its mirror image in
 * that plane as one mesh: the vertices in the plane shared (bit for bit:
 * those whose coordinate across it is the plane's), the others and every
 * element doubled (the image's corners reordered so that it keeps its
 * orientation; fields copied to the images), the faces in the plane left
 * out (they are inside the whole). VM_ERR_ARG if m names no plane. */
int vm_mesh_mirror(vm_ctx *ctx, const vm_mesh *m, vm_mesh **out);

/* Deep copy of src into a new mesh. */
int vm_mesh_clone(const vm_mesh *src, vm_mesh **out);

/* Count elements per type into counts[VM_NTYPES]; returns the highest
 * topological dimension present (0 if no elements). */
int vm_mesh_count_types(const vm_mesh *m, int64_t counts[VM_NTYPES]);

/* Apply the "fixed" convention: an int vertex field named "fixed" with
 * nonzero value marks vertices FIXED. Returns the number marked. */
int64_t vm_mesh_apply_fixed_field(vm_mesh *m);

/* Axis-aligned bounding box of all vertices into lo, hi (lo = +inf and
 * hi = -inf if there are none); returns its diagonal (0 if empty). */
double vm_mesh_bounds(const vm_mesh *m, double lo[3], double hi[3]);

#ifdef __cplusplus
}
#endif
#endif
