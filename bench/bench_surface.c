/* bench/bench_surface.c: the surface stage on a real model (default
 * ../shared/data/plane.stl): repair, uniform remeshing, curvature and
 * curvature-adapted node movement; prints time, vertices, Hausdorff
 * distance to the input (% of the bounding box diagonal), minimum angle,
 * flipped triangles and the Spearman correlation between local edge
 * length and |H|, and checks them against the targets with --check.
 * The pipeline is vm-surface's with --remesh yes (--no-remesh: its default
 * on a model without slivers); --eval OUT measures a file vm-surface wrote.
 * usage: bench_surface [--check] [--no-remesh] [--iter N] [--threads N]
 *                      [--eval OUT] [STL] */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "varmesh/adapt.h"
#include "varmesh/cleanup.h"
#include "varmesh/curvature.h"
#include "varmesh/features.h"
#include "varmesh/io.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"
#include "varmesh/surface_mesh.h"

typedef struct {
  double v;
  int64_t i;
} keyed;

static int cmp_keyed(const void *a, const void *b) {
  double x = ((const keyed *)a)->v, y = ((const keyed *)b)->v;
  if (x != y) return x < y ? -1 : 1;
  int64_t i = ((const keyed *)a)->i, j = ((const keyed *)b)->i;
  return i < j ? -1 : i > j;
}

/* Ranks with ties averaged. */
static void ranks(const double *x, int64_t n, double *r) {
  keyed *a = malloc(sizeof *a * (size_t)n);
  for (int64_t i = 0; i < n; i++) a[i].v = x[i], a[i].i = i;
  qsort(a, (size_t)n, sizeof *a, cmp_keyed);
  for (int64_t i = 0; i < n;) {
    int64_t j = i;
    while (j + 1 < n && a[j + 1].v == a[i].v) j++;
    for (int64_t k = i; k <= j; k++) r[a[k].i] = 0.5 * (double)(i + j);
    i = j + 1;
  }
  free(a);
}

static double spearman(const double *x, const double *y, int64_t n) {
  double *rx = malloc(sizeof *rx * (size_t)n), *ry = malloc(sizeof *ry * (size_t)n);
  ranks(x, n, rx);
  ranks(y, n, ry);
  double mx = 0, my = 0, sxy = 0, sxx = 0, syy = 0;
  for (int64_t i = 0; i < n; i++) mx += rx[i], my += ry[i];
  mx /= (double)n;
  my /= (double)n;
  for (int64_t i = 0; i < n; i++) {
    sxy += (rx[i] - mx) * (ry[i] - my);
    sxx += (rx[i] - mx) * (rx[i] - mx);
    syy += (ry[i] - my) * (ry[i] - my);
  }
  free(rx);
  free(ry);
  return sxy / sqrt(sxx * syy);
}

/* Mean length of the edges at each vertex (triangle meshes). */
static void local_edge_length(const vm_mesh *m, double *L) {
  int *cnt = calloc((size_t)m->nv, sizeof *cnt);
  memset(L, 0, sizeof *L * (size_t)m->nv);
  for (int64_t e = 0; e < m->ne; e++)
    for (int a = 0; a < 3; a++) {
      int32_t p = m->conn[3 * e + a], q = m->conn[3 * e + (a + 1) % 3];
      double d = 0;
      for (int r = 0; r < 3; r++)
        d += (m->xyz[3 * p + r] - m->xyz[3 * q + r]) * (m->xyz[3 * p + r] - m->xyz[3 * q + r]);
      d = sqrt(d);
      /* each interior edge is seen twice, once from each side: fine for a mean */
      L[p] += d, L[q] += d;
      cnt[p]++, cnt[q]++;
    }
  for (int64_t v = 0; v < m->nv; v++) L[v] /= cnt[v] ? cnt[v] : 1;
  free(cnt);
}

static double bbox_diagonal(const vm_mesh *m) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, s = 0;
  for (int64_t v = 0; v < m->nv; v++)
    for (int r = 0; r < 3; r++) {
      lo[r] = fmin(lo[r], m->xyz[3 * v + r]);
      hi[r] = fmax(hi[r], m->xyz[3 * v + r]);
    }
  for (int r = 0; r < 3; r++) s += (hi[r] - lo[r]) * (hi[r] - lo[r]);
  return sqrt(s);
}

static void tri_normal(const vm_mesh *m, int64_t e, double n[3], double ctr[3]) {
  const double *a = m->xyz + 3 * m->conn[3 * e], *b = m->xyz + 3 * m->conn[3 * e + 1],
               *c = m->xyz + 3 * m->conn[3 * e + 2];
  double u[3], v[3];
  for (int r = 0; r < 3; r++) {
    u[r] = b[r] - a[r];
    v[r] = c[r] - a[r];
    ctr[r] = (a[r] + b[r] + c[r]) / 3;
  }
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
}

/* Triangles whose orientation reversed between a and b (same connectivity). */
static int64_t count_reversed(const vm_mesh *a, const vm_mesh *b) {
  int64_t k = 0;
  for (int64_t e = 0; e < a->ne; e++) {
    double na[3], nb[3], c[3];
    tri_normal(a, e, na, c);
    tri_normal(b, e, nb, c);
    k += na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2] <= 0;
  }
  return k;
}

static double cpu_seconds(void) { return (double)clock() / CLOCKS_PER_SEC; }

typedef struct {
  double spearman_raw, spearman_metric, hausdorff, min_angle;
  double spearman_input_unsmoothed, spearman_own, spearman_own_smoothed;
  int64_t opposing;
} figures;

/* Figures of mesh m against the input surface: Spearman of local edge
 * length vs |H| of the input (smoothed twice, evaluated at m's vertices)
 * and vs the metric's filtered |H|; symmetric Hausdorff distance. */
static figures measure(const vm_mesh *m, const vm_mesh *input, vm_surface_projector *pin,
                       const double *Hin, const double *Hin0, vm_surface_projector *pstart,
                       const double *Hmetric, double spacing) {
  figures f;
  double *L = malloc(sizeof *L * (size_t)m->nv), *H = malloc(sizeof *H * (size_t)m->nv);
  local_edge_length(m, L);
  vm_surface_projector_interpolate(pin, Hin, m->nv, m->xyz, H);
  for (int64_t v = 0; v < m->nv; v++) H[v] = fabs(H[v]);
  f.spearman_raw = spearman(L, H, m->nv);
  /* sensitivity to the |H| used: the input's without smoothing, and m's
   * own (the cotangent H of m, noisier on a graded mesh), raw and smoothed */
  vm_surface_projector_interpolate(pin, Hin0, m->nv, m->xyz, H);
  for (int64_t v = 0; v < m->nv; v++) H[v] = fabs(H[v]);
  f.spearman_input_unsmoothed = spearman(L, H, m->nv);
  vm_surface_mean_curvature(m, H, NULL, NULL, NULL);
  for (int64_t v = 0; v < m->nv; v++) H[v] = fabs(H[v]);
  f.spearman_own = spearman(L, H, m->nv);
  vm_curvature_filter sm = {0, 0, 2};
  vm_surface_mean_curvature(m, H, NULL, NULL, NULL);
  vm_curvature_filter_apply(m, &sm, H);
  for (int64_t v = 0; v < m->nv; v++) H[v] = fabs(H[v]);
  f.spearman_own_smoothed = spearman(L, H, m->nv);
  f.spearman_metric = NAN;
  if (pstart) {
    vm_surface_projector_interpolate(pstart, Hmetric, m->nv, m->xyz, H);
    for (int64_t v = 0; v < m->nv; v++) H[v] = fabs(H[v]);
    f.spearman_metric = spearman(L, H, m->nv);
  }
  double ab = 0, ba = 0;
  vm_surface_hausdorff(m, input, spacing, &ab, &ba);
  f.hausdorff = fmax(ab, ba);
  f.min_angle = vm_surface_min_angle(m);
  f.opposing = vm_surface_count_opposing(m, pin, NULL);
  free(L);
  free(H);
  return f;
}

int main(int argc, char **argv) {
  const char *path = NULL, *eval = NULL;
  int check = 0, remesh = 1, iter = 200, threads = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--check"))
      check = 1;
    else if (!strcmp(argv[i], "--no-remesh"))
      remesh = 0;
    else if (!strcmp(argv[i], "--iter") && i + 1 < argc)
      iter = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
      threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--eval") && i + 1 < argc)
      eval = argv[++i];
    else
      path = argv[i];
  }
  char buf[4096];
  if (!path) {
    const char *root = getenv("VM_SOURCE_ROOT");
    snprintf(buf, sizeof buf, "%s/../shared/data/plane.stl", root ? root : ".");
    path = buf;
  }
  vm_ctx *ctx = NULL;
  vm_mesh *m = NULL, *input = NULL, *start = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, threads);
  double t0 = omp_get_wtime(), c0 = cpu_seconds();
  if (vm_mesh_read(ctx, path, VM_FMT_AUTO, &m) < 0) {
    fprintf(stderr, "bench_surface: %s\n", vm_ctx_error(ctx));
    return 1;
  }
  vm_repair_report rr;
  if (vm_surface_repair(m, NULL, &rr) < 0) {
    fprintf(stderr, "bench_surface: %s\n", vm_ctx_error(ctx));
    return 1;
  }
  double t_repair = omp_get_wtime() - t0;
  vm_mesh_clone(m, &input);
  const double diag = bbox_diagonal(input), spacing = diag / 2000;
  vm_adapt_opts ao = vm_adapt_opts_default();
  ao.max_iter = iter;
  printf("surface stage on %s: %lld vertices, %lld triangles, bounding box diagonal %.4f, "
         "minimum angle %.2f deg\n",
         path, (long long)input->nv, (long long)input->ne, diag, vm_surface_min_angle(input));
  printf("  repair: %.2f s (%lld reoriented, %lld degenerate, closed: %s, self-intersections "
         "%lld)\n",
         t_repair, (long long)rr.reoriented, (long long)rr.removed_degenerate,
         rr.border_edges ? "no" : "yes", (long long)rr.self_intersections);

  /* the input surface: features, projector, its smoothed |H| */
  vm_surface_features fin;
  vm_surface_projector *pin = NULL, *pstart = NULL;
  vm_surface_detect_features(input, ao.feature_angle, ao.corner_angle, &fin);
  vm_surface_projector_create(ctx, input, &fin, &pin);
  double *Hin = malloc(sizeof *Hin * (size_t)input->nv);
  double *Hin0 = malloc(sizeof *Hin0 * (size_t)input->nv);
  vm_surface_mean_curvature(input, Hin, NULL, NULL, NULL);
  memcpy(Hin0, Hin, sizeof *Hin0 * (size_t)input->nv);
  vm_curvature_filter sm = {0, 0, 2};
  vm_curvature_filter_apply(input, &sm, Hin);

  if (eval) {
    /* a result of vm-surface against the (repaired) input */
    vm_mesh *r = NULL;
    int64_t counts[VM_NTYPES];
    if (vm_mesh_read(ctx, eval, VM_FMT_AUTO, &r) < 0 || vm_mesh_count_types(r, counts) != 2 ||
        counts[VM_TRI] != r->ne) {
      fprintf(stderr, "bench_surface: %s: %s\n", eval,
              r ? "not a triangle mesh" : vm_ctx_error(ctx));
      return 1;
    }
    figures fe = measure(r, input, pin, Hin, Hin0, NULL, NULL, spacing);
    printf("  %s: %lld vertices, %lld triangles\n", eval, (long long)r->nv, (long long)r->ne);
    printf("  Spearman(edge length, |H|) %.4f; Hausdorff %.4g = %.4f%% of the diagonal; minimum "
           "angle %.2f deg; triangles opposing the input's normal %lld\n",
           fe.spearman_raw, fe.hausdorff, 100 * fe.hausdorff / diag, fe.min_angle,
           (long long)fe.opposing);
    printf("  Spearman vs the input's unsmoothed |H| %.4f, vs the mesh's own |H| %.4f, smoothed "
           "twice %.4f\n",
           fe.spearman_input_unsmoothed, fe.spearman_own, fe.spearman_own_smoothed);
    /* corners and tips of the input (feature corners, cone points): how
     * far the nearest vertex of the result is, relative to the mean
     * length of the input's edges there */
    {
      vm_surface_features fc;
      int64_t ncone = 0;
      vm_surface_detect_features_cones(input, ao.feature_angle, ao.corner_angle, ao.cone_angle, &fc,
                                       &ncone);
      vm_surf_edges E;
      vm_surf_edges_build(ctx, input, &E);
      double worst = 0, worst_rel = 0;
      int64_t moved = 0;
      for (int64_t v = 0; v < input->nv; v++) {
        if (fc.vclass[v] != VM_FEATURE_CORNER) continue;
        const double *p = input->xyz + 3 * v;
        double best = INFINITY;
        for (int64_t w = 0; w < r->nv; w++) {
          const double *q = r->xyz + 3 * w;
          double d = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                          (p[2] - q[2]) * (p[2] - q[2]));
          if (d < best) best = d;
        }
        double len = 0;
        int64_t nl = E.rowptr[v + 1] - E.rowptr[v];
        for (int64_t j = E.rowptr[v]; j < E.rowptr[v + 1]; j++) {
          const double *q = input->xyz + 3 * (int64_t)E.adj[j];
          len += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                      (p[2] - q[2]) * (p[2] - q[2]));
        }
        double rel = nl && len > 0 ? best / (len / nl) : 0;
        if (best > 0) moved++;
        if (best > worst) worst = best;
        if (rel > worst_rel) worst_rel = rel;
      }
      printf("  corners and tips of the input: %lld (%lld cone points), %lld without a vertex of "
             "the result on them; farthest %.4g = %.3f of the local edge length\n",
             (long long)fc.ncorner, (long long)ncone, (long long)moved, worst, worst_rel);
      vm_surface_features_free(ctx, &fc);
      vm_surf_edges_free(ctx, &E);
    }
    int ok = fe.spearman_raw <= -0.5 && fe.hausdorff <= 1e-3 * diag && fe.opposing == 0 &&
             fe.min_angle >= 15;
    printf("  targets: %s\n", ok ? "all met" : "NOT all met");
    vm_mesh_destroy(&r);
    free(Hin);
    free(Hin0);
    vm_surface_projector_destroy(&pin);
    vm_surface_features_free(ctx, &fin);
    vm_mesh_destroy(&m);
    vm_mesh_destroy(&input);
    vm_ctx_destroy(&ctx);
    return check && !ok ? 1 : 0;
  }

  double t_remesh = 0, h_target = vm_surface_mean_edge(input);
  if (remesh) {
    double t1 = omp_get_wtime();
    vm_surface_features f;
    vm_surface_detect_features(m, ao.feature_angle, ao.corner_angle, &f);
    vm_remesh_opts ro = vm_remesh_opts_default();
    ro.target_edge_length = h_target;
    if (vm_surface_remesh(m, &f, &ro, ao.corner_angle) < 0) {
      fprintf(stderr, "bench_surface: %s\n", vm_ctx_error(ctx));
      return 1;
    }
    vm_surface_features_free(ctx, &f);
    t_remesh = omp_get_wtime() - t1;
  }
  vm_mesh_clone(m, &start);
  /* the metric's field: filtered H of the starting mesh, as vm_surface_adapt does */
  double *Hmetric = malloc(sizeof *Hmetric * (size_t)start->nv);
  vm_surface_mean_curvature(start, Hmetric, NULL, NULL, NULL);
  double hs = vm_surface_mean_edge(start);
  vm_curvature_filter filt = {-ao.filter.threshold / diag, -ao.filter.cap / hs, ao.filter.smooth};
  vm_curvature_filter_apply(start, &filt, Hmetric);
  vm_surface_projector_create(ctx, start, NULL, &pstart);
  figures f0 = measure(start, input, pin, Hin, Hin0, pstart, Hmetric, spacing);
  if (remesh)
    printf("  remesh (uniform, target %.4f = the input's mean edge length): %.2f s, %lld "
           "vertices\n",
           h_target, t_remesh, (long long)start->nv);

  vm_adapt_result ar;
  double t2 = omp_get_wtime(), c2 = cpu_seconds();
  int st = vm_surface_adapt(m, pin, &ao, &ar);
  double t_adapt = omp_get_wtime() - t2;
  double cpu_total = cpu_seconds() - c0, cpu_adapt = cpu_seconds() - c2;
  if (st < 0) {
    fprintf(stderr, "bench_surface: adapt: %s\n", vm_ctx_error(ctx));
    return 1;
  }
  figures f1 = measure(m, input, pin, Hin, Hin0, pstart, Hmetric, spacing);
  printf("  adapt: %.2f s (CPU %.2f s), %d iterations (%s), c %.4f, threshold %.4f, cap %.3f; "
         "%lld smooth, %lld feature-line, %lld fixed vertices\n",
         t_adapt, cpu_adapt, ar.iterations, ar.stop, ar.c, ar.threshold, ar.cap,
         (long long)ar.nsmooth, (long long)ar.nline_vertices, (long long)ar.nfixed);
  printf("\n  %-28s %12s %12s\n", "", remesh ? "remeshed" : "input", "adapted");
  printf("  %-28s %12lld %12lld\n", "vertices", (long long)start->nv, (long long)m->nv);
  printf("  %-28s %12.4f %12.4f\n", "Spearman(edge length, |H|)", f0.spearman_raw, f1.spearman_raw);
  printf("  %-28s %12.4f %12.4f\n", "  ... vs the metric's |H|", f0.spearman_metric,
         f1.spearman_metric);
  printf("  %-28s %12.4f %12.4f\n", "  ... input's, unsmoothed", f0.spearman_input_unsmoothed,
         f1.spearman_input_unsmoothed);
  printf("  %-28s %12.4f %12.4f\n", "  ... the mesh's own |H|", f0.spearman_own, f1.spearman_own);
  printf("  %-28s %12.4f %12.4f\n", "  ... own, smoothed twice", f0.spearman_own_smoothed,
         f1.spearman_own_smoothed);
  printf("  %-28s %11.4f%% %11.4f%%\n", "Hausdorff / diagonal", 100 * f0.hausdorff / diag,
         100 * f1.hausdorff / diag);
  printf("  %-28s %12.2f %12.2f\n", "minimum angle (deg)", f0.min_angle, f1.min_angle);
  printf("  %-28s %12s %12lld\n", "flipped (vm_surface_adapt)", "-", (long long)ar.flipped);
  int64_t reversed = count_reversed(start, m);
  printf("  %-28s %12s %12lld\n", "reversed by the adaptation", "-", (long long)reversed);
  printf("  %-28s %12lld %12lld\n", "opposing the input normal", (long long)f0.opposing,
         (long long)f1.opposing);
  printf("  %-28s %12s %12.2f\n", "wall time (s)", "", t_repair + t_remesh + t_adapt);
  printf("  %-28s %12s %12.2f\n", "CPU time (s)", "", cpu_total);
  int flips = reversed || ar.flipped || f1.opposing > f0.opposing;
  int ok = f1.spearman_raw <= -0.5 && f1.hausdorff <= 1e-3 * diag && !flips && f1.min_angle >= 15;
  printf("\n  targets: Spearman <= -0.5: %s; Hausdorff <= 0.1%%: %s; no flips: %s; min angle "
         ">= 15: %s\n",
         f1.spearman_raw <= -0.5 ? "yes" : "NO", f1.hausdorff <= 1e-3 * diag ? "yes" : "NO",
         !flips ? "yes" : "NO", f1.min_angle >= 15 ? "yes" : "NO");
  free(Hin);
  free(Hin0);
  free(Hmetric);
  vm_surface_projector_destroy(&pin);
  vm_surface_projector_destroy(&pstart);
  vm_surface_features_free(ctx, &fin);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&input);
  vm_mesh_destroy(&start);
  vm_ctx_destroy(&ctx);
  return check && !ok ? 1 : 0;
}
