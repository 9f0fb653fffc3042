/* apps/vm-volume.c: the volume stage: untangle and optimize a tet, hex,
 * prism, pyramid or mixed mesh in place of its vertices, connectivity and
 * boundary kept. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_report.h"
#include "cli_verify.h"
#include "varmesh/io.h"
#include "varmesh/jacobian.h"
#include "varmesh/planar.h"
#include "varmesh/quality.h"
#include "varmesh/slip.h"
#include "varmesh/topology.h"
#include "varmesh/volume.h"

typedef struct {
  vm_cli *cli;
  int every;
  const char *last_phase;
  vm_report_history *hist; /* --report: every iteration */
} progress_state;

static void progress(void *user, const vm_volume_progress *p) {
  progress_state *ps = user;
  if (ps->hist) vm_report_history_add(ps->hist, p->phase, p->total_iter, p->F, p->inverted, p->eps);
  if (ps->cli->quiet) return;
  int first = !ps->last_phase || strcmp(ps->last_phase, p->phase);
  ps->last_phase = p->phase;
  if (!first && p->iter % ps->every) return;
  fprintf(stderr,
          "%-9s it %6d  F %.6e  M %8lld  min det %+.3e  %s %.2e  tau %.2e  pcg %4d  %7.2fs\n",
          p->phase, p->iter, p->F, (long long)p->inverted, p->min_det,
          strcmp(p->phase, "quasi-iso") ? "eps" : "t  ", p->eps, p->tau, p->pcg_iters, p->elapsed);
}

typedef struct {
  const char *in, *out, *report_dir;
  const char *reference; /* --reference: target shapes from this mesh */
  int json, free_boundary, slip_boundary, fout, every, method, direct;
  int repair;        /* index into repairs[] */
  int auto_schedule; /* neither --staged nor --direct: chosen from the mesh, with fallback */
  double feature_deg, corner_deg;
  double boundary_tol; /* free or sliding boundary: largest move, relative to the diagonal */
  double min_sj;       /* an element below this scaled Jacobian is flat */
  vm_volume_opts o;
  vm_write_opts wo;
} args;

static int opt_measure(vm_cli *cli, const vm_opt *opt, const char *val, void *a) {
  const vm_measure_ops *ops = val ? vm_measure_by_name(val) : NULL;
  if (!ops || (ops->kind != VM_MEASURE_BALANCED && ops->kind != VM_MEASURE_SHAPE &&
               ops->kind != VM_MEASURE_SHAPE_ALT))
    return vm_cli_usage_error(cli, "%s expects balanced, shape or shape-alt", opt->name);
  ((args *)a)->o.measure = ops->kind;
  return VM_EXIT_OK;
}

#define A(f) offsetof(args, f)
static const char *const methods[] = {"penalty", "oneway", "barrier", "adaptive", "foldover", NULL};
static const char *const solvers[] = {"explicit", "implicit", "newton", NULL};
static const char *const rules[] = {"corner", "geometric", NULL};
static const char *const repairs[] = {"geometric", "coefficients", "nodes", NULL};
static const vm_opt opts[] = {
    {"--untangle", NULL, VM_OPT_CHOICE, A(method), NULL,
     "untangling method: (35), its one-way variant, contraction (39), adaptive ((35) with a "
     "bounded eps decay; the fallback), foldover (default: eps from the decrease of F, "
     "Garanzha et al. 2021)",
     .choices = methods},
    {"--solver", NULL, VM_OPT_CHOICE, A(o.solver), "implicit|explicit|newton",
     "global solver (default implicit; newton: full coupled Hessian, projected to PSD per node, "
     "for the optimization: the untangling then runs with implicit)",
     .choices = solvers, .error = "expects implicit, explicit or newton"},
    {"--measure", NULL, VM_OPT_CALL, 0, "balanced|shape|shape-alt",
     "optimization measure (default balanced)", .fn = opt_measure},
    {"--theta", NULL, VM_OPT_DOUBLE, A(o.theta), "T",
     "volumetric weight of the balanced measure (default 0.8)", .lo = 0, .hi = 0.999},
    {"--theta-untangle", NULL, VM_OPT_DOUBLE, A(o.theta_untangle), "T",
     "theta of the penalty in global untangling (default 0.999; the adaptive fallback: "
     "--theta)",
     .lo = 0, .hi = 0.999},
    {"--eps-inner", NULL, VM_OPT_INT, A(o.eps_inner), "N",
     "foldover: iterations per eps (default 3)", .lo = 1, .hi = 1e8},
    {"--eps-cap", NULL, VM_OPT_DOUBLE, A(o.eps_cap), "R",
     "foldover: while some nodes are guarded (staged, after the split; the repair) or in the "
     "repair's geometric global rounds, and one is inverted, eps after each block at most "
     "R |min det| (default 1; 0: no cap)",
     .lo = 0, .hi = 1e8},
    {"--staged", NULL, VM_OPT_FLAG, A(o.staged), NULL,
     "hexahedra: untangle their 6-tet split first, then the rule's nodes with the split held "
     "valid (the default on meshes with hexahedra)",
     .ival = 1},
    {"--direct", NULL, VM_OPT_FLAG, A(direct), NULL,
     "the direct schedule even on hexahedra (default: staged when the mesh has hexahedra, "
     "direct otherwise; if the first stalls, the direct one after staged, the adaptive "
     "penalty after direct)",
     .ival = 1},
    {"--rule", NULL, VM_OPT_CHOICE, A(o.rule), NULL,
     "quadrature (default corner; geometric: 64 per hex)", .choices = rules},
    {"--repair", NULL, VM_OPT_CHOICE, A(repair), NULL,
     "how cells not certified after the schedule are repaired: geometric (default: the whole "
     "mesh untangled under the 64-node rule (24) until every cell is certified, then rounds "
     "on what is left), coefficients (rounds on the hexes' Bernstein coefficients first: "
     "faster on mild twists, fails on the worst), nodes (rounds on the nodes of (24))",
     .choices = repairs},
    {"--target-size", NULL, VM_OPT_DOUBLE, A(o.target_size), "H",
     "ideal element edge length (default: total volume kept)", .lo = 1e-300, .hi = 1e300},
    {"--reference", NULL, VM_OPT_STRING, A(reference), "REF",
     "target shapes from REF, IN's mesh in its rest shape (same vertices and elements): its "
     "cells' shapes and sizes are the ideal ones (instead of --target-size)",
     .error = "expects a mesh file"},
    {"--max-iter", NULL, VM_OPT_INT, A(o.max_iter), "N", "untangling iterations (default 20000)",
     .lo = 0, .hi = 1e8},
    {"--opt-iter", NULL, VM_OPT_INT, A(o.opt_iter), "N",
     "optimization iterations once valid (default 100)", .lo = 0, .hi = 1e8},
    {"--qi-steps", NULL, VM_OPT_INT, A(o.qi_steps), "N",
     "quasi-isometric continuation steps, the last optimization (default 1 in the staged "
     "schedule, else 0)",
     .lo = 0, .hi = 1e8},
    {"--local-threshold", NULL, VM_OPT_INT, A(o.local_threshold), "N",
     "untangle locally below N inverted simplices (default 100)", .lo = 0, .hi = 1e8},
    {"--time-limit", NULL, VM_OPT_DOUBLE, A(o.time_limit), "S", "seconds for the whole run",
     .lo = 1e-300, .hi = 1e300},
    VM_CLI_OPT_THREADS,
    {"--free-boundary", NULL, VM_OPT_FLAG, A(free_boundary), NULL,
     "do not fix the boundary (only 'fixed' vertices stay)", .ival = 1},
    {"--slip-boundary", NULL, VM_OPT_FLAG, A(slip_boundary), NULL,
     "boundary vertices slide on the input's boundary surface: along its sharp edges, its "
     "corners fixed ('fixed' ones stay)",
     .ival = 1},
    {"--boundary-tolerance", NULL, VM_OPT_DOUBLE, A(boundary_tol), "R",
     "free or sliding boundary: the largest distance (two-sided Hausdorff) the boundary may "
     "move from the input's, relative to its bounding-box diagonal; beyond it the run fails "
     "(default 0.01)",
     .lo = 0, .hi = 1e300},
    {"--min-sj", NULL, VM_OPT_DOUBLE, A(min_sj), "S",
     "an element with a free vertex and a scaled Jacobian below S is flat, and the run fails "
     "(default 1e-5; 0: no check)",
     .lo = 0, .hi = 1},
    {"--feature-angle", NULL, VM_OPT_DOUBLE, A(feature_deg), "D",
     "dihedral angle making a boundary edge sharp (default 40)", .lo = 1e-3, .hi = 180},
    {"--corner-angle", NULL, VM_OPT_DOUBLE, A(corner_deg), "D",
     "turn of a sharp edge making a corner (default 60)", .lo = 1e-3, .hi = 180},
    {"--format", NULL, VM_OPT_CALL, A(fout), "F", "output format", .fn = vm_cli_opt_format},
    {"--binary", NULL, VM_OPT_FLAG, A(wo.binary), NULL, "binary output where the format has both",
     .ival = 1},
    {"--progress-every", NULL, VM_OPT_INT, A(every), "N",
     "a progress line every N iterations (default 10)", .lo = 1, .hi = 1e8},
    {"--json", NULL, VM_OPT_FLAG, A(json), NULL, "JSON summary on stdout", .ival = 1},
    {"--report", NULL, VM_OPT_STRING, A(report_dir), "DIR",
     "write DIR/index.html with pictures: convergence, quality histograms and slices before "
     "and after",
     .error = "expects a directory"},
    VM_CLI_OPT_QUIET("no progress"),
    VM_CLI_OPT_VERBOSE("debug messages too"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-volume [options] IN OUT\n"
    "Untangle (Section 5 of the paper) and optimize a volume mesh, or a 2D mesh of\n"
    "triangles and quads in a plane (any plane; its boundary gives the orientation);\n"
    "fixed vertices (int point field 'fixed', the file's own flags, and by default\n"
    "the boundary) never move. OUT is written in the format of its extension, else\n"
    "IN's.\n",
    opts,
    "exit: 0 valid result: every cell certified det J > 0 everywhere, checked as\n"
    "vm-quality --verify does (exact predicates, Bernstein certification); 1 bad input\n"
    "or I/O; 2 usage; 3 cells not certified valid remain, an inverted element has only\n"
    "fixed vertices, or the check failed (the best mesh is still written); 4 interrupted\n"
    "or --time-limit reached (the best state so far written; a second interrupt exits\n"
    "at once without writing)\n",
    {A(in), A(out)},
    2,
    "need IN and OUT"};

/* What the stage did and what the independent check found. */
typedef struct {
  int st; /* of vm_volume_run */
  vm_volume_report rep;
  vm_quality q; /* corner rule */
  int64_t bad;  /* inverted nodes of the rule used, as vm_mesh_quality counts them */
  double slip_dist;
  /* free or sliding boundary: how far the shape moved (NAN: fixed boundary) */
  double shape_dist, shape_diag, shape_at[3]; /* shape_at: where it moved most */
  int shape_moved;
  /* flat elements left: those with a free vertex and sj < --min-sj */
  int64_t flat, flat_worst;
  double flat_sj, flat_at[3]; /* the worst one's sj and centroid */
  int verified;
  vm_jac_report cert; /* the independent certification of the written mesh */
  int staged;         /* the schedule that ran last */
  int fell_back;      /* the first schedule stalled, the other one ran */
  int planar;         /* a 2D mesh in a plane */
  int mirrored;       /* a volume mesh numbered against VTK's orientation */
} outcome;

/* The boundary conditions of this run on m's flags (the file's own flags are
 * saved by the caller and written back): 'fixed' vertices and, unless
 * --free-boundary, the boundary fixed or (--slip-boundary) sliding on *slip. */
static int boundary_conditions(vm_cli *cli, const args *a, vm_mesh *m, vm_volume_slip **slip) {
  /* slip vertices of the file have no surface here: they stay put */
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_SLIP) m->vflag[v] = VM_VERTEX_FIXED;
  int64_t nfixed = vm_mesh_apply_fixed_field(m), nbnd = 0;
  if (a->slip_boundary) {
    vm_volume_slip_info si;
    if (vm_volume_slip_create(cli->ctx, m, a->feature_deg, a->corner_deg, slip, &si) < 0)
      return vm_cli_input_error(cli, a->in);
    nbnd = si.nboundary;
    if (!cli->quiet)
      fprintf(stderr,
              "vm-volume: slip boundary: %lld boundary vertices: %lld slide on the "
              "surface, %lld along %d sharp edge lines, %lld corners and %lld fixed ones stay\n",
              (long long)si.nboundary, (long long)si.nsurface, (long long)si.nline, si.lines,
              (long long)si.ncorner, (long long)si.nkept_fixed);
    if (si.fold_edges > 0 && !cli->quiet)
      fprintf(stderr,
              "vm-volume: slip boundary: %lld sharp edges and line turns where the input's "
              "boundary folds back over tangled elements (%g degrees or more) are not "
              "features: their vertices slide\n",
              (long long)si.fold_edges, VM_SLIP_FOLD_DEG);
  } else if (!a->free_boundary && vm_mesh_mark_boundary(m, VM_VERTEX_FIXED, &nbnd) < 0) {
    return vm_cli_input_error(cli, NULL);
  }
  int64_t nfree = 0, nslip = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    nfree += m->vflag[v] == VM_VERTEX_FREE;
    nslip += m->vflag[v] == VM_VERTEX_SLIP;
  }
  if (!cli->quiet)
    fprintf(stderr,
            "vm-volume: %s: %lld vertices (%lld free, %lld sliding; %lld fixed by field, "
            "%lld on the boundary), %lld elements\n",
            a->in, (long long)m->nv, (long long)nfree, (long long)nslip, (long long)nfixed,
            (long long)nbnd, (long long)m->ne);
  return VM_EXIT_OK;
}

/* The exit code the run earns before the exact check. */
static int run_code(const outcome *r) {
  if (r->st == VM_ERR_INTERRUPTED) return VM_EXIT_INTERRUPTED;
  int fails = r->bad > 0 || !r->rep.valid || r->cert.invalid + r->cert.undecided > 0 ||
              r->shape_moved || r->flat > 0;
  /* the time limit is a budget: a mesh certified valid when it ran out
   * (the optimization after the repair stopped early) is a success, said
   * on stderr and as "timed_out" in the JSON */
  if (r->rep.timed_out) return fails ? VM_EXIT_INTERRUPTED : VM_EXIT_OK;
  return fails ? VM_EXIT_CHECK : VM_EXIT_OK;
}

/* The run ended with inverted nodes because its last untangling phase was
 * stopped as stalled (not a repair that left cells, not the budget). */
static int ended_stalled(const vm_volume_report *rep) {
  return rep->stalled && !rep->valid && rep->M_final > 0;
}

static void print_summary(const vm_cli *cli, const args *a, const outcome *r, int rc) {
  const vm_volume_report *rep = &r->rep;
  if (!cli->quiet) {
    if (r->staged && rep->split_M_init > 0)
      fprintf(stderr, "vm-volume: staged: the 6-tet split's M %lld (max %lld) %s after %.2f s\n",
              (long long)rep->split_M_init, (long long)rep->split_M_max,
              rep->split_valid ? "untangled" : "NOT untangled", rep->time_split);
    fprintf(stderr,
            "vm-volume: %s: M %lld -> %lld (max %lld), %d untangling + %d local + %d "
            "optimization + %d repair iterations, %.2f s",
            a->out, (long long)rep->M_init, (long long)rep->M_final, (long long)rep->M_max,
            rep->iter_untangle, rep->iter_local, rep->iter_opt, rep->iter_repair, rep->time_total);
    if (rep->valid)
      fprintf(stderr, " (certified valid after %.2f s)\n", rep->time_certified);
    else
      fprintf(stderr, "\n");
    if (rep->cert_bad_init > 0) {
      fprintf(stderr, "vm-volume: repair: %lld cells with M = 0 but not certified valid",
              (long long)rep->cert_bad_init);
      if (rep->geometric_left >= 0)
        fprintf(stderr, " -> %lld under the geometric rule (%.2f s)",
                (long long)rep->geometric_left, rep->time_geometric);
      fprintf(stderr, " -> %lld after %d rounds\n",
              (long long)(r->cert.invalid + r->cert.undecided), rep->repair_rounds);
    }
    fprintf(stderr,
            "vm-volume: phi_min %.4e  psi_min %.4e  min scaled Jacobian %.4f  inverted "
            "corner tets %lld in %lld elements\n",
            rep->phi_min, rep->psi_min, r->q.all.sj_min, (long long)r->q.all.inverted_nodes,
            (long long)r->q.all.inverted_elems);
    fprintf(stderr,
            "vm-volume: certified (det J > 0 everywhere in the cell): %lld of %lld cells; %lld "
            "invalid, %lld undecided%s\n",
            (long long)(r->cert.cells - r->cert.invalid - r->cert.undecided),
            (long long)r->cert.cells, (long long)r->cert.invalid, (long long)r->cert.undecided,
            rc == VM_EXIT_CHECK ? "  -- NOT VALID"
            : rc == VM_EXIT_INTERRUPTED
                ? (rep->timed_out && r->st != VM_ERR_INTERRUPTED ? "  -- time limit reached"
                                                                 : "  -- interrupted")
                : "");
  }
  if (!cli->quiet && ended_stalled(rep))
    fprintf(stderr,
            "vm-volume: the untangling was stopped as stalled: its eps had fallen to %.3g and %d "
            "iterations brought neither fewer inverted nodes nor a higher min det (%.3g)\n",
            rep->stall_eps, VM_VOLUME_STALL_ITER, rep->stall_min_det);
  if (!cli->quiet && rc == VM_EXIT_OK && rep->timed_out)
    fprintf(stderr,
            "vm-volume: the time limit was reached after the mesh was certified valid (after "
            "%.2f s): the optimization stopped early; the mesh written is valid\n",
            rep->time_certified);
  if (!cli->quiet && r->q.top_dim == 3 && r->q.foam_pyramid_errors + r->q.foam_neg_volumes > 0)
    fprintf(stderr,
            "vm-volume: warning: OpenFOAM's checkMesh will fail it: %lld cells of volume <= 0, "
            "%lld face pyramids incorrectly oriented (the cell centre outside a face's plane)\n",
            (long long)r->q.foam_neg_volumes, (long long)r->q.foam_pyramid_errors);
  if (a->slip_boundary && !cli->quiet)
    fprintf(stderr,
            "vm-volume: slip boundary: largest distance of a boundary vertex from the "
            "input's boundary surface %.3e\n",
            r->slip_dist);
  if (!isnan(r->shape_dist) && !cli->quiet && !r->shape_moved)
    fprintf(stderr,
            "vm-volume: the boundary moved by at most %.3e (Hausdorff), %.3g %% of its "
            "diagonal, within --boundary-tolerance %g\n",
            r->shape_dist, 100 * r->shape_dist / r->shape_diag, a->boundary_tol);
  if (r->mirrored && rc == VM_EXIT_OK && !cli->quiet)
    fprintf(stderr,
            "vm-volume: warning: %s keeps %s's numbering, in which a valid cell has a negative "
            "volume by VTK's convention: vm-quality and solvers read its cells as inverted until "
            "each one's vertices are numbered the other way round\n",
            a->out, a->in);
  /* the shape and flatness verdicts are on a finished run's result only */
  if (rc == VM_EXIT_INTERRUPTED) return;
  if (r->shape_moved)
    vm_cli_error(cli,
                 "%s: the boundary moved by %.3e (Hausdorff distance to the input's boundary, "
                 "largest near (%.6g, %.6g, %.6g)), %.3g %% of its diagonal, beyond "
                 "--boundary-tolerance %g: the shape is not kept%s",
                 a->out, r->shape_dist, r->shape_at[0], r->shape_at[1], r->shape_at[2],
                 100 * r->shape_dist / r->shape_diag, a->boundary_tol,
                 r->planar          ? "; a larger --boundary-tolerance accepts it"
                 : a->free_boundary ? "; --slip-boundary keeps it on the surface"
                                    : "; a smaller --feature-angle keeps more of its edges and "
                                      "corners");
  if (rc == VM_EXIT_CHECK && !r->shape_moved && !r->flat &&
      (r->bad > 0 || !r->rep.valid || r->cert.invalid + r->cert.undecided > 0))
    vm_cli_error(cli,
                 "%s: not valid: %lld of %lld cells not certified det J > 0 everywhere, %lld "
                 "inverted corner simplices in %lld elements; the best state is written",
                 a->out, (long long)(r->cert.invalid + r->cert.undecided), (long long)r->cert.cells,
                 (long long)r->q.all.inverted_nodes, (long long)r->q.all.inverted_elems);
  if (r->flat > 0)
    vm_cli_error(cli,
                 "%s: %lld elements are flat (scaled Jacobian below --min-sj %g): the worst, "
                 "element %lld near (%.6g, %.6g, %.6g), has %.3e",
                 a->out, (long long)r->flat, a->min_sj, (long long)r->flat_worst, r->flat_at[0],
                 r->flat_at[1], r->flat_at[2], r->flat_sj);
}

static void print_json(const args *a, const outcome *r, int rc) {
  const vm_volume_report *rep = &r->rep;
  printf("{\"input\": ");
  vm_json_string(stdout, a->in);
  printf(", \"output\": ");
  vm_json_string(stdout, a->out);
  printf(", \"valid\": %s, \"interrupted\": %s, \"timed_out\": %s, \"stalled\": %s, "
         "\"method\": \"%s\", \"rule\": \"%s\", "
         "\"nodes\": %lld, \"M_init\": %lld, \"M_max\": %lld, \"M_final\": %lld, "
         "\"inverted_corner_tets\": %lld, \"inverted_elements\": %lld, \"iter_untangle\": %d, "
         "\"iter_local\": %d, \"iter_opt\": %d, \"time_untangle\": %.3f, \"time_total\": %.3f, "
         "\"phi_min\": ",
         rep->valid && r->bad == 0 && rc == VM_EXIT_OK ? "true" : "false",
         r->st == VM_ERR_INTERRUPTED ? "true" : "false", rep->timed_out ? "true" : "false",
         ended_stalled(rep) ? "true" : "false", vm_untangle_method_name(a->o.method),
         rules[a->o.rule], (long long)rep->nodes, (long long)rep->M_init, (long long)rep->M_max,
         (long long)rep->M_final, (long long)r->q.all.inverted_nodes,
         (long long)r->q.all.inverted_elems, rep->iter_untangle, rep->iter_local, rep->iter_opt,
         rep->time_untangle, rep->time_total);
  vm_json_double(stdout, rep->phi_min);
  printf(", \"psi_min\": ");
  vm_json_double(stdout, rep->psi_min);
  printf(", \"sj_min\": ");
  vm_json_double(stdout, r->q.all.sj_min);
  if (a->slip_boundary) {
    printf(", \"slip_max_distance\": ");
    vm_json_double(stdout, r->slip_dist);
  }
  if (!isnan(r->shape_dist)) {
    printf(", \"boundary_deviation\": ");
    vm_json_double(stdout, r->shape_dist);
    printf(", \"boundary_deviation_rel\": ");
    vm_json_double(stdout, r->shape_dist / r->shape_diag);
    printf(", \"boundary_moved\": %s", r->shape_moved ? "true" : "false");
  }
  printf(", \"flat_elements\": %lld", (long long)r->flat);
  if (r->q.top_dim == 3)
    printf(", \"foam_negative_volumes\": %lld, \"foam_pyramid_errors\": %lld",
           (long long)r->q.foam_neg_volumes, (long long)r->q.foam_pyramid_errors);
  printf(", \"corner_valid\": %s, \"certified_cells\": %lld, \"certified_invalid\": %lld, "
         "\"certified_undecided\": %lld, \"repair_cells_init\": %lld, \"iter_repair\": %d, "
         "\"repair_geometric_left\": %lld, \"time_repair_geometric\": %.3f, "
         "\"time_certified\": %.3f",
         r->q.all.inverted_nodes == 0 && rep->M_final == 0 ? "true" : "false",
         (long long)r->cert.cells, (long long)r->cert.invalid, (long long)r->cert.undecided,
         (long long)rep->cert_bad_init, rep->iter_repair, (long long)rep->geometric_left,
         rep->time_geometric, rep->valid ? rep->time_certified : -1.0);
  printf(", \"staged\": %s, \"fallback\": %s", r->staged ? "true" : "false",
         r->fell_back ? "true" : "false");
  if (r->staged)
    printf(", \"split_M_init\": %lld, \"split_M_max\": %lld, \"split_valid\": %s, "
           "\"time_split\": %.3f",
           (long long)rep->split_M_init, (long long)rep->split_M_max,
           rep->split_valid ? "true" : "false", rep->time_split);
  printf(", \"t_reached\": ");
  vm_json_double(stdout, rep->t_reached);
  printf(", \"planar\": %s, \"orientation_reversed\": %s", r->planar ? "true" : "false",
         r->mirrored ? "true" : "false");
  printf(", \"verified\": %s}\n", r->verified ? "true" : "false");
}

/* What a run holds, freed by stage_free. */
typedef struct {
  vm_mesh *m, *before; /* before: a copy of the input for --report */
  vm_volume_slip *slip;
  vm_volume_shape *shape; /* free or sliding boundary: the input's boundary */
  uint8_t *vflag0;        /* the file's own flags, written back unchanged: the */
  int32_t *vsurf0;        /* stage's boundary conditions are for this run only */
  vm_report *report;
  vm_report_history *hist;
  int planar;           /* a 2D mesh, optimized in the coordinates of its plane */
  vm_plane_frame plane; /* that plane */
  double *xyz0, *x2d0;  /* planar: the input's coordinates and the plane's */
  int mirrored;         /* volume elements numbered the other way round: x negated */
  vm_mesh *ref;         /* --reference */
} stage;

static void stage_free(vm_ctx *ctx, stage *s) {
  vm_volume_slip_destroy(&s->slip);
  vm_volume_shape_destroy(&s->shape);
  if (s->vflag0) vm_free(ctx, s->vflag0);
  if (s->vsurf0) vm_free(ctx, s->vsurf0);
  vm_free(ctx, s->xyz0);
  vm_free(ctx, s->x2d0);
  vm_mesh_destroy(&s->ref);
  vm_report_destroy(&s->report);
  vm_report_history_destroy(&s->hist);
  vm_mesh_destroy(&s->before);
  vm_mesh_destroy(&s->m);
}

/* A 2D mesh in a plane (z = 0, another axis-aligned plane or a tilted one)
 * to the plane's own coordinates: the stage runs on it in 2D. A surface
 * that is not planar is refused: its optimization is the surface stage's. */
static int to_plane(vm_cli *cli, const args *a, stage *s) {
  vm_mesh *m = s->m;
  if (vm_mesh_plane_frame(m, VM_PLANE_TOL, &s->plane) < 0) {
    const double *x = s->plane.worst >= 0 ? m->xyz + 3 * s->plane.worst : NULL;
    if (!x) return vm_cli_input_error(cli, a->in);
    vm_cli_error(cli,
                 "%s: the triangles and quadrilaterals are not in one plane (vertex %lld at "
                 "(%.6g, %.6g, %.6g) is %.3g off it): vm-volume takes volume meshes and planar "
                 "2D meshes; vm-surface optimizes surface meshes",
                 a->in, (long long)s->plane.worst, x[0], x[1], x[2], s->plane.offset);
    return VM_EXIT_INPUT;
  }
  if (a->slip_boundary) {
    vm_cli_error(cli,
                 "%s: --slip-boundary takes volume meshes; the boundary of a planar mesh is "
                 "fixed, or moves with --free-boundary",
                 a->in);
    return VM_EXIT_USAGE;
  }
  if (a->report_dir) {
    vm_cli_error(cli, "%s: --report draws volume meshes; vm-quality --report draws this one",
                 a->in);
    return VM_EXIT_USAGE;
  }
  int64_t pair[2];
  int32_t edge[2];
  int64_t nconf = vm_mesh_orientation_conflicts_2d(m, pair, edge);
  if (nconf < 0) return vm_cli_input_error(cli, NULL);
  if (nconf > 0) {
    vm_cli_error(cli,
                 "%s: the elements are not oriented alike: elements %lld and %lld run through "
                 "their shared edge (%lld, %lld) in the same direction (%lld such edges); "
                 "number every element's vertices the same way round first",
                 a->in, (long long)pair[0], (long long)pair[1], (long long)edge[0],
                 (long long)edge[1], (long long)nconf);
    return VM_EXIT_INPUT;
  }
  size_t n = (size_t)m->nv * 3;
  s->xyz0 = vm_alloc_array(cli->ctx, n, sizeof *s->xyz0);
  s->x2d0 = vm_alloc_array(cli->ctx, n, sizeof *s->x2d0);
  if (!s->xyz0 || !s->x2d0) return vm_cli_input_error(cli, NULL);
  memcpy(s->xyz0, m->xyz, n * sizeof *s->xyz0);
  vm_mesh_to_plane(m, &s->plane);
  memcpy(s->x2d0, m->xyz, n * sizeof *s->x2d0);
  s->planar = 1;
  if (!cli->quiet) {
    const vm_plane_frame *f = &s->plane;
    const char axis_name[] = "xyz";
    char where[160];
    if (f->axis >= 0)
      snprintf(where, sizeof where, "the plane %c = %.9g", axis_name[f->axis], f->level);
    else
      snprintf(where, sizeof where,
               "the plane through (%.6g, %.6g, %.6g) with normal (%.4f, %.4f, %.4f)", f->o[0],
               f->o[1], f->o[2], f->n[0], f->n[1], f->n[2]);
    fprintf(stderr, "vm-volume: %s: a 2D mesh in %s, optimized in that plane%s\n", a->in, where,
            f->flip ? "; its elements turn clockwise seen from the plane's normal, and so "
                      "does its boundary: that orientation is taken as positive"
                    : "");
  }
  return VM_EXIT_OK;
}

/* x -> -x for every vertex: a mirror, exact both ways (every coordinate
 * back bit for bit). */
static void negate_x(vm_mesh *m) {
  for (int64_t v = 0; v < m->nv; v++) m->xyz[3 * v] = -m->xyz[3 * v];
}

/* What is written: a mesh run mirrored with its x back (exact), a planar
 * mesh back in its plane (what did not move bit for bit as it was read). */
static int write_mesh(vm_cli *cli, const args *a, stage *s) {
  if (!s->planar && !s->mirrored)
    return vm_mesh_write(cli->ctx, s->m, a->out, a->fout, &a->wo) < 0
               ? vm_cli_input_error(cli, NULL)
               : VM_EXIT_OK;
  vm_mesh *w = NULL;
  if (vm_mesh_clone(s->m, &w) < 0) return vm_cli_input_error(cli, NULL);
  if (s->mirrored)
    negate_x(w);
  else
    vm_mesh_from_plane(w, &s->plane, s->x2d0, s->xyz0);
  int st = vm_mesh_write(cli->ctx, w, a->out, a->fout, &a->wo);
  vm_mesh_destroy(&w);
  return st < 0 ? vm_cli_input_error(cli, NULL) : VM_EXIT_OK;
}

/* --reference: IN's mesh in its rest shape, its cells the targets. */
static int read_reference(vm_cli *cli, const args *a, stage *s) {
  const vm_mesh *m = s->m;
  if (s->planar) {
    vm_cli_error(cli, "%s: --reference takes volume meshes", a->reference);
    return VM_EXIT_USAGE;
  }
  if (vm_mesh_read(cli->ctx, a->reference, VM_FMT_AUTO, &s->ref) < 0)
    return vm_cli_input_error(cli, NULL);
  vm_mesh *r = s->ref;
  int same = r->nv == m->nv && r->ne == m->ne;
  int64_t bad = -1;
  for (int64_t e = 0; same && e < m->ne; e++) {
    int64_t k = m->eoff[e + 1] - m->eoff[e];
    if (r->etype[e] != m->etype[e] || r->eoff[e + 1] - r->eoff[e] != k ||
        memcmp(r->conn + r->eoff[e], m->conn + m->eoff[e], (size_t)k * sizeof *m->conn) != 0)
      bad = e, same = 0;
  }
  if (!same) {
    if (bad >= 0)
      vm_cli_error(cli, "%s: not %s's mesh in another shape: element %lld differs", a->reference,
                   a->in, (long long)bad);
    else
      vm_cli_error(cli,
                   "%s: not %s's mesh in another shape: %lld vertices and %lld elements "
                   "against %lld and %lld",
                   a->reference, a->in, (long long)r->nv, (long long)r->ne, (long long)m->nv,
                   (long long)m->ne);
    return VM_EXIT_INPUT;
  }
  double vr = vm_mesh_signed_volume(r);
  if (!(vr != 0) || (vr < 0) != s->mirrored) {
    vm_cli_error(cli,
                 "%s: its total signed volume is %s, %s's %s: the two are not numbered the same "
                 "way round",
                 a->reference,
                 vr < 0   ? "negative"
                 : vr > 0 ? "positive"
                          : "0",
                 a->in, s->mirrored ? "negative" : "positive");
    return VM_EXIT_INPUT;
  }
  if (s->mirrored) negate_x(r);
  return VM_EXIT_OK;
}

/* IN, with its own flags saved. */
static int read_input(vm_cli *cli, const args *a, stage *s) {
  int64_t counts[VM_NTYPES];
  int rc;
  if (vm_mesh_read(cli->ctx, a->in, VM_FMT_AUTO, &s->m) < 0) return vm_cli_input_error(cli, NULL);
  vm_mesh *m = s->m;
  int tdim = vm_mesh_count_types(m, counts);
  if (tdim == 2 && (rc = to_plane(cli, a, s)) != VM_EXIT_OK) return rc;
  if (tdim != 3 && tdim != 2) {
    vm_cli_error(
        cli, "%s: no elements to optimize (tet, pyramid, prism, hex; tri, quad in a plane)", a->in);
    return VM_EXIT_INPUT;
  }
  if (tdim == 3 && vm_mesh_signed_volume(m) < 0) {
    /* the boundary encloses a negative volume: the cells are numbered the
     * other way round (a mirror's convention), not nearly all inverted;
     * the run takes the mesh mirrored, and the output gets its x back */
    s->mirrored = 1;
    negate_x(m);
    if (!cli->quiet)
      fprintf(stderr,
              "vm-volume: %s: the cells are numbered the other way round from VTK's convention "
              "(the total signed volume is negative): untangled and optimized in that "
              "orientation\n",
              a->in);
  }
  if (a->reference && (rc = read_reference(cli, a, s)) != VM_EXIT_OK) return rc;
  s->vflag0 = vm_malloc(cli->ctx, (size_t)m->nv + 1);
  s->vsurf0 = vm_alloc_array(cli->ctx, (size_t)m->nv + 1, sizeof *s->vsurf0);
  if (!s->vflag0 || !s->vsurf0) return vm_cli_input_error(cli, NULL);
  memcpy(s->vflag0, m->vflag, (size_t)m->nv);
  memcpy(s->vsurf0, m->vsurf, (size_t)m->nv * sizeof *s->vsurf0);
  return VM_EXIT_OK;
}

/* The report is made (or refused) before the run, with a copy of the input. */
static int open_report(vm_cli *cli, const args *a, stage *s) {
  char title[512];
  snprintf(title, sizeof title, "vm-volume: %s", a->in);
  int rc = vm_cli_report_open(cli, a->report_dir, title, &s->report, &s->hist);
  if (rc == VM_EXIT_OK && vm_mesh_clone(s->m, &s->before) < 0) rc = vm_cli_input_error(cli, NULL);
  return rc;
}

/* Flat elements left by the run (sj: the scaled Jacobian of every
 * element): of the top dimension, with a vertex the stage could move, and a
 * scaled Jacobian below --min-sj (elements whose vertices are all fixed are
 * the input's). */
static void flat_elements(const args *a, const vm_mesh *m, const double *sj, outcome *r) {
  r->flat = 0;
  r->flat_worst = -1;
  r->flat_sj = INFINITY;
  if (!(a->min_sj > 0)) return;
  for (int64_t e = 0; e < m->ne; e++) {
    /* inverted elements (sj < 0) are counted as such, not as flat */
    if (isnan(sj[e]) || !(sj[e] >= 0 && sj[e] < a->min_sj)) continue;
    int movable = 0;
    for (int64_t i = m->eoff[e]; i < m->eoff[e + 1]; i++)
      movable |= m->vflag[m->conn[i]] != VM_VERTEX_FIXED;
    if (!movable) continue;
    r->flat++;
    if (sj[e] < r->flat_sj) {
      r->flat_sj = sj[e];
      r->flat_worst = e;
    }
  }
  if (r->flat_worst >= 0) {
    int64_t e = r->flat_worst, n = m->eoff[e + 1] - m->eoff[e];
    for (int k = 0; k < 3; k++) {
      double c = 0;
      for (int64_t i = m->eoff[e]; i < m->eoff[e + 1]; i++)
        c += m->xyz[3 * (int64_t)m->conn[i] + k];
      r->flat_at[k] = c / (double)n;
    }
  }
}

/* An independent check of the result: every corner simplex (and the
 * geometric rule's simplices if that rule was used), the distance from the
 * slip surface. */
static int check_result(vm_cli *cli, const args *a, const stage *s, outcome *r) {
  vm_quality qg;
  vm_quality_opts qo = {VM_RULE_CORNER, a->o.target_size};
  double *sj = vm_alloc_array(cli->ctx, (size_t)s->m->ne + 1, sizeof *sj);
  if (!sj || vm_mesh_element_quality(s->m, &qo, &r->q, sj, NULL) < 0) {
    vm_free(cli->ctx, sj);
    return vm_cli_input_error(cli, NULL);
  }
  flat_elements(a, s->m, sj, r);
  vm_free(cli->ctx, sj);
  qo.rule = VM_RULE_GEOMETRIC;
  vm_mesh_quality(s->m, &qo, &qg);
  r->bad = r->q.all.inverted_nodes + (a->o.rule == VM_RULE_GEOMETRIC ? qg.all.inverted_nodes : 0);
  if (vm_mesh_jacobian_certify(s->m, &r->cert, NULL) < 0) return vm_cli_input_error(cli, NULL);
  if (s->slip && vm_volume_slip_distance(s->slip, s->m, &r->slip_dist) < 0)
    return vm_cli_input_error(cli, NULL);
  r->shape_dist = NAN;
  if (s->shape && (a->free_boundary || a->slip_boundary)) {
    if (vm_volume_shape_deviation(s->shape, s->m, &r->shape_dist, &r->shape_diag, r->shape_at) < 0)
      return vm_cli_input_error(cli, NULL);
    r->shape_moved = r->shape_dist > a->boundary_tol * r->shape_diag;
  }
  if (s->mirrored) {
    r->shape_at[0] = -r->shape_at[0];
    r->flat_at[0] = -r->flat_at[0];
  }
  if (s->planar) {
    /* where things are, said in the file's coordinates */
    double p[3];
    vm_plane_to_space(&s->plane, r->shape_at, p);
    memcpy(r->shape_at, p, sizeof p);
    vm_plane_to_space(&s->plane, r->flat_at, p);
    memcpy(r->flat_at, p, sizeof p);
  }
  return VM_EXIT_OK;
}

/* The options of one schedule: staged (hexahedra) or direct, both by
 * foldover (eps_inner 3, theta_untangle 0.999); `adaptive`: the adaptive
 * penalty instead, the fallback after a direct foldover run that stalled
 * (the 6-tet split of the n = 32 cube turned by pi about (0,1,1) is
 * certified by foldover after 21 s, while the adaptive penalty still had
 * 70,000 tets inverted after 200 s; docs/volume.md). What the user gave
 * stays. */
static vm_volume_opts schedule_opts(const args *a, int staged, int adaptive) {
  vm_volume_opts d = staged     ? vm_volume_opts_staged()
                     : adaptive ? vm_volume_opts_default()
                                : vm_volume_opts_direct(),
                 o = a->o;
  o.staged = staged;
  o.method = a->method >= 0 ? (vm_untangle_method)a->method : d.method;
  o.eps_inner = a->o.eps_inner ? a->o.eps_inner : d.eps_inner;
  o.theta_untangle = !isnan(a->o.theta_untangle) ? a->o.theta_untangle : d.theta_untangle;
  o.eps_cap = !isnan(a->o.eps_cap) ? a->o.eps_cap : d.eps_cap;
  o.qi_steps = a->o.qi_steps >= 0 ? a->o.qi_steps : d.qi_steps;
  return o;
}

static int has_type(const vm_mesh *m, int type) {
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] == type) return 1;
  return 0;
}

/* Volume elements not certified valid whose vertices are all fixed:
 * certified inverted, or degenerate (det J = 0 somewhere in it: not
 * certified either way, like Mesquite's hybrid_3quad_1tri_tangled.vtk,
 * whose three inner vertices coincide on the boundary). Nothing the stage
 * may move can make them valid. Their number; the first in *first, its
 * verdict in *verdict. */
static int64_t impossible_elements(const vm_mesh *m, int64_t *first, int *verdict) {
  int64_t n = 0, counts[VM_NTYPES];
  int tdim = vm_mesh_count_types(m, counts);
  *first = -1;
  *verdict = VM_JAC_VALID;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e], nv = (int)(m->eoff[e + 1] - m->eoff[e]), fixed = 1;
    if (vm_elem_dim(t) != tdim) continue;
    double x[3 * VM_MAX_ELEM_VERTS];
    for (int k = 0; k < nv; k++) {
      int32_t v = m->conn[m->eoff[e] + k];
      fixed &= m->vflag[v] == VM_VERTEX_FIXED;
      memcpy(x + 3 * k, m->xyz + 3 * (int64_t)v, sizeof(double) * 3);
    }
    if (!fixed) continue;
    int vd = vm_jacobian_certify(t, x, 0, NULL);
    if (vd == VM_JAC_VALID) continue;
    if (vd != VM_JAC_INVALID) {
      /* not a degenerate element where the input is bad: a vertex at two
       * corners, or coordinates whose determinants overflow (the stage
       * says what those are) */
      double ext = 0;
      for (int i = 0; i < nv; i++)
        for (int j = i + 1; j < nv; j++)
          for (int r = 0; r < 3; r++) ext = fmax(ext, fabs(x[3 * i + r] - x[3 * j + r]));
      if (vm_mesh_repeated_vertex(m, e) >= 0 || !isfinite(ext * ext * ext)) continue;
    }
    if (!n++) {
      *first = e;
      *verdict = vd;
    }
  }
  return n;
}

/* The file's own flags back on the mesh before it is written. */
static void restore_flags(stage *s) {
  memcpy(s->m->vflag, s->vflag0, (size_t)s->m->nv);
  memcpy(s->m->vsurf, s->vsurf0, (size_t)s->m->nv * sizeof *s->vsurf0);
}

/* An impossible problem: the input written unchanged to OUT (its own flags
 * back), exit 3. */
static int write_unchanged(vm_cli *cli, const args *a, stage *s) {
  restore_flags(s);
  int rc = write_mesh(cli, a, s);
  return rc == VM_EXIT_OK ? VM_EXIT_CHECK : rc;
}

/* Whether a fallback run that did not end valid ended worse than the
 * first: more cells not certified, or as many and more inverted nodes. */
static int worse_than(const vm_volume_report *fb, const vm_volume_report *first) {
  int64_t b = fb->cert_invalid + fb->cert_undecided,
          b0 = first->cert_invalid + first->cert_undecided;
  return b > b0 || (b == b0 && fb->M_final > first->M_final);
}

/* Add the other run's iterations, largest M and seconds to the report of
 * the run whose state is kept (a fallback run, or the first one when the
 * fallback ended worse). */
static void add_run(vm_volume_report *r, const vm_volume_report *other) {
  if (other->M_max > r->M_max) r->M_max = other->M_max;
  r->iter_untangle += other->iter_untangle;
  r->iter_local += other->iter_local;
  r->iter_opt += other->iter_opt;
  r->iter_repair += other->iter_repair;
  r->time_untangle += other->time_total;
  r->time_total += other->time_total;
}

/* Merge the report of a fallback run into the first one's. */
static void merge_reports(vm_volume_report *r, const vm_volume_report *first) {
  r->M_init = first->M_init;
  add_run(r, first);
  r->time_certified += first->time_total;
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-volume");
  vm_volume_opts d = vm_volume_opts_default();
  args a = {.o = d,
            .wo = vm_write_opts_default(),
            .fout = VM_FMT_AUTO,
            .every = 10,
            .method = -1,
            .feature_deg = 40,
            .corner_deg = 60,
            .boundary_tol = 0.01,
            .min_sj = 1e-5};
  a.o.eps_inner = 0; /* not given: the default, or --staged's, below */
  a.o.theta_untangle = NAN;
  a.o.eps_cap = NAN;
  a.o.qi_steps = -1;
  stage s = {0};
  outcome r = {0};
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  a.o.repair_geometric = a.repair == 0;
  a.o.repair_bernstein = a.repair != 2;
  if (a.o.staged && a.direct) {
    rc = vm_cli_usage_error(&cli, "--staged and --direct exclude each other");
    goto done;
  }
  if (a.reference && a.o.target_size > 0) {
    rc = vm_cli_usage_error(&cli, "--reference and --target-size exclude each other");
    goto done;
  }
  if (a.free_boundary && a.slip_boundary) {
    rc = vm_cli_usage_error(&cli, "--free-boundary and --slip-boundary exclude each other");
    goto done;
  }
  /* newton's full coupled Hessian stalls while elements are inverted (the
   * n = 16 rotated cube at pi: past 120 s where the default finishes in
   * 1.6 s): it optimizes, the untangling runs with the implicit solver */
  if (a.o.solver == VM_MINIMIZER_NEWTON) a.o.untangle_solver = VM_MINIMIZER_IMPLICIT;
  if (a.fout == VM_FMT_AUTO && vm_format_from_path(a.out) == VM_FMT_AUTO)
    a.fout = vm_format_from_path(a.in);
  if ((rc = vm_cli_volume_output(
           &cli, a.out, a.fout != VM_FMT_AUTO ? a.fout : vm_format_from_path(a.out))) != VM_EXIT_OK)
    goto done;
  if ((rc = read_input(&cli, &a, &s)) != VM_EXIT_OK ||
      (rc = boundary_conditions(&cli, &a, s.m, &s.slip)) != VM_EXIT_OK ||
      (a.report_dir && (rc = open_report(&cli, &a, &s)) != VM_EXIT_OK))
    goto done;
  /* the input's boundary: to measure how far a free or sliding one moved,
   * and to find fixed vertices outside a fixed or sliding one */
  if (vm_volume_shape_create(cli.ctx, s.m, &s.shape) < 0 && (a.free_boundary || a.slip_boundary)) {
    rc = vm_cli_input_error(&cli, a.in);
    goto done;
  }
  {
    int vd;
    int64_t first, nimp = impossible_elements(s.m, &first, &vd);
    if (nimp > 0) {
      /* fixed vertices force the fold: say so at once, the input written */
      vm_cli_error(&cli,
                   "%s: element %lld (%s) is %s and all its vertices are fixed (%lld "
                   "such elements): no motion of the others can untangle it; %s; %s written "
                   "unchanged",
                   a.in, (long long)first, vm_elem_name(s.m->etype[first]),
                   vd == VM_JAC_INVALID ? "inverted"
                                        : "degenerate (det J = 0 in it: it cannot be certified)",
                   (long long)nimp,
                   s.planar ? "--free-boundary lets boundary vertices move"
                            : "--slip-boundary lets boundary vertices slide (--free-boundary move)",
                   a.out);
      rc = write_unchanged(&cli, &a, &s);
      goto done;
    }
    /* a pre-check only: where it cannot answer (geometry beyond what the
     * AABB tree takes, e.g. coordinates near overflow) the run goes on and
     * says what is wrong itself */
    int64_t nout = 0;
    if (s.shape && !a.free_boundary &&
        vm_volume_shape_fixed_outside(s.shape, s.m, &nout, &first) < 0)
      nout = 0;
    if (nout > 0) {
      const double *x = s.m->xyz + 3 * first;
      vm_cli_error(&cli,
                   "%s: fixed vertex %lld at (%.6g, %.6g, %.6g) lies outside the %s boundary "
                   "(%lld such vertices): no motion of the others can untangle the mesh; "
                   "--free-boundary lets the boundary move; %s written unchanged",
                   a.in, (long long)first, s.mirrored ? -x[0] : x[0], x[1], x[2],
                   a.slip_boundary ? "sliding" : "fixed", (long long)nout, a.out);
      rc = write_unchanged(&cli, &a, &s);
      goto done;
    }
  }
  r.planar = s.planar;
  r.mirrored = s.mirrored;
  if (s.ref) a.o.target_xyz = s.ref->xyz;
  /* by default the schedule follows the mesh: staged where there are hexahedra */
  a.auto_schedule = !a.o.staged && !a.direct;
  r.staged = a.o.staged || (a.auto_schedule && has_type(s.m, VM_HEX));
  vm_volume_opts o = schedule_opts(&a, r.staged, 0);
  a.o.method = o.method;
  /* the first schedule chosen for the user gets a quarter of the iterations,
   * so that a stall (local rounds churning: the adaptive penalty on the
   * n = 8 pi/2 cube's 6-tet split spent all 20,000 and left 4 inverted,
   * which foldover untangles in 125) leaves the rest to the fallback */
  if (a.auto_schedule && o.max_iter >= 4) o.max_iter /= 4;
  progress_state ps = {&cli, a.every, NULL, s.hist};
  o.progress = progress;
  o.user = &ps;
  vm_cli_catch_interrupts(&cli);
  vm_surface_ops sops;
  if (s.slip) sops = vm_volume_slip_ops(s.slip);
  r.st = vm_volume_run(cli.ctx, s.m, s.slip ? &sops : NULL, &o, &r.rep);
  /* after staged, direct; after direct, the adaptive penalty */
  vm_volume_opts f = schedule_opts(&a, 0, !r.staged);
  int differs = r.staged || f.method != o.method || f.eps_inner != o.eps_inner ||
                f.theta_untangle != o.theta_untangle || f.eps_cap != o.eps_cap ||
                f.qi_steps != o.qi_steps;
  if (r.st == VM_WARN_INVERTED && r.rep.M_final > 0 && a.auto_schedule && differs &&
      !r.rep.timed_out) {
    /* the first schedule stalled with inverted nodes left (not the repair:
     * another untangling schedule would not help it): the other one, from
     * the best state */
    if (!cli.quiet)
      fprintf(stderr,
              "vm-volume: the %s schedule stalled with %lld inverted nodes left; going on "
              "from its best state with the direct schedule (%s)\n",
              r.staged ? "staged" : "direct", (long long)r.rep.M_final,
              vm_untangle_method_name(f.method));
    vm_volume_report first = r.rep;
    int first_st = r.st;
    /* the first run's state, kept if the fallback ends worse (the
     * staged run of vm-gen rotcube --n 32 --angle 3pi/4 --axis 1,2,3
     * --inner 0.3 left 2 cells not certified and 6 inverted corner tets;
     * the direct run from there ended with 20 cells) */
    size_t nx = (size_t)s.m->nv * 3;
    double *keep = vm_alloc_array(cli.ctx, nx ? nx : 1, sizeof *keep);
    if (!keep) {
      rc = vm_cli_input_error(&cli, NULL); /* out of memory, not the input's fault */
      goto done;
    }
    memcpy(keep, s.m->xyz, nx * sizeof *keep);
    f.progress = progress;
    f.user = &ps;
    if (o.time_limit > 0) f.time_limit = fmax(o.time_limit - first.time_total, 1e-3);
    f.max_iter = a.o.max_iter - first.iter_untangle - first.iter_local - first.iter_repair;
    if (f.max_iter < 1) f.max_iter = 1;
    r.st = vm_volume_run(cli.ctx, s.m, s.slip ? &sops : NULL, &f, &r.rep);
    r.fell_back = 1;
    if (r.st == VM_WARN_INVERTED && worse_than(&r.rep, &first)) {
      if (!cli.quiet)
        fprintf(stderr,
                "vm-volume: the fallback ended with %lld cells not certified and %lld inverted "
                "nodes, the %s schedule with %lld and %lld: its state is kept\n",
                (long long)(r.rep.cert_invalid + r.rep.cert_undecided), (long long)r.rep.M_final,
                r.staged ? "staged" : "direct",
                (long long)(first.cert_invalid + first.cert_undecided), (long long)first.M_final);
      memcpy(s.m->xyz, keep, nx * sizeof *keep);
      /* the counts of both runs, the final figures of the kept state */
      vm_volume_report fb = r.rep;
      r.rep = first;
      r.st = first_st;
      add_run(&r.rep, &fb);
      r.rep.timed_out = fb.timed_out;
    } else {
      merge_reports(&r.rep, &first);
      r.staged = 0;
      a.o.method = f.method;
    }
    vm_free(cli.ctx, keep);
  }
  if (r.st < 0 && r.st != VM_ERR_INTERRUPTED) {
    rc = vm_cli_input_error(&cli, a.in);
    goto done;
  }
  if ((rc = check_result(&cli, &a, &s, &r)) != VM_EXIT_OK) goto done;
  restore_flags(&s);
  if ((rc = write_mesh(&cli, &a, &s)) != VM_EXIT_OK) goto done;
  if ((rc = run_code(&r)) == VM_EXIT_OK) {
    /* before success is reported, vm-quality --verify's exact checks (CGAL
     * predicates, no arithmetic shared with the solver) on the written mesh */
    rc = vm_cli_verify(&cli, a.out, s.m, a.o.rule, 0, NULL);
    r.verified = rc == VM_EXIT_OK;
    if (r.verified && !cli.quiet)
      fprintf(stderr,
              "vm-volume: %s: verify: every quadrature simplex (%s rule) positively "
              "oriented (exact), every cell certified det J > 0\n",
              a.out, rules[a.o.rule]);
  }
  print_summary(&cli, &a, &r, rc);
  if (s.report) {
    int rrc = vm_cli_report_volume(&cli, &s.report, a.report_dir, a.in, a.out, s.before, s.m,
                                   s.hist, &a.o, &r.rep);
    if (rrc != VM_EXIT_OK && rc == VM_EXIT_OK) rc = rrc;
  }
  if (a.json) print_json(&a, &r, rc);
done:
  stage_free(cli.ctx, &s);
  vm_cli_finish(&cli);
  return rc;
}
