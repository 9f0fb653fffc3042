/* test/solver/test_pcg.c: PCG with Jacobi and AMG on Dirichlet Poisson
 * matrices (2D 5/9-point, 3D 7/27-point) and on the implicit minimizer's
 * coordinate systems of jittered hex cubes: convergence, bounded AMG
 * iteration counts under refinement, thread-count independence. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshgen.h"
#include "varmesh/linsolve.h"
#include "varmesh/problem.h"
#include "vmtest.h"

/* Stencil weights by offset class: number of nonzero offsets (0 center,
 * 1 face, 2 edge, 3 corner). */
typedef struct {
  int dim;
  double w[4];
} stencil;

static const stencil ST_5 = {2, {4, -1, 0, 0}};
static const stencil ST_9 = {2, {8.0 / 3, -1.0 / 3, -1.0 / 3, 0}};
static const stencil ST_7 = {3, {6, -1, 0, 0}};
static const stencil ST_27 = {3, {8.0 / 3, 0, -1.0 / 6, -1.0 / 12}};

/* n^dim interior grid points, Dirichlet boundary eliminated. */
static int poisson(vm_ctx *ctx, const stencil *s, int n, vm_csr *A) {
  int64_t N = s->dim == 2 ? (int64_t)n * n : (int64_t)n * n * n;
  int st = vm_csr_alloc(ctx, A, N, N * (s->dim == 2 ? 9 : 27));
  if (st) return st;
  int64_t pos = 0;
  int kr = s->dim == 2 ? 0 : 1;
  for (int64_t r = 0; r < N; r++) {
    int i = (int)(r % n), j = (int)((r / n) % n), k = s->dim == 2 ? 0 : (int)(r / n / n);
    for (int dk = -kr; dk <= kr; dk++)
      for (int dj = -1; dj <= 1; dj++)
        for (int di = -1; di <= 1; di++) {
          int ii = i + di, jj = j + dj, kk = k + dk;
          if (ii < 0 || jj < 0 || kk < 0 || ii >= n || jj >= n || kk >= n) continue;
          int cls = (di != 0) + (dj != 0) + (dk != 0);
          double w = s->w[cls];
          if (w == 0) continue;
          A->col[pos] = (int32_t)(ii + (int64_t)n * (jj + (int64_t)n * kk));
          A->val[pos++] = w;
        }
    A->rowptr[r + 1] = pos;
  }
  return VM_OK;
}

typedef struct {
  int iters;
  double relres;
  double err;
  vm_precond_info info;
} solve_out;

static solve_out solve(vm_ctx *ctx, const vm_csr *A, vm_precond_kind kind, double rtol) {
  solve_out o;
  memset(&o, 0, sizeof o);
  o.iters = -1;
  int64_t n = A->n;
  double *xt = malloc((size_t)n * sizeof *xt), *b = malloc((size_t)n * sizeof *b),
         *x = calloc((size_t)n, sizeof *x);
  vm_ctx_seed(ctx, 42);
  for (int64_t i = 0; i < n; i++) xt[i] = vm_ctx_rand_unit(ctx) - 0.5;
  vm_csr_matvec(ctx, A, xt, b);
  vm_precond *M = NULL;
  int st = vm_precond_create(ctx, kind, NULL, &M);
  if (!st) st = vm_precond_setup(M, A);
  if (!st) vm_precond_get_info(M, &o.info);
  vm_pcg_options po = {rtol, 2000};
  vm_pcg_result pr;
  if (!st) st = vm_pcg_solve(ctx, A, M, b, x, &po, &pr);
  CHECK(st == VM_OK, "pcg status %d", st);
  if (!st) {
    CHECK(pr.converged, "pcg did not converge (%d its, relres %g)", pr.iterations, pr.rel_residual);
    o.iters = pr.iterations;
    o.relres = pr.rel_residual;
    double e = 0, nx = 0;
    for (int64_t i = 0; i < n; i++) {
      e += (x[i] - xt[i]) * (x[i] - xt[i]);
      nx += xt[i] * xt[i];
    }
    o.err = sqrt(e / nx);
  }
  vm_precond_destroy(&M);
  free(xt);
  free(b);
  free(x);
  return o;
}

static void test_small_exact(vm_ctx *ctx) {
  /* a matrix below the coarse size: AMG is a direct solve, 1 iteration */
  vm_csr A;
  CHECK(poisson(ctx, &ST_7, 6, &A) == VM_OK, "poisson");
  solve_out o = solve(ctx, &A, VM_PRECOND_AMG, 1e-10);
  CHECK(o.iters == 1, "direct coarse solve: %d iterations", o.iters);
  CHECK(o.err < 1e-10, "error %g", o.err);
  vm_csr_free(ctx, &A);
}

static void test_scaling(vm_ctx *ctx, const char *name, const stencil *s, const int *ns, int count,
                         double rtol) {
  int amg[3] = {0}, jac[3] = {0};
  for (int c = 0; c < count; c++) {
    vm_csr A;
    CHECK(poisson(ctx, s, ns[c], &A) == VM_OK, "poisson");
    solve_out oa = solve(ctx, &A, VM_PRECOND_AMG, rtol);
    vm_precond_info info = oa.info;
    solve_out oj = solve(ctx, &A, VM_PRECOND_JACOBI, rtol);
    amg[c] = oa.iters;
    jac[c] = oj.iters;
    printf("%-10s n=%3d^%d  unknowns %8lld  AMG %3d its (levels %d, op.cx %.2f, err %.1e)"
           "  Jacobi %4d its\n",
           name, ns[c], s->dim, (long long)A.n, oa.iters, info.levels, info.op_complexity, oa.err,
           oj.iters);
    CHECK(oa.err < 1e-4, "%s: AMG solution error %g", name, oa.err);
    vm_csr_free(ctx, &A);
  }
  CHECK(amg[count - 1] <= 2 * amg[0], "%s: AMG iterations grow: %d -> %d", name, amg[0],
        amg[count - 1]);
  CHECK(jac[count - 1] > 2 * jac[0], "%s: Jacobi iterations should grow: %d -> %d", name, jac[0],
        jac[count - 1]);
  CHECK(amg[count - 1] < jac[count - 1] / 4, "%s: AMG %d vs Jacobi %d", name, amg[count - 1],
        jac[count - 1]);
}

/* The x-coordinate system of the implicit minimizer on an n^3 hex cube
 * with interior vertices jittered by 0.1 h: (H_vv)_00 and (H_uv)_00 over
 * the interior vertices (the boundary is fixed), right side -grad_x. */
static int hessian_system(vm_ctx *ctx, int n, vm_csr *A, double **b) {
  vm_mesh *m = NULL;
  gen_cube(ctx, n, 0, &m);
  mark_boundary(m, VM_VERTEX_FIXED, -1);
  jitter_free(ctx, m, 0.1 / n, 1);
  vm_problem *p = NULL;
  int st = vm_problem_create(ctx, m, &p);
  if (st) return st;
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  double F, *g = malloc((size_t)m->nv * 3 * sizeof *g),
            *hd = malloc((size_t)m->nv * 9 * sizeof *hd),
            *ho = malloc((size_t)rp[m->nv] * 3 * sizeof *ho);
  vm_eval ev = {&F, g, hd, ho};
  st = vm_problem_eval(p, m->xyz, &ev);
  int32_t *idx = malloc((size_t)m->nv * sizeof *idx);
  int64_t nu = 0, nnz = 0, pos = 0;
  for (int64_t v = 0; v < m->nv; v++) idx[v] = m->vflag[v] == VM_VERTEX_FREE ? (int32_t)nu++ : -1;
  for (int64_t v = 0; v < m->nv; v++)
    if (idx[v] >= 0) {
      nnz++;
      for (int64_t k = rp[v]; k < rp[v + 1]; k++) nnz += idx[adj[k]] >= 0;
    }
  if (!st) st = vm_csr_alloc(ctx, A, nu, nnz);
  *b = malloc((size_t)(nu > 0 ? nu : 1) * sizeof **b);
  for (int64_t v = 0; v < m->nv && !st; v++) {
    int32_t i = idx[v];
    if (i < 0) continue;
    (*b)[i] = -g[3 * v];
    int diag = 0;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++) {
      int32_t j = idx[adj[k]];
      if (j < 0) continue;
      if (!diag && j > i) {
        A->col[pos] = i;
        A->val[pos++] = hd[9 * v];
        diag = 1;
      }
      A->col[pos] = j;
      A->val[pos++] = ho[3 * k];
    }
    if (!diag) {
      A->col[pos] = i;
      A->val[pos++] = hd[9 * v];
    }
    A->rowptr[i + 1] = pos;
  }
  free(idx);
  free(g);
  free(hd);
  free(ho);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
  return st;
}

static void test_hessian_systems(vm_ctx *ctx) {
  int amg[2], jac[2];
  for (int c = 0; c < 2; c++) {
    int n = c ? 32 : 16;
    vm_csr A;
    double *b = NULL;
    CHECK(hessian_system(ctx, n, &A, &b) == VM_OK, "hessian system: %s", vm_ctx_error(ctx));
    vm_pcg_options po = {1e-6, 1000};
    for (int k = 0; k < 2; k++) {
      double *x = calloc((size_t)A.n, sizeof *x);
      vm_precond *M = NULL;
      vm_precond_create(ctx, k ? VM_PRECOND_JACOBI : VM_PRECOND_AMG, NULL, &M);
      CHECK(vm_precond_setup(M, &A) == VM_OK, "setup");
      vm_pcg_result r;
      CHECK(vm_pcg_solve(ctx, &A, M, b, x, &po, &r) == VM_OK && r.converged, "solve");
      (k ? jac : amg)[c] = r.iterations;
      vm_precond_destroy(&M);
      free(x);
    }
    printf("hex Hessian x-system %d^3 (jitter 0.1 h): AMG %d its, Jacobi %d its (rtol 1e-6)\n", n,
           amg[c], jac[c]);
    free(b);
    vm_csr_free(ctx, &A);
  }
  CHECK(amg[1] <= amg[0] + amg[0] / 2, "AMG iterations grow: %d -> %d", amg[0], amg[1]);
  CHECK(amg[1] < jac[1] / 4, "AMG %d vs Jacobi %d", amg[1], jac[1]);
}

/* Same bits for 1 and 2 threads (also exercises the parallel branches). */
static void test_threads(vm_ctx *ctx) {
  vm_csr A;
  CHECK(poisson(ctx, &ST_27, 40, &A) == VM_OK, "poisson");
  int64_t n = A.n;
  double *b = malloc((size_t)n * sizeof *b), *x1 = calloc((size_t)n, sizeof *x1),
         *x2 = calloc((size_t)n, sizeof *x2);
  for (int64_t i = 0; i < n; i++) b[i] = sin(0.001 * (double)i) + 1;
  vm_pcg_options po = {1e-8, 500};
  vm_pcg_result r1, r2;
  for (int t = 1; t <= 2; t++) {
    vm_ctx_set_threads(ctx, t);
    vm_precond *M = NULL;
    vm_precond_create(ctx, VM_PRECOND_AMG, NULL, &M);
    vm_precond_setup(M, &A);
    vm_pcg_solve(ctx, &A, M, b, t == 1 ? x1 : x2, &po, t == 1 ? &r1 : &r2);
    vm_precond_destroy(&M);
  }
  vm_ctx_set_threads(ctx, 1);
  CHECK(r1.iterations == r2.iterations, "iterations %d vs %d", r1.iterations, r2.iterations);
  CHECK(memcmp(x1, x2, (size_t)n * sizeof *x1) == 0, "1 vs 2 threads differ");
  free(b);
  free(x1);
  free(x2);
  vm_csr_free(ctx, &A);
}

/* update(): new values on the same pattern reuse the prolongators. */
static void test_update(vm_ctx *ctx) {
  vm_csr A;
  CHECK(poisson(ctx, &ST_27, 24, &A) == VM_OK, "poisson");
  vm_precond *M = NULL;
  vm_precond_create(ctx, VM_PRECOND_AMG, NULL, &M);
  CHECK(vm_precond_setup(M, &A) == VM_OK, "setup");
  /* scale by a smooth positive coefficient, symmetrically */
  int64_t n = A.n;
  for (int64_t i = 0; i < n; i++)
    for (int64_t k = A.rowptr[i]; k < A.rowptr[i + 1]; k++) {
      double ci = 1 + 0.5 * sin(0.01 * (double)i), cj = 1 + 0.5 * sin(0.01 * (double)A.col[k]);
      A.val[k] *= sqrt(ci * cj);
    }
  CHECK(vm_precond_update(M, &A) == VM_OK, "update");
  size_t nb = (size_t)(n > 0 ? n : 1);
  double *b = malloc(nb * sizeof *b), *x = calloc(nb, sizeof *x);
  for (int64_t i = 0; i < n; i++) b[i] = 1;
  vm_pcg_options po = {1e-8, 200};
  vm_pcg_result r;
  CHECK(vm_pcg_solve(ctx, &A, M, b, x, &po, &r) == VM_OK, "solve");
  CHECK(r.converged && r.iterations < 30, "after update: %d its", r.iterations);
  vm_precond_destroy(&M);
  free(b);
  free(x);
  vm_csr_free(ctx, &A);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_threads(ctx, 1); /* fast on a loaded machine; test_threads checks 2 threads */
  test_small_exact(ctx);
  const int n2[] = {64, 128, 256};
  const int n3[] = {16, 32, 64};
  test_scaling(ctx, "2D 5-pt", &ST_5, n2, 3, 1e-8);
  test_scaling(ctx, "2D 9-pt", &ST_9, n2, 3, 1e-8);
  test_scaling(ctx, "3D 7-pt", &ST_7, n3, 3, 1e-8);
  test_scaling(ctx, "3D 27-pt", &ST_27, n3, 3, 1e-8);
  test_hessian_systems(ctx);
  test_threads(ctx);
  test_update(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_pcg");
}
