/* test/surface/test_symmetry.c: half models (varmesh/symmetry.h).
 *  - The plane's syntax: "y=0", "Z=-1.5:-", bad ones refused; the
 *    attribute written shortest and read back bit for bit.
 *  - The unit cube (4 x 4 squares per face) cut at z = 0.3: 0.7 of its
 *    volume and 3.8 of area left, 32 border edges and 32 border vertices
 *    (each face's 4 vertical edges and 4 diagonals crossed), every border
 *    vertex at z == 0.3 exactly, Euler characteristic 1 (a disc), no
 *    zero-area triangle, a linear vertex field interpolated exactly, an
 *    element field copied from the parents; the same cut twice gives the
 *    same bits.
 *  - The cube cut at z = 0.5, a grid line: no edge split, 6 n^2 of its 12
 *    n^2 triangles kept; at z = 0.5 + 1e-12 the ring's 16 vertices are
 *    snapped onto the plane and the result is the same bit for bit.
 *  - An icosphere (level 3) cut at y = 0, a plane of symmetry with
 *    vertices and edges in it: half the area and half the volume (1e-12),
 *    the + and the - side mirror images in counts; cut at z = 0.3, the
 *    default side is the larger one (below), a disc with its border in
 *    the plane, its volume the sphere's less the cap's within 1 %.
 *  - The default side of the cube cut at z = 0.8: below (0.8 of volume).
 *  - Refused: a quad, a side with nothing on it.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support/check_surface.h"
#include "varmesh/shapes.h"
#include "varmesh/cleanup.h"
#include "varmesh/features.h"
#include "varmesh/surface.h"
#include "varmesh/symmetry.h"
#include "vmtest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* V - E + F, border edges, border vertices off coordinate c on axis, and
 * whether any triangle has zero area */
static void topo(const vm_mesh *m, int axis, double c, int64_t *chi, int64_t *nb, int64_t *off,
                 int64_t *zero) {
  int64_t n = 3 * m->ne;
  uint64_t *k = malloc((size_t)(n > 0 ? n : 1) * sizeof *k);
  for (int64_t e = 0; e < m->ne; e++)
    for (int i = 0; i < 3; i++) {
      uint32_t a = (uint32_t)m->conn[3 * e + i], b = (uint32_t)m->conn[3 * e + (i + 1) % 3];
      k[3 * e + i] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
    }
  qsort(k, (size_t)n, sizeof *k, chk_cmp_u64);
  int64_t ne = 0;
  *nb = *off = *zero = 0;
  for (int64_t i = 0; i < n;) {
    int64_t j = i + 1;
    while (j < n && k[j] == k[i]) j++;
    ne++;
    if (j == i + 1) {
      (*nb)++;
      uint32_t a = (uint32_t)(k[i] >> 32), b = (uint32_t)k[i];
      *off += m->xyz[3 * (int64_t)a + axis] != c || m->xyz[3 * (int64_t)b + axis] != c;
    }
    i = j;
  }
  *chi = m->nv - ne + m->ne;
  for (int64_t e = 0; e < m->ne; e++) {
    const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e],
                 *b = m->xyz + 3 * (int64_t)m->conn[3 * e + 1],
                 *d = m->xyz + 3 * (int64_t)m->conn[3 * e + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2],
           z = u[0] * w[1] - u[1] * w[0];
    *zero += x == 0 && y == 0 && z == 0;
  }
  free(k);
}

static double area(const vm_mesh *m) {
  double s = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e],
                 *b = m->xyz + 3 * (int64_t)m->conn[3 * e + 1],
                 *d = m->xyz + 3 * (int64_t)m->conn[3 * e + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2],
           z = u[0] * w[1] - u[1] * w[0];
    s += sqrt(x * x + y * y + z * z) / 2;
  }
  return s;
}

/* The volume between an open surface whose border lies in x[axis] = c and
 * that plane: the divergence theorem with the field (x[axis] - c) e_axis,
 * which vanishes on the plane. */
static double half_volume(const vm_mesh *m, int axis, double c) {
  double v = 0;
  int p = (axis + 1) % 3, q = (axis + 2) % 3;
  for (int64_t e = 0; e < m->ne; e++) {
    const double *a = m->xyz + 3 * (int64_t)m->conn[3 * e],
                 *b = m->xyz + 3 * (int64_t)m->conn[3 * e + 1],
                 *d = m->xyz + 3 * (int64_t)m->conn[3 * e + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    double n = u[p] * w[q] - u[q] * w[p]; /* twice the area times the normal's axis part */
    v += ((a[axis] + b[axis] + d[axis]) / 3 - c) * n / 2;
  }
  return v;
}

static void test_parse(vm_ctx *ctx) {
  int axis, side;
  double c;
  CHECK(vm_axis_plane_parse(ctx, "y=0", &axis, &c, &side) == VM_OK && axis == 1 && c == 0 &&
            side == 0,
        "y=0");
  CHECK(vm_axis_plane_parse(ctx, "Z=-1.5:-", &axis, &c, &side) == VM_OK && axis == 2 && c == -1.5 &&
            side == -1,
        "Z=-1.5:-");
  CHECK(vm_axis_plane_parse(ctx, "x=2e-3:+", &axis, &c, &side) == VM_OK && axis == 0 && c == 2e-3 &&
            side == 1,
        "x=2e-3:+");
  const char *bad[] = {"", "y", "y=", "w=0", "y=0:", "y=0:*", "y=nan", "y=1e999", "y=0 ", "y0"};
  for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
    CHECK(vm_axis_plane_parse(ctx, bad[i], &axis, &c, &side) == VM_ERR_ARG, "'%s' accepted",
          bad[i]);
  vm_ctx_clear_error(ctx);
  CHECK(vm_axis_plane_parse(ctx, "y=0:-", &axis, &c, NULL) == VM_ERR_ARG, "side not asked for");
  vm_ctx_clear_error(ctx);
  char buf[64];
  CHECK(!strcmp(vm_axis_plane_format(1, 0, buf, sizeof buf), "y=0"), "%s", buf);
  CHECK(!strcmp(vm_axis_plane_format(2, -1.25, buf, sizeof buf), "z=-1.25"), "%s", buf);
  vm_axis_plane_format(0, 0.1, buf, sizeof buf);
  CHECK(!strcmp(buf, "x=0.1") && strtod(buf + 2, NULL) == 0.1, "%s", buf);
  double odd = 1.0 / 3;
  vm_axis_plane_format(0, odd, buf, sizeof buf);
  CHECK(strtod(buf + 2, NULL) == odd, "%s", buf);
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_mesh_get_symmetry_plane(m, &axis, &c) == 0, "no attribute");
  vm_mesh_set_symmetry_plane(m, 1, odd);
  CHECK(vm_mesh_get_symmetry_plane(m, &axis, &c) == 1 && axis == 1 && c == odd, "round trip");
  vm_mesh_set_attr(m, VM_SYMMETRY_PLANE_ATTR, "q=1");
  CHECK(vm_mesh_get_symmetry_plane(m, &axis, &c) == VM_ERR_FORMAT, "malformed");
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&m);
}

static void test_cube(vm_ctx *ctx) {
  const int n = 4;
  int32_t vid[(n + 1) * (n + 1) * (n + 1)];
  vm_mesh *m = chk_grid_cube(ctx, n, 1, vid), *m2 = NULL;
  vm_field *f = NULL, *g = NULL;
  vm_mesh_add_field(m, "lin", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    ((double *)f->data)[v] = p[0] + 2 * p[1] + 3 * p[2];
  }
  vm_mesh_add_field(m, "id", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &g);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)g->data)[e] = (int32_t)e;
  const int64_t nf0 = m->ne;
  vm_mesh_clone(m, &m2);
  vm_cut_report r;
  int st = vm_mesh_cut_plane(m, 2, 0.3, 1, 0, &r);
  CHECK(st == VM_OK, "cut: %s", vm_ctx_error(ctx));
  int64_t chi, nb, off, zero, nbv = 0;
  topo(m, 2, 0.3, &chi, &nb, &off, &zero);
  for (int64_t v = 0; v < m->nv; v++) nbv += m->xyz[3 * v + 2] == 0.3;
  CHECK(chi == 1 && nb == 32 && off == 0 && zero == 0 && nbv == 32,
        "cube z=0.3: chi %lld, %lld border edges, %lld off, %lld zero, %lld in the plane",
        (long long)chi, (long long)nb, (long long)off, (long long)zero, (long long)nbv);
  CHECK(r.border_edges == 32 && r.border_off == 0 && r.split_edges == 32 && r.snapped == 0 &&
            r.degenerate == 0 && r.side == 1 && r.nf == m->ne,
        "report: %lld border, %lld split, %lld snapped", (long long)r.border_edges,
        (long long)r.split_edges, (long long)r.snapped);
  CHECK_NEAR(half_volume(m, 2, 0.3), 0.7, 1e-14, "cube z=0.3 volume");
  CHECK_NEAR(area(m), 3.8, 1e-13, "cube z=0.3 area");
  f = vm_mesh_find_field(m, "lin", VM_FIELD_VERTEX);
  g = vm_mesh_find_field(m, "id", VM_FIELD_ELEMENT);
  double ferr = 0;
  int gok = 1;
  for (int64_t v = 0; f && v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    ferr = fmax(ferr, fabs(((double *)f->data)[v] - (p[0] + 2 * p[1] + 3 * p[2])));
  }
  for (int64_t e = 0; g && e < m->ne; e++)
    gok &= ((int32_t *)g->data)[e] >= 0 && ((int32_t *)g->data)[e] < nf0;
  CHECK(f && g && ferr < 1e-14 && gok, "fields: linear off by %g", ferr);
  vm_mesh_cut_plane(m2, 2, 0.3, 1, 0, NULL);
  CHECK(m2->nv == m->nv && m2->ne == m->ne &&
            !memcmp(m2->xyz, m->xyz, 3 * (size_t)m->nv * sizeof *m->xyz) &&
            !memcmp(m2->conn, m->conn, 3 * (size_t)m->ne * sizeof *m->conn),
        "the same cut twice differs");
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&m2);

  /* on a grid line, and just off it: snapped */
  m = chk_grid_cube(ctx, n, 1, vid);
  m2 = chk_grid_cube(ctx, n, 1, vid);
  st = vm_mesh_cut_plane(m, 2, 0.5, 1, 0, &r);
  CHECK(st == VM_OK && r.split_edges == 0 && r.snapped == 0 && m->ne == 6 * n * n &&
            r.border_edges == 4 * n && r.border_off == 0,
        "cube z=0.5: %lld triangles, %lld split", (long long)m->ne, (long long)r.split_edges);
  CHECK_NEAR(half_volume(m, 2, 0.5), 0.5, 1e-15, "cube z=0.5 volume");
  st = vm_mesh_cut_plane(m2, 2, 0.5 + 1e-12, 1, 0, &r);
  CHECK(st == VM_OK && r.snapped == 4 * n && r.split_edges == 0 && m2->nv == m->nv &&
            m2->ne == m->ne && !memcmp(m2->conn, m->conn, 3 * (size_t)m->ne * sizeof *m->conn),
        "cube z=0.5+1e-12: %lld snapped", (long long)r.snapped);
  int same = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    same &= m2->xyz[3 * v] == m->xyz[3 * v] && m2->xyz[3 * v + 1] == m->xyz[3 * v + 1];
    same &= m2->xyz[3 * v + 2] == (m->xyz[3 * v + 2] == 0.5 ? 0.5 + 1e-12 : m->xyz[3 * v + 2]);
  }
  CHECK(same, "snapped onto 0.5 + 1e-12 bit for bit");
  /* the default side is the larger one: z = 0.3 keeps z >= 0.3 (0.7 deep) */
  vm_mesh_destroy(&m);
  m = chk_grid_cube(ctx, n, 1, vid);
  vm_mesh_cut_plane(m, 2, 0.8, 0, 0, &r);
  CHECK(r.side == -1, "z=0.8: default side %d", r.side);
  CHECK_NEAR(half_volume(m, 2, 0.8), 0.8, 1e-14, "cube z=0.8 - side: volume");
  /* nothing on the side asked for */
  vm_mesh_destroy(&m);
  m = chk_grid_cube(ctx, n, 1, vid);
  CHECK(vm_mesh_cut_plane(m, 0, 2.0, 1, 0, NULL) == VM_ERR_ARG && m->ne == 12 * n * n,
        "x=2 + side: refused, m unchanged");
  vm_ctx_clear_error(ctx);
  int32_t q[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_QUAD, q);
  CHECK(vm_mesh_cut_plane(m, 0, 0.5, 0, 0, NULL) == VM_ERR_ARG, "a quad: refused");
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&m2);
}

static void test_sphere(vm_ctx *ctx) {
  const double o[3] = {0, 0, 0};
  vm_mesh *m = NULL, *p = NULL, *q = NULL;
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, o, 1, 3, 0, NULL);
  const double a0 = area(m), v0 = chk_volume(m);
  vm_mesh_clone(m, &p);
  vm_mesh_clone(m, &q);
  vm_cut_report rp, rq;
  CHECK(vm_mesh_cut_plane(p, 1, 0, 1, 0, &rp) == VM_OK &&
            vm_mesh_cut_plane(q, 1, 0, -1, 0, &rq) == 0,
        "sphere y=0: %s", vm_ctx_error(ctx));
  int64_t chi, nb, off, zero;
  topo(p, 1, 0, &chi, &nb, &off, &zero);
  CHECK(chi == 1 && off == 0 && zero == 0 && nb == rp.border_edges && nb > 0,
        "sphere y=0 +: chi %lld, %lld border, %lld off", (long long)chi, (long long)nb,
        (long long)off);
  CHECK(p->ne == q->ne && p->nv == q->nv && rp.border_edges == rq.border_edges,
        "+ and - sides: %lld / %lld triangles", (long long)p->ne, (long long)q->ne);
  CHECK_NEAR(area(p) / a0, 0.5, 1e-12, "half sphere area");
  CHECK_NEAR(half_volume(p, 1, 0) / v0, 0.5, 1e-12, "half sphere volume");
  CHECK_NEAR(half_volume(q, 1, 0) / v0, 0.5, 1e-12, "other half sphere volume");
  /* an offset plane clips triangles: still a disc, its border in it */
  vm_mesh_destroy(&p);
  vm_mesh_clone(m, &p);
  CHECK(vm_mesh_cut_plane(p, 2, 0.3, 0, 0, &rp) == VM_OK && rp.side == -1 && rp.clipped > 0,
        "sphere z=0.3");
  topo(p, 2, 0.3, &chi, &nb, &off, &zero);
  CHECK(chi == 1 && off == 0 && zero == 0, "sphere z=0.3: chi %lld, %lld off, %lld zero",
        (long long)chi, (long long)off, (long long)zero);
  /* the spherical cap z >= 0.3 has volume pi h^2 (3 - h) / 3, h = 0.7;
     the rest is the polyhedron's volume minus about that */
  double cap = M_PI * 0.49 * (3 - 0.7) / 3;
  CHECK(fabs(half_volume(p, 2, 0.3) - (v0 - cap)) < 0.01 * v0, "sphere z=0.3 volume %g vs %g",
        half_volume(p, 2, 0.3), v0 - cap);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&p);
  vm_mesh_destroy(&q);
}

/* border vertices of m (nface 1 edges), how many are off x[axis] = c */
static int64_t border_off(const vm_mesh *m, int axis, double c, int64_t *nbv) {
  int64_t chi, nb, off, zero;
  topo(m, axis, c, &chi, &nb, &off, &zero);
  *nbv = nb; /* a single loop: as many vertices as edges */
  return off;
}

/* a + b as one mesh */
static vm_mesh *merged(vm_ctx *ctx, const vm_mesh *a, const vm_mesh *b) {
  vm_mesh *m = NULL;
  vm_mesh_clone(a, &m);
  int64_t base = m->nv;
  for (int64_t v = 0; v < b->nv; v++)
    vm_mesh_add_vertex(m, b->xyz[3 * v], b->xyz[3 * v + 1], b->xyz[3 * v + 2], NULL);
  for (int64_t e = 0; e < b->ne; e++) {
    int32_t t[3];
    for (int i = 0; i < 3; i++) t[i] = (int32_t)(b->conn[3 * e + i] + base);
    vm_mesh_add_element(m, VM_TRI, t);
  }
  (void)ctx;
  return m;
}

static vm_mesh *hemisphere(vm_ctx *ctx, int level, double cx) {
  const double o[3] = {cx, 0, 0};
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, o, 1, level, 0, NULL);
  vm_mesh_cut_plane(m, 2, 0, 1, 0, NULL);
  return m;
}

static void test_detect(vm_ctx *ctx) {
  vm_symmetry_report r;
  vm_symmetry_opts o = {0};
  /* a hemisphere: z = 0 found, nothing to snap */
  vm_mesh *m = hemisphere(ctx, 3, 0);
  int st = vm_symmetry_detect(m, &o, &r);
  int axis = -1;
  double c = 1;
  CHECK(st == VM_OK && r.found && r.axis == 2 && r.value == 0 && r.side == 1 && r.loops == 1 &&
            r.border_edges == r.border_vertices && r.border_edges > 0 && r.snapped == 0 &&
            vm_mesh_get_symmetry_plane(m, &axis, &c) == 1 && axis == 2 && c == 0,
        "hemisphere: found %d axis %d value %g side %d, %lld loops", r.found, r.axis, r.value,
        r.side, (long long)r.loops);
  /* every other border vertex 1e-8 off (within 1e-6 of the diagonal): snapped */
  vm_mesh_remove_field(m, "x", VM_FIELD_VERTEX);
  int64_t k = 0, nbv = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->xyz[3 * v + 2] == 0 && k++ % 2) m->xyz[3 * v + 2] = 1e-8;
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_OK && r.found && r.value == 0 && r.snapped == k / 2 &&
            border_off(m, 2, 0, &nbv) == 0 && fabs(r.max_offset - 1e-8) < 1e-20,
        "hemisphere, border 1e-8 off: %lld snapped of %lld", (long long)r.snapped, (long long)k);
  /* given: z = 0 accepted; z = 0.01 refused, saying the farthest vertex */
  o.given = 1, o.axis = 2, o.value = 0;
  CHECK(vm_symmetry_detect(m, &o, &r) == VM_OK && r.found && r.given == 1, "given z=0");
  o.value = 0.01;
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "not in the symmetry plane z=0.01") &&
            strstr(vm_ctx_error(ctx), "by 0.01"),
        "given z=0.01: %s", vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  o.given = 0;
  /* the attribute names the plane: taken as given */
  vm_mesh_set_attr(m, VM_SYMMETRY_PLANE_ATTR, "z=0.5");
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "attribute symmetry_plane"),
        "attribute z=0.5: %s", vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  vm_mesh_set_attr(m, VM_SYMMETRY_PLANE_ATTR, "z=0");
  /* the wall on both sides: a few vertices pushed below the plane */
  vm_mesh *w = NULL;
  vm_mesh_clone(m, &w);
  for (int64_t v = 0; v < w->nv; v++)
    if (w->xyz[3 * v + 2] > 0.9) w->xyz[3 * v + 2] -= 2.5;
  st = vm_symmetry_detect(w, &o, &r);
  CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "both sides"), "both sides: %s",
        vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&w);
  /* tilted: the hemisphere turned by 20 degrees about x: no plane */
  vm_mesh_destroy(&m);
  m = hemisphere(ctx, 3, 0);
  const double ca = cos(20 * M_PI / 180), sa = sin(20 * M_PI / 180);
  for (int64_t v = 0; v < m->nv; v++) {
    double y = m->xyz[3 * v + 1], z = m->xyz[3 * v + 2];
    m->xyz[3 * v + 1] = ca * y - sa * z;
    m->xyz[3 * v + 2] = sa * y + ca * z;
  }
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_OK && !r.found && strstr(r.why, "in no plane") &&
            !vm_mesh_get_attr(m, VM_SYMMETRY_PLANE_ATTR),
        "tilted: found %d: %s", r.found, r.why);
  o.given = 1, o.axis = 2, o.value = 0;
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "the farthest ("), "tilted, given: %s",
        vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  o.given = 0;
  vm_mesh_destroy(&m);
  /* two planes: the cube without its top and bottom faces */
  const int n = 4;
  int32_t vid[(n + 1) * (n + 1) * (n + 1)];
  vm_mesh *cube = chk_grid_cube(ctx, n, 1, vid);
  vm_mesh_create(ctx, &m);
  vm_mesh_set_vertices(m, cube->nv);
  memcpy(m->xyz, cube->xyz, 3 * (size_t)cube->nv * sizeof *m->xyz);
  for (int64_t e = 0; e < cube->ne; e++) {
    const int32_t *t = cube->conn + 3 * e;
    int top = 1, bottom = 1;
    for (int i = 0; i < 3; i++)
      top &= cube->xyz[3 * (int64_t)t[i] + 2] == 1, bottom &= cube->xyz[3 * (int64_t)t[i] + 2] == 0;
    if (!top && !bottom) vm_mesh_add_element(m, VM_TRI, t);
  }
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_OK && !r.found && r.loops == 2 && strstr(r.why, "different planes: z=0") &&
            strstr(r.why, "z=1"),
        "two planes: %s", r.why);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&cube);
  /* crossing loops: two hemispheres 1 apart */
  vm_mesh *h1 = hemisphere(ctx, 3, 0), *h2 = hemisphere(ctx, 3, 1);
  m = merged(ctx, h1, h2);
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "cross each other"), "crossing: %s",
        vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&h2);
  /* two hemispheres apart: one plane, two loops, accepted */
  h2 = hemisphere(ctx, 3, 3);
  m = merged(ctx, h1, h2);
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_OK && r.found && r.loops == 2, "two loops in z=0: found %d, %lld loops", r.found,
        (long long)r.loops);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&h1);
  vm_mesh_destroy(&h2);
  /* closed, plane given: refused; closed, not given: nothing */
  const double oo[3] = {0, 0, 0};
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, oo, 1, 2, 0, NULL);
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_OK && !r.found && r.border_edges == 0 && !r.why[0], "closed sphere");
  o.given = 1;
  st = vm_symmetry_detect(m, &o, &r);
  CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "closed"), "closed, given: %s",
        vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&m);
}

/* The surface stage on a hemisphere (icosphere level 4 cut at z = 0), its
 * equator on z = 0, turned inside out first: found, turned outward,
 * remeshed (uniform, to about 2,000 triangles) and adapted; every border
 * vertex of the result at z == 0 bit for bit, none below, the volume it
 * bounds with the plane 2 pi / 3 within 1 %. */
static void test_stage(vm_ctx *ctx) {
  vm_mesh *m = hemisphere(ctx, 4, 0);
  for (int64_t e = 0; e < m->ne; e++) {
    int32_t t = m->conn[3 * e + 1];
    m->conn[3 * e + 1] = m->conn[3 * e + 2];
    m->conn[3 * e + 2] = t;
  }
  vm_surface_opts o = vm_surface_opts_default();
  o.size = VM_SURFACE_SIZE_UNIFORM;
  o.remesh = VM_SURFACE_YES;
  o.triangles = 2000;
  o.adapt.max_iter = 40;
  vm_surface_summary s;
  int st = vm_surface_run(ctx, m, &o, &s);
  int64_t nbv = 0, below = 0;
  int64_t off = border_off(m, 2, 0, &nbv);
  for (int64_t v = 0; v < m->nv; v++) below += m->xyz[3 * v + 2] < 0;
  int axis = -1;
  double c = 1;
  CHECK(st == VM_OK && s.symmetry.found && s.symmetry_reoriented && s.remeshed && s.adapted &&
            off == 0 && below == 0 && nbv > 0 && s.symmetry_border == nbv && s.symmetry_off == 0 &&
            vm_mesh_get_symmetry_plane(m, &axis, &c) == 1 && axis == 2 && c == 0,
        "hemisphere through the stage: %d (%s), found %d, reoriented %d, %lld of %lld border "
        "vertices off, %lld below",
        st, vm_ctx_error(ctx), s.symmetry.found, s.symmetry_reoriented, (long long)off,
        (long long)nbv, (long long)below);
  CHECK_NEAR(vm_symmetry_half_volume(m, 2, 0) / (2 * M_PI / 3), 1, 0.01, "hemisphere volume");
  CHECK(vm_surface_min_angle(m) > 25, "smallest angle %g", vm_surface_min_angle(m));
  fprintf(stderr,
          "hemisphere: %lld triangles, %lld border vertices, smallest angle %.2f, "
          "volume/(2pi/3) %.5f, %lld border vertices put back, drift %g\n",
          (long long)m->ne, (long long)nbv, vm_surface_min_angle(m),
          vm_symmetry_half_volume(m, 2, 0) / (2 * M_PI / 3), (long long)s.symmetry_resnapped,
          s.symmetry_drift);
  /* a wrap asked for: refused */
  vm_mesh_destroy(&m);
  m = hemisphere(ctx, 3, 0);
  o = vm_surface_opts_default();
  o.wrap = 0.01;
  st = vm_surface_run(ctx, m, &o, &s);
  CHECK(st == VM_ERR_ARG && strstr(vm_ctx_error(ctx), "not wrapped"), "wrap: %s",
        vm_ctx_error(ctx));
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&m);
}

/* The sliver removal along a half model's border (border_collapse): a
 * hemisphere's border edge split 1 % from an end makes a needle there;
 * with border_collapse the new vertex is collapsed along the border (the
 * vertex count back, the border at z == 0 exactly, the smallest angle the
 * hemisphere's); without it the border vertex stays and so does the
 * needle. */
static void test_border_collapse(vm_ctx *ctx) {
  for (int on = 0; on < 2; on++) {
    vm_mesh *m = hemisphere(ctx, 3, 0);
    const int64_t nv0 = m->nv;
    const double amin0 = vm_surface_min_angle(m);
    int64_t f = -1;
    int i0 = 0;
    for (int64_t e = 0; e < m->ne && f < 0; e++)
      for (int i = 0; i < 3 && f < 0; i++)
        if (m->xyz[3 * (int64_t)m->conn[3 * e + i] + 2] == 0 &&
            m->xyz[3 * (int64_t)m->conn[3 * e + (i + 1) % 3] + 2] == 0)
          f = e, i0 = i;
    int32_t a = m->conn[3 * f + i0], b = m->conn[3 * f + (i0 + 1) % 3],
            c = m->conn[3 * f + (i0 + 2) % 3];
    const double *pa = m->xyz + 3 * (int64_t)a, *pb = m->xyz + 3 * (int64_t)b;
    int64_t sv = -1;
    vm_mesh_add_vertex(m, pa[0] + 0.01 * (pb[0] - pa[0]), pa[1] + 0.01 * (pb[1] - pa[1]), 0, &sv);
    m->conn[3 * f + (i0 + 1) % 3] = (int32_t)sv; /* (a, s, c) */
    int32_t t2[3] = {(int32_t)sv, b, c};
    vm_mesh_add_element(m, VM_TRI, t2);
    vm_surface_features ft;
    vm_surface_detect_features(m, 20, 50, &ft);
    vm_cleanup_opts o = vm_cleanup_opts_default();
    o.border_collapse = on;
    vm_cleanup_report r;
    int st = vm_surface_cleanup(m, &ft, &o, &r);
    vm_surface_features_free(ctx, &ft);
    int64_t nbv = 0, off = border_off(m, 2, 0, &nbv);
    if (on)
      CHECK(st == VM_OK && r.border_collapses >= 1 && m->nv == nv0 && off == 0 &&
                vm_surface_min_angle(m) >= amin0 - 1e-9,
            "border collapse: %lld along the border, %lld vertices (%lld), %lld off, smallest "
            "angle %g (%g)",
            (long long)r.border_collapses, (long long)m->nv, (long long)nv0, (long long)off,
            vm_surface_min_angle(m), amin0);
    else
      CHECK(st == VM_OK && r.border_collapses == 0 && m->nv == nv0 + 1 && off == 0 &&
                vm_surface_min_angle(m) < 2,
            "no border collapse: %lld vertices, smallest angle %g", (long long)m->nv,
            vm_surface_min_angle(m));
    vm_mesh_destroy(&m);
  }
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  test_parse(ctx);
  test_cube(ctx);
  test_sphere(ctx);
  test_detect(ctx);
  test_stage(ctx);
  test_border_collapse(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_symmetry");
}
