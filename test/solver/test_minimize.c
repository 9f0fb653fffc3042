/* test/solver/test_minimize.c: explicit and implicit minimizers on
 * generated meshes: jittered hex cube, quad and triangle squares return to
 * the uniform mesh; fixed vertices keep their bits; thread-count
 * independence; the line search's admissibility test. */
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
} monitor_data;

static void monitor(void *user, const vm_iter_info *in) {
  monitor_data *md = user;
  if (md->calls > 0 && in->F > md->last_F) md->F_increase++;
  md->calls++;
  md->last_F = in->F;
  if (!(in->min_det > 0)) md->bad_det++;
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
  monitor_data md = {0, 0, 0, 0};
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

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, 1); /* fast on a loaded machine; test_control checks 2 threads */
  test_return_to_uniform(ctx);
  test_admissible(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_minimize");
}
