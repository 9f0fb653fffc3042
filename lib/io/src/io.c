/* lib/io/src/io.c: format dispatch by extension, whole-file reading with size
 * checks, and atomic output through a temporary file (or directory) and
 * rename. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "varmesh/io.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "formats_private.h"

/* Every format the project knows, in one table: its id, the names a user
 * may give it (the first is the canonical one, then the file extensions),
 * its reader and its writer (NULL where the format cannot be read or
 * written). The library registers them itself: every program reads and
 * writes every format. */
static const struct vm_format_entry {
  int fmt;
  const char *names[3];
  vm_reader_fn read;
  vm_writer_fn write;
} format_tab[] = {
    {VM_FMT_VMSH, {"vmsh"}, vm_read_vmsh, vm_write_vmsh},
    {VM_FMT_VMSH_TEXT, {"vmsht"}, vm_read_vmsh, vm_write_vmsh_text},
    {VM_FMT_VTK, {"vtk"}, vm_read_vtk, vm_write_vtk},
    {VM_FMT_VTU, {"vtu"}, vm_read_vtu, vm_write_vtu},
    {VM_FMT_MSH, {"msh", "gmsh"}, vm_read_msh, vm_write_msh},
    {VM_FMT_MEDIT, {"mesh", "medit"}, vm_read_medit, vm_write_medit},
    {VM_FMT_STL, {"stl"}, vm_read_stl, vm_write_stl},
    {VM_FMT_OBJ, {"obj"}, vm_read_obj, vm_write_obj},
    {VM_FMT_OFF, {"off"}, vm_read_off, vm_write_off},
    {VM_FMT_PLY, {"ply"}, vm_read_ply, vm_write_ply},
    {VM_FMT_SU2, {"su2"}, vm_read_su2, vm_write_su2},
    {VM_FMT_CGNS, {"cgns"}, vm_read_cgns, vm_write_cgns},
    {VM_FMT_FOAM, {"foam", "openfoam"}, NULL, vm_write_foam},
};
#define NFORMATS (sizeof format_tab / sizeof format_tab[0])

static const struct vm_format_entry *entry(int fmt) {
  for (size_t i = 0; i < NFORMATS; i++)
    if (format_tab[i].fmt == fmt) return &format_tab[i];
  return NULL;
}

int vm_format_from_name(const char *name) {
  for (size_t i = 0; i < NFORMATS; i++)
    for (int k = 0; k < 3 && format_tab[i].names[k]; k++)
      if (!strcasecmp(name, format_tab[i].names[k])) return format_tab[i].fmt;
  return VM_FMT_AUTO;
}

int vm_format_from_path(const char *path) {
  /* trailing slashes ignored: "case.foam/" is a .foam case directory */
  size_t n = strlen(path);
  while (n > 1 && path[n - 1] == '/') n--;
  size_t dot = n;
  while (dot > 0 && path[dot - 1] != '.' && path[dot - 1] != '/') dot--;
  if (dot == 0 || path[dot - 1] != '.' || n - dot >= 16) return VM_FMT_AUTO;
  char ext[16];
  memcpy(ext, path + dot, n - dot);
  ext[n - dot] = 0;
  return vm_format_from_name(ext);
}

const char *vm_format_name(int f) {
  if (f == VM_FMT_AUTO) return "auto";
  const struct vm_format_entry *e = entry(f);
  return e ? e->names[0] : "?";
}

vm_write_opts vm_write_opts_default(void) {
  vm_write_opts o = {0, 41};
  return o;
}

static void handlers(int fmt, vm_reader_fn *rd, vm_writer_fn *wr) {
  const struct vm_format_entry *e = entry(fmt);
  *rd = e ? e->read : NULL;
  *wr = e ? e->write : NULL;
}

int vm_read_file(vm_ctx *ctx, const char *path, uint8_t **buf, size_t *len) {
  *buf = NULL;
  *len = 0;
  /* opened without blocking: a FIFO blocked fopen until a writer came */
  int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return vm_error(ctx, VM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    return vm_error(ctx, VM_ERR_IO, "%s: not a regular file", path);
  }
  int fl = fcntl(fd, F_GETFL);
  if (fl >= 0) fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
  FILE *f = fdopen(fd, "rb");
  if (!f) {
    close(fd);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
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

int vm_mesh_read_memory(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, int format,
                        vm_mesh **out) {
  *out = NULL;
  if (format == VM_FMT_AUTO) format = vm_format_from_path(name);
  if (format == VM_FMT_AUTO)
    return vm_error(ctx, VM_ERR_ARG, "%s: cannot tell the format from the extension", name);
  vm_reader_fn rd;
  vm_writer_fn wr;
  handlers(format, &rd, &wr);
  if (!rd)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: format '%s' cannot be read", name,
                    vm_format_name(format));
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
  vm_reader_fn rd;
  vm_writer_fn wr;
  handlers(format, &rd, &wr);
  if (!rd)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: format '%s' cannot be read", path,
                    vm_format_name(format));
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
  handlers(format, &rd, &wr);
  if (!wr)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: format '%s' cannot be written", path,
                    vm_format_name(format));
  if (!strcmp(path, "-") && (format == VM_FMT_CGNS || format == VM_FMT_FOAM))
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "-: %s cannot be written to standard output",
                    vm_format_name(format));
  vm_write_opts def = vm_write_opts_default();
  int st = vm_mesh_check(m);
  if (st < 0) return st;
  return wr(ctx, m, path, opts ? opts : &def);
}

/* A temporary name in path's folder: "<dir>/<pre><base><tag><pid>.<n>"
 * (pid + a counter keep concurrent writers of the same path apart), or,
 * where that last component would be longer than the folder allows (a
 * legal 245-byte name plus the tag is not), the short "<dir>/.vm<tag><pid>.<n>". */
char *vm_io_temp_name(vm_ctx *ctx, const char *path, const char *pre, const char *tag) {
  static _Thread_local unsigned long counter;
  size_t n = strlen(path) + strlen(pre) + strlen(tag) + 48;
  char *s = vm_malloc(ctx, n);
  if (!s) return NULL;
  const char *slash = strrchr(path, '/');
  int dl = slash ? (int)(slash - path + 1) : 0;
  long name_max = pathconf(".", _PC_NAME_MAX);
  if (dl) {
    char *dir = vm_malloc(ctx, (size_t)dl + 1);
    if (!dir) {
      vm_free(ctx, s);
      return NULL;
    }
    memcpy(dir, path, (size_t)dl);
    dir[dl] = 0;
    name_max = pathconf(dir, _PC_NAME_MAX);
    vm_free(ctx, dir);
  }
  if (name_max <= 0) name_max = 255;
  unsigned long k = ++counter;
  int len = snprintf(s, n, "%.*s%s%s%s%ld.%lu", dl, path, pre, path + dl, tag, (long)getpid(), k);
  if (len - dl > name_max) snprintf(s, n, "%.*s.vm%s%ld.%lu", dl, path, tag, (long)getpid(), k);
  return s;
}

struct vm_outfile {
  vm_ctx *ctx;
  FILE *fp;
  char *path;
  char *tmp;  /* NULL: written straight through (stdout, a device, a FIFO) */
  int mode;   /* the permissions of the file replaced (-1: a new file) */
  int stream; /* fp is stdout: not closed */
};

int vm_outfile_open(vm_ctx *ctx, const char *path, vm_outfile **out) {
  *out = NULL;
  static const char suffix[] = ".tmp.";
  vm_outfile *f = vm_calloc(ctx, 1, sizeof *f);
  char *p = vm_strdup(ctx, path);
  if (!f || !p) {
    vm_free(ctx, f);
    vm_free(ctx, p);
    return VM_ERR_NOMEM;
  }
  f->ctx = ctx;
  f->path = p;
  f->mode = -1;
  /* "-": standard output */
  if (!strcmp(path, "-")) {
    f->fp = stdout;
    f->stream = 1;
    *out = f;
    return VM_OK;
  }
  /* a symbolic link: its target is written (the link stays); a device or
   * a FIFO: written straight through (renaming a file onto it replaced it:
   * /dev/null became a regular file); a file: its permissions kept */
  struct stat st;
  char *target = NULL;
  if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
    target = realpath(path, NULL);
    if (!target) {
      /* a dangling link: its target's name, relative to the link's folder */
      char lk[4096];
      ssize_t k = readlink(path, lk, sizeof lk - 1);
      if (k > 0) {
        lk[k] = 0;
        const char *slash = strrchr(path, '/');
        size_t dl = lk[0] == '/' || !slash ? 0 : (size_t)(slash - path + 1);
        target = malloc(dl + (size_t)k + 1);
        if (target) {
          memcpy(target, path, dl);
          memcpy(target + dl, lk, (size_t)k + 1);
        }
      }
    }
    if (target) {
      char *t = vm_strdup(ctx, target);
      free(target);
      if (!t) {
        vm_free(ctx, p);
        vm_free(ctx, f);
        return VM_ERR_NOMEM;
      }
      vm_free(ctx, f->path);
      f->path = p = t;
    }
  }
  if (stat(p, &st) == 0) {
    if (S_ISDIR(st.st_mode)) {
      vm_free(ctx, p);
      vm_free(ctx, f);
      return vm_error(ctx, VM_ERR_IO, "%s: is a directory", path);
    }
    if (!S_ISREG(st.st_mode)) {
      f->fp = fopen(p, "wb");
      if (!f->fp) {
        int e = errno;
        vm_free(ctx, p);
        vm_free(ctx, f);
        return vm_error(ctx, VM_ERR_IO, "%s: cannot open for writing: %s", path, strerror(e));
      }
      *out = f;
      return VM_OK;
    }
    if (!(st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH))) {
      vm_free(ctx, p);
      vm_free(ctx, f);
      return vm_error(ctx, VM_ERR_IO, "%s: the file is read-only (mode %04o): not replaced", path,
                      (unsigned)(st.st_mode & 07777));
    }
    f->mode = (int)(st.st_mode & 07777);
  }
  char *tmp = vm_io_temp_name(ctx, p, "", suffix);
  if (!tmp) {
    vm_free(ctx, p);
    vm_free(ctx, f);
    return VM_ERR_NOMEM;
  }
  f->fp = fopen(tmp, "wb");
  if (!f->fp) {
    int e = errno;
    vm_free(ctx, f);
    vm_free(ctx, tmp);
    vm_free(ctx, p);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot create: %s", path, strerror(e));
  }
  f->tmp = tmp;
  vm_io_tmp_register(tmp);
  *out = f;
  return VM_OK;
}

FILE *vm_outfile_fp(vm_outfile *f) { return f->fp; }

/* The temporary files being written, for a signal handler to remove
 * (vm_io_remove_temporaries): a fixed table of pointers to their names,
 * claimed and released with atomic operations, read without locks. */
#define TMP_SLOTS 64
static char *tmp_slot[TMP_SLOTS];

void vm_io_tmp_register(char *path) {
  for (int i = 0; i < TMP_SLOTS; i++) {
    char *expect = NULL;
    if (__atomic_compare_exchange_n(&tmp_slot[i], &expect, path, 0, __ATOMIC_SEQ_CST,
                                    __ATOMIC_SEQ_CST))
      return;
  }
}

void vm_io_tmp_unregister(const char *path) {
  for (int i = 0; i < TMP_SLOTS; i++) {
    char *expect = (char *)path;
    __atomic_compare_exchange_n(&tmp_slot[i], &expect, NULL, 0, __ATOMIC_SEQ_CST, __ATOMIC_SEQ_CST);
  }
}

void vm_io_remove_temporaries(void) {
  for (int i = 0; i < TMP_SLOTS; i++) {
    char *p = __atomic_load_n(&tmp_slot[i], __ATOMIC_SEQ_CST);
    if (p) unlink(p);
  }
}

static void outfile_free(vm_outfile *f) {
  vm_ctx *ctx = f->ctx;
  vm_free(ctx, f->tmp);
  vm_free(ctx, f->path);
  vm_free(ctx, f);
}

void vm_outfile_abort(vm_outfile **pf) {
  if (!pf || !*pf) return;
  vm_outfile *f = *pf;
  if (f->fp && !f->stream) fclose(f->fp);
  if (f->tmp) {
    vm_io_tmp_unregister(f->tmp);
    remove(f->tmp);
  }
  outfile_free(f);
  *pf = NULL;
}

int vm_outfile_commit(vm_outfile **pf) {
  vm_outfile *f = *pf;
  vm_ctx *ctx = f->ctx;
  int bad = fflush(f->fp) != 0 || ferror(f->fp);
  if (!f->stream) bad |= fclose(f->fp) != 0;
  f->fp = NULL;
  if (bad) {
    int st = vm_error(ctx, VM_ERR_IO, "%s: write failed: %s", f->path, strerror(errno));
    vm_outfile_abort(pf);
    return st;
  }
  if (!f->tmp) { /* written straight through */
    outfile_free(f);
    *pf = NULL;
    return VM_OK;
  }
  if (f->mode >= 0) chmod(f->tmp, (mode_t)f->mode);
  if (rename(f->tmp, f->path) != 0) {
    int st = vm_error(ctx, VM_ERR_IO, "%s: cannot rename into place: %s", f->path, strerror(errno));
    vm_outfile_abort(pf);
    return st;
  }
  vm_io_tmp_unregister(f->tmp);
  outfile_free(f);
  *pf = NULL;
  return VM_OK;
}

struct vm_outdir {
  vm_ctx *ctx;
  char *path, *tmp;
};

/* "<dir>/.<base><tag><pid>.<n>" beside path (path without trailing '/') */
static char *beside(vm_ctx *ctx, const char *path, const char *tag) {
  return vm_io_temp_name(ctx, path, ".", tag);
}

/* Remove `name` in the directory dfd, descending through directories
 * without following links. */
static int rm_at(int dfd, const char *name) {
  struct stat st;
  if (fstatat(dfd, name, &st, AT_SYMLINK_NOFOLLOW) != 0) return errno == ENOENT ? 0 : -1;
  if (!S_ISDIR(st.st_mode)) return unlinkat(dfd, name, 0);
  int fd = openat(dfd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW);
  if (fd < 0) return -1;
  DIR *d = fdopendir(fd);
  if (!d) {
    close(fd);
    return -1;
  }
  int bad = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) bad |= rm_at(fd, e->d_name);
  closedir(d);
  return unlinkat(dfd, name, AT_REMOVEDIR) || bad ? -1 : 0;
}

int vm_rmtree(const char *path) { return rm_at(AT_FDCWD, path); }

int vm_outdir_open(vm_ctx *ctx, const char *path, vm_outdir **out) {
  *out = NULL;
  size_t len = strlen(path);
  while (len > 1 && path[len - 1] == '/') len--;
  vm_outdir *d = vm_calloc(ctx, 1, sizeof *d);
  char *p = vm_malloc(ctx, len + 1);
  if (!d || !p) {
    vm_free(ctx, d);
    vm_free(ctx, p);
    return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", path);
  }
  memcpy(p, path, len);
  p[len] = 0;
  struct stat st;
  int e = 0;
  if (stat(p, &st) == 0 && !S_ISDIR(st.st_mode)) e = ENOTDIR;
  char *tmp = e ? NULL : beside(ctx, p, ".tmp.");
  if (!e && !tmp) e = ENOMEM;
  if (!e && mkdir(tmp, 0777) != 0) e = errno;
  if (e) {
    vm_free(ctx, tmp);
    vm_free(ctx, d);
    int st2 = e == ENOMEM ? VM_ERR_NOMEM : VM_ERR_IO;
    st2 = vm_error(ctx, st2, "%s: cannot create: %s", p, strerror(e));
    vm_free(ctx, p);
    return st2;
  }
  d->ctx = ctx;
  d->path = p;
  d->tmp = tmp;
  *out = d;
  return VM_OK;
}

const char *vm_outdir_tmp(const vm_outdir *d) { return d->tmp; }

static void outdir_free(vm_outdir *d) {
  vm_ctx *ctx = d->ctx;
  vm_free(ctx, d->tmp);
  vm_free(ctx, d->path);
  vm_free(ctx, d);
}

void vm_outdir_abort(vm_outdir **pd) {
  if (!pd || !*pd) return;
  vm_rmtree((*pd)->tmp);
  outdir_free(*pd);
  *pd = NULL;
}

int vm_outdir_commit(vm_outdir **pd) {
  vm_outdir *d = *pd;
  vm_ctx *ctx = d->ctx;
  /* rename() replaces nothing but an empty directory: move the old tree
   * aside first, put it back if the new one cannot take its place */
  char *old = NULL;
  struct stat st;
  int st2 = VM_OK;
  if (lstat(d->path, &st) == 0) {
    if (!(old = beside(ctx, d->path, ".old."))) {
      st2 = vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", d->path);
    } else if (rename(d->path, old) != 0) {
      st2 = vm_error(ctx, VM_ERR_IO, "%s: cannot move the old one aside: %s", d->path,
                     strerror(errno));
      vm_free(ctx, old);
      old = NULL;
    }
  }
  if (!st2 && rename(d->tmp, d->path) != 0) {
    st2 = vm_error(ctx, VM_ERR_IO, "%s: cannot rename into place: %s", d->path, strerror(errno));
    if (old) rename(old, d->path);
    vm_free(ctx, old);
    old = NULL;
  }
  if (st2) {
    vm_outdir_abort(pd);
    return st2;
  }
  if (old) {
    if (vm_rmtree(old))
      vm_log(ctx, VM_LOG_WARN, "%s: the old one (moved to %s) could not be removed: %s", d->path,
             old, strerror(errno));
    vm_free(ctx, old);
  }
  outdir_free(d);
  *pd = NULL;
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

void vm_lost_init(vm_lost_list *l) {
  memset(l, 0, sizeof *l);
  l->group = -1;
}

void vm_lost_add(vm_lost_list *l, int group, const char *title, const char *item) {
  int fresh = group != l->group && title;
  const char *sep = !l->items ? "" : group != l->group ? "; " : ", ";
  size_t need = strlen(sep) + (fresh ? strlen(title) + 1 : 0) + strlen(item);
  /* room kept for " and N more" */
  if (l->more || l->n + need + 1 >= sizeof l->buf - 32) {
    l->more++;
    return;
  }
  l->n += (size_t)snprintf(l->buf + l->n, sizeof l->buf - l->n, "%s%s%s%s", sep, fresh ? title : "",
                           fresh ? " " : "", item);
  l->group = group;
  l->items++;
}

const char *vm_lost_text(vm_lost_list *l) {
  if (l->more) {
    snprintf(l->buf + l->n, sizeof l->buf - l->n, " and %d more", l->more);
    l->more = 0;
    l->n = strlen(l->buf);
  }
  return l->buf;
}
