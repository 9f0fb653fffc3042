/* test/io_solver/solver_testlib.h: what the SU2 and CGNS tests share: a
 * prism-layer-like mixed mesh with named boundary families, and exact mesh
 * comparisons. */
#ifndef VM_SOLVER_TESTLIB_H
#define VM_SOLVER_TESTLIB_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

/* An n x n grid of quads on a wavy wall (coordinates with all 53 bits in
 * use), extruded in three layers: prisms (each quad split in two
 * triangles), then prisms, then hexahedra; on one hex a pyramid, on that a
 * tetrahedron. Faces: the wall triangles (tag 1 "wall"), the top quads and
 * the pyramid and tet faces above them (tag 2 "outer"), the side quads of
 * layer 0 with tag 7 and no name (a family "boundary_7"), interleaved with
 * the others so that the writers have to group them. Element fields:
 * "layer" (int) and "thickness" (f64). */
static inline vm_mesh *layered_mesh(vm_ctx *ctx, int n) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  int np = n + 1;
  static const double h[4] = {0, 0.1, 0.25, 0.7};
  for (int k = 0; k < 4; k++)
    for (int j = 0; j < np; j++)
      for (int i = 0; i < np; i++) {
        double x = i / (double)n, y = j / (double)n;
        double z = 0.05 * sin(3.0 * x + 1.0) * cos(2.0 * y) + h[k] * (1.0 + 0.1 * x * y);
        vm_mesh_add_vertex(m, x + 1e-3 * sin(7.0 * z), y, z, NULL);
      }
#define VID(i, j, k) ((int32_t)((k)*np * np + (j)*np + (i)))
  int64_t apex, tip;
  vm_mesh_add_vertex(m, 0.5 / n, 0.5 / n, 1.0, &apex);
  vm_mesh_add_vertex(m, 0.5 / n, 0.5 / n, 1.5, &tip);
  int32_t *tag = malloc(sizeof *tag * (size_t)(64 * n * n + 64));
  int32_t *lay = malloc(sizeof *lay * (size_t)(64 * n * n + 64));
  int64_t ne = 0;
#define ADD(t, v, tg, ly)                                                                          \
  do {                                                                                             \
    vm_mesh_add_element(m, (t), (v));                                                              \
    tag[ne] = (tg);                                                                                \
    lay[ne++] = (ly);                                                                              \
  } while (0)
  for (int k = 0; k < 3; k++)
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        int32_t a = VID(i, j, k), b = VID(i + 1, j, k), c = VID(i + 1, j + 1, k),
                d = VID(i, j + 1, k), up = VID(0, 0, 1);
        if (k < 2) {
          int32_t p1[6] = {a, b, c, a + up, b + up, c + up};
          int32_t p2[6] = {a, c, d, a + up, c + up, d + up};
          ADD(VM_PRISM, p1, 0, k);
          ADD(VM_PRISM, p2, 0, k);
          if (k == 0) {
            int32_t t1[3] = {a, c, b}, t2[3] = {a, d, c};
            ADD(VM_TRI, t1, 1, -1);
            ADD(VM_TRI, t2, 1, -1);
            if (j == 0) {
              int32_t s[4] = {a, b, b + up, a + up};
              ADD(VM_QUAD, s, 7, -1);
            }
          }
        } else {
          int32_t hx[8] = {a, b, c, d, a + up, b + up, c + up, d + up};
          ADD(VM_HEX, hx, 0, k);
          if (i || j) {
            int32_t q[4] = {a + up, b + up, c + up, d + up};
            ADD(VM_QUAD, q, 2, -1);
          }
        }
      }
  int32_t a = VID(0, 0, 3), b = VID(1, 0, 3), c = VID(1, 1, 3), d = VID(0, 1, 3);
  int32_t py[5] = {a, b, c, d, (int32_t)apex};
  int32_t te[4] = {a, b, (int32_t)apex, (int32_t)tip};
  ADD(VM_PYRAMID, py, 0, 3);
  ADD(VM_TET, te, 0, 4);
  int32_t f1[3] = {b, c, (int32_t)apex}, f2[3] = {c, d, (int32_t)apex};
  ADD(VM_TRI, f1, 2, -1);
  ADD(VM_TRI, f2, 2, -1);
#undef ADD
#undef VID
  vm_field *f;
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  memcpy(f->data, tag, sizeof *tag * (size_t)ne);
  vm_mesh_add_field(m, "layer", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  memcpy(f->data, lay, sizeof *lay * (size_t)ne);
  vm_mesh_add_field(m, "thickness", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
  for (int64_t e = 0; e < ne; e++) ((double *)f->data)[e] = lay[e] < 0 ? 0 : sqrt(2.0 + e);
  vm_mesh_set_attr(m, "gmsh:physical_name:2:1", "wall");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:2", "outer");
  free(tag);
  free(lay);
  return m;
}

static inline const int32_t *i32_field(const vm_mesh *m, const char *name) {
  const vm_field *f = vm_mesh_find_field(m, name, VM_FIELD_ELEMENT);
  return f && f->type == VM_FIELD_I32 ? f->data : NULL;
}

/* The name of element e's family, as the writers see it. */
static inline const char *family_of(const vm_mesh *m, int64_t e, char *buf, size_t n) {
  const int32_t *t = i32_field(m, "gmsh:physical");
  int tag = t ? t[e] : 0;
  char key[64];
  snprintf(key, sizeof key, "gmsh:physical_name:2:%d", tag);
  const char *nm = vm_mesh_get_attr(m, key);
  if (nm) return nm;
  snprintf(buf, n, "boundary_%d", tag);
  return buf;
}

/* Is b's element eb the same as a's ea: type and vertices in order? */
static inline int same_elem(const vm_mesh *a, int64_t ea, const vm_mesh *b, int64_t eb) {
  if (a->etype[ea] != b->etype[eb]) return 0;
  int k = vm_elem_nverts(a->etype[ea]);
  return !memcmp(a->conn + a->eoff[ea], b->conn + b->eoff[eb], sizeof(int32_t) * (size_t)k);
}

/* The writers' element order: cells (in `cell_order`: 0 mesh order, 1
 * grouped by type as CGNS stores them), then faces by family tag, each
 * family in mesh order (SU2) or its triangles then its quads, each in mesh
 * order (CGNS: a section per face type). Fills ord[] and returns its
 * length. */
static inline int64_t writer_order(const vm_mesh *m, int cell_order, int64_t *ord) {
  int64_t k = 0;
  static const int vol[4] = {VM_TET, VM_PYRAMID, VM_PRISM, VM_HEX};
  if (!cell_order) {
    for (int64_t e = 0; e < m->ne; e++)
      if (vm_elem_dim(m->etype[e]) == 3) ord[k++] = e;
  } else {
    for (int t = 0; t < 4; t++)
      for (int64_t e = 0; e < m->ne; e++)
        if (m->etype[e] == vol[t]) ord[k++] = e;
  }
  const int32_t *tg = i32_field(m, "gmsh:physical");
  int32_t lo = INT32_MAX, hi = INT32_MIN;
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 2) {
      int32_t t = tg ? tg[e] : 0;
      lo = t < lo ? t : lo;
      hi = t > hi ? t : hi;
    }
  for (int64_t t = lo; t <= hi; t++)
    for (int ft = VM_TRI; ft <= VM_QUAD; ft++)
      for (int64_t e = 0; e < m->ne; e++)
        if (vm_elem_dim(m->etype[e]) == 2 && (tg ? tg[e] : 0) == t &&
            (!cell_order || m->etype[e] == ft) && (cell_order || ft == VM_TRI))
          ord[k++] = e;
  return k;
}

/* `got` (read back) against `orig` as the writer saw it: coordinates bit
 * for bit, elements in the writer's order with their vertices in order,
 * faces in families of the same names; element fields listed in `fields`
 * carried value for value. Returns the number of differences. */
static inline int compare_read_back(const char *what, const vm_mesh *orig, const vm_mesh *got,
                                    int cell_order, const char *const *fields) {
  int bad = 0;
  CHECK(got->nv == orig->nv, "%s: %lld vertices, want %lld", what, (long long)got->nv,
        (long long)orig->nv);
  CHECK(got->ne == orig->ne, "%s: %lld elements, want %lld", what, (long long)got->ne,
        (long long)orig->ne);
  if (got->nv != orig->nv || got->ne != orig->ne) return 1;
  if (memcmp(got->xyz, orig->xyz, sizeof(double) * 3 * (size_t)orig->nv)) bad++;
  CHECK(!bad, "%s: coordinates differ", what);
  int64_t *ord = malloc(sizeof *ord * (size_t)(orig->ne + 1));
  int64_t n = writer_order(orig, cell_order, ord);
  CHECK(n == orig->ne, "%s: writer order covers %lld of %lld", what, (long long)n,
        (long long)orig->ne);
  int64_t ndiff = 0, nfam = 0;
  for (int64_t e = 0; e < n; e++) {
    ndiff += !same_elem(orig, ord[e], got, e);
    if (vm_elem_dim(got->etype[e]) == 2) {
      char b1[32], b2[32];
      nfam += strcmp(family_of(orig, ord[e], b1, sizeof b1), family_of(got, e, b2, sizeof b2)) != 0;
    }
  }
  CHECK(ndiff == 0, "%s: %lld elements differ", what, (long long)ndiff);
  CHECK(nfam == 0, "%s: %lld faces in another family", what, (long long)nfam);
  bad += ndiff != 0 || nfam != 0;
  for (int i = 0; fields && fields[i]; i++) {
    const vm_field *fa = vm_mesh_find_field(orig, fields[i], VM_FIELD_ELEMENT);
    const vm_field *fb = vm_mesh_find_field(got, fields[i], VM_FIELD_ELEMENT);
    CHECK(fa && fb && fa->type == fb->type && fb->ncomp == 1, "%s: field '%s' missing", what,
          fields[i]);
    if (!fa || !fb || fa->type != fb->type) {
      bad++;
      continue;
    }
    int64_t nd = 0;
    for (int64_t e = 0; e < n; e++) {
      if (vm_elem_dim(got->etype[e]) != 3) continue;
      if (fa->type == VM_FIELD_I32)
        nd += ((int32_t *)fa->data)[ord[e]] != ((int32_t *)fb->data)[e];
      else
        nd += memcmp((double *)fa->data + ord[e], (double *)fb->data + e, sizeof(double)) != 0;
    }
    CHECK(nd == 0, "%s: field '%s': %lld cell values differ", what, fields[i], (long long)nd);
    bad += nd != 0;
  }
  free(ord);
  return bad;
}

/* Two meshes bit for bit (counts, coordinates, elements, fields, attributes). */
static inline const char *mesh_diff(const vm_mesh *a, const vm_mesh *b) {
  if (a->dim != b->dim) return "dim";
  if (a->nv != b->nv || a->ne != b->ne) return "counts";
  if (a->nv && memcmp(a->xyz, b->xyz, sizeof(double) * 3 * (size_t)a->nv)) return "coordinates";
  for (int64_t e = 0; e < a->ne; e++)
    if (!same_elem(a, e, b, e)) return "elements";
  if (a->nfield != b->nfield) return "number of fields";
  for (int i = 0; i < a->nfield; i++) {
    const vm_field *f = &a->fields[i];
    const vm_field *g = vm_mesh_find_field(b, f->name, f->location);
    if (!g || g->type != f->type || g->ncomp != f->ncomp) return "field";
    size_t n = (size_t)vm_field_count(a, f) * (size_t)f->ncomp;
    if (n && memcmp(f->data, g->data, n * (f->type == VM_FIELD_F64 ? 8 : 4))) return "field values";
  }
  if (a->nattr != b->nattr) return "number of attributes";
  for (int i = 0; i < a->nattr; i++) {
    const char *v = vm_mesh_get_attr(b, a->attrs[i].key);
    if (!v || strcmp(v, a->attrs[i].value)) return "attribute";
  }
  return NULL;
}

/* A surface in 3D: a jittered icosphere (triangles, coordinates with all
 * bits in use) and a jittered torus of quadrilaterals. interleave 0: the
 * triangles then the quads, as CGNS stores them (a section per type);
 * 1: the two alternate (SU2 keeps any order). */
static inline vm_mesh *surface_mesh(vm_ctx *ctx, int interleave) {
  vm_mesh *s, *m;
  vm_mesh_create(ctx, &s);
  vm_gen_jitter j = {0.2, 7};
  static const double c[3] = {3.0, 0.25, -1.0 / 3.0};
  vm_gen_icosphere(s, NULL, 1.0, 2, 0, &j);
  vm_gen_torus(s, c, 1.5, 0.5, 12, 8, VM_GEN_TORUS_QUAD, &j, NULL);
  if (!interleave) return s;
  vm_mesh_create(ctx, &m);
  vm_mesh_set_vertices(m, s->nv);
  memcpy(m->xyz, s->xyz, sizeof(double) * 3 * (size_t)s->nv);
  int64_t ntri = 0;
  while (ntri < s->ne && s->etype[ntri] == VM_TRI) ntri++;
  for (int64_t i = 0, k = ntri; i < ntri || k < s->ne;) {
    if (i < ntri) vm_mesh_add_element(m, VM_TRI, s->conn + s->eoff[i++]);
    if (k < s->ne) vm_mesh_add_element(m, VM_QUAD, s->conn + s->eoff[k++]);
  }
  vm_mesh_destroy(&s);
  return m;
}

/* Whole file into a malloc'd NUL-terminated string. */
static inline char *slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  size_t got = fread(s, 1, (size_t)n, f);
  fclose(f);
  s[got] = 0;
  if (len) *len = got;
  return s;
}

/* Log sink that counts warnings. */
typedef struct {
  int warnings;
  char last[512];
} tlog;

static inline void tlog_fn(void *user, int level, const char *msg) {
  tlog *l = user;
  if (level == VM_LOG_WARN) {
    l->warnings++;
    snprintf(l->last, sizeof l->last, "%s", msg);
  }
}

#endif
