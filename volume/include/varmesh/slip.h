/* varmesh/slip.h: slip boundary conditions for the volume stage: the
 * boundary vertices of a volume mesh slide on the mesh's own initial
 * boundary surface; vertices on its sharp edges (dihedral angle above a
 * threshold) slide along those edges, its corners stay fixed. */
#ifndef VARMESH_SLIP_H
#define VARMESH_SLIP_H

#include <stdint.h>

#include "varmesh/boundary.h"
#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_volume_slip vm_volume_slip;

/* Degrees: a sharp edge or a feature line's turn of this much or more
 * between vertices of tangled elements is a fold of the boundary. */
#define VM_SLIP_FOLD_DEG 150.0

typedef struct vm_volume_slip_info {
  int64_t nboundary;   /* boundary vertices */
  int64_t nsurface;    /* of them sliding on the surface */
  int64_t nline;       /* sliding along a feature line */
  int64_t ncorner;     /* fixed as corners of the features */
  int64_t nkept_fixed; /* already fixed (flag or 'fixed' field): left fixed */
  int32_t lines;       /* feature lines */
  int32_t patches;     /* surface patches bounded by the feature lines */
  int64_t fold_edges;  /* sharp edges and line turns left out as folds of tangled
                          boundary elements */
} vm_volume_slip_info;

/* Make every boundary vertex of the volume mesh m that is not FIXED a SLIP
 * vertex on m's current boundary surface (the reference, copied here):
 * m->vflag / m->vsurf are overwritten for those vertices (corners become
 * FIXED; vsurf 0..patches-1: the patch, bounded by feature lines, a vertex
 * slides on without crossing them; patches + k - 1: feature line k). Feature edges:
 * dihedral angle >= feature_deg (in (0, 180]); a feature line turning by
 * more than corner_deg at a vertex makes it a corner. The returned object
 * Where boundary elements are tangled, sharp edges of nearly 180 degrees
 * (VM_SLIP_FOLD_DEG or more) between their vertices, and feature lines
 * turning back as much there, are the boundary's folds, not its shape, and
 * are not features (info->fold_edges). The returned object
 * supplies the projector (vm_volume_slip_ops) for vm_volume_run and must
 * outlive it. info may be NULL. Returns VM_OK, VM_ERR_ARG (no volume
 * elements, bad angles, non-manifold boundary), VM_ERR_NOMEM,
 * VM_ERR_BACKEND. */
int vm_volume_slip_create(vm_ctx *ctx, vm_mesh *m, double feature_deg, double corner_deg,
                          vm_volume_slip **out, vm_volume_slip_info *info);
vm_surface_ops vm_volume_slip_ops(vm_volume_slip *s);
/* Largest distance from a boundary vertex of m to the reference surface
 * (how far the slip vertices left it; 0 up to rounding after a run). */
int vm_volume_slip_distance(vm_volume_slip *s, const vm_mesh *m, double *maxdist);
void vm_volume_slip_destroy(vm_volume_slip **p);

/* The shape of a volume mesh: its boundary surface, recorded before a run
 * whose boundary may move (free or sliding), to say afterwards how far the
 * shape moved. */
typedef struct vm_volume_shape vm_volume_shape;

/* Record m's boundary surface (triangles and quads, quads split in two for
 * the distances). Returns VM_OK, VM_ERR_ARG (no boundary faces, a
 * non-manifold boundary), VM_ERR_NOMEM, VM_ERR_BACKEND. */
int vm_volume_shape_create(vm_ctx *ctx, const vm_mesh *m, vm_volume_shape **out);

/* How far the boundary of m (the recorded mesh's connectivity, vertices
 * moved) lies from the recorded surface: the two-sided Hausdorff distance,
 * sampled on both surfaces (vertices, edge points and a grid of spacing
 * 1/200 of the recorded diagonal on every face) in *dist, the sample where
 * it was found in at[3], the recorded surface's bounding-box diagonal in
 * *diag. Any output may be NULL. Deterministic. */
int vm_volume_shape_deviation(vm_volume_shape *s, const vm_mesh *m, double *dist, double *diag,
                              double at[3]);
/* Fixed vertices of m (m->vflag, not on the recorded boundary) that lie
 * outside the recorded closed surface, farther from it than rounding: while
 * the boundary stays on that surface (fixed or sliding), no motion of the
 * other vertices can give a valid mesh. Their number in *count, the first
 * in *first (-1 if none). */
int vm_volume_shape_fixed_outside(vm_volume_shape *s, const vm_mesh *m, int64_t *count,
                                  int64_t *first);
void vm_volume_shape_destroy(vm_volume_shape **p);

#ifdef __cplusplus
}
#endif
#endif
