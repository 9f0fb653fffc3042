/* test/surface/test_cleanup.c: sliver removal without remeshing
 * (vm_surface_cleanup) and cone points (vm_surface_mark_cones).
 *  - A cube whose faces are 12 x 12 grids with needles made by pulling
 *    some inner vertices almost onto a neighbour: afterwards no triangle
 *    under 15 degrees, the smallest angle at least the grid's 45 degrees
 *    less what a pulled vertex leaves, the surface closed and manifold
 *    (Euler characteristic 2), the volume exact (nothing moved), every
 *    vertex an input vertex bit for bit with its field value, the 12
 *    edges still features and the 8 corners still corners.
 *  - An icosphere with needles on the sphere: the smallest angle never
 *    falls, the slivers go, the surface stays within the tolerance.
 *  - A clean graded surface is left exactly as it was (grading kept).
 *  - A non-manifold vertex (two tetrahedra touching) is refused.
 *  - A spindle (two cones): its two tips are cone points, its rings are
 *    not; through vm_surface_run (input size and uniform size) the tips
 *    stay where they are, bit for bit. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/cleanup.h"
#include "varmesh/features.h"
#include "varmesh/repair.h"
#include "varmesh/shapes.h"
#include "varmesh/surface.h"
#include "support/check_surface.h"
#include "vmtest.h"

#define N 12

static int32_t vid[N + 1][N + 1][N + 1];

static vm_mesh *cube(vm_ctx *ctx) {
  vm_mesh *m = chk_grid_cube(ctx, N, 1, &vid[0][0][0]);
  CHECK(m != NULL, "mesh");
  return m;
}

/* Is every vertex of m a vertex of ref, bit for bit? (O(n m), small meshes) */
static int64_t find_vertex(const vm_mesh *ref, const double *p) {
  for (int64_t v = 0; v < ref->nv; v++)
    if (!memcmp(ref->xyz + 3 * v, p, 3 * sizeof *p)) return v;
  return -1;
}

static void test_cube(vm_ctx *ctx) {
  vm_mesh *m = cube(ctx);
  /* needles: pull inner face vertices 97 % of the way to a neighbour */
  int pulled = 0;
  for (int i = 2; i < N - 1; i += 3)
    for (int j = 2; j < N - 1; j += 3) {
      int32_t v = vid[i][j][0], w = vid[i + 1][j][0];
      double *p = m->xyz + 3 * (int64_t)v, *q = m->xyz + 3 * (int64_t)w;
      for (int r = 0; r < 3; r++) p[r] += 0.97 * (q[r] - p[r]);
      v = vid[N][i][j], w = vid[N][i][j + 1];
      p = m->xyz + 3 * (int64_t)v, q = m->xyz + 3 * (int64_t)w;
      for (int r = 0; r < 3; r++) p[r] += 0.97 * (q[r] - p[r]);
      pulled += 2;
    }
  vm_field *fld = NULL;
  CHECK(vm_mesh_add_field(m, "id", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &fld) == 0, "field");
  for (int64_t v = 0; v < m->nv; v++) ((int32_t *)fld->data)[v] = (int32_t)(7 * v + 3);
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "features");
  CHECK(f.nedge == 12 * N && f.ncorner == 8, "cube features: %lld edges, %lld corners",
        (long long)f.nedge, (long long)f.ncorner);
  vm_cleanup_report r;
  vm_cleanup_opts o = vm_cleanup_opts_default();
  CHECK(vm_surface_cleanup(m, &f, &o, &r) == 0, "cleanup: %s", vm_ctx_error(ctx));
  fprintf(stderr,
          "cube: %d pulled; %lld flips, %lld collapses; under 15 deg %lld -> %lld; min "
          "%.3f -> %.3f; vertices %lld -> %lld\n",
          pulled, (long long)r.flips, (long long)r.collapses, (long long)r.below_in,
          (long long)r.below, r.min_angle_in, r.min_angle, (long long)r.nv_in, (long long)r.nv);
  CHECK(r.below_in >= 2 * pulled && r.min_angle_in < 2, "the needles are there: %lld, %.2f",
        (long long)r.below_in, r.min_angle_in);
  CHECK(r.below == 0 && r.min_angle >= 15, "slivers left: %lld, smallest angle %.2f",
        (long long)r.below, r.min_angle);
  CHECK(r.nv >= r.nv_in - pulled && r.nv < r.nv_in, "vertices %lld -> %lld", (long long)r.nv_in,
        (long long)r.nv);
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed manifold, chi %lld", (long long)chi);
  CHECK_NEAR(chk_volume(m), 1.0, 1e-13, "volume");
  CHECK(r.max_dev < 1e-15, "a planar collapse moved the surface by %g", r.max_dev);
  vm_field *g = vm_mesh_find_field(m, "id", VM_FIELD_VERTEX);
  int64_t lost = 0, wrong = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int64_t s = find_vertex(in, m->xyz + 3 * v);
    if (s < 0)
      lost++;
    else if (!g || ((int32_t *)g->data)[v] != (int32_t)(7 * s + 3))
      wrong++;
  }
  CHECK(lost == 0 && wrong == 0, "vertices not from the input: %lld, field values wrong: %lld",
        (long long)lost, (long long)wrong);
  CHECK(f.nv == m->nv && f.nedge == 12 * N && f.ncorner == 8,
        "features after: %lld edges, %lld corners", (long long)f.nedge, (long long)f.ncorner);
  int64_t corners_kept = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (f.vclass[v] == VM_FEATURE_CORNER) {
      const double *p = m->xyz + 3 * v;
      corners_kept +=
          (p[0] == 0 || p[0] == 1) && (p[1] == 0 || p[1] == 1) && (p[2] == 0 || p[2] == 1);
    }
  CHECK(corners_kept == 8, "the cube's corners: %lld", (long long)corners_kept);
  /* a second run finds nothing to do */
  vm_cleanup_report r2;
  CHECK(vm_surface_cleanup(m, &f, &o, &r2) == 0 && r2.flips == 0 && r2.collapses == 0,
        "second run: %lld flips, %lld collapses", (long long)r2.flips, (long long)r2.collapses);
  /* the whole stage on the needled cube: every face is flat, so the
   * result lies on the input wherever it is measured (deviation 0), and
   * the corners stay */
  {
    vm_mesh *w = NULL;
    vm_mesh_clone(in, &w);
    vm_surface_opts so = vm_surface_opts_default();
    so.adapt.max_iter = 20;
    vm_surface_summary sum;
    CHECK(vm_surface_run(ctx, w, &so, &sum) == 0, "cube through the stage: %s", vm_ctx_error(ctx));
    CHECK(sum.deviation_measured && sum.deviation_rel <= 1e-12 &&
              sum.deviation_feature_rel <= 1e-12 && sum.corners_moved == 0 &&
              sum.deviation_features == 12 * (N - 1) + 8,
          "cube: deviation %g (features %g at %lld vertices), corners moved %lld",
          sum.deviation_rel, sum.deviation_feature_rel, (long long)sum.deviation_features,
          (long long)sum.corners_moved);
    vm_mesh_destroy(&w);
  }
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

/* Needles on the unit icosphere m: every 37th triangle's first vertex 95 %
 * of the way to its second, back on the sphere (bench/surface_shapes.py's
 * slivers). Returns how many were pulled. */
static int64_t pull_needles(vm_mesh *m) {
  int64_t pulled = 0;
  for (int64_t e = 0; e < m->ne; e += 37) {
    const int32_t *t = m->conn + 3 * e;
    double *p = m->xyz + 3 * (int64_t)t[0], *q = m->xyz + 3 * (int64_t)t[1];
    for (int r = 0; r < 3; r++) p[r] += 0.95 * (q[r] - p[r]);
    double l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int r = 0; r < 3; r++) p[r] /= l;
    pulled++;
  }
  return pulled;
}

static void test_sphere(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  double c[3] = {0, 0, 0};
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_icosphere(m, c, 1.0, 4, 0, NULL) == 0, "icosphere");
  int64_t pulled = pull_needles(m);
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "sphere features");
  vm_cleanup_opts o = vm_cleanup_opts_default();
  vm_cleanup_report r;
  CHECK(vm_surface_cleanup(m, &f, &o, &r) == 0, "cleanup: %s", vm_ctx_error(ctx));
  fprintf(stderr,
          "sphere: %lld pulled; %lld flips, %lld collapses; under 15 deg %lld -> %lld; min "
          "%.3f -> %.3f; moved <= %.3g\n",
          (long long)pulled, (long long)r.flips, (long long)r.collapses, (long long)r.below_in,
          (long long)r.below, r.min_angle_in, r.min_angle, r.max_dev);
  CHECK(r.min_angle >= r.min_angle_in, "the smallest angle fell: %.3f -> %.3f", r.min_angle_in,
        r.min_angle);
  CHECK(r.below_in > 0 && r.below <= r.below_in / 10, "slivers %lld -> %lld", (long long)r.below_in,
        (long long)r.below);
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed manifold, chi %lld", (long long)chi);
  double ab = 0, ba = 0, tol = 2.5e-4 * 2 * sqrt(3.0);
  CHECK(vm_surface_hausdorff(in, m, 0.01, &ab, &ba) == 0, "hausdorff");
  CHECK(ab <= 2 * tol && ba <= 2 * tol, "moved %g / %g, tolerance %g", ab, ba, tol);
  vm_surface_features_free(ctx, &f);
  /* the whole stage: the needles' sharp corners in the input stay where
   * they are, also those the sliver removal left on a smooth patch (the
   * adaptation used to slide them away: 2 of 4 on the level-3 sphere, 0.5
   * of the local edge) */
  for (int level = 3; level <= 4; level++) {
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    vm_gen_icosphere(w, c, 1.0, level, 0, NULL);
    pull_needles(w);
    vm_surface_opts so = vm_surface_opts_default();
    so.adapt.max_iter = 40;
    vm_surface_summary sum;
    CHECK(vm_surface_run(ctx, w, &so, &sum) == 0, "needled sphere through the stage: %s",
          vm_ctx_error(ctx));
    vm_mesh_destroy(&w);
    fprintf(stderr,
            "needled sphere (level %d) through the stage: %lld feature vertices, deviation %.3g "
            "there, %.3g anywhere; corners moved %lld\n",
            level, (long long)sum.deviation_features, sum.deviation_feature_rel, sum.deviation_rel,
            (long long)sum.corners_moved);
    CHECK(sum.deviation_measured && sum.deviation_features > 0 && sum.corners_moved == 0 &&
              sum.deviation_feature_rel < 0.01,
          "needled sphere (level %d): %lld corners moved, deviation at features %g", level,
          (long long)sum.corners_moved, sum.deviation_feature_rel);
  }
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);

  /* the deviation the stage reports, where it has a known size: the unit
   * sphere (level 4, edges of about h = 0.08) remeshed uniformly to edges
   * of L = 0.4 has triangles whose centroids lie about L^2 / (6 R) inside
   * it: L / 6 of their own edge, and (L^2 / 6) / h of the input's edge at
   * the input's vertices there */
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, c, 1.0, 4, 0, NULL);
  double h = 0;
  for (int64_t e = 0; e < m->ne; e++)
    for (int k = 0; k < 3; k++) {
      const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e + k],
                   *b = m->xyz + 3 * (int64_t)m->conn[3 * e + (k + 1) % 3];
      h += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2])) /
           (3.0 * (double)m->ne);
    }
  vm_surface_opts so = vm_surface_opts_default();
  so.step = VM_SURFACE_REMESH;
  so.size = VM_SURFACE_SIZE_UNIFORM;
  so.remesh_opts.target_edge_length = 0.4;
  vm_surface_summary sum;
  CHECK(vm_surface_run(ctx, m, &so, &sum) == 0, "uniform remeshing: %s", vm_ctx_error(ctx));
  double sag = 0.4 * 0.4 / 6;
  fprintf(stderr,
          "sphere at L = 0.4: deviation %.4f (%.4f of the local edge), L^2 / 6 = %.4f, over h = "
          "%.4f: %.4f\n",
          sum.deviation_abs, sum.deviation_rel, sag, h, sag / h);
  CHECK(sum.deviation_measured && sum.deviation_abs >= 0.7 * sag &&
            sum.deviation_abs <= 1.5 * sag && sum.deviation_rel >= 0.7 * sag / h &&
            sum.deviation_rel <= 1.5 * sag / h && sum.deviation_features == 0,
        "sphere at L = 0.4: deviation %g (%g of the local edge), expected about %g (%g)",
        sum.deviation_abs, sum.deviation_rel, sag, sag / h);
  vm_mesh_destroy(&m);
}

/* A flat graded grid (spacing growing by 1.3 in x and y), closed into a
 * slab by its mirror image is not needed: an open surface is enough. */
static void test_graded(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  const int n = 10;
  double s[11];
  s[0] = 0;
  for (int i = 1; i <= n; i++) s[i] = s[i - 1] + pow(1.3, i);
  vm_mesh_set_vertices(m, (n + 1) * (n + 1));
  for (int i = 0; i <= n; i++)
    for (int j = 0; j <= n; j++) {
      double *p = m->xyz + 3 * (int64_t)(i * (n + 1) + j);
      p[0] = s[i], p[1] = s[j], p[2] = 0.01 * s[i] * s[j];
    }
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      int32_t a = i * (n + 1) + j, b = a + n + 1;
      int32_t t0[3] = {a, b, b + 1}, t1[3] = {a, b + 1, a + 1};
      vm_mesh_add_element(m, VM_TRI, t0);
      vm_mesh_add_element(m, VM_TRI, t1);
    }
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "graded features");
  vm_cleanup_report r;
  CHECK(vm_surface_cleanup(m, &f, NULL, &r) == 0, "cleanup graded: %s", vm_ctx_error(ctx));
  CHECK(r.flips == 0 && r.collapses == 0 && m->nv == in->nv && m->ne == in->ne &&
            !memcmp(m->xyz, in->xyz, 3 * (size_t)m->nv * sizeof(double)) &&
            !memcmp(m->conn, in->conn, 3 * (size_t)m->ne * sizeof(int32_t)),
        "a clean graded surface changed: %lld flips, %lld collapses", (long long)r.flips,
        (long long)r.collapses);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

static vm_mesh *spindle(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_spindle(m, 48, 0.001) == 0, "spindle");
  return m;
}

/* Two tetrahedra sharing one vertex: not a manifold vertex. */
static void test_bowtie(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  chk_bowtie(m);
  double x[7][3];
  memcpy(x, m->xyz, sizeof x);
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  f.nv = m->nv;
  f.vclass = calloc(7, 1);
  f.vline = calloc(7, sizeof *f.vline);
  CHECK(vm_surface_cleanup(m, &f, NULL, NULL) == VM_ERR_ARG &&
            strstr(vm_ctx_error(ctx), "not manifold"),
        "a non-manifold vertex is refused: %s", vm_ctx_error(ctx));
  CHECK(m->nv == 7 && m->ne == 8, "and the mesh is left as it was");
  free(f.vclass);
  free(f.vline);
  vm_mesh_destroy(&m);
}

static void test_cones(vm_ctx *ctx) {
  vm_mesh *m = spindle(ctx);
  CHECK(m->nv == 2 + 10 * 48 && m->ne == 20 * 48, "spindle: %lld vertices, %lld triangles",
        (long long)m->nv, (long long)m->ne);
  vm_mesh *bad = NULL;
  vm_mesh_create(ctx, &bad);
  CHECK(vm_gen_spindle(bad, 2, 0.001) == VM_ERR_ARG && vm_gen_spindle(bad, 8, 0.3) == VM_ERR_ARG,
        "spindle: bad arguments refused");
  vm_mesh_destroy(&bad);
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "spindle features");
  CHECK(f.vclass[0] != VM_FEATURE_CORNER && f.vclass[1] != VM_FEATURE_CORNER,
        "the tips are not corners by their edges");
  int64_t nc = vm_surface_mark_cones(m, &f, 60);
  CHECK(nc == 2 && f.vclass[0] == VM_FEATURE_CORNER && f.vclass[1] == VM_FEATURE_CORNER,
        "cone points: %lld", (long long)nc);
  vm_surface_features_free(ctx, &f);
  /* a sphere has none */
  vm_mesh *s = NULL;
  double c[3] = {0, 0, 0};
  vm_mesh_create(ctx, &s);
  vm_gen_icosphere(s, c, 1.0, 3, 0, NULL);
  CHECK(vm_surface_detect_features(s, 20, 50, &f) == 0, "sphere features");
  CHECK(vm_surface_mark_cones(s, &f, 60) == 0, "a sphere has no cone point");
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&s);

  /* the stage keeps the tips, with either size */
  for (int size = 0; size < 2; size++) {
    vm_mesh *w = spindle(ctx);
    double tip[2][3];
    memcpy(tip, w->xyz, sizeof tip);
    vm_surface_opts o = vm_surface_opts_default();
    o.size = size;
    o.adapt.max_iter = 40;
    vm_surface_summary sum;
    int st = vm_surface_run(ctx, w, &o, &sum);
    CHECK(st == 0, "run (size %d): %d %s", size, st, vm_ctx_error(ctx));
    CHECK(find_vertex(w, tip[0]) >= 0 && find_vertex(w, tip[1]) >= 0,
          "size %d: a tip moved or went away", size);
    CHECK(sum.cones == 2 && sum.cleaned, "size %d: %lld cones, cleaned %d, refused %lld", size,
          (long long)sum.cones, sum.cleaned, (long long)sum.remesh_refused);
    double mn = vm_surface_min_angle(w);
    CHECK(mn >= sum.min_angle_input, "size %d: smallest angle %.3f -> %.3f", size,
          sum.min_angle_input, mn);
    fprintf(stderr,
            "spindle size %d: %lld -> %lld vertices, smallest angle %.2f -> %.2f; deviation "
            "%.3g, at %lld feature vertices %.3g\n",
            size, (long long)sum.nv_before_remesh, (long long)w->nv, sum.min_angle_input, mn,
            sum.deviation_rel, (long long)sum.deviation_features, sum.deviation_feature_rel);
    CHECK(sum.deviation_measured && sum.corners_moved == 0 && sum.deviation_feature_rel <= 0.15,
          "size %d: %lld corners or tips moved, deviation at features %g of the local edge", size,
          (long long)sum.corners_moved, sum.deviation_feature_rel);
    vm_mesh_destroy(&w);
  }
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  CHECK(vm_ctx_create(&ctx) == 0, "context");
  test_cube(ctx);
  test_sphere(ctx);
  test_graded(ctx);
  test_bowtie(ctx);
  test_cones(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("cleanup");
}
