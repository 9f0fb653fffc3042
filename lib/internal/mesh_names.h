/* lib/internal/mesh_names.h: duplicate field names and attribute keys,
 * found by sorting (n log n), so that a file or a mesh with many names
 * cannot make a check quadratic. Defined in lib/core/src/mesh.c; shared by
 * vm_mesh_check and the .vmsh readers (not installed, not public API). */
#ifndef VARMESH_INTERNAL_MESH_NAMES_H
#define VARMESH_INTERNAL_MESH_NAMES_H

#include "varmesh/mesh.h"

/* *dup: index (in input order) of the first field name (fields != 0) or
 * attribute key that repeats an earlier one in its group (a field's
 * location), -1 if none. Returns VM_OK or VM_ERR_NOMEM. */
int vm_mesh_first_duplicate(vm_ctx *ctx, const vm_mesh *m, int fields, int *dup);

#endif
