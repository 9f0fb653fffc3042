/* lib/io/src/surface_text_private.h: helpers shared by the surface format
 * readers and writers (text scanning, polygon soup to elements, writer
 * checks, byte order) and the per-format entry points. */
#ifndef VARMESH_SURFACE_TEXT_PRIVATE_H
#define VARMESH_SURFACE_TEXT_PRIVATE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "varmesh/io.h"

/* A text buffer scanned token by token with line tracking. The buffer need
 * not be NUL-terminated. If `comment` is nonzero, a token starting with it
 * ends the line. */
typedef struct vm_surf_text {
  vm_ctx *ctx;
  const char *name;
  const char *p, *end;
  int64_t line; /* 1-based line of p */
  char comment;
} vm_surf_text;

void vm_surf_text_init(vm_surf_text *t, vm_ctx *ctx, const char *name, const uint8_t *buf,
                       size_t len, char comment);
/* Next token on the current line: 1 and (s, n), or 0 at the end of the line. */
int vm_surf_tok_line(vm_surf_text *t, const char **s, size_t *n);
/* Next token, crossing lines: 1 and (s, n), or 0 at the end of the buffer. */
int vm_surf_tok(vm_surf_text *t, const char **s, size_t *n);
/* Move past the end of the current line; returns 0 at the end of the buffer. */
int vm_surf_next_line(vm_surf_text *t);
/* Record "name: line N: what" as VM_ERR_FORMAT and return it. */
int vm_surf_fail(vm_surf_text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Token helpers: case-insensitive equality; numbers must fill the token.
 * parse_double accepts nan/inf (callers decide); both return 0 or -1. */
int vm_surf_tok_is(const char *s, size_t n, const char *word);
int vm_surf_parse_double(const char *s, size_t n, double *v);
int vm_surf_parse_int(const char *s, size_t n, int64_t *v);
/* Print a token for a message: at most 32 characters, "..." if cut. */
const char *vm_surf_tok_show(const char *s, size_t n, char buf[40]);

/* A polygon soup collected while parsing: vertex indices are 0-based but
 * unchecked until vm_surf_polys_build; `rec` says where each polygon came
 * from (a line number, or a face number for binary input). */
typedef struct vm_surf_polys {
  vm_ctx *ctx;
  int64_t n, cap;
  int64_t *off; /* n + 1 */
  int64_t *rec; /* n */
  int64_t *idx;
  int64_t icap;
} vm_surf_polys;

void vm_surf_polys_init(vm_surf_polys *P, vm_ctx *ctx);
void vm_surf_polys_free(vm_surf_polys *P);
int vm_surf_polys_add(vm_surf_polys *P, const int64_t *v, int64_t k, int64_t rec);
/* Check every index against m->nv and append the polygons to m as TRI,
 * QUAD, or ear-clipped triangles. rec_kind is "line" or "face" and base the
 * file's first vertex index (for messages). Warns about split polygons. */
int vm_surf_polys_build(vm_surf_polys *P, const char *name, const char *rec_kind, int base,
                        vm_mesh *m);
/* Warn about faces with a repeated vertex and edges shared by more than two
 * faces (does not change the mesh). */
int vm_surf_report_topology(vm_ctx *ctx, const char *name, const vm_mesh *m);

/* A text surface reader around its parser: refuses an empty buffer, runs
 * parse on the buffer (comment character `comment`), reports the topology,
 * and returns the mesh in *out or destroys it on failure. */
typedef int (*vm_surf_parse_fn)(vm_surf_text *t, vm_mesh *m, vm_surf_polys *P);
int vm_surf_read_text(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, char comment,
                      vm_surf_parse_fn parse, vm_mesh **out);

/* Writers: count what can be written and warn about what cannot. On success
 * *lossy is set to 1 if anything is lost; n2d receives the number of
 * triangles and quads. Returns a negative status if nothing can be written. */
int vm_surf_write_prepare(vm_ctx *ctx, const vm_mesh *m, const char *path, const char *fmt,
                          int split_quads, int *lossy, int64_t *ntri, int64_t *nquad);
/* Finish an output file: check the stream, commit or abort. Returns
 * VM_WARN_LOSSY if lossy and all went well. */
int vm_surf_write_finish(vm_ctx *ctx, vm_outfile **f, const char *path, int lossy);

/* Little/big-endian scalars. */
static inline uint32_t vm_surf_le32(const uint8_t *p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline void vm_surf_put_le32(uint8_t *p, uint32_t v) {
  p[0] = (uint8_t)v;
  p[1] = (uint8_t)(v >> 8);
  p[2] = (uint8_t)(v >> 16);
  p[3] = (uint8_t)(v >> 24);
}

#endif
