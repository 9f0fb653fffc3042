/* varmesh/features.h: sharp features of a surface mesh: feature edges
 * (dihedral angle threshold, and boundary edges), feature lines (chains of
 * feature edges between corners) and corners; the vertex classes the
 * surface stage gives the minimizer (smooth: slip on surface 0; on feature
 * line k: slip on surface k; corner: fixed). */
#ifndef VARMESH_FEATURES_H
#define VARMESH_FEATURES_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { VM_FEATURE_SMOOTH = 0, VM_FEATURE_LINE = 1, VM_FEATURE_CORNER = 2 };

/* Features of one mesh (plain data; free with vm_surface_features_free).
 *  - edge[2k], edge[2k+1] (smaller index first), sorted: the feature edges;
 *    eline[k] in 1..nline: the line the edge belongs to;
 *  - vclass[v]: VM_FEATURE_SMOOTH, _LINE or _CORNER; vline[v]: the line of
 *    a LINE vertex, 0 for SMOOTH, -1 for CORNER.
 * A corner is a vertex with 1 or >= 3 feature edges, one where its feature
 * line turns by more than the corner angle, or one marked by the caller.
 * A line is a maximal chain of feature edges whose inner vertices are not
 * corners; a closed chain without corners is one line. */
typedef struct vm_surface_features {
  int64_t nv;
  int64_t nedge;
  int32_t *edge;
  int32_t *eline;
  uint8_t *vclass;
  int32_t *vline;
  int32_t nline;
  int64_t ncorner;
  int64_t nline_vertices;
  int64_t nboundary; /* boundary edges (open surfaces), always features */
} vm_surface_features;

/* Detect the features of the 2D elements of m: an interior edge is a
 * feature if the angle between the normals of its two faces is at least
 * `angle_deg` (in (0, 180]; e.g. 40); boundary edges always are. A
 * degree-2 feature vertex where the line turns by more than `corner_deg`
 * (the angle between the two edge directions, in (0, 180]; >= 180: never)
 * is a corner. Needs a manifold mesh: a face that would make an edge or
 * vertex non-manifold gives VM_ERR_FORMAT naming the element. f is
 * overwritten (not freed first). Returns VM_OK, VM_ERR_ARG, VM_ERR_FORMAT,
 * VM_ERR_NOMEM, VM_ERR_BACKEND. */
int vm_surface_detect_features(const vm_mesh *m, double angle_deg, double corner_deg,
                               vm_surface_features *f);

/* Build the features of m from a given list of feature edges (2 per edge,
 * any order, duplicates allowed) and optional extra corners (corner[v]
 * != 0; NULL: none), classifying with `corner_deg` as above. Edges that are
 * not edges of m are an error (VM_ERR_ARG). */
int vm_surface_features_from_edges(const vm_mesh *m, int64_t nedge, const int32_t *edges,
                                   const uint8_t *corner, double corner_deg,
                                   vm_surface_features *f);

void vm_surface_features_free(vm_ctx *ctx, vm_surface_features *f);

/* Turning angle (degrees, 0 straight, 180 back) of a polyline through the
 * points xyz at vertex v between its neighbours a and b: the angle between
 * a -> v and v -> b (180 if either is degenerate). The corner test of the
 * functions above. */
double vm_surface_turning_deg(const double *xyz, int32_t v, int32_t a, int32_t b);

/* Vertex classes for the minimizer: SMOOTH -> VM_VERTEX_SLIP on surface 0,
 * LINE on line k -> VM_VERTEX_SLIP on surface line_map ? line_map[k] : k,
 * CORNER -> VM_VERTEX_FIXED. Vertices already FIXED stay fixed, vertices
 * used by no 2D element become FIXED. */
int vm_surface_features_apply(vm_mesh *m, const vm_surface_features *f, const int32_t *line_map);

#ifdef __cplusplus
}
#endif
#endif
