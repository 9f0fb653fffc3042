/* test/solver/test_control.c: the minimizer driver: barrier measures never
 * accept a step out of the admissible set, an untangling schedule (39)
 * through the before_iteration hook, stop reasons and statuses, 1 vs 2
 * threads, allocation failures. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshgen.h"
#include "varmesh/minimize.h"
#include "vmtest.h"

typedef struct {
  vm_problem *p;
  int calls, hook_calls;
  int bad;          /* iterations ending outside the admissible set */
  double eps;       /* current barrier epsilon */
  double sigma;     /* (39) */
  int stop_at;      /* hook: stop (> 0) at this iteration */
  int fail_at;      /* hook: fail at this iteration */
  int interrupt_at; /* monitor: raise the interrupt flag */
  volatile int flag;
  int last_iter;
  int short_steps; /* iterations whose line search backtracked */
  int infeasible;  /* trial points rejected as outside the domain */
} ctl;

static void monitor(void *user, const vm_iter_info *in) {
  ctl *c = user;
  c->calls++;
  c->last_iter = in->iter;
  if (in->tau < 1) c->short_steps++;
  c->infeasible += in->ls_infeasible;
  /* admissible: det + eps > 0 at every node */
  if (!(in->min_det + c->eps > 0) || !isfinite(in->F)) c->bad++;
  if (c->interrupt_at && in->iter == c->interrupt_at) c->flag = 1;
}

/* (39): eps^{l+1} = max(delta0, eps^l - sigma (eps^l - |min(det, 0)|)). */
static int hook(void *user, int iter, const double *x) {
  ctl *c = user;
  c->hook_calls++;
  if (c->stop_at && iter == c->stop_at) return 1;
  if (c->fail_at && iter == c->fail_at) return VM_ERR_NUMERIC;
  if (c->sigma > 0) {
    vm_node_stats st;
    vm_problem_node_stats(c->p, x, &st);
    double neg = st.min_det < 0 ? -st.min_det : 0;
    double e = c->eps - c->sigma * (c->eps - neg);
    c->eps = e > 1e-11 ? e : 1e-11;
    vm_measure_params prm = *vm_problem_params(c->p);
    prm.eps = c->eps;
    vm_problem_set_params(c->p, &prm);
  }
  return 0;
}

static vm_mesh *jittered_cube(vm_ctx *ctx, int n, double amp) {
  vm_mesh *m = NULL;
  gen_cube(ctx, n, 0, &m);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  jitter_free(ctx, m, amp / n, 3);
  return m;
}

/* A strongly graded cube (x -> x^3 per coordinate) with the barrier form
 * at eps = 0 (the balanced measure's domain): full steps leave the domain
 * and are rejected, every accepted iterate keeps det > 0. */
static void test_barrier_admissible(vm_ctx *ctx, vm_minimizer_kind kind) {
  vm_mesh *m = jittered_cube(ctx, 6, 0);
  for (int64_t i = 0; i < 3 * m->nv; i++) m->xyz[i] = pow(m->xyz[i], 3);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  vm_measure_params prm = vm_measure_params_default();
  prm.eps = 0;
  vm_problem_set_measure(p, VM_MEASURE_BARRIER, &prm);
  vm_node_stats ns;
  vm_problem_node_stats(p, m->xyz, &ns);
  CHECK(ns.inverted == 0, "start must be admissible (%lld inverted)", (long long)ns.inverted);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, kind, &mn);
  ctl c;
  memset(&c, 0, sizeof c);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 100;
  o.monitor = monitor;
  o.user = &c;
  o.ls_extrapolate = 3;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  printf("barrier %-8s its %d F %.6g -> %.10g min det %.3g (start %.3g) backtracked %d, "
         "%d trial points outside\n",
         vm_minimizer_name(mn), r.iterations, r.F_initial, r.F, r.min_det, ns.min_det,
         c.short_steps, c.infeasible);

  CHECK(st >= 0, "run %d: %s", st, vm_ctx_error(ctx));
  CHECK(c.calls == r.iterations && c.calls > 0, "monitor calls %d", c.calls);
  CHECK(c.bad == 0, "%d iterates left the admissible set", c.bad);
  CHECK(r.inverted == 0 && r.min_det > 0 && r.F < r.F_initial, "final min det %g", r.min_det);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* One free vertex whose target (reference) quads are nearly degenerate:
 * full Newton steps from the uniform start cross the barrier, the line
 * search rejects those trial points and the vertex still reaches its
 * target position. */
static void test_barrier_rejects(vm_ctx *ctx, vm_minimizer_kind kind) {
  vm_mesh *m = NULL;
  gen_square(ctx, 2, 0, &m);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  double ref[27];
  memcpy(ref, m->xyz, sizeof ref);
  ref[12] = ref[13] = 0.26;
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  CHECK(vm_problem_set_target_reference(p, ref) == VM_OK, "target: %s", vm_ctx_error(ctx));
  vm_measure_params prm = vm_measure_params_default();
  vm_problem_set_measure(p, VM_MEASURE_BARRIER, &prm);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, kind, &mn);
  ctl c;
  memset(&c, 0, sizeof c);
  vm_minimize_options o = vm_minimize_options_default();
  o.monitor = monitor;
  o.user = &c;
  o.rel_decrease_tol = 0;
  o.grad_rtol = 1e-12;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  printf("barrier rejects %-8s its %d  %d trial points outside  x = (%.9f, %.9f)\n",
         vm_minimizer_name(mn), r.iterations, c.infeasible, m->xyz[12], m->xyz[13]);
  CHECK(st == VM_OK, "run %d", st);
  /* the diagonal methods overshoot; Newton's full step may stay inside */
  CHECK(c.infeasible > 0 || kind == VM_MINIMIZER_NEWTON, "no trial point was outside the domain");
  CHECK(c.bad == 0, "%d iterates left the admissible set", c.bad);
  CHECK(fabs(m->xyz[12] - 0.26) < 1e-7 && fabs(m->xyz[13] - 0.26) < 1e-7, "target not reached");
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* A tangled cube untangled by the barrier with admissible-set contraction
 * (39) driven from the hook; every iterate stays in det + eps > 0. */
static void test_untangle_hook(vm_ctx *ctx, vm_minimizer_kind kind) {
  const int n = 6;
  vm_mesh *m = jittered_cube(ctx, n, 0.1);
  /* push an interior vertex through its neighbour */
  int64_t v = 3 + 7 * (3 + 7 * 3);
  m->xyz[3 * v] += 1.3 / n;
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  vm_node_stats ns;
  vm_problem_node_stats(p, m->xyz, &ns);
  CHECK(ns.inverted > 0 && ns.min_det < 0, "tangled start (%lld inverted)", (long long)ns.inverted);
  ctl c;
  memset(&c, 0, sizeof c);
  c.p = p;
  c.eps = 1.5 * fabs(ns.min_det);
  c.sigma = 0.5;
  vm_measure_params prm = vm_measure_params_default();
  prm.eps = c.eps;
  vm_problem_set_measure(p, VM_MEASURE_BARRIER, &prm);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, kind, &mn);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 60;
  o.rel_decrease_tol = 0;
  o.monitor = monitor;
  o.before_iteration = hook;
  o.user = &c;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  printf("untangle %-8s its %d  inverted %lld -> %lld  min det %.3g -> %.3g  eps %.2g  "
         "backtracked %d  reason %s\n",
         vm_minimizer_name(mn), r.iterations, (long long)ns.inverted, (long long)r.inverted,
         ns.min_det, r.min_det, c.eps, c.short_steps, vm_stop_reason_name(r.reason));
  CHECK(st >= 0, "run %d: %s", st, vm_ctx_error(ctx));
  CHECK(c.hook_calls >= r.iterations, "hook calls %d", c.hook_calls);
  CHECK(c.bad == 0, "%d iterates left det + eps > 0", c.bad);
  CHECK(r.inverted == 0 && r.min_det > 0, "still %lld inverted", (long long)r.inverted);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

static int run_small(vm_ctx *ctx, vm_minimize_options *o, vm_minimize_result *r) {
  vm_mesh *m = jittered_cube(ctx, 5, 0.2);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, VM_MINIMIZER_IMPLICIT, &mn);
  CHECK(vm_minimizer_set_options(mn, o) == VM_OK, "options");
  int st = vm_minimizer_run(mn, m->xyz, r);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
  return st;
}

static void test_stops(vm_ctx *ctx) {
  vm_minimize_options o = vm_minimize_options_default();
  vm_minimize_result r;
  ctl c;
  memset(&c, 0, sizeof c);
  o.user = &c;

  o.max_iter = 2;
  CHECK(run_small(ctx, &o, &r) == VM_WARN_MAXITER, "max iter status");
  CHECK(r.reason == VM_STOP_MAX_ITER && r.iterations == 2, "max iter: %s %d",
        vm_stop_reason_name(r.reason), r.iterations);

  o.max_iter = 100;
  o.time_limit = 1e-9;
  CHECK(run_small(ctx, &o, &r) == VM_WARN_TIME, "time status");
  CHECK(r.reason == VM_STOP_TIME, "time: %s", vm_stop_reason_name(r.reason));
  o.time_limit = 0;

  o.before_iteration = hook;
  c.stop_at = 3;
  CHECK(run_small(ctx, &o, &r) == VM_OK, "hook stop status");
  CHECK(r.reason == VM_STOP_CALLBACK && r.iterations == 2 && c.hook_calls == 3,
        "hook stop: %s its %d calls %d", vm_stop_reason_name(r.reason), r.iterations, c.hook_calls);
  c.stop_at = 0;
  c.fail_at = 2;
  CHECK(run_small(ctx, &o, &r) == VM_ERR_NUMERIC, "hook error passed through");
  c.fail_at = 0;
  o.before_iteration = NULL;

  o.monitor = monitor;
  c.interrupt_at = 2;
  c.flag = 0;
  vm_ctx_set_interrupt(ctx, &c.flag);
  CHECK(run_small(ctx, &o, &r) == VM_ERR_INTERRUPTED, "interrupt status");
  CHECK(r.reason == VM_STOP_INTERRUPTED && r.iterations == 2, "interrupt: %s %d",
        vm_stop_reason_name(r.reason), r.iterations);
  vm_ctx_set_interrupt(ctx, NULL);
  o.monitor = NULL;

  o.grad_rtol = 1e-3;
  CHECK(run_small(ctx, &o, &r) == VM_OK && r.reason == VM_STOP_GRAD_NORM, "grad stop: %s",
        vm_stop_reason_name(r.reason));
  o.grad_rtol = 0;
  o.rel_decrease_tol = 1e-4;
  CHECK(run_small(ctx, &o, &r) == VM_OK && r.reason == VM_STOP_REL_DECREASE, "rel stop: %s",
        vm_stop_reason_name(r.reason));

  o = vm_minimize_options_default();
  o.pcg_rtol = 2;
  vm_mesh *m = jittered_cube(ctx, 2, 0);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  vm_minimizer *mn = NULL;
  CHECK(vm_minimizer_create(ctx, p, (vm_minimizer_kind)7, &mn) == VM_ERR_ARG, "bad kind");
  vm_minimizer_create(ctx, p, VM_MINIMIZER_EXPLICIT, &mn);
  CHECK(vm_minimizer_set_options(mn, &o) == VM_ERR_ARG, "bad option accepted");
  /* a tangled start outside the balanced measure's domain is refused */
  m->xyz[3 * 13] += 0.9;
  double *x = malloc((size_t)m->nv * 3 * sizeof *x);
  memcpy(x, m->xyz, (size_t)m->nv * 3 * sizeof *x);
  CHECK(vm_minimizer_run(mn, x, &r) == VM_ERR_ARG, "inverted start accepted");
  free(x);
  vm_minimizer_destroy(&mn);
  CHECK(mn == NULL, "destroy sets NULL");
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* Local work through the hook: at iteration 3 only the elements with a
 * vertex below z = 0.3 stay active (the other vertices get zero rows and
 * drop out of the implicit systems: they must not move), at iteration 6
 * all are active again. */
typedef struct {
  vm_problem *p;
  uint8_t *mask;
  double *x3; /* x at the start of iteration 3 */
  int64_t n3;
  int moved;            /* vertices outside the active part that moved in 3..5 */
  const uint8_t *touch; /* per vertex: in an active element */
  int calls;
} mask_ctl;

static int mask_hook(void *user, int iter, const double *x) {
  mask_ctl *c = user;
  c->calls++;
  if (iter == 3) {
    memcpy(c->x3, x, (size_t)c->n3 * sizeof *x);
    return vm_problem_set_active(c->p, c->mask);
  }
  if (iter == 6) {
    for (int64_t v = 0; v < c->n3 / 3; v++)
      if (!c->touch[v] && memcmp(x + 3 * v, c->x3 + 3 * v, 3 * sizeof *x) != 0) c->moved++;
    return vm_problem_set_active(c->p, NULL);
  }
  return 0;
}

static void test_active_mask(vm_ctx *ctx) {
  vm_mesh *m = jittered_cube(ctx, 8, 0.2);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  uint8_t *mask = calloc((size_t)m->ne, 1), *touch = calloc((size_t)m->nv, 1);
  for (int64_t e = 0; e < m->ne; e++)
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++)
      if (m->xyz[3 * m->conn[k] + 2] < 0.3) mask[e] = 1;
  int64_t ntouch = 0;
  for (int64_t e = 0; e < m->ne; e++)
    if (mask[e])
      for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) touch[m->conn[k]] = 1;
  for (int64_t v = 0; v < m->nv; v++) ntouch += touch[v];
  mask_ctl c = {p, mask, malloc((size_t)m->nv * 3 * sizeof(double)), 3 * m->nv, 0, touch, 0};
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, VM_MINIMIZER_IMPLICIT, &mn);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 10;
  o.rel_decrease_tol = 0;
  o.amg.coarse_size = 20;
  o.before_iteration = mask_hook;
  o.user = &c;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  CHECK(st == VM_WARN_MAXITER && r.iterations == 10 && c.calls == 10, "masked run: %d %s", st,
        vm_ctx_error(ctx));
  CHECK(ntouch > 0 && ntouch < m->nv, "mask covers part of the mesh");
  CHECK(c.moved == 0, "%d vertices outside the active elements moved", c.moved);
  CHECK(isfinite(r.F) && r.inverted == 0, "F %g, %lld inverted", r.F, (long long)r.inverted);
  free(c.x3);
  free(mask);
  free(touch);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* The same bits for 1 and 2 threads. */
static void test_threads(vm_ctx *ctx, vm_minimizer_kind kind, vm_precond_kind pc) {
  double *res[2] = {NULL, NULL};
  int64_t nv = 0;
  for (int t = 1; t <= 2; t++) {
    vm_ctx_set_threads(ctx, t);
    vm_mesh *m = jittered_cube(ctx, 20, 0.2);
    vm_problem *p = NULL;
    vm_problem_create(ctx, m, &p);
    vm_minimizer *mn = NULL;
    vm_minimizer_create(ctx, p, kind, &mn);
    vm_minimize_options o = vm_minimize_options_default();
    o.max_iter = 6;
    o.amg.coarse_size = 50;
    o.precond = pc;
    vm_minimizer_set_options(mn, &o);
    vm_minimize_result r;
    vm_minimizer_run(mn, m->xyz, &r);
    nv = m->nv;
    res[t - 1] = malloc((size_t)nv * 3 * sizeof(double));
    memcpy(res[t - 1], m->xyz, (size_t)nv * 3 * sizeof(double));
    vm_minimizer_destroy(&mn);
    vm_problem_destroy(&p);
    vm_mesh_destroy(&m);
  }
  vm_ctx_set_threads(ctx, 1);
  CHECK(memcmp(res[0], res[1], (size_t)nv * 3 * sizeof(double)) == 0,
        "%s (precond %d): 1 and 2 threads differ",
        kind == VM_MINIMIZER_NEWTON ? "newton"
        : kind                      ? "implicit"
                                    : "explicit",
        (int)pc);
  free(res[0]);
  free(res[1]);
}

/* Every allocation of a run fails once: the run reports VM_ERR_NOMEM (or
 * succeeds if the failure hit nothing) and leaks nothing. */
static void test_alloc_failures(vm_ctx *ctx) {
  vm_mesh *m = jittered_cube(ctx, 5, 0.2);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  size_t bytes = (size_t)m->nv * 3 * sizeof(double);
  double *x = malloc(bytes);
  int bad = 0, runs = 0;
  for (int kind = 0; kind < 3; kind++) {
    vm_minimizer *mn = NULL;
    vm_minimizer_create(ctx, p, kind, &mn);
    vm_minimize_options o = vm_minimize_options_default();
    o.max_iter = 1;
    o.amg.coarse_size = 10;
    vm_minimizer_set_options(mn, &o);
    /* a first run lets the problem build its lazy tables (e.g. hoff positions) */
    memcpy(x, m->xyz, bytes);
    vm_minimizer_run(mn, x, NULL);
    long live0 = vm_ctx_alloc_live(ctx);
    for (long k = 1; k < 5000; k++) {
      memcpy(x, m->xyz, bytes);
      long before = vm_ctx_alloc_count(ctx);
      vm_ctx_set_alloc_fail(ctx, k);
      vm_minimize_result r;
      int st = vm_minimizer_run(mn, x, &r);
      long used = vm_ctx_alloc_count(ctx) - before;
      vm_ctx_set_alloc_fail(ctx, 0);
      runs++;
      if ((st != VM_OK && st != VM_WARN_MAXITER && st != VM_ERR_NOMEM) ||
          vm_ctx_alloc_live(ctx) != live0) {
        if (bad++ < 5)
          fprintf(stderr, "kind %d fail at %ld: status %d (%s), live %ld vs %ld\n", kind, k, st,
                  vm_ctx_error(ctx), vm_ctx_alloc_live(ctx), live0);
      }
      if (used < k) break;
    }
    vm_minimizer_destroy(&mn);
  }
  printf("allocation failure runs: %d\n", runs);
  CHECK(bad == 0, "%d runs with a wrong status or a leak", bad);
  free(x);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, 1);
  for (int kind = 0; kind < 3; kind++) {
    test_barrier_admissible(ctx, (vm_minimizer_kind)kind);
    test_barrier_rejects(ctx, (vm_minimizer_kind)kind);
    test_untangle_hook(ctx, (vm_minimizer_kind)kind);
  }
  test_stops(ctx);
  test_active_mask(ctx);
  test_threads(ctx, VM_MINIMIZER_EXPLICIT, VM_PRECOND_AMG);
  test_threads(ctx, VM_MINIMIZER_IMPLICIT, VM_PRECOND_AMG);
  test_threads(ctx, VM_MINIMIZER_NEWTON, VM_PRECOND_AMG);
  test_threads(ctx, VM_MINIMIZER_NEWTON, VM_PRECOND_BLOCK_JACOBI);
  test_alloc_failures(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_control");
}
