/* varmesh/ctx.h: the context every call takes: status codes, error text,
 * log callback, allocator (with test-only failure injection), seeded RNG. */
#ifndef VARMESH_CTX_H
#define VARMESH_CTX_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Status codes: 0 ok, negative error, positive warning. */
enum {
  VM_OK = 0,
  VM_ERR_NOMEM = -1,       /* allocation failed */
  VM_ERR_IO = -2,          /* open/read/write/rename failed */
  VM_ERR_FORMAT = -3,      /* malformed or lying input */
  VM_ERR_ARG = -4,         /* invalid argument from the caller */
  VM_ERR_BACKEND = -5,     /* OpenMesh/CGAL/Embree raised an error */
  VM_ERR_UNSUPPORTED = -6, /* valid request this build/format cannot serve */
  VM_ERR_NUMERIC = -7,     /* NaN/Inf or a breakdown in a numerical kernel */
  VM_ERR_INTERRUPTED = -8, /* stopped by the caller's interrupt flag */
  VM_WARN_MAXITER = 1,     /* stopped at the iteration limit */
  VM_WARN_TIME = 2,        /* stopped at the time limit */
  VM_WARN_INVERTED = 3,    /* finished, but inverted simplices remain */
  VM_WARN_LOSSY = 4        /* output format could not carry everything */
};

/* Log levels passed to the log callback. */
enum { VM_LOG_ERROR = 0, VM_LOG_WARN = 1, VM_LOG_INFO = 2, VM_LOG_DEBUG = 3 };

typedef struct vm_ctx vm_ctx;

typedef void (*vm_log_fn)(void *user, int level, const char *msg);

/* Create a context. out: receives the context (NULL on failure).
 * Returns VM_OK or VM_ERR_NOMEM. Free with vm_ctx_destroy. */
int vm_ctx_create(vm_ctx **out);
/* Destroy *p (may be NULL) and set *p = NULL. */
void vm_ctx_destroy(vm_ctx **p);

/* Record an error (or warning) message: printf-style, one line, no newline.
 * Returns `status` so callers can write `return vm_error(ctx, VM_ERR_IO, ...)`.
 * Messages at VM_LOG_ERROR level also go to the log callback. */
int vm_error(vm_ctx *ctx, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The last error message ("" if none). Valid until the next vm_error. */
const char *vm_ctx_error(const vm_ctx *ctx);
/* The status passed to the last vm_error (VM_OK if none). */
int vm_ctx_status(const vm_ctx *ctx);
void vm_ctx_clear_error(vm_ctx *ctx);

/* Log a message through the callback (no-op without one). */
void vm_log(vm_ctx *ctx, int level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
void vm_ctx_set_log(vm_ctx *ctx, vm_log_fn fn, void *user);

/* Allocator. All allocations in lib/ go through these. vm_calloc and
 * vm_alloc_array check n*size for overflow. Return NULL on failure and
 * record VM_ERR_NOMEM on the context. vm_free(ctx, NULL) is a no-op. */
void *vm_malloc(vm_ctx *ctx, size_t size);
void *vm_calloc(vm_ctx *ctx, size_t n, size_t size);
void *vm_alloc_array(vm_ctx *ctx, size_t n, size_t size);
void *vm_realloc(vm_ctx *ctx, void *p, size_t size);
void vm_free(vm_ctx *ctx, void *p);
char *vm_strdup(vm_ctx *ctx, const char *s);

/* Testing: make the n-th allocation from now fail (n >= 1); 0 disables.
 * vm_ctx_alloc_count returns allocations made so far; vm_ctx_alloc_live
 * the number not yet freed (leak check). */
void vm_ctx_set_alloc_fail(vm_ctx *ctx, long n);
long vm_ctx_alloc_count(const vm_ctx *ctx);
long vm_ctx_alloc_live(const vm_ctx *ctx);

/* Threads for OpenMP regions (0 = library default). Results do not depend
 * on this number: reductions are done in a fixed order. */
void vm_ctx_set_threads(vm_ctx *ctx, int nthreads);
int vm_ctx_threads(const vm_ctx *ctx);

/* Interrupt flag: the caller (e.g. a signal handler) sets *flag nonzero;
 * long-running calls poll it and stop with their best result. */
void vm_ctx_set_interrupt(vm_ctx *ctx, volatile int *flag);
int vm_ctx_interrupted(const vm_ctx *ctx);

/* Seeded pseudo-random numbers (xoshiro256**): same seed, same sequence. */
void vm_ctx_seed(vm_ctx *ctx, uint64_t seed);
uint64_t vm_ctx_rand_u64(vm_ctx *ctx);
/* Uniform in [0, 1). */
double vm_ctx_rand_unit(vm_ctx *ctx);

/* The process's peak resident memory so far, in MiB (getrusage's
 * ru_maxrss: what the caller holds is in it too); 0 where the platform
 * does not give it. For figures, never for decisions. */
double vm_peak_memory_mb(void);

/* Library version string, e.g. "0.1.0". */
const char *vm_version(void);

#ifdef __cplusplus
}
#endif
#endif
