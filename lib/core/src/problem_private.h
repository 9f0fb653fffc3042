/* lib/core/src/problem_private.h: the layout of vm_problem, shared by its setup
 * (problem.c) and its assembly (assembly.c); lib/ only. */
#ifndef VARMESH_PROBLEM_PRIVATE_H
#define VARMESH_PROBLEM_PRIVATE_H

#include <stdint.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "varmesh/problem.h"

/* How the active elements are measured. */
enum {
  VM_PK_VOL3 = 0,  /* 3D elements in 3D */
  VM_PK_PLANE = 1, /* 2D elements of a 2D mesh: xy components */
  VM_PK_SURF = 2   /* 2D elements in 3D: tangent frame with reference normal */
};

enum { VM_TGT_IDEAL = 0, VM_TGT_REFERENCE = 1, VM_TGT_FIELD = 2 };
enum { VM_METRIC_IDENTITY = 0, VM_METRIC_SCALAR = 1, VM_METRIC_TENSOR = 2 };

/* Below this many active elements the assembly runs on one thread: the
 * per-colour barriers would cost more than the work. */
#define VM_PROBLEM_MIN_PARALLEL 1024

/* Elements per block of the fixed-order sum of F. */
#define VM_PROBLEM_FBLOCK 512

/* A rule node's distinct local vertices u and their coefficients a_u in the
 * columns of E (+1 head, -1 tail): E = sum_u x_u a_u^T; pidx[k] is the
 * element pair index of the k-th pair (u, v), u < v, in loop order. */
typedef struct vm_nodepat {
  int nloc;
  signed char loc[6];
  signed char a[6][3];
  signed char pidx[15];
  double ad[6][3]; /* a as doubles */
} vm_nodepat;

#define VM_MAX_PAIRS 28

struct vm_problem {
  vm_ctx *ctx;
  vm_mesh *m;
  int tdim; /* 2 or 3: dimension of the active elements (d) */
  int kind; /* VM_PK_* */

  const vm_measure_ops *ops;
  vm_measure_params prm;

  /* quadrature rule per element type, node patterns, and the pairs of
   * local vertices (a < b) coupled by some node of the rule */
  int rule;
  const vm_qrule *qr[VM_NTYPES];
  vm_nodepat pat[VM_NTYPES][VM_QRULE_MAX_NODES];
  int npair[VM_NTYPES];
  signed char pair[VM_NTYPES][VM_MAX_PAIRS][2];

  /* active elements (highest dimension, mesh order) and their nodes */
  int64_t nae;
  int32_t *ael;  /* mesh element of active element i */
  int64_t *noff; /* nae + 1: first node of active element i */
  int64_t nn;
  int32_t *nelem; /* mesh element of each node */

  /* targets: node S = T^{-1} (d x d row-major) and wb = beta kappa det T,
   * shared per element type for ideal targets, per node otherwise */
  int tgt;
  double tgt_size;   /* edge length of the ideal targets */
  double *tgt_ref;   /* VM_TGT_REFERENCE: 3*nv copy */
  double *tgt_fld;   /* VM_TGT_FIELD: 3*eoff[ne] copy, element e vertex a at 3*(eoff[e]+a) */
  double *Snode;     /* nn*d*d or NULL */
  double *wnode;     /* nn or NULL */
  int64_t tgt_store; /* bytes of node targets kept at most (vm_problem_set_target_store) */
  double *wsum;      /* nae or NULL: the sum of wb over each element's nodes when S and wb
                        are computed at evaluation (Snode, wnode NULL; see compute_targets) */
  double Sid[VM_NTYPES][VM_QRULE_MAX_NODES * 9];
  double wid[VM_NTYPES][VM_QRULE_MAX_NODES];
  int sdiag[VM_NTYPES]; /* ideal S of every node of the type is diagonal */
  double tvol;          /* sum of w beta kappa det T over all nodes */

  /* metric G_x per active element: g (scalar), G (tensor: xx yy zz xy yz xz;
   * plane meshes use xx yy xy with zz = yz = xz = 0) and det Q */
  int metric;
  double *mg;
  double *mG;
  double *mdq;

  double *wel; /* nae weights (12) */
  double *nrm; /* VM_PK_SURF: nae reference unit normals */

  /* vertex graph (CSR, no diagonal, sorted) */
  int64_t *rowptr;
  int32_t *adj;
  /* hoff positions of every element pair (u, v) and (v, u), offsets within
   * the rows, built at the first Hessian assembly when every row has at
   * most 255 entries; ppos_stride bytes per active element (0: not built
   * yet, -1: rows too long, binary search instead) */
  uint8_t *ppos;
  int ppos_stride;

  /* greedy colouring of chunks of `chunk` consecutive active elements: no
   * two chunks of a colour share a vertex, so threads scatter without races
   * and every vertex sums its contributions in the same order for any
   * thread count. Colour c holds chunks clist[coff[c] .. coff[c+1]). */
  int64_t chunk, nchunk;
  int ncolor;
  int64_t *coff;
  int32_t *clist;
  uint8_t *amask; /* nae or NULL: the active subset */

  double *eps_node; /* nn or NULL */
  double *node_w;   /* nn or NULL: per-node weight factor (0: node left out) */
  double *bern_w;   /* nae or NULL: weight of the hex's Bernstein term */
  double *bern_eps; /* 27 nae or NULL: eps per coefficient (NULL: prm.eps) */
  double bern_scale;

  /* scratch for the fixed-order sum of F */
  double *Fe;   /* nae */
  double *part; /* blocks of VM_PROBLEM_FBLOCK elements */
  int64_t nblock;

  /* F of the elements all of whose vertices are fixed (vflag, when the
   * slots were assigned at the first evaluation), kept for the problem's
   * state `gen` at the vertex positions it was computed at: a minimizer
   * evaluates such an element once per state (its eps changes every
   * iteration) instead of at every trial point. Every setter that can
   * change an element's F calls vm_problem_touch. With skip_fixed
   * (vm_problem_set_fixed_derivatives) their derivatives, which reach only
   * the rows of fixed vertices, are not computed at all. */
  uint64_t gen;
  int fix_built;     /* slots assigned (fix_of NULL then: none, or no memory) */
  int skip_fixed;    /* derivatives of all-fixed elements left out */
  int32_t *fix_of;   /* nae: the element's slot, -1 for none */
  double *fix_x;     /* per slot, 3 VM_MAX_ELEM_VERTS: its vertices' positions */
  double *fix_F;     /* per slot */
  uint64_t *fix_gen; /* per slot: the state fix_F is for, 0 for none */
  /* and their nodes' s and det C (vm_problem_node_dets, _node_stats),
   * which change only with the geometry state `ggen` (targets, rule,
   * metric, normals): 2 per node from fix_noff[slot], sized for the rule
   * fix_sd_rule (-1: not sized; fix_sd NULL then: no memory) */
  uint64_t ggen;
  int64_t nslot;
  int fix_sd_rule;
  int64_t *fix_noff;  /* nslot + 1 */
  double *fix_sd;     /* s, det per node */
  uint64_t *fix_sgen; /* per slot: the geometry state fix_sd is for, 0 for none */

  /* Every node's s and det C (2 per node) as the last vm_problem_node_dets
   * or _node_stats computed them, at the positions nsd_x (nv x 3) and the
   * geometry state nsd_ggen, for the present rule's nsd_n nodes: a
   * minimizer's statistics after a step and the caller's before the next
   * are at the same point, and the second pass reads them here. Only up to
   * VM_PROBLEM_NSD_MAX bytes (none beyond: each pass computes). */
  double *nsd;
  double *nsd_x;
  int64_t nsd_n;
  size_t nsd_nx;     /* nv x 3 when kept */
  uint64_t nsd_ggen; /* 0: nothing kept */
};

/* The most memory the kept node values (nsd) take. */
#define VM_PROBLEM_NSD_MAX (64ll << 20)

/* The kept node values freed (assembly.c). */
void vm_problem_nsd_free(vm_problem *p);

/* The kept values of all-fixed elements freed (assembly.c): no cache. */
void vm_problem_fix_free(vm_problem *p);

/* The problem's state changed (targets, rule, measure, parameters, weights,
 * metric, normals, node eps or weights, Bernstein terms): the cached F of
 * all-fixed elements is stale. */
static inline void vm_problem_touch(vm_problem *p) {
  if (p) p->gen++;
}

/* ... and what the nodes' s and det C depend on changed too (targets,
 * rule, metric, normals). */
static inline void vm_problem_touch_geometry(vm_problem *p) {
  if (!p) return;
  p->gen++;
  p->ggen++;
}

/* Node targets above this many bytes are by default not stored but
 * computed from the element's target coordinates whenever it is evaluated
 * (vm_problem_set_target_store). */
#define VM_PROBLEM_TARGET_STORE (64ll << 20)

/* S (d x d per node) and wb of every node of active element i from its
 * reference or field targets: what compute_targets stores, or what an
 * evaluation computes when they are not stored (the same bits). Returns
 * -1, or the first node whose target is degenerate or inverted (its det T
 * in *fdet; 0 for a 2D element without a normal). */
int vm_problem_elem_targets(const vm_problem *p, int64_t i, double *S, double *wb, double *fdet);

/* Threads for an OpenMP region of this problem (the context's setting,
 * else the OpenMP default). */
static inline int vm_problem_threads(const vm_problem *p) {
  int nt = vm_ctx_threads(p->ctx);
#ifdef _OPENMP
  if (nt <= 0) nt = omp_get_max_threads();
#endif
  return nt > 0 && p->nae >= VM_PROBLEM_MIN_PARALLEL ? nt : 1;
}

#endif
