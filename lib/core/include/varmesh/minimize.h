/* varmesh/minimize.h: the projected Newton-type minimizers of Section 4:
 * explicit (3x3 block per vertex, (34)) and implicit (three scalar sparse
 * systems solved by PCG), with a line search on tau (33), (37), slip
 * boundary conditions and stopping rules. */
#ifndef VARMESH_MINIMIZE_H
#define VARMESH_MINIMIZE_H

#include <stdint.h>

#include "varmesh/boundary.h"
#include "varmesh/ctx.h"
#include "varmesh/linsolve.h"
#include "varmesh/problem.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_MINIMIZER_EXPLICIT = 0, /* H_ij = 0 for i != j (34) */
  VM_MINIMIZER_IMPLICIT = 1, /* off-diagonal entries of the 3x3 blocks dropped */
  VM_MINIMIZER_NEWTON = 2    /* full 3x3 blocks of the Hessian, each node's part
                                projected to positive semidefinite, one coupled
                                system (3 unknowns per vertex) by PCG with a
                                block preconditioner (precond AMG: block AMG
                                aggregating vertices; JACOBI or BLOCK_JACOBI:
                                3x3 block Jacobi), plus a Levenberg-Marquardt
                                shift adapted from the line search */
} vm_minimizer_kind;

/* Why a run stopped. */
typedef enum {
  VM_STOP_NONE = 0,
  VM_STOP_REL_DECREASE = 1, /* converged: relative decrease of F below tolerance */
  VM_STOP_GRAD_NORM = 2,    /* converged: projected gradient norm below tolerance */
  VM_STOP_MAX_ITER = 3,     /* iteration limit (VM_WARN_MAXITER) */
  VM_STOP_TIME = 4,         /* time limit (VM_WARN_TIME) */
  VM_STOP_LINE_SEARCH = 5,  /* no acceptable step along the direction */
  VM_STOP_INTERRUPTED = 6,  /* vm_ctx_interrupted (VM_ERR_INTERRUPTED) */
  VM_STOP_CALLBACK = 7      /* before_iteration asked to stop */
} vm_stop_reason;

/* Reported to the monitor after every iteration. */
typedef struct vm_iter_info {
  int iter;          /* 1, 2, ... */
  double F;          /* F after the step */
  double F_before;   /* F at the start of the iteration (after before_iteration) */
  double grad_norm;  /* |L grad F|_2 at the start of the iteration */
  double tau;        /* accepted step length */
  int ls_evals;      /* functional evaluations of the line search */
  int ls_infeasible; /* of those, trial points outside the measure's domain (F = +inf) */
  int pcg_iters;     /* implicit: CG iterations summed over the coordinate systems;
                        newton: CG iterations of the coupled system */
  int64_t held;      /* vertices held still in the accepted step (hold_tau), else 0 */
  double elapsed;    /* seconds since vm_minimizer_run started */
  int64_t inverted;  /* quadrature nodes with det C <= 0 after the step (-1: not computed) */
  double min_det;    /* min det C over all nodes after the step (NAN: not computed) */
} vm_iter_info;

typedef void (*vm_monitor_fn)(void *user, const vm_iter_info *info);
/* Called before every iteration (iter 1, 2, ...) with the current x, e.g.
 * to update epsilon of (35) or (39) through vm_problem_set_params. Return
 * 0 to go on, > 0 to stop (VM_STOP_CALLBACK, status VM_OK), < 0 to abort
 * with that status. */
typedef int (*vm_before_iteration_fn)(void *user, int iter, const double *x);

typedef struct vm_minimize_options {
  int max_iter;            /* iteration limit (default 200) */
  double time_limit;       /* seconds, <= 0: none (default 0) */
  double rel_decrease_tol; /* stop when (F_old - F_new) <= tol |F_new| ... */
  int rel_decrease_count;  /* ... in this many consecutive iterations (default 1e-10, 2) */
  double grad_atol;        /* stop when |L grad|_2 <= grad_atol (default 0: off) */
  double grad_rtol;        /* ... or <= grad_rtol |L grad_0|_2 (default 1e-10) */
  /* line search */
  double armijo;      /* sufficient decrease constant c1 (default 1e-4) */
  int ls_max_evals;   /* evaluations per line search (default 40) */
  int ls_extrapolate; /* tries of a longer step after tau = 1 passed (default 2) */
  /* > 0: a step held below this by a few elements is tried again without
   * them. When the line search accepts a step shorter than hold_tau (or
   * none), each element's change of F over the full step is measured
   * (+inf where it turns over); the vertices of those that rise most are
   * held still, the largest rise first, until the others' changes sum to
   * at most a quarter of the directional derivative (a twentieth of the
   * elements at most); the direction is solved again without them (their
   * gradients and couplings zeroed: a descent direction), up to 3 rounds
   * each adding the elements that still hold the new full step back; of
   * the two line searches the lower F is kept. After a retry that did
   * not pay, the next 2 short steps go without one. Where a few
   * degenerate elements (slivers at a sharp corner that cannot reach
   * their targets) cut every vertex's step, the others take theirs.
   * 0 (default): off. vm_minimize_result.held_steps counts the steps so
   * taken. */
  double hold_tau;
  /* implicit and newton minimizers */
  double pcg_rtol;         /* relative residual of the inexact Newton step (default 1e-2) */
  int pcg_maxit;           /* CG iteration cap per system (default 100) */
  vm_precond_kind precond; /* default VM_PRECOND_AMG (newton: block AMG, vertices
                              aggregated; JACOBI means block Jacobi there, and
                              BLOCK_JACOBI means Jacobi for implicit) */
  vm_amg_options amg;      /* AMG parameters (vm_amg_options_default, but
                              update_coarse 0) */
  int amg_rebuild_every;   /* new AMG hierarchy every k-th iteration, vm_precond_update
                              in between (default 4). With amg.update_coarse 0 the
                              update only refreshes the finest smoother: on a 64^3
                              jittered hex cube an implicit iteration then costs
                              0.96 s instead of 2.25 s, at 17 instead of 9 CG
                              iterations (see bench/bench_solver.c) */
  /* reporting and hooks */
  int stats_every; /* node statistics (M, min det) every k iterations (default 1; 0 off) */
  vm_monitor_fn monitor;
  vm_before_iteration_fn before_iteration;
  /* optional: a trial point of the line search at which it returns 0 is
   * treated as outside the measure's domain (the step is shortened), so
   * every accepted iterate satisfies it when the start does (e.g. every
   * cell certified det J > 0 everywhere); NULL: none */
  int (*admissible)(void *user, const double *x);
  void *user; /* passed to monitor, before_iteration and admissible */
} vm_minimize_options;

vm_minimize_options vm_minimize_options_default(void);

typedef struct vm_minimize_result {
  int iterations;
  vm_stop_reason reason;
  double F_initial;       /* F at the start of the first iteration */
  double F;               /* final F */
  double grad_norm;       /* |L grad|_2 at the last evaluation */
  int64_t pcg_iterations; /* total over the run */
  int held_steps;         /* accepted steps taken with vertices held still (hold_tau) */
  double elapsed;         /* seconds */
  int64_t inverted;       /* final node statistics (computed at the end) */
  double min_det;
} vm_minimize_result;

typedef struct vm_minimizer vm_minimizer;

/* Create a minimizer of `kind` for `problem` (not owned: it must outlive
 * the minimizer) with default options. Free with vm_minimizer_destroy. */
int vm_minimizer_create(vm_ctx *ctx, vm_problem *problem, vm_minimizer_kind kind,
                        vm_minimizer **out);
void vm_minimizer_destroy(vm_minimizer **p);
/* Options (copied). VM_ERR_ARG on nonsensical values. */
int vm_minimizer_set_options(vm_minimizer *m, const vm_minimize_options *opt);
const vm_minimize_options *vm_minimizer_options(const vm_minimizer *m);
/* Constraint surfaces for the SLIP vertices of the problem's mesh
 * (copied; NULL removes them). */
int vm_minimizer_set_surfaces(vm_minimizer *m, const vm_surface_ops *surf);
/* The family member's name: "explicit", "implicit" or "newton". */
const char *vm_minimizer_name(const vm_minimizer *m);

/* Minimize F over x (3*nv, in/out; e.g. the mesh's own xyz). Vertex
 * classes are read from the mesh's vflag / vsurf at the call. Slip
 * vertices are first projected onto their surfaces (V of (33)); fixed
 * vertices are never written. x must be inside the measure's domain
 * (F finite) at the start of every iteration; each accepted step keeps F
 * finite, so with a barrier measure the mesh never leaves the admissible
 * set. res may be NULL.
 * Returns VM_OK (converged, stopped by the line search or by the hook),
 * VM_WARN_MAXITER, VM_WARN_TIME, VM_ERR_INTERRUPTED (x holds the last
 * accepted iterate), VM_ERR_ARG (bad argument, F infinite at an iterate's
 * start), VM_ERR_NOMEM, VM_ERR_NUMERIC, or a hook's or projection's
 * status. */
int vm_minimizer_run(vm_minimizer *m, double *x, vm_minimize_result *res);

/* Name of a stop reason ("rel-decrease", "grad-norm", ...). */
const char *vm_stop_reason_name(vm_stop_reason r);

#ifdef __cplusplus
}
#endif
#endif
