/* varmesh/quality.h: mesh quality figures of the paper's Table 1 (M,
 * phi_min, psi_min) and the scaled Jacobian, per element type and overall. */
#ifndef VARMESH_QUALITY_H
#define VARMESH_QUALITY_H

#include <stdint.h>

#include "varmesh/mesh.h"
#include "varmesh/quadrature.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_quality_opts {
  int rule;           /* VM_RULE_CORNER (default) or VM_RULE_GEOMETRIC */
  double target_size; /* > 0: edge length of the ideal target element, for
                         psi = 2 det C/(1 + det C^2); <= 0: use an element
                         f64 field "target_size" if present, else no psi */
} vm_quality_opts;

#define VM_QUALITY_NBINS 20 /* scaled-Jacobian histogram over [-1, 1] */

typedef struct vm_type_quality {
  int64_t count;          /* elements of this type */
  int64_t nodes;          /* quadrature nodes measured */
  int64_t inverted_nodes; /* nodes with det C <= 0 */
  int64_t inverted_elems; /* elements with at least one such node */
  double phi_min;         /* min det C/(tr C^T C/d)^{d/2} */
  double psi_min;         /* min 2 det C/(1 + det C^2), NAN without a target size */
  double sj_min;          /* min scaled Jacobian */
} vm_type_quality;

typedef struct vm_quality {
  int top_dim;      /* elements of this dimension are measured */
  int64_t measured; /* elements measured */
  int64_t skipped;  /* lower-dimensional elements, not measured */
  vm_type_quality type[VM_NTYPES];
  vm_type_quality all;
  double min_det; /* min det C over nodes (target-scaled if a size is known) */
  double sj_p01, sj_p05, sj_p25, sj_p50; /* scaled-Jacobian percentiles */
  int64_t sj_hist[VM_QUALITY_NBINS];
  /* OpenFOAM's checkMesh on the 3D cells (vm_cell_foam): cells of volume
   * <= 0 and face pyramids of volume <= 0 ("incorrectly oriented"; a face
   * counts once per cell it bounds, as checkMesh counts) */
  int64_t foam_neg_volumes, foam_pyramid_errors;
  /* prisms not positive in every one of their 3-tet splits
   * (vm_prism_split_check): a solver or mesher that splits prisms into
   * tets (Pointwise checks this before it accepts a prism) fails there */
  int64_t prism_split_negative;
} vm_quality;

/* A prism (VM_PRISM: vertices 0-2 the bottom, 3-5 the top, 3 over 0; x
 * its 18 coordinates) is positive in all six of its 3-tet splits iff its 6
 * corner tets (the corner rule's) and the 6 tets of two bottom and two top
 * vertices off a side face are. Those 6 tets' det / (|e1| |e2| |e3|), the
 * edges from their first vertex, into q (6 values, may be NULL; about 0.7
 * on a right prism, -1 for a zero edge); returns how many have det <= 0. */
int vm_prism_split_check(const double *x, double *q);

/* Quality of every element of the top dimension. The scaled Jacobian of an
 * element is the minimum over its corner nodes of det E/(|e1||e2||e3|)
 * (2D: det E/(|e1||e2|)), normalized to 1 on the ideal element. 2D elements
 * of a mesh with dim == 3 are measured against their own (Newell) normal, so
 * a lone triangle cannot be inverted. opts may be NULL. */
int vm_mesh_quality(const vm_mesh *m, const vm_quality_opts *opts, vm_quality *q);

/* The same, and per element: sj[e] the scaled Jacobian and phi[e] the
 * minimum of det C/(tr C^T C/d)^{d/2} over the element's quadrature
 * simplices (rule of opts), NAN for elements not measured (not of the top
 * dimension). sj and phi: m->ne doubles each, or NULL; q may be NULL. */
int vm_mesh_element_quality(const vm_mesh *m, const vm_quality_opts *opts, vm_quality *q,
                            double *sj, double *phi);

/* OpenFOAM's face centre c and area vector s of the polygon y (n >= 3
 * vertices, 3 coordinates each): a triangle's centroid and half cross
 * product; otherwise the triangles fanned around the vertex mean, their
 * centroids weighted by their areas (s their summed area vectors). */
void vm_foam_face(const double *y, int n, double *c, double *s);

/* OpenFOAM's geometry of one 3D cell (type VM_TET..VM_HEX) with its
 * vertices at x (3 per vertex, varmesh order), as its primitiveMesh
 * computes it: each face's centre and area vector by the triangles fanned
 * around its vertex mean (a triangle directly), the cell centre by the
 * pyramids on the face centres around their mean, weighted by their signed
 * volumes. Returns the number of the cell's face pyramids (its outward face
 * and its centre) whose volume is not positive: those checkMesh reports as
 * "incorrectly oriented" (a valid cell can have them: a twisted or bent
 * cell whose centre falls outside one of its faces' planes). *volume (may
 * be NULL) gets the cell volume. -1 for a type that is not 3D. */
int vm_cell_foam(int type, const double *x, double *volume);
/* The same, and the cell centre as OpenFOAM computes it (3 doubles). */
int vm_cell_foam_centre(int type, const double *x, double *centre, double *volume);
/* OpenFOAM's measures of an internal face with centre c and area vector s
 * (vm_foam_face; x its n vertices) between the cells centred at cp and cn,
 * as its checkMesh computes them. Skewness: the distance from the face
 * centre to where the line joining the centres meets the face, over the
 * face's extent that way (at least a fifth of the centres' distance; fails
 * beyond 4). */
double vm_foam_skew(const double *x, int n, const double *c, const double *s, const double *cp,
                    const double *cn);
/* Cosine of the non-orthogonality: of the angle between the area vector,
 * turned to point from cp's side to cn's, and cn - cp (1: orthogonal; <= 0:
 * the centres on the wrong sides; -1 for a degenerate face). */
double vm_foam_ortho_cos(const double *c, const double *s, const double *cp, const double *cn);
/* Interpolation weight: the lesser of the two shares of the centres'
 * distances from the face along s (fails below 0.05). */
double vm_foam_weight(const double *c, const double *s, const double *cp, const double *cn);
/* OpenFOAM's cell determinant from the area vectors s of a cell's nf
 * internal faces: |det| of the sum of s s^T over the squared mean face
 * area, over 8 (1 for a cube with every face internal; checkMesh, as
 * Debian's OpenFOAM computes it, fails a cell below 0.001). */
double vm_foam_cell_determinant(int nf, const double (*s)[3]);
/* The least of those face pyramid volumes over the cell volume (scale-free;
 * > 0 when none is wrong; -INFINITY for a cell of volume 0, NAN for a type
 * that is not 3D). */
double vm_cell_foam_margin(int type, const double *x);

#ifdef __cplusplus
}
#endif
#endif
