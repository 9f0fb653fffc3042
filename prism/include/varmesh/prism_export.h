/* varmesh/prism_export.h: volume-mesh formats flow solvers read natively:
 * SU2's own format and CGNS (unstructured, through libcgns), with the
 * boundary faces grouped into named families (markers). */
#ifndef VARMESH_PRISM_EXPORT_H
#define VARMESH_PRISM_EXPORT_H

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How faces are grouped. The volume elements of the mesh's top dimension
 * become the cells. Boundary faces (TRI / QUAD elements of the mesh) are
 * grouped by the int element field "gmsh:physical" and named by the
 * attributes "gmsh:physical_name:2:<tag>" ("wall", "outer" for the output
 * of vm_prism_result); a face without a tag, or a tag without a name, goes
 * to a family named "boundary_<tag>". If the mesh has no faces at all,
 * its boundary faces (vm_mesh_boundary) form one family "boundary".
 * Element fields of the cells (int or f64, one component; for example
 * "layer") are written where the format can hold them. */

/* SU2 native mesh (.su2, ASCII): NDIME=3, NELEM with VTK type ids and
 * 0-based indices, NPOIN with coordinates printed with 17 significant
 * digits, NMARK with one MARKER_TAG per family. Fields cannot be stored
 * (VM_WARN_LOSSY after writing, one VM_LOG_WARN). Atomic.
 * Returns VM_OK, VM_WARN_LOSSY, VM_ERR_ARG (no volume elements),
 * VM_ERR_UNSUPPORTED (pyramids mixed with others are fine; 2D meshes are
 * not), VM_ERR_IO, VM_ERR_NOMEM. */
int vm_write_su2(vm_ctx *ctx, const vm_mesh *m, const char *path);

/* CGNS (.cgns, through libcgns): one base (cell dimension 3), one
 * unstructured zone, coordinates in double, one element section per cell
 * type (TETRA_4, PYRA_5, PENTA_6, HEXA_8; 1-based, VTK order equals CGNS
 * order for these types), one section per face family (TRI_3 / QUAD_4),
 * a Family_t per face family (BCWall for "wall", BCFarfield for "outer",
 * else BCTypeUserDefined) and a BC_t per family referring to it by
 * FamilyName with its element range at FaceCenter; cell fields as a
 * cell-centred FlowSolution_t. Atomic (temporary file + rename).
 * Returns VM_OK, VM_WARN_LOSSY (vertex fields, flags and attributes are
 * not written), VM_ERR_UNSUPPORTED (built without libcgns), VM_ERR_ARG,
 * VM_ERR_IO, VM_ERR_BACKEND (libcgns failed; its message on ctx),
 * VM_ERR_NOMEM. */
int vm_write_cgns(vm_ctx *ctx, const vm_mesh *m, const char *path);

/* 1 if this build can write CGNS. */
int vm_have_cgns(void);

#ifdef __cplusplus
}
#endif
#endif
