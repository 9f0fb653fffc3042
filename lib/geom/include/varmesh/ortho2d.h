/* varmesh/ortho2d.h: a triangle surface made fit to carry a finite-volume
 * prism layer. A layer's lateral faces over a wall edge (a, b) take the
 * wall's own non-orthogonality there: the angle between the line joining
 * the centroids of the edge's two triangles and the edge's normal in the
 * surface, (b - a) x (n1 + n2) with n1, n2 the triangles' unit normals
 * (OpenFOAM's checkMesh warns beyond 70 degrees; the thin first layers
 * cannot lean it away: their side edges stand on the wall's normal). A
 * stretched triangulation, as curvature adaptation leaves near a sharp
 * trailing edge or a CAD export has everywhere, puts that angle past 70
 * degrees on hundreds of edges. The relief moves vertices on the surface
 * to lower it, without remeshing: connectivity, corners and feature lines
 * stay. */
#ifndef VARMESH_ORTHO2D_H
#define VARMESH_ORTHO2D_H

#include <stdint.h>

#include "varmesh/mesh.h"
#include "varmesh/project.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_ortho2d_opts {
  int sweeps;        /* sweeps at most (default 8; 0: the figures only) */
  double relief_deg; /* edges beyond this angle weigh in the penalty (default 55) */
  double active_deg; /* the vertices of the triangles on an edge beyond this are
                        visited (default 65) */
  double min_angle;  /* a step keeps the smallest angle of the vertex's triangles at
                        least min(this, what it was before the step) (default 20
                        degrees) */
  double max_move;   /* a vertex ends at most this share of its mean edge at the
                        start from where it started (default 0.5) */
  double feature_angle, corner_angle, cone_angle; /* vertex classes, as
                          vm_surface_adapt's (defaults 20, 50, 60) */
} vm_ortho2d_opts;

vm_ortho2d_opts vm_ortho2d_opts_default(void);

typedef struct vm_ortho2d_result {
  int64_t edges;                       /* interior edges (two triangles each) */
  int64_t over70_before, over70_after; /* edges beyond 70 degrees */
  int64_t over60_before, over60_after; /* and beyond 60 */
  double max_before, max_after;        /* the largest angle, degrees */
  int64_t moves;                       /* vertex steps kept */
  int64_t moved;                       /* vertices not where they started */
  int sweeps;
  double max_shift; /* the largest distance a vertex went */
  double elapsed;   /* seconds */
} vm_ortho2d_result;

/* The wall non-orthogonality (degrees) of the interior edge (a, b) whose
 * triangles (a, b, p) and (b, a, q) are both oriented the same way; 90
 * for a degenerate configuration. */
double vm_surface_edge_nonortho(const double *a, const double *b, const double *p, const double *q);

/* Relieve the triangle surface m in place: its vertices, one at a time in
 * vertex order, take steps of gradient descent on the sum over the edges
 * of their triangles of max(0, cos(relief_deg) - cos(angle))^2, smooth
 * vertices on ref's surface (closest point), feature-line vertices along
 * their reference line, corners and cone points fixed (the classes of
 * vm_surface_adapt: features of m by o's angles, tied to ref's within 1e-3
 * of the mean edge), vertices FIXED in m too. A step is kept only if the
 * penalty falls, the worst angle around does not rise (or stays within
 * active_deg), no triangle around turns more than 60 degrees from its
 * normal before the relief, their smallest angle stays at least
 * min(min_angle, what it was), and the vertex stays within max_move of
 * its mean edge from where it started. Sweeps repeat while one lowers the count of edges
 * beyond 70 degrees by at least 1 %. Deterministic (serial). Meshes with
 * elements other than triangles are left as they are (the figures zero).
 * ref NULL: m itself as it is now. Returns VM_OK, VM_ERR_ARG,
 * VM_ERR_NOMEM, VM_ERR_INTERRUPTED (m holds the last accepted step). */
int vm_surface_ortho_relief(vm_mesh *m, vm_surface_projector *ref, const vm_ortho2d_opts *o,
                            vm_ortho2d_result *r);

#ifdef __cplusplus
}
#endif
#endif
