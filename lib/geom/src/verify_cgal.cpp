// lib/geom/src/verify_cgal.cpp: exact verification of meshes with CGAL: the
// orientation of every quadrature simplex, and the prism layer's outer
// surface against itself and the wall (varmesh/verify.h).
#include "varmesh/verify.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/determinant.h>

#include <algorithm>
#include <array>
#include <vector>

#include "varmesh/ctx.h"
#include "varmesh/quadrature.h"
#include "cxx_private.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point3;
typedef K::Point_2 Point2;

const double *vertex(const vm_mesh *m, int32_t v) { return m->xyz + 3 * (size_t)v; }

Point3 p3(const double *x) { return Point3(x[0], x[1], x[2]); }
Point2 p2(const double *x) { return Point2(x[0], x[1]); }

// Exact sign of det[h_k - t_k] (k = 0..d-1 columns) restricted to the
// coordinate rows `rows`: interval arithmetic first, exact rationals when
// the interval contains zero. The differences are never rounded.
template <class NT>
NT diff_det(int d, const double *const h[3], const double *const t[3], const int rows[3]) {
  NT c[3][3];
  for (int k = 0; k < d; k++)
    for (int r = 0; r < d; r++) c[k][r] = NT(h[k][rows[r]]) - NT(t[k][rows[r]]);
  if (d == 2) return c[0][0] * c[1][1] - c[1][0] * c[0][1];
  return CGAL::determinant(c[0][0], c[1][0], c[2][0], c[0][1], c[1][1], c[2][1], c[0][2], c[1][2],
                           c[2][2]);
}

CGAL::Sign diff_det_sign(int d, const double *const h[3], const double *const t[3],
                         const int rows[3]) {
  {
    CGAL::Protect_FPU_rounding<true> upward;
    CGAL::Uncertain<CGAL::Sign> s = CGAL::sign(diff_det<CGAL::Interval_nt_advanced>(d, h, t, rows));
    if (CGAL::is_certain(s)) return CGAL::get_certain(s);
  }
  return CGAL::sign(diff_det<CGAL::Exact_rational>(d, h, t, rows));
}

// Is quadrature node q of an element with vertex coordinates x[] bad
// (not positively oriented; for surface elements: degenerate)?
// `surface`: a 2D element embedded in 3D.
bool node_is_bad(const vm_qnode *q, int d, bool surface, const double *const x[8]) {
  const double *h[3] = {NULL, NULL, NULL}, *t[3] = {NULL, NULL, NULL};
  for (int k = 0; k < d; k++) {
    h[k] = x[(int)q->head[k]];
    t[k] = x[(int)q->tail[k]];
  }
  bool one_tail = t[0] == t[1] && (d == 2 || t[1] == t[2]);
  if (surface) {
    if (one_tail) return CGAL::collinear(p3(t[0]), p3(h[0]), p3(h[1]));
    // parallel edges: every component of their cross product is zero
    static const int planes[3][3] = {{1, 2, 0}, {2, 0, 0}, {0, 1, 0}};
    for (int c = 0; c < 3; c++)
      if (diff_det_sign(2, h, t, planes[c]) != CGAL::ZERO) return false;
    return true;
  }
  static const int xyz[3] = {0, 1, 2};
  CGAL::Sign s;
  if (d == 3)
    s = one_tail ? CGAL::orientation(p3(t[0]), p3(h[0]), p3(h[1]), p3(h[2]))
                 : diff_det_sign(3, h, t, xyz);
  else
    s = one_tail ? CGAL::orientation(p2(t[0]), p2(h[0]), p2(h[1])) : diff_det_sign(2, h, t, xyz);
  return s != CGAL::POSITIVE;
}

// A boundary triangle of the prism layer.
struct Face {
  std::array<int32_t, 3> v; // mesh vertices as in the element
  int64_t elem;             // prism
  bool outer;               // top (outer surface) or bottom (wall)
};

typedef CGAL::Box_intersection_d::Box_with_handle_d<double, 3, const Face *,
                                                    CGAL::Box_intersection_d::ID_FROM_HANDLE>
    Box;

// Do triangles a and b have a common point other than shared vertices or a
// shared edge? (CGAL's PMP::internal::do_faces_intersect, for a soup.)
bool faces_intersect(const vm_mesh *m, const Face &a, const Face &b) {
  int ia[3], ib[3], nshared = 0;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      if (a.v[i] == b.v[j]) {
        ia[nshared] = i;
        ib[nshared] = j;
        nshared++;
      }
  Point3 pa[3], pb[3];
  for (int i = 0; i < 3; i++) {
    pa[i] = p3(vertex(m, a.v[i]));
    pb[i] = p3(vertex(m, b.v[i]));
  }
  if (nshared >= 3) return true; // the same triangle twice
  if (nshared == 2) {
    // overlap only if coplanar with both apexes on the same side of the edge
    const Point3 &e0 = pa[ia[0]], &e1 = pa[ia[1]];
    const Point3 &ra = pa[3 - ia[0] - ia[1]], &rb = pb[3 - ib[0] - ib[1]];
    return CGAL::coplanar(e0, e1, ra, rb) &&
           CGAL::coplanar_orientation(e0, e1, ra, rb) == CGAL::POSITIVE;
  }
  K::Triangle_3 ta(pa[0], pa[1], pa[2]), tb(pb[0], pb[1], pb[2]);
  if (nshared == 1) {
    // beyond the shared vertex iff an opposite edge meets the other triangle
    int i = ia[0], j = ib[0];
    K::Segment_3 sa(pa[(i + 1) % 3], pa[(i + 2) % 3]), sb(pb[(j + 1) % 3], pb[(j + 2) % 3]);
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}

} // namespace

extern "C" int vm_verify_orientation(const vm_mesh *m, int rule, int64_t *bad_nodes,
                                     int64_t *bad_elems, int64_t *first_bad_elem) {
  if (bad_nodes) *bad_nodes = 0;
  if (bad_elems) *bad_elems = 0;
  if (first_bad_elem) *first_bad_elem = -1;
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  if (rule != VM_RULE_CORNER && rule != VM_RULE_GEOMETRIC)
    return vm_error(ctx, VM_ERR_ARG, "verify: unknown quadrature rule %d", rule);
  VM_CXX_BEGIN
  int top = 0;
  for (int64_t e = 0; e < m->ne; e++) top = std::max(top, vm_elem_dim(m->etype[e]));
  bool surface = top == 2 && m->dim == 3;
  int64_t nbad = 0, ebad = 0, first = -1;
  for (int64_t e = 0; e < m->ne; e++) {
    int type = m->etype[e];
    if (vm_elem_dim(type) != top) continue;
    const vm_qrule *qr = vm_qrule_get(type, rule);
    if (!qr)
      return vm_error(ctx, VM_ERR_ARG, "verify: element %lld: unknown type %d", (long long)e, type);
    const double *x[8];
    for (int i = 0; i < vm_elem_nverts(type); i++) x[i] = vertex(m, m->conn[m->eoff[e] + i]);
    int64_t here = 0;
    for (int q = 0; q < qr->nnodes; q++) here += node_is_bad(&qr->nodes[q], qr->dim, surface, x);
    if (here) {
      nbad += here;
      ebad++;
      if (first < 0) first = e;
    }
  }
  if (bad_nodes) *bad_nodes = nbad;
  if (bad_elems) *bad_elems = ebad;
  if (first_bad_elem) *first_bad_elem = first;
  return VM_OK;
  VM_CXX_END(ctx, "verify orientation")
}

extern "C" int vm_verify_prism_layer(const vm_mesh *m, int64_t *intersecting_pairs,
                                     int64_t *wall_crossings, int64_t first_pair[2]) {
  if (intersecting_pairs) *intersecting_pairs = 0;
  if (wall_crossings) *wall_crossings = 0;
  if (first_pair) first_pair[0] = first_pair[1] = -1;
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  VM_CXX_BEGIN
  // every prism's bottom and top triangle; keep those no other one repeats
  std::vector<Face> all;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_PRISM) continue;
    const int32_t *c = m->conn + m->eoff[e];
    all.push_back(Face{{{c[0], c[1], c[2]}}, e, false});
    all.push_back(Face{{{c[3], c[4], c[5]}}, e, true});
  }
  std::vector<std::array<int32_t, 3>> key(all.size());
  std::vector<size_t> order(all.size());
  for (size_t i = 0; i < all.size(); i++) {
    key[i] = all[i].v;
    std::sort(key[i].begin(), key[i].end());
    order[i] = i;
  }
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
  std::vector<Face> faces;
  for (size_t i = 0; i < order.size();) {
    size_t j = i + 1;
    while (j < order.size() && key[order[j]] == key[order[i]]) j++;
    const Face &f = all[order[i]];
    // degenerate triangles are left to the orientation check
    if (j == i + 1 &&
        !CGAL::collinear(p3(vertex(m, f.v[0])), p3(vertex(m, f.v[1])), p3(vertex(m, f.v[2]))))
      faces.push_back(f);
    i = j;
  }
  std::vector<Box> boxes;
  boxes.reserve(faces.size());
  for (const Face &f : faces) {
    CGAL::Bbox_3 b =
        p3(vertex(m, f.v[0])).bbox() + p3(vertex(m, f.v[1])).bbox() + p3(vertex(m, f.v[2])).bbox();
    boxes.push_back(Box(b, &f));
  }
  int64_t nout = 0, nwall = 0;
  // the first offending pair: (kind, lower prism, higher prism), kind 0 for
  // outer-outer, 1 for outer-wall; the minimum does not depend on the
  // order in which the boxes are reported
  std::array<int64_t, 3> best{{2, -1, -1}};
  auto report = [&](const Box &ba, const Box &bb) {
    const Face &a = *ba.handle(), &b = *bb.handle();
    if (!a.outer && !b.outer) return;
    if (!faces_intersect(m, a, b)) return;
    int64_t kind = a.outer && b.outer ? 0 : 1;
    (kind ? nwall : nout)++;
    std::array<int64_t, 3> cand{{kind, std::min(a.elem, b.elem), std::max(a.elem, b.elem)}};
    if (cand < best) best = cand;
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), report);
  if (intersecting_pairs) *intersecting_pairs = nout;
  if (wall_crossings) *wall_crossings = nwall;
  if (first_pair && best[0] < 2) {
    first_pair[0] = best[1];
    first_pair[1] = best[2];
  }
  return VM_OK;
  VM_CXX_END(ctx, "verify prism layer")
}
