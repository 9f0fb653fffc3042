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

/* The direction that sees k unit vectors n (3 each: a vertex's incident
 * face normals) best: the unit e maximizing min_i n_i . e, exactly. It is
 * the least-norm point p of the convex hull of the n_i, scaled to unit
 * length, and the minimum is |p| (hard-margin duality); p is the
 * projection of the origin onto the affine hull of one, two or three of
 * the n_i, so every such projection is tried and the best kept: O(k^4),
 * for the few vertices a cheaper guess does not serve. Returns that
 * minimum, and e in dir (dir may be NULL); where no direction sees every
 * n_i (the origin in their hull: the surface folds back there) the best
 * of the candidates, at most 0. k <= 0: returns -1. */
double vm_visible_direction(const double *n, int k, double dir[3]);

#ifdef __cplusplus
}
#endif
#endif
