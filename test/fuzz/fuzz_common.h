/* test/fuzz/fuzz_common.h: what a fuzzed reader must do, shared by the
 * libFuzzer entry point (fuzz_reader.c) and the corpus replay (replay.c):
 * read one buffer through vm_mesh_read_memory, then check the contract, and
 * that what was read survives a round trip through .vmsh and .vmsht. */
#ifndef VM_FUZZ_COMMON_H
#define VM_FUZZ_COMMON_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/ctx.h"
#include "varmesh/io.h"
#include "varmesh/mesh.h"

typedef struct vm_fuzz_reader {
  const char *dir;  /* corpus folder: test/fuzz/corpus/<dir>, test/fuzz/regress/<dir> */
  const char *name; /* name passed to the reader (error messages only) */
  int format;
} vm_fuzz_reader;

static const vm_fuzz_reader vm_fuzz_readers[] = {
    {"vmsh", "fuzz.vmsh", VM_FMT_VMSH}, {"vmsht", "fuzz.vmsht", VM_FMT_VMSH_TEXT},
    {"vtk", "fuzz.vtk", VM_FMT_VTK},    {"vtu", "fuzz.vtu", VM_FMT_VTU},
    {"msh", "fuzz.msh", VM_FMT_MSH},    {"medit", "fuzz.mesh", VM_FMT_MEDIT},
    {"stl", "fuzz.stl", VM_FMT_STL},    {"obj", "fuzz.obj", VM_FMT_OBJ},
    {"off", "fuzz.off", VM_FMT_OFF},    {"ply", "fuzz.ply", VM_FMT_PLY},
    {"su2", "fuzz.su2", VM_FMT_SU2},
};
enum { VM_FUZZ_NREADERS = (int)(sizeof vm_fuzz_readers / sizeof vm_fuzz_readers[0]) };

#ifdef VM_FUZZ_VERBOSE
static int vm_fuzz_verbose; /* replay -v: status and message of every file */
#endif

/* A broken contract is a crash, so that libFuzzer keeps the input. */
#define VM_FUZZ_REQUIRE(cond, what)                                                                \
  do {                                                                                             \
    if (!(cond)) {                                                                                 \
      fprintf(stderr, "fuzz: %s:%d: contract broken: %s (%s)\n", __FILE__, __LINE__, what, #cond); \
      abort();                                                                                     \
    }                                                                                              \
  } while (0)

static inline void vm_fuzz_discard_log(void *user, int level, const char *msg) {
  (void)user;
  (void)level;
  (void)msg;
}

/* A private directory for round-trip files (in /dev/shm when there is one),
 * removed at exit. */
static void vm_fuzz_rmdir(void);
static char vm_fuzz_dir[64];
static void vm_fuzz_rmdir(void) { rmdir(vm_fuzz_dir); }
static inline const char *vm_fuzz_tmpdir(void) {
  if (!vm_fuzz_dir[0]) {
    strcpy(vm_fuzz_dir, "/dev/shm/vm-fuzz-XXXXXX");
    if (!mkdtemp(vm_fuzz_dir)) {
      strcpy(vm_fuzz_dir, "/tmp/vm-fuzz-XXXXXX");
      VM_FUZZ_REQUIRE(mkdtemp(vm_fuzz_dir) != NULL, "cannot make a temporary directory");
    }
    atexit(vm_fuzz_rmdir);
  }
  return vm_fuzz_dir;
}

/* Are the f64 values the same bits, or (nan_payload_free) NaNs of one sign?
 * (.vmsht keeps the sign of a NaN but not its payload: docs/vmsh.md.) */
static inline int vm_fuzz_same_f64(const double *x, const double *y, size_t n,
                                   int nan_payload_free) {
  if (!n || !memcmp(x, y, n * sizeof *x)) return 1;
  for (size_t i = 0; i < n; i++) {
    if (!memcmp(&x[i], &y[i], sizeof *x)) continue;
    if (!nan_payload_free || !isnan(x[i]) || !isnan(y[i]) || !signbit(x[i]) != !signbit(y[i]))
      return 0;
  }
  return 1;
}

/* NULL if b is a bit for bit copy of a, else what differs. */
static inline const char *vm_fuzz_mesh_diff(const vm_mesh *a, const vm_mesh *b,
                                            int nan_payload_free) {
  if (a->dim != b->dim) return "dim";
  if (a->nv != b->nv || a->ne != b->ne) return "counts";
  if (a->nfield != b->nfield) return "number of fields";
  if (a->nattr != b->nattr) return "number of attributes";
  size_t nv = (size_t)a->nv, ne = (size_t)a->ne, nc = (size_t)a->eoff[a->ne];
  if (nv && memcmp(a->xyz, b->xyz, 3 * nv * sizeof *a->xyz)) return "coordinates";
  if (nv && memcmp(a->vflag, b->vflag, nv * sizeof *a->vflag)) return "vertex flags";
  if (nv && memcmp(a->vsurf, b->vsurf, nv * sizeof *a->vsurf)) return "slip surface ids";
  if (ne && (memcmp(a->etype, b->etype, ne * sizeof *a->etype) ||
             memcmp(a->eoff, b->eoff, (ne + 1) * sizeof *a->eoff)))
    return "element types";
  if (nc && memcmp(a->conn, b->conn, nc * sizeof *a->conn)) return "connectivity";
  for (int i = 0; i < a->nfield; i++) {
    const vm_field *f = &a->fields[i], *g = &b->fields[i];
    if (strcmp(f->name, g->name)) return "field name";
    if (f->location != g->location || f->type != g->type || f->ncomp != g->ncomp)
      return "field location, type or components";
    size_t n = (size_t)vm_field_count(a, f) * (size_t)f->ncomp;
    if (f->type == VM_FIELD_F64 ? !vm_fuzz_same_f64(f->data, g->data, n, nan_payload_free)
                                : n && memcmp(f->data, g->data, n * sizeof(int32_t)))
      return "field values";
  }
  for (int i = 0; i < a->nattr; i++) {
    if (strcmp(a->attrs[i].key, b->attrs[i].key)) return "attribute key";
    if (strcmp(a->attrs[i].value, b->attrs[i].value)) return "attribute value";
  }
  return NULL;
}

/* Whatever a reader accepts, the native formats must carry exactly: write m
 * as .vmsh and .vmsht and read it back, bit for bit. */
static inline void vm_fuzz_roundtrip(vm_ctx *ctx, const vm_mesh *m) {
  static const int fmts[2] = {VM_FMT_VMSH, VM_FMT_VMSH_TEXT};
  for (int k = 0; k < 2; k++) {
    char path[128];
    snprintf(path, sizeof path, "%s/rt.%s", vm_fuzz_tmpdir(), k ? "vmsht" : "vmsh");
    int st = vm_mesh_write(ctx, m, path, fmts[k], NULL);
    if (st != VM_OK) fprintf(stderr, "fuzz: round trip: write: %d %s\n", st, vm_ctx_error(ctx));
    VM_FUZZ_REQUIRE(st == VM_OK, "a mesh the reader accepted cannot be written losslessly");
    vm_mesh *b = NULL;
    st = vm_mesh_read(ctx, path, fmts[k], &b);
    remove(path);
    if (st != VM_OK) fprintf(stderr, "fuzz: round trip: read: %d %s\n", st, vm_ctx_error(ctx));
    VM_FUZZ_REQUIRE(st == VM_OK, "the native format does not read back what it wrote");
    const char *diff = vm_fuzz_mesh_diff(m, b, fmts[k] == VM_FMT_VMSH_TEXT);
    if (diff) fprintf(stderr, "fuzz: round trip through %s: %s differ\n", path, diff);
    VM_FUZZ_REQUIRE(!diff, "the native format changed the mesh");
    vm_mesh_destroy(&b);
  }
}

/* One read with allocation `fail_at` failing (0: none). Returns the status;
 * *nalloc receives the number of allocations made. Checks: a status of 0 or
 * negative (readers give no warnings), a mesh exactly on success, a
 * non-empty one-line message on failure, VM_ERR_NOMEM when the injected
 * failure was hit, and nothing left allocated afterwards. */
static inline int vm_fuzz_read(const vm_fuzz_reader *r, const uint8_t *data, size_t size,
                               long fail_at, long *nalloc) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) abort();
  vm_ctx_set_log(ctx, vm_fuzz_discard_log, NULL);
  long live0 = vm_ctx_alloc_live(ctx), count0 = vm_ctx_alloc_count(ctx);
  if (fail_at > 0) vm_ctx_set_alloc_fail(ctx, fail_at);
  vm_mesh *m = (vm_mesh *)(uintptr_t)1; /* must be overwritten */
  int st = vm_mesh_read_memory(ctx, r->name, data, size, r->format, &m);
  vm_ctx_set_alloc_fail(ctx, 0);
  *nalloc = vm_ctx_alloc_count(ctx) - count0;
  VM_FUZZ_REQUIRE(st <= 0, "reader returned a positive status");
  if (st == 0) {
    VM_FUZZ_REQUIRE(m != NULL, "success without a mesh");
    VM_FUZZ_REQUIRE(m->ctx == ctx, "mesh bound to another context");
    VM_FUZZ_REQUIRE(m->dim == 2 || m->dim == 3, "mesh dimension");
    VM_FUZZ_REQUIRE(vm_mesh_check(m) == VM_OK, "mesh invariants");
    if (fail_at == 0) vm_fuzz_roundtrip(ctx, m);
    vm_mesh_destroy(&m);
    VM_FUZZ_REQUIRE(m == NULL, "destroy did not clear the handle");
  } else {
    const char *msg = vm_ctx_error(ctx);
    VM_FUZZ_REQUIRE(m == NULL, "failure left a mesh");
    VM_FUZZ_REQUIRE(msg && msg[0], "failure without a message");
    VM_FUZZ_REQUIRE(!strchr(msg, '\n'), "multi-line error message");
    if (fail_at > 0 && fail_at <= *nalloc)
      VM_FUZZ_REQUIRE(st == VM_ERR_NOMEM, "injected allocation failure not reported as NOMEM");
  }
#ifdef VM_FUZZ_VERBOSE
  if (vm_fuzz_verbose && fail_at == 0 && st < 0) fprintf(stderr, "  %s\n", vm_ctx_error(ctx));
#endif
  VM_FUZZ_REQUIRE(vm_ctx_alloc_live(ctx) == live0, "allocations leaked");
  vm_ctx_destroy(&ctx);
  return st;
}

/* FNV-1a: a deterministic choice of which allocation to fail. */
static inline uint64_t vm_fuzz_hash(const uint8_t *data, size_t size) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < size; i++) h = (h ^ data[i]) * 1099511628211ull;
  return h;
}

/* CRC-32 (IEEE, as zlib's crc32), for the .vmsh trailer. */
static inline uint32_t vm_fuzz_crc32(const uint8_t *p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; i++) {
    c ^= p[i];
    for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

static void vm_fuzz_one_raw(const vm_fuzz_reader *r, const uint8_t *data, size_t size);

/* Run the input as it is; for .vmsh also with the file-size field and the
 * CRC-32 trailer made to match, so mutations reach the chunk parser (as
 * PNG fuzzers ignore CRCs). */
static inline void vm_fuzz_one(const vm_fuzz_reader *r, const uint8_t *data, size_t size) {
  vm_fuzz_one_raw(r, data, size);
  if (r->format != VM_FMT_VMSH || size < 28) return;
  uint8_t *fixed = (uint8_t *)malloc(size);
  if (!fixed) abort();
  memcpy(fixed, data, size);
  for (int i = 0; i < 8; i++) fixed[16 + i] = (uint8_t)((uint64_t)size >> (8 * i));
  uint32_t crc = vm_fuzz_crc32(fixed, size - 4);
  for (int i = 0; i < 4; i++) fixed[size - 4 + (size_t)i] = (uint8_t)(crc >> (8 * i));
  if (memcmp(fixed, data, size)) vm_fuzz_one_raw(r, fixed, size);
  free(fixed);
}

/* Read the input; if it parses, read it again with one allocation failing
 * (chosen from the input's hash), so error paths are fuzzed too. */
static void vm_fuzz_one_raw(const vm_fuzz_reader *r, const uint8_t *data, size_t size) {
  long nalloc = 0;
  int st = vm_fuzz_read(r, data, size, 0, &nalloc);
#ifdef VM_FUZZ_VERBOSE
  if (vm_fuzz_verbose) fprintf(stderr, "  %s: status %d, %ld allocations\n", r->dir, st, nalloc);
#endif
  if (nalloc > 0) {
    long k = 1 + (long)(vm_fuzz_hash(data, size) % (uint64_t)nalloc);
    long n2 = 0;
    int st2 = vm_fuzz_read(r, data, size, k, &n2);
    /* the same input must fail the same way or run out of memory */
    VM_FUZZ_REQUIRE(st2 == VM_ERR_NOMEM || st2 == st, "status changed under allocation failure");
  }
}

#endif
