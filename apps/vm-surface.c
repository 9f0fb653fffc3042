/* apps/vm-surface.c: the surface stage: repair an imported surface,
 * remesh it uniformly when it needs it, compute its mean curvature and
 * adapt the mesh to it with the 2D functional (20); or any step alone. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "cli_report.h"
#include "varmesh/adapt.h"
#include "varmesh/curvature.h"
#include "varmesh/features.h"
#include "varmesh/io.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"

static const char usage[] =
    "usage: vm-surface [STEP] [options] IN OUT\n"
    "The surface stage. STEP is one of\n"
    "  all        (default) repair -> remesh (if needed) -> curvature -> adapt\n"
    "  repair     repair only\n"
    "  remesh     repair -> isotropic remeshing\n"
    "  curvature  mean curvature fields only\n"
    "  adapt      curvature -> curvature-adapted node movement (no remeshing)\n"
    "OUT is written in the format of its extension (.vmsh keeps the curvature fields\n"
    "'mean_curvature' and 'mean_curvature_filtered').\n"
    "  --repair auto|yes|no    repair the input (auto: for .stl .obj .off .ply inputs,\n"
    "                          and always for the steps all, repair and remesh)\n"
    "  --open-ok               accept an open surface (borders become feature lines)\n"
    "  --no-intersection-check skip the self-intersection check of the repair\n"
    "  --remesh auto|yes|no    uniform remeshing in 'all' (auto: if the smallest angle\n"
    "                          is below --sliver-angle)\n"
    "  --sliver-angle DEG      (default 15)\n"
    "  --target-edge-length L  remeshing edge length (default: the mean edge length)\n"
    "  --remesh-iter N         remeshing iterations (default 5)\n"
    "  --feature-angle DEG     dihedral angle of a sharp edge (default 20)\n"
    "  --corner-angle DEG      turning angle of a feature line at a corner (default 50)\n"
    "  --c C                   metric G = (1 + C|H|) I, C a length (default 4 h, h the\n"
    "                          mean edge length); --c-rel K sets C = K h\n"
    "  --threshold T           |H| < T -> 0 (default 4/D, D the bounding box diagonal)\n"
    "  --cap X                 |H| > X -> X (default 1/h)\n"
    "  --smooth N              smoothing passes of the curvature (default 2)\n"
    "  --iter N                adaptation iterations in all (default 200)\n"
    "  --rounds N              metric / normal updates during adaptation (default 5)\n"
    "  --theta T               balanced measure weight (default 0.8)\n"
    "  --implicit              implicit minimizer instead of the explicit one\n"
    "  --time-limit S          seconds for the adaptation\n"
    "  --threads N             OpenMP threads (results do not depend on it)\n"
    "  --format F, --binary    output format; binary where the format has both\n"
    "  --progress-every N      a progress line every N iterations (default 20)\n"
    "  --report DIR            write DIR/index.html with pictures: convergence of the\n"
    "                          adaptation (F per iteration), quality histograms, the\n"
    "                          surface coloured by its (filtered) mean curvature\n"
    "  --json                  JSON summary on stdout\n"
    "  -q, --quiet             no progress\n"
    "  --help, --version\n"
    "exit: 0 done; 1 bad input (what is wrong and where is printed) or I/O; 2 usage;\n"
    "3 the adapted mesh has flipped elements; 4 interrupted (last iterate written)\n";

typedef struct {
  vm_cli *cli;
  int every;
  vm_report_history *hist; /* --report: every iteration */
} progress_state;

static void progress(void *user, const vm_adapt_progress *p) {
  progress_state *ps = user;
  if (ps->hist) {
    char phase[32];
    snprintf(phase, sizeof phase, "round %d", p->round);
    vm_report_history_add(ps->hist, phase, p->total_iter, p->F, 0, NAN);
  }
  if (ps->cli->quiet || (p->iter % ps->every && p->iter != 1)) return;
  fprintf(stderr, "vm-surface: adapt round %d it %5d  F %.8e  |grad| %.3e  tau %.2e  %7.2fs\n",
          p->round, p->iter, p->F, p->grad_norm, p->tau, p->elapsed);
}

static int pick(const char *v, const char *const *names, int n) {
  for (int i = 0; v && i < n; i++)
    if (!strcmp(v, names[i])) return i;
  return -1;
}

enum { STEP_ALL, STEP_REPAIR, STEP_REMESH, STEP_CURVATURE, STEP_ADAPT };
enum { TRI_AUTO, TRI_YES, TRI_NO };

static double wall_seconds(void) {
  struct timespec ts;
  timespec_get(&ts, TIME_UTC);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* A border edge (an element side no other element shares) of a surface
 * mesh: 1 and its vertices, 0 if the surface is closed, -1 out of memory. */
static int border_edge(const vm_mesh *m, int32_t *a, int32_t *b) {
  size_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) n += (size_t)vm_elem_nverts(m->etype[e]);
  uint64_t *key = malloc((n ? n : 1) * sizeof *key);
  if (!key) return -1;
  n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int k = vm_elem_nverts(m->etype[e]);
    const int32_t *c = m->conn + m->eoff[e];
    for (int i = 0; i < k; i++) {
      uint32_t p = (uint32_t)c[i], q = (uint32_t)c[(i + 1) % k];
      key[n++] = (uint64_t)(p < q ? p : q) << 32 | (p < q ? q : p);
    }
  }
  qsort(key, n, sizeof *key, cmp_u64);
  int found = 0;
  for (size_t i = 0; i < n && !found;) {
    size_t j = i;
    while (j + 1 < n && key[j + 1] == key[i]) j++;
    if (j == i) {
      *a = (int32_t)(key[i] >> 32);
      *b = (int32_t)(key[i] & 0xffffffffu);
      found = 1;
    }
    i = j + 1;
  }
  free(key);
  return found;
}

int main(int argc, char **argv) {
  double t0 = wall_seconds();
  vm_cli cli;
  vm_cli_init(&cli, "vm-surface");
  static const char *const steps[] = {"all", "repair", "remesh", "curvature", "adapt"};
  static const char *const tri[] = {"auto", "yes", "no"};
  vm_adapt_opts ao = vm_adapt_opts_default();
  vm_repair_opts ro = vm_repair_opts_default();
  vm_remesh_opts mo = vm_remesh_opts_default();
  vm_write_opts wo = vm_write_opts_default();
  const char *in = NULL, *out = NULL, *report_dir = NULL;
  vm_report *report = NULL;
  vm_report_history *hist = NULL;
  int step = STEP_ALL, repair = TRI_AUTO, remesh = TRI_AUTO, json = 0, fout = VM_FMT_AUTO;
  double sliver = 15, c_abs = -1, thr = -1, cap = -1;
  long every = 20, lv;
  int rc = VM_EXIT_OK, st = VM_OK;
  vm_mesh *m = NULL, *input = NULL;
  vm_surface_features fin;
  memset(&fin, 0, sizeof fin);
  vm_surface_projector *ref = NULL;
  int argi = 1;
  if (argc > 1 && pick(argv[1], steps, 5) >= 0) step = pick(argv[argi++], steps, 5);
  for (int i = argi; i < argc; i++) {
    const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
    int k;
    double x;
    if (vm_cli_info_option(&cli, a, usage)) {
      goto done;
    } else if (!strcmp(a, "--json")) {
      json = 1;
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      cli.quiet = 1;
    } else if (!strcmp(a, "--open-ok")) {
      ro.require_closed = 0;
    } else if (!strcmp(a, "--no-intersection-check")) {
      ro.check_self_intersections = 0;
    } else if (!strcmp(a, "--implicit")) {
      ao.implicit = 1;
    } else if (!strcmp(a, "--binary")) {
      wo.binary = 1;
    } else if (!strcmp(a, "--repair") || !strcmp(a, "--remesh")) {
      i++;
      if ((k = pick(val, tri, 3)) < 0) {
        rc = vm_cli_usage_error(&cli, "%s expects auto, yes or no", a);
        goto done;
      }
      if (!strcmp(a, "--repair"))
        repair = k;
      else
        remesh = k;
    } else if (!strcmp(a, "--sliver-angle") || !strcmp(a, "--feature-angle") ||
               !strcmp(a, "--corner-angle") || !strcmp(a, "--theta") ||
               !strcmp(a, "--target-edge-length") || !strcmp(a, "--c") ||
               !strcmp(a, "--c-rel") || !strcmp(a, "--threshold") || !strcmp(a, "--cap") ||
               !strcmp(a, "--time-limit")) {
      i++;
      int angle = strstr(a, "angle") && strcmp(a, "--target-edge-length");
      double lo = angle ? 1e-6 : 0, hi = angle ? 180 : !strcmp(a, "--theta") ? 1 : 1e300;
      if (vm_cli_double(&cli, a, val, lo, hi, &x)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      if (!strcmp(a, "--sliver-angle"))
        sliver = x;
      else if (!strcmp(a, "--feature-angle"))
        ao.feature_angle = x;
      else if (!strcmp(a, "--corner-angle"))
        ao.corner_angle = x;
      else if (!strcmp(a, "--theta"))
        ao.theta = x;
      else if (!strcmp(a, "--target-edge-length")) {
        if (!(x > 0)) {
          rc = vm_cli_usage_error(&cli, "--target-edge-length must be positive");
          goto done;
        }
        mo.target_edge_length = x;
      } else if (!strcmp(a, "--c"))
        c_abs = x;
      else if (!strcmp(a, "--c-rel"))
        ao.c = -x;
      else if (!strcmp(a, "--threshold"))
        thr = x;
      else if (!strcmp(a, "--cap"))
        cap = x;
      else
        ao.time_limit = x;
    } else if (!strcmp(a, "--iter") || !strcmp(a, "--rounds") || !strcmp(a, "--smooth") ||
               !strcmp(a, "--remesh-iter") || !strcmp(a, "--threads") ||
               !strcmp(a, "--progress-every")) {
      i++;
      long lo = !strcmp(a, "--rounds") || !strcmp(a, "--remesh-iter") ||
                        !strcmp(a, "--progress-every")
                    ? 1
                    : 0;
      if (vm_cli_int(&cli, a, val, lo, 100000000, &lv)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      if (!strcmp(a, "--iter"))
        ao.max_iter = (int)lv;
      else if (!strcmp(a, "--rounds"))
        ao.rounds = (int)lv;
      else if (!strcmp(a, "--smooth"))
        ao.filter.smooth = (int)lv;
      else if (!strcmp(a, "--remesh-iter"))
        mo.iterations = (int)lv;
      else if (!strcmp(a, "--threads"))
        vm_ctx_set_threads(cli.ctx, (int)lv);
      else
        every = lv;
    } else if (!strcmp(a, "--report")) {
      i++;
      if (!(report_dir = val)) {
        rc = vm_cli_usage_error(&cli, "--report expects a directory");
        goto done;
      }
    } else if (!strcmp(a, "--format")) {
      i++;
      if ((rc = vm_cli_format(&cli, val, &fout)) != VM_EXIT_OK) goto done;
    } else if ((rc = vm_cli_operand(&cli, a, (const char **const[]){&in, &out}, 2)) != VM_EXIT_OK) {
      goto done;
    }
  }
  if (!in || !out) {
    rc = vm_cli_usage_error(&cli, "need IN and OUT");
    goto done;
  }
  if (c_abs >= 0) ao.c = c_abs;
  if (thr >= 0) ao.filter.threshold = thr;
  if (cap >= 0) ao.filter.cap = cap;
  if (fout == VM_FMT_AUTO && vm_format_from_path(out) == VM_FMT_AUTO)
    fout = vm_format_from_path(in);

  /* the report is made (or refused) before the run */
  if (report_dir) {
    char title[512];
    snprintf(title, sizeof title, "vm-surface %s: %s", steps[step], in);
    if ((rc = vm_cli_report_open(&cli, report_dir, title, &report, &hist)) != VM_EXIT_OK)
      goto done;
  }
  if (vm_mesh_read(cli.ctx, in, VM_FMT_AUTO, &m) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 2 || m->dim != 3) {
    vm_cli_error(&cli, "%s: not a surface mesh in 3D (it needs triangles or quads and "
                 "nothing else)", in);
    rc = VM_EXIT_INPUT;
    goto done;
  }
  vm_mesh_apply_fixed_field(m);
  int fin_fmt = vm_format_from_path(in);
  int soup = fin_fmt == VM_FMT_STL || fin_fmt == VM_FMT_OBJ || fin_fmt == VM_FMT_OFF ||
             fin_fmt == VM_FMT_PLY;
  int do_repair = repair == TRI_YES ||
                  (repair == TRI_AUTO && (soup || step == STEP_ALL || step == STEP_REPAIR ||
                                          step == STEP_REMESH));
  if (step == STEP_REPAIR) do_repair = 1;
  if (!cli.quiet)
    fprintf(stderr, "vm-surface: %s: %lld vertices, %lld faces\n", in, (long long)m->nv,
            (long long)m->ne);

  vm_repair_report rr;
  memset(&rr, 0, sizeof rr);
  rr.self_intersections = -1;
  if (do_repair) {
    st = vm_surface_repair(m, &ro, &rr);
    if (st < 0) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
    if (!cli.quiet)
      fprintf(stderr,
              "vm-surface: repair: %lld vertices, %lld triangles; merged %lld points, removed "
              "%lld invalid/duplicate and %lld degenerate faces and %lld isolated vertices, "
              "reoriented %lld faces, stitched %lld edges; %s, %lld components%s\n",
              (long long)rr.nv, (long long)rr.nf, (long long)rr.merged_vertices,
              (long long)rr.removed_polygons, (long long)rr.removed_degenerate,
              (long long)rr.removed_isolated, (long long)rr.reoriented, (long long)rr.stitched,
              rr.border_edges ? "open" : "closed", (long long)rr.components,
              rr.self_intersections > 0 ? ", SELF-INTERSECTING" : "");
  }

  double min_angle_in = vm_surface_min_angle(m), h_in = vm_surface_mean_edge(m);
  int did_remesh = 0;
  int64_t nv_before_remesh = m->nv;
  if (step == STEP_REMESH || (step == STEP_ALL && (remesh == TRI_YES ||
                                                    (remesh == TRI_AUTO && min_angle_in < sliver)))) {
    if (mo.target_edge_length <= 0) mo.target_edge_length = h_in;
    vm_surface_features f;
    memset(&f, 0, sizeof f);
    st = vm_mesh_clone(m, &input);
    if (!st) st = vm_surface_detect_features(m, ao.feature_angle, ao.corner_angle, &f);
    if (!st) st = vm_surface_remesh(m, &f, &mo, ao.corner_angle);
    vm_surface_features_free(cli.ctx, &f);
    if (st < 0) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
    did_remesh = 1;
    if (!cli.quiet)
      fprintf(stderr, "vm-surface: remesh: target edge length %g: %lld -> %lld vertices, "
              "smallest angle %.2f -> %.2f deg\n", mo.target_edge_length,
              (long long)nv_before_remesh, (long long)m->nv, min_angle_in,
              vm_surface_min_angle(m));
  }

  vm_curvature_stats cs;
  memset(&cs, 0, sizeof cs);
  vm_adapt_result ar;
  memset(&ar, 0, sizeof ar);
  int adapted = 0;
  if (step == STEP_CURVATURE) {
    double lo[3], hi[3], h = vm_surface_mean_edge(m), diag = vm_mesh_bounds(m, lo, hi);
    vm_curvature_filter f = ao.filter;
    if (f.threshold < 0) f.threshold = -f.threshold / diag;
    if (f.cap < 0) f.cap = h > 0 ? -f.cap / h : 0;
    ar.threshold = f.threshold;
    ar.cap = f.cap;
    st = vm_surface_curvature(m, &f, &cs);
    if (st < 0) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
    if (!cli.quiet)
      fprintf(stderr, "vm-surface: curvature: H in [%g, %g], mean |H| %g; filter: threshold "
              "%g, cap %g, %d smoothing passes\n", cs.min, cs.max, cs.mean_abs, f.threshold,
              f.cap, f.smooth);
  } else if (step == STEP_ALL || step == STEP_ADAPT) {
    /* the reference surface: the (repaired) input, before any remeshing */
    const vm_mesh *refm = input ? input : m;
    /* without the repair nothing has checked that the surface is closed */
    int32_t ba, bb;
    int open = do_repair || !ro.require_closed ? 0 : border_edge(refm, &ba, &bb);
    if (open < 0) {
      vm_cli_error(&cli, "out of memory");
      rc = VM_EXIT_INPUT;
      goto done;
    }
    if (open) {
      const double *p = refm->xyz + 3 * (int64_t)ba, *q = refm->xyz + 3 * (int64_t)bb;
      vm_cli_error(&cli, "%s: open surface: e.g. the border edge (%g, %g, %g)-(%g, %g, %g) "
                   "(--open-ok accepts it)", in, p[0], p[1], p[2], q[0], q[1], q[2]);
      rc = VM_EXIT_INPUT;
      goto done;
    }
    st = vm_surface_detect_features(refm, ao.feature_angle, ao.corner_angle, &fin);
    if (!st) st = vm_surface_projector_create(cli.ctx, refm, &fin, &ref);
    if (st < 0) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
    progress_state ps = {&cli, (int)every, hist};
    ao.monitor = progress;
    ao.user = &ps;
    vm_cli_catch_interrupts(&cli);
    st = vm_surface_adapt(m, ref, &ao, &ar);
    if (st < 0 && st != VM_ERR_INTERRUPTED) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
    adapted = 1;
    if (st == VM_ERR_INTERRUPTED) rc = VM_EXIT_INTERRUPTED;
    if (ar.flipped > 0) rc = VM_EXIT_CHECK;
    if (!cli.quiet)
      fprintf(stderr,
              "vm-surface: adapt: %d iterations in %d rounds (%s), F %.8e -> %.8e; c %g, "
              "threshold %g, cap %g; %lld smooth, %lld feature-line vertices on %d lines, %lld "
              "fixed; smallest angle %.2f -> %.2f deg; %lld flipped; %.2f s%s\n",
              ar.iterations, ar.rounds, ar.stop, ar.F_initial, ar.F, ar.c, ar.threshold,
              ar.cap, (long long)ar.nsmooth, (long long)ar.nline_vertices, ar.nline,
              (long long)ar.nfixed, ar.min_angle_before, ar.min_angle_after,
              (long long)ar.flipped, ar.elapsed, rc == VM_EXIT_CHECK ? "  -- FLIPPED ELEMENTS" : "");
  }

  int wst = vm_mesh_write(cli.ctx, m, out, fout, &wo);
  if (wst < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  if (!cli.quiet)
    fprintf(stderr, "vm-surface: wrote %s: %lld vertices, %lld faces, smallest angle %.2f deg; "
            "%.2f s\n", out, (long long)m->nv, (long long)m->ne, vm_surface_min_angle(m),
            wall_seconds() - t0);
  if (json) {
    printf("{\"input\": ");
    vm_json_string(stdout, in);
    printf(", \"output\": ");
    vm_json_string(stdout, out);
    printf(", \"step\": \"%s\", \"exit\": %d, \"vertices\": %lld, \"faces\": %lld",
           steps[step], rc, (long long)m->nv, (long long)m->ne);
    if (do_repair)
      printf(", \"repair\": {\"vertices\": %lld, \"faces\": %lld, \"merged_vertices\": %lld, "
             "\"removed_faces\": %lld, \"removed_degenerate\": %lld, \"removed_isolated\": %lld, "
             "\"reoriented\": %lld, \"stitched\": %lld, \"border_edges\": %lld, \"holes\": %lld, "
             "\"components\": %lld, \"self_intersections\": %lld, \"volume\": ",
             (long long)rr.nv, (long long)rr.nf, (long long)rr.merged_vertices,
             (long long)rr.removed_polygons, (long long)rr.removed_degenerate,
             (long long)rr.removed_isolated, (long long)rr.reoriented, (long long)rr.stitched,
             (long long)rr.border_edges, (long long)rr.holes, (long long)rr.components,
             (long long)rr.self_intersections);
    if (do_repair) {
      vm_json_double(stdout, rr.volume);
      printf("}");
    }
    printf(", \"remeshed\": %s", did_remesh ? "true" : "false");
    if (did_remesh) {
      printf(", \"target_edge_length\": ");
      vm_json_double(stdout, mo.target_edge_length);
    }
    if (step == STEP_CURVATURE) {
      printf(", \"curvature\": {\"min\": ");
      vm_json_double(stdout, cs.min);
      printf(", \"max\": ");
      vm_json_double(stdout, cs.max);
      printf(", \"mean_abs\": ");
      vm_json_double(stdout, cs.mean_abs);
      printf(", \"threshold\": ");
      vm_json_double(stdout, ar.threshold);
      printf(", \"cap\": ");
      vm_json_double(stdout, ar.cap);
      printf(", \"degenerate\": %lld, \"boundary\": %lld}", (long long)cs.degenerate,
             (long long)cs.boundary);
    }
    if (adapted) {
      printf(", \"adapt\": {\"iterations\": %d, \"rounds\": %d, \"stop\": \"%s\", \"F_initial\": ",
             ar.iterations, ar.rounds, ar.stop);
      vm_json_double(stdout, ar.F_initial);
      printf(", \"F\": ");
      vm_json_double(stdout, ar.F);
      printf(", \"c\": ");
      vm_json_double(stdout, ar.c);
      printf(", \"threshold\": ");
      vm_json_double(stdout, ar.threshold);
      printf(", \"cap\": ");
      vm_json_double(stdout, ar.cap);
      printf(", \"smooth_vertices\": %lld, \"line_vertices\": %lld, \"fixed_vertices\": %lld, "
             "\"lines\": %d, \"corners\": %lld, \"flipped\": %lld, \"min_angle_before\": ",
             (long long)ar.nsmooth, (long long)ar.nline_vertices, (long long)ar.nfixed, ar.nline,
             (long long)ar.ncorner, (long long)ar.flipped);
      vm_json_double(stdout, ar.min_angle_before);
      printf(", \"min_angle_after\": ");
      vm_json_double(stdout, ar.min_angle_after);
      printf(", \"max_distance\": ");
      vm_json_double(stdout, ar.max_distance);
      printf(", \"time\": ");
      vm_json_double(stdout, ar.elapsed);
      printf("}");
    }
    printf(", \"min_angle\": ");
    vm_json_double(stdout, vm_surface_min_angle(m));
    printf(", \"time\": ");
    vm_json_double(stdout, wall_seconds() - t0);
    printf("}\n");
  }
  if (report) {
    int st2 = vm_report_heading(report, "run");
    if (st2 >= 0) st2 = vm_report_row(report, "input, output", "%s, %s", in, out);
    if (st2 >= 0)
      st2 = vm_report_row(report, "step; vertices, faces", "%s; %lld, %lld", steps[step],
                          (long long)m->nv, (long long)m->ne);
    if (st2 >= 0 && do_repair)
      st2 = vm_report_row(report, "repair",
                          "merged %lld points, removed %lld invalid/duplicate and %lld "
                          "degenerate faces, reoriented %lld, stitched %lld edges; %s, %lld "
                          "components, %lld self-intersections",
                          (long long)rr.merged_vertices, (long long)rr.removed_polygons,
                          (long long)rr.removed_degenerate, (long long)rr.reoriented,
                          (long long)rr.stitched, rr.border_edges ? "open" : "closed",
                          (long long)rr.components, (long long)rr.self_intersections);
    if (st2 >= 0 && did_remesh)
      st2 = vm_report_row(report, "remeshed", "target edge length %g, %lld -> %lld vertices",
                          mo.target_edge_length, (long long)nv_before_remesh, (long long)m->nv);
    if (st2 >= 0 && adapted)
      st2 = vm_report_row(report, "adaptation",
                          "%d iterations in %d rounds (%s), F %.6e -> %.6e; c %g; %lld flipped; "
                          "max distance to the input %g; %.2f s",
                          ar.iterations, ar.rounds, ar.stop, ar.F_initial, ar.F, ar.c,
                          (long long)ar.flipped, ar.max_distance, ar.elapsed);
    if (st2 >= 0)
      st2 = vm_report_row(report, "smallest angle: input, output", "%.2f, %.2f deg",
                          min_angle_in, vm_surface_min_angle(m));
    int rrc = vm_cli_report_result(&cli, &report, report_dir, st2, "surface", m, NULL, hist,
                                   "Convergence of the adaptation: the functional (20) F per "
                                   "iteration (the metric and normals are updated between "
                                   "rounds, so F jumps there); dashed lines separate the "
                                   "rounds.");
    if (rrc != VM_EXIT_OK && rc == VM_EXIT_OK) rc = rrc;
  }
done:
  vm_report_destroy(&report);
  vm_report_history_destroy(&hist);
  vm_surface_projector_destroy(&ref);
  vm_surface_features_free(cli.ctx, &fin);
  vm_mesh_destroy(&input);
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
