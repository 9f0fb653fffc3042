/* test/surface/test_graded.c: graded isotropic remeshing
 * (vm_surface_remesh_graded).
 *  - A box meshed with stretched triangles (aspect 6): afterwards the
 *    triangles are near-isotropic (no centroid-to-centroid
 *    non-orthogonality, OpenFOAM's measure on a surface, beyond 45 degrees
 *    where it was 75), the 8 corners are the input's bit for bit and still
 *    corners, the 12 edges still feature lines, every vertex on the box
 *    (1e-12), the volume exact, closed and manifold, and a second run gives
 *    the same bytes (deterministic).
 *  - A graded plate (spacing growing by 1.3 per cell): the grading stays
 *    (short edges where the input's are short, long where they are long).
 *  - vm-gen's swept wing (stretched triangles, sharp trailing edge, tips):
 *    no triangle turned over against the input, no self-intersection,
 *    every vertex on the input surface, the smallest angle away from
 *    corners and the worst non-orthogonality better than the input's, and
 *    the triangle count within a factor 3 of the input's.
 *  - A triangle count asked for, with the input's sizes and with the
 *    curvature's: met within 40 %; the curvature's sizes fine at the
 *    leading edge, coarse mid-chord.
 *  - Bad input: a non-manifold vertex and features of another mesh are
 *    refused, the mesh left as it was. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/cleanup.h"
#include "varmesh/features.h"
#include "varmesh/graded.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"
#include "varmesh/shapes.h"
#include "support/check_surface.h"
#include "vmtest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void tri_n(const vm_mesh *m, int64_t e, double n[3], double c[3]) {
  const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e],
               *b = m->xyz + 3 * (int64_t)m->conn[3 * e + 1],
               *d = m->xyz + 3 * (int64_t)m->conn[3 * e + 2];
  double u[3], w[3];
  for (int r = 0; r < 3; r++)
    u[r] = b[r] - a[r], w[r] = d[r] - a[r], c[r] = (a[r] + b[r] + d[r]) / 3;
  n[0] = u[1] * w[2] - u[2] * w[1];
  n[1] = u[2] * w[0] - u[0] * w[2];
  n[2] = u[0] * w[1] - u[1] * w[0];
  double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int r = 0; r < 3; r++) n[r] /= l;
}

typedef struct {
  uint64_t key;
  int64_t face;
} ekey;

static int cmp_ekey(const void *a, const void *b) {
  const ekey *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->face < y->face ? -1 : x->face > y->face;
}

/* OpenFOAM's non-orthogonality of a surface: over interior edges whose two
 * triangles lie within `flat` degrees of each other, the angle between the
 * line joining the two centroids and the edge's normal in the surface.
 * The largest, and how many are beyond 70 degrees (*over). */
static double worst_nonortho(const vm_mesh *m, double flat, int64_t *over) {
  int64_t n = 3 * m->ne;
  ekey *k = malloc((size_t)n * sizeof *k);
  for (int64_t e = 0; e < m->ne; e++)
    for (int i = 0; i < 3; i++) {
      uint32_t a = (uint32_t)m->conn[3 * e + i], b = (uint32_t)m->conn[3 * e + (i + 1) % 3];
      k[3 * e + i].key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
      k[3 * e + i].face = e;
    }
  qsort(k, (size_t)n, sizeof *k, cmp_ekey);
  double worst = 0;
  *over = 0;
  for (int64_t i = 0; i + 1 < n; i++) {
    if (k[i].key != k[i + 1].key) continue;
    double n0[3], n1[3], c0[3], c1[3], e[3], s[3], q[3], d[3];
    tri_n(m, k[i].face, n0, c0);
    tri_n(m, k[i + 1].face, n1, c1);
    if (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] < cos(flat * M_PI / 180)) continue;
    const double *a = m->xyz + 3 * (int64_t)(k[i].key >> 32),
                 *b = m->xyz + 3 * (int64_t)(k[i].key & 0xffffffffu);
    for (int r = 0; r < 3; r++) e[r] = b[r] - a[r], s[r] = n0[r] + n1[r], d[r] = c1[r] - c0[r];
    q[0] = e[1] * s[2] - e[2] * s[1];
    q[1] = e[2] * s[0] - e[0] * s[2];
    q[2] = e[0] * s[1] - e[1] * s[0];
    double c = fabs(q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) /
               (sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) *
                sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    double ang = acos(c > 1 ? 1 : c) * 180 / M_PI;
    if (ang > worst) worst = ang;
    *over += ang > 70;
  }
  free(k);
  return worst;
}

static void test_box(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const int n[3] = {24, 4, 4};
  CHECK(vm_gen_box(m, lo, hi, n) == 0, "box");
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  int64_t over0 = 0;
  double no0 = worst_nonortho(m, 20, &over0);
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "box features");
  CHECK(f.ncorner == 8 && f.nline == 12, "box: %lld corners, %d lines", (long long)f.ncorner,
        f.nline);
  vm_graded_report r;
  CHECK(vm_surface_remesh_graded(m, &f, NULL, &r) == 0, "graded box: %s", vm_ctx_error(ctx));
  int64_t over = 0;
  double no = worst_nonortho(m, 20, &over);
  fprintf(stderr,
          "box: %lld -> %lld vertices, sizes %.4g..%.4g, non-orthogonality %.1f -> %.1f deg, "
          "smallest angle %.2f -> %.2f\n",
          (long long)r.nv_in, (long long)r.nv, r.h_min, r.h_max, no0, no, r.min_angle_in,
          r.min_angle);
  CHECK(no0 > 70 && no < 45, "non-orthogonality %.1f -> %.1f", no0, no);
  CHECK(r.min_angle > 30, "smallest angle %.2f", r.min_angle);
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed manifold, chi %lld", (long long)chi);
  CHECK_NEAR(chk_volume(m), 1.0, 1e-12, "volume");
  int64_t off = 0, corners = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    double d = 1;
    for (int r2 = 0; r2 < 3; r2++) {
      if (fabs(p[r2]) < d) d = fabs(p[r2]);
      if (fabs(1 - p[r2]) < d) d = fabs(1 - p[r2]);
    }
    off += d > 1e-12;
    if (f.vclass[v] == VM_FEATURE_CORNER)
      corners += (p[0] == 0 || p[0] == 1) && (p[1] == 0 || p[1] == 1) && (p[2] == 0 || p[2] == 1);
  }
  CHECK(off == 0, "%lld vertices off the box", (long long)off);
  CHECK(f.ncorner == 8 && corners == 8 && f.nline == 12,
        "after: %lld corners (%lld exact), %d lines", (long long)f.ncorner, (long long)corners,
        f.nline);
  /* deterministic */
  vm_mesh *again = NULL;
  vm_mesh_clone(in, &again);
  vm_surface_features f2;
  CHECK(vm_surface_detect_features(again, 20, 50, &f2) == 0, "features again");
  CHECK(vm_surface_remesh_graded(again, &f2, NULL, NULL) == 0, "graded again");
  CHECK(again->nv == m->nv && again->ne == m->ne &&
            !memcmp(again->xyz, m->xyz, 3 * (size_t)m->nv * sizeof(double)) &&
            !memcmp(again->conn, m->conn, 3 * (size_t)m->ne * sizeof(int32_t)),
        "a second run differs");
  vm_surface_features_free(ctx, &f2);
  vm_mesh_destroy(&again);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

/* mean edge length of the triangles whose centroid lies in the square
 * [x0, x1] x [x0, x1] of the plate */
static double mean_edge_in(const vm_mesh *m, double x0, double x1) {
  double s = 0;
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    double n[3], c[3];
    tri_n(m, e, n, c);
    if (c[0] < x0 || c[0] > x1 || c[1] < x0 || c[1] > x1) continue;
    for (int i = 0; i < 3; i++) {
      const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e + i],
                   *b = m->xyz + 3 * (int64_t)m->conn[3 * e + (i + 1) % 3];
      s += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
      k++;
    }
  }
  return k ? s / k : 0;
}

static void test_plate(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  const int n = 14;
  double s[15];
  s[0] = 0;
  for (int i = 1; i <= n; i++) s[i] = s[i - 1] + pow(1.3, i);
  vm_mesh_set_vertices(m, (n + 1) * (n + 1));
  for (int i = 0; i <= n; i++)
    for (int j = 0; j <= n; j++) {
      double *p = m->xyz + 3 * (int64_t)(i * (n + 1) + j);
      p[0] = s[i], p[1] = s[j], p[2] = 0;
    }
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      int32_t a = i * (n + 1) + j, b = a + n + 1;
      int32_t t0[3] = {a, b, b + 1}, t1[3] = {a, b + 1, a + 1};
      vm_mesh_add_element(m, VM_TRI, t0);
      vm_mesh_add_element(m, VM_TRI, t1);
    }
  double fine0 = mean_edge_in(m, 0, s[3]), coarse0 = mean_edge_in(m, s[n - 3], s[n]);
  vm_surface_features f;
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "plate features");
  vm_graded_report r;
  CHECK(vm_surface_remesh_graded(m, &f, NULL, &r) == 0, "graded plate: %s", vm_ctx_error(ctx));
  double fine = mean_edge_in(m, 0, s[3]), coarse = mean_edge_in(m, s[n - 3], s[n]);
  fprintf(
      stderr,
      "plate: %lld -> %lld vertices; mean edge near the origin %.3g -> %.3g, far %.3g -> %.3g\n",
      (long long)r.nv_in, (long long)r.nv, fine0, fine, coarse0, coarse);
  CHECK(fine < 2 * fine0 && coarse > 0.5 * coarse0 && coarse > 10 * fine,
        "grading lost: near %.3g -> %.3g, far %.3g -> %.3g", fine0, fine, coarse0, coarse);
  CHECK(r.nv < 3 * r.nv_in, "vertices %lld -> %lld", (long long)r.nv_in, (long long)r.nv);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&m);
}

static void test_wing(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_wing(m, 40, 24, 0.12, 30) == 0, "wing");
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  int64_t over0 = 0, over = 0;
  double no0 = worst_nonortho(m, 20, &over0);
  vm_surface_features f;
  int64_t cones = 0;
  CHECK(vm_surface_detect_features_cones(m, 20, 50, 60, &f, &cones) == 0, "wing features");
  vm_graded_report r;
  CHECK(vm_surface_remesh_graded(m, &f, NULL, &r) == 0, "graded wing: %s", vm_ctx_error(ctx));
  double no = worst_nonortho(m, 20, &over);
  vm_surface_projector *p = NULL;
  CHECK(vm_surface_projector_create(ctx, in, NULL, &p) == 0, "projector");
  int64_t opposing = vm_surface_count_opposing(m, p, NULL);
  double *dist = malloc((size_t)m->nv * sizeof *dist), dmax = 0;
  CHECK(vm_surface_projector_distance(p, m->nv, m->xyz, dist) == 0, "distances");
  for (int64_t v = 0; v < m->nv; v++)
    if (dist[v] > dmax) dmax = dist[v];
  free(dist);
  vm_surface_projector_destroy(&p);
  int64_t pairs = -1;
  CHECK(vm_surface_self_intersections(m, &pairs, NULL) == 0, "self-intersections");
  double lo[3], hi[3], diag = vm_mesh_bounds(in, lo, hi);
  fprintf(stderr,
          "wing: %lld -> %lld triangles; smallest angle %.2f -> %.2f (away from corners %.2f -> "
          "%.2f); non-orthogonality %.1f -> %.1f (beyond 70: %lld -> %lld); vertices off the "
          "input <= %.3g diag; %lld opposing, %lld intersecting pairs\n",
          (long long)r.nf_in, (long long)r.nf, r.min_angle_in, r.min_angle, r.min_angle_free_in,
          r.min_angle_free, no0, no, (long long)over0, (long long)over, dmax / diag,
          (long long)opposing, (long long)pairs);
  CHECK(opposing == 0 && pairs == 0, "%lld opposing, %lld intersecting", (long long)opposing,
        (long long)pairs);
  CHECK(dmax <= 1e-9 * diag, "a vertex is %g off the input", dmax);
  CHECK(r.min_angle_free > r.min_angle_free_in, "smallest angle away from corners %.2f -> %.2f",
        r.min_angle_free_in, r.min_angle_free);
  CHECK(over < over0 && no < no0, "non-orthogonality %.1f -> %.1f, beyond 70 %lld -> %lld", no0, no,
        (long long)over0, (long long)over);
  CHECK(r.nf <= 3 * r.nf_in, "triangles %lld -> %lld", (long long)r.nf_in, (long long)r.nf);
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed manifold, chi %lld", (long long)chi);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

/* A triangle count asked for, with either sizing: met within the
 * estimate's accuracy; the curvature's sizes fine at the leading edge
 * (x small for the section at y = 0) and coarse mid-chord. */
static void test_count(vm_ctx *ctx) {
  for (int sizing = 0; sizing < 2; sizing++) {
    vm_mesh *m = NULL;
    vm_mesh_create(ctx, &m);
    CHECK(vm_gen_wing(m, 40, 24, 0.12, 0) == 0, "wing");
    vm_surface_features f;
    CHECK(vm_surface_detect_features_cones(m, 20, 50, 60, &f, NULL) == 0, "features");
    vm_graded_opts o = vm_graded_opts_default();
    o.sizing = sizing ? VM_GRADED_CURVATURE : VM_GRADED_INPUT;
    o.triangles = 3000;
    vm_graded_report r;
    CHECK(vm_surface_remesh_graded(m, &f, &o, &r) == 0, "count %d: %s", sizing, vm_ctx_error(ctx));
    fprintf(stderr, "count, sizing %d: %lld -> %lld triangles (asked 3000), sizes %.4g..%.4g\n",
            sizing, (long long)r.nf_in, (long long)r.nf, r.h_min, r.h_max);
    CHECK(r.nf > 0.6 * 3000 && r.nf < 1.6 * 3000, "sizing %d: %lld triangles for 3000", sizing,
          (long long)r.nf);
    if (sizing) {
      double lo[3], hi[3];
      vm_mesh_bounds(m, lo, hi);
      double c = hi[0] - lo[0];
      double le = 0, mid = 0;
      int64_t nle = 0, nmid = 0;
      for (int64_t e = 0; e < m->ne; e++) {
        double n[3], ctr[3];
        tri_n(m, e, n, ctr);
        double l = 0;
        for (int i = 0; i < 3; i++) {
          const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e + i],
                       *b = m->xyz + 3 * (int64_t)m->conn[3 * e + (i + 1) % 3];
          l += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                    (a[2] - b[2]) * (a[2] - b[2])) /
               3;
        }
        if (ctr[0] < lo[0] + 0.02 * c) le += l, nle++;
        if (fabs(ctr[0] - lo[0] - 0.5 * c) < 0.1 * c) mid += l, nmid++;
      }
      CHECK(nle > 0 && nmid > 0 && le / nle < 0.5 * mid / nmid,
            "curvature sizes: leading edge %.4g, mid-chord %.4g", nle ? le / nle : 0,
            nmid ? mid / nmid : 0);
    }
    vm_surface_features_free(ctx, &f);
    vm_mesh_destroy(&m);
  }
}

static void test_bad(vm_ctx *ctx) {
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
  CHECK(vm_surface_remesh_graded(m, &f, NULL, NULL) == VM_ERR_ARG &&
            strstr(vm_ctx_error(ctx), "not manifold"),
        "a non-manifold vertex is refused: %s", vm_ctx_error(ctx));
  CHECK(m->nv == 7 && m->ne == 8 && !memcmp(m->xyz, x, sizeof x), "and the mesh is left as it was");
  f.nv = 6;
  CHECK(vm_surface_remesh_graded(m, &f, NULL, NULL) == VM_ERR_ARG, "features of another mesh");
  free(f.vclass);
  free(f.vline);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  CHECK(vm_ctx_create(&ctx) == 0, "context");
  test_box(ctx);
  test_plate(ctx);
  test_wing(ctx);
  test_count(ctx);
  test_bad(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("graded");
}
