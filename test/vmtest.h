/* test/vmtest.h: a tiny assertion harness: CHECK(cond, ...) counts and
 * reports failures; vmtest_end() prints a summary and returns the exit code. */
#ifndef VMTEST_H
#define VMTEST_H

#include <math.h>
#include <stdio.h>

static int vmtest_checks, vmtest_failures;

#define CHECK(cond, ...)                                                                           \
  do {                                                                                             \
    vmtest_checks++;                                                                               \
    if (!(cond)) {                                                                                 \
      vmtest_failures++;                                                                           \
      fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond);                     \
      fprintf(stderr, __VA_ARGS__);                                                                \
      fputc('\n', stderr);                                                                         \
    }                                                                                              \
  } while (0)

#define CHECK_NEAR(a, b, tol, what)                                                                \
  do {                                                                                             \
    double vmt_a_ = (a), vmt_b_ = (b);                                                             \
    CHECK(fabs(vmt_a_ - vmt_b_) <= (tol), "%s: %.17g vs %.17g (tol %g)", what, vmt_a_, vmt_b_,     \
          (double)(tol));                                                                          \
  } while (0)

static inline int vmtest_end(const char *name) {
  fprintf(stderr, "%s: %d checks, %d failed\n", name, vmtest_checks, vmtest_failures);
  return vmtest_failures ? 1 : 0;
}

#endif
