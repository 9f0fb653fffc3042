/* test/io_vmsh/test_vmsh_bad.c: the .vmsh/.vmsht readers fed empty,
 * truncated, lying, non-finite, inconsistent and garbage input: each must
 * fail with a one-line message naming the file, quickly, without leaks. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "vmsh_testlib.h"
#include "vmtest.h"

static const char *BIN = "bad.vmsh";
static const char *TXT = "bad.vmsht";

/* Read buf; it must fail with a message naming `name` and containing
 * `needle` (if any), return no mesh, leak nothing. Returns the number of
 * allocations the attempt made. */
static long expect_fail(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                        const char *needle, const char *what) {
  long live0 = vm_ctx_alloc_live(ctx), count0 = vm_ctx_alloc_count(ctx);
  vm_ctx_clear_error(ctx);
  vm_mesh *m = NULL;
  int st = vm_mesh_read_memory(ctx, name, buf, len, VM_FMT_VMSH, &m);
  const char *msg = vm_ctx_error(ctx);
  CHECK(st < 0 && m == NULL, "%s: expected failure, got %d", what, st);
  CHECK(strncmp(msg, name, strlen(name)) == 0, "%s: message must start with the file name: '%s'",
        what, msg);
  CHECK(!needle || strstr(msg, needle), "%s: message '%s' lacks '%s'", what, msg, needle);
  CHECK(!strchr(msg, '\n'), "%s: one line", what);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leak", what);
  vm_mesh_destroy(&m);
  return vm_ctx_alloc_count(ctx) - count0;
}

static uint8_t *copy(const uint8_t *b, size_t n) {
  uint8_t *c = malloc(n ? n : 1);
  memcpy(c, b, n);
  return c;
}

static uint64_t xorshift(uint64_t *s) {
  uint64_t x = *s;
  x ^= x << 13;
  x ^= x >> 7;
  x ^= x << 17;
  return *s = x;
}

/* A valid binary file in memory: the mixed mesh, or one with two vertex
 * fields "aa"/"ab" and attributes "k1"/"k2" for the duplicate tests. */
static uint8_t *binary_of(vm_ctx *ctx, vm_mesh *m, const char *dir, size_t *n) {
  char p[300];
  snprintf(p, sizeof p, "%s/base.vmsh", dir);
  CHECK(vm_mesh_write(ctx, m, p, VM_FMT_AUTO, NULL) == VM_OK, "write base: %s", vm_ctx_error(ctx));
  uint8_t *b = vt_slurp(p, n);
  remove(p);
  return b;
}

static void test_binary(vm_ctx *ctx, const char *dir) {
  vm_mesh *m = vt_mixed(ctx);
  size_t n;
  uint8_t *base = binary_of(ctx, m, dir, &n);
  vm_mesh_destroy(&m);
  CHECK(base && n > 200, "base file");
  if (!base || n <= 200) {
    free(base);
    return;
  }
  vm_mesh *ok = NULL;
  CHECK(vm_mesh_read_memory(ctx, BIN, base, n, VM_FMT_VMSH, &ok) == VM_OK, "base reads");
  vm_mesh_destroy(&ok);
  size_t mesh = vt_find_chunk(base, n, "MESH", 0), vert = vt_find_chunk(base, n, "VERT", 0);
  size_t vflg = vt_find_chunk(base, n, "VFLG", 0), elem = vt_find_chunk(base, n, "ELEM", 0);
  size_t fild = vt_find_chunk(base, n, "FILD", 0), attr = vt_find_chunk(base, n, "ATTR", 0);
  CHECK(mesh == 24 && vert && vflg && elem && fild && attr, "chunks found");
  if (!(mesh == 24 && vert && vflg && elem && fild && attr)) {
    free(base);
    return;
  }
  uint8_t *b;

  expect_fail(ctx, BIN, base, 0, "empty", "empty file");
  for (size_t k = 1; k < n; k++) {
    char what[64];
    snprintf(what, sizeof what, "truncated to %zu of %zu bytes", k, n);
    expect_fail(ctx, BIN, base, k, NULL, what);
  }

  b = copy(base, n);
  b[1] = 'X';
  expect_fail(ctx, BIN, b, n, "magic", "wrong magic");
  memcpy(b, "VMSH", 4);
  expect_fail(ctx, BIN, b, n, "magic", "magic without the high byte");
  free(b);

  b = copy(base, n);
  b[8] = 2;
  expect_fail(ctx, BIN, b, n, "newer", "major version 2");
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, 12, "newer", "major version 2, header only");
  expect_fail(ctx, BIN, b, n, "version 2.0 is newer", "major version 2, CRC fixed");
  b[8] = 0;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "version", "major version 0");
  free(b);

  b = copy(base, n);
  b[vert + 20] ^= 0x10;
  expect_fail(ctx, BIN, b, n, "checksum mismatch", "flipped coordinate bit");
  free(b);
  b = copy(base, n);
  b[n - 1] ^= 1;
  expect_fail(ctx, BIN, b, n, "checksum", "flipped CRC bit");
  free(b);

  b = copy(base, n);
  vt_put64(b + 16, n + 8);
  expect_fail(ctx, BIN, b, n, "file size", "file size field too large");
  vt_put64(b + 16, (uint64_t)1 << 62);
  expect_fail(ctx, BIN, b, n, "file size", "file size field huge");
  free(b);
  b = copy(base, n);
  b[12] = 1;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "reserved", "header reserved word");
  free(b);

  /* lying counts: must fail fast, before allocating anything */
  static const struct {
    int off;
    uint64_t v;
    const char *needle;
  } lies[] = {{8, (uint64_t)1 << 40, "vertex count 1099511627776"},
              {8, INT32_MAX, "VERT"},
              {8, 1000000, "VERT"},
              {16, (uint64_t)1 << 40, "element count"},
              {16, 1000000, "connectivity"},
              {24, (uint64_t)1 << 40, "connectivity"},
              {24, UINT64_MAX, "connectivity"}};
  for (size_t i = 0; i < sizeof lies / sizeof lies[0]; i++) {
    b = copy(base, n);
    vt_put64(b + mesh + 16 + lies[i].off, lies[i].v);
    vt_fix_crc(b, n);
    double t0 = vt_now();
    long allocs = expect_fail(ctx, BIN, b, n, lies[i].needle, lies[i].needle);
    double dt = vt_now() - t0;
    CHECK(allocs == 0, "lie %zu: %ld allocations before failing", i, allocs);
    CHECK(dt < 0.5, "lie %zu: took %g s", i, dt);
    CHECK(strstr(vm_ctx_error(ctx), "MESH chunk at offset 24") ||
              strstr(vm_ctx_error(ctx), "VERT chunk at offset"),
          "lie %zu: location in message: %s", i, vm_ctx_error(ctx));
    free(b);
  }
  static const struct {
    const char *tag;
    int off;
    uint64_t v;
    int width;
    const char *needle;
  } chunk_lies[] = {{"VERT", 8, (uint64_t)1 << 40, 8, "exceeds"},
                    {"VERT", 8, UINT64_MAX, 8, "exceeds"},
                    {"ELEM", 8, (uint64_t)1 << 40, 8, "exceeds"},
                    {"FILD", 8, UINT64_MAX - 3, 8, "exceeds"},
                    {"FILD", 16 + 4, 1 << 20, 4, "length"},
                    {"FILD", 16 + 4, 1u << 30, 4, "component count"},
                    {"FILD", 16 + 4, 0, 4, "component count"},
                    {"FILD", 16 + 8, 0xFFFFFFFFu, 4, "name length"},
                    {"FILD", 16 + 8, 0, 4, "name is empty"},
                    {"ATTR", 16, 0xFFFFFFFFu, 4, "length"},
                    {"ATTR", 16 + 4, 0xFFFFFFFFu, 4, "length"},
                    {"ATTR", 16, 0, 4, "key is empty"},
                    {"MESH", 8, 40, 8, "length"}};
  for (size_t i = 0; i < sizeof chunk_lies / sizeof chunk_lies[0]; i++) {
    b = copy(base, n);
    size_t at = vt_find_chunk(b, n, chunk_lies[i].tag, 0);
    if (chunk_lies[i].width == 8)
      vt_put64(b + at + chunk_lies[i].off, chunk_lies[i].v);
    else
      vt_put32(b + at + chunk_lies[i].off, (uint32_t)chunk_lies[i].v);
    vt_fix_crc(b, n);
    char what[64];
    snprintf(what, sizeof what, "chunk lie %zu (%s)", i, chunk_lies[i].tag);
    long allocs = expect_fail(ctx, BIN, b, n, chunk_lies[i].needle, what);
    CHECK(allocs == 0, "%s: %ld allocations", what, allocs);
    CHECK(strstr(vm_ctx_error(ctx), chunk_lies[i].tag), "%s: message names the chunk: %s", what,
          vm_ctx_error(ctx));
    free(b);
  }

  /* values */
  b = copy(base, n);
  b[elem + 16] = 99;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "element 0: type 99", "element type 99");
  b[elem + 16] = VM_TET; /* known type, but now the counts disagree */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "indices", "type change breaks the index count");
  free(b);
  b = copy(base, n);
  b[elem + 16 + 6] = 1; /* padding after 6 type bytes */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "padding", "nonzero type padding");
  free(b);
  size_t conn = elem + 16 + 8;
  b = copy(base, n);
  vt_put32(b + conn + 4 * 9, 13); /* prism's 2nd index = nv */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "element 1: vertex index 13 out of range", "index == nv");
  vt_put32(b + conn + 4 * 9, 0xFFFFFFFFu);
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "vertex index -1", "negative index");
  free(b);

  static const uint64_t nonfinite[3] = {0x7FF8000000000000ull, 0x7FF0000000000000ull,
                                        0xFFF0000000000000ull};
  for (int i = 0; i < 3; i++) {
    b = copy(base, n);
    vt_put64(b + vert + 16 + 8 * (3 * 5 + 1), nonfinite[i]); /* vertex 5, y */
    vt_fix_crc(b, n);
    expect_fail(ctx, BIN, b, n,
                i ? "vertex 5: coordinate y is infinite" : "vertex 5: coordinate y is NaN",
                "non-finite coordinate");
    free(b);
  }
  b = copy(base, n);
  b[vflg + 16 + 4 * 13 + 2] = 7;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "vertex 2: flag 7", "flag 7");
  free(b);

  b = copy(base, n);
  vt_put32(b + fild + 16 + 4, 2); /* curvature: 1 -> 2 components, data too short */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "expected", "field with the wrong size");
  free(b);
  b = copy(base, n);
  b[fild + 16] = 1; /* vertex -> element: 13 items no longer match ne = 6 */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "elements", "field at the wrong location");
  b[fild + 16] = 2;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "location 2", "field location 2");
  free(b);
  b = copy(base, n);
  b[fild + 17] = 5;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "field type 5", "field type 5");
  free(b);
  b = copy(base, n);
  b[fild + 16 + 16 + 2] = 0; /* "cu\0vature" */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "NUL", "NUL in a field name");
  free(b);
  b = copy(base, n);
  b[fild + 16 + 16 + 9] = 'x'; /* "curvature" is 9 bytes, padded to 16 */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "padding after the field name", "nonzero name padding");
  free(b);
  b = copy(base, n);
  b[attr + 16 + 8 + 1] = 0;
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "NUL", "NUL in an attribute key");
  free(b);

  /* structure */
  b = copy(base, n);
  memcpy(b + mesh, "MESX", 4);
  vt_put32(b + mesh + 4, 0);
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "first chunk must be MESH", "MESH missing");
  free(b);
  b = copy(base, n);
  memcpy(b + vert, "VERX", 4);
  vt_put32(b + vert + 4, 0);
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "missing the required VERT", "VERT missing");
  free(b);
  b = copy(base, n);
  memcpy(b + elem, "VFLG", 4);
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "more than once", "VFLG twice");
  free(b);
  b = copy(base, n);
  memcpy(b + vflg, "ZZZZ", 4);
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "critical", "unknown critical chunk");
  free(b);
  b = copy(base, n);
  b[vflg + 16 + 5 * 13] = 9; /* padding after VFLG's 65 bytes */
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "padding byte", "nonzero chunk padding");
  free(b);
  free(base);

  /* duplicates: rename "ab" -> "aa" and "k2" -> "k1" inside a valid file */
  vm_mesh_create(ctx, &m);
  vm_mesh_set_vertices(m, 2);
  vm_mesh_add_field(m, "aa", VM_FIELD_VERTEX, VM_FIELD_F64, 1, NULL);
  vm_mesh_add_field(m, "ab", VM_FIELD_VERTEX, VM_FIELD_F64, 1, NULL);
  vm_mesh_add_field(m, "aa", VM_FIELD_ELEMENT, VM_FIELD_I32, 3, NULL);
  vm_mesh_set_attr(m, "k1", "x");
  vm_mesh_set_attr(m, "k2", "y");
  base = binary_of(ctx, m, dir, &n);
  vm_mesh_destroy(&m);
  b = copy(base, n);
  size_t f1 = vt_find_chunk(b, n, "FILD", 1);
  b[f1 + 16 + 16 + 1] = 'a';
  vt_fix_crc(b, n);
  char want[80];
  snprintf(want, sizeof want, "FILD chunk at offset %zu: vertex field 'aa' appears twice", f1);
  expect_fail(ctx, BIN, b, n, want, "duplicate field");
  free(b);
  b = copy(base, n);
  size_t a1 = vt_find_chunk(b, n, "ATTR", 1);
  b[a1 + 16 + 8 + 1] = '1';
  vt_fix_crc(b, n);
  expect_fail(ctx, BIN, b, n, "attribute 'k1' appears twice", "duplicate attribute");
  free(b);
  free(base);
}

/* Garbage, and every single-byte corruption of a valid file with the CRC
 * fixed up so the structural checks (not the checksum) must catch it. */
static void test_garbage(vm_ctx *ctx, const char *dir) {
  uint64_t s = 0x9E3779B97F4A7C15ull;
  uint8_t g[4096];
  for (int round = 0; round < 200; round++) {
    size_t len = 1 + (size_t)(xorshift(&s) % sizeof g);
    for (size_t i = 0; i < len; i++) g[i] = (uint8_t)xorshift(&s);
    if (round % 4 == 1 && len >= 8) memcpy(g, "\x89VMSH\r\n\x1a", 8);
    if (round % 4 == 2 && len >= 24) {
      memcpy(g, "\x89VMSH\r\n\x1a\x01\x00\x00\x00\x00\x00\x00\x00", 16);
      len = 28 + (len - 28) / 8 * 8;
      vt_put64(g + 16, len);
      vt_fix_crc(g, len);
    }
    if (round % 4 == 3 && len >= 6) memcpy(g, "vmsht ", 6);
    expect_fail(ctx, round % 4 == 3 ? TXT : BIN, g, len, NULL, "garbage");
  }

  vm_mesh *m = vt_mixed(ctx);
  size_t n;
  uint8_t *base = binary_of(ctx, m, dir, &n);
  CHECK(base && n > 200, "base file");
  if (!base) {
    vm_mesh_destroy(&m);
    return;
  }
  long live0 = vm_ctx_alloc_live(ctx);
  int accepted = 0, refused = 0;
  static const uint8_t masks[3] = {0x01, 0x80, 0xFF};
  for (size_t i = 0; i < n - 4; i++)
    for (int k = 0; k < 3; k++) {
      uint8_t *b = copy(base, n);
      b[i] ^= masks[k];
      vt_fix_crc(b, n);
      vm_mesh *r = NULL;
      int st = vm_mesh_read_memory(ctx, BIN, b, n, VM_FMT_VMSH, &r);
      if (st == VM_OK) {
        accepted++; /* e.g. a changed coordinate: still a valid mesh */
        CHECK(vm_mesh_check(r) == VM_OK, "accepted mesh is valid");
      } else {
        refused++;
        CHECK(st < 0 && !r && strstr(vm_ctx_error(ctx), BIN), "byte %zu: clean failure", i);
      }
      vm_mesh_destroy(&r);
      free(b);
    }
  CHECK(vm_ctx_alloc_live(ctx) == live0, "corruptions leak nothing");
  CHECK(refused > 300 && accepted > 100, "corruptions: %d refused, %d accepted", refused, accepted);
  free(base);
  vm_mesh_destroy(&m);
}

static void test_text(vm_ctx *ctx, const char *dir) {
  /* every truncation of a valid text file fails (except losing the final newline) */
  vm_mesh *m = vt_planar(ctx);
  char p[300];
  snprintf(p, sizeof p, "%s/base.vmsht", dir);
  CHECK(vm_mesh_write(ctx, m, p, VM_FMT_AUTO, NULL) == VM_OK, "write text");
  vm_mesh_destroy(&m);
  size_t n;
  uint8_t *base = vt_slurp(p, &n);
  remove(p);
  CHECK(base && n > 50 && base[n - 1] == '\n', "text base");
  if (!base) return;
  for (size_t k = 0; k < n - 1; k++) {
    char what[64];
    snprintf(what, sizeof what, "text truncated to %zu of %zu bytes", k, n);
    expect_fail(ctx, TXT, base, k, NULL, what);
  }
  free(base);

  static const struct {
    const char *text;
    const char *needle;
  } cases[] = {
      {"vmsht 2 0\ndim 3\n", "line 1: format version 2.0 is newer"},
      {"vmsht 1\n", "line 2: unexpected end of file"},
      {"vmsht 1 0\ndim 4\n", "line 2: dimension 4"},
      {"vmsht 1 0\ndim 3\nvertices 1099511627776\n0 0 0 free -1\n", "line 3: vertex count"},
      {"vmsht 1 0\ndim 3\nvertices 1000000\n0 0 0 free -1\n", "cannot fit"},
      {"vmsht 1 0\ndim 3\nvertices -1\n", "vertex count -1"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n0 0 0 stuck -1\n", "line 5: vertex flag"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n0 nan 0 free -1\n",
       "line 5: vertex 1: coordinate y is NaN"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n0 0 -inf free -1\n",
       "line 5: vertex 1: coordinate z is infinite"},
      {"vmsht 1 0\ndim 3\nvertices 1\n0 0 1e999 free -1\n", "infinite"},
      {"vmsht 1 0\ndim 3\nvertices 1\n0 0 0x free -1\n", "not a number"},
      {"vmsht 1 0\ndim 3\nvertices 1\n0 0 0 slip 2147483648\n", "surface id"},
      {"vmsht 1 0\ndim 3\nvertices 3\n0 0 0 free -1\n1 0 0 free -1\n0 1 0 free -1\n"
       "elements 1\nhexa 0 1 2\n",
       "line 8: element type: unknown 'hexa'"},
      {"vmsht 1 0\ndim 3\nvertices 3\n0 0 0 free -1\n1 0 0 free -1\n0 1 0 free -1\n"
       "elements 1\ntri 0 1 3\n",
       "line 8: element 0: vertex index 3 out of range"},
      {"vmsht 1 0\ndim 3\nvertices 3\n0 0 0 free -1\n1 0 0 free -1\n0 1 0 free -1\n"
       "elements 1\nquad 0 1 2\nfields 0\nattributes 0\nend\n",
       "not an integer"},
      {"vmsht 1 0\ndim 3\nvertices 0\nelements 99999999\ntri 0 1 2\n", "cannot fit"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 0 \"a\"\n",
       "component count 0"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 \"a\"\n1\nattributes 0\nend\n",
       "line 10: field value: 'attributes' is not a number"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex i32 1 \"a\"\n1\n2147483648\nattributes 0\nend\n",
       "does not fit in i32"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 \"\"\n1\n2\nattributes 0\nend\n",
       "field name is empty"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 a\n1\n2\nattributes 0\nend\n",
       "quoted string"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 \"a%G1\"\n1\n2\nattributes 0\nend\n",
       "hex digits"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 \"a%2\"\n1\n2\nattributes 0\nend\n",
       "hex digits"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 \"a%00b\"\n1\n2\nattributes 0\nend\n",
       "NUL"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1 \"a\"b\"\n1\n2\nattributes 0\nend\n",
       "unescaped"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 1\n"
       "field vertex f64 1048577 \"a\"\n",
       "component count"},
      {"vmsht 1 0\ndim 3\nvertices 1000\n", "cannot fit"},
      {"vmsht 1 0\ndim 3\nvertices 2\n0 0 0 free -1\n1 0 0 free -1\nelements 0\nfields 2\n"
       "field vertex f64 1 \"a\"\n1\n2\nfield vertex i32 1 \"a\"\n3\n4\nattributes 0\nend\n",
       "line 11: vertex field 'a' appears twice"},
      {"vmsht 1 0\ndim 3\nvertices 0\nelements 0\nfields 0\nattributes 2\n\"k\" \"1\"\n"
       "\"k\" \"2\"\nend\n",
       "line 8: attribute 'k' appears twice"},
      {"vmsht 1 0\ndim 3\nvertices 0\nelements 0\nfields 0\nattributes 1\n\"\" \"1\"\nend\n",
       "attribute key is empty"},
      {"vmsht 1 0\ndim 3\nvertices 0\nelements 0\nfields 0\nattributes 0\nend\nmore\n",
       "line 8: unexpected 'more' after 'end'"},
      {"vmsht 1 0\ndim 3\nvertices 0\nelements 0\nfields 0\nattributes 0\n", "expected end"},
      {"vmsht 1 0\ndim 3\nvertices 0\nelements 0\nfields 0\nattributes 0\nfin\n", "expected 'end'"},
      {"vmshtx 1 0\n", "magic"},
      {"# comment first\nvmsht 1 0\n", "magic"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char what[64];
    snprintf(what, sizeof what, "text case %zu", i);
    long allocs = expect_fail(ctx, TXT, (const uint8_t *)cases[i].text, strlen(cases[i].text),
                              cases[i].needle, what);
    CHECK(allocs < 20, "%s: %ld allocations", what, allocs);
  }

  /* a minimal valid text file with comments, odd spacing and CRLF */
  static const char good[] = "vmsht 1 3\r\n# a comment\r\ndim 2\nvertices 3\n"
                             "0 0 0 FIXED -1\n1 0 0 free -1   0 1 0 slip 4\n"
                             "elements 1\n  tri 0 1 2 # trailing comment\n"
                             "fields 0\nattributes 1\n\"a%20b\" \"\"\nend";
  vm_mesh *r = NULL;
  int st = vm_mesh_read_memory(ctx, TXT, (const uint8_t *)good, sizeof good - 1, VM_FMT_VMSH, &r);
  CHECK(st == VM_OK, "good text: %s", vm_ctx_error(ctx));
  if (r) {
    CHECK(r->dim == 2 && r->nv == 3 && r->ne == 1 && r->vflag[0] == VM_VERTEX_FIXED &&
              r->vflag[2] == VM_VERTEX_SLIP && r->vsurf[2] == 4,
          "good text content");
    CHECK(r->nattr == 1 && !strcmp(r->attrs[0].key, "a b") && !*r->attrs[0].value, "attr");
  }
  vm_mesh_destroy(&r);
}

int main(void) {
  char dir[] = "/tmp/vmsh_bad_XXXXXX";
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  long live0 = vm_ctx_alloc_live(ctx);
  double t0 = vt_now();
  test_binary(ctx, dir);
  test_garbage(ctx, dir);
  test_text(ctx, dir);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "no leak overall");
  CHECK(vt_now() - t0 < 8, "whole suite is quick");
  vm_ctx_destroy(&ctx);
  rmdir(dir);
  return vmtest_end("test_vmsh_bad");
}
