/* varmesh/rotcube.h: generated benchmark meshes: the uniform cube and the
 * rotated-cube untangling problem of the paper's Section 6.1. */
#ifndef VARMESH_GENERATE_H
#define VARMESH_GENERATE_H

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { VM_GEN_HEX = 0, VM_GEN_TETS = 1, VM_GEN_MIXED = 2 };

typedef struct vm_rotcube_opts {
  int n;             /* cells per direction (>= 2) */
  double alpha;      /* rotation angle of the inner cube, radians */
  double axis[3];    /* rotation axis (normalized internally; default z) */
  double inner;      /* half-size of the inner cube (default 1/(2 sqrt 2)) */
  int cells;         /* VM_GEN_HEX, VM_GEN_TETS (6 Kuhn tets per cube) or
                        VM_GEN_MIXED (cubes by (i+j+k) mod 4: hex, 2 prisms,
                        6 pyramids around an added centre vertex, 6 tets);
                        the mixed mesh shares every vertex between cells but a
                        quad face may meet two triangles, so it is for solver
                        tests, not for boundary extraction */
  int free_boundary; /* leave the outer boundary vertices FREE (for slip
                        boundary runs); default 0: FIXED */
} vm_rotcube_opts;

/* Defaults: n 8, alpha 0, axis z, inner 1/(2 sqrt 2), hexahedra. */
vm_rotcube_opts vm_rotcube_opts_default(void);

/* The unit cube [-1/2, 1/2]^3 with n^3 cells; vertices strictly inside the
 * inner cube are rotated by alpha about the axis and FIXED, boundary
 * vertices FIXED, all others FREE at their Cartesian positions (the
 * untangling problem of Section 6.1). An int vertex field "fixed" mirrors
 * the flags. If xyz_ref != NULL it receives the Cartesian coordinates (the
 * target; 3*nv doubles, vm_free). */
int vm_gen_rotated_cube(vm_ctx *ctx, const vm_rotcube_opts *o, vm_mesh **out, double **xyz_ref);

#ifdef __cplusplus
}
#endif
#endif
