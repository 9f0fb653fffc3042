/* varmesh/fill.h: the fill stage: tetrahedra between a boundary layer's
 * outer surface (the envelope) and a far-field boundary, by Gmsh's 3D
 * Delaunay mesher through its C API, in memory. The envelope's triangles
 * are kept exactly (same vertices, bit-identical coordinates), so the
 * merged mesh is conformal by construction; then the variational optimizer
 * improves the tetrahedra next to the layer (the layer fixed). */
#ifndef VARMESH_FILL_H
#define VARMESH_FILL_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { VM_FAR_BOX = 0, VM_FAR_SPHERE = 1 } vm_far_shape;

typedef struct vm_fill_opts {
  double farfield;     /* far-field distance from the model's centre, in model
                          lengths (the wall's largest bounding-box extent); 20 */
  vm_far_shape shape;  /* box (default: a cube of half-width farfield) or sphere */
  double growth;       /* bound on the size growth per unit distance: the size at x
                          is min over envelope vertices v of h_v + (growth - 1)|x - v|,
                          h_v the mean edge length at v; default 1.2 */
  double far_size;     /* largest tet size (also the far field's triangle size);
                          <= 0: as the growth bound gives at the far field */
  double refine_lo[3]; /* a refinement box (a wake, a region of interest): */
  double refine_hi[3]; /* inside it the size is at most refine_size */
  double refine_size;  /* <= 0: no refinement box */
  int opt_iter;        /* optimization iterations of the tets next to the layer
                          (shape measure, the layer and the far field fixed); 0: off;
                          default 30 */
  int opt_rings;       /* vertex rings from the envelope that move (default 3) */
  int algorithm;       /* Gmsh's Mesh.Algorithm3D: 1 Delaunay (default), 10 HXT */
  int threads;         /* Gmsh's General.NumThreads (0: the context's) */
} vm_fill_opts;

vm_fill_opts vm_fill_opts_default(void);

/* Figures of the tetrahedra (the prisms are not measured). */
typedef struct vm_fill_tet_quality {
  double min_dihedral;   /* degrees */
  double max_dihedral;   /* degrees */
  double sj_min;         /* min scaled Jacobian (1 for the regular tet) */
  double vol_ratio_env;  /* max over envelope faces of the larger over the smaller
                            volume of the two cells sharing it (layer cell, tet);
                            0 without a layer */
  double vol_ratio_tets; /* the same over faces shared by two tets */
  int64_t inverted;      /* tets with volume <= 0 */
} vm_fill_tet_quality;

typedef struct vm_fill_report {
  int64_t layer_cells;  /* 3D cells of the input */
  int64_t env_faces;    /* envelope triangles */
  int64_t far_faces;    /* far-field triangles */
  int64_t tets;         /* tetrahedra made */
  int64_t new_vertices; /* vertices added (inside and on the far field) */
  int surface_input;    /* the input was a closed surface: it became the wall */
  double model_length, far_distance, far_size, env_size_min, env_size_max;
  int64_t opt_free;                  /* vertices the optimizer moved */
  int64_t flat_env_tets;             /* tets of four envelope vertices with a dihedral angle below
                                        5 degrees (no vertex of theirs may move) */
  vm_fill_tet_quality before, after; /* before and after the optimization */
  double time_mesh, time_opt, time_total; /* seconds */
} vm_fill_report;

/* Fill the region between the envelope of `in` and a far-field boundary.
 * `in` is either a boundary-layer mesh (3D cells; the envelope is its faces
 * named "outer" by "gmsh:physical", else the outermost component of its
 * boundary) or a closed triangulated surface (it becomes the wall).
 * *out receives the merged mesh: the input's vertices first (unchanged,
 * same indices), then the new ones; the input's elements in order except
 * the envelope faces (now interior), then the tetrahedra, then the far-field
 * triangles named "farfield" ("gmsh:physical"). Fields pass through (new
 * items 0, -1 for int element fields other than "gmsh:physical").
 * Errors (one line): no envelope or one with quadrilaterals, a far field
 * that cuts the layer, Gmsh failing or not keeping the envelope. Gmsh's own
 * messages go to the context's log (VM_LOG_DEBUG), never to stdout. */
int vm_fill_run(vm_ctx *ctx, const vm_mesh *in, const vm_fill_opts *opts, vm_mesh **out,
                vm_fill_report *report);

/* The tet figures of report's vm_fill_tet_quality for any mesh (the
 * envelope ratio over faces shared by a tet and a non-tet cell). */
int vm_fill_tet_quality_of(vm_ctx *ctx, const vm_mesh *m, vm_fill_tet_quality *q);

#ifdef __cplusplus
}
#endif
#endif
