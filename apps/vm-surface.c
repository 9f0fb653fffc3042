/* apps/vm-surface.c: the surface stage: repair an imported surface,
 * remesh it uniformly when it needs it, compute its mean curvature and
 * adapt the mesh to it with the 2D functional (20); or any step alone. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "cli_report.h"
#include "varmesh/io.h"
#include "varmesh/surface.h"

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

typedef struct {
  const char *in, *out, *report_dir;
  int json, fout, every, edge_length_given;
  int triangles;       /* --triangles, 0: not given */
  int size;            /* -1: not given */
  double c_abs, c_rel; /* --c, --c-rel: < 0 if not given */
  vm_surface_opts so;
  vm_write_opts wo;
} args;

static int opt_symmetry(vm_cli *cli, const vm_opt *opt, const char *val, void *a) {
  vm_symmetry_opts *y = &((args *)a)->so.symmetry;
  if (vm_axis_plane_parse(cli->ctx, val, &y->axis, &y->value, NULL))
    return vm_cli_usage_error(cli, "%s %s", opt->name, vm_ctx_error(cli->ctx));
  y->given = 1;
  return VM_EXIT_OK;
}

static int opt_edge_length(vm_cli *cli, const vm_opt *opt, const char *val, void *a) {
  double x;
  if (vm_cli_double(cli, opt->name, val, 0, 1e300, &x)) return VM_EXIT_USAGE;
  if (!(x > 0)) return vm_cli_usage_error(cli, "%s must be positive", opt->name);
  ((args *)a)->so.remesh_opts.target_edge_length = x;
  ((args *)a)->edge_length_given = 1;
  return VM_EXIT_OK;
}

#define A(f) offsetof(args, f)
static const char *const steps[] = {"all", "repair", "remesh", "curvature", "adapt", NULL};
static const char *const tri[] = {"auto", "yes", "no", NULL};
static const char *const sizes[] = {"input", "uniform", "graded", "curvature", NULL};
static const vm_opt opts[] = {
    {"--repair", NULL, VM_OPT_CHOICE, A(so.repair), NULL,
     "repair the input (auto: for .stl .obj .off .ply inputs, and always for the steps all, "
     "repair and remesh)",
     .choices = tri},
    {"--open-ok", NULL, VM_OPT_FLAG, A(so.repair_opts.require_closed), NULL,
     "accept an open surface (borders become feature lines)", .ival = 0},
    {"--symmetry", NULL, VM_OPT_CALL, 0, "AXIS=C",
     "the input is a half model whose open border lies in the plane x, y or z = C (refused, "
     "saying where, if a border vertex is farther than 1e-6 of the diagonal from it); by default "
     "an open input whose border lies in one such plane is taken as a half model, said on "
     "stderr. Its border stays open and in the plane bit for bit through every step (a feature "
     "line); the output carries the attribute symmetry_plane",
     .fn = opt_symmetry},
    {"--no-union", NULL, VM_OPT_FLAG, A(so.repair_opts.union_overlaps), NULL,
     "no union of closed parts: overlapping ones are refused, one inside another is a cavity "
     "(by default the repair replaces them by their union: an assembly's wing through its "
     "fuselage, a part hidden inside)",
     .ival = 0},
    {"--no-heal", NULL, VM_OPT_FLAG, A(so.repair_opts.heal_self), NULL,
     "a closed part that intersects itself is refused (by default its crossing faces are "
     "removed and the holes filled, if that moves the surface by less than twice the local "
     "edge length)",
     .ival = 0},
    {"--no-intersection-check", NULL, VM_OPT_FLAG, A(so.repair_opts.check_self_intersections), NULL,
     "skip the self-intersection check of the repair", .ival = 0},
    {"--remesh", NULL, VM_OPT_CHOICE, A(so.remesh), NULL,
     "remeshing in 'all' (auto: if the smallest angle is below --sliver-angle)", .choices = tri},
    {"--size", NULL, VM_OPT_CHOICE, A(size), NULL,
     "what the remeshing keeps: input (default: the input's vertices and grading, slivers "
     "removed by edge flips and collapses; where needles under --needle-angle are left, "
     "curvature instead; named, always the input's vertices); graded (isotropic remeshing to the "
     "input's own "
     "local edge lengths, grown by at most 25 % per edge length); curvature (isotropic "
     "remeshing to sizes from the curvature, about the input's number of triangles); uniform "
     "(isotropic remeshing to one edge length, CGAL; the default with --target-edge-length). "
     "Every one ends with the same sliver removal; a remeshing that loses a tip, folds or "
     "intersects is given up for input, with a warning",
     .choices = sizes},
    {"--triangles", NULL, VM_OPT_INT, A(triangles), "N",
     "about N triangles: the sizes of graded, curvature and uniform scaled to it (default: "
     "graded as the input, curvature and uniform the input's count)",
     .lo = 4, .hi = 2e9},
    {"--cone-angle", NULL, VM_OPT_DOUBLE, A(so.adapt.cone_angle), "DEG",
     "angle deficit of a cone point (a tip), kept like a corner (default 60; 360: none)",
     .lo = 1e-6, .hi = 360},
    {"--sliver-angle", NULL, VM_OPT_DOUBLE, A(so.sliver_angle), "DEG", "(default 15)", .lo = 1e-6,
     .hi = 180},
    {"--needle-angle", NULL, VM_OPT_DOUBLE, A(so.needle_angle), "DEG",
     "without --size: triangles under this angle left after the sliver removal make the "
     "stage remesh by the curvature (default 1; 0: never)",
     .lo = 0, .hi = 60},
    {"--target-edge-length", NULL, VM_OPT_CALL, 0, "L",
     "uniform remeshing edge length (default: the mean edge length)", .fn = opt_edge_length},
    {"--remesh-iter", NULL, VM_OPT_INT, A(so.remesh_opts.iterations), "N",
     "remeshing iterations (default 5)", .lo = 1, .hi = 1e8},
    {"--feature-angle", NULL, VM_OPT_DOUBLE, A(so.adapt.feature_angle), "DEG",
     "dihedral angle of a sharp edge (default 20)", .lo = 1e-6, .hi = 180},
    {"--corner-angle", NULL, VM_OPT_DOUBLE, A(so.adapt.corner_angle), "DEG",
     "turning angle of a feature line at a corner (default 50)", .lo = 1e-6, .hi = 180},
    {"--c", NULL, VM_OPT_DOUBLE, A(c_abs), "C",
     "metric G = (1 + C|H|) I, C a length (default 4 h, h the mean edge length); overrides --c-rel",
     .lo = 0, .hi = 1e300},
    {"--c-rel", NULL, VM_OPT_DOUBLE, A(c_rel), "K", "C = K h", .lo = 0, .hi = 1e300},
    {"--threshold", NULL, VM_OPT_DOUBLE, A(so.adapt.filter.threshold), "T",
     "|H| < T -> 0 (default 4/D, D the bounding box diagonal)", .lo = 0, .hi = 1e300},
    {"--cap", NULL, VM_OPT_DOUBLE, A(so.adapt.filter.cap), "X", "|H| > X -> X (default 1/h)",
     .lo = 0, .hi = 1e300},
    {"--smooth", NULL, VM_OPT_INT, A(so.adapt.filter.smooth), "N",
     "smoothing passes of the curvature (default 2)", .lo = 0, .hi = 1e8},
    {"--iter", NULL, VM_OPT_INT, A(so.adapt.max_iter), "N",
     "adaptation iterations in all (default 200)", .lo = 0, .hi = 1e8},
    {"--rounds", NULL, VM_OPT_INT, A(so.adapt.rounds), "N",
     "metric / normal updates during adaptation (default 5)", .lo = 1, .hi = 1e8},
    {"--theta", NULL, VM_OPT_DOUBLE, A(so.adapt.theta), "T",
     "balanced measure weight (default 0.8)", .lo = 0, .hi = 1},
    {"--implicit", NULL, VM_OPT_FLAG, A(so.adapt.implicit), NULL,
     "implicit minimizer instead of the explicit one", .ival = 1},
    {"--time-limit", NULL, VM_OPT_DOUBLE, A(so.adapt.time_limit), "S", "seconds for the adaptation",
     .lo = 0, .hi = 1e300},
    {"--ortho-sweeps", NULL, VM_OPT_INT, A(so.ortho.sweeps), "N",
     "step all, last: sweeps of the wall's finite-volume orthogonality relief (vertices "
     "slide on the surface where the line joining two triangles' centroids leans from their "
     "edge's normal, as a prism layer's side faces inherit it; default 8; 0: measured only)",
     .lo = 0, .hi = 1000},
    {"--wrap", NULL, VM_OPT_DOUBLE, A(so.wrap), "F",
     "first put a closed, manifold surface around the input (CGAL's alpha wrapping: no ball "
     "of F times the bounding box's diagonal passes between it and the input; it lies R F of "
     "the diagonal outside, R the --wrap-offset); by default only a model the repair refuses as "
     "non-manifold or crossing itself, or left with needles, is wrapped (F 0.005), said on "
     "stderr; 0: never (such a model is refused)",
     .lo = 0, .hi = 1},
    {"--wrap-offset", NULL, VM_OPT_DOUBLE, A(so.wrap_offset), "R",
     "how far outside the input the wrap lies, a fraction of its alpha (default 0.2: the wrap's "
     "triangles stay well shaped where it rounds a sharp edge or the rim of a thin sheet; "
     "smaller follows the input more closely, with caps and needles there)",
     .lo = 1e-6, .hi = 1},
    VM_CLI_OPT_THREADS,
    {"--format", NULL, VM_OPT_CALL, A(fout), "F", "output format", .fn = vm_cli_opt_format},
    {"--binary", NULL, VM_OPT_FLAG, A(wo.binary), NULL, "binary output where the format has both",
     .ival = 1},
    {"--progress-every", NULL, VM_OPT_INT, A(every), "N",
     "a progress line every N iterations (default 20)", .lo = 1, .hi = 1e8},
    {"--report", NULL, VM_OPT_STRING, A(report_dir), "DIR",
     "write DIR/index.html with pictures: convergence of the adaptation (F per iteration), "
     "quality histograms, the surface coloured by its (filtered) mean curvature",
     .error = "expects a directory"},
    {"--json", NULL, VM_OPT_FLAG, A(json), NULL, "JSON summary on stdout", .ival = 1},
    VM_CLI_OPT_QUIET("no progress"),
    VM_CLI_OPT_VERBOSE("debug messages too"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-surface [STEP] [options] IN OUT\n"
    "The surface stage. STEP is one of\n"
    "  all        (default) repair -> remesh (if needed) -> curvature -> adapt ->\n"
    "             orthogonality relief of the wall\n"
    "  repair     repair only\n"
    "  remesh     repair -> slivers removed (--size uniform: isotropic remeshing first)\n"
    "  curvature  mean curvature fields only\n"
    "  adapt      curvature -> curvature-adapted node movement (no remeshing)\n"
    "OUT is written in the format of its extension (.vmsh keeps the curvature fields\n"
    "'mean_curvature' and 'mean_curvature_filtered').\n",
    opts,
    "exit: 0 done; 1 bad input (what is wrong and where is printed) or I/O; 2 usage;\n"
    "3 the result has flipped elements or intersects itself (checked exactly; written);\n"
    "4 interrupted (last iterate written)\n",
    {A(in), A(out)},
    2,
    "need IN and OUT"};

static double wall_seconds(void) {
  struct timespec ts;
  timespec_get(&ts, TIME_UTC);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* One deviation figure of the summary: "<pre>rel", "<pre>abs", "<pre>at". */
static void json_deviation(const char *pre, double rel, double abs, const double at[3]) {
  printf("\"%srel\": ", pre);
  vm_json_double(stdout, rel);
  printf(", \"%sabs\": ", pre);
  vm_json_double(stdout, abs);
  printf(", \"%sat\": ", pre);
  vm_json_doubles(stdout, at, 3);
}

static void print_json(const args *a, const vm_mesh *m, const vm_surface_summary *s, int rc,
                       double t0) {
  const vm_repair_report *rr = &s->repair;
  const vm_adapt_result *ar = &s->adapt;
  printf("{\"input\": ");
  vm_json_string(stdout, a->in);
  printf(", \"output\": ");
  vm_json_string(stdout, a->out);
  printf(", \"step\": \"%s\", \"exit\": %d, \"vertices\": %lld, \"faces\": %lld",
         vm_surface_step_name(a->so.step), rc, (long long)m->nv, (long long)m->ne);
  if (s->repaired) {
    printf(", \"repair\": {\"vertices\": %lld, \"faces\": %lld, \"merged_vertices\": %lld, "
           "\"removed_faces\": %lld, \"removed_degenerate\": %lld, \"removed_isolated\": %lld, "
           "\"reoriented\": %lld, \"stitched\": %lld, \"border_edges\": %lld, \"holes\": %lld, "
           "\"components\": %lld, \"self_intersections\": %lld, \"united\": %lld, "
           "\"union_pairs\": %lld, \"healed\": %lld, \"heal_pairs\": %lld, \"volume\": ",
           (long long)rr->nv, (long long)rr->nf, (long long)rr->merged_vertices,
           (long long)rr->removed_polygons, (long long)rr->removed_degenerate,
           (long long)rr->removed_isolated, (long long)rr->reoriented, (long long)rr->stitched,
           (long long)rr->border_edges, (long long)rr->holes, (long long)rr->components,
           (long long)rr->self_intersections, (long long)rr->united, (long long)rr->union_pairs,
           (long long)rr->healed, (long long)rr->heal_pairs);
    vm_json_double(stdout, rr->volume);
    printf("}");
  }
  if (s->symmetry.found) {
    char pl[64];
    printf(", \"symmetry\": {\"plane\": \"%s\", \"axis\": \"%c\", \"value\": ",
           vm_axis_plane_format(s->symmetry.axis, s->symmetry.value, pl, sizeof pl),
           'x' + s->symmetry.axis);
    vm_json_double(stdout, s->symmetry.value);
    printf(", \"given\": %s, \"side\": %d, \"border_edges_in\": %lld, \"loops_in\": %lld, "
           "\"border_vertices_in\": %lld, \"snapped_in\": %lld, \"max_offset_in\": ",
           s->symmetry.given ? "true" : "false", s->symmetry.side,
           (long long)s->symmetry.border_edges, (long long)s->symmetry.loops,
           (long long)s->symmetry.border_vertices, (long long)s->symmetry.snapped);
    vm_json_double(stdout, s->symmetry.max_offset);
    printf(", \"border_vertices\": %lld, \"off_plane\": %lld, \"resnapped\": %lld, "
           "\"drift\": ",
           (long long)s->symmetry_border, (long long)s->symmetry_off,
           (long long)s->symmetry_resnapped);
    vm_json_double(stdout, s->symmetry_drift);
    printf(", \"reoriented\": %s}", s->symmetry_reoriented ? "true" : "false");
  }
  printf(", \"size\": \"%s\", \"needles\": %lld, \"remeshed\": %s",
         s->size_used == VM_SURFACE_SIZE_UNIFORM     ? "uniform"
         : s->size_used == VM_SURFACE_SIZE_GRADED    ? "graded"
         : s->size_used == VM_SURFACE_SIZE_CURVATURE ? "curvature"
                                                     : "input",
         (long long)s->needles_in, s->remeshed ? "true" : "false");
  {
    const vm_unblind_report *u = &s->unblind;
    printf(", \"unblind\": {\"folded_in\": %lld, \"folded\": %lld, \"collapses\": %lld, "
           "\"flips\": %lld, \"caps_in\": %lld, \"caps\": %lld, \"cap_flips\": %lld, "
           "\"undone\": %s, \"moved\": ",
           (long long)u->blind_in, (long long)u->blind, (long long)u->collapses,
           (long long)u->flips, (long long)u->caps_in, (long long)u->caps, (long long)u->cap_flips,
           u->undone ? "true" : "false");
    vm_json_double(stdout, u->max_dev);
    printf("}");
  }
  if (s->remeshed && s->size_used == VM_SURFACE_SIZE_UNIFORM) {
    printf(", \"target_edge_length\": ");
    vm_json_double(stdout, s->target_edge_length);
  }
  if (s->remeshed && s->size_used != VM_SURFACE_SIZE_UNIFORM) {
    const vm_graded_report *g = &s->graded;
    printf(", \"graded\": {\"vertices_in\": %lld, \"vertices\": %lld, \"faces_in\": %lld, "
           "\"faces\": %lld, \"splits\": %lld, \"collapses\": %lld, \"flips\": %lld, "
           "\"moves\": %lld, \"size_min\": ",
           (long long)g->nv_in, (long long)g->nv, (long long)g->nf_in, (long long)g->nf,
           (long long)g->splits, (long long)g->collapses, (long long)g->flips, (long long)g->moves);
    vm_json_double(stdout, g->h_min);
    printf(", \"size_max\": ");
    vm_json_double(stdout, g->h_max);
    printf(", \"min_angle_in\": ");
    vm_json_double(stdout, g->min_angle_in);
    printf(", \"min_angle\": ");
    vm_json_double(stdout, g->min_angle);
    printf("}");
  }
  if (s->cleaned) {
    const vm_cleanup_report *c = &s->cleanup;
    printf(", \"slivers\": {\"flips\": %lld, \"collapses\": %lld, \"vertices_in\": %lld, "
           "\"vertices\": %lld, \"faces_in\": %lld, \"faces\": %lld, \"below_in\": %lld, "
           "\"below\": %lld, \"cones\": %lld, \"min_angle_in\": ",
           (long long)c->flips, (long long)c->collapses, (long long)c->nv_in, (long long)c->nv,
           (long long)c->nf_in, (long long)c->nf, (long long)c->below_in, (long long)c->below,
           (long long)s->cones);
    vm_json_double(stdout, c->min_angle_in);
    printf(", \"min_angle\": ");
    vm_json_double(stdout, c->min_angle);
    printf(", \"min_angle_free_in\": ");
    vm_json_double(stdout, c->min_angle_free_in);
    printf(", \"min_angle_free\": ");
    vm_json_double(stdout, c->min_angle_free);
    printf(", \"max_dev\": ");
    vm_json_double(stdout, c->max_dev);
    printf("}");
  }
  if (s->curvature) {
    printf(", \"curvature\": {\"min\": ");
    vm_json_double(stdout, s->curvature_stats.min);
    printf(", \"max\": ");
    vm_json_double(stdout, s->curvature_stats.max);
    printf(", \"mean_abs\": ");
    vm_json_double(stdout, s->curvature_stats.mean_abs);
    printf(", \"threshold\": ");
    vm_json_double(stdout, s->threshold);
    printf(", \"cap\": ");
    vm_json_double(stdout, s->cap);
    printf(", \"degenerate\": %lld, \"boundary\": %lld}", (long long)s->curvature_stats.degenerate,
           (long long)s->curvature_stats.boundary);
  }
  if (s->adapted) {
    printf(", \"adapt\": {\"iterations\": %d, \"rounds\": %d, \"stop\": \"%s\", \"F_initial\": ",
           ar->iterations, ar->rounds, ar->stop);
    vm_json_double(stdout, ar->F_initial);
    printf(", \"F\": ");
    vm_json_double(stdout, ar->F);
    printf(", \"c\": ");
    vm_json_double(stdout, ar->c);
    printf(", \"threshold\": ");
    vm_json_double(stdout, ar->threshold);
    printf(", \"cap\": ");
    vm_json_double(stdout, ar->cap);
    printf(", \"smooth_vertices\": %lld, \"line_vertices\": %lld, \"fixed_vertices\": %lld, "
           "\"lines\": %d, \"corners\": %lld, \"flipped\": %lld, \"min_angle_before\": ",
           (long long)ar->nsmooth, (long long)ar->nline_vertices, (long long)ar->nfixed, ar->nline,
           (long long)ar->ncorner, (long long)ar->flipped);
    vm_json_double(stdout, ar->min_angle_before);
    printf(", \"min_angle_after\": ");
    vm_json_double(stdout, ar->min_angle_after);
    printf(", \"max_distance\": ");
    vm_json_double(stdout, ar->max_distance);
    printf(", \"angle_floor\": ");
    vm_json_double(stdout, s->angle_floor);
    printf(", \"held_back_vertices\": %lld", (long long)s->angle_restored);
    printf(", \"time\": ");
    vm_json_double(stdout, ar->elapsed);
    printf("}");
  }
  if (s->wrapped) {
    printf(", \"wrap\": {\"auto\": %s, \"faces_in\": %lld, \"faces\": %lld, \"vertices\": %lld, "
           "\"alpha\": ",
           s->wrap_auto ? "true" : "false", (long long)s->wrap.nf_in, (long long)s->wrap.nf,
           (long long)s->wrap.nv);
    vm_json_double(stdout, s->wrap.alpha);
    printf(", \"offset\": ");
    vm_json_double(stdout, s->wrap.offset);
    printf(", \"time\": ");
    vm_json_double(stdout, s->wrap.elapsed);
    printf("}");
  }
  if (s->ortho_ran) {
    const vm_ortho2d_result *o = &s->ortho;
    printf(", \"ortho\": {\"edges\": %lld, \"over70_before\": %lld, \"over70_after\": %lld, "
           "\"over60_before\": %lld, \"over60_after\": %lld, \"max_before\": ",
           (long long)o->edges, (long long)o->over70_before, (long long)o->over70_after,
           (long long)o->over60_before, (long long)o->over60_after);
    vm_json_double(stdout, o->max_before);
    printf(", \"max_after\": ");
    vm_json_double(stdout, o->max_after);
    printf(", \"steps\": %lld, \"sweeps\": %d, \"moved\": %lld, \"undone\": %s, "
           "\"max_shift\": ",
           (long long)o->moves, o->sweeps, (long long)o->moved, s->ortho_undone ? "true" : "false");
    vm_json_double(stdout, o->max_shift);
    printf(", \"time\": ");
    vm_json_double(stdout, o->elapsed);
    printf("}");
  }
  printf(", \"opposing\": %lld, \"remesh_lost_corners\": %lld, \"remesh_opposing\": %lld",
         (long long)s->opposing, (long long)s->remesh_lost_corners, (long long)s->remesh_opposing);
  printf(", \"self_intersections\": %lld, \"remesh_refused_pairs\": %lld, "
         "\"folds_found\": %lld, \"backed_off_vertices\": %lld",
         (long long)s->self_intersections, (long long)s->remesh_refused, (long long)s->folds_found,
         (long long)s->adapt_backed_off);
  if (s->deviation_measured) {
    printf(", \"deviation\": {");
    json_deviation("", s->deviation_rel, s->deviation_abs, s->deviation_at);
    printf(", ");
    json_deviation("feature_", s->deviation_feature_rel, s->deviation_feature_abs,
                   s->deviation_feature_at);
    printf(", \"feature_vertices\": %lld, \"corners_moved\": %lld}",
           (long long)s->deviation_features, (long long)s->corners_moved);
  }
  printf(", \"min_angle\": ");
  vm_json_double(stdout, vm_surface_min_angle(m));
  printf(", \"time\": ");
  vm_json_double(stdout, wall_seconds() - t0);
  printf("}\n");
}

/* The report's table of the run; the page's figures and its exit code. */
static int write_report(vm_cli *cli, vm_report **report, vm_report_history *hist, const args *a,
                        const vm_mesh *m, const vm_surface_summary *s) {
  const vm_repair_report *rr = &s->repair;
  const vm_adapt_result *ar = &s->adapt;
  int st = vm_report_heading(*report, "run");
  if (st >= 0) st = vm_report_row(*report, "input, output", "%s, %s", a->in, a->out);
  if (st >= 0)
    st = vm_report_row(*report, "step; vertices, faces", "%s; %lld, %lld",
                       vm_surface_step_name(a->so.step), (long long)m->nv, (long long)m->ne);
  if (st >= 0 && s->repaired)
    st = vm_report_row(*report, "repair",
                       "merged %lld points, removed %lld invalid/duplicate and %lld "
                       "degenerate faces, reoriented %lld, stitched %lld edges; %s, %lld "
                       "components, %lld self-intersections; %lld overlapping or nested "
                       "components united",
                       (long long)rr->merged_vertices, (long long)rr->removed_polygons,
                       (long long)rr->removed_degenerate, (long long)rr->reoriented,
                       (long long)rr->stitched, rr->border_edges ? "open" : "closed",
                       (long long)rr->components, (long long)rr->self_intersections,
                       (long long)rr->united);
  if (st >= 0 && s->symmetry.found) {
    char pl[64];
    st = vm_report_row(*report, "half model",
                       "symmetry plane %s (%s); %lld border vertices in it bit for bit (%lld in "
                       "the input, %lld put onto it); %lld off it",
                       vm_axis_plane_format(s->symmetry.axis, s->symmetry.value, pl, sizeof pl),
                       s->symmetry.given ? "given" : "found", (long long)s->symmetry_border,
                       (long long)s->symmetry.border_vertices, (long long)s->symmetry.snapped,
                       (long long)s->symmetry_off);
  }
  if (st >= 0 && s->remeshed)
    st = vm_report_row(
        *report, "remeshed", "%s%s%.3g, %lld -> %lld vertices", sizes[s->size_used],
        s->size_used == VM_SURFACE_SIZE_UNIFORM ? ", target edge length " : ", sizes from ",
        s->size_used == VM_SURFACE_SIZE_UNIFORM ? s->target_edge_length : s->graded.h_min,
        (long long)s->nv_before_remesh, (long long)s->cleanup.nv_in);
  if (st >= 0 && s->cleaned)
    st =
        vm_report_row(*report, "slivers removed",
                      "%lld flips, %lld collapses; triangles under %g deg %lld -> %lld; smallest "
                      "angle %.2f -> %.2f deg (away from feature corners %.2f -> %.2f); %lld "
                      "cone points kept",
                      (long long)s->cleanup.flips, (long long)s->cleanup.collapses,
                      a->so.sliver_angle, (long long)s->cleanup.below_in,
                      (long long)s->cleanup.below, s->cleanup.min_angle_in, s->cleanup.min_angle,
                      s->cleanup.min_angle_free_in, s->cleanup.min_angle_free, (long long)s->cones);
  if (st >= 0 && s->adapted)
    st = vm_report_row(*report, "adaptation",
                       "%d iterations in %d rounds (%s), F %.6e -> %.6e; c %g; %lld flipped; "
                       "max distance to the input %g; %.2f s",
                       ar->iterations, ar->rounds, ar->stop, ar->F_initial, ar->F, ar->c,
                       (long long)ar->flipped, ar->max_distance, ar->elapsed);
  if (st >= 0 && s->ortho_ran) {
    const vm_ortho2d_result *o = &s->ortho;
    st = vm_report_row(*report, "wall orthogonality relief",
                       "edges beyond 70 deg %lld -> %lld (beyond 60: %lld -> %lld) of %lld, "
                       "largest %.1f -> %.1f deg; %lld vertices moved%s",
                       (long long)o->over70_before, (long long)o->over70_after,
                       (long long)o->over60_before, (long long)o->over60_after, (long long)o->edges,
                       o->max_before, o->max_after, (long long)o->moved,
                       s->ortho_undone ? " (undone: it intersected)" : "");
  }
  if (st >= 0)
    st = vm_report_row(*report, "exact check of the result",
                       "%lld intersecting triangle pairs%s; remeshing given up: %s; folds of "
                       "the adaptation taken back: %lld pairs, %lld vertices",
                       (long long)s->self_intersections,
                       s->self_intersections < 0 ? " (not checked: quads)" : "",
                       s->remesh_refused ? "yes" : "no", (long long)s->folds_found,
                       (long long)s->adapt_backed_off);
  if (st >= 0 && s->deviation_measured)
    st = vm_report_row(*report, "deviation from the input (of the local edge length)",
                       "%.3g (%g); at %lld feature vertices %.3g (%g); corners and tips moved: "
                       "%lld",
                       s->deviation_rel, s->deviation_abs, (long long)s->deviation_features,
                       s->deviation_feature_rel, s->deviation_feature_abs,
                       (long long)s->corners_moved);
  if (st >= 0)
    st = vm_report_row(*report, "smallest angle: input, output", "%.2f, %.2f deg",
                       s->min_angle_input, vm_surface_min_angle(m));
  return vm_cli_report_result(cli, report, a->report_dir, st, "surface", m, NULL, hist,
                              "Convergence of the adaptation: the functional (20) F per "
                              "iteration (the metric and normals are updated between "
                              "rounds, so F jumps there); dashed lines separate the "
                              "rounds.");
}

int main(int argc, char **argv) {
  double t0 = wall_seconds();
  vm_cli cli;
  vm_cli_init(&cli, "vm-surface");
  args a = {.so = vm_surface_opts_default(),
            .wo = vm_write_opts_default(),
            .fout = VM_FMT_AUTO,
            .every = 20,
            .c_abs = -1,
            .c_rel = -1,
            .size = -1};
  vm_mesh *m = NULL;
  vm_report *report = NULL;
  vm_report_history *hist = NULL;
  vm_surface_summary s;
  int k = 0; /* the STEP, if the first argument is one */
  while (argc > 1 && steps[k] && strcmp(argv[1], steps[k])) k++;
  int skip = argc > 1 && steps[k];
  if (skip) a.so.step = (vm_surface_step)k;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1 - skip, argv + 1 + skip);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  if (a.c_rel >= 0) a.so.adapt.c = -a.c_rel;
  if (a.c_abs >= 0) a.so.adapt.c = a.c_abs;
  a.so.size = a.size >= 0           ? a.size
              : a.edge_length_given ? VM_SURFACE_SIZE_UNIFORM
                                    : VM_SURFACE_SIZE_INPUT;
  /* --size input named: the input's own vertices, needles or not */
  if (a.size == VM_SURFACE_SIZE_INPUT) a.so.needle_angle = 0;
  if (a.so.size != VM_SURFACE_SIZE_UNIFORM && a.edge_length_given)
    vm_log(cli.ctx, VM_LOG_WARN,
           "--target-edge-length has no effect with --size %s (it is the uniform size)",
           sizes[a.so.size]);
  if (a.triangles > 0) {
    if (a.so.size == VM_SURFACE_SIZE_INPUT && a.so.needle_angle <= 0)
      vm_log(cli.ctx, VM_LOG_WARN, "--triangles has no effect with --size input");
    a.so.triangles = a.triangles;
  }
  /* a remeshing asked for by name runs whatever the smallest angle */
  if (a.so.remesh == VM_SURFACE_AUTO && a.so.size != VM_SURFACE_SIZE_INPUT &&
      (a.size >= 0 || a.edge_length_given || a.triangles > 0))
    a.so.remesh = VM_SURFACE_YES;
  if (a.fout == VM_FMT_AUTO && vm_format_from_path(a.out) == VM_FMT_AUTO)
    a.fout = vm_format_from_path(a.in);
  if (a.report_dir) { /* made (or refused) before the run */
    char title[512];
    snprintf(title, sizeof title, "vm-surface %s: %s", steps[a.so.step], a.in);
    if ((rc = vm_cli_report_open(&cli, a.report_dir, title, &report, &hist)) != VM_EXIT_OK)
      goto done;
  }
  if (vm_mesh_read(cli.ctx, a.in, VM_FMT_AUTO, &m) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 2 || m->dim != 3) {
    vm_cli_error(&cli,
                 "%s: not a surface mesh in 3D (it needs triangles or quads and "
                 "nothing else)",
                 a.in);
    rc = VM_EXIT_INPUT;
    goto done;
  }
  vm_mesh_apply_fixed_field(m);
  a.so.soup = vm_cli_soup_format(a.in);
  if (!cli.quiet)
    fprintf(stderr, "vm-surface: %s: %lld vertices, %lld faces\n", a.in, (long long)m->nv,
            (long long)m->ne);
  progress_state ps = {&cli, a.every, hist};
  a.so.adapt.monitor = progress;
  a.so.adapt.user = &ps;
  /* every step: an interrupt during the repair or the remeshing ends the
   * run after it (exit 4, the mesh so far written) */
  vm_cli_catch_interrupts(&cli);
  int st = vm_surface_run(cli.ctx, m, &a.so, &s);
  if (st < 0 && st != VM_ERR_INTERRUPTED) {
    vm_cli_error(&cli, "%s: %s%s", a.in, vm_ctx_error(cli.ctx),
                 s.open ? " (--open-ok accepts it)" : "");
    rc = VM_EXIT_INPUT;
    goto done;
  }
  rc = (s.adapted && s.adapt.flipped > 0) || s.self_intersections > 0 ? VM_EXIT_CHECK
       : st == VM_ERR_INTERRUPTED                                     ? VM_EXIT_INTERRUPTED
                                                                      : VM_EXIT_OK;
  if (vm_mesh_write(cli.ctx, m, a.out, a.fout, &a.wo) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  if (!cli.quiet)
    fprintf(stderr,
            "vm-surface: wrote %s: %lld vertices, %lld faces, smallest angle %.2f deg; "
            "%.2f s\n",
            a.out, (long long)m->nv, (long long)m->ne, vm_surface_min_angle(m),
            wall_seconds() - t0);
  if (a.json) print_json(&a, m, &s, rc, t0);
  if (report) {
    int rrc = write_report(&cli, &report, hist, &a, m, &s);
    if (rrc != VM_EXIT_OK && rc == VM_EXIT_OK) rc = rrc;
  }
done:
  vm_report_destroy(&report);
  vm_report_history_destroy(&hist);
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
