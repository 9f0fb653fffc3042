/* varmesh/volume.h: the volume stage: untangling (Section 5: penalty
 * (35) with its one-way variant, barrier with admissible-set contraction
 * (39), local untangling of subdomains) followed by optimization with a
 * barrier measure and optional quasi-isometric continuation (11). */
#ifndef VARMESH_VOLUME_H
#define VARMESH_VOLUME_H

#include <stdint.h>

#include "varmesh/boundary.h"
#include "varmesh/measure.h"
#include "varmesh/minimize.h"
#include "varmesh/mesh.h"
#include "varmesh/quadrature.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_UNTANGLE_PENALTY = 0,        /* (14)-(16) with eps from (35) */
  VM_UNTANGLE_PENALTY_ONEWAY = 1, /* (35) with eps = delta0 on non-degenerate nodes */
  VM_UNTANGLE_BARRIER = 2,        /* (17) with admissible-set contraction (39) */
  VM_UNTANGLE_ADAPTIVE = 3,       /* (35) with eps falling by at most kappa per
                                     iteration, ending when det >= eps > 0 on
                                     every node (no near-degenerate result) */
  VM_UNTANGLE_FOLDOVER = 4        /* (14)-(16) with eps set every eps_inner
                                     iterations so that chi at the worst node
                                     shrinks as F did (Garanzha et al. 2021,
                                     "Foldover-free maps in 50 lines of code") */
} vm_untangle_method;

/* Progress, reported every iteration of every phase. */
typedef struct vm_volume_progress {
  const char *phase; /* "untangle", "local", "optimize", "quasi-iso" */
  int iter;          /* iteration within the phase */
  int total_iter;    /* iterations over all phases */
  double F;
  int64_t inverted; /* M: quadrature nodes with det C <= 0 */
  double min_det;
  double eps; /* current epsilon (untangling), or t (quasi-iso) */
  double tau; /* accepted step */
  int pcg_iters;
  double elapsed; /* seconds since the start */
} vm_volume_progress;

typedef void (*vm_volume_progress_fn)(void *user, const vm_volume_progress *p);

typedef struct vm_volume_opts {
  vm_untangle_method method; /* default VM_UNTANGLE_ADAPTIVE */
  vm_minimizer_kind solver;  /* global untangling and optimization (default implicit;
                                newton runs with block Jacobi, at most 200 CG
                                iterations per step) */
  int untangle_solver;       /* a vm_minimizer_kind for the global untangling
                                phases alone, < 0 (default -1): solver */
  vm_rule rule;              /* quadrature rule (default corner) */
  vm_measure_kind measure;   /* optimization measure: balanced (default), shape,
                                shape-alt or barrier-free quasi-iso */
  double theta;              /* of phi_theta (default 0.8) */
  double theta_untangle;     /* of phi_theta in the global untangling phase
                                (local rounds use theta), <= 0: theta */
  double delta0;             /* smallest epsilon (default 1e-11; det C is target-relative) */
  double sigma;              /* contraction of (39), in (0, 1) (default 0.5) */
  double kappa;              /* adaptive: slowest eps decay per iteration (0.7) */
  int eps_inner;             /* foldover: iterations per eps (default 10) */
  double eps_cap;            /* foldover: while nodes are guarded (the staged
                                schedule's second stage, the repair's rounds)
                                or in the geometric phase's global rounds,
                                and a node is inverted, a block's new eps is at
                                most eps_cap |min det| (what a start from that
                                mesh would take), not below the run's
                                eps_restart; <= 0: no cap (default 0; 1 in the
                                foldover schedules) */
  int max_iter;              /* untangling iterations, global + local (default 20000) */
  int opt_iter;              /* optimization iterations once valid (default 100) */
  double time_limit;         /* seconds for the whole run, <= 0: none */
  int local_threshold;       /* go local when fewer nodes than this are inverted (100) */
  int local_rings;           /* rings of elements around inverted ones (default 3) */
  int qi_steps;              /* quasi-isometric continuation steps (0: off;
                                1 in the staged schedule); with hexahedra and
                                the repair on, after the repair, every step
                                keeping every cell certified */
  int staged;                /* meshes with hexahedra, corner or geometric rule:
                                untangle the hexes' 6-tet split first, then the
                                rule's nodes with the split held admissible
                                (VM_RULE_CORNER_SPLIT / _GEOMETRIC_SPLIT, the
                                split's nodes at eps = delta0), then the rule */
  double eps_restart;        /* foldover: eps after a stalled local round is at
                                least this (default 1e-2; det C is relative to
                                the target) */
  int repair;                /* after optimization, drive the cells that are not
                                certified valid (det J > 0 everywhere, see
                                varmesh/jacobian.h) to it: the geometric rule's
                                nodes of those cells untangled locally, every
                                positive node elsewhere guarded (default 1) */
  int repair_rounds;         /* certify-and-repair rounds at most (default 20) */
  int repair_round_iter;     /* iterations of one repair round at most (default
                                1000: the n = 16 pi cube's rounds took 280-480) */
  int repair_rings;          /* rings of elements around the uncertified ones
                                that a repair round may move (default 4; 3 more
                                after a round without progress, when the
                                certified cells next to the others also lose
                                their guards, one ring more each time) */
  int repair_bernstein;      /* repair rounds on hexahedra penalize the Bernstein
                                coefficients of det J themselves (default 1; after
                                a round without progress, and for other cells, the
                                geometric rule's nodes); 0: the nodes throughout */
  int repair_geometric;      /* the repair begins by untangling the whole mesh
                                under the geometric rule (24) until every cell is
                                certified (all 64 nodes of a hex positive give
                                det J > 0 in it, Theorem 3.1), then rounds for
                                what is left (default 1); 0: the rounds alone */
  double geometric_decay;    /* the geometric phase's global rounds under
                                --untangle foldover: the most of the penalty at
                                the worst node that one block of eps_inner
                                iterations keeps (default 0.7; the other phases
                                and a value outside (0, 1): 0.9) */
  double target_size;        /* ideal target edge length, <= 0: automatic */
  const double *target_xyz;  /* reference coordinates as targets (overrides size) */
  vm_volume_progress_fn progress;
  void *user;
} vm_volume_opts;

vm_volume_opts vm_volume_opts_default(void);
/* The direct schedule's settings, vm-volume's default on meshes without
 * hexahedra: the defaults with the foldover untangling measured on the
 * rotated cube and its 6-tet split (eps_inner 3, theta_untangle 0.999;
 * docs/volume.md). The defaults' adaptive penalty is vm-volume's fallback
 * when this stalls. */
vm_volume_opts vm_volume_opts_direct(void);
/* The staged schedule's settings, vm-volume's default on meshes with
 * hexahedra: vm_volume_opts_direct() with staged = 1. */
vm_volume_opts vm_volume_opts_staged(void);

/* Iterations without progress at a collapsed eps after which foldover's
 * untangling is given up as stalled (vm_volume_report.stalled). */
#define VM_VOLUME_STALL_ITER 300

typedef struct vm_volume_report {
  int64_t nodes; /* quadrature nodes */
  int64_t M_init, M_max, M_final;
  int iter_untangle;    /* global untangling iterations */
  int iter_local;       /* local untangling iterations */
  int iter_opt;         /* optimization (and quasi-iso) iterations */
  double time_untangle; /* seconds until M = 0 (or the end) */
  double time_total;
  int timed_out; /* the run was cut short by opts.time_limit */
  /* the last untangling phase was given up as stalled (foldover: its eps
   * collapsed below 1e-6 |min det| and VM_VOLUME_STALL_ITER iterations
   * brought neither fewer inverted nodes nor a min det 5 % higher), and
   * its figures then */
  int stalled;
  double stall_min_det, stall_eps;
  double phi_min, psi_min, min_det; /* final, over all nodes */
  double t_reached;                 /* quasi-iso: the largest t with a finite W_t (0 if off) */
  int valid;                        /* M_final == 0 and every cell certified valid */
  int64_t cert_cells;               /* cells certified (vm_mesh_jacobian_certify) at the end */
  int64_t cert_invalid;             /* of them certified det J <= 0 somewhere */
  int64_t cert_undecided;           /* of them neither (not valid) */
  int64_t cert_bad_init;            /* cells not certified valid when the repair began
                                       (-1: no repair ran) */
  int iter_repair;                  /* repair iterations (global + local) */
  int repair_rounds;                /* certify-and-repair rounds run */
  int64_t geometric_left;           /* cells not certified after the repair's
                                       geometric phase (-1: it did not run) */
  double time_geometric;            /* seconds the geometric phase took */
  double time_certified;            /* seconds until every cell was certified valid */
  int64_t split_M_init;             /* staged: inverted split tets at the start */
  int64_t split_M_max;              /* staged: the most while untangling the split (M_max
                                       counts the rule's nodes, split stage excluded) */
  int split_valid;                  /* staged: the split was untangled */
  double time_split;                /* staged: seconds until then */
  vm_stop_reason last_stop;         /* how the last minimizer run stopped */
} vm_volume_report;

/* Untangle and optimize mesh m in place. Which vertices move comes from
 * m->vflag (FIXED never move: bit-identical; SLIP slide on `surf`, which
 * may be NULL when there are no slip vertices). If the mesh cannot be made
 * valid, m holds the state with the fewest inverted nodes seen.
 * Returns VM_OK when the result is valid (M = 0), VM_WARN_INVERTED when
 * inverted nodes remain, VM_ERR_INTERRUPTED (m holds the best state so
 * far), or a negative error. report may be NULL. */
int vm_volume_run(vm_ctx *ctx, vm_mesh *m, const vm_surface_ops *surf, const vm_volume_opts *opts,
                  vm_volume_report *report);

const char *vm_untangle_method_name(vm_untangle_method m);

#ifdef __cplusplus
}
#endif
#endif
