/* prism/src/solve.c: the layer's variational solves: its problem and
 * targets, minimizer runs with progress, time limit and step budget. */
#include <math.h>
#include <string.h>

#include "state.h"

enum { FALL_WINDOW_MAX = 64 };

static int64_t settle_slivers(vm_prism *p);

typedef struct {
  vm_prism *p;
  vm_prism_phase ph;
  int base;     /* iterations of the solve's earlier runs */
  int budget;   /* > 0: stop after this many iterations once the steps sum to a share of it */
  double share; /* that share (k.budget_step_share) */
  double steps; /* sum of the accepted step lengths (at most 1 each) */
  /* ... and once F falls slowly: by less than `fall` of itself over the
   * last `window` iterations (F after iteration i in F[i % (window + 1)]) */
  int window, last;
  double fall, F[FALL_WINDOW_MAX + 1];
  /* past the budget with the steps still short (the line search held to
   * short steps): stop this run to go on with held retries (hold), and
   * say so (held) */
  int hold, held;
} monitor_data;

static void monitor(void *user, const vm_iter_info *it) {
  monitor_data *d = user;
  int i = d->base + it->iter;
  d->steps += it->tau < 1 ? it->tau : 1;
  d->F[i % (d->window + 1)] = it->F;
  d->last = i;
  /* in the cutting phase the progress steps are rounds (pairs left), not
   * the iterations of the local re-solves */
  if (d->ph != VM_PRISM_PHASE_CUT) pr_progress(d->p, d->ph, i, it->F, it->inverted, 1);
}

static int budget_spent(void *user, int iter, const double *x) {
  (void)x;
  monitor_data *d = user;
  int i = d->base + iter;
  if (i <= d->budget) return 0;
  if (d->steps < d->share * d->budget) {
    if (!d->hold) return 0;
    d->held = 1;
    return 1;
  }
  /* still falling fast: the solve is not done (the demo aircraft's F fell
   * 11 % in the 10 iterations past the budget and settled 50 later) */
  if (d->window > 0 && d->last >= d->window) {
    double f0 = d->F[(d->last - d->window) % (d->window + 1)], f1 = d->F[d->last % (d->window + 1)];
    if (isfinite(f0) && isfinite(f1) && f0 - f1 > d->fall * fabs(f0)) return 0;
  }
  return 1;
}

/* A half model's symmetry plane as the minimizers' slip surface 0: the
 * point with its coordinate across the plane set to the plane's, exactly. */
static int sym_project(void *user, int surf_id, const double x[3], double out[3],
                       double normals[9]) {
  const vm_prism *p = user;
  if (surf_id != 0 || p->sym_ax < 0) return VM_ERR_ARG;
  memcpy(out, x, 3 * sizeof *out);
  out[p->sym_ax] = p->sym_val;
  normals[0] = normals[1] = normals[2] = 0;
  normals[p->sym_ax] = 1;
  return 1;
}

/* One minimizer run of the solve: at most max_iter iterations, hold_tau
 * as given; the slivers settled once if it cannot start. */
static int solve_run(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind,
                     int max_iter, double hold_tau, monitor_data *md, int *iters) {
  *iters = 0;
  double left = pr_time_left(p);
  if (left <= 0) return VM_WARN_TIME;
  vm_minimizer *mz = NULL;
  int st = vm_minimizer_create(p->ctx, prob, kind, &mz);
  if (st) return st;
  if (p->sym_ax >= 0) {
    /* the vertices of the columns in the symmetry plane slide in it */
    for (int64_t i = 0; i < m->nv; i++)
      if (m->vflag[i] == VM_VERTEX_SLIP) m->vsurf[i] = 0;
    vm_surface_ops ops = {sym_project, p, NULL, 1};
    if ((st = vm_minimizer_set_surfaces(mz, &ops))) {
      vm_minimizer_destroy(&mz);
      return st;
    }
  }
  vm_minimize_options mo = vm_minimize_options_default();
  mo.max_iter = max_iter;
  mo.time_limit = isfinite(left) ? left : 0;
  mo.rel_decrease_tol = p->k.rel_decrease_tol;
  mo.rel_decrease_count = p->k.rel_decrease_count;
  mo.hold_tau = hold_tau;
  mo.stats_every = 0;
  mo.monitor = monitor;
  mo.user = md;
  if (md->budget > 0) mo.before_iteration = budget_spent;
  vm_minimize_result res;
  if (!(st = vm_minimizer_set_options(mz, &mo))) st = vm_minimizer_run(mz, m->xyz, &res);
  /* the layer's solve that could not start (F = inf at its first
   * iteration, nothing moved): its slivers settled, once more */
  if (st == VM_ERR_ARG && prob == p->prob && m == p->layer) {
    int64_t n = settle_slivers(p);
    if (n > 0) {
      vm_log(p->ctx, VM_LOG_INFO,
             "prism: %lld slivers the solver judges inverted under their new targets take "
             "their present shape as target",
             (long long)n);
      st = vm_minimizer_run(mz, m->xyz, &res);
    }
  }
  if (st >= 0) {
    *iters = res.iterations;
    p->rep.held_steps += res.held_steps;
  }
  vm_minimizer_destroy(&mz);
  if (st == VM_WARN_MAXITER) st = VM_OK;
  return st;
}

int pr_solve_budget(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind, int max_iter,
                    int budget, vm_prism_phase ph, int *iters) {
  if (iters) *iters = 0;
  if (max_iter <= 0) return VM_OK;
  monitor_data md = {p, ph, 0, budget, p->k.budget_step_share, 0, 0, 0, 0, {0}, 0, 0};
  md.window = p->k.budget_fall_window < FALL_WINDOW_MAX ? p->k.budget_fall_window : FALL_WINDOW_MAX;
  md.fall = p->k.budget_fall;
  md.hold = budget > 0 && p->o.hold_retries && p->k.hold_tau > 0;
  int it = 0;
  int st = solve_run(p, prob, m, kind, max_iter, 0, &md, &it);
  /* (held only where the budget's callback stopped the run: VM_OK, fewer
   * than max_iter iterations done) */
  if (st == VM_OK && md.held) {
    /* held past its budget (o.hold_retries): on with the vertices of the
     * prisms that hold each short step back held still in a retry of it
     * (hold_tau). Only here, so a solve that is not held is what it was: in
     * every solve of
     * the single layer the retries changed the demo aircraft's layer at
     * T = 5 % (faces beyond 70 degrees 914 -> 1,120, plane.stl's 1,173 ->
     * 1,132), and in the marching's stack solves they took that phase
     * from 77 to 340 s at T = 20 % */
    md.base = it;
    md.hold = 0;
    int it2 = 0;
    st = solve_run(p, prob, m, kind, max_iter - it, p->k.hold_tau, &md, &it2);
    it += it2;
  }
  if (iters) *iters = it;
  return st;
}

int pr_solve(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind, int max_iter,
             vm_prism_phase ph, int *iters) {
  return pr_solve_budget(p, prob, m, kind, max_iter, 0, ph, iters);
}

int pr_set_targets(vm_prism *p, const double *hv) {
  vm_field *f = vm_mesh_find_field(p->layer, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT);
  if (!f) return vm_error(p->ctx, VM_ERR_ARG, "prism: layer without targets");
  pr_build_targets(p->nt, p->tri, &p->k.dir, p->wall, p->fnrm, p->dir, hv, f->data);
  return vm_problem_set_target_field(p->prob, PRISM_TARGET_FIELD);
}

int pr_make_problem(vm_prism *p) {
  if (p->prob) return VM_OK;
  int st = vm_problem_create(p->ctx, p->layer, &p->prob);
  if (st) return st;
  vm_measure_params prm = vm_measure_params_default();
  prm.theta = p->o.theta;
  /* the single layer's node targets stay stored however large: the
   * marching's patch (up to every layer) sets the peak, and this problem
   * is freed before it */
  if ((st = vm_problem_set_measure(p->prob, VM_MEASURE_BALANCED, &prm)) ||
      (st = vm_problem_set_rule(p->prob, VM_RULE_GEOMETRIC)) ||
      (st = vm_problem_set_target_store(p->prob, INT64_MAX)))
    return st;
  return VM_OK;
}

/* det C of every node of the layer's problem at its present position
 * (vm_alloc'd, *nq values), or NULL (*nq: a negative status). */
static double *node_dets(vm_prism *p, int64_t *nq) {
  *nq = vm_problem_num_nodes(p->prob);
  double *det = vm_alloc_array(p->ctx, (size_t)(*nq > 0 ? *nq : 1), sizeof *det);
  int st = det ? vm_problem_node_dets(p->prob, p->layer->xyz, det) : VM_ERR_NOMEM;
  if (st) {
    vm_free(p->ctx, det);
    *nq = st;
    return NULL;
  }
  return det;
}

int64_t pr_mark_inverted(vm_prism *p, uint8_t *mark) {
  int64_t nq;
  double *det = node_dets(p, &nq);
  if (!det) return nq;
  memset(mark, 0, (size_t)p->nw);
  const int32_t *ne = vm_problem_node_elements(p->prob);
  int64_t n = 0;
  for (int64_t q = 0; q < nq; q++) {
    if (det[q] > 0 || ne[q] < 0 || ne[q] >= p->nt) continue;
    for (int i = 0; i < 3; i++) mark[p->tri[3 * (int64_t)ne[q] + i]] = 1;
    n++;
  }
  vm_free(p->ctx, det);
  return n;
}

/* A sliver whose node det C is <= 0 in the solver's own rounding, though
 * it and its target are positive by pr_prism_quality (prisms of quality
 * 1e-10 over needles under targets just installed: a public Cessna
 * model's cutting stopped at its 26th local solve, "iteration 1 starts
 * outside the measure's domain"), takes its present shape as its target
 * (det C = 1 there), so that the solve can start. How many, or a negative
 * status. */
static int64_t settle_slivers(vm_prism *p) {
  vm_field *f = vm_mesh_find_field(p->layer, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT);
  if (!f) return 0;
  int64_t nq;
  double *det = node_dets(p, &nq);
  if (!det) return nq;
  const int32_t *ne = vm_problem_node_elements(p->prob);
  double *t = f->data;
  int64_t n = 0;
  for (int64_t q = 0; q < nq; q++) {
    int64_t e = ne[q];
    if (det[q] > 0 || e < 0 || e >= p->nt) continue;
    const int32_t *c = p->layer->conn + 6 * e;
    double y[18];
    for (int i = 0; i < 6; i++) memcpy(y + 3 * i, p->layer->xyz + 3 * (int64_t)c[i], sizeof y / 6);
    if (!memcmp(t + 18 * e, y, sizeof y)) continue;
    memcpy(t + 18 * e, y, sizeof y);
    n++;
  }
  vm_free(p->ctx, det);
  int st = n ? vm_problem_set_target_field(p->prob, PRISM_TARGET_FIELD) : VM_OK;
  return st ? st : n;
}

int pr_check_valid(vm_prism *p, const char *when) {
  vm_node_stats ns;
  int st = vm_problem_node_stats(p->prob, p->layer->xyz, &ns);
  if (st < 0) return st;
  if (ns.inverted)
    return vm_error(p->ctx, VM_ERR_NUMERIC, "prism: %lld inverted nodes after %s",
                    (long long)ns.inverted, when);
  return VM_OK;
}
