/* prism/src/geom.h: geometry of prisms and surfaces on plain arrays:
 * prism quality over quadrature simplices, column
 * directions and per-prism targets of a triangulated surface. */
#ifndef VARMESH_PRISM_GEOM_H
#define VARMESH_PRISM_GEOM_H

#include <math.h>
#include <stdint.h>

#include "params.h"
#include "varmesh/ctx.h"
#include "vec3.h"

#define PR_PI 3.14159265358979323846

/* Minimum over the 12 compound matrices of the prism's geometric rule of
 * det / (|c1| |c2| |c3|), normalized to 1 on the right prism with an
 * equilateral base: > 0 iff every node (and every corner tet) is positive.
 * x: 6 vertices, x[3*i + k]. */
double pr_prism_quality(const double *x);
/* The same over the 6 corner tets (the figure the report calls the scaled
 * Jacobian), and the number of corner tets with det <= 0 in *inverted. */
double pr_prism_corner_quality(const double *x, int *inverted);

/* Angle in degrees between side edge o -> x and the unit normal n (180 for
 * an edge of zero length). */
double pr_tilt_deg(const double *o, const double *x, const double *n);

/* A closed triangulated surface's connectivity, as plain arrays: nt
 * triangles (3 vertex indices each) on nv vertices, vertex -> triangles
 * and vertex -> neighbour vertices in CSR form. Borrowed, never owned.
 * A half model's surface is closed by its mirror image in the plane
 * x[sym_ax] = const: its open boundary lies in that plane, and the
 * vertices there (onsym[v] = 1) see their triangles' mirror images too
 * (sym_ax -1, onsym NULL: a closed surface). */
typedef struct pr_surf {
  int64_t nv, nt;
  const int32_t *tri;
  const int64_t *vt_off;
  const int32_t *vt;
  const int64_t *vv_off;
  const int32_t *vv;
  int sym_ax;
  const uint8_t *onsym;
} pr_surf;

/* Unit angle-weighted vertex normals of the surface s at coordinates xyz,
 * then made visible from every incident face where possible (min over
 * faces of n . f maximized where it was below k->visible_min) and blended
 * with their neighbours where the surface has sharp edges, so columns
 * spread instead of crossing. fn: 3*nt face normals (computed here).
 * vnrm may be NULL; dir receives the blended directions. Returns the
 * number of vertices where no visible direction was found, the first of
 * them into *first_blind (may be NULL; ctx: scratch memory; without it the
 * blending is skipped). On a half model (s->onsym) the directions of the
 * vertices in the symmetry plane are those of the whole model: in the
 * plane, their component across it exactly 0. */
int64_t pr_surface_dirs(vm_ctx *ctx, const pr_surf *s, const pr_dir_params *k, const double *xyz,
                        double *fn, double *vnrm, double *dir, int blend_passes,
                        int64_t *first_blind);

/* Targets of the prisms on triangles tri (nt) over surface `base`: each
 * corner a of triangle t goes to base_a + h_a * u_a with u_a = dir_a
 * blended towards the face normal as little as needed for the target to
 * be valid with a margin (k->target_quality); where the unblended target
 * widens away from the wall (a convex part: a fan around a tip or a
 * trailing edge) it is taken as it is once its quality is above
 * k->fair_quality, since there it is the exact offset and a blended one
 * would overlap its neighbours'. Writes 18 values per triangle into tgt. */
void pr_build_targets(int64_t nt, const int32_t *tri, const pr_dir_params *k, const double *base,
                      const double *fn, const double *dir, const double *h, double *tgt);

/* ---- a finite-volume solver's view of the cells (OpenFOAM's definitions,
 * as its checkMesh computes them) ---- */

/* The prism's faces in its 18 coordinates: bottom, top, three quads (-1
 * ends a triangle). */
extern const int pr_prism_faces[5][4];
/* Face centres and area vectors: vm_foam_face (varmesh/quality.h). */
/* Cell centre of prism x: the pyramids on its faces around the face
 * centres' mean, volume-weighted. */
void pr_foam_cell(const double *x, double *cc);
/* The same, with its faces' centres fc and area vectors fs (in
 * pr_prism_faces' order and orientation). */
void pr_foam_cell_faces(const double *x, double *cc, double (*fc)[3], double (*fs)[3]);
/* checkMesh -allGeometry fails a cell whose determinant is below this. */
#define PR_FOAM_DET_MIN 1e-3
/* OpenFOAM's determinant of a prism from its faces' area vectors fs
 * (pr_foam_cell_faces), over those inside the hybrid mesh (internal[f]):
 * checkMesh leaves out the boundary's, the wall under layer 0 and a side
 * over an open edge; the top of the last layer is inside once the fill's
 * tets stand on it. */
double pr_foam_cell_det(const double (*fs)[3], const int *internal);
/* Skewness of face x (n vertices) between the cells centred at cp and cn:
 * the distance from the face centre to where the line joining the centres
 * meets the face, over the face's extent that way (at least a fifth of
 * the centres' distance). */
double pr_foam_skew(const double *x, int n, const double *cp, const double *cn);
/* (Of a face whose centre and area vector are known: vm_foam_skew,
 * vm_foam_ortho_cos, vm_foam_weight in varmesh/quality.h.) */
/* Skewness of boundary face x (n vertices) of the cell centred at cp. */
double pr_foam_boundary_skew(const double *x, int n, const double *cp);
/* Cosine of the non-orthogonality of face x (n vertices) between the cells
 * centred at cp and cn: of the angle between its area vector, turned to
 * point from cp's side to cn's, and cn - cp (1: orthogonal; <= 0: the
 * centres on the wrong sides, -1 for a degenerate face). */
double pr_foam_ortho_cos(const double *x, int n, const double *cp, const double *cn);
/* Is the prism with cell centre cc and faces fc, fs (pr_foam_cell_faces)
 * concave as OpenFOAM's checkMesh sees it: another face's centre on or
 * beyond the plane of a face (within a cosine of 1e-6)? */
int pr_foam_cell_concave(const double (*fc)[3], const double (*fs)[3], const double *cc);
/* Does face x (n vertices, centre c, area vector s) decompose into positive
 * tets with both cell centres, from one of its vertices as the base point
 * (OpenFOAM's face-tet check, which a solver's particle tracking and
 * interpolation need)? */
int pr_foam_face_tets_ok(const double *x, int n, const double *c, const double *s, const double *cp,
                         const double *cn);

#endif
