/* varmesh/planar.h: a 2D mesh (triangles, quadrilaterals) that lies in a
 * plane, taken to the plane's own coordinates for the 2D optimizer and back.
 *
 * A file stores a planar mesh with three coordinates: in the plane z = 0
 * (read as dimension 2), in another plane z = c, x = c or y = c, or in a
 * tilted plane. The volume stage untangles and optimizes it in 2D
 * (Section 2 of the paper, the triangle and the bilinear quad rules), with
 * the orientation its boundary gives: the sign of the total signed area, so
 * that a tangled mesh keeps the orientation of the region it covers.
 *
 * Mapping back is exact for what did not move: a vertex whose plane
 * coordinates are bit for bit those it was given gets its input coordinates
 * back, so fixed vertices stay bit-identical, also in a tilted plane. In an
 * axis-aligned plane every mapping is exact (a permutation, a sign). */
#ifndef VARMESH_PLANAR_H
#define VARMESH_PLANAR_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  int axis;     /* 0, 1, 2: the plane is x, y or z = c exactly; -1: tilted */
  double level; /* the constant coordinate (axis >= 0) */
  double o[3];  /* tilted: origin, and the frame u, v, n (unit, right-handed) */
  double u[3], v[3], n[3];
  int flip;      /* 1: the plane's second coordinate negated, so that the
                    total signed area is positive */
  int dim0;      /* the mesh's dimension before the mapping */
  double offset; /* the largest distance of a vertex from the plane */
  int64_t worst; /* that vertex */
} vm_plane_frame;

/* The tolerance the stages take a mesh as planar with: files written with 7
 * digits (single precision) put the vertices of a tilted plane about 1e-7
 * of the diagonal off it. */
#define VM_PLANE_TOL 1e-6

/* Whether m's elements are 2D and its vertices in one plane, within `tol`
 * relative to the bounding-box diagonal. VM_OK and *f filled when they are;
 * VM_ERR_ARG with the vertex farthest from the best plane in f->worst and
 * f->offset when they are not (or the mesh has volume elements). */
int vm_mesh_plane_frame(const vm_mesh *m, double tol, vm_plane_frame *f);

/* m's coordinates to the plane's: (x', y', 0), dimension 2; y' negated
 * (f->flip) where the total signed area would be negative. */
void vm_mesh_to_plane(vm_mesh *m, vm_plane_frame *f);

/* The plane coordinates of m back to space, in place. `x2d0` holds the plane
 * coordinates the mapping gave (3 per vertex) and `xyz0` the input's: a
 * vertex still at x2d0 gets xyz0 back bit for bit. */
void vm_mesh_from_plane(vm_mesh *m, const vm_plane_frame *f, const double *x2d0,
                        const double *xyz0);

/* One point of the plane (its coordinates as vm_mesh_to_plane gave them) in
 * space. */
void vm_plane_to_space(const vm_plane_frame *f, const double q[3], double p[3]);

/* The total signed area of m's 2D elements in the xy plane (quadrilaterals
 * by the shoelace formula). */
double vm_mesh_signed_area_2d(const vm_mesh *m);

/* The total signed volume of m's volume elements (each by its faces,
 * outward as vm_elem_faces orders them): negative when the elements are
 * numbered the other way round from VTK's convention (a tangled mesh's
 * folds cancel; the boundary decides). */
double vm_mesh_signed_volume(const vm_mesh *m);

/* Edges of m's 2D elements that two elements run through in the same
 * direction: the elements are not oriented alike (a tangled mesh's are; its
 * geometry folds, not its order). Their number (or VM_ERR_NOMEM); the first
 * pair's elements in first[], its edge's vertices in edge[]. */
int64_t vm_mesh_orientation_conflicts_2d(const vm_mesh *m, int64_t first[2], int32_t edge[2]);

#ifdef __cplusplus
}
#endif

#endif
