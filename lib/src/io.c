/* lib/src/io.c: format dispatch by extension, whole-file reading with size
 * checks, and atomic output through a temporary file and rename. */
#include "varmesh/io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ctx_private.h"
#include "formats_private.h"

static const struct {
  const char *ext;
  int fmt;
} ext_tab[] = {{"vmsh", VM_FMT_VMSH}, {"vmsht", VM_FMT_VMSH_TEXT}, {"vtk", VM_FMT_VTK},
               {"vtu", VM_FMT_VTU},   {"msh", VM_FMT_MSH},        {"mesh", VM_FMT_MEDIT},
               {"stl", VM_FMT_STL},   {"obj", VM_FMT_OBJ},        {"off", VM_FMT_OFF},
               {"ply", VM_FMT_PLY}};

static const char *fmt_names[VM_FMT_COUNT] = {"auto", "vmsh", "vmsht", "vtk", "vtu", "msh",
                                              "mesh", "stl",  "obj",   "off", "ply"};

int vm_format_from_name(const char *name) {
  for (size_t i = 0; i < sizeof ext_tab / sizeof ext_tab[0]; i++)
    if (!strcasecmp(name, ext_tab[i].ext)) return ext_tab[i].fmt;
  if (!strcasecmp(name, "medit")) return VM_FMT_MEDIT;
  if (!strcasecmp(name, "gmsh")) return VM_FMT_MSH;
  return VM_FMT_AUTO;
}

int vm_format_from_path(const char *path) {
  const char *dot = strrchr(path, '.');
  const char *slash = strrchr(path, '/');
  if (!dot || (slash && dot < slash)) return VM_FMT_AUTO;
  return vm_format_from_name(dot + 1);
}

const char *vm_format_name(int f) { return f >= 0 && f < VM_FMT_COUNT ? fmt_names[f] : "?"; }

vm_write_opts vm_write_opts_default(void) {
  vm_write_opts o = {0, 41};
  return o;
}

int vm_ctx_set_format_handler(vm_ctx *ctx, int format, vm_reader_fn rd, vm_writer_fn wr) {
  if (!ctx || format <= VM_FMT_AUTO || format >= VM_FMT_COUNT)
    return vm_error(ctx, VM_ERR_ARG, "bad format id %d", format);
  ctx->formats[format].read = rd;
  ctx->formats[format].write = wr;
  return VM_OK;
}

static void builtin(int fmt, vm_reader_fn *rd, vm_writer_fn *wr) {
  *rd = NULL;
  *wr = NULL;
  switch (fmt) {
  case VM_FMT_VMSH:
    *rd = vm_read_vmsh;
    *wr = vm_write_vmsh;
    break;
  case VM_FMT_VMSH_TEXT:
    *rd = vm_read_vmsh;
    *wr = vm_write_vmsh_text;
    break;
  case VM_FMT_VTK:
    *rd = vm_read_vtk;
    *wr = vm_write_vtk;
    break;
  case VM_FMT_VTU:
    *rd = vm_read_vtu;
    *wr = vm_write_vtu;
    break;
  case VM_FMT_MSH:
    *rd = vm_read_msh;
    *wr = vm_write_msh;
    break;
  case VM_FMT_MEDIT:
    *rd = vm_read_medit;
    *wr = vm_write_medit;
    break;
  default:
    break;
  }
}

static void handlers(vm_ctx *ctx, int fmt, vm_reader_fn *rd, vm_writer_fn *wr) {
  builtin(fmt, rd, wr);
  if (ctx && fmt > 0 && fmt < VM_FMT_COUNT) {
    if (ctx->formats[fmt].read) *rd = ctx->formats[fmt].read;
    if (ctx->formats[fmt].write) *wr = ctx->formats[fmt].write;
  }
}

int vm_read_file(vm_ctx *ctx, const char *path, uint8_t **buf, size_t *len) {
  *buf = NULL;
  *len = 0;
  FILE *f = fopen(path, "rb");
  if (!f) return vm_error(ctx, VM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
  struct stat st;
  if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
    fclose(f);
    return vm_error(ctx, VM_ERR_IO, "%s: not a regular file", path);
  }
  if ((uint64_t)st.st_size > (uint64_t)SIZE_MAX / 2) {
    fclose(f);
    return vm_error(ctx, VM_ERR_IO, "%s: file too large", path);
  }
  size_t n = (size_t)st.st_size;
  uint8_t *b = vm_malloc(ctx, n + 1);
  if (!b) {
    fclose(f);
    return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory reading %zu bytes", path, n);
  }
  size_t got = fread(b, 1, n, f);
  int bad = ferror(f);
  fclose(f);
  if (bad || got != n) {
    vm_free(ctx, b);
    return vm_error(ctx, VM_ERR_IO, "%s: read error", path);
  }
  b[n] = 0; /* text readers may rely on a terminating NUL */
  *buf = b;
  *len = n;
  return VM_OK;
}

int vm_mesh_read_memory(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                        int format, vm_mesh **out) {
  *out = NULL;
  if (format == VM_FMT_AUTO) format = vm_format_from_path(name);
  if (format == VM_FMT_AUTO)
    return vm_error(ctx, VM_ERR_ARG, "%s: cannot tell the format from the extension", name);
  vm_reader_fn rd;
  vm_writer_fn wr;
  handlers(ctx, format, &rd, &wr);
  if (!rd)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: no reader for format '%s' in this program",
                    name, vm_format_name(format));
  int st = rd(ctx, name, buf, len, out);
  if (st < 0) {
    vm_mesh_destroy(out);
    return st;
  }
  st = vm_mesh_check(*out);
  if (st < 0) {
    /* prefix the file name to the invariant message */
    char msg[900];
    snprintf(msg, sizeof msg, "%s", vm_ctx_error(ctx));
    vm_mesh_destroy(out);
    return vm_error(ctx, st, "%s: %s", name, msg);
  }
  return VM_OK;
}

int vm_mesh_read(vm_ctx *ctx, const char *path, int format, vm_mesh **out) {
  *out = NULL;
  if (format == VM_FMT_AUTO) format = vm_format_from_path(path);
  if (format == VM_FMT_AUTO)
    return vm_error(ctx, VM_ERR_ARG, "%s: cannot tell the format from the extension", path);
  uint8_t *buf;
  size_t len;
  int st = vm_read_file(ctx, path, &buf, &len);
  if (st) return st;
  st = vm_mesh_read_memory(ctx, path, buf, len, format, out);
  vm_free(ctx, buf);
  return st;
}

int vm_mesh_write(vm_ctx *ctx, const vm_mesh *m, const char *path, int format,
                  const vm_write_opts *opts) {
  if (format == VM_FMT_AUTO) format = vm_format_from_path(path);
  if (format == VM_FMT_AUTO)
    return vm_error(ctx, VM_ERR_ARG, "%s: cannot tell the format from the extension", path);
  vm_reader_fn rd;
  vm_writer_fn wr;
  handlers(ctx, format, &rd, &wr);
  if (!wr)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: no writer for format '%s' in this program",
                    path, vm_format_name(format));
  vm_write_opts def = vm_write_opts_default();
  int st = vm_mesh_check(m);
  if (st < 0) return st;
  return wr(ctx, m, path, opts ? opts : &def);
}

struct vm_outfile {
  vm_ctx *ctx;
  FILE *fp;
  char *path;
  char *tmp;
};

int vm_outfile_open(vm_ctx *ctx, const char *path, vm_outfile **out) {
  *out = NULL;
  static const char suffix[] = ".tmp.";
  size_t n = strlen(path) + sizeof suffix + 48;
  vm_outfile *f = vm_calloc(ctx, 1, sizeof *f);
  char *tmp = vm_malloc(ctx, n);
  char *p = vm_strdup(ctx, path);
  if (!f || !tmp || !p) {
    vm_free(ctx, f);
    vm_free(ctx, tmp);
    vm_free(ctx, p);
    return VM_ERR_NOMEM;
  }
  /* pid + a counter keep concurrent writers of the same path apart */
  static _Thread_local unsigned long counter;
  snprintf(tmp, n, "%s%s%ld.%lu", path, suffix, (long)getpid(), ++counter);
  f->fp = fopen(tmp, "wb");
  if (!f->fp) {
    int e = errno;
    vm_free(ctx, f);
    vm_free(ctx, tmp);
    vm_free(ctx, p);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot create: %s", path, strerror(e));
  }
  f->ctx = ctx;
  f->tmp = tmp;
  f->path = p;
  *out = f;
  return VM_OK;
}

FILE *vm_outfile_fp(vm_outfile *f) { return f->fp; }

static void outfile_free(vm_outfile *f) {
  vm_ctx *ctx = f->ctx;
  vm_free(ctx, f->tmp);
  vm_free(ctx, f->path);
  vm_free(ctx, f);
}

void vm_outfile_abort(vm_outfile **pf) {
  if (!pf || !*pf) return;
  vm_outfile *f = *pf;
  if (f->fp) fclose(f->fp);
  remove(f->tmp);
  outfile_free(f);
  *pf = NULL;
}

int vm_outfile_commit(vm_outfile **pf) {
  vm_outfile *f = *pf;
  vm_ctx *ctx = f->ctx;
  int bad = fflush(f->fp) != 0 || ferror(f->fp);
  bad |= fclose(f->fp) != 0;
  f->fp = NULL;
  if (bad) {
    int st = vm_error(ctx, VM_ERR_IO, "%s: write failed: %s", f->path, strerror(errno));
    vm_outfile_abort(pf);
    return st;
  }
  if (rename(f->tmp, f->path) != 0) {
    int st = vm_error(ctx, VM_ERR_IO, "%s: cannot rename into place: %s", f->path,
                      strerror(errno));
    vm_outfile_abort(pf);
    return st;
  }
  outfile_free(f);
  *pf = NULL;
  return VM_OK;
}

int vm_error_name_prefix(vm_ctx *ctx, int st, const char *name) {
  const char *e = vm_ctx_error(ctx);
  size_t nl = strlen(name);
  if (strncmp(e, name, nl) || e[nl] != ':') {
    char msg[900];
    snprintf(msg, sizeof msg, "%s", e);
    vm_error(ctx, st, "%s: %s", name, msg);
  }
  return st;
}
