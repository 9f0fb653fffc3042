/* prism/src/springback.c: phase 2, elastic springback of the thin layer
 * to its target thickness (implicit solver, targets grown by
 * continuation). */
#include <math.h>
#include <omp.h>

#include "state.h"

/* Column lengths of the layer. */
static void column_lengths(const vm_prism *p, double *len) {
  const double *x = p->layer->xyz;
  for (int64_t v = 0; v < p->nw; v++) len[v] = vm_dist3(x + 3 * v, x + 3 * (v + p->nw));
}

/* Phase 2. The target heights grow by continuation (at most
 * k.springback_grow times the current column length per stage) so each solve starts near its
 * answer; the last stage has the full height T. */
int vm_prism_springback(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 1) return vm_error(p->ctx, VM_ERR_ARG, "prism: springback needs the thin layer");
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  int total = 0, warn = 0;
  int st = pr_make_problem(p);
  if (st) return st;
  double *len = vm_alloc_array(ctx, (size_t)p->nw, sizeof *len);
  double *hs = vm_alloc_array(ctx, (size_t)p->nw, sizeof *hs);
  if (!len || !hs) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  const double grow = p->k.springback_grow;
  column_lengths(p, len);
  for (int stage = 0; stage < p->k.springback_stages; stage++) {
    int last = 1;
    for (int64_t v = 0; v < p->nw; v++) {
      hs[v] = len[v] * pow(grow, stage + 1);
      if (hs[v] >= p->h[v])
        hs[v] = p->h[v];
      else
        last = 0;
    }
    if ((st = pr_set_targets(p, hs))) goto done;
    int it = 0;
    /* the last stage's budget is springback_iter iterations at a step of
     * 1/4 or more: where a few poor prisms (the demo aircraft's wing tips)
     * hold the single line search to 1/16 on every iteration it goes on,
     * up to k.springback_budget_mult times as many iterations */
    st = last ? pr_solve_budget(p, p->prob, p->layer, VM_MINIMIZER_IMPLICIT,
                                p->k.springback_budget_mult * p->o.springback_iter,
                                p->o.springback_iter, VM_PRISM_PHASE_SPRINGBACK, &it)
              : pr_solve(p, p->prob, p->layer, VM_MINIMIZER_IMPLICIT, p->k.springback_stage_iter,
                         VM_PRISM_PHASE_SPRINGBACK, &it);
    total += it;
    if (st == VM_WARN_TIME) warn = st;
    if (st < 0 || st == VM_WARN_TIME) break;
    if (last) break;
  }
  if (st >= 0) st = pr_check_valid(p, "springback");
  if (st == VM_OK) st = warn;
done:
  vm_free(ctx, len);
  vm_free(ctx, hs);
  p->rep.springback_iter += total;
  p->rep.time[VM_PRISM_PHASE_SPRINGBACK] += omp_get_wtime() - t0;
  if (st >= 0) p->done = 2;
  return st;
}
