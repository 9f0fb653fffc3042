/* test/solver/test_slip.c: slip boundary conditions in the minimizers: a
 * jittered tet ball keeps its boundary on the sphere while F decreases; a
 * hex cube sliding on its box returns to the uniform mesh with edge
 * vertices on their edges and corners untouched. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshgen.h"
#include "varmesh/minimize.h"
#include "vmtest.h"

typedef struct {
  int calls, bad_det, F_increase;
  double last_F;
} monitor_data;

static void monitor(void *user, const vm_iter_info *in) {
  monitor_data *md = user;
  if (md->calls > 0 && in->F > md->last_F) md->F_increase++;
  md->calls++;
  md->last_F = in->F;
  if (!(in->min_det > 0)) md->bad_det++;
}

static void test_ball(vm_ctx *ctx, vm_minimizer_kind kind) {
  const double R = 2.0;
  vm_mesh *m = NULL;
  CHECK(gen_ball(ctx, 6, R, 3, &m) == VM_OK, "ball");
  /* jitter: interior vertices freely, boundary vertices then projected */
  vm_ctx_seed(ctx, 11);
  double h = 2 * R / 6;
  for (int64_t v = 0; v < m->nv; v++)
    for (int k = 0; k < 3; k++) m->xyz[3 * v + k] += 0.1 * h * (2 * vm_ctx_rand_unit(ctx) - 1);
  vm_analytic_surfaces *s = NULL;
  vm_analytic_surfaces_create(ctx, &s);
  double c[3] = {0, 0, 0};
  vm_analytic_add_sphere(s, 3, c, R);
  vm_surface_ops ops = vm_analytic_surfaces_ops(s);
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == VM_OK, "problem: %s", vm_ctx_error(ctx));
  vm_node_stats ns;
  vm_problem_node_stats(p, m->xyz, &ns);
  CHECK(ns.inverted == 0, "initial ball has %lld inverted nodes", (long long)ns.inverted);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, kind, &mn);
  vm_minimizer_set_surfaces(mn, &ops);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = kind == VM_MINIMIZER_IMPLICIT ? 40 : 150;
  monitor_data md = {0, 0, 0, 0};
  o.monitor = monitor;
  o.user = &md;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  printf("ball %-8s its %3d  F %.10g -> %.10g  reason %s  phi_min %.3f\n", vm_minimizer_name(mn),
         r.iterations, r.F_initial, r.F, vm_stop_reason_name(r.reason),
         (vm_problem_node_stats(p, m->xyz, &ns), ns.phi_min));
  CHECK(st >= 0, "run: %d %s", st, vm_ctx_error(ctx));
  CHECK(r.F < r.F_initial - 1e-3 * fabs(r.F_initial), "F did not decrease enough");
  CHECK(md.F_increase == 0 && md.bad_det == 0, "monotone and valid");
  double worst = 0;
  int64_t nslip = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    if (m->vflag[v] != VM_VERTEX_SLIP) continue;
    nslip++;
    const double *x = m->xyz + 3 * v;
    double e = fabs(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - R);
    if (e > worst) worst = e;
  }
  CHECK(nslip > 0 && worst < 1e-10, "boundary off the sphere by %g", worst);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_analytic_surfaces_destroy(&s);
  vm_mesh_destroy(&m);
}

/* Classify a unit-cube boundary point: number of coordinates at 0 or 1. */
static int nbound(const double *p) {
  int c = 0;
  for (int k = 0; k < 3; k++) c += p[k] == 0.0 || p[k] == 1.0;
  return c;
}

static void test_box(vm_ctx *ctx, vm_minimizer_kind kind) {
  const int n = 5;
  const double h = 1.0 / n;
  vm_mesh *m = NULL;
  gen_cube(ctx, n, 0, &m);
  size_t bytes = (size_t)m->nv * 3 * sizeof(double);
  double *ref = malloc(bytes);
  memcpy(ref, m->xyz, bytes);
  mark_boundary(m, VM_VERTEX_SLIP, 0);
  /* jitter every vertex within its feature: free ones in 3D, face vertices
   * in the face, edge vertices along the edge, corners not at all */
  vm_ctx_seed(ctx, 5);
  int *feat = malloc((size_t)m->nv * sizeof *feat);
  for (int64_t v = 0; v < m->nv; v++) {
    double *p = m->xyz + 3 * v;
    feat[v] = nbound(p);
    for (int k = 0; k < 3; k++) {
      double d = 0.2 * h * (2 * vm_ctx_rand_unit(ctx) - 1);
      if (p[k] != 0.0 && p[k] != 1.0) p[k] += d;
    }
  }
  double *before = malloc(bytes);
  memcpy(before, m->xyz, bytes);
  vm_analytic_surfaces *s = NULL;
  vm_analytic_surfaces_create(ctx, &s);
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  vm_analytic_add_box(s, 0, lo, hi);
  vm_surface_ops ops = vm_analytic_surfaces_ops(s);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, kind, &mn);
  vm_minimizer_set_surfaces(mn, &ops);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 3000;
  o.rel_decrease_tol = 0;
  o.grad_rtol = 1e-12;
  o.pcg_rtol = 1e-3;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  double err = 0;
  for (size_t i = 0; i < (size_t)m->nv * 3; i++)
    if (fabs(m->xyz[i] - ref[i]) > err) err = fabs(m->xyz[i] - ref[i]);
  printf("box slip %-8s its %4d  F %.12g -> %.15g  reason %s  err %.2e h\n", vm_minimizer_name(mn),
         r.iterations, r.F_initial, r.F, vm_stop_reason_name(r.reason), err / h);
  CHECK(st == VM_OK, "run %d: %s", st, vm_ctx_error(ctx));
  CHECK(err / h < 1e-6, "box slip: error %g h", err / h);
  int feat_ok = 1, corners_ok = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    if (nbound(m->xyz + 3 * v) != feat[v]) feat_ok = 0;
    if (feat[v] == 3 && memcmp(m->xyz + 3 * v, before + 3 * v, 24) != 0) corners_ok = 0;
  }
  CHECK(feat_ok, "a vertex left its face/edge");
  CHECK(corners_ok, "a corner moved");
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_analytic_surfaces_destroy(&s);
  vm_mesh_destroy(&m);
  free(ref);
  free(before);
  free(feat);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, 1); /* fast on a loaded machine; test_control checks 2 threads */
  test_ball(ctx, VM_MINIMIZER_IMPLICIT);
  test_ball(ctx, VM_MINIMIZER_EXPLICIT);
  test_box(ctx, VM_MINIMIZER_IMPLICIT);
  test_box(ctx, VM_MINIMIZER_EXPLICIT);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_slip");
}
