/* lib/io/src/formats_private.h: every format's reader and writer, for the
 * table in io.c. */
#ifndef VARMESH_FORMATS_PRIVATE_H
#define VARMESH_FORMATS_PRIVATE_H

#include "varmesh/io.h"

/* A reader's error message starts with the file's name: prefix the
 * context's message with "name: " unless it already does. Returns st. */
int vm_error_name_prefix(vm_ctx *ctx, int st, const char *name);

int vm_read_vmsh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_vmsh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_write_vmsh_text(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_vtk(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_vtk(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_vtu(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_vtu(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_msh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_msh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_medit(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_medit(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_stl(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_stl(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_obj(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_obj(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_off(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_off(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_ply(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_ply(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_su2(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_su2(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);
int vm_read_cgns(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out);
int vm_write_cgns(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);

#endif
