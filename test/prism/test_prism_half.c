/* test/prism/test_prism_half.c: the prism stage on half models. A
 * hemisphere on the plane z = 0 (a UV sphere's upper half, its equator
 * exactly in the plane) has an exact answer: concentric half-shells, the
 * columns of the equator in the plane bit for bit, the faces on the plane
 * facing -z. Its mirror image then closes it into a valid whole: every
 * vertex in the plane is its own image, every other one strictly above
 * it. Walls that are open but not half models, and a plane that does not
 * fit, are refused with where. The fill closes the layer with a half far
 * field (box and sphere) and the plane's own triangles: every boundary
 * face is a wall, far-field or symmetry face, those in the plane exactly
 * so; an envelope whose border leaves the plane, or that crosses it, is
 * refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/check_prism.h"
#include "varmesh/fill.h"
#include "varmesh/prism.h"
#include "varmesh/topology.h"
#include "vmtest.h"

#define PI 3.14159265358979323846

/* A UV hemisphere of radius 1 around the origin: nr rings from the equator
 * (z = 0 exactly) to the pole, 4 nr vertices on each, turned by `tilt`
 * radians about the x axis (0: the equator in z = 0); the pole is one
 * vertex. Outward oriented. */
static vm_mesh *hemisphere(vm_ctx *ctx, int nr, double tilt) {
  int np = 4 * nr;
  int64_t nv = (int64_t)nr * np + 1, nt = (int64_t)(2 * nr - 1) * np;
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m) || vm_mesh_set_vertices(m, nv) || vm_mesh_set_elements(m, nt, 3 * nt))
    return NULL;
  for (int i = 0; i < nr; i++)
    for (int j = 0; j < np; j++) {
      double th = i * (PI / 2) / nr, ph = j * 2 * PI / np;
      double *x = m->xyz + 3 * ((int64_t)i * np + j);
      x[0] = cos(th) * cos(ph);
      x[1] = cos(th) * sin(ph);
      x[2] = i == 0 ? 0.0 : sin(th);
    }
  double *pole = m->xyz + 3 * (nv - 1);
  pole[0] = pole[1] = 0;
  pole[2] = 1;
  if (tilt != 0)
    for (int64_t v = 0; v < nv; v++) {
      double *x = m->xyz + 3 * v, y = x[1], z = x[2];
      x[1] = cos(tilt) * y - sin(tilt) * z;
      x[2] = sin(tilt) * y + cos(tilt) * z;
    }
  int64_t e = 0;
#define V(i, j) ((int32_t)((i) == nr ? nv - 1 : (int64_t)(i)*np + ((j) % np)))
#define TRI(a, b, c)                                                                               \
  do {                                                                                             \
    m->etype[e] = VM_TRI;                                                                          \
    m->conn[3 * e] = (a);                                                                          \
    m->conn[3 * e + 1] = (b);                                                                      \
    m->conn[3 * e + 2] = (c);                                                                      \
    m->eoff[e + 1] = 3 * (e + 1);                                                                  \
    e++;                                                                                           \
  } while (0)
  for (int i = 0; i < nr; i++)
    for (int j = 0; j < np; j++) {
      TRI(V(i, j), V(i, j + 1), V(i + 1, j + 1));
      if (i < nr - 1) TRI(V(i, j), V(i + 1, j + 1), V(i + 1, j));
    }
#undef TRI
#undef V
  return m;
}

static double radius3(const double *x) { return sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]); }

/* The fill of the hemisphere's layer: a half far field (a box, or a
 * sphere) at 4 model lengths closed by the symmetry plane's triangles. */
static void fill_half(vm_ctx *ctx, const vm_mesh *layer, int sphere) {
  vm_fill_opts fo = vm_fill_opts_default();
  fo.farfield = 4;
  fo.shape = sphere ? VM_FAR_SPHERE : VM_FAR_BOX;
  vm_mesh *out = NULL;
  vm_fill_report fr;
  int st = vm_fill_run(ctx, layer, &fo, &out, &fr);
  const char *name = sphere ? "fill (sphere)" : "fill (box)";
  CHECK(st == 0, "%s: %d %s", name, st, vm_ctx_error(ctx));
  if (st < 0) return;
  fprintf(stderr, "%s: %lld tets, %lld far-field and %lld symmetry triangles, plane %d %g\n", name,
          (long long)fr.tets, (long long)fr.far_faces, (long long)fr.sym_faces, fr.sym_axis,
          fr.sym_value);
  CHECK(fr.sym_axis == 2 && fr.sym_value == 0 && fr.sym_faces > 0, "%s: the plane z = 0 meshed",
        name);
  /* the boundary faces of the cells are exactly the named faces: wall,
   * far field, symmetry (the layer's quads and the fill's triangles), the
   * symmetry ones in z = 0 bit for bit, nothing below it */
  const vm_field *ph = vm_mesh_find_field(out, "gmsh:physical", VM_FIELD_ELEMENT);
  int32_t t_sym = -1, t_far = -1, t_wall = -1;
  for (int i = 0; i < out->nattr; i++) {
    const char *k = out->attrs[i].key, *v = out->attrs[i].value;
    if (strncmp(k, "gmsh:physical_name:2:", 21)) continue;
    int32_t t = (int32_t)atoi(k + 21);
    if (!strcmp(v, "symmetry")) t_sym = t;
    if (!strcmp(v, "farfield")) t_far = t;
    if (!strcmp(v, "wall")) t_wall = t;
  }
  int64_t nb = 0, nface = 0, off = 0, other = 0, below = 0, nsymf = 0;
  int32_t *bfv = NULL;
  uint8_t *bnv = NULL;
  CHECK(vm_mesh_boundary(out, &nb, &bfv, &bnv, NULL, NULL) == 0, "%s: boundary", name);
  for (int64_t e = 0; e < out->ne; e++) {
    if (vm_elem_dim(out->etype[e]) != 2) continue;
    int32_t t = ((const int32_t *)ph->data)[e];
    if (t == t_sym) {
      nsymf++;
      for (int64_t k = out->eoff[e]; k < out->eoff[e + 1]; k++)
        off += out->xyz[3 * (int64_t)out->conn[k] + 2] != 0.0;
    } else if (t != t_far && t != t_wall) {
      other++;
    }
    nface++;
  }
  for (int64_t v = 0; v < out->nv; v++) below += out->xyz[3 * v + 2] < 0;
  CHECK(t_sym >= 0 && t_far >= 0 && t_wall >= 0, "%s: named %d %d %d", name, t_sym, t_far, t_wall);
  CHECK(nb == nface && other == 0, "%s: %lld boundary faces, %lld named faces (%lld others)", name,
        (long long)nb, (long long)nface, (long long)other);
  CHECK(off == 0 && below == 0, "%s: %lld symmetry-face corners off z = 0, %lld vertices below",
        name, (long long)off, (long long)below);
  /* the whole, mirrored: closed, no symmetry face left, every cell positive */
  vm_mesh *whole = NULL;
  CHECK(vm_mesh_mirror(ctx, out, &whole) == 0, "%s: mirror", name);
  if (whole) {
    int64_t wb = 0;
    int32_t *wfv = NULL;
    uint8_t *wnv = NULL;
    vm_mesh_boundary(whole, &wb, &wfv, &wnv, NULL, NULL);
    int64_t wsym = 0, tneg = 0;
    const vm_field *wph = vm_mesh_find_field(whole, "gmsh:physical", VM_FIELD_ELEMENT);
    for (int64_t e = 0; e < whole->ne; e++) {
      wsym += vm_elem_dim(whole->etype[e]) == 2 && ((const int32_t *)wph->data)[e] == t_sym;
      if (whole->etype[e] != VM_TET) continue;
      const int32_t *c = whole->conn + whole->eoff[e];
      double a[3], b[3], d[3], x[3];
      for (int k = 0; k < 3; k++) {
        a[k] = whole->xyz[3 * c[1] + k] - whole->xyz[3 * c[0] + k];
        b[k] = whole->xyz[3 * c[2] + k] - whole->xyz[3 * c[0] + k];
        d[k] = whole->xyz[3 * c[3] + k] - whole->xyz[3 * c[0] + k];
      }
      chk_cross(a, b, x);
      tneg += !(chk_dot(x, d) > 0);
    }
    CHECK(wsym == 0 && wb == 2 * (nb - nsymf),
          "%s: whole: %lld symmetry faces, %lld boundary faces (the half's %lld off the plane, "
          "twice)",
          name, (long long)wsym, (long long)wb, (long long)(nb - nsymf));
    CHECK(chk_corner_inverted(whole) == 0 && tneg == 0,
          "%s: whole: every cell positive (%lld tets)", name, (long long)tneg);
    vm_free(ctx, wfv);
    vm_free(ctx, wnv);
  }
  vm_mesh_destroy(&whole);
  vm_free(ctx, bfv);
  vm_free(ctx, bnv);
  vm_mesh_destroy(&out);
}

/* The fill refuses an envelope whose border leaves the plane, or which
 * crosses it. */
static void fill_refused(vm_ctx *ctx, const vm_mesh *layer, int64_t np) {
  vm_fill_opts fo = vm_fill_opts_default();
  fo.farfield = 4;
  for (int c = 0; c < 2; c++) {
    vm_mesh *m = NULL, *out = NULL;
    vm_fill_report fr;
    CHECK(vm_mesh_clone(layer, &m) == 0, "clone");
    if (!m) return;
    /* the outer level's first equator vertex lifted off the plane, or a
     * vertex of the ring above it pulled below */
    int64_t top = m->nv - (m->nv / 6); /* the outer level (6 levels of nw) */
    m->xyz[3 * (top + (c ? np : 0)) + 2] = c ? -0.01 : 1e-3;
    int st = vm_fill_run(ctx, m, &fo, &out, &fr);
    const char *msg = vm_ctx_error(ctx);
    const char *says = c ? "crosses its symmetry plane" : "not on the symmetry plane z = 0";
    CHECK(st == VM_ERR_ARG && !out && msg && strstr(msg, says), "fill refuses (%d): %s", st,
          msg ? msg : "");
    fprintf(stderr, "fill refused: %s\n", msg ? msg : "");
    vm_ctx_clear_error(ctx);
    vm_mesh_destroy(&out);
    vm_mesh_destroy(&m);
  }
}

/* The exact answer and the mirror check on the hemisphere. */
static void concentric(vm_ctx *ctx) {
  const int nr = 10, layers = 5;
  const double T = 0.2;
  vm_mesh *w = hemisphere(ctx, nr, 0);
  CHECK(w != NULL, "hemisphere");
  if (!w) return;
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = T;
  o.nlayers = layers;
  o.check_incremental = 1;
  vm_mesh *res = NULL;
  vm_prism_report r;
  int st = vm_prism_run(ctx, w, &o, &res, &r);
  CHECK(st == 0, "hemisphere: run %d %s", st, vm_ctx_error(ctx));
  if (st < 0) {
    vm_mesh_destroy(&w);
    return;
  }
  int64_t nw = r.wall_vertices, np = 4 * nr;
  fprintf(stderr,
          "hemisphere: %lld prisms, plane %c = %g, %lld columns in it, snapped %lld, crossing "
          "%lld, full %.3f, thickness %.4f..%.4f, sj %.3f\n",
          (long long)r.prisms, r.sym_axis >= 0 ? "xyz"[r.sym_axis] : '-', r.sym_value,
          (long long)r.sym_columns, (long long)r.sym_snapped, (long long)r.sym_crossing,
          r.full_fraction, r.thick_min, r.thick_max, r.sj_min);
  CHECK(r.sym_axis == 2 && r.sym_value == 0, "the plane z = 0 found: %d %g", r.sym_axis,
        r.sym_value);
  CHECK(r.sym_columns == np, "columns in the plane %lld (%lld)", (long long)r.sym_columns,
        (long long)np);
  CHECK(r.sym_snapped == 0, "every step kept them in it (%lld put back)", (long long)r.sym_snapped);
  CHECK(r.sym_crossing == 0, "no other vertex on or below it (%lld)", (long long)r.sym_crossing);
  CHECK(r.inverted == 0 && r.split_negative == 0, "valid: %lld inverted, %lld split",
        (long long)r.inverted, (long long)r.split_negative);
  CHECK(r.full_fraction == 1, "every column at full thickness (%.4f)", r.full_fraction);
  CHECK(chk_corner_inverted(res) == 0, "every corner tet positive (independent check)");
  /* the wall bit for bit, the equator's columns exactly in the plane,
   * everything else strictly above it; each level a half-shell */
  CHECK(!memcmp(res->xyz, w->xyz, sizeof(double) * 3 * (size_t)nw), "the wall bit for bit");
  int64_t off = 0, below = 0;
  double dev = 0;
  for (int k = 0; k <= layers; k++)
    for (int64_t v = 0; v < nw; v++) {
      const double *x = res->xyz + 3 * ((int64_t)k * nw + v);
      int eq = v < np; /* ring 0: the equator */
      if (eq)
        off += x[2] != 0.0 || signbit(x[2]);
      else
        below += !(x[2] > 0);
      if (k == layers) dev = fmax(dev, fabs(radius3(x) - (1 + T)));
    }
  CHECK(off == 0, "%lld vertices of the equator's columns off z = +0.0", (long long)off);
  CHECK(below == 0, "%lld other vertices on or below the plane", (long long)below);
  CHECK(dev < 0.02 * T, "the outer level a half-shell of radius 1 + T: off by %.3g", dev);
  /* the faces on the plane: one quad per layer over each equator edge,
   * tagged symmetry, in the plane, facing -z; every wall and outer
   * triangle and every cell accounted for */
  const vm_field *ph = vm_mesh_find_field(res, VM_PRISM_FIELD_PHYS, VM_FIELD_ELEMENT);
  int64_t nsym = 0, bad = 0, ntri = 0, ncell = 0;
  for (int64_t e = 0; e < res->ne; e++) {
    int tag = ((const int32_t *)ph->data)[e];
    const int32_t *c = res->conn + res->eoff[e];
    if (res->etype[e] == VM_PRISM) ncell++;
    if (res->etype[e] == VM_TRI) ntri++;
    if (tag != VM_PRISM_TAG_SYMMETRY) continue;
    nsym++;
    if (res->etype[e] != VM_QUAD) {
      bad++;
      continue;
    }
    double a = 0;
    for (int i = 0; i < 4; i++) {
      const double *x0 = res->xyz + 3 * (int64_t)c[i], *x1 = res->xyz + 3 * (int64_t)c[(i + 1) % 4];
      a += x0[0] * x1[1] - x1[0] * x0[1];
      bad += x0[2] != 0.0;
    }
    bad += !(a < 0);
  }
  CHECK(nsym == np * layers, "faces on the plane %lld (%lld)", (long long)nsym,
        (long long)(np * layers));
  CHECK(bad == 0, "%lld faces on the plane not quads in it facing -z", (long long)bad);
  CHECK(ncell == r.prisms && ntri == 2 * r.wall_triangles, "cells %lld, triangles %lld",
        (long long)ncell, (long long)ntri);
  const char *plane = vm_mesh_get_attr(res, VM_SYMMETRY_PLANE_ATTR);
  CHECK(plane && !strcmp(plane, "z=0"), "attribute %s = %s", VM_SYMMETRY_PLANE_ATTR,
        plane ? plane : "(none)");
  fill_half(ctx, res, 0);
  fill_half(ctx, res, 1);
  fill_refused(ctx, res, np);
  vm_mesh_destroy(&res);
  vm_mesh_destroy(&w);
}

/* Refused, with where: an open wall whose border is not in an axis plane,
 * a plane asked for that the border is off, a wall that reaches across
 * its plane, a closed wall with a plane asked for, open boundaries on two
 * planes, and an open wall when half models are switched off. */
static void refuse(vm_ctx *ctx, const char *name, vm_mesh *w, int axis, double value,
                   const char *says) {
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = 0.1;
  o.nlayers = 3;
  o.symmetry_axis = axis;
  o.symmetry_value = value;
  vm_mesh *res = NULL;
  vm_prism_report r;
  int st = vm_prism_run(ctx, w, &o, &res, &r);
  const char *msg = vm_ctx_error(ctx);
  CHECK(st == VM_ERR_ARG && res == NULL, "%s: refused (%d)", name, st);
  CHECK(msg && strstr(msg, says), "%s: says '%s': %s", name, says, msg ? msg : "(nothing)");
  fprintf(stderr, "%s: %s\n", name, msg ? msg : "");
  vm_ctx_clear_error(ctx);
  vm_mesh_destroy(&res);
}

static void bad_input(vm_ctx *ctx) {
  vm_mesh *w = hemisphere(ctx, 6, 0.1);
  refuse(ctx, "tilted", w, 0, 0, "not in a plane x, y or z = const");
  vm_mesh_destroy(&w);
  w = hemisphere(ctx, 6, 0);
  refuse(ctx, "plane asked", w, 3, 0.25, "is 0.25 off it");
  refuse(ctx, "none", w, -1, 0, "the wall is not closed");
  /* a vertex of the first ring pulled below the plane */
  w->xyz[3 * 24 + 2] = -0.05;
  refuse(ctx, "across", w, 0, 0, "crosses its symmetry plane z = 0");
  vm_mesh_destroy(&w);
  /* a cylinder's side, open at z = 0 and z = 1: two planes */
  int na = 16;
  vm_mesh *c = NULL;
  if (!vm_mesh_create(ctx, &c) && !vm_mesh_set_vertices(c, 2 * na) &&
      !vm_mesh_set_elements(c, 2 * na, 6 * na)) {
    for (int s = 0; s < 2; s++)
      for (int j = 0; j < na; j++) {
        double *x = c->xyz + 3 * (s * na + j);
        x[0] = cos(2 * PI * j / na);
        x[1] = sin(2 * PI * j / na);
        x[2] = s;
      }
    for (int j = 0; j < na; j++) {
      int32_t a = j, b = (j + 1) % na, a1 = a + na, b1 = b + na;
      int32_t t[6] = {a, b, b1, a, b1, a1};
      for (int i = 0; i < 2; i++) {
        c->etype[2 * j + i] = VM_TRI;
        memcpy(c->conn + 6 * j + 3 * i, t + 3 * i, 3 * sizeof *t);
        c->eoff[2 * j + i + 1] = 6 * j + 3 * (i + 1);
      }
    }
    refuse(ctx, "two planes", c, 0, 0, "not in a plane x, y or z = const");
  }
  vm_mesh_destroy(&c);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  concentric(ctx);
  bad_input(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_half");
}
