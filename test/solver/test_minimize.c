/* test/solver/test_minimize.c: explicit and implicit minimizers on
 * generated meshes: jittered hex cube, quad and triangle squares return to
 * the uniform mesh; fixed vertices keep their bits; thread-count
 * independence; the line search's admissibility test; held retries of
 * short steps (hold_tau); the elements' values. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshgen.h"
#include "varmesh/minimize.h"
#include "vmtest.h"

typedef struct {
  int calls;
  int bad_det; /* iterations that ended with min det <= 0 */
  double last_F;
  int F_increase;
  int held_iters; /* iterations whose step held vertices still */
} monitor_data;

static void monitor(void *user, const vm_iter_info *in) {
  monitor_data *md = user;
  if (md->calls > 0 && in->F > md->last_F) md->F_increase++;
  md->calls++;
  md->last_F = in->F;
  if (!(in->min_det > 0)) md->bad_det++;
  if (in->held > 0) md->held_iters++;
}

/* Max distance of the vertices from `ref`, in units of h. */
static double max_err(const vm_mesh *m, const double *ref, double h) {
  double e = 0;
  for (int64_t v = 0; v < m->nv; v++)
    for (int k = 0; k < 3; k++) {
      double d = fabs(m->xyz[3 * v + k] - ref[3 * v + k]);
      if (d > e) e = d;
    }
  return e / h;
}

/* Jitter the free vertices of a unit cube/square mesh, minimize with
 * `kind`, and compare with the uniform mesh. reference: use the uniform
 * mesh as target (triangles and tets, whose ideal shapes differ). */
static void run_return(vm_ctx *ctx, const char *name, vm_mesh *m, int n, vm_minimizer_kind kind,
                       int reference, int max_iter) {
  double h = 1.0 / n;
  size_t bytes = (size_t)m->nv * 3 * sizeof(double);
  double *ref = malloc(bytes), *before = malloc(bytes);
  memcpy(ref, m->xyz, bytes);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  jitter_free(ctx, m, 0.2 * h, 7);
  memcpy(before, m->xyz, bytes);
  vm_problem *p = NULL;
  int st = vm_problem_create(ctx, m, &p);
  CHECK(st == VM_OK, "%s: problem_create %d: %s", name, st, vm_ctx_error(ctx));
  if (st) goto out;
  if (reference) vm_problem_set_target_reference(p, ref);
  vm_minimizer *mn = NULL;
  CHECK(vm_minimizer_create(ctx, p, kind, &mn) == VM_OK, "create");
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = max_iter;
  o.rel_decrease_tol = 0;
  o.grad_rtol = 1e-12;
  o.pcg_rtol = 1e-3;
  monitor_data md = {0, 0, 0, 0, 0};
  o.monitor = monitor;
  o.user = &md;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  st = vm_minimizer_run(mn, m->xyz, &r);
  double err = max_err(m, ref, h);
  printf("%-22s %-8s its %4d  F %.12g -> %.15g  |g| %.2e  reason %-12s pcg %lld  err %.2e h\n",
         name, vm_minimizer_name(mn), r.iterations, r.F_initial, r.F, r.grad_norm,
         vm_stop_reason_name(r.reason), (long long)r.pcg_iterations, err);
  CHECK(st == VM_OK, "%s: run status %d (%s)", name, st, vm_ctx_error(ctx));
  CHECK(err < 1e-6, "%s %s: max error %g h", name, vm_minimizer_name(mn), err);
  CHECK(md.bad_det == 0, "%s: %d iterations with min det <= 0", name, md.bad_det);
  CHECK(md.F_increase == 0, "%s: F increased %d times", name, md.F_increase);
  int same = 1;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_FIXED && memcmp(m->xyz + 3 * v, before + 3 * v, 24) != 0) same = 0;
  CHECK(same, "%s: a fixed vertex was written", name);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
out:
  free(ref);
  free(before);
}

static void test_return_to_uniform(vm_ctx *ctx) {
  for (int kind = 0; kind < 2; kind++) {
    vm_mesh *m = NULL;
    gen_cube(ctx, 6, 0, &m);
    run_return(ctx, "hex cube 6^3", m, 6, kind, 0, 3000);
    vm_mesh_destroy(&m);
    gen_cube(ctx, 4, 1, &m);
    run_return(ctx, "tet cube 4^3 (ref)", m, 4, kind, 1, 3000);
    vm_mesh_destroy(&m);
    gen_square(ctx, 10, 0, &m);
    run_return(ctx, "quad square 10^2", m, 10, kind, 0, 3000);
    vm_mesh_destroy(&m);
    gen_square(ctx, 10, 1, &m);
    run_return(ctx, "tri square 10^2 (ref)", m, 10, kind, 1, 3000);
    vm_mesh_destroy(&m);
  }
}

/* The line search's admissibility test: a free vertex whose uniform place
 * lies right of where the jitter put it may move right only halfway; the
 * run keeps to it (the final iterate too), F still falls, and without the
 * test the vertex goes back to its place. */
typedef struct {
  int64_t v;
  double xmax;
  int calls, refused;
} fence;

static int fence_ok(void *user, const double *x) {
  fence *f = user;
  f->calls++;
  int ok = x[3 * f->v] <= f->xmax;
  f->refused += !ok;
  return ok;
}

static void test_admissible(vm_ctx *ctx) {
  for (int kind = 0; kind < 2; kind++) {
    vm_mesh *m = NULL;
    gen_cube(ctx, 4, 0, &m);
    size_t bytes = (size_t)m->nv * 3 * sizeof(double);
    double *ref = malloc(bytes), *x0 = malloc(bytes);
    memcpy(ref, m->xyz, bytes);
    mark_boundary(m, VM_VERTEX_FIXED, -1);
    jitter_free(ctx, m, 0.05, 7);
    fence f = {-1, 0, 0, 0};
    for (int64_t v = 0; v < m->nv && f.v < 0; v++)
      if (m->vflag[v] != VM_VERTEX_FIXED && m->xyz[3 * v] < ref[3 * v] - 0.02) f.v = v;
    CHECK(f.v >= 0, "no free vertex left of its place");
    if (f.v < 0) goto next;
    f.xmax = 0.5 * (m->xyz[3 * f.v] + ref[3 * f.v]);
    memcpy(x0, m->xyz, bytes);
    for (int with = 0; with < 2; with++) {
      memcpy(m->xyz, x0, bytes);
      vm_problem *p = NULL;
      vm_minimizer *mn = NULL;
      vm_problem_create(ctx, m, &p);
      vm_minimizer_create(ctx, p, kind, &mn);
      vm_minimize_options o = vm_minimize_options_default();
      o.max_iter = 200;
      if (with) {
        o.admissible = fence_ok;
        o.user = &f;
      }
      vm_minimizer_set_options(mn, &o);
      vm_minimize_result r;
      int st = vm_minimizer_run(mn, m->xyz, &r);
      CHECK(st >= 0 && r.F < r.F_initial, "admissible %d: status %d, F %g -> %g", with, st,
            r.F_initial, r.F);
      if (with)
        CHECK(m->xyz[3 * f.v] <= f.xmax && f.refused > 0,
              "admissible: x %.17g beyond %.17g (%d of %d trials refused)", m->xyz[3 * f.v], f.xmax,
              f.refused, f.calls);
      else
        CHECK(m->xyz[3 * f.v] > f.xmax + 0.01, "without the test the vertex stays at %g (%g)",
              m->xyz[3 * f.v], f.xmax);
      vm_minimizer_destroy(&mn);
      vm_problem_destroy(&p);
    }
  next:
    free(ref);
    free(x0);
    vm_mesh_destroy(&m);
  }
}

/* hold_tau: a square of triangles whose corner block of B x B cells wants
 * to be S times larger than the fixed boundary lets it (as the prism
 * layer's columns at a sharp corner that cannot reach their targets), the
 * rest jittered. Without the retries every step is cut short by the
 * corner; with them the rest relaxes: its F (from vm_problem_elem_values)
 * and the total end lower, steps were taken with vertices held, F never
 * rose, every iterate stayed valid, the fixed vertices kept their bits,
 * and one and two threads give the same bits. */
enum { HOLD_N = 12, HOLD_B = 3 };

static int in_corner(int64_t e) {
  int ci = (int)(e / 2) % HOLD_N, cj = (int)(e / 2) / HOLD_N;
  return ci < HOLD_B && cj < HOLD_B;
}

static int corner_square(vm_ctx *ctx, double S, vm_mesh **out) {
  int st = gen_square(ctx, HOLD_N, 1, out);
  if (st) return st;
  vm_mesh *m = *out;
  vm_field *f = NULL;
  if ((st = vm_mesh_add_field(m, "target", VM_FIELD_ELEMENT, VM_FIELD_F64, 9, &f))) return st;
  double *t = f->data;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    double s = in_corner(e) ? S : 1;
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) t[9 * e + 3 * i + k] = s * m->xyz[3 * (int64_t)c[i] + k];
  }
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  jitter_free(ctx, m, 0.25 / HOLD_N, 11);
  return VM_OK;
}

/* 30 implicit iterations with hold_tau; F of the elements outside the
 * corner into *rest. */
static void hold_run(vm_ctx *ctx, vm_mesh *m, double hold_tau, vm_minimize_result *r,
                     monitor_data *md, double *rest) {
  vm_problem *p = NULL;
  vm_minimizer *mn = NULL;
  memset(r, 0, sizeof *r);
  memset(md, 0, sizeof *md);
  *rest = NAN;
  int st = vm_problem_create(ctx, m, &p);
  if (!st) st = vm_problem_set_target_field(p, "target");
  if (!st) st = vm_minimizer_create(ctx, p, VM_MINIMIZER_IMPLICIT, &mn);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 30;
  o.rel_decrease_tol = 0;
  o.hold_tau = hold_tau;
  o.monitor = monitor;
  o.user = md;
  if (!st) st = vm_minimizer_set_options(mn, &o);
  if (!st) st = vm_minimizer_run(mn, m->xyz, r);
  CHECK(st >= 0, "hold %g: run %d: %s", hold_tau, st, vm_ctx_error(ctx));
  double *fe = malloc(sizeof *fe * (size_t)m->ne);
  if (st >= 0 && fe && vm_problem_elem_values(p, m->xyz, fe) == VM_OK) {
    *rest = 0;
    for (int64_t e = 0; e < m->ne; e++)
      if (!in_corner(e)) *rest += fe[e];
  }
  free(fe);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
}

static void test_hold(vm_ctx *ctx) {
  vm_mesh *m0 = NULL, *m1 = NULL, *m2 = NULL;
  if (corner_square(ctx, 500, &m0) || vm_mesh_clone(m0, &m1) || vm_mesh_clone(m0, &m2)) {
    CHECK(0, "hold: corner square");
    goto out;
  }
  size_t bytes = (size_t)m0->nv * 3 * sizeof(double);
  double *x0 = malloc(bytes);
  memcpy(x0, m0->xyz, bytes);
  vm_minimize_result r0, r1, r2;
  monitor_data h0, h1, h2;
  double rest0, rest1, rest2;
  hold_run(ctx, m0, 0, &r0, &h0, &rest0);
  hold_run(ctx, m1, 0.25, &r1, &h1, &rest1);
  vm_ctx_set_threads(ctx, 2);
  hold_run(ctx, m2, 0.25, &r2, &h2, &rest2);
  vm_ctx_set_threads(ctx, 1);
  printf("hold: F %.6g -> %.6g without (the rest %.6g), %.6g with (the rest %.6g; %d held steps)\n",
         r0.F_initial, r0.F, rest0, r1.F, rest1, r1.held_steps);
  CHECK(r0.held_steps == 0 && h0.held_iters == 0, "hold off: %d held steps", r0.held_steps);
  CHECK(r1.held_steps > 0 && h1.held_iters == r1.held_steps, "hold: %d held steps (monitor %d)",
        r1.held_steps, h1.held_iters);
  CHECK(r1.F < r0.F, "hold: F %.17g, without %.17g", r1.F, r0.F);
  CHECK(rest1 < 0.7 * rest0, "hold: the rest's F %g, without %g", rest1, rest0);
  CHECK(h1.F_increase == 0 && h1.bad_det == 0, "hold: F rose %d times, %d invalid iterates",
        h1.F_increase, h1.bad_det);
  int same = 1;
  for (int64_t v = 0; v < m1->nv; v++)
    if (m1->vflag[v] == VM_VERTEX_FIXED && memcmp(m1->xyz + 3 * v, x0 + 3 * v, 24)) same = 0;
  CHECK(same, "hold: a fixed vertex was written");
  CHECK(!memcmp(m1->xyz, m2->xyz, bytes) && r1.held_steps == r2.held_steps,
        "hold: two threads give other bits");
  /* the option's range */
  vm_problem *p = NULL;
  vm_minimizer *mn = NULL;
  if (!vm_problem_create(ctx, m0, &p) && !vm_minimizer_create(ctx, p, VM_MINIMIZER_IMPLICIT, &mn)) {
    const double bad[] = {-0.1, 1.5, NAN};
    for (int k = 0; k < 3; k++) {
      vm_minimize_options o = vm_minimize_options_default();
      o.hold_tau = bad[k];
      CHECK(vm_minimizer_set_options(mn, &o) == VM_ERR_ARG, "hold_tau %g accepted", bad[k]);
    }
  }
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  free(x0);
out:
  vm_mesh_destroy(&m0);
  vm_mesh_destroy(&m1);
  vm_mesh_destroy(&m2);
}

/* vm_problem_elem_values: the elements' values sum to F; an inactive
 * element gives 0, an element turned over +inf. */
static void test_elem_values(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  gen_cube(ctx, 4, 1, &m);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  jitter_free(ctx, m, 0.05, 3);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  double *fe = malloc(sizeof *fe * (size_t)m->ne), F = 0, s = 0;
  CHECK(vm_problem_value(p, m->xyz, &F) == VM_OK && vm_problem_elem_values(p, m->xyz, fe) == VM_OK,
        "elem values: %s", vm_ctx_error(ctx));
  int pos = 1;
  for (int64_t e = 0; e < m->ne; e++) {
    s += fe[e];
    pos &= fe[e] > 0 && isfinite(fe[e]);
  }
  CHECK(pos && fabs(s - F) <= 1e-12 * F, "elem values sum %.17g, F %.17g", s, F);
  uint8_t *mask = calloc((size_t)m->ne, 1);
  for (int64_t e = 0; e < m->ne; e += 2) mask[e] = 1;
  vm_problem_set_active(p, mask);
  vm_problem_elem_values(p, m->xyz, fe);
  int ok = 1;
  for (int64_t e = 0; e < m->ne; e++) ok &= e % 2 ? fe[e] == 0 : fe[e] > 0;
  CHECK(ok, "elem values: inactive elements not 0");
  vm_problem_set_active(p, NULL);
  /* a free vertex pushed through the boundary: its elements turn over */
  int64_t v = 0;
  while (v < m->nv && m->vflag[v] == VM_VERTEX_FIXED) v++;
  m->xyz[3 * v] = -1;
  vm_problem_elem_values(p, m->xyz, fe);
  int64_t ninf = 0;
  for (int64_t e = 0; e < m->ne; e++) ninf += isinf(fe[e]) != 0;
  CHECK(ninf > 0 && vm_problem_value(p, m->xyz, &F) > 0 && isinf(F),
        "elem values: %lld infinite after a fold, F %g", (long long)ninf, F);
  free(mask);
  free(fe);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, 1); /* fast on a loaded machine; test_control checks 2 threads */
  test_return_to_uniform(ctx);
  test_admissible(ctx);
  test_hold(ctx);
  test_elem_values(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_minimize");
}
