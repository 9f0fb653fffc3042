/* volume/src/fill_private.h: what fill.c shares with fill_fv.c (the fill
 * stage's internals, not an API). */
#ifndef VM_FILL_PRIVATE_H
#define VM_FILL_PRIVATE_H

#include "varmesh/mesh.h"

/* A triangular face of a 3D cell: its vertices sorted, the cell, and the
 * face's index among the cell's faces (vm_elem_faces). */
typedef struct {
  int32_t v[3];
  int32_t cell;
  int32_t face;
} tface;

/* Every triangular face of the 3D cells, sorted by its vertex set (then
 * cell): the two sides of an interior face are neighbours. */
int fill_tri_faces(vm_ctx *ctx, const vm_mesh *m, tface **out, int64_t *n);
/* Have a and b the same vertices? */
int fill_same_face(const tface *a, const tface *b);

#endif
