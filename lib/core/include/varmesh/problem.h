/* varmesh/problem.h: the discrete functional (13)/(20) on a mesh: measure,
 * quadrature rule, targets (G_xi), metric (G_x), weights (12), and the
 * assembly of F, its gradient and Hessian blocks over all quadrature nodes. */
#ifndef VARMESH_PROBLEM_H
#define VARMESH_PROBLEM_H

#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/measure.h"
#include "varmesh/mesh.h"
#include "varmesh/quadrature.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_problem vm_problem;

/* Create a problem on mesh m (not copied: m must outlive the problem; its
 * connectivity must not change, its coordinates are the unknowns).
 * The active elements are those of the highest topological dimension in
 * the mesh (lower-dimensional elements, e.g. boundary triangles of a tet
 * mesh, are ignored by the functional). Defaults: balanced measure,
 * theta 0.8, corner rule, ideal targets of automatic size, identity
 * metric, unit weights.
 * 2D elements: if m->dim == 2 they are measured in the xy plane; if
 * m->dim == 3 (surfaces) each element is measured in its own tangent frame
 * with a reference unit normal n_e (see vm_problem_update_normals):
 *   det = n_e . (e1 x e2) / det T,  s = |E T^{-1}|_F^2. */
int vm_problem_create(vm_ctx *ctx, vm_mesh *m, vm_problem **out);
void vm_problem_destroy(vm_problem **p);

int vm_problem_set_measure(vm_problem *p, vm_measure_kind kind, const vm_measure_params *prm);
/* Change only the parameters (eps, t, theta) during continuation. */
int vm_problem_set_params(vm_problem *p, const vm_measure_params *prm);
const vm_measure_params *vm_problem_params(const vm_problem *p);
int vm_problem_set_rule(vm_problem *p, vm_rule rule);

/* Targets: T of each node from the ideal element (vm_elem_ideal) scaled to
 * edge length `size` (size <= 0: chosen so the total target volume equals
 * the mesh's total |volume|); from reference vertex coordinates xyz_ref
 * (3*nv, copied; e.g. the untangled Cartesian mesh); or from a per-element
 * f64 field of nverts*3 components holding the target element's vertex
 * coordinates (copied). Each fails with VM_ERR_ARG if a target is
 * degenerate or inverted. For 2D elements in 3D, T of each node is taken in
 * that node's own plane (T^T T is the Gram matrix of its target edges),
 * oriented by the target element's normal. */
int vm_problem_set_target_ideal(vm_problem *p, double size);
int vm_problem_set_target_reference(vm_problem *p, const double *xyz_ref);
int vm_problem_set_target_field(vm_problem *p, const char *field_name);
/* Reference and field targets: T^{-1} and det T of every quadrature node
 * are kept in memory ((d^2 + 1) doubles a node: 960 bytes a prism under
 * the corner rule, 4.6 KB a hex under the geometric one) while they take
 * at most max_bytes (default 64 MiB), else computed from the element's
 * target coordinates whenever it is evaluated: less memory, a little more
 * time, the same results bit for bit. */
int vm_problem_set_target_store(vm_problem *p, int64_t max_bytes);

/* Metric G_x of (13)/(20): NULL for identity; else per-vertex values
 * averaged over each element's vertices: scalar g > 0 (G_x = g I, used by
 * the surface stage with g = 1 + c|H|), or a symmetric positive definite
 * tensor (6 per vertex: xx yy zz xy yz xz). Copied. */
int vm_problem_set_metric_scalar(vm_problem *p, const double *g);
int vm_problem_set_metric_tensor(vm_problem *p, const double *G);
/* Weights w of (12), one per element (NULL: all 1). Copied. */
int vm_problem_set_weights(vm_problem *p, const double *w);
/* Reference normals of 2D elements in 3D: from unit vertex normals
 * (3*nv, averaged per element) or, with NULL, from the current geometry. */
int vm_problem_update_normals(vm_problem *p, const double *vertex_normals);

/* Sizes. */
int64_t vm_problem_num_nodes(const vm_problem *p); /* quadrature nodes */
int vm_problem_dim(const vm_problem *p);           /* 2 or 3 */
const vm_mesh *vm_problem_mesh(const vm_problem *p);
/* Sum of w beta kappa det T over all nodes: the value of F where W = 1
 * everywhere (the total target volume, or area, for unit weights). */
double vm_problem_target_volume(const vm_problem *p);
/* Edge length of the ideal targets in use (the automatic size after
 * vm_problem_set_target_ideal(p, 0)); 0 for other targets. */
double vm_problem_target_size(const vm_problem *p);

/* Assembly at coordinates x (3*nv; pass m->xyz for the mesh's own).
 * What is computed is chosen by the non-NULL outputs:
 *   F       the functional (sum of w beta kappa det T W over all nodes);
 *   grad    3*nv, dF/dx;
 *   hdiag   9*nv, the 3x3 diagonal blocks H_vv, row-major;
 *   hoff    the off-diagonal blocks' diagonal entries (H_uv)_mm, m = 0..2,
 *           3 per entry of the vertex graph (vm_problem_graph), u != v.
 * Results are identical bit for bit for any number of threads. Not
 * reentrant on one problem (it keeps scratch space). The first call with
 * hoff builds a table of hoff positions (VM_ERR_NOMEM if that fails).
 * For plane meshes (dim 2) the z rows and columns are zero.
 * Returns 0 when every node is inside the measure's domain; otherwise
 * VM_WARN_INVERTED with *F = +INFINITY (gradients undefined). */
typedef struct vm_eval {
  double *F;
  double *grad;
  double *hdiag;
  double *hoff;
} vm_eval;
int vm_problem_eval(vm_problem *p, const double *x, vm_eval *out);

/* Newton's method: F, the gradient and the full Hessian in 3x3 blocks.
 *   F, grad  as vm_eval;
 *   hdiag    9*nv, the diagonal blocks H_vv (row-major);
 *   hblk     9 per entry of the vertex graph (vm_problem_graph), u != v:
 *            the full block H_uv (row-major, rows: u's coordinates) at the
 *            position of v in u's row, so H_vu = H_uv^T.
 * With psd != 0 the Hessian of W with respect to C at every node is first
 * projected to positive semidefinite (its negative eigenvalues set to 0,
 * see vm_measure_hessian_psd), so the assembled H is positive semidefinite;
 * where nothing is clamped it is the exact Hessian. Outputs may be NULL.
 * Same determinism, return values and scratch use as vm_problem_eval. */
typedef struct vm_eval_blocks {
  double *F;
  double *grad;
  double *hdiag;
  double *hblk;
  int psd;
} vm_eval_blocks;
int vm_problem_eval_blocks(vm_problem *p, const double *x, vm_eval_blocks *out);

/* Which entries of the vertex graph can carry a nonzero Hessian block for
 * the current rule: mask[k] = 1 if some node couples the two vertices
 * (e.g. not the body diagonals of hexahedra under the corner rule), else
 * 0; rowptr[nv] values. */
int vm_problem_graph_coupled(const vm_problem *p, uint8_t *mask);

/* The Hessian d2W/dC2 of one d x d Jacobian C (d = 2, 3; W, G, H as in
 * vm_measure_eval) projected to positive semidefinite: in 3D through the
 * analytic eigensystem of isotropic energies f(tr C^T C, det C) (twists,
 * flips and the 3x3 scaling block at the signed SVD of C), in 2D by a dense
 * eigen-decomposition; negative eigenvalues are set to 0. *nclamped (may be
 * NULL) gets their number. Returns as vm_measure_eval. */
int vm_measure_hessian_psd(const vm_measure_ops *ops, const vm_measure_params *prm, int d,
                           const double *C, double *W, double *G, double *H, int *nclamped);

/* F only, stopping early at the first node outside the domain (for line
 * searches). Same value as vm_problem_eval's F. */
int vm_problem_value(vm_problem *p, const double *x, double *F);
/* Each element's share of F at x: fe[e] for every element e of the mesh
 * (+INFINITY where it is outside the measure's domain, 0 where it is not
 * active). Their sum is F up to the order of the additions. */
int vm_problem_elem_values(vm_problem *p, const double *x, double *fe);

/* The symmetric vertex graph in CSR form without the diagonal: neighbours
 * of v are adj[rowptr[v] .. rowptr[v+1]), sorted; two vertices are
 * neighbours if they share an active element. */
void vm_problem_graph(const vm_problem *p, const int64_t **rowptr, const int32_t **adj);

/* Statistics over all quadrature nodes at x: the number of nodes with
 * det C <= 0 (M of Table 1), the minimum det C, phi_min = min det/(s/d)^{d/2}
 * and psi_min = min 2 det/(1 + det^2). Any output may be NULL. */
typedef struct vm_node_stats {
  int64_t inverted;
  double min_det;
  double phi_min;
  double psi_min;
} vm_node_stats;
int vm_problem_node_stats(vm_problem *p, const double *x, vm_node_stats *st);

/* det C of every node at x (num_nodes values; node order: element by
 * element, rule order). Used by untangling (35), (39) and local subdomains. */
int vm_problem_node_dets(vm_problem *p, const double *x, double *det);
/* Element of each node (num_nodes values), for mapping nodes to elements. */
const int32_t *vm_problem_node_elements(const vm_problem *p);

/* Restrict assembly to a subset of active elements (mask[e] != 0 over all
 * mesh elements; NULL restores all): local untangling of a subdomain.
 * The graph is unchanged; vertices outside the subset get zero rows. */
int vm_problem_set_active(vm_problem *p, const uint8_t *mask);

/* Whether vm_problem_eval and vm_problem_eval_blocks compute the
 * derivatives of the elements all of whose vertices are fixed (the mesh's
 * vflag VM_VERTEX_FIXED): want != 0, the default, gives complete gradient
 * and Hessian rows; want = 0 leaves those elements' derivatives out (they
 * reach only the rows of fixed vertices, which the minimizers discard).
 * F is the same bits either way. vm_minimizer_run sets 0 for its run and
 * 1 when it ends. (Such elements' F, and their nodes' determinants, are
 * computed once per state of the problem and kept while their vertices
 * stay where they were, either way.) */
int vm_problem_set_fixed_derivatives(vm_problem *p, int want);

/* Per-node epsilon for the one-way penalty variant: if eps_node != NULL
 * (num_nodes values, copied), node q uses eps_node[q] instead of params.eps. */
int vm_problem_set_node_eps(vm_problem *p, const double *eps_node);

/* Per-node weight factors: if w_node != NULL (num_nodes values >= 0,
 * copied), node q contributes w_node[q] times its term to F and its
 * derivatives; a node of weight 0 is left out altogether (not evaluated,
 * so it may lie outside the measure's domain, and not counted by
 * vm_problem_node_stats). NULL restores 1 for every node; changing the rule
 * resets it. Used by the certifying repair (only uncertified cells'
 * nodes penalized, the others guarded or left out). */
int vm_problem_set_node_weights(vm_problem *p, const double *w_node);

/* A Bernstein term on hexahedra: with w_elem != NULL (one value >= 0 per
 * mesh element, copied), F gains for every active hex e with w_elem[e] > 0
 *   w_e w_elem[e] sum_{c < 27} 1 / chi_eps(scale b_c),
 * w_e the element's weight times the mean weight of its rule's nodes
 * b_c the Bernstein coefficients of its det J (vm_hex_bernstein), chi_eps
 * the regularized determinant of (14) with eps = eps_coef[27 e + c] (> 0;
 * NULL: params.eps): a penalty that drives a coefficient positive, or with
 * a tiny eps a wall that keeps it there; all 27 positive certify the cell.
 * The Hessian blocks are the Gauss-Newton part (1/chi)'' grad b grad b^T,
 * positive semidefinite, on the pairs of vertices the rule couples. scale
 * makes b relative to the target (1 / h^3 for ideal hexes of edge h).
 * NULL turns the term off; it survives a change of rule. */
int vm_problem_set_bernstein(vm_problem *p, const double *w_elem, const double *eps_coef,
                             double scale);

#ifdef __cplusplus
}
#endif
#endif
