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
  int fv_sweeps;       /* sweeps of the finite-volume relief (OpenFOAM's measures of the
                          tets and their faces; fill_fv.c); 0: off (its figures are still
                          measured); default 8 */
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

/* OpenFOAM's checkMesh measures of the fill: over the internal faces with a
 * tet of the fill on a side (a face between two of them once) and over
 * the fill's tets (the determinant, over their internal faces); counts of
 * faces or cells beyond checkMesh's limits. */
typedef struct vm_fill_fv_figures {
  int64_t faces, tets;
  int64_t nonortho_over70; /* non-orthogonality > 70 degrees (a warning in checkMesh) */
  double nonortho_max;     /* degrees */
  int64_t skew_over4;      /* skewness > 4 */
  double skew_max;
  int64_t weight_under; /* interpolation weight < 0.05 */
  double weight_min;
  int64_t volratio_under; /* volume ratio of the two cells < 0.01 */
  double volratio_min;
  int64_t det_under; /* cell determinant < 0.001 */
  double det_min;
} vm_fill_fv_figures;

typedef struct vm_fill_report {
  int64_t layer_cells; /* 3D cells of the input */
  int64_t env_faces;   /* envelope triangles */
  int64_t far_faces;   /* far-field triangles */
  /* a half model (the envelope open, its border in a plane x, y or z =
   * const): the plane (sym_axis 0, 1, 2; -1: a closed envelope) and the
   * triangles that mesh it between the far field and the layer */
  int sym_axis;
  double sym_value;
  int64_t sym_faces;
  int64_t tets;         /* tetrahedra made */
  int64_t new_vertices; /* vertices added (inside and on the far field) */
  int surface_input;    /* the input was a closed surface: it became the wall */
  double model_length, far_distance, far_size, env_size_min, env_size_max;
  int64_t opt_free;                  /* vertices the optimizer moved */
  int64_t flat_env_tets;             /* tets of four envelope vertices with a dihedral angle below
                                        5 degrees (no vertex of theirs may move) */
  vm_fill_tet_quality before, after; /* before and after the optimization */
  vm_fill_fv_figures fv_before, fv_after; /* before and after the finite-volume relief */
  int64_t fv_moved;                       /* vertices the relief moved */
  int64_t fv_flips; /* edge removals and 2-3 flips on tets the relief left failing a check */
  double time_fv;
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

/* The finite-volume relief (vm_fill_run's last step), on any mesh m whose
 * tets e0.. are the ones to judge: the vertices from index `first` on
 * that lie on no boundary face and have only tets around them move where
 * those tets or their faces are near the limits of OpenFOAM's checkMesh
 * (non-orthogonality beyond 60 degrees, skewness beyond 2, weights below
 * 0.1, volume ratios below 0.05, determinants below 0.005); at most
 * `sweeps` sweeps, every tet keeping its orientation. The figures before
 * and after (over e0..'s tets and their internal faces); *moved the
 * vertices moved. */
int vm_fill_fv_relief(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int sweeps,
                      vm_fill_fv_figures *before, vm_fill_fv_figures *after, int64_t *moved);

/* Flips where the relief leaves a tet of e0.. failing one of checkMesh's
 * checks (its determinant below 0.001, or one of its faces beyond 70
 * degrees, skewness 4, weight 0.05 or volume ratio 0.01): edge removal
 * (rings of 3 to 7 tets), 2-3 flips and collapses of its vertices from
 * index `first` on that lie on no boundary face and have only tets
 * around them, each taken only where it leaves fewer failures (or as
 * many with half the penalty) and no measure beyond a limit it was within.
 * The tets e0.. must come before any other element from e0 on; the new
 * ones follow the kept ones and take their element fields from a tet
 * they replace; collapsed vertices are dropped (the later ones renumbered,
 * vertex fields with them); *nflips the operations made. */
int vm_fill_fv_flips(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int64_t *nflips);

/* The tet figures of report's vm_fill_tet_quality for any mesh (the
 * envelope ratio over faces shared by a tet and a non-tet cell). */
int vm_fill_tet_quality_of(vm_ctx *ctx, const vm_mesh *m, vm_fill_tet_quality *q);

#ifdef __cplusplus
}
#endif
#endif
