/* test/volume/test_volume.c: the volume stage on generated tangled meshes:
 * rotated cubes of hexes, tets and mixed cells untangle to M = 0, fixed
 * vertices stay bit-identical, every untangling method, determinism, and a
 * problem that cannot be untangled ends promptly with the best state. */
#include <math.h>
#include <string.h>
#include <time.h>

#include "varmesh/generate.h"
#include "varmesh/quality.h"
#include "varmesh/untangle.h"
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
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
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
  fprintf(stderr, "%-28s M %5lld -> 0 (max %5lld), %4d + %4d local + %4d opt iterations, "
          "phi_min %.3e psi_min %.3e, %.2f s\n", name, (long long)r.M_init, (long long)r.M_max,
          r.iter_untangle, r.iter_local, r.iter_opt, r.phi_min, r.psi_min, r.time_total);
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
  static const double p[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
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
  untangle_case(ctx, "mixed n=8 pi/8", 8, 0.125, VM_GEN_MIXED, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_CORNER, NULL);
  untangle_case(ctx, "hex n=12 3pi/8", 12, 0.375, VM_GEN_HEX, VM_UNTANGLE_ADAPTIVE,
                VM_RULE_CORNER, NULL);
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
  determinism(ctx);
  impossible(ctx);
  amg_fallback(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leak: %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  vm_ctx_destroy(&ctx);
  return vmtest_end("volume");
}
