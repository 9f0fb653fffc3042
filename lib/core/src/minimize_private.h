/* lib/core/src/minimize_private.h: the minimizer object and the operation table
 * each member of the family (minimize_explicit.c, minimize_implicit.c) fills. */
#ifndef VARMESH_MINIMIZE_PRIVATE_H
#define VARMESH_MINIMIZE_PRIVATE_H

#include "varmesh/minimize.h"

typedef struct vm_minimizer_ops {
  const char *name;
  int needs_hoff; /* 1: the direction uses the off-diagonal Hessian entries
                     (hoff); 2: the full PSD-projected blocks (hblk of
                     vm_problem_eval_blocks, passed as hoff; hdiag projected) */
  /* Per-run state, after m->bc exists. */
  int (*begin)(vm_minimizer *m);
  /* Descent direction d (3*nv) at the current iterate from the projected
   * gradient g = L grad F, the diagonal blocks hdiag and (if needs_hoff)
   * the off-diagonal entries hoff. d must satisfy d_k = L_k d_k (zero at
   * fixed vertices). *lin_iters: linear solver iterations spent. */
  int (*direction)(vm_minimizer *m, int iter, const double *g, const double *hdiag,
                   const double *hoff, double *d, int *lin_iters);
  void (*end)(vm_minimizer *m); /* frees the per-run state (safe without begin) */
} vm_minimizer_ops;

struct vm_minimizer {
  vm_ctx *ctx;
  vm_problem *prob;
  vm_minimizer_kind kind;
  const vm_minimizer_ops *ops;
  vm_minimize_options opt;
  vm_surface_ops surf;
  int has_surf;
  vm_bc *bc; /* during a run */
  int64_t nv;
  int sdim;            /* space dimension of the vertices: 2 or 3 */
  void *impl;          /* the member's per-run state */
  double last_tau;     /* the last accepted step length (0 before the first) */
  int last_infeasible; /* infeasible trials in its line search */
};

extern const vm_minimizer_ops vm_minimizer_explicit_ops;
extern const vm_minimizer_ops vm_minimizer_implicit_ops;
extern const vm_minimizer_ops vm_minimizer_newton_ops;

/* Newton step in the admissible subspace of one vertex:
 * a = -(Q^T H Q + mu I)^{-1} Q^T g with the smallest mu >= 0 from a short
 * sequence that makes the k x k matrix numerically positive definite;
 * d = Q a. Returns 0, or 1 if H is zero in the subspace (d = 0). */
int vm_min_vertex_step(const double H[9], const double g[3], const double Q[9], int k, double d[3]);

#endif
