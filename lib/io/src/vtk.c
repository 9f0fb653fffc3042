/* lib/io/src/vtk.c: legacy VTK (.vtk) reader and writer, ASCII and binary,
 * and the cell / convention helpers it shares with the VTU code. */
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats_private.h"
#include "lex_private.h"
#include "vtk_private.h"

/* Shared with vtu.c. */

static const char *vtk_type_name(int t) {
  switch (t) {
  case 1: return "vertex";
  case 2: return "poly-vertex";
  case 3: return "line";
  case 4: return "poly-line";
  case 5: return "triangle";
  case 6: return "triangle strip";
  case 7: return "polygon";
  case 8: return "pixel";
  case 9: return "quad";
  case 10: return "tetra";
  case 11: return "voxel";
  case 12: return "hexahedron";
  case 13: return "wedge";
  case 14: return "pyramid";
  case 42: return "polyhedron";
  default: return t >= 21 && t <= 37 ? "quadratic or higher-order cell" : "unknown";
  }
}

int vm_vtk_build_elements(vm_ctx *ctx, vm_mesh *m, const char *name, const char *where,
                          const vm_vtk_cells *c, int64_t **map) {
  *map = NULL;
  int64_t *mp = vm_alloc_array(ctx, c->n > 0 ? (size_t)c->n : 1, sizeof *mp);
  if (!mp) return VM_ERR_NOMEM;
  int64_t ne = 0, nconn = 0, skipped = 0;
  for (int64_t i = 0; i < c->n; i++) {
    int32_t t = c->types[i];
    int64_t k = c->off[i + 1] - c->off[i];
    if (t == 1 || t == 3 || t == 4) {
      mp[i] = -1;
      skipped++;
      continue;
    }
    int et = vm_elem_from_vtk(t);
    if (et < 0) {
      vm_free(ctx, mp);
      return vm_error(ctx, VM_ERR_FORMAT,
                      "%s: %s: cell %lld: VTK cell type %d (%s, %lld points) is not supported",
                      name, where, (long long)i, (int)t, vtk_type_name(t), (long long)k);
    }
    if (k != vm_elem_nverts(et)) {
      vm_free(ctx, mp);
      return vm_error(ctx, VM_ERR_FORMAT, "%s: %s: cell %lld: VTK %s needs %d points, has %lld",
                      name, where, (long long)i, vtk_type_name(t), vm_elem_nverts(et),
                      (long long)k);
    }
    for (int64_t j = c->off[i]; j < c->off[i + 1]; j++)
      if (c->conn[j] < 0 || c->conn[j] >= m->nv) {
        vm_free(ctx, mp);
        return vm_error(ctx, VM_ERR_FORMAT,
                        "%s: %s: cell %lld: point index %lld out of range [0,%lld)", name, where,
                        (long long)i, (long long)c->conn[j], (long long)m->nv);
      }
    mp[i] = ne++;
    nconn += k;
  }
  if (ne > INT32_MAX) {
    vm_free(ctx, mp);
    return vm_error(ctx, VM_ERR_FORMAT, "%s: %s: too many cells (%lld)", name, where,
                    (long long)ne);
  }
  int st = vm_mesh_set_elements(m, ne, nconn);
  if (st) {
    vm_free(ctx, mp);
    return st;
  }
  m->eoff[0] = 0;
  for (int64_t i = 0; i < c->n; i++) {
    if (mp[i] < 0) continue;
    int64_t e = mp[i];
    int et = vm_elem_from_vtk(c->types[i]);
    m->etype[e] = (uint8_t)et;
    int64_t o = m->eoff[e], k = c->off[i + 1] - c->off[i];
    for (int64_t j = 0; j < k; j++)
      m->conn[o + j] = (int32_t)c->conn[c->off[i] + vm_elem_vtk_node(et, (int)j)];
    m->eoff[e + 1] = o + k;
  }
  if (skipped)
    vm_log(ctx, VM_LOG_WARN,
           "%s: skipped %lld vertex/line cells (VTK types 1, 3, 4) and their cell data", name,
           (long long)skipped);
  *map = mp;
  return VM_OK;
}

/* An int32 single-component point field named `fname`, or NULL. */
static vm_field *int_point_field(const vm_mesh *m, const char *fname) {
  vm_field *f = vm_mesh_find_field(m, fname, VM_FIELD_VERTEX);
  return f && f->type == VM_FIELD_I32 && f->ncomp == 1 ? f : NULL;
}

int vm_vtk_finish_mesh(vm_ctx *ctx, vm_mesh *m, const char *where) {
  vm_field *f = int_point_field(m, VM_VTK_FLAG_NAME);
  if (f) {
    const int32_t *d = f->data;
    for (int64_t v = 0; v < m->nv; v++) {
      if (d[v] < VM_VERTEX_FREE || d[v] > VM_VERTEX_SLIP)
        return vm_error(ctx, VM_ERR_FORMAT,
                        "%s: point array %s: point %lld has flag %d (expected 0 free, 1 fixed "
                        "or 2 slip)",
                        where, VM_VTK_FLAG_NAME, (long long)v, (int)d[v]);
      m->vflag[v] = (uint8_t)d[v];
    }
    vm_mesh_remove_field(m, VM_VTK_FLAG_NAME, VM_FIELD_VERTEX);
  }
  f = int_point_field(m, VM_VTK_SURF_NAME);
  if (f) {
    memcpy(m->vsurf, f->data, (size_t)m->nv * sizeof *m->vsurf);
    vm_mesh_remove_field(m, VM_VTK_SURF_NAME, VM_FIELD_VERTEX);
  }
  if (int_point_field(m, "fixed")) vm_mesh_apply_fixed_field(m);
  int dim = 2;
  for (int64_t e = 0; e < m->ne && dim == 2; e++)
    if (vm_elem_dim(m->etype[e]) != 2) dim = 3;
  for (int64_t v = 0; v < m->nv && dim == 2; v++)
    if (m->xyz[3 * v + 2] != 0.0) dim = 3;
  m->dim = dim;
  return VM_OK;
}

int vm_vtk_need_flags(const vm_mesh *m) {
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] != VM_VERTEX_FREE) return 1;
  return 0;
}

int vm_vtk_field_written(const vm_field *f, int flags) {
  if (!flags || f->location != VM_FIELD_VERTEX) return 1;
  return strcmp(f->name, VM_VTK_FLAG_NAME) != 0 && strcmp(f->name, VM_VTK_SURF_NAME) != 0;
}

int vm_vtk_report_lost(vm_ctx *ctx, const vm_mesh *m, const char *path, int flags) {
  int lost = 0;
  /* one line for the group names (their tags stay), one for the other
   * attributes, one per shadowed field */
  vm_lost_list names, other;
  vm_lost_init(&names);
  vm_lost_init(&other);
  for (int i = 0; i < m->nattr; i++, lost++) {
    const char *k = m->attrs[i].key, *tag = NULL;
    char item[320];
    if (!strncmp(k, "gmsh:physical_name:", 19) && (tag = strchr(k + 19, ':'))) {
      snprintf(item, sizeof item, "'%s' of tag %s (attribute '%s')", m->attrs[i].value, tag + 1, k);
      vm_lost_add(&names, 0, NULL, item);
    } else {
      snprintf(item, sizeof item, "'%s'", k);
      vm_lost_add(&other, 0, NULL, item);
    }
  }
  if (names.items || names.more)
    vm_log(ctx, VM_LOG_WARN,
           "%s: VTK cannot carry the group names %s (the tags stay in the cell data "
           "gmsh:physical)",
           path, vm_lost_text(&names));
  if (other.items || other.more)
    vm_log(ctx, VM_LOG_WARN, "%s: VTK cannot carry the attributes %s", path, vm_lost_text(&other));
  for (int i = 0; i < m->nfield; i++)
    if (!vm_vtk_field_written(&m->fields[i], flags)) {
      vm_log(ctx, VM_LOG_WARN, "%s: point field '%s' is shadowed by the vertex flags", path,
             m->fields[i].name);
      lost++;
    }
  return lost;
}

/* Legacy reader. */

typedef struct {
  int size;  /* bytes per value in binary files */
  char kind; /* 'i' signed, 'u' unsigned, 'f' floating point, 'b' bit (text only) */
} dtype;

static const struct {
  const char *name;
  dtype t;
} dtype_tab[] = {{"unsigned_char", {1, 'u'}},
                 {"char", {1, 'i'}},
                 {"signed_char", {1, 'i'}},
                 {"unsigned_short", {2, 'u'}},
                 {"short", {2, 'i'}},
                 {"unsigned_int", {4, 'u'}},
                 {"int", {4, 'i'}},
                 {"unsigned_long", {8, 'u'}},
                 {"long", {8, 'i'}},
                 {"vtkidtype", {8, 'i'}},
                 {"vtktypeint8", {1, 'i'}},
                 {"vtktypeuint8", {1, 'u'}},
                 {"vtktypeint16", {2, 'i'}},
                 {"vtktypeuint16", {2, 'u'}},
                 {"vtktypeint32", {4, 'i'}},
                 {"vtktypeuint32", {4, 'u'}},
                 {"vtktypeint64", {8, 'i'}},
                 {"vtktypeuint64", {8, 'u'}},
                 {"float", {4, 'f'}},
                 {"double", {8, 'f'}},
                 {"vtktypefloat32", {4, 'f'}},
                 {"vtktypefloat64", {8, 'f'}}};

/* One section of cells as read (CELLS, or a POLYDATA section). */
typedef struct {
  int present;
  int64_t n;
  int64_t *off; /* n + 1 */
  int64_t *conn;
  int64_t line; /* where the section starts, for messages */
  size_t byte;
} cellsec;

enum { SEC_CELLS = 0, SEC_VERTS = 0, SEC_LINES, SEC_POLYS, SEC_STRIPS, NSEC };

typedef struct {
  vm_ctx *ctx;
  const char *name;
  vm_lex lx;
  const char *base;
  int binary;
  int polydata;
  vm_mesh *m;
  int have_points;
  cellsec sec[NSEC];
  int32_t *types; /* CELL_TYPES */
  int64_t ntypes;
  int have_types;
  int geom_done;
  int64_t nfilecells; /* cells in the file, skipped ones included */
  int64_t *map;       /* file cell -> element or -1 */
  int loc;            /* -1 before POINT_DATA / CELL_DATA */
  int nstored;        /* arrays stored as fields so far (at most VM_IO_MAX_ARRAYS) */
} vtkrd;

static size_t rd_off(const vtkrd *r) { return (size_t)(r->lx.p - r->base); }

/* A message naming the line (text) or the record and byte offset (binary data). */
static int rd_fail(vtkrd *r, const char *rec, size_t at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static int rd_fail(vtkrd *r, const char *rec, size_t at, const char *fmt, ...) {
  char msg[600];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (r->binary && rec)
    return vm_error(r->ctx, VM_ERR_FORMAT, "%s: %s data at byte %zu: %s", r->name, rec, at, msg);
  if (rec) return vm_lex_fail(&r->lx, "%s: %s", rec, msg);
  return vm_lex_fail(&r->lx, "%s", msg);
}

static int get_dtype(vtkrd *r, dtype *t, const char *rec) {
  const char *s;
  size_t n;
  int st = vm_lex_word(&r->lx, &s, &n, "a data type");
  if (st) return st;
  if (vm_tok_is(s, n, "bit") && strcmp(rec, "POINTS") != 0 && !strstr(rec, "OFFSETS")) {
    /* a data array's (Mesquite writes its 'fixed' flags so): 0 and 1 in
     * text, read as small integers; in binary packed 8 per byte */
    if (r->binary)
      return vm_lex_fail(&r->lx, "%s: data type 'bit' is supported in ASCII files only", rec);
    *t = (dtype){1, 'b'};
    return VM_OK;
  }
  for (size_t i = 0; i < sizeof dtype_tab / sizeof dtype_tab[0]; i++)
    if (vm_tok_is(s, n, dtype_tab[i].name)) {
      *t = dtype_tab[i].t;
      return VM_OK;
    }
  return vm_lex_fail(&r->lx, "%s: data type '%.*s' is not supported", rec, (int)(n > 40 ? 40 : n),
                     s);
}

static int get_count(vtkrd *r, int64_t *v, const char *what) {
  int st = vm_lex_int(&r->lx, v, what);
  if (st) return st;
  if (*v < 0) return vm_lex_fail(&r->lx, "%s: negative count %lld", what, (long long)*v);
  return VM_OK;
}

/* Nonzero if more than blanks follow on the current line. */
static int line_has_more(const vtkrd *r) {
  const char *q = r->lx.p;
  while (q < r->lx.end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
  return q < r->lx.end && *q != '\n';
}

/* End of a keyword line: in binary files the data start right after it,
 * so nothing else may stand there; text files are read token by token. */
static int end_line(vtkrd *r, const char *rec) {
  if (!r->binary) return VM_OK;
  if (line_has_more(r)) return vm_lex_fail(&r->lx, "%s: unexpected text at end of line", rec);
  const char *s;
  size_t n;
  vm_lex_line(&r->lx, &s, &n);
  return VM_OK;
}

/* In binary files the next text line may follow binary data, so peek at the
 * raw bytes: blanks, then `word` as a whole token. Consumes it on a match. */
static int take_word(vtkrd *r, const char *word) {
  if (!r->binary) {
    if (!vm_lex_peek_is(&r->lx, word)) return 0;
    const char *s;
    size_t n;
    vm_lex_word(&r->lx, &s, &n, word);
    return 1;
  }
  const char *q = r->lx.p;
  int64_t nl = 0;
  while (q < r->lx.end && (*q == ' ' || *q == '\t' || *q == '\r' || *q == '\n')) nl += *q++ == '\n';
  size_t w = strlen(word);
  if ((size_t)(r->lx.end - q) < w || strncasecmp(q, word, w) != 0) return 0;
  if (q + w < r->lx.end && !(q[w] == ' ' || q[w] == '\t' || q[w] == '\r' || q[w] == '\n')) return 0;
  r->lx.p = q + w;
  r->lx.line += nl;
  return 1;
}

/* a * b, or an error if that many values cannot be in the rest of the file. */
static int fit_count(vtkrd *r, int64_t a, int64_t b, int size, int64_t *out, const char *rec) {
  uint64_t rem = (uint64_t)(r->lx.end - r->lx.p);
  /* text: every value takes a character and a separator (the last one none) */
  uint64_t cap = r->binary ? rem / (uint64_t)size : (rem + 1) / 2;
  if ((a > 0 && (uint64_t)b > cap / (uint64_t)a) || (uint64_t)a * (uint64_t)b > cap)
    return vm_lex_fail(
        &r->lx, "%s: %lld x %lld values cannot fit in the %" PRIu64 " bytes left in the file", rec,
        (long long)a, (long long)b, rem);
  *out = a * b;
  return VM_OK;
}

static uint64_t load_be(const uint8_t *p, int size) {
  uint64_t v = 0;
  for (int i = 0; i < size; i++) v = v << 8 | p[i];
  return v;
}

/* Advance over `n` bytes of binary data, keeping the line count honest. */
static void skip_bytes(vtkrd *r, size_t n) {
  const char *e = r->lx.p + n;
  for (const char *q = r->lx.p; (q = memchr(q, '\n', (size_t)(e - q))) != NULL; q++) r->lx.line++;
  r->lx.p = e;
}

/* Describes what is being read, for messages. */
typedef struct {
  const char *rec;  /* "POINTS", "SCALARS 'p'" */
  const char *item; /* "point", "tuple", "value" */
  int ncomp;        /* values per item */
} rdesc;

/* Read `count` integers of type t into out (may be NULL: skip), each in
 * [lo, hi]. The caller has checked the count against the file size. */
static int read_ints(vtkrd *r, const dtype *t, int64_t count, int64_t *out, int64_t lo, int64_t hi,
                     const rdesc *d) {
  if (t->kind == 'f') return vm_lex_fail(&r->lx, "%s: needs an integer data type", d->rec);
  if (r->binary) {
    size_t at = rd_off(r);
    const uint8_t *p = (const uint8_t *)r->lx.p;
    for (int64_t i = 0; i < count; i++, p += t->size) {
      uint64_t u = load_be(p, t->size);
      int64_t v;
      if (t->kind == 'u') {
        if (u > INT64_MAX)
          return rd_fail(r, d->rec, at + (size_t)(i * t->size), "%s %lld: value too large", d->item,
                         (long long)(i / d->ncomp));
        v = (int64_t)u;
      } else if (t->size == 8) {
        memcpy(&v, &u, sizeof v);
      } else {
        v = (int64_t)u;
        if (u >> (8 * t->size - 1)) v -= (int64_t)1 << (8 * t->size);
      }
      if (v < lo || v > hi)
        return rd_fail(r, d->rec, at + (size_t)(i * t->size),
                       "%s %lld: value %lld out of range [%lld, %lld]", d->item,
                       (long long)(i / d->ncomp), (long long)v, (long long)lo, (long long)hi);
      if (out) out[i] = v;
    }
    skip_bytes(r, (size_t)count * (size_t)t->size);
    return VM_OK;
  }
  for (int64_t i = 0; i < count; i++) {
    int64_t v;
    int st = vm_lex_int(&r->lx, &v, d->rec);
    if (st) return st;
    if (v < lo || v > hi)
      return vm_lex_fail(&r->lx, "%s: %s %lld: value %lld out of range [%lld, %lld]", d->rec,
                         d->item, (long long)(i / d->ncomp), (long long)v, (long long)lo,
                         (long long)hi);
    if (out) out[i] = v;
  }
  return VM_OK;
}

/* Read `count` numbers of any type as doubles into out (may be NULL: skip);
 * with need_finite, a NaN or infinity is an error naming the item. */
static int read_reals(vtkrd *r, const dtype *t, int64_t count, double *out, int need_finite,
                      const rdesc *d) {
  if (r->binary) {
    size_t at = rd_off(r);
    const uint8_t *p = (const uint8_t *)r->lx.p;
    for (int64_t i = 0; i < count; i++, p += t->size) {
      uint64_t u = load_be(p, t->size);
      double x;
      if (t->kind == 'f' && t->size == 4) {
        uint32_t u32 = (uint32_t)u;
        float f;
        memcpy(&f, &u32, sizeof f);
        x = f;
      } else if (t->kind == 'f') {
        memcpy(&x, &u, sizeof x);
      } else if (t->kind == 'u') {
        x = (double)u;
      } else {
        int64_t v;
        if (t->size == 8) {
          memcpy(&v, &u, sizeof v);
        } else {
          v = (int64_t)u;
          if (u >> (8 * t->size - 1)) v -= (int64_t)1 << (8 * t->size);
        }
        x = (double)v;
      }
      if (need_finite && !isfinite(x))
        return rd_fail(r, d->rec, at + (size_t)(i * t->size), "%s %lld is not finite", d->item,
                       (long long)(i / d->ncomp));
      if (out) out[i] = x;
    }
    skip_bytes(r, (size_t)count * (size_t)t->size);
    return VM_OK;
  }
  for (int64_t i = 0; i < count; i++) {
    double x;
    int st = vm_lex_double(&r->lx, &x, d->rec);
    if (st) return st;
    if (need_finite && !isfinite(x))
      return vm_lex_fail(&r->lx, "%s: %s %lld is not finite", d->rec, d->item,
                         (long long)(i / d->ncomp));
    if (out) out[i] = x;
  }
  return VM_OK;
}

static int hexval(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

/* VTK writes special characters of array names as %XX. */
static int decode_name(vtkrd *r, const char *s, size_t n, char **out) {
  char *d = vm_malloc(r->ctx, n + 1);
  if (!d) return VM_ERR_NOMEM;
  size_t k = 0;
  for (size_t i = 0; i < n; i++) {
    if (s[i] == '%' && i + 2 < n && hexval(s[i + 1]) >= 0 && hexval(s[i + 2]) >= 0) {
      d[k++] = (char)(hexval(s[i + 1]) * 16 + hexval(s[i + 2]));
      i += 2;
    } else {
      d[k++] = s[i];
    }
  }
  d[k] = 0;
  if (k == 0 || strlen(d) != k) {
    vm_free(r->ctx, d);
    return vm_lex_fail(&r->lx, "bad array name '%.*s'", (int)(n > 40 ? 40 : n), s);
  }
  *out = d;
  return VM_OK;
}

static int get_name(vtkrd *r, char **out, const char *what) {
  const char *s;
  size_t n;
  int st = vm_lex_word(&r->lx, &s, &n, what);
  if (st) return st;
  return decode_name(r, s, n, out);
}

/* Items at the current attribute location. */
static int64_t loc_count(const vtkrd *r) {
  return r->loc == VM_FIELD_VERTEX ? r->m->nv : r->nfilecells;
}

/* Read an array of `ntuples` x `ncomp` values of type t and store it as a
 * field `fname` at the current location (fname NULL or no location: skip).
 * Cell rows of skipped cells are dropped. */
static int read_array(vtkrd *r, const char *fname, int64_t ntuples, int ncomp, const dtype *t,
                      double scale, const char *rec) {
  int64_t count = 0;
  int st = fit_count(r, ntuples, ncomp, t->size, &count, rec);
  if (st) return st;
  rdesc d = {rec, "tuple", ncomp};
  vm_ctx *ctx = r->ctx;
  if (!fname || r->loc < 0) {
    if (t->kind == 'f' || !r->binary) return read_reals(r, t, count, NULL, 0, &d);
    return read_ints(r, t, count, NULL, INT64_MIN, INT64_MAX, &d);
  }
  /* every field costs a search of the others: many small arrays (a FIELD
   * block of 40,000 took 11 s for 0.9 MB) would be quadratic */
  if (r->nstored == VM_IO_MAX_ARRAYS)
    return vm_lex_fail(&r->lx, "%s: more than %d data arrays (the reader's ceiling)", rec,
                       VM_IO_MAX_ARRAYS);
  r->nstored++;
  int isint = t->kind != 'f' && scale == 1.0;
  void *tmp =
      vm_alloc_array(ctx, count > 0 ? (size_t)count : 1, isint ? sizeof(int64_t) : sizeof(double));
  if (!tmp) return VM_ERR_NOMEM;
  if (isint && t->kind == 'b')
    st = read_ints(r, t, count, tmp, 0, 1, &d);
  else if (isint)
    st = read_ints(r, t, count, tmp, INT32_MIN, INT32_MAX, &d);
  else
    st = read_reals(r, t, count, tmp, 0, &d);
  vm_field *f = NULL;
  if (!st)
    st = vm_mesh_add_field(r->m, fname, r->loc, isint ? VM_FIELD_I32 : VM_FIELD_F64, ncomp, &f);
  if (!st) {
    for (int64_t i = 0; i < ntuples; i++) {
      int64_t row = r->loc == VM_FIELD_ELEMENT ? r->map[i] : i;
      if (row < 0) continue;
      for (int c = 0; c < ncomp; c++) {
        int64_t k = i * ncomp + c;
        if (isint)
          ((int32_t *)f->data)[row * ncomp + c] = (int32_t)((int64_t *)tmp)[k];
        else
          ((double *)f->data)[row * ncomp + c] = ((double *)tmp)[k] * scale;
      }
    }
  }
  vm_free(ctx, tmp);
  return st;
}

/* "<KEYWORD> n size" then either the classic list (count, ids...) or the
 * 5.1 layout with OFFSETS and CONNECTIVITY arrays. */
static int read_cells(vtkrd *r, const char *kw, cellsec *s) {
  vm_ctx *ctx = r->ctx;
  if (s->present) return vm_lex_fail(&r->lx, "%s appears twice", kw);
  if (r->geom_done) return vm_lex_fail(&r->lx, "%s after POINT_DATA or CELL_DATA", kw);
  s->line = r->lx.line;
  int64_t a, b;
  int st = get_count(r, &a, kw);
  if (!st) st = get_count(r, &b, kw);
  if (!st) st = end_line(r, kw);
  if (st) return st;
  s->present = 1;
  s->byte = rd_off(r);
  rdesc d = {kw, "entry", 1};
  if (take_word(r, "OFFSETS")) {
    dtype t;
    int64_t cnt;
    char rec[64];
    snprintf(rec, sizeof rec, "%s OFFSETS", kw);
    if ((st = get_dtype(r, &t, rec)) || (st = end_line(r, rec)) ||
        (st = fit_count(r, a, 1, t.size, &cnt, rec)))
      return st;
    s->n = a > 0 ? a - 1 : 0;
    s->off = vm_alloc_array(ctx, (size_t)s->n + 1, sizeof *s->off);
    if (!s->off) return VM_ERR_NOMEM;
    s->off[0] = 0;
    s->byte = rd_off(r);
    d.rec = rec;
    if ((st = read_ints(r, &t, a, a > 0 ? s->off : NULL, 0, INT64_MAX, &d))) return st;
    if (s->off[0] != 0) return rd_fail(r, rec, s->byte, "first offset is not 0");
    for (int64_t i = 0; i < s->n; i++)
      if (s->off[i + 1] < s->off[i])
        return rd_fail(r, rec, s->byte, "offsets decrease at cell %lld", (long long)i);
    if (s->off[s->n] != b)
      return rd_fail(r, rec, s->byte, "last offset %lld is not the connectivity size %lld",
                     (long long)s->off[s->n], (long long)b);
    snprintf(rec, sizeof rec, "%s CONNECTIVITY", kw);
    if ((st = vm_lex_expect(&r->lx, "CONNECTIVITY")) || (st = get_dtype(r, &t, rec)) ||
        (st = end_line(r, rec)) || (st = fit_count(r, b, 1, t.size, &cnt, rec)))
      return st;
    s->conn = vm_alloc_array(ctx, b > 0 ? (size_t)b : 1, sizeof *s->conn);
    if (!s->conn) return VM_ERR_NOMEM;
    d.rec = rec;
    return read_ints(r, &t, b, s->conn, INT64_MIN, INT64_MAX, &d);
  }
  if (a > b)
    return vm_lex_fail(&r->lx, "%s: %lld cells cannot fit in a list of size %lld", kw, (long long)a,
                       (long long)b);
  int64_t cnt;
  dtype ti = {4, 'i'};
  if ((st = fit_count(r, b, 1, 4, &cnt, kw))) return st;
  s->n = a;
  s->off = vm_alloc_array(ctx, (size_t)a + 1, sizeof *s->off);
  s->conn = vm_alloc_array(ctx, b > 0 ? (size_t)b : 1, sizeof *s->conn);
  if (!s->off || !s->conn) return VM_ERR_NOMEM;
  if ((st = read_ints(r, &ti, b, s->conn, INT32_MIN, INT32_MAX, &d))) return st;
  /* compact the list in place: conn keeps only the ids */
  int64_t in = 0, o = 0;
  s->off[0] = 0;
  for (int64_t i = 0; i < a; i++) {
    if (in == b)
      return rd_fail(r, kw, s->byte, "cell %lld: the list of size %lld is used up", (long long)i,
                     (long long)b);
    int64_t k = s->conn[in++];
    if (k < 0 || k > b - in)
      return rd_fail(r, kw, s->byte, "cell %lld: point count %lld overruns the list size %lld",
                     (long long)i, (long long)k, (long long)b);
    for (int64_t j = 0; j < k; j++) s->conn[o++] = s->conn[in++];
    s->off[i + 1] = o;
  }
  if (in != b)
    return rd_fail(r, kw, s->byte, "list size %lld but the %lld cells use %lld entries",
                   (long long)b, (long long)a, (long long)in);
  return VM_OK;
}

static int read_points(vtkrd *r) {
  if (r->have_points) return vm_lex_fail(&r->lx, "POINTS appears twice");
  if (r->geom_done) return vm_lex_fail(&r->lx, "POINTS after POINT_DATA or CELL_DATA");
  int64_t n = 0, cnt = 0;
  dtype t;
  int st = get_count(r, &n, "POINTS");
  if (!st) st = get_dtype(r, &t, "POINTS");
  if (!st) st = end_line(r, "POINTS");
  if (!st) st = fit_count(r, n, 3, t.size, &cnt, "POINTS");
  if (st) return st;
  if (n > INT32_MAX) return vm_lex_fail(&r->lx, "POINTS: too many points (%lld)", (long long)n);
  if ((st = vm_mesh_set_vertices(r->m, n))) return st;
  r->have_points = 1;
  rdesc d = {"POINTS", "point", 3};
  return read_reals(r, &t, cnt, r->m->xyz, 1, &d);
}

static int read_cell_types(vtkrd *r) {
  if (r->have_types) return vm_lex_fail(&r->lx, "CELL_TYPES appears twice");
  if (r->geom_done) return vm_lex_fail(&r->lx, "CELL_TYPES after POINT_DATA or CELL_DATA");
  int64_t n, cnt;
  int st = get_count(r, &n, "CELL_TYPES");
  if (!st) st = end_line(r, "CELL_TYPES");
  if (!st) st = fit_count(r, n, 1, 4, &cnt, "CELL_TYPES");
  if (st) return st;
  int64_t *tmp = vm_alloc_array(r->ctx, n > 0 ? (size_t)n : 1, sizeof *tmp);
  r->types = vm_alloc_array(r->ctx, n > 0 ? (size_t)n : 1, sizeof *r->types);
  if (!tmp || !r->types) {
    vm_free(r->ctx, tmp);
    return VM_ERR_NOMEM;
  }
  dtype ti = {4, 'i'};
  rdesc d = {"CELL_TYPES", "cell", 1};
  st = read_ints(r, &ti, n, tmp, 0, 255, &d);
  for (int64_t i = 0; !st && i < n; i++) r->types[i] = (int32_t)tmp[i];
  vm_free(r->ctx, tmp);
  r->ntypes = n;
  r->have_types = 1;
  return st;
}

static const char *where_of(const vtkrd *r, const cellsec *s, const char *kw, char *buf, size_t n) {
  if (r->binary)
    snprintf(buf, n, "%s data at byte %zu", kw, s->byte);
  else
    snprintf(buf, n, "line %lld", (long long)s->line);
  return buf;
}

/* Turn the cell sections into mesh elements (once, before any data). */
static int finish_geometry(vtkrd *r) {
  if (r->geom_done) return VM_OK;
  r->geom_done = 1;
  vm_ctx *ctx = r->ctx;
  if (!r->have_points) return vm_lex_fail(&r->lx, "no POINTS section before this point");
  char where[96];
  if (!r->polydata) {
    cellsec *s = &r->sec[SEC_CELLS];
    if (s->present != r->have_types)
      return vm_lex_fail(&r->lx, "%s without %s", s->present ? "CELLS" : "CELL_TYPES",
                         s->present ? "CELL_TYPES" : "CELLS");
    if (!s->present) s->n = 0;
    if (s->present && r->ntypes != s->n)
      return vm_lex_fail(&r->lx, "CELL_TYPES has %lld cells but CELLS has %lld",
                         (long long)r->ntypes, (long long)s->n);
    vm_vtk_cells c = {s->n, s->off, s->conn, r->types};
    int64_t zero = 0;
    if (!s->present) c.off = &zero;
    r->nfilecells = s->n;
    return vm_vtk_build_elements(ctx, r->m, r->name, where_of(r, s, "CELLS", where, sizeof where),
                                 &c, &r->map);
  }
  /* POLYDATA: cells are numbered vertices, lines, polygons, strips */
  int64_t n = 0, nc = 0;
  for (int k = 0; k < NSEC; k++)
    if (r->sec[k].present) {
      n += r->sec[k].n;
      nc += r->sec[k].off[r->sec[k].n];
    }
  int64_t *off = vm_alloc_array(ctx, (size_t)n + 1, sizeof *off);
  int64_t *conn = vm_alloc_array(ctx, nc > 0 ? (size_t)nc : 1, sizeof *conn);
  int32_t *types = vm_alloc_array(ctx, n > 0 ? (size_t)n : 1, sizeof *types);
  int st = VM_ERR_NOMEM;
  if (off && conn && types) {
    int64_t c = 0, o = 0;
    off[0] = 0;
    for (int k = 0; k < NSEC; k++) {
      const cellsec *s = &r->sec[k];
      if (!s->present) continue;
      for (int64_t i = 0; i < s->n; i++, c++) {
        int64_t len = s->off[i + 1] - s->off[i];
        memcpy(conn + o, s->conn + s->off[i], (size_t)len * sizeof *conn);
        o += len;
        off[c + 1] = o;
        types[c] = k == SEC_VERTS    ? 1
                   : k == SEC_LINES  ? (len == 2 ? 3 : 4)
                   : k == SEC_STRIPS ? 6
                   : len == 3        ? 5
                   : len == 4        ? 9
                                     : 7;
      }
    }
    const cellsec *ws = r->sec[SEC_POLYS].present ? &r->sec[SEC_POLYS] : &r->sec[SEC_STRIPS];
    vm_vtk_cells cl = {n, off, conn, types};
    r->nfilecells = n;
    st = vm_vtk_build_elements(ctx, r->m, r->name,
                               where_of(r, ws,
                                        ws == &r->sec[SEC_POLYS] ? "POLYGONS" : "TRIANGLE_STRIPS",
                                        where, sizeof where),
                               &cl, &r->map);
  }
  vm_free(ctx, off);
  vm_free(ctx, conn);
  vm_free(ctx, types);
  return st;
}

/* METADATA blocks (component names, information keys) end at a blank line. */
static void skip_metadata(vtkrd *r) {
  const char *l;
  size_t ln;
  vm_lex_line(&r->lx, &l, &ln);
  do {
    vm_lex_line(&r->lx, &l, &ln);
    while (ln && (l[ln - 1] == ' ' || l[ln - 1] == '\t' || l[ln - 1] == '\r')) ln--;
  } while (ln && r->lx.p < r->lx.end);
}

/* "FIELD name n" then n arrays "name ncomp ntuples type" with data. */
static int read_field_block(vtkrd *r) {
  vm_ctx *ctx = r->ctx;
  const char *s;
  size_t n;
  int64_t narr;
  int st = vm_lex_word(&r->lx, &s, &n, "FIELD name");
  if (!st) st = get_count(r, &narr, "FIELD");
  if (!st) st = end_line(r, "FIELD");
  for (int64_t a = 0; !st && a < narr; a++) {
    if (take_word(r, "NULL_ARRAY")) {
      st = end_line(r, "NULL_ARRAY");
      continue;
    }
    char *fname = NULL;
    int64_t ncomp, ntup;
    dtype t;
    char rec[96];
    if ((st = get_name(r, &fname, "FIELD array name"))) break;
    snprintf(rec, sizeof rec, "FIELD array '%.40s'", fname);
    if (!(st = get_count(r, &ncomp, rec)) && !(st = get_count(r, &ntup, rec)) &&
        !(st = get_dtype(r, &t, rec)) && !(st = end_line(r, rec))) {
      if (ncomp < 1 || ncomp > (1 << 20))
        st = vm_lex_fail(&r->lx, "%s: bad component count %lld", rec, (long long)ncomp);
      else if (r->loc >= 0 && ntup != loc_count(r))
        st = vm_lex_fail(&r->lx, "%s: %lld tuples, expected %lld", rec, (long long)ntup,
                         (long long)loc_count(r));
      else
        st = read_array(r, fname, ntup, (int)ncomp, &t, 1.0, rec);
    }
    vm_free(ctx, fname);
    if (!st && take_word(r, "METADATA")) skip_metadata(r);
  }
  return st;
}

/* Attribute records: SCALARS, VECTORS, NORMALS, ... at the current location. */
static int read_attribute(vtkrd *r, const char *kw, size_t kwn) {
  vm_ctx *ctx = r->ctx;
  char kwbuf[32];
  snprintf(kwbuf, sizeof kwbuf, "%.*s", (int)(kwn < 31 ? kwn : 31), kw);
  if (r->loc < 0) return vm_lex_fail(&r->lx, "%s outside POINT_DATA / CELL_DATA", kwbuf);
  if (vm_tok_is(kw, kwn, "LOOKUP_TABLE")) {
    const char *s;
    size_t n;
    int64_t size = 0, cnt = 0;
    int st = vm_lex_word(&r->lx, &s, &n, "LOOKUP_TABLE name");
    if (!st) st = get_count(r, &size, "LOOKUP_TABLE");
    if (!st) st = end_line(r, "LOOKUP_TABLE");
    dtype t = r->binary ? (dtype){1, 'u'} : (dtype){4, 'f'};
    if (!st) st = fit_count(r, size, 4, t.size, &cnt, "LOOKUP_TABLE");
    rdesc d = {"LOOKUP_TABLE", "entry", 4};
    if (!st) st = read_reals(r, &t, cnt, NULL, 0, &d);
    return st;
  }
  char *fname = NULL;
  char rec[96];
  int st = get_name(r, &fname, "array name");
  if (st) return st;
  snprintf(rec, sizeof rec, "%s '%.40s'", kwbuf, fname);
  dtype t = {4, 'f'};
  int64_t ncomp = 1;
  double scale = 1.0;
  if (vm_tok_is(kw, kwn, "COLOR_SCALARS")) {
    st = get_count(r, &ncomp, rec);
    if (r->binary) {
      t = (dtype){1, 'u'};
      scale = 1.0 / 255.0;
    }
  } else if (vm_tok_is(kw, kwn, "TEXTURE_COORDINATES")) {
    st = get_count(r, &ncomp, rec);
    if (!st) st = get_dtype(r, &t, rec);
  } else {
    st = get_dtype(r, &t, rec);
    if (vm_tok_is(kw, kwn, "VECTORS") || vm_tok_is(kw, kwn, "NORMALS")) ncomp = 3;
    if (vm_tok_is(kw, kwn, "TENSORS")) ncomp = 9;
    if (vm_tok_is(kw, kwn, "TENSORS6")) ncomp = 6;
    if (!st && vm_tok_is(kw, kwn, "SCALARS") && line_has_more(r)) st = get_count(r, &ncomp, rec);
  }
  if (!st && (ncomp < 1 || ncomp > (1 << 20)))
    st = vm_lex_fail(&r->lx, "%s: bad component count %lld", rec, (long long)ncomp);
  if (!st) st = end_line(r, rec);
  if (!st && vm_tok_is(kw, kwn, "SCALARS") && take_word(r, "LOOKUP_TABLE")) {
    const char *s;
    size_t n;
    st = vm_lex_word(&r->lx, &s, &n, "LOOKUP_TABLE name");
    if (!st) st = end_line(r, rec);
  }
  if (!st) st = read_array(r, fname, loc_count(r), (int)ncomp, &t, scale, rec);
  vm_free(ctx, fname);
  return st;
}

static int is_attribute(const char *s, size_t n) {
  static const char *kws[] = {"SCALARS",       "VECTORS",      "NORMALS",
                              "TENSORS",       "TENSORS6",     "TEXTURE_COORDINATES",
                              "COLOR_SCALARS", "LOOKUP_TABLE", "GLOBAL_IDS",
                              "PEDIGREE_IDS"};
  for (size_t i = 0; i < sizeof kws / sizeof kws[0]; i++)
    if (vm_tok_is(s, n, kws[i])) return 1;
  return 0;
}

/* "# vtk DataFile Version x.y", a title line, ASCII or BINARY, DATASET. */
static int read_header(vtkrd *r) {
  const char *s;
  size_t n;
  vm_lex_line(&r->lx, &s, &n);
  char line[128];
  snprintf(line, sizeof line, "%.*s", (int)(n < 127 ? n : 127), s);
  int major = -1, minor = -1, used = 0;
  char w1[8], w2[16], w3[16];
  if (sscanf(line, " # %7s %15s %15s %d.%d%n", w1, w2, w3, &major, &minor, &used) != 5 ||
      strcasecmp(w1, "vtk") || strcasecmp(w2, "DataFile") || strcasecmp(w3, "Version")) {
    r->lx.line = 1;
    return vm_lex_fail(&r->lx, "not a legacy VTK file (no '# vtk DataFile Version' header)");
  }
  /* compare before combining: a huge major must not overflow major * 10 */
  if (major < 1 || major > 5 || minor < 0 || minor > 9 || major * 10 + minor > 51) {
    r->lx.line = 1;
    return vm_lex_fail(&r->lx, "VTK file version %d.%d is not supported (1.0 to 5.1 are)", major,
                       minor);
  }
  if (r->lx.p >= r->lx.end) return vm_lex_fail(&r->lx, "unexpected end of file after the header");
  vm_lex_line(&r->lx, &s, &n); /* title */
  int st = vm_lex_word(&r->lx, &s, &n, "ASCII or BINARY");
  if (st) return st;
  if (vm_tok_is(s, n, "BINARY"))
    r->binary = 1;
  else if (!vm_tok_is(s, n, "ASCII"))
    return vm_lex_fail(&r->lx, "expected ASCII or BINARY, found '%.*s'", (int)(n > 40 ? 40 : n), s);
  if ((st = vm_lex_expect(&r->lx, "DATASET"))) return st;
  if ((st = vm_lex_word(&r->lx, &s, &n, "dataset type"))) return st;
  if (vm_tok_is(s, n, "POLYDATA"))
    r->polydata = 1;
  else if (!vm_tok_is(s, n, "UNSTRUCTURED_GRID"))
    return vm_lex_fail(&r->lx,
                       "DATASET %.*s is not supported (only UNSTRUCTURED_GRID and POLYDATA)",
                       (int)(n > 40 ? 40 : n), s);
  return end_line(r, "DATASET");
}

static int read_body(vtkrd *r) {
  static const char *pd_kw[NSEC] = {"VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS"};
  int st = VM_OK;
  while (!st && !vm_lex_eof(&r->lx)) {
    const char *s;
    size_t n;
    if ((st = vm_lex_word(&r->lx, &s, &n, "a keyword"))) break;
    int sec = -1;
    if (r->polydata)
      for (int k = 0; k < NSEC; k++)
        if (vm_tok_is(s, n, pd_kw[k])) sec = k;
    if (vm_tok_is(s, n, "POINTS")) {
      st = read_points(r);
    } else if (!r->polydata && vm_tok_is(s, n, "CELLS")) {
      st = read_cells(r, "CELLS", &r->sec[SEC_CELLS]);
    } else if (!r->polydata && vm_tok_is(s, n, "CELL_TYPES")) {
      st = read_cell_types(r);
    } else if (sec >= 0) {
      st = read_cells(r, pd_kw[sec], &r->sec[sec]);
    } else if (vm_tok_is(s, n, "POINT_DATA") || vm_tok_is(s, n, "CELL_DATA")) {
      int loc = vm_tok_is(s, n, "POINT_DATA") ? VM_FIELD_VERTEX : VM_FIELD_ELEMENT;
      const char *kw = loc == VM_FIELD_VERTEX ? "POINT_DATA" : "CELL_DATA";
      int64_t cnt;
      if ((st = finish_geometry(r)) || (st = get_count(r, &cnt, kw))) break;
      r->loc = loc;
      if (cnt != loc_count(r))
        st = vm_lex_fail(&r->lx, "%s %lld does not match the %lld %s", kw, (long long)cnt,
                         (long long)loc_count(r), loc == VM_FIELD_VERTEX ? "points" : "cells");
      else
        st = end_line(r, kw);
    } else if (vm_tok_is(s, n, "FIELD")) {
      st = read_field_block(r);
    } else if (is_attribute(s, n)) {
      st = read_attribute(r, s, n);
    } else if (vm_tok_is(s, n, "METADATA")) {
      skip_metadata(r);
    } else {
      st = vm_lex_fail(&r->lx, "unknown keyword '%.*s'", (int)(n > 40 ? 40 : n), s);
    }
  }
  if (!st) st = finish_geometry(r);
  return st;
}

int vm_read_vtk(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  vtkrd r;
  memset(&r, 0, sizeof r);
  r.ctx = ctx;
  r.name = name;
  r.base = (const char *)buf;
  r.loc = -1;
  vm_lex_init(&r.lx, ctx, name, buf, len);
  int st = vm_mesh_create(ctx, &r.m);
  if (!st) st = read_header(&r);
  if (!st) st = read_body(&r);
  if (!st) st = vm_vtk_finish_mesh(ctx, r.m, name);
  for (int k = 0; k < NSEC; k++) {
    vm_free(ctx, r.sec[k].off);
    vm_free(ctx, r.sec[k].conn);
  }
  vm_free(ctx, r.types);
  vm_free(ctx, r.map);
  if (st) {
    vm_mesh_destroy(&r.m);
    return st;
  }
  *out = r.m;
  return VM_OK;
}

/* Legacy writer. */

static void put_be(FILE *fp, uint64_t v, int size) {
  unsigned char b[8];
  for (int i = size - 1; i >= 0; i--, v >>= 8) b[i] = (unsigned char)(v & 0xff);
  fwrite(b, 1, (size_t)size, fp);
}

static void put_f64(FILE *fp, double x, int binary) {
  if (binary) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    put_be(fp, u, 8);
  } else {
    fprintf(fp, "%.17g", x);
  }
}

static void put_i32(FILE *fp, int32_t v, int binary) {
  if (binary)
    put_be(fp, (uint32_t)v, 4);
  else
    fprintf(fp, "%d", (int)v);
}

/* Names go out with blanks, '%' and non-ASCII bytes as %XX, as VTK does. */
static void put_name(FILE *fp, const char *s) {
  for (; *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c <= ' ' || c > '~' || c == '%')
      fprintf(fp, "%%%02X", c);
    else
      fputc(c, fp);
  }
}

static void put_sep(FILE *fp, int binary, int last) {
  if (!binary) fputc(last ? '\n' : ' ', fp);
}

static void write_field(FILE *fp, const char *fname, int ncomp, int64_t n, int type,
                        const void *data, int binary) {
  put_name(fp, fname);
  fprintf(fp, " %d %lld %s\n", ncomp, (long long)n, type == VM_FIELD_F64 ? "double" : "int");
  for (int64_t i = 0; i < n; i++)
    for (int c = 0; c < ncomp; c++) {
      if (type == VM_FIELD_F64)
        put_f64(fp, ((const double *)data)[i * ncomp + c], binary);
      else
        put_i32(fp, ((const int32_t *)data)[i * ncomp + c], binary);
      put_sep(fp, binary, c == ncomp - 1);
    }
  if (binary) fputc('\n', fp);
}

static void write_data_block(FILE *fp, const vm_mesh *m, int loc, int flags, int binary,
                             int32_t *fl) {
  int64_t n = loc == VM_FIELD_VERTEX ? m->nv : m->ne;
  int k = 0;
  for (int i = 0; i < m->nfield; i++)
    k += m->fields[i].location == loc && vm_vtk_field_written(&m->fields[i], flags);
  int withflags = loc == VM_FIELD_VERTEX && flags;
  if (withflags) k += 2;
  if (n == 0 || k == 0) return;
  fprintf(fp, "%s %lld\nFIELD FieldData %d\n", loc == VM_FIELD_VERTEX ? "POINT_DATA" : "CELL_DATA",
          (long long)n, k);
  if (withflags) {
    for (int64_t v = 0; v < m->nv; v++) fl[v] = m->vflag[v];
    write_field(fp, VM_VTK_FLAG_NAME, 1, n, VM_FIELD_I32, fl, binary);
    write_field(fp, VM_VTK_SURF_NAME, 1, n, VM_FIELD_I32, m->vsurf, binary);
  }
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (f->location == loc && vm_vtk_field_written(f, flags))
      write_field(fp, f->name, f->ncomp, n, f->type, f->data, binary);
  }
}

int vm_write_vtk(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  int binary = o && o->binary;
  int flags = vm_vtk_need_flags(m);
  int32_t *fl = NULL;
  if (flags) {
    fl = vm_alloc_array(ctx, (size_t)m->nv, sizeof *fl);
    if (!fl) return VM_ERR_NOMEM;
  }
  vm_outfile *of;
  int st = vm_outfile_open(ctx, path, &of);
  if (st) {
    vm_free(ctx, fl);
    return st;
  }
  FILE *fp = vm_outfile_fp(of);
  fprintf(fp, "# vtk DataFile Version 3.0\nvarmesh %s\n%s\nDATASET UNSTRUCTURED_GRID\n",
          vm_version(), binary ? "BINARY" : "ASCII");
  fprintf(fp, "POINTS %lld double\n", (long long)m->nv);
  for (int64_t v = 0; v < m->nv; v++)
    for (int c = 0; c < 3; c++) {
      put_f64(fp, m->xyz[3 * v + c], binary);
      put_sep(fp, binary, c == 2);
    }
  if (binary && m->nv) fputc('\n', fp);
  int64_t nconn = m->eoff[m->ne];
  fprintf(fp, "CELLS %lld %lld\n", (long long)m->ne, (long long)(m->ne + nconn));
  for (int64_t e = 0; e < m->ne; e++) {
    int64_t k = m->eoff[e + 1] - m->eoff[e];
    put_i32(fp, (int32_t)k, binary);
    for (int64_t j = 0; j < k; j++) {
      put_sep(fp, binary, 0);
      put_i32(fp, m->conn[m->eoff[e] + vm_elem_vtk_node(m->etype[e], (int)j)], binary);
    }
    put_sep(fp, binary, 1);
  }
  if (binary && m->ne) fputc('\n', fp);
  fprintf(fp, "CELL_TYPES %lld\n", (long long)m->ne);
  for (int64_t e = 0; e < m->ne; e++) {
    put_i32(fp, vm_elem_to_vtk(m->etype[e]), binary);
    put_sep(fp, binary, 1);
  }
  if (binary && m->ne) fputc('\n', fp);
  write_data_block(fp, m, VM_FIELD_VERTEX, flags, binary, fl);
  write_data_block(fp, m, VM_FIELD_ELEMENT, flags, binary, NULL);
  vm_free(ctx, fl);
  st = vm_outfile_commit(&of);
  if (st) return st;
  return vm_vtk_report_lost(ctx, m, path, flags) ? VM_WARN_LOSSY : VM_OK;
}
