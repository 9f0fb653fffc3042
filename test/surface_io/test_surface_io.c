/* test/surface_io/test_surface_io.c: STL/OBJ/OFF/PLY reading of the plane
 * model (closed, oriented, positive volume), round trips of generated
 * meshes, lossy and refused writes, bad input and allocation failures. */
#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "vmtest.h"

/* ---- log capture ---- */

typedef struct {
  int nwarn;
  char last[1024];
  char all[8192];
} logbuf;

static void log_fn(void *user, int level, const char *msg) {
  logbuf *L = user;
  if (level != VM_LOG_WARN) return;
  L->nwarn++;
  snprintf(L->last, sizeof L->last, "%s", msg);
  size_t l = strlen(L->all);
  snprintf(L->all + l, sizeof L->all - l, "%s\n", msg);
}

static void log_reset(logbuf *L) { memset(L, 0, sizeof *L); }

/* ---- generated meshes ---- */

static int64_t midpoint(vm_mesh *m, int32_t a, int32_t b, int32_t *cache, int64_t *keys,
                        int64_t *ncache) {
  int64_t key = a < b ? (int64_t)a << 32 | b : (int64_t)b << 32 | a;
  for (int64_t i = 0; i < *ncache; i++)
    if (keys[i] == key) return cache[i];
  const double *p = m->xyz + 3 * a, *q = m->xyz + 3 * b;
  double x = 0.5 * (p[0] + q[0]), y = 0.5 * (p[1] + q[1]), z = 0.5 * (p[2] + q[2]);
  double l = sqrt(x * x + y * y + z * z);
  int64_t v;
  vm_mesh_add_vertex(m, x / l, y / l, z / l, &v);
  keys[*ncache] = key;
  cache[(*ncache)++] = (int32_t)v;
  return v;
}

/* Unit icosphere subdivided `level` times, then scaled and shifted so the
 * coordinates are not short decimals. */
static vm_mesh *icosphere(vm_ctx *ctx, int level) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  const double t = (1 + sqrt(5.0)) / 2;
  const double P[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  static const int32_t F[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  double l = sqrt(1 + t * t);
  for (int i = 0; i < 12; i++) vm_mesh_add_vertex(m, P[i][0] / l, P[i][1] / l, P[i][2] / l, NULL);
  for (int f = 0; f < 20; f++) vm_mesh_add_element(m, VM_TRI, F[f]);
  for (int s = 0; s < level; s++) {
    int64_t ne = m->ne;
    int32_t *old = malloc(sizeof(int32_t) * 3 * (size_t)ne);
    memcpy(old, m->conn, sizeof(int32_t) * 3 * (size_t)ne);
    int32_t *cache = malloc(sizeof(int32_t) * 3 * (size_t)ne);
    int64_t *keys = malloc(sizeof(int64_t) * 3 * (size_t)ne), nc = 0;
    m->ne = 0;
    for (int64_t e = 0; e < ne; e++) {
      int32_t a = old[3 * e], b = old[3 * e + 1], c = old[3 * e + 2];
      int32_t ab = (int32_t)midpoint(m, a, b, cache, keys, &nc);
      int32_t bc = (int32_t)midpoint(m, b, c, cache, keys, &nc);
      int32_t ca = (int32_t)midpoint(m, c, a, cache, keys, &nc);
      int32_t T[4][3] = {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}};
      for (int k = 0; k < 4; k++) vm_mesh_add_element(m, VM_TRI, T[k]);
    }
    free(old);
    free(cache);
    free(keys);
  }
  for (int64_t v = 0; v < m->nv; v++) {
    m->xyz[3 * v] = 1.7 * m->xyz[3 * v] + 0.3;
    m->xyz[3 * v + 1] = 1.7 * m->xyz[3 * v + 1] - 0.2;
    m->xyz[3 * v + 2] = 1.7 * m->xyz[3 * v + 2] + 0.1;
  }
  return m;
}

/* Append a unit cube of 6 outward quads at offset (ox, 0, 0). */
static void add_cube(vm_mesh *m, double ox) {
  int64_t base = m->nv;
  for (int i = 0; i < 8; i++) {
    double x = (i == 1 || i == 2 || i == 5 || i == 6), y = (i == 2 || i == 3 || i == 6 || i == 7);
    vm_mesh_add_vertex(m, ox + x / 3.0, y / 7.0, (i >= 4) * 0.1, NULL);
  }
  int faces[6][4], nfv[6];
  vm_elem_faces(VM_HEX, faces, nfv);
  for (int f = 0; f < 6; f++) {
    int32_t q[4];
    for (int i = 0; i < 4; i++) q[i] = (int32_t)(base + faces[f][i]);
    vm_mesh_add_element(m, VM_QUAD, q);
  }
}

/* ---- mesh checks ---- */

static double enclosed_volume(const vm_mesh *m) {
  double vol = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    int k = vm_elem_nverts(m->etype[e]);
    for (int j = 1; j + 1 < k; j++) {
      const double *a = m->xyz + 3 * c[0], *b = m->xyz + 3 * c[j], *d = m->xyz + 3 * c[j + 1];
      vol += (a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
              a[2] * (b[0] * d[1] - b[1] * d[0])) /
             6.0;
    }
  }
  return vol;
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Closed: every undirected edge used by exactly two faces; oriented: every
 * directed edge used once. */
static void check_closed_oriented(const vm_mesh *m, const char *what) {
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) n += vm_elem_nverts(m->etype[e]);
  uint64_t *dir = malloc(sizeof *dir * (size_t)n), *und = malloc(sizeof *und * (size_t)n);
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    int nv = vm_elem_nverts(m->etype[e]);
    for (int i = 0; i < nv; i++) {
      uint64_t a = (uint32_t)c[i], b = (uint32_t)c[(i + 1) % nv];
      dir[k] = a << 32 | b;
      und[k++] = a < b ? a << 32 | b : b << 32 | a;
    }
  }
  qsort(dir, (size_t)n, sizeof *dir, cmp_u64);
  qsort(und, (size_t)n, sizeof *und, cmp_u64);
  int64_t dup_dir = 0, bad_und = 0;
  for (int64_t i = 1; i < n; i++) dup_dir += dir[i] == dir[i - 1];
  for (int64_t i = 0; i < n;) {
    int64_t j = i;
    while (j < n && und[j] == und[i]) j++;
    bad_und += j - i != 2;
    i = j;
  }
  CHECK(bad_und == 0, "%s: %lld edges not used by exactly two faces", what, (long long)bad_und);
  CHECK(dup_dir == 0, "%s: %lld directed edges used twice (inconsistent orientation)", what,
        (long long)dup_dir);
  free(dir);
  free(und);
}

static int same_mesh_exact(const vm_mesh *a, const vm_mesh *b) {
  if (a->nv != b->nv || a->ne != b->ne) return 0;
  if (memcmp(a->xyz, b->xyz, sizeof(double) * 3 * (size_t)a->nv)) return 0;
  if (memcmp(a->etype, b->etype, (size_t)a->ne)) return 0;
  if (memcmp(a->eoff, b->eoff, sizeof(int64_t) * (size_t)(a->ne + 1))) return 0;
  return !memcmp(a->conn, b->conn, sizeof(int32_t) * (size_t)a->eoff[a->ne]);
}

typedef struct {
  int32_t v[3];
} tri3;

static int cmp_tri(const void *a, const void *b) { return memcmp(a, b, sizeof(tri3)); }

/* Triangles of m (quads split 0-1-2, 0-2-3) through vertex map `map`,
 * rotated so the smallest index comes first (orientation kept), sorted. */
static tri3 *canonical_tris(const vm_mesh *m, const int32_t *map, int64_t *n) {
  tri3 *t = malloc(sizeof *t * (size_t)(2 * m->ne + 1));
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    int32_t s[2][3] = {{c[0], c[1], c[2]}, {c[0], c[2], m->etype[e] == VM_QUAD ? c[3] : 0}};
    for (int j = 0; j < (m->etype[e] == VM_QUAD ? 2 : 1); j++) {
      int32_t a = map ? map[s[j][0]] : s[j][0], b = map ? map[s[j][1]] : s[j][1],
              d = map ? map[s[j][2]] : s[j][2];
      if (b < a && b < d)
        t[k] = (tri3){{b, d, a}};
      else if (d < a && d < b)
        t[k] = (tri3){{d, a, b}};
      else
        t[k] = (tri3){{a, b, d}};
      k++;
    }
  }
  qsort(t, (size_t)k, sizeof *t, cmp_tri);
  *n = k;
  return t;
}

/* Same triangles (as oriented sets) up to vertex renumbering; the vertices
 * of `got` must equal those of `ref` rounded by round_fn (float for binary
 * STL, identity otherwise). */
static void check_same_tris(const vm_mesh *ref, const vm_mesh *got, int to_float,
                            const char *what) {
  CHECK(got->nv == ref->nv, "%s: %lld vertices, expected %lld", what, (long long)got->nv,
        (long long)ref->nv);
  if (got->nv != ref->nv) return;
  int32_t *map = malloc(sizeof *map * (size_t)ref->nv);
  int64_t unmatched = 0;
  for (int64_t v = 0; v < ref->nv; v++) {
    /* Round through a volatile float: GCC 12.2 at -O3 vectorizes the plain
     * `to_float ? (double)(float)x : x` in this loop and drops the rounding
     * of two of the three lanes (seen with Debian's gcc 12.2.0-14). */
    double p[3];
    for (int d = 0; d < 3; d++) {
      p[d] = ref->xyz[3 * v + d];
      if (to_float) {
        volatile float r = (float)p[d];
        p[d] = r;
      }
    }
    map[v] = -1;
    for (int64_t w = 0; w < got->nv; w++)
      if (!memcmp(p, got->xyz + 3 * w, sizeof p)) {
        map[v] = (int32_t)w;
        break;
      }
    unmatched += map[v] < 0;
  }
  CHECK(unmatched == 0, "%s: %lld vertices without an exact match", what, (long long)unmatched);
  if (!unmatched) {
    int64_t na, nb;
    tri3 *a = canonical_tris(ref, map, &na), *b = canonical_tris(got, NULL, &nb);
    CHECK(na == nb && !memcmp(a, b, sizeof *a * (size_t)na), "%s: triangle sets differ", what);
    free(a);
    free(b);
  }
  free(map);
}

/* ---- files ---- */

static char tmpdir[1024];

static const char *tmp_path(const char *file) {
  static char buf[8][1400];
  static int k;
  char *p = buf[k++ % 8];
  snprintf(p, sizeof buf[0], "%s/%s", tmpdir, file);
  return p;
}

static uint8_t *slurp(const char *path, size_t *len) {
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

/* ---- tests ---- */

static void test_plane(vm_ctx *ctx, logbuf *L) {
  const char *root = getenv("VM_SOURCE_ROOT");
  char path[4200];
  snprintf(path, sizeof path, "%s/../shared/data/plane.stl", root ? root : ".");
  vm_mesh *m;
  log_reset(L);
  int st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &m);
  CHECK(st == VM_OK, "read %s: %s", path, vm_ctx_error(ctx));
  if (st) return;
  CHECK(L->nwarn == 0, "plane.stl: unexpected warnings: %s", L->all);
  CHECK(m->nv == 8730, "plane: %lld vertices", (long long)m->nv);
  CHECK(m->ne == 17456, "plane: %lld triangles", (long long)m->ne);
  CHECK(m->dim == 3, "plane: dim %d", m->dim);
  int64_t bad = 0, nontri = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    nontri += m->etype[e] != VM_TRI;
    for (int i = 0; i < 3; i++) bad += m->conn[3 * e + i] < 0 || m->conn[3 * e + i] >= m->nv;
  }
  CHECK(nontri == 0 && bad == 0, "plane: %lld non-triangles, %lld bad indices", (long long)nontri,
        (long long)bad);
  check_closed_oriented(m, "plane");
  double vol = enclosed_volume(m);
  CHECK(vol > 0, "plane: enclosed volume %g", vol);
  fprintf(stderr, "plane.stl: %lld vertices, %lld triangles, volume %.6g\n", (long long)m->nv,
          (long long)m->ne, vol);

  /* the plane through every writer: float coordinates survive exactly */
  static const struct {
    const char *file;
    int binary;
  } out[] = {{"plane_a.stl", 0}, {"plane_b.stl", 1}, {"plane.obj", 0},
             {"plane.off", 0},   {"plane_a.ply", 0}, {"plane_b.ply", 1}};
  for (size_t i = 0; i < sizeof out / sizeof out[0]; i++) {
    vm_write_opts o = vm_write_opts_default();
    o.binary = out[i].binary;
    const char *p = tmp_path(out[i].file);
    st = vm_mesh_write(ctx, m, p, VM_FMT_AUTO, &o);
    CHECK(st == VM_OK, "write %s: %d %s", p, st, vm_ctx_error(ctx));
    vm_mesh *r;
    st = vm_mesh_read(ctx, p, VM_FMT_AUTO, &r);
    CHECK(st == VM_OK, "read %s: %s", p, vm_ctx_error(ctx));
    if (st) continue;
    CHECK(same_mesh_exact(m, r), "%s: plane round trip not exact", out[i].file);
    vm_mesh_destroy(&r);
    remove(p);
  }
  vm_mesh_destroy(&m);
}

static void test_round_trips(vm_ctx *ctx, logbuf *L) {
  vm_mesh *ico = icosphere(ctx, 2);
  CHECK(ico->nv == 162 && ico->ne == 320, "icosphere %lld %lld", (long long)ico->nv,
        (long long)ico->ne);
  CHECK(enclosed_volume(ico) > 0, "icosphere oriented outward");
  check_closed_oriented(ico, "icosphere");

  /* STL renumbers (vertices by first use) */
  for (int binary = 0; binary < 2; binary++) {
    vm_write_opts o = vm_write_opts_default();
    o.binary = binary;
    const char *p = tmp_path(binary ? "ico_b.stl" : "ico_a.stl");
    log_reset(L);
    int st = vm_mesh_write(ctx, ico, p, VM_FMT_STL, &o);
    CHECK(st == VM_OK && L->nwarn == 0, "write %s: %d %s", p, st, L->all);
    vm_mesh *r;
    st = vm_mesh_read(ctx, p, VM_FMT_AUTO, &r);
    CHECK(st == VM_OK, "read %s: %s", p, vm_ctx_error(ctx));
    if (st) continue;
    /* ASCII keeps every double bit; binary is float32, rounded to nearest */
    check_same_tris(ico, r, binary, binary ? "binary STL" : "ASCII STL");
    check_closed_oriented(r, p);
    vm_mesh_destroy(&r);
  }

  /* OBJ/OFF/PLY keep numbering, element types and every double bit; a mesh
   * of triangles and quads with awkward values */
  vm_mesh *mix;
  vm_mesh_clone(ico, &mix);
  add_cube(mix, 5.0);
  int64_t v0;
  vm_mesh_add_vertex(mix, -0.0, 5e-324, 1e300, &v0);
  vm_mesh_add_vertex(mix, 0.1, -1e-300, 123456789.123456789, NULL);
  vm_mesh_add_vertex(mix, 2.2250738585072014e-308, 1.0 / 3.0, -7.0e22, NULL);
  int32_t tri[3] = {(int32_t)v0, (int32_t)v0 + 1, (int32_t)v0 + 2};
  vm_mesh_add_element(mix, VM_TRI, tri);
  static const struct {
    const char *file;
    int binary;
  } out[] = {{"mix.obj", 0}, {"mix.off", 0}, {"mix_a.ply", 0}, {"mix_b.ply", 1}};
  for (size_t i = 0; i < sizeof out / sizeof out[0]; i++) {
    vm_write_opts o = vm_write_opts_default();
    o.binary = out[i].binary;
    const char *p = tmp_path(out[i].file);
    log_reset(L);
    int st = vm_mesh_write(ctx, mix, p, VM_FMT_AUTO, &o);
    CHECK(st == VM_OK && L->nwarn == 0, "write %s: %d %s", p, st, L->all);
    vm_mesh *r;
    log_reset(L);
    st = vm_mesh_read(ctx, p, VM_FMT_AUTO, &r);
    CHECK(st == VM_OK, "read %s: %s", p, vm_ctx_error(ctx));
    if (st) continue;
    CHECK(L->nwarn == 0, "%s: warnings: %s", p, L->all);
    CHECK(same_mesh_exact(mix, r), "%s: round trip not bit-exact", out[i].file);
    vm_mesh_destroy(&r);
  }

  /* STL of the mixed mesh: quads become two triangles each, lossy */
  vm_mesh *mix2;
  vm_mesh_clone(ico, &mix2);
  add_cube(mix2, 5.0);
  log_reset(L);
  int st = vm_mesh_write(ctx, mix2, tmp_path("mix.stl"), VM_FMT_AUTO, NULL);
  CHECK(st == VM_WARN_LOSSY && L->nwarn == 1 && strstr(L->last, "quads"), "quads to STL: %d %s", st,
        L->all);
  vm_mesh *r;
  st = vm_mesh_read(ctx, tmp_path("mix.stl"), VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r->ne == 320 + 12, "mix.stl: %d %s", st, vm_ctx_error(ctx));
  if (!st) check_same_tris(mix2, r, 0, "mixed mesh through STL");
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&mix2);
  vm_mesh_destroy(&mix);
  vm_mesh_destroy(&ico);
}

static void test_lossy_and_refused(vm_ctx *ctx, logbuf *L) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  add_cube(m, 0.0);
  vm_field *f;
  vm_mesh_add_field(m, "curvature", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  m->vflag[3] = VM_VERTEX_FIXED;
  vm_mesh_set_attr(m, "origin", "test");
  const char *fmts[] = {"lossy.stl", "lossy.obj", "lossy.off", "lossy.ply"};
  for (int i = 0; i < 4; i++) {
    log_reset(L);
    int st = vm_mesh_write(ctx, m, tmp_path(fmts[i]), VM_FMT_AUTO, NULL);
    int expect = i == 0 ? 4 : 3; /* STL also splits the quads */
    CHECK(st == VM_WARN_LOSSY && L->nwarn == expect, "%s: status %d, %d warnings: %s", fmts[i], st,
          L->nwarn, L->all);
    CHECK(strstr(L->all, "curvature") && strstr(L->all, "flags") && strstr(L->all, "origin"),
          "%s: warnings name the losses: %s", fmts[i], L->all);
  }
  vm_mesh_destroy(&m);

  /* volume elements: alone refused (target untouched), mixed dropped */
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, i == 1, i == 2, i == 3, NULL);
  int32_t tet[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_TET, tet);
  const char *keep = tmp_path("keep.obj");
  FILE *fp = fopen(keep, "w");
  fputs("v 0 0 0\n", fp);
  fclose(fp);
  const char *all4[] = {"keep.obj", "vol.stl", "vol.off", "vol.ply"};
  for (int i = 0; i < 4; i++) {
    const char *p = tmp_path(all4[i]);
    int st = vm_mesh_write(ctx, m, p, VM_FMT_AUTO, NULL);
    CHECK(st == VM_ERR_UNSUPPORTED && strstr(vm_ctx_error(ctx), p), "tet-only to %s: %d %s",
          all4[i], st, vm_ctx_error(ctx));
    if (i) CHECK(access(p, F_OK) != 0, "%s must not exist", p);
  }
  size_t len;
  uint8_t *b = slurp(keep, &len);
  CHECK(b && len == 8 && !memcmp(b, "v 0 0 0\n", 8), "failed write left keep.obj unchanged");
  free(b);
  int32_t tri[3] = {0, 2, 1};
  vm_mesh_add_element(m, VM_TRI, tri);
  log_reset(L);
  int st = vm_mesh_write(ctx, m, keep, VM_FMT_AUTO, NULL);
  CHECK(st == VM_WARN_LOSSY && L->nwarn == 1 && strstr(L->last, "volume"), "tet+tri: %d %s", st,
        L->all);
  vm_mesh *r;
  st = vm_mesh_read(ctx, keep, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r->nv == 4 && r->ne == 1 && r->etype[0] == VM_TRI &&
            !memcmp(r->conn, tri, sizeof tri),
        "tet+tri read back: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&r);
  st = vm_mesh_write(ctx, m, "/nonexistent-dir/x.obj", VM_FMT_AUTO, NULL);
  CHECK(st == VM_ERR_IO, "unwritable path: %d", st);
  vm_mesh_destroy(&m);
}

/* Feed `text` (len bytes) to the reader for `name`; expect failure whose
 * message names the file and contains `needle`; nothing may leak. */
static void bad(vm_ctx *ctx, const char *name, const void *text, size_t len, const char *needle) {
  long live = vm_ctx_alloc_live(ctx);
  vm_mesh *m = (vm_mesh *)1;
  int st = vm_mesh_read_memory(ctx, name, text, len, VM_FMT_AUTO, &m);
  const char *e = vm_ctx_error(ctx);
  CHECK(st < 0 && m == NULL, "%s: expected failure, got %d", name, st);
  CHECK(strncmp(e, name, strlen(name)) == 0 && strchr(e, '\n') == NULL,
        "%s: message should start with the name: '%s'", name, e);
  CHECK(!needle || strstr(e, needle), "%s: message '%s' should mention '%s'", name, e, needle);
  CHECK(vm_ctx_alloc_live(ctx) == live, "%s: %ld blocks leaked", name,
        vm_ctx_alloc_live(ctx) - live);
  if (getenv("VM_TEST_VERBOSE")) fprintf(stderr, "  %s\n", e);
}

#define BAD(ctx, name, str, needle) bad(ctx, name, str, sizeof str - 1, needle)

static vm_mesh *good(vm_ctx *ctx, const char *name, const void *text, size_t len) {
  vm_mesh *m;
  int st = vm_mesh_read_memory(ctx, name, text, len, VM_FMT_AUTO, &m);
  CHECK(st == VM_OK, "%s: %s", name, vm_ctx_error(ctx));
  return st ? NULL : m;
}

#define GOOD(ctx, name, str) good(ctx, name, str, sizeof str - 1)

static void test_bad_stl(vm_ctx *ctx) {
  BAD(ctx, "empty.stl", "", "empty");
  BAD(ctx, "short.stl", "hello", "too short");
  BAD(ctx, "nofacet.stl", "solid x\n vertex 0 0 0\nendsolid x\n", "expected 'facet'");
  BAD(ctx, "missing_vertex.stl",
      "solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n endloop\n"
      "endfacet\nendsolid x\n",
      "line 6: facet 0: expected 'vertex', found 'endloop'");
  BAD(ctx, "four.stl",
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "vertex 1 1 0\nendloop\nendfacet\nendsolid\n",
      "more than 3 vertices");
  BAD(ctx, "nan.stl",
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 nan 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid\n",
      "line 5: facet 0: vertex 1: coordinate is not finite");
  BAD(ctx, "inf.stl",
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 1e999\n"
      "endloop\nendfacet\nendsolid\n",
      "not finite");
  BAD(ctx, "noend.stl",
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\n",
      "end of file");
  BAD(ctx, "word.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 zero 0\n",
      "'zero'");
  BAD(ctx, "trailing.stl", "solid x\nendsolid x\ngarbage\n", "after 'endsolid'");

  /* NaN normals are common in the wild and ignored; several solids */
  vm_mesh *m = GOOD(ctx, "nan_normal.stl",
                    "solid a\nfacet normal nan -nan nan\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                    "vertex 0 1 0\nendloop\nendfacet\nendsolid a\nsolid b\nfacet normal 0 0 1\n"
                    "outer loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\n"
                    "endsolid b\n");
  if (m)
    CHECK(m->nv == 4 && m->ne == 2, "two solids merged: %lld %lld", (long long)m->nv,
          (long long)m->ne);
  vm_mesh_destroy(&m);

  m = GOOD(ctx, "oneline.stl",
           "solid x facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop "
           "endfacet endsolid x");
  if (m) CHECK(m->nv == 3 && m->ne == 1, "single-line STL");
  vm_mesh_destroy(&m);

  /* binary: build 2 triangles by hand */
  uint8_t b[84 + 100];
  memset(b, 0, sizeof b);
  memcpy(b, "solid but binary", 16); /* must not fool the detection */
  b[80] = 2;
  float co[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}};
  for (int t = 0; t < 2; t++) memcpy(b + 84 + 50 * t + 12, co[t], sizeof co[t]);
  m = good(ctx, "solid_binary.stl", b, sizeof b);
  if (m)
    CHECK(m->nv == 4 && m->ne == 2 && m->xyz[3 * 1] == 1.0 && m->xyz[3 * 2 + 1] == 1.0,
          "binary with 'solid' header");
  vm_mesh_destroy(&m);
  bad(ctx, "truncated.stl", b, sizeof b - 7,
      "the header says 2 triangles (184 bytes) but the file has 177");
  uint8_t big[84 + 100 + 3];
  memcpy(big, b, sizeof b);
  memset(big + sizeof b, 0, 3);
  bad(ctx, "oversized.stl", big, sizeof big, "has 187 bytes");
  memcpy(b, "binary header  ", 15);
  bad(ctx, "truncated2.stl", b, 100, "binary STL");
  float nanv = NAN;
  memcpy(b + 84 + 50 + 12 + 4 * 7, &nanv, 4);
  bad(ctx, "nan_binary.stl", b, sizeof b, "triangle 1: vertex 2: coordinate is not finite");
}

/* A non-convex hexagon (L shape) on a tilted plane, listed in either
 * direction: ear clipping gives 4 triangles with its area and orientation. */
static void check_hexagon(vm_ctx *ctx, logbuf *L, int reversed) {
  const double Lxy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  char text[2048];
  size_t n = 0;
  for (int i = 0; i < 6; i++) {
    double x = Lxy[i][0], y = Lxy[i][1];
    /* rotated about the x axis by 0.7 rad: normal (0, -sin 0.7, cos 0.7) */
    n += (size_t)snprintf(text + n, sizeof text - n, "v %.17g %.17g %.17g\n", x, y * cos(0.7),
                          y * sin(0.7));
  }
  n += (size_t)snprintf(text + n, sizeof text - n, "%s",
                        reversed ? "f 6 5 4 3 2 1\n" : "f 1 2 3 4 5 6\n");
  log_reset(L);
  vm_mesh *m = good(ctx, "hexagon.obj", text, n);
  if (!m) return;
  CHECK(m->ne == 4 && L->nwarn == 1 && strstr(L->last, "split into triangles"),
        "hexagon: %lld triangles, %s", (long long)m->ne, L->all);
  double area = 0, ny = -sin(0.7), nz = cos(0.7), sign = reversed ? -1 : 1;
  int wrong = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + 3 * e;
    const double *a = m->xyz + 3 * c[0], *b = m->xyz + 3 * c[1], *d = m->xyz + 3 * c[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    double cx[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                    u[0] * w[1] - u[1] * w[0]};
    double s = 0.5 * sign * (cx[1] * ny + cx[2] * nz);
    wrong += s <= 0;
    area += s;
  }
  CHECK(wrong == 0, "hexagon (reversed %d): %d triangles flipped or degenerate", reversed, wrong);
  CHECK_NEAR(area, 3.0, 1e-12, "hexagon area");
  vm_mesh_destroy(&m);
}

static void test_obj(vm_ctx *ctx, logbuf *L) {
  BAD(ctx, "empty.obj", "", "empty");
  BAD(ctx, "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n",
      "line 3: vertex 3: coordinate is not finite");
  BAD(ctx, "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# c\nf 1 2 4\n",
      "line 5: vertex index 4 out of range (1..3)");
  BAD(ctx, "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0");
  BAD(ctx, "rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n", "before the first vertex");
  BAD(ctx, "two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: face with 2 vertices");
  BAD(ctx, "word.obj", "v 0 0 0\nv 1 x 0\n", "line 2: expected a coordinate, found 'x'");
  BAD(ctx, "short.obj", "v 0 0\n", "vertex with 2 coordinates");
  BAD(ctx, "ref.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", "bad vertex reference '1/a'");

  /* non-manifold: three faces on edge 1-2; kept, with a warning */
  log_reset(L);
  vm_mesh *m = GOOD(ctx, "nonmanifold.obj",
                    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
  if (m) {
    CHECK(m->ne == 3, "non-manifold faces kept: %lld", (long long)m->ne);
    CHECK(L->nwarn == 1 && strstr(L->last, "nonmanifold.obj") &&
              strstr(L->last, "1 edges are shared by more than two faces (first: vertices 0-1"),
          "non-manifold warning: %s", L->all);
  }
  vm_mesh_destroy(&m);

  /* references with / and negative indices, normals/texcoords/colors dropped */
  log_reset(L);
  m = GOOD(ctx, "forms.obj",
           "# cube corner\nmtllib x.mtl\no thing\nv 0 0 0 1 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
           "vt 0 0\nvn 0 0 1\ng side\nusemtl red\nf 1/1/1 2//1 3/1 4\nf -4 -2 -1 # tail\n"
           "s off\nl 1 2\ncurv 0 1 1 2\n");
  if (m) {
    CHECK(m->nv == 4 && m->ne == 2 && m->etype[0] == VM_QUAD && m->etype[1] == VM_TRI,
          "forms.obj: %lld %lld", (long long)m->nv, (long long)m->ne);
    int32_t q[4] = {0, 1, 2, 3}, t[3] = {0, 2, 3};
    CHECK(!memcmp(m->conn, q, sizeof q) && !memcmp(m->conn + 4, t, sizeof t), "forms.obj conn");
    CHECK(L->nwarn == 6 && strstr(L->all, "vertex normals") && strstr(L->all, "texture") &&
              strstr(L->all, "colors") && strstr(L->all, "'curv'"),
          "forms.obj warnings: %s", L->all);
  }
  vm_mesh_destroy(&m);

  check_hexagon(ctx, L, 0);
  check_hexagon(ctx, L, 1);
}

static void test_off(vm_ctx *ctx, logbuf *L) {
  BAD(ctx, "empty.off", "", "empty");
  BAD(ctx, "lying.off", "OFF\n1000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "cannot hold");
  BAD(ctx, "nan.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 NaN 0\n3 0 1 2\n",
      "line 5: vertex 2: coordinate is not finite");
  BAD(ctx, "range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
      "line 6: face 0: bad vertex index '3'");
  BAD(ctx, "few.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n# padding, padding\n",
      "expected face 1");
  BAD(ctx, "more.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n",
      "after the last face");
  BAD(ctx, "4d.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n", "not supported");
  BAD(ctx, "bin.off", "OFF BINARY\n", "binary OFF");
  BAD(ctx, "notoff.off", "hello\n", "not an OFF file");
  BAD(ctx, "two.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "bad vertex count");
  log_reset(L);
  vm_mesh *m = GOOD(ctx, "colors.off",
                    "COFF # colored\n# comment\n4 2 5\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n"
                    "1 1 0 0 0 255 255\n\n0 1 0 9 9 9 255\n3 0 1 2 1 0 0\n4 0 1 2 3\n");
  if (m) {
    CHECK(m->nv == 4 && m->ne == 2 && m->etype[1] == VM_QUAD, "colors.off");
    CHECK(L->nwarn == 2, "colors.off warnings: %s", L->all);
  }
  vm_mesh_destroy(&m);
  m = GOOD(ctx, "nokeyword.off", "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  vm_mesh_destroy(&m);
}

static void test_ply(vm_ctx *ctx, logbuf *L) {
  BAD(ctx, "empty.ply", "", "empty");
  BAD(ctx, "noply.ply", "plx\n", "not a PLY file");
  BAD(ctx, "noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
      "end_header");
  static const char head[] =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  BAD(ctx, "nan.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n",
      "line 12: vertex 2: coordinate is not finite");
  BAD(ctx, "range.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
      "line 13: vertex index 7 out of range (0..2)");
  BAD(ctx, "short.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1\n",
      "end of file");
  BAD(ctx, "extra.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n5\n",
      "after the last element");
  BAD(ctx, "noz.ply",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 "
      "0\n",
      "no scalar property 'z'");
  (void)head;

  /* binary little-endian, with a lying vertex count and a truncation */
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  add_cube(m, 0.0);
  vm_write_opts o = vm_write_opts_default();
  o.binary = 1;
  const char *p = tmp_path("cube_b.ply");
  int st = vm_mesh_write(ctx, m, p, VM_FMT_AUTO, &o);
  CHECK(st == VM_OK, "write %s", p);
  size_t len;
  uint8_t *b = slurp(p, &len);
  if (b) {
    vm_mesh *r = good(ctx, "cube_b.ply", b, len);
    if (r) CHECK(same_mesh_exact(m, r), "binary ply from memory");
    vm_mesh_destroy(&r);
    bad(ctx, "cut.ply", b, len - 3, "past the end of the file");
    char *q = strstr((char *)b, "element vertex 8");
    if (q) {
      memcpy(q, "element vertex 9", 16);
      bad(ctx, "lying.ply", b, len, NULL);
      memcpy(q, "element vertex 7", 16);
      bad(ctx, "lying2.ply", b, len, NULL);
    }
    free(b);
  }
  vm_mesh_destroy(&m);

  /* big-endian float with extra properties and elements */
  static const char be_head[] =
      "ply\nformat binary_big_endian 1.0\ncomment hand made\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "element face 1\nproperty list uchar uint vertex_indices\nproperty float quality\n"
      "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  uint8_t be[sizeof be_head - 1 + 3 * 13 + 1 + 12 + 4 + 8];
  size_t k = 0;
  memcpy(be, be_head, sizeof be_head - 1);
  k = sizeof be_head - 1;
  const float co[9] = {0.1f, 0, 0, 1, 0, 0, 0, 1, -2.5f};
  for (int v = 0; v < 3; v++) {
    for (int d = 0; d < 3; d++) {
      uint32_t u;
      memcpy(&u, &co[3 * v + d], 4);
      for (int i = 0; i < 4; i++) be[k++] = (uint8_t)(u >> (24 - 8 * i));
    }
    be[k++] = 200;
  }
  be[k++] = 3;
  for (int i = 0; i < 3; i++) {
    uint32_t u = (uint32_t)(2 - i);
    for (int j = 0; j < 4; j++) be[k++] = (uint8_t)(u >> (24 - 8 * j));
  }
  memset(be + k, 0, 12);
  k += 12;
  CHECK(k == sizeof be, "be buffer size %zu vs %zu", k, sizeof be);
  log_reset(L);
  m = good(ctx, "be.ply", be, sizeof be);
  if (m) {
    CHECK(m->nv == 3 && m->ne == 1 && m->xyz[0] == (double)0.1f && m->xyz[8] == -2.5,
          "big-endian values");
    int32_t t[3] = {2, 1, 0};
    CHECK(!memcmp(m->conn, t, sizeof t), "big-endian face");
    CHECK(L->nwarn == 3 && strstr(L->all, "red") && strstr(L->all, "quality") &&
              strstr(L->all, "edge"),
          "be.ply warnings: %s", L->all);
  }
  vm_mesh_destroy(&m);
}

/* Every allocation of a read and a write fails once: clean error, no leak,
 * no stray file. */
static void test_alloc_failures(vm_ctx *ctx) {
  static const char obj[] =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nf 1 2 3 5 4\nf 1 2 3\nvn 0 0 1\n";
  static const char stl[] =
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid\n";
  static const char off[] = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 1 2 3\n";
  static const char ply[] =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const struct {
    const char *name, *text;
    size_t len;
  } in[] = {{"a.obj", obj, sizeof obj - 1},
            {"a.stl", stl, sizeof stl - 1},
            {"a.off", off, sizeof off - 1},
            {"a.ply", ply, sizeof ply - 1}};
  vm_mesh *src = icosphere(ctx, 1);
  add_cube(src, 3.0);
  vm_mesh_add_field(src, "w", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, NULL);
  for (int i = 0; i < 4; i++) {
    int fails = 0;
    for (long n = 1; n < 1000; n++) {
      long live = vm_ctx_alloc_live(ctx);
      vm_mesh *m = NULL;
      vm_ctx_set_alloc_fail(ctx, n);
      int st = vm_mesh_read_memory(ctx, in[i].name, (const uint8_t *)in[i].text, in[i].len,
                                   VM_FMT_AUTO, &m);
      vm_ctx_set_alloc_fail(ctx, 0);
      if (st == VM_OK) {
        vm_mesh_destroy(&m);
        CHECK(vm_ctx_alloc_live(ctx) == live, "%s: leak after success", in[i].name);
        break;
      }
      fails++;
      CHECK(st == VM_ERR_NOMEM && m == NULL, "%s: alloc %ld: status %d (%s)", in[i].name, n, st,
            vm_ctx_error(ctx));
      CHECK(vm_ctx_alloc_live(ctx) == live, "%s: alloc %ld: %ld blocks leaked", in[i].name, n,
            vm_ctx_alloc_live(ctx) - live);
    }
    CHECK(fails > 2, "%s: only %d allocations tried", in[i].name, fails);
    for (int binary = 0; binary < 2; binary++) {
      char file[32];
      snprintf(file, sizeof file, "alloc%d_%s", binary, in[i].name);
      const char *p = tmp_path(file);
      vm_write_opts o = vm_write_opts_default();
      o.binary = binary;
      for (long n = 1; n < 1000; n++) {
        long live = vm_ctx_alloc_live(ctx);
        vm_ctx_set_alloc_fail(ctx, n);
        int st = vm_mesh_write(ctx, src, p, VM_FMT_AUTO, &o);
        vm_ctx_set_alloc_fail(ctx, 0);
        CHECK(vm_ctx_alloc_live(ctx) == live, "write %s: alloc %ld: leak", file, n);
        if (st >= 0) break;
        CHECK(st == VM_ERR_NOMEM && access(p, F_OK) != 0, "write %s: alloc %ld: %d", file, n, st);
      }
      remove(p);
    }
  }
  vm_mesh_destroy(&src);
}

static void cleanup_tmpdir(void) {
  DIR *d = opendir(tmpdir);
  if (!d) return;
  struct dirent *de;
  int stray = 0;
  while ((de = readdir(d))) {
    if (de->d_name[0] == '.') continue;
    if (strstr(de->d_name, ".tmp.")) stray++;
    remove(tmp_path(de->d_name));
  }
  closedir(d);
  CHECK(stray == 0, "%d temporary files left behind", stray);
  rmdir(tmpdir);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  logbuf L;
  vm_ctx_set_log(ctx, log_fn, &L);
  const char *broot = getenv("VM_BUILD_ROOT");
  snprintf(tmpdir, sizeof tmpdir, "%s/surface_io_XXXXXX", broot ? broot : ".");
  if (!mkdtemp(tmpdir)) {
    fprintf(stderr, "cannot create a temporary directory\n");
    return 1;
  }
  test_plane(ctx, &L);
  test_round_trips(ctx, &L);
  test_lossy_and_refused(ctx, &L);
  test_bad_stl(ctx);
  test_obj(ctx, &L);
  test_off(ctx, &L);
  test_ply(ctx, &L);
  test_alloc_failures(ctx);
  cleanup_tmpdir();
  CHECK(vm_ctx_alloc_live(ctx) == 0, "%ld blocks live at the end", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("surface_io");
}
