/* bench/bench_prism.c: the prism stage on plane.stl, the generated
 * aircraft, two spheres with a narrow gap and two 0.06 apart (a squeeze) at T = 5% and 20% of
 * the model's length, 20 layers:
 * per case prisms, time, columns at full thickness, achieved/requested thickness, the room the
 * geometry leaves (columns whose exterior medial radius is at least 1.05 T, the share of those at
 * full thickness, the fill of the allowed thickness), inverted prisms, minimum scaled Jacobian,
 * deviation from the wall normal, intersecting pairs (Embree and, independently, CGAL's exact
 * check), the growth ratios and OpenFOAM's figures (faces beyond 70 degrees, the largest
 * non-orthogonality and skewness, cells below checkMesh's determinant limit, short columns
 * ended). usage: bench_prism [--data DIR] [--layers N] [--growth R]
 * [--res N]
 *                    [--only plane|aircraft|spheres] [--frac F] [--verbose]
 * VM_BENCH_DUMP=FILE writes "x y z thickness/T" per wall vertex of each case
 * (the last case run wins). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "varmesh/aircraft.h"
#include "varmesh/io.h"
#include "varmesh/prism.h"
#include "varmesh/quadrature.h"
#include "varmesh/shapes.h"
#include "varmesh/verify.h"

static void progress(void *user, const vm_prism_progress *pg) {
  (void)user;
  fprintf(stderr, "  [%6.2f s] %-10s %4d %s %.6g  %lld\n", pg->elapsed,
          vm_prism_phase_name(pg->phase), pg->step, pg->solver ? "F" : " ", pg->value,
          (long long)pg->count);
}

/* Warnings (a marching stopped early, ...) on stderr, so a "(warn)" row
 * says why. */
static void log_warn(void *user, int level, const char *msg) {
  (void)user;
  if (level <= VM_LOG_WARN) fprintf(stderr, "  warning: %s\n", msg);
}

static double model_length(const vm_mesh *m) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int64_t v = 0; v < m->nv; v++)
    for (int k = 0; k < 3; k++) {
      lo[k] = fmin(lo[k], m->xyz[3 * v + k]);
      hi[k] = fmax(hi[k], m->xyz[3 * v + k]);
    }
  return fmax(fmax(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]);
}

/* Where the worst prisms are: the 8 lowest corner qualities with their
 * layer, column, column thickness / T and the layer's height there. */
static void worst_prisms(const vm_mesh *res, const vm_prism_report *r) {
  const vm_qrule *R = vm_qrule_get(VM_PRISM, VM_RULE_CORNER);
  int64_t nw = r->wall_vertices, nt = r->wall_triangles;
  enum { NW = 8 };
  double wq[NW];
  int64_t we[NW];
  int nwq = 0;
  int64_t below[3] = {0, 0, 0};
  for (int64_t e = 0; e < res->ne; e++) {
    if (res->etype[e] != VM_PRISM) continue;
    const int32_t *c = res->conn + res->eoff[e];
    double q = INFINITY;
    for (int j = 0; j < R->nnodes; j++) {
      double u[3][3];
      for (int k = 0; k < 3; k++)
        for (int d = 0; d < 3; d++)
          u[k][d] = res->xyz[3 * (int64_t)c[R->nodes[j].head[k]] + d] -
                    res->xyz[3 * (int64_t)c[R->nodes[j].tail[k]] + d];
      double det = u[0][0] * (u[1][1] * u[2][2] - u[1][2] * u[2][1]) -
                   u[0][1] * (u[1][0] * u[2][2] - u[1][2] * u[2][0]) +
                   u[0][2] * (u[1][0] * u[2][1] - u[1][1] * u[2][0]);
      double l = 1;
      for (int k = 0; k < 3; k++)
        l *= sqrt(u[k][0] * u[k][0] + u[k][1] * u[k][1] + u[k][2] * u[k][2]);
      q = fmin(q, det / l / (sqrt(3.0) / 2));
    }
    below[0] += q < 0.01;
    below[1] += q < 0.05;
    below[2] += q < 0.1;
    int pos = nwq < NW ? nwq++ : NW;
    if (pos == NW && !(q < wq[NW - 1])) continue;
    if (pos == NW) pos = NW - 1;
    while (pos > 0 && wq[pos - 1] > q) {
      wq[pos] = wq[pos - 1];
      we[pos] = we[pos - 1];
      pos--;
    }
    wq[pos] = q;
    we[pos] = e;
  }
  fprintf(stderr, "  prisms with scaled Jacobian < 0.01: %lld, < 0.05: %lld, < 0.1: %lld\n",
          (long long)below[0], (long long)below[1], (long long)below[2]);
  const vm_field *th = vm_mesh_find_field(res, VM_PRISM_FIELD_THICKNESS, VM_FIELD_VERTEX);
  for (int i = 0; i < nwq; i++) {
    const int32_t *c = res->conn + res->eoff[we[i]];
    int64_t v = c[0] % nw;
    const double *x = res->xyz + 3 * v;
    double h = 0;
    for (int d = 0; d < 3; d++)
      h += pow(res->xyz[3 * (int64_t)c[3] + d] - res->xyz[3 * (int64_t)c[0] + d], 2);
    fprintf(stderr,
            "  sj %.3g layer %lld column %lld at (%.3f %.3f %.3f): thickness/T %.3f, h %.3g\n",
            wq[i], (long long)(we[i] / nt), (long long)v, x[0], x[1], x[2],
            th ? ((const double *)th->data)[v] / r->thickness : -1, sqrt(h));
  }
}

static int run_case(vm_ctx *ctx, const char *name, const vm_mesh *w, double frac, int layers,
                    double growth, int verbose) {
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = frac * model_length(w);
  o.nlayers = layers;
  o.growth = growth;
  if (verbose) {
    o.progress = progress;
  }
  struct timespec c0, c1;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
  vm_prism_report r;
  vm_mesh *res = NULL;
  int st = vm_prism_run(ctx, w, &o, &res, &r);
  if (st < 0 && r.wall_triangles == 0) {
    fprintf(stderr, "%s: %s\n", name, vm_ctx_error(ctx));
    return 1;
  }
  if (st < 0) fprintf(stderr, "%s: run: %s\n", name, vm_ctx_error(ctx));
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
  double cpu = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
  int64_t emb = -1, cg_pairs = -1, cg_wall = -1, cg_bad = -1;
  if (res) {
    const char *dump = getenv("VM_BENCH_DUMP");
    const vm_field *thf = vm_mesh_find_field(res, VM_PRISM_FIELD_THICKNESS, VM_FIELD_VERTEX);
    FILE *df = dump && thf ? fopen(dump, "w") : NULL;
    if (df) {
      for (int64_t v = 0; v < r.wall_vertices; v++)
        fprintf(df, "%.6f %.6f %.6f %.6f\n", res->xyz[3 * v], res->xyz[3 * v + 1],
                res->xyz[3 * v + 2], ((const double *)thf->data)[v] / r.thickness);
      fclose(df);
    }
    uint8_t *wall = calloc((size_t)res->nv, 1);
    for (int64_t v = 0; v < r.wall_vertices; v++) wall[v] = 1;
    vm_prism_mesh_intersections(ctx, res, wall, &emb);
    free(wall);
    vm_verify_prism_layer(res, &cg_pairs, &cg_wall, NULL);
    vm_verify_orientation(res, VM_RULE_CORNER, &cg_bad, NULL, NULL);
  }
  printf("| %-14s | %4.0f%% | %7lld | %6.1f / %6.1f | %5.1f%% | %5.1f%% / %6.2f%% (%lld) / %.3f "
         "(%.3f) | %.3f / %.3f / %.3f | %lld / %lld | %lld | "
         "%.3f | %5.2f / %5.2f (%lld > 5) / %5.2f / %5.2f "
         "| %lld / %lld+%lld | %.3f / %.3f / %.2f%% | %lld / %.1f / %.2f / %lld (%lld) | %d%s |\n",
         name, 100 * frac, (long long)r.prisms, r.time_total, cpu, 100 * r.full_fraction,
         100 * r.medial_room, 100 * r.medial_reach, (long long)r.medial_short, r.medial_fill,
         r.medial_fill_rest, r.thick_min, r.thick_mean, r.thick_max, (long long)r.inverted,
         (long long)cg_bad, (long long)r.split_negative, r.sj_min, r.normal_dev_max,
         r.normal_dev_p99, (long long)r.normal_dev_over5, r.normal_dev_all_max,
         r.normal_dev_all_p99, (long long)emb, (long long)cg_pairs, (long long)cg_wall,
         r.growth_max, r.growth_p99, 100 * r.growth_band_share, (long long)r.nonortho_over70,
         r.nonortho_max, r.skew_max, (long long)r.det_small, (long long)r.short_ended, r.layers,
         st ? " (warn)" : "");
  fflush(stdout);
  if (verbose) {
    fprintf(stderr, "  phases:");
    for (int k = 0; k < VM_PRISM_NPHASES; k++)
      fprintf(stderr, " %s %.2f s", vm_prism_phase_name((vm_prism_phase)k), r.time[k]);
    fprintf(stderr, "; implicit iterations %d, cut rounds %d (%lld pairs first)\n",
            r.springback_iter, r.cut_rounds, (long long)r.cut_pairs_first);
  }
  if (verbose && res) worst_prisms(res, &r);
  vm_mesh_destroy(&res);
  return 0;
}

int main(int argc, char **argv) {
  const char *data = NULL, *only = NULL;
  int layers = 20, res = 4, verbose = 0;
  double growth = 1.2, fracs[2] = {0.05, 0.20};
  int nfrac = 2;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--data") && i + 1 < argc)
      data = argv[++i];
    else if (!strcmp(argv[i], "--layers") && i + 1 < argc)
      layers = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--growth") && i + 1 < argc)
      growth = atof(argv[++i]);
    else if (!strcmp(argv[i], "--res") && i + 1 < argc)
      res = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--only") && i + 1 < argc)
      only = argv[++i];
    else if (!strcmp(argv[i], "--frac") && i + 1 < argc) {
      fracs[0] = atof(argv[++i]);
      nfrac = 1;
    } else if (!strcmp(argv[i], "--verbose"))
      verbose = 1;
    else {
      fprintf(stderr, "usage: bench_prism [--data DIR] [--layers N] [--growth R] [--res N] "
                      "[--only plane|aircraft|spheres] [--frac F] [--verbose]\n");
      return 2;
    }
  }
  char path[4096];
  if (data)
    snprintf(path, sizeof path, "%s/plane.stl", data);
  else if (getenv("VM_SOURCE_ROOT"))
    snprintf(path, sizeof path, "%s/../shared/data/plane.stl", getenv("VM_SOURCE_ROOT"));
  else
    snprintf(path, sizeof path, "../shared/data/plane.stl");
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_log(ctx, log_warn, NULL);
  printf("| case | T/L | prisms | time s (wall / CPU) | full | room for T / of those at T (short) "
         "/ fill (where no room) | thick/T min / mean / max | inverted "
         "(own / CGAL) | 3-tet split negative "
         "| min SJ | first layer off the normal, deg: smooth max / p99 (> 5°) / all max / p99 "
         "| intersecting pairs (Embree / CGAL outer+wall) | growth: max / p99 / columns within "
         "[1/1.5, 1.5] x | OpenFOAM: faces > 70° / max non-orth. / max skewness / cells "
         "det < 0.001 (short columns ended) | layers |\n");
  printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  if (!only || !strcmp(only, "plane")) {
    vm_mesh *m = NULL;
    if (vm_mesh_read(ctx, path, VM_FMT_AUTO, &m)) {
      fprintf(stderr, "plane: %s (skipped)\n", vm_ctx_error(ctx));
    } else {
      for (int f = 0; f < nfrac; f++)
        run_case(ctx, "plane.stl", m, fracs[f], layers, growth, verbose);
      vm_mesh_destroy(&m);
    }
  }
  if (!only || !strcmp(only, "aircraft")) {
    vm_aircraft_opts ao = vm_aircraft_opts_default();
    ao.resolution = res;
    vm_mesh *m = NULL;
    if (vm_gen_aircraft(ctx, &ao, &m)) {
      fprintf(stderr, "aircraft: %s\n", vm_ctx_error(ctx));
    } else {
      for (int f = 0; f < nfrac; f++)
        run_case(ctx, "aircraft", m, fracs[f], layers, growth, verbose);
      vm_mesh_destroy(&m);
    }
  }
  if (!only || !strcmp(only, "spheres")) {
    /* a narrow gap: two unit spheres 0.6 apart (length 4.6): room for T
     * everywhere at 5 %, a contact at 20 % */
    vm_mesh *m = NULL;
    const double ca[3] = {-1.3, 0, 0}, cb[3] = {1.3, 0, 0};
    if (vm_mesh_create(ctx, &m) || vm_gen_icosphere(m, ca, 1.0, 4, 0, NULL) ||
        vm_gen_icosphere(m, cb, 1.0, 4, 0, NULL)) {
      fprintf(stderr, "spheres: %s\n", vm_ctx_error(ctx));
    } else {
      for (int f = 0; f < nfrac; f++)
        run_case(ctx, "two spheres", m, fracs[f], layers, growth, verbose);
    }
    vm_mesh_destroy(&m);
    /* a squeeze: the same spheres 0.06 apart (length 4.06), the layers
     * meeting in the gap at either thickness (test prism_short's shape) */
    const double sa[3] = {-1.03, 0, 0}, sb[3] = {1.03, 0, 0};
    if (vm_mesh_create(ctx, &m) || vm_gen_icosphere(m, sa, 1.0, 4, 0, NULL) ||
        vm_gen_icosphere(m, sb, 1.0, 4, 0, NULL)) {
      fprintf(stderr, "spheres: %s\n", vm_ctx_error(ctx));
    } else {
      for (int f = 0; f < nfrac; f++)
        run_case(ctx, "spheres 0.06", m, fracs[f], layers, growth, verbose);
    }
    vm_mesh_destroy(&m);
  }
  vm_ctx_destroy(&ctx);
  return 0;
}
