/* prism/src/medial.c: the room the geometry leaves a column: the exterior
 * medial radius of each wall vertex by the shrinking-ball method (Ma, Bai
 * and van Oosterom 2012) on Embree point queries over the wall's triangles
 * in double precision.
 *
 * The ball at a wall vertex p touches the wall at p from outside: its
 * centre is c = p + r n, n the vertex's angle-weighted normal. It starts at
 * the cap radius; while a wall point q lies inside it (|c - q| < r) it
 * shrinks to the ball through p and the nearest such q, r = |q - p|^2 /
 * (2 n.(q - p)), which is smaller. It stops when the ball is empty: the
 * largest empty ball touching the wall at p along n. A straight column of
 * height h at p meets the straight column of another wall point q no later
 * than where the two balls' centres meet, so r is the height a column can
 * have without meeting another part's layer (concentric shells reach it
 * exactly: two spheres at gap g give g / 2 at their nearest points).
 *
 * A faceted concave surface makes every ball at one of its vertices shrink
 * to nothing (the incident facets tilt into it). Triangles whose normal is
 * within k.medial_sep_deg of n are therefore not obstacles: on a faceted
 * concave cylinder of radius R the ball then stops at R (the far side of
 * the cylinder holds it), and a fold of the wall sharper than the angle (a
 * wing root without a fillet) still counts, as it should: two straight
 * columns on either side of it meet at the height the ball gives. */
#include <math.h>
#include <string.h>

#include "state.h"

typedef struct {
  float *box; /* first (pr_tri_scene): 6 per triangle, rounded outwards */
  const double *xyz;
  const int32_t *tri;
  const double *fnrm;
} wall_geom;

typedef struct {
  const wall_geom *g;
  const double *c, *n; /* the ball's centre and the vertex normal */
  double cos_sep;      /* triangles with fnrm.n above it are not obstacles */
  double best;         /* squared distance of the nearest obstacle point so far */
  int64_t best_t;      /* its triangle (-1: none) */
  double q[3];
} ball_query;

/* The point q of triangle (a, b, c) nearest to p (Voronoi regions of the
 * vertices, then the edges, then the inside). */
static void closest_on_triangle(const double *p, const double *a, const double *b, const double *c,
                                double *q) {
  double ab[3], ac[3], ap[3];
  vm_sub3(b, a, ab);
  vm_sub3(c, a, ac);
  vm_sub3(p, a, ap);
  double d1 = vm_dot3(ab, ap), d2 = vm_dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    memcpy(q, a, 3 * sizeof *q);
    return;
  }
  double bp[3];
  vm_sub3(p, b, bp);
  double d3 = vm_dot3(ab, bp), d4 = vm_dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    memcpy(q, b, 3 * sizeof *q);
    return;
  }
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    double s = d1 / (d1 - d3);
    for (int k = 0; k < 3; k++) q[k] = a[k] + s * ab[k];
    return;
  }
  double cp[3];
  vm_sub3(p, c, cp);
  double d5 = vm_dot3(ab, cp), d6 = vm_dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    memcpy(q, c, 3 * sizeof *q);
    return;
  }
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    double s = d2 / (d2 - d6);
    for (int k = 0; k < 3; k++) q[k] = a[k] + s * ac[k];
    return;
  }
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    for (int k = 0; k < 3; k++) q[k] = b[k] + s * (c[k] - b[k]);
    return;
  }
  double den = va + vb + vc;
  double v = vb / den, w = vc / den;
  for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k] + w * ac[k];
}

/* Embree's callback: the nearest point of one triangle to the centre; the
 * nearest of all (ties: the lower triangle) is kept and the query radius
 * shrunk to it. */
static bool ball_point(struct RTCPointQueryFunctionArguments *a) {
  ball_query *b = a->userPtr;
  const wall_geom *g = b->g;
  int64_t t = a->primID;
  if (vm_dot3(g->fnrm + 3 * t, b->n) > b->cos_sep) return false;
  const int32_t *v = g->tri + 3 * t;
  double q[3];
  closest_on_triangle(b->c, g->xyz + 3 * (int64_t)v[0], g->xyz + 3 * (int64_t)v[1],
                      g->xyz + 3 * (int64_t)v[2], q);
  double d[3];
  vm_sub3(q, b->c, d);
  double d2 = vm_dot3(d, d);
  if (d2 < b->best || (d2 == b->best && t < b->best_t)) {
    b->best = d2;
    b->best_t = t;
    memcpy(b->q, q, sizeof b->q);
    float r = pr_float_up(sqrt(d2));
    if (r < a->query->radius) {
      a->query->radius = r;
      return true;
    }
  }
  return false;
}

/* The exterior medial radius at every vertex of the closed triangulation
 * (xyz, tri, fnrm) along its vertex normal vnrm, capped at `cap`; a ball
 * smaller than k.medial_floor times elen[v] is 0. */
int pr_medial_radius_of(vm_prism *p, const double *xyz, const int32_t *tri, const double *fnrm,
                        const double *vnrm, const double *elen, int64_t nv, int64_t nt, double cap,
                        double *radius, int64_t *hit) {
  vm_ctx *ctx = p->ctx;
  int st;
  if (!p->rt && (st = pr_rt_create(ctx, &p->rt))) return st;
  wall_geom g = {NULL, xyz, tri, fnrm};
  /* a half model's balls are stopped by its mirror image too: triangles
   * nt..2nt - 1 are the mirror images of 0..nt - 1 (turned, so that they
   * face outwards) */
  double *mx = NULL, *mf = NULL;
  int32_t *mt = NULL;
  int64_t ntq = nt;
  if (p->sym_ax >= 0) {
    int ax = p->sym_ax;
    mx = vm_alloc_array(ctx, (size_t)(6 * nv), sizeof *mx);
    mf = vm_alloc_array(ctx, (size_t)(6 * nt), sizeof *mf);
    mt = vm_alloc_array(ctx, (size_t)(6 * nt), sizeof *mt);
    if (!mx || !mf || !mt) {
      vm_free(ctx, mx);
      vm_free(ctx, mf);
      vm_free(ctx, mt);
      return VM_ERR_NOMEM;
    }
    memcpy(mx, xyz, (size_t)(3 * nv) * sizeof *mx);
    memcpy(mx + 3 * nv, xyz, (size_t)(3 * nv) * sizeof *mx);
    for (int64_t v = 0; v < nv; v++) mx[3 * (nv + v) + ax] = 2 * p->sym_val - xyz[3 * v + ax];
    memcpy(mf, fnrm, (size_t)(3 * nt) * sizeof *mf);
    memcpy(mf + 3 * nt, fnrm, (size_t)(3 * nt) * sizeof *mf);
    memcpy(mt, tri, (size_t)(3 * nt) * sizeof *mt);
    for (int64_t t = 0; t < nt; t++) {
      mf[3 * (nt + t) + ax] = -fnrm[3 * t + ax];
      mt[3 * (nt + t)] = (int32_t)(tri[3 * t] + nv);
      mt[3 * (nt + t) + 1] = (int32_t)(tri[3 * t + 2] + nv);
      mt[3 * (nt + t) + 2] = (int32_t)(tri[3 * t + 1] + nv);
    }
    g = (wall_geom){NULL, mx, mt, mf};
    ntq = 2 * nt;
  }
  g.box = vm_alloc_array(ctx, (size_t)ntq * 6, sizeof *g.box);
  if (!g.box) {
    vm_free(ctx, mx);
    vm_free(ctx, mf);
    vm_free(ctx, mt);
    return VM_ERR_NOMEM;
  }
  RTCScene scene = pr_tri_scene(p->rt, g.xyz, g.tri, NULL, ntq, 0, g.box, &g, NULL, NULL);
  st = pr_rt_check(ctx, p->rt, "scene build (medial radius)");
  const double cos_sep = cos(p->k.medial_sep_deg * PR_PI / 180);
  const int max_iter = p->k.medial_iter;
  if (st == VM_OK) {
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t v = 0; v < nv; v++) {
      const double *x = xyz + 3 * v, *n = vnrm + 3 * v;
      double r = cap;
      int64_t last = -1;
      for (int it = 0; it < max_iter; it++) {
        double c[3] = {x[0] + r * n[0], x[1] + r * n[1], x[2] + r * n[2]};
        ball_query b = {&g, c, n, cos_sep, INFINITY, -1, {0, 0, 0}};
        struct RTCPointQuery pq;
        pq.x = (float)c[0];
        pq.y = (float)c[1];
        pq.z = (float)c[2];
        pq.time = 0;
        /* the float centre is off by a rounding: the radius covers it */
        double off = fabs(c[0] - pq.x) + fabs(c[1] - pq.y) + fabs(c[2] - pq.z);
        pq.radius = pr_float_up(r + off);
        struct RTCPointQueryContext qc;
        rtcInitPointQueryContext(&qc);
        rtcPointQuery(scene, &pq, &qc, ball_point, &b);
        /* empty ball (the touching point p itself is at distance r) */
        if (b.best_t < 0 || !(b.best < r * r * (1 - p->k.medial_rel_tol))) break;
        double dq[3];
        vm_sub3(b.q, x, dq);
        double along = vm_dot3(dq, n);
        if (!(along > 0)) break; /* inside the ball q is ahead of p; only rounding says not */
        double rn = vm_dot3(dq, dq) / (2 * along);
        if (!(rn < r)) break;
        r = rn;
        last = b.best_t;
        if (r <= p->k.medial_floor * elen[v]) {
          r = 0;
          break;
        }
      }
      radius[v] = r;
      if (hit) hit[v] = last;
    }
  }
  rtcReleaseScene(scene);
  if (st == VM_OK) st = pr_rt_check(ctx, p->rt, "point query (medial radius)");
  vm_free(ctx, g.box);
  vm_free(ctx, mx);
  vm_free(ctx, mf);
  vm_free(ctx, mt);
  return st;
}

int pr_ball_faces_back(const vm_prism *p, int64_t hit, const double *fnrm, const double *n) {
  if (hit < 0) return 0;
  double f[3];
  memcpy(f, fnrm + 3 * (hit % p->nt), sizeof f);
  if (hit >= p->nt) f[p->sym_ax] = -f[p->sym_ax]; /* a mirror image's */
  return vm_dot3(f, n) < -cos(p->k.slot_face_deg * PR_PI / 180);
}

/* The wall vertices in a gap narrower than half their triangles' edges:
 * the ball (half the gap) stopped closer than k.gap_share of the vertex's
 * mean edge by a triangle facing back (within k.slot_face_deg of
 * opposite; a concave fold's triangles stand across, not opposite). A
 * slot between two parts (a strut against a wing, a flap's gap on a
 * published model) that the wall's triangles do not resolve: the columns
 * on both sides end nearly at once, the cells there are flat, and so are
 * the fill's tets across what is left, whatever the stage does; a solver
 * may fail there (simpleFoam did, on such a Cessna). Counted in the
 * report, said once as a warning. */
static void narrow_gaps(vm_prism *p, const double *r, const int64_t *hit) {
  int64_t n = 0, at = -1;
  for (int64_t v = 0; v < p->nw; v++) {
    if (!(r[v] < p->k.gap_share * p->elen[v])) continue;
    if (!pr_ball_faces_back(p, hit[v], p->fnrm, p->vnrm + 3 * v)) continue;
    n++;
    if (at < 0 || r[v] * p->elen[at] < r[at] * p->elen[v]) at = v;
  }
  p->rep.narrow_gap = n;
  if (!n) return;
  p->rep.narrow_gap_min = 2 * r[at];
  memcpy(p->rep.narrow_gap_at, p->wall + 3 * at, sizeof p->rep.narrow_gap_at);
  const double *x = p->wall + 3 * at;
  vm_log(p->ctx, VM_LOG_WARN,
         "prism: at %lld wall vertices the wall comes closer to itself than half its edges' "
         "length (a gap its triangles do not resolve); the narrowest, %g against edges of %g, "
         "near (%g, %g, %g): the layer's cells and the fill's tets there will be flat and a "
         "solver may fail on them; refine the wall there or close the gap",
         (long long)n, 2 * r[at], p->elen[at], x[0], x[1], x[2]);
}

int vm_prism_medial_radius(vm_prism *p, const double **radius) {
  if (!p || !radius) return VM_ERR_ARG;
  *radius = NULL;
  if (!p->medial) {
    double *r = vm_alloc_array(p->ctx, (size_t)p->nw, sizeof *r);
    int64_t *hit = vm_alloc_array(p->ctx, (size_t)p->nw, sizeof *hit);
    if (!r || !hit) {
      vm_free(p->ctx, r);
      vm_free(p->ctx, hit);
      return VM_ERR_NOMEM;
    }
    int st = pr_medial_radius_of(p, p->wall, p->tri, p->fnrm, p->vnrm, p->elen, p->nw, p->nt,
                                 p->k.medial_cap * p->o.thickness, r, hit);
    if (st < 0) {
      vm_free(p->ctx, r);
      vm_free(p->ctx, hit);
      return st;
    }
    narrow_gaps(p, r, hit);
    vm_free(p->ctx, hit);
    p->medial = r;
  }
  *radius = p->medial;
  return VM_OK;
}
