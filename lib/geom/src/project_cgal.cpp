// lib/geom/src/project_cgal.cpp: CGAL adapter: closest-point projection onto
// a reference surface and its feature lines (AABB trees) for the
// minimizer's slip vertices, point-to-surface distances, Hausdorff.
#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Ray_3.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <memory>
#include <unordered_map>
#include <vector>

#include "cxx_private.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"

namespace {

// plain double arithmetic: the queries lie on the surface, where the
// filtered predicates of Epick keep falling back to exact arithmetic
typedef CGAL::Simple_cartesian<double> K;
typedef K::Point_3 Point;
typedef K::Vector_3 Vector;
typedef K::Triangle_3 Triangle;
typedef K::Segment_3 Segment;
typedef std::vector<Triangle>::const_iterator TriIt;
typedef CGAL::AABB_triangle_primitive<K, TriIt> TriPrim;
typedef CGAL::AABB_tree<CGAL::AABB_traits<K, TriPrim>> TriTree;
typedef std::vector<Segment>::const_iterator SegIt;
typedef CGAL::AABB_segment_primitive<K, SegIt> SegPrim;
typedef CGAL::AABB_tree<CGAL::AABB_traits<K, SegPrim>> SegTree;

// Triangles of the 2D elements of m (quads split along 0-2), their
// vertex indices and, if te is given, the element each came from;
// degenerate triangles break the AABB distance code and are left out.
void collect_triangles(const vm_mesh *m, std::vector<Triangle> &tri, std::vector<int32_t> &tv,
                       std::vector<int64_t> *te = nullptr) {
  int64_t elem = 0;
  auto P = [m](int32_t v) {
    const double *x = m->xyz + 3 * static_cast<int64_t>(v);
    return Point(x[0], x[1], x[2]);
  };
  auto add = [&](int32_t a, int32_t b, int32_t c) {
    Triangle t(P(a), P(b), P(c));
    if (t.is_degenerate()) return;
    tri.push_back(t);
    tv.push_back(a);
    tv.push_back(b);
    tv.push_back(c);
    if (te) te->push_back(elem);
  };
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    elem = e;
    if (m->etype[e] == VM_TRI) {
      add(c[0], c[1], c[2]);
    } else if (m->etype[e] == VM_QUAD) {
      add(c[0], c[1], c[2]);
      add(c[0], c[2], c[3]);
    }
  }
}

struct TriSurface {
  std::vector<Triangle> tri;
  std::vector<int32_t> tv;
  std::vector<int64_t> te; // the element of m each triangle came from
  std::vector<Vector> normal;
  std::unique_ptr<TriTree> tree;
  int64_t nv = 0;
  void build(const vm_mesh *m) {
    nv = m->nv;
    collect_triangles(m, tri, tv, &te);
    normal.reserve(tri.size());
    for (const Triangle &t : tri) {
      Vector n = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
      double l = std::sqrt(n.squared_length());
      normal.push_back(l > 0 ? n / l : Vector(0, 0, 0));
    }
    tree.reset(new TriTree(tri.begin(), tri.end()));
    tree->accelerate_distance_queries();
  }
};

// Closest point of segment s to p, and the segment parameter t in [0, 1].
Point closest_on_segment(const Segment &s, const Point &p, double *t) {
  Vector d = s.target() - s.source();
  double l2 = d.squared_length();
  double u = l2 > 0 ? ((p - s.source()) * d) / l2 : 0.0;
  u = u < 0 ? 0 : u > 1 ? 1 : u;
  *t = u;
  return s.source() + u * d;
}

// Two unit vectors orthogonal to the unit direction t.
void orthogonal_pair(const double t[3], double n[6]) {
  double a[3] = {0, 0, 0};
  int k = std::fabs(t[0]) <= std::fabs(t[1]) && std::fabs(t[0]) <= std::fabs(t[2]) ? 0
          : std::fabs(t[1]) <= std::fabs(t[2])                                     ? 1
                                                                                   : 2;
  a[k] = 1;
  double u[3] = {t[1] * a[2] - t[2] * a[1], t[2] * a[0] - t[0] * a[2], t[0] * a[1] - t[1] * a[0]};
  double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int i = 0; i < 3; i++) u[i] /= lu;
  double w[3] = {t[1] * u[2] - t[2] * u[1], t[2] * u[0] - t[0] * u[2], t[0] * u[1] - t[1] * u[0]};
  for (int i = 0; i < 3; i++) {
    n[i] = u[i];
    n[3 + i] = w[i];
  }
}

} // namespace

// lines up to this many segments are scanned whole
constexpr std::size_t kLineScan = 32;

struct vm_surface_projector {
  vm_ctx *ctx;
  TriSurface surf;
  // feature lines: segments of line k are seg[lstart[k] .. lstart[k+1])
  std::vector<Segment> seg;
  std::vector<int32_t> seg_line;
  std::vector<std::size_t> lstart;
  std::unique_ptr<SegTree> segtree;
  // a tree per line of more than kLineScan segments (line k: ltree[k - 1]):
  // its candidates near the query, in index order, are scanned as the
  // whole line would be, so a long line costs a logarithm, not its length
  std::vector<std::unique_ptr<SegTree>> ltree;
  std::vector<Point> corner;
  int32_t nline = 0;
};

extern "C" {
static int project_cb(void *user, int surf_id, const double p[3], double out[3], double normals[9]);
static int project_hinted_cb(void *user, int surf_id, const double p[3], int64_t *hint,
                             double out[3], double normals[9]);
}

// The closest point of the surface to q and its triangle: from the hint
// triangle's closest point if *hint is one (and then *hint updated).
static TriTree::Point_and_primitive_id closest(const vm_surface_projector *p, const Point &q,
                                               int64_t *hint) {
  const std::vector<Triangle> &tri = p->surf.tri;
  TriTree::Point_and_primitive_id cp;
  if (hint && *hint >= 0 && static_cast<std::size_t>(*hint) < tri.size()) {
    TriIt h = tri.begin() + static_cast<std::ptrdiff_t>(*hint);
    Point c = K::Construct_projected_point_3()(*h, q);
    cp = p->surf.tree->closest_point_and_primitive(q, TriTree::Point_and_primitive_id(c, h));
  } else {
    cp = p->surf.tree->closest_point_and_primitive(q);
  }
  if (hint) *hint = static_cast<int64_t>(cp.second - tri.begin());
  return cp;
}

// The projection; on the surface (id 0) *hint, if not NULL, is the index
// of a triangle: the closest point on it bounds the tree's search from the
// start (instead of the nearest of the tree's sample points, which on long
// thin triangles is far off), and it is replaced by the triangle found.
static int project_impl(vm_surface_projector *pr, int surf_id, const double p[3], int64_t *hint,
                        double out[3], double normals[9]) {
  VM_CXX_BEGIN
  if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return VM_ERR_NUMERIC;
  Point q(p[0], p[1], p[2]);
  if (surf_id == 0) {
    if (pr->surf.tri.empty()) return VM_ERR_ARG;
    auto cp = closest(pr, q, hint);
    std::size_t fi = static_cast<std::size_t>(cp.second - pr->surf.tri.begin());
    out[0] = cp.first.x();
    out[1] = cp.first.y();
    out[2] = cp.first.z();
    const Vector &n = pr->surf.normal[fi];
    normals[0] = n.x();
    normals[1] = n.y();
    normals[2] = n.z();
    return 1;
  }
  if (surf_id < 0 || surf_id > pr->nline) return VM_ERR_ARG;
  std::size_t b = pr->lstart[static_cast<std::size_t>(surf_id) - 1],
              e = pr->lstart[static_cast<std::size_t>(surf_id)];
  if (b == e) return VM_ERR_ARG;
  // the segments that can be closest: all of a short line; of a long one
  // those whose boxes meet a box around q a little larger than the
  // distance its tree finds (every segment at that distance is in, so the
  // scan below picks what the scan of the whole line would)
  std::vector<std::size_t> cand;
  const SegTree *lt =
      pr->ltree.empty() ? nullptr : pr->ltree[static_cast<std::size_t>(surf_id) - 1].get();
  if (lt) {
    double r = std::sqrt(lt->squared_distance(q));
    r = r * (1 + 1e-6) + 1e-12 * (std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]) + r);
    CGAL::Bbox_3 box(p[0] - r, p[1] - r, p[2] - r, p[0] + r, p[1] + r, p[2] + r);
    std::vector<SegIt> hit;
    lt->all_intersected_primitives(box, std::back_inserter(hit));
    for (const SegIt &it : hit) cand.push_back(static_cast<std::size_t>(it - pr->seg.begin()));
    std::sort(cand.begin(), cand.end());
  }
  double best = INFINITY, bt = 0;
  std::size_t bi = b;
  Point bp = q;
  std::size_t nc = lt ? cand.size() : e - b;
  for (std::size_t ci = 0; ci < nc; ci++) {
    std::size_t i = lt ? cand[ci] : b + ci;
    double t;
    Point c = closest_on_segment(pr->seg[i], q, &t);
    double d = CGAL::squared_distance(c, q);
    if (d < best) {
      best = d;
      bi = i;
      bp = c;
      bt = t;
    }
  }
  out[0] = bp.x();
  out[1] = bp.y();
  out[2] = bp.z();
  // direction: the segment's; at a joint of two segments, their mean
  Vector d = pr->seg[bi].to_vector();
  d = d / std::sqrt(d.squared_length());
  auto neighbour = [&](std::size_t j) {
    Vector dj = pr->seg[j].to_vector();
    double l = std::sqrt(dj.squared_length());
    if (l > 0) d = d + dj / l;
  };
  if (bt == 0 && bi > b && pr->seg[bi - 1].target() == pr->seg[bi].source()) neighbour(bi - 1);
  if (bt == 1 && bi + 1 < e && pr->seg[bi + 1].source() == pr->seg[bi].target()) neighbour(bi + 1);
  double l = std::sqrt(d.squared_length());
  double t[3] = {d.x() / l, d.y() / l, d.z() / l};
  orthogonal_pair(t, normals);
  return 2;
  VM_CXX_END(pr->ctx, "projection")
}

static int project_cb(void *user, int surf_id, const double p[3], double out[3],
                      double normals[9]) {
  return project_impl(static_cast<vm_surface_projector *>(user), surf_id, p, NULL, out, normals);
}

static int project_hinted_cb(void *user, int surf_id, const double p[3], int64_t *hint,
                             double out[3], double normals[9]) {
  return project_impl(static_cast<vm_surface_projector *>(user), surf_id, p, hint, out, normals);
}

extern "C" int vm_surface_projector_create(vm_ctx *ctx, const vm_mesh *ref,
                                           const vm_surface_features *f,
                                           vm_surface_projector **out) {
  if (!out || !ref) return vm_error(ctx, VM_ERR_ARG, "projector: NULL argument");
  *out = NULL;
  if (f && f->nv != ref->nv)
    return vm_error(ctx, VM_ERR_ARG, "projector: the features belong to another mesh");
  vm_surface_projector *p = NULL;
  VM_CXX_BEGIN
  std::unique_ptr<vm_surface_projector> pr(new vm_surface_projector);
  pr->ctx = ctx;
  pr->surf.build(ref);
  if (pr->surf.tri.empty())
    return vm_error(ctx, VM_ERR_ARG, "projector: the reference has no non-degenerate face");
  if (f)
    for (int64_t v = 0; v < f->nv; v++)
      if (f->vclass[v] == VM_FEATURE_CORNER)
        pr->corner.emplace_back(ref->xyz[3 * v], ref->xyz[3 * v + 1], ref->xyz[3 * v + 2]);
  if (f && f->nline > 0) {
    pr->nline = f->nline;
    // order each line's edges into a chain so neighbouring segments are adjacent
    std::vector<std::vector<int64_t>> by_line(static_cast<std::size_t>(f->nline) + 1);
    for (int64_t k = 0; k < f->nedge; k++)
      by_line[static_cast<std::size_t>(f->eline[k])].push_back(k);
    pr->lstart.push_back(0);
    for (int32_t l = 1; l <= f->nline; l++) {
      const std::vector<int64_t> &ed = by_line[static_cast<std::size_t>(l)];
      // chain: start at an end (a vertex used once) if there is one
      std::vector<std::pair<int32_t, int32_t>> es;
      for (int64_t k : ed) es.emplace_back(f->edge[2 * k], f->edge[2 * k + 1]);
      std::unordered_map<int32_t, std::vector<std::size_t>> inc;
      for (std::size_t j = 0; j < es.size(); j++) {
        inc[es[j].first].push_back(j);
        inc[es[j].second].push_back(j);
      }
      std::vector<char> used(es.size(), 0);
      int32_t cur = es.empty() ? -1 : es[0].first;
      for (const std::pair<int32_t, int32_t> &a : es) {
        if (inc[a.first].size() == 1) {
          cur = a.first;
          break;
        }
        if (inc[a.second].size() == 1) {
          cur = a.second;
          break;
        }
      }
      std::size_t next_unused = 0;
      for (std::size_t n = 0; n < es.size(); n++) {
        std::size_t pick = es.size();
        for (std::size_t j : inc[cur])
          if (!used[j]) {
            pick = j;
            break;
          }
        if (pick == es.size()) { // not a simple chain: continue from any unused edge
          while (used[next_unused]) next_unused++;
          pick = next_unused;
          cur = es[pick].first;
        }
        used[pick] = 1;
        int32_t nxt = es[pick].first == cur ? es[pick].second : es[pick].first;
        const double *pa = ref->xyz + 3 * static_cast<int64_t>(cur);
        const double *pb = ref->xyz + 3 * static_cast<int64_t>(nxt);
        pr->seg.emplace_back(Point(pa[0], pa[1], pa[2]), Point(pb[0], pb[1], pb[2]));
        pr->seg_line.push_back(l);
        cur = nxt;
      }
      pr->lstart.push_back(pr->seg.size());
    }
    pr->segtree.reset(new SegTree(pr->seg.begin(), pr->seg.end()));
    pr->segtree->accelerate_distance_queries();
    pr->ltree.resize(static_cast<std::size_t>(pr->nline));
    for (std::size_t k = 0; k + 1 < pr->lstart.size(); k++) {
      std::size_t b = pr->lstart[k], e = pr->lstart[k + 1];
      if (e - b <= kLineScan) continue;
      pr->ltree[k].reset(new SegTree(pr->seg.begin() + static_cast<std::ptrdiff_t>(b),
                                     pr->seg.begin() + static_cast<std::ptrdiff_t>(e)));
      pr->ltree[k]->accelerate_distance_queries();
    }
  } else {
    pr->lstart.push_back(0);
  }
  p = pr.release();
  *out = p;
  return VM_OK;
  VM_CXX_END(ctx, "projector")
}

extern "C" void vm_surface_projector_destroy(vm_surface_projector **p) {
  if (!p || !*p) return;
  delete *p;
  *p = NULL;
}

extern "C" vm_surface_ops vm_surface_projector_ops(vm_surface_projector *p) {
  vm_surface_ops ops;
  ops.project = project_cb;
  ops.user = p;
  ops.project_hinted = project_hinted_cb;
  ops.reentrant = 1; // const queries of the trees (CGAL builds them under a lock)
  return ops;
}

extern "C" int32_t vm_surface_projector_nlines(const vm_surface_projector *p) {
  return p ? p->nline : 0;
}

extern "C" int vm_surface_projector_assign(vm_surface_projector *p, const vm_mesh *m,
                                           const vm_surface_features *f, double tol,
                                           int32_t *vsurf) {
  if (!p || !m || !f || !vsurf || f->nv != m->nv || !(tol >= 0)) return VM_ERR_ARG;
  vm_ctx *ctx = p->ctx;
  VM_CXX_BEGIN
  const double tol2 = tol * tol;
  // the reference corners by x, for a window search around each vertex
  std::vector<Point> corner(p->corner);
  std::sort(corner.begin(), corner.end(),
            [](const Point &a, const Point &b) { return a.x() < b.x(); });
  auto at_corner = [&](const Point &q) {
    auto it = std::lower_bound(corner.begin(), corner.end(), q.x() - tol,
                               [](const Point &a, double x) { return a.x() < x; });
    for (; it != corner.end() && it->x() <= q.x() + tol; ++it)
      if (CGAL::squared_distance(*it, q) <= tol2) return true;
    return false;
  };
  for (int64_t v = 0; v < m->nv; v++) {
    int c = f->vclass[v];
    if (c == VM_FEATURE_CORNER) {
      vsurf[v] = -1;
      continue;
    }
    Point q(m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2]);
    vsurf[v] = 0;
    // a reference corner stays where it is, whatever the vertex is on m
    // (the sliver removal can leave a corner of the input smooth)
    if (at_corner(q)) {
      vsurf[v] = -1;
      continue;
    }
    if (c == VM_FEATURE_SMOOTH || !p->segtree) continue;
    auto cp = p->segtree->closest_point_and_primitive(q);
    if (CGAL::squared_distance(cp.first, q) > tol2) continue;
    vsurf[v] = p->seg_line[static_cast<std::size_t>(cp.second - p->seg.begin())];
  }
  return VM_OK;
  VM_CXX_END(ctx, "projector")
}

extern "C" int vm_surface_projector_distance(vm_surface_projector *p, int64_t n, const double *pts,
                                             double *dist) {
  if (!p || n < 0 || (n > 0 && (!pts || !dist))) return VM_ERR_ARG;
  vm_ctx *ctx = p->ctx;
  VM_CXX_BEGIN
  for (int64_t i = 0; i < n; i++) {
    Point q(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]);
    dist[i] = std::sqrt(p->surf.tree->squared_distance(q));
  }
  return VM_OK;
  VM_CXX_END(ctx, "projector")
}

extern "C" int vm_surface_projector_closest_element(vm_surface_projector *p, int64_t n,
                                                    const double *pts, int64_t *elem) {
  if (!p || n < 0 || (n > 0 && (!pts || !elem))) return VM_ERR_ARG;
  vm_ctx *ctx = p->ctx;
  VM_CXX_BEGIN
  if (p->surf.tri.empty()) {
    for (int64_t i = 0; i < n; i++) elem[i] = -1;
    return VM_OK;
  }
  int64_t hint = -1;
  for (int64_t i = 0; i < n; i++) {
    auto cp = closest(p, Point(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]), &hint);
    elem[i] = p->surf.te[static_cast<std::size_t>(cp.second - p->surf.tri.begin())];
  }
  return VM_OK;
  VM_CXX_END(ctx, "projector")
}

// The field at the closest point of q, linear in its triangle.
static double interpolate_at(const vm_surface_projector *p, const double *field, const Point &q,
                             int64_t *hint) {
  auto cp = closest(p, q, hint);
  std::size_t fi = static_cast<std::size_t>(cp.second - p->surf.tri.begin());
  const Triangle &t = p->surf.tri[fi];
  // barycentric coordinates of the closest point (it lies in the triangle)
  Vector e1 = t[1] - t[0], e2 = t[2] - t[0], r = cp.first - t[0];
  double d11 = e1 * e1, d12 = e1 * e2, d22 = e2 * e2, r1 = r * e1, r2 = r * e2;
  double det = d11 * d22 - d12 * d12;
  double b1 = det > 0 ? (d22 * r1 - d12 * r2) / det : 0.0;
  double b2 = det > 0 ? (d11 * r2 - d12 * r1) / det : 0.0;
  b1 = std::min(1.0, std::max(0.0, b1));
  b2 = std::min(1.0 - b1, std::max(0.0, b2));
  const int32_t *v = &p->surf.tv[3 * fi];
  return (1 - b1 - b2) * field[v[0]] + b1 * field[v[1]] + b2 * field[v[2]];
}

extern "C" int vm_surface_projector_interpolate(vm_surface_projector *p, const double *field,
                                                int64_t n, const double *pts, double *out) {
  if (!p || !field || n < 0 || (n > 0 && (!pts || !out))) return VM_ERR_ARG;
  vm_ctx *ctx = p->ctx;
  VM_CXX_BEGIN
  for (int64_t i = 0; i < n; i++)
    out[i] = interpolate_at(p, field, Point(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]), NULL);
  return VM_OK;
  VM_CXX_END(ctx, "projector")
}

extern "C" int vm_surface_projector_interpolate_hinted(vm_surface_projector *p, const double *field,
                                                       const double pt[3], int64_t *hint,
                                                       double *out) {
  if (!p || !field || !pt || !hint || !out) return VM_ERR_ARG;
  vm_ctx *ctx = p->ctx;
  VM_CXX_BEGIN
  *out = interpolate_at(p, field, Point(pt[0], pt[1], pt[2]), hint);
  return VM_OK;
  VM_CXX_END(ctx, "projector")
}

namespace {

// Largest distance from samples of `from` to the surface `to`.
double one_sided(const std::vector<Triangle> &from, const TriTree &to, double spacing,
                 double *where) {
  double worst = -1;
  for (const Triangle &t : from) {
    double lmax =
        std::sqrt(std::max({(t[1] - t[0]).squared_length(), (t[2] - t[1]).squared_length(),
                            (t[0] - t[2]).squared_length()}));
    int n = static_cast<int>(std::ceil(lmax / spacing));
    n = std::max(1, std::min(n, 64));
    for (int i = 0; i <= n; i++)
      for (int j = 0; i + j <= n; j++) {
        double a = static_cast<double>(i) / n, b = static_cast<double>(j) / n;
        Point q = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
        double d = to.squared_distance(q);
        if (d > worst) {
          worst = d;
          if (where) {
            where[0] = q.x();
            where[1] = q.y();
            where[2] = q.z();
          }
        }
      }
  }
  return std::sqrt(std::max(worst, 0.0));
}

} // namespace

extern "C" int vm_surface_hausdorff_at(const vm_mesh *a, const vm_mesh *b, double spacing,
                                       double *ab, double *ba, double ab_at[3], double ba_at[3]) {
  if (!a || !b) return VM_ERR_ARG;
  vm_ctx *ctx = a->ctx;
  VM_CXX_BEGIN
  TriSurface sa, sb;
  sa.build(a);
  sb.build(b);
  if (sa.tri.empty() || sb.tri.empty())
    return vm_error(ctx, VM_ERR_ARG, "hausdorff: a mesh has no non-degenerate face");
  if (!(spacing > 0)) {
    CGAL::Bbox_3 bb = sa.tree->bbox();
    double diag = std::sqrt((bb.xmax() - bb.xmin()) * (bb.xmax() - bb.xmin()) +
                            (bb.ymax() - bb.ymin()) * (bb.ymax() - bb.ymin()) +
                            (bb.zmax() - bb.zmin()) * (bb.zmax() - bb.zmin()));
    spacing = diag / 100;
  }
  if (ab || ab_at) {
    double d = one_sided(sa.tri, *sb.tree, spacing, ab_at);
    if (ab) *ab = d;
  }
  if (ba || ba_at) {
    double d = one_sided(sb.tri, *sa.tree, spacing, ba_at);
    if (ba) *ba = d;
  }
  return VM_OK;
  VM_CXX_END(ctx, "hausdorff")
}

extern "C" int vm_surface_hausdorff(const vm_mesh *a, const vm_mesh *b, double spacing, double *ab,
                                    double *ba) {
  return vm_surface_hausdorff_at(a, b, spacing, ab, ba, NULL, NULL);
}

// Crossings of the ray from p along d with the triangles of s, or -1 when
// the ray meets a triangle within rounding of one of its edges or vertices,
// or runs along one (the parity would say nothing there).
int ray_crossings(const TriSurface &s, const Point &p, const Vector &d) {
  std::vector<TriIt> hit;
  s.tree->all_intersected_primitives(K::Ray_3(p, d), std::back_inserter(hit));
  const double eps = 1e-9;
  int n = 0;
  for (TriIt it : hit) {
    const Triangle &t = *it;
    Vector e1 = t[1] - t[0], e2 = t[2] - t[0];
    Vector q = CGAL::cross_product(d, e2);
    double det = e1 * q;
    double scale = std::sqrt(e1.squared_length() * e2.squared_length() * d.squared_length());
    if (!(std::fabs(det) > eps * scale)) return -1;
    Vector r = p - t[0];
    double u = (r * q) / det;
    Vector w = CGAL::cross_product(r, e1);
    double v = (d * w) / det;
    if (u < -eps || v < -eps || u + v > 1 + eps) continue; // the box test's slack
    if (u < eps || v < eps || u + v > 1 - eps) return -1;
    n++;
  }
  return n;
}

extern "C" int vm_surface_inside(const vm_mesh *surf, int64_t n, const double *pts, double tol,
                                 int8_t *inside) {
  if (!surf || n < 0 || (n > 0 && (!pts || !inside))) return VM_ERR_ARG;
  vm_ctx *ctx = surf->ctx;
  // squared distances and ray crossings overflow beyond this: no answer
  // rather than a wrong one (CGAL's own checks are off under NDEBUG)
  const double big = 1e150;
  for (int64_t i = 0; i < 3 * surf->nv; i++)
    if (!(std::fabs(surf->xyz[i]) < big))
      return vm_error(ctx, VM_ERR_UNSUPPORTED,
                      "inside test: surface coordinate %g beyond what it can take (1e150)",
                      surf->xyz[i]);
  for (int64_t i = 0; i < 3 * n; i++)
    if (!(std::fabs(pts[i]) < big))
      return vm_error(ctx, VM_ERR_UNSUPPORTED,
                      "inside test: point coordinate %g beyond what it can take (1e150)", pts[i]);
  VM_CXX_BEGIN
  TriSurface s;
  s.build(surf);
  if (s.tri.empty()) {
    for (int64_t i = 0; i < n; i++) inside[i] = 0;
    return VM_OK;
  }
  // Directions with no algebraic relation to the axes, to each other or to
  // rotations by simple angles (unit vectors made of 1/sqrt(2), 1/sqrt(3),
  // 1/sqrt(6) grazed the grid edges of a cube's surface from points of a
  // cube turned by pi/4: two of three rays, a wrong majority). A ray that
  // still passes within rounding of an edge or a vertex of a triangle it
  // meets, or along one, is not counted: the next direction is tried, and
  // the first three clean rays vote.
  static const double dir[8][3] = {{0.4217, 0.7433, 0.5192},    {-0.6329, 0.2871, 0.7193},
                                   {0.3391, -0.5478, 0.7649},   {0.8123, 0.3307, -0.4806},
                                   {-0.2713, -0.8419, 0.4664},  {0.5521, -0.6013, -0.5776},
                                   {-0.7339, -0.1547, -0.6614}, {0.1911, 0.9093, -0.3697}};
  for (int64_t i = 0; i < n; i++) {
    Point p(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]);
    if (s.tree->squared_distance(p) <= tol * tol) {
      inside[i] = -1;
      continue;
    }
    int votes = 0, clean = 0;
    for (int k = 0; k < 8 && clean < 3; k++) {
      int c = ray_crossings(s, p, Vector(dir[k][0], dir[k][1], dir[k][2]));
      if (c < 0) continue;
      clean++;
      votes += c & 1;
    }
    inside[i] = clean == 3 ? votes >= 2 : -1;
  }
  return VM_OK;
  VM_CXX_END(ctx, "inside")
}
