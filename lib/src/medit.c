/* lib/src/medit.c: MEDIT .mesh reader and writer. */
#include "formats_private.h"

int vm_read_medit(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  (void)buf; (void)len; (void)out;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: MEDIT .mesh reader not written yet", name);
}
int vm_write_medit(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)m; (void)o;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: MEDIT .mesh writer not written yet", path);
}
