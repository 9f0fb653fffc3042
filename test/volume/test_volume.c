/* test/volume/test_volume.c: the volume stage on generated tangled meshes:
 * rotated cubes of hexes, tets and mixed cells untangle to M = 0, fixed
 * vertices stay bit-identical, every untangling method, determinism, and a
 * problem that cannot be untangled ends promptly with the best state. */
#include <math.h>
#include <string.h>
#include <time.h>

#include "varmesh/rotcube.h"
#include "varmesh/quality.h"
#include "varmesh/volume.h"
#include "vmtest.h"

static const double PI = 3.14159265358979323846;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Global solver of untangle_case. */
static vm_minimizer_kind case_solver = VM_MINIMIZER_IMPLICIT;
/* theta of the penalty while untangling (0: the optimization's) */
static double case_theta_untangle = 0;
/* iterations per eps of the foldover rule (0: the default) */
static int case_eps_inner = 0;
/* vm_volume_opts.staged */
static int case_staged = 0;

/* Untangle a generated rotated cube; check validity with the independent
 * quality code and that fixed vertices did not move by a single bit. */
static void untangle_case(vm_ctx *ctx, const char *name, int n, double frac, int cells,
                          vm_untangle_method method, int rule, double *phi_out) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = n;
  ro.alpha = frac * PI;
  ro.cells = cells;
  vm_mesh *m;
  double *ref;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m, &ref) == VM_OK, "%s: generate", name);
  vm_mesh *before;
  vm_mesh_clone(m, &before);
  vm_volume_opts o = vm_volume_opts_default();
  o.method = method;
  o.rule = rule;
  o.target_xyz = ref;
  /* a guard against hangs, not a speed test: sanitizer builds on a busy
   * machine are 10-20x slower than the figures in the comments */
  o.time_limit = 900;
  o.solver = case_solver;
  o.theta_untangle = case_theta_untangle;
  if (case_eps_inner > 0) o.eps_inner = case_eps_inner;
  o.staged = case_staged;
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  if (case_staged)
    CHECK(r.split_valid && r.split_M_init > 0 && r.split_M_max >= r.split_M_init &&
              r.time_split <= r.time_untangle,
          "%s: the split was tangled (M %lld, max %lld) and untangled first (%.2f s of %.2f)", name,
          (long long)r.split_M_init, (long long)r.split_M_max, r.time_split, r.time_untangle);
  CHECK(st == VM_OK, "%s: status %d (%s), M %lld -> %lld", name, st, vm_ctx_error(ctx),
        (long long)r.M_init, (long long)r.M_final);
  CHECK(r.M_init > 0, "%s: the problem is tangled (M_init %lld)", name, (long long)r.M_init);
  CHECK(r.valid && r.M_final == 0, "%s: valid", name);
  vm_quality q;
  vm_quality_opts qo = {rule, 1.0 / n};
  vm_mesh_quality(m, &qo, &q);
  CHECK(q.all.inverted_nodes == 0 && q.all.phi_min > 0, "%s: independent check: M %lld phi %g",
        name, (long long)q.all.inverted_nodes, q.all.phi_min);
  int64_t moved_fixed = 0, moved_free = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int same = !memcmp(m->xyz + 3 * v, before->xyz + 3 * v, 3 * sizeof(double));
    if (m->vflag[v] == VM_VERTEX_FIXED)
      moved_fixed += !same;
    else
      moved_free += !same;
  }
  CHECK(moved_fixed == 0, "%s: %lld fixed vertices moved", name, (long long)moved_fixed);
  CHECK(moved_free > 0, "%s: free vertices moved", name);
  fprintf(stderr,
          "%-28s M %5lld -> 0 (max %5lld), %4d + %4d local + %4d opt iterations, "
          "phi_min %.3e psi_min %.3e, %.2f s\n",
          name, (long long)r.M_init, (long long)r.M_max, r.iter_untangle, r.iter_local, r.iter_opt,
          r.phi_min, r.psi_min, r.time_total);
  if (phi_out) *phi_out = r.phi_min;
  vm_free(ctx, ref);
  vm_mesh_destroy(&before);
  vm_mesh_destroy(&m);
}

/* A Galerkin coarse level of AMG can lose its positive diagonal on the
 * indefinite Hessians of a hard untangling (here the 6-tet split at 7pi/8,
 * n = 16, theta_untangle 0.999, no local rounds: "amg: non-positive
 * diagonal -6.2e+09 in row 51 of level 2" ended the run after 672
 * iterations). The implicit solver then takes that step with Jacobi and
 * goes on. */
static int jacobi_steps;
static void count_fallback(void *user, int level, const char *msg) {
  (void)user;
  (void)level;
  if (strstr(msg, "this step uses Jacobi")) jacobi_steps++;
}

static void amg_fallback(vm_ctx *ctx) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = 16;
  ro.alpha = 0.875 * PI;
  ro.cells = VM_GEN_TETS;
  vm_mesh *m;
  double *ref;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m, &ref) == VM_OK, "amg fallback: generate");
  vm_volume_opts o = vm_volume_opts_default();
  o.target_xyz = ref;
  o.theta_untangle = 0.999;
  o.local_threshold = 0;
  o.max_iter = 700;
  o.opt_iter = 0;
  o.time_limit = 900;
  jacobi_steps = 0;
  vm_ctx_set_log(ctx, count_fallback, NULL);
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  vm_ctx_set_log(ctx, NULL, NULL);
  CHECK(st >= 0, "amg fallback: the run ends without an error (status %d: %s)", st,
        vm_ctx_error(ctx));
  CHECK(jacobi_steps > 0, "amg fallback: a step used Jacobi (%d)", jacobi_steps);
  fprintf(stderr, "amg fallback: %d steps with Jacobi, %d iterations, M %lld -> %lld, status %d\n",
          jacobi_steps, r.iter_untangle, (long long)r.M_init, (long long)r.M_final, st);
  vm_free(ctx, ref);
  vm_mesh_destroy(&m);
}

/* Node determinants of `rule` on the rotated cube (hex or 6 tets per hex). */
static double *cube_dets(vm_ctx *ctx, int cells, int rule, int64_t *nn) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = 4;
  ro.alpha = 2.0;
  ro.cells = cells;
  vm_mesh *m;
  vm_problem *P;
  double *d = NULL;
  *nn = 0;
  if (vm_gen_rotated_cube(ctx, &ro, &m, NULL)) return NULL;
  /* a jiggle so that no two nodes agree by symmetry */
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] != VM_VERTEX_FIXED)
      for (int k = 0; k < 3; k++) m->xyz[3 * v + k] += 0.01 * sin(1.7 * (double)v + k);
  if (vm_problem_create(ctx, m, &P) == VM_OK) {
    if (vm_problem_set_rule(P, (vm_rule)rule) == VM_OK &&
        vm_problem_set_target_ideal(P, 0.25) == VM_OK) {
      *nn = vm_problem_num_nodes(P);
      d = vm_alloc_array(ctx, (size_t)*nn, sizeof *d);
      if (d && vm_problem_node_dets(P, m->xyz, d) < 0) *nn = 0;
    }
    vm_problem_destroy(&P);
  }
  vm_mesh_destroy(&m);
  return d;
}

/* The split rule of a hex mesh is its 6-tet split, node by node (the
 * generator's --tets mesh: same vertices, the same 6 tets per cube in the
 * same order); the guarded rules are the base rule's nodes then the split's. */
static void split_rules(vm_ctx *ctx) {
  int64_t nt, ns, nc, ncs, ng, ngs;
  double *t = cube_dets(ctx, VM_GEN_TETS, VM_RULE_CORNER, &nt);
  double *sp = cube_dets(ctx, VM_GEN_HEX, VM_RULE_SPLIT, &ns);
  double *c = cube_dets(ctx, VM_GEN_HEX, VM_RULE_CORNER, &nc);
  double *cs = cube_dets(ctx, VM_GEN_HEX, VM_RULE_CORNER_SPLIT, &ncs);
  double *g = cube_dets(ctx, VM_GEN_HEX, VM_RULE_GEOMETRIC, &ng);
  double *gs = cube_dets(ctx, VM_GEN_HEX, VM_RULE_GEOMETRIC_SPLIT, &ngs);
  CHECK(nt == 64 * 6 && ns == nt && nc == 64 * 8 && ncs == 64 * 14 && ng == 64 * 64 &&
            ngs == 64 * 70,
        "split rules: node counts %lld %lld %lld %lld %lld %lld", (long long)nt, (long long)ns,
        (long long)nc, (long long)ncs, (long long)ng, (long long)ngs);
  if (nt == 64 * 6 && ns == nt && nc == 64 * 8 && ncs == 64 * 14 && ng == 64 * 64 &&
      ngs == 64 * 70) {
    int64_t bad = 0, neg = 0;
    for (int64_t q = 0; q < nt; q++) {
      /* the ideal tet and the cube's Kuhn tet differ in T: compare signs and
       * ratios, the same for every node of the mesh */
      neg += sp[q] <= 0;
      if (fabs(sp[q] / t[q] - sp[0] / t[0]) > 1e-9 * fabs(sp[0] / t[0])) bad++;
    }
    CHECK(bad == 0, "split rule = the 6-tet split: %lld of %lld nodes differ", (long long)bad,
          (long long)nt);
    CHECK(neg > 0, "the test problem is tangled (%lld split nodes inverted)", (long long)neg);
    int64_t bc = 0, bg = 0;
    for (int64_t e = 0; e < 64; e++) {
      for (int q = 0; q < 8; q++) bc += cs[14 * e + q] != c[8 * e + q];
      for (int q = 0; q < 6; q++) bc += cs[14 * e + 8 + q] != sp[6 * e + q];
      for (int q = 0; q < 64; q++) bg += gs[70 * e + q] != g[64 * e + q];
      for (int q = 0; q < 6; q++) bg += gs[70 * e + 64 + q] != sp[6 * e + q];
    }
    CHECK(bc == 0 && bg == 0, "guarded rules: base nodes then split nodes (%lld, %lld differ)",
          (long long)bc, (long long)bg);
  }
  vm_free(ctx, t);
  vm_free(ctx, sp);
  vm_free(ctx, c);
  vm_free(ctx, cs);
  vm_free(ctx, g);
  vm_free(ctx, gs);
}

/* The foldover rule's cap (opts eps_cap) on the n = 12 pi cube with an
 * inner cube of half-size 0.3 (golden case volume-staged): where a
 * block of the guarded stage or of the geometric phase's global rounds
 * ends with a node inverted, the next eps is at most eps_cap |min det| of
 * that mesh (not below the run's restart floor, opts eps_restart, in a
 * restarted local round). The split stage is left to the rule alone.
 * Read from the progress records: a record's min det is the mesh after its
 * step, so the next record of the same phase, one iteration on, carries
 * the eps chosen at that mesh. */
typedef struct {
  vm_volume_progress prev;
  int have;
  int64_t checked, above;
  int64_t geo_checked, geo_above; /* of those, the geometric phase's */
  int64_t split_above;            /* the split stage's new eps above |min det| */
  double floor;                   /* opts eps_restart */
  double worst;                   /* the largest eps / max(|min det|, floor) */
} cap_watch;

static void watch_cap(void *user, const vm_volume_progress *p) {
  cap_watch *w = user;
  /* a new eps chosen at a mesh with a node inverted */
  int new_eps = w->have && !strcmp(p->phase, w->prev.phase) && p->iter == w->prev.iter + 1 &&
                w->prev.min_det < 0 && p->eps != w->prev.eps;
  if (new_eps && !strcmp(p->phase, "split"))
    w->split_above += p->eps > -w->prev.min_det * (1 + 1e-12);
  int geo = !strcmp(p->phase, "geometric");
  if (new_eps && (geo || !strcmp(p->phase, "guarded"))) {
    double bound = fmax(-w->prev.min_det, w->floor);
    int up = p->eps > bound * (1 + 1e-12);
    w->checked++;
    w->above += up;
    w->geo_checked += geo;
    w->geo_above += geo && up;
    if (p->eps / bound > w->worst) w->worst = p->eps / bound;
  }
  w->prev = *p;
  w->have = 1;
}

static void eps_cap(vm_ctx *ctx) {
  int64_t above[2] = {0, 0}, geo_above[2] = {0, 0};
  for (int k = 0; k < 2; k++) {
    vm_rotcube_opts ro = vm_rotcube_opts_default();
    ro.n = 12;
    ro.alpha = PI;
    ro.inner = 0.3;
    vm_mesh *m;
    double *ref;
    CHECK(vm_gen_rotated_cube(ctx, &ro, &m, &ref) == VM_OK, "eps cap: generate");
    vm_volume_opts o = vm_volume_opts_staged();
    CHECK(o.eps_cap == 1 && vm_volume_opts_direct().eps_cap == 1,
          "eps cap: 1 in the foldover schedules");
    o.eps_cap = k ? 0 : 1;
    o.target_xyz = ref;
    /* the rule, not the outcome: the first 600 iterations and the repair */
    o.max_iter = 600;
    o.time_limit = 900;
    cap_watch w = {.floor = o.eps_restart};
    o.progress = watch_cap;
    o.user = &w;
    vm_volume_report r;
    int st = vm_volume_run(ctx, m, NULL, &o, &r);
    CHECK(st >= 0 || st == VM_WARN_INVERTED, "eps cap %g: status %d (%s)", o.eps_cap, st,
          vm_ctx_error(ctx));
    CHECK(w.checked > 20, "eps cap %g: %lld new eps with a node inverted", o.eps_cap,
          (long long)w.checked);
    above[k] = w.above;
    geo_above[k] = w.geo_above;
    CHECK(w.geo_checked >= 2, "eps cap %g: the geometric phase's new eps (%lld)", o.eps_cap,
          (long long)w.geo_checked);
    if (!k)
      CHECK(w.split_above > 0, "eps cap 1: the split stage is not capped (%lld new eps above)",
            (long long)w.split_above);
    fprintf(stderr,
            "eps cap %g: %lld of %lld new eps of the guarded stage and the geometric phase above "
            "max(|min det|, %g) (the phase's: %lld of %lld), at most %.3g times (the split's: %lld "
            "above); %d + %d + %d repair iterations\n",
            o.eps_cap, (long long)w.above, (long long)w.checked, w.floor, (long long)w.geo_above,
            (long long)w.geo_checked, w.worst, (long long)w.split_above, r.iter_untangle,
            r.iter_local, r.iter_repair);
    vm_free(ctx, ref);
    vm_mesh_destroy(&m);
  }
  CHECK(above[0] == 0, "eps cap 1: no eps above the cap (%lld)", (long long)above[0]);
  /* the records can show the rule: without it they do go above */
  CHECK(above[1] > 0, "eps cap 0: eps above |min det| somewhere (%lld)", (long long)above[1]);
  CHECK(geo_above[1] > 0, "eps cap 0: the geometric phase's eps above |min det| (%lld)",
        (long long)geo_above[1]);
}

/* The same run twice gives the same bits. */
static void determinism(vm_ctx *ctx) {
  double *xs[2];
  int64_t nv = 0;
  for (int k = 0; k < 2; k++) {
    vm_rotcube_opts ro = vm_rotcube_opts_default();
    ro.alpha = PI / 2;
    vm_mesh *m;
    double *ref;
    vm_gen_rotated_cube(ctx, &ro, &m, &ref);
    vm_ctx_set_threads(ctx, k + 1);
    vm_volume_opts o = vm_volume_opts_default();
    o.target_xyz = ref;
    vm_volume_run(ctx, m, NULL, &o, NULL);
    nv = m->nv;
    xs[k] = vm_malloc(ctx, sizeof(double) * 3 * (size_t)nv);
    memcpy(xs[k], m->xyz, sizeof(double) * 3 * (size_t)nv);
    vm_free(ctx, ref);
    vm_mesh_destroy(&m);
  }
  vm_ctx_set_threads(ctx, 0);
  CHECK(!memcmp(xs[0], xs[1], sizeof(double) * 3 * (size_t)nv),
        "1 and 2 threads give identical coordinates");
  vm_free(ctx, xs[0]);
  vm_free(ctx, xs[1]);
}

/* A hex mirrored through its fixed vertices cannot be untangled: the only
 * free vertex cannot reach an admissible place. The run must end promptly,
 * report the inverted simplices, and keep the fixed vertices. */
static void impossible(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  static const double p[8][3] = {{0, 0, 0},  {1, 0, 0},  {1, 1, 0},  {0, 1, 0},
                                 {0, 0, -1}, {1, 0, -1}, {1, 1, -1}, {0.5, 0.5, -0.5}};
  for (int i = 0; i < 8; i++) vm_mesh_add_vertex(m, p[i][0], p[i][1], p[i][2], NULL);
  static const int32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  vm_mesh_add_element(m, VM_HEX, hex);
  for (int i = 0; i < 7; i++) m->vflag[i] = VM_VERTEX_FIXED;
  double before[21];
  memcpy(before, m->xyz, sizeof before);
  vm_volume_opts o = vm_volume_opts_default();
  o.target_size = 1;
  o.time_limit = 20;
  vm_volume_report r;
  double t0 = now();
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  double dt = now() - t0;
  CHECK(st == VM_WARN_INVERTED, "impossible: status %d (%s)", st, vm_ctx_error(ctx));
  CHECK(!r.valid && r.M_final > 0 && r.M_final <= 8, "impossible: M_final %lld",
        (long long)r.M_final);
  CHECK(dt < 10, "impossible: ended promptly (%.2f s)", dt);
  CHECK(!memcmp(before, m->xyz, sizeof before), "impossible: fixed vertices unchanged");
  fprintf(stderr, "impossible hex: ended after %.2f s with M %lld (status %d)\n", dt,
          (long long)r.M_final, st);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  long live0 = vm_ctx_alloc_live(ctx);
  double phi_corner, phi_geom;
  untangle_case(ctx, "hex n=8 pi/2", 8, 0.5, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE, VM_RULE_CORNER,
                &phi_corner);
  untangle_case(ctx, "hex n=8 pi/2 geometric", 8, 0.5, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_GEOMETRIC, &phi_geom);
  untangle_case(ctx, "hex n=8 3pi/8 penalty (35)", 8, 0.375, VM_GEN_HEX, VM_UNTANGLE_PENALTY,
                VM_RULE_CORNER, NULL);
  untangle_case(ctx, "hex n=8 pi/2 one-way", 8, 0.5, VM_GEN_HEX, VM_UNTANGLE_PENALTY_ONEWAY,
                VM_RULE_CORNER, NULL);
  untangle_case(ctx, "tets n=8 pi/2", 8, 0.5, VM_GEN_TETS, VM_UNTANGLE_ADAPTIVE, VM_RULE_CORNER,
                NULL);
  untangle_case(ctx, "mixed n=8 pi/8", 8, 0.125, VM_GEN_MIXED, VM_UNTANGLE_ADAPTIVE, VM_RULE_CORNER,
                NULL);
  untangle_case(ctx, "hex n=12 3pi/8", 12, 0.375, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE, VM_RULE_CORNER,
                NULL);
  untangle_case(ctx, "hex n=8 pi/2 foldover", 8, 0.5, VM_GEN_HEX, VM_UNTANGLE_FOLDOVER,
                VM_RULE_CORNER, NULL);
  untangle_case(ctx, "tets n=8 pi/2 foldover", 8, 0.5, VM_GEN_TETS, VM_UNTANGLE_FOLDOVER,
                VM_RULE_CORNER, NULL);
  case_theta_untangle = 0.95;
  untangle_case(ctx, "hex n=8 pi/2 theta_u 0.95", 8, 0.5, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_CORNER, NULL);
  /* the last folds used to stay (2 left after 60 s): the foldover rule
   * drove eps to 1e-11, far below |min det|, and the local rounds could no
   * longer move them; a stalled local round now restarts eps */
  case_theta_untangle = 0.999;
  case_eps_inner = 3;
  untangle_case(ctx, "tets n=16 7pi/8 foldover", 16, 0.875, VM_GEN_TETS, VM_UNTANGLE_FOLDOVER,
                VM_RULE_CORNER, NULL);
  /* the pi cube, which no direct schedule untangles as hexes: its split
   * first, then the corner tets with the split held valid (n = 16: ~11 s) */
  case_staged = 1;
  untangle_case(ctx, "hex n=16 pi staged", 16, 1.0, VM_GEN_HEX, VM_UNTANGLE_FOLDOVER,
                VM_RULE_CORNER, NULL);
  case_staged = 0;
  case_eps_inner = 0;
  case_theta_untangle = 0;
  case_solver = VM_MINIMIZER_NEWTON;
  untangle_case(ctx, "hex n=8 pi/2 newton", 8, 0.5, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_CORNER, NULL);
  untangle_case(ctx, "tets n=8 pi/2 newton", 8, 0.5, VM_GEN_TETS, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_CORNER, NULL);
  untangle_case(ctx, "hex n=12 3pi/8 newton", 12, 0.375, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_CORNER, NULL);
  case_solver = VM_MINIMIZER_IMPLICIT;
  split_rules(ctx);
  eps_cap(ctx);
  determinism(ctx);
  impossible(ctx);
  amg_fallback(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leak: %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  vm_ctx_destroy(&ctx);
  return vmtest_end("volume");
}
