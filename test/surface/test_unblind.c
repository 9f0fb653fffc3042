/* test/surface/test_unblind.c: the direction that sees a vertex's
 * triangles best (vm_visible_direction) and the folds taken out of a
 * surface where there is none (vm_surface_unblind).
 *  - Known answers: one normal (margin 1), a cube corner (1/sqrt 3 along
 *    the diagonal), a wedge of half-angle a (cos a, also at a = 89.9
 *    degrees), two opposite normals (no direction: at most 0); and on 200 pseudo-random
 *    sets of 3 to 9 normals in a cap, no direction of a 20,000-point
 *    spiral on the sphere sees them better than the answer, and the
 *    answer's own least n . e is the margin it returns.
 *  - A flap folded flat: a vertex of a cube's face grid pushed in the
 *    face's plane past its neighbour turns triangles over onto their
 *    neighbours (normals exactly opposite): it and its neighbours are
 *    blind. Afterwards none is, the surface is closed with Euler
 *    characteristic 2, the volume is 1 to 1e-12 (every move in the plane;
 *    the change measured between the patches is under half an edge),
 *    every vertex left is an input vertex bit for bit with its field
 *    value, at most two vertices went, and two runs give the same mesh.
 *  - With reach 0 nothing is done: the mesh is unchanged and the report
 *    says how many are left.
 *  - The same fold lifted out of the plane by 1e-5 (no two triangles
 *    intersect) through vm_surface_run, step repair: no blind vertex left.
 *  - A cap on a crease: a point inserted into a triangle beside the cube's
 *    edge, 1e-5 of the edge from it, makes a triangle with an angle of
 *    179.99 degrees. Its long edge (the crease) is flipped: no cap left,
 *    no vertex removed, every vertex bit for bit, closed, the volume
 *    within 1e-6 of 1, and the smallest angle far above the cap's.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/cleanup.h"
#include "varmesh/surface.h"
#include "varmesh/surface_mesh.h"
#include "support/check_surface.h"
#include "vmtest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define N 6

static int32_t vid[N + 1][N + 1][N + 1];

static void unit(double *n, double x, double y, double z) {
  double l = sqrt(x * x + y * y + z * z);
  n[0] = x / l, n[1] = y / l, n[2] = z / l;
}

static void test_visible(void) {
  double n[3 * 9], e[3];
  unit(n, 0, 0, 1);
  double m = vm_visible_direction(n, 1, e);
  CHECK(fabs(m - 1) < 1e-15 && fabs(e[2] - 1) < 1e-15, "one normal: %g", m);
  unit(n, 1, 0, 0), unit(n + 3, 0, 1, 0), unit(n + 6, 0, 0, 1);
  m = vm_visible_direction(n, 3, e);
  CHECK(fabs(m - 1 / sqrt(3.0)) < 1e-14 && fabs(e[0] - e[1]) < 1e-14 && fabs(e[1] - e[2]) < 1e-14,
        "cube corner: %.17g (%g %g %g)", m, e[0], e[1], e[2]);
  for (int k = 0; k < 3; k++) {
    double a = (k == 0 ? 30 : k == 1 ? 80 : 89.9) * M_PI / 180;
    unit(n, sin(a), 0, cos(a)), unit(n + 3, -sin(a), 0, cos(a)), unit(n + 6, 0, sin(a), cos(a));
    m = vm_visible_direction(n, 3, e);
    CHECK(fabs(m - cos(a)) < 1e-12 && fabs(e[2] - 1) < 1e-12, "wedge %g deg: %.17g, want %.17g",
          a * 180 / M_PI, m, cos(a));
  }
  unit(n, 1, 0, 0), unit(n + 3, -1, 0, 0), unit(n + 6, 0, 0, 1);
  m = vm_visible_direction(n, 3, e);
  CHECK(m <= 1e-15, "opposite normals: %g", m);
  CHECK(vm_visible_direction(n, 0, e) == -1, "no normal");
  /* against a dense spiral of directions */
  uint64_t s = 12345;
  int worse = 0, wrong = 0;
  for (int set = 0; set < 200; set++) {
    int k = 3 + set % 7;
    for (int i = 0; i < k; i++) {
      double r[3];
      for (int c = 0; c < 3; c++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        r[c] = (double)(s >> 11) / 9007199254740992.0 - 0.5;
      }
      unit(n + 3 * i, r[0], r[1], r[2] + 0.6);
    }
    m = vm_visible_direction(n, k, e);
    double own = INFINITY;
    for (int i = 0; i < k; i++) {
      double d = n[3 * i] * e[0] + n[3 * i + 1] * e[1] + n[3 * i + 2] * e[2];
      if (d < own) own = d;
    }
    wrong += fabs(own - m) > 1e-12;
    const int P = 20000;
    for (int j = 0; j < P; j++) {
      double z = 1 - (2 * j + 1.0) / P, rr = sqrt(1 - z * z), ph = j * 2.399963229728653;
      double u[3] = {rr * cos(ph), rr * sin(ph), z}, mm = INFINITY;
      for (int i = 0; i < k; i++) {
        double d = n[3 * i] * u[0] + n[3 * i + 1] * u[1] + n[3 * i + 2] * u[2];
        if (d < mm) mm = d;
      }
      if (mm > m + 1e-12) {
        worse++;
        break;
      }
    }
  }
  CHECK(worse == 0 && wrong == 0, "random sets: %d beaten by a sampled direction, %d not their own",
        worse, wrong);
}

/* the cube with the flap: vertex (3, 3, 0) of the z = 0 face pushed in
 * the plane past its neighbour (4, 3, 0), and lifted by `lift` (outwards:
 * -z); an id field on the vertices */
static vm_mesh *folded(vm_ctx *ctx, double lift) {
  vm_mesh *m = chk_grid_cube(ctx, N, 1, &vid[0][0][0]);
  CHECK(m != NULL, "mesh");
  if (!m) return NULL;
  double *p = m->xyz + 3 * (int64_t)vid[3][3][0];
  p[0] = (4 + 0.3) / N;
  p[2] = -lift;
  vm_field *fld = NULL;
  CHECK(vm_mesh_add_field(m, "id", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &fld) == 0, "field");
  for (int64_t v = 0; v < m->nv; v++) ((int32_t *)fld->data)[v] = (int32_t)(7 * v + 3);
  return m;
}

static void test_flap(vm_ctx *ctx) {
  vm_mesh *m = folded(ctx, 0), *in = NULL, *again = NULL;
  if (!m) return;
  vm_mesh_clone(m, &in);
  vm_mesh_clone(m, &again);
  int64_t b0 = vm_surface_count_blind(m, 1e-3, NULL);
  CHECK(b0 >= 1, "the fold makes blind vertices: %lld", (long long)b0);
  vm_unblind_report r;
  CHECK(vm_surface_unblind(m, NULL, &r) == 0, "unblind: %s", vm_ctx_error(ctx));
  fprintf(stderr,
          "flap: blind %lld -> %lld, %lld collapses, %lld flips, moved %g, %lld -> %lld vertices\n",
          (long long)r.blind_in, (long long)r.blind, (long long)r.collapses, (long long)r.flips,
          r.max_dev, (long long)in->nv, (long long)m->nv);
  CHECK(r.blind_in == b0 && r.blind == 0, "blind %lld -> %lld", (long long)r.blind_in,
        (long long)r.blind);
  CHECK(vm_surface_count_blind(m, 1e-3, NULL) == 0, "blind vertices counted afterwards");
  CHECK(r.max_dev < 0.5 / N, "moved less than half an edge: %g", r.max_dev);
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed, Euler characteristic %lld", (long long)chi);
  CHECK(fabs(chk_volume(m) - 1) < 1e-12, "volume %.17g", chk_volume(m));
  CHECK(m->nv >= in->nv - 2 && m->nv < in->nv + 1, "vertices %lld -> %lld", (long long)in->nv,
        (long long)m->nv);
  const vm_field *fi = vm_mesh_find_field(in, "id", VM_FIELD_VERTEX),
                 *fo = vm_mesh_find_field(m, "id", VM_FIELD_VERTEX);
  CHECK(fo != NULL, "the id field is kept");
  int64_t lost = 0;
  for (int64_t v = 0; fo && v < m->nv; v++) {
    int32_t id = ((const int32_t *)fo->data)[v];
    int64_t w = (id - 3) / 7;
    if (w < 0 || w >= in->nv || ((const int32_t *)fi->data)[w] != id ||
        memcmp(in->xyz + 3 * w, m->xyz + 3 * v, 3 * sizeof *m->xyz))
      lost++;
  }
  CHECK(lost == 0, "%lld vertices not an input vertex with its id", (long long)lost);
  vm_unblind_report r2;
  CHECK(vm_surface_unblind(again, NULL, &r2) == 0, "unblind again");
  CHECK(again->nv == m->nv && again->ne == m->ne &&
            !memcmp(again->xyz, m->xyz, 3 * (size_t)m->nv * sizeof *m->xyz) &&
            !memcmp(again->conn, m->conn, 3 * (size_t)m->ne * sizeof *m->conn),
        "the same mesh twice");
  /* reach 0: nothing done */
  vm_mesh *z = NULL;
  vm_mesh_clone(in, &z);
  vm_unblind_opts o = vm_unblind_opts_default();
  o.reach = 0;
  CHECK(vm_surface_unblind(z, &o, &r2) == 0, "unblind, reach 0");
  CHECK(r2.blind == r2.blind_in && r2.blind_in == b0 && r2.flips + r2.collapses == 0 &&
            z->nv == in->nv && z->ne == in->ne &&
            !memcmp(z->xyz, in->xyz, 3 * (size_t)in->nv * sizeof *in->xyz) &&
            !memcmp(z->conn, in->conn, 3 * (size_t)in->ne * sizeof *in->conn),
        "reach 0: left as it was, %lld left", (long long)r2.blind);
  vm_mesh_destroy(&z);
  vm_mesh_destroy(&again);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

static void test_run(vm_ctx *ctx) {
  vm_mesh *m = folded(ctx, 1e-5);
  if (!m) return;
  int64_t b0 = vm_surface_count_blind(m, 1e-3, NULL), pairs = -1;
  CHECK(vm_surface_self_intersections(m, &pairs, NULL) == 0 && pairs == 0,
        "the lifted fold intersects nothing: %lld pairs", (long long)pairs);
  vm_surface_opts o = vm_surface_opts_default();
  o.step = VM_SURFACE_REPAIR;
  vm_surface_summary s;
  int st = vm_surface_run(ctx, m, &o, &s);
  CHECK(st >= 0, "run: %s", vm_ctx_error(ctx));
  CHECK(b0 >= 1 && s.unblind.blind_in == b0 && s.unblind.blind == 0 && !s.unblind.undone,
        "through the run: %lld -> %lld blind (%lld before)", (long long)s.unblind.blind_in,
        (long long)s.unblind.blind, (long long)b0);
  CHECK(vm_surface_count_blind(m, 1e-3, NULL) == 0, "none left");
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed, Euler characteristic %lld", (long long)chi);
  vm_mesh_destroy(&m);
}

static double min_angle(const vm_mesh *m) {
  double a = 180;
  for (int64_t e = 0; e < m->ne; e++)
    for (int i = 0; i < 3; i++) {
      const double *p = m->xyz + 3 * (int64_t)m->conn[3 * e + i],
                   *q = m->xyz + 3 * (int64_t)m->conn[3 * e + (i + 1) % 3],
                   *r = m->xyz + 3 * (int64_t)m->conn[3 * e + (i + 2) % 3];
      double u[3], w[3], c[3];
      for (int k = 0; k < 3; k++) u[k] = q[k] - p[k], w[k] = r[k] - p[k];
      c[0] = u[1] * w[2] - u[2] * w[1], c[1] = u[2] * w[0] - u[0] * w[2],
      c[2] = u[0] * w[1] - u[1] * w[0];
      double d = atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                       u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) *
                 180 / M_PI;
      if (d < a) a = d;
    }
  return a;
}

static void test_cap(vm_ctx *ctx) {
  vm_mesh *m = chk_grid_cube(ctx, N, 1, &vid[0][0][0]);
  CHECK(m != NULL, "mesh");
  if (!m) return;
  /* the triangle on the edge (2, 0, 0) -> (3, 0, 0) of the cube's crease
   * y = z = 0, split at a point 1e-5 of the edge inside it */
  int32_t a = vid[2][0][0], b = vid[3][0][0];
  int64_t f = -1;
  int k = 0;
  for (int64_t e = 0; e < m->ne && f < 0; e++)
    for (int i = 0; i < 3; i++)
      if (m->conn[3 * e + i] == a && m->conn[3 * e + (i + 1) % 3] == b) f = e, k = i;
  CHECK(f >= 0, "the crease edge");
  if (f < 0) {
    vm_mesh_destroy(&m);
    return;
  }
  int32_t d = m->conn[3 * f + (k + 2) % 3];
  const double *pa = m->xyz + 3 * (int64_t)a, *pb = m->xyz + 3 * (int64_t)b,
               *pd = m->xyz + 3 * (int64_t)d;
  double mid[3], to[3], l = 0;
  for (int r = 0; r < 3; r++) mid[r] = (pa[r] + pb[r]) / 2, to[r] = pd[r] - mid[r];
  for (int r = 0; r < 3; r++) l += to[r] * to[r];
  l = sqrt(l);
  int64_t c = 0;
  CHECK(vm_mesh_add_vertex(m, mid[0] + 1e-5 / N * to[0] / l, mid[1] + 1e-5 / N * to[1] / l,
                           mid[2] + 1e-5 / N * to[2] / l, &c) == 0,
        "vertex");
  int32_t t1[3] = {b, d, (int32_t)c}, t2[3] = {d, a, (int32_t)c};
  m->conn[3 * f + (k + 2) % 3] = (int32_t)c; /* (a, b, c): the cap */
  CHECK(vm_mesh_add_element(m, VM_TRI, t1) == 0 && vm_mesh_add_element(m, VM_TRI, t2) == 0,
        "triangles");
  vm_mesh *in = NULL;
  vm_mesh_clone(m, &in);
  double a0 = min_angle(m);
  vm_unblind_report r;
  CHECK(vm_surface_unblind(m, NULL, &r) == 0, "unblind: %s", vm_ctx_error(ctx));
  double a1 = min_angle(m);
  fprintf(stderr, "cap: caps %lld -> %lld, %lld flips; smallest angle %.3g -> %.3g deg\n",
          (long long)r.caps_in, (long long)r.caps, (long long)r.cap_flips, a0, a1);
  CHECK(r.caps_in == 1 && r.caps == 0 && r.cap_flips == 1 && r.blind_in == 0,
        "caps %lld -> %lld, %lld flips, %lld blind", (long long)r.caps_in, (long long)r.caps,
        (long long)r.cap_flips, (long long)r.blind_in);
  CHECK(a0 < 0.01 && a1 > 10, "smallest angle %g -> %g", a0, a1);
  CHECK(m->nv == in->nv && !memcmp(m->xyz, in->xyz, 3 * (size_t)m->nv * sizeof *m->xyz),
        "no vertex moved or removed");
  int64_t chi = 0;
  CHECK(chk_closed_euler(m, &chi) && chi == 2, "closed, Euler characteristic %lld", (long long)chi);
  CHECK(fabs(chk_volume(m) - 1) < 1e-6, "volume %.17g", chk_volume(m));
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  test_visible();
  test_flap(ctx);
  test_run(ctx);
  test_cap(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("unblind");
}
