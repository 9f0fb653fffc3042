/* prism/src/prism_private.h: the layer builder's state and the helpers its
 * phases share (geometry of prisms, targets, solves, detection). */
#ifndef VARMESH_PRISM_PRIVATE_H
#define VARMESH_PRISM_PRIVATE_H

#include <math.h>
#include <stdint.h>

#include "varmesh/minimize.h"
#include "varmesh/prism.h"
#include "varmesh/problem.h"

#define PR_PI 3.14159265358979323846

/* A prism at least this good (pr_prism_quality) may be its own target. */
#define PR_FAIR_QUALITY 0.05
/* Element field holding the per-prism target vertex coordinates. */
#define PRISM_TARGET_FIELD "vm_prism_target"

struct vm_prism {
  vm_ctx *ctx;
  vm_prism_opts o;
  double t0;       /* omp_get_wtime() at creation */
  int done;        /* phases completed (vm_prism_phase + 1) */
  int64_t nw, nt;  /* wall vertices and triangles */
  int64_t ned;     /* unique wall edges */
  double *wall;    /* 3*nw, bit-identical copies of the input */
  int32_t *tri;    /* 3*nt */
  double *fnrm;    /* 3*nt unit face normals */
  double *vnrm;    /* 3*nw angle-weighted unit vertex normals */
  double *dir;     /* 3*nw blended column directions (visible from every face) */
  double *elen;    /* nw: mean incident edge length */
  uint8_t *smooth; /* nw: incident face normals within 10 degrees of vnrm */
  int64_t *vt_off; /* vertex -> triangles (CSR) */
  int32_t *vt;
  int64_t *vv_off; /* vertex -> neighbour vertices (CSR, sorted) */
  int32_t *vv;
  int32_t *edge;   /* 2*ned, a < b */
  int32_t *etri;   /* 2*ned triangles on each side (-1: open edge) */

  struct pr_soup *soup; /* the layer's faces for intersection queries */
  double *soup_xyz;     /* 3*(2nw + ned): wall, top, then the side quads' centres */
  vm_mesh *layer;  /* single layer: 2nw vertices, nt prisms, target field */
  vm_problem *prob;
  double *h;       /* nw target heights */
  double *cap;     /* nw upper bounds of the thickness left by cutting */
  uint8_t *cut;    /* nw: rounds the column was cut in (saturates at 255) */

  /* marching result */
  int nlev;        /* levels (layers + 1); 0 before marching */
  double *lev;     /* nlev * 3 * nw */
  double *sched;   /* heights of the schedule (nlayers) */

  vm_prism_report rep;
};

/* ---- small vector helpers ---- */
static inline double pr_dot(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void pr_cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline double pr_norm(const double *a) { return sqrt(pr_dot(a, a)); }
static inline double pr_normalize(double *a) {
  double n = pr_norm(a);
  if (n > 0)
    for (int k = 0; k < 3; k++) a[k] /= n;
  return n;
}
static inline double pr_dist(const double *a, const double *b) {
  double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return pr_norm(d);
}

/* Minimum over the 12 compound matrices of the prism's geometric rule of
 * det / (|c1| |c2| |c3|), normalized to 1 on the right prism with an
 * equilateral base: > 0 iff every node (and every corner tet) is positive.
 * x: 6 vertices, x[3*i + k]. */
double pr_prism_quality(const double *x);
/* The same over the 6 corner tets (the figure the report calls the scaled
 * Jacobian), and the number of corner tets with det <= 0 in *inverted. */
double pr_prism_corner_quality(const double *x, int *inverted);

/* Unit angle-weighted vertex normals of a triangulated surface (xyz, nt
 * triangles), then made visible from every incident face where possible
 * (min over faces of n . f maximized where it was below 0.2) and blended
 * with their neighbours where the surface has sharp edges, so columns
 * spread instead of crossing. fn: 3*nt face normals (computed here).
 * vnrm may be NULL; dir receives the blended directions. Returns the
 * number of vertices where no visible direction was found. */
int64_t pr_surface_dirs(const vm_prism *p, const double *xyz, double *fn, double *vnrm,
                        double *dir, int blend_passes);

/* Targets of the prisms on surface `base` (3*nw): each corner a of
 * triangle t goes to base_a + h_a * u_a with u_a = dir_a blended towards
 * the face normal as little as needed for the target to be valid with a
 * margin (quality 0.5); where the unblended target widens away from the
 * wall (a convex part: a fan around a tip or a trailing edge) it is taken
 * as it is once its quality is above 0.05, since there it is the exact
 * offset and a blended one would overlap its neighbours'. Writes 18 values
 * per triangle into tgt. */
void pr_build_targets(const vm_prism *p, const double *base, const double *fn,
                      const double *dir, const double *h, double *tgt);

/* Time since creation. */
double pr_elapsed(const vm_prism *p);
/* Report progress (solver: 1 for a solve's iteration, see vm_prism_progress). */
void pr_progress(vm_prism *p, vm_prism_phase ph, int step, double value, int64_t count,
                 int solver);
/* Time limit left (seconds, +inf if none). */
double pr_time_left(const vm_prism *p);

/* Minimize the layer's functional with the current targets (implicit or
 * explicit), at most max_iter iterations, reporting progress in phase ph.
 * *iters receives the iterations done. */
int pr_solve(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind, int max_iter,
             vm_prism_phase ph, int *iters);

/* Count invalid prisms (some compound det <= 0) of a prism mesh over all
 * prisms, and the minimum of pr_prism_quality. */
int64_t pr_count_invalid(const vm_mesh *m, double *qmin);

/* Intersections of the single layer's faces (top, sides, wall): per pair
 * the columns involved. Marks the wall vertex of every column that carries
 * an intersecting top or side face in
 * `mark` (nw, may be NULL). Returns the number of intersecting face pairs
 * in *npairs. */
int pr_layer_intersections(vm_prism *p, uint8_t *mark, int64_t *npairs);

/* A triangle soup with its edges, for repeated intersection queries at
 * changing coordinates (the topology is fixed). */
typedef struct pr_soup pr_soup;
int pr_soup_create(vm_ctx *ctx, int64_t ntri, const int32_t *tri, const int32_t *group,
                   pr_soup **out);
void pr_soup_destroy(vm_ctx *ctx, pr_soup **s);
/* Pairs of intersecting triangles at coordinates xyz (see
 * vm_prism_find_intersections). */
int pr_soup_intersections(vm_ctx *ctx, const pr_soup *s, const double *xyz, int64_t *npairs,
                          int64_t **pairs);
/* The same answer, computed from the soup's last query where few vertices
 * moved since: pairs of two unmoved faces are kept, and only the edges of
 * moved faces (against all faces) and all edges against the moved faces
 * are cast. With VM_PRISM_CHECK_INCREMENTAL=1 in the environment each such
 * answer is compared with the full query (an error if they differ). */
int pr_soup_intersections_cached(vm_ctx *ctx, pr_soup *s, const double *xyz, int64_t *npairs,
                                 int64_t **pairs);

/* Write the top vertices of the layer from thickness t along unit
 * directions d: top_v = wall_v + t_v d_v. */
void pr_set_top(vm_prism *p, const double *t, const double *d);

#endif
