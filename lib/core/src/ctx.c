/* lib/core/src/ctx.c: context: error text, logging, counted allocator with
 * failure injection, thread count, interrupt flag, seeded RNG. */
#include "varmesh/ctx.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__unix__) || defined(__APPLE__)
#include <sys/resource.h>
#endif

#include "ctx_private.h"

int vm_ctx_create(vm_ctx **out) {
  if (!out) return VM_ERR_ARG;
  *out = NULL;
  vm_ctx *c = calloc(1, sizeof *c);
  if (!c) return VM_ERR_NOMEM;
  vm_ctx_seed(c, 0x9e3779b97f4a7c15ULL);
  *out = c;
  return VM_OK;
}

void vm_ctx_destroy(vm_ctx **p) {
  if (!p || !*p) return;
  vm_ctx *c = *p;
  free(c);
  *p = NULL;
}

int vm_error(vm_ctx *ctx, int status, const char *fmt, ...) {
  if (!ctx) return status;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(ctx->err, sizeof ctx->err, fmt, ap);
  va_end(ap);
  /* one line: fold any newline a caller let through */
  for (char *s = ctx->err; *s; s++)
    if (*s == '\n' || *s == '\r') *s = ' ';
  ctx->status = status;
  if (ctx->log && status < 0) ctx->log(ctx->log_user, VM_LOG_ERROR, ctx->err);
  return status;
}

const char *vm_ctx_error(const vm_ctx *ctx) { return ctx ? ctx->err : ""; }
int vm_ctx_status(const vm_ctx *ctx) { return ctx ? ctx->status : VM_OK; }
void vm_ctx_clear_error(vm_ctx *ctx) {
  if (!ctx) return;
  ctx->err[0] = 0;
  ctx->status = VM_OK;
}

void vm_log(vm_ctx *ctx, int level, const char *fmt, ...) {
  if (!ctx || !ctx->log) return;
  char buf[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  ctx->log(ctx->log_user, level, buf);
}

void vm_ctx_set_log(vm_ctx *ctx, vm_log_fn fn, void *user) {
  if (!ctx) return;
  ctx->log = fn;
  ctx->log_user = user;
}

/* Every block carries a 16-byte header with its size, so realloc/free keep
 * the live count exact and the failure injection sees every call. */
typedef struct {
  size_t size;
  size_t pad;
} vm_blockhdr;

static int alloc_should_fail(vm_ctx *ctx) {
  ctx->alloc_count++;
  if (ctx->alloc_fail_at > 0 && ctx->alloc_count == ctx->alloc_fail_at) return 1;
  return 0;
}

void *vm_malloc(vm_ctx *ctx, size_t size) {
  if (size > SIZE_MAX - sizeof(vm_blockhdr)) goto fail;
  if (ctx && alloc_should_fail(ctx)) goto fail;
  vm_blockhdr *h = malloc(sizeof *h + (size ? size : 1));
  if (!h) goto fail;
  h->size = size;
  if (ctx) ctx->alloc_live++;
  return h + 1;
fail:
  if (ctx) vm_error(ctx, VM_ERR_NOMEM, "out of memory (requested %zu bytes)", size);
  return NULL;
}

void *vm_alloc_array(vm_ctx *ctx, size_t n, size_t size) {
  if (size && n > SIZE_MAX / size) {
    if (ctx) vm_error(ctx, VM_ERR_NOMEM, "out of memory (array of %zu x %zu bytes)", n, size);
    return NULL;
  }
  return vm_malloc(ctx, n * size);
}

void *vm_calloc(vm_ctx *ctx, size_t n, size_t size) {
  void *p = vm_alloc_array(ctx, n, size);
  if (p) memset(p, 0, n * size);
  return p;
}

void *vm_realloc(vm_ctx *ctx, void *p, size_t size) {
  if (!p) return vm_malloc(ctx, size);
  if (size > SIZE_MAX - sizeof(vm_blockhdr)) goto fail;
  if (ctx && alloc_should_fail(ctx)) goto fail;
  vm_blockhdr *h = (vm_blockhdr *)p - 1;
  vm_blockhdr *n = realloc(h, sizeof *n + (size ? size : 1));
  if (!n) goto fail;
  n->size = size;
  return n + 1;
fail:
  if (ctx) vm_error(ctx, VM_ERR_NOMEM, "out of memory (requested %zu bytes)", size);
  return NULL;
}

void vm_free(vm_ctx *ctx, void *p) {
  if (!p) return;
  if (ctx) ctx->alloc_live--;
  free((vm_blockhdr *)p - 1);
}

char *vm_strdup(vm_ctx *ctx, const char *s) {
  size_t n = strlen(s) + 1;
  char *d = vm_malloc(ctx, n);
  if (d) memcpy(d, s, n);
  return d;
}

void vm_ctx_set_alloc_fail(vm_ctx *ctx, long n) {
  if (!ctx) return;
  ctx->alloc_fail_at = n > 0 ? ctx->alloc_count + n : 0;
}
long vm_ctx_alloc_count(const vm_ctx *ctx) { return ctx ? ctx->alloc_count : 0; }
long vm_ctx_alloc_live(const vm_ctx *ctx) { return ctx ? ctx->alloc_live : 0; }

void vm_ctx_set_threads(vm_ctx *ctx, int nthreads) {
  if (ctx) ctx->nthreads = nthreads > 0 ? nthreads : 0;
}
int vm_ctx_threads(const vm_ctx *ctx) { return ctx ? ctx->nthreads : 0; }

void vm_ctx_set_interrupt(vm_ctx *ctx, volatile int *flag) {
  if (ctx) ctx->interrupt = flag;
}
int vm_ctx_interrupted(const vm_ctx *ctx) { return ctx && ctx->interrupt && *ctx->interrupt; }

static uint64_t splitmix64(uint64_t *x) {
  uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

void vm_ctx_seed(vm_ctx *ctx, uint64_t seed) {
  if (!ctx) return;
  uint64_t x = seed;
  for (int i = 0; i < 4; i++) ctx->rng[i] = splitmix64(&x);
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t vm_ctx_rand_u64(vm_ctx *ctx) {
  uint64_t *s = ctx->rng;
  uint64_t r = rotl(s[1] * 5, 7) * 9;
  uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  return r;
}

double vm_ctx_rand_unit(vm_ctx *ctx) { return (double)(vm_ctx_rand_u64(ctx) >> 11) * 0x1.0p-53; }

double vm_peak_memory_mb(void) {
#if defined(__unix__) || defined(__APPLE__)
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru)) return 0;
#ifdef __APPLE__
  return (double)ru.ru_maxrss / (1024.0 * 1024.0); /* bytes there */
#else
  return (double)ru.ru_maxrss / 1024.0; /* KiB */
#endif
#else
  return 0;
#endif
}

const char *vm_version(void) { return VM_VERSION_STRING; }
