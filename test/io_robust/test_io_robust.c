/* test/io_robust/test_io_robust.c: every reader against truncated, mutated
 * and out-of-memory conditions: a clean status, a one-line message naming
 * the file, no leak (sanitizer builds also catch memory errors). */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "vmtest.h"

typedef struct {
  const char *ext;
  int binary;
} fmt_case;

static const fmt_case cases[] = {{"vmsh", 0}, {"vmsht", 0}, {"vtk", 0}, {"vtk", 1}, {"vtu", 0},
                                 {"msh", 0},  {"msh", 1},   {"mesh", 0}};

/* A small mixed mesh: one element of each 3D type sharing vertices. */
static vm_mesh *small_mesh(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  static const double p[][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1},
                                {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {2, 0, 0}, {2, 1, 0},
                                {2, 0, 1}, {2, 1, 1}, {0.5, 0.5, -1}, {1.5, 0.5, 2}};
  int n = (int)(sizeof p / sizeof p[0]);
  for (int i = 0; i < n; i++) vm_mesh_add_vertex(m, p[i][0], p[i][1], p[i][2], NULL);
  static const int32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  static const int32_t prism[6] = {1, 8, 9, 5, 10, 11};
  static const int32_t pyr[5] = {0, 3, 2, 1, 12};
  static const int32_t tet[4] = {5, 10, 11, 13};
  vm_mesh_add_element(m, VM_HEX, hex);
  vm_mesh_add_element(m, VM_PRISM, prism);
  vm_mesh_add_element(m, VM_PYRAMID, pyr);
  vm_mesh_add_element(m, VM_TET, tet);
  vm_field *f;
  vm_mesh_add_field(m, "temperature", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  for (int i = 0; i < n; i++) ((double *)f->data)[i] = 0.25 * i;
  vm_mesh_add_field(m, "fixed", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f);
  ((int32_t *)f->data)[0] = 1;
  m->vflag[0] = VM_VERTEX_FIXED;
  return m;
}

static int try_read(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                    int *bad_msg) {
  long live = vm_ctx_alloc_live(ctx);
  vm_mesh *m = NULL;
  vm_ctx_clear_error(ctx);
  int st = vm_mesh_read_memory(ctx, name, buf, len, VM_FMT_AUTO, &m);
  if (st < 0) {
    const char *msg = vm_ctx_error(ctx);
    if (m || !strstr(msg, name) || strchr(msg, '\n')) *bad_msg = 1;
  } else if (!m) {
    *bad_msg = 1;
  }
  vm_mesh_destroy(&m);
  if (vm_ctx_alloc_live(ctx) != live) *bad_msg = 2;
  return st;
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  vm_ctx_seed(ctx, 12345);
  char dir[] = "/tmp/vm_robust_XXXXXX";
  if (!mkdtemp(dir)) return 1;
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    char path[256], name[64];
    snprintf(name, sizeof name, "case%zu.%s", c, cases[c].ext);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    vm_mesh *m = small_mesh(ctx);
    vm_write_opts wo = vm_write_opts_default();
    wo.binary = cases[c].binary;
    int st = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, &wo);
    vm_mesh_destroy(&m);
    CHECK(st >= 0, "%s: write: %s", name, vm_ctx_error(ctx));
    if (st < 0) continue;
    uint8_t *buf;
    size_t len;
    vm_read_file(ctx, path, &buf, &len);
    int bad = 0, ok_reads = 0;
    CHECK(try_read(ctx, name, buf, len, &bad) == VM_OK, "%s: clean read: %s", name,
          vm_ctx_error(ctx));
    /* every truncation */
    uint8_t *copy = malloc(len + 16);
    for (size_t n = 0; n < len; n++) {
      memcpy(copy, buf, n);
      if (try_read(ctx, name, copy, n, &bad) == VM_OK) ok_reads++;
    }
    CHECK(!bad, "%s: truncation: bad message or leak (%d)", name, bad);
    /* seeded mutations: byte flips, digits, huge numbers spliced in */
    static const char *splice[] = {"99999999999", "-1", "nan", "1e308", "4294967296", "0",
                                   "\xff\xff\xff\x7f", "2147483647"};
    int nmut = 3000;
    for (int it = 0; it < nmut; it++) {
      memcpy(copy, buf, len);
      size_t n = len;
      size_t pos = (size_t)(vm_ctx_rand_unit(ctx) * (double)len);
      int kind = (int)(vm_ctx_rand_u64(ctx) % 3);
      if (kind == 0) {
        copy[pos] ^= (uint8_t)(1u << (vm_ctx_rand_u64(ctx) % 8));
      } else if (kind == 1) {
        copy[pos] = (uint8_t)('0' + vm_ctx_rand_u64(ctx) % 10);
      } else {
        const char *s = splice[vm_ctx_rand_u64(ctx) % 8];
        size_t k = strlen(s);
        if (pos + k > n) pos = n > k ? n - k : 0;
        memcpy(copy + pos, s, k < n ? k : n);
      }
      try_read(ctx, name, copy, n, &bad);
    }
    CHECK(!bad, "%s: mutation: bad message or leak (%d)", name, bad);
    /* allocation failure at every allocation of a clean read */
    long before = vm_ctx_alloc_count(ctx);
    vm_mesh *mm = NULL;
    vm_mesh_read_memory(ctx, name, buf, len, VM_FMT_AUTO, &mm);
    vm_mesh_destroy(&mm);
    long nalloc = vm_ctx_alloc_count(ctx) - before;
    int leaks = 0, silent = 0;
    for (long k = 1; k <= nalloc; k++) {
      long live = vm_ctx_alloc_live(ctx);
      vm_ctx_set_alloc_fail(ctx, k);
      int s2 = vm_mesh_read_memory(ctx, name, buf, len, VM_FMT_AUTO, &mm);
      vm_ctx_set_alloc_fail(ctx, 0);
      if (s2 >= 0) silent++;
      vm_mesh_destroy(&mm);
      if (vm_ctx_alloc_live(ctx) != live) leaks++;
    }
    CHECK(leaks == 0 && silent == 0, "%s: alloc-failure sweep over %ld allocations: %d leaks, %d "
          "failures not reported", name, nalloc, leaks, silent);
    fprintf(stderr, "%-8s %s: %zu bytes, %zu truncations (%d read fine), %d mutations, %ld "
            "allocation failures tried\n", cases[c].ext, cases[c].binary ? "binary" : "text",
            len, len, ok_reads, nmut, nalloc);
    free(copy);
    vm_free(ctx, buf);
    remove(path);
  }
  rmdir(dir);
  vm_ctx_destroy(&ctx);
  return vmtest_end("io_robust");
}
