/* test/volume/test_fill.c: the fill stage on generated shapes with known
 * answers: a closed icosphere filled out to a box and to a sphere, and a
 * shell of prisms between two icospheres (wall inside, 'outer' outside)
 * filled around. Checks: the input's vertices bit-identical and first, the
 * envelope's triangles faces of exactly one tet, the tets' unshared faces
 * exactly the envelope and the far field, every tet positive, the far
 * field at the asked distance and named, 'outer' gone, the total volume
 * (box or sphere minus the model) right, determinism, and bad input. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/fill.h"
#include "varmesh/rotcube.h"
#include "varmesh/shapes.h"
#include "varmesh/topology.h"
#include "vmtest.h"

static double tetvol(const vm_mesh *m, const int32_t *c) {
  const double *a = m->xyz + 3 * c[0], *b = m->xyz + 3 * c[1], *p = m->xyz + 3 * c[2],
               *d = m->xyz + 3 * c[3];
  double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double v[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
          u[2] * (v[0] * w[1] - v[1] * w[0])) /
         6;
}

static int32_t tag_of(const vm_mesh *m, const char *name) {
  for (int i = 0; i < m->nattr; i++)
    if (!strncmp(m->attrs[i].key, "gmsh:physical_name:", 19) && !strcmp(m->attrs[i].value, name))
      return (int32_t)atol(strrchr(m->attrs[i].key, ':') + 1);
  return -1;
}

/* The closed surface of the fill region's volume (the model's volume, as
 * a polyhedron, is what the tets leave out). */
static double surface_volume(const vm_mesh *m, int32_t tag) {
  const vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  double v = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI || (tag >= 0 && ((const int32_t *)ph->data)[e] != tag)) continue;
    const int32_t *c = m->conn + m->eoff[e];
    const double *a = m->xyz + 3 * c[0], *b = m->xyz + 3 * c[1], *p = m->xyz + 3 * c[2];
    v += (a[0] * (b[1] * p[2] - b[2] * p[1]) - a[1] * (b[0] * p[2] - b[2] * p[0]) +
          a[2] * (b[0] * p[1] - b[1] * p[0])) /
         6;
  }
  return v;
}

/* What every fill must be, for input `in` and output `o`. */
static void check_fill(const char *name, const vm_mesh *in, const vm_mesh *o,
                       const vm_fill_report *r, double model_volume, double far_volume) {
  CHECK(o->nv > in->nv, "%s: vertices added", name);
  CHECK(!memcmp(o->xyz, in->xyz, (size_t)(3 * in->nv) * sizeof(double)),
        "%s: the input's vertices bit-identical and first", name);
  int64_t ntet = 0, nneg = 0;
  double vol = 0;
  for (int64_t e = 0; e < o->ne; e++) {
    if (o->etype[e] != VM_TET) continue;
    double v = tetvol(o, o->conn + o->eoff[e]);
    ntet++;
    nneg += v <= 0;
    vol += v;
  }
  CHECK(ntet == r->tets && ntet > 100, "%s: %lld tets (report %lld)", name, (long long)ntet,
        (long long)r->tets);
  CHECK(nneg == 0, "%s: %lld tets not positive", name, (long long)nneg);
  /* the tets fill the far field's volume less the model's exactly */
  CHECK(fabs(vol - (far_volume - model_volume)) < 1e-9 * far_volume,
        "%s: tet volume %.12g, expected %.12g", name, vol, far_volume - model_volume);
  int32_t tf = tag_of(o, "farfield");
  CHECK(tf >= 0, "%s: a 'farfield' name", name);
  CHECK(tag_of(o, "fill") >= 0, "%s: the tets named 'fill'", name);
  CHECK(fabs(surface_volume(o, tf) - far_volume) < 1e-9 * far_volume,
        "%s: far field encloses %.12g, expected %.12g", name, surface_volume(o, tf), far_volume);
  /* the boundary of the tets alone: the envelope and the far field */
  vm_mesh *t = NULL;
  vm_mesh_clone(o, &t);
  int64_t k = 0;
  for (int64_t e = 0; e < t->ne; e++)
    if (t->etype[e] == VM_TET) {
      memmove(t->conn + 4 * k, t->conn + t->eoff[e], 4 * sizeof(int32_t));
      t->etype[k++] = VM_TET;
    }
  t->ne = k;
  for (int64_t e = 0; e <= k; e++) t->eoff[e] = 4 * e;
  while (t->nfield) vm_mesh_remove_field(t, t->fields[0].name, t->fields[0].location);
  int64_t nb = 0, nonman = 0;
  vm_mesh_boundary(t, &nb, NULL, NULL, NULL, &nonman);
  CHECK(nb == r->env_faces + r->far_faces && nonman == 0,
        "%s: tets' boundary %lld faces, envelope %lld + far field %lld (non-manifold %lld)", name,
        (long long)nb, (long long)r->env_faces, (long long)r->far_faces, (long long)nonman);
  vm_mesh_destroy(&t);
  CHECK(r->after.min_dihedral > 3, "%s: min dihedral %.2f deg", name, r->after.min_dihedral);
  CHECK(r->after.min_dihedral >= r->before.min_dihedral - 1e-9 ||
            r->after.sj_min >= r->before.sj_min - 1e-9,
        "%s: the optimization made the worst tet worse", name);
}

static void sphere_case(vm_ctx *ctx, vm_far_shape shape) {
  const char *name = shape == VM_FAR_BOX ? "sphere in a box" : "sphere in a sphere";
  vm_mesh *in = NULL, *o = NULL, *o2 = NULL;
  vm_mesh_create(ctx, &in);
  vm_gen_icosphere(in, NULL, 1.0, 3, 0, NULL);
  vm_fill_opts fo = vm_fill_opts_default();
  fo.farfield = 4;
  fo.shape = shape;
  vm_fill_report r;
  int st = vm_fill_run(ctx, in, &fo, &o, &r);
  CHECK(st == VM_OK, "%s: %s", name, vm_ctx_error(ctx));
  if (st == VM_OK) {
    double L = 2 * 1.0; /* the icosphere's extent: vertices on the poles */
    CHECK(fabs(r.model_length - L) < 0.05, "%s: model length %g", name, r.model_length);
    double H = fo.farfield * r.model_length;
    double far = shape == VM_FAR_BOX ? 8 * H * H * H : surface_volume(o, tag_of(o, "farfield"));
    if (shape == VM_FAR_SPHERE)
      CHECK(far > 0.9 * 4.0 / 3 * 3.14159265 * H * H * H, "%s: far sphere volume %g", name, far);
    CHECK(r.surface_input && tag_of(o, "wall") >= 0, "%s: the surface became the wall", name);
    check_fill(name, in, o, &r, surface_volume(in, -1), far);
    /* determinism */
    st = vm_fill_run(ctx, in, &fo, &o2, &r);
    CHECK(st == VM_OK && o2->nv == o->nv && o2->ne == o->ne &&
              !memcmp(o2->xyz, o->xyz, (size_t)(3 * o->nv) * sizeof(double)) &&
              !memcmp(o2->conn, o->conn, (size_t)o->eoff[o->ne] * sizeof(int32_t)),
          "%s: same input, same output", name);
  }
  vm_mesh_destroy(&o2);
  vm_mesh_destroy(&o);
  vm_mesh_destroy(&in);
}

/* Prisms between icospheres of radius 1 (wall) and 1.15 ('outer'). */
static void layer_case(vm_ctx *ctx) {
  vm_mesh *s = NULL, *m = NULL, *o = NULL;
  vm_mesh_create(ctx, &s);
  vm_gen_icosphere(s, NULL, 1.0, 3, 0, NULL);
  vm_mesh_create(ctx, &m);
  int64_t n = s->nv, nt = s->ne;
  vm_mesh_set_vertices(m, 2 * n);
  for (int64_t v = 0; v < n; v++)
    for (int k = 0; k < 3; k++) {
      m->xyz[3 * v + k] = s->xyz[3 * v + k];
      m->xyz[3 * (n + v) + k] = 1.15 * s->xyz[3 * v + k];
    }
  for (int64_t e = 0; e < nt; e++) {
    const int32_t *c = s->conn + s->eoff[e];
    int32_t p[6] = {
        c[0], c[1], c[2], (int32_t)(c[0] + n), (int32_t)(c[1] + n), (int32_t)(c[2] + n)};
    vm_mesh_add_element(m, VM_PRISM, p);
  }
  for (int64_t e = 0; e < nt; e++) {
    const int32_t *c = s->conn + s->eoff[e];
    int32_t w[3] = {c[0], c[2], c[1]}; /* out of the layer: into the model */
    vm_mesh_add_element(m, VM_TRI, w);
  }
  for (int64_t e = 0; e < nt; e++) {
    const int32_t *c = s->conn + s->eoff[e];
    int32_t u[3] = {(int32_t)(c[0] + n), (int32_t)(c[1] + n), (int32_t)(c[2] + n)};
    vm_mesh_add_element(m, VM_TRI, u);
  }
  vm_field *ph, *layer;
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &ph);
  vm_mesh_add_field(m, "layer", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &layer);
  /* adding a field may move the field array: find the first one again */
  ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  for (int64_t e = 0; e < m->ne; e++) {
    ((int32_t *)ph->data)[e] = e < nt ? 3 : e < 2 * nt ? 1 : 2;
    ((int32_t *)layer->data)[e] = e < nt ? 0 : -1;
  }
  vm_mesh_set_attr(m, "gmsh:physical_name:2:1", "wall");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:2", "outer");
  vm_mesh_set_attr(m, "gmsh:physical_name:3:3", "layer");
  vm_fill_opts fo = vm_fill_opts_default();
  fo.farfield = 5;
  vm_fill_report r;
  int st = vm_fill_run(ctx, m, &fo, &o, &r);
  CHECK(st == VM_OK, "layer: %s", vm_ctx_error(ctx));
  if (st == VM_OK) {
    CHECK(r.env_faces == nt && r.layer_cells == nt && !r.surface_input,
          "layer: envelope %lld faces of %lld", (long long)r.env_faces, (long long)nt);
    double H = fo.farfield * r.model_length;
    /* the tets leave out the polyhedron of the outer sphere */
    double inner = 0;
    for (int64_t e = 0; e < nt; e++) {
      const int32_t *c = s->conn + s->eoff[e];
      const double *a = m->xyz + 3 * (c[0] + n), *b = m->xyz + 3 * (c[1] + n),
                   *p = m->xyz + 3 * (c[2] + n);
      inner += (a[0] * (b[1] * p[2] - b[2] * p[1]) - a[1] * (b[0] * p[2] - b[2] * p[0]) +
                a[2] * (b[0] * p[1] - b[1] * p[0])) /
               6;
    }
    check_fill("layer", m, o, &r, inner, 8 * H * H * H);
    /* 'outer' is interior now: its triangles are gone, the wall's stay */
    const vm_field *q = vm_mesh_find_field(o, "gmsh:physical", VM_FIELD_ELEMENT);
    const vm_field *ly = vm_mesh_find_field(o, "layer", VM_FIELD_ELEMENT);
    int64_t nouter = 0, nwall = 0, nprism = 0, badlayer = 0;
    for (int64_t e = 0; e < o->ne; e++) {
      int32_t t = ((const int32_t *)q->data)[e];
      nouter += o->etype[e] == VM_TRI && t == 2;
      nwall += o->etype[e] == VM_TRI && t == 1;
      nprism += o->etype[e] == VM_PRISM;
      badlayer += o->etype[e] == VM_TET && ((const int32_t *)ly->data)[e] != -1;
    }
    CHECK(nouter == 0 && nwall == nt && nprism == nt, "layer: outer %lld, wall %lld, prisms %lld",
          (long long)nouter, (long long)nwall, (long long)nprism);
    CHECK(badlayer == 0, "layer: %lld tets with a layer number", (long long)badlayer);
    CHECK(r.after.vol_ratio_env > 1 && r.after.vol_ratio_env < 20,
          "layer: volume ratio across the envelope %g", r.after.vol_ratio_env);
  }
  /* the far field must not cut the layer */
  vm_mesh *bad = NULL;
  fo.farfield = 0.55;
  st = vm_fill_run(ctx, m, &fo, &bad, &r);
  CHECK(st == VM_ERR_ARG && bad == NULL && strstr(vm_ctx_error(ctx), "far field"),
        "a far field cutting the layer: %d %s", st, vm_ctx_error(ctx));
  vm_mesh_destroy(&o);
  vm_mesh_destroy(&m);
  vm_mesh_destroy(&s);
}

/* Signed volume of tet e of m. */
static double tet_signed(const vm_mesh *m, int64_t e) {
  const int32_t *c = m->conn + m->eoff[e];
  const double *a = m->xyz + 3 * c[0], *b = m->xyz + 3 * c[1], *p = m->xyz + 3 * c[2],
               *d = m->xyz + 3 * c[3];
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; k++) u[k] = b[k] - a[k], v[k] = p[k] - a[k], w[k] = d[k] - a[k];
  return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
          u[2] * (v[0] * w[1] - v[1] * w[0])) /
         6;
}

/* The finite-volume relief on a known case: the unit cube in 4^3 cubes of
 * 6 Kuhn tets, its 27 inner vertices pulled off the lattice (a fixed
 * pattern up to 0.065 of the 0.25 spacing, every tet still positive). The
 * lattice is within every limit; the pulled mesh has faces beyond 70
 * degrees (74.5 measured). The relief must bring every face within
 * checkMesh's limits, move only inner vertices (the boundary's
 * bit-identical), keep every tet positive, and give the same result twice.
 * The 24 tets with two faces on the cube's boundary keep a determinant of
 * 0, as in checkMesh (their two internal faces' area tensor has rank 2). */
static void relief_case(vm_ctx *ctx) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = 4;
  ro.alpha = 0;
  ro.cells = VM_GEN_TETS;
  vm_mesh *m = NULL, *m2 = NULL;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m, NULL) == VM_OK, "relief: the tet cube");
  if (!m) return;
  double *x0 = malloc(3 * (size_t)m->nv * sizeof *x0);
  int64_t k = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    double *x = m->xyz + 3 * v;
    int inner = fabs(x[0]) < 0.49 && fabs(x[1]) < 0.49 && fabs(x[2]) < 0.49;
    if (inner) {
      /* a fixed pattern, no rand() */
      x[0] += 0.065 * sin(1.7 * (double)k + 0.3);
      x[1] += 0.065 * cos(2.3 * (double)k + 1.1);
      x[2] += 0.065 * sin(3.1 * (double)k + 2.0);
      k++;
    }
  }
  memcpy(x0, m->xyz, 3 * (size_t)m->nv * sizeof *x0);
  int64_t neg = 0;
  for (int64_t e = 0; e < m->ne; e++) neg += tet_signed(m, e) <= 0;
  CHECK(k == 27 && neg == 0, "relief: 27 inner vertices pulled (%lld), %lld tets not positive",
        (long long)k, (long long)neg);
  vm_mesh_clone(m, &m2);
  vm_fill_fv_figures b, a, b2, a2;
  int64_t moved = 0, moved2 = 0;
  int st = vm_fill_fv_relief(ctx, m, 0, 0, 20, &b, &a, &moved);
  CHECK(st == VM_OK, "relief: %s", vm_ctx_error(ctx));
  CHECK(b.tets == m->ne && b.faces == (4 * m->ne - 6 * 16 * 2) / 2, /* 192 boundary triangles */
        "relief: %lld tets, %lld internal faces", (long long)b.tets, (long long)b.faces);
  CHECK(b.nonortho_over70 > 0 && b.det_under > 24,
        "relief: before, %lld faces beyond 70 degrees (largest %.1f), %lld determinants",
        (long long)b.nonortho_over70, b.nonortho_max, (long long)b.det_under);
  CHECK(a.nonortho_over70 == 0 && a.skew_over4 == 0 && a.weight_under == 0 &&
            a.volratio_under == 0 && a.det_under == 24,
        "relief: after, beyond the limits: %lld faces > 70 deg, %lld skewed, %lld weights, %lld "
        "volume ratios, %lld determinants",
        (long long)a.nonortho_over70, (long long)a.skew_over4, (long long)a.weight_under,
        (long long)a.volratio_under, (long long)a.det_under);
  CHECK(a.nonortho_max < 70 && a.skew_max < 2,
        "relief: non-orthogonality %.1f -> %.1f, skewness %.2f -> %.2f", b.nonortho_max,
        a.nonortho_max, b.skew_max, a.skew_max);
  int64_t bmoved = 0, imoved = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    const double *x = x0 + 3 * v;
    int inner = fabs(x[0]) < 0.49 && fabs(x[1]) < 0.49 && fabs(x[2]) < 0.49;
    int same = !memcmp(x, m->xyz + 3 * v, 3 * sizeof *x);
    bmoved += !inner && !same;
    imoved += inner && !same;
  }
  CHECK(bmoved == 0 && imoved == moved && moved > 0,
        "relief: %lld boundary vertices moved, %lld inner (reported %lld)", (long long)bmoved,
        (long long)imoved, (long long)moved);
  neg = 0;
  for (int64_t e = 0; e < m->ne; e++) neg += tet_signed(m, e) <= 0;
  CHECK(neg == 0, "relief: %lld tets not positive after", (long long)neg);
  st = vm_fill_fv_relief(ctx, m2, 0, 0, 20, &b2, &a2, &moved2);
  CHECK(st == VM_OK && !memcmp(m->xyz, m2->xyz, 3 * (size_t)m->nv * sizeof(double)),
        "relief: the same result twice");
  /* only vertices from `first` on move */
  vm_mesh_destroy(&m2);
  vm_mesh_clone(m, &m2);
  memcpy(m2->xyz, x0, 3 * (size_t)m->nv * sizeof *x0);
  st = vm_fill_fv_relief(ctx, m2, 0, m2->nv, 20, &b2, &a2, &moved2);
  CHECK(st == VM_OK && moved2 == 0 && !memcmp(m2->xyz, x0, 3 * (size_t)m->nv * sizeof *x0),
        "relief: nothing moves below `first`");
  free(x0);
  vm_mesh_destroy(&m2);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  sphere_case(ctx, VM_FAR_BOX);
  sphere_case(ctx, VM_FAR_SPHERE);
  layer_case(ctx);
  relief_case(ctx);
  /* no envelope: an empty mesh */
  vm_mesh *e = NULL, *o = NULL;
  vm_mesh_create(ctx, &e);
  CHECK(vm_fill_run(ctx, e, NULL, &o, NULL) == VM_ERR_ARG && !o, "empty mesh refused");
  vm_mesh_destroy(&e);
  vm_ctx_destroy(&ctx);
  return vmtest_end("fill");
}
