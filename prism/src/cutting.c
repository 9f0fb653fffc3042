/* prism/src/cutting.c: phase 3, the cutting of self-intersections: target
 * heights of the columns carrying intersecting faces reduced by a factor
 * close to one and re-solved around them, until none remain. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "state.h"

int pr_layer_intersections(vm_prism *p, uint8_t *mark, int64_t *npairs) {
  int st;
  if (!p->rt && (st = pr_rt_create(p->ctx, &p->rt))) return st;
  if (!p->faces && (st = pr_layer_faces_create(p->ctx, p->rt, &p->k.isect, p->o.check_incremental,
                                               p->nw, p->nt, p->tri, p->ned, p->edge, &p->faces)))
    return st;
  if ((st = pr_layer_faces_query(p->ctx, p->faces, p->layer->xyz, mark, npairs))) return st;
  /* a half model: a top on or beyond the symmetry plane (other than its
   * own columns' there) would meet the mirror image's layer; counted as a
   * pair, its column cut */
  if (p->sym_ax >= 0) {
    const double *top = p->layer->xyz + 3 * p->nw;
    for (int64_t v = 0; v < p->nw; v++)
      if (!pr_on_sym(p, v) && !pr_sym_inside(p, top + 3 * v)) {
        ++*npairs;
        if (mark) mark[v] = 1;
      }
  }
  return VM_OK;
}

/* Re-solve only around the marked columns: the top vertices within
 * k.resolve_rings rings of them move, every prism touching one of those is active, all
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
  for (int r = 0; r < p->k.resolve_rings; r++) {
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
  for (int64_t v = 0; v < nw; v++) fl[v] = reg[v] ? pr_moving_flag(p, v) : VM_VERTEX_FIXED;
  if ((st = vm_problem_set_active(p->prob, act)) == VM_OK) {
    st = pr_solve(p, p->prob, p->layer, VM_MINIMIZER_IMPLICIT, max_iter, VM_PRISM_PHASE_CUT, iters);
    int s2 = vm_problem_set_active(p->prob, NULL);
    if (st >= 0 && s2) st = s2;
  }
  for (int64_t v = 0; v < nw; v++) fl[v] = pr_moving_flag(p, v);
done:
  vm_free(ctx, reg);
  vm_free(ctx, tmp);
  vm_free(ctx, act);
  return st;
}

/* A column cut many times (k.stuck_rounds) whose length stays above
 * k.stuck_ratio times its target (a
 * fold the local solve does not undo: two side faces of the same column
 * crossing at a thin tip) is shortened directly along its side edge by the
 * cut factor, where every prism on it stays valid. In order, so the result
 * does not depend on threads. */
static void shorten_stuck(vm_prism *p, const uint8_t *mark) {
  int64_t nw = p->nw;
  double *x = p->layer->xyz;
  for (int64_t v = 0; v < nw; v++) {
    if (!mark[v] || p->cut[v] < p->k.stuck_rounds) continue;
    double *top = x + 3 * (v + nw), old[3] = {top[0], top[1], top[2]};
    if (!(vm_dist3(top, p->wall + 3 * v) > p->k.stuck_ratio * p->h[v])) continue;
    for (int k = 0; k < 3; k++)
      top[k] = p->wall[3 * v + k] + p->o.cut_factor * (old[k] - p->wall[3 * v + k]);
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
        p->h[v] = fmax(p->h[v] * p->o.cut_factor, p->k.cut_floor * p->elen[v]);
        if (p->cut[v] < 255) p->cut[v]++;
      }
    if ((st = pr_set_targets(p, p->h))) break;
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
    int s2 = pr_check_valid(p, "cutting");
    if (s2) st = s2;
  }
  p->rep.time[VM_PRISM_PHASE_CUT] += omp_get_wtime() - t0;
  if (st >= 0) p->done = 3;
  return st;
}
