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

static int cmp_tri(const void *a, const void *b) {
  const int32_t *x = a, *y = b;
  for (int i = 0; i < 3; i++)
    if (x[i] != y[i]) return x[i] < y[i] ? -1 : 1;
  return 0;
}

/* The faces of m's tets, each sorted, then the list sorted: the boundary
 * faces (seen once) into *bnd (*nb), and how many faces are seen neither
 * once nor twice. */
static int64_t tet_faces(const vm_mesh *m, const int32_t *vmap, int32_t **bnd, int64_t *nb) {
  static const int F[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  int32_t *f = malloc(12 * (size_t)m->ne * sizeof *f);
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    for (int j = 0; j < 4; j++) {
      int32_t *t = f + 12 * e + 3 * j;
      for (int i = 0; i < 3; i++) t[i] = vmap ? vmap[c[F[j][i]]] : c[F[j][i]];
      for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2 - a; b++)
          if (t[b] > t[b + 1]) {
            int32_t x = t[b];
            t[b] = t[b + 1];
            t[b + 1] = x;
          }
    }
  }
  qsort(f, 4 * (size_t)m->ne, 3 * sizeof *f, cmp_tri);
  int64_t bad = 0, n = 0;
  *bnd = malloc(12 * (size_t)m->ne * sizeof **bnd);
  for (int64_t i = 0; i < 4 * m->ne;) {
    int64_t k = i + 1;
    while (k < 4 * m->ne && !cmp_tri(f + 3 * k, f + 3 * i)) k++;
    if (k - i == 1) memcpy(*bnd + 3 * n++, f + 3 * i, 3 * sizeof **bnd);
    bad += k - i > 2;
    i = k;
  }
  *nb = n;
  free(f);
  return bad;
}

/* The flips on a known case: the relief's pulled cube (every tet
 * positive; 33 determinants below 0.001, 24 of them the tets with two
 * faces on the cube's boundary, and 5 faces beyond 70 degrees). Without
 * moving a vertex (first = nv) and with collapses allowed (first = 0):
 * fewer failures by every count, none more; every tet positive; the
 * cube's volume; the same boundary triangles (by the vertices' original
 * indices); every inner face shared by exactly two tets; the kept
 * vertices bit-identical, their vertex field and the tets' element field
 * carried; the same result twice. */
static void flips_case(vm_ctx *ctx) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = 4;
  ro.alpha = 0;
  ro.cells = VM_GEN_TETS;
  vm_mesh *m0 = NULL;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m0, NULL) == VM_OK, "flips: the tet cube");
  if (!m0) return;
  int64_t k = 0;
  for (int64_t v = 0; v < m0->nv; v++) {
    double *x = m0->xyz + 3 * v;
    if (fabs(x[0]) < 0.49 && fabs(x[1]) < 0.49 && fabs(x[2]) < 0.49) {
      x[0] += 0.065 * sin(1.7 * (double)k + 0.3);
      x[1] += 0.065 * cos(2.3 * (double)k + 1.1);
      x[2] += 0.065 * sin(3.1 * (double)k + 2.0);
      k++;
    }
  }
  vm_field *vid = NULL, *tag = NULL;
  vm_mesh_add_field(m0, "vid", VM_FIELD_VERTEX, VM_FIELD_I32, 1, NULL);
  vm_mesh_add_field(m0, "tag", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, NULL);
  /* (looked up after both: adding a field may move the others) */
  vid = vm_mesh_find_field(m0, "vid", VM_FIELD_VERTEX);
  tag = vm_mesh_find_field(m0, "tag", VM_FIELD_ELEMENT);
  for (int64_t v = 0; v < m0->nv; v++) ((int32_t *)vid->data)[v] = (int32_t)v;
  for (int64_t e = 0; e < m0->ne; e++) ((int32_t *)tag->data)[e] = 7;
  int32_t *b0 = NULL;
  int64_t nb0 = 0;
  tet_faces(m0, NULL, &b0, &nb0);
  for (int pass = 0; pass < 2; pass++) {
    const char *name = pass ? "flips with collapses" : "flips";
    vm_mesh *m = NULL, *m2 = NULL;
    vm_mesh_clone(m0, &m);
    vm_mesh_clone(m0, &m2);
    int64_t first = pass ? 0 : m->nv, nf = 0, nf2 = 0, mv;
    vm_fill_fv_figures b, a, x;
    vm_fill_fv_relief(ctx, m, 0, 0, 0, &b, &x, &mv);
    int st = vm_fill_fv_flips(ctx, m, 0, first, &nf);
    CHECK(st == VM_OK && nf > 0, "%s: %s, %lld made", name, st ? vm_ctx_error(ctx) : "ok",
          (long long)nf);
    vm_fill_fv_relief(ctx, m, 0, 0, 0, &a, &x, &mv);
    CHECK(a.det_under < b.det_under && a.nonortho_over70 <= b.nonortho_over70 &&
              a.skew_over4 <= b.skew_over4 && a.weight_under <= b.weight_under &&
              a.volratio_under <= b.volratio_under,
          "%s: determinants %lld -> %lld, faces > 70 deg %lld -> %lld, skewed %lld -> %lld, "
          "weights %lld -> %lld, volume ratios %lld -> %lld",
          name, (long long)b.det_under, (long long)a.det_under, (long long)b.nonortho_over70,
          (long long)a.nonortho_over70, (long long)b.skew_over4, (long long)a.skew_over4,
          (long long)b.weight_under, (long long)a.weight_under, (long long)b.volratio_under,
          (long long)a.volratio_under);
    int64_t neg = 0, badtag = 0;
    double vol = 0;
    for (int64_t e = 0; e < m->ne; e++) {
      double t = tet_signed(m, e);
      neg += t <= 0;
      vol += t;
      badtag += ((const int32_t *)vm_mesh_find_field(m, "tag", VM_FIELD_ELEMENT)->data)[e] != 7;
    }
    CHECK(neg == 0 && fabs(vol - 1) < 1e-12 && badtag == 0,
          "%s: %lld tets not positive, volume %.15g, %lld tets without the element field", name,
          (long long)neg, vol, (long long)badtag);
    /* the vertices: kept in order, bit-identical, carrying their field */
    const int32_t *id = vm_mesh_find_field(m, "vid", VM_FIELD_VERTEX)->data;
    int64_t badv = 0;
    for (int64_t v = 0; v < m->nv; v++)
      badv += (v && id[v] <= id[v - 1]) ||
              memcmp(m->xyz + 3 * v, m0->xyz + 3 * (int64_t)id[v], 3 * sizeof(double));
    CHECK(badv == 0 && (pass ? m->nv <= m0->nv : m->nv == m0->nv),
          "%s: %lld vertices not kept as they were (%lld of %lld left)", name, (long long)badv,
          (long long)m->nv, (long long)m0->nv);
    int32_t *b1 = NULL;
    int64_t nb1 = 0, over = tet_faces(m, id, &b1, &nb1);
    CHECK(over == 0 && nb1 == nb0 && !memcmp(b1, b0, 3 * (size_t)nb0 * sizeof *b0),
          "%s: %lld faces on more than two tets, %lld boundary triangles of %lld, the same: %d",
          name, (long long)over, (long long)nb1, (long long)nb0,
          nb1 == nb0 && !memcmp(b1, b0, 3 * (size_t)nb0 * sizeof *b0));
    free(b1);
    st = vm_fill_fv_flips(ctx, m2, 0, first, &nf2);
    CHECK(st == VM_OK && nf2 == nf && m2->ne == m->ne && m2->nv == m->nv &&
              !memcmp(m2->conn, m->conn, 4 * (size_t)m->ne * sizeof *m->conn),
          "%s: the same result twice", name);
    vm_mesh_destroy(&m2);
    vm_mesh_destroy(&m);
  }
  int64_t nf = 0;
  CHECK(vm_fill_fv_flips(ctx, m0, m0->ne + 1, 0, &nf) == VM_ERR_ARG && nf == 0,
        "flips: a first tet past the end refused");
  free(b0);
  vm_mesh_destroy(&m0);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  sphere_case(ctx, VM_FAR_BOX);
  sphere_case(ctx, VM_FAR_SPHERE);
  layer_case(ctx);
  relief_case(ctx);
  flips_case(ctx);
  /* no envelope: an empty mesh */
  vm_mesh *e = NULL, *o = NULL;
  vm_mesh_create(ctx, &e);
  CHECK(vm_fill_run(ctx, e, NULL, &o, NULL) == VM_ERR_ARG && !o, "empty mesh refused");
  vm_mesh_destroy(&e);
  vm_ctx_destroy(&ctx);
  return vmtest_end("fill");
}
