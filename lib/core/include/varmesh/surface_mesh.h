/* varmesh/surface_mesh.h: the triangles of a surface mesh (quads as their
 * four corner triangles), its edges with incidence counts and vertex
 * one-rings, for the modules that work on surfaces. */
#ifndef VARMESH_SURFACE_MESH_H
#define VARMESH_SURFACE_MESH_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Triangles of the 2D elements of a mesh. A triangle element gives itself
 * (weight 1); a quad 0-1-2-3 gives its four corner triangles (3,0,1),
 * (0,1,2), (1,2,3), (2,3,0) with weight 1/2 each, i.e. both diagonal
 * splittings averaged. Volume elements are ignored. elem[t] is the mesh
 * element of triangle t. */
typedef struct vm_surf_tris {
  int64_t nt;
  int32_t *tri; /* 3 per triangle */
  double *w;
  int32_t *elem;
} vm_surf_tris;

int vm_surf_tris_build(vm_ctx *ctx, const vm_mesh *m, vm_surf_tris *t);
void vm_surf_tris_free(vm_ctx *ctx, vm_surf_tris *t);

/* Polygon edges of the 2D elements (the sides of triangles and quads, not
 * quad diagonals), unique, sorted by (a, b) with a < b; nface[e] is the
 * number of element sides on the edge (1 boundary, 2 interior, > 2
 * non-manifold). rowptr/adj: the vertex graph of these edges (CSR, sorted
 * neighbours). onbnd[v]: 1 if v lies on an edge with nface != 2. */
typedef struct vm_surf_edges {
  int64_t ne;
  int32_t *ev; /* 2 per edge */
  int32_t *nface;
  int64_t *rowptr;
  int32_t *adj;
  uint8_t *onbnd;
  int64_t nboundary, nnonmanifold;
} vm_surf_edges;

int vm_surf_edges_build(vm_ctx *ctx, const vm_mesh *m, vm_surf_edges *e);
void vm_surf_edges_free(vm_ctx *ctx, vm_surf_edges *e);
/* Index of edge (a, b) (either order) or -1. */
int64_t vm_surf_edge_find(const vm_surf_edges *e, int32_t a, int32_t b);

#ifdef __cplusplus
}
#endif
#endif
