/* test/io_vmsh/test_vmsh.c: .vmsh/.vmsht round trips (bit-exact, byte-stable
 * rewrites), the documented worked example, the golden text file, forward
 * compatibility, atomic writes, and allocation-failure injection. */
#include <dirent.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "vmsh_testlib.h"
#include "vmtest.h"

static char dir[64];

static const char *tmp(const char *name) {
  static char buf[8][256];
  static int k;
  char *p = buf[k++ % 8];
  snprintf(p, 256, "%s/%s", dir, name);
  return p;
}

/* write m to path, read it back, check equal, write again, compare bytes */
static void roundtrip(vm_ctx *ctx, const vm_mesh *m, const char *name) {
  const char *p1 = tmp(name);
  char p2[300];
  const char *dot = strrchr(name, '.');
  snprintf(p2, sizeof p2, "%s/again%s", dir, dot);
  long live0 = vm_ctx_alloc_live(ctx);
  CHECK(vm_mesh_write(ctx, m, p1, VM_FMT_AUTO, NULL) == VM_OK, "write %s: %s", name,
        vm_ctx_error(ctx));
  vm_mesh *r = NULL;
  int st = vm_mesh_read(ctx, p1, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r, "read %s: %s", name, vm_ctx_error(ctx));
  if (!r) return;
  CHECK(vt_mesh_equal(m, r), "%s: read back differs", name);
  CHECK(vm_mesh_write(ctx, r, p2, VM_FMT_AUTO, NULL) == VM_OK, "rewrite %s: %s", name,
        vm_ctx_error(ctx));
  CHECK(vt_same_file(p1, p2), "%s: write -> read -> write changed the bytes", name);
  vm_mesh_destroy(&r);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leak", name);
}

static void test_roundtrips(vm_ctx *ctx) {
  vm_mesh *m = vt_mixed(ctx);
  CHECK(m && vm_mesh_check(m) == VM_OK, "mixed mesh builds: %s", vm_ctx_error(ctx));
  int64_t counts[VM_NTYPES];
  vm_mesh_count_types(m, counts);
  for (int t = 0; t < VM_NTYPES; t++) CHECK(counts[t] == 1, "one %s", vm_elem_name(t));
  roundtrip(ctx, m, "mixed.vmsh");
  roundtrip(ctx, m, "mixed.vmsht");

  /* binary -> text -> binary gives the same bytes as binary directly */
  vm_mesh *r = NULL;
  CHECK(vm_mesh_read(ctx, tmp("mixed.vmsht"), VM_FMT_AUTO, &r) == VM_OK, "read text");
  if (r) {
    CHECK(vm_mesh_write(ctx, r, tmp("via_text.vmsh"), VM_FMT_AUTO, NULL) == VM_OK, "write");
    CHECK(vt_same_file(tmp("via_text.vmsh"), tmp("mixed.vmsh")), "text -> binary bytes");
    vm_mesh_destroy(&r);
  }
  /* the binary reader is chosen by magic, not extension */
  CHECK(vm_mesh_read(ctx, tmp("mixed.vmsh"), VM_FMT_VMSH_TEXT, &r) == VM_OK, "magic wins");
  CHECK(r && vt_mesh_equal(m, r), "read by magic equal");
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);

  m = vt_planar(ctx);
  CHECK(m && m->dim == 2, "planar mesh");
  roundtrip(ctx, m, "planar.vmsh");
  roundtrip(ctx, m, "planar.vmsht");
  CHECK(vm_mesh_read(ctx, tmp("planar.vmsh"), VM_FMT_AUTO, &r) == VM_OK && r && r->dim == 2,
        "2D stays 2D");
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);

  /* the empty mesh */
  vm_mesh_create(ctx, &m);
  roundtrip(ctx, m, "empty.vmsh");
  roundtrip(ctx, m, "empty.vmsht");
  vm_mesh_destroy(&m);
}

/* The worked example of docs/vmsh.md, byte for byte. */
static const uint8_t example[308] = {
    0x89, 0x56, 0x4d, 0x53, 0x48, 0x0d, 0x0a, 0x1a, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x34, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x4d, 0x45, 0x53, 0x48, 0x01, 0x00, 0x00, 0x00,
    0x20, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x56, 0x45, 0x52, 0x54, 0x01, 0x00, 0x00, 0x00,
    0x48, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x56, 0x46, 0x4c, 0x47, 0x01, 0x00, 0x00, 0x00, 0x0f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0xff, 0xff, 0xff, 0xff, 0x05, 0x00, 0x00, 0x00, 0xff, 0xff, 0xff, 0xff, 0x01, 0x02, 0x00, 0x00,
    0x45, 0x4c, 0x45, 0x4d, 0x01, 0x00, 0x00, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00,
    0x46, 0x49, 0x4c, 0x44, 0x01, 0x00, 0x00, 0x00, 0x1c, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x01, 0x01, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x68, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x41, 0x54, 0x54, 0x52, 0x01, 0x00, 0x00, 0x00, 0x0c, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x62, 0x79, 0x6d, 0x65, 0x00, 0x00, 0x00, 0x00,
    0x8d, 0x0d, 0xfa, 0x37};

static const char example_text[] = "vmsht 1 0\n"
                                   "dim 2\n"
                                   "vertices 3\n"
                                   "0 0 0 fixed -1\n"
                                   "1 0 0 slip 5\n"
                                   "0 1 0 free -1\n"
                                   "elements 1\n"
                                   "tri 0 1 2\n"
                                   "fields 1\n"
                                   "field element i32 1 \"h\"\n"
                                   "7\n"
                                   "attributes 1\n"
                                   "\"by\" \"me\"\n"
                                   "end\n";

static vm_mesh *example_mesh(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  m->dim = 2;
  vm_mesh_add_vertex(m, 0, 0, 0, NULL);
  vm_mesh_add_vertex(m, 1, 0, 0, NULL);
  vm_mesh_add_vertex(m, 0, 1, 0, NULL);
  m->vflag[0] = VM_VERTEX_FIXED;
  m->vflag[1] = VM_VERTEX_SLIP;
  m->vsurf[1] = 5;
  static const int32_t t[3] = {0, 1, 2};
  vm_mesh_add_element(m, VM_TRI, t);
  vm_field *f;
  vm_mesh_add_field(m, "h", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  ((int32_t *)f->data)[0] = 7;
  vm_mesh_set_attr(m, "by", "me");
  return m;
}

static void test_worked_example(vm_ctx *ctx) {
  vm_mesh *m = example_mesh(ctx);
  CHECK(vm_mesh_write(ctx, m, tmp("example.vmsh"), VM_FMT_AUTO, NULL) == VM_OK, "write");
  CHECK(vm_mesh_write(ctx, m, tmp("example.vmsht"), VM_FMT_AUTO, NULL) == VM_OK, "write");
  size_t n;
  uint8_t *b = vt_slurp(tmp("example.vmsh"), &n);
  CHECK(b && n == sizeof example && !memcmp(b, example, n), "binary matches docs/vmsh.md");
  CHECK(vt_crc32(example, sizeof example - 4) == 0x37FA0D8Du, "documented CRC");
  free(b);
  b = vt_slurp(tmp("example.vmsht"), &n);
  CHECK(b && n == strlen(example_text) && !memcmp(b, example_text, n), "text matches docs/vmsh.md");
  free(b);
  vm_mesh *r = NULL;
  CHECK(vm_mesh_read_memory(ctx, "example.vmsh", example, sizeof example, VM_FMT_AUTO, &r) == VM_OK,
        "read example: %s", vm_ctx_error(ctx));
  CHECK(r && vt_mesh_equal(m, r), "example content");
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);
}

/* The golden text file is the mixed mesh written by the text writer; set
 * VM_REGEN_GOLDEN=1 to rewrite it after an intended format change. */
static void test_golden(vm_ctx *ctx) {
  const char *root = getenv("VM_SOURCE_ROOT");
  if (!root) root = ".";
  char path[1024];
  snprintf(path, sizeof path, "%s/test/io_vmsh/mixed.vmsht", root);
  vm_mesh *m = vt_mixed(ctx);
  if (getenv("VM_REGEN_GOLDEN"))
    CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) == VM_OK, "regenerate %s", path);
  vm_mesh *g = NULL;
  CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &g) == VM_OK, "read golden: %s", vm_ctx_error(ctx));
  CHECK(g && vt_mesh_equal(m, g), "golden content equals the mesh built in code");
  if (g) {
    CHECK(g->vflag[9] == VM_VERTEX_SLIP && g->vsurf[9] == 3 && g->vsurf[11] == 7, "slip ids");
    CHECK(!strcmp(vm_mesh_get_attr(g, "note"), "spaces, \"quotes\", 100% and a\ttab"),
          "escaped attribute");
    CHECK(vm_mesh_get_attr(g, "empty") && !*vm_mesh_get_attr(g, "empty"), "empty value");
    CHECK(vm_mesh_find_field(g, "target thickness", VM_FIELD_ELEMENT), "name with a space");
    CHECK(signbit(g->xyz[0]) && g->xyz[0] == 0 && g->xyz[1] == 1e-310, "-0 and subnormal");
  }
  CHECK(vm_mesh_write(ctx, m, tmp("golden.vmsht"), VM_FMT_AUTO, NULL) == VM_OK, "write");
  CHECK(vt_same_file(path, tmp("golden.vmsht")), "writer output equals the golden file");
  vm_mesh_destroy(&g);
  vm_mesh_destroy(&m);
}

/* Unknown chunks: skipped when optional, refused when critical; a newer
 * minor version is read. */
static void test_forward_compat(vm_ctx *ctx) {
  size_t n;
  uint8_t *b = vt_slurp(tmp("mixed.vmsh"), &n);
  CHECK(b != NULL, "read mixed.vmsh");
  if (!b) return;
  size_t at = vt_find_chunk(b, n, "ELEM", 0);
  CHECK(at > 0, "ELEM found");
  static const char note[] = "written by a future vm-prism"; /* 28 bytes -> padded to 32 */
  size_t extra = 16 + 32, m2 = n + extra;
  uint8_t *c = calloc(1, m2);
  memcpy(c, b, at);
  memcpy(c + at, "NOTE", 4);
  vt_put32(c + at + 4, 0);
  vt_put64(c + at + 8, sizeof note - 1);
  memcpy(c + at + 16, note, sizeof note - 1);
  memcpy(c + at + extra, b + at, n - at);
  vt_put64(c + 16, m2);
  c[10] = 7; /* minor version 1.7 */
  vt_fix_crc(c, m2);
  long live0 = vm_ctx_alloc_live(ctx);
  vm_mesh *r = NULL, *m = vt_mixed(ctx);
  CHECK(vm_mesh_read_memory(ctx, "future.vmsh", c, m2, VM_FMT_VMSH, &r) == VM_OK,
        "optional unknown chunk skipped: %s", vm_ctx_error(ctx));
  CHECK(r && vt_mesh_equal(m, r), "content unchanged");
  vm_mesh_destroy(&r);
  vt_put32(c + at + 4, 1); /* now critical */
  vt_fix_crc(c, m2);
  int st = vm_mesh_read_memory(ctx, "future.vmsh", c, m2, VM_FMT_VMSH, &r);
  CHECK(st == VM_ERR_FORMAT && !r, "critical unknown chunk refused");
  CHECK(strstr(vm_ctx_error(ctx), "future.vmsh") && strstr(vm_ctx_error(ctx), "NOTE") &&
            strstr(vm_ctx_error(ctx), "critical"),
        "message: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "no leak");
  free(c);
  free(b);
}

static int count_dir_entries(void) {
  DIR *d = opendir(dir);
  int n = 0;
  struct dirent *e;
  while (d && (e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
  if (d) closedir(d);
  return n;
}

static void test_write_failures(vm_ctx *ctx) {
  long start = vm_ctx_alloc_live(ctx);
  vm_mesh *m = vt_mixed(ctx);
  long live0 = vm_ctx_alloc_live(ctx);
  const char *fmts[2] = {"vmsh", "vmsht"};
  for (int k = 0; k < 2; k++) {
    char bad[300];
    snprintf(bad, sizeof bad, "%s/no/such/dir/out.%s", dir, fmts[k]);
    int st = vm_mesh_write(ctx, m, bad, VM_FMT_AUTO, NULL);
    CHECK(st < 0, "write into a missing directory fails");
    CHECK(strstr(vm_ctx_error(ctx), bad) != NULL, "message names the path: %s", vm_ctx_error(ctx));
    CHECK(vm_ctx_alloc_live(ctx) == live0, "no leak");
  }

  /* a real mid-write failure (file size limit) leaves the old file intact */
  vm_mesh *big = NULL;
  vm_mesh_create(ctx, &big);
  vm_mesh_set_vertices(big, 20000);
  for (int i = 0; i < 60000; i++) big->xyz[i] = i / 7.0;
  long live1 = vm_ctx_alloc_live(ctx);
  static const char old[] = "previous contents\n";
  struct rlimit saved, lim;
  getrlimit(RLIMIT_FSIZE, &saved);
  void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
  for (int k = 0; k < 2; k++) {
    char target[64];
    snprintf(target, sizeof target, "keep.%s", fmts[k]);
    vt_spit(tmp(target), old, sizeof old - 1);
    int before = count_dir_entries();
    lim = saved;
    lim.rlim_cur = 65536;
    setrlimit(RLIMIT_FSIZE, &lim);
    int st = vm_mesh_write(ctx, big, tmp(target), VM_FMT_AUTO, NULL);
    setrlimit(RLIMIT_FSIZE, &saved);
    CHECK(st == VM_ERR_IO, "%s: write past the size limit fails (%d: %s)", fmts[k], st,
          vm_ctx_error(ctx));
    CHECK(strstr(vm_ctx_error(ctx), target) != NULL, "message: %s", vm_ctx_error(ctx));
    size_t n;
    uint8_t *b = vt_slurp(tmp(target), &n);
    CHECK(b && n == sizeof old - 1 && !memcmp(b, old, n), "%s: old file untouched", fmts[k]);
    free(b);
    CHECK(count_dir_entries() == before, "%s: no temporary file left behind", fmts[k]);
    CHECK(vm_ctx_alloc_live(ctx) == live1, "%s: no leak", fmts[k]);
  }
  signal(SIGXFSZ, prev);

  /* an invalid mesh is refused before the target is touched */
  big->xyz[5] = (double)NAN;
  vt_spit(tmp("keep.vmsh"), old, sizeof old - 1);
  CHECK(vm_mesh_write(ctx, big, tmp("keep.vmsh"), VM_FMT_AUTO, NULL) < 0, "NaN refused");
  size_t n;
  uint8_t *b = vt_slurp(tmp("keep.vmsh"), &n);
  CHECK(b && n == sizeof old - 1, "old file untouched after a refused write");
  free(b);
  vm_mesh_destroy(&big);
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == start, "no leak");
}

/* Every allocation of every read and write fails once: each must return an
 * error without leaking; the last attempt succeeds. */
static void test_alloc_failures(vm_ctx *ctx) {
  vm_mesh *m = vt_mixed(ctx);
  CHECK(vm_mesh_write(ctx, m, tmp("af.vmsh"), VM_FMT_AUTO, NULL) == VM_OK, "write");
  CHECK(vm_mesh_write(ctx, m, tmp("af.vmsht"), VM_FMT_AUTO, NULL) == VM_OK, "write");
  const char *paths[2] = {tmp("af.vmsh"), tmp("af.vmsht")};
  for (int k = 0; k < 2; k++) {
    long live0 = vm_ctx_alloc_live(ctx);
    int ok = 0, failures = 0;
    for (long i = 1; i < 500 && !ok; i++) {
      vm_ctx_set_alloc_fail(ctx, i);
      vm_mesh *r = NULL;
      int st = vm_mesh_read(ctx, paths[k], VM_FMT_AUTO, &r);
      vm_ctx_set_alloc_fail(ctx, 0);
      if (st == VM_OK) {
        ok = 1;
        CHECK(vt_mesh_equal(m, r), "read after failures");
        vm_mesh_destroy(&r);
      } else {
        failures++;
        CHECK(st == VM_ERR_NOMEM && !r, "read fails with NOMEM (%d: %s)", st, vm_ctx_error(ctx));
      }
      CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leak after failing allocation %ld", paths[k], i);
    }
    CHECK(ok && failures > 5, "%s: read eventually succeeds (%d failures)", paths[k], failures);

    ok = 0;
    failures = 0;
    char out[300];
    snprintf(out, sizeof out, "%s/afw.%s", dir, k ? "vmsht" : "vmsh");
    for (long i = 1; i < 100 && !ok; i++) {
      vm_ctx_set_alloc_fail(ctx, i);
      int st = vm_mesh_write(ctx, m, out, VM_FMT_AUTO, NULL);
      vm_ctx_set_alloc_fail(ctx, 0);
      if (st == VM_OK)
        ok = 1;
      else
        failures++;
      CHECK(st == VM_OK || st == VM_ERR_NOMEM, "write status %d", st);
      CHECK(vm_ctx_alloc_live(ctx) == live0, "write leak at %ld", i);
    }
    CHECK(ok && failures > 0, "write eventually succeeds");
    CHECK(vt_same_file(out, paths[k]), "written file complete");
  }
  vm_mesh_destroy(&m);
}

int main(void) {
  snprintf(dir, sizeof dir, "/tmp/vmsh_test_XXXXXX");
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  long live0 = vm_ctx_alloc_live(ctx);
  test_roundtrips(ctx);
  test_worked_example(ctx);
  test_golden(ctx);
  test_forward_compat(ctx);
  test_write_failures(ctx);
  test_alloc_failures(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "no leak overall");
  vm_ctx_destroy(&ctx);
  /* clean up the temporary directory (flat) */
  DIR *d = opendir(dir);
  struct dirent *e;
  while (d && (e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    char p[600];
    snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
    remove(p);
  }
  if (d) closedir(d);
  rmdir(dir);
  return vmtest_end("test_vmsh");
}
