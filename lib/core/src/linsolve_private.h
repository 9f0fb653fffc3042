/* lib/core/src/linsolve_private.h: preconditioner operation table and the
 * deterministic vector kernels shared by pcg.c, amg.c and the minimizers. */
#ifndef VARMESH_LINSOLVE_PRIVATE_H
#define VARMESH_LINSOLVE_PRIVATE_H

#include <stdint.h>

#include "varmesh/linsolve.h"

/* One implementation of the preconditioner family. */
typedef struct vm_precond_ops {
  const char *name;
  int (*setup)(vm_precond *p, const vm_csr *A);
  int (*update)(vm_precond *p, const vm_csr *A);
  void (*apply)(vm_precond *p, const double *r, double *z);
  void (*info)(const vm_precond *p, vm_precond_info *info);
  void (*destroy)(vm_precond *p); /* frees p->impl only */
} vm_precond_ops;

struct vm_precond {
  vm_ctx *ctx;
  vm_precond_kind kind;
  const vm_precond_ops *ops;
  vm_amg_options amg;
  void *impl;
};

extern const vm_precond_ops vm_precond_amg_ops;

/* Threads to use for OpenMP regions: the context's count or the default. */
int vm_nthreads(const vm_ctx *ctx);

/* Below this length vector kernels run on one thread (no fork overhead). */
#define VM_PAR_MIN 8192

/* Below this many rows a sparse matrix-vector product runs on one thread.
 * The threads wait passively (apps/cli.c), so a parallel region costs
 * their wake-up, tens of microseconds, more than a product of a few
 * thousand rows: at 1,024 rows the coarse levels of the AMG cycles made
 * the prism stage's springback on the demo aircraft slower on two threads
 * than on one (7.2 to 8.0 s against 7.1 s, a sixth of the samples in the
 * kernel's scheduler); at 16,384 it takes 4.9 to 5.0 s. Rows are
 * independent, so the threshold changes no result. */
#define VM_PAR_MIN_MV 16384

/* Inner product summed in fixed blocks whose size depends only on n, then
 * the block sums in order: the same bits for any thread count. */
double vm_dot(const vm_ctx *ctx, int64_t n, const double *a, const double *b);

#endif
