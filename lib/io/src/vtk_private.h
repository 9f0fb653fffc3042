/* lib/io/src/vtk_private.h: what the legacy VTK (vtk.c) and VTU (vtu.c) readers
 * and writers share: turning VTK cells into mesh elements, the vm_flag /
 * vm_surface / fixed conventions, and reporting what the formats lose. */
#ifndef VARMESH_VTK_PRIVATE_H
#define VARMESH_VTK_PRIVATE_H

#include <stddef.h>
#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

/* Names of the point arrays that carry m->vflag and m->vsurf. */
#define VM_VTK_FLAG_NAME "vm_flag"
#define VM_VTK_SURF_NAME "vm_surface"

/* VTK cells in file order: cell c has VTK type types[c] and the point ids
 * conn[off[c] .. off[c+1]-1]. */
typedef struct vm_vtk_cells {
  int64_t n;
  const int64_t *off;
  const int64_t *conn;
  const int32_t *types;
} vm_vtk_cells;

/* Replace m's elements by the linear cells of `c` (m->nv must be set).
 * VTK_VERTEX, VTK_LINE and VTK_POLY_LINE cells are skipped with one
 * VM_LOG_WARN naming how many; any other non-linear type, a wrong vertex
 * count or a point id outside [0, m->nv) is an error "<where>: cell N: ...".
 * map: receives a new array (vm_free) of c->n entries, the element index of
 * each cell or -1 where it was skipped (for dropping cell data rows).
 * Returns VM_OK or a negative status with the message recorded. */
int vm_vtk_build_elements(vm_ctx *ctx, vm_mesh *m, const char *name, const char *where,
                          const vm_vtk_cells *c, int64_t **map);

/* After all arrays are read: an int point array vm_flag sets m->vflag and
 * vm_surface m->vsurf (both consumed); an int point array "fixed" marks
 * vertices FIXED and stays; m->dim becomes 2 when every element is 2D and
 * every z is 0, else 3. Errors name `where` and the offending point. */
int vm_vtk_finish_mesh(vm_ctx *ctx, vm_mesh *m, const char *where);

/* Writers: nonzero when the vm_flag / vm_surface arrays must be written
 * (some vertex is not FREE). */
int vm_vtk_need_flags(const vm_mesh *m);
/* Writers: nonzero when field f is written (a point field that clashes with
 * the flag arrays is not, and is reported as lost). */
int vm_vtk_field_written(const vm_field *f, int flags);
/* Writers: log one VM_LOG_WARN per item the format cannot carry (string
 * attributes, fields shadowed by the flag arrays); returns how many. */
int vm_vtk_report_lost(vm_ctx *ctx, const vm_mesh *m, const char *path, int flags);

#endif
