// lib/geom/src/repair_cgal.cpp: CGAL adapter: repair of an imported surface
// (Polygon_mesh_processing), a closed wrap around one no repair can close
// (3D alpha wrapping), self-intersection detection, isotropic remeshing
// with protected features.
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <set>
#include <cmath>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include "cxx_private.h"
#include "varmesh/repair.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Surface_mesh<Point> SMesh;
typedef boost::graph_traits<SMesh>::vertex_descriptor vertex_descriptor;
typedef boost::graph_traits<SMesh>::face_descriptor face_descriptor;
typedef boost::graph_traits<SMesh>::halfedge_descriptor halfedge_descriptor;
typedef boost::graph_traits<SMesh>::edge_descriptor edge_descriptor;
namespace PMP = CGAL::Polygon_mesh_processing;

typedef std::vector<std::size_t> Polygon;

// What orient_polygon_soup met on the way (the visitor is copied by CGAL,
// so it records through a pointer).
struct OrientLog {
  std::set<std::pair<std::size_t, std::size_t>> nm_edge_set;
  std::size_t nm_edges = 0, nm_vertices = 0, duplicated = 0, reversed = 0;
  std::size_t edge_a = 0, edge_b = 0, edge_n = 0, vertex = 0;
};
struct OrientVisitor : public PMP::Default_orientation_visitor {
  OrientLog *log;
  explicit OrientVisitor(OrientLog *l) : log(l) {}
  void non_manifold_edge(std::size_t a, std::size_t b, std::size_t n) {
    // reported once per polygon on the edge: count each edge once
    if (!log->nm_edge_set.insert(std::make_pair(std::min(a, b), std::max(a, b))).second) return;
    if (!log->nm_edges++) {
      log->edge_a = a;
      log->edge_b = b;
      log->edge_n = n;
    }
  }
  void non_manifold_vertex(std::size_t v, std::size_t) {
    if (!log->nm_vertices++) log->vertex = v;
  }
  void duplicated_vertex(std::size_t v, std::size_t) {
    if (!log->duplicated++ && !log->nm_vertices) log->vertex = v;
  }
  void polygon_orientation_reversed(std::size_t) { log->reversed++; }
};

// m's 2D elements as a polygon soup; false if m has volume elements.
bool to_soup(const vm_mesh *m, std::vector<Point> &pts, std::vector<Polygon> &polys) {
  pts.reserve(static_cast<size_t>(m->nv));
  for (int64_t v = 0; v < m->nv; v++)
    pts.emplace_back(m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2]);
  polys.reserve(static_cast<size_t>(m->ne));
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) return false;
    Polygon p;
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++)
      p.push_back(static_cast<std::size_t>(m->conn[k]));
    polys.push_back(std::move(p));
  }
  return true;
}

// Drop repeated consecutive vertices; a polygon left with < 3 distinct
// vertices (or a repeated one elsewhere) is removed. Returns the count.
std::size_t remove_invalid(std::vector<Polygon> &polys) {
  std::size_t removed = 0, k = 0;
  for (std::size_t i = 0; i < polys.size(); i++) {
    Polygon p;
    for (std::size_t a = 0; a < polys[i].size(); a++)
      if (p.empty() || p.back() != polys[i][a]) p.push_back(polys[i][a]);
    while (p.size() > 1 && p.front() == p.back()) p.pop_back();
    Polygon s = p;
    std::sort(s.begin(), s.end());
    bool bad = p.size() < 3 || std::adjacent_find(s.begin(), s.end()) != s.end();
    if (bad) {
      removed++;
      continue;
    }
    polys[k++] = std::move(p);
  }
  polys.resize(k);
  return removed;
}

// Where the items of the repaired mesh n came from in m: a vertex of n is
// the first vertex of m at exactly its coordinates (repair merges, stitches
// and collapses, but never moves a vertex it keeps); a triangle of n is the
// first element of m whose vertices (up to coincident copies) include its
// three. -1: new (the repair made it).
struct Origin {
  std::vector<int64_t> vertex, face;
  int64_t new_vertices = 0, new_faces = 0;
};

void find_origin(const vm_mesh *m, const vm_mesh *n, Origin &o) {
  typedef std::pair<std::array<double, 3>, int64_t> PointId;
  std::vector<PointId> pts;
  pts.reserve(static_cast<size_t>(m->nv));
  for (int64_t v = 0; v < m->nv; v++)
    pts.push_back(PointId({m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2]}, v));
  std::sort(pts.begin(), pts.end());
  // canon[v]: the first vertex of m at v's coordinates
  std::vector<int64_t> canon(static_cast<size_t>(m->nv));
  for (size_t i = 0; i < pts.size(); i++)
    canon[static_cast<size_t>(pts[i].second)] = i > 0 && pts[i].first == pts[i - 1].first
                                                    ? canon[static_cast<size_t>(pts[i - 1].second)]
                                                    : pts[i].second;
  o.vertex.assign(static_cast<size_t>(n->nv), -1);
  for (int64_t v = 0; v < n->nv; v++) {
    std::array<double, 3> x = {n->xyz[3 * v], n->xyz[3 * v + 1], n->xyz[3 * v + 2]};
    auto it = std::lower_bound(pts.begin(), pts.end(), PointId(x, INT64_MIN));
    if (it != pts.end() && it->first == x)
      o.vertex[static_cast<size_t>(v)] = canon[static_cast<size_t>(it->second)];
    else
      o.new_vertices++;
  }
  // every triangle an element of m can be cut into (quads: four), by its
  // sorted canonical vertices
  typedef std::pair<std::array<int64_t, 3>, int64_t> TriId;
  std::vector<TriId> tris;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    int k = static_cast<int>(m->eoff[e + 1] - m->eoff[e]);
    if (k != 3 && k != 4) continue;
    for (int skip = k == 3 ? 3 : 0; skip < 4; skip++) {
      std::array<int64_t, 3> t;
      int j = 0;
      for (int i = 0; i < k; i++)
        if (i != skip) t[static_cast<size_t>(j++)] = canon[static_cast<size_t>(c[i])];
      std::sort(t.begin(), t.end());
      tris.push_back(TriId(t, e));
    }
  }
  std::sort(tris.begin(), tris.end());
  o.face.assign(static_cast<size_t>(n->ne), -1);
  for (int64_t e = 0; e < n->ne; e++) {
    std::array<int64_t, 3> t;
    bool ok = true;
    for (int i = 0; i < 3; i++) {
      t[static_cast<size_t>(i)] = o.vertex[static_cast<size_t>(n->conn[3 * e + i])];
      ok = ok && t[static_cast<size_t>(i)] >= 0;
    }
    std::sort(t.begin(), t.end());
    auto it = std::lower_bound(tris.begin(), tris.end(), TriId(t, INT64_MIN));
    if (ok && it != tris.end() && it->first == t)
      o.face[static_cast<size_t>(e)] = it->second;
    else
      o.new_faces++;
  }
}

// m's fields, vertex flags and slip surfaces onto the repaired mesh n where
// every item of the field's location has an origin in m; a field with new
// items is dropped, said once (flags of new vertices stay free).
int map_fields(const vm_mesh *m, vm_mesh *n, const Origin &o) {
  vm_ctx *ctx = m->ctx;
  for (int64_t v = 0; v < n->nv; v++) {
    int64_t s = o.vertex[static_cast<size_t>(v)];
    if (s < 0) continue;
    n->vflag[v] = m->vflag[s];
    n->vsurf[v] = m->vsurf[s];
  }
  int dropped = 0;
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    bool vert = f->location == VM_FIELD_VERTEX;
    if (vert ? o.new_vertices : o.new_faces) {
      if (!dropped++)
        vm_log(ctx, VM_LOG_WARN,
               "repair: field '%s' dropped: %lld of its %lld %s are new (made by the repair); "
               "fields are kept where every %s came through the repair",
               f->name, static_cast<long long>(vert ? o.new_vertices : o.new_faces),
               static_cast<long long>(vert ? n->nv : n->ne), vert ? "vertices" : "faces",
               vert ? "vertex" : "face");
      else
        vm_log(ctx, VM_LOG_WARN, "repair: field '%s' dropped too", f->name);
      continue;
    }
    vm_field *g;
    int st = vm_mesh_add_field(n, f->name, f->location, f->type, f->ncomp, &g);
    if (st) return st;
    const std::vector<int64_t> &from = vert ? o.vertex : o.face;
    size_t row = (f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t)) *
                 static_cast<size_t>(f->ncomp);
    for (size_t k = 0; k < from.size(); k++)
      std::memcpy(static_cast<char *>(g->data) + k * row,
                  static_cast<const char *>(f->data) + static_cast<size_t>(from[k]) * row, row);
  }
  return VM_OK;
}

// m's arrays replaced by sm's (compact: garbage collected) triangles;
// attributes kept; fields and flags mapped (map_fields) if `map`, else
// dropped.
int replace_mesh(vm_mesh *m, const SMesh &sm, bool map) {
  vm_ctx *ctx = m->ctx;
  vm_mesh *n = NULL;
  int st = vm_mesh_create(ctx, &n);
  if (st) return st;
  n->dim = 3;
  std::vector<int32_t> idx(sm.number_of_vertices() + sm.number_of_removed_vertices(), -1);
  int64_t nv = 0;
  for (vertex_descriptor v : sm.vertices()) idx[v.idx()] = static_cast<int32_t>(nv++);
  if ((st = vm_mesh_set_vertices(n, nv))) goto fail;
  for (vertex_descriptor v : sm.vertices()) {
    const Point &p = sm.point(v);
    double *x = n->xyz + 3 * static_cast<int64_t>(idx[v.idx()]);
    x[0] = p.x();
    x[1] = p.y();
    x[2] = p.z();
  }
  {
    int64_t nf = static_cast<int64_t>(sm.number_of_faces());
    if ((st = vm_mesh_set_elements(n, nf, 3 * nf))) goto fail;
    int64_t e = 0;
    for (face_descriptor f : sm.faces()) {
      n->etype[e] = VM_TRI;
      n->eoff[e + 1] = n->eoff[e] + 3;
      int a = 0;
      for (vertex_descriptor v : CGAL::vertices_around_face(sm.halfedge(f), sm))
        n->conn[3 * e + a++] = idx[v.idx()];
      e++;
    }
  }
  for (int i = 0; i < m->nattr; i++)
    if ((st = vm_mesh_set_attr(n, m->attrs[i].key, m->attrs[i].value))) goto fail;
  if (map) {
    Origin o;
    find_origin(m, n, o);
    if ((st = map_fields(m, n, o))) goto fail;
  }
  {
    vm_mesh tmp = *m;
    *m = *n;
    *n = tmp;
  }
  vm_mesh_destroy(&n);
  return VM_OK;
fail:
  vm_mesh_destroy(&n);
  return st;
}

// sm with its vertices in the order of their coordinates and its faces in
// the order of their vertices (each starting at its least, its orientation
// kept): CGAL's corefinement and hole filling return the faces in an order
// that follows the heap's layout (the same input gave different files in
// different environments), and this order is the input's alone.
void canonical_order(SMesh &sm) {
  std::vector<vertex_descriptor> vs(sm.vertices().begin(), sm.vertices().end());
  std::sort(vs.begin(), vs.end(), [&](vertex_descriptor a, vertex_descriptor b) {
    const Point &p = sm.point(a), &q = sm.point(b);
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  });
  std::vector<std::size_t> rank(sm.number_of_vertices() + sm.number_of_removed_vertices());
  std::vector<Point> pts;
  pts.reserve(vs.size());
  for (std::size_t i = 0; i < vs.size(); i++) {
    rank[vs[i].idx()] = i;
    pts.push_back(sm.point(vs[i]));
  }
  std::vector<Polygon> polys;
  polys.reserve(sm.number_of_faces());
  for (face_descriptor f : sm.faces()) {
    Polygon p;
    for (vertex_descriptor v : CGAL::vertices_around_face(sm.halfedge(f), sm))
      p.push_back(rank[v.idx()]);
    std::rotate(p.begin(), std::min_element(p.begin(), p.end()), p.end());
    polys.push_back(std::move(p));
  }
  std::sort(polys.begin(), polys.end());
  SMesh out;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, out);
  sm = std::move(out);
}

// A triangle mesh from m (triangles only); false if a face cannot be added.
bool to_surface_mesh(const vm_mesh *m, SMesh &sm, int64_t *bad_elem) {
  std::vector<vertex_descriptor> vh;
  vh.reserve(static_cast<size_t>(m->nv));
  for (int64_t v = 0; v < m->nv; v++)
    vh.push_back(sm.add_vertex(Point(m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2])));
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    if (m->etype[e] != VM_TRI ||
        sm.add_face(vh[static_cast<size_t>(c[0])], vh[static_cast<size_t>(c[1])],
                    vh[static_cast<size_t>(c[2])]) == SMesh::null_face()) {
      *bad_elem = e;
      return false;
    }
  }
  return true;
}

// Face f's largest squared edge length and the squared norm of its doubled
// area vector.
void face_sizes(const SMesh &sm, face_descriptor f, double &l2, double &a4) {
  halfedge_descriptor h = sm.halfedge(f);
  const Point &a = sm.point(sm.source(h)), &b = sm.point(sm.target(h)),
              &c = sm.point(sm.target(sm.next(h)));
  K::Vector_3 u = b - a, v = c - a, w = c - b;
  l2 = std::max({u.squared_length(), v.squared_length(), w.squared_length()});
  a4 = CGAL::cross_product(u, v).squared_length();
}

// A face whose area or squared edge lengths overflow double precision
// (coordinates too large: not a zero area), or null.
face_descriptor overflowing_face(const SMesh &sm) {
  for (face_descriptor f : sm.faces()) {
    double l2, a4;
    face_sizes(sm, f, l2, a4);
    if (!std::isfinite(l2) || !std::isfinite(a4)) return f;
  }
  return SMesh::null_face();
}

// Faces whose doubled area is below 1e-12 times the squared longest edge.
std::size_t numerically_degenerate(const SMesh &sm) {
  std::size_t n = 0;
  for (face_descriptor f : sm.faces()) {
    double l2, a4;
    face_sizes(sm, f, l2, a4);
    if (!(std::sqrt(a4) > 1e-12 * l2)) n++;
  }
  return n;
}

Point face_centroid(const SMesh &sm, face_descriptor f) {
  double s[3] = {0, 0, 0};
  int n = 0;
  for (vertex_descriptor v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
    const Point &p = sm.point(v);
    s[0] += p.x();
    s[1] += p.y();
    s[2] += p.z();
    n++;
  }
  return Point(s[0] / n, s[1] / n, s[2] / n);
}

// Zero-area faces of sm removed (exactly, then to working precision) and
// isolated vertices; refused if some stay, nothing is left, or the surface
// has become non-manifold (stitching and collapses can make it so).
int remove_degenerate(vm_ctx *ctx, SMesh &sm, vm_repair_report *r) {
  {
    std::vector<face_descriptor> deg;
    PMP::degenerate_faces(sm, std::back_inserter(deg));
    r->removed_degenerate += static_cast<int64_t>(deg.size());
    if (!deg.empty() && !PMP::remove_degenerate_faces(sm))
      return vm_error(ctx, VM_ERR_FORMAT, "repair: %zu zero-area faces could not all be removed",
                      deg.size());
    // faces of zero area to working precision (not exactly collinear after
    // rounding): caps within 1e-6 rad of 180 degrees, needles of ratio 1e8
    std::size_t ndeg = numerically_degenerate(sm);
    if (ndeg > 0) {
      r->removed_degenerate += static_cast<int64_t>(ndeg);
      PMP::experimental::remove_almost_degenerate_faces(sm, -1.0 + 5e-13, 1e8, 0.0);
      std::size_t left = numerically_degenerate(sm);
      if (left > 0)
        return vm_error(ctx, VM_ERR_FORMAT,
                        "repair: %zu faces of zero area (to working precision) could not be "
                        "removed",
                        left);
    }
  }
  r->removed_isolated += static_cast<int64_t>(PMP::remove_isolated_vertices(sm));
  sm.collect_garbage();
  if (sm.number_of_faces() == 0)
    return vm_error(ctx, VM_ERR_FORMAT, "repair: no face left after removing degenerate ones");
  std::vector<halfedge_descriptor> nmv;
  PMP::non_manifold_vertices(sm, std::back_inserter(nmv));
  if (!nmv.empty()) {
    std::vector<std::size_t> ids;
    for (halfedge_descriptor h : nmv) ids.push_back(sm.target(h).idx());
    std::sort(ids.begin(), ids.end());
    std::size_t nids = static_cast<std::size_t>(std::unique(ids.begin(), ids.end()) - ids.begin());
    const Point &p = sm.point(vertex_descriptor(static_cast<SMesh::size_type>(ids.front())));
    return vm_error(ctx, VM_ERR_FORMAT,
                    "%zu non-manifold vertices after repair (faces meeting at a point); the "
                    "first at (%g, %g, %g)",
                    nids, p.x(), p.y(), p.z());
  }
  return VM_OK;
}

// Each component of sm (fcc, ncc of them) as a mesh of its own, oriented
// to bound a positive volume (one pass: a vertex of a manifold surface is
// in one component).
std::vector<SMesh> component_meshes(const SMesh &sm,
                                    const SMesh::Property_map<face_descriptor, std::size_t> &fcc,
                                    std::size_t ncc) {
  std::vector<SMesh> out(ncc);
  std::vector<vertex_descriptor> to(sm.number_of_vertices() + sm.number_of_removed_vertices(),
                                    SMesh::null_vertex());
  for (face_descriptor f : sm.faces()) {
    SMesh &o = out[fcc[f]];
    std::array<vertex_descriptor, 3> t;
    int a = 0;
    for (vertex_descriptor v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
      if (to[v.idx()] == SMesh::null_vertex()) to[v.idx()] = o.add_vertex(sm.point(v));
      t[static_cast<size_t>(a++)] = to[v.idx()];
    }
    o.add_face(t[0], t[1], t[2]);
  }
  for (SMesh &o : out)
    if (PMP::volume(o) < 0) PMP::reverse_face_orientations(o);
  return out;
}

// Append the triangles of b to a (a copy).
void append_mesh(SMesh &a, const SMesh &b) {
  std::vector<vertex_descriptor> to(b.number_of_vertices() + b.number_of_removed_vertices());
  for (vertex_descriptor v : b.vertices()) to[v.idx()] = a.add_vertex(b.point(v));
  for (face_descriptor f : b.faces()) {
    std::array<vertex_descriptor, 3> t;
    int k = 0;
    for (vertex_descriptor v : CGAL::vertices_around_face(b.halfedge(f), b))
      t[static_cast<size_t>(k++)] = to[v.idx()];
    a.add_face(t[0], t[1], t[2]);
  }
}

// The largest distance from a vertex or a face centroid of a to the
// surface b (one side of a Hausdorff distance, at those points).
double max_distance_to(const SMesh &a, const SMesh &b) {
  typedef CGAL::AABB_face_graph_triangle_primitive<SMesh> Prim;
  typedef CGAL::AABB_tree<CGAL::AABB_traits<K, Prim>> Tree;
  Tree tree(faces(b).first, faces(b).second, b);
  tree.accelerate_distance_queries();
  double d2 = 0;
  for (vertex_descriptor v : a.vertices()) d2 = std::max(d2, tree.squared_distance(a.point(v)));
  for (face_descriptor f : a.faces()) d2 = std::max(d2, tree.squared_distance(face_centroid(a, f)));
  return std::sqrt(d2);
}

// How far healing may move the surface, in local edge lengths: a coarse
// model's fold spans a face or two (a public 1,118-triangle airplane:
// 1.43), a spike pushed through a part many (a sphere's pole through its
// south side: 5.2).
const double heal_reach = 2;

// The closed components of sm that intersect themselves (pairs of faces of
// one component: a model's local folds, a T-junction closed by a cap that
// rounding turned over) healed: the crossing faces removed and the holes
// filled (CGAL's remove_self_intersections, per component). A component
// is healed only if the result is closed, intersects itself nowhere,
// bounds a volume and lies within heal_reach local edge lengths of the
// input both ways (the median length of the edges at the crossing faces'
// vertices); a part pushed through itself would be cut off: refused, with
// how far, sm unchanged. *healed: the components healed (0: none
// intersected itself, sm unchanged); *heal_pairs: their pairs; *moved:
// the largest distance between a healed component and its input.
int heal_components(vm_ctx *ctx, SMesh &sm,
                    const std::vector<std::pair<face_descriptor, face_descriptor>> &pairs,
                    const SMesh::Property_map<face_descriptor, std::size_t> &fcc, std::size_t ncc,
                    int64_t *healed, int64_t *heal_pairs, double *moved) {
  *healed = *heal_pairs = 0;
  *moved = 0;
  // per component: its pairs, and the local edge length: the median
  // length of the edges at the crossing faces' vertices (the crossing
  // faces' own edges are stretched by the fold; most edges there are not)
  std::vector<int64_t> npair(ncc, 0);
  std::vector<face_descriptor> first(ncc);
  std::vector<std::vector<double>> len(ncc);
  std::vector<char> seen(sm.number_of_vertices() + sm.number_of_removed_vertices(), 0);
  for (const auto &p : pairs) {
    std::size_t c = fcc[p.first];
    if (c != fcc[p.second]) continue;
    if (!npair[c]++) first[c] = p.first;
    for (face_descriptor f : {p.first, p.second})
      for (vertex_descriptor v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
        if (seen[v.idx()]) continue;
        seen[v.idx()] = 1;
        for (halfedge_descriptor h : CGAL::halfedges_around_target(v, sm))
          len[c].push_back(std::sqrt(CGAL::squared_distance(sm.point(sm.source(h)), sm.point(v))));
      }
  }
  std::size_t nself = 0;
  for (std::size_t c = 0; c < ncc; c++) nself += npair[c] > 0;
  if (!nself) return VM_OK;
  std::vector<SMesh> comp = component_meshes(sm, fcc, ncc);
  for (std::size_t c = 0; c < ncc; c++) {
    if (!npair[c]) continue;
    std::vector<double> &l = len[c];
    std::nth_element(l.begin(), l.begin() + static_cast<std::ptrdiff_t>(l.size() / 2), l.end());
    double edge = l[l.size() / 2], tol = heal_reach * edge;
    SMesh h = comp[c];
    bool ok =
        PMP::experimental::remove_self_intersections(h, CGAL::parameters::preserve_genus(false));
    h.collect_garbage();
    const char *why = NULL;
    double d = 0;
    if (!ok || h.is_empty() || !CGAL::is_closed(h) || PMP::does_self_intersect(h))
      why = "the crossing faces could not be removed and the holes filled";
    else if (!PMP::does_bound_a_volume(h))
      why = "the healed part does not bound a volume";
    else if ((d = std::max(max_distance_to(comp[c], h), max_distance_to(h, comp[c]))) > tol)
      why = "healing would move the surface by more than twice the local edge length";
    if (why) {
      Point p = face_centroid(sm, first[c]);
      return vm_error(ctx, VM_ERR_FORMAT,
                      "self-intersecting surface: %zu pairs of faces intersect, %lld of them "
                      "within one closed component, which intersects itself near (%g, %g, %g): "
                      "%s (moved %g, local edge length %g); repair the model",
                      pairs.size(), static_cast<long long>(npair[c]), p.x(), p.y(), p.z(), why, d,
                      edge);
    }
    if (PMP::volume(h) < 0) PMP::reverse_face_orientations(h);
    comp[c] = std::move(h);
    *moved = std::max(*moved, d);
    (*healed)++;
    *heal_pairs += npair[c];
  }
  SMesh out;
  for (const SMesh &c : comp) append_mesh(out, c);
  sm = std::move(out);
  return VM_OK;
}

// The closed components of sm that overlap (a face of one intersects a
// face of another: pairs) or nest (one inside another) replaced by their
// union (CGAL corefinement, pairwise in rounds, the largest volumes
// first); the others kept as they are. A component that intersects itself
// cannot be united: refused. *united: the components the union took in
// (0: none overlapped or nested, sm unchanged); *cavities: the voids the
// union enclosed (inward shells), dropped.
int unite_components(vm_ctx *ctx, SMesh &sm,
                     const std::vector<std::pair<face_descriptor, face_descriptor>> &pairs,
                     const SMesh::Property_map<face_descriptor, std::size_t> &fcc, std::size_t ncc,
                     int64_t *united, int64_t *cavities) {
  *united = *cavities = 0;
  for (const auto &p : pairs)
    if (fcc[p.first] == fcc[p.second]) {
      Point c = face_centroid(sm, p.first);
      return vm_error(ctx, VM_ERR_FORMAT,
                      "self-intersecting surface: %zu pairs of faces intersect, and a closed "
                      "component intersects itself (it cannot be united with the others); e.g. "
                      "near (%g, %g, %g)",
                      pairs.size(), c.x(), c.y(), c.z());
    }
  if (ncc < 2) return VM_OK;
  std::vector<char> in(ncc, 0);
  for (const auto &p : pairs) in[fcc[p.first]] = in[fcc[p.second]] = 1;
  std::vector<SMesh> comp = component_meshes(sm, fcc, ncc);
  std::vector<CGAL::Bbox_3> box(ncc);
  for (std::size_t c = 0; c < ncc; c++) box[c] = PMP::bbox(comp[c]);
  // nesting: a vertex of i inside j (i's box within j's); i and j do not
  // intersect, so one vertex tells for the whole of i. Up to 256
  // components (each pair a box test; a point query only when nested boxes)
  if (ncc <= 256) {
    for (std::size_t j = 0; j < ncc; j++) {
      std::unique_ptr<CGAL::Side_of_triangle_mesh<SMesh, K>> side;
      for (std::size_t i = 0; i < ncc; i++) {
        if (i == j || (in[i] && in[j])) continue;
        const CGAL::Bbox_3 &a = box[i], &b = box[j];
        if (!(a.xmin() >= b.xmin() && a.xmax() <= b.xmax() && a.ymin() >= b.ymin() &&
              a.ymax() <= b.ymax() && a.zmin() >= b.zmin() && a.zmax() <= b.zmax()))
          continue;
        if (!side) side.reset(new CGAL::Side_of_triangle_mesh<SMesh, K>(comp[j]));
        if ((*side)(comp[i].point(*comp[i].vertices().begin())) == CGAL::ON_BOUNDED_SIDE)
          in[i] = in[j] = 1;
      }
    }
  }
  // the united ones, largest volume first, merged pairwise in rounds (each
  // round copies every triangle once: N log k for k components, not N k)
  std::vector<std::pair<double, std::size_t>> order;
  for (std::size_t c = 0; c < ncc; c++)
    if (in[c]) order.emplace_back(-PMP::volume(comp[c]), c);
  *united = static_cast<int64_t>(order.size());
  if (order.empty()) return VM_OK;
  std::sort(order.begin(), order.end());
  std::vector<SMesh> work;
  for (const auto &oc : order) work.push_back(std::move(comp[oc.second]));
  while (work.size() > 1) {
    std::vector<SMesh> next;
    for (std::size_t i = 0; i + 1 < work.size(); i += 2) {
      SMesh out;
      if (!PMP::corefine_and_compute_union(work[i], work[i + 1], out) || out.is_empty() ||
          PMP::does_self_intersect(out)) {
        Point p = work[i + 1].point(*work[i + 1].vertices().begin());
        return vm_error(ctx, VM_ERR_FORMAT,
                        "self-intersecting surface: %zu pairs of faces intersect, and the union "
                        "of its overlapping closed components failed (not a manifold surface, "
                        "or it intersects itself after rounding) at the component through (%g, "
                        "%g, %g)",
                        pairs.size(), p.x(), p.y(), p.z());
      }
      out.collect_garbage();
      next.push_back(std::move(out));
    }
    if (work.size() % 2) next.push_back(std::move(work.back()));
    work = std::move(next);
  }
  SMesh u = std::move(work.front());
  // the union of parts that overlap can enclose voids (between a wing, a
  // fuselage and a fairing): closed shells oriented inwards, negative
  // volume, inside the union's outer shell; no layer grows into them
  {
    auto ucc = u.add_property_map<face_descriptor, std::size_t>("f:vm_ucc").first;
    std::size_t nu = PMP::connected_components(u, ucc);
    std::vector<double> vol(nu, 0);
    for (face_descriptor f : u.faces()) {
      halfedge_descriptor h = u.halfedge(f);
      const Point &a = u.point(u.source(h)), &b = u.point(u.target(h)),
                  &c = u.point(u.target(u.next(h)));
      vol[ucc[f]] += CGAL::scalar_product(a - CGAL::ORIGIN,
                                          CGAL::cross_product(b - CGAL::ORIGIN, c - CGAL::ORIGIN));
    }
    std::vector<std::size_t> drop;
    for (std::size_t c = 0; c < nu; c++)
      if (vol[c] < 0) drop.push_back(c);
    if (!drop.empty() && drop.size() < nu) {
      PMP::remove_connected_components(u, drop, ucc);
      u.collect_garbage();
      *cavities = static_cast<int64_t>(drop.size());
    }
    u.remove_property_map(ucc);
  }
  for (std::size_t c = 0; c < ncc; c++)
    if (!in[c]) append_mesh(u, comp[c]);
  sm = std::move(u);
  return VM_OK;
}

} // namespace

extern "C" vm_repair_opts vm_repair_opts_default(void) {
  vm_repair_opts o;
  o.require_closed = 1;
  o.check_self_intersections = 1;
  o.union_overlaps = 1;
  o.heal_self = 1;
  return o;
}

extern "C" vm_remesh_opts vm_remesh_opts_default(void) {
  vm_remesh_opts o;
  o.target_edge_length = 0;
  o.iterations = 5;
  o.relaxation_steps = 1;
  o.keep_angle = 10;
  return o;
}

extern "C" int vm_surface_repair(vm_mesh *m, const vm_repair_opts *opts, vm_repair_report *rep) {
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_repair_opts o = opts ? *opts : vm_repair_opts_default();
  vm_repair_report r;
  std::memset(&r, 0, sizeof r);
  r.self_intersections = -1;
  if (rep) *rep = r;
  // a refusal's reason, in the report the caller gets
  auto refuse = [&](int why) {
    r.refused = why;
    if (rep) *rep = r;
  };
  VM_CXX_BEGIN
  std::vector<Point> pts;
  std::vector<Polygon> polys;
  if (!to_soup(m, pts, polys))
    return vm_error(ctx, VM_ERR_ARG, "repair: the mesh has volume elements");
  r.nv_in = m->nv;
  r.nf_in = static_cast<int64_t>(polys.size());
  if (polys.empty()) {
    refuse(VM_REPAIR_EMPTY);
    return vm_error(ctx, VM_ERR_FORMAT, "repair: the surface has no faces");
  }

  r.merged_vertices = static_cast<int64_t>(PMP::merge_duplicate_points_in_polygon_soup(pts, polys));
  r.removed_polygons = static_cast<int64_t>(remove_invalid(polys));
  r.removed_polygons +=
      static_cast<int64_t>(PMP::merge_duplicate_polygons_in_polygon_soup(pts, polys));
  r.removed_isolated =
      static_cast<int64_t>(PMP::remove_isolated_points_in_polygon_soup(pts, polys));
  if (polys.empty())
    return refuse(VM_REPAIR_EMPTY),
           vm_error(ctx, VM_ERR_FORMAT, "repair: no valid face left (all %lld were degenerate)",
                    static_cast<long long>(r.nf_in));

  const std::size_t npts = pts.size();
  OrientLog vis;
  bool ok = PMP::orient_polygon_soup(pts, polys, CGAL::parameters::visitor(OrientVisitor(&vis)));
  r.reoriented = static_cast<int64_t>(vis.reversed);
  if (vis.nm_edges) {
    const Point &a = pts[vis.edge_a], &b = pts[vis.edge_b];
    refuse(VM_REPAIR_NONMANIFOLD);
    return vm_error(ctx, VM_ERR_FORMAT,
                    "non-manifold surface: %zu edges are shared by more than two faces; the "
                    "first, (%g, %g, %g)-(%g, %g, %g), by %zu",
                    vis.nm_edges, a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), vis.edge_n);
  }
  if (vis.nm_vertices || !ok || pts.size() != npts) {
    const Point &p = pts[std::min(vis.vertex, npts - 1)];
    refuse(VM_REPAIR_NONMANIFOLD);
    return vm_error(ctx, VM_ERR_FORMAT,
                    "the surface cannot be made manifold and consistently oriented without "
                    "cutting it at %zu vertices (non-manifold vertex, or a non-orientable "
                    "surface); the first at (%g, %g, %g)",
                    std::max<std::size_t>(pts.size() - npts, 1), p.x(), p.y(), p.z());
  }

  SMesh sm;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, sm);
  PMP::triangulate_faces(sm);
  r.stitched = static_cast<int64_t>(PMP::stitch_borders(sm));
  {
    face_descriptor big = overflowing_face(sm);
    if (big != SMesh::null_face()) {
      Point c = face_centroid(sm, big);
      refuse(VM_REPAIR_RANGE);
      return vm_error(ctx, VM_ERR_FORMAT,
                      "repair: the area of the face near (%g, %g, %g) overflows double "
                      "precision (coordinates too large); scale the surface down",
                      c.x(), c.y(), c.z());
    }
  }
  int st = remove_degenerate(ctx, sm, &r);
  if (st) return st;

  std::vector<halfedge_descriptor> cycles;
  PMP::extract_boundary_cycles(sm, std::back_inserter(cycles));
  r.holes = static_cast<int64_t>(cycles.size());
  for (halfedge_descriptor h : sm.halfedges())
    if (sm.is_border(h)) r.border_edges++;
  auto fcc = sm.add_property_map<face_descriptor, std::size_t>("f:vm_cc").first;
  r.components = static_cast<int64_t>(PMP::connected_components(sm, fcc));
  if (r.border_edges > 0 && o.require_closed) {
    refuse(VM_REPAIR_OPEN); // the caller can tell an open surface from other errors
    halfedge_descriptor h = cycles.front();
    const Point &a = sm.point(sm.source(h)), &b = sm.point(sm.target(h));
    return vm_error(ctx, VM_ERR_FORMAT,
                    "open surface: %lld border edges around %lld hole(s); e.g. the border edge "
                    "(%g, %g, %g)-(%g, %g, %g)",
                    static_cast<long long>(r.border_edges), static_cast<long long>(r.holes), a.x(),
                    a.y(), a.z(), b.x(), b.y(), b.z());
  }

  if (o.check_self_intersections) {
    std::vector<std::pair<face_descriptor, face_descriptor>> pairs;
    PMP::self_intersections(sm, std::back_inserter(pairs));
    r.self_intersections = static_cast<int64_t>(pairs.size());
    // after the healing or the union sm is a new mesh: its degenerate faces
    // removed, its border, pairs and component map found again
    auto renewed = [&]() -> int {
      int s2 = remove_degenerate(ctx, sm, &r);
      if (s2) return s2;
      r.border_edges = 0;
      for (halfedge_descriptor h : sm.halfedges())
        if (sm.is_border(h)) r.border_edges++;
      pairs.clear();
      PMP::self_intersections(sm, std::back_inserter(pairs));
      r.self_intersections = static_cast<int64_t>(pairs.size());
      fcc = sm.add_property_map<face_descriptor, std::size_t>("f:vm_cc").first;
      return VM_OK;
    };
    if (o.heal_self && r.border_edges == 0 && !pairs.empty()) {
      int64_t healed = 0, hpairs = 0;
      double moved = 0;
      if ((st = heal_components(ctx, sm, pairs, fcc, static_cast<std::size_t>(r.components),
                                &healed, &hpairs, &moved))) {
        if (st == VM_ERR_FORMAT) refuse(VM_REPAIR_CROSSING);
        return st;
      }
      if (healed) {
        r.healed = healed;
        r.heal_pairs = hpairs;
        r.heal_moved = moved;
        if ((st = renewed())) return st;
        r.components = static_cast<int64_t>(PMP::connected_components(sm, fcc));
        vm_log(ctx, VM_LOG_WARN,
               "repair: %lld closed components intersected themselves (%lld pairs of faces): "
               "their crossing faces removed and the holes filled, the surface moved by at most "
               "%g",
               static_cast<long long>(healed), static_cast<long long>(hpairs), moved);
      }
    }
    if (o.union_overlaps && r.border_edges == 0 && r.components > 1) {
      int64_t united = 0, cavities = 0;
      if ((st = unite_components(ctx, sm, pairs, fcc, static_cast<std::size_t>(r.components),
                                 &united, &cavities))) {
        if (st == VM_ERR_FORMAT) refuse(VM_REPAIR_CROSSING);
        return st;
      }
      if (united) {
        r.united = united;
        r.union_pairs = static_cast<int64_t>(pairs.size());
        if ((st = renewed())) return st;
        std::size_t left = PMP::connected_components(sm, fcc);
        vm_log(ctx, VM_LOG_WARN,
               "repair: %lld of the %lld closed components %s (%lld pairs of faces intersected): "
               "replaced by their union, %lld triangles (%lld voids it enclosed dropped); %zu "
               "components left (--no-union: not united)",
               static_cast<long long>(united), static_cast<long long>(r.components),
               r.union_pairs ? "overlap or lie inside one another" : "lie inside one another",
               static_cast<long long>(r.union_pairs), static_cast<long long>(sm.number_of_faces()),
               static_cast<long long>(cavities), left);
        r.components = static_cast<int64_t>(left);
        if (r.border_edges > 0)
          return refuse(VM_REPAIR_CROSSING),
                 vm_error(ctx, VM_ERR_FORMAT,
                          "repair: the union of the overlapping components is open (%lld border "
                          "edges)",
                          static_cast<long long>(r.border_edges));
      }
    }
    if (!pairs.empty()) {
      std::sort(pairs.begin(), pairs.end());
      Point c = face_centroid(sm, pairs.front().first);
      if (o.require_closed)
        return refuse(VM_REPAIR_CROSSING),
               vm_error(ctx, VM_ERR_FORMAT,
                        "self-intersecting surface: %zu pairs of faces intersect; e.g. near "
                        "(%g, %g, %g)",
                        pairs.size(), c.x(), c.y(), c.z());
      vm_log(ctx, VM_LOG_WARN, "repair: %zu pairs of faces intersect; e.g. near (%g, %g, %g)",
             pairs.size(), c.x(), c.y(), c.z());
    }
  }

  if (r.border_edges == 0) {
    std::vector<K::Vector_3> before;
    before.reserve(sm.number_of_faces());
    for (face_descriptor f : sm.faces()) before.push_back(PMP::compute_face_normal(f, sm));
    if (r.self_intersections == 0)
      PMP::orient_to_bound_a_volume(sm);
    else
      PMP::orient(sm);
    std::size_t i = 0;
    for (face_descriptor f : sm.faces())
      if (before[i++] * PMP::compute_face_normal(f, sm) < 0) r.reoriented++;
    r.volume = PMP::volume(sm);
  }
  sm.remove_property_map(fcc);
  if (r.united || r.healed) canonical_order(sm);

  r.nv = static_cast<int64_t>(sm.number_of_vertices());
  r.nf = static_cast<int64_t>(sm.number_of_faces());
  st = replace_mesh(m, sm, true);
  if (st) return st;
  if (rep) *rep = r;
  return VM_OK;
  VM_CXX_END(ctx, "repair")
}

extern "C" int vm_surface_wrap(vm_mesh *m, double alpha, double offset, vm_wrap_report *rep) {
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_wrap_report r;
  std::memset(&r, 0, sizeof r);
  r.alpha = alpha;
  r.offset = offset;
  if (rep) *rep = r;
  if (!(alpha > 0) || !(offset > 0) || !std::isfinite(alpha) || !std::isfinite(offset))
    return vm_error(ctx, VM_ERR_ARG, "wrap: alpha %g and offset %g must be positive", alpha,
                    offset);
  VM_CXX_BEGIN
  auto t0 = std::chrono::steady_clock::now();
  std::vector<Point> pts;
  std::vector<Polygon> polys;
  if (!to_soup(m, pts, polys))
    return vm_error(ctx, VM_ERR_ARG, "wrap: the mesh has volume elements");
  r.nv_in = m->nv;
  r.nf_in = static_cast<int64_t>(polys.size());
  std::vector<std::array<std::size_t, 3>> tris;
  tris.reserve(polys.size());
  for (const Polygon &p : polys)
    for (std::size_t k = 1; k + 1 < p.size(); k++) tris.push_back({p[0], p[k], p[k + 1]});
  if (tris.empty()) return vm_error(ctx, VM_ERR_ARG, "wrap: the surface has no faces");
  SMesh wrap;
  CGAL::alpha_wrap_3(pts, tris, alpha, offset, wrap);
  if (wrap.number_of_faces() == 0)
    return vm_error(ctx, VM_ERR_BACKEND, "wrap: alpha wrapping gave no surface");
  int st = replace_mesh(m, wrap, false);
  if (st) return st;
  r.nv = m->nv;
  r.nf = m->ne;
  r.elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (rep) *rep = r;
  return VM_OK;
  VM_CXX_END(ctx, "wrap")
}

extern "C" int vm_surface_self_intersections(const vm_mesh *m, int64_t *count, int32_t **pairs) {
  if (!m || !count) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  *count = 0;
  if (pairs) *pairs = NULL;
  VM_CXX_BEGIN
  SMesh sm;
  int64_t bad = -1;
  if (!to_surface_mesh(m, sm, &bad))
    return vm_error(ctx, VM_ERR_ARG,
                    "self-intersections: element %lld is not a triangle of a manifold surface",
                    static_cast<long long>(bad));
  std::vector<std::pair<face_descriptor, face_descriptor>> fp;
  PMP::self_intersections(sm, std::back_inserter(fp));
  std::vector<std::pair<int32_t, int32_t>> ip;
  ip.reserve(fp.size());
  for (auto &p : fp) {
    int32_t a = static_cast<int32_t>(p.first.idx()), b = static_cast<int32_t>(p.second.idx());
    ip.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(ip.begin(), ip.end());
  *count = static_cast<int64_t>(ip.size());
  if (pairs) {
    int32_t *out =
        static_cast<int32_t *>(vm_alloc_array(ctx, 2 * (ip.size() ? ip.size() : 1), sizeof *out));
    if (!out) return VM_ERR_NOMEM;
    for (std::size_t i = 0; i < ip.size(); i++) {
      out[2 * i] = ip[i].first;
      out[2 * i + 1] = ip[i].second;
    }
    *pairs = out;
  }
  return VM_OK;
  VM_CXX_END(ctx, "self-intersections")
}

extern "C" int vm_surface_remesh(vm_mesh *m, vm_surface_features *f, const vm_remesh_opts *o,
                                 double corner_deg) {
  if (!m || !o) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  if (!(o->target_edge_length > 0) || !std::isfinite(o->target_edge_length) || o->iterations < 1 ||
      o->relaxation_steps < 0 || !(o->keep_angle >= 0))
    return vm_error(ctx, VM_ERR_ARG, "remesh: target edge length %g, %d iterations",
                    o->target_edge_length, o->iterations);
  if (f && f->nv != m->nv)
    return vm_error(ctx, VM_ERR_ARG, "remesh: the features belong to another mesh");
  VM_CXX_BEGIN
  SMesh sm;
  int64_t bad = -1;
  if (!to_surface_mesh(m, sm, &bad))
    return vm_error(ctx, VM_ERR_ARG,
                    "remesh: element %lld is not a triangle of a manifold surface (repair first)",
                    static_cast<long long>(bad));
  auto ecm = sm.add_property_map<edge_descriptor, bool>("e:vm_constrained", false).first;
  auto vcm = sm.add_property_map<vertex_descriptor, bool>("v:vm_constrained", false).first;
  auto vcorner = sm.add_property_map<vertex_descriptor, bool>("v:vm_corner", false).first;
  if (f) {
    for (int64_t k = 0; k < f->nedge; k++) {
      halfedge_descriptor h =
          sm.halfedge(vertex_descriptor(static_cast<SMesh::size_type>(f->edge[2 * k])),
                      vertex_descriptor(static_cast<SMesh::size_type>(f->edge[2 * k + 1])));
      if (h == SMesh::null_halfedge())
        return vm_error(ctx, VM_ERR_ARG, "remesh: feature edge %lld is not a mesh edge",
                        static_cast<long long>(k));
      ecm[sm.edge(h)] = true;
    }
    for (int64_t v = 0; v < m->nv; v++)
      if (f->vclass[v] == VM_FEATURE_CORNER)
        vcm[vertex_descriptor(static_cast<SMesh::size_type>(v))] =
            vcorner[vertex_descriptor(static_cast<SMesh::size_type>(v))] = true;
    // line vertices where the line bends: kept, so collapses only straighten
    // nearly straight stretches (the chord error stays small)
    std::vector<std::vector<int32_t>> nb(static_cast<std::size_t>(m->nv));
    for (int64_t k = 0; k < f->nedge; k++) {
      nb[static_cast<std::size_t>(f->edge[2 * k])].push_back(f->edge[2 * k + 1]);
      nb[static_cast<std::size_t>(f->edge[2 * k + 1])].push_back(f->edge[2 * k]);
    }
    const double ckeep = std::cos(o->keep_angle * 3.14159265358979323846 / 180);
    for (int64_t v = 0; v < m->nv; v++) {
      const std::vector<int32_t> &n = nb[static_cast<std::size_t>(v)];
      if (f->vclass[v] != VM_FEATURE_LINE || n.size() != 2) continue;
      const double *p = m->xyz + 3 * v, *a = m->xyz + 3 * static_cast<int64_t>(n[0]),
                   *b = m->xyz + 3 * static_cast<int64_t>(n[1]);
      double u[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]},
             w[3] = {b[0] - p[0], b[1] - p[1], b[2] - p[2]};
      double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
      double lw = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
      if (lu > 0 && lw > 0 && (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (lu * lw) < ckeep)
        vcm[vertex_descriptor(static_cast<SMesh::size_type>(v))] = true;
    }
  }
  PMP::isotropic_remeshing(
      faces(sm), o->target_edge_length, sm,
      CGAL::parameters::number_of_iterations(static_cast<unsigned>(o->iterations))
          .number_of_relaxation_steps(static_cast<unsigned>(o->relaxation_steps))
          .edge_is_constrained_map(ecm)
          .vertex_is_constrained_map(vcm)
          .protect_constraints(false)
          .collapse_constraints(true)
          .relax_constraints(false));
  sm.collect_garbage();
  // Feature vertices are not relaxed along their lines: CGAL 5.5 then also
  // moves constrained vertices (corners).
  // the new mesh's features: constrained edges and corners, in the new numbering
  std::vector<int32_t> fe;
  std::vector<uint8_t> corner(sm.number_of_vertices(), 0);
  for (edge_descriptor e : sm.edges())
    if (ecm[e] || sm.is_border(e)) {
      fe.push_back(static_cast<int32_t>(sm.source(sm.halfedge(e)).idx()));
      fe.push_back(static_cast<int32_t>(sm.target(sm.halfedge(e)).idx()));
    }
  for (vertex_descriptor v : sm.vertices())
    if (vcorner[v]) corner[v.idx()] = 1;
  if (m->nfield > 0)
    vm_log(ctx, VM_LOG_WARN, "remesh: %d fields dropped (the vertices are new)", m->nfield);
  int st = replace_mesh(m, sm, false);
  if (st) return st;
  if (f) {
    vm_surface_features_free(ctx, f);
    st = vm_surface_features_from_edges(m, static_cast<int64_t>(fe.size() / 2), fe.data(),
                                        corner.data(), corner_deg, f);
    if (st) return st;
  }
  return VM_OK;
  VM_CXX_END(ctx, "remesh")
}
