/* test/io_vmsh/vmsh_testlib.h: shared helpers for the .vmsh tests: sample
 * meshes, deep comparison, file helpers, and chunk patching with CRC fix-up. */
#ifndef VMSH_TESTLIB_H
#define VMSH_TESTLIB_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "vmtest.h"

/* A 3D mixed mesh: hex, prism, pyramid, tet, tri, quad; fixed and slip
 * vertices; f64/i32 fields with 1 and 3 components on vertices and
 * elements; attributes with characters the text variant must escape. */
static inline vm_mesh *vt_mixed(vm_ctx *ctx) {
  static const double base[13][3] = {{0, 0, 0}, {1, 0, 0},      {1, 1, 0},   {0, 1, 0}, {0, 0, 1},
                                     {1, 0, 1}, {1, 1, 1},      {0, 1, 1},   {0, 0, 2}, {1, 0, 2},
                                     {1, 1, 2}, {0.5, 0.5, -1}, {-1, 0.5, 1}};
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m)) return NULL;
  for (int i = 0; i < 13; i++) {
    /* awkward values: not representable in short decimal */
    double d = (i + 1) / 3.0 * 1e-2;
    vm_mesh_add_vertex(m, base[i][0] + d, base[i][1] - d / 7.0, base[i][2] + 0.1 * d, NULL);
  }
  m->xyz[0] = -0.0;
  m->xyz[1] = 1e-310; /* subnormal */
  m->xyz[2] = 1e300;
  for (int v = 0; v < 4; v++) m->vflag[v] = VM_VERTEX_FIXED;
  for (int v = 8; v < 11; v++) {
    m->vflag[v] = VM_VERTEX_SLIP;
    m->vsurf[v] = 3;
  }
  m->vflag[11] = VM_VERTEX_SLIP;
  m->vsurf[11] = 7;
  static const int32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  static const int32_t prism[6] = {4, 5, 6, 8, 9, 10};
  static const int32_t pyr[5] = {0, 3, 2, 1, 11};
  static const int32_t tet[4] = {0, 4, 3, 12};
  static const int32_t tri[3] = {8, 9, 10};
  static const int32_t quad[4] = {0, 1, 5, 4};
  vm_mesh_add_element(m, VM_HEX, hex);
  vm_mesh_add_element(m, VM_PRISM, prism);
  vm_mesh_add_element(m, VM_PYRAMID, pyr);
  vm_mesh_add_element(m, VM_TET, tet);
  vm_mesh_add_element(m, VM_TRI, tri);
  vm_mesh_add_element(m, VM_QUAD, quad);
  vm_field *f;
  vm_mesh_add_field(m, "curvature", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  for (int v = 0; v < 13; v++) ((double *)f->data)[v] = v * 0.25 - 1 / 3.0;
  vm_mesh_add_field(m, "normal", VM_FIELD_VERTEX, VM_FIELD_F64, 3, &f);
  for (int i = 0; i < 39; i++) ((double *)f->data)[i] = (i % 5) / 9.0 - 0.2;
  vm_mesh_add_field(m, "fixed", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f);
  for (int v = 0; v < 4; v++) ((int32_t *)f->data)[v] = 1;
  vm_mesh_add_field(m, "layer", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int e = 0; e < 6; e++) ((int32_t *)f->data)[e] = e;
  vm_mesh_add_field(m, "tags", VM_FIELD_ELEMENT, VM_FIELD_I32, 3, &f);
  for (int i = 0; i < 18; i++) ((int32_t *)f->data)[i] = (i - 9) * 100003;
  ((int32_t *)f->data)[0] = INT32_MIN;
  ((int32_t *)f->data)[1] = INT32_MAX;
  vm_mesh_add_field(m, "target thickness", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
  for (int e = 0; e < 6; e++) ((double *)f->data)[e] = 1e-3 * (e + 1) / 7.0;
  /* same name as a vertex field, other location: allowed */
  vm_mesh_add_field(m, "curvature", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
  for (int e = 0; e < 6; e++) ((double *)f->data)[e] = -e / 11.0;
  vm_mesh_set_attr(m, "gmsh:physical_name:2:7", "wall");
  vm_mesh_set_attr(m, "note", "spaces, \"quotes\", 100% and a\ttab");
  vm_mesh_set_attr(m, "empty", "");
  vm_mesh_set_attr(m, "utf8", "\xd1\x81\xd0\xb5\xd1\x82\xd0\xba\xd0\xb0");
  return m;
}

/* A 2D mesh (dim 2, z = 0): two triangles and a quad, one field. */
static inline vm_mesh *vt_planar(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m)) return NULL;
  m->dim = 2;
  static const double p[6][2] = {{0, 0}, {1, 0}, {2, 0}, {0, 1}, {1, 1}, {2, 1.5}};
  for (int i = 0; i < 6; i++) vm_mesh_add_vertex(m, p[i][0] + i / 30.0, p[i][1], 0, NULL);
  m->vflag[0] = VM_VERTEX_FIXED;
  m->vflag[2] = VM_VERTEX_SLIP;
  m->vsurf[2] = 1;
  static const int32_t t0[3] = {0, 1, 4}, t1[3] = {0, 4, 3}, q[4] = {1, 2, 5, 4};
  vm_mesh_add_element(m, VM_TRI, t0);
  vm_mesh_add_element(m, VM_TRI, t1);
  vm_mesh_add_element(m, VM_QUAD, q);
  vm_field *f;
  vm_mesh_add_field(m, "weight", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
  for (int e = 0; e < 3; e++) ((double *)f->data)[e] = 1.0 / (e + 3);
  return m;
}

/* memcmp that accepts NULL for empty ranges */
static inline int vt_differ(const void *a, const void *b, size_t n) {
  return n && memcmp(a, b, n) != 0;
}

/* Deep, bit-exact comparison; reports the first difference. */
static inline int vt_mesh_equal(const vm_mesh *a, const vm_mesh *b) {
  if (a->dim != b->dim || a->nv != b->nv || a->ne != b->ne) {
    fprintf(stderr, "dim/nv/ne differ\n");
    return 0;
  }
  size_t nv = (size_t)a->nv, ne = (size_t)a->ne;
  if (vt_differ(a->xyz, b->xyz, 3 * nv * sizeof(double)) || vt_differ(a->vflag, b->vflag, nv) ||
      vt_differ(a->vsurf, b->vsurf, nv * sizeof(int32_t))) {
    fprintf(stderr, "vertex data differ\n");
    return 0;
  }
  if (vt_differ(a->etype, b->etype, ne) ||
      vt_differ(a->eoff, b->eoff, (ne + 1) * sizeof(int64_t)) ||
      vt_differ(a->conn, b->conn, (size_t)a->eoff[ne] * sizeof(int32_t))) {
    fprintf(stderr, "element data differ\n");
    return 0;
  }
  if (a->nfield != b->nfield || a->nattr != b->nattr) {
    fprintf(stderr, "field/attribute counts differ\n");
    return 0;
  }
  for (int i = 0; i < a->nfield; i++) {
    const vm_field *f = &a->fields[i], *g = &b->fields[i];
    size_t esz = f->type == VM_FIELD_F64 ? 8 : 4;
    if (strcmp(f->name, g->name) || f->location != g->location || f->type != g->type ||
        f->ncomp != g->ncomp ||
        vt_differ(f->data, g->data, (size_t)vm_field_count(a, f) * (size_t)f->ncomp * esz)) {
      fprintf(stderr, "field %d ('%s') differs\n", i, f->name);
      return 0;
    }
  }
  for (int i = 0; i < a->nattr; i++)
    if (strcmp(a->attrs[i].key, b->attrs[i].key) || strcmp(a->attrs[i].value, b->attrs[i].value)) {
      fprintf(stderr, "attribute %d differs\n", i);
      return 0;
    }
  return 1;
}

static inline uint8_t *vt_slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  *len = 0;
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  uint8_t *b = malloc((size_t)n + 1);
  if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
    free(b);
    b = NULL;
  }
  fclose(f);
  if (b) *len = (size_t)n;
  return b;
}

static inline int vt_spit(const char *path, const void *buf, size_t len) {
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  size_t w = fwrite(buf, 1, len, f);
  return (fclose(f) == 0 && w == len) ? 0 : -1;
}

static inline int vt_same_file(const char *a, const char *b) {
  size_t na, nb;
  uint8_t *x = vt_slurp(a, &na), *y = vt_slurp(b, &nb);
  int same = x && y && na == nb && !memcmp(x, y, na);
  free(x);
  free(y);
  return same;
}

/* Independent bitwise CRC-32 (IEEE, reflected 0xEDB88320, init/xorout ~0). */
static inline uint32_t vt_crc32(const uint8_t *p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; i++) {
    c ^= p[i];
    for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1)));
  }
  return c ^ 0xFFFFFFFFu;
}

static inline uint32_t vt_get32(const uint8_t *p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline uint64_t vt_get64(const uint8_t *p) {
  return (uint64_t)vt_get32(p) | (uint64_t)vt_get32(p + 4) << 32;
}
static inline void vt_put32(uint8_t *p, uint32_t v) {
  for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i));
}
static inline void vt_put64(uint8_t *p, uint64_t v) {
  for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i));
}

/* Recompute the trailer CRC after patching a binary file in memory. */
static inline void vt_fix_crc(uint8_t *buf, size_t len) {
  if (len >= 4) vt_put32(buf + len - 4, vt_crc32(buf, len - 4));
}

/* Offset of the n-th (0-based) chunk with this tag, or 0 if none. */
static inline size_t vt_find_chunk(const uint8_t *buf, size_t len, const char *tag, int nth) {
  size_t p = 24;
  while (p + 16 <= len - 4) {
    uint64_t l = vt_get64(buf + p + 8);
    if (!memcmp(buf + p, tag, 4) && nth-- == 0) return p;
    p += 16 + ((l + 7) & ~(uint64_t)7);
  }
  return 0;
}

static inline double vt_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
