// lib/geom/src/features_openmesh.cpp: OpenMesh adapter: half-edge build of
// a surface mesh (which faces would make it non-manifold), dihedral angles
// and boundary status of its edges.

// OpenMesh's PropertyT<VectorT>::push_back copies a default-constructed
// (uninitialized) vector, which GCC flags wherever it gets inlined.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <cstring>
#include <vector>

#include "adapter_private.h"
#include "cxx_private.h"

namespace {

struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
typedef OpenMesh::PolyMesh_ArrayKernelT<DoubleTraits> Mesh;

// OpenMesh reports refused faces on omerr(); the library must not print.
class QuietOpenMesh {
public:
  QuietOpenMesh() : was_(omerr().is_enabled()) { omerr().disable(); }
  ~QuietOpenMesh() {
    if (was_) omerr().enable();
  }

private:
  bool was_;
};

} // namespace

extern "C" int vm_om_edge_angles(const vm_mesh *m, int64_t *nedge, int32_t **ev, double **angle,
                                 uint8_t **boundary, int64_t *nrefused, int64_t *first_refused) {
  vm_ctx *ctx = m->ctx;
  *nedge = 0;
  *ev = NULL;
  *angle = NULL;
  *boundary = NULL;
  *nrefused = 0;
  *first_refused = -1;
  VM_CXX_BEGIN
  QuietOpenMesh quiet;
  Mesh mesh;
  mesh.reserve(static_cast<size_t>(m->nv), static_cast<size_t>(3 * m->ne),
               static_cast<size_t>(m->ne));
  std::vector<Mesh::VertexHandle> vh(static_cast<size_t>(m->nv));
  for (int64_t v = 0; v < m->nv; v++)
    vh[static_cast<size_t>(v)] =
        mesh.add_vertex(Mesh::Point(m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2]));
  std::vector<Mesh::VertexHandle> fv;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    int k = vm_elem_nverts(m->etype[e]);
    fv.clear();
    for (int a = 0; a < k; a++) fv.push_back(vh[static_cast<size_t>(m->conn[m->eoff[e] + a])]);
    if (!mesh.add_face(fv).is_valid()) {
      if (*nrefused == 0) *first_refused = e;
      ++*nrefused;
    }
  }
  const size_t ne = mesh.n_edges();
  int32_t *pv = static_cast<int32_t *>(vm_alloc_array(ctx, 2 * (ne ? ne : 1), sizeof *pv));
  double *pa = static_cast<double *>(vm_alloc_array(ctx, ne ? ne : 1, sizeof *pa));
  uint8_t *pb = static_cast<uint8_t *>(vm_alloc_array(ctx, ne ? ne : 1, sizeof *pb));
  if (!pv || !pa || !pb) {
    vm_free(ctx, pv);
    vm_free(ctx, pa);
    vm_free(ctx, pb);
    return VM_ERR_NOMEM;
  }
  size_t i = 0;
  for (auto eh : mesh.edges()) {
    auto h = mesh.halfedge_handle(eh, 0);
    pv[2 * i] = mesh.from_vertex_handle(h).idx();
    pv[2 * i + 1] = mesh.to_vertex_handle(h).idx();
    pb[i] = mesh.is_boundary(eh) ? 1 : 0;
    pa[i] = pb[i] ? 0.0 : static_cast<double>(mesh.calc_dihedral_angle(eh));
    i++;
  }
  *nedge = static_cast<int64_t>(ne);
  *ev = pv;
  *angle = pa;
  *boundary = pb;
  return VM_OK;
  VM_CXX_END(ctx, "OpenMesh")
}
