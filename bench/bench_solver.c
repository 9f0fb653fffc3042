/* bench/bench_solver.c: the implicit minimizer on jittered hex cubes:
 * PCG iteration counts (AMG vs Jacobi) on the per-coordinate Hessian
 * systems, setup/solve times, time of one implicit iteration, AMG reuse
 * across iterations, peak RSS.
 * Usage: bench_solver [max_n (default 64)] [threads (default: OpenMP's)]
 * Jitter is the amplitude of the interior vertices' random displacement in
 * units of h; the worst element (min det) degrades with n at 0.2. The thin
 * slab (cell aspect 20) shows the anisotropic systems of stretched targets. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "meshgen.h"
#include "varmesh/minimize.h"

/* Process CPU seconds: on a shared machine this is steadier than wall time
 * (with one thread it is the compute time of the run). */
static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double peak_rss_mb(void) { return vm_peak_memory_mb(); }

/* The x-coordinate system of the implicit minimizer for a mesh whose free
 * vertices are the interior ones: diagonal (H_vv)_00, off-diagonals
 * (H_uv)_00 between free vertices. */
static int coord_system(vm_ctx *ctx, vm_problem *p, const vm_mesh *m, const double *hdiag,
                        const double *hoff, const double *grad, vm_csr *A, double **b) {
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  int32_t *idx = malloc((size_t)m->nv * sizeof *idx);
  int64_t nu = 0, nnz = 0;
  for (int64_t v = 0; v < m->nv; v++) idx[v] = m->vflag[v] == VM_VERTEX_FREE ? (int32_t)nu++ : -1;
  for (int64_t v = 0; v < m->nv; v++) {
    if (idx[v] < 0) continue;
    nnz++;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++) nnz += idx[adj[k]] >= 0;
  }
  int st = vm_csr_alloc(ctx, A, nu, nnz);
  if (st) return st;
  *b = malloc((size_t)nu * sizeof **b);
  int64_t pos = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int32_t i = idx[v];
    if (i < 0) continue;
    (*b)[i] = -grad[3 * v];
    int diag = 0;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++) {
      int32_t j = idx[adj[k]];
      if (j < 0) continue;
      if (!diag && j > i) {
        A->col[pos] = i;
        A->val[pos++] = hdiag[9 * v];
        diag = 1;
      }
      A->col[pos] = j;
      A->val[pos++] = hoff[3 * k];
    }
    if (!diag) {
      A->col[pos] = i;
      A->val[pos++] = hdiag[9 * v];
    }
    A->rowptr[i + 1] = pos;
  }
  free(idx);
  return VM_OK;
}

typedef struct {
  int its;
  double setup, solve;
} solve_stat;

static solve_stat solve(vm_ctx *ctx, const vm_csr *A, const double *b, vm_precond_kind kind,
                        double rtol) {
  solve_stat s = {0, 0, 0};
  double *x = calloc((size_t)A->n, sizeof *x);
  vm_precond *M = NULL;
  vm_precond_create(ctx, kind, NULL, &M);
  double t0 = cpu_now();
  vm_precond_setup(M, A);
  double t1 = cpu_now();
  vm_pcg_options po = {rtol, 5000};
  vm_pcg_result r;
  vm_pcg_solve(ctx, A, M, b, x, &po, &r);
  s.solve = cpu_now() - t1;
  s.setup = t1 - t0;
  s.its = r.converged ? r.iterations : -r.iterations;
  vm_precond_destroy(&M);
  free(x);
  return s;
}

typedef struct {
  int n;
  double t_first, t_rest; /* seconds: first iteration, mean of the others */
  int pcg_first, pcg_rest;
  double t0;   /* CPU time at the start of the run */
  double last; /* CPU time at the previous iteration */
} run_log;

static void monitor(void *user, const vm_iter_info *in) {
  run_log *L = user;
  double now = cpu_now() - L->t0;
  if (in->iter == 1) {
    L->t_first = now;
    L->pcg_first = in->pcg_iters;
    L->t_rest = 0;
    L->pcg_rest = 0;
    L->n = 0;
  } else {
    L->t_rest += now - L->last;
    L->pcg_rest += in->pcg_iters;
    L->n++;
  }
  L->last = now;
}

static void implicit_iterations(vm_ctx *ctx, vm_problem *p, vm_mesh *m, const double *x0,
                                vm_precond_kind kind, int rebuild, int update_coarse, int iters) {
  vm_minimizer *mn = NULL;
  vm_minimizer_create(ctx, p, VM_MINIMIZER_IMPLICIT, &mn);
  vm_minimize_options o = vm_minimize_options_default();
  o.max_iter = iters;
  o.precond = kind;
  o.amg_rebuild_every = rebuild;
  o.amg.update_coarse = update_coarse;
  o.stats_every = 0;
  o.pcg_maxit = 1000;
  run_log L;
  memset(&L, 0, sizeof L);
  o.monitor = monitor;
  o.user = &L;
  vm_minimizer_set_options(mn, &o);
  memcpy(m->xyz, x0, (size_t)m->nv * 3 * sizeof *x0);
  vm_minimize_result r;
  L.t0 = cpu_now();
  vm_minimizer_run(mn, m->xyz, &r);
  char what[64];
  if (kind != VM_PRECOND_AMG)
    snprintf(what, sizeof what, "Jacobi");
  else if (rebuild == 1)
    snprintf(what, sizeof what, "AMG, new hierarchy every it.");
  else
    snprintf(what, sizeof what, "AMG, built once, %s",
             update_coarse ? "Galerkin update" : "frozen coarse");
  printf("  %-40s iter 1 %.3f s (%3d CG)", what, L.t_first, L.pcg_first);
  if (L.n)
    printf(", iters 2-%d %.3f s/it (%5.1f CG/it)", L.n + 1, L.t_rest / L.n,
           (double)L.pcg_rest / L.n);
  printf(", F %.6f -> %.6f\n", r.F_initial, r.F);
  vm_minimizer_destroy(&mn);
}

/* One mesh: the x-system table row, then (if iters) implicit iterations. */
static void bench_mesh(vm_ctx *ctx, int n, double jitter, double zscale, int iters) {
  vm_mesh *m = NULL;
  gen_cube(ctx, n, 0, &m);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  double *ref = NULL;
  if (zscale != 1) {
    /* a thin slab: cells h x h x zscale h, the uniform slab as target */
    for (int64_t v = 0; v < m->nv; v++) m->xyz[3 * v + 2] *= zscale;
    ref = malloc((size_t)m->nv * 3 * sizeof *ref);
    memcpy(ref, m->xyz, (size_t)m->nv * 3 * sizeof *ref);
    for (int64_t v = 0; v < m->nv; v++) m->xyz[3 * v + 2] /= zscale;
  }
  jitter_free(ctx, m, jitter / n, 1);
  if (zscale != 1)
    for (int64_t v = 0; v < m->nv; v++) m->xyz[3 * v + 2] *= zscale;
  vm_problem *p = NULL;
  if (vm_problem_create(ctx, m, &p) || (ref && vm_problem_set_target_reference(p, ref))) {
    fprintf(stderr, "problem: %s\n", vm_ctx_error(ctx));
    exit(1);
  }
  free(ref);
  vm_node_stats ns;
  vm_problem_node_stats(p, m->xyz, &ns);
  const int64_t *rp;
  vm_problem_graph(p, &rp, NULL);
  double *grad = malloc((size_t)m->nv * 3 * sizeof *grad);
  double *hdiag = malloc((size_t)m->nv * 9 * sizeof *hdiag);
  double *hoff = malloc((size_t)rp[m->nv] * 3 * sizeof *hoff);
  double F;
  vm_eval ev = {&F, grad, hdiag, hoff};
  double t0 = cpu_now();
  int st = vm_problem_eval(p, m->xyz, &ev);
  double teval = cpu_now() - t0;
  if (st) {
    fprintf(stderr, "%d^3 jitter %.2f: eval status %d (inverted start)\n", n, jitter, st);
    exit(1);
  }
  vm_csr A;
  double *b = NULL;
  coord_system(ctx, p, m, hdiag, hoff, grad, &A, &b);
  solve_stat a2 = solve(ctx, &A, b, VM_PRECOND_AMG, 1e-2);
  solve_stat a6 = solve(ctx, &A, b, VM_PRECOND_AMG, 1e-6);
  solve_stat j2 = solve(ctx, &A, b, VM_PRECOND_JACOBI, 1e-2);
  solve_stat j6 = solve(ctx, &A, b, VM_PRECOND_JACOBI, 1e-6);
  vm_precond *M = NULL;
  vm_precond_create(ctx, VM_PRECOND_AMG, NULL, &M);
  vm_precond_setup(M, &A);
  vm_precond_info info;
  vm_precond_get_info(M, &info);
  vm_precond_destroy(&M);
  char name[32];
  if (zscale != 1)
    snprintf(name, sizeof name, "%d^3/%g", n, 1 / zscale);
  else
    snprintf(name, sizeof name, "%d^3", n);
  printf("%-9s %6.2f %7.3f %9lld %7.3f | %6d / %-6d | %6d / %-6d | %7.3f %7.3f %7.3f %3d %5.2f\n",
         name, jitter, ns.min_det, (long long)A.n, teval, a2.its, a6.its, j2.its, j6.its, a6.setup,
         a6.solve, j6.solve, info.levels, info.op_complexity);
  fflush(stdout);
  if (iters > 0) {
    double *x0 = malloc((size_t)m->nv * 3 * sizeof *x0);
    memcpy(x0, m->xyz, (size_t)m->nv * 3 * sizeof *x0);
    implicit_iterations(ctx, p, m, x0, VM_PRECOND_AMG, 1, 1, iters);
    implicit_iterations(ctx, p, m, x0, VM_PRECOND_AMG, iters, 1, iters);
    implicit_iterations(ctx, p, m, x0, VM_PRECOND_AMG, iters, 0, iters);
    implicit_iterations(ctx, p, m, x0, VM_PRECOND_JACOBI, 1, 1, iters);
    printf("  peak RSS %.1f MB\n", peak_rss_mb());
    fflush(stdout);
    free(x0);
  }
  free(b);
  vm_csr_free(ctx, &A);
  free(grad);
  free(hdiag);
  free(hoff);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

int main(int argc, char **argv) {
  int max_n = argc > 1 ? atoi(argv[1]) : 64;
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  if (argc > 2) vm_ctx_set_threads(ctx, atoi(argv[2]));
  printf("threads %d; times are process CPU seconds; x-coordinate system of the first "
         "implicit iteration, PCG from 0\n",
         vm_ctx_threads(ctx) > 0 ? vm_ctx_threads(ctx) : omp_get_max_threads());
  printf("%-9s %6s %7s %9s %7s | %-15s | %-15s | %7s %7s %7s %3s %5s\n", "mesh", "jitter",
         "min det", "unknowns", "eval s", "AMG its 1e-2/-6", "Jac. its 1e-2/-6", "AMGset", "AMGsol",
         "Jac.sol", "lev", "opcx");
  for (int j = 1; j <= 2; j++)
    for (int n = 16; n <= max_n; n *= 2) bench_mesh(ctx, n, 0.1 * j, 1, 0);
  printf("thin slab, cells of aspect 20 (h x h x h/20), uniform slab as target:\n");
  for (int n = 16; n <= max_n; n *= 2) bench_mesh(ctx, n, 0.1, 0.05, 0);
  printf("implicit minimizer, jitter 0.2, 6 iterations, PCG rtol 1e-2, CPU s per iteration "
         "(CG iterations summed over the 3 systems)\n");
  for (int n = 32; n <= max_n; n *= 2) {
    printf("%d^3:\n", n);
    bench_mesh(ctx, n, 0.2, 1, 6);
  }
  vm_ctx_destroy(&ctx);
  return 0;
}
