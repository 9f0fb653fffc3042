/* apps/vm-volume.c: the volume stage: untangle and optimize a tet, hex,
 * prism, pyramid or mixed mesh in place of its vertices, connectivity and
 * boundary kept. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_report.h"
#include "cli_verify.h"
#include "varmesh/io.h"
#include "varmesh/quality.h"
#include "varmesh/slip.h"
#include "varmesh/topology.h"
#include "varmesh/volume.h"

static const char usage[] =
    "usage: vm-volume [options] IN OUT\n"
    "Untangle (Section 5 of the paper) and optimize a volume mesh; fixed vertices\n"
    "(int point field 'fixed', the file's own flags, and by default the boundary)\n"
    "never move. OUT is written in the format of its extension, else IN's.\n"
    "  --untangle penalty|oneway|barrier|adaptive|foldover   untangling method: (35),\n"
    "                       its one-way variant, contraction (39), adaptive (default:\n"
    "                       (35) with a bounded eps decay), foldover (eps from the\n"
    "                       decrease of F, Garanzha et al. 2021)\n"
    "  --solver implicit|explicit|newton   global solver (default implicit; newton:\n"
    "                       full coupled Hessian, projected to PSD per node)\n"
    "  --measure balanced|shape|shape-alt  optimization measure (default balanced)\n"
    "  --theta T            volumetric weight of the balanced measure (default 0.8)\n"
    "  --theta-untangle T   theta of the penalty in global untangling (default: --theta)\n"
    "  --eps-inner N        foldover: iterations per eps (default 10)\n"
    "  --staged             hexahedra: untangle their 6-tet split first, then the\n"
    "                       rule's nodes with the split held valid (for twisted\n"
    "                       meshes; implies --untangle foldover --eps-inner 3\n"
    "                       --theta-untangle 0.999 unless those are given)\n"
    "  --rule corner|geometric   quadrature (default corner; geometric: 64 per hex)\n"
    "  --target-size H      ideal element edge length (default: total volume kept)\n"
    "  --max-iter N         untangling iterations (default 20000)\n"
    "  --opt-iter N         optimization iterations once valid (default 100)\n"
    "  --qi-steps N         quasi-isometric continuation steps (default 0)\n"
    "  --local-threshold N  untangle locally below N inverted simplices (default 100)\n"
    "  --time-limit S       seconds for the whole run\n"
    "  --threads N          OpenMP threads (results do not depend on it)\n"
    "  --free-boundary      do not fix the boundary (only 'fixed' vertices stay)\n"
    "  --slip-boundary      boundary vertices slide on the input's boundary surface:\n"
    "                       along its sharp edges, its corners fixed ('fixed' ones stay)\n"
    "  --feature-angle D    dihedral angle making a boundary edge sharp (default 40)\n"
    "  --corner-angle D     turn of a sharp edge making a corner (default 60)\n"
    "  --format F           output format\n"
    "  --binary             binary output where the format has both\n"
    "  --progress-every N   a progress line every N iterations (default 10)\n"
    "  --json               JSON summary on stdout\n"
    "  --report DIR         write DIR/index.html with pictures: convergence, quality\n"
    "                       histograms and slices before and after\n"
    "  -q, --quiet          no progress\n"
    "  --help, --version\n"
    "exit: 0 valid result (checked as vm-quality --verify does, with exact predicates);\n"
    "1 bad input or I/O; 2 usage; 3 inverted elements remain or the exact check failed\n"
    "(the best mesh is still written); 4 interrupted or --time-limit reached (the best\n"
    "state so far written; a second interrupt exits at once without writing)\n";

typedef struct {
  vm_cli *cli;
  int every;
  const char *last_phase;
  vm_report_history *hist; /* --report: every iteration */
} progress_state;

static void progress(void *user, const vm_volume_progress *p) {
  progress_state *ps = user;
  if (ps->hist)
    vm_report_history_add(ps->hist, p->phase, p->total_iter, p->F, p->inverted, p->eps);
  if (ps->cli->quiet) return;
  int first = !ps->last_phase || strcmp(ps->last_phase, p->phase);
  ps->last_phase = p->phase;
  if (!first && p->iter % ps->every) return;
  fprintf(stderr, "%-9s it %6d  F %.6e  M %8lld  min det %+.3e  %s %.2e  tau %.2e  pcg %4d  %7.2fs\n",
          p->phase, p->iter, p->F, (long long)p->inverted, p->min_det,
          strcmp(p->phase, "quasi-iso") ? "eps" : "t  ", p->eps, p->tau, p->pcg_iters,
          p->elapsed);
}

static int pick(const char *v, const char *const *names, int n) {
  for (int i = 0; v && i < n; i++)
    if (!strcmp(v, names[i])) return i;
  return -1;
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-volume");
  vm_volume_opts o = vm_volume_opts_default();
  vm_write_opts wo = vm_write_opts_default();
  const char *in = NULL, *out = NULL, *report_dir = NULL;
  vm_report *report = NULL;
  vm_report_history *hist = NULL;
  vm_mesh *before = NULL;
  int json = 0, free_boundary = 0, slip_boundary = 0, fout = VM_FMT_AUTO, verified = 0;
  long every = 10, lv;
  int rc = VM_EXIT_OK;
  vm_mesh *m = NULL;
  vm_volume_slip *slip = NULL;
  uint8_t *vflag0 = NULL;
  int32_t *vsurf0 = NULL;
  double feature_deg = 40, corner_deg = 60;
  static const char *const methods[] = {"penalty", "oneway", "barrier", "adaptive", "foldover"};
  static const char *const solvers[] = {"explicit", "implicit", "newton"};
  static const char *const rules[] = {"corner", "geometric"};
  int staged = 0, set_method = 0, set_inner = 0, set_thu = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
    int k;
    set_method |= !strcmp(a, "--untangle");
    set_inner |= !strcmp(a, "--eps-inner");
    set_thu |= !strcmp(a, "--theta-untangle");
    if (vm_cli_info_option(&cli, a, usage)) {
      goto done;
    } else if (!strcmp(a, "--json")) {
      json = 1;
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      cli.quiet = 1;
    } else if (!strcmp(a, "--free-boundary")) {
      free_boundary = 1;
    } else if (!strcmp(a, "--slip-boundary")) {
      slip_boundary = 1;
    } else if (!strcmp(a, "--staged")) {
      staged = 1;
    } else if (!strcmp(a, "--feature-angle") || !strcmp(a, "--corner-angle")) {
      i++;
      if (vm_cli_double(&cli, a, val, 1e-3, 180, !strcmp(a, "--feature-angle") ? &feature_deg
                                                                              : &corner_deg)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
    } else if (!strcmp(a, "--binary")) {
      wo.binary = 1;
    } else if (!strcmp(a, "--untangle")) {
      i++;
      if ((k = pick(val, methods, 5)) < 0) {
        rc = vm_cli_usage_error(
            &cli, "--untangle expects penalty, oneway, barrier, adaptive or foldover");
        goto done;
      }
      o.method = (vm_untangle_method)k;
    } else if (!strcmp(a, "--solver")) {
      i++;
      if ((k = pick(val, solvers, 3)) < 0) {
        rc = vm_cli_usage_error(&cli, "--solver expects implicit, explicit or newton");
        goto done;
      }
      o.solver = (vm_minimizer_kind)k;
    } else if (!strcmp(a, "--rule")) {
      i++;
      if ((k = pick(val, rules, 2)) < 0) {
        rc = vm_cli_usage_error(&cli, "--rule expects corner or geometric");
        goto done;
      }
      o.rule = (vm_rule)k;
    } else if (!strcmp(a, "--measure")) {
      i++;
      const vm_measure_ops *ops = val ? vm_measure_by_name(val) : NULL;
      if (!ops || (ops->kind != VM_MEASURE_BALANCED && ops->kind != VM_MEASURE_SHAPE &&
                   ops->kind != VM_MEASURE_SHAPE_ALT)) {
        rc = vm_cli_usage_error(&cli, "--measure expects balanced, shape or shape-alt");
        goto done;
      }
      o.measure = ops->kind;
    } else if (!strcmp(a, "--theta") || !strcmp(a, "--theta-untangle") ||
               !strcmp(a, "--target-size") || !strcmp(a, "--time-limit")) {
      i++;
      double x;
      int th = !strcmp(a, "--theta") || !strcmp(a, "--theta-untangle");
      double lo = th ? 0 : 1e-300, hi = th ? 0.999 : 1e300;
      if (vm_cli_double(&cli, a, val, lo, hi, &x)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      if (!strcmp(a, "--theta"))
        o.theta = x;
      else if (!strcmp(a, "--theta-untangle"))
        o.theta_untangle = x;
      else if (!strcmp(a, "--target-size"))
        o.target_size = x;
      else
        o.time_limit = x;
    } else if (!strcmp(a, "--max-iter") || !strcmp(a, "--opt-iter") ||
               !strcmp(a, "--qi-steps") || !strcmp(a, "--local-threshold") ||
               !strcmp(a, "--threads") || !strcmp(a, "--progress-every") ||
               !strcmp(a, "--eps-inner")) {
      i++;
      int lo1 = !strcmp(a, "--progress-every") || !strcmp(a, "--eps-inner");
      if (vm_cli_int(&cli, a, val, lo1 ? 1 : 0, 100000000, &lv)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      if (!strcmp(a, "--max-iter"))
        o.max_iter = (int)lv;
      else if (!strcmp(a, "--opt-iter"))
        o.opt_iter = (int)lv;
      else if (!strcmp(a, "--qi-steps"))
        o.qi_steps = (int)lv;
      else if (!strcmp(a, "--local-threshold"))
        o.local_threshold = (int)lv;
      else if (!strcmp(a, "--threads"))
        vm_ctx_set_threads(cli.ctx, (int)lv);
      else if (!strcmp(a, "--eps-inner"))
        o.eps_inner = (int)lv;
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
  if (staged) {
    /* the schedule measured on the rotated cube (docs/volume.md) */
    o.staged = 1;
    if (!set_method) o.method = VM_UNTANGLE_FOLDOVER;
    if (!set_inner) o.eps_inner = 3;
    if (!set_thu) o.theta_untangle = 0.999;
  }
  if (!in || !out) {
    rc = vm_cli_usage_error(&cli, "need IN and OUT");
    goto done;
  }
  if (free_boundary && slip_boundary) {
    rc = vm_cli_usage_error(&cli, "--free-boundary and --slip-boundary exclude each other");
    goto done;
  }
  if (fout == VM_FMT_AUTO && vm_format_from_path(out) == VM_FMT_AUTO)
    fout = vm_format_from_path(in);
  if (vm_mesh_read(cli.ctx, in, VM_FMT_AUTO, &m) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 3) {
    vm_cli_error(&cli, "%s: no volume elements (tet, pyramid, prism, hex) to optimize", in);
    rc = VM_EXIT_INPUT;
    goto done;
  }
  /* the file's own flags are written back unchanged: the stage's boundary
   * conditions below are for this run only */
  vflag0 = vm_malloc(cli.ctx, (size_t)m->nv + 1);
  vsurf0 = vm_alloc_array(cli.ctx, (size_t)m->nv + 1, sizeof *vsurf0);
  if (!vflag0 || !vsurf0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  memcpy(vflag0, m->vflag, (size_t)m->nv);
  memcpy(vsurf0, m->vsurf, (size_t)m->nv * sizeof *vsurf0);
  /* slip vertices of the file have no surface here: they stay put */
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_SLIP) m->vflag[v] = VM_VERTEX_FIXED;
  int64_t nfixed = vm_mesh_apply_fixed_field(m), nbnd = 0;
  if (slip_boundary) {
    vm_volume_slip_info si;
    if (vm_volume_slip_create(cli.ctx, m, feature_deg, corner_deg, &slip, &si) < 0) {
      vm_cli_error(&cli, "%s: %s", in, vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
    nbnd = si.nboundary;
    if (!cli.quiet)
      fprintf(stderr, "vm-volume: slip boundary: %lld boundary vertices: %lld slide on the "
              "surface, %lld along %d sharp edge lines, %lld corners and %lld fixed ones stay\n",
              (long long)si.nboundary, (long long)si.nsurface, (long long)si.nline, si.lines,
              (long long)si.ncorner, (long long)si.nkept_fixed);
  } else if (!free_boundary && vm_mesh_mark_boundary(m, VM_VERTEX_FIXED, &nbnd) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  int64_t nfree = 0, nslip = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    nfree += m->vflag[v] == VM_VERTEX_FREE;
    nslip += m->vflag[v] == VM_VERTEX_SLIP;
  }
  if (!cli.quiet)
    fprintf(stderr, "vm-volume: %s: %lld vertices (%lld free, %lld sliding; %lld fixed by field, "
            "%lld on the boundary), %lld elements\n", in, (long long)m->nv, (long long)nfree,
            (long long)nslip, (long long)nfixed, (long long)nbnd, (long long)m->ne);
  if (report_dir) {
    char title[512];
    snprintf(title, sizeof title, "vm-volume: %s", in);
    if ((rc = vm_cli_report_open(&cli, report_dir, title, &report, &hist)) != VM_EXIT_OK)
      goto done;
    if (vm_mesh_clone(m, &before) < 0) {
      vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
      rc = VM_EXIT_INPUT;
      goto done;
    }
  }
  progress_state ps = {&cli, (int)every, NULL, hist};
  o.progress = progress;
  o.user = &ps;
  vm_cli_catch_interrupts(&cli);
  vm_volume_report rep;
  vm_surface_ops sops;
  if (slip) sops = vm_volume_slip_ops(slip);
  int st = vm_volume_run(cli.ctx, m, slip ? &sops : NULL, &o, &rep);
  if (st < 0 && st != VM_ERR_INTERRUPTED) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  /* an independent check of the result: every corner simplex (and the
   * geometric rule's simplices if that rule was used) */
  vm_quality q, qg;
  vm_quality_opts qo = {VM_RULE_CORNER, o.target_size};
  vm_mesh_quality(m, &qo, &q);
  qo.rule = VM_RULE_GEOMETRIC;
  vm_mesh_quality(m, &qo, &qg);
  int64_t bad = q.all.inverted_nodes + (o.rule == VM_RULE_GEOMETRIC ? qg.all.inverted_nodes : 0);
  double slip_dist = 0;
  if (slip && vm_volume_slip_distance(slip, m, &slip_dist) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  memcpy(m->vflag, vflag0, (size_t)m->nv);
  memcpy(m->vsurf, vsurf0, (size_t)m->nv * sizeof *vsurf0);
  int wst = vm_mesh_write(cli.ctx, m, out, fout, &wo);
  if (wst < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  if (st == VM_ERR_INTERRUPTED || rep.timed_out)
    rc = VM_EXIT_INTERRUPTED;
  else if (bad > 0 || !rep.valid)
    rc = VM_EXIT_CHECK;
  else {
    /* before success is reported, vm-quality --verify's exact checks (CGAL
     * predicates, no arithmetic shared with the solver) on the written mesh */
    int vrc = vm_cli_verify(&cli, out, m, o.rule, 0, NULL);
    if (vrc != VM_EXIT_OK) rc = vrc;
    verified = vrc == VM_EXIT_OK;
    if (verified && !cli.quiet)
      fprintf(stderr, "vm-volume: %s: verify: every quadrature simplex (%s rule) positively "
              "oriented (exact)\n", out, rules[o.rule]);
  }
  if (!cli.quiet) {
    if (o.staged)
      fprintf(stderr, "vm-volume: staged: the 6-tet split's M %lld (max %lld) %s after %.2f s\n",
              (long long)rep.split_M_init, (long long)rep.split_M_max,
              rep.split_valid ? "untangled" : "NOT untangled", rep.time_split);
    fprintf(stderr, "vm-volume: %s: M %lld -> %lld (max %lld), %d untangling + %d local + %d "
            "optimization iterations, %.2f s (untangled after %.2f s)\n", out,
            (long long)rep.M_init, (long long)rep.M_final, (long long)rep.M_max,
            rep.iter_untangle, rep.iter_local, rep.iter_opt, rep.time_total, rep.time_untangle);
    fprintf(stderr, "vm-volume: phi_min %.4e  psi_min %.4e  min scaled Jacobian %.4f  inverted "
            "corner tets %lld in %lld elements%s\n", rep.phi_min, rep.psi_min, q.all.sj_min,
            (long long)q.all.inverted_nodes, (long long)q.all.inverted_elems,
            rc == VM_EXIT_CHECK ? "  -- NOT VALID"
            : rc == VM_EXIT_INTERRUPTED ? (rep.timed_out && st != VM_ERR_INTERRUPTED
                                               ? "  -- time limit reached"
                                               : "  -- interrupted")
                                        : "");
  }
  if (slip && !cli.quiet)
    fprintf(stderr, "vm-volume: slip boundary: largest distance of a boundary vertex from the "
            "input's boundary surface %.3e\n", slip_dist);
  if (report) {
    int rrc = vm_cli_report_volume(&cli, &report, report_dir, in, out, before, m, hist, &o, &rep);
    if (rrc != VM_EXIT_OK && rc == VM_EXIT_OK) rc = rrc;
  }
  if (json) {
    printf("{\"input\": ");
    vm_json_string(stdout, in);
    printf(", \"output\": ");
    vm_json_string(stdout, out);
    printf(", \"valid\": %s, \"interrupted\": %s, \"timed_out\": %s, \"method\": \"%s\", \"rule\": \"%s\", "
           "\"nodes\": %lld, \"M_init\": %lld, \"M_max\": %lld, \"M_final\": %lld, "
           "\"inverted_corner_tets\": %lld, \"inverted_elements\": %lld, \"iter_untangle\": %d, "
           "\"iter_local\": %d, \"iter_opt\": %d, \"time_untangle\": %.3f, \"time_total\": %.3f, "
           "\"phi_min\": ",
           rep.valid && bad == 0 && rc != VM_EXIT_CHECK ? "true" : "false",
           st == VM_ERR_INTERRUPTED ? "true" : "false", rep.timed_out ? "true" : "false",
           vm_untangle_method_name(o.method), rules[o.rule], (long long)rep.nodes,
           (long long)rep.M_init, (long long)rep.M_max, (long long)rep.M_final,
           (long long)q.all.inverted_nodes, (long long)q.all.inverted_elems, rep.iter_untangle,
           rep.iter_local, rep.iter_opt, rep.time_untangle, rep.time_total);
    vm_json_double(stdout, rep.phi_min);
    printf(", \"psi_min\": ");
    vm_json_double(stdout, rep.psi_min);
    printf(", \"sj_min\": ");
    vm_json_double(stdout, q.all.sj_min);
    if (slip) {
      printf(", \"slip_max_distance\": ");
      vm_json_double(stdout, slip_dist);
    }
    printf(", \"staged\": %s", o.staged ? "true" : "false");
    if (o.staged)
      printf(", \"split_M_init\": %lld, \"split_M_max\": %lld, \"split_valid\": %s, "
             "\"time_split\": %.3f",
             (long long)rep.split_M_init, (long long)rep.split_M_max,
             rep.split_valid ? "true" : "false", rep.time_split);
    printf(", \"t_reached\": ");
    vm_json_double(stdout, rep.t_reached);
    printf(", \"verified\": %s}\n", verified ? "true" : "false");
  }
done:
  vm_volume_slip_destroy(&slip);
  if (vflag0) vm_free(cli.ctx, vflag0);
  if (vsurf0) vm_free(cli.ctx, vsurf0);
  vm_report_destroy(&report);
  vm_report_history_destroy(&hist);
  vm_mesh_destroy(&before);
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
