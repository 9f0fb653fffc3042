/* test/solver/test_newton.c: the projected Newton minimizer and what it
 * rests on: the PSD projection of the measures' Hessians (analytic
 * eigensystem in 3D) against finite differences and a dense
 * eigen-decomposition; the full Hessian blocks of the assembly against
 * finite differences of the gradient (plane, surface and volume elements,
 * all metric kinds); positive semidefiniteness of the projected assembled
 * Hessian on tangled meshes; Newton's method returning jittered meshes to
 * uniform in few iterations; thread-count independence. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshgen.h"
#include "varmesh/minimize.h"
#include "varmesh/problem.h"
#include "vmtest.h"

/* Cyclic Jacobi eigenvalues of the symmetric n x n A (destroyed), sorted. */
static void eigvals(int n, double *A, double *w) {
  for (int sweep = 0; sweep < 100; sweep++) {
    double off = 0, tot = 0;
    for (int p = 0; p < n; p++)
      for (int q = 0; q < n; q++) {
        tot += A[p * n + q] * A[p * n + q];
        if (p != q) off += A[p * n + q] * A[p * n + q];
      }
    if (off <= 1e-32 * tot) break;
    for (int p = 0; p < n; p++)
      for (int q = p + 1; q < n; q++) {
        double apq = A[p * n + q];
        if (apq == 0) continue;
        double th = (A[q * n + q] - A[p * n + p]) / (2 * apq);
        double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
        double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; k++) {
          double a = A[k * n + p], b = A[k * n + q];
          A[k * n + p] = c * a - s * b;
          A[k * n + q] = s * a + c * b;
        }
        for (int k = 0; k < n; k++) {
          double a = A[p * n + k], b = A[q * n + k];
          A[p * n + k] = c * a - s * b;
          A[q * n + k] = s * a + c * b;
        }
      }
  }
  for (int i = 0; i < n; i++) w[i] = A[i * n + i];
  for (int i = 0; i < n; i++)
    for (int j = i + 1; j < n; j++)
      if (w[j] < w[i]) {
        double t = w[i];
        w[i] = w[j];
        w[j] = t;
      }
}

static double urand(unsigned *s) {
  *s = *s * 1103515245u + 12345u;
  return (double)((*s >> 8) & 0xffffff) / 16777216.0;
}

/* Per measure and dimension: random C (admissible, and with det < 0 for
 * the penalty and barrier forms): the projected Hessian's eigenvalues are
 * those of the exact Hessian with the negative ones set to 0; when nothing
 * is clamped it equals finite differences of the gradient. */
static void test_measure_psd(void) {
  unsigned seed = 12345;
  int fd_checked = 0, clamped_seen = 0;
  for (int kind = 0; kind < VM_MEASURE_COUNT; kind++) {
    const vm_measure_ops *ops = vm_measure_get((vm_measure_kind)kind);
    vm_measure_params prm = vm_measure_params_default();
    prm.eps = 0.05;
    prm.t = kind == VM_MEASURE_QUASI_ISO ? 0.2 : 0;
    for (int chi2 = 0; chi2 < 2; chi2++) {
      prm.drop_chi2 = chi2;
      for (int d = 2; d <= 3; d++)
        for (int trial = 0; trial < 200; trial++) {
          int nn = d * d;
          double C[9], H[81], Hp[81], G[9], W, Wp;
          for (int k = 0; k < nn; k++)
            C[k] = (k % (d + 1) == 0 ? 1.0 : 0.0) + 0.9 * (2 * urand(&seed) - 1);
          if (trial % 3 == 0 && (kind == VM_MEASURE_PENALTY || kind == VM_MEASURE_BARRIER))
            for (int k = 0; k < d; k++) C[k] = -C[k]; /* det < 0 */
          if (trial % 5 == 1) /* near a rotation: nothing to clamp for most */
            for (int k = 0; k < nn; k++)
              C[k] = (k % (d + 1) == 0 ? 1.0 : 0.0) + 0.05 * (2 * urand(&seed) - 1);
          if (vm_measure_eval(ops, &prm, d, C, &W, G, H)) continue;
          int ncl = -1;
          int st = vm_measure_hessian_psd(ops, &prm, d, C, &Wp, NULL, Hp, &ncl);
          CHECK(st == 0 && Wp == W, "%s d %d: psd status %d", ops->name, d, st);
          double scale = 0;
          for (int k = 0; k < nn * nn; k++) scale = fmax(scale, fabs(H[k]));
          double A[81], B[81], we[9], wp[9];
          memcpy(A, H, sizeof A);
          memcpy(B, Hp, sizeof B);
          eigvals(nn, A, we);
          eigvals(nn, B, wp);
          int neg = 0;
          for (int k = 0; k < nn; k++) {
            if (we[k] < 0) neg++;
            CHECK(fabs(wp[k] - fmax(we[k], 0)) <= 1e-9 * scale,
                  "%s d %d trial %d: eigenvalue %d: %g, exact %g", ops->name, d, trial, k, wp[k],
                  we[k]);
          }
          /* near-zero eigenvalues may be counted either way */
          int strict = 0;
          for (int k = 0; k < nn; k++)
            if (we[k] < -1e-9 * scale) strict++;
          CHECK(ncl >= strict && ncl <= nn, "%s: clamped %d, negative %d", ops->name, ncl, neg);
          if (ncl > 0) clamped_seen++;
          double sym = 0;
          for (int a = 0; a < nn; a++)
            for (int b = 0; b < nn; b++) sym = fmax(sym, fabs(Hp[a * nn + b] - Hp[b * nn + a]));
          CHECK(sym <= 1e-10 * scale, "%s: projected Hessian not symmetric (%g)", ops->name, sym);
          if (ncl != 0) continue;
          /* finite differences of the gradient */
          double err = 0;
          for (int b = 0; b < nn; b++) {
            double Cp[9], Cm[9], Gp[9], Gm[9], w1, w2;
            double h = 1e-6 * fmax(1, fabs(C[b]));
            memcpy(Cp, C, sizeof Cp);
            memcpy(Cm, C, sizeof Cm);
            Cp[b] += h;
            Cm[b] -= h;
            if (vm_measure_eval(ops, &prm, d, Cp, &w1, Gp, NULL) ||
                vm_measure_eval(ops, &prm, d, Cm, &w2, Gm, NULL))
              goto next;
            for (int a = 0; a < nn; a++)
              err = fmax(err, fabs((Gp[a] - Gm[a]) / (2 * h) - Hp[a * nn + b]));
          }
          if (prm.drop_chi2 && kind == VM_MEASURE_PENALTY) continue; /* not the true Hessian */
          CHECK(err <= 1e-5 * fmax(scale, 1), "%s d %d: FD error %g (scale %g)", ops->name, d, err,
                scale);
          fd_checked++;
        next:;
        }
    }
  }
  printf("measure PSD: %d FD checks, %d clamped cases\n", fd_checked, clamped_seen);
  CHECK(fd_checked > 500 && clamped_seen > 100, "too few cases (%d, %d)", fd_checked, clamped_seen);
}

/* Dense symmetric matrix of the assembled blocks (3 nv). */
static double *dense_blocks(const vm_problem *p, const double *hdiag, const double *hblk,
                            int64_t nv) {
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  int64_t n = 3 * nv;
  double *A = calloc((size_t)(n * n), sizeof *A);
  for (int64_t u = 0; u < nv; u++) {
    for (int r = 0; r < 3; r++)
      for (int q = 0; q < 3; q++) A[(3 * u + r) * n + 3 * u + q] = hdiag[9 * u + 3 * r + q];
    for (int64_t k = rp[u]; k < rp[u + 1]; k++)
      for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) A[(3 * u + r) * n + 3 * adj[k] + q] = hblk[9 * k + 3 * r + q];
  }
  return A;
}

/* Exact blocks (psd = 0) against central differences of the gradient, and
 * against vm_problem_eval's hdiag / hoff. */
static void check_blocks_fd(vm_ctx *ctx, const char *name, vm_mesh *m, int metric, int measure) {
  vm_problem *p = NULL;
  int st = vm_problem_create(ctx, m, &p);
  CHECK(st == VM_OK, "%s: create", name);
  if (st) return;
  vm_measure_params prm = vm_measure_params_default();
  prm.eps = 0.02;
  prm.drop_chi2 = 0;
  vm_problem_set_measure(p, (vm_measure_kind)measure, &prm);
  const int64_t nv = m->nv;
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  int64_t nnz = rp[nv];
  if (metric == 1) {
    double *g = malloc((size_t)nv * sizeof *g);
    for (int64_t v = 0; v < nv; v++) g[v] = 1.0 + 0.5 * sin(3.0 * (double)v);
    vm_problem_set_metric_scalar(p, g);
    free(g);
  } else if (metric == 2) {
    double *G = malloc((size_t)nv * 6 * sizeof *G);
    for (int64_t v = 0; v < nv; v++) {
      double t = (double)v;
      double a[6] = {1.5 + 0.3 * sin(t), 1.2 + 0.2 * cos(t), 1.0 + 0.1 * sin(2 * t),
                     0.2 * sin(3 * t),   0.1 * cos(t),       0.15 * sin(t + 1)};
      memcpy(G + 6 * v, a, sizeof a);
    }
    vm_problem_set_metric_tensor(p, G);
    free(G);
  }
  double *x = m->xyz, F;
  size_t n3 = (size_t)nv * 3;
  double *g = malloc(n3 * sizeof *g), *gp = malloc(n3 * sizeof *gp), *gm = malloc(n3 * sizeof *gm);
  double *hd = malloc(9 * (size_t)nv * sizeof *hd), *hb = malloc(9 * (size_t)nnz * sizeof *hb);
  double *hd2 = malloc(9 * (size_t)nv * sizeof *hd2), *ho = malloc(3 * (size_t)nnz * sizeof *ho);
  vm_eval_blocks eb = {&F, g, hd, hb, 0};
  st = vm_problem_eval_blocks(p, x, &eb);
  CHECK(st == VM_OK, "%s: eval_blocks %d", name, st);
  vm_eval ev = {NULL, NULL, hd2, ho};
  vm_problem_eval(p, x, &ev);
  double scale = 0, dd = 0, od = 0;
  for (size_t k = 0; k < 9 * (size_t)nv; k++) {
    scale = fmax(scale, fabs(hd[k]));
    dd = fmax(dd, fabs(hd[k] - hd2[k]));
  }
  for (int64_t k = 0; k < nnz; k++)
    for (int c = 0; c < 3; c++) od = fmax(od, fabs(hb[9 * k + 4 * c] - ho[3 * k + c]));
  CHECK(dd <= 1e-12 * scale && od <= 1e-12 * scale, "%s: hdiag/hoff differ: %g %g", name, dd, od);
  double *A = dense_blocks(p, hd, hb, nv);
  int64_t n = 3 * nv;
  double err = 0;
  int dim = m->dim == 2 ? 2 : 3;
  for (int64_t j = 0; j < n; j++) {
    if ((int)(j % 3) >= dim) continue;
    double h = 1e-6, save = x[j];
    vm_eval e1 = {NULL, gp, NULL, NULL}, e2 = {NULL, gm, NULL, NULL};
    x[j] = save + h;
    vm_problem_eval(p, x, &e1);
    x[j] = save - h;
    vm_problem_eval(p, x, &e2);
    x[j] = save;
    for (int64_t i = 0; i < n; i++) {
      if ((int)(i % 3) >= dim) continue;
      err = fmax(err, fabs((gp[i] - gm[i]) / (2 * h) - A[i * n + j]));
    }
  }
  printf("blocks FD %-28s scale %.3e err %.3e\n", name, scale, err);
  CHECK(err <= 2e-5 * scale, "%s: FD error %g (scale %g)", name, err, scale);
  free(A);
  free(g);
  free(gp);
  free(gm);
  free(hd);
  free(hb);
  free(hd2);
  free(ho);
  vm_problem_destroy(&p);
}

/* Jitter all vertices (z too for surfaces) by amp. */
static void jitter_all(vm_mesh *m, double amp, unsigned seed, int zdim) {
  for (int64_t v = 0; v < m->nv; v++)
    for (int k = 0; k < zdim; k++) m->xyz[3 * v + k] += amp * (2 * urand(&seed) - 1);
}

static void test_blocks_fd(vm_ctx *ctx) {
  static const int measures[] = {VM_MEASURE_BALANCED, VM_MEASURE_PENALTY, VM_MEASURE_SHAPE};
  for (int mi = 0; mi < 3; mi++)
    for (int metric = 0; metric < 3; metric++) {
      int ms = measures[mi];
      char name[96];
      vm_mesh *m = NULL;
      gen_cube(ctx, 2, 0, &m);
      jitter_all(m, 0.08, 11u + (unsigned)metric, 3);
      snprintf(name, sizeof name, "hex m%d metric %d", ms, metric);
      check_blocks_fd(ctx, name, m, metric, ms);
      vm_mesh_destroy(&m);
      gen_cube(ctx, 2, 1, &m);
      jitter_all(m, 0.05, 13u + (unsigned)metric, 3);
      snprintf(name, sizeof name, "tet m%d metric %d", ms, metric);
      check_blocks_fd(ctx, name, m, metric, ms);
      vm_mesh_destroy(&m);
      gen_square(ctx, 3, 0, &m);
      jitter_all(m, 0.06, 17u + (unsigned)metric, 2);
      snprintf(name, sizeof name, "quad m%d metric %d", ms, metric);
      check_blocks_fd(ctx, name, m, metric, ms);
      vm_mesh_destroy(&m);
      if (metric < 2) { /* surfaces take scalar metrics only */
        gen_square(ctx, 3, 1, &m);
        m->dim = 3;
        jitter_all(m, 0.06, 19u + (unsigned)metric, 3);
        snprintf(name, sizeof name, "surface tri m%d metric %d", ms, metric);
        check_blocks_fd(ctx, name, m, metric, ms);
        vm_mesh_destroy(&m);
      }
    }
}

/* Cholesky of A + shift I (n x n, destroyed): 0 if positive definite. */
static int chol_ok(int64_t n, double *A, double shift) {
  for (int64_t j = 0; j < n; j++) {
    double s = A[j * n + j] + shift;
    for (int64_t k = 0; k < j; k++) s -= A[j * n + k] * A[j * n + k];
    if (!(s > 0)) return 0;
    double l = sqrt(s);
    A[j * n + j] = l;
    for (int64_t i = j + 1; i < n; i++) {
      double t = A[i * n + j];
      for (int64_t k = 0; k < j; k++) t -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = t / l;
    }
  }
  return 1;
}

/* Projected assembled Hessians of tangled meshes are PSD; the exact ones
 * are not. */
static void test_blocks_psd(vm_ctx *ctx) {
  for (int c = 0; c < 4; c++) {
    vm_mesh *m = NULL;
    if (c < 2)
      gen_cube(ctx, 2, c, &m);
    else
      gen_square(ctx, 4, c - 2, &m);
    int zdim = c < 2 ? 3 : 2;
    jitter_all(m, c < 2 ? 0.4 : 0.3, 23u + (unsigned)c, zdim); /* tangles */
    vm_problem *p = NULL;
    vm_problem_create(ctx, m, &p);
    vm_measure_params prm = vm_measure_params_default();
    prm.eps = 0.01;
    prm.drop_chi2 = 0;
    vm_problem_set_measure(p, VM_MEASURE_PENALTY, &prm);
    vm_node_stats ns;
    vm_problem_node_stats(p, m->xyz, &ns);
    const int64_t *rp;
    const int32_t *adj;
    vm_problem_graph(p, &rp, &adj);
    int64_t nv = m->nv, n = 3 * nv;
    double *hd = malloc(9 * (size_t)nv * sizeof *hd), *hb = malloc(9 * (size_t)rp[nv] * sizeof *hb);
    int ok[2] = {0, 0};
    for (int psd = 0; psd < 2; psd++) {
      vm_eval_blocks eb = {NULL, NULL, hd, hb, psd};
      CHECK(vm_problem_eval_blocks(p, m->xyz, &eb) == VM_OK, "eval_blocks");
      double *A = dense_blocks(p, hd, hb, nv), tr = 0;
      for (int64_t i = 0; i < n; i++) tr = fmax(tr, A[i * n + i]);
      /* plane meshes: the z rows are zero or decoupled */
      for (int64_t i = 0; i < n; i++)
        if (A[i * n + i] == 0) A[i * n + i] = 1;
      ok[psd] = chol_ok(n, A, 1e-9 * tr);
      free(A);
    }
    printf("PSD case %d: %lld inverted nodes, exact PD %d, projected PD %d\n", c,
           (long long)ns.inverted, ok[0], ok[1]);
    CHECK(ns.inverted > 0, "case %d: mesh not tangled", c);
    CHECK(ok[1], "case %d: projected Hessian not PSD", c);
    CHECK(!ok[0], "case %d: exact Hessian unexpectedly PSD", c);
    free(hd);
    free(hb);
    vm_problem_destroy(&p);
    vm_mesh_destroy(&m);
  }
}

/* Jittered meshes return to the uniform one (ideal or reference targets)
 * in few Newton iterations, F decreasing, fixed vertices untouched. */
static void run_return(vm_ctx *ctx, const char *name, vm_mesh *m, int n, int reference,
                       vm_precond_kind pc, int max_its) {
  double h = 1.0 / n;
  size_t bytes = (size_t)m->nv * 3 * sizeof(double);
  double *ref = malloc(bytes), *before = malloc(bytes);
  memcpy(ref, m->xyz, bytes);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  jitter_free(ctx, m, 0.2 * h, 7);
  memcpy(before, m->xyz, bytes);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  if (reference) vm_problem_set_target_reference(p, ref);
  vm_minimizer *mn = NULL;
  CHECK(vm_minimizer_create(ctx, p, VM_MINIMIZER_NEWTON, &mn) == VM_OK, "create");
  CHECK(strcmp(vm_minimizer_name(mn), "newton") == 0, "name");
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 100;
  o.rel_decrease_tol = 0;
  o.grad_rtol = 1e-11;
  o.pcg_rtol = 1e-4;
  o.pcg_maxit = 500;
  o.precond = pc;
  o.amg.coarse_size = 20;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  double err = 0;
  for (int64_t v = 0; v < m->nv; v++)
    for (int k = 0; k < 3; k++) err = fmax(err, fabs(m->xyz[3 * v + k] - ref[3 * v + k]) / h);
  printf("newton %-24s precond %d its %3d  F %.10g -> %.14g  |g| %.2e  %s  cg %lld  err %.1e h\n",
         name, (int)pc, r.iterations, r.F_initial, r.F, r.grad_norm, vm_stop_reason_name(r.reason),
         (long long)r.pcg_iterations, err);
  CHECK(st == VM_OK && r.reason == VM_STOP_GRAD_NORM, "%s: status %d reason %s", name, st,
        vm_stop_reason_name(r.reason));
  CHECK(err < 1e-6, "%s: max error %g h", name, err);
  CHECK(r.iterations <= max_its, "%s: %d iterations (at most %d expected)", name, r.iterations,
        max_its);
  int same = 1;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_FIXED && memcmp(m->xyz + 3 * v, before + 3 * v, 24) != 0) same = 0;
  CHECK(same, "%s: a fixed vertex was written", name);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  free(ref);
  free(before);
}

static void test_return_to_uniform(vm_ctx *ctx) {
  static const vm_precond_kind pcs[2] = {VM_PRECOND_BLOCK_JACOBI, VM_PRECOND_AMG};
  for (int k = 0; k < 2; k++) {
    vm_mesh *m = NULL;
    gen_cube(ctx, 6, 0, &m);
    run_return(ctx, "hex cube 6^3", m, 6, 0, pcs[k], 12);
    vm_mesh_destroy(&m);
    gen_cube(ctx, 4, 1, &m);
    run_return(ctx, "tet cube 4^3 (ref)", m, 4, 1, pcs[k], 12);
    vm_mesh_destroy(&m);
    gen_square(ctx, 10, 0, &m);
    run_return(ctx, "quad square 10^2", m, 10, 0, pcs[k], 12);
    vm_mesh_destroy(&m);
    gen_square(ctx, 10, 1, &m);
    run_return(ctx, "tri square 10^2 (ref)", m, 10, 1, pcs[k], 12);
    vm_mesh_destroy(&m);
  }
}

/* Slip vertices on a sphere: the projected Newton system (L H L) keeps
 * them on it and converges. */
static void test_slip_ball(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  gen_ball(ctx, 4, 1.0, 3, &m);
  vm_analytic_surfaces *as = NULL;
  vm_analytic_surfaces_create(ctx, &as);
  double c[3] = {0, 0, 0};
  vm_analytic_add_sphere(as, 3, c, 1.0);
  vm_surface_ops ops = vm_analytic_surfaces_ops(as);
  vm_problem *p = NULL;
  vm_problem_create(ctx, m, &p);
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, VM_MINIMIZER_NEWTON, &mn);
  vm_minimizer_set_surfaces(mn, &ops);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = 200;
  o.pcg_rtol = 1e-4;
  o.pcg_maxit = 500;
  o.precond = VM_PRECOND_BLOCK_JACOBI;
  vm_minimizer_set_options(mn, &o);
  vm_minimize_result r;
  int st = vm_minimizer_run(mn, m->xyz, &r);
  double off = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_SLIP) {
      const double *x = m->xyz + 3 * v;
      off = fmax(off, fabs(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 1));
    }
  printf("newton slip ball: its %d F %.10g -> %.12g |g| %.2e %s, off sphere %.1e, min det %.3g\n",
         r.iterations, r.F_initial, r.F, r.grad_norm, vm_stop_reason_name(r.reason), off,
         r.min_det);
  CHECK(st == VM_OK && r.reason != VM_STOP_LINE_SEARCH, "slip ball: status %d %s", st,
        vm_stop_reason_name(r.reason));
  CHECK(r.F < r.F_initial && r.inverted == 0, "slip ball: F %g -> %g", r.F_initial, r.F);
  CHECK(off < 1e-12, "slip ball: %g off the sphere", off);
  CHECK(r.iterations < 60, "slip ball: %d iterations", r.iterations);
  vm_minimizer_destroy(&mn);
  vm_problem_destroy(&p);
  vm_analytic_surfaces_destroy(&as);
  vm_mesh_destroy(&m);
}

/* The same bits for 1 and 2 threads (assembly of the projected blocks,
 * PCG with both preconditioners): a 14^3 cube (above the parallel
 * thresholds), tangled, with the penalty form. */
static void test_threads(vm_ctx *ctx) {
  for (int pc = 0; pc < 2; pc++) {
    double *res[2] = {NULL, NULL};
    int64_t nv = 0;
    for (int t = 1; t <= 2; t++) {
      vm_ctx_set_threads(ctx, t);
      vm_mesh *m = NULL;
      gen_cube(ctx, 14, 0, &m);
      mark_boundary(m, VM_VERTEX_FIXED, -1);
      jitter_free(ctx, m, 0.6 / 14, 5);
      vm_problem *p = NULL;
      vm_problem_create(ctx, m, &p);
      vm_measure_params prm = vm_measure_params_default();
      prm.eps = 0.05;
      vm_problem_set_measure(p, VM_MEASURE_PENALTY, &prm);
      vm_minimizer *mn = NULL;
      vm_minimizer_create(ctx, p, VM_MINIMIZER_NEWTON, &mn);
      vm_minimize_options o = vm_minimize_options_default();
      o.max_iter = 5;
      o.precond = pc ? VM_PRECOND_AMG : VM_PRECOND_BLOCK_JACOBI;
      o.amg.coarse_size = 60;
      vm_minimizer_set_options(mn, &o);
      vm_minimize_result r;
      vm_minimizer_run(mn, m->xyz, &r);
      CHECK(r.iterations == 5, "threads: %d iterations", r.iterations);
      nv = m->nv;
      res[t - 1] = malloc((size_t)nv * 3 * sizeof(double));
      memcpy(res[t - 1], m->xyz, (size_t)nv * 3 * sizeof(double));
      vm_minimizer_destroy(&mn);
      vm_problem_destroy(&p);
      vm_mesh_destroy(&m);
    }
    vm_ctx_set_threads(ctx, 1);
    CHECK(memcmp(res[0], res[1], (size_t)nv * 3 * sizeof(double)) == 0,
          "newton precond %d: 1 and 2 threads differ", pc);
    free(res[0]);
    free(res[1]);
  }
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  test_measure_psd();
  test_blocks_fd(ctx);
  test_blocks_psd(ctx);
  vm_ctx_set_threads(ctx, 1);
  test_return_to_uniform(ctx);
  test_slip_ball(ctx);
  test_threads(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("newton");
}
