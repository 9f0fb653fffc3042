/* lib/geom/src/adapter_private.h: the extern "C" entry points of the
 * OpenMesh adapter (features_openmesh.cpp) used by the C modules of the
 * geometry library. No C++ here. */
#ifndef VARMESH_GEOM_ADAPTER_PRIVATE_H
#define VARMESH_GEOM_ADAPTER_PRIVATE_H

#include <stdint.h>

#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Half-edge analysis of the 2D elements of m with OpenMesh: the mesh is
 * built face by face; a face OpenMesh cannot add (it would make an edge or
 * a vertex non-manifold, or it is inconsistently oriented with respect to
 * a neighbour) is counted in *nrefused and the first one's element index
 * stored in *first_refused (-1 if none). For every edge of the built mesh:
 * its end vertices (ev, 2 per edge), its dihedral angle in radians
 * (0 flat, signed: > 0 convex w.r.t. the orientation normal) and whether
 * it is a boundary edge. Arrays allocated with vm_malloc on m->ctx
 * (free with vm_free). Returns VM_OK, VM_ERR_NOMEM or VM_ERR_BACKEND. */
int vm_om_edge_angles(const vm_mesh *m, int64_t *nedge, int32_t **ev, double **angle,
                      uint8_t **boundary, int64_t *nrefused, int64_t *first_refused);

#ifdef __cplusplus
}
#endif
#endif
