/* bench/bench_assembly.c: throughput of the assembly (quadrature nodes per
 * second for F, F + gradient, F + gradient + Hessian blocks) on jittered
 * uniform hex meshes, with 1 and 2 threads, and the peak resident memory. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "meshgen.h"
#include "varmesh/problem.h"

static double clock_s(clockid_t id) {
  struct timespec ts;
  clock_gettime(id, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static double now(void) { return clock_s(CLOCK_MONOTONIC); }

/* Best wall time of at least 3 runs and at least 0.5 s in total, and the
 * process CPU time of that run (the two differ on a busy machine). */
static double best_time(vm_problem *p, const double *x, int mode, double *g, double *hd, double *ho,
                        int *status, double *cpu) {
  double best = 1e30, total = 0;
  for (int rep = 0; rep < 3 || (total < 0.5 && rep < 100); rep++) {
    double F, t0 = now(), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    if (mode == 0) {
      *status |= vm_problem_value(p, x, &F);
    } else {
      vm_eval ev = {&F, g, mode > 1 ? hd : NULL, mode > 1 ? ho : NULL};
      *status |= vm_problem_eval(p, x, &ev);
    }
    double t = now() - t0, c = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
    total += t;
    if (t < best) {
      best = t;
      *cpu = c;
    }
  }
  return best;
}

static int run(vm_ctx *ctx, int n, int rule) {
  static const char *mode_name[3] = {"F", "F+grad", "F+grad+hess"};
  vm_ctx_seed(ctx, 2014);
  double h = 1.0 / n;
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, n, n, n, h);
  if (!m) return 1;
  mg_jitter(ctx, m, 0.15 * h);
  vm_problem *p = NULL;
  double t0 = now();
  int st = vm_problem_create(ctx, m, &p);
  if (!st) st = vm_problem_set_rule(p, rule);
  double tc = now() - t0;
  if (st) {
    fprintf(stderr, "bench_assembly: %s\n", vm_ctx_error(ctx));
    vm_mesh_destroy(&m);
    return 1;
  }
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  int64_t nn = vm_problem_num_nodes(p);
  double *g = malloc((size_t)m->nv * 3 * sizeof *g);
  double *hd = malloc((size_t)m->nv * 9 * sizeof *hd);
  double *ho = malloc((size_t)rp[m->nv] * 3 * sizeof *ho);
  if (!g || !hd || !ho) return 1;
  printf("hex %d^3 %s rule: %lld elements, %lld vertices, %lld nodes, setup %.1f ms\n", n,
         rule ? "geometric" : "corner", (long long)m->ne, (long long)m->nv, (long long)nn,
         1e3 * tc);
  for (int mode = 0; mode < 3; mode++)
    for (int nt = 1; nt <= 2; nt++) {
      vm_ctx_set_threads(ctx, nt);
      st = 0;
      double cpu = 0, t = best_time(p, m->xyz, mode, g, hd, ho, &st, &cpu);
      printf("  %-12s threads %d: %8.2f ms/pass %7.2f Mnodes/s  cpu %8.2f ms = %6.1f ns/node%s\n",
             mode_name[mode], nt, 1e3 * t, 1e-6 * (double)nn / t, 1e3 * cpu, 1e9 * cpu / (double)nn,
             st ? "  (status != 0)" : "");
    }
  vm_ctx_set_threads(ctx, 0);
  free(g);
  free(hd);
  free(ho);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
  return 0;
}

int main(int argc, char **argv) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  int rc = 0;
  int big = argc > 1 ? atoi(argv[1]) : 64;
  rc |= run(ctx, 32, VM_RULE_CORNER);
  rc |= run(ctx, 32, VM_RULE_GEOMETRIC);
  if (big > 0) rc |= run(ctx, big, VM_RULE_CORNER);
  printf("peak RSS %.1f MB\n", vm_peak_memory_mb());
  vm_ctx_destroy(&ctx);
  return rc;
}
