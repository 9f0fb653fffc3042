/* apps/vm-prism.c: the prism stage: a closed triangulated wall (a .vmsh
 * from vm-surface, or STL/OBJ/OFF/PLY directly) in, a thick, valid,
 * multi-layer prismatic mesh out (Section 6.2 of the paper). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "cli_report.h"
#include "cli_verify.h"
#include "varmesh/io.h"
#include "varmesh/quadrature.h"
#include "varmesh/prism.h"
#include "varmesh/io.h"

static const char usage[] =
    "usage: vm-prism [options] IN OUT\n"
    "Build a thick multi-layer prism mesh on the closed, outward-oriented triangulated\n"
    "wall IN (.vmsh, .stl, .obj, .off, .ply, ...): thin layer, elastic springback,\n"
    "cutting of self-intersections (Embree), thickness restoration with smoothing,\n"
    "marching split into layers. OUT by extension: .vmsh .msh (Gmsh 4.1) .vtu .vtk\n"
    ".cgns .su2 (wall and outer boundary as separate families / markers).\n"
    "  -T, --thickness X      total thickness, absolute\n"
    "  -t, --thickness-rel F  total thickness as a fraction of the model's length\n"
    "                         (largest bounding-box extent; default 0.05)\n"
    "  -n, --layers N         number of layers (default 20)\n"
    "  --first-height H       height of the first layer (absolute)\n"
    "  --growth R             ratio of successive layer heights (default 1.2; with\n"
    "                         --first-height alone the ratio is solved for)\n"
    "  --springback-iter N    implicit iterations of the springback (default 100; up\n"
    "                         to 3N while the line search keeps cutting the step)\n"
    "  --resolve-iter N       implicit iterations after each cutting round (default 6)\n"
    "  --cut-rounds N         cutting rounds at most (default 400)\n"
    "  --cut-factor F         target height reduction per cut (default 0.85)\n"
    "  --smooth-iter N        restoration / smoothing passes (default 30)\n"
    "  --march-iter N         explicit iterations per split (default 8)\n"
    "  --ortho-weight W       weight of the inner sublayer when splitting (default 10)\n"
    "  --drop-quality Q       drop the outermost layer if its minimum scaled Jacobian\n"
    "                         is below Q (default 0: keep)\n"
    "  --time-limit S         seconds for the whole run\n"
    "  --threads N            OpenMP threads (results do not depend on it)\n"
    "  --format F             output format (vmsh, msh, vtu, vtk, cgns, su2)\n"
    "  --binary               binary output where the format has both\n"
    "  --report DIR           write DIR/index.html with pictures: convergence (F per\n"
    "                         solver iteration, pairs per cutting round), quality\n"
    "                         histograms, slices through the layers, the surface\n"
    "                         coloured by the achieved thickness\n"
    "  --json                 JSON summary on stdout\n"
    "  -q, --quiet            no progress on stderr\n"
    "  --help, --version\n"
    "exit: 0 valid layers; 1 bad input or I/O; 2 usage; 3 inverted prisms or\n"
    "intersections remain (the mesh is still written); 4 interrupted\n";

typedef struct {
  vm_cli *cli;
  int last_phase;
  vm_report_history *hist; /* --report: every solver iteration and cutting round */
  int total;               /* samples so far (the history's x axis) */
  double F;                /* the last functional, carried through cutting rounds */
  const char *in;          /* the run's first line, once the wall is accepted */
  const vm_mesh *m;
  double L;
  const vm_prism_opts *o;
} progress_state;

/* The run's first line, before its first progress (or error) line: the
 * wall was accepted. */
static void announce(progress_state *ps) {
  if (!ps->in) return;
  if (!ps->cli->quiet)
    fprintf(stderr, "vm-prism: %s: %lld wall triangles, model length %g, thickness %g, %d layers\n",
            ps->in, (long long)ps->m->ne, ps->L, ps->o->thickness, ps->o->nlayers);
  ps->in = NULL;
}

static void progress(void *user, const vm_prism_progress *p) {
  progress_state *ps = user;
  announce(ps);
  if (ps->hist) {
    /* M: intersecting pairs while cutting (the barrier keeps every prism
     * valid, so 0 elsewhere) */
    if (p->solver) ps->F = p->value;
    if (p->solver || p->phase == VM_PRISM_PHASE_CUT)
      vm_report_history_add(ps->hist, vm_prism_phase_name(p->phase), ++ps->total, ps->F,
                            p->phase == VM_PRISM_PHASE_CUT && !p->solver ? (int64_t)p->value : 0,
                            NAN);
  }
  if (ps->cli->quiet) return;
  /* a solve's iterations every 10th; the phases' own steps (cutting
   * rounds, marching's layers) each, the others every 10th */
  static const char *const what[] = {"height", "F", "pairs", "mean t/T", "height"};
  int first = (int)p->phase != ps->last_phase;
  if (p->solver) {
    if (first || p->step % 10 == 0) {
      fprintf(stderr, "%-10s %5d  %-8s %.6g  ", vm_prism_phase_name(p->phase), p->step, "F",
              p->value);
      if (p->count >= 0) fprintf(stderr, "inverted %lld  ", (long long)p->count);
      fprintf(stderr, "%7.2fs\n", p->elapsed);
    }
  } else if (first || p->phase == VM_PRISM_PHASE_CUT || p->phase == VM_PRISM_PHASE_MARCH ||
             p->step % 10 == 0) {
    fprintf(stderr, "%-10s %5d  %-8s %.6g  %7.2fs\n", vm_prism_phase_name(p->phase), p->step,
            what[p->phase], p->value, p->elapsed);
  }
  ps->last_phase = (int)p->phase;
}

typedef enum { OUT_MESH, OUT_CGNS, OUT_SU2 } out_kind;

static int ends_with(const char *s, const char *suf) {
  size_t a = strlen(s), b = strlen(suf);
  return a >= b && !strcasecmp(s + a - b, suf);
}

/* Copy the vertex fields of the wall mesh w onto the prism mesh r, whose
 * vertex k*nw + l is level k of the column on the l-th wall vertex used by
 * a triangle or quad of w (in w's order, as vm_prism_create numbers them):
 * the column takes its wall vertex's value; a 'fixed' field only on the
 * wall itself. Fields the prism stage writes itself win. */
static int pass_wall_fields(const vm_mesh *w, vm_mesh *r, int64_t nw) {
  if (nw <= 0 || r->nv % nw) return VM_OK;
  int64_t nlev = r->nv / nw, n = 0;
  int32_t *src = vm_alloc_array(w->ctx, (size_t)nw, sizeof *src);
  uint8_t *used = vm_calloc(w->ctx, (size_t)w->nv + 1, 1);
  int st = (!src || !used) ? VM_ERR_NOMEM : VM_OK;
  for (int64_t e = 0; st == VM_OK && e < w->ne; e++)
    if (w->etype[e] == VM_TRI || w->etype[e] == VM_QUAD)
      for (int64_t k = w->eoff[e]; k < w->eoff[e + 1]; k++) used[w->conn[k]] = 1;
  for (int64_t v = 0; st == VM_OK && v < w->nv; v++)
    if (used[v]) {
      if (n == nw) break;
      src[n++] = (int32_t)v;
    }
  if (n != nw) st = VM_OK; /* not the numbering expected: pass nothing */
  for (int i = 0; st == VM_OK && n == nw && i < w->nfield; i++) {
    const vm_field *f = &w->fields[i];
    if (f->location != VM_FIELD_VERTEX || vm_mesh_find_field(r, f->name, VM_FIELD_VERTEX))
      continue;
    vm_field *g;
    if ((st = vm_mesh_add_field(r, f->name, VM_FIELD_VERTEX, f->type, f->ncomp, &g)) < 0) break;
    size_t sz = f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t), row = sz * f->ncomp;
    int64_t levels = strcmp(f->name, "fixed") ? nlev : 1;
    for (int64_t k = 0; k < levels; k++)
      for (int64_t l = 0; l < nw; l++)
        memcpy((char *)g->data + (size_t)(k * nw + l) * row,
               (const char *)f->data + (size_t)src[l] * row, row);
  }
  vm_free(w->ctx, src);
  vm_free(w->ctx, used);
  return st;
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-prism");
  vm_prism_opts o = vm_prism_opts_default();
  vm_write_opts wo = vm_write_opts_default();
  const char *in = NULL, *out = NULL, *fmt = NULL, *report_dir = NULL;
  double T_abs = 0, T_rel = 0.05;
  int json = 0, rc = VM_EXIT_OK;
  vm_mesh *m = NULL, *res = NULL;
  vm_report *report = NULL;
  vm_report_history *hist = NULL;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
    double x;
    long lv;
    if (vm_cli_info_option(&cli, a, usage)) {
      goto done;
    } else if (!strcmp(a, "--json")) {
      json = 1;
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      cli.quiet = 1;
    } else if (!strcmp(a, "--binary")) {
      wo.binary = 1;
    } else if (!strcmp(a, "--report")) {
      i++;
      if (!(report_dir = val)) {
        rc = vm_cli_usage_error(&cli, "--report expects a directory");
        goto done;
      }
    } else if (!strcmp(a, "--format")) {
      i++;
      if (!(fmt = val)) {
        rc = vm_cli_usage_error(&cli, "--format expects a format name");
        goto done;
      }
    } else if (!strcmp(a, "-T") || !strcmp(a, "--thickness") || !strcmp(a, "-t") ||
               !strcmp(a, "--thickness-rel") || !strcmp(a, "--first-height") ||
               !strcmp(a, "--growth") || !strcmp(a, "--cut-factor") ||
               !strcmp(a, "--ortho-weight") || !strcmp(a, "--drop-quality") ||
               !strcmp(a, "--time-limit")) {
      i++;
      double lo = 1e-300, hi = 1e300;
      if (!strcmp(a, "-t") || !strcmp(a, "--thickness-rel")) hi = 10;
      if (!strcmp(a, "--growth")) lo = 1, hi = 10;
      if (!strcmp(a, "--cut-factor")) lo = 0.5, hi = 0.999;
      if (!strcmp(a, "--ortho-weight")) lo = 1;
      if (!strcmp(a, "--drop-quality")) lo = 0, hi = 0.999;
      if (vm_cli_double(&cli, a, val, lo, hi, &x)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      if (!strcmp(a, "-T") || !strcmp(a, "--thickness")) T_abs = x;
      else if (!strcmp(a, "-t") || !strcmp(a, "--thickness-rel")) T_rel = x, T_abs = 0;
      else if (!strcmp(a, "--first-height")) o.first_height = x;
      else if (!strcmp(a, "--growth")) o.growth = x;
      else if (!strcmp(a, "--cut-factor")) o.cut_factor = x;
      else if (!strcmp(a, "--ortho-weight")) o.ortho_weight = x;
      else if (!strcmp(a, "--drop-quality")) o.drop_quality = x;
      else o.time_limit = x;
    } else if (!strcmp(a, "-n") || !strcmp(a, "--layers") || !strcmp(a, "--springback-iter") ||
               !strcmp(a, "--resolve-iter") || !strcmp(a, "--cut-rounds") ||
               !strcmp(a, "--smooth-iter") || !strcmp(a, "--march-iter") ||
               !strcmp(a, "--threads")) {
      i++;
      int layers = !strcmp(a, "-n") || !strcmp(a, "--layers");
      if (vm_cli_int(&cli, a, val, layers ? 1 : 0, layers ? 1000 : 100000000, &lv)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      if (layers) o.nlayers = (int)lv;
      else if (!strcmp(a, "--springback-iter")) o.springback_iter = (int)lv;
      else if (!strcmp(a, "--resolve-iter")) o.resolve_iter = (int)lv;
      else if (!strcmp(a, "--cut-rounds")) o.max_cut_rounds = (int)lv;
      else if (!strcmp(a, "--smooth-iter")) o.smooth_iter = (int)lv;
      else if (!strcmp(a, "--march-iter")) o.march_iter = (int)lv;
      else vm_ctx_set_threads(cli.ctx, (int)lv);
    } else if ((rc = vm_cli_operand(&cli, a, (const char **const[]){&in, &out}, 2)) != VM_EXIT_OK) {
      goto done;
    }
  }
  if (!in || !out) {
    rc = vm_cli_usage_error(&cli, "need IN and OUT");
    goto done;
  }
  out_kind kind = OUT_MESH;
  int fout = VM_FMT_AUTO;
  if (fmt ? !strcmp(fmt, "cgns") : ends_with(out, ".cgns")) {
    kind = OUT_CGNS;
  } else if (fmt ? !strcmp(fmt, "su2") : ends_with(out, ".su2")) {
    kind = OUT_SU2;
  } else {
    fout = fmt ? vm_format_from_name(fmt) : vm_format_from_path(out);
    if (fout == VM_FMT_AUTO) {
      rc = vm_cli_usage_error(&cli, "cannot tell the output format of '%s' (use --format)", out);
      goto done;
    }
  }
  if (kind == OUT_CGNS && !vm_have_cgns()) {
    vm_cli_error(&cli, "this build has no CGNS support (libcgns)");
    rc = VM_EXIT_USAGE;
    goto done;
  }
  if (vm_mesh_read(cli.ctx, in, VM_FMT_AUTO, &m) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI && m->etype[e] != VM_QUAD) continue;
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++)
      for (int c = 0; c < 3; c++) {
        double v = m->xyz[3 * (int64_t)m->conn[k] + c];
        lo[c] = fmin(lo[c], v);
        hi[c] = fmax(hi[c], v);
      }
  }
  double L = fmax(fmax(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]);
  if (!(L > 0)) {
    vm_cli_error(&cli, "%s: no triangles (or all in one point)", in);
    rc = VM_EXIT_INPUT;
    goto done;
  }
  o.thickness = T_abs > 0 ? T_abs : T_rel * L;
  if (o.first_height > 0 && !(o.first_height < o.thickness)) {
    rc = vm_cli_usage_error(&cli, "--first-height %g is not below the thickness %g",
                            o.first_height, o.thickness);
    goto done;
  }
  /* the report is made (or refused) before the run */
  if (report_dir) {
    char title[512];
    snprintf(title, sizeof title, "vm-prism: %s", in);
    if ((rc = vm_cli_report_open(&cli, report_dir, title, &report, &hist)) != VM_EXIT_OK)
      goto done;
  }
  progress_state ps = {&cli, -1, hist, 0, NAN, in, m, L, &o};
  o.progress = progress;
  o.user = &ps;
  /* the prism tests check every incremental intersection query */
  const char *chk = getenv("VM_PRISM_CHECK_INCREMENTAL");
  o.check_incremental = chk && *chk && strcmp(chk, "0");
  vm_cli_catch_interrupts(&cli);
  vm_prism_report r;
  int st = vm_prism_run(cli.ctx, m, &o, &res, &r);
  if (st < 0 && st != VM_ERR_INTERRUPTED) {
    /* no wall triangles counted: the wall or the options were refused */
    if (r.wall_triangles == 0) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
    } else {
      announce(&ps);
      vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    }
    rc = VM_EXIT_INPUT;
    goto done;
  }
  announce(&ps);
  /* nothing is lost: the wall's vertex fields (the surface stage's
   * curvature, ...) go up every column */
  if (pass_wall_fields(m, res, r.wall_vertices) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  /* the final check, on the mesh that is written */
  int64_t npairs = 0;
  {
    uint8_t *wall = vm_calloc(cli.ctx, (size_t)res->nv, 1);
    if (!wall) {
      vm_cli_error(&cli, "out of memory");
      rc = VM_EXIT_INPUT;
      goto done;
    }
    for (int64_t v = 0; v < r.wall_vertices; v++) wall[v] = 1;
    int s2 = vm_prism_mesh_intersections(cli.ctx, res, wall, &npairs);
    vm_free(cli.ctx, wall);
    if (s2 < 0) {
      vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
  }
  int wst = kind == OUT_CGNS  ? vm_mesh_write(cli.ctx, res, out, VM_FMT_CGNS, NULL)
            : kind == OUT_SU2 ? vm_mesh_write(cli.ctx, res, out, VM_FMT_SU2, NULL)
                              : vm_mesh_write(cli.ctx, res, out, fout, &wo);
  if (wst < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  if (st == VM_ERR_INTERRUPTED)
    rc = VM_EXIT_INTERRUPTED;
  else if (r.inverted > 0 || npairs > 0)
    rc = VM_EXIT_CHECK;
  int verified = 0;
  if (rc == VM_EXIT_OK) {
    /* before success is reported, vm-quality --verify's exact checks (CGAL
     * predicates, nothing shared with the solver or Embree): every corner
     * tet positive, outer faces crossing neither each other nor the wall */
    int vrc = vm_cli_verify(&cli, out, res, VM_RULE_CORNER, 0, NULL);
    if (vrc != VM_EXIT_OK) rc = vrc;
    verified = vrc == VM_EXIT_OK;
    if (verified && !cli.quiet)
      fprintf(stderr, "vm-prism: %s: verify: every corner tet positive, no outer faces crossing "
              "each other or the wall (exact)\n", out);
  }
  if (!cli.quiet) {
    fprintf(stderr,
            "vm-prism: %s: %lld prisms in %d layers (first %g, growth %g), %.1f%% of columns at "
            "full thickness, thickness/T min %.3f mean %.3f, inverted corner tets %lld, min "
            "scaled Jacobian %.3f, normal deviation max %.2f deg (%lld of %lld smooth vertices "
            "above 5 deg), intersecting pairs %lld, max "
            "growth %.3f, %.2f s%s\n",
            out, (long long)r.prisms, r.layers, r.first_height, r.growth, 100 * r.full_fraction,
            r.thick_min, r.thick_mean, (long long)r.inverted, r.sj_min, r.normal_dev_max,
            (long long)r.normal_dev_over5, (long long)r.smooth_vertices, (long long)npairs, r.growth_max, r.time_total,
            rc == VM_EXIT_CHECK ? "  -- NOT VALID" : rc == VM_EXIT_INTERRUPTED ? "  -- interrupted" : "");
  }
  if (json) {
    printf("{\"input\": ");
    vm_json_string(stdout, in);
    printf(", \"output\": ");
    vm_json_string(stdout, out);
    printf(", \"valid\": %s, \"verified\": %s, \"interrupted\": %s, \"wall_vertices\": %lld, "
           "\"wall_triangles\": %lld, \"prisms\": %lld, \"layers_requested\": %d, \"layers\": %d, "
           "\"thickness\": ",
           rc == VM_EXIT_OK ? "true" : "false", verified ? "true" : "false",
           st == VM_ERR_INTERRUPTED ? "true" : "false", (long long)r.wall_vertices, (long long)r.wall_triangles, (long long)r.prisms,
           r.layers_requested, r.layers);
    vm_json_double(stdout, r.thickness);
    printf(", \"model_length\": ");
    vm_json_double(stdout, L);
    printf(", \"first_height\": ");
    vm_json_double(stdout, r.first_height);
    printf(", \"growth\": ");
    vm_json_double(stdout, r.growth);
    printf(", \"full_fraction\": ");
    vm_json_double(stdout, r.full_fraction);
    printf(", \"thickness_min\": ");
    vm_json_double(stdout, r.thick_min);
    printf(", \"thickness_mean\": ");
    vm_json_double(stdout, r.thick_mean);
    printf(", \"inverted_corner_tets\": %lld, \"intersecting_pairs\": %lld, \"sj_min\": ",
           (long long)r.inverted, (long long)npairs);
    vm_json_double(stdout, r.sj_min);
    printf(", \"normal_dev_max_deg\": ");
    vm_json_double(stdout, r.normal_dev_max);
    printf(", \"thickness_max\": ");
    vm_json_double(stdout, r.thick_max);
    printf(", \"normal_dev_mean_deg\": ");
    vm_json_double(stdout, r.normal_dev_mean);
    printf(", \"smooth_vertices\": %lld, \"normal_dev_over_5deg\": %lld", (long long)r.smooth_vertices,
           (long long)r.normal_dev_over5);
    printf(", \"growth_max\": ");
    vm_json_double(stdout, r.growth_max);
    printf(", \"springback_iterations\": %d, \"cut_rounds\": %d, \"cut_pairs_first\": %lld, "
           "\"time\": {",
           r.springback_iter, r.cut_rounds, (long long)r.cut_pairs_first);
    for (int k = 0; k < VM_PRISM_NPHASES; k++)
      printf("\"%s\": %.3f, ", vm_prism_phase_name((vm_prism_phase)k), r.time[k]);
    printf("\"total\": %.3f}}\n", r.time_total);
  }
  if (report) {
    int st2 = vm_report_heading(report, "run");
    if (st2 >= 0) st2 = vm_report_row(report, "input, output", "%s, %s", in, out);
    if (st2 >= 0)
      st2 = vm_report_row(report, "wall triangles, prisms, layers (requested)",
                          "%lld, %lld, %d (%d)", (long long)r.wall_triangles,
                          (long long)r.prisms, r.layers, r.layers_requested);
    if (st2 >= 0)
      st2 = vm_report_row(report, "thickness T (of the model's length), first height, growth",
                          "%g (%.3g), %g, %g", r.thickness, r.thickness / L, r.first_height,
                          r.growth);
    if (st2 >= 0)
      st2 = vm_report_row(report, "columns at full thickness", "%.1f %%", 100 * r.full_fraction);
    if (st2 >= 0)
      st2 = vm_report_row(report, "thickness / T: min, mean, max", "%.3f, %.3f, %.3f",
                          r.thick_min, r.thick_mean, r.thick_max);
    if (st2 >= 0)
      st2 = vm_report_row(report, "inverted corner tets, intersecting pairs, min scaled Jacobian",
                          "%lld, %lld, %.3g", (long long)r.inverted, (long long)npairs, r.sj_min);
    if (st2 >= 0)
      st2 = vm_report_row(report, "first layer off the wall normal (smooth vertices)",
                          "max %.2f deg, %lld of %lld above 5 deg", r.normal_dev_max,
                          (long long)r.normal_dev_over5, (long long)r.smooth_vertices);
    if (st2 >= 0) st2 = vm_report_row(report, "max growth of successive heights", "%.3f", r.growth_max);
    if (st2 >= 0)
      st2 = vm_report_row(report, "springback iterations, cutting rounds (pairs at first)",
                          "%d, %d (%lld)", r.springback_iter, r.cut_rounds,
                          (long long)r.cut_pairs_first);
    char times[256];
    int len = 0;
    for (int k = 0; k < VM_PRISM_NPHASES && len < (int)sizeof times; k++)
      len += snprintf(times + len, sizeof times - (size_t)len, "%s%s %.2f s", k ? ", " : "",
                      vm_prism_phase_name((vm_prism_phase)k), r.time[k]);
    if (st2 >= 0) st2 = vm_report_row(report, "time per phase", "%s (%.2f s in all)", times, r.time_total);
    if (st2 >= 0)
      st2 = vm_report_row(report, "valid, verified (exact)", "%s, %s",
                          rc == VM_EXIT_OK ? "yes" : "no", verified ? "yes" : "no");
    int rrc = vm_cli_report_result(&cli, &report, report_dir, st2, "prism layers", res,
                                   "thickness", hist,
                                   "Convergence of the run: the functional F per solver "
                                   "iteration (springback, the solves after cutting, "
                                   "marching), the intersecting pairs left per cutting round "
                                   "in the M panel (0 elsewhere: every prism stays valid); "
                                   "dashed lines separate the phases.");
    if (rrc != VM_EXIT_OK && rc == VM_EXIT_OK) rc = rrc;
  }
done:
  vm_report_destroy(&report);
  vm_report_history_destroy(&hist);
  vm_mesh_destroy(&res);
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
