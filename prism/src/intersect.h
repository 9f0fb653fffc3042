/* prism/src/intersect.h: the intersection query service on plain arrays
 * (coordinates, triangles, groups): an Embree device per run, triangle
 * soups queried at changing coordinates, and the single layer's faces. */
#ifndef VARMESH_PRISM_INTERSECT_H
#define VARMESH_PRISM_INTERSECT_H

#include <embree3/rtcore.h>
#include <math.h>
#include <stdint.h>

#include "params.h"
#include "varmesh/ctx.h"

/* v rounded to a float below (down) or above (up) it: Embree's boxes and
 * radii hold what the double-precision tests need. */
static inline float pr_float_down(double v) {
  float f = (float)v;
  if ((double)f > v) f = nextafterf(f, -INFINITY);
  return f;
}
static inline float pr_float_up(double v) {
  float f = (float)v;
  if ((double)f < v) f = nextafterf(f, INFINITY);
  return f;
}

/* An Embree device with an error callback: created once per run, shared
 * by every query of the run. An error Embree reports (on any thread) is
 * kept, and the query that sees it copies the message to the context's
 * error (VM_ERR_BACKEND). Errors: VM_ERR_NOMEM, VM_ERR_BACKEND. */
typedef struct pr_rt pr_rt;
int pr_rt_create(vm_ctx *ctx, pr_rt **out);
void pr_rt_destroy(pr_rt **rt);
/* The device's error since the last look (rtcGetDeviceError and the
 * callback's), copied to the context as VM_ERR_BACKEND naming `what`;
 * VM_OK if none. */
int pr_rt_check(vm_ctx *ctx, pr_rt *rt, const char *what);

/* A committed scene of one user geometry over nprim triangles of (xyz,
 * tri): primitive q is triangle prims[q] (prims NULL: q). Their boxes,
 * rounded outwards to float and padded by `pad`, are written to `box` (6
 * floats per primitive), which must be the first member of the user data
 * `data` (the bounds callback reads them there). isect and occl are the
 * geometry's ray callbacks (NULL for point queries only). The caller
 * releases the scene and checks the device (pr_rt_check). */
RTCScene pr_tri_scene(pr_rt *rt, const double *xyz, const int32_t *tri, const int32_t *prims,
                      int64_t nprim, double pad, float *box, void *data,
                      RTCIntersectFunctionN isect, RTCOccludedFunctionN occl);

/* A triangle soup with its edges, for repeated intersection queries at
 * changing coordinates (the topology is fixed): ntri triangles (3 vertex
 * indices each), group NULL or one per triangle (see
 * vm_prism_find_intersections). The soup copies tri and group and
 * borrows rt. check != 0: compare every incremental answer with the full
 * query (an error if they differ). */
typedef struct pr_soup pr_soup;
int pr_soup_create(vm_ctx *ctx, pr_rt *rt, const pr_isect_params *k, int64_t ntri,
                   const int32_t *tri, const int32_t *group, int check, pr_soup **out);
void pr_soup_destroy(vm_ctx *ctx, pr_soup **s);
/* Pairs of intersecting triangles at coordinates xyz (see
 * vm_prism_find_intersections). */
int pr_soup_intersections(vm_ctx *ctx, pr_soup *s, const double *xyz, int64_t *npairs,
                          int64_t **pairs);
/* The same answer, computed from the soup's last query where few vertices
 * moved since: pairs of two unmoved faces are kept, and only the edges of
 * moved faces (against all faces) and all edges against the moved faces
 * are cast. */
int pr_soup_intersections_cached(vm_ctx *ctx, pr_soup *s, const double *xyz, int64_t *npairs,
                                 int64_t **pairs);

/* The faces of a single prism layer over a wall of nw vertices, nt
 * triangles (tri) and ned edges (edge, 2 per edge): the tops, the side
 * quads (each split into four triangles around its centre) and the wall.
 * Borrows rt; copies the rest. */
typedef struct pr_layer_faces pr_layer_faces;
int pr_layer_faces_create(vm_ctx *ctx, pr_rt *rt, const pr_isect_params *k, int check, int64_t nw,
                          int64_t nt, const int32_t *tri, int64_t ned, const int32_t *edge,
                          pr_layer_faces **out);
void pr_layer_faces_destroy(vm_ctx *ctx, pr_layer_faces **lf);
/* Intersecting face pairs of the layer at coordinates xyz (2nw vertices:
 * the wall, then the tops), queried incrementally from the last call.
 * Marks the wall vertex of every column that carries an intersecting top
 * or side face in `mark` (nw, may be NULL). The number of intersecting
 * face pairs in *npairs. */
int pr_layer_faces_query(vm_ctx *ctx, pr_layer_faces *lf, const double *xyz, uint8_t *mark,
                         int64_t *npairs);

#endif
