/* varmesh/graded.h: graded isotropic remeshing of a triangle surface, in
 * plain C: a size field from the input's own local edge lengths (bounded
 * by its curvature, smoothed to a growth rate), then rounds of edge
 * splits, edge collapses, angle-improving flips and weighted tangential
 * smoothing with every vertex projected back onto the input surface (its
 * feature lines for feature vertices). Corners and cone points stay bit
 * for bit; feature lines keep their shape (their vertices slide on them);
 * every operation is refused where it would turn a triangle over. */
#ifndef VARMESH_GRADED_H
#define VARMESH_GRADED_H

#include <stdint.h>

#include "varmesh/features.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where the sizes come from. */
enum {
  VM_GRADED_INPUT = 0,    /* the input's own: the mean length of each vertex's edges,
                             bounded by max_turn / curvature */
  VM_GRADED_CURVATURE = 1 /* the surface's curvature k: h ~ 1 / sqrt(k) (one chord
                             error everywhere), at most max_size */
};

typedef struct vm_graded_opts {
  int sizing;         /* VM_GRADED_INPUT (default) or VM_GRADED_CURVATURE */
  int64_t triangles;  /* > 0: the sizes scaled so that about this many triangles result;
                         0 (default): the sizes as they are (INPUT), about the input's
                         number of triangles (CURVATURE) */
  double growth;      /* the size field grows by at most this much per unit length:
                         h(a) <= h(b) + growth |ab| (default 0.25) */
  double max_turn;    /* INPUT: no size along which the surface's normal turns by more than
                         this many degrees (default 30) */
  double max_size;    /* no size above this fraction of the bounding-box diagonal, with
                         CURVATURE or a count (default 0.05) */
  int iterations;     /* collapse / split / flip / smooth rounds (default 12; a
                         long edge is halved once per round) */
  double smooth_keep; /* a smoothing move is kept only if its triangles' smallest angle
                         stays at least min(before, smooth_keep) degrees (default 30) */
} vm_graded_opts;

vm_graded_opts vm_graded_opts_default(void);

typedef struct vm_graded_report {
  int64_t nv_in, nf_in, nv, nf;
  int64_t splits, collapses, flips, moves;
  double min_angle_in, min_angle;           /* smallest angle, degrees */
  double min_angle_free_in, min_angle_free; /* away from feature corners */
  double h_min, h_max;                      /* the size field's range */
} vm_graded_report;

/* Remesh the closed or open manifold, consistently oriented triangle mesh
 * m in place to the size field of its own edges (see the file comment).
 * f: the features of m (not NULL; cone points marked as corners by the
 * caller if wanted); on return the features of the new mesh. The input's
 * corner vertices keep their coordinates bit for bit; every other vertex
 * lies on the input surface (on its feature line for line vertices), up to
 * the closest-point projection's rounding. Vertex fields, flags and surface
 * ids follow the vertices that stay, new vertices get zeros; element fields
 * are dropped (a warning says so). Deterministic. Returns VM_OK,
 * VM_ERR_ARG (not a triangle mesh, features of another mesh, a
 * non-manifold vertex), VM_ERR_NOMEM, VM_ERR_INTERRUPTED, VM_ERR_BACKEND. */
int vm_surface_remesh_graded(vm_mesh *m, vm_surface_features *f, const vm_graded_opts *o,
                             vm_graded_report *r);

#ifdef __cplusplus
}
#endif
#endif
