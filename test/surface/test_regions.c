/* test/surface/test_regions.c: regions (int element fields) and vertex
 * fields through the surface stage's remeshings.
 *  - The generated aircraft with its "component" field, remeshed to sizes
 *    from the curvature and to one edge length: every component keeps its
 *    area within 0.5 %, every border vertex of the result lies on a border
 *    of the input (the borders are kept as lines), and a vertex field equal
 *    to x is carried as x (linear interpolation on the input).
 *  - The graded wing (rows of needles) with a region field splitting it at
 *    mid-chord, through the stage's defaults (the input remeshed because of
 *    its needles): the region is kept instead of blocking the remeshing,
 *    with its area within 0.5 %. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/aircraft.h"
#include "varmesh/shapes.h"
#include "varmesh/surface.h"
#include "vmtest.h"

static double tri_area(const vm_mesh *m, int64_t e) {
  const int32_t *c = m->conn + m->eoff[e];
  const double *a = m->xyz + 3 * (int64_t)c[0], *b = m->xyz + 3 * (int64_t)c[1],
               *d = m->xyz + 3 * (int64_t)c[2];
  double u[3], v[3], w[3];
  for (int i = 0; i < 3; i++) u[i] = b[i] - a[i], v[i] = d[i] - a[i];
  w[0] = u[1] * v[2] - u[2] * v[1];
  w[1] = u[2] * v[0] - u[0] * v[2];
  w[2] = u[0] * v[1] - u[1] * v[0];
  return 0.5 * sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}

/* Area per value 0..nr-1 of the element field `name`; -1 if a value is out
 * of range. */
static int region_areas(const vm_mesh *m, const char *name, int nr, double *area) {
  const vm_field *f = vm_mesh_find_field(m, name, VM_FIELD_ELEMENT);
  if (!f || f->type != VM_FIELD_I32 || f->ncomp != 1) return -1;
  for (int r = 0; r < nr; r++) area[r] = 0;
  const int32_t *d = f->data;
  for (int64_t e = 0; e < m->ne; e++) {
    if (d[e] < 0 || d[e] >= nr) return -1;
    area[d[e]] += tri_area(m, e);
  }
  return 0;
}

static int cmp_key(const void *x, const void *y) {
  const int64_t *a = x, *b = y;
  for (int i = 0; i < 3; i++)
    if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
  return 0;
}

/* Border edges of the field `name` of m (pairs of vertex coordinates, 6
 * doubles each); *n their number. */
static double *border_segments(const vm_mesh *m, const char *name, int64_t *n) {
  const vm_field *f = vm_mesh_find_field(m, name, VM_FIELD_ELEMENT);
  const int32_t *d = f->data;
  double *seg = malloc(18 * (size_t)m->ne * sizeof *seg);
  *n = 0;
  /* the two faces of an edge: neighbours once the keys are sorted */
  int64_t ne3 = 3 * m->ne;
  int64_t(*key)[3] = malloc((size_t)ne3 * sizeof *key);
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    for (int i = 0; i < 3; i++) {
      int64_t a = c[i], b = c[(i + 1) % 3];
      key[3 * e + i][0] = a < b ? a : b;
      key[3 * e + i][1] = a < b ? b : a;
      key[3 * e + i][2] = e;
    }
  }
  qsort(key, (size_t)ne3, sizeof *key, cmp_key);
  for (int64_t k = 0; k + 1 < ne3; k++) {
    if (key[k][0] != key[k + 1][0] || key[k][1] != key[k + 1][1]) continue;
    if (d[key[k][2]] != d[key[k + 1][2]]) {
      memcpy(seg + 6 * *n, m->xyz + 3 * key[k][0], 3 * sizeof *seg);
      memcpy(seg + 6 * *n + 3, m->xyz + 3 * key[k][1], 3 * sizeof *seg);
      (*n)++;
    }
  }
  free(key);
  return seg;
}

static double point_segment(const double *p, const double *s) {
  double d[3], r[3], t = 0, l2 = 0, dot = 0;
  for (int i = 0; i < 3; i++) {
    d[i] = s[3 + i] - s[i];
    r[i] = p[i] - s[i];
    l2 += d[i] * d[i];
    dot += r[i] * d[i];
  }
  t = l2 > 0 ? dot / l2 : 0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  double q = 0;
  for (int i = 0; i < 3; i++) {
    double x = r[i] - t * d[i];
    q += x * x;
  }
  return sqrt(q);
}

/* Largest distance from a border vertex of `out` to the borders of `in`
 * (field `name`). */
static double border_distance(const vm_mesh *in, const vm_mesh *out, const char *name,
                              int64_t *nborder) {
  int64_t ni = 0, no = 0;
  double *si = border_segments(in, name, &ni), *so = border_segments(out, name, &no);
  double worst = 0;
  for (int64_t k = 0; k < 2 * no; k++) {
    const double *p = so + 3 * k;
    double best = INFINITY;
    for (int64_t j = 0; j < ni; j++) {
      double dd = point_segment(p, si + 6 * j);
      if (dd < best) best = dd;
    }
    if (best > worst) worst = best;
  }
  *nborder = no;
  free(si);
  free(so);
  return worst;
}

static void add_x_field(vm_mesh *m) {
  vm_field *f = NULL;
  CHECK(vm_mesh_add_field(m, "x", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f) == VM_OK, "field x");
  double *d = f->data;
  for (int64_t v = 0; v < m->nv; v++) d[v] = m->xyz[3 * v];
  CHECK(vm_mesh_add_field(m, "id", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f) == VM_OK, "field id");
  int32_t *id = f->data;
  for (int64_t v = 0; v < m->nv; v++) id[v] = (int32_t)v + 1;
}

static void aircraft(vm_ctx *ctx, int size) {
  vm_aircraft_opts ao = vm_aircraft_opts_default();
  ao.resolution = 2;
  ao.tag_components = 1;
  vm_mesh *in = NULL, *m = NULL;
  CHECK(vm_gen_aircraft(ctx, &ao, &in) == VM_OK, "aircraft");
  add_x_field(in);
  CHECK(vm_mesh_clone(in, &m) == VM_OK, "clone");
  vm_surface_opts so = vm_surface_opts_default();
  so.step = VM_SURFACE_REMESH;
  so.remesh = VM_SURFACE_YES;
  so.size = size;
  vm_surface_summary s;
  int st = vm_surface_run(ctx, m, &so, &s);
  const char *what = size == VM_SURFACE_SIZE_CURVATURE ? "curvature" : "uniform";
  CHECK(st == VM_OK && s.remeshed, "%s: remeshed (status %d, remeshed %d)", what, st, s.remeshed);
  double a0[VM_AIRCRAFT_NCOMP], a1[VM_AIRCRAFT_NCOMP];
  CHECK(region_areas(in, "component", VM_AIRCRAFT_NCOMP, a0) == 0, "input components");
  CHECK(region_areas(m, "component", VM_AIRCRAFT_NCOMP, a1) == 0,
        "%s: the component field is carried, every value in range", what);
  for (int r = 0; r < VM_AIRCRAFT_NCOMP; r++)
    CHECK(fabs(a1[r] - a0[r]) <= 0.005 * a0[r], "%s: component %d's area %.6g vs %.6g", what, r,
          a1[r], a0[r]);
  int64_t nb = 0;
  double bd = border_distance(in, m, "component", &nb);
  CHECK(nb > 0 && bd <= 1e-9 * ao.length, "%s: %lld border edges, on the input's borders (%.3g)",
        what, (long long)nb, bd);
  const vm_field *fx = vm_mesh_find_field(m, "x", VM_FIELD_VERTEX);
  CHECK(fx && fx->type == VM_FIELD_F64, "%s: the vertex field x is carried", what);
  double worst = 0;
  for (int64_t v = 0; fx && v < m->nv; v++) {
    double d = fabs(((const double *)fx->data)[v] - m->xyz[3 * v]);
    if (d > worst) worst = d;
  }
  /* linear on the input's triangles: off by at most the distance to the
   * input surface */
  CHECK(worst <= 1e-3 * ao.length, "%s: the field x at the new vertices is x (off by %.3g)", what,
        worst);
  /* an I32 vertex field (here: the input's vertex numbers) is not spread:
   * nonzero only where the input vertex it names still is, bit for bit */
  const vm_field *fid = vm_mesh_find_field(m, "id", VM_FIELD_VERTEX);
  int64_t kept = 0, wrong = 0;
  for (int64_t v = 0; fid && v < m->nv; v++) {
    int32_t id = ((const int32_t *)fid->data)[v];
    if (!id) continue;
    kept++;
    wrong += id < 1 || id > in->nv ||
             memcmp(in->xyz + 3 * (int64_t)(id - 1), m->xyz + 3 * v, 3 * sizeof(double));
  }
  CHECK(fid && kept > 0 && wrong == 0,
        "%s: the id field: %lld vertices keep an input id, %lld of them elsewhere", what,
        (long long)kept, (long long)wrong);
  fprintf(stderr,
          "aircraft, %s: %lld -> %lld triangles, %lld border edges, x off by %.3g, %lld input "
          "vertices kept with their ids\n",
          what, (long long)in->ne, (long long)m->ne, (long long)nb, worst, (long long)kept);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

static void wing(vm_ctx *ctx) {
  vm_mesh *in = NULL, *m = NULL;
  CHECK(vm_mesh_create(ctx, &in) == VM_OK, "mesh");
  CHECK(vm_gen_wing(in, 160, 8, 0.12, 28) == VM_OK, "wing");
  vm_field *f = NULL;
  CHECK(vm_mesh_add_field(in, "zone", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f) == VM_OK, "zone");
  /* the outer half of the span (y from 0 to 1.196) */
  int32_t *z = f->data;
  for (int64_t e = 0; e < in->ne; e++) {
    const int32_t *c = in->conn + in->eoff[e];
    double y = 0;
    for (int i = 0; i < 3; i++) y += in->xyz[3 * (int64_t)c[i] + 1] / 3;
    z[e] = y > 0.6;
  }
  CHECK(vm_mesh_clone(in, &m) == VM_OK, "clone");
  vm_surface_opts so = vm_surface_opts_default();
  so.adapt.max_iter = 10;
  vm_surface_summary s;
  int st = vm_surface_run(ctx, m, &so, &s);
  CHECK(st >= 0 && s.remeshed && s.size_used == VM_SURFACE_SIZE_CURVATURE,
        "wing: the needles make the stage remesh it despite its region field (status %d, "
        "remeshed %d)",
        st, s.remeshed);
  double a0[2], a1[2];
  CHECK(region_areas(in, "zone", 2, a0) == 0, "wing: input zones");
  CHECK(region_areas(m, "zone", 2, a1) == 0, "wing: the zone field is carried");
  for (int r = 0; r < 2; r++)
    CHECK(fabs(a1[r] - a0[r]) <= 0.005 * a0[r], "wing: zone %d's area %.6g vs %.6g", r, a1[r],
          a0[r]);
  int64_t nb = 0;
  double bd = border_distance(in, m, "zone", &nb);
  CHECK(nb > 0 && bd <= 1e-9, "wing: %lld border edges, on the input's border (%.3g)",
        (long long)nb, bd);
  fprintf(stderr, "wing: %lld -> %lld triangles, zone areas %.6g %.6g (input %.6g %.6g)\n",
          (long long)in->ne, (long long)m->ne, a1[0], a1[1], a0[0], a0[1]);
  vm_mesh_destroy(&in);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx) != VM_OK) return 1;
  aircraft(ctx, VM_SURFACE_SIZE_CURVATURE);
  aircraft(ctx, VM_SURFACE_SIZE_UNIFORM);
  wing(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_regions");
}
