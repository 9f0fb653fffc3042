/* lib/src/formats_private.h: the built-in readers and writers, for io.c. */
#ifndef VARMESH_FORMATS_PRIVATE_H
#define VARMESH_FORMATS_PRIVATE_H

#include "varmesh/io.h"

/* A reader's error message starts with the file's name: prefix the
 * context's message with "name: " unless it already does. Returns st. */
int vm_error_name_prefix(vm_ctx *ctx, int st, const char *name);

int vm_read_vmsh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_vmsh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_write_vmsh_text(vm_ctx *ctx, const vm_mesh *m, const char *path,
                       const vm_write_opts *o);
int vm_read_vtk(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_vtk(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_vtu(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_vtu(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_msh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_msh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_medit(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                  vm_mesh **out);
int vm_write_medit(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);

#endif
