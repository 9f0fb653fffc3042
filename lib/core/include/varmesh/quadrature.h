/* varmesh/quadrature.h: quadrature "simplices" of each element type: the
 * corner rules and the geometric rules of Theorem 3.1 / (24). */
#ifndef VARMESH_QUADRATURE_H
#define VARMESH_QUADRATURE_H

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_RULE_CORNER = 0,         /* corner simplices: tri/tet itself, quad 4 triangles,
                                 hex 8 tets, prism 6 tets, pyramid 4 base-corner tets */
  VM_RULE_GEOMETRIC = 1,      /* (24): hex 64 compound matrices, prism 12; other
                                 types use their corner rule, which is geometric */
  VM_RULE_SPLIT = 2,          /* hex: the 6 Kuhn tets around the 0-6 diagonal (the
                                 mesh's 6-tet split); other types their corner rule.
                                 For untangling only: no quality meaning of its own */
  VM_RULE_CORNER_SPLIT = 3,   /* hex: the 8 corner tets, then the 6 Kuhn
                                 tets (nodes 8..13); other types corner */
  VM_RULE_GEOMETRIC_SPLIT = 4 /* hex: the 64 nodes of (24), then the 6 Kuhn
                                 tets (nodes 64..69); prism its geometric
                                 rule; other types corner */
} vm_rule;

/* One quadrature node: a d x d "compound" edge matrix whose column k is
 * x[head[k]] - x[tail[k]] (local vertex indices of the element), weight beta.
 * For every rule sum(beta) = 1. The node's contribution to (13) is
 *   w * beta * kappa * det(T) * W(Q E T^{-1}),
 * E the node's edge matrix in the mesh, T the same edge matrix of the target
 * element, kappa the rule's volume factor: sum_q beta_q kappa det T_q is the
 * volume of the target element (exactly for the geometric rules; exactly for
 * the corner rules on the ideal elements). */
typedef struct vm_qnode {
  signed char head[3];
  signed char tail[3];
  double beta;
} vm_qnode;

/* The most nodes of any rule (hex, VM_RULE_GEOMETRIC_SPLIT). */
enum { VM_QRULE_MAX_NODES = 70 };

typedef struct vm_qrule {
  int type; /* element type */
  int rule; /* the rule actually used (VM_RULE_CORNER or _GEOMETRIC) */
  int dim;  /* 2 or 3: columns per node */
  int nnodes;
  double kappa; /* 1/2 tri, 1 quad, 1/6 tet, 1/3 pyramid, 1/2 prism, 1 hex */
  const vm_qnode *nodes;
} vm_qrule;

/* The rule for an element type; NULL for an unknown type or rule. */
const vm_qrule *vm_qrule_get(int type, int rule);

/* Vertices of the ideal element with unit edge length (equilateral
 * triangle, square, regular tet, pyramid with all edges 1, prism with
 * equilateral base and unit height, unit cube), in VTK order, positively
 * oriented. ref[i*3 + k]. */
void vm_elem_ideal(int type, double ref[VM_MAX_ELEM_VERTS * 3]);

/* The node's edge matrix from element vertex coordinates `x` (x[i*3+k] for
 * local vertex i), d x d row-major: E[r*d + k] = x[head[k]][r] - x[tail[k]][r]
 * (2D elements use r = 0, 1 of a frame chosen by the caller). */
void vm_qnode_edges(const vm_qnode *q, int d, const double *x, double *E);

#ifdef __cplusplus
}
#endif
#endif
