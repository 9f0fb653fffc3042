/* lib/core/src/minimize.c: the minimizer interface and driver: projected
 * gradient (30), line search on tau (33), (37), stopping rules, monitor. */
#include <math.h>
#include <stdlib.h>
#include <omp.h>
#include <string.h>

#include "linsolve_private.h"
#include "minimize_private.h"

/* F differences below this fraction of |F| are treated as rounding noise:
 * the line search then judges a step by the directional derivative. */
#define LS_NOISE 1e-10
/* Approximate Armijo condition of Hager and Zhang, delta = 0.1. */
#define LS_APPROX_DELTA 0.1
#define LS_MIN_TAU 1e-14
/* hold_tau: steps short of it that go without a retry after one that did
 * not pay (the demo aircraft's springback at T = 20 %: 189 of 236 retries
 * lost; skipping 2 after each loss took its time from 63 to 43 s for a
 * reach of 88.2 % instead of 90.4 %) */
#define HOLD_SKIP 2
/* hold_tau: rounds of held vertices, each adding the elements that still
 * hold the new full step back */
#define HOLD_ROUNDS 3

vm_minimize_options vm_minimize_options_default(void) {
  vm_minimize_options o;
  memset(&o, 0, sizeof o);
  o.max_iter = 200;
  o.time_limit = 0;
  o.rel_decrease_tol = 1e-10;
  o.rel_decrease_count = 2;
  o.grad_atol = 0;
  o.grad_rtol = 1e-10;
  o.armijo = 1e-4;
  o.ls_max_evals = 40;
  o.ls_extrapolate = 2;
  o.pcg_rtol = 1e-2;
  o.pcg_maxit = 100;
  o.precond = VM_PRECOND_AMG;
  o.amg = vm_amg_options_default();
  o.amg.update_coarse = 0;
  o.amg_rebuild_every = 4;
  o.stats_every = 1;
  return o;
}

const char *vm_stop_reason_name(vm_stop_reason r) {
  switch (r) {
  case VM_STOP_REL_DECREASE: return "rel-decrease";
  case VM_STOP_GRAD_NORM: return "grad-norm";
  case VM_STOP_MAX_ITER: return "max-iter";
  case VM_STOP_TIME: return "time-limit";
  case VM_STOP_LINE_SEARCH: return "line-search";
  case VM_STOP_INTERRUPTED: return "interrupted";
  case VM_STOP_CALLBACK: return "callback";
  default: return "none";
  }
}

int vm_minimizer_create(vm_ctx *ctx, vm_problem *problem, vm_minimizer_kind kind,
                        vm_minimizer **out) {
  static const vm_minimizer_ops *const table[] = {
      &vm_minimizer_explicit_ops, &vm_minimizer_implicit_ops, &vm_minimizer_newton_ops};
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_minimizer_create: out is NULL");
  *out = NULL;
  if (!problem) return vm_error(ctx, VM_ERR_ARG, "vm_minimizer_create: problem is NULL");
  if ((int)kind < 0 || (int)kind > 2)
    return vm_error(ctx, VM_ERR_ARG, "vm_minimizer_create: unknown kind %d", (int)kind);
  vm_minimizer *m = vm_calloc(ctx, 1, sizeof *m);
  if (!m) return VM_ERR_NOMEM;
  m->ctx = ctx;
  m->prob = problem;
  m->kind = kind;
  m->ops = table[kind];
  m->opt = vm_minimize_options_default();
  *out = m;
  return VM_OK;
}

void vm_minimizer_destroy(vm_minimizer **p) {
  if (!p || !*p) return;
  vm_minimizer *m = *p;
  m->ops->end(m);
  vm_bc_destroy(&m->bc);
  vm_free(m->ctx, m);
  *p = NULL;
}

int vm_minimizer_set_options(vm_minimizer *m, const vm_minimize_options *o) {
  if (!m || !o) return VM_ERR_ARG;
  if (o->max_iter < 0 || !(o->armijo > 0 && o->armijo < 0.5) || o->ls_max_evals < 1 ||
      !(o->pcg_rtol > 0 && o->pcg_rtol < 1) || o->pcg_maxit < 1 || o->rel_decrease_tol < 0 ||
      o->grad_atol < 0 || o->grad_rtol < 0 || o->amg_rebuild_every < 1 || (int)o->precond < 0 ||
      !(o->hold_tau >= 0 && o->hold_tau <= 1) || (int)o->precond > VM_PRECOND_BLOCK_JACOBI ||
      o->stats_every < 0 || o->ls_extrapolate < 0)
    return vm_error(m->ctx, VM_ERR_ARG, "vm_minimizer_set_options: invalid option value");
  m->opt = *o;
  if (m->opt.rel_decrease_count < 1) m->opt.rel_decrease_count = 1;
  return VM_OK;
}

const vm_minimize_options *vm_minimizer_options(const vm_minimizer *m) { return &m->opt; }

int vm_minimizer_set_surfaces(vm_minimizer *m, const vm_surface_ops *surf) {
  if (!m) return VM_ERR_ARG;
  m->has_surf = surf != NULL;
  if (surf) m->surf = *surf;
  return VM_OK;
}

const char *vm_minimizer_name(const vm_minimizer *m) { return m->ops->name; }

/* Work arrays of one run. xa/xb are trial buffers whose fixed-vertex
 * entries equal x from the start and are never written. */
typedef struct {
  double *g, *hdiag, *hoff, *d, *xa, *xb, *gt;
  int64_t nhoff;
  /* hold_tau only, allocated at the first retry: the first search's
   * point, the elements' values at x and at a trial point, their rises,
   * the held vertices */
  double *xsave, *fe0, *fe1;
  struct elem_rise_s *rise;
  uint8_t *hold;
} run_bufs;

static void free_bufs(vm_ctx *ctx, run_bufs *b) {
  vm_free(ctx, b->g);
  vm_free(ctx, b->hdiag);
  vm_free(ctx, b->hoff);
  vm_free(ctx, b->d);
  vm_free(ctx, b->xa);
  vm_free(ctx, b->xb);
  vm_free(ctx, b->gt);
  vm_free(ctx, b->xsave);
  vm_free(ctx, b->fe0);
  vm_free(ctx, b->fe1);
  vm_free(ctx, b->rise);
  vm_free(ctx, b->hold);
  memset(b, 0, sizeof *b);
}

/* Copy the non-fixed vertices of src into x. */
static void commit(const vm_minimizer *m, const double *src, double *x) {
  int nt = vm_nthreads(m->ctx);
  const int64_t nv = m->nv;
#pragma omp parallel for num_threads(nt) schedule(static) if (nv >= VM_PAR_MIN)
  for (int64_t v = 0; v < nv; v++)
    if (vm_bc_class(m->bc, v) != VM_VERTEX_FIXED) memcpy(x + 3 * v, src + 3 * v, 3 * sizeof *x);
}

/* F at V(x + tau d) into *F (+INFINITY outside the domain or when a
 * projection fails). Returns VM_OK or a hard error. */
static int trial_value(vm_minimizer *m, const double *x, const double *d, double tau, double *xt,
                       double *F) {
  int st = vm_bc_step(m->bc, x, d, tau, xt);
  if (st < 0) {
    *F = INFINITY;
    return VM_OK;
  }
  st = vm_problem_value(m->prob, xt, F);
  if (st < 0) return st;
  if (st > 0 || !isfinite(*F)) *F = INFINITY;
  if (isfinite(*F) && m->opt.admissible && !m->opt.admissible(m->opt.user, xt)) *F = INFINITY;
  return VM_OK;
}

typedef struct {
  int accepted;
  double tau, F;
  int evals, infeasible;
  double *x; /* buffer holding the accepted point */
} ls_result;

/* Backtracking line search on tau from 1 with the Armijo condition,
 * quadratic interpolation, the approximate Armijo test when F is at its
 * rounding level, and up to ls_extrapolate longer tries after a full step. */
static int line_search(vm_minimizer *m, const double *x, const double *d, double F0, double gd,
                       run_bufs *b, ls_result *out) {
  const vm_minimize_options *o = &m->opt;
  const int64_t n3 = 3 * m->nv;
  double noise = LS_NOISE * fabs(F0);
  double tau = 1.0, F = INFINITY;
  double *xt = b->xa, *xs = b->xb;
  memset(out, 0, sizeof *out);
  int st, approx = 0;
  for (int k = 0; k < o->ls_max_evals; k++) {
    st = trial_value(m, x, d, tau, xt, &F);
    if (st) return st;
    out->evals++;
    if (isfinite(F)) {
      int ok = F <= F0 + o->armijo * tau * gd;
      if (!ok && F <= F0 + noise) {
        approx = 1;
        vm_eval ev = {NULL, b->gt, NULL, NULL};
        double Ft;
        ev.F = &Ft;
        st = vm_problem_eval(m->prob, xt, &ev);
        if (st < 0) return st;
        if (st == VM_OK) {
          vm_bc_apply(m->bc, b->gt);
          double gtd = vm_dot(m->ctx, n3, b->gt, d);
          ok = gtd <= (2 * LS_APPROX_DELTA - 1) * gd;
        }
      }
      if (ok) {
        out->accepted = 1;
        break;
      }
      double den = 2 * (F - F0 - gd * tau);
      double tq = den > 0 ? -gd * tau * tau / den : 0.5 * tau;
      tau = tq < 0.1 * tau ? 0.1 * tau : tq > 0.5 * tau ? 0.5 * tau : tq;
    } else {
      out->infeasible++;
      tau *= 0.25;
    }
    if (tau < LS_MIN_TAU) break;
  }
  if (!out->accepted) return VM_OK;
  out->tau = tau;
  out->F = F;
  out->x = xt;
  if (tau != 1.0 || approx) return VM_OK;
  for (int e = 0; e < o->ls_extrapolate && out->evals < o->ls_max_evals; e++) {
    double t = out->tau, Ft = out->F;
    double den = 2 * (Ft - F0 - gd * t);
    double tq = den > 0 ? -gd * t * t / den : 4 * t;
    if (tq < 1.5 * t) break;
    if (tq > 4 * t) tq = 4 * t;
    double Fe;
    st = trial_value(m, x, d, tq, xs, &Fe);
    if (st) return st;
    out->evals++;
    if (!isfinite(Fe)) out->infeasible++;
    if (!(Fe < out->F) || !(Fe <= F0 + o->armijo * tq * gd)) break;
    out->tau = tq;
    out->F = Fe;
    out->x = xs;
    double *sw = xs;
    xs = xt;
    xt = sw;
  }
  return VM_OK;
}

/* Diagonally scaled projected gradient, used when the member's direction
 * is not a descent direction (a numerical breakdown). */
static void fallback_direction(const vm_minimizer *m, const double *g, const double *hdiag,
                               double *d) {
  for (int64_t v = 0; v < m->nv; v++) {
    const double *H = hdiag + 9 * v;
    double s = (H[0] + H[4] + H[8]) / m->sdim;
    if (!(s > 0) || !isfinite(s)) s = 1;
    for (int k = 0; k < 3; k++) d[3 * v + k] = -g[3 * v + k] / s;
  }
  vm_bc_apply(m->bc, d);
}

/* An element's change of F over a full step, for sorting. */
typedef struct elem_rise_s {
  double rise;
  int64_t e;
} elem_rise;

static int cmp_rise(const void *a, const void *b) {
  const elem_rise *x = a, *y = b;
  if (x->rise != y->rise) return x->rise > y->rise ? -1 : 1;
  return (x->e > y->e) - (x->e < y->e);
}

/* Can vertex v still be held (neither held yet nor fixed)? */
static int holdable(const vm_minimizer *m, const run_bufs *b, int32_t v) {
  return !b->hold[v] && vm_bc_class(m->bc, v) != VM_VERTEX_FIXED;
}

/* Hold still the vertices of the elements that hold the step x + d
 * back: each element's change of F over the full step (+inf where it
 * turns over), the largest rises first, until the other elements' changes
 * sum to at most gd / 4 (gd < 0: half the decrease a Newton step's model
 * expects), at most a twentieth of the elements (and 16). b->fe0 holds
 * the elements' values at x. Marks them in b->hold; returns how many
 * vertices (free or sliding) were newly marked, or a negative status. */
static int64_t hold_blocking(vm_minimizer *m, const double *x, const double *d, double gd,
                             run_bufs *b) {
  int st = vm_bc_step(m->bc, x, d, 1.0, b->xa);
  if (st < 0) return 0;
  const vm_mesh *mesh = vm_problem_mesh(m->prob);
  if ((st = vm_problem_elem_values(m->prob, b->xa, b->fe1)) < 0) return st;
  double rest = 0;
  int64_t nc = 0;
  for (int64_t e = 0; e < mesh->ne; e++) {
    double r = b->fe1[e] - b->fe0[e];
    if (!(r > 0)) {
      rest += r;
      continue;
    }
    int open = 0; /* a vertex of e can still be held */
    for (int64_t k = mesh->eoff[e]; k < mesh->eoff[e + 1] && !open; k++)
      open = holdable(m, b, mesh->conn[k]);
    if (!open) continue;
    if (isfinite(r)) rest += r;
    b->rise[nc].rise = r;
    b->rise[nc++].e = e;
  }
  qsort(b->rise, (size_t)nc, sizeof *b->rise, cmp_rise);
  int64_t cap = mesh->ne / 20 > 16 ? mesh->ne / 20 : 16, n = 0;
  for (int64_t j = 0; j < nc && j < cap; j++) {
    double r = b->rise[j].rise;
    if (isfinite(r) && rest <= 0.25 * gd) break;
    if (isfinite(r)) rest -= r;
    int64_t e = b->rise[j].e;
    for (int64_t k = mesh->eoff[e]; k < mesh->eoff[e + 1]; k++) {
      int32_t v = mesh->conn[k];
      if (!holdable(m, b, v)) continue;
      b->hold[v] = 1;
      n++;
    }
  }
  return n;
}

/* The step again with the held vertices still: their gradient and their
 * couplings to the others zeroed, so the others' direction is solved as
 * if they were fixed (a descent direction: the projected system stays
 * SPD), and their own entries of d zeroed. */
static int held_direction(vm_minimizer *m, int iter, run_bufs *b, int *lin) {
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(m->prob, &rp, &adj);
  const int bs = m->ops->needs_hoff == 2 ? 9 : m->ops->needs_hoff ? 3 : 0;
  for (int64_t v = 0; v < m->nv; v++) {
    if (b->hold[v]) memset(b->g + 3 * v, 0, 3 * sizeof *b->g);
    if (!bs) continue;
    for (int64_t k = rp[v]; k < rp[v + 1]; k++)
      if (b->hold[v] || b->hold[adj[k]]) memset(b->hoff + bs * k, 0, (size_t)bs * sizeof *b->hoff);
  }
  int l = 0;
  int st = m->ops->direction(m, iter, b->g, b->hdiag, b->hoff, b->d, &l);
  *lin += l;
  if (st < 0) return st;
  for (int64_t v = 0; v < m->nv; v++)
    if (b->hold[v]) memset(b->d + 3 * v, 0, 3 * sizeof *b->d);
  return VM_OK;
}

/* hold_tau: the step from x (F0, directional derivative gd0 along b->d)
 * that the line search cut below hold_tau or refused, tried again with
 * the vertices of the elements that hold the full step back held still
 * (up to HOLD_ROUNDS rounds). *ls becomes the better of the two searches;
 * *held the vertices held in it (0: the first search kept). b->g, b->hoff
 * and b->d are spent. */
static int hold_retry(vm_minimizer *m, const double *x, double F0, double gd0, int iter,
                      run_bufs *b, ls_result *ls, int *lin, int64_t *held) {
  vm_ctx *ctx = m->ctx;
  const int64_t n3 = 3 * m->nv;
  const int64_t ne = vm_problem_mesh(m->prob)->ne;
  *held = 0;
  if (!b->xsave) {
    size_t sne = (size_t)(ne > 0 ? ne : 1);
    b->xsave = vm_alloc_array(ctx, (size_t)(n3 > 0 ? n3 : 1), sizeof *b->xsave);
    b->fe0 = vm_alloc_array(ctx, sne, sizeof *b->fe0);
    b->fe1 = vm_alloc_array(ctx, sne, sizeof *b->fe1);
    b->rise = vm_alloc_array(ctx, sne, sizeof *b->rise);
    b->hold = vm_alloc_array(ctx, (size_t)(m->nv > 0 ? m->nv : 1), sizeof *b->hold);
    if (!b->xsave || !b->fe0 || !b->fe1 || !b->rise || !b->hold) return VM_ERR_NOMEM;
  }
  /* the first search's point out of the trial buffers the retry uses */
  double F1 = ls->accepted ? ls->F : F0;
  if (ls->accepted && ls->x != b->xsave) {
    memcpy(b->xsave, ls->x, (size_t)n3 * sizeof *x);
    ls->x = b->xsave;
  }
  int st = vm_problem_elem_values(m->prob, x, b->fe0);
  if (st < 0) return st;
  memset(b->hold, 0, (size_t)m->nv);
  int64_t nh = hold_blocking(m, x, b->d, gd0, b);
  if (nh <= 0) return nh < 0 ? (int)nh : VM_OK;
  int64_t total = nh;
  double gd = 0;
  for (int round = 0; round < HOLD_ROUNDS; round++) {
    if ((st = held_direction(m, iter, b, lin)) < 0) return st;
    gd = vm_dot(ctx, n3, b->g, b->d);
    if (!(gd < 0)) return VM_OK;
    double Ft;
    if ((st = trial_value(m, x, b->d, 1.0, b->xa, &Ft))) return st;
    if (Ft <= F0 + m->opt.armijo * gd || round == HOLD_ROUNDS - 1) break;
    int64_t more = hold_blocking(m, x, b->d, gd, b);
    if (more < 0) return (int)more;
    if (more == 0) break;
    total += more;
  }
  ls_result l2;
  st = line_search(m, x, b->d, F0, gd, b, &l2);
  if (st < 0) return st;
  if (l2.accepted && l2.F < F1) {
    *ls = l2;
    *held = total;
  }
  return VM_OK;
}

static void node_stats(vm_minimizer *m, const double *x, int64_t *inv, double *mindet) {
  vm_node_stats st;
  if (vm_problem_node_stats(m->prob, x, &st) >= 0) {
    *inv = st.inverted;
    *mindet = st.min_det;
  } else {
    *inv = -1;
    *mindet = NAN;
  }
}

int vm_minimizer_run(vm_minimizer *m, double *x, vm_minimize_result *res) {
  if (!m || !x) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  const vm_minimize_options *o = &m->opt;
  double t0 = omp_get_wtime();
  const vm_mesh *mesh = vm_problem_mesh(m->prob);
  vm_minimize_result r;
  memset(&r, 0, sizeof r);
  r.inverted = -1;
  r.min_det = NAN;
  r.F = r.F_initial = NAN;
  if (res) *res = r;
  m->nv = mesh->nv;
  m->sdim = mesh->dim == 2 ? 2 : 3;
  run_bufs b;
  memset(&b, 0, sizeof b);
  vm_bc_destroy(&m->bc);
  int st = vm_bc_create(ctx, mesh, m->has_surf ? &m->surf : NULL, &m->bc);
  if (st) return st;
  /* the fixed vertices' rows are discarded (vm_bc_apply, the members'
   * unknowns): the elements that reach only them add F alone */
  vm_problem_set_fixed_derivatives(m->prob, 0);
  const size_t n3 = (size_t)(3 * m->nv > 0 ? 3 * m->nv : 1);
  if (m->ops->needs_hoff) {
    const int64_t *rp;
    const int32_t *adj;
    vm_problem_graph(m->prob, &rp, &adj);
    b.nhoff = (m->ops->needs_hoff == 2 ? 9 : 3) * rp[m->nv];
    b.hoff = vm_alloc_array(ctx, b.nhoff > 0 ? (size_t)b.nhoff : 1, sizeof *b.hoff);
    if (!b.hoff) st = VM_ERR_NOMEM;
  }
  b.g = vm_alloc_array(ctx, n3, sizeof *b.g);
  b.hdiag = vm_alloc_array(ctx, 3 * n3, sizeof *b.hdiag);
  b.d = vm_alloc_array(ctx, n3, sizeof *b.d);
  b.xa = vm_alloc_array(ctx, n3, sizeof *b.xa);
  b.xb = vm_alloc_array(ctx, n3, sizeof *b.xb);
  b.gt = vm_alloc_array(ctx, n3, sizeof *b.gt);
  if (st || !b.g || !b.hdiag || !b.d || !b.xa || !b.xb || !b.gt) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  st = vm_bc_project(m->bc, x);
  if (st) goto done;
  memcpy(b.xa, x, (size_t)m->nv * 3 * sizeof *x);
  memcpy(b.xb, x, (size_t)m->nv * 3 * sizeof *x);
  m->last_tau = 0;
  m->last_infeasible = 0;
  st = m->ops->begin(m);
  if (st) goto done;

  double g0 = -1, F = NAN;
  int stall = 0, hold_skip = 0;
  const int64_t nn3 = 3 * m->nv;
  for (int iter = 1;; iter++) {
    if (vm_ctx_interrupted(ctx)) {
      r.reason = VM_STOP_INTERRUPTED;
      st = vm_error(ctx, VM_ERR_INTERRUPTED, "minimizer interrupted at iteration %d", iter);
      break;
    }
    if (iter > o->max_iter) {
      r.reason = VM_STOP_MAX_ITER;
      st = VM_WARN_MAXITER;
      break;
    }
    if (o->time_limit > 0 && omp_get_wtime() - t0 >= o->time_limit) {
      r.reason = VM_STOP_TIME;
      st = VM_WARN_TIME;
      break;
    }
    if (o->before_iteration) {
      int h = o->before_iteration(o->user, iter, x);
      if (h > 0) {
        r.reason = VM_STOP_CALLBACK;
        st = VM_OK;
        break;
      }
      if (h < 0) {
        st = h;
        break;
      }
    }
    if (m->ops->needs_hoff == 2) {
      vm_eval_blocks eb = {&F, b.g, b.hdiag, b.hoff, 1};
      st = vm_problem_eval_blocks(m->prob, x, &eb);
    } else {
      vm_eval ev = {&F, b.g, b.hdiag, m->ops->needs_hoff ? b.hoff : NULL};
      st = vm_problem_eval(m->prob, x, &ev);
    }
    if (st < 0) break;
    if (st > 0 || !isfinite(F)) {
      st = vm_error(ctx, VM_ERR_ARG, "iteration %d starts outside the measure's domain (F = %g)",
                    iter, F);
      break;
    }
    if (iter == 1) r.F_initial = F;
    r.F = F;
    vm_bc_apply(m->bc, b.g);
    double gn = sqrt(vm_dot(ctx, nn3, b.g, b.g));
    if (g0 < 0) g0 = gn;
    r.grad_norm = gn;
    if (!isfinite(gn)) {
      st = vm_error(ctx, VM_ERR_NUMERIC, "non-finite gradient at iteration %d", iter);
      break;
    }
    if (gn == 0 || gn <= o->grad_atol || gn <= o->grad_rtol * g0) {
      r.reason = VM_STOP_GRAD_NORM;
      st = VM_OK;
      break;
    }
    int lin = 0;
    st = m->ops->direction(m, iter, b.g, b.hdiag, b.hoff, b.d, &lin);
    if (st < 0) break;
    r.pcg_iterations += lin;
    double gd = vm_dot(ctx, nn3, b.g, b.d);
    if (!(gd < 0)) {
      fallback_direction(m, b.g, b.hdiag, b.d);
      gd = vm_dot(ctx, nn3, b.g, b.d);
    }
    ls_result ls;
    st = line_search(m, x, b.d, F, gd, &b, &ls);
    if (st < 0) break;
    int64_t held = 0;
    if (o->hold_tau > 0 && (!ls.accepted || ls.tau < o->hold_tau) && hold_skip-- <= 0) {
      int l2 = 0;
      st = hold_retry(m, x, F, gd, iter, &b, &ls, &l2, &held);
      lin += l2;
      r.pcg_iterations += l2;
      if (st < 0) break;
      if (held) r.held_steps++;
      /* a retry that did not pay: the next HOLD_SKIP such steps go
       * without (where the whole step is too long most retries lose, and
       * each costs about an iteration) */
      hold_skip = held ? 0 : HOLD_SKIP;
    }
    if (!ls.accepted) {
      r.reason = VM_STOP_LINE_SEARCH;
      st = VM_OK;
      break;
    }
    m->last_tau = ls.tau;
    m->last_infeasible = ls.infeasible;
    commit(m, ls.x, x);
    st = vm_bc_refresh(m->bc, x);
    if (st) break;
    r.iterations = iter;
    r.F = ls.F;
    vm_iter_info info;
    info.iter = iter;
    info.F = ls.F;
    info.F_before = F;
    info.grad_norm = gn;
    info.tau = ls.tau;
    info.ls_evals = ls.evals;
    info.ls_infeasible = ls.infeasible;
    info.pcg_iters = lin;
    info.held = held;
    info.inverted = -1;
    info.min_det = NAN;
    if (o->stats_every > 0 && iter % o->stats_every == 0)
      node_stats(m, x, &info.inverted, &info.min_det);
    info.elapsed = omp_get_wtime() - t0;
    if (o->monitor) o->monitor(o->user, &info);
    if (F - ls.F <= o->rel_decrease_tol * fabs(ls.F)) {
      if (++stall >= o->rel_decrease_count) {
        r.reason = VM_STOP_REL_DECREASE;
        st = VM_OK;
        break;
      }
    } else {
      stall = 0;
    }
  }
  node_stats(m, x, &r.inverted, &r.min_det);
done:
  m->ops->end(m);
  free_bufs(ctx, &b);
  vm_bc_destroy(&m->bc);
  vm_problem_set_fixed_derivatives(m->prob, 1);
  r.elapsed = omp_get_wtime() - t0;
  if (res) *res = r;
  return st;
}
