/* varmesh/jacobian.h: certified validity of cells in the solver's sense:
 * the Jacobian determinant of the element's map from its reference cell is
 * positive everywhere in the cell, decided from its Bernstein coefficients
 * (not sampled at a few points). */
#ifndef VARMESH_JACOBIAN_H
#define VARMESH_JACOBIAN_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_JAC_INVALID = 0,  /* det J <= 0 somewhere in the cell (certified) */
  VM_JAC_VALID = 1,    /* det J > 0 everywhere in the cell (certified) */
  VM_JAC_UNDECIDED = 2 /* neither could be shown within the subdivision budget
                          or the rounding tolerance: det J comes within
                          rounding of 0 (a flat or nearly flat cell); counts
                          as not valid */
} vm_jac_verdict;

/* The verdict on one cell of type `type` (VM_TRI, VM_QUAD in the plane,
 * VM_TET, VM_PYRAMID, VM_PRISM, VM_HEX) with vertex coordinates xyz (3 per
 * vertex, in the element's vertex order; 2D elements use x and y only).
 *  - triangle, tet: the map is affine; det J is one number.
 *  - quad: the bilinear map's det J is bilinear in (u, v): its 4 Bernstein
 *    coefficients are the corner values.
 *  - hex: the trilinear map's det J is triquadratic: its 27 Bernstein
 *    coefficients (tensor degree (2,2,2)) bound it. All above the rounding
 *    tolerance: valid; a value at a corner of the cell or of a sub-cell
 *    below minus the tolerance: invalid; else the cell is split in 8 by de
 *    Casteljau's algorithm and each part decided, up to `max_depth` levels
 *    (<= 0: the default, 6) and a budget of 4096 parts per cell.
 *  - prism: x = sum_i lambda_i(u,v) ((1-w) P_i + w P_i+3); det J is linear
 *    in (u, v) on the triangle and quadratic in w, so it is positive
 *    everywhere iff the three quadratics at the triangle's corners are
 *    positive on [0, 1]; decided in closed form from their Bernstein
 *    coefficients (b0, b2 > 0 and, if b1 < 0, b1^2 < b0 b2).
 *  - pyramid: the map of a hexahedron whose top face is collapsed to the
 *    apex A, x = (1-w) Q(u,v) + w A with Q the bilinear base; det J =
 *    (1-w)^2 q(u,v), q = (Q_u x Q_v) . (A - Q) biquadratic (9 Bernstein
 *    coefficients, subdivided like the hex). The factor (1-w)^2 vanishes
 *    only at the apex, which every pyramid map shares; the verdict is q's.
 * The rounding tolerance is a bound on the error of each coefficient:
 * 64 units in the last place of the sum of the magnitudes of its terms,
 * growing with the subdivision level. min_bound (may be NULL) receives the
 * smallest Bernstein coefficient of the last level examined divided by the
 * cube (in 2D the square) of the cell's longest edge: a lower bound of the
 * scaled det J where the cell is valid. Other element types:
 * VM_JAC_VALID. */
vm_jac_verdict vm_jacobian_certify(int type, const double *xyz, int max_depth, double *min_bound);

/* The 27 Bernstein coefficients of det J of the trilinear hexahedron with
 * vertices xyz (8 x 3, the mesh's hex order): det J(u,v,w) = sum over
 * I,J,K in {0,1,2} of b[9 I + 3 J + K] B_I(u) B_J(v) B_K(w), B the
 * quadratic Bernstein basis. b is the mean of the determinants of the
 * geometric rule's compound simplices (24) that fall on it (1, 2, 4 or 8
 * of them), so it is cubic in the coordinates; grad (may be NULL)
 * receives d b[c] / d xyz[a][r] at grad[24 c + 3 a + r]. The corner
 * coefficients are the corner tets' determinants; all 27 positive imply
 * det J > 0 in the whole cell. */
void vm_hex_bernstein(const double *xyz, double b[27], double *grad);

/* Counts over the cells of a mesh (elements of its top dimension: volume
 * elements in a mesh that has any, else the 2D elements of a planar mesh;
 * the triangles and quads of a 3D surface mesh have no orientation and are
 * not counted). */
typedef struct vm_jac_report {
  int64_t cells;
  int64_t invalid;   /* certified det J <= 0 somewhere */
  int64_t undecided; /* not certified either way (not valid) */
  int64_t first_bad; /* lowest element index that is not valid, -1 if none */
} vm_jac_report;

/* Certify every cell of m (in parallel; the counts do not depend on the
 * thread count). verdict (m->ne bytes, may be NULL) receives each element's
 * vm_jac_verdict (VM_JAC_VALID for elements that are not cells). Returns
 * VM_OK when the check ran, VM_ERR_ARG for a NULL mesh or report. The mesh
 * is valid when invalid + undecided == 0. */
int vm_mesh_jacobian_certify(const vm_mesh *m, vm_jac_report *rep, uint8_t *verdict);

/* The least shape quality phi = det C / (tr C^T C / 3)^{3/2} and the
 * least volume quality psi = 2 det C / (1 + det C^2) of the paper's Table 1
 * over the whole of every hexahedron (C = grad x / h, x the trilinear map
 * of the reference cube [0, 1]^3, h the target cube's edge), not at a rule's
 * nodes. Each is bracketed: lo <= the least value <= hi, where hi is a value
 * attained at a point of a cell and lo a bound certified (to rounding) by
 * the Bernstein coefficients of det J on sub-cells (their least, over the
 * largest squared edge lengths for phi's denominator: the derivative along
 * an axis is a convex combination of the sub-cell's edge vectors on that
 * axis). Sub-cells are split in 8 while their bound is below the least
 * value found less `rel` times its magnitude (rel <= 0: 0.01), at most
 * `max_depth` levels (<= 0: 8). phi is scale-free; h <= 0 leaves psi
 * NAN. Cells that are not hexahedra are not measured; a mesh without
 * hexahedra gives NAN. */
typedef struct vm_hex_bounds {
  int64_t hexes;   /* hexahedra measured */
  int64_t refined; /* of those, cells subdivided to tighten lo */
  int64_t parts;   /* sub-cells examined in all */
  double phi_lo, phi_hi;
  double psi_lo, psi_hi;
} vm_hex_bounds;

int vm_mesh_hex_bounds(const vm_mesh *m, double h, double rel, int max_depth, vm_hex_bounds *out);

#ifdef __cplusplus
}
#endif
#endif
