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

/* Cap the targets of the columns of near-degenerate prisms: a prism with
 * a quadrature node of det C below k.springback_stuck_det against its
 * targets gets at most k.springback_grow times the current length at its
 * columns. Such columns are held back by their neighbours: on a CAD-graded
 * wing, the tiny triangles where the sharp trailing edge meets a cap and
 * the needles along the edge, 1e5 times shorter than their targets. Left
 * at T, their prisms carry F ~ 1e10 and hold the single line search of
 * every solve to a step of 1e-5 or less: the rest of the layer hardly
 * moved (vm-gen wing at T = 20 %: no column at T). Returns the number of
 * columns capped, or a negative status. */
static int64_t cap_stuck(vm_prism *p, const double *len, double *hs, double *det) {
  int st = vm_problem_node_dets(p->prob, p->layer->xyz, det);
  if (st) return st;
  const int32_t *ne = vm_problem_node_elements(p->prob);
  const int64_t nq = vm_problem_num_nodes(p->prob);
  const double lim = p->k.springback_stuck_det, grow = p->k.springback_grow;
  int64_t n = 0;
  for (int64_t q = 0; q < nq; q++) {
    if (!(det[q] < lim)) continue;
    const int32_t *t = p->tri + 3 * (int64_t)ne[q];
    for (int j = 0; j < 3; j++)
      if (hs[t[j]] > grow * len[t[j]]) hs[t[j]] = grow * len[t[j]], n++;
  }
  return n;
}

/* Phase 2. The target heights grow by continuation (at most
 * k.springback_grow times the initial column length per stage) so each
 * solve starts near its answer; the last stage has the full height T.
 * Once a stage's solve was held to a mean step below
 * k.springback_held_step, the columns of near-degenerate prisms are capped
 * in every later stage (cap_stuck). The pipeline's models never trigger
 * it (their stages' mean steps are 1/40 or more). */
int vm_prism_springback(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 1) return vm_error(p->ctx, VM_ERR_ARG, "prism: springback needs the thin layer");
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  int total = 0, warn = 0, held = 0;
  int st = pr_make_problem(p);
  if (st) return st;
  double *len = vm_alloc_array(ctx, (size_t)p->nw, sizeof *len);
  double *hs = vm_alloc_array(ctx, (size_t)p->nw, sizeof *hs);
  double *now = NULL, *det = NULL; /* once held */
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
    if (held) {
      if (!now) now = vm_alloc_array(ctx, (size_t)p->nw, sizeof *now);
      if (!det) det = vm_alloc_array(ctx, (size_t)vm_problem_num_nodes(p->prob), sizeof *det);
      if (!now || !det) {
        st = VM_ERR_NOMEM;
        goto done;
      }
      column_lengths(p, now);
      for (int round = 0; round < 3; round++) {
        int64_t n = cap_stuck(p, now, hs, det);
        if (n < 0) {
          st = (int)n;
          goto done;
        }
        if (!n) break;
        if ((st = pr_set_targets(p, hs))) goto done;
      }
    }
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
    held = held || (it > 0 && p->solve_steps < p->k.springback_held_step * it);
    if (st == VM_WARN_TIME) warn = st;
    if (st < 0 || st == VM_WARN_TIME) break;
    if (last) break;
  }
  if (st >= 0) st = pr_check_valid(p, "springback");
  if (st == VM_OK) st = warn;
done:
  vm_free(ctx, len);
  vm_free(ctx, hs);
  vm_free(ctx, now);
  vm_free(ctx, det);
  p->rep.springback_iter += total;
  p->rep.time[VM_PRISM_PHASE_SPRINGBACK] += omp_get_wtime() - t0;
  if (st >= 0) p->done = 2;
  return st;
}
