/* test/surface/test_repair.c: the CGAL/OpenMesh side of the surface stage:
 * repair of good and bad surfaces (open, non-manifold, zero-area faces,
 * inconsistent orientation, self-intersections, empty), the union of
 * overlapping and nested closed parts, a part crossing itself healed, a
 * model no repair can close wrapped,
 * features,
 * isotropic remeshing with protected features, the projector, Hausdorff. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/curvature.h"
#include "varmesh/features.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

/* Every edge used once in each direction: closed and consistently oriented. */
static int consistently_closed(const vm_mesh *m) {
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) n += vm_elem_nverts(m->etype[e]);
  int64_t *k = malloc(sizeof *k * (size_t)n);
  int64_t c = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int nv = vm_elem_nverts(m->etype[e]);
    const int32_t *v = m->conn + m->eoff[e];
    for (int a = 0; a < nv; a++) k[c++] = (int64_t)v[a] * m->nv + v[(a + 1) % nv];
  }
  int ok = 1;
  for (int64_t i = 0; i < n && ok; i++) {
    int64_t a = k[i] / m->nv, b = k[i] % m->nv, fwd = 0, back = 0;
    for (int64_t j = 0; j < n; j++) {
      fwd += k[j] == k[i];
      back += k[j] == b * m->nv + a;
    }
    ok = fwd == 1 && back == 1;
  }
  free(k);
  return ok;
}

static void flip(vm_mesh *m, int64_t e) {
  int32_t *c = m->conn + m->eoff[e];
  int32_t s = c[1];
  c[1] = c[2];
  c[2] = s;
}

static void test_good_and_reoriented(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_repair_report r;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_icosphere(m, NULL, 1.0, 2, 0, NULL) == 0, "icosphere");
  CHECK(vm_surface_repair(m, NULL, &r) == 0, "repair of a good sphere: %s", vm_ctx_error(ctx));
  CHECK(r.nv == 162 && r.nf == 320 && r.border_edges == 0 && r.components == 1 &&
            r.self_intersections == 0 && r.reoriented == 0,
        "good sphere report: nv %lld nf %lld border %lld reor %lld", (long long)r.nv,
        (long long)r.nf, (long long)r.border_edges, (long long)r.reoriented);
  CHECK(r.volume > 3.9 && r.volume < 4.19, "volume %g", r.volume);
  /* three faces flipped: repaired, consistent and outward */
  flip(m, 3);
  flip(m, 100);
  flip(m, 211);
  CHECK(vm_surface_repair(m, NULL, &r) == 0, "repair of flipped faces: %s", vm_ctx_error(ctx));
  CHECK(r.reoriented == 3, "reoriented %lld", (long long)r.reoriented);
  CHECK(consistently_closed(m), "consistent after repair");
  CHECK(r.volume > 3.9, "outward: volume %g", r.volume);
  /* all faces flipped: turned outward */
  for (int64_t e = 0; e < m->ne; e++) flip(m, e);
  CHECK(vm_surface_repair(m, NULL, &r) == 0, "repair of an inward sphere");
  CHECK(r.reoriented == 320 && r.volume > 3.9, "inward sphere: reoriented %lld volume %g",
        (long long)r.reoriented, r.volume);
  double H[200];
  vm_curvature_stats cs;
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, &cs) == 0 && cs.min > 0.9,
        "outward after repair: H > 0 (min %g)", cs.min);
  vm_mesh_destroy(&m);
}

static void test_soup_cleanup(vm_ctx *ctx) {
  /* a cube whose triangle 0 appears twice (reversed) and whose vertex 0 is
   * duplicated in triangle 5, with an unused vertex */
  vm_mesh *m = NULL;
  vm_repair_report r;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_cube(m, 1) == 0, "cube");
  int32_t dup[3] = {m->conn[0], m->conn[2], m->conn[1]};
  vm_mesh_add_element(m, VM_TRI, dup);
  int64_t nv0 = m->nv, extra;
  vm_mesh_add_vertex(m, m->xyz[3 * m->conn[15]], m->xyz[3 * m->conn[15] + 1],
                     m->xyz[3 * m->conn[15] + 2], &extra);
  m->conn[15] = (int32_t)extra;
  vm_mesh_add_vertex(m, 5, 5, 5, NULL);
  CHECK(vm_surface_repair(m, NULL, &r) == 0, "soup cleanup: %s", vm_ctx_error(ctx));
  CHECK(r.merged_vertices == 1 && r.removed_polygons == 1 && r.removed_isolated >= 1,
        "merged %lld removed %lld isolated %lld", (long long)r.merged_vertices,
        (long long)r.removed_polygons, (long long)r.removed_isolated);
  CHECK(m->nv == nv0 && m->ne == 12 && consistently_closed(m), "clean cube: nv %lld ne %lld",
        (long long)m->nv, (long long)m->ne);
  CHECK(fabs(r.volume - 1) < 1e-12, "unit volume %g", r.volume);
  vm_mesh_destroy(&m);
}

static void test_refusals(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_repair_report r;
  vm_repair_opts o = vm_repair_opts_default();
  /* open: one face removed */
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_icosphere(m, NULL, 1.0, 1, 0, NULL) == 0, "icosphere");
  m->ne--;
  int64_t nv = m->nv, ne = m->ne;
  double x0 = m->xyz[0];
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && r.refused == VM_REPAIR_OPEN,
        "open surface refused (refused %d)", r.refused);
  CHECK(strstr(vm_ctx_error(ctx), "open surface") && strstr(vm_ctx_error(ctx), "3 border edges"),
        "message: %s", vm_ctx_error(ctx));
  CHECK(m->nv == nv && m->ne == ne && m->xyz[0] == x0, "refused mesh unchanged");
  o.require_closed = 0;
  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.border_edges == 3 && r.holes == 1,
        "open accepted when allowed: border %lld holes %lld", (long long)r.border_edges,
        (long long)r.holes);
  vm_mesh_destroy(&m);
  o.require_closed = 1;

  /* non-manifold edge: a fin on a cube edge */
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_cube(m, 1) == 0, "cube");
  int64_t fin;
  vm_mesh_add_vertex(m, 0.5, -1, 0.5, &fin);
  int32_t t[3] = {m->conn[0], m->conn[1], (int32_t)fin};
  vm_mesh_add_element(m, VM_TRI, t);
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && r.refused == VM_REPAIR_NONMANIFOLD,
        "non-manifold edge refused (refused %d)", r.refused);
  CHECK(strstr(vm_ctx_error(ctx), "non-manifold") != NULL, "message: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);

  /* non-manifold vertex: two cubes touching at a corner */
  vm_mesh *a = NULL, *b = NULL;
  vm_mesh_create(ctx, &a);
  vm_gen_cube(a, 1);
  vm_mesh_create(ctx, &b);
  vm_gen_cube(b, 1);
  int64_t base = a->nv;
  for (int64_t v = 0; v < b->nv; v++)
    vm_mesh_add_vertex(a, b->xyz[3 * v] + 1, b->xyz[3 * v + 1] + 1, b->xyz[3 * v + 2] + 1, NULL);
  for (int64_t e = 0; e < b->ne; e++) {
    int32_t tt[3];
    for (int k = 0; k < 3; k++) tt[k] = (int32_t)(b->conn[3 * e + k] + base);
    vm_mesh_add_element(a, VM_TRI, tt);
  }
  CHECK(vm_surface_repair(a, &o, &r) == VM_ERR_FORMAT && r.refused == VM_REPAIR_NONMANIFOLD,
        "non-manifold vertex refused (refused %d)", r.refused);
  CHECK(strstr(vm_ctx_error(ctx), "(1, 1, 1)") != NULL, "names the vertex: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);

  /* self-intersecting: two overlapping spheres */
  vm_mesh_create(ctx, &a);
  vm_gen_icosphere(a, NULL, 1.0, 2, 0, NULL);
  vm_mesh_create(ctx, &b);
  vm_gen_icosphere(b, NULL, 1.0, 2, 0, NULL);
  base = a->nv;
  for (int64_t v = 0; v < b->nv; v++)
    vm_mesh_add_vertex(a, b->xyz[3 * v] + 0.5, b->xyz[3 * v + 1], b->xyz[3 * v + 2], NULL);
  for (int64_t e = 0; e < b->ne; e++) {
    int32_t tt[3];
    for (int k = 0; k < 3; k++) tt[k] = (int32_t)(b->conn[3 * e + k] + base);
    vm_mesh_add_element(a, VM_TRI, tt);
  }
  int64_t count = 0;
  int32_t *pairs = NULL;
  CHECK(vm_surface_self_intersections(a, &count, &pairs) == 0 && count > 0, "pairs %lld",
        (long long)count);
  int sorted = 1;
  for (int64_t i = 1; i < count; i++)
    sorted &= pairs[2 * i - 2] < pairs[2 * i] ||
              (pairs[2 * i - 2] == pairs[2 * i] && pairs[2 * i - 1] < pairs[2 * i + 1]);
  CHECK(sorted && pairs[0] < pairs[1], "pairs sorted");
  vm_free(ctx, pairs);
  o.union_overlaps = 0;
  CHECK(vm_surface_repair(a, &o, &r) == VM_ERR_FORMAT && r.refused == VM_REPAIR_CROSSING,
        "self-intersecting refused without union (refused %d)", r.refused);
  CHECK(strstr(vm_ctx_error(ctx), "self-intersecting") != NULL, "message: %s", vm_ctx_error(ctx));
  o.require_closed = 0;
  CHECK(vm_surface_repair(a, &o, &r) == 0 && r.self_intersections == count && r.components == 2,
        "accepted with a warning when not required closed: %lld pairs",
        (long long)r.self_intersections);
  o.require_closed = 1;
  o.union_overlaps = 1;
  /* by default: their union, one closed component, nothing intersecting */
  CHECK(vm_surface_repair(a, &o, &r) == 0 && r.united == 2 && r.union_pairs == count &&
            r.components == 1 && r.self_intersections == 0 && r.border_edges == 0 &&
            consistently_closed(a),
        "two overlapping spheres united: %lld components, %lld pairs left (%s)",
        (long long)r.components, (long long)r.self_intersections, vm_ctx_error(ctx));
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);

  /* empty, volume elements, all degenerate */
  vm_mesh_create(ctx, &m);
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && r.refused == VM_REPAIR_EMPTY,
        "empty surface refused (refused %d)", r.refused);
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, i == 1, i == 2, i == 3, NULL);
  int32_t tet[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_TET, tet);
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_ARG, "volume elements refused");
  vm_mesh_destroy(&m);
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 3; i++) vm_mesh_add_vertex(m, i, 0, 0, NULL);
  int32_t t0[3] = {0, 1, 1};
  vm_mesh_add_element(m, VM_TRI, t0);
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && r.refused == VM_REPAIR_EMPTY,
        "all-degenerate refused (refused %d)", r.refused);
  vm_mesh_destroy(&m);
}

static void test_zero_area(vm_ctx *ctx) {
  /* a closed sphere with a zero-area triangle (a, b, m), m the midpoint of
   * edge (a, b): the neighbour (a, b, c) is split at m */
  vm_mesh *m = NULL;
  vm_repair_report r;
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 2, 0, NULL);
  int32_t *f = m->conn; /* face 0 = (a, b, c) */
  int32_t a = f[0], b = f[1], c = f[2];
  int64_t mid;
  vm_mesh_add_vertex(m, 0.5 * (m->xyz[3 * a] + m->xyz[3 * b]),
                     0.5 * (m->xyz[3 * a + 1] + m->xyz[3 * b + 1]),
                     0.5 * (m->xyz[3 * a + 2] + m->xyz[3 * b + 2]), &mid);
  f = m->conn;
  f[0] = a, f[1] = (int32_t)mid, f[2] = c;
  int32_t t2[3] = {(int32_t)mid, b, c}, deg[3] = {a, b, (int32_t)mid};
  vm_mesh_add_element(m, VM_TRI, t2);
  vm_mesh_add_element(m, VM_TRI, deg);
  CHECK(consistently_closed(m), "constructed mesh is closed");
  vm_curvature_stats cs;
  double *H = malloc(sizeof *H * (size_t)m->nv);
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, &cs) == 0 && cs.degenerate == 1,
        "curvature skips the zero-area triangle (%lld)", (long long)cs.degenerate);
  free(H);
  CHECK(vm_surface_repair(m, NULL, &r) == 0, "zero-area face repaired: %s", vm_ctx_error(ctx));
  CHECK(r.removed_degenerate >= 1 && r.border_edges == 0 && consistently_closed(m),
        "degenerate removed (%lld), still closed", (long long)r.removed_degenerate);
  H = malloc(sizeof *H * (size_t)m->nv);
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, &cs) == 0 && cs.degenerate == 0,
        "no degenerate triangle left");
  free(H);
  vm_mesh_destroy(&m);
}

static void test_features(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_surface_features f;
  vm_mesh_create(ctx, &m);
  vm_gen_cube(m, 4);
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "cube features");
  CHECK(f.nedge == 48 && f.nline == 12 && f.ncorner == 8 && f.nline_vertices == 36 &&
            f.nboundary == 0,
        "cube: %lld edges %d lines %lld corners %lld line vertices", (long long)f.nedge, f.nline,
        (long long)f.ncorner, (long long)f.nline_vertices);
  int ok = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    int on = 0;
    for (int k = 0; k < 3; k++) on += m->xyz[3 * v + k] == 0 || m->xyz[3 * v + k] == 1;
    int want = on == 3 ? VM_FEATURE_CORNER : on == 2 ? VM_FEATURE_LINE : VM_FEATURE_SMOOTH;
    ok &= f.vclass[v] == want;
  }
  CHECK(ok, "cube vertex classes");
  /* flags for the minimizer */
  CHECK(vm_surface_features_apply(m, &f, NULL) == 0, "apply");
  int64_t nfixed = 0, nslip0 = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    nfixed += m->vflag[v] == VM_VERTEX_FIXED;
    nslip0 += m->vflag[v] == VM_VERTEX_SLIP && m->vsurf[v] == 0;
  }
  CHECK(nfixed == 8 && nslip0 == m->nv - 8 - 36, "flags: %lld fixed", (long long)nfixed);
  vm_surface_features_free(ctx, &f);
  /* above the cube's dihedral angle: no features */
  CHECK(vm_surface_detect_features(m, 91, 50, &f) == 0 && f.nedge == 0 && f.nline == 0,
        "91 degrees: none");
  vm_surface_features_free(ctx, &f);
  CHECK(vm_surface_detect_features(m, 0, 50, &f) == VM_ERR_ARG, "angle 0 refused");
  /* an edge that is not a mesh edge */
  int32_t bad[2] = {0, (int32_t)m->nv - 1};
  CHECK(vm_surface_features_from_edges(m, 1, bad, NULL, 50, &f) == VM_ERR_ARG,
        "not an edge refused");
  vm_mesh_destroy(&m);

  /* open cylinder: two boundary loops, no corners */
  vm_mesh_create(ctx, &m);
  vm_gen_cylinder(m, 0.5, 1.0, 24, 6, NULL);
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == 0, "cylinder features");
  CHECK(f.nline == 2 && f.ncorner == 0 && f.nboundary == 48 && f.nline_vertices == 48,
        "cylinder: %d lines %lld corners %lld boundary", f.nline, (long long)f.ncorner,
        (long long)f.nboundary);
  vm_surface_features_free(ctx, &f);
  /* a flipped face: OpenMesh cannot build it; named in the message */
  flip(m, 7);
  CHECK(vm_surface_detect_features(m, 20, 50, &f) == VM_ERR_FORMAT, "flipped face refused");
  CHECK(strstr(vm_ctx_error(ctx), "element") != NULL, "message: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
}

static void test_remesh(vm_ctx *ctx) {
  vm_mesh *m = NULL, *in = NULL;
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 3, 0, NULL);
  vm_mesh_clone(m, &in);
  vm_remesh_opts o = vm_remesh_opts_default();
  o.target_edge_length = 0.2;
  CHECK(vm_surface_remesh(m, NULL, &o, 50) == 0, "remesh sphere: %s", vm_ctx_error(ctx));
  double s = 0;
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++)
    for (int a = 0; a < 3; a++) {
      const double *p = m->xyz + 3 * m->conn[3 * e + a],
                   *q = m->xyz + 3 * m->conn[3 * e + (a + 1) % 3];
      s += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                (p[2] - q[2]) * (p[2] - q[2]));
      n++;
    }
  CHECK(s / n > 0.16 && s / n < 0.24, "mean edge %g for target 0.2", s / n);
  CHECK(consistently_closed(m), "remeshed sphere closed");
  double ab, ba;
  CHECK(vm_surface_hausdorff(m, in, 0, &ab, &ba) == 0 && ab < 0.01 && ba < 0.02, "hausdorff %g %g",
        ab, ba);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&in);

  /* cube with features: corners and edges stay exact */
  vm_mesh_create(ctx, &m);
  vm_gen_cube(m, 3);
  vm_surface_features f;
  vm_surface_detect_features(m, 20, 50, &f);
  o.target_edge_length = 0.1;
  CHECK(vm_surface_remesh(m, &f, &o, 50) == 0, "remesh cube: %s", vm_ctx_error(ctx));
  CHECK(m->nv > 300 && f.nv == m->nv, "refined cube: %lld vertices", (long long)m->nv);
  CHECK(f.ncorner == 8 && f.nline == 12, "cube after remesh: %lld corners %d lines",
        (long long)f.ncorner, f.nline);
  int exact = 1, corners = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int on = 0;
    for (int k = 0; k < 3; k++) on += m->xyz[3 * v + k] == 0 || m->xyz[3 * v + k] == 1;
    if (f.vclass[v] == VM_FEATURE_LINE) exact &= on == 2;
    if (f.vclass[v] == VM_FEATURE_CORNER) corners += on == 3;
    exact &= on >= 1; /* on a face plane */
  }
  CHECK(exact && corners == 8, "feature vertices exactly on the cube's edges, %d corners", corners);
  CHECK(consistently_closed(m), "remeshed cube closed");
  vm_surface_features_free(ctx, &f);
  o.target_edge_length = 0;
  CHECK(vm_surface_remesh(m, NULL, &o, 50) == VM_ERR_ARG, "zero target refused");
  vm_mesh_destroy(&m);
}

static void test_projector(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_surface_features f;
  vm_surface_projector *p = NULL;
  vm_mesh_create(ctx, &m);
  vm_gen_cube(m, 2);
  vm_surface_detect_features(m, 20, 50, &f);
  CHECK(vm_surface_projector_create(ctx, m, &f, &p) == 0, "projector");
  CHECK(vm_surface_projector_nlines(p) == 12, "12 lines");
  vm_surface_ops ops = vm_surface_projector_ops(p);
  double q[3], out[3], nr[9];
  /* surface: a point above the top face */
  q[0] = 0.3, q[1] = 0.6, q[2] = 1.4;
  CHECK(ops.project(ops.user, 0, q, out, nr) == 1, "surface projection");
  CHECK(fabs(out[0] - 0.3) + fabs(out[1] - 0.6) + fabs(out[2] - 1) < 1e-14 &&
            fabs(nr[2] - 1) < 1e-14,
        "onto the top face (%g %g %g), normal (%g %g %g)", out[0], out[1], out[2], nr[0], nr[1],
        nr[2]);
  /* each line: a point near its middle lands on it, normals orthogonal to it */
  int32_t *vs = malloc(sizeof *vs * (size_t)m->nv);
  CHECK(vm_surface_projector_assign(p, m, &f, 1e-9, vs) == 0, "assign");
  int ok = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    int want = f.vclass[v] == VM_FEATURE_CORNER   ? -1
               : f.vclass[v] == VM_FEATURE_SMOOTH ? 0
                                                  : f.vline[v];
    ok &= vs[v] == want;
    if (f.vclass[v] != VM_FEATURE_LINE) continue;
    double pt[3] = {m->xyz[3 * v] + 0.05, m->xyz[3 * v + 1] - 0.03, m->xyz[3 * v + 2] + 0.02};
    int nn = ops.project(ops.user, f.vline[v], pt, out, nr);
    ok &= nn == 2;
    /* the line direction: the axis along which v's coordinate is 0.5 */
    int ax = m->xyz[3 * v] == 0.5 ? 0 : m->xyz[3 * v + 1] == 0.5 ? 1 : 2;
    for (int k = 0; k < 3; k++)
      if (k != ax) ok &= out[k] == m->xyz[3 * v + k];
    ok &= fabs(out[ax] - pt[ax]) < 1e-14;
    ok &= fabs(nr[ax]) < 1e-14 && fabs(nr[3 + ax]) < 1e-14;
    ok &= fabs(nr[0] * nr[3] + nr[1] * nr[4] + nr[2] * nr[5]) < 1e-14;
  }
  CHECK(ok, "assign and line projections");
  free(vs);
  CHECK(ops.project(ops.user, 13, q, out, nr) == VM_ERR_ARG, "unknown surface id");
  CHECK(ops.project(ops.user, -1, q, out, nr) == VM_ERR_ARG, "negative surface id");
  /* interpolation of a linear field is exact on the surface */
  double *fx = malloc(sizeof *fx * (size_t)m->nv);
  for (int64_t v = 0; v < m->nv; v++) fx[v] = 2 * m->xyz[3 * v] - m->xyz[3 * v + 2];
  double pts[6] = {0.2, 0.7, 1.3, 1.2, 0.4, 0.45}, val[2], dist[2];
  CHECK(vm_surface_projector_interpolate(p, fx, 2, pts, val) == 0, "interpolate");
  CHECK(fabs(val[0] - (0.4 - 1)) < 1e-13 && fabs(val[1] - (2 - 0.45)) < 1e-13,
        "linear field: %g %g", val[0], val[1]);
  CHECK(vm_surface_projector_distance(p, 2, pts, dist) == 0 && fabs(dist[0] - 0.3) < 1e-14 &&
            fabs(dist[1] - 0.2) < 1e-14,
        "distances %g %g", dist[0], dist[1]);
  free(fx);
  vm_surface_projector_destroy(&p);
  CHECK(p == NULL, "destroy clears");
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&m);

  /* Hausdorff between concentric spheres */
  vm_mesh *a = NULL, *b = NULL;
  vm_mesh_create(ctx, &a);
  vm_gen_icosphere(a, NULL, 1.0, 3, 0, NULL);
  vm_mesh_create(ctx, &b);
  vm_gen_icosphere(b, NULL, 1.1, 3, 0, NULL);
  double ab, ba;
  CHECK(vm_surface_hausdorff(a, b, 0.05, &ab, &ba) == 0, "hausdorff");
  CHECK(ab > 0.09 && ab < 0.101 && ba > 0.09 && ba < 0.101, "spheres 0.1 apart: %g %g", ab, ba);
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);
}

/* The box [lo, hi] (12 outward triangles) added to m. */
static void add_box(vm_mesh *m, const double lo[3], const double hi[3]) {
  int32_t b = (int32_t)m->nv;
  for (int i = 0; i < 8; i++)
    vm_mesh_add_vertex(m, i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2],
                       NULL);
  static const int q[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                              {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (int f = 0; f < 6; f++) {
    int32_t t1[3] = {b + q[f][0], b + q[f][1], b + q[f][2]},
            t2[3] = {b + q[f][0], b + q[f][2], b + q[f][3]};
    vm_mesh_add_element(m, VM_TRI, t1);
    vm_mesh_add_element(m, VM_TRI, t2);
  }
}

/* Closed parts that overlap or nest: their union (known volumes), the
 * voids it encloses dropped; parts that do neither are left as they are,
 * fields and all. */
static void test_union(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_repair_report r;
  vm_repair_opts o = vm_repair_opts_default();
  const double u0[3] = {0, 0, 0}, u1[3] = {1, 1, 1};
  /* a bar through the unit cube's face x = 1: 1 + 1/4 - 1/8 */
  const double b0[3] = {0.5, 0.25, 0.25}, b1[3] = {1.5, 0.75, 0.75};
  vm_mesh_create(ctx, &m);
  add_box(m, u0, u1);
  add_box(m, b0, b1);
  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.united == 2 && r.union_pairs > 0 &&
            r.components == 1 && r.self_intersections == 0 && consistently_closed(m),
        "overlapping boxes united: %lld united, %lld components (%s)", (long long)r.united,
        (long long)r.components, vm_ctx_error(ctx));
  CHECK(fabs(r.volume - 1.125) < 1e-12, "the union's volume %.17g (1.125)", r.volume);
  int on = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    const double *x = m->xyz + 3 * v;
    int in_u = x[0] >= 0 && x[0] <= 1 && x[1] >= 0 && x[1] <= 1 && x[2] >= 0 && x[2] <= 1;
    int in_b =
        x[0] >= 0.5 && x[0] <= 1.5 && x[1] >= 0.25 && x[1] <= 0.75 && x[2] >= 0.25 && x[2] <= 0.75;
    on &= in_u || in_b;
  }
  CHECK(on, "every vertex of the union in one of the boxes");
  vm_mesh_destroy(&m);

  /* a box inside the cube: the cube alone (its 8 vertices), volume 1 */
  const double i0[3] = {0.4, 0.4, 0.4}, i1[3] = {0.6, 0.6, 0.6};
  vm_mesh_create(ctx, &m);
  add_box(m, u0, u1);
  add_box(m, i0, i1);
  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.united == 2 && r.union_pairs == 0 &&
            r.components == 1 && m->nv == 8 && m->ne == 12 && fabs(r.volume - 1) < 1e-15,
        "nested box dropped: %lld components, %lld vertices, volume %g", (long long)r.components,
        (long long)m->nv, r.volume);
  vm_mesh_destroy(&m);

  /* two boxes apart: not touched, their field kept */
  const double d0[3] = {2, 0, 0}, d1[3] = {3, 1, 1};
  vm_mesh_create(ctx, &m);
  add_box(m, u0, u1);
  add_box(m, d0, d1);
  vm_field *f = NULL;
  vm_mesh_add_field(m, "component", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = e < 12 ? 1 : 2;
  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.united == 0 && r.components == 2 &&
            vm_mesh_find_field(m, "component", VM_FIELD_ELEMENT) != NULL &&
            fabs(r.volume - 2) < 1e-15,
        "boxes apart kept: %lld united, %lld components", (long long)r.united,
        (long long)r.components);
  vm_mesh_destroy(&m);

  /* six slabs overlapping at the edges, the walls of a box: their union
   * encloses a void (the unit cube), dropped. No two slabs share a face's
   * plane (x walls 0.1 thick spanning [-0.1, 1.1]^2, y walls 0.09 over
   * [-0.05, 1.05]^2, z walls 0.08 over [-0.03, 1.03]^2): the solid's volume,
   * counted cell by cell over the slabs' coordinates, is 1.6496 */
  vm_mesh_create(ctx, &m);
  const double span[3] = {0.1, 0.05, 0.03}, thick[3] = {0.1, 0.09, 0.08};
  for (int a = 0; a < 3; a++)
    for (int side = 0; side < 2; side++) {
      double w = span[a], lo[3] = {-w, -w, -w}, hi[3] = {1 + w, 1 + w, 1 + w};
      lo[a] = side ? 1 : -thick[a];
      hi[a] = side ? 1 + thick[a] : 0;
      add_box(m, lo, hi);
    }
  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.united == 6 && r.components == 1 &&
            r.self_intersections == 0 && consistently_closed(m) && fabs(r.volume - 1.6496) < 1e-12,
        "a hollow box of slabs: its void dropped, %lld components, volume %.17g (1.6496; %s)",
        (long long)r.components, r.volume, vm_ctx_error(ctx));
  int outside = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    double d = 0;
    for (int k = 0; k < 3; k++) d = fmax(d, fabs(m->xyz[3 * v + k] - 0.5));
    outside &= d > 0.52;
  }
  CHECK(outside, "no vertex on the void's walls");
  vm_mesh_destroy(&m);

  /* without the union: refused, the mesh as it was */
  vm_mesh_create(ctx, &m);
  add_box(m, u0, u1);
  add_box(m, b0, b1);
  o.union_overlaps = 0;
  double x5 = m->xyz[15];
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && m->nv == 16 && m->ne == 24 &&
            m->xyz[15] == x5 && strstr(vm_ctx_error(ctx), "self-intersecting surface"),
        "refused with union_overlaps 0: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
}

/* A closed part that intersects itself: an icosphere (level 3, radius 1)
 * whose north pole is pushed 2 edge lengths sideways along the sphere
 * folds its fan over its neighbours' (a model's local fold): healed, the
 * crossing faces removed and the hole filled, the rest of the sphere kept
 * bit for bit; the pole pushed through the south side instead is refused
 * (healing would cut the spike off, far beyond the local edge length), as
 * is the fold with heal_self 0. Each refusal leaves the mesh as it was. */
static void test_heal(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_repair_report r;
  vm_repair_opts o = vm_repair_opts_default();
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 3, 0, NULL);
  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.healed == 0 && r.self_intersections == 0,
        "the sphere as it is: nothing to heal");
  double vol0 = r.volume, edge = 0;
  int64_t top = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->xyz[3 * v + 2] > m->xyz[3 * top + 2]) top = v;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *t = m->conn + m->eoff[e];
    for (int k = 0; k < 3; k++) {
      const double *a = m->xyz + 3 * t[k], *b = m->xyz + 3 * t[(k + 1) % 3];
      edge += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
    }
  }
  edge /= 3.0 * (double)m->ne;
  double *x = m->xyz + 3 * top, q[3] = {x[0] + 2 * edge, x[1], x[2]};
  double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
  for (int d = 0; d < 3; d++) x[d] = q[d] / nq;
  int64_t nv0 = m->nv;
  double *keep = malloc(sizeof *keep * 3 * (size_t)nv0);
  int64_t nkeep = 0;
  for (int64_t v = 0; v < nv0; v++)
    if (m->xyz[3 * v + 2] < 0.5) memcpy(keep + 3 * nkeep++, m->xyz + 3 * v, sizeof *keep * 3);
  int64_t pairs = 0;
  CHECK(vm_surface_self_intersections(m, &pairs, NULL) == 0 && pairs > 0, "the fold: %lld pairs",
        (long long)pairs);

  /* with heal_self 0: refused, untouched */
  o.heal_self = 0;
  double x0 = x[0];
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && m->nv == nv0 && m->xyz[3 * top] == x0 &&
            strstr(vm_ctx_error(ctx), "self-intersecting surface") &&
            r.refused == VM_REPAIR_CROSSING,
        "the fold refused with heal_self 0: %s (refused %d)", vm_ctx_error(ctx), r.refused);
  o.heal_self = 1;

  CHECK(vm_surface_repair(m, &o, &r) == 0 && r.healed == 1 && r.heal_pairs == pairs &&
            r.self_intersections == 0 && r.components == 1 && consistently_closed(m),
        "the fold healed: %lld healed, %lld pairs healed, %lld left (%s)", (long long)r.healed,
        (long long)r.heal_pairs, (long long)r.self_intersections, vm_ctx_error(ctx));
  CHECK(r.heal_moved > 0 && r.heal_moved < edge && fabs(r.volume - vol0) < 0.01 * vol0,
        "moved %g (edge %g), volume %.6g against %.6g", r.heal_moved, edge, r.volume, vol0);
  int64_t found = 0;
  for (int64_t i = 0; i < nkeep; i++)
    for (int64_t v = 0; v < m->nv; v++)
      if (!memcmp(m->xyz + 3 * v, keep + 3 * i, sizeof *keep * 3)) {
        found++;
        break;
      }
  CHECK(found == nkeep, "the vertices away from the fold kept bit for bit: %lld of %lld",
        (long long)found, (long long)nkeep);
  free(keep);
  vm_mesh_destroy(&m);

  /* the pole pushed through the south side: refused, untouched */
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 3, 0, NULL);
  m->xyz[3 * top + 2] = -1.5;
  nv0 = m->nv;
  CHECK(vm_surface_repair(m, &o, &r) == VM_ERR_FORMAT && m->nv == nv0 &&
            m->xyz[3 * top + 2] == -1.5 && strstr(vm_ctx_error(ctx), "intersects itself near") &&
            strstr(vm_ctx_error(ctx), "healing would move the surface by more than twice the "
                                      "local edge length"),
        "a spike through the sphere refused: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
}

/* A model no repair can close: a unit cube and a box touching it along an
 * edge (an edge of four faces), and a third box 3 away with a triangle
 * missing (a hole). Refused by the repair; wrapped (alpha 0.5, offset
 * 0.01) it is closed, manifold and consistently oriented, in two parts
 * (the ball of radius alpha neither bridges the gap nor enters the hole,
 * whose inscribed circle's radius is 0.29), free of intersections, every
 * vertex of the wrap at the offset from the input, and its volume the
 * input's 3, grown by the offset and the two concave corners the ball
 * cannot reach (at most 2 x 0.5^2 (1 - pi / 4) each). */
static void test_wrap(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  const double c0[3] = {0, 0, 0}, c1[3] = {1, 1, 1}, e0[3] = {1, 1, 0}, e1[3] = {2, 2, 1},
               h0[3] = {5, 0, 0}, h1[3] = {6, 1, 1};
  vm_mesh_create(ctx, &m);
  add_box(m, c0, c1);
  add_box(m, e0, e1);
  add_box(m, h0, h1);
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  in->ne--; /* (the input as given, for the distances) */
  m->ne--;  /* the hole: the third box's last triangle dropped */
  vm_repair_report r;
  vm_repair_opts o = vm_repair_opts_default();
  vm_mesh *tmp = NULL;
  vm_mesh_clone(m, &tmp);
  CHECK(vm_surface_repair(tmp, &o, &r) == VM_ERR_FORMAT, "the soup is refused by the repair (%s)",
        vm_ctx_error(ctx));
  vm_mesh_destroy(&tmp);
  vm_wrap_report w;
  double alpha = 0.5, offset = 0.01;
  int st = vm_surface_wrap(m, alpha, offset, &w);
  CHECK(st == VM_OK && w.nf_in == 35 && w.nf == m->ne && w.nv == m->nv && m->ne > 35,
        "wrapped: %d, %lld faces in, %lld triangles out (%s)", st, (long long)w.nf_in,
        (long long)m->ne, vm_ctx_error(ctx));
  double far = 0, near = INFINITY;
  vm_surface_projector *pr = NULL;
  double *dist = malloc(sizeof *dist * (size_t)m->nv);
  CHECK(dist && vm_surface_projector_create(ctx, in, NULL, &pr) == 0 &&
            vm_surface_projector_distance(pr, m->nv, m->xyz, dist) == 0,
        "the wrap's distances to the input (%s)", vm_ctx_error(ctx));
  for (int64_t v = 0; dist && pr && v < m->nv; v++) {
    far = dist[v] > far ? dist[v] : far;
    near = dist[v] < near ? dist[v] : near;
  }
  vm_surface_projector_destroy(&pr);
  free(dist);
  CHECK(far <= offset * 1.01 && near >= 0.99 * offset,
        "every vertex of the wrap %.4g to %.4g from the input (offset %g)", near, far, offset);
  st = vm_surface_repair(m, &o, &r);
  CHECK(st == VM_OK && r.border_edges == 0 && r.components == 2 && r.self_intersections == 0 &&
            r.merged_vertices == 0 && r.removed_degenerate == 0 && r.united == 0,
        "the wrap is closed, manifold, in 2 parts, free of intersections (%d: %lld border edges, "
        "%lld parts, %lld pairs; %s)",
        st, (long long)r.border_edges, (long long)r.components, (long long)r.self_intersections,
        vm_ctx_error(ctx));
  CHECK(r.volume > 3 && r.volume < 3 + 18 * offset * 1.2 + 4 * 0.25 * (1 - 3.14159265358979 / 4),
        "the wrap's volume %.6g (3 inside)", r.volume);
  CHECK(vm_surface_wrap(m, 0, offset, NULL) == VM_ERR_ARG &&
            vm_surface_wrap(m, alpha, NAN, NULL) == VM_ERR_ARG,
        "alpha and offset must be positive and finite");
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  test_good_and_reoriented(ctx);
  test_soup_cleanup(ctx);
  test_refusals(ctx);
  test_union(ctx);
  test_heal(ctx);
  test_wrap(ctx);
  test_zero_area(ctx);
  test_features(ctx);
  test_remesh(ctx);
  test_projector(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("repair");
}
