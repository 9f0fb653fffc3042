/* varmesh/curvature.h: discrete mean curvature of a surface mesh by the
 * finite-volume (dual cell) discretization of the Laplace-Beltrami
 * operator, the filter of Section 6.1, and vertex normals. */
#ifndef VARMESH_CURVATURE_H
#define VARMESH_CURVATURE_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Names of the per-vertex f64 fields written by vm_surface_curvature. */
#define VM_FIELD_MEAN_CURVATURE "mean_curvature"
#define VM_FIELD_MEAN_CURVATURE_FILTERED "mean_curvature_filtered"

/* Sign convention. H is the mean curvature (k1 + k2) / 2 with respect to
 * the orientation normal nu of the elements (right-hand rule, mesh.h):
 * H > 0 where the surface bends away from nu. For a closed, outward
 * oriented surface convex parts have H > 0: a sphere of radius R has
 * H = 1/R, a cylinder of radius r has H = 1/(2r). The Laplace-Beltrami
 * operator of the position is then Delta_B y = -2 H nu; the quantity the
 * paper writes as H in "Delta_B y = nu H" is -2 times this one. */

typedef struct vm_curvature_stats {
  int64_t degenerate; /* triangles with (numerically) zero area, skipped */
  int64_t boundary;   /* boundary / non-manifold vertices (H extrapolated) */
  double min, max;    /* of the raw H */
  double mean_abs;    /* area-weighted mean of |H| */
} vm_curvature_stats;

/* Unit vertex normals (3*nv) of the 2D elements (triangles; quads as their
 * four corner triangles averaged): face normals weighted by the corner
 * angles. A vertex with no non-degenerate incident triangle gets 0.
 * Returns VM_OK, VM_ERR_ARG (no 2D elements) or VM_ERR_NOMEM. */
int vm_surface_normals(const vm_mesh *m, double *normals);

/* Mean curvature H (nv values) at every vertex, from the cotangent
 * (finite-volume) Laplace-Beltrami operator on mixed Voronoi dual cells
 * (Meyer et al.): with A_i the mixed area of vertex i (Voronoi part of
 * each non-obtuse triangle; 1/2 or 1/4 of an obtuse one),
 *   Delta_B y(i) = 1/(2 A_i) sum_j (cot a_ij + cot b_ij) (y_j - y_i),
 *   H_i = -Delta_B y(i) . n_i / 2,
 * n_i the angle-weighted normal. Boundary and non-manifold vertices
 * (edges with other than two incident elements), whose dual cells are not
 * closed, get the mean H of their interior edge neighbours (0 if none).
 * Quads count as their four corner triangles with weight 1/2. Volume
 * elements are ignored. Optional outputs (may be NULL): normals (3*nv,
 * as vm_surface_normals), area (nv, A_i), st.
 * Returns VM_OK, VM_ERR_ARG (no 2D elements), VM_ERR_NOMEM. */
int vm_surface_mean_curvature(const vm_mesh *m, double *H, double *normals, double *area,
                              vm_curvature_stats *st);

/* The filter of Section 6.1 for a noisy curvature field, applied in this
 * order: |H| above `cap` becomes cap (sign kept); then `smooth` passes of
 * area-weighted averaging over each vertex's closed one-ring (vertex and
 * its edge neighbours); then |H| below `threshold` becomes 0. threshold 0
 * and cap 0 (or +inf) switch those parts off. */
typedef struct vm_curvature_filter {
  double threshold;
  double cap;
  int smooth;
} vm_curvature_filter;

/* All parts off. */
vm_curvature_filter vm_curvature_filter_default(void);

/* Filter H (nv values) in place. Returns VM_OK, VM_ERR_ARG (negative
 * threshold or cap, negative passes, NaN), VM_ERR_NOMEM. */
int vm_curvature_filter_apply(const vm_mesh *m, const vm_curvature_filter *f, double *H);

/* Compute H and store the per-vertex f64 fields VM_FIELD_MEAN_CURVATURE
 * (raw) and VM_FIELD_MEAN_CURVATURE_FILTERED (filtered with f; NULL: no
 * filter) on m, replacing existing ones. st may be NULL. */
int vm_surface_curvature(vm_mesh *m, const vm_curvature_filter *f, vm_curvature_stats *st);

#ifdef __cplusplus
}
#endif
#endif
