/* lib/io/src/msh.c: Gmsh .msh reader (4.1 and 2.x, ASCII and binary) and writer (4.1 or 2.2). */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats_private.h"
#include "lex_private.h"

/* Names that carry Gmsh's grouping and varmesh's vertex flags through a .msh file. */
#define MSH_PHYS "gmsh:physical"
#define MSH_ENT "gmsh:entity"
#define MSH_PNAME "gmsh:physical_name:"
#define MSH_FLAG "vm_flag"
#define MSH_SURF "vm_surf"
/* Our own section (Gmsh skips sections it does not know): the mesh dimension
 * and which data sections hold integer fields, so both survive a round trip. */
#define MSH_INFO "VarmeshInfo"

/* vm type -> Gmsh element type. Gmsh's linear cells list their vertices in
 * VTK's order, so connectivity is copied unchanged in both directions. */
static const int gmsh_of_vm[VM_NTYPES] = {2, 3, 4, 7, 6, 5};

static int vm_of_gmsh(int64_t t) {
  switch (t) {
  case 2: return VM_TRI;
  case 3: return VM_QUAD;
  case 4: return VM_TET;
  case 5: return VM_HEX;
  case 6: return VM_PRISM;
  case 7: return VM_PYRAMID;
  default: return -1;
  }
}

/* Gmsh numbers its element types up to about 140; anything from 8 on except
 * the point (15) is higher order or special. */
static const char *gmsh_type_problem(int64_t t) {
  return t >= 8 && t <= 150 && t != 15 ? "is not a linear element (higher order or special)"
                                       : "is not a Gmsh element type";
}

/* The reader: one pass over the buffer; text and binary numbers go through the same helpers. */

typedef struct {
  int32_t dim, tag, phys;
} msh_ent;

typedef struct {
  int64_t key, idx;
} tagpair;

typedef struct {
  int loc;
  char *name;
} msh_i32;

typedef struct {
  int32_t dim, tag;
  int64_t idx;
  char *name;
} msh_pname;

/* Distinct datasets per file: a generous cap that keeps name lookups cheap. */
#define MSH_MAX_DATASETS 1024

typedef struct {
  vm_ctx *ctx;
  const char *name;
  vm_lex lx;
  const char *base;
  int binary, swap, v4;
  char sec[80]; /* current section, for messages */
  vm_mesh *m;
  int have_nodes, have_elems, have_ents;
  int64_t *ntag; /* node tags, ascending, one per vertex */
  int ndense;    /* tags are ntag[0], ntag[0]+1, ... */
  int64_t *etag; /* element tags, ascending, one per element */
  int8_t *edim;
  int32_t *eent, *ephys;
  msh_ent *ents;
  int64_t nent;
  int dim_hint;
  int ni32, cap32;
  msh_i32 *i32;   /* fields listed as integer by $VarmeshInfo */
  int64_t budget; /* field values the file may still ask for */
  int ndata;
  int64_t n_points, n_lines, n_steps, n_multiphys, n_orphan;
} msh_rd;

static int rd_fail_st(msh_rd *r, int status, const char *fmt, va_list ap) {
  char msg[700];
  vsnprintf(msg, sizeof msg, fmt, ap);
  if (r->binary)
    return vm_error(r->ctx, status, "%s: %s: byte %lld: %s", r->name, r->sec,
                    (long long)(r->lx.p - r->base), msg);
  return vm_error(r->ctx, status, "%s: line %lld: %s: %s", r->name, (long long)r->lx.line, r->sec,
                  msg);
}

static int rd_fail(msh_rd *r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static int rd_fail(msh_rd *r, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int st = rd_fail_st(r, VM_ERR_FORMAT, fmt, ap);
  va_end(ap);
  return st;
}

static int rd_unsupported(msh_rd *r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static int rd_unsupported(msh_rd *r, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int st = rd_fail_st(r, VM_ERR_UNSUPPORTED, fmt, ap);
  va_end(ap);
  return st;
}

static int64_t rd_left(const msh_rd *r) { return (int64_t)(r->lx.end - r->lx.p); }

/* A count that claims more items than the bytes left can hold is a lie:
 * refuse it before anything is allocated for it. */
static int rd_guard(msh_rd *r, int64_t count, int64_t minbytes, const char *what) {
  if (count < 0) return rd_fail(r, "negative count of %s: %lld", what, (long long)count);
  if (count > rd_left(r) / minbytes)
    return rd_fail(r, "%lld %s cannot fit in the %lld bytes left", (long long)count, what,
                   (long long)rd_left(r));
  return VM_OK;
}

static int rd_word(msh_rd *r, const char **s, size_t *n, const char *what) {
  if (vm_lex_eof(&r->lx)) return rd_fail(r, "unexpected end of file, expected %s", what);
  return vm_lex_word(&r->lx, s, n, what);
}

/* ASCII integer token (also used for the parts of binary files that stay text). */
static int rd_tint(msh_rd *r, int64_t *v, const char *what) {
  const char *s;
  size_t n;
  int st = rd_word(r, &s, &n, what);
  if (st) return st;
  char buf[32];
  if (n < sizeof buf) {
    memcpy(buf, s, n);
    buf[n] = 0;
    char *e;
    errno = 0;
    long long x = strtoll(buf, &e, 10);
    if (e != buf && !*e && !errno) {
      *v = x;
      return VM_OK;
    }
  }
  return rd_fail(r, "%s: '%.*s' is not an integer", what, (int)(n > 40 ? 40 : n), s);
}

static int rd_tdbl(msh_rd *r, double *v, const char *what) {
  const char *s;
  size_t n;
  int st = rd_word(r, &s, &n, what);
  if (st) return st;
  char buf[64];
  if (n < sizeof buf) {
    memcpy(buf, s, n);
    buf[n] = 0;
    char *e;
    double x = strtod(buf, &e);
    if (e != buf && !*e) {
      *v = x;
      return VM_OK;
    }
  }
  return rd_fail(r, "%s: '%.*s' is not a number", what, (int)(n > 40 ? 40 : n), s);
}

static int rd_raw(msh_rd *r, void *dst, size_t n, const char *what) {
  if (rd_left(r) < (int64_t)n) return rd_fail(r, "unexpected end of file reading %s", what);
  memcpy(dst, r->lx.p, n);
  if (r->swap) {
    uint8_t *b = dst;
    for (size_t i = 0; i < n / 2; i++) {
      uint8_t t = b[i];
      b[i] = b[n - 1 - i];
      b[n - 1 - i] = t;
    }
  }
  r->lx.p += n;
  return VM_OK;
}

/* size_t of the format: 8 bytes in binary files (data-size 8). */
static int rd_size(msh_rd *r, int64_t *v, const char *what) {
  if (r->binary) {
    uint64_t u = 0;
    int st = rd_raw(r, &u, 8, what);
    if (st) return st;
    if (u > (uint64_t)INT64_MAX)
      return rd_fail(r, "%s %llu is too large", what, (unsigned long long)u);
    *v = (int64_t)u;
    return VM_OK;
  }
  int st = rd_tint(r, v, what);
  if (!st && *v < 0) return rd_fail(r, "%s %lld is negative", what, (long long)*v);
  return st;
}

/* int of the format: 4 bytes in binary files. */
static int rd_int(msh_rd *r, int64_t *v, const char *what) {
  if (r->binary) {
    int32_t x = 0;
    int st = rd_raw(r, &x, 4, what);
    if (!st) *v = x;
    return st;
  }
  return rd_tint(r, v, what);
}

static int rd_int32(msh_rd *r, int32_t *v, const char *what) {
  int64_t x;
  int st = rd_int(r, &x, what);
  if (st) return st;
  if (x < INT32_MIN || x > INT32_MAX)
    return rd_fail(r, "%s %lld is out of range", what, (long long)x);
  *v = (int32_t)x;
  return VM_OK;
}

static int rd_dbl(msh_rd *r, double *v, const char *what) {
  if (r->binary) return rd_raw(r, v, 8, what);
  return rd_tdbl(r, v, what);
}

/* End of a text line that binary data follows. */
static int rd_eol(msh_rd *r) {
  const char *s;
  size_t n;
  vm_lex_line(&r->lx, &s, &n);
  while (n && isspace((unsigned char)*s)) {
    s++;
    n--;
  }
  if (n) return rd_fail(r, "unexpected text '%.*s' before binary data", (int)(n > 40 ? 40 : n), s);
  return VM_OK;
}

/* Nonzero if only blanks remain on the current line (ASCII record checks). */
static int rd_line_done(const msh_rd *r) {
  const char *p = r->lx.p;
  while (p < r->lx.end && (*p == ' ' || *p == '\t' || *p == '\r')) p++;
  return p >= r->lx.end || *p == '\n';
}

/* A "quoted string" (names never span lines); a bare word is accepted too. */
static int rd_quoted(msh_rd *r, char **out, const char *what) {
  *out = NULL;
  if (vm_lex_eof(&r->lx)) return rd_fail(r, "unexpected end of file, expected %s", what);
  const char *s = r->lx.p, *q;
  size_t n;
  if (*s == '"') {
    q = s + 1;
    while (q < r->lx.end && *q != '"' && *q != '\n') q++;
    if (q >= r->lx.end || *q != '"') return rd_fail(r, "%s: unterminated string", what);
    n = (size_t)(q - s - 1);
    s++;
    r->lx.p = q + 1;
  } else {
    vm_lex_word(&r->lx, &s, &n, what);
  }
  char *c = vm_malloc(r->ctx, n + 1);
  if (!c) return VM_ERR_NOMEM;
  memcpy(c, s, n);
  c[n] = 0;
  *out = c;
  return VM_OK;
}

static int rd_end(msh_rd *r, const char *sec) {
  char want[96];
  snprintf(want, sizeof want, "$End%s", sec);
  const char *s;
  size_t n;
  int st = rd_word(r, &s, &n, want);
  if (st) return st;
  if (!vm_tok_is(s, n, want))
    return rd_fail(r, "expected %s, found '%.*s'", want, (int)(n > 40 ? 40 : n), s);
  return VM_OK;
}

static int cmp_tagpair(const void *a, const void *b) {
  const tagpair *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return (x->idx > y->idx) - (x->idx < y->idx);
}

/* Sort items by tag: fills tp (n pairs) and reports a duplicate tag. */
static int sort_tags(msh_rd *r, const int64_t *tags, int64_t n, tagpair *tp, const char *what) {
  for (int64_t i = 0; i < n; i++) {
    tp[i].key = tags[i];
    tp[i].idx = i;
  }
  qsort(tp, (size_t)n, sizeof *tp, cmp_tagpair);
  for (int64_t i = 1; i < n; i++)
    if (tp[i].key == tp[i - 1].key)
      return rd_fail(r, "%s tag %lld appears twice", what, (long long)tp[i].key);
  return VM_OK;
}

static void permute(void *arr, size_t esz, const tagpair *tp, int64_t n, void *tmp) {
  char *a = arr, *t = tmp;
  for (int64_t k = 0; k < n; k++) memcpy(t + (size_t)k * esz, a + (size_t)tp[k].idx * esz, esz);
  memcpy(a, t, (size_t)n * esz);
}

/* Vertices are kept in ascending tag order: Gmsh identifies nodes by tag. */
static int finish_nodes(msh_rd *r) {
  vm_mesh *m = r->m;
  int64_t nv = m->nv;
  int sorted = 1;
  for (int64_t i = 1; i < nv && sorted; i++) {
    if (r->ntag[i] == r->ntag[i - 1])
      return rd_fail(r, "node tag %lld appears twice", (long long)r->ntag[i]);
    sorted = r->ntag[i] > r->ntag[i - 1];
  }
  if (!sorted) {
    tagpair *tp = vm_alloc_array(r->ctx, (size_t)nv, sizeof *tp);
    double *tmp = vm_alloc_array(r->ctx, (size_t)nv, 3 * sizeof *tmp);
    int st = tp && tmp ? sort_tags(r, r->ntag, nv, tp, "node") : VM_ERR_NOMEM;
    if (!st) {
      permute(m->xyz, 3 * sizeof(double), tp, nv, tmp);
      for (int64_t i = 0; i < nv; i++) r->ntag[i] = tp[i].key;
    }
    vm_free(r->ctx, tp);
    vm_free(r->ctx, tmp);
    if (st) return st;
  }
  r->ndense = nv == 0 || r->ntag[nv - 1] - r->ntag[0] == nv - 1;
  r->have_nodes = 1;
  return VM_OK;
}

static int node_index(const msh_rd *r, int64_t tag, int32_t *idx) {
  int64_t nv = r->m->nv;
  if (nv == 0) return -1;
  if (r->ndense) {
    if (tag < r->ntag[0] || tag - r->ntag[0] >= nv) return -1;
    *idx = (int32_t)(tag - r->ntag[0]);
    return 0;
  }
  int64_t lo = 0, hi = nv - 1;
  while (lo <= hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (r->ntag[mid] == tag) {
      *idx = (int32_t)mid;
      return 0;
    }
    if (r->ntag[mid] < tag)
      lo = mid + 1;
    else
      hi = mid - 1;
  }
  return -1;
}

static int64_t elem_index(const msh_rd *r, int64_t tag) {
  int64_t lo = 0, hi = r->m->ne - 1;
  while (lo <= hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (r->etag[mid] == tag) return mid;
    if (r->etag[mid] < tag)
      lo = mid + 1;
    else
      hi = mid - 1;
  }
  return -1;
}

static int check_coord(msh_rd *r, const double *p, int64_t tag) {
  if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
    return rd_fail(r, "node %lld: coordinate is not finite", (long long)tag);
  return VM_OK;
}

static int alloc_nodes(msh_rd *r, int64_t nn) {
  if (r->have_nodes) return rd_unsupported(r, "a second $Nodes section is not supported");
  if (nn > INT32_MAX) return rd_unsupported(r, "%lld nodes are too many", (long long)nn);
  int st = vm_mesh_set_vertices(r->m, nn);
  if (st) return st;
  r->ntag = vm_alloc_array(r->ctx, (size_t)nn, sizeof *r->ntag);
  return r->ntag ? VM_OK : VM_ERR_NOMEM;
}

static int read_nodes41(msh_rd *r) {
  int64_t nblk, nn, tmin, tmax;
  int st;
  if (r->binary && (st = rd_eol(r))) return st;
  if ((st = rd_size(r, &nblk, "entity block count")) || (st = rd_size(r, &nn, "node count")) ||
      (st = rd_size(r, &tmin, "minimum node tag")) || (st = rd_size(r, &tmax, "maximum node tag")))
    return st;
  if ((st = rd_guard(r, nn, r->binary ? 32 : 8, "nodes")) ||
      (st = rd_guard(r, nblk, r->binary ? 20 : 8, "node blocks")) || (st = alloc_nodes(r, nn)))
    return st;
  double *xyz = r->m->xyz;
  int64_t pos = 0;
  for (int64_t b = 0; b < nblk; b++) {
    int64_t edim, etag, par, cnt;
    if ((st = rd_int(r, &edim, "entity dimension")) || (st = rd_int(r, &etag, "entity tag")) ||
        (st = rd_int(r, &par, "parametric flag")) || (st = rd_size(r, &cnt, "block node count")))
      return st;
    if (edim < 0 || edim > 3)
      return rd_fail(r, "node block %lld: entity dimension %lld", (long long)b, (long long)edim);
    if (par != 0 && par != 1)
      return rd_fail(r, "node block %lld: parametric flag %lld", (long long)b, (long long)par);
    if (cnt > nn - pos)
      return rd_fail(r, "node block %lld holds more nodes than the %lld announced", (long long)b,
                     (long long)nn);
    for (int64_t i = 0; i < cnt; i++) {
      if ((st = rd_size(r, &r->ntag[pos + i], "node tag"))) return st;
      if (r->ntag[pos + i] < 1)
        return rd_fail(r, "node tag %lld is not positive", (long long)r->ntag[pos + i]);
    }
    int npar = par ? (int)edim : 0;
    for (int64_t i = 0; i < cnt; i++) {
      double *p = xyz + 3 * (pos + i), uvw;
      for (int c = 0; c < 3; c++)
        if ((st = rd_dbl(r, &p[c], "node coordinate"))) return st;
      if ((st = check_coord(r, p, r->ntag[pos + i]))) return st;
      for (int c = 0; c < npar; c++)
        if ((st = rd_dbl(r, &uvw, "parametric coordinate"))) return st;
    }
    pos += cnt;
  }
  if (pos != nn)
    return rd_fail(r, "%lld nodes announced, the blocks hold %lld", (long long)nn, (long long)pos);
  return finish_nodes(r);
}

static int read_nodes2(msh_rd *r) {
  int64_t nn;
  int st = rd_tint(r, &nn, "node count");
  if (st) return st;
  if ((st = rd_guard(r, nn, r->binary ? 28 : 8, "nodes")) || (st = alloc_nodes(r, nn))) return st;
  if (r->binary && (st = rd_eol(r))) return st;
  for (int64_t i = 0; i < nn; i++) {
    double *p = r->m->xyz + 3 * i;
    if ((st = rd_int(r, &r->ntag[i], "node number"))) return st;
    if (r->ntag[i] < 1)
      return rd_fail(r, "node number %lld is not positive", (long long)r->ntag[i]);
    for (int c = 0; c < 3; c++)
      if ((st = rd_dbl(r, &p[c], "node coordinate"))) return st;
    if ((st = check_coord(r, p, r->ntag[i]))) return st;
  }
  return finish_nodes(r);
}

static int alloc_elems(msh_rd *r, int64_t ne) {
  if (!r->have_nodes) return rd_fail(r, "$Elements before $Nodes");
  if (r->have_elems) return rd_unsupported(r, "a second $Elements section is not supported");
  if (ne > INT32_MAX) return rd_unsupported(r, "%lld elements are too many", (long long)ne);
  vm_ctx *ctx = r->ctx;
  r->etag = vm_alloc_array(ctx, (size_t)ne, sizeof *r->etag);
  r->edim = vm_alloc_array(ctx, (size_t)ne, sizeof *r->edim);
  r->eent = vm_alloc_array(ctx, (size_t)ne, sizeof *r->eent);
  r->ephys = vm_alloc_array(ctx, (size_t)ne, sizeof *r->ephys);
  return r->etag && r->edim && r->eent && r->ephys ? VM_OK : VM_ERR_NOMEM;
}

/* Reads one element record's node tags (after its tag) and appends it, or
 * only consumes it for skipped types (vmt < 0). */
static int read_record(msh_rd *r, int64_t et, int vmt, int nn, int64_t line, int dim, int32_t ent,
                       int32_t phys) {
  int32_t v[VM_MAX_ELEM_VERTS];
  int st;
  for (int j = 0; j < nn; j++) {
    int64_t t;
    if ((st = r->v4 ? rd_size(r, &t, "node tag") : rd_int(r, &t, "node number"))) return st;
    if (vmt >= 0 && node_index(r, t, &v[j]))
      return rd_fail(r, "element %lld: node %lld does not exist", (long long)et, (long long)t);
  }
  if (!r->binary && (r->lx.line != line || !rd_line_done(r)))
    return rd_fail(r, "element %lld: expected %d node tags on its line", (long long)et, nn);
  if (vmt < 0) {
    if (nn == 1)
      r->n_points++;
    else
      r->n_lines++;
    return VM_OK;
  }
  int64_t k = r->m->ne;
  if ((st = vm_mesh_add_element(r->m, vmt, v))) return st;
  r->etag[k] = et;
  r->edim[k] = (int8_t)dim;
  r->eent[k] = ent;
  r->ephys[k] = phys;
  return VM_OK;
}

/* Node count of a Gmsh type we read or skip (0 for the others). */
static int gmsh_nodes(int64_t type) {
  int vmt = vm_of_gmsh(type);
  if (vmt >= 0) return vm_elem_nverts(vmt);
  return type == 1 ? 2 : type == 15 ? 1 : 0;
}

static int bad_type(msh_rd *r, int64_t type, int64_t count, const char *what) {
  int64_t et;
  if (count > 0) {
    int st = r->v4 ? rd_size(r, &et, "element tag") : rd_int(r, &et, "element number");
    if (st) return st;
    return rd_unsupported(r, "element %lld: Gmsh element type %lld %s", (long long)et,
                          (long long)type, gmsh_type_problem(type));
  }
  return rd_unsupported(r, "%s: Gmsh element type %lld %s", what, (long long)type,
                        gmsh_type_problem(type));
}

static int finish_elems(msh_rd *r) {
  vm_mesh *m = r->m;
  int64_t ne = m->ne;
  int sorted = 1;
  for (int64_t e = 1; e < ne && sorted; e++) {
    if (r->etag[e] == r->etag[e - 1])
      return rd_fail(r, "element tag %lld appears twice", (long long)r->etag[e]);
    sorted = r->etag[e] > r->etag[e - 1];
  }
  r->have_elems = 1;
  if (sorted) return VM_OK;
  /* elements are kept in ascending tag order, as Gmsh identifies them */
  vm_ctx *ctx = r->ctx;
  tagpair *tp = vm_alloc_array(ctx, (size_t)ne, sizeof *tp);
  int64_t *tmp = vm_alloc_array(ctx, (size_t)ne, sizeof *tmp);
  int st = tp && tmp ? sort_tags(r, r->etag, ne, tp, "element") : VM_ERR_NOMEM;
  if (st) goto done;
  uint8_t *oty = m->etype;
  int64_t *ooff = m->eoff;
  int32_t *ocn = m->conn;
  m->etype = NULL;
  m->eoff = NULL;
  m->conn = NULL;
  if ((st = vm_mesh_set_elements(m, ne, ooff[ne]))) {
    m->etype = oty;
    m->eoff = ooff;
    m->conn = ocn;
    goto done;
  }
  int64_t c = 0;
  for (int64_t k = 0; k < ne; k++) {
    int64_t e = tp[k].idx, n = ooff[e + 1] - ooff[e];
    m->etype[k] = oty[e];
    memcpy(m->conn + c, ocn + ooff[e], (size_t)n * sizeof *ocn);
    c += n;
    m->eoff[k + 1] = c;
  }
  vm_free(ctx, oty);
  vm_free(ctx, ooff);
  vm_free(ctx, ocn);
  for (int64_t k = 0; k < ne; k++) r->etag[k] = tp[k].key;
  permute(r->edim, sizeof *r->edim, tp, ne, tmp);
  permute(r->eent, sizeof *r->eent, tp, ne, tmp);
  permute(r->ephys, sizeof *r->ephys, tp, ne, tmp);
done:
  vm_free(ctx, tp);
  vm_free(ctx, tmp);
  return st;
}

static int read_elems41(msh_rd *r) {
  int64_t nblk, ne, tmin, tmax;
  int st;
  if (r->binary && (st = rd_eol(r))) return st;
  if ((st = rd_size(r, &nblk, "entity block count")) || (st = rd_size(r, &ne, "element count")) ||
      (st = rd_size(r, &tmin, "minimum element tag")) ||
      (st = rd_size(r, &tmax, "maximum element tag")))
    return st;
  if ((st = rd_guard(r, ne, r->binary ? 16 : 4, "elements")) ||
      (st = rd_guard(r, nblk, r->binary ? 20 : 8, "element blocks")) || (st = alloc_elems(r, ne)))
    return st;
  int64_t pos = 0;
  for (int64_t b = 0; b < nblk; b++) {
    int64_t edim, type, cnt;
    int32_t etag;
    if ((st = rd_int(r, &edim, "entity dimension")) || (st = rd_int32(r, &etag, "entity tag")) ||
        (st = rd_int(r, &type, "element type")) || (st = rd_size(r, &cnt, "block element count")))
      return st;
    if (edim < 0 || edim > 3)
      return rd_fail(r, "element block %lld: entity dimension %lld", (long long)b, (long long)edim);
    if (cnt > ne - pos)
      return rd_fail(r, "element block %lld holds more elements than the %lld announced",
                     (long long)b, (long long)ne);
    int vmt = vm_of_gmsh(type), nn = gmsh_nodes(type);
    char what[48];
    snprintf(what, sizeof what, "element block %lld", (long long)b);
    if (!nn) return bad_type(r, type, cnt, what);
    for (int64_t i = 0; i < cnt; i++) {
      int64_t et;
      if ((st = rd_size(r, &et, "element tag"))) return st;
      if (et < 1) return rd_fail(r, "element tag %lld is not positive", (long long)et);
      if ((st = read_record(r, et, vmt, nn, r->lx.line, (int)edim, etag, 0))) return st;
    }
    pos += cnt;
  }
  if (pos != ne)
    return rd_fail(r, "%lld elements announced, the blocks hold %lld", (long long)ne,
                   (long long)pos);
  return finish_elems(r);
}

static int read_tags2(msh_rd *r, int64_t ntags, int32_t *phys, int32_t *ent) {
  *phys = *ent = 0;
  for (int64_t j = 0; j < ntags; j++) {
    int32_t t = 0;
    int st = rd_int32(r, &t, "element tag");
    if (st) return st;
    if (j == 0) *phys = t;
    if (j == 1) *ent = t;
  }
  return VM_OK;
}

static int read_elems2(msh_rd *r) {
  int64_t ne;
  int st = rd_tint(r, &ne, "element count");
  if (st) return st;
  if ((st = rd_guard(r, ne, 8, "elements")) || (st = alloc_elems(r, ne))) return st;
  if (r->binary && (st = rd_eol(r))) return st;
  int64_t pos = 0;
  while (pos < ne) {
    int64_t type, cnt = 1, ntags, num = 0, line = 0;
    if (r->binary) {
      if ((st = rd_int(r, &type, "element type")) || (st = rd_int(r, &cnt, "element count")) ||
          (st = rd_int(r, &ntags, "tag count")))
        return st;
      if (cnt < 0 || cnt > ne - pos)
        return rd_fail(r, "element header announces %lld elements, %lld are left", (long long)cnt,
                       (long long)(ne - pos));
    } else {
      if ((st = rd_int(r, &num, "element number"))) return st;
      line = r->lx.line;
      if ((st = rd_int(r, &type, "element type")) || (st = rd_int(r, &ntags, "tag count")))
        return st;
    }
    if (ntags < 0 || ntags > 1000) return rd_fail(r, "tag count %lld", (long long)ntags);
    int vmt = vm_of_gmsh(type), nn = gmsh_nodes(type);
    if (!nn) {
      if (r->binary) return bad_type(r, type, cnt, "element header");
      return rd_unsupported(r, "element %lld: Gmsh element type %lld %s", (long long)num,
                            (long long)type, gmsh_type_problem(type));
    }
    if (r->binary && (st = rd_guard(r, cnt, 4 * (1 + ntags + nn), "elements"))) return st;
    for (int64_t i = 0; i < cnt; i++) {
      int32_t phys = 0, ent = 0;
      if (r->binary && (st = rd_int(r, &num, "element number"))) return st;
      if (num < 1) return rd_fail(r, "element number %lld is not positive", (long long)num);
      if ((st = read_tags2(r, ntags, &phys, &ent)) ||
          (st = read_record(r, num, vmt, nn, line, vm_elem_dim(vmt), ent, phys)))
        return st;
    }
    pos += cnt;
  }
  return finish_elems(r);
}

static int cmp_ent(const void *a, const void *b) {
  const msh_ent *x = a, *y = b;
  if (x->dim != y->dim) return x->dim < y->dim ? -1 : 1;
  return (x->tag > y->tag) - (x->tag < y->tag);
}

static int read_entities(msh_rd *r) {
  if (r->have_ents) return rd_unsupported(r, "a second $Entities section is not supported");
  int64_t cnt[4], total = 0;
  int st = r->binary ? rd_eol(r) : VM_OK;
  if (st) return st;
  for (int d = 0; d < 4; d++) {
    if ((st = rd_size(r, &cnt[d], "entity count")) ||
        (st = rd_guard(r, cnt[d], d == 0 ? (r->binary ? 36 : 10) : (r->binary ? 68 : 18),
                       "entities")))
      return st;
    total += cnt[d];
  }
  r->ents = vm_alloc_array(r->ctx, (size_t)total, sizeof *r->ents);
  if (!r->ents) return VM_ERR_NOMEM;
  for (int d = 0; d < 4; d++)
    for (int64_t i = 0; i < cnt[d]; i++) {
      msh_ent *e = &r->ents[r->nent];
      double bb;
      int64_t np, nb;
      e->dim = d;
      e->phys = 0;
      if ((st = rd_int32(r, &e->tag, "entity tag"))) return st;
      for (int c = 0; c < (d ? 6 : 3); c++)
        if ((st = rd_dbl(r, &bb, "entity bounding box"))) return st;
      if ((st = rd_size(r, &np, "physical tag count"))) return st;
      for (int64_t j = 0; j < np; j++) {
        int32_t p = 0;
        if ((st = rd_int32(r, &p, "physical tag"))) return st;
        if (j == 0) e->phys = p;
      }
      if (np > 1) r->n_multiphys++;
      if (d > 0) {
        if ((st = rd_size(r, &nb, "bounding entity count"))) return st;
        for (int64_t j = 0; j < nb; j++) {
          int32_t t;
          if ((st = rd_int32(r, &t, "bounding entity tag"))) return st;
        }
      }
      r->nent++;
    }
  qsort(r->ents, (size_t)r->nent, sizeof *r->ents, cmp_ent);
  for (int64_t i = 1; i < r->nent; i++)
    if (!cmp_ent(&r->ents[i], &r->ents[i - 1]))
      return rd_fail(r, "entity (dimension %d, tag %d) is defined twice", (int)r->ents[i].dim,
                     (int)r->ents[i].tag);
  r->have_ents = 1;
  return VM_OK;
}

static int cmp_pname(const void *a, const void *b) {
  const msh_pname *x = a, *y = b;
  if (x->dim != y->dim) return x->dim < y->dim ? -1 : 1;
  if (x->tag != y->tag) return x->tag < y->tag ? -1 : 1;
  return (x->idx > y->idx) - (x->idx < y->idx);
}

/* Sorted names become attributes, the last of equal keys winning; a mesh
 * without attributes takes them in one append, so many groups cost n log n. */
static int add_pnames(msh_rd *r, msh_pname *pn, int64_t n) {
  vm_mesh *m = r->m;
  int fresh = m->nattr == 0;
  if (fresh && n > 0 && !(m->attrs = vm_alloc_array(r->ctx, (size_t)n, sizeof *m->attrs)))
    return VM_ERR_NOMEM;
  for (int64_t i = 0; i < n; i++) {
    if (i + 1 < n && pn[i].dim == pn[i + 1].dim && pn[i].tag == pn[i + 1].tag) continue;
    char key[64];
    snprintf(key, sizeof key, "%s%d:%d", MSH_PNAME, (int)pn[i].dim, (int)pn[i].tag);
    if (!fresh) {
      int st = vm_mesh_set_attr(m, key, pn[i].name);
      if (st) return st;
      continue;
    }
    char *kc = vm_strdup(r->ctx, key);
    if (!kc) return VM_ERR_NOMEM;
    m->attrs[m->nattr].key = kc;
    m->attrs[m->nattr++].value = pn[i].name;
    pn[i].name = NULL;
  }
  return VM_OK;
}

static int read_physnames(msh_rd *r) {
  int64_t n;
  int st = rd_tint(r, &n, "physical name count");
  if (st || (st = rd_guard(r, n, 6, "physical names"))) return st;
  if (n > INT32_MAX / 2) return rd_unsupported(r, "%lld physical names are too many", (long long)n);
  msh_pname *pn = vm_calloc(r->ctx, (size_t)n, sizeof *pn);
  if (!pn) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < n && !st; i++) {
    int64_t dim, tag;
    if ((st = rd_tint(r, &dim, "physical dimension")) || (st = rd_tint(r, &tag, "physical tag")))
      break;
    if (dim < 0 || dim > 3)
      st = rd_fail(r, "physical dimension %lld", (long long)dim);
    else if (tag < INT32_MIN || tag > INT32_MAX)
      st = rd_fail(r, "physical tag %lld", (long long)tag);
    else
      st = rd_quoted(r, &pn[i].name, "physical name");
    pn[i].dim = (int32_t)dim;
    pn[i].tag = (int32_t)tag;
    pn[i].idx = i;
  }
  if (!st) {
    qsort(pn, (size_t)n, sizeof *pn, cmp_pname);
    st = add_pnames(r, pn, n);
  }
  for (int64_t i = 0; i < n; i++) vm_free(r->ctx, pn[i].name);
  vm_free(r->ctx, pn);
  return st;
}

static int is_reserved_elem(const char *name) {
  return !strcmp(name, MSH_PHYS) || !strcmp(name, MSH_ENT);
}

/* $NodeData / $ElementData: the first time step of each named dataset
 * becomes an f64 field; later steps are skipped (and counted). */
static int read_data(msh_rd *r, int loc) {
  vm_ctx *ctx = r->ctx;
  const char *kind = loc == VM_FIELD_VERTEX ? "node" : "element";
  if (loc == VM_FIELD_VERTEX ? !r->have_nodes : !r->have_elems)
    return rd_fail(r, "data before the %ss", kind);
  int64_t nstr, nreal, nint, itag[3] = {0, 0, 0};
  char *name = NULL;
  int st = rd_tint(r, &nstr, "string tag count");
  if (st || (st = rd_guard(r, nstr, 2, "string tags"))) return st;
  for (int64_t i = 0; i < nstr; i++) {
    char *s;
    if ((st = rd_quoted(r, &s, "string tag"))) goto done;
    if (i == 0)
      name = s;
    else
      vm_free(ctx, s);
  }
  if ((st = rd_tint(r, &nreal, "real tag count")) || (st = rd_guard(r, nreal, 2, "real tags")))
    goto done;
  for (int64_t i = 0; i < nreal; i++) {
    double x;
    if ((st = rd_tdbl(r, &x, "real tag"))) goto done;
  }
  if ((st = rd_tint(r, &nint, "integer tag count")) || (st = rd_guard(r, nint, 2, "integer tags")))
    goto done;
  for (int64_t i = 0; i < nint; i++) {
    int64_t x;
    if ((st = rd_tint(r, &x, "integer tag"))) goto done;
    if (i < 3) itag[i] = x;
  }
  if (nint < 3) {
    st = rd_fail(r, "%lld integer tags, expected time step, components and count", (long long)nint);
    goto done;
  }
  int64_t ncomp = itag[1], count = itag[2];
  if (ncomp < 1 || ncomp > (1 << 20)) {
    st = rd_fail(r, "%lld components", (long long)ncomp);
    goto done;
  }
  if ((st = rd_guard(r, count, r->binary ? 4 + 8 * ncomp : 2 * (1 + ncomp), "data values")))
    goto done;
  if (r->binary && (st = rd_eol(r))) goto done;
  const char *nm = name && *name ? name : loc == VM_FIELD_VERTEX ? "NodeData" : "ElementData";
  int skip = 0;
  if (loc == VM_FIELD_ELEMENT && is_reserved_elem(nm)) {
    vm_log(ctx, VM_LOG_WARN, "%s: element data '%s' skipped: the name is reserved for groups",
           r->name, nm);
    skip = 1;
  } else if (vm_mesh_find_field(r->m, nm, loc)) {
    r->n_steps++;
    skip = 1;
  }
  double *data = NULL;
  int64_t stored = 0, items = loc == VM_FIELD_VERTEX ? r->m->nv : r->m->ne;
  if (!skip) {
    /* a field holds a value per item even if the file gives a few: its size
     * is charged to a budget proportional to the file's length */
    int64_t cost = items * ncomp + 256;
    if (r->ndata == MSH_MAX_DATASETS) {
      st = rd_unsupported(r, "more than %d datasets", MSH_MAX_DATASETS);
      goto done;
    }
    if (cost > r->budget) {
      st = rd_fail(r, "'%s': %lld x %lld values are more than this file can hold", nm,
                   (long long)items, (long long)ncomp);
      goto done;
    }
    r->budget -= cost;
    r->ndata++;
    vm_field *f;
    if ((st = vm_mesh_add_field(r->m, nm, loc, VM_FIELD_F64, (int)ncomp, &f))) goto done;
    data = f->data;
  }
  /* binary rows start with a 4-byte tag, whatever the size_t of the header:
   * that is what Gmsh writes and reads */
  for (int64_t i = 0; i < count; i++) {
    int64_t tag, e = -1;
    int32_t v;
    if ((st = r->binary ? rd_int(r, &tag, "data tag") : rd_tint(r, &tag, "data tag"))) goto done;
    if (!skip && loc == VM_FIELD_VERTEX) {
      if (node_index(r, tag, &v)) {
        st = rd_fail(r, "'%s': node %lld does not exist", nm, (long long)tag);
        goto done;
      }
      e = v;
    } else if (!skip) {
      e = elem_index(r, tag);
      if (e < 0) r->n_orphan++;
    }
    stored += e >= 0;
    for (int64_t c = 0; c < ncomp; c++) {
      double x;
      if ((st = rd_dbl(r, &x, "data value"))) goto done;
      if (e >= 0) data[e * ncomp + c] = x; /* NaN stays: views use it for "no value" */
    }
  }
  if (!skip && stored < items)
    vm_log(ctx, VM_LOG_WARN, "%s: '%s' has values for %lld of %lld %ss, the rest are 0", r->name,
           nm, (long long)stored, (long long)items, kind);
done:
  vm_free(ctx, name);
  return st;
}

static int read_info(msh_rd *r) {
  char want[32];
  snprintf(want, sizeof want, "$End%s", MSH_INFO);
  while (!vm_lex_peek_is(&r->lx, want)) {
    const char *s;
    size_t n;
    int st = rd_word(r, &s, &n, want);
    if (st) return st;
    if (vm_tok_is(s, n, "dim")) {
      int64_t d;
      if ((st = rd_tint(r, &d, "dimension"))) return st;
      if (d != 2 && d != 3) return rd_fail(r, "dimension %lld", (long long)d);
      r->dim_hint = (int)d;
    } else if (vm_tok_is(s, n, "i32")) {
      if ((st = rd_word(r, &s, &n, "node or element"))) return st;
      int loc = vm_tok_is(s, n, "node")      ? VM_FIELD_VERTEX
                : vm_tok_is(s, n, "element") ? VM_FIELD_ELEMENT
                                             : -1;
      if (loc < 0)
        return rd_fail(r, "expected node or element, found '%.*s'", (int)(n > 40 ? 40 : n), s);
      if (r->ni32 == INT32_MAX / 2) return rd_unsupported(r, "too many integer fields");
      if (r->ni32 == r->cap32) {
        int cap = r->cap32 ? 2 * r->cap32 : 8;
        msh_i32 *a = vm_realloc(r->ctx, r->i32, (size_t)cap * sizeof *a);
        if (!a) return VM_ERR_NOMEM;
        r->i32 = a;
        r->cap32 = cap;
      }
      if ((st = rd_quoted(r, &r->i32[r->ni32].name, "field name"))) return st;
      r->i32[r->ni32++].loc = loc;
    } else {
      const char *rest;
      vm_lex_line(&r->lx, &rest, &n); /* newer keyword: ignore its line */
    }
  }
  return VM_OK;
}

/* Skips a section we do not read, binary or not, up to its $End line. */
static int skip_section(msh_rd *r, const char *sec) {
  size_t n = strlen(sec);
  for (const char *p = r->lx.p; p + 4 + n <= r->lx.end; p++) {
    if (*p != '$' || (p > r->base && p[-1] != '\n')) continue;
    if (strncasecmp(p + 1, "End", 3) || strncasecmp(p + 4, sec, n)) continue;
    if (p + 4 + n < r->lx.end && !isspace((unsigned char)p[4 + n])) continue;
    for (const char *q = r->lx.p; q < p; q++) r->lx.line += *q == '\n';
    r->lx.p = p + 4 + n;
    return VM_OK;
  }
  return rd_fail(r, "no $End%s", sec);
}

static int read_format(msh_rd *r) {
  const char *s;
  size_t n;
  int64_t ftype, dsize;
  snprintf(r->sec, sizeof r->sec, "$MeshFormat");
  int st = rd_word(r, &s, &n, "$MeshFormat");
  if (st) return st;
  if (!vm_tok_is(s, n, "$MeshFormat"))
    return rd_fail(r, "not a Gmsh .msh file: it does not start with $MeshFormat");
  if ((st = rd_word(r, &s, &n, "version"))) return st;
  char ver[16];
  if (n >= sizeof ver) return rd_fail(r, "bad version '%.*s'", 15, s);
  memcpy(ver, s, n);
  ver[n] = 0;
  if (!strcmp(ver, "4.1"))
    r->v4 = 1;
  else if (strcmp(ver, "2.2") && strcmp(ver, "2.1") && strcmp(ver, "2.0") && strcmp(ver, "2"))
    return rd_unsupported(r, "MSH version %s is not supported (4.1 and 2.x are)", ver);
  if ((st = rd_tint(r, &ftype, "file type")) || (st = rd_tint(r, &dsize, "data size"))) return st;
  if (ftype != 0 && ftype != 1) return rd_fail(r, "file type %lld is not 0 or 1", (long long)ftype);
  if (dsize != 8)
    return rd_unsupported(r, "data size %lld (only 8 is supported)", (long long)dsize);
  if (ftype == 1) {
    int32_t one = 0;
    r->binary = 1;
    if ((st = rd_eol(r)) || (st = rd_raw(r, &one, 4, "endianness check"))) return st;
    if (one == 0x01000000)
      r->swap = 1;
    else if (one != 1)
      return rd_fail(r, "endianness check reads %d, expected 1", (int)one);
  }
  return rd_end(r, "MeshFormat");
}

static int cmp_ent_key(const msh_ent *e, int dim, int32_t tag) {
  if (e->dim != dim) return e->dim < dim ? -1 : 1;
  return (e->tag > tag) - (e->tag < tag);
}

static int32_t entity_phys(const msh_rd *r, int dim, int32_t tag) {
  int64_t lo = 0, hi = r->nent - 1;
  while (lo <= hi) {
    int64_t mid = lo + (hi - lo) / 2;
    int c = cmp_ent_key(&r->ents[mid], dim, tag);
    if (!c) return r->ents[mid].phys;
    if (c < 0)
      lo = mid + 1;
    else
      hi = mid - 1;
  }
  return 0;
}

static int add_i32_field(vm_mesh *m, const char *name, const int32_t *src) {
  vm_field *f;
  int st = vm_mesh_add_field(m, name, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  if (!st && m->ne) memcpy(f->data, src, (size_t)m->ne * sizeof *src);
  return st;
}

static int cmp_i32(const void *a, const void *b) {
  const msh_i32 *x = a, *y = b;
  if (x->loc != y->loc) return x->loc < y->loc ? -1 : 1;
  return strcmp(x->name, y->name);
}

/* Integral f64 values -> i32 data in place; 1 if the values did not fit. */
static int to_i32(vm_ctx *ctx, const vm_mesh *m, vm_field *f, int *st) {
  int64_t n = vm_field_count(m, f) * f->ncomp;
  const double *d = f->data;
  *st = VM_OK;
  for (int64_t i = 0; i < n; i++)
    if (d[i] != floor(d[i]) || d[i] < INT32_MIN || d[i] > INT32_MAX) return 1;
  int32_t *v = vm_alloc_array(ctx, (size_t)n, sizeof *v);
  if (!v) {
    *st = VM_ERR_NOMEM;
    return 0;
  }
  for (int64_t i = 0; i < n; i++) v[i] = (int32_t)d[i];
  vm_free(ctx, f->data);
  f->data = v;
  f->type = VM_FIELD_I32;
  return 0;
}

static int finish(msh_rd *r) {
  vm_mesh *m = r->m;
  vm_ctx *ctx = r->ctx;
  int st;
  snprintf(r->sec, sizeof r->sec, "end of file");
  if (!r->have_nodes) return rd_fail(r, "no $Nodes section (truncated file?)");
  if (!r->have_elems) return rd_fail(r, "no $Elements section (truncated file?)");
  if (r->v4)
    for (int64_t e = 0; e < m->ne; e++)
      r->ephys[e] = r->have_ents ? entity_phys(r, r->edim[e], r->eent[e]) : 0;
  if ((st = add_i32_field(m, MSH_PHYS, r->ephys)) || (st = add_i32_field(m, MSH_ENT, r->eent)))
    return st;
  vm_field *f = vm_mesh_find_field(m, MSH_FLAG, VM_FIELD_VERTEX);
  if (f && f->ncomp == 1) {
    const double *d = f->data;
    for (int64_t v = 0; v < m->nv; v++) {
      if (d[v] != VM_VERTEX_FREE && d[v] != VM_VERTEX_FIXED && d[v] != VM_VERTEX_SLIP)
        return rd_fail(r, "%s of node %lld is %g, not a vertex flag", MSH_FLAG,
                       (long long)r->ntag[v], d[v]);
      m->vflag[v] = (uint8_t)d[v];
    }
    vm_mesh_remove_field(m, MSH_FLAG, VM_FIELD_VERTEX);
  }
  f = vm_mesh_find_field(m, MSH_SURF, VM_FIELD_VERTEX);
  if (f && f->ncomp == 1) {
    const double *d = f->data;
    for (int64_t v = 0; v < m->nv; v++) {
      if (d[v] != floor(d[v]) || d[v] < INT32_MIN || d[v] > INT32_MAX)
        return rd_fail(r, "%s of node %lld is %g, not a surface id", MSH_SURF,
                       (long long)r->ntag[v], d[v]);
      m->vsurf[v] = (int32_t)d[v];
    }
    vm_mesh_remove_field(m, MSH_SURF, VM_FIELD_VERTEX);
  }
  if (r->ni32) qsort(r->i32, (size_t)r->ni32, sizeof *r->i32, cmp_i32);
  for (int i = 0; i < m->nfield; i++) {
    f = &m->fields[i];
    msh_i32 key = {f->location, f->name};
    if (f->type != VM_FIELD_F64 || !r->ni32 ||
        !bsearch(&key, r->i32, (size_t)r->ni32, sizeof *r->i32, cmp_i32))
      continue;
    if (to_i32(ctx, m, f, &st))
      vm_log(ctx, VM_LOG_WARN,
             "%s: field '%s' is listed as integer but has other values; kept as f64", r->name,
             f->name);
    if (st) return st;
  }
  int flat = 1, has3d = 0;
  for (int64_t v = 0; v < m->nv && flat; v++) flat = m->xyz[3 * v + 2] == 0.0;
  for (int64_t e = 0; e < m->ne && !has3d; e++) has3d = vm_elem_dim(m->etype[e]) == 3;
  if (r->dim_hint == 2 && (!flat || has3d)) {
    vm_log(ctx, VM_LOG_WARN, "%s: dimension 2 announced but the mesh is not planar; using 3",
           r->name);
    m->dim = 3;
  } else if (r->dim_hint) {
    m->dim = r->dim_hint;
  } else {
    m->dim = m->nv > 0 && flat && !has3d ? 2 : 3;
  }
  if (r->n_points || r->n_lines)
    vm_log(ctx, VM_LOG_WARN, "%s: skipped %lld point and %lld line elements", r->name,
           (long long)r->n_points, (long long)r->n_lines);
  if (r->n_steps)
    vm_log(ctx, VM_LOG_WARN, "%s: kept the first time step of each dataset, skipped %lld more",
           r->name, (long long)r->n_steps);
  if (r->n_multiphys)
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld entities belong to several physical groups; only the first is kept", r->name,
           (long long)r->n_multiphys);
  if (r->n_orphan)
    vm_log(ctx, VM_LOG_WARN, "%s: ignored %lld element data rows of elements not read", r->name,
           (long long)r->n_orphan);
  return VM_OK;
}

static int read_sections(msh_rd *r) {
  int st = read_format(r);
  if (st) return st;
  while (!vm_lex_eof(&r->lx)) {
    const char *s;
    size_t n;
    vm_lex_word(&r->lx, &s, &n, "section");
    if (n < 2 || n > 64 || s[0] != '$')
      return rd_fail(r, "expected a section like $Nodes, found '%.*s'", (int)(n > 40 ? 40 : n), s);
    char sec[72];
    memcpy(sec, s + 1, n - 1);
    sec[n - 1] = 0;
    snprintf(r->sec, sizeof r->sec, "$%s", sec);
    if (!strcasecmp(sec, "PhysicalNames"))
      st = read_physnames(r);
    else if (!strcasecmp(sec, "Entities") && r->v4)
      st = read_entities(r);
    else if (!strcasecmp(sec, "Nodes"))
      st = r->v4 ? read_nodes41(r) : read_nodes2(r);
    else if (!strcasecmp(sec, "Elements"))
      st = r->v4 ? read_elems41(r) : read_elems2(r);
    else if (!strcasecmp(sec, "NodeData"))
      st = read_data(r, VM_FIELD_VERTEX);
    else if (!strcasecmp(sec, "ElementData"))
      st = read_data(r, VM_FIELD_ELEMENT);
    else if (!strcasecmp(sec, MSH_INFO))
      st = read_info(r);
    else if (!strcasecmp(sec, "MeshFormat"))
      st = rd_fail(r, "a second $MeshFormat");
    else {
      if (strcasecmp(sec, "Comments"))
        vm_log(r->ctx, VM_LOG_WARN, "%s: skipped section $%s", r->name, sec);
      if ((st = skip_section(r, sec))) return st;
      continue;
    }
    if (st || (st = rd_end(r, sec))) return st;
  }
  return finish(r);
}

int vm_read_msh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  msh_rd r;
  memset(&r, 0, sizeof r);
  r.ctx = ctx;
  r.name = name;
  r.base = (const char *)buf;
  r.budget = 16 * (int64_t)len + 65536;
  vm_lex_init(&r.lx, ctx, name, buf, len);
  int st = vm_mesh_create(ctx, &r.m);
  if (!st) st = read_sections(&r);
  vm_free(ctx, r.ntag);
  vm_free(ctx, r.etag);
  vm_free(ctx, r.edim);
  vm_free(ctx, r.eent);
  vm_free(ctx, r.ephys);
  vm_free(ctx, r.ents);
  for (int i = 0; i < r.ni32; i++) vm_free(ctx, r.i32[i].name);
  vm_free(ctx, r.i32);
  if (st < 0) {
    vm_mesh_destroy(&r.m);
    return vm_error_name_prefix(ctx, st, name);
  }
  *out = r.m;
  return VM_OK;
}

/* The writer: entities are planned from the group fields, then each section is written once. */

typedef struct {
  int32_t dim, tag, phys;
  double lo[3], hi[3];
} msh_went;

typedef struct {
  int32_t k[3];
  int64_t idx;
} ekey;

typedef struct {
  int32_t *ent;   /* entity tag per element */
  int32_t *phys;  /* physical tag per element */
  msh_went *ents; /* sorted by (dim, tag) */
  int64_t nent;
  int32_t node_dim, node_tag;
  int lossy;
} msh_plan;

static int cmp_ekey(const void *a, const void *b) {
  const ekey *x = a, *y = b;
  for (int i = 0; i < 3; i++)
    if (x->k[i] != y->k[i]) return x->k[i] < y->k[i] ? -1 : 1;
  return (x->idx > y->idx) - (x->idx < y->idx);
}

static int name_ok(const char *s) { return *s && !strpbrk(s, "\"\n\r"); }

/* A physical-name attribute we can write: "gmsh:physical_name:<dim>:<tag>". */
static int pname_ok(const vm_attr *a, int *dim, int32_t *tag) {
  size_t n = strlen(MSH_PNAME);
  if (strncmp(a->key, MSH_PNAME, n) || !name_ok(a->value)) return 0;
  const char *s = a->key + n;
  char *e;
  if (!isdigit((unsigned char)*s)) return 0;
  long d = strtol(s, &e, 10);
  if (*e != ':' || d > 3) return 0;
  s = e + 1;
  if (!isdigit((unsigned char)*s) && *s != '-') return 0;
  errno = 0;
  long long t = strtoll(s, &e, 10);
  if (*e || errno || t < INT32_MIN || t > INT32_MAX) return 0;
  *dim = (int)d;
  *tag = (int32_t)t;
  return 1;
}

/* 1: the element group fields; 0: written as data; -1: cannot be written. */
static int field_role(const vm_field *f) {
  int group = f->location == VM_FIELD_ELEMENT && is_reserved_elem(f->name);
  if (group) return f->type == VM_FIELD_I32 && f->ncomp == 1 ? 1 : -1;
  if (f->location == VM_FIELD_VERTEX && (!strcmp(f->name, MSH_FLAG) || !strcmp(f->name, MSH_SURF)))
    return -1;
  return name_ok(f->name) ? 0 : -1;
}

static void plan_free(vm_ctx *ctx, msh_plan *p) {
  vm_free(ctx, p->ent);
  vm_free(ctx, p->phys);
  vm_free(ctx, p->ents);
}

/* Losses are logged here, once each, before anything is written. */
static void plan_losses(vm_ctx *ctx, const vm_mesh *m, const char *path, msh_plan *p) {
  for (int i = 0; i < m->nattr; i++) {
    int d;
    int32_t t = 0;
    if (pname_ok(&m->attrs[i], &d, &t)) continue;
    vm_log(ctx, VM_LOG_WARN, "%s: attribute '%s' cannot be stored in .msh; dropped", path,
           m->attrs[i].key);
    p->lossy = 1;
  }
  for (int i = 0; i < m->nfield; i++) {
    if (field_role(&m->fields[i]) >= 0) continue;
    vm_log(ctx, VM_LOG_WARN, "%s: %s field '%s' cannot be stored in .msh; dropped", path,
           m->fields[i].location == VM_FIELD_VERTEX ? "vertex" : "element", m->fields[i].name);
    p->lossy = 1;
  }
}

static int plan_groups(vm_ctx *ctx, const vm_mesh *m, const char *path, msh_plan *p) {
  int64_t ne = m->ne;
  const vm_field *fp = vm_mesh_find_field(m, MSH_PHYS, VM_FIELD_ELEMENT);
  const vm_field *fe = vm_mesh_find_field(m, MSH_ENT, VM_FIELD_ELEMENT);
  if (fp && field_role(fp) != 1) fp = NULL;
  if (fe && field_role(fe) != 1) fe = NULL;
  p->ent = vm_alloc_array(ctx, (size_t)ne, sizeof *p->ent);
  p->phys = vm_alloc_array(ctx, (size_t)ne, sizeof *p->phys);
  ekey *k = vm_alloc_array(ctx, (size_t)ne, sizeof *k);
  if (!p->ent || !p->phys || !k) {
    vm_free(ctx, k);
    return VM_ERR_NOMEM;
  }
  int64_t nneg = 0, nrenum = 0;
  for (int64_t e = 0; e < ne; e++) {
    int32_t ph = fp ? ((const int32_t *)fp->data)[e] : 0;
    if (ph < 0) {
      nneg++;
      ph = 0;
    }
    p->phys[e] = ph;
    k[e].k[0] = vm_elem_dim(m->etype[e]);
    k[e].k[1] = fe ? ((const int32_t *)fe->data)[e] : 0;
    k[e].k[2] = ph;
    k[e].idx = e;
  }
  qsort(k, (size_t)ne, sizeof *k, cmp_ekey);
  /* one entity per (dimension, tag) with a single physical group: an entity
   * tag shared by two groups, or not positive, gets a fresh tag */
  int st = VM_OK;
  for (int64_t i = 0, j; i < ne; i = j) {
    for (j = i; j < ne && k[j].k[0] == k[i].k[0];) j++;
    int64_t next = (k[j - 1].k[1] > 0 ? k[j - 1].k[1] : 0) + 1;
    for (int64_t a = i, b; a < j; a = b) {
      for (b = a; b < j && k[b].k[1] == k[a].k[1] && k[b].k[2] == k[a].k[2];) b++;
      int32_t tag = k[a].k[1];
      if (tag <= 0 || (a > i && k[a - 1].k[1] == tag)) {
        if (next > INT32_MAX) {
          st = vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: entity tags exhausted", path);
          goto done;
        }
        tag = (int32_t)next++;
        if (fe) nrenum += b - a;
      }
      for (int64_t t = a; t < b; t++) p->ent[k[t].idx] = tag;
    }
  }
  if (nneg) {
    vm_log(ctx, VM_LOG_WARN, "%s: %lld elements have a negative %s; written without a group", path,
           (long long)nneg, MSH_PHYS);
    p->lossy = 1;
  }
  if (nrenum) {
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld elements got new %s tags (a .msh entity has positive tags and one group)",
           path, (long long)nrenum, MSH_ENT);
    p->lossy = 1;
  }
  for (int64_t e = 0; e < ne; e++) {
    k[e].k[0] = vm_elem_dim(m->etype[e]);
    k[e].k[1] = p->ent[e];
    k[e].k[2] = gmsh_of_vm[m->etype[e]];
    k[e].idx = e;
  }
  qsort(k, (size_t)ne, sizeof *k, cmp_ekey);
  p->nent = 0;
  for (int64_t e = 0; e < ne; e++)
    p->nent += !e || k[e].k[0] != k[e - 1].k[0] || k[e].k[1] != k[e - 1].k[1];
  p->ents = vm_calloc(ctx, (size_t)p->nent, sizeof *p->ents);
  if (!p->ents) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t e = 0, n = -1; e < ne; e++) {
    int64_t idx = k[e].idx;
    if (!e || k[e].k[0] != k[e - 1].k[0] || k[e].k[1] != k[e - 1].k[1]) {
      msh_went *w = &p->ents[++n];
      w->dim = k[e].k[0];
      w->tag = k[e].k[1];
      w->phys = p->phys[idx];
      for (int c = 0; c < 3; c++) {
        w->lo[c] = HUGE_VAL;
        w->hi[c] = -HUGE_VAL;
      }
    }
    msh_went *w = &p->ents[n];
    for (int64_t c = m->eoff[idx]; c < m->eoff[idx + 1]; c++)
      for (int d = 0; d < 3; d++) {
        double x = m->xyz[3 * (int64_t)m->conn[c] + d];
        if (x < w->lo[d]) w->lo[d] = x;
        if (x > w->hi[d]) w->hi[d] = x;
      }
  }
  p->node_dim = m->dim;
  p->node_tag = 1;
  if (p->nent) {
    int64_t i = p->nent - 1;
    while (i > 0 && p->ents[i - 1].dim == p->ents[p->nent - 1].dim) i--;
    p->node_dim = p->ents[i].dim;
    p->node_tag = p->ents[i].tag;
  }
done:
  vm_free(ctx, k);
  return st;
}

static void put_i32(FILE *fp, int32_t v) { fwrite(&v, sizeof v, 1, fp); }
static void put_u64(FILE *fp, uint64_t v) { fwrite(&v, sizeof v, 1, fp); }
static void put_f64(FILE *fp, double v) { fwrite(&v, sizeof v, 1, fp); }

static void write_header(FILE *fp, int bin, const char *ver) {
  fprintf(fp, "$MeshFormat\n%s %d 8\n", ver, bin);
  if (bin) {
    put_i32(fp, 1);
    fputc('\n', fp);
  }
  fputs("$EndMeshFormat\n", fp);
}

static void write_physnames(FILE *fp, const vm_mesh *m) {
  int n = 0, d;
  int32_t t;
  for (int i = 0; i < m->nattr; i++) n += pname_ok(&m->attrs[i], &d, &t);
  if (!n) return;
  fprintf(fp, "$PhysicalNames\n%d\n", n);
  for (int i = 0; i < m->nattr; i++)
    if (pname_ok(&m->attrs[i], &d, &t)) fprintf(fp, "%d %d \"%s\"\n", d, (int)t, m->attrs[i].value);
  fputs("$EndPhysicalNames\n", fp);
}

static void write_entities41(FILE *fp, int bin, const msh_plan *p) {
  int64_t cnt[4] = {0, 0, 0, 0};
  if (!p->nent) return;
  for (int64_t i = 0; i < p->nent; i++) cnt[p->ents[i].dim]++;
  fputs("$Entities\n", fp);
  if (bin)
    for (int d = 0; d < 4; d++) put_u64(fp, (uint64_t)cnt[d]);
  else
    fprintf(fp, "%lld %lld %lld %lld\n", (long long)cnt[0], (long long)cnt[1], (long long)cnt[2],
            (long long)cnt[3]);
  for (int64_t i = 0; i < p->nent; i++) {
    const msh_went *w = &p->ents[i];
    if (bin) {
      put_i32(fp, w->tag);
      for (int c = 0; c < 3; c++) put_f64(fp, w->lo[c]);
      for (int c = 0; c < 3; c++) put_f64(fp, w->hi[c]);
      put_u64(fp, w->phys ? 1 : 0);
      if (w->phys) put_i32(fp, w->phys);
      put_u64(fp, 0);
    } else {
      fprintf(fp, "%d %.17g %.17g %.17g %.17g %.17g %.17g", (int)w->tag, w->lo[0], w->lo[1],
              w->lo[2], w->hi[0], w->hi[1], w->hi[2]);
      if (w->phys)
        fprintf(fp, " 1 %d 0\n", (int)w->phys);
      else
        fputs(" 0 0\n", fp);
    }
  }
  if (bin) fputc('\n', fp);
  fputs("$EndEntities\n", fp);
}

static void write_nodes41(FILE *fp, int bin, const vm_mesh *m, const msh_plan *p) {
  int64_t nv = m->nv;
  fputs("$Nodes\n", fp);
  if (bin) {
    put_u64(fp, nv ? 1 : 0);
    put_u64(fp, (uint64_t)nv);
    put_u64(fp, nv ? 1 : 0);
    put_u64(fp, (uint64_t)nv);
    if (nv) {
      put_i32(fp, p->node_dim);
      put_i32(fp, p->node_tag);
      put_i32(fp, 0);
      put_u64(fp, (uint64_t)nv);
    }
    for (int64_t v = 0; v < nv; v++) put_u64(fp, (uint64_t)(v + 1));
    if (nv) fwrite(m->xyz, sizeof(double), (size_t)(3 * nv), fp);
    fputc('\n', fp);
  } else if (!nv) {
    fputs("0 0 0 0\n", fp);
  } else {
    fprintf(fp, "1 %lld 1 %lld\n%d %d 0 %lld\n", (long long)nv, (long long)nv, (int)p->node_dim,
            (int)p->node_tag, (long long)nv);
    for (int64_t v = 0; v < nv; v++) fprintf(fp, "%lld\n", (long long)(v + 1));
    for (int64_t v = 0; v < nv; v++)
      fprintf(fp, "%.17g %.17g %.17g\n", m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2]);
  }
  fputs("$EndNodes\n", fp);
}

/* A block: elements of one type on one entity (the type fixes the dimension).
 * Blocks are the runs of such elements in mesh order, and element tags are
 * 1..N in file order, which is the mesh's: readers that number elements by
 * their position in the file (meshio puts $ElementData on cells that way)
 * and readers that go by the tags (Gmsh, ours) then agree, and a round trip
 * keeps the element order. A mesh whose types or groups interleave gets
 * many small blocks, which is valid .msh. */
static int same_block(const vm_mesh *m, const msh_plan *p, int64_t a, int64_t b) {
  return p->ent[a] == p->ent[b] && m->etype[a] == m->etype[b];
}

static void write_elems41(FILE *fp, int bin, const vm_mesh *m, const msh_plan *p) {
  int64_t ne = m->ne, nblk = 0;
  for (int64_t e = 0; e < ne; e++) nblk += !e || !same_block(m, p, e, e - 1);
  fputs("$Elements\n", fp);
  if (bin) {
    put_u64(fp, (uint64_t)nblk);
    put_u64(fp, (uint64_t)ne);
    put_u64(fp, ne ? 1 : 0);
    put_u64(fp, (uint64_t)ne);
  } else {
    fprintf(fp, "%lld %lld %d %lld\n", (long long)nblk, (long long)ne, ne ? 1 : 0, (long long)ne);
  }
  for (int64_t i = 0, j; i < ne; i = j) {
    for (j = i + 1; j < ne && same_block(m, p, j, i);) j++;
    int t = m->etype[i];
    if (bin) {
      put_i32(fp, vm_elem_dim(t));
      put_i32(fp, p->ent[i]);
      put_i32(fp, gmsh_of_vm[t]);
      put_u64(fp, (uint64_t)(j - i));
    } else {
      fprintf(fp, "%d %d %d %lld\n", vm_elem_dim(t), (int)p->ent[i], gmsh_of_vm[t],
              (long long)(j - i));
    }
    for (int64_t e = i; e < j; e++) {
      if (bin)
        put_u64(fp, (uint64_t)(e + 1));
      else
        fprintf(fp, "%lld", (long long)(e + 1));
      for (int64_t c = m->eoff[e]; c < m->eoff[e + 1]; c++) {
        if (bin)
          put_u64(fp, (uint64_t)m->conn[c] + 1);
        else
          fprintf(fp, " %d", m->conn[c] + 1);
      }
      if (!bin) fputc('\n', fp);
    }
  }
  if (bin) fputc('\n', fp);
  fputs("$EndElements\n", fp);
}

static void write_nodes22(FILE *fp, int bin, const vm_mesh *m) {
  fprintf(fp, "$Nodes\n%lld\n", (long long)m->nv);
  for (int64_t v = 0; v < m->nv; v++) {
    const double *x = m->xyz + 3 * v;
    if (bin) {
      put_i32(fp, (int32_t)(v + 1));
      fwrite(x, sizeof *x, 3, fp);
    } else {
      fprintf(fp, "%lld %.17g %.17g %.17g\n", (long long)(v + 1), x[0], x[1], x[2]);
    }
  }
  if (bin) fputc('\n', fp);
  fputs("$EndNodes\n", fp);
}

static void write_elems22(FILE *fp, int bin, const vm_mesh *m, const msh_plan *p) {
  int64_t ne = m->ne;
  fprintf(fp, "$Elements\n%lld\n", (long long)ne);
  for (int64_t i = 0, j; i < ne; i = j) {
    for (j = i + 1; j < ne && m->etype[j] == m->etype[i];) j++;
    int t = gmsh_of_vm[m->etype[i]];
    if (bin) {
      put_i32(fp, t);
      put_i32(fp, (int32_t)(j - i));
      put_i32(fp, 2);
    }
    for (int64_t e = i; e < j; e++) {
      if (bin) {
        put_i32(fp, (int32_t)(e + 1));
        put_i32(fp, p->phys[e]);
        put_i32(fp, p->ent[e]);
      } else {
        fprintf(fp, "%lld %d 2 %d %d", (long long)(e + 1), t, (int)p->phys[e], (int)p->ent[e]);
      }
      for (int64_t c = m->eoff[e]; c < m->eoff[e + 1]; c++) {
        if (bin)
          put_i32(fp, m->conn[c] + 1);
        else
          fprintf(fp, " %d", m->conn[c] + 1);
      }
      if (!bin) fputc('\n', fp);
    }
  }
  if (bin) fputc('\n', fp);
  fputs("$EndElements\n", fp);
}

static void write_info(FILE *fp, const vm_mesh *m) {
  fprintf(fp, "$%s\ndim %d\n", MSH_INFO, m->dim);
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (f->type == VM_FIELD_I32 && field_role(f) == 0)
      fprintf(fp, "i32 %s \"%s\"\n", f->location == VM_FIELD_VERTEX ? "node" : "element", f->name);
  }
  fprintf(fp, "$End%s\n", MSH_INFO);
}

/* One dataset: from f64 or i32 field data, or from the vertex flags. */
typedef struct {
  const char *name;
  int loc, ncomp;
  const double *f;
  const int32_t *i;
  const uint8_t *u;
} msh_src;

static double src_value(const msh_src *s, int64_t k) {
  return s->f ? s->f[k] : s->i ? (double)s->i[k] : (double)s->u[k];
}

static void write_data(FILE *fp, int bin, const msh_src *s, int64_t n) {
  const char *sec = s->loc == VM_FIELD_VERTEX ? "NodeData" : "ElementData";
  fprintf(fp, "$%s\n1\n\"%s\"\n1\n0\n3\n0\n%d\n%lld\n", sec, s->name, s->ncomp, (long long)n);
  for (int64_t i = 0; i < n; i++) {
    if (bin) {
      put_i32(fp, (int32_t)(i + 1));
      for (int c = 0; c < s->ncomp; c++) put_f64(fp, src_value(s, i * s->ncomp + c));
      continue;
    }
    fprintf(fp, "%lld", (long long)(i + 1));
    for (int c = 0; c < s->ncomp; c++) {
      int64_t k = i * s->ncomp + c;
      if (s->f)
        fprintf(fp, " %.17g", s->f[k]);
      else
        fprintf(fp, " %d", s->i ? (int)s->i[k] : (int)s->u[k]);
    }
    fputc('\n', fp);
  }
  if (bin) fputc('\n', fp);
  fprintf(fp, "$End%s\n", sec);
}

static void write_fields(FILE *fp, int bin, const vm_mesh *m) {
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (field_role(f) != 0) continue;
    msh_src s = {f->name, f->location, f->ncomp, NULL, NULL, NULL};
    if (f->type == VM_FIELD_F64)
      s.f = f->data;
    else
      s.i = f->data;
    write_data(fp, bin, &s, vm_field_count(m, f));
  }
  int flags = 0, surf = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    flags |= m->vflag[v] != VM_VERTEX_FREE;
    surf |= m->vsurf[v] != -1;
  }
  msh_src s = {MSH_FLAG, VM_FIELD_VERTEX, 1, NULL, NULL, m->vflag};
  if (flags) write_data(fp, bin, &s, m->nv);
  msh_src t = {MSH_SURF, VM_FIELD_VERTEX, 1, NULL, m->vsurf, NULL};
  if (surf) write_data(fp, bin, &t, m->nv);
}

int vm_write_msh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  int ver = o && o->msh_version ? o->msh_version : 41;
  int bin = o && o->binary;
  if (ver != 41 && ver != 22)
    return vm_error(ctx, VM_ERR_ARG, "%s: .msh version %d is not 41 or 22", path, ver);
  msh_plan p;
  memset(&p, 0, sizeof p);
  int st = plan_groups(ctx, m, path, &p);
  if (st) {
    plan_free(ctx, &p);
    if (st == VM_ERR_NOMEM) vm_error(ctx, st, "%s: out of memory", path);
    return st;
  }
  plan_losses(ctx, m, path, &p);
  vm_outfile *of;
  if ((st = vm_outfile_open(ctx, path, &of))) {
    plan_free(ctx, &p);
    if (st == VM_ERR_NOMEM) vm_error(ctx, st, "%s: out of memory", path);
    return st;
  }
  FILE *fp = vm_outfile_fp(of);
  write_header(fp, bin, ver == 41 ? "4.1" : "2.2");
  write_physnames(fp, m);
  if (ver == 41) {
    write_entities41(fp, bin, &p);
    write_nodes41(fp, bin, m, &p);
    write_elems41(fp, bin, m, &p);
  } else {
    write_nodes22(fp, bin, m);
    write_elems22(fp, bin, m, &p);
  }
  write_info(fp, m);
  write_fields(fp, bin, m);
  int lossy = p.lossy;
  plan_free(ctx, &p);
  if ((st = vm_outfile_commit(&of))) return st;
  return lossy ? VM_WARN_LOSSY : VM_OK;
}
