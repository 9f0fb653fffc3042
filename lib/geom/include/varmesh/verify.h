/* varmesh/verify.h: independent, exact verification of a mesh: the
 * orientation of every quadrature simplex and, for prism layers, that the
 * outer surface neither intersects itself nor crosses the wall. Decided with
 * CGAL's exact predicates; no arithmetic is shared with the solvers. */
#ifndef VARMESH_VERIFY_H
#define VARMESH_VERIFY_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Orientation of every quadrature node of every element of the mesh's top
 * dimension (lower-dimensional elements are skipped), under `rule`
 * (VM_RULE_CORNER or VM_RULE_GEOMETRIC, see quadrature.h). A node is bad
 * when the exact sign of det E (its edge matrix; det C has the same sign) is
 * not positive: inverted or degenerate.
 *  - Nodes whose columns share one tail vertex (tets, corner simplices):
 *    CGAL::orientation of the 4 (3 in 2D) points with
 *    Exact_predicates_inexact_constructions_kernel.
 *  - Compound nodes of the geometric rule (hex 64, prism 12; columns are
 *    parallel edges with different tails): the determinant of the exact
 *    edge differences, by interval arithmetic with an exact rational
 *    fallback (CGAL::Interval_nt, CGAL::Exact_rational).
 *  - 2D elements in a 3D mesh (a surface) have no orientation: a node is bad
 *    when its two edges are exactly parallel (degenerate element).
 * Outputs (each may be NULL): bad_nodes, bad_elems (elements with at least
 * one bad node), first_bad_elem (lowest index of such an element, -1 if
 * none).
 * Returns VM_OK when the check ran (whatever its outcome; read the counts),
 * VM_ERR_ARG (NULL mesh, unknown rule), VM_ERR_NOMEM or VM_ERR_BACKEND
 * (message on m->ctx). */
int vm_verify_orientation(const vm_mesh *m, int rule, int64_t *bad_nodes, int64_t *bad_elems,
                          int64_t *first_bad_elem);

/* The prism layer check. The layer is every VM_PRISM of the mesh (other
 * elements are ignored); a prism's bottom triangle (0,1,2) and top triangle
 * (3,4,5) are on the layer's boundary when no other prism has a bottom or
 * top triangle on the same three vertices. Boundary bottoms are the wall,
 * boundary tops the outer surface (one layer or several stacked).
 * Two triangles intersect when they have a common point other than shared
 * vertices or a shared edge (triangles on the same edge intersect only when
 * coplanar and overlapping; the test mirrors CGAL's PMP::does_self_intersect
 * for triangle soups): candidate pairs from CGAL::box_self_intersection_d,
 * decided with Epick's exact do_intersect / coplanar predicates.
 * Outputs:
 *  intersecting_pairs: pairs of outer triangles that intersect;
 *  wall_crossings: pairs (outer triangle, wall triangle) that intersect;
 *  first_pair: the prisms of the first offending pair (outer-outer pairs
 *    first, then outer-wall; lowest prism indices), {-1, -1} if none.
 * Any output may be NULL. Returns VM_OK when the check ran (read the
 * counts), VM_ERR_ARG, VM_ERR_NOMEM or VM_ERR_BACKEND. */
int vm_verify_prism_layer(const vm_mesh *m, int64_t *intersecting_pairs, int64_t *wall_crossings,
                          int64_t first_pair[2]);

#ifdef __cplusplus
}
#endif
#endif
