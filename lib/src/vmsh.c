/* lib/src/vmsh.c: the .vmsh binary and .vmsht text formats (docs/vmsh.md). */
#include "formats_private.h"

int vm_read_vmsh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  (void)buf; (void)len; (void)out;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: .vmsh reader not written yet", name);
}
int vm_write_vmsh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)m; (void)o;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: .vmsh writer not written yet", path);
}
int vm_write_vmsh_text(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)m; (void)o;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: .vmsht writer not written yet", path);
}
