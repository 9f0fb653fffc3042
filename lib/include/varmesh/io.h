/* varmesh/io.h: reading and writing meshes in every supported format,
 * dispatch by extension, and atomic (temporary file + rename) output. */
#ifndef VARMESH_IO_H
#define VARMESH_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_FMT_AUTO = 0,  /* from the file name's extension */
  VM_FMT_VMSH,      /* .vmsh  binary (docs/vmsh.md) */
  VM_FMT_VMSH_TEXT, /* .vmsht text variant */
  VM_FMT_VTK,       /* .vtk   legacy VTK, ASCII or binary */
  VM_FMT_VTU,       /* .vtu   VTK XML unstructured grid */
  VM_FMT_MSH,       /* .msh   Gmsh 4.1 (read 2.2 too) */
  VM_FMT_MEDIT,     /* .mesh  MEDIT / mmg / TetGen */
  VM_FMT_STL,       /* .stl   through the surface adapter */
  VM_FMT_OBJ,
  VM_FMT_OFF,
  VM_FMT_PLY,
  VM_FMT_COUNT
} vm_format;

/* Format from a path's extension (case-insensitive); VM_FMT_AUTO if unknown. */
int vm_format_from_path(const char *path);
/* Format from a name ("vtk", "vtu", "msh", "mesh", "vmsh", "vmsht", "stl", ...). */
int vm_format_from_name(const char *name);
const char *vm_format_name(int format);

typedef struct vm_write_opts {
  int binary;      /* VTK legacy, .msh, STL: 1 binary, 0 ASCII (default 0 for
                      VTK/.msh/STL; VTU always writes base64 binary) */
  int msh_version; /* 41 (default) or 22 */
} vm_write_opts;

/* Default options: ASCII, msh 4.1. */
vm_write_opts vm_write_opts_default(void);

/* Reader from memory: `name` is used only in error messages. */
typedef int (*vm_reader_fn)(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                            vm_mesh **out);
/* Writer to a path (the writer must use vm_outfile for atomicity). */
typedef int (*vm_writer_fn)(vm_ctx *ctx, const vm_mesh *m, const char *path,
                            const vm_write_opts *opts);

/* Install a reader/writer for a format on this context (used by the surface
 * adapter for STL/OBJ/OFF/PLY). Either may be NULL. */
int vm_ctx_set_format_handler(vm_ctx *ctx, int format, vm_reader_fn rd, vm_writer_fn wr);

/* Read a mesh. format VM_FMT_AUTO guesses from the extension. Files larger
 * than the host can hold are refused; every count is checked against the
 * file size before allocating. Errors are one line: "path: record: what". */
int vm_mesh_read(vm_ctx *ctx, const char *path, int format, vm_mesh **out);
/* The same from a buffer (fuzzing, tests). */
int vm_mesh_read_memory(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                        int format, vm_mesh **out);
/* Write a mesh atomically: either the complete file appears at `path` or
 * nothing there changes. Returns VM_WARN_LOSSY (> 0) if the format could not
 * carry something (each loss is logged at VM_LOG_WARN). opts may be NULL. */
int vm_mesh_write(vm_ctx *ctx, const vm_mesh *m, const char *path, int format,
                  const vm_write_opts *opts);

/* Read a whole file into a new buffer (freed with vm_free). */
int vm_read_file(vm_ctx *ctx, const char *path, uint8_t **buf, size_t *len);

/* Atomic output: writes go to "<path>.tmp.<pid>.<n>", commit renames it over
 * path; abort (or a failed commit) removes the temporary file. */
typedef struct vm_outfile vm_outfile;
int vm_outfile_open(vm_ctx *ctx, const char *path, vm_outfile **out);
FILE *vm_outfile_fp(vm_outfile *f);
int vm_outfile_commit(vm_outfile **f);
void vm_outfile_abort(vm_outfile **f);

#ifdef __cplusplus
}
#endif
#endif
