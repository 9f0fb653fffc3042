/* lib/io/src/formats_private.h: every format's reader and writer, for the
 * table in io.c. */
#ifndef VARMESH_FORMATS_PRIVATE_H
#define VARMESH_FORMATS_PRIVATE_H

#include "varmesh/io.h"

/* A reader's error message starts with the file's name: prefix the
 * context's message with "name: " unless it already does. Returns st. */
int vm_error_name_prefix(vm_ctx *ctx, int st, const char *name);

/* Atomic output of a directory tree (a format whose output is a directory).
 * vm_outdir_open makes an empty temporary directory beside `path`
 * ("<parent>/.<name>.tmp.<pid>.<n>"; path may not be a file); the writer
 * fills the directory vm_outdir_tmp names; commit puts it at `path`,
 * replacing what was there (the old tree is moved aside, then removed),
 * and abort (or a failed commit) removes the temporary tree. Between the
 * two renames of a commit that replaces a tree, `path` is briefly absent. */
typedef struct vm_outdir vm_outdir;
int vm_outdir_open(vm_ctx *ctx, const char *path, vm_outdir **out);
const char *vm_outdir_tmp(const vm_outdir *d);
int vm_outdir_commit(vm_outdir **d);
void vm_outdir_abort(vm_outdir **d);
/* Remove a file or a directory tree (symbolic links are removed, never
 * followed); 0 if it is gone, -1 with errno if something stayed. */
int vm_rmtree(const char *path);

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
int vm_write_foam(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o);

/* A temporary file written outside vm_outfile (CGNS): registered while it
 * exists so that vm_io_remove_temporaries finds it. path stays valid until
 * unregistered. */
void vm_io_tmp_register(char *path);
/* The most data arrays a reader stores as fields (each one costs a search
 * of the others, so many small ones would take quadratic time). */
#define VM_IO_MAX_ARRAYS 1024
/* A temporary name beside path, "<dir>/<pre><base><tag><pid>.<n>", short
 * ("<dir>/.vm<tag><pid>.<n>") where that would exceed the folder's
 * NAME_MAX; vm_malloc'd, NULL if out of memory. */
char *vm_io_temp_name(vm_ctx *ctx, const char *path, const char *pre, const char *tag);
void vm_io_tmp_unregister(const char *path);

/* The list in a writer's one warning line of what its format cannot
 * store: items appended as "title 'a', 'b'; title2 'c'" (a new group
 * starts with its title, if not NULL), as many as fit, the rest counted
 * (vm_lost_text then ends it with " and N more"). */
typedef struct {
  char buf[900];
  size_t n;
  int group, items, more;
} vm_lost_list;
void vm_lost_init(vm_lost_list *l);
void vm_lost_add(vm_lost_list *l, int group, const char *title, const char *item);
/* The list's text (its items, then " and N more" if some did not fit). */
const char *vm_lost_text(vm_lost_list *l);

#endif
