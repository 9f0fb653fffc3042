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

/* Inner product summed in fixed blocks whose size depends only on n, then
 * the block sums in order: the same bits for any thread count. */
double vm_dot(const vm_ctx *ctx, int64_t n, const double *a, const double *b);

#endif
