/* lib/internal/inline.h: VM_INLINE, a static function the compiler must
 * inline (so that a constant argument specializes it: a dimension, an
 * order, a vertex count), shared by the project's libraries. */
#ifndef VARMESH_INTERNAL_INLINE_H
#define VARMESH_INTERNAL_INLINE_H

#if defined(__GNUC__)
#define VM_INLINE static inline __attribute__((always_inline))
#else
#define VM_INLINE static inline
#endif

#endif
