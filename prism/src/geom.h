/* prism/src/geom.h: geometry of prisms and surfaces on plain arrays:
 * prism quality over quadrature simplices, column
 * directions and per-prism targets of a triangulated surface. */
#ifndef VARMESH_PRISM_GEOM_H
#define VARMESH_PRISM_GEOM_H

#include <math.h>
#include <stdint.h>

#include "params.h"
#include "varmesh/ctx.h"
#include "vec3.h"

#define PR_PI 3.14159265358979323846

/* Minimum over the 12 compound matrices of the prism's geometric rule of
 * det / (|c1| |c2| |c3|), normalized to 1 on the right prism with an
 * equilateral base: > 0 iff every node (and every corner tet) is positive.
 * x: 6 vertices, x[3*i + k]. */
double pr_prism_quality(const double *x);
/* The same over the 6 corner tets (the figure the report calls the scaled
 * Jacobian), and the number of corner tets with det <= 0 in *inverted. */
double pr_prism_corner_quality(const double *x, int *inverted);

/* Angle in degrees between side edge o -> x and the unit normal n (180 for
 * an edge of zero length). */
double pr_tilt_deg(const double *o, const double *x, const double *n);

/* A closed triangulated surface's connectivity, as plain arrays: nt
 * triangles (3 vertex indices each) on nv vertices, vertex -> triangles
 * and vertex -> neighbour vertices in CSR form. Borrowed, never owned. */
typedef struct pr_surf {
  int64_t nv, nt;
  const int32_t *tri;
  const int64_t *vt_off;
  const int32_t *vt;
  const int64_t *vv_off;
  const int32_t *vv;
} pr_surf;

/* Unit angle-weighted vertex normals of the surface s at coordinates xyz,
 * then made visible from every incident face where possible (min over
 * faces of n . f maximized where it was below k->visible_min) and blended
 * with their neighbours where the surface has sharp edges, so columns
 * spread instead of crossing. fn: 3*nt face normals (computed here).
 * vnrm may be NULL; dir receives the blended directions. Returns the
 * number of vertices where no visible direction was found (ctx: scratch
 * memory; without it the blending is skipped). */
int64_t pr_surface_dirs(vm_ctx *ctx, const pr_surf *s, const pr_dir_params *k, const double *xyz,
                        double *fn, double *vnrm, double *dir, int blend_passes);

/* Targets of the prisms on triangles tri (nt) over surface `base`: each
 * corner a of triangle t goes to base_a + h_a * u_a with u_a = dir_a
 * blended towards the face normal as little as needed for the target to
 * be valid with a margin (k->target_quality); where the unblended target
 * widens away from the wall (a convex part: a fan around a tip or a
 * trailing edge) it is taken as it is once its quality is above
 * k->fair_quality, since there it is the exact offset and a blended one
 * would overlap its neighbours'. Writes 18 values per triangle into tgt. */
void pr_build_targets(int64_t nt, const int32_t *tri, const pr_dir_params *k, const double *base,
                      const double *fn, const double *dir, const double *h, double *tgt);

#endif
