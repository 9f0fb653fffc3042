/* test/surface/test_adapt.c: curvature-adapted node movement on a lens
 * with a sharp circular ridge: vertices condense near the ridge
 * (quantified), stay on the surface (Hausdorff bound), nothing flips,
 * connectivity and flags are kept, runs are deterministic; open surfaces,
 * fixed vertices and bad input; the projection onto a long feature line
 * against a brute-force scan. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/adapt.h"
#include "varmesh/curvature.h"
#include "varmesh/features.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Lens R = 1, d = 0.5: the ridge is the circle z = 0, r = sqrt(3)/2. */
static double ridge_distance(const double *p) {
  double r = sqrt(p[0] * p[0] + p[1] * p[1]) - sqrt(0.75);
  return sqrt(r * r + p[2] * p[2]);
}

typedef struct {
  double near_frac; /* vertices within 0.2 of the ridge / all */
  double len_near;  /* mean length of edges with midpoint within 0.2 of the ridge */
  double len_far;   /* ... farther than 0.4 */
} ridge_stats;

static ridge_stats measure(const vm_mesh *m) {
  ridge_stats s = {0, 0, 0};
  int64_t nn = 0, cn = 0, cf = 0;
  for (int64_t v = 0; v < m->nv; v++) nn += ridge_distance(m->xyz + 3 * v) < 0.2;
  s.near_frac = (double)nn / (double)m->nv;
  for (int64_t e = 0; e < m->ne; e++)
    for (int a = 0; a < 3; a++) {
      const double *p = m->xyz + 3 * m->conn[3 * e + a],
                   *q = m->xyz + 3 * m->conn[3 * e + (a + 1) % 3];
      double mid[3] = {0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 0.5 * (p[2] + q[2])};
      double l = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                      (p[2] - q[2]) * (p[2] - q[2]));
      double d = ridge_distance(mid);
      if (d < 0.2) {
        s.len_near += l;
        cn++;
      } else if (d > 0.4) {
        s.len_far += l;
        cf++;
      }
    }
  s.len_near /= (double)cn;
  s.len_far /= (double)cf;
  return s;
}

static void test_lens(vm_ctx *ctx) {
  vm_mesh *m = NULL, *in = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_lens(m, 1.0, 0.5, 0.08) == 0, "lens");
  vm_repair_report rr;
  CHECK(vm_surface_repair(m, NULL, &rr) == 0 && rr.border_edges == 0 && rr.reoriented == 0,
        "the lens is closed and outward: %s", vm_ctx_error(ctx));
  /* a vertex fixed by the user and the flags to be kept */
  int64_t fixed_v = 5;
  m->vflag[fixed_v] = VM_VERTEX_FIXED;
  double fixed_p[3];
  memcpy(fixed_p, m->xyz + 3 * fixed_v, sizeof fixed_p);
  vm_mesh_clone(m, &in);
  ridge_stats s0 = measure(m);
  double min0 = vm_surface_min_angle(m);

  vm_adapt_opts o = vm_adapt_opts_default();
  o.max_iter = 150;
  vm_adapt_result r;
  int st = vm_surface_adapt(m, NULL, &o, &r);
  CHECK(st == 0, "adapt: %d %s", st, vm_ctx_error(ctx));
  ridge_stats s1 = measure(m);
  double ab, ba;
  vm_surface_hausdorff(m, in, 0.01, &ab, &ba);
  printf("lens: %lld vertices, %d iterations, F %.6g -> %.6g (%s); ridge: %d line(s), %lld "
         "corners\n",
         (long long)m->nv, r.iterations, r.F_initial, r.F, r.stop, r.nline, (long long)r.ncorner);
  printf("  vertices within 0.2 of the ridge: %.3f -> %.3f; edge length near/far: %.4f/%.4f = "
         "%.3f -> %.4f/%.4f = %.3f\n",
         s0.near_frac, s1.near_frac, s0.len_near, s0.len_far, s0.len_near / s0.len_far, s1.len_near,
         s1.len_far, s1.len_near / s1.len_far);
  printf("  min angle %.2f -> %.2f, flipped %lld, Hausdorff %.2e / %.2e (diagonal 2.45), max "
         "vertex distance %.2e\n",
         min0, r.min_angle_after, (long long)r.flipped, ab, ba, r.max_distance);
  /* condensation near the ridge, quantified */
  CHECK(s1.near_frac > 1.25 * s0.near_frac, "near-ridge vertex fraction %g -> %g", s0.near_frac,
        s1.near_frac);
  CHECK(s1.len_near / s1.len_far < 0.85 * (s0.len_near / s0.len_far),
        "near/far edge length ratio %g -> %g", s0.len_near / s0.len_far, s1.len_near / s1.len_far);
  /* on the surface, nothing flipped, quality kept */
  CHECK(r.max_distance < 1e-12, "vertex distance to the surface %g", r.max_distance);
  CHECK(ab < 0.002 * 2.45 && ba < 0.002 * 2.45, "Hausdorff %g %g within 0.2%% of the diagonal", ab,
        ba);
  CHECK(r.flipped == 0, "flipped %lld", (long long)r.flipped);
  CHECK(r.min_angle_after >= 15, "min angle %g", r.min_angle_after);
  CHECK(r.nline == 1 && r.ncorner == 0, "one closed ridge line, no corner");
  /* connectivity, flags, the fixed vertex, the fields */
  CHECK(m->nv == in->nv && m->ne == in->ne &&
            !memcmp(m->conn, in->conn, sizeof *m->conn * (size_t)m->eoff[m->ne]),
        "connectivity unchanged");
  CHECK(!memcmp(m->vflag, in->vflag, (size_t)m->nv) &&
            !memcmp(m->vsurf, in->vsurf, sizeof *m->vsurf * (size_t)m->nv),
        "flags restored");
  CHECK(!memcmp(fixed_p, m->xyz + 3 * fixed_v, sizeof fixed_p), "fixed vertex kept");
  CHECK(vm_mesh_find_field(m, VM_FIELD_MEAN_CURVATURE, VM_FIELD_VERTEX) &&
            vm_mesh_find_field(m, VM_FIELD_MEAN_CURVATURE_FILTERED, VM_FIELD_VERTEX),
        "curvature fields written");
  /* ridge vertices still on the ridge polygon: in z = 0, between its
   * chords (about 68 of them) and the circle */
  int on = 1, nridge = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (in->xyz[3 * v + 2] == 0) {
      const double *p = m->xyz + 3 * v;
      double rad = sqrt(p[0] * p[0] + p[1] * p[1]);
      on &= fabs(p[2]) < 1e-14 && rad <= sqrt(0.75) + 1e-12 && rad > sqrt(0.75) * 0.998;
      nridge++;
    }
  CHECK(on && nridge > 30, "%d ridge vertices slid along the ridge", nridge);

  /* deterministic: the same bits again; and with a separate reference */
  vm_mesh *m2 = NULL;
  vm_mesh_clone(in, &m2);
  CHECK(vm_surface_adapt(m2, NULL, &o, NULL) == 0, "second run");
  CHECK(!memcmp(m->xyz, m2->xyz, sizeof *m->xyz * 3 * (size_t)m->nv), "deterministic");
  vm_mesh_destroy(&m2);
  vm_surface_features f;
  vm_surface_projector *ref = NULL;
  vm_surface_detect_features(in, o.feature_angle, o.corner_angle, &f);
  vm_surface_projector_create(ctx, in, &f, &ref);
  vm_mesh_clone(in, &m2);
  CHECK(vm_surface_adapt(m2, ref, &o, &r) == 0 && r.nline_vertices > 0, "with a reference");
  CHECK(!memcmp(m->xyz, m2->xyz, sizeof *m->xyz * 3 * (size_t)m->nv),
        "a reference equal to the mesh gives the same result");
  vm_mesh_destroy(&m2);
  vm_surface_projector_destroy(&ref);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&in);
}

/* Distance from p to the segment a-b. */
static double seg_dist(const double *p, const double *a, const double *b) {
  double ab[3], ap[3], l2 = 0, t = 0;
  for (int r = 0; r < 3; r++) ab[r] = b[r] - a[r], ap[r] = p[r] - a[r], l2 += ab[r] * ab[r];
  for (int r = 0; r < 3; r++) t += ap[r] * ab[r];
  t = l2 > 0 ? t / l2 : 0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  double d2 = 0;
  for (int r = 0; r < 3; r++) {
    double c = a[r] + t * ab[r] - p[r];
    d2 += c * c;
  }
  return sqrt(d2);
}

/* Projection onto a long feature line (the lens's ridge, a closed line of
 * more segments than the projector scans whole, so its tree answers):
 * the point it returns lies on the line and is as close as the closest
 * point of a brute-force scan of the line's edges, for points around the
 * ridge and far from it. */
static void test_line_projection(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_lens(m, 1.0, 0.5, 0.02) == 0, "fine lens");
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0 && f.nline == 1, "one ridge line: %d",
        f.nline);
  vm_surface_projector *pr = NULL;
  CHECK(vm_surface_projector_create(ctx, m, &f, &pr) == 0, "projector");
  vm_surface_ops ops = vm_surface_projector_ops(pr);
  int64_t bad = 0, off = 0, n = 0;
  double worst = 0;
  for (int i = 0; i < 40; i++)
    for (int j = 0; j < 9; j++) {
      double a = 2 * M_PI * (i + 0.37 * j) / 40, rad = 0.3 + 0.15 * j, z = 0.2 * (j - 4);
      double p[3] = {rad * cos(a), rad * sin(a), z}, q[3], nr[9];
      CHECK(ops.project(ops.user, 1, p, q, nr) == 2, "line projection");
      double brute = INFINITY, on = INFINITY;
      for (int64_t k = 0; k < f.nedge; k++) {
        const double *u = m->xyz + 3 * (int64_t)f.edge[2 * k],
                     *v = m->xyz + 3 * (int64_t)f.edge[2 * k + 1];
        double d = seg_dist(p, u, v), e = seg_dist(q, u, v);
        if (d < brute) brute = d;
        if (e < on) on = e;
      }
      double got = sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                        (q[2] - p[2]) * (q[2] - p[2]));
      if (fabs(got - brute) > 1e-12) bad++;
      if (on > 1e-12) off++;
      if (fabs(got - brute) > worst) worst = fabs(got - brute);
      n++;
    }
  fprintf(stderr, "line projection: %lld points onto a line of %lld segments, worst %.3g\n",
          (long long)n, (long long)f.nedge, worst);
  CHECK(f.nedge > 64, "the ridge has %lld segments", (long long)f.nedge);
  CHECK(bad == 0 && off == 0, "%lld not the closest point (worst %g), %lld off the line",
        (long long)bad, worst, (long long)off);
  vm_surface_projector_destroy(&pr);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&m);
}

/* The hinted projection (what the minimizers use) finds the closest
 * point whatever the hint: no hint, a triangle far away, the last answer;
 * on vm-gen wing, whose long thin triangles make the tree's own first
 * guess poor. */
static void test_hinted_projection(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_wing(m, 80, 8, 0.12, 25) == 0, "wing");
  vm_surface_projector *pr = NULL;
  CHECK(vm_surface_projector_create(ctx, m, NULL, &pr) == 0, "projector");
  vm_surface_ops ops = vm_surface_projector_ops(pr);
  CHECK(ops.project_hinted != NULL, "the projector has a hinted projection");
  int64_t bad = 0, n = 0, last = -1;
  double worst = 0;
  for (int64_t v = 0; v < m->nv; v += 3) {
    for (int j = 0; j < 3; j++) {
      const double *x = m->xyz + 3 * v;
      double p[3] = {x[0] + 0.01 * sin(v + j), x[1] + 0.02 * cos(3.0 * v + j),
                     x[2] + 0.01 * sin(7.0 * v - j)};
      double q0[3], q[3], nr[9];
      CHECK(ops.project(ops.user, 0, p, q0, nr) == 1, "projection");
      double d0 = sqrt((q0[0] - p[0]) * (q0[0] - p[0]) + (q0[1] - p[1]) * (q0[1] - p[1]) +
                       (q0[2] - p[2]) * (q0[2] - p[2]));
      int64_t hints[3] = {-1, (v * 7919 + j) % (m->ne > 0 ? m->ne : 1), last};
      for (int h = 0; h < 3; h++) {
        int64_t hint = hints[h];
        CHECK(ops.project_hinted(ops.user, 0, p, &hint, q, nr) == 1, "hinted projection");
        double d = sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                        (q[2] - p[2]) * (q[2] - p[2]));
        if (fabs(d - d0) > 1e-14 || hint < 0 || hint >= m->ne) bad++;
        if (fabs(d - d0) > worst) worst = fabs(d - d0);
        if (h == 2) last = hint;
        n++;
      }
    }
  }
  fprintf(stderr, "hinted projection: %lld queries, worst distance difference %.3g\n", (long long)n,
          worst);
  CHECK(bad == 0, "%lld hinted projections not the closest point (worst %g)", (long long)bad,
        worst);
  vm_surface_projector_destroy(&pr);
  vm_mesh_destroy(&m);
}

/* The projections of the slip vertices run on several threads: the same
 * result, bit for bit, with 1 and 2 threads (each vertex keeps its own
 * hint, and a failed projection does not stop the others), on vm-gen wing
 * (2,880 vertices: more than the 1,024 a parallel pass needs). */
static void test_threads_same(vm_ctx *ctx) {
  vm_mesh *m[2] = {NULL, NULL};
  for (int k = 0; k < 2; k++) {
    vm_mesh_create(ctx, &m[k]);
    CHECK(vm_gen_wing(m[k], 160, 8, 0.12, 25) == 0, "wing");
    vm_ctx_set_threads(ctx, k + 1);
    vm_adapt_opts o = vm_adapt_opts_default();
    o.max_iter = 30;
    vm_adapt_result r;
    CHECK(vm_surface_adapt(m[k], NULL, &o, &r) == 0 && r.iterations > 0, "adapt, %d thread(s): %s",
          k + 1, vm_ctx_error(ctx));
  }
  vm_ctx_set_threads(ctx, 0);
  CHECK(m[0]->nv == m[1]->nv &&
            memcmp(m[0]->xyz, m[1]->xyz, 3 * (size_t)m[0]->nv * sizeof(double)) == 0,
        "1 and 2 threads give different vertices");
  vm_mesh_destroy(&m[0]);
  vm_mesh_destroy(&m[1]);
}

static void test_open_cylinder(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  vm_gen_cylinder(m, 0.5, 1.0, 32, 12, &(vm_gen_jitter){0.2, 9});
  vm_adapt_opts o = vm_adapt_opts_default();
  o.max_iter = 30;
  vm_adapt_result r;
  CHECK(vm_surface_adapt(m, NULL, &o, &r) == 0, "open cylinder: %s", vm_ctx_error(ctx));
  int ok = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    /* on the (faceted) cylinder: radius between the chord's and 0.5 */
    double rad = sqrt(p[0] * p[0] + p[1] * p[1]);
    ok &= rad <= 0.5 + 1e-12 && rad >= 0.5 * cos(M_PI / 32 * 1.3);
    if (v < 32 || v >= m->nv - 32) ok &= p[2] == (v < 32 ? 0.0 : 1.0); /* border rows */
  }
  CHECK(ok, "vertices on the cylinder, borders on their circles");
  CHECK(r.flipped == 0 && r.nline == 2, "flipped %lld, lines %d", (long long)r.flipped, r.nline);
  vm_mesh_destroy(&m);
}

static void test_bad(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_adapt_result r;
  int st;
  vm_adapt_opts o = vm_adapt_opts_default();
  /* volume mesh */
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, i == 1, i == 2, i == 3, NULL);
  int32_t tet[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_TET, tet);
  CHECK(vm_surface_adapt(m, NULL, &o, &r) == VM_ERR_ARG, "volume mesh refused");
  vm_mesh_destroy(&m);
  /* non-manifold: two cubes sharing a corner */
  vm_mesh *a = NULL, *b = NULL;
  vm_mesh_create(ctx, &a);
  vm_gen_cube(a, 2);
  vm_mesh_create(ctx, &b);
  vm_gen_cube(b, 2);
  int64_t base = a->nv;
  for (int64_t v = 0; v < b->nv; v++)
    vm_mesh_add_vertex(a, b->xyz[3 * v] + 1, b->xyz[3 * v + 1] + 1, b->xyz[3 * v + 2] + 1, NULL);
  for (int64_t e = 0; e < b->ne; e++) {
    int32_t t[3];
    for (int k = 0; k < 3; k++) t[k] = (int32_t)(b->conn[3 * e + k] + base);
    vm_mesh_add_element(a, VM_TRI, t);
  }
  /* merge the touching corners into one vertex: a pinched surface */
  int64_t corner_b = -1, corner_a = -1;
  for (int64_t v = 0; v < a->nv; v++) {
    const double *p = a->xyz + 3 * v;
    if (p[0] == 1 && p[1] == 1 && p[2] == 1) {
      if (corner_a < 0)
        corner_a = v;
      else
        corner_b = v;
    }
  }
  for (int64_t k = 0; k < a->eoff[a->ne]; k++)
    if (a->conn[k] == corner_b) a->conn[k] = (int32_t)corner_a;
  double *x0 = malloc(sizeof *x0 * 3 * (size_t)a->nv);
  memcpy(x0, a->xyz, sizeof *x0 * 3 * (size_t)a->nv);
  CHECK(vm_surface_adapt(a, NULL, &o, &r) == VM_ERR_FORMAT, "non-manifold refused: %s",
        vm_ctx_error(ctx));
  CHECK(!memcmp(x0, a->xyz, sizeof *x0 * 3 * (size_t)a->nv), "refused mesh unchanged");
  free(x0);
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);
  /* a zero-area triangle: refused up front, naming it, mesh unchanged */
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 1, 0, NULL);
  int32_t *c = m->conn + 3 * 7;
  for (int r3 = 0; r3 < 3; r3++) /* vertex c[2] onto the midpoint of c[0]-c[1] */
    m->xyz[3 * c[2] + r3] = 0.5 * (m->xyz[3 * c[0] + r3] + m->xyz[3 * c[1] + r3]);
  x0 = malloc(sizeof *x0 * 3 * (size_t)m->nv);
  memcpy(x0, m->xyz, sizeof *x0 * 3 * (size_t)m->nv);
  st = vm_surface_adapt(m, NULL, &o, &r);
  CHECK(st == VM_ERR_ARG && strstr(vm_ctx_error(ctx), "zero-area element") &&
            !strchr(vm_ctx_error(ctx), '\n'),
        "zero-area triangle refused: %d %s", st, vm_ctx_error(ctx));
  CHECK(!memcmp(x0, m->xyz, sizeof *x0 * 3 * (size_t)m->nv), "refused mesh unchanged");
  free(x0);
  vm_mesh_destroy(&m);
  /* bad options */
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 1, 0, NULL);
  o.rounds = 0;
  CHECK(vm_surface_adapt(m, NULL, &o, &r) == VM_ERR_ARG, "rounds 0 refused");
  o = vm_adapt_opts_default();
  o.theta = 2;
  CHECK(vm_surface_adapt(m, NULL, &o, &r) == VM_ERR_ARG, "theta 2 refused");
  o = vm_adapt_opts_default();
  o.max_iter = 0;
  CHECK(vm_surface_adapt(m, NULL, &o, &r) == 0 && r.iterations == 0, "zero iterations: no-op");
  vm_mesh_destroy(&m);
}

/* Every allocation of an adaptation fails once: a clean error, no leak,
 * the mesh as it was. */
static void test_alloc_failures(vm_ctx *ctx) {
  vm_mesh *m = NULL, *m0 = NULL;
  vm_mesh_create(ctx, &m0);
  vm_gen_lens(m0, 1.0, 0.5, 0.3);
  vm_adapt_opts o = vm_adapt_opts_default();
  o.max_iter = 4;
  o.rounds = 2;
  int failures = 0, bad = 0;
  for (long n = 1; n < 5000; n++) {
    long live = vm_ctx_alloc_live(ctx);
    vm_mesh_clone(m0, &m);
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_surface_adapt(m, NULL, &o, NULL);
    vm_ctx_set_alloc_fail(ctx, 0);
    int same = !memcmp(m->xyz, m0->xyz, sizeof *m->xyz * 3 * (size_t)m->nv);
    vm_mesh_destroy(&m);
    if (st == 0) break;
    failures++;
    if (st != VM_ERR_NOMEM || vm_ctx_alloc_live(ctx) != live || !same) {
      if (!bad++)
        fprintf(stderr, "allocation %ld: status %d, live %ld -> %ld, same %d\n", n, st, live,
                vm_ctx_alloc_live(ctx), same);
    }
  }
  vm_ctx_clear_error(ctx);
  printf("allocation failures: %d points, each a clean VM_ERR_NOMEM: %s\n", failures,
         bad ? "NO" : "yes");
  CHECK(failures > 20 && bad == 0, "%d failure points, %d bad", failures, bad);
  vm_mesh_destroy(&m0);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, 1);
  test_lens(ctx);
  test_line_projection(ctx);
  test_hinted_projection(ctx);
  test_threads_same(ctx);
  test_open_cylinder(ctx);
  test_bad(ctx);
  test_alloc_failures(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("adapt");
}
