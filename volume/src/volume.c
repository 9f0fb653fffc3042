/* volume/src/volume.c: the volume stage's schedule: global untangling by
 * penalty (35) or barrier contraction (39), local untangling of subdomains
 * around what is still inverted, optimization with a barrier measure, and
 * quasi-isometric continuation (11). */
#include "varmesh/volume.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "varmesh/jacobian.h"
#include "varmesh/problem.h"
#include "varmesh/quality.h"
#include "varmesh/topology.h"
#include "vec3.h"

vm_volume_opts vm_volume_opts_default(void) {
  vm_volume_opts o;
  memset(&o, 0, sizeof o);
  o.method = VM_UNTANGLE_ADAPTIVE;
  o.solver = VM_MINIMIZER_IMPLICIT;
  o.untangle_solver = -1;
  o.rule = VM_RULE_CORNER;
  o.measure = VM_MEASURE_BALANCED;
  o.theta = 0.8;
  o.delta0 = 1e-11;
  o.sigma = 0.5;
  o.kappa = 0.7;
  o.eps_inner = 10;
  o.max_iter = 20000;
  o.opt_iter = 100;
  o.local_threshold = 100;
  o.local_rings = 3;
  o.eps_restart = 1e-2;
  o.repair = 1;
  o.repair_rounds = 20;
  o.repair_rings = 4;
  o.repair_round_iter = 1000;
  o.repair_bernstein = 1;
  o.repair_geometric = 1;
  o.geometric_decay = 0.7;
  return o;
}

vm_volume_opts vm_volume_opts_direct(void) {
  vm_volume_opts o = vm_volume_opts_default();
  o.method = VM_UNTANGLE_FOLDOVER;
  o.eps_inner = 3;
  o.eps_cap = 1;
  o.theta_untangle = 0.999;
  return o;
}

vm_volume_opts vm_volume_opts_staged(void) {
  vm_volume_opts o = vm_volume_opts_direct();
  o.staged = 1;
  o.qi_steps = 1;
  return o;
}

const char *vm_untangle_method_name(vm_untangle_method m) {
  switch (m) {
  case VM_UNTANGLE_PENALTY: return "penalty";
  case VM_UNTANGLE_PENALTY_ONEWAY: return "penalty-oneway";
  case VM_UNTANGLE_BARRIER: return "barrier";
  case VM_UNTANGLE_ADAPTIVE: return "adaptive";
  case VM_UNTANGLE_FOLDOVER: return "foldover";
  }
  return "?";
}

typedef struct {
  vm_ctx *ctx;
  vm_mesh *m;
  vm_problem *P;
  const vm_volume_opts *o;
  vm_volume_report *rep;
  const vm_surface_ops *surf;
  int64_t nnodes;
  vm_rule rule;       /* the problem's present rule */
  double *dets;       /* per node, at the last statistics */
  double *node_eps;   /* one-way penalty */
  int split_stage;    /* staged: untangling the 6-tet split (M_max, best not kept) */
  int repair_stage;   /* certifying repair (M_max, best not kept: the rule's M stays 0) */
  uint8_t *guard;     /* staged: nodes kept admissible (eps = delta0), or NULL */
  double *nw;         /* repair: node weights (0: left out, not counted), or NULL */
  double *best;       /* coordinates with the fewest inverted nodes */
  const double *tref; /* reference target coordinates of m's vertices, or NULL */
  double *tref_own;   /* a sub-state's own copy of them */
  int64_t best_M;
  int64_t M; /* at the last statistics */
  double min_det;
  double eps;
  const char *phase;
  const char *phase_name; /* of the global untangling phase */
  int phase_iter;
  int total_iter;
  int go_local;    /* the global phase stops when few nodes remain inverted */
  double F_before; /* adaptive: F before and after the last step (same eps) */
  double F_after;
  int have_step;
  int done;            /* adaptive: det >= eps everywhere: untangled with margin */
  double pressure;     /* adaptive: multiplier of (35), halved on stalls */
  int block_iter;      /* foldover: iterations at the current eps */
  double F_block0;     /* foldover: F before the first of them */
  double eps_restart;  /* foldover: least eps after a stalled local round */
  double eps_floor;    /* foldover: that least eps of the present run, the
                          floor of the cap on eps (opts eps_cap) */
  int keep_certified;  /* optimization: every step keeps every cell certified */
  int no_local;        /* untangling without local rounds */
  int keep_guards;     /* every step keeps every guarded node positive */
  int64_t foam_max;    /* >= 0: every step keeps the face pyramids OpenFOAM
                          calls incorrectly oriented at most this many */
  int stop_certified;  /* untangling ends once every cell is certified */
  int check_certified; /* a local round of the geometric phase ends once
                          every cell of its region is certified */
  int local_scale;     /* local_threshold counts this many times the nodes */
  /* the stall watch of foldover's untangling (stalled): the best M and
   * min det since the last progress, and the iterations since */
  int64_t watch_M;
  double watch_D;
  int watch_n;
  int stalled; /* the untangling stalled for good: eps collapsed, no progress */
  int sub;     /* a region's state (sub_begin), not the mesh's */
  int reached_certified;
  /* the Bernstein repair: per element of m a weight (hexes of the region),
   * per coefficient penalized (1) or walled (0) and its eps, and the scale
   * that makes the coefficients target-relative */
  double *bw;
  uint8_t *bpen;
  double *beps;
  double bscale;
  double t0;
} ut_state;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Cells of s->m not certified det J > 0 everywhere (varmesh/jacobian.h)
 * with the vertices at x; -1 on error. */
static int64_t uncertified_at(const ut_state *s, const double *x) {
  vm_mesh mx = *s->m;
  mx.xyz = (double *)x;
  vm_jac_report jr;
  if (vm_mesh_jacobian_certify(&mx, &jr, NULL) < 0) return -1;
  return jr.invalid + jr.undecided;
}

/* Cell e's vertices at x into y; its type. */
static int cell_coords(const vm_mesh *m, const double *x, int64_t e, double *y) {
  int t = m->etype[e], k = vm_elem_nverts(t);
  for (int i = 0; i < k; i++) memcpy(y + 3 * i, x + 3 * m->conn[m->eoff[e] + i], 3 * sizeof *y);
  return t;
}

/* Face pyramids OpenFOAM's checkMesh would call incorrectly oriented
 * (vm_cell_foam) over the 3D cells with the vertices at x. */
static int64_t foam_errors_at(const ut_state *s, const double *x) {
  const vm_mesh *m = s->m;
  int64_t bad = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 3) continue;
    double y[3 * VM_MAX_ELEM_VERTS];
    bad += vm_cell_foam(cell_coords(m, x, e, y), y, NULL);
  }
  return bad;
}

/* The line search's test while the optimization keeps the mesh certified
 * (a step that leaves a cell not certified is outside the domain) and the
 * face pyramids from getting worse. */
static int keep_admissible(void *user, const double *x) {
  const ut_state *s = user;
  if (s->foam_max >= 0 && foam_errors_at(s, x) > s->foam_max) return 0;
  return !s->keep_certified || uncertified_at(s, x) == 0;
}

/* The line search's test while the guarded nodes must stay positive: a
 * guard's wall (eps = delta0) is steep only away from det = 0, and next to
 * a penalty grown large a node squeezed flat against it could cross. */
static int guards_positive(void *user, const double *x) {
  ut_state *s = user;
  if (vm_problem_node_dets(s->P, x, s->dets) < 0) return 0;
  for (int64_t q = 0; q < s->nnodes; q++)
    if (s->guard[q] && s->dets[q] <= 0) return 0;
  return 1;
}

/* The Bernstein coefficients of det J of hex e of m with the vertices at x. */
static void hex_coefs(const vm_mesh *m, const double *x, int64_t e, double b[27]) {
  double xe[24];
  cell_coords(m, x, e, xe);
  vm_hex_bernstein(xe, b, NULL);
}

/* The scale that makes m's Bernstein coefficients target-relative: 1 / h^3
 * for ideal targets of edge h, else over the mean centre coefficient (the
 * mean hex volume). */
static double hex_scale(const vm_problem *P, const vm_mesh *m) {
  double h = vm_problem_target_size(P);
  if (h > 0) return 1 / (h * h * h);
  double vsum = 0, b[27];
  int64_t nhex = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_HEX) continue;
    hex_coefs(m, m->xyz, e, b);
    vsum += fabs(b[13]);
    nhex++;
  }
  return nhex > 0 && vsum > 0 ? (double)nhex / vsum : 1;
}

/* The stall watch, after each global untangling iteration's stats: 1 when
 * foldover's eps has collapsed (below 1e-6 of |min det|: the penalty at the
 * folds so steep that steps shrink to nothing) and for VM_VOLUME_STALL_ITER such
 * iterations neither M reached a new least nor min det rose by 5 % of its
 * best. The n = 12 cube turned by pi about (0,1,1), inner half-size 0.35:
 * the 6-tet split's eps fell to delta0 (1e-11) at min det -2.3 after 800
 * iterations and sat there with M between 4,700 and 4,860 for 65 s, the
 * direct schedule after it the same for 50 s, until the time limit. Not
 * in the repair, which has its own rounds and budget. */
static int stall_watch(ut_state *s) {
  if (s->sub || s->repair_stage || s->o->method != VM_UNTANGLE_FOLDOVER || s->M == 0) return 0;
  double D = s->min_det;
  if (s->M < s->watch_M || D > s->watch_D + 0.05 * fabs(s->watch_D)) {
    if (s->M < s->watch_M) s->watch_M = s->M;
    if (D > s->watch_D) s->watch_D = D;
    s->watch_n = 0;
    return 0;
  }
  if (!(D < 0 && s->eps < 1e-6 * -D)) return 0;
  return ++s->watch_n >= VM_VOLUME_STALL_ITER;
}

static void stall_reset(ut_state *s) {
  s->stalled = 0;
  s->watch_M = INT64_MAX;
  s->watch_D = -INFINITY;
  s->watch_n = 0;
}

/* Node determinants at x: M, min det, and the best state so far. */
static int stats(ut_state *s, const double *x) {
  int st = vm_problem_node_dets(s->P, x, s->dets);
  if (st < 0) return st;
  int64_t M = 0;
  double mn = INFINITY;
  for (int64_t q = 0; q < s->nnodes; q++) {
    if (s->nw && s->nw[q] == 0) continue; /* left out of the functional */
    if (s->dets[q] <= 0) M++;
    /* a guard's small positive det is not what eps should follow */
    if (s->dets[q] < mn && (!s->guard || !s->guard[q] || s->dets[q] <= 0)) mn = s->dets[q];
  }
  if (s->bpen) {
    /* the Bernstein repair: the penalized coefficients are its nodes */
    for (int64_t e = 0; e < s->m->ne; e++) {
      if (!(s->bw[e] > 0)) continue;
      double b[27];
      hex_coefs(s->m, x, e, b);
      for (int c = 0; c < 27; c++) {
        if (!s->bpen[27 * e + c]) continue;
        if (b[c] <= 0) M++;
        if (s->bscale * b[c] < mn) mn = s->bscale * b[c];
      }
    }
  }
  s->M = M;
  s->min_det = mn;
  if (s->repair_stage) return VM_OK;
  if (s->split_stage) {
    if (M > s->rep->split_M_max) s->rep->split_M_max = M;
  } else if (M > s->rep->M_max) {
    s->rep->M_max = M;
  }
  /* the split's counts are not the rule's (the guarded stage's are: its
   * split nodes stay positive) */
  if (!s->split_stage && M < s->best_M) {
    s->best_M = M;
    memcpy(s->best, x, (size_t)s->m->nv * 3 * sizeof *x);
  }
  return VM_OK;
}

/* (35), or (39) for the barrier; the one-way variant gives non-degenerate
 * nodes delta0; the adaptive rule lowers eps by the progress of the last
 * step. Called before every untangling iteration. */
static int update_eps(ut_state *s, int first) {
  const vm_volume_opts *o = s->o;
  double neg = s->min_det < 0 ? -s->min_det : 0;
  vm_measure_params prm = *vm_problem_params(s->P);
  switch (o->method) {
  case VM_UNTANGLE_BARRIER:
    if (first)
      s->eps = neg > 0 ? 1.5 * neg : o->delta0;
    else
      s->eps = fmax(o->delta0, s->eps - o->sigma * (s->eps - neg)); /* (39) */
    /* degenerate (det = 0) nodes need eps > 0 strictly above |min det| */
    if (s->eps <= neg) s->eps = neg + o->delta0;
    break;
  case VM_UNTANGLE_ADAPTIVE: {
    /* (35) scaled by a pressure factor that halves whenever a step stalls
     * (a stationary point of P_eps with folds left: a smaller eps makes
     * folds dearer), and falling by at most kappa per iteration, so nodes
     * squeezed towards det = 0 from below see a smooth penalty and cross
     * instead of shrinking with eps; done once det >= eps everywhere */
    double e35 = sqrt(o->delta0 * o->delta0 + 0.004 * neg * neg);
    if (first) {
      s->pressure = 1;
      s->eps = e35;
      break;
    }
    if (s->M == 0 && s->min_det >= s->eps) {
      s->done = 1;
      break;
    }
    if (s->have_step && s->F_before - s->F_after < 1e-3 * fabs(s->F_before))
      s->pressure = fmax(0.5 * s->pressure, 0.1);
    s->eps = fmax(fmax(s->pressure * e35, o->delta0), o->kappa * s->eps);
    break;
  }
  case VM_UNTANGLE_FOLDOVER: {
    /* eps stays for eps_inner iterations (or until a step stalls); then
     * chi_eps at the worst node is scaled by mu = min(F_end/F_start, cap)
     * of that block, which fixes the new eps: chi_eps'(D) = mu chi_eps(D)
     * <=> eps' = 2 sqrt(mu' (mu' - D)) with mu' = mu chi_eps(D). The cap
     * is 0.9 but in the geometric phase's global rounds (stop_certified;
     * its local rounds clear it): geometric_decay there. At that pace the
     * local rounds squeezed the last folds with eps down to delta0 (n = 12
     * pi cube about (1,1,1), inner 0.3: 12 stalled rounds, 2,547 iterations
     * against 600). */
    if (first) {
      s->eps = fmax(neg > 0 ? neg : o->delta0, s->eps_restart);
      s->eps_floor = s->eps_restart;
      s->eps_restart = 0;
      s->block_iter = 0;
      break;
    }
    int stalled = s->have_step && s->F_before - s->F_after <= 1e-6 * fabs(s->F_before);
    if (s->block_iter < o->eps_inner && !stalled) break; /* re-applied: a phase may reset it */
    double D = s->min_det, q = sqrt(s->eps * s->eps + D * D);
    double chi = D >= 0 ? 0.5 * (D + q) : 0.5 * s->eps * s->eps / (q - D);
    double ratio = s->block_iter > 0 && s->F_block0 > 0 ? s->F_after / s->F_block0 : 1;
    double dk = o->geometric_decay, cap = s->stop_certified && dk > 0 && dk < 1 ? dk : 0.9;
    double mu = fmin(ratio, cap) * chi;
    s->eps = D < mu ? 2 * sqrt(mu * (mu - D)) : o->delta0;
    /* while nodes are guarded (the staged schedule's second stage, the
     * repair's rounds), never above where a start from here would put it
     * (eps_cap |D|, not below the run's restart floor): where the worst
     * det rose faster than the blocks lowered eps, the penalty stayed flat
     * at the folds (n = 32 7pi/8: eps 145 at min det -40 after 30 of 429
     * guarded iterations). And in the geometric phase's global rounds
     * (stop_certified), which start from a corner-valid mesh with eps 4.5
     * times |min det| (n = 32 7pi/8: 255 at -56) and had eps 17 times it
     * ten iterations later: there the cap took the phase from 52 to 35 s.
     * Not in the split stage (no guards there), whose M rises tenfold from
     * its start: there the cap took eps down with thousands of nodes
     * inverted, and the n = 16 pi cube's split stalled at M ~ 150. */
    if (o->eps_cap > 0 && D < 0 && (s->guard || s->stop_certified))
      s->eps = fmin(s->eps, fmax(o->eps_cap * -D, s->eps_floor));
    if (s->eps < o->delta0) s->eps = o->delta0;
    s->block_iter = 0;
    break;
  }
  default:
    s->eps = sqrt(o->delta0 * o->delta0 + 0.004 * neg * neg); /* (35) */
    if (o->method == VM_UNTANGLE_PENALTY_ONEWAY) {
      for (int64_t q = 0; q < s->nnodes; q++) s->node_eps[q] = s->dets[q] > 0 ? o->delta0 : s->eps;
      int st = vm_problem_set_node_eps(s->P, s->node_eps);
      if (st < 0) return st;
    }
  }
  if (s->guard) {
    /* staged: the split's nodes, all positive, are held there by the
     * smallest eps (a wall of height ~ 1/delta0 at det = 0) */
    int oneway = o->method == VM_UNTANGLE_PENALTY_ONEWAY;
    for (int64_t q = 0; q < s->nnodes; q++)
      s->node_eps[q] = s->guard[q] ? o->delta0 : oneway ? s->node_eps[q] : s->eps;
    int st = vm_problem_set_node_eps(s->P, s->node_eps);
    if (st < 0) return st;
  }
  if (s->bpen) {
    /* the penalized coefficients follow eps, the others stay walled */
    for (int64_t k = 0; k < 27 * s->m->ne; k++)
      s->beps[k] = s->bpen[k] ? fmax(s->eps, o->delta0) : o->delta0;
    int st = vm_problem_set_bernstein(s->P, s->bw, s->beps, s->bscale);
    if (st < 0) return st;
  }
  prm.eps = s->eps;
  return vm_problem_set_params(s->P, &prm);
}

/* Inverted nodes below which the untangling goes local: the option counts
 * the corner rule's nodes, 8 per hex; the geometric phase's 64 per hex
 * count 8 times as many for the same cells (the n = 32 7pi/8 cube's
 * geometric phase stalled globally with ~215 nodes in ~10 cells). */
static int64_t local_threshold(const ut_state *s) {
  return (int64_t)s->o->local_threshold * (s->local_scale > 1 ? s->local_scale : 1);
}

/* The geometric phase's stop: 1 (and s->reached_certified set) when every
 * cell is certified at x, 0 when not, < 0 on error. */
static int reach_certified(ut_state *s, const double *x) {
  int64_t nb = uncertified_at(s, x);
  if (nb < 0) return VM_ERR_NOMEM;
  s->reached_certified = nb == 0;
  return nb == 0;
}

static int before_untangle(void *user, int iter, const double *x) {
  ut_state *s = user;
  int st = stats(s, x);
  if (st < 0) return st;
  int adaptive = s->o->method == VM_UNTANGLE_ADAPTIVE;
  /* the adaptive rule goes on past M = 0 until min det clears mu */
  if (s->M == 0 && (!adaptive || s->done)) return 1;
  /* the geometric phase: certified is what it is for, every node of (24)
   * positive only the way there */
  if ((s->stop_certified || s->check_certified) && (iter == 1 || iter % 5 == 0)) {
    if ((st = reach_certified(s, x)) != 0) return st;
  }
  /* the geometric phase takes at least one global step: from a
   * corner-valid mesh its first eps is that of the worst of the 64 nodes,
   * and a local round started there turned the few inverted nodes into
   * thousands (n = 12 cube turned by 5pi/8 about (1,1,1), inner 0.35,
   * with session 58's cap in every stage: 36 cells, < 800 nodes -> 22,000 in its local rounds, 77 s
   * in the phase; from a global start the phase took 5 s) */
  if (s->go_local && s->M > 0 && s->M < local_threshold(s) && !(s->stop_certified && iter == 1))
    return 1;
  if ((st = update_eps(s, iter == 1 && s->eps == 0)) < 0) return st;
  if (adaptive && s->M == 0 && s->done) return 1;
  if (stall_watch(s)) {
    s->stalled = 1;
    s->rep->stall_min_det = s->min_det;
    s->rep->stall_eps = s->eps;
    return 1;
  }
  s->have_step = 0;
  return VM_OK;
}

static int before_plain(void *user, int iter, const double *x) {
  (void)user;
  (void)iter;
  (void)x;
  return 0;
}

static void monitor(void *user, const vm_iter_info *it) {
  ut_state *s = user;
  s->F_before = it->F_before;
  s->F_after = it->F;
  s->have_step = 1;
  if (s->block_iter == 0) s->F_block0 = it->F_before;
  s->block_iter++;
  s->phase_iter = it->iter;
  s->total_iter++;
  if (!s->o->progress) return;
  vm_volume_progress p = {s->phase,    it->iter, s->total_iter, it->F,         it->inverted,
                          it->min_det, s->eps,   it->tau,       it->pcg_iters, now() - s->t0};
  s->o->progress(s->o->user, &p);
}

/* Run one minimizer phase. */
static int run_phase(ut_state *s, const char *phase, vm_minimizer_kind kind, int max_iter,
                     vm_before_iteration_fn hook, vm_minimize_result *res) {
  const vm_volume_opts *o = s->o;
  vm_minimizer *mz = NULL;
  int st = vm_minimizer_create(s->ctx, s->P, kind, &mz);
  if (st < 0) return st;
  vm_minimize_options mo = vm_minimize_options_default();
  mo.max_iter = max_iter;
  /* untangling phases end by their own tests or limits; optimization when
   * F stops decreasing */
  mo.rel_decrease_tol = hook == before_plain ? 1e-9 : 0;
  mo.grad_rtol = 1e-12;
  if (o->time_limit > 0) {
    mo.time_limit = o->time_limit - (now() - s->t0);
    if (mo.time_limit <= 0) mo.time_limit = 1e-3;
  }
  if (kind == VM_MINIMIZER_NEWTON) {
    /* the coupled 3n system: block Jacobi beats the block AMG per second
     * while the Hessian changes fast (untangling) */
    mo.precond = VM_PRECOND_BLOCK_JACOBI;
    mo.pcg_maxit = 200;
  }
  mo.monitor = monitor;
  mo.before_iteration = hook;
  if (s->keep_certified || s->foam_max >= 0) mo.admissible = keep_admissible;
  if (s->keep_guards && s->guard) mo.admissible = guards_positive;
  mo.user = s;
  s->phase = phase;
  if ((st = vm_minimizer_set_options(mz, &mo)) < 0) goto done;
  if (s->surf && (st = vm_minimizer_set_surfaces(mz, s->surf)) < 0) goto done;
  st = vm_minimizer_run(mz, s->m->xyz, res);
  s->rep->last_stop = res->reason;
done:
  vm_minimizer_destroy(&mz);
  return st;
}

static int out_of_time(const ut_state *s) {
  return s->o->time_limit > 0 && now() - s->t0 >= s->o->time_limit;
}

/* emask grown by `rings` layers of elements (sharing a vertex, marked 1;
 * the marks already there stay); vmark[v] then says whether every element
 * around v is in it (v may move). */
static void grow_mask(const vm_mesh *m, int rings, const int64_t *vrp, const int32_t *vel,
                      uint8_t *emask, uint8_t *vmark) {
  for (int r = 0; r < rings; r++) {
    memset(vmark, 0, (size_t)m->nv);
    for (int64_t e = 0; e < m->ne; e++)
      if (emask[e])
        for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) vmark[m->conn[k]] = 1;
    for (int64_t v = 0; v < m->nv; v++)
      if (vmark[v])
        for (int64_t k = vrp[v]; k < vrp[v + 1]; k++)
          if (!emask[vel[k]]) emask[vel[k]] = 1;
  }
  /* a vertex may move only if every element around it is in the functional:
   * otherwise it would fold the elements outside unseen */
  for (int64_t v = 0; v < m->nv; v++) {
    vmark[v] = vrp[v + 1] > vrp[v];
    for (int64_t k = vrp[v]; k < vrp[v + 1]; k++)
      if (!emask[vel[k]]) vmark[v] = 0;
  }
}

/* Elements of emask marked 1 (grown, not the seeds marked 2) whose vertices
 * are all fixed, in the mesh or by vmark, taken out of it: their nodes are
 * constants of the region's functional (on the rotated cube, the cells
 * inside the fixed inner cube, about a third of the mesh), so evaluating
 * them every iteration is wasted. No vertex that moves loses an element. */
static void drop_fixed(const vm_mesh *m, const uint8_t *vmark, uint8_t *emask) {
  for (int64_t e = 0; e < m->ne; e++) {
    if (emask[e] != 1) continue;
    int fixed = 1;
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1] && fixed; k++)
      fixed = !vmark[m->conn[k]] || m->vflag[m->conn[k]] == VM_VERTEX_FIXED;
    if (fixed) emask[e] = 0;
  }
}

/* Elements within `rings` layers of the elements holding inverted nodes;
 * vertices of other elements do not move; cells all of whose vertices are
 * fixed are left out (drop_fixed). */
static int local_mask(ut_state *s, int rings, const int64_t *vrp, const int32_t *vel,
                      uint8_t *emask, uint8_t *vmark) {
  const vm_mesh *m = s->m;
  const int32_t *nel = vm_problem_node_elements(s->P);
  memset(emask, 0, (size_t)m->ne);
  for (int64_t q = 0; q < s->nnodes; q++)
    if (s->dets[q] <= 0 && !(s->nw && s->nw[q] == 0)) emask[nel[q]] = 2;
  grow_mask(m, rings, vrp, vel, emask, vmark);
  drop_fixed(m, vmark, emask);
  return VM_OK;
}

/* 3D cells whose face pyramids can be wrong while the cell is valid: all
 * but tetrahedra (whose centre is inside). */
static int has_foam_cells(const vm_mesh *m) {
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 3 && m->etype[e] != VM_TET) return 1;
  return 0;
}

static int has_hex(const vm_mesh *m) {
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] == VM_HEX) return 1;
  return 0;
}

/* The per-node arrays sized for the problem's present rule; no guards. */
static int size_node_arrays(ut_state *s) {
  s->nnodes = vm_problem_num_nodes(s->P);
  size_t nn = (size_t)(s->nnodes ? s->nnodes : 1);
  vm_free(s->ctx, s->dets);
  vm_free(s->ctx, s->node_eps);
  vm_free(s->ctx, s->guard);
  vm_free(s->ctx, s->nw);
  s->guard = NULL;
  s->nw = NULL;
  s->dets = vm_alloc_array(s->ctx, nn, sizeof *s->dets);
  s->node_eps = vm_alloc_array(s->ctx, nn, sizeof *s->node_eps);
  return s->dets && s->node_eps ? VM_OK : VM_ERR_NOMEM;
}

/* The elements of m marked in emask (those of dimension tdim) as a mesh of
 * their own, with their vertices in ascending order of their numbers in m:
 * e_of and v_of give those numbers. Vertices not marked in vmark are fixed
 * in it; the others keep their flags and surfaces. */
typedef struct {
  vm_mesh *m;
  int32_t *e_of; /* per element of m: its number in the full mesh */
  int32_t *v_of; /* per vertex */
} submesh;

static void submesh_destroy(vm_ctx *ctx, submesh *sm) {
  vm_mesh_destroy(&sm->m);
  vm_free(ctx, sm->e_of);
  vm_free(ctx, sm->v_of);
  memset(sm, 0, sizeof *sm);
}

static int submesh_create(vm_ctx *ctx, const vm_mesh *m, int tdim, const uint8_t *emask,
                          const uint8_t *vmark, submesh *sm) {
  memset(sm, 0, sizeof *sm);
  int32_t *vloc = vm_alloc_array(ctx, (size_t)m->nv + 1, sizeof *vloc);
  if (!vloc) return VM_ERR_NOMEM;
  for (int64_t v = 0; v < m->nv; v++) vloc[v] = -1;
  int64_t ne = 0, nc = 0, nv = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (!emask[e] || vm_elem_dim(m->etype[e]) != tdim) continue;
    ne++;
    nc += m->eoff[e + 1] - m->eoff[e];
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) vloc[m->conn[k]] = 0;
  }
  for (int64_t v = 0; v < m->nv; v++)
    if (vloc[v] == 0) vloc[v] = (int32_t)++nv; /* 1-based until the end */
  int st = vm_mesh_create(ctx, &sm->m);
  if (st >= 0) st = vm_mesh_set_vertices(sm->m, nv);
  if (st >= 0) st = vm_mesh_set_elements(sm->m, ne, nc);
  sm->e_of = vm_alloc_array(ctx, (size_t)ne + 1, sizeof *sm->e_of);
  sm->v_of = vm_alloc_array(ctx, (size_t)nv + 1, sizeof *sm->v_of);
  if (st >= 0 && (!sm->e_of || !sm->v_of)) st = VM_ERR_NOMEM;
  if (st < 0) {
    vm_free(ctx, vloc);
    submesh_destroy(ctx, sm);
    return st;
  }
  vm_mesh *s = sm->m;
  s->dim = m->dim;
  for (int64_t v = 0; v < m->nv; v++) {
    if (vloc[v] <= 0) continue;
    int32_t w = --vloc[v];
    sm->v_of[w] = (int32_t)v;
    memcpy(s->xyz + 3 * (int64_t)w, m->xyz + 3 * v, 3 * sizeof *s->xyz);
    s->vflag[w] = vmark[v] ? m->vflag[v] : VM_VERTEX_FIXED;
    if (m->vsurf) s->vsurf[w] = m->vsurf[v];
  }
  int64_t se = 0, k1 = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (!emask[e] || vm_elem_dim(m->etype[e]) != tdim) continue;
    sm->e_of[se] = (int32_t)e;
    s->etype[se] = m->etype[e];
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) s->conn[k1++] = vloc[m->conn[k]];
    s->eoff[++se] = k1;
  }
  vm_free(ctx, vloc);
  return VM_OK;
}

/* A state for the elements in emask as a mesh of their own (submesh_create,
 * vertices not in vmark fixed): its own problem with `rule`, the parent's
 * targets and the measure k, prm; the parent's per-node guards and weights
 * carried over when the rule is the parent's (the sub-problem's nodes are
 * the parent's nodes of those elements, in the same order); the scalar
 * state (eps and its rule's counters) copied. Costs what the region costs. */
static int sub_begin(ut_state *s, vm_rule rule, vm_measure_kind k, const vm_measure_params *prm,
                     const uint8_t *emask, const uint8_t *vmark, ut_state *ss, submesh *sm) {
  vm_ctx *ctx = s->ctx;
  *ss = *s;
  ss->sub = 1;
  ss->tref_own = NULL;
  ss->P = NULL;
  ss->dets = ss->node_eps = ss->nw = ss->best = NULL;
  ss->guard = NULL;
  int st = submesh_create(ctx, s->m, vm_problem_dim(s->P), emask, vmark, sm);
  if (st < 0) return st;
  ss->m = sm->m;
  if ((st = vm_problem_create(ctx, sm->m, &ss->P)) < 0) return st;
  ss->tref_own = NULL;
  if (s->tref) {
    /* the parent's numbering, which is the full mesh's only at the top */
    double *tref = vm_alloc_array(ctx, (size_t)sm->m->nv * 3 + 1, sizeof *tref);
    if (!(ss->tref_own = tref)) return VM_ERR_NOMEM;
    ss->tref = tref;
    for (int64_t v = 0; v < sm->m->nv; v++)
      memcpy(tref + 3 * v, s->tref + 3 * (int64_t)sm->v_of[v], 3 * sizeof *tref);
    st = vm_problem_set_target_reference(ss->P, tref);
  } else {
    /* the full mesh's size, not one fitted to the region */
    st = vm_problem_set_target_ideal(ss->P, vm_problem_target_size(s->P));
  }
  if (st < 0 || (st = vm_problem_set_rule(ss->P, rule)) < 0) return st;
  ss->rule = rule;
  if ((st = size_node_arrays(ss)) < 0) return st;
  if ((st = vm_problem_set_measure(ss->P, k, prm)) < 0) return st;
  /* the Bernstein roles are the repair round's own (repair_round_bern) */
  ss->bw = ss->beps = NULL;
  ss->bpen = NULL;
  /* the sub-problem's M is the mesh's (every inverted node is in it, and
   * nothing outside moves): its best state is the mesh's best state */
  if (s->best && !(ss->best = vm_alloc_array(ctx, (size_t)sm->m->nv * 3 + 1, sizeof *ss->best)))
    return VM_ERR_NOMEM;
  if (rule != s->rule || (!s->guard && !s->nw)) return VM_OK;
  size_t nn = (size_t)ss->nnodes + 1;
  if (s->guard && !(ss->guard = vm_alloc_array(ctx, nn, 1))) return VM_ERR_NOMEM;
  if (s->nw && !(ss->nw = vm_alloc_array(ctx, nn, sizeof *ss->nw))) return VM_ERR_NOMEM;
  const int32_t *nel = vm_problem_node_elements(s->P);
  int64_t r = 0;
  for (int64_t q = 0; q < s->nnodes && r < ss->nnodes; q++) {
    int32_t e = nel[q];
    if (!emask[e] || vm_elem_dim(s->m->etype[e]) != vm_problem_dim(s->P)) continue;
    if (ss->guard) ss->guard[r] = s->guard[q];
    if (ss->nw) ss->nw[r] = s->nw[q];
    r++;
  }
  if (r != ss->nnodes)
    return vm_error(ctx, VM_ERR_ARG, "sub-problem: %lld of %lld nodes", (long long)r,
                    (long long)ss->nnodes);
  return ss->nw ? vm_problem_set_node_weights(ss->P, ss->nw) : VM_OK;
}

/* The free vertices' coordinates and the scalar state back to the parent;
 * the sub-state freed. */
static void sub_end(ut_state *s, ut_state *ss, submesh *sm, const uint8_t *vmark) {
  vm_ctx *ctx = s->ctx;
  if (ss->best && ss->best_M < s->best_M) {
    memcpy(s->best, s->m->xyz, (size_t)s->m->nv * 3 * sizeof *s->best);
    for (int64_t v = 0; v < sm->m->nv; v++)
      if (vmark[sm->v_of[v]])
        memcpy(s->best + 3 * (int64_t)sm->v_of[v], ss->best + 3 * v, 3 * sizeof *s->best);
    s->best_M = ss->best_M;
  }
  if (sm->m && ss->m == sm->m)
    for (int64_t v = 0; v < sm->m->nv; v++)
      if (vmark[sm->v_of[v]])
        memcpy(s->m->xyz + 3 * (int64_t)sm->v_of[v], sm->m->xyz + 3 * v, 3 * sizeof *s->m->xyz);
  s->eps = ss->eps;
  s->eps_restart = ss->eps_restart;
  s->eps_floor = ss->eps_floor;
  s->pressure = ss->pressure;
  s->done = ss->done;
  s->block_iter = ss->block_iter;
  s->F_block0 = ss->F_block0;
  s->F_before = ss->F_before;
  s->F_after = ss->F_after;
  s->have_step = ss->have_step;
  s->phase_iter = ss->phase_iter;
  s->total_iter = ss->total_iter;
  vm_free(ctx, ss->dets);
  vm_free(ctx, ss->node_eps);
  vm_free(ctx, ss->guard);
  vm_free(ctx, ss->nw);
  vm_free(ctx, ss->best);
  vm_free(ctx, ss->tref_own);
  vm_problem_destroy(&ss->P);
  submesh_destroy(ctx, sm);
}

/* Local untangling: penalty on subdomains with the explicit solver, rings
 * growing when a round makes no progress. Each round runs on its subdomain
 * as a mesh of its own (sub_begin): node determinants, eps and the steps
 * cost what the subdomain costs, not what the mesh does. */
static int local_phase(ut_state *s, vm_measure_kind k, const vm_measure_params *prm, int *budget) {
  vm_mesh *m = s->m;
  vm_ctx *ctx = s->ctx;
  int64_t *vrp = NULL;
  int32_t *vel = NULL;
  uint8_t *emask = vm_malloc(ctx, (size_t)m->ne + 1);
  uint8_t *vmark = vm_malloc(ctx, (size_t)m->nv + 1);
  int st = (!emask || !vmark) ? VM_ERR_NOMEM : vm_mesh_vertex_elements(m, &vrp, &vel);
  int rings = s->o->local_rings, stalls = 0;
  while (st >= 0 && s->M > 0 && !s->stalled && *budget > 0 && !out_of_time(s) &&
         rings <= 4 * s->o->local_rings + 8) {
    int64_t M0 = s->M;
    local_mask(s, rings, vrp, vel, emask, vmark);
    ut_state ss;
    submesh sm;
    vm_minimize_result res = {0};
    int chunk = *budget < 200 ? *budget : 200;
    st = sub_begin(s, s->rule, k, prm, emask, vmark, &ss, &sm);
    /* its eps falls at the usual pace (update_eps), and in the geometric
     * phase the round ends once its region's cells are all certified: every
     * cell with a node of (24) not positive is in the region, and every
     * other cell has all 64 positive, so then the mesh's are too (checked
     * below on the whole mesh, which decides). Run to its own M = 0 the
     * round kept going after that: n = 32, 7pi/8 308 -> 259 repair
     * iterations, pi 294 -> 275 (certified 4-8 s sooner). */
    ss.check_certified = s->stop_certified;
    ss.stop_certified = 0;
    if (st >= 0) st = stats(&ss, ss.m->xyz);
    if (st >= 0) {
      ss.go_local = 0;
      st = run_phase(&ss, "local", VM_MINIMIZER_EXPLICIT, chunk, before_untangle, &res);
    }
    sub_end(s, &ss, &sm, vmark);
    s->rep->iter_local += res.iterations;
    *budget -= res.iterations > 0 ? res.iterations : 1;
    if (st < 0) break;
    if ((st = stats(s, m->xyz)) < 0) break;
    if (s->stop_certified && (st = reach_certified(s, m->xyz)) != 0) {
      if (st > 0) st = VM_OK;
      break;
    }
    if (s->M >= M0) {
      stalls++;
      rings += 2;
      /* eps starts again from the worst det: the rule may have driven it
       * far below |min det|, where the penalty of the folds left is so
       * steep that the explicit steps no longer move them */
      s->eps = 0;
      /* and not below eps_restart: a fold squeezed flat (det ~ -1e-10)
       * would restart from an eps too small to lift it */
      s->eps_restart = s->o->eps_restart;
    } else {
      stalls = 0;
    }
  }
  vm_free(ctx, emask);
  vm_free(ctx, vmark);
  vm_free(ctx, vrp);
  vm_free(ctx, vel);
  return st;
}

/* Largest t in [lo, 1) with W_t finite at the current mesh (bisection on
 * the domain test det > t phi). */
static double qi_feasible_t(ut_state *s, double lo) {
  vm_measure_params prm = *vm_problem_params(s->P);
  double a = lo, b = 1.0;
  for (int k = 0; k < 30; k++) {
    double t = 0.5 * (a + b), F;
    prm.t = t;
    vm_problem_set_params(s->P, &prm);
    if (vm_problem_value(s->P, s->m->xyz, &F) == VM_OK && isfinite(F))
      a = t;
    else
      b = t;
  }
  return a;
}

/* Global untangling, local rounds, and back to global if they stall. */
static int untangle_rounds(ut_state *s, const vm_measure_params *prm0, int *budget) {
  const vm_volume_opts *o = s->o;
  vm_measure_params prm = *prm0;
  vm_minimize_result res;
  int st = VM_OK;
  stall_reset(s);
  for (int round = 0; s->M > 0 && !s->stalled && !s->reached_certified && *budget > 0 &&
                      !out_of_time(s) && round < 50;
       round++) {
    vm_measure_kind k = o->method == VM_UNTANGLE_BARRIER ? VM_MEASURE_BARRIER : VM_MEASURE_PENALTY;
    prm.drop_chi2 = 1;
    vm_measure_params pu = prm;
    if (o->theta_untangle > 0) pu.theta = o->theta_untangle;
    if ((st = vm_problem_set_measure(s->P, k, &pu)) < 0) return st;
    if ((st = vm_problem_set_node_eps(s->P, NULL)) < 0) return st;
    s->go_local = o->local_threshold > 0 && !s->no_local;
    int64_t M0 = s->M;
    vm_minimizer_kind ks =
        o->untangle_solver >= 0 ? (vm_minimizer_kind)o->untangle_solver : o->solver;
    st = run_phase(s, s->phase_name, ks, *budget, before_untangle, &res);
    s->rep->iter_untangle += res.iterations;
    *budget -= res.iterations > 0 ? res.iterations : 1;
    if (st < 0) return st;
    if ((st = stats(s, s->m->xyz)) < 0) return st;
    if (s->M > 0 && !s->reached_certified && !s->no_local && s->M < local_threshold(s)) {
      if ((st = local_phase(s, k, &prm, budget)) < 0) return st;
    }
    if (s->M > 0 && s->M >= M0 && res.reason == VM_STOP_LINE_SEARCH) break; /* stuck */
  }
  return st;
}

/* Switch the problem to `rule` for a stage: node arrays sized for it, the
 * split's nodes of the guarded rules marked as guards. */
static int set_stage_rule(ut_state *s, vm_rule rule) {
  int st = vm_problem_set_rule(s->P, rule);
  if (st >= 0) s->rule = rule;
  if (st < 0 || (st = size_node_arrays(s)) < 0) return st;
  size_t nn = (size_t)(s->nnodes ? s->nnodes : 1);
  if (rule == VM_RULE_CORNER_SPLIT || rule == VM_RULE_GEOMETRIC_SPLIT) {
    /* the split's nodes follow the base rule's */
    int first_guard =
        vm_qrule_get(VM_HEX, rule == VM_RULE_CORNER_SPLIT ? VM_RULE_CORNER : VM_RULE_GEOMETRIC)
            ->nnodes;
    if (!(s->guard = vm_alloc_array(s->ctx, nn, 1))) return VM_ERR_NOMEM;
    const int32_t *nel = vm_problem_node_elements(s->P);
    int64_t first = 0;
    for (int64_t q = 0; q < s->nnodes; q++) {
      if (q == 0 || nel[q] != nel[q - 1]) first = q;
      s->guard[q] = s->m->etype[nel[q]] == VM_HEX && q - first >= first_guard;
    }
  }
  s->eps = 0;
  return VM_OK;
}

/* Certify every cell at the mesh's coordinates: verdicts into `verdict`,
 * the counts into the report; returns the number of cells not valid. */
static int64_t certify(ut_state *s, uint8_t *verdict) {
  vm_jac_report jr;
  if (vm_mesh_jacobian_certify(s->m, &jr, verdict) < 0) return -1;
  s->rep->cert_cells = jr.cells;
  s->rep->cert_invalid = jr.invalid;
  s->rep->cert_undecided = jr.undecided;
  return jr.invalid + jr.undecided;
}

/* Bernstein coefficient of det J that node n of the hex's geometric rule
 * (24) belongs to: det J = sum over nodes of products of linear Bernstein
 * polynomials times the node's determinant, and the node with columns at
 * (j, k), (i2, k2), (i3, j3) lands on the triquadratic coefficient
 * (i2 + i3, j + j3, k + k2); each coefficient is the mean of its nodes
 * (1, 2, 4 or 8 of them: the 64 nodes partition the 27 coefficients). */
static int hex_node_coef(int n) {
  int j3 = n & 1, i3 = n >> 1 & 1, k2 = n >> 2 & 1, i2 = n >> 3 & 1, k = n >> 4 & 1, j = n >> 5 & 1;
  return 9 * (i2 + i3) + 3 * (j + j3) + (k + k2);
}

/* The repair's roles of the nodes of VM_RULE_GEOMETRIC_SPLIT at the present
 * coordinates. In a hex not certified, the nodes of its non-positive
 * Bernstein coefficients (their means; of the least one if none is) are
 * penalized: all of them positive make the coefficient positive; in other
 * cells not certified every node of the rule is (for a prism the 12 of (24)
 * imply det J > 0). Elsewhere a positive node is guarded (eps = delta0: it
 * stays positive, so a certified cell keeps the determinants it has) and a
 * non-positive one is left out (a certified cell may have some). In the
 * cells marked `soft` (may be NULL) the positive nodes are penalized
 * instead of guarded. */
static int repair_roles(ut_state *s, const uint8_t *verdict, const uint8_t *soft) {
  int st = vm_problem_node_dets(s->P, s->m->xyz, s->dets);
  if (st < 0) return st;
  const int32_t *nel = vm_problem_node_elements(s->P);
  int ngeo = vm_qrule_get(VM_HEX, VM_RULE_GEOMETRIC)->nnodes;
  for (int64_t q = 0, q1; q < s->nnodes; q = q1) {
    int32_t e = nel[q];
    for (q1 = q + 1; q1 < s->nnodes && nel[q1] == e; q1++) continue;
    int bad = verdict[e] != VM_JAC_VALID, hex = s->m->etype[e] == VM_HEX && q1 - q > ngeo;
    uint8_t pen_coef[27] = {0};
    if (bad && hex) {
      double b[27] = {0};
      int cnt[27] = {0}, least = 0, any = 0;
      for (int n = 0; n < ngeo; n++) {
        b[hex_node_coef(n)] += s->dets[q + n];
        cnt[hex_node_coef(n)]++;
      }
      for (int c = 0; c < 27; c++) {
        b[c] /= cnt[c];
        if (b[c] <= 0) pen_coef[c] = any = 1;
        if (b[c] < b[least]) least = c;
      }
      if (!any) pen_coef[least] = 1;
    }
    for (int64_t r = q; r < q1; r++) {
      int n = (int)(r - q), pos = s->dets[r] > 0;
      int pen = bad && (hex ? n < ngeo && pen_coef[hex_node_coef(n)] : 1);
      /* near the cells a guarded round could not repair, the certified
       * cells' positive nodes are only penalized: no wall */
      if (!bad && soft && soft[e] && pos) pen = 1;
      s->guard[r] = pos && !pen;
      s->nw[r] = s->guard[r] || pen ? 1 : 0;
    }
  }
  return vm_problem_set_node_weights(s->P, s->nw);
}

/* One round of the certifying repair on the active region only: the cells
 * marked in emask as a mesh of their own (sub_begin), with the vertices
 * marked in vmark free and the nodes of VM_RULE_GEOMETRIC_SPLIT in their
 * roles (repair_roles); the untangling of steps 1-2 runs on it and the
 * free vertices' coordinates are copied back. Everything outside the
 * region is untouched, bit for bit. */
static int repair_round(ut_state *s, const vm_measure_params *prm, const uint8_t *verdict,
                        const uint8_t *soft, const uint8_t *emask, const uint8_t *vmark,
                        int *budget) {
  vm_ctx *ctx = s->ctx;
  ut_state ss;
  submesh sm;
  int st = sub_begin(s, VM_RULE_GEOMETRIC_SPLIT, VM_MEASURE_PENALTY, prm, emask, vmark, &ss, &sm);
  ss.repair_stage = 1;
  uint8_t *sv = NULL, *ssoft = NULL;
  if (st >= 0) {
    size_t nn = (size_t)ss.nnodes + 1, ne = (size_t)sm.m->ne + 1;
    ss.guard = vm_alloc_array(ctx, nn, 1);
    ss.nw = vm_alloc_array(ctx, nn, sizeof *ss.nw);
    sv = vm_malloc(ctx, ne);
    ssoft = soft ? vm_malloc(ctx, ne) : NULL;
    if (!ss.guard || !ss.nw || !sv || (soft && !ssoft)) st = VM_ERR_NOMEM;
  }
  if (st >= 0) {
    for (int64_t e = 0; e < sm.m->ne; e++) {
      sv[e] = verdict[sm.e_of[e]];
      if (ssoft) ssoft[e] = soft[sm.e_of[e]];
    }
    if ((st = repair_roles(&ss, sv, ssoft)) >= 0) st = stats(&ss, sm.m->xyz);
  }
  if (st >= 0) {
    ss.eps = 0;
    ss.eps_restart = 0;
    st = untangle_rounds(&ss, prm, budget);
  }
  sub_end(s, &ss, &sm, vmark);
  vm_free(ctx, sv);
  vm_free(ctx, ssoft);
  return st;
}

/* One round of the certifying repair on hexahedra, on the Bernstein
 * coefficients themselves: the region as in repair_round, with the rule's
 * nodes (all positive after the untangling) guarded, and the Bernstein
 * term of varmesh/problem.h on every hex of the region: in a hex not
 * certified, its coefficients <= 0 (the least one if none is) are
 * penalized with the untangling's eps, the others walled (eps = delta0);
 * in a certified hex every positive coefficient is walled. All 27 of a hex
 * positive certify it, and a coefficient is the mean of the geometric
 * rule's nodes behind it, so this asks far less than every one of those
 * nodes positive. The round ends when every coefficient of its region is
 * positive. (After a round without progress repair_phase goes on with
 * repair_round, so there are no soft cells here.) */
static int repair_round_bern(ut_state *s, const vm_measure_params *prm, const uint8_t *verdict,
                             const uint8_t *emask, const uint8_t *vmark, int *budget) {
  vm_ctx *ctx = s->ctx;
  ut_state ss;
  submesh sm;
  int st = sub_begin(s, s->rule, VM_MEASURE_PENALTY, prm, emask, vmark, &ss, &sm);
  ss.repair_stage = 1;
  /* no local rounds: the roles are the region's own */
  ss.no_local = 1;
  ss.keep_guards = 1;
  if (st >= 0) {
    size_t nn = (size_t)ss.nnodes + 1, ne = (size_t)sm.m->ne + 1;
    vm_free(ctx, ss.guard);
    ss.guard = vm_alloc_array(ctx, nn, 1);
    ss.bw = vm_alloc_array(ctx, ne, sizeof *ss.bw);
    ss.bpen = vm_alloc_array(ctx, 27 * ne, 1);
    ss.beps = vm_alloc_array(ctx, 27 * ne, sizeof *ss.beps);
    if (!ss.guard || !ss.bw || !ss.bpen || !ss.beps) st = VM_ERR_NOMEM;
  }
  if (st >= 0) st = vm_problem_node_dets(ss.P, sm.m->xyz, ss.dets);
  if (st >= 0) {
    const vm_mesh *r = sm.m;
    for (int64_t e = 0; e < r->ne; e++) {
      int32_t e0 = sm.e_of[e];
      int bad = verdict[e0] != VM_JAC_VALID;
      ss.bw[e] = 0;
      memset(ss.bpen + 27 * e, 0, 27);
      if (r->etype[e] != VM_HEX) continue;
      double b[27];
      hex_coefs(r, r->xyz, e, b);
      ss.bw[e] = 1;
      int least = 0, any = 0;
      for (int c = 0; c < 27; c++) {
        ss.bpen[27 * e + c] = b[c] <= 0;
        any |= b[c] <= 0;
        if (b[c] < b[least]) least = c;
      }
      if (bad && !any) ss.bpen[27 * e + least] = 1;
    }
    ss.bscale = hex_scale(ss.P, r);
    /* the rule's nodes stay walled: the repair must not give back what
     * the untangling won */
    for (int64_t q = 0; q < ss.nnodes; q++) ss.guard[q] = ss.dets[q] > 0;
    st = stats(&ss, sm.m->xyz);
  }
  if (st >= 0) {
    ss.eps = 0;
    ss.eps_restart = 0;
    st = untangle_rounds(&ss, prm, budget);
  }
  vm_free(ctx, ss.bw);
  vm_free(ctx, ss.bpen);
  vm_free(ctx, ss.beps);
  sub_end(s, &ss, &sm, vmark);
  return st;
}

/* The guarantee: every node of the geometric rule (24) positive gives
 * det J > 0 throughout a hex (Theorem 3.1) or a prism, so all of its
 * Bernstein coefficients (means of those nodes) are positive and the cell
 * is certified. The whole mesh untangled under that rule from where it is
 * (the corner rule's nodes all positive, most of the 64 already), every
 * node penalized, none guarded (the freedom to rearrange is what the
 * guarded rounds lack: they left 63-133 cells of the n = 32 pi cube), with
 * the global and local rounds of steps 1-2, until every cell is certified
 * (checked every 5 global iterations: all 64 nodes positive is more than
 * that asks) or the rounds stall. Under foldover its eps falls faster than
 * the other phases' (opts geometric_decay, 0.7 against 0.9 per block: from
 * a mesh whose corner nodes are all positive, the n = 32 7pi/8 cube's
 * phase ran at the 0.9 cap for 330 iterations, 107 s; with 0.7, 41 s, and
 * with both 0.7 and one iteration per block it no longer certified); its
 * local rounds keep 0.9 (update_eps). */
static int geometric_phase(ut_state *s, const vm_measure_params *prm, int *budget) {
  int u0 = s->rep->iter_untangle, l0 = s->rep->iter_local;
  int st = set_stage_rule(s, VM_RULE_GEOMETRIC);
  if (st >= 0) st = stats(s, s->m->xyz);
  if (st >= 0) {
    s->phase_name = "geometric";
    s->eps = 0;
    s->eps_restart = 0;
    s->stop_certified = 1;
    s->local_scale = 8;
    st = untangle_rounds(s, prm, budget);
    s->stop_certified = s->reached_certified = s->local_scale = 0;
  }
  int st2 = set_stage_rule(s, s->o->rule);
  if (st2 >= 0) st2 = stats(s, s->m->xyz);
  s->rep->iter_repair += s->rep->iter_untangle - u0 + s->rep->iter_local - l0;
  s->rep->iter_untangle = u0;
  s->rep->iter_local = l0;
  s->phase_name = "repair";
  return st < 0 ? st : st2;
}

/* Certifying repair: while some cells are not certified valid (the corner
 * rule's nodes can all be positive with det J < 0 inside a hex), untangle
 * their Bernstein coefficients (repair_round_bern; when they are all hexes,
 * until a round makes no progress) or the geometric rule's nodes of those
 * cells (repair_round), on the cells within
 * `rings` of them (repair_round), with every positive node elsewhere
 * guarded, then certify again; stops when every cell is certified, after
 * three rounds in a row without fewer uncertified cells, or at the budget.
 * Leaves the mesh with the fewest uncertified cells seen. */
static int repair_phase(ut_state *s, const vm_measure_params *prm, int *budget) {
  vm_ctx *ctx = s->ctx;
  vm_mesh *m = s->m;
  const vm_volume_opts *o0 = s->o;
  uint8_t *verdict = vm_malloc(ctx, (size_t)m->ne + 1);
  uint8_t *emask = vm_malloc(ctx, (size_t)m->ne + 1);
  uint8_t *soft = vm_malloc(ctx, (size_t)m->ne + 1);
  uint8_t *vmark = vm_malloc(ctx, (size_t)m->nv + 1);
  double *best = vm_alloc_array(ctx, (size_t)m->nv * 3 + 1, sizeof *best);
  int64_t *vrp = NULL;
  int32_t *vel = NULL;
  int st = verdict && best && emask && soft && vmark ? vm_mesh_vertex_elements(m, &vrp, &vel)
                                                     : VM_ERR_NOMEM;
  int rings = s->o->repair_rings;
  int64_t nbad = st < 0 ? -1 : certify(s, verdict), best_bad = nbad;
  s->rep->cert_bad_init = nbad;
  if (nbad < 0 && st >= 0) st = VM_ERR_NOMEM;
  if (st >= 0) memcpy(best, m->xyz, (size_t)m->nv * 3 * sizeof *best);
  int stalls = 0;
  s->phase_name = "repair";
  s->repair_stage = 1;
  if (st >= 0 && nbad > 0 && o0->repair_geometric && !out_of_time(s)) {
    /* the guarantee first: the whole mesh under the rule of (24) until
     * every cell is certified; the rounds below take what it leaves */
    double t = now();
    vm_log(ctx, VM_LOG_INFO,
           "repair: %lld cells not certified; untangling under the geometric rule (24)",
           (long long)nbad);
    st = geometric_phase(s, prm, budget);
    int64_t nb = st >= 0 || st == VM_ERR_INTERRUPTED ? certify(s, verdict) : -1;
    s->rep->geometric_left = nb;
    s->rep->time_geometric = now() - t;
    if (nb >= 0 && nb < best_bad) {
      best_bad = nbad = nb;
      memcpy(best, m->xyz, (size_t)m->nv * 3 * sizeof *best);
    } else if (nb >= 0) {
      /* no better: the rounds start from where the phase did */
      memcpy(m->xyz, best, (size_t)m->nv * 3 * sizeof *best);
      nbad = certify(s, verdict);
      if (st >= 0) st = stats(s, m->xyz);
    }
    if (nb < 0 && st >= 0) st = VM_ERR_NOMEM;
    if (nbad > 0 && st >= 0)
      vm_log(ctx, VM_LOG_INFO, "repair: the geometric rule left %lld cells not certified",
             (long long)nbad);
  }
  /* the Bernstein repair when every cell to repair is a hex (prisms and
   * pyramids: the geometric rule's nodes) */
  int bern = o0->repair_bernstein;
  for (int64_t e = 0; e < m->ne && bern && st >= 0; e++)
    if (verdict[e] != VM_JAC_VALID && m->etype[e] != VM_HEX) bern = 0;
  for (int round = 0; st >= 0 && nbad > 0 && round<o0->repair_rounds && * budget> 0 &&
                      !out_of_time(s) && stalls < 3;
       round++) {
    /* after a round without progress, the walls of the certified cells
     * around the rest are lowered to penalties, one ring more each time */
    if (stalls > 0) {
      for (int64_t e = 0; e < m->ne; e++) soft[e] = verdict[e] != VM_JAC_VALID;
      grow_mask(m, stalls, vrp, vel, soft, vmark);
    }
    /* only the cells within `rings` of those not certified take part and
     * only their inner vertices move: the rest of the mesh keeps its
     * certified cells and costs nothing */
    for (int64_t e = 0; e < m->ne; e++) emask[e] = verdict[e] != VM_JAC_VALID ? 2 : 0;
    grow_mask(m, rings, vrp, vel, emask, vmark);
    drop_fixed(m, vmark, emask);
    /* the untangling counters keep the schedule's iterations */
    int u0 = s->rep->iter_untangle, l0 = s->rep->iter_local;
    /* a round ends at its own budget: a fold squeezed flat against a guard
     * would otherwise keep the local rounds busy until the run's budget */
    int round_budget = *budget < o0->repair_round_iter ? *budget : o0->repair_round_iter;
    int used0 = round_budget;
    /* after a Bernstein round without progress, the rounds go on with
     * the geometric rule's nodes and the soft walls, as before the
     * Bernstein rounds existed */
    if (stalls > 0) bern = 0;
    st = bern
             ? repair_round_bern(s, prm, verdict, emask, vmark, &round_budget)
             : repair_round(s, prm, verdict, stalls > 0 ? soft : NULL, emask, vmark, &round_budget);
    *budget -= used0 - round_budget;
    s->rep->iter_repair += s->rep->iter_untangle - u0 + s->rep->iter_local - l0;
    s->rep->iter_untangle = u0;
    s->rep->iter_local = l0;
    s->rep->repair_rounds++;
    if (st < 0) break;
    int64_t nb = certify(s, verdict);
    if (nb < 0) {
      st = VM_ERR_NOMEM;
      break;
    }
    stalls = nb < best_bad ? 0 : stalls + 1;
    if (nb >= best_bad) rings += 3;
    if (nb < best_bad) {
      best_bad = nb;
      memcpy(best, m->xyz, (size_t)m->nv * 3 * sizeof *best);
    }
    nbad = nb;
  }
  if ((st >= 0 || st == VM_ERR_INTERRUPTED) && nbad > best_bad) {
    memcpy(m->xyz, best, (size_t)m->nv * 3 * sizeof *best);
    certify(s, verdict);
  }
  if (nbad == 0) s->rep->time_certified = now() - s->t0;
  s->phase_name = "untangle";
  s->repair_stage = 0;
  vm_free(ctx, verdict);
  vm_free(ctx, emask);
  vm_free(ctx, soft);
  vm_free(ctx, vmark);
  vm_free(ctx, vrp);
  vm_free(ctx, vel);
  vm_free(ctx, best);
  return st;
}

/* The Bernstein term on every hex (weight w), so that the optimization
 * after the repair keeps the cells certified without the line search
 * having to cut its steps to nothing at a wall it cannot see: a positive
 * coefficient walled (eps delta0), and a coefficient <= 0 of a cell
 * certified by subdivision penalized (eps twice its magnitude), which
 * lifts it. Without that penalty such a cell was held only by the line
 * search's certification and sank towards det J = 0 inside: the n = 32
 * 7pi/8 cube with the reference targets ended with one whose phi over the
 * whole cell was 4.8e-6 against 1.6e-4 at the corners (a coefficient of
 * -1.2e-7). w <= 0 takes the term off. */
static int bern_walls(ut_state *s, double w) {
  vm_ctx *ctx = s->ctx;
  const vm_mesh *m = s->m;
  if (!(w > 0)) return vm_problem_set_bernstein(s->P, NULL, NULL, 1);
  double *bw = vm_alloc_array(ctx, (size_t)m->ne + 1, sizeof *bw);
  double *be = vm_alloc_array(ctx, 27 * (size_t)m->ne + 1, sizeof *be);
  int st = bw && be ? VM_OK : VM_ERR_NOMEM;
  double scale = hex_scale(s->P, m);
  for (int64_t e = 0; e < m->ne && st >= 0; e++) {
    bw[e] = 0;
    for (int c = 0; c < 27; c++) be[27 * e + c] = s->o->delta0;
    if (m->etype[e] != VM_HEX) continue;
    double b[27];
    hex_coefs(m, m->xyz, e, b);
    for (int c = 0; c < 27; c++)
      if (b[c] <= 0) be[27 * e + c] = fmax(-2 * scale * b[c], s->o->delta0);
    bw[e] = w;
  }
  if (st >= 0) st = vm_problem_set_bernstein(s->P, bw, be, scale);
  vm_free(ctx, bw);
  vm_free(ctx, be);
  return st;
}

/* Optimization of an untangled mesh: the barrier measure (which keeps the
 * mesh admissible) for opt_iter iterations (if `plain`), then `qi` steps of
 * the quasi-isometric continuation (11), raising t of W_t to push up the
 * worst element. With s->keep_certified every step also keeps every cell
 * certified; on a mesh with 3D cells other than tets no step adds a face
 * pyramid OpenFOAM's checkMesh calls incorrectly oriented (a certified
 * cell can have one: a warped face with the cell centre beyond it). */
static int optimize_phase(ut_state *s, const vm_measure_params *prm, int plain, int qi) {
  const vm_volume_opts *o = s->o;
  vm_minimize_result res;
  int st;
  if ((st = vm_problem_set_node_eps(s->P, NULL)) < 0) return st;
  s->eps = 0;
  if ((st = vm_problem_set_measure(s->P, o->measure, prm)) < 0) return st;
  if (has_foam_cells(s->m)) s->foam_max = foam_errors_at(s, s->m->xyz);
  if (plain && o->opt_iter > 0) {
    st = run_phase(s, "optimize", o->solver, o->opt_iter, before_plain, &res);
    s->rep->iter_opt += res.iterations;
    if (st < 0) goto done;
    if (s->foam_max > 0) s->foam_max = foam_errors_at(s, s->m->xyz);
  }
  for (int k = 0; k < qi && st >= 0 && !out_of_time(s); k++) {
    if ((st = vm_problem_set_measure(s->P, VM_MEASURE_QUASI_ISO, prm)) < 0) goto done;
    double lo = k == 0 ? 0 : s->rep->t_reached;
    double tmax = qi_feasible_t(s, lo);
    vm_measure_params q = *prm;
    q.t = lo + 0.9 * (tmax - lo);
    s->eps = q.t;
    if ((st = vm_problem_set_params(s->P, &q)) < 0) goto done;
    st = run_phase(s, "quasi-iso", o->solver, o->opt_iter > 0 ? o->opt_iter : 50, before_plain,
                   &res);
    s->rep->iter_opt += res.iterations;
    s->rep->t_reached = q.t;
  }
done:
  s->foam_max = -1;
  return st > 0 ? VM_OK : st;
}

/* optimize_phase with every step keeping every cell certified and the
 * Bernstein walls on (after the repair, whose cells it must not lose);
 * the walls and the flag are off again on return */
static int optimize_certified(ut_state *s, const vm_measure_params *prm, int plain, int qi) {
  s->keep_certified = 1;
  int st = bern_walls(s, 0.1);
  if (st >= 0) st = optimize_phase(s, prm, plain, qi);
  s->keep_certified = 0;
  bern_walls(s, 0);
  return st;
}

/* The face pyramids OpenFOAM calls wrong that the optimization left (its
 * guard keeps their count from rising; the repair before it is free to make
 * them). For each cell that has one, in cell order, up to 20 rounds: each
 * free vertex of the cell tries a step up the gradient of the cell's least
 * face pyramid (vm_cell_foam_margin, by finite differences), of 1/10 of the
 * cell's extent halved down to 1e-4 of it; the step that raises the margin
 * most is kept if every cell around that vertex stays certified and the
 * others have no more wrong pyramids than before (so the count falls when
 * the cell's own are gone). Deterministic. Returns the count left
 * over the mesh, or a negative error. */
static int64_t foam_relief(ut_state *s) {
  vm_mesh *m = s->m;
  int64_t left = foam_errors_at(s, m->xyz);
  if (left <= 0) return left;
  int64_t *vrp = NULL;
  int32_t *vel = NULL;
  int st = vm_mesh_vertex_elements(m, &vrp, &vel);
  if (st < 0) return st;
  int64_t was = left, moves = 0;
  double y[3 * VM_MAX_ELEM_VERTS];
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 3 || t == VM_TET) continue;
    int k = vm_elem_nverts(t);
    for (int round = 0; round < 20; round++) {
      cell_coords(m, m->xyz, e, y);
      double m0 = vm_cell_foam_margin(t, y), ext = 0;
      if (m0 > 0) break; /* no face pyramid of the cell wrong */
      for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++) ext = fmax(ext, vm_dist3(y + 3 * i, y + 3 * j));
      double best = m0, bp[3];
      int64_t bv = -1;
      for (int i = 0; i < k; i++) {
        int32_t v = m->conn[m->eoff[e] + i];
        if (m->vflag[v] != VM_VERTEX_FREE) continue;
        double *p = m->xyz + 3 * v, p0[3], g[3], h = 1e-7 * ext;
        memcpy(p0, p, sizeof p0);
        int before = 0;
        for (int64_t j = vrp[v]; j < vrp[v + 1]; j++)
          if (vel[j] != e && vm_elem_dim(m->etype[vel[j]]) == 3) {
            int tj = cell_coords(m, m->xyz, vel[j], y);
            before += vm_cell_foam(tj, y, NULL);
          }
        for (int r = 0; r < 3; r++) {
          p[r] = p0[r] + h;
          cell_coords(m, m->xyz, e, y);
          g[r] = (vm_cell_foam_margin(t, y) - m0) / h;
          p[r] = p0[r];
        }
        double gn = vm_norm3(g);
        if (!(gn > 0) || !isfinite(gn)) continue;
        for (double a = 0.1; a > 1e-4; a /= 2) {
          for (int r = 0; r < 3; r++) p[r] = p0[r] + a * ext * g[r] / gn;
          cell_coords(m, m->xyz, e, y);
          double m1 = vm_cell_foam_margin(t, y);
          if (!(m1 > best)) continue;
          int ok = 1, after = 0;
          for (int64_t j = vrp[v]; j < vrp[v + 1] && ok; j++) {
            if (vm_elem_dim(m->etype[vel[j]]) != 3) continue;
            int tj = cell_coords(m, m->xyz, vel[j], y);
            ok = vm_jacobian_certify(tj, y, 0, NULL) == VM_JAC_VALID;
            if (vel[j] != e) after += vm_cell_foam(tj, y, NULL);
          }
          if (ok && after <= before) {
            best = m1;
            bv = v;
            memcpy(bp, p, sizeof bp);
            break;
          }
        }
        memcpy(p, p0, sizeof p0);
      }
      if (bv < 0) break;
      memcpy(m->xyz + 3 * bv, bp, sizeof bp);
      moves++;
    }
  }
  vm_free(s->ctx, vrp);
  vm_free(s->ctx, vel);
  left = foam_errors_at(s, m->xyz);
  vm_log(s->ctx, VM_LOG_INFO,
         "volume: face pyramids OpenFOAM calls wrong after the optimization: %lld -> %lld (%lld "
         "vertex moves)",
         (long long)was, (long long)left, (long long)moves);
  return left;
}

int vm_volume_run(vm_ctx *ctx, vm_mesh *m, const vm_surface_ops *surf, const vm_volume_opts *opts,
                  vm_volume_report *report) {
  vm_volume_opts o = opts ? *opts : vm_volume_opts_default();
  vm_volume_report rep;
  memset(&rep, 0, sizeof rep);
  rep.cert_bad_init = -1;
  rep.geometric_left = -1;
  ut_state s;
  memset(&s, 0, sizeof s);
  s.ctx = ctx;
  s.m = m;
  s.tref = o.target_xyz;
  s.o = &o;
  s.rep = &rep;
  s.surf = surf;
  s.t0 = now();
  s.best_M = INT64_MAX;
  s.foam_max = -1;
  s.phase_name = "untangle";
  int st = vm_problem_create(ctx, m, &s.P);
  if (st < 0) return st;
  vm_measure_params prm = vm_measure_params_default();
  prm.theta = o.theta;
  if ((st = vm_problem_set_rule(s.P, o.rule)) < 0) goto done;
  s.rule = o.rule;
  if (o.target_xyz)
    st = vm_problem_set_target_reference(s.P, o.target_xyz);
  else
    st = vm_problem_set_target_ideal(s.P, o.target_size);
  if (st < 0) goto done;
  s.best = vm_alloc_array(ctx, (size_t)m->nv * 3 + 1, sizeof *s.best);
  if (!s.best) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if ((st = size_node_arrays(&s)) < 0) goto done;
  rep.nodes = s.nnodes;
  if ((st = stats(&s, m->xyz)) < 0) goto done;
  rep.M_init = rep.M_max = s.M;
  int budget = o.max_iter;
  if (o.staged && (o.rule == VM_RULE_CORNER || o.rule == VM_RULE_GEOMETRIC) && has_hex(m) &&
      s.M > 0) {
    /* the 6-tet split first (the most freedom to find the twist), then the
     * rule's nodes with the split kept admissible, then the rule alone */
    s.split_stage = 1;
    if ((st = set_stage_rule(&s, VM_RULE_SPLIT)) < 0 || (st = stats(&s, m->xyz)) < 0) goto done;
    rep.split_M_init = s.M;
    s.phase_name = "split";
    st = untangle_rounds(&s, &prm, &budget);
    s.split_stage = 0;
    if (st < 0) goto done;
    rep.split_valid = s.M == 0;
    rep.time_split = now() - s.t0;
    if (s.M == 0) {
      vm_rule g = o.rule == VM_RULE_CORNER ? VM_RULE_CORNER_SPLIT : VM_RULE_GEOMETRIC_SPLIT;
      if ((st = set_stage_rule(&s, g)) < 0 || (st = stats(&s, m->xyz)) < 0) goto done;
      s.phase_name = "guarded";
      if ((st = untangle_rounds(&s, &prm, &budget)) < 0) goto done;
    }
    if ((st = set_stage_rule(&s, o.rule)) < 0 || (st = stats(&s, m->xyz)) < 0) goto done;
    s.phase_name = "untangle";
  }
  if ((st = untangle_rounds(&s, &prm, &budget)) < 0) goto done;
  if (s.M > 0 && s.best_M < s.M) memcpy(m->xyz, s.best, (size_t)m->nv * 3 * sizeof *m->xyz);
  rep.time_untangle = now() - s.t0;
  /* with hexes to certify, the quasi-isometric steps come last, on the
   * certified mesh (below): before the repair they would change what it
   * starts from */
  int qi_last = o.repair && has_hex(m);
  if (s.M == 0 && !out_of_time(&s))
    if ((st = optimize_phase(&s, &prm, 1, qi_last ? 0 : o.qi_steps)) < 0 &&
        st != VM_ERR_INTERRUPTED)
      goto done;
  if (st >= 0 && s.M == 0 && o.repair && !out_of_time(&s)) {
    /* the corner rule's M = 0 is not det J > 0 inside every hex */
    if ((st = repair_phase(&s, &prm, &budget)) < 0) goto done;
    if (rep.cert_bad_init > 0 && rep.cert_invalid + rep.cert_undecided == 0 && !out_of_time(&s)) {
      /* the repair squeezed cells to certify them: optimize again, every
       * step keeping every cell certified */
      if ((st = optimize_certified(&s, &prm, 1, 0)) < 0 && st != VM_ERR_INTERRUPTED) goto done;
    }
    if (st >= 0 && qi_last && o.qi_steps > 0 && rep.cert_cells > 0 &&
        rep.cert_invalid + rep.cert_undecided == 0 && !out_of_time(&s)) {
      /* the worst cells lifted, every step keeping every cell certified:
       * the n = 32 pi cube's phi_min 2.5e-4 -> 5.3e-4 in one step (the
       * paper's 2.65e-4), about 15 s on 2 threads */
      if ((st = optimize_certified(&s, &prm, 0, o.qi_steps)) < 0 && st != VM_ERR_INTERRUPTED)
        goto done;
    }
  }
  if (st >= 0 && s.M == 0 && s.rule == VM_RULE_CORNER && has_foam_cells(m) && !out_of_time(&s)) {
    /* what the optimization's guard could not take away (under the corner
     * rule, whose nodes a certified cell keeps positive: a node of another
     * rule could turn over) */
    int64_t left = foam_relief(&s);
    if (left < 0) {
      st = (int)left;
      goto done;
    }
  }
  if (st >= 0 && (st = stats(&s, m->xyz)) < 0) goto done;
  {
    vm_node_stats ns;
    vm_problem_set_measure(s.P, VM_MEASURE_BALANCED, &prm);
    vm_problem_node_stats(s.P, m->xyz, &ns);
    rep.phi_min = ns.phi_min;
    rep.psi_min = ns.psi_min;
    rep.min_det = ns.min_det;
    rep.M_final = ns.inverted;
  }
  {
    /* valid as a solver means it: every cell certified det J > 0 */
    int64_t nbad = certify(&s, NULL);
    if (nbad < 0) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    rep.valid = rep.M_final == 0 && nbad == 0;
    if (rep.valid && rep.cert_bad_init <= 0) rep.time_certified = rep.time_untangle;
  }
  if (st >= 0) st = rep.valid ? VM_OK : VM_WARN_INVERTED;
done:
  rep.time_total = now() - s.t0;
  rep.timed_out = out_of_time(&s);
  /* the last untangling phase's: a stage that stalled before another ran
   * is not why the run ended */
  rep.stalled = s.stalled;
  if (st == VM_ERR_INTERRUPTED && (s.split_stage || s.guard || s.nw)) {
    /* interrupted while staged: count the rule's own nodes again */
    s.split_stage = 0;
    if (set_stage_rule(&s, o.rule) < 0 || stats(&s, m->xyz) < 0) s.M = INT64_MAX;
  }
  if (st == VM_ERR_INTERRUPTED && s.best_M < INT64_MAX && s.M > s.best_M)
    memcpy(m->xyz, s.best, (size_t)m->nv * 3 * sizeof *m->xyz);
  vm_free(ctx, s.dets);
  vm_free(ctx, s.node_eps);
  vm_free(ctx, s.best);
  vm_free(ctx, s.guard);
  vm_free(ctx, s.nw);
  vm_problem_destroy(&s.P);
  if (report) *report = rep;
  return st;
}
