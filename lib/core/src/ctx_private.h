/* lib/core/src/ctx_private.h: the context's layout, for lib/ only. */
#ifndef VARMESH_CTX_PRIVATE_H
#define VARMESH_CTX_PRIVATE_H

#include <stdint.h>

#include "varmesh/ctx.h"

#ifndef VM_VERSION_STRING
#define VM_VERSION_STRING "0.1.0"
#endif

struct vm_ctx {
  char err[1024];
  int status;
  vm_log_fn log;
  void *log_user;
  long alloc_count;
  long alloc_fail_at;
  long alloc_live;
  int nthreads;
  volatile int *interrupt;
  uint64_t rng[4];
};

#endif
