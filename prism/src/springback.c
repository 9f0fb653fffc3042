/* prism/src/springback.c: elastic springback of the thin layer to its
 * target thickness (phase 2, implicit solver) and the cutting of
 * self-intersections (phase 3: target heights of intersecting prisms
 * reduced by a factor close to one, re-solved until none remain). */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "prism_private.h"

typedef struct {
  vm_prism *p;
  vm_prism_phase ph;
  int base;
  int budget;     /* > 0: stop after this many iterations once the steps sum to a quarter of it */
  double steps;   /* sum of the accepted step lengths (at most 1 each) */
} monitor_data;

static void monitor(void *user, const vm_iter_info *it) {
  monitor_data *d = user;
  d->steps += it->tau < 1 ? it->tau : 1;
  /* in the cutting phase the progress steps are rounds (pairs left), not
   * the iterations of the local re-solves */
  if (d->ph != VM_PRISM_PHASE_CUT) pr_progress(d->p, d->ph, d->base + it->iter, it->F, it->inverted, 1);
}

static int budget_spent(void *user, int iter, const double *x) {
  (void)x;
  const monitor_data *d = user;
  return iter > d->budget && d->steps >= 0.25 * d->budget;
}

/* pr_solve with an iteration budget counted in steps: past `budget`
 * iterations it goes on (up to max_iter) while the accepted step lengths
 * sum to less than budget / 4, i.e. while the line search keeps cutting
 * the step (budget <= 0: no budget, max_iter iterations). */
static int solve_budget(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind,
                        int max_iter, int budget, vm_prism_phase ph, int *iters) {
  if (iters) *iters = 0;
  if (max_iter <= 0) return VM_OK;
  double left = pr_time_left(p);
  if (left <= 0) return VM_WARN_TIME;
  vm_minimizer *mz = NULL;
  int st = vm_minimizer_create(p->ctx, prob, kind, &mz);
  if (st) return st;
  vm_minimize_options mo = vm_minimize_options_default();
  mo.max_iter = max_iter;
  mo.time_limit = isfinite(left) ? left : 0;
  mo.rel_decrease_tol = 1e-5;
  mo.rel_decrease_count = 2;
  mo.stats_every = 0;
  monitor_data md = {p, ph, 0, budget, 0};
  mo.monitor = monitor;
  mo.user = &md;
  if (budget > 0) mo.before_iteration = budget_spent;
  vm_minimize_result res;
  if (!(st = vm_minimizer_set_options(mz, &mo))) st = vm_minimizer_run(mz, m->xyz, &res);
  if (iters && st >= 0) *iters = res.iterations;
  vm_minimizer_destroy(&mz);
  if (st == VM_WARN_MAXITER) st = VM_OK;
  return st;
}

int pr_solve(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind, int max_iter,
             vm_prism_phase ph, int *iters) {
  return solve_budget(p, prob, m, kind, max_iter, 0, ph, iters);
}

/* Targets from heights hv along the blended directions, installed on the
 * layer's problem. */
static int set_targets(vm_prism *p, const double *hv) {
  vm_field *f = vm_mesh_find_field(p->layer, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT);
  if (!f) return vm_error(p->ctx, VM_ERR_ARG, "prism: layer without targets");
  pr_build_targets(p, p->wall, p->fnrm, p->dir, hv, f->data);
  return vm_problem_set_target_field(p->prob, PRISM_TARGET_FIELD);
}

static int make_problem(vm_prism *p) {
  if (p->prob) return VM_OK;
  int st = vm_problem_create(p->ctx, p->layer, &p->prob);
  if (st) return st;
  vm_measure_params prm = vm_measure_params_default();
  prm.theta = p->o.theta;
  if ((st = vm_problem_set_measure(p->prob, VM_MEASURE_BALANCED, &prm)) ||
      (st = vm_problem_set_rule(p->prob, VM_RULE_GEOMETRIC)))
    return st;
  return VM_OK;
}

/* Column lengths of the layer. */
static void column_lengths(const vm_prism *p, double *len) {
  const double *x = p->layer->xyz;
  for (int64_t v = 0; v < p->nw; v++) len[v] = pr_dist(x + 3 * v, x + 3 * (v + p->nw));
}

static int check_valid(vm_prism *p, const char *when) {
  vm_node_stats ns;
  int st = vm_problem_node_stats(p->prob, p->layer->xyz, &ns);
  if (st < 0) return st;
  if (ns.inverted)
    return vm_error(p->ctx, VM_ERR_NUMERIC, "prism: %lld inverted nodes after %s",
                    (long long)ns.inverted, when);
  return VM_OK;
}

/* Phase 2. The target heights grow by continuation (at most `grow` times
 * the current column length per stage) so each solve starts near its
 * answer; the last stage has the full height T. */
int vm_prism_springback(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 1) return vm_error(p->ctx, VM_ERR_ARG, "prism: springback needs the thin layer");
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  int total = 0, warn = 0;
  int st = make_problem(p);
  if (st) return st;
  double *len = vm_alloc_array(ctx, (size_t)p->nw, sizeof *len);
  double *hs = vm_alloc_array(ctx, (size_t)p->nw, sizeof *hs);
  if (!len || !hs) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  const double grow = 8;
  column_lengths(p, len);
  for (int stage = 0; stage < 60; stage++) {
    int last = 1;
    for (int64_t v = 0; v < p->nw; v++) {
      hs[v] = len[v] * pow(grow, stage + 1);
      if (hs[v] >= p->h[v])
        hs[v] = p->h[v];
      else
        last = 0;
    }
    if ((st = set_targets(p, hs))) goto done;
    int it = 0;
    /* the last stage's budget is springback_iter iterations at a step of
     * 1/4 or more: where a few poor prisms (the demo aircraft's wing tips)
     * hold the single line search to 1/16 on every iteration it goes on,
     * up to 3 times as many iterations */
    st = last ? solve_budget(p, p->prob, p->layer, VM_MINIMIZER_IMPLICIT, 3 * p->o.springback_iter,
                             p->o.springback_iter, VM_PRISM_PHASE_SPRINGBACK, &it)
              : pr_solve(p, p->prob, p->layer, VM_MINIMIZER_IMPLICIT, 5, VM_PRISM_PHASE_SPRINGBACK,
                         &it);
    total += it;
    if (st == VM_WARN_TIME) warn = st;
    if (st < 0 || st == VM_WARN_TIME) break;
    if (last) break;
  }
  if (st >= 0) st = check_valid(p, "springback");
  if (st == VM_OK) st = warn;
done:
  vm_free(ctx, len);
  vm_free(ctx, hs);
  p->rep.springback_iter += total;
  p->rep.time[VM_PRISM_PHASE_SPRINGBACK] += omp_get_wtime() - t0;
  if (st >= 0) p->done = 2;
  return st;
}

/* Re-solve only around the marked columns: the top vertices within a few
 * rings of them move, every prism touching one of those is active, all
 * other top vertices are held fixed for the solve. */
static int local_solve(vm_prism *p, const uint8_t *mark, int max_iter, int *iters) {
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt;
  uint8_t *reg = vm_alloc_array(ctx, (size_t)nw, sizeof *reg);
  uint8_t *tmp = vm_alloc_array(ctx, (size_t)nw, sizeof *tmp);
  uint8_t *act = vm_calloc(ctx, (size_t)nt, sizeof *act);
  int st = VM_OK;
  if (!reg || !tmp || !act) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(reg, mark, (size_t)nw);
  for (int r = 0; r < 4; r++) {
    memcpy(tmp, reg, (size_t)nw);
    for (int64_t v = 0; v < nw; v++)
      if (!tmp[v])
        for (int64_t k = p->vv_off[v]; k < p->vv_off[v + 1]; k++)
          if (tmp[p->vv[k]]) {
            reg[v] = 1;
            break;
          }
  }
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++)
      if (reg[p->tri[3 * t + i]]) act[t] = 1;
  uint8_t *fl = p->layer->vflag + nw;
  for (int64_t v = 0; v < nw; v++) fl[v] = reg[v] ? VM_VERTEX_FREE : VM_VERTEX_FIXED;
  if ((st = vm_problem_set_active(p->prob, act)) == VM_OK) {
    st = pr_solve(p, p->prob, p->layer, VM_MINIMIZER_IMPLICIT, max_iter, VM_PRISM_PHASE_CUT,
                  iters);
    int s2 = vm_problem_set_active(p->prob, NULL);
    if (st >= 0 && s2) st = s2;
  }
  for (int64_t v = 0; v < nw; v++) fl[v] = VM_VERTEX_FREE;
done:
  vm_free(ctx, reg);
  vm_free(ctx, tmp);
  vm_free(ctx, act);
  return st;
}

/* A column cut many times whose length stays above twice its target (a
 * fold the local solve does not undo: two side faces of the same column
 * crossing at a thin tip) is shortened directly along its side edge by the
 * cut factor, where every prism on it stays valid. In order, so the result
 * does not depend on threads. */
static void shorten_stuck(vm_prism *p, const uint8_t *mark) {
  int64_t nw = p->nw;
  double *x = p->layer->xyz;
  for (int64_t v = 0; v < nw; v++) {
    if (!mark[v] || p->cut[v] < 10) continue;
    double *top = x + 3 * (v + nw), old[3] = {top[0], top[1], top[2]};
    if (!(pr_dist(top, p->wall + 3 * v) > 2 * p->h[v])) continue;
    for (int k = 0; k < 3; k++) top[k] = p->wall[3 * v + k] + p->o.cut_factor * (old[k] - p->wall[3 * v + k]);
    int ok = 1;
    for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1] && ok; j++) {
      const int32_t *c = p->layer->conn + 6 * (int64_t)p->vt[j];
      double y[18];
      for (int i = 0; i < 6; i++) memcpy(y + 3 * i, x + 3 * (int64_t)c[i], 3 * sizeof *y);
      ok = pr_prism_quality(y) > 0;
    }
    if (!ok) memcpy(top, old, sizeof old);
  }
}

/* Phase 3. */
int vm_prism_cut(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 2) return vm_error(p->ctx, VM_ERR_ARG, "prism: cutting needs the springback");
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  uint8_t *mark = vm_alloc_array(ctx, (size_t)p->nw, sizeof *mark);
  if (!mark) return VM_ERR_NOMEM;
  int st = VM_OK, round = 0;
  int64_t np = 0;
  for (;; round++) {
    if ((st = pr_layer_intersections(p, mark, &np))) break;
    int64_t nmark = 0;
    for (int64_t v = 0; v < p->nw; v++) nmark += mark[v];
    if (round == 0) p->rep.cut_pairs_first = np;
    pr_progress(p, VM_PRISM_PHASE_CUT, round, (double)np, nmark, 0);
    if (np == 0) break;
    if (round >= p->o.max_cut_rounds) {
      st = VM_WARN_MAXITER;
      break;
    }
    if (pr_time_left(p) <= 0) {
      st = VM_WARN_TIME;
      break;
    }
    for (int64_t v = 0; v < p->nw; v++)
      if (mark[v]) {
        /* floored: a target far flatter than its base is numerically
         * degenerate, and shortening stuck columns takes over there */
        p->h[v] = fmax(p->h[v] * p->o.cut_factor, 1e-3 * p->elen[v]);
        if (p->cut[v] < 255) p->cut[v]++;
      }
    if ((st = set_targets(p, p->h))) break;
    int it = 0;
    st = local_solve(p, mark, p->o.resolve_iter, &it);
    p->rep.springback_iter += it;
    if (st < 0) break;
    if (st == VM_WARN_TIME) break;
    shorten_stuck(p, mark);
  }
  vm_free(ctx, mark);
  p->rep.cut_rounds = round;
  p->rep.intersections = np;
  if (st >= 0) {
    int s2 = check_valid(p, "cutting");
    if (s2) st = s2;
  }
  p->rep.time[VM_PRISM_PHASE_CUT] += omp_get_wtime() - t0;
  if (st >= 0) p->done = 3;
  return st;
}
