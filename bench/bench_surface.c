/* bench/bench_surface.c: the surface stage on a real model (default
 * ../shared/data/plane.stl): repair, uniform remeshing, curvature and
 * curvature-adapted node movement; prints time, vertices, Hausdorff
 * distance to the input (% of the bounding box diagonal), minimum angle,
 * flipped triangles and the Spearman correlation between local edge
 * length and |H|, and checks them against the targets with --check.
 * usage: bench_surface [--check] [--no-remesh] [--iter N] [--threads N] [STL] */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/adapt.h"
#include "varmesh/curvature.h"
#include "varmesh/features.h"
#include "varmesh/io.h"
#include "varmesh/repair.h"
#include "varmesh/surface_io.h"

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
      for (int r = 0; r < 3; r++) d += (m->xyz[3 * p + r] - m->xyz[3 * q + r]) * (m->xyz[3 * p + r] - m->xyz[3 * q + r]);
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

static double mean_edge(const vm_mesh *m) {
  double *L = malloc(sizeof *L * (size_t)m->nv), s = 0;
  local_edge_length(m, L);
  for (int64_t v = 0; v < m->nv; v++) s += L[v];
  free(L);
  return s / (double)m->nv;
}

typedef struct {
  double spearman_raw, spearman_metric, hausdorff, min_angle;
} figures;

/* Figures of mesh m against the input surface: Spearman of local edge
 * length vs |H| of the input (smoothed twice, evaluated at m's vertices)
 * and vs the metric's filtered |H|; symmetric Hausdorff distance. */
static figures measure(const vm_mesh *m, const vm_mesh *input, vm_surface_projector *pin,
                       const double *Hin, vm_surface_projector *pstart, const double *Hmetric,
                       double spacing) {
  figures f;
  double *L = malloc(sizeof *L * (size_t)m->nv), *H = malloc(sizeof *H * (size_t)m->nv);
  local_edge_length(m, L);
  vm_surface_projector_interpolate(pin, Hin, m->nv, m->xyz, H);
  for (int64_t v = 0; v < m->nv; v++) H[v] = fabs(H[v]);
  f.spearman_raw = spearman(L, H, m->nv);
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
  free(L);
  free(H);
  return f;
}

int main(int argc, char **argv) {
  const char *path = NULL;
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
  vm_surface_register_formats(ctx);
  double t0 = omp_get_wtime();
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
  printf("surface stage on %s: %lld vertices, %lld triangles, bounding box diagonal %.4f\n",
         path, (long long)input->nv, (long long)input->ne, diag);
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
  vm_surface_mean_curvature(input, Hin, NULL, NULL, NULL);
  vm_curvature_filter sm = {0, 0, 2};
  vm_curvature_filter_apply(input, &sm, Hin);

  double t_remesh = 0, h_target = mean_edge(input);
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
  double hs = mean_edge(start);
  vm_curvature_filter filt = {-ao.filter.threshold / diag, -ao.filter.cap / hs, ao.filter.smooth};
  vm_curvature_filter_apply(start, &filt, Hmetric);
  vm_surface_projector_create(ctx, start, NULL, &pstart);
  figures f0 = measure(start, input, pin, Hin, pstart, Hmetric, spacing);
  if (remesh)
    printf("  remesh (uniform, target %.4f = the input's mean edge length): %.2f s, %lld "
           "vertices\n",
           h_target, t_remesh, (long long)start->nv);

  vm_adapt_result ar;
  double t2 = omp_get_wtime();
  int st = vm_surface_adapt(m, pin, &ao, &ar);
  double t_adapt = omp_get_wtime() - t2;
  if (st < 0) {
    fprintf(stderr, "bench_surface: adapt: %s\n", vm_ctx_error(ctx));
    return 1;
  }
  figures f1 = measure(m, input, pin, Hin, pstart, Hmetric, spacing);
  printf("  adapt: %.2f s, %d iterations (%s), c %.4f, threshold %.4f, cap %.3f; %lld smooth, "
         "%lld feature-line, %lld fixed vertices\n",
         t_adapt, ar.iterations, ar.stop, ar.c, ar.threshold, ar.cap, (long long)ar.nsmooth,
         (long long)ar.nline_vertices, (long long)ar.nfixed);
  printf("\n  %-28s %12s %12s\n", "", remesh ? "remeshed" : "input", "adapted");
  printf("  %-28s %12lld %12lld\n", "vertices", (long long)start->nv, (long long)m->nv);
  printf("  %-28s %12.4f %12.4f\n", "Spearman(edge length, |H|)", f0.spearman_raw,
         f1.spearman_raw);
  printf("  %-28s %12.4f %12.4f\n", "  ... vs the metric's |H|", f0.spearman_metric,
         f1.spearman_metric);
  printf("  %-28s %11.4f%% %11.4f%%\n", "Hausdorff / diagonal", 100 * f0.hausdorff / diag,
         100 * f1.hausdorff / diag);
  printf("  %-28s %12.2f %12.2f\n", "minimum angle (deg)", f0.min_angle, f1.min_angle);
  printf("  %-28s %12s %12lld\n", "flipped triangles", "-", (long long)ar.flipped);
  printf("  %-28s %12s %12.2f\n", "time (s)", "", t_repair + t_remesh + t_adapt);
  int ok = f1.spearman_raw <= -0.5 && f1.hausdorff <= 1e-3 * diag && ar.flipped == 0 &&
           f1.min_angle >= 15;
  printf("\n  targets: Spearman <= -0.5: %s; Hausdorff <= 0.1%%: %s; no flips: %s; min angle "
         ">= 15: %s\n",
         f1.spearman_raw <= -0.5 ? "yes" : "NO", f1.hausdorff <= 1e-3 * diag ? "yes" : "NO",
         ar.flipped == 0 ? "yes" : "NO", f1.min_angle >= 15 ? "yes" : "NO");
  free(Hin);
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
