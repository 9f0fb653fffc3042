/* varmesh/aircraft.h: the bundled example model: a generated, closed,
 * outward-oriented triangulated aircraft (fuselage, swept wings with NACA
 * sections, horizontal stabilizers and a fin), for demos and tests. */
#ifndef VARMESH_AIRCRAFT_H
#define VARMESH_AIRCRAFT_H

#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Components, in the order of the "component" element field. */
enum {
  VM_AIRCRAFT_FUSELAGE = 0,
  VM_AIRCRAFT_WING_RIGHT = 1, /* y > 0 */
  VM_AIRCRAFT_WING_LEFT = 2,
  VM_AIRCRAFT_STAB_RIGHT = 3, /* horizontal stabilizer, y > 0 */
  VM_AIRCRAFT_STAB_LEFT = 4,
  VM_AIRCRAFT_FIN = 5,
  VM_AIRCRAFT_NCOMP = 6
};

typedef struct vm_aircraft_opts {
  int resolution;      /* 1..32: scales every parametric direction (default 4:
                          about 15k triangles; 1: 3k, 2: 6k, 8: 44k) */
  double length;       /* nose (x = 0) to tail tip (x = length), default 15 */
  double span;         /* wing tip to tip (y extent), default 13.5; allowed
                          0.35..2.5 times the length */
  double sweep_deg;    /* wing leading-edge sweep, degrees, 0..50, default 28 */
  double dihedral_deg; /* wing dihedral, degrees, -5..12, default 5 */
  int tag_components;  /* nonzero: add the int element field "component"
                          (VM_AIRCRAFT_*); default 0, so that surface formats
                          such as STL write the model without loss */
} vm_aircraft_opts;

/* Facts about the generated model (for tests and reports). */
typedef struct vm_aircraft_info {
  /* triangles per component */
  int64_t ntri[VM_AIRCRAFT_NCOMP];
  /* total length of the five sharp trailing edges, each from where its
   * surface meets the fuselage to its tip */
  double te_length;
  /* the part of te_length on the two wings */
  double wing_te_length;
} vm_aircraft_info;

/* Defaults as documented above. */
vm_aircraft_opts vm_aircraft_opts_default(void);

/* Generate the aircraft. Axes: x from nose to tail (the flow direction),
 * y to the right wing, z up; the fuselage axis is z = 0 along the cabin.
 *
 * The surface is one closed, 2-manifold triangulation (every edge in two
 * triangles, one fan around every vertex), oriented with normals pointing
 * out (positive enclosed volume), without degenerate or intersecting
 * triangles:
 *  - fuselage: elliptic sections, rounded nose, upswept tapered tail cone
 *    ending in a small rounded tip. Its grid of rings is built around
 *    "ports" whose boundaries are exactly the root curves of the five
 *    lifting surfaces: the root vertices are shared, nothing is cut or
 *    intersected;
 *  - wings: trapezoidal planform with the requested span, sweep and
 *    dihedral, cambered NACA 4-digit sections (14% thick at the root, 10% at
 *    the tip) with sharp trailing edges, tips closed by rounding every
 *    section point around the camber line; stabilizers (33 degrees sweep,
 *    6 degrees dihedral) and fin (40 degrees sweep) likewise, symmetric.
 * The trailing edges are the sharp edges of the model (dihedral angle about
 * 160 degrees); from resolution 3 on the leading edges are resolved (first
 * chordwise station inside half the nose radius), below that they are
 * polygonal. Grids are structured (quads split along the shorter diagonal),
 * so there is some anisotropy near leading edges and the poles (at the
 * default resolution the smallest angle is about 2 degrees).
 * Bounding box: x from 0 to length (a long, strongly swept wing may reach
 * further aft), y in [-span/2, span/2], z about -0.06 to +0.21 times the
 * length.
 *
 * output: *out a new mesh of VM_TRI elements, dim 3, all vertices FREE
 *         (free with vm_mesh_destroy); if tag_components, the int element
 *         field "component". info (may be NULL) receives counts and lengths.
 * status: VM_OK; VM_ERR_ARG for options out of range (nothing allocated);
 *         VM_ERR_NOMEM; VM_ERR_NUMERIC if the geometry could not be built
 *         (not expected within the documented ranges).
 * The same options give the same mesh, bit for bit. */
int vm_gen_aircraft(vm_ctx *ctx, const vm_aircraft_opts *o, vm_mesh **out);
int vm_gen_aircraft_info(vm_ctx *ctx, const vm_aircraft_opts *o, vm_mesh **out,
                         vm_aircraft_info *info);

#ifdef __cplusplus
}
#endif
#endif
