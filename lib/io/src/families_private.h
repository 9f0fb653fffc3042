/* lib/io/src/families_private.h: what the SU2, CGNS and OpenFOAM writers
 * share: the cells of the mesh, its boundary faces grouped into named
 * families, and the kind of boundary a family's name says. */
#ifndef VARMESH_FAMILIES_PRIVATE_H
#define VARMESH_FAMILIES_PRIVATE_H

#include <stdint.h>

#include "varmesh/mesh.h"

typedef struct {
  int64_t ncell;
  int32_t *cell; /* element indices of the cells (top dimension) */
  int nfam;
  char **name;   /* family names (vm_strdup) */
  int64_t *fbeg; /* faces of family f: [fbeg[f], fbeg[f+1]) */
  int64_t nface;
  int32_t *fv;    /* 4 vertices per face (unused -1) */
  uint8_t *fnv;   /* 3 or 4 */
  int32_t *felem; /* the face's element in the mesh, -1 if extracted */
} ex_groups;

/* VM_OK if the mesh can be exported (3D, with volume cells or a surface of
 * triangles and quads), else a one-line error naming path and the format
 * fmt ("SU2", "CGNS"). */
int ex_groups_check(vm_ctx *ctx, const vm_mesh *m, const char *path, const char *fmt);
/* Nonzero if the mesh is a surface in 3D (top dimension 2): it is exported
 * as its triangles and quads as cells, without faces or families. */
int ex_groups_surface(const vm_mesh *m);
/* Log (VM_LOG_WARN) each thing the export cannot carry: fields other than
 * "gmsh:physical" (that one too for a surface mesh) (and, if cell_fields, one-component element
 * fields not named "gmsh:..."), attributes other than the family names (all of them for a surface
 * mesh), vertex flags. Returns nonzero if anything is lost. */
int ex_groups_lossy(vm_ctx *ctx, const vm_mesh *m, const char *path, const char *fmt,
                    int cell_fields);
/* Group the mesh's faces (see varmesh/io.h); for a surface mesh, the cells
 * are its triangles and quads in mesh order and there are no families. */
int ex_groups_build(vm_ctx *ctx, const vm_mesh *m, ex_groups *g);
void ex_groups_free(vm_ctx *ctx, ex_groups *g);

/* The kind of boundary a family's name says (letter case ignored): a name
 * starting with "wall" is a wall, "farfield" a far field, "symmetry" a
 * symmetry plane; anything else ("outer", the top of a prism layer, "inlet",
 * ...) is another boundary, which the writers leave to the user. */
enum { EX_FAM_OTHER = 0, EX_FAM_WALL, EX_FAM_FARFIELD, EX_FAM_SYMMETRY };
int ex_family_kind(const char *name);

#endif
