/* test/fuzz/fuzz_common.h: what a fuzzed reader must do, shared by the
 * libFuzzer entry point (fuzz_reader.c) and the corpus replay (replay.c):
 * read one buffer through vm_mesh_read_memory, then check the contract. */
#ifndef VM_FUZZ_COMMON_H
#define VM_FUZZ_COMMON_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/ctx.h"
#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "varmesh/surface_io.h"

typedef struct vm_fuzz_reader {
  const char *dir;  /* corpus folder: test/fuzz/corpus/<dir>, test/fuzz/regress/<dir> */
  const char *name; /* name passed to the reader (error messages only) */
  int format;
} vm_fuzz_reader;

static const vm_fuzz_reader vm_fuzz_readers[] = {
    {"vmsh", "fuzz.vmsh", VM_FMT_VMSH},    {"vmsht", "fuzz.vmsht", VM_FMT_VMSH_TEXT},
    {"vtk", "fuzz.vtk", VM_FMT_VTK},       {"vtu", "fuzz.vtu", VM_FMT_VTU},
    {"msh", "fuzz.msh", VM_FMT_MSH},       {"medit", "fuzz.mesh", VM_FMT_MEDIT},
    {"stl", "fuzz.stl", VM_FMT_STL},       {"obj", "fuzz.obj", VM_FMT_OBJ},
    {"off", "fuzz.off", VM_FMT_OFF},       {"ply", "fuzz.ply", VM_FMT_PLY},
};
enum { VM_FUZZ_NREADERS = (int)(sizeof vm_fuzz_readers / sizeof vm_fuzz_readers[0]) };

#ifdef VM_FUZZ_VERBOSE
static int vm_fuzz_verbose; /* replay -v: status and message of every file */
#endif

/* A broken contract is a crash, so that libFuzzer keeps the input. */
#define VM_FUZZ_REQUIRE(cond, what)                                                  \
  do {                                                                               \
    if (!(cond)) {                                                                   \
      fprintf(stderr, "fuzz: %s:%d: contract broken: %s (%s)\n", __FILE__, __LINE__, \
              what, #cond);                                                          \
      abort();                                                                       \
    }                                                                                \
  } while (0)

static inline void vm_fuzz_discard_log(void *user, int level, const char *msg) {
  (void)user;
  (void)level;
  (void)msg;
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
  VM_FUZZ_REQUIRE(vm_surface_register_formats(ctx) == VM_OK, "register surface formats");
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
