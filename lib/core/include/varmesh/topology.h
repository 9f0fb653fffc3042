/* varmesh/topology.h: boundary faces of a mesh, boundary vertices, and
 * vertex-to-element adjacency. */
#ifndef VARMESH_TOPOLOGY_H
#define VARMESH_TOPOLOGY_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Boundary faces of the elements of the highest dimension present: faces
 * (3D: triangles/quads; 2D: edges) used by exactly one element. Output:
 * nface faces, face f has fnv[f] vertices (2, 3 or 4) at fverts[4*f ..],
 * oriented outward, and belongs to element felem[f]. Arrays allocated with
 * vm_malloc (free with vm_free); any output pointer may be NULL.
 * Faces used by more than two elements make the mesh non-manifold: counted
 * in *nonmanifold (may be NULL) and treated as interior. */
int vm_mesh_boundary(const vm_mesh *m, int64_t *nface, int32_t **fverts, uint8_t **fnv,
                     int32_t **felem, int64_t *nonmanifold);

/* Mark every vertex on the boundary (vm_mesh_boundary) with `flag`, leaving
 * vertices already FIXED alone; returns the number of boundary vertices in
 * *count (may be NULL). */
int vm_mesh_mark_boundary(vm_mesh *m, int flag, int64_t *count);

/* Vertex -> element adjacency (elements of every dimension), CSR:
 * elements of v are elems[rowptr[v] .. rowptr[v+1]), increasing. */
int vm_mesh_vertex_elements(const vm_mesh *m, int64_t **rowptr, int32_t **elems);

#ifdef __cplusplus
}
#endif
#endif
