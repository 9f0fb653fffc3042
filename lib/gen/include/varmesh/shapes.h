/* varmesh/shapes.h: generated test surfaces with known geometry (sphere,
 * torus, cylinder, cube, box, a lens with a sharp ridge), appended to a
 * mesh, for tests, benchmarks and demos. */
#ifndef VARMESH_SHAPES_H
#define VARMESH_SHAPES_H

#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Common contract of every vm_gen_* below:
 *  - the shape is appended to m (vertices after m->nv, elements after
 *    m->ne; vertex flags FREE), so several shapes can share one mesh; m
 *    should carry no fields (they are not extended);
 *  - surfaces are triangulated (the torus optionally with quads) and
 *    closed ones are oriented with the normal pointing outward;
 *  - the result depends only on the arguments: same arguments, same bits;
 *  - returns VM_OK, VM_ERR_ARG for an invalid argument (message on the
 *    context) or VM_ERR_NOMEM; on error m is left with the vertex and
 *    element counts it had on entry. Scratch memory comes from m's context.
 * centre: NULL means the origin (and then no addition takes place, so the
 * coordinates are exactly those computed about the origin). */

/* Random displacement of the generated vertices: `amount` is relative to
 * the shape's grid step (see each function); the sequence is splitmix64
 * from `seed`, independent of the context's generator. NULL or
 * amount <= 0: no jitter. */
typedef struct vm_gen_jitter {
  double amount;
  uint64_t seed;
} vm_gen_jitter;

/* vm_gen_icosphere flags. */
enum {
  /* Midpoints are put on the sphere only after the last subdivision (the
   * older variant: less uniform triangles). Default: projected at every
   * level. Same vertex and triangle order either way. */
  VM_GEN_PROJECT_AT_END = 1
};

/* Icosphere of `radius` about centre: the icosahedron subdivided `level`
 * times (0..12): 10 * 4^level + 2 vertices, 20 * 4^level triangles, every
 * vertex on the sphere; mean curvature H = 1/radius. jitter: every vertex
 * moved by up to amount * (about the mean edge length, 1.1 radius /
 * 2^level) per coordinate, then put back on the sphere. */
int vm_gen_icosphere(vm_mesh *m, const double centre[3], double radius, int level, unsigned flags,
                     const vm_gen_jitter *jitter);

/* An isolated, closed swept wing with the ONERA M6 planform (root chord
 * 0.806, tip chord 0.455, semispan 1.196 along y, leading edge swept by
 * sweep_deg, z up) and symmetric NACA 00xx sections of thickness ratio
 * `thickness` with a sharp trailing edge, closed by flat root and tip caps.
 * The sections are graded as a CAD mesher grades them: nc chordwise
 * intervals per side with cosine spacing (fine at the leading and the
 * trailing edge: the last panel is about 1 - cos(pi / nc) / 2 of the
 * chord), ns spanwise intervals, so at nc = 160, ns = 8 a trailing-edge
 * triangle is about 1,500 times longer than wide. 2 nc (ns + 1) vertices,
 * 4 nc ns + 4 (nc - 1) triangles, oriented outward. */
int vm_gen_wing(vm_mesh *m, int nc, int ns, double thickness, double sweep_deg);

/* A spindle: two cones base to base along z, tips (cone points of half
 * angle atan 0.5, angle deficit 199 degrees) at z = -1 and 1 as vertices 0
 * and 1, radius 0.5 at z = 0 (a sharp ring), ns sectors and rings at z =
 * -0.8, -0.6, -0.35, -0.1, 0, 0.2, 0.45, 0.45 + gap, 0.7, 0.85: a row of
 * needles between the two close rings (gap 0.001: about 1.8 degrees at 48
 * sectors). Closed, oriented outward, 2 + 10 ns vertices. ns >= 3, gap in
 * (0, 0.2). */
int vm_gen_spindle(vm_mesh *m, int ns, double gap);

/* vm_gen_torus cells. */
enum {
  VM_GEN_TORUS_TRI = 0,     /* each grid cell split along the same diagonal */
  VM_GEN_TORUS_TRI_ALT = 1, /* diagonals alternate in a checkerboard */
  VM_GEN_TORUS_QUAD = 2     /* quadrilaterals */
};

/* Torus about the z axis through centre: major radius R, minor r (0 < r <
 * R); nu >= 3 vertices around the axis (angle u), nv >= 3 around the tube
 * (angle v); vertex i * nv + j (after the existing ones) at u = 2 pi i/nu,
 * v = 2 pi j/nv: centre + ((R + r cos v) cos u, (R + r cos v) sin u, r sin v).
 * jitter: u and v each moved by up to amount * (their grid step), so the
 * vertices stay on the torus. H (may be NULL): nu * nv values, the exact
 * mean curvature at each generated vertex, (R + 2 r cos v) / (2 r (R + r cos v)). */
int vm_gen_torus(vm_mesh *m, const double centre[3], double R, double r, int nu, int nv, int cells,
                 const vm_gen_jitter *jitter, double *H);

/* Open cylinder about the z axis, radius r, from z = 0 to z = h: nz >= 2
 * rows of na >= 3 vertices; normal outward; H = 1/(2 r). jitter: vertices
 * of the inner rows moved by up to amount * (grid step) in angle and z. */
int vm_gen_cylinder(vm_mesh *m, double r, double h, int na, int nz, const vm_gen_jitter *jitter);

/* The closed unit cube [0,1]^3, n >= 1 squares a side per face, each split
 * into two triangles; vertices in lattice order (x slowest). */
int vm_gen_cube(vm_mesh *m, int n);

/* The closed axis-aligned box [lo, hi] (lo < hi), n[k] >= 1 squares along
 * axis k, each split into two triangles; conforming (faces share their
 * edge vertices). Vertices numbered face by face (x faces, then y, then z;
 * low side first) on first use. */
int vm_gen_box(vm_mesh *m, const double lo[3], const double hi[3], const int n[3]);

/* A half model: the upper half (z >= 0) of the equal-angle cube-sphere of
 * `radius` about the origin, n (even, 2..1000) intervals along each cube
 * edge: its open border, 4 n vertices, lies in the plane z = 0 exactly,
 * the rest above it; oriented outward. Its mirror image in z = 0 closes
 * it into the whole cube-sphere. */
int vm_gen_hemisphere(vm_mesh *m, double radius, int n);

/* A lens: two spherical caps of radius R, centres (0, 0, -d) (the upper
 * cap, z >= 0) and (0, 0, d) (the lower), 0 <= d < R, meeting at the sharp
 * circular ridge z = 0, radius sqrt(R^2 - d^2), where the normal turns by
 * 2 asin(d/R). Rings of nearly equilateral triangles of edge about h > 0. */
int vm_gen_lens(vm_mesh *m, double R, double d, double h);

#ifdef __cplusplus
}
#endif
#endif
