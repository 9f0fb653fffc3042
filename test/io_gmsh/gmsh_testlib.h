/* test/io_gmsh/gmsh_testlib.h: shared helpers for the .msh / MEDIT tests:
 * warning capture, reference cells, signed volumes, exact mesh comparison,
 * byte buffers for hand-built binary files, temporary directories. */
#ifndef GMSH_TESTLIB_H
#define GMSH_TESTLIB_H

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/ctx.h"
#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "vmtest.h"

/* warning capture */

typedef struct {
  int nwarn;
  char all[8192]; /* every warning, newline separated (truncated) */
} tlog;

static inline void tlog_fn(void *user, int level, const char *msg) {
  tlog *l = user;
  if (level != VM_LOG_WARN) return;
  l->nwarn++;
  size_t n = strlen(l->all);
  if (n + strlen(msg) + 2 < sizeof l->all) {
    strcat(l->all, msg);
    strcat(l->all, "\n");
  }
}

static inline void tlog_reset(tlog *l) {
  l->nwarn = 0;
  l->all[0] = 0;
}

static inline int tlog_has(const tlog *l, const char *s) { return strstr(l->all, s) != NULL; }

/* signed measure of one element: area in the xy plane for 2D cells,
 * volume by the divergence theorem over the outward faces of vm_elem_faces */

static inline double elem_measure(const vm_mesh *m, int64_t e) {
  const int32_t *c = m->conn + m->eoff[e];
  int t = m->etype[e];
  if (vm_elem_dim(t) == 2) {
    int k = vm_elem_nverts(t);
    double a = 0;
    for (int i = 0; i < k; i++) {
      const double *p = m->xyz + 3 * c[i], *q = m->xyz + 3 * c[(i + 1) % k];
      a += p[0] * q[1] - q[0] * p[1];
    }
    return 0.5 * a;
  }
  int faces[6][4], nfv[6];
  int nf = vm_elem_faces(t, faces, nfv);
  double v = 0;
  for (int f = 0; f < nf; f++)
    for (int j = 1; j + 1 < nfv[f]; j++) {
      const double *a = m->xyz + 3 * c[faces[f][0]];
      const double *b = m->xyz + 3 * c[faces[f][j]];
      const double *d = m->xyz + 3 * c[faces[f][j + 1]];
      v += a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
           a[2] * (b[0] * d[1] - b[1] * d[0]);
    }
  return v / 6.0;
}

/* reference cells of every type, positively oriented in vm (VTK) order */

static const double ref_area_or_volume[VM_NTYPES] = {0.5, 1.0, 1.0 / 6.0, 1.0 / 3.0, 0.5, 1.0};

/* Appends the reference cell of `type` translated by `shift` along x. */
static inline void add_ref_cell(vm_mesh *m, int type, double shift) {
  static const double tri[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  static const double quad[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  static const double tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  static const double pyr[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  static const double pri[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  static const double hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const double(*p)[3] = type == VM_TRI       ? tri
                        : type == VM_QUAD    ? quad
                        : type == VM_TET     ? tet
                        : type == VM_PYRAMID ? pyr
                        : type == VM_PRISM   ? pri
                                             : hex;
  int k = vm_elem_nverts(type);
  int32_t v[8];
  for (int i = 0; i < k; i++) {
    int64_t idx;
    vm_mesh_add_vertex(m, p[i][0] + shift, p[i][1], p[i][2], &idx);
    v[i] = (int32_t)idx;
  }
  vm_mesh_add_element(m, type, v);
}

/* exact comparison of two meshes (fields and attributes by name) */

static inline int same_field(const vm_mesh *a, const vm_field *f, const vm_mesh *b) {
  const vm_field *g = vm_mesh_find_field(b, f->name, f->location);
  if (!g || g->type != f->type || g->ncomp != f->ncomp) return 0;
  size_t esz = f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t);
  return !memcmp(f->data, g->data, (size_t)vm_field_count(a, f) * (size_t)f->ncomp * esz);
}

/* Compares geometry, connectivity, flags, every field of `a` and every
 * attribute of `a`; reports the first difference through CHECK. */
static inline int check_same_mesh(const vm_mesh *a, const vm_mesh *b, const char *what) {
  int ok = 1;
#define SAME(cond, ...)                                                                            \
  do {                                                                                             \
    CHECK(cond, __VA_ARGS__);                                                                      \
    if (!(cond)) ok = 0;                                                                           \
  } while (0)
  SAME(a->dim == b->dim, "%s: dim %d vs %d", what, a->dim, b->dim);
  SAME(a->nv == b->nv, "%s: nv %lld vs %lld", what, (long long)a->nv, (long long)b->nv);
  SAME(a->ne == b->ne, "%s: ne %lld vs %lld", what, (long long)a->ne, (long long)b->ne);
  if (!ok) return 0;
  SAME(!memcmp(a->xyz, b->xyz, (size_t)a->nv * 3 * sizeof(double)), "%s: coordinates differ", what);
  SAME(!memcmp(a->vflag, b->vflag, (size_t)a->nv), "%s: vertex flags differ", what);
  SAME(!memcmp(a->vsurf, b->vsurf, (size_t)a->nv * sizeof(int32_t)), "%s: surface ids differ",
       what);
  SAME(!memcmp(a->etype, b->etype, (size_t)a->ne), "%s: element types differ", what);
  SAME(!memcmp(a->eoff, b->eoff, (size_t)(a->ne + 1) * sizeof(int64_t)), "%s: offsets differ",
       what);
  if (ok)
    SAME(!memcmp(a->conn, b->conn, (size_t)a->eoff[a->ne] * sizeof(int32_t)),
         "%s: connectivity differs", what);
  for (int i = 0; i < a->nfield; i++)
    SAME(same_field(a, &a->fields[i], b), "%s: field '%s' differs or is missing", what,
         a->fields[i].name);
  for (int i = 0; i < a->nattr; i++) {
    const char *v = vm_mesh_get_attr(b, a->attrs[i].key);
    SAME(v && !strcmp(v, a->attrs[i].value), "%s: attribute '%s' differs or is missing", what,
         a->attrs[i].key);
  }
#undef SAME
  return ok;
}

/* byte buffer for hand-built files (optionally byte-swapped numbers) */

typedef struct {
  uint8_t *p;
  size_t n, cap;
  int swap;
} tbuf;

static inline void tb_raw(tbuf *b, const void *src, size_t n) {
  if (b->n + n > b->cap) {
    b->cap = (b->n + n) * 2 + 64;
    b->p = realloc(b->p, b->cap);
  }
  memcpy(b->p + b->n, src, n);
  if (b->swap && (n == 4 || n == 8))
    for (size_t i = 0; i < n / 2; i++) {
      uint8_t t = b->p[b->n + i];
      b->p[b->n + i] = b->p[b->n + n - 1 - i];
      b->p[b->n + n - 1 - i] = t;
    }
  b->n += n;
}
static inline void tb_str(tbuf *b, const char *s) {
  int sw = b->swap;
  b->swap = 0;
  tb_raw(b, s, strlen(s));
  b->swap = sw;
}
static inline void tb_i32(tbuf *b, int32_t v) { tb_raw(b, &v, 4); }
static inline void tb_u64(tbuf *b, uint64_t v) { tb_raw(b, &v, 8); }
static inline void tb_f64(tbuf *b, double v) { tb_raw(b, &v, 8); }
static inline void tb_free(tbuf *b) {
  free(b->p);
  memset(b, 0, sizeof *b);
}

/* temporary files */

static char tdir[64];

static inline void tdir_make(void) {
  strcpy(tdir, "/tmp/vm_gmsh_XXXXXX");
  if (!mkdtemp(tdir)) {
    perror("mkdtemp");
    exit(1);
  }
}

static inline void tdir_path(char *out, size_t n, const char *file) {
  snprintf(out, n, "%s/%s", tdir, file);
}

/* Number of entries in the temporary directory (temp files left behind?). */
static inline int tdir_count(void) {
  DIR *d = opendir(tdir);
  int n = 0;
  struct dirent *e;
  while (d && (e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
  if (d) closedir(d);
  return n;
}

static inline void tdir_remove(void) {
  DIR *d = opendir(tdir);
  struct dirent *e;
  char p[600];
  while (d && (e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(p, sizeof p, "%s/%s", tdir, e->d_name);
    unlink(p);
  }
  if (d) closedir(d);
  rmdir(tdir);
}

/* Reads a whole file with stdio (test side). */
static inline uint8_t *slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  uint8_t *b = malloc((size_t)n + 1);
  *len = fread(b, 1, (size_t)n, f);
  fclose(f);
  return b;
}

/* Reads from memory, expecting success; NULL (and a failed CHECK) otherwise. */
static inline vm_mesh *read_ok(vm_ctx *ctx, const char *name, const void *buf, size_t len,
                               int fmt) {
  vm_mesh *m = NULL;
  int st = vm_mesh_read_memory(ctx, name, buf, len, fmt, &m);
  CHECK(st == VM_OK && m, "%s: read failed: %d %s", name, st, vm_ctx_error(ctx));
  return st == VM_OK ? m : NULL;
}

static inline int32_t ifield(const vm_mesh *m, const char *name, int loc, int64_t i) {
  const vm_field *f = vm_mesh_find_field(m, name, loc);
  if (!f || f->type != VM_FIELD_I32) return INT32_MIN;
  return ((const int32_t *)f->data)[i * f->ncomp];
}

static inline double dfield(const vm_mesh *m, const char *name, int loc, int64_t i, int c) {
  const vm_field *f = vm_mesh_find_field(m, name, loc);
  if (!f || f->type != VM_FIELD_F64) return -1e300;
  return ((const double *)f->data)[i * f->ncomp + c];
}

#endif
