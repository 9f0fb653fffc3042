/* test/io_vtk/test_vtk.c: legacy VTK and VTU readers and writers: round
 * trips, hand-written files, element orientation, conventions, bad input. */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "vmtest.h"
#include "zlib_vectors.h"

static char tmpdir[64];
static int nwarn;
static char warns[8192];

static void on_log(void *user, int level, const char *msg) {
  (void)user;
  if (level != VM_LOG_WARN) return;
  nwarn++;
  size_t n = strlen(warns);
  snprintf(warns + n, sizeof warns - n, "%s\n", msg);
}

static void clear_warns(void) {
  nwarn = 0;
  warns[0] = 0;
}

/* Building meshes. */

static const double ref_tri[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
static const double ref_quad[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
static const double ref_tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const double ref_pyr[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
static const double ref_prism[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                       {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
static const double ref_hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

static const double (*ref_cell(int type))[3] {
  switch (type) {
  case VM_TRI: return ref_tri;
  case VM_QUAD: return ref_quad;
  case VM_TET: return ref_tet;
  case VM_PYRAMID: return ref_pyr;
  case VM_PRISM: return ref_prism;
  default: return ref_hex;
  }
}

/* One reference cell of each type, own vertices, awkward coordinates. */
static vm_mesh *mixed_mesh(vm_ctx *ctx) {
  vm_mesh *m;
  if (vm_mesh_create(ctx, &m)) return NULL;
  const int order[6] = {VM_HEX, VM_PRISM, VM_PYRAMID, VM_TET, VM_TRI, VM_QUAD};
  for (int c = 0; c < 6; c++) {
    int t = order[c], k = vm_elem_nverts(t);
    const double(*p)[3] = ref_cell(t);
    int32_t ids[8];
    for (int i = 0; i < k; i++) {
      int64_t id;
      vm_mesh_add_vertex(m, p[i][0] / 3.0 + 1.7 * c + 1e-9 * i, p[i][1] * 3.14159265358979 - 0.1,
                         p[i][2] * 1e-7 + 1.0 / 7.0 * c, &id);
      ids[i] = (int32_t)id;
    }
    vm_mesh_add_element(m, t, ids);
  }
  /* two loose vertices with values %.17g must still carry exactly */
  vm_mesh_add_vertex(m, -0.0, 1e-310, 1.7976931348623157e308, NULL);
  vm_mesh_add_vertex(m, -2.2250738585072014e-308, 4.9406564584124654e-324, -1e300, NULL);
  /* flags: two fixed, two slip on surfaces 5 and 7 */
  m->vflag[0] = m->vflag[1] = VM_VERTEX_FIXED;
  m->vflag[2] = m->vflag[3] = VM_VERTEX_SLIP;
  m->vsurf[2] = 5;
  m->vsurf[3] = 7;
  vm_field *f;
  vm_mesh_add_field(m, "temperature", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  for (int64_t v = 0; v < m->nv; v++) ((double *)f->data)[v] = v * 0.1 + 1.0 / 7.0;
  vm_mesh_add_field(m, "velocity", VM_FIELD_VERTEX, VM_FIELD_F64, 3, &f);
  for (int64_t i = 0; i < 3 * m->nv; i++) ((double *)f->data)[i] = sin((double)i) * 1e3;
  vm_mesh_add_field(m, "fixed", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f);
  ((int32_t *)f->data)[0] = ((int32_t *)f->data)[1] = 1;
  vm_mesh_add_field(m, "label id", VM_FIELD_VERTEX, VM_FIELD_I32, 3, &f);
  for (int64_t i = 0; i < 3 * m->nv; i++) ((int32_t *)f->data)[i] = (int32_t)(i * 7919 - 1000);
  ((int32_t *)f->data)[0] = INT32_MIN;
  ((int32_t *)f->data)[1] = INT32_MAX;
  vm_mesh_add_field(m, "region", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(10 + e);
  vm_mesh_add_field(m, "stress<&>\"", VM_FIELD_ELEMENT, VM_FIELD_F64, 3, &f);
  for (int64_t i = 0; i < 3 * m->ne; i++) ((double *)f->data)[i] = 1.0 / (i + 3.0);
  vm_mesh_add_field(m, "cell ids", VM_FIELD_ELEMENT, VM_FIELD_I32, 3, &f);
  for (int64_t i = 0; i < 3 * m->ne; i++) ((int32_t *)f->data)[i] = (int32_t)(-i * 100003);
  vm_mesh_add_field(m, "temperature", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((double *)f->data)[e] = -1.5 * e;
  return m;
}

static void same_mesh(const vm_mesh *a, const vm_mesh *b, const char *what) {
  CHECK(a->dim == b->dim, "%s: dim %d vs %d", what, a->dim, b->dim);
  CHECK(a->nv == b->nv, "%s: nv %lld vs %lld", what, (long long)a->nv, (long long)b->nv);
  CHECK(a->ne == b->ne, "%s: ne %lld vs %lld", what, (long long)a->ne, (long long)b->ne);
  if (a->nv != b->nv || a->ne != b->ne) return;
  CHECK(!memcmp(a->xyz, b->xyz, (size_t)a->nv * 3 * sizeof(double)), "%s: coordinates differ",
        what);
  CHECK(!memcmp(a->vflag, b->vflag, (size_t)a->nv), "%s: flags differ", what);
  CHECK(!memcmp(a->vsurf, b->vsurf, (size_t)a->nv * 4), "%s: surface ids differ", what);
  CHECK(!memcmp(a->etype, b->etype, (size_t)a->ne), "%s: types differ", what);
  CHECK(!memcmp(a->eoff, b->eoff, (size_t)(a->ne + 1) * 8), "%s: offsets differ", what);
  CHECK(!memcmp(a->conn, b->conn, (size_t)a->eoff[a->ne] * 4), "%s: connectivity differs", what);
  CHECK(a->nfield == b->nfield, "%s: %d fields vs %d", what, a->nfield, b->nfield);
  for (int i = 0; i < a->nfield; i++) {
    const vm_field *f = &a->fields[i], *g = vm_mesh_find_field(b, f->name, f->location);
    CHECK(g != NULL, "%s: field '%s' lost", what, f->name);
    if (!g) continue;
    CHECK(g->type == f->type && g->ncomp == f->ncomp, "%s: field '%s' type/ncomp", what, f->name);
    if (g->type != f->type || g->ncomp != f->ncomp) continue;
    size_t n = (size_t)vm_field_count(a, f) * (size_t)f->ncomp *
               (f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
    CHECK(!memcmp(f->data, g->data, n), "%s: field '%s' values differ", what, f->name);
  }
}

/* Signed measures, computed here independently of the library. */

static void sub(const double *a, const double *b, double *r) {
  for (int i = 0; i < 3; i++) r[i] = a[i] - b[i];
}
static double det3(const double *a, const double *b, const double *c) {
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* Volume (3D) by the divergence theorem over outward faces in VTK order, or
 * signed area seen from +z (2D). */
static double signed_measure(const vm_mesh *m, int64_t e) {
  static const int tet[4][4] = {{0, 2, 1, -1}, {0, 1, 3, -1}, {1, 2, 3, -1}, {0, 3, 2, -1}};
  static const int pyr[5][4] = {
      {0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}};
  static const int pri[5][4] = {
      {0, 2, 1, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};
  static const int hex[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                {1, 2, 6, 5}, {2, 3, 7, 6}, {0, 4, 7, 3}};
  const int32_t *c = m->conn + m->eoff[e];
  int t = m->etype[e], k = vm_elem_nverts(t);
  const double *x[8];
  for (int i = 0; i < k; i++) x[i] = m->xyz + 3 * c[i];
  if (t == VM_TRI || t == VM_QUAD) {
    double a = 0;
    for (int i = 0; i < k; i++) {
      const double *p = x[i], *q = x[(i + 1) % k];
      a += p[0] * q[1] - q[0] * p[1];
    }
    return a / 2;
  }
  const int(*f)[4] = t == VM_TET ? tet : t == VM_PYRAMID ? pyr : t == VM_PRISM ? pri : hex;
  int nf = t == VM_TET ? 4 : t == VM_PYRAMID ? 5 : t == VM_PRISM ? 5 : 6;
  double cen[3] = {0, 0, 0}, vol = 0;
  for (int i = 0; i < k; i++)
    for (int d = 0; d < 3; d++) cen[d] += x[i][d] / k;
  for (int j = 0; j < nf; j++) {
    int nv = f[j][3] < 0 ? 3 : 4;
    for (int i = 1; i + 1 < nv; i++) {
      double a[3], b[3], d[3];
      sub(x[f[j][0]], cen, a);
      sub(x[f[j][i]], cen, b);
      sub(x[f[j][i + 1]], cen, d);
      vol += det3(a, b, d) / 6;
    }
  }
  return vol;
}

/* File helpers. */

static void path_of(char *buf, size_t n, const char *file) {
  snprintf(buf, n, "%s/%s", tmpdir, file);
}

static char *slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  *len = fread(b, 1, (size_t)n, f);
  b[*len] = 0;
  fclose(f);
  return b;
}

/* strstr over binary text that may hold NUL bytes */
static int contains(const char *text, size_t len, const char *needle) {
  size_t n = strlen(needle);
  for (size_t i = 0; i + n <= len; i++)
    if (!memcmp(text + i, needle, n)) return 1;
  return 0;
}

/* Read from an exact-size copy, so the sanitizers see any overread. */
static int read_mem(vm_ctx *ctx, const char *name, const void *buf, size_t len, vm_mesh **m) {
  void *copy = malloc(len ? len : 1);
  memcpy(copy, buf, len);
  int st = vm_mesh_read_memory(ctx, name, copy, len, VM_FMT_AUTO, m);
  free(copy);
  return st;
}

static vm_mesh *read_ok(vm_ctx *ctx, const char *name, const void *buf, size_t len) {
  vm_mesh *m = NULL;
  int st = read_mem(ctx, name, buf, len, &m);
  CHECK(st == VM_OK && m, "%s: status %d: %s", name, st, vm_ctx_error(ctx));
  return m;
}

static vm_mesh *read_str(vm_ctx *ctx, const char *name, const char *text) {
  return read_ok(ctx, name, text, strlen(text));
}

/* Must fail: negative status (== status if nonzero), one line naming the
 * file (and containing `needle`), no mesh, nothing leaked. Files named
 * lie_* hold a lying count: it must be refused before anything sized by it
 * is allocated (a format error, not out-of-memory; under the sanitizers a
 * terabyte request would abort), after only the few blocks the valid part
 * of the file needs. */
static void expect_fail(vm_ctx *ctx, const char *name, const void *buf, size_t len,
                        const char *needle, int status) {
  long live = vm_ctx_alloc_live(ctx), n0 = vm_ctx_alloc_count(ctx);
  vm_mesh *m = NULL;
  int st = read_mem(ctx, name, buf, len, &m);
  const char *e = vm_ctx_error(ctx);
  CHECK(st < 0, "%s: expected failure, got %d", name, st);
  CHECK(!status || st == status, "%s: status %d, expected %d (%s)", name, st, status, e);
  CHECK(m == NULL, "%s: mesh returned on failure", name);
  CHECK(strstr(e, name) != NULL, "%s: message does not name the file: %s", name, e);
  CHECK(!needle || strstr(e, needle) != NULL, "%s: message lacks '%s': %s", name, needle, e);
  CHECK(strchr(e, '\n') == NULL, "%s: message is not one line", name);
  CHECK(vm_ctx_alloc_live(ctx) == live, "%s: %ld blocks leaked", name,
        vm_ctx_alloc_live(ctx) - live);
  CHECK(strncmp(name, "lie_", 4) || vm_ctx_alloc_count(ctx) - n0 <= 16,
        "%s: %ld allocations before refusing a lying count", name, vm_ctx_alloc_count(ctx) - n0);
  if (m) vm_mesh_destroy(&m);
}

static void expect_fail_str(vm_ctx *ctx, const char *name, const char *text, const char *needle,
                            int status) {
  expect_fail(ctx, name, text, strlen(text), needle, status);
}

/* A legacy file cut at a record boundary is a valid smaller file, and a
 * text number cut short is still a number: where the rest of the full file
 * starts with (the tail of a text token,) blanks and then an upper-case
 * keyword, a prefix may be accepted. */
static int record_boundary(const uint8_t *b, size_t len, size_t n, int text) {
  if (text && n > 0 && b[n - 1] != ' ' && b[n - 1] != '\n')
    while (n < len && b[n] != ' ' && b[n] != '\n') n++;
  else if (n < len && b[n] == '\n')
    n++;
  while (text && n < len && (b[n] == ' ' || b[n] == '\n')) n++;
  return n == len || (b[n] >= 'A' && b[n] <= 'Z');
}

/* Every prefix must fail, except (legacy) at record boundaries; VTU files
 * end with </VTKFile>, so only dropping the final newline may pass. The
 * failures name the file and leak nothing. legacy: 0 VTU, 1 text, 2 binary.
 * Prefixes ending in (skip_lo, skip_hi] (a skipped METADATA block) may pass. */
static void truncations_in(vm_ctx *ctx, const char *name, const void *buf, size_t len, int legacy,
                           size_t skip_lo, size_t skip_hi) {
  int bad = 0, accepted = 0;
  for (size_t n = 0; n < len; n++) {
    long live = vm_ctx_alloc_live(ctx);
    vm_mesh *m = NULL;
    int st = read_mem(ctx, name, buf, n, &m);
    if (st < 0) {
      if (!strstr(vm_ctx_error(ctx), name) || m) bad++;
    } else {
      accepted++;
      int ok = legacy ? record_boundary(buf, len, n, legacy == 1) : n + 1 == len;
      ok |= n > skip_lo && n <= skip_hi;
      if (!ok) {
        bad++;
        fprintf(stderr, "%s: prefix of %zu bytes accepted\n", name, n);
      }
      vm_mesh_destroy(&m);
    }
    if (vm_ctx_alloc_live(ctx) != live) bad++;
  }
  CHECK(bad == 0, "%s: %d truncations misbehaved", name, bad);
  CHECK(accepted < (int)len / 8, "%s: %d of %zu prefixes accepted", name, accepted, len);
}

static void truncations(vm_ctx *ctx, const char *name, const void *buf, size_t len, int legacy) {
  truncations_in(ctx, name, buf, len, legacy, 0, 0);
}

/* Allocation failure at every step: a clean error and no leak each time. */
static void alloc_failures(vm_ctx *ctx, const char *name, const void *buf, size_t len) {
  int bad = 0, n;
  for (n = 1; n < 10000; n++) {
    long live = vm_ctx_alloc_live(ctx);
    vm_mesh *m = NULL;
    vm_ctx_set_alloc_fail(ctx, n);
    int st = read_mem(ctx, name, buf, len, &m);
    vm_ctx_set_alloc_fail(ctx, 0);
    if (st == VM_OK) {
      vm_mesh_destroy(&m);
      break;
    }
    if (st != VM_ERR_NOMEM || m) bad++;
    if (vm_ctx_alloc_live(ctx) != live) bad++;
  }
  CHECK(bad == 0 && n > 1 && n < 10000, "%s: %d allocation failures misbehaved (n=%d)", name, bad,
        n);
}

/* A byte builder for binary files. */

typedef struct {
  uint8_t *b;
  size_t n, cap;
} bytes;

static void put(bytes *s, const void *p, size_t n) {
  if (s->n + n > s->cap) {
    s->cap = (s->n + n) * 2 + 64;
    s->b = realloc(s->b, s->cap);
  }
  memcpy(s->b + s->n, p, n);
  s->n += n;
}
static void putf(bytes *s, const char *fmt, ...) {
  char buf[4096];
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  put(s, buf, (size_t)n);
}
static void put_int(bytes *s, uint64_t v, int size, int big) {
  uint8_t b[8];
  for (int i = 0; i < size; i++) b[big ? size - 1 - i : i] = (uint8_t)(v >> (8 * i));
  put(s, b, (size_t)size);
}
static void put_f64(bytes *s, double x, int big) {
  uint64_t u;
  memcpy(&u, &x, 8);
  put_int(s, u, 8, big);
}
static void put_f32(bytes *s, float x, int big) {
  uint32_t u;
  memcpy(&u, &x, 4);
  put_int(s, u, 4, big);
}

static void b64(bytes *out, const uint8_t *p, size_t n) {
  static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t i = 0; i < n; i += 3) {
    uint32_t w = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0) |
                 (i + 2 < n ? p[i + 2] : 0);
    char q[4] = {t[w >> 18 & 63], t[w >> 12 & 63], i + 1 < n ? t[w >> 6 & 63] : '=',
                 i + 2 < n ? t[w & 63] : '='};
    put(out, q, 4);
  }
}

/* Round trips. */

static void test_roundtrips(vm_ctx *ctx) {
  long live0 = vm_ctx_alloc_live(ctx);
  vm_mesh *m = mixed_mesh(ctx);
  CHECK(m && vm_mesh_check(m) == VM_OK, "mixed mesh invalid: %s", vm_ctx_error(ctx));
  const struct {
    const char *file;
    int binary;
  } cases[] = {{"rt_ascii.vtk", 0}, {"rt_binary.vtk", 1}, {"rt.vtu", 0}, {"rt_b.vtu", 1}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char path[256];
    path_of(path, sizeof path, cases[i].file);
    vm_write_opts o = vm_write_opts_default();
    o.binary = cases[i].binary;
    clear_warns();
    int st = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, &o);
    CHECK(st == VM_OK, "%s: write status %d: %s", path, st, vm_ctx_error(ctx));
    CHECK(nwarn == 0, "%s: unexpected warnings: %s", path, warns);
    vm_mesh *r = NULL;
    st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &r);
    CHECK(st == VM_OK, "%s: read status %d: %s", path, st, vm_ctx_error(ctx));
    if (r) {
      same_mesh(m, r, path);
      for (int64_t e = 0; e < r->ne; e++)
        CHECK(signed_measure(r, e) > 0, "%s: %s lost its orientation", path,
              vm_elem_name(r->etype[e]));
      vm_mesh_destroy(&r);
    }
    size_t len;
    char *text = slurp(path, &len);
    CHECK(text != NULL, "%s: not written", path);
    if (text && strstr(cases[i].file, ".vtk")) {
      CHECK(!strncmp(text, "# vtk DataFile Version 3.0\n", 27), "%s: header", path);
      CHECK(contains(text, len, cases[i].binary ? "\nBINARY\n" : "\nASCII\n"), "%s: mode", path);
      CHECK(contains(text, len, "\nlabel%20id 3 32 int\n"), "%s: encoded name", path);
      alloc_failures(ctx, path, text, len);
      truncations(ctx, path, text, len, cases[i].binary ? 2 : 1);
    } else if (text) {
      CHECK(strstr(text, "header_type=\"UInt64\"") && strstr(text, "version=\"1.0\""),
            "%s: VTKFile attributes", path);
      CHECK(strstr(text, "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"binary\">"),
            "%s: connectivity array", path);
      CHECK(strstr(text, "Name=\"stress&lt;&amp;&gt;&quot;\" NumberOfComponents=\"3\""),
            "%s: escaped name", path);
      CHECK(strstr(text, "Name=\"vm_flag\"") && strstr(text, "Name=\"vm_surface\""),
            "%s: flag arrays", path);
      alloc_failures(ctx, path, text, len);
      truncations(ctx, path, text, len, 0);
    }
    free(text);
  }
  /* a point field named like the flag arrays cannot be written beside them */
  vm_field *sh;
  vm_mesh_add_field(m, "vm_surface", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &sh);
  for (int i = 0; i < 2; i++) {
    char p2[256];
    path_of(p2, sizeof p2, i ? "shadow.vtu" : "shadow.vtk");
    clear_warns();
    CHECK(vm_mesh_write(ctx, m, p2, VM_FMT_AUTO, NULL) == VM_WARN_LOSSY, "%s: lossy", p2);
    CHECK(nwarn == 1 && strstr(warns, "'vm_surface' is shadowed"), "%s: %s", p2, warns);
    vm_mesh *r2 = NULL;
    CHECK(vm_mesh_read(ctx, p2, VM_FMT_AUTO, &r2) == VM_OK && r2 && r2->vsurf[3] == 7 &&
              !vm_mesh_find_field(r2, "vm_surface", VM_FIELD_VERTEX),
          "%s: flags win", p2);
    vm_mesh_destroy(&r2);
  }
  vm_mesh_remove_field(m, "vm_surface", VM_FIELD_VERTEX);
  /* no flags, no arrays named vm_flag */
  memset(m->vflag, 0, (size_t)m->nv);
  vm_mesh_remove_field(m, "fixed", VM_FIELD_VERTEX);
  for (int64_t v = 0; v < m->nv; v++) m->vsurf[v] = -1;
  char path[256];
  path_of(path, sizeof path, "noflags.vtu");
  CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) == VM_OK, "noflags write");
  size_t len;
  char *text = slurp(path, &len);
  CHECK(text && !strstr(text, "vm_flag"), "flag arrays written for a mesh without flags");
  free(text);
  vm_mesh *r = NULL;
  CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &r) == VM_OK, "noflags read");
  if (r) same_mesh(m, r, path);
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "round trips leaked %ld", vm_ctx_alloc_live(ctx) - live0);
}

/* 2D detection, attributes lost with a warning, atomic failure. */
static void test_dim_and_lossy(vm_ctx *ctx) {
  long live0 = vm_ctx_alloc_live(ctx);
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, ref_quad[i][0], ref_quad[i][1], 0, NULL);
  vm_mesh_add_vertex(m, 2, 0.5, 0, NULL);
  const int32_t q[4] = {0, 1, 2, 3}, t[3] = {1, 4, 2};
  vm_mesh_add_element(m, VM_QUAD, q);
  vm_mesh_add_element(m, VM_TRI, t);
  m->dim = 2;
  vm_mesh_set_attr(m, "gmsh:physical_name:2:7", "wall");
  vm_mesh_set_attr(m, "title", "x");
  const char *files[3] = {"flat.vtk", "flat_b.vtk", "flat.vtu"};
  for (int i = 0; i < 3; i++) {
    char path[256];
    path_of(path, sizeof path, files[i]);
    vm_write_opts o = vm_write_opts_default();
    o.binary = i == 1;
    clear_warns();
    int st = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, &o);
    CHECK(st == VM_WARN_LOSSY, "%s: status %d, expected VM_WARN_LOSSY", path, st);
    CHECK(nwarn == 2, "%s: %d warnings", path, nwarn);
    CHECK(strstr(warns, "VTK cannot carry the group names 'wall' of tag 7 (attribute "
                        "'gmsh:physical_name:2:7')") &&
              strstr(warns, "VTK cannot carry the attributes 'title'") && strstr(warns, path),
          "%s: warnings: %s", path, warns);
    vm_mesh *r = NULL;
    st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &r);
    CHECK(st == VM_OK && r && r->dim == 2, "%s: not read back as 2D", path);
    CHECK(r && r->nattr == 0, "%s: attributes", path);
    vm_mesh_destroy(&r);
  }
  /* a z != 0 makes it 3D */
  m->xyz[3 * 4 + 2] = 1e-300;
  char path[256];
  path_of(path, sizeof path, "bent.vtk");
  vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL);
  vm_mesh *r = NULL;
  CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &r) == VM_OK && r && r->dim == 3,
        "bent surface must be 3D");
  vm_mesh_destroy(&r);
  /* unwritable target: error, nothing left behind */
  path_of(path, sizeof path, "no/such/dir/x.vtu");
  CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) == VM_ERR_IO, "unwritable path");
  path_of(path, sizeof path, "no/such/dir/x.vtk");
  CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) == VM_ERR_IO, "unwritable path");
  /* writers under allocation failure: error or success, never a leak or a temp file */
  for (int i = 0; i < 2; i++) {
    path_of(path, sizeof path, i ? "af.vtu" : "af.vtk");
    for (int n = 1; n < 20; n++) {
      long live = vm_ctx_alloc_live(ctx);
      vm_ctx_set_alloc_fail(ctx, n);
      int st = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL);
      vm_ctx_set_alloc_fail(ctx, 0);
      CHECK(st == VM_WARN_LOSSY || st == VM_ERR_NOMEM, "%s: status %d", path, st);
      CHECK(vm_ctx_alloc_live(ctx) == live, "%s: writer leaked", path);
      CHECK(st != VM_ERR_NOMEM || access(path, F_OK) != 0, "%s: file after failure", path);
      if (st >= 0) break;
    }
  }
  vm_mesh_destroy(&m);
  /* the empty mesh */
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 3; i++) {
    path_of(path, sizeof path, files[i]);
    vm_write_opts o = vm_write_opts_default();
    o.binary = i == 1;
    CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, &o) == VM_OK, "%s: empty write", path);
    vm_mesh *r = NULL;
    CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &r) == VM_OK && r && r->nv == 0 && r->ne == 0,
          "%s: empty read: %s", path, vm_ctx_error(ctx));
    vm_mesh_destroy(&r);
  }
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leak %ld", vm_ctx_alloc_live(ctx) - live0);
}

/* Hand-written legacy files. */

/* The six reference cells, VTK orientation, as VTK's documentation lays
 * out an UNSTRUCTURED_GRID; positive measures after reading. */
static void test_reference_cells(vm_ctx *ctx) {
  bytes s = {0};
  putf(&s, "# vtk DataFile Version 2.0\nreference cells\nASCII\n\nDATASET UNSTRUCTURED_GRID\n");
  putf(&s, "POINTS 30 float\n");
  const int types[6] = {VM_TRI, VM_QUAD, VM_TET, VM_PYRAMID, VM_PRISM, VM_HEX};
  for (int c = 0; c < 6; c++) {
    const double(*p)[3] = ref_cell(types[c]);
    for (int i = 0; i < vm_elem_nverts(types[c]); i++)
      putf(&s, "%g %g %g\n", p[i][0] + 2 * c, p[i][1], p[i][2]);
  }
  putf(&s, "CELLS 6 36\n");
  int base = 0;
  /* VTK's vertex order, written out: the same as varmesh's except the
   * wedge, whose base (0,1,2) has its normal pointing away from (3,4,5) */
  static const int vtk_order[6][8] = {{0, 1, 2},          {0, 1, 2, 3},
                                      {0, 1, 2, 3},       {0, 1, 2, 3, 4},
                                      {0, 2, 1, 3, 5, 4}, {0, 1, 2, 3, 4, 5, 6, 7}};
  for (int c = 0; c < 6; c++) {
    int k = vm_elem_nverts(types[c]);
    putf(&s, "%d", k);
    for (int i = 0; i < k; i++) putf(&s, " %d", base + vtk_order[c][i]);
    putf(&s, "\n");
    base += k;
  }
  putf(&s, "CELL_TYPES 6\n5\n9\n10\n14\n13\n12\n");
  vm_mesh *m = read_ok(ctx, "ref.vtk", s.b, s.n);
  if (m) {
    CHECK(m->ne == 6 && m->dim == 3, "reference cells: ne %lld", (long long)m->ne);
    for (int64_t e = 0; e < m->ne && e < 6; e++) {
      CHECK(m->etype[e] == types[e], "cell %lld type %d", (long long)e, m->etype[e]);
      double v = signed_measure(m, e);
      CHECK(v > 0, "%s from a VTK file has measure %g", vm_elem_name(m->etype[e]), v);
    }
    CHECK(m->xyz[3 * 29 + 2] == 1.0f, "float points");
    vm_mesh_destroy(&m);
  }
  free(s.b);
}

static const char polydata_vtk[] = "# vtk DataFile Version 3.0\n"
                                   "polydata with everything\n"
                                   "ASCII\n"
                                   "DATASET POLYDATA\n"
                                   "POINTS 5 double\n"
                                   "0 0 0  1 0 0  1 1 0  0 1 0  2 0.5 0\n"
                                   "VERTICES 1 2\n"
                                   "1 4\n"
                                   "LINES 1 3\n"
                                   "2 0 4\n"
                                   "POLYGONS 2 9\n"
                                   "4 0 1 2 3\n"
                                   "3 1 4 2\n"
                                   "POINT_DATA 5\n"
                                   "SCALARS pressure float 1\n"
                                   "LOOKUP_TABLE default\n"
                                   "0.5 1.5 2.5 3.5 4.5\n"
                                   "NORMALS n double\n"
                                   "0 0 1 0 0 1 0 0 1 0 0 1 0 0 1\n"
                                   "LOOKUP_TABLE mytable 2\n"
                                   "0 0 0 1  1 1 1 1\n"
                                   "CELL_DATA 4\n"
                                   "SCALARS part int\n"
                                   "100 101 102 103\n"
                                   "VECTORS v float\n"
                                   "0 0 0 1 1 1 2 2 2 3 3 3\n";

/* The written files carry VTK's wedge order, read back from the text
 * itself (not by our reader): the base (0,1,2) of a valid prism has its
 * normal pointing away from the top (3,4,5), as vtkWedge and ParaView's
 * cell volumes expect, and the pyramid, tet and hex keep varmesh's order. */
static double vtk_wedge_side(const double (*x)[3], const long *c) {
  double a[3], b[3], n[3], t[3] = {0, 0, 0};
  for (int k = 0; k < 3; k++) {
    a[k] = x[c[1]][k] - x[c[0]][k];
    b[k] = x[c[2]][k] - x[c[0]][k];
    for (int i = 3; i < 6; i++) t[k] += x[c[i]][k] / 3;
    t[k] -= x[c[0]][k];
  }
  n[0] = a[1] * b[2] - a[2] * b[1];
  n[1] = a[2] * b[0] - a[0] * b[2];
  n[2] = a[0] * b[1] - a[1] * b[0];
  return n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
}

static void test_written_wedge_order(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m) || vm_mesh_set_vertices(m, 6) || vm_mesh_set_elements(m, 1, 6)) {
    CHECK(0, "wedge mesh");
    vm_mesh_destroy(&m);
    return;
  }
  memcpy(m->xyz, ref_prism, sizeof ref_prism);
  m->etype[0] = VM_PRISM;
  m->eoff[1] = 6;
  for (int i = 0; i < 6; i++) m->conn[i] = i;
  CHECK(signed_measure(m, 0) > 0, "varmesh's prism is valid");
  const char *names[2] = {"wedge.vtk", "wedge.vtu"};
  for (int f = 0; f < 2; f++) {
    char path[128];
    path_of(path, sizeof path, names[f]);
    CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) >= 0, "%s: write", names[f]);
    size_t len;
    char *t = slurp(path, &len);
    long c[6] = {-1, -1, -1, -1, -1, -1};
    const char *at = t ? (f ? strstr(t, "Name=\"connectivity\"") : strstr(t, "CELLS 1 7")) : NULL;
    if (at) at = f ? strchr(at, '>') : strchr(at, '\n');
    int ok = 0;
    if (at && !f) {
      ok = sscanf(at + 1, "6 %ld %ld %ld %ld %ld %ld", c, c + 1, c + 2, c + 3, c + 4, c + 5) == 6;
    } else if (at) { /* base64 of a UInt64 byte count and six Int64 */
      static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
      unsigned char raw[64];
      int nb = 0, bits = 0;
      unsigned acc = 0;
      for (const char *q = at + 1; *q && *q != '<' && nb < 64; q++) {
        const char *d = strchr(b64, *q);
        if (!d || !*q) continue;
        acc = (acc << 6) | (unsigned)(d - b64);
        if ((bits += 6) >= 8) raw[nb++] = (unsigned char)(acc >> (bits -= 8));
      }
      if (nb >= 56) {
        for (int i = 0; i < 6; i++) {
          uint64_t u = 0;
          for (int k = 7; k >= 0; k--) u = (u << 8) | raw[8 + 8 * i + k];
          c[i] = (long)u;
        }
        ok = 1;
      }
    }
    CHECK(ok, "%s: connectivity in the text", names[f]);
    if (ok)
      CHECK(vtk_wedge_side(ref_prism, c) < 0, "%s: base normal points away from the top", names[f]);
    vm_mesh *r = NULL;
    CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &r) >= 0 && r && signed_measure(r, 0) > 0 &&
              !memcmp(r->conn, m->conn, 6 * sizeof *m->conn),
          "%s: read back in varmesh's order", names[f]);
    vm_mesh_destroy(&r);
    free(t);
  }
  vm_mesh_destroy(&m);
}

static void test_polydata(vm_ctx *ctx) {
  clear_warns();
  vm_mesh *m = read_str(ctx, "poly.vtk", polydata_vtk);
  if (!m) return;
  CHECK(m->ne == 2 && m->etype[0] == VM_QUAD && m->etype[1] == VM_TRI, "polygons");
  CHECK(m->dim == 2, "flat polydata is 2D");
  CHECK(nwarn == 1 && strstr(warns, "skipped 2") && strstr(warns, "poly.vtk"), "skip warning: %s",
        warns);
  vm_field *p = vm_mesh_find_field(m, "pressure", VM_FIELD_VERTEX);
  vm_field *n = vm_mesh_find_field(m, "n", VM_FIELD_VERTEX);
  vm_field *part = vm_mesh_find_field(m, "part", VM_FIELD_ELEMENT);
  vm_field *v = vm_mesh_find_field(m, "v", VM_FIELD_ELEMENT);
  CHECK(p && p->type == VM_FIELD_F64 && ((double *)p->data)[4] == 4.5, "SCALARS");
  CHECK(n && n->ncomp == 3 && ((double *)n->data)[14] == 1, "NORMALS");
  /* rows of the skipped vertex and line cells are dropped */
  CHECK(part && part->type == VM_FIELD_I32 && ((int32_t *)part->data)[0] == 102 &&
            ((int32_t *)part->data)[1] == 103,
        "cell data rows");
  CHECK(v && v->ncomp == 3 && ((double *)v->data)[0] == 2 && ((double *)v->data)[5] == 3,
        "cell vectors rows");
  vm_mesh_destroy(&m);
}

static const char offsets_vtk[] = "# vtk DataFile Version 5.1\n"
                                  "vtk output\n"
                                  "ASCII\n"
                                  "DATASET UNSTRUCTURED_GRID\n"
                                  "POINTS 5 float\n"
                                  "0 0 0 1 0 0 0 1 0\n"
                                  "0 0 1 1 1 1\n"
                                  "METADATA\n"
                                  "INFORMATION 0\n"
                                  "\n"
                                  "CELLS 4 9\n"
                                  "OFFSETS vtktypeint64\n"
                                  "0 4 5 9\n"
                                  "CONNECTIVITY vtktypeint64\n"
                                  "0 1 2 3\n"
                                  "4\n"
                                  "1 2 3 4\n"
                                  "CELL_TYPES 3\n"
                                  "10\n1\n10\n"
                                  "CELL_DATA 3\n"
                                  "FIELD FieldData 2\n"
                                  "quality 1 3 double\n"
                                  "0.25 0.5 0.75\n"
                                  "METADATA\n"
                                  "COMPONENT_NAMES\n"
                                  "q\n"
                                  "\n"
                                  "ids 2 3 vtktypeint64\n"
                                  "1 2 3 4 5 -6\n"
                                  "POINT_DATA 5\n"
                                  "FIELD FieldData 3\n"
                                  "vm_flag 1 5 unsigned_char\n"
                                  "1 0 2 0 0\n"
                                  "vm_surface 1 5 int\n"
                                  "-1 -1 3 -1 -1\n"
                                  "fixed 1 5 int\n"
                                  "0 0 0 0 1\n";

static void test_offsets_and_fields(vm_ctx *ctx) {
  clear_warns();
  vm_mesh *m = read_str(ctx, "layout51.vtk", offsets_vtk);
  if (!m) return;
  CHECK(m->ne == 2 && m->etype[0] == VM_TET && m->conn[4] == 1 && m->conn[7] == 4,
        "5.1 layout cells");
  CHECK(nwarn == 1 && strstr(warns, "skipped 1"), "skip warning: %s", warns);
  vm_field *q = vm_mesh_find_field(m, "quality", VM_FIELD_ELEMENT);
  vm_field *ids = vm_mesh_find_field(m, "ids", VM_FIELD_ELEMENT);
  CHECK(q && ((double *)q->data)[0] == 0.25 && ((double *)q->data)[1] == 0.75, "FIELD f64");
  CHECK(ids && ids->type == VM_FIELD_I32 && ids->ncomp == 2 && ((int32_t *)ids->data)[3] == -6 &&
            ((int32_t *)ids->data)[0] == 1,
        "FIELD int64 -> i32");
  CHECK(m->vflag[0] == VM_VERTEX_FIXED && m->vflag[1] == VM_VERTEX_FREE &&
            m->vflag[2] == VM_VERTEX_SLIP && m->vflag[4] == VM_VERTEX_FIXED,
        "vm_flag and fixed");
  CHECK(m->vsurf[2] == 3 && m->vsurf[0] == -1, "vm_surface");
  CHECK(!vm_mesh_find_field(m, "vm_flag", VM_FIELD_VERTEX) &&
            !vm_mesh_find_field(m, "vm_surface", VM_FIELD_VERTEX),
        "flag arrays consumed");
  CHECK(vm_mesh_find_field(m, "fixed", VM_FIELD_VERTEX) != NULL, "fixed stays a field");
  vm_mesh_destroy(&m);
}

/* Tolerance: CRLF line ends, data on keyword lines, blank lines, a 2.0 header. */
static const char sloppy_vtk[] = "# vtk DataFile Version 2.0\r\n"
                                 "\r\n"
                                 "ascii\r\n"
                                 "DATASET UNSTRUCTURED_GRID\r\n"
                                 "POINTS 3 double 0 0 0 1 0 0\r\n"
                                 "0 1 0\r\n"
                                 "\r\n"
                                 "CELLS 1 4 3 0 1 2\r\n"
                                 "CELL_TYPES 1 5\r\n";

static const char empty_cells_vtu[] =
    "<VTKFile type=\"UnstructuredGrid\">\n"
    "<UnstructuredGrid><Piece NumberOfPoints=\"1\" NumberOfCells=\"0\">\n"
    "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">1 2 3"
    "</DataArray></Points>\n"
    "<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\"/>\n"
    "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\"></DataArray>\n"
    "<DataArray type=\"UInt8\" Name=\"types\" format=\"binary\">AAAAAA==</DataArray></Cells>\n"
    "</Piece></UnstructuredGrid></VTKFile>";

static void test_tolerance(vm_ctx *ctx) {
  vm_mesh *m = read_str(ctx, "sloppy.vtk", sloppy_vtk);
  CHECK(m && m->ne == 1 && m->etype[0] == VM_TRI && m->dim == 2, "sloppy legacy file");
  vm_mesh_destroy(&m);
  m = read_str(ctx, "empty_cells.vtu", empty_cells_vtu);
  CHECK(m && m->nv == 1 && m->ne == 0 && m->xyz[2] == 3 && m->dim == 3, "VTU without cells");
  vm_mesh_destroy(&m);
}

/* A binary file as VTK 9 writes it: 5.1 layout, float points, int64 ids,
 * dataset FIELD, SCALARS with LOOKUP_TABLE, COLOR_SCALARS. */
static size_t meta_lo, meta_hi;

static void build_binary_vtk(bytes *s, int classic) {
  putf(s, "# vtk DataFile Version %s\nbinary\nBINARY\nDATASET UNSTRUCTURED_GRID\n",
       classic ? "3.0" : "5.1");
  putf(s, "FIELD FieldData 1\nTIME 1 1 double\n");
  put_f64(s, 2.5, 1);
  putf(s, "\nPOINTS 6 float\n");
  for (int i = 0; i < 6; i++) {
    put_f32(s, (float)ref_prism[i][0] + 0.1f, 1);
    put_f32(s, (float)ref_prism[i][1], 1);
    put_f32(s, (float)ref_prism[i][2] * 10, 1);
  }
  if (classic) {
    putf(s, "\nCELLS 2 9\n");
    /* VTK's wedge: base (0,2,1) of the points, its normal away from the top */
    const int32_t c[9] = {6, 0, 2, 1, 3, 5, 4, 1, 5};
    for (int i = 0; i < 9; i++) put_int(s, (uint32_t)c[i], 4, 1);
  } else {
    putf(s, "\nCELLS 3 7\nOFFSETS vtktypeint64\n");
    const int64_t o[3] = {0, 6, 7}, c[7] = {0, 2, 1, 3, 5, 4, 5};
    for (int i = 0; i < 3; i++) put_int(s, (uint64_t)o[i], 8, 1);
    putf(s, "\nCONNECTIVITY vtktypeint64\n");
    for (int i = 0; i < 7; i++) put_int(s, (uint64_t)c[i], 8, 1);
  }
  putf(s, "\nCELL_TYPES 2\n");
  put_int(s, 13, 4, 1);
  put_int(s, 1, 4, 1);
  putf(s, "\nCELL_DATA 2\nSCALARS level short 1\nLOOKUP_TABLE default\n");
  put_int(s, (uint16_t)-7, 2, 1);
  put_int(s, 9, 2, 1);
  putf(s, "\nPOINT_DATA 6\nCOLOR_SCALARS rgb 3\n");
  for (int i = 0; i < 18; i++) put_int(s, (uint64_t)(i * 15), 1, 1);
  putf(s, "\n");
  meta_lo = s->n;
  putf(s, "METADATA\nCOMPONENT_NAMES\nr\ng\nb\n\n");
  meta_hi = s->n;
  putf(s, "VECTORS disp double\n");
  for (int i = 0; i < 18; i++) put_f64(s, i / 3.0, 1);
  putf(s, "\n");
}

static void test_binary_handmade(vm_ctx *ctx) {
  for (int classic = 0; classic < 2; classic++) {
    bytes s = {0};
    build_binary_vtk(&s, classic);
    const char *name = classic ? "hand_classic_b.vtk" : "hand51_b.vtk";
    vm_mesh *m = read_ok(ctx, name, s.b, s.n);
    if (m) {
      CHECK(m->ne == 1 && m->etype[0] == VM_PRISM && signed_measure(m, 0) > 0, "%s: prism", name);
      CHECK(m->xyz[0] == 0.1f && m->xyz[3 * 5 + 2] == 10.0f, "%s: float points", name);
      vm_field *l = vm_mesh_find_field(m, "level", VM_FIELD_ELEMENT);
      CHECK(l && l->type == VM_FIELD_I32 && ((int32_t *)l->data)[0] == -7, "%s: short", name);
      vm_field *c = vm_mesh_find_field(m, "rgb", VM_FIELD_VERTEX);
      CHECK(c && c->ncomp == 3 && ((double *)c->data)[17] == 1.0, "%s: color scalars", name);
      vm_field *d = vm_mesh_find_field(m, "disp", VM_FIELD_VERTEX);
      CHECK(d && ((double *)d->data)[17] == 17 / 3.0, "%s: doubles", name);
      vm_mesh_destroy(&m);
    }
    /* the last byte is the newline after the data */
    truncations_in(ctx, name, s.b, s.n, 2, meta_lo, meta_hi);
    alloc_failures(ctx, name, s.b, s.n);
    free(s.b);
  }
}

/* Hand-written VTU files. */

static const char vtu_ascii[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<!-- written by hand -->\n"
    "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" extra='yes'>\n"
    "  <UnstructuredGrid>\n"
    "    <FieldData>\n"
    "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">3"
    "</DataArray>\n"
    "    </FieldData>\n"
    "    <Piece NumberOfPoints=\"5\" NumberOfCells=\"3\">\n"
    "      <PointData Scalars=\"t\">\n"
    "        <DataArray type=\"Float32\" Name=\"t\" format=\"ascii\" RangeMin=\"0\">"
    " 0 0.5 1 1.5 2 </DataArray>\n"
    "        <DataArray type=\"String\" Name=\"names\" format=\"ascii\">97 0</DataArray>\n"
    "        <DataArray type=\"Float64\" Name=\"n\" NumberOfComponents=\"2\" format=\"binary\">\n"
    "          <InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\">\n"
    "            <Value index=\"0\">1</Value><Value index=\"1\">2</Value>\n"
    "          </InformationKey>\n"
    "          "
    "UAAAAAAAAAAAAAAAAAAAAAAA8D8AAAAAAAAAQAAAAAAAAAhAAAAAAAAAEEAAAAAAAAAUQAAAAAAAABhAAAAAAAAAHEAA"
    "AAAAAAAgQAAAAAAAACJA\n"
    "        </DataArray>\n"
    "      </PointData>\n"
    "      <CellData>\n"
    "        <DataArray type=\"Int64\" Name=\"a&amp;b\" NumberOfComponents=\"2\" format=\"ascii\">"
    "1 2 3 4 5 6</DataArray>\n"
    "      </CellData>\n"
    "      <Points>\n"
    "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n"
    "          0 0 0 1 0 0 0 1 0 0 0 1 -1 -1 -1\n"
    "        </DataArray>\n"
    "      </Points>\n"
    "      <Cells>\n"
    "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3 0 4"
    "</DataArray>\n"
    "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4 5 6</DataArray>\n"
    "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 1 3</DataArray>\n"
    "      </Cells>\n"
    "    </Piece>\n"
    "  </UnstructuredGrid>\n"
    "</VTKFile>\n";

static void test_vtu_ascii(vm_ctx *ctx) {
  clear_warns();
  vm_mesh *m = read_str(ctx, "hand.vtu", vtu_ascii);
  if (!m) return;
  CHECK(m->nv == 5 && m->ne == 1 && m->etype[0] == VM_TET && m->xyz[14] == -1, "ascii VTU");
  CHECK(nwarn == 2 && strstr(warns, "skipped 2") && strstr(warns, "'names'"), "warnings: %s",
        warns);
  vm_field *t = vm_mesh_find_field(m, "t", VM_FIELD_VERTEX);
  vm_field *nf = vm_mesh_find_field(m, "n", VM_FIELD_VERTEX);
  CHECK(nf && nf->ncomp == 2 && ((double *)nf->data)[9] == 9.0,
        "inline data after <InformationKey>");
  vm_field *ab = vm_mesh_find_field(m, "a&b", VM_FIELD_ELEMENT);
  CHECK(t && ((double *)t->data)[3] == 1.5, "Float32 field");
  CHECK(ab && ab->type == VM_FIELD_I32 && ab->ncomp == 2 && ((int32_t *)ab->data)[1] == 2,
        "entity-decoded name, cell rows");
  vm_mesh_destroy(&m);
}

/* A tet + pyramid mesh written as VTU by the test's own encoder, with a
 * choice of header type, byte order, and inline or appended data. */
typedef struct {
  int h8, big, appended, raw;
} vtu_style;

static void block(bytes *out, const vtu_style *st, const bytes *data) {
  bytes blk = {0};
  put_int(&blk, data->n, st->h8 ? 8 : 4, st->big);
  put(&blk, data->b, data->n);
  if (st->raw)
    put(out, blk.b, blk.n);
  else
    b64(out, blk.b, blk.n);
  free(blk.b);
}

static void build_vtu(bytes *s, const vtu_style *st) {
  bytes arr[6] = {{0}};
  const double pts[9][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},         {1, 1, 0},
                            {2, 0, 0}, {2, 1, 0}, {3, 3, 3}, {-0.5, 0.25, 1e-3}};
  for (int i = 0; i < 9; i++)
    for (int d = 0; d < 3; d++) put_f64(&arr[0], pts[i][d], st->big);
  const int32_t conn[9] = {0, 1, 2, 3, 1, 5, 6, 4, 8};
  for (int i = 0; i < 9; i++) put_int(&arr[1], (uint32_t)conn[i], 4, st->big);
  put_int(&arr[2], 4, 8, st->big);
  put_int(&arr[2], 9, 8, st->big);
  put_int(&arr[3], 10, 1, st->big);
  put_int(&arr[3], 14, 1, st->big);
  for (int i = 0; i < 9; i++) put_int(&arr[4], (uint16_t)(i * 1000), 2, st->big);
  put_f32(&arr[5], 0.5f, st->big);
  put_f32(&arr[5], -2.0f, st->big);
  const char *decl[6] = {
      "type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"",
      "type=\"Int32\" Name=\"connectivity\"",
      "type=\"Int64\" Name=\"offsets\"",
      "type=\"UInt8\" Name=\"types\"",
      "type=\"UInt16\" Name=\"u16\"",
      "type=\"Float32\" Name=\"f32\"",
  };
  const char *parent[6] = {"Points", "Cells", "Cells", "Cells", "PointData", "CellData"};
  putf(s,
       "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"%s\" "
       "byte_order=\"%s\"%s>\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"9\" "
       "NumberOfCells=\"2\">\n",
       st->h8 ? "1.0" : "0.1", st->big ? "BigEndian" : "LittleEndian",
       st->h8 ? " header_type=\"UInt64\"" : "");
  bytes app = {0};
  const char *order[4] = {"PointData", "CellData", "Points", "Cells"};
  for (int o = 0; o < 4; o++) {
    putf(s, "<%s>\n", order[o]);
    for (int i = 0; i < 6; i++) {
      if (strcmp(parent[i], order[o])) continue;
      if (st->appended) {
        putf(s, "<DataArray %s format=\"appended\" offset=\"%zu\"/>\n", decl[i], app.n);
        block(&app, st, &arr[i]);
      } else {
        putf(s, "<DataArray %s format=\"binary\">\n  ", decl[i]);
        block(s, st, &arr[i]);
        putf(s, "\n</DataArray>\n");
      }
    }
    putf(s, "</%s>\n", order[o]);
  }
  putf(s, "</Piece>\n</UnstructuredGrid>\n");
  if (st->appended) {
    putf(s, "<AppendedData encoding=\"%s\">\n   _", st->raw ? "raw" : "base64");
    put(s, app.b, app.n);
    putf(s, "\n</AppendedData>\n");
  }
  putf(s, "</VTKFile>\n");
  for (int i = 0; i < 6; i++) free(arr[i].b);
  free(app.b);
}

static void test_vtu_binary(vm_ctx *ctx) {
  const vtu_style styles[] = {{0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0},
                              {0, 0, 1, 1}, {1, 1, 1, 1}, {0, 0, 1, 0}};
  const char *names[] = {"u32.vtu",     "u64.vtu",           "big.vtu",
                         "app_raw.vtu", "app_raw_big64.vtu", "app_b64.vtu"};
  for (size_t k = 0; k < sizeof styles / sizeof styles[0]; k++) {
    bytes s = {0};
    build_vtu(&s, &styles[k]);
    vm_mesh *m = read_ok(ctx, names[k], s.b, s.n);
    if (m) {
      CHECK(m->nv == 9 && m->ne == 2 && m->etype[0] == VM_TET && m->etype[1] == VM_PYRAMID,
            "%s: cells", names[k]);
      CHECK(m->xyz[3 * 8] == -0.5 && m->xyz[3 * 8 + 2] == 1e-3, "%s: points", names[k]);
      CHECK(m->ne == 2 && signed_measure(m, 0) > 0 && signed_measure(m, 1) > 0, "%s: orientation",
            names[k]);
      vm_field *u = vm_mesh_find_field(m, "u16", VM_FIELD_VERTEX);
      vm_field *f = vm_mesh_find_field(m, "f32", VM_FIELD_ELEMENT);
      CHECK(u && u->type == VM_FIELD_I32 && ((int32_t *)u->data)[8] == 8000, "%s: UInt16",
            names[k]);
      CHECK(f && f->type == VM_FIELD_F64 && ((double *)f->data)[1] == -2.0, "%s: Float32",
            names[k]);
      vm_mesh_destroy(&m);
    }
    truncations(ctx, names[k], s.b, s.n, 0);
    if (k == 0 || k == 3 || k == 5) alloc_failures(ctx, names[k], s.b, s.n);
    free(s.b);
  }
}

static char *join(const char *const *pieces) {
  size_t n = 0;
  for (int i = 0; pieces[i]; i++) n += strlen(pieces[i]);
  char *s = malloc(n + 1);
  s[0] = 0;
  for (int i = 0; pieces[i]; i++) strcat(s, pieces[i]);
  return s;
}

static void test_vtu_zlib(vm_ctx *ctx) {
  char *vec[4] = {join(zv_dynamic), join(zv_blocks), join(zv_stored), join(zv_fixed_appended)};
  const char *names[4] = {"zdyn.vtu", "zblocks.vtu", "zstored.vtu", "zfixed_app.vtu"};
  for (int k = 0; k < 4; k++) {
    vm_mesh *m = read_str(ctx, names[k], vec[k]);
    if (!m) continue;
    int ok = m->nv == ZV_NP && m->ne == 1 && m->etype[0] == VM_TET;
    for (int64_t i = 0; ok && i < m->nv; i++)
      ok = m->xyz[3 * i] == (double)i && m->xyz[3 * i + 1] == i / 2.0 &&
           m->xyz[3 * i + 2] == i / 4.0;
    CHECK(ok, "%s: points", names[k]);
    vm_field *r = vm_mesh_find_field(m, "ramp", VM_FIELD_VERTEX);
    vm_field *id = vm_mesh_find_field(m, "id", VM_FIELD_ELEMENT);
    CHECK(r && ((double *)r->data)[ZV_NP - 1] == (ZV_NP - 1) / 8.0, "%s: ramp", names[k]);
    CHECK(id && ((int32_t *)id->data)[0] == 42, "%s: id", names[k]);
    vm_mesh_destroy(&m);
  }
  /* one changed character inside compressed data must be caught (Adler-32 or code) */
  for (int k = 0; k < 3; k++) {
    char *bad = vec[k];
    char *p = strstr(bad, "Name=\"ramp\" format=\"binary\">");
    CHECK(p != NULL, "ramp array in vector %d", k);
    if (!p) continue;
    p = strchr(p, '>') + 1;
    p += (strchr(p, '<') - p) / 2;
    char keep = *p;
    *p = *p == 'A' ? 'B' : 'A';
    expect_fail(ctx, "zbad.vtu", bad, strlen(bad), "zlib", VM_ERR_FORMAT);
    *p = keep;
  }
  truncations(ctx, "zfixed_app.vtu", vec[3], strlen(vec[3]), 0);
  alloc_failures(ctx, "zblocks.vtu", vec[1], strlen(vec[1]));
  expect_fail_str(ctx, "lz4.vtu",
                  "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkLZ4DataCompressor\">",
                  "compressed VTU not supported", VM_ERR_FORMAT);
  for (int k = 0; k < 4; k++) free(vec[k]);
}

/* Bad input. */

static const char tiny_vtk[] = "# vtk DataFile Version 3.0\n"
                               "t\n"
                               "ASCII\n"
                               "DATASET UNSTRUCTURED_GRID\n"
                               "POINTS 4 double\n"
                               "0 0 0 1 0 0 0 1 0 0 0 1\n"
                               "CELLS 1 5\n"
                               "4 0 1 2 3\n"
                               "CELL_TYPES 1\n"
                               "10\n"
                               "POINT_DATA 4\n"
                               "SCALARS s double 1\n"
                               "LOOKUP_TABLE default\n"
                               "1 2 3 4\n";

static void test_bad_vtk(vm_ctx *ctx) {
  const int F = VM_ERR_FORMAT;
  expect_fail(ctx, "empty.vtk", "", 0, "header", F);
  vm_mesh *m = read_str(ctx, "tiny.vtk", tiny_vtk);
  vm_mesh_destroy(&m);
  truncations(ctx, "tiny.vtk", tiny_vtk, strlen(tiny_vtk), 1);
  alloc_failures(ctx, "tiny.vtk", tiny_vtk, strlen(tiny_vtk));
  const char *hdr = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  char buf[2048];
#define BAD(name, body, needle)                                                                    \
  snprintf(buf, sizeof buf, "%s%s", hdr, body);                                                    \
  expect_fail_str(ctx, name, buf, needle, F)
  BAD("lie_points.vtk", "POINTS 1000000000000 double\n0 0 0\n", "POINTS");
  BAD("lie_points2.vtk", "POINTS 9223372036854775807 double\n0 0 0\n", "POINTS");
  BAD("lie_cells.vtk", "POINTS 1 double\n0 0 0\nCELLS 1 1000000000000\n1 0\n", "CELLS");
  BAD("lie_cells2.vtk", "POINTS 1 double\n0 0 0\nCELLS 1000000000000 1000000000000\n1 0\n",
      "CELLS");
  BAD("lie_types.vtk", "POINTS 1 double\n0 0 0\nCELLS 1 2\n1 0\nCELL_TYPES 1000000000000\n1\n",
      "CELL_TYPES");
  BAD("lie_field.vtk",
      "POINTS 1 double\n0 0 0\nPOINT_DATA 1\nFIELD f 1\na 1000000000 1 double\n1\n", "a");
  BAD("lie_offsets.vtk",
      "POINTS 1 double\n0 0 0\nCELLS 1000000000000 4\nOFFSETS vtktypeint64\n0 1\n", "OFFSETS");
  BAD("nan.vtk", "POINTS 2 double\n0 0 0 1 nan 0\n", "point 1 is not finite");
  BAD("inf.vtk", "POINTS 2 double\n0 0 0 1 0 -inf\n", "point 1 is not finite");
  BAD("range.vtk", "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 3\nCELL_TYPES 1\n5\n",
      "point index 3 out of range");
  BAD("neg.vtk", "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 -1 2\nCELL_TYPES 1\n5\n",
      "out of range");
  BAD("count.vtk",
      "POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n10\n",
      "cell 0: VTK tetra needs 4 points, has 3");
  BAD("unknown.vtk",
      "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 2 8\n3 0 1 2\n3 0 1 2\nCELL_TYPES 2\n5\n99\n",
      "cell 1: VTK cell type 99");
  BAD("polygon.vtk", "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n7\n",
      "cell 0: VTK cell type 7 (polygon");
  BAD("quadratic.vtk", "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n22\n",
      "cell type 22");
  BAD("overrun.vtk", "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n7 0 1 2\nCELL_TYPES 1\n5\n",
      "overruns");
  BAD("mismatch.vtk", "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 2\n5 5\n",
      "CELL_TYPES has 2 cells but CELLS has 1");
  BAD("pdcount.vtk", "POINTS 1 double\n0 0 0\nPOINT_DATA 2\n", "POINT_DATA 2");
  BAD("big_int.vtk",
      "POINTS 1 double\n0 0 0\nPOINT_DATA 1\nFIELD f 1\nid 1 1 vtktypeint64\n4294967296\n",
      "out of range");
  BAD("keyword.vtk", "POINTS 1 double\n0 0 0\nFOO 3\n", "unknown keyword 'FOO'");
  BAD("nocells.vtk", "POINTS 1 double\n0 0 0\nCELL_TYPES 1\n5\n", "CELL_TYPES without CELLS");
  BAD("dtype.vtk", "POINTS 1 bit\n0 0 0\n", "bit");
  BAD("dtype_cells.vtk",
      "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n"
      "POINT_DATA 3\nSCALARS fixed bit 1\nLOOKUP_TABLE default\n0 1 2\n",
      "out of range");
  BAD("badnum.vtk", "POINTS 1 double\n0 0 x\n", "not a number");
  BAD("badflag.vtk", "POINTS 1 double\n0 0 0\nPOINT_DATA 1\nSCALARS vm_flag int\n7\n",
      "vm_flag: point 0 has flag 7");
  BAD("offs.vtk",
      "POINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 2 3\nOFFSETS vtktypeint64\n0 4\n"
      "CONNECTIVITY vtktypeint64\n0 1 2\nCELL_TYPES 1\n5\n",
      "last offset 4");
#undef BAD
  expect_fail_str(ctx, "version.vtk",
                  "# vtk DataFile Version 6.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n",
                  "version 6.0", F);
  expect_fail_str(ctx, "dataset.vtk",
                  "# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n",
                  "STRUCTURED_POINTS", F);
  /* binary: lies, NaN and garbage with byte offsets */
  const char *bh = "# vtk DataFile Version 3.0\nt\nBINARY\nDATASET UNSTRUCTURED_GRID\n";
  bytes s = {0};
  putf(&s, "%sPOINTS 2 double\n", bh);
  put_f64(&s, 0, 1);
  put_f64(&s, 0, 1);
  put_f64(&s, 0, 1);
  put_f64(&s, 1, 1);
  put_f64(&s, NAN, 1);
  put_f64(&s, 0, 1);
  expect_fail(ctx, "nan_b.vtk", s.b, s.n, "point 1 is not finite", F);
  expect_fail(ctx, "nan_b.vtk", s.b, s.n, "POINTS data at byte", F);
  s.n = 0;
  putf(&s, "%sPOINTS 1000000000000 float\n", bh);
  put_f32(&s, 0, 1);
  expect_fail(ctx, "lie_b.vtk", s.b, s.n, "POINTS", F);
  s.n = 0;
  putf(&s, "%sPOINTS 1 float\n", bh);
  for (int i = 0; i < 3; i++) put_f32(&s, 0, 1);
  putf(&s, "\nCELLS 1 4\n");
  put_int(&s, 3, 4, 1);
  put_int(&s, 0, 4, 1);
  put_int(&s, 0, 4, 1);
  put_int(&s, 5, 4, 1);
  putf(&s, "\nCELL_TYPES 1\n");
  put_int(&s, 5, 4, 1);
  putf(&s, "\n");
  expect_fail(ctx, "range_b.vtk", s.b, s.n, "point index 5 out of range", F);
  s.n = 0;
  putf(&s, "%sPOINTS 1 float\n", bh);
  for (int i = 0; i < 3; i++) put_f32(&s, 0, 1);
  putf(&s, "\nCELLS 1 2\n");
  put_int(&s, 0x7fffffff, 4, 1);
  put_int(&s, 0, 4, 1);
  expect_fail(ctx, "overrun_b.vtk", s.b, s.n, "CELLS data at byte", F);
  free(s.b);
  /* garbage: deterministic pseudo-random bytes, with and without a header */
  uint8_t g[600];
  uint32_t x = 12345;
  for (size_t i = 0; i < sizeof g; i++) {
    x = x * 1103515245u + 12345u;
    g[i] = (uint8_t)(x >> 16);
  }
  expect_fail(ctx, "garbage.vtk", g, sizeof g, NULL, F);
  bytes gs = {0};
  putf(&gs, "%sPOINTS 10 double\n", bh);
  put(&gs, g, 100);
  putf(&gs, "\nCELLS 3 12\n");
  put(&gs, g + 100, 300);
  expect_fail(ctx, "garbage_b.vtk", gs.b, gs.n, NULL, 0);
  free(gs.b);
}

static void test_bad_vtu(vm_ctx *ctx) {
  const int F = VM_ERR_FORMAT;
  expect_fail(ctx, "empty.vtu", "", 0, "VTKFile", F);
  truncations(ctx, "hand.vtu", vtu_ascii, strlen(vtu_ascii), 0);
  alloc_failures(ctx, "hand.vtu", vtu_ascii, strlen(vtu_ascii));
  char buf[4096];
  const char *head =
      "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
      "<UnstructuredGrid>";
#define VTU(name, piece, points, cells, needle)                                                    \
  snprintf(buf, sizeof buf,                                                                        \
           "%s<Piece %s><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" "             \
           "format=\"ascii\">%s</DataArray></Points><Cells>%s</Cells></Piece>"                     \
           "</UnstructuredGrid></VTKFile>",                                                        \
           head, piece, points, cells);                                                            \
  expect_fail_str(ctx, name, buf, needle, F)
  const char *tet =
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>";
  const char *p4 = "0 0 0 1 0 0 0 1 0 0 0 1";
  VTU("lie_np.vtu", "NumberOfPoints=\"1000000000000\" NumberOfCells=\"1\"", p4, tet, "too many");
  VTU("lie_np2.vtu", "NumberOfPoints=\"100000000\" NumberOfCells=\"1\"", p4, tet, "cannot fit");
  VTU("nan.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", "0 0 0 1 0 0 0 1 0 0 0 nan", tet,
      "point 3 is not finite");
  VTU("range.vtu", "NumberOfPoints=\"3\" NumberOfCells=\"1\"", "0 0 0 1 0 0 0 1 0", tet,
      "point index 3 out of range");
  VTU("nodes.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">3</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>",
      "needs 4 points, has 3");
  VTU("unknown.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">42</DataArray>",
      "cell 0: VTK cell type 42");
  VTU("missing.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4, "", "Cells needs");
  VTU("b64.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">EAAAAA*AAAA</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>",
      "bad base64");
  VTU("b64pad.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">B=AAAAQAAAA=</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>",
      "base64");
  VTU("b64end.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">BAAAAAAAA</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>",
      "ends inside a group");
  VTU("lie_hdr.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">AAAAAP8AAAAAAAAA"
      "</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>",
      "connectivity");
  VTU("short.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">CAAAAAAAAAABAAAA"
      "</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>",
      "expected 4 values");
  VTU("extra.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"1\"", "0 0 0 1 0 0 0 1 0 0 0 1 5", tet,
      "more than the 12 values");
  VTU("noattr.vtu", "NumberOfPoints=\"4\"", p4, tet, "NumberOfCells");
  VTU("decrease.vtu", "NumberOfPoints=\"4\" NumberOfCells=\"2\"", p4,
      "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4 2</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 10</DataArray>",
      "offsets decrease");
#undef VTU
  expect_fail_str(ctx, "poly.vtu", "<VTKFile type=\"PolyData\"><PolyData/></VTKFile>", "PolyData",
                  F);
  expect_fail_str(ctx, "nest.vtu", "<VTKFile type=\"UnstructuredGrid\"><A></B></VTKFile>",
                  "</B> closes <A>", F);
  expect_fail_str(ctx, "comment.vtu", "<VTKFile type=\"UnstructuredGrid\"><!-- x", "comment", F);
  expect_fail_str(ctx, "attr.vtu", "<VTKFile type=\"UnstructuredGrid\" a=b>", "quoted", F);
  expect_fail_str(ctx, "nopiece.vtu",
                  "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid/></VTKFile>", "Piece", F);
  expect_fail_str(ctx, "hdrtype.vtu",
                  "<VTKFile type=\"UnstructuredGrid\" header_type=\"UInt16\"></VTKFile>",
                  "header_type", F);
  /* appended: offsets and sizes that lie */
  snprintf(buf, sizeof buf,
           "%s<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points><DataArray "
           "type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"%s\"/>"
           "</Points></Piece></UnstructuredGrid><AppendedData encoding=\"raw\">_%s"
           "</AppendedData></VTKFile>",
           head, "0", "\xff\xff\xff\x7f");
  expect_fail_str(ctx, "lie_app.vtu", buf, "truncated", F);
  snprintf(buf, sizeof buf,
           "%s<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points><DataArray "
           "type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"%s\"/>"
           "</Points></Piece></UnstructuredGrid><AppendedData encoding=\"raw\">_%s"
           "</AppendedData></VTKFile>",
           head, "99999999999", "xxxx");
  expect_fail_str(ctx, "lie_off.vtu", buf, "offset", F);
  snprintf(buf, sizeof buf,
           "%s<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points><DataArray "
           "type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>"
           "</Points></Piece></UnstructuredGrid><AppendedData encoding=\"base64\">_%s"
           "</AppendedData></VTKFile>",
           head, "/////w==");
  expect_fail_str(ctx, "lie_app64.vtu", buf, "base64", F);
  /* a NaN in base64 points */
  {
    uint8_t raw[4 + 24];
    uint32_t nb = 24;
    memcpy(raw, &nb, 4);
    const double xyz[3] = {0, NAN, 0};
    memcpy(raw + 4, xyz, 24);
    bytes enc = {0};
    b64(&enc, raw, sizeof raw);
    put(&enc, "", 1);
    snprintf(buf, sizeof buf,
             "%s<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points><DataArray "
             "type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">%s</DataArray>"
             "</Points></Piece></UnstructuredGrid></VTKFile>",
             head, (const char *)enc.b);
    free(enc.b);
    expect_fail_str(ctx, "nan_b.vtu", buf, "point 0 is not finite", F);
  }
  /* compressed header with an absurd block count or size */
  snprintf(buf, sizeof buf,
           "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkZLibDataCompressor\">"
           "<UnstructuredGrid><Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points>"
           "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">%s"
           "</DataArray></Points></Piece></UnstructuredGrid></VTKFile>",
           "/////wAAAQAAAAAA");
  expect_fail_str(ctx, "lie_z.vtu", buf, "Points", F);
  snprintf(buf, sizeof buf,
           "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkZLibDataCompressor\">"
           "<UnstructuredGrid><Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points>"
           "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">%s"
           "</DataArray></Points></Piece></UnstructuredGrid></VTKFile>",
           "AQAAAP///3////9/CAAAAHicAwAAAAAB");
  expect_fail_str(ctx, "lie_bomb_z.vtu", buf, "claims more data", F);
  /* garbage */
  uint8_t g[700];
  uint32_t x = 777;
  for (size_t i = 0; i < sizeof g; i++) {
    x = x * 1103515245u + 12345u;
    g[i] = (uint8_t)(x >> 16);
  }
  expect_fail(ctx, "garbage.vtu", g, sizeof g, NULL, F);
  bytes s = {0};
  putf(&s, "%s<Piece NumberOfPoints=\"3\" NumberOfCells=\"1\"><Points><DataArray ", head);
  put(&s, g, 300);
  expect_fail(ctx, "garbage2.vtu", s.b, s.n, NULL, F);
  free(s.b);
}

/* Mutated copies of valid files (deterministic): each read either succeeds
 * or fails cleanly naming the file, and never leaks (or, under the
 * sanitizers, touches memory it should not). For longer runs by hand:
 * VM_VTK_FUZZ_ROUNDS=100000 VM_VTK_FUZZ_SEED=7 test_vtk. */
static void mutations(vm_ctx *ctx, const char *name, const void *buf, size_t len, int rounds) {
  static const char alphabet[] = "0123456789-.e =_<>/\"\n\0\xff\x7f"
                                 "AZnafi";
  uint8_t *b = malloc(len);
  const char *seed = getenv("VM_VTK_FUZZ_SEED");
  uint32_t x = 2463534242u ^ (uint32_t)(seed ? atol(seed) : 0);
  int bad = 0;
  for (int r = 0; r < rounds; r++) {
    memcpy(b, buf, len);
    int k = 1 + r % 4;
    for (int j = 0; j < k; j++) {
      x ^= x << 13;
      x ^= x >> 17;
      x ^= x << 5;
      size_t at = x % len;
      b[at] =
          (x >> 20) & 1 ? (uint8_t)(x >> 24) : (uint8_t)alphabet[(x >> 24) % (sizeof alphabet - 1)];
    }
    long live = vm_ctx_alloc_live(ctx);
    vm_mesh *m = NULL;
    int st = read_mem(ctx, name, b, len, &m);
    int ok = st >= 0 || (!m && strstr(vm_ctx_error(ctx), name));
    vm_mesh_destroy(&m);
    ok &= vm_ctx_alloc_live(ctx) == live;
    if (!ok) {
      bad++;
      fprintf(stderr, "%s: mutation %d: status %d, %ld leaked: %s\n", name, r, st,
              vm_ctx_alloc_live(ctx) - live, vm_ctx_error(ctx));
    }
  }
  free(b);
  CHECK(bad == 0, "%s: %d mutations misbehaved", name, bad);
}

static void test_mutations(vm_ctx *ctx, int rounds) {
  vm_ctx_set_log(ctx, NULL, NULL);
  mutations(ctx, "mut.vtk", tiny_vtk, strlen(tiny_vtk), rounds);
  mutations(ctx, "mut_poly.vtk", polydata_vtk, strlen(polydata_vtk), rounds);
  mutations(ctx, "mut51.vtk", offsets_vtk, strlen(offsets_vtk), rounds);
  for (int classic = 0; classic < 2; classic++) {
    bytes s = {0};
    build_binary_vtk(&s, classic);
    mutations(ctx, "mut_b.vtk", s.b, s.n, rounds);
    free(s.b);
  }
  mutations(ctx, "mut.vtu", vtu_ascii, strlen(vtu_ascii), rounds);
  const vtu_style styles[] = {{0, 0, 0, 0}, {1, 1, 1, 1}, {0, 0, 1, 0}};
  for (int k = 0; k < 3; k++) {
    bytes s = {0};
    build_vtu(&s, &styles[k]);
    mutations(ctx, "mut_b.vtu", s.b, s.n, rounds);
    free(s.b);
  }
  char *z[3] = {join(zv_dynamic), join(zv_stored), join(zv_fixed_appended)};
  for (int k = 0; k < 3; k++) {
    mutations(ctx, "mut_z.vtu", z[k], strlen(z[k]), rounds);
    free(z[k]);
  }
  vm_ctx_set_log(ctx, on_log, NULL);
}

int main(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/vm_vtk_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  vm_ctx *ctx;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_log(ctx, on_log, NULL);
  long live0 = vm_ctx_alloc_live(ctx);
  test_roundtrips(ctx);
  test_dim_and_lossy(ctx);
  test_reference_cells(ctx);
  test_written_wedge_order(ctx);
  test_polydata(ctx);
  test_offsets_and_fields(ctx);
  test_binary_handmade(ctx);
  test_vtu_ascii(ctx);
  test_tolerance(ctx);
  test_vtu_binary(ctx);
  test_vtu_zlib(ctx);
  test_bad_vtk(ctx);
  test_bad_vtu(ctx);
  const char *fuzz = getenv("VM_VTK_FUZZ_ROUNDS");
  test_mutations(ctx, fuzz ? atoi(fuzz) : 300);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leaked %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  vm_ctx_destroy(&ctx);
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  return vmtest_end("test_vtk");
}
