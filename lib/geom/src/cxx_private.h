/* lib/geom/src/cxx_private.h: the one try/catch pair every extern "C" body
 * of the C++ adapters (*_openmesh.cpp, *_cgal.cpp) sits in: std::bad_alloc
 * becomes VM_ERR_NOMEM, any other exception VM_ERR_BACKEND with its text
 * on the context. C++ only; included by the adapters, never by a header. */
#ifndef VARMESH_GEOM_CXX_PRIVATE_H
#define VARMESH_GEOM_CXX_PRIVATE_H

#ifndef __cplusplus
#error "cxx_private.h is for the C++ adapters only"
#endif

#include <exception>
#include <new>

#include "varmesh/ctx.h"

#define VM_CXX_BEGIN try {
#define VM_CXX_END(ctx, where)                                                                     \
  }                                                                                                \
  catch (const std::bad_alloc &) {                                                                 \
    return vm_error((ctx), VM_ERR_NOMEM, "%s: out of memory", (where));                            \
  }                                                                                                \
  catch (const std::exception &e) {                                                                \
    return vm_error((ctx), VM_ERR_BACKEND, "%s: %s", (where), e.what());                           \
  }                                                                                                \
  catch (...) {                                                                                    \
    return vm_error((ctx), VM_ERR_BACKEND, "%s: unknown exception", (where));                      \
  }

#endif
