/* lib/io/src/ply.c: PLY reader (ASCII, binary little- and big-endian;
 * vertex x/y/z and face vertex_indices kept, the rest reported and skipped)
 * and writer (double coordinates, ASCII or binary little-endian). */
#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "surface_text_private.h"

enum { PLY_ASCII, PLY_LE, PLY_BE };
enum { T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64, T_COUNT };

static const struct {
  const char *name, *alias;
  int size, integral;
} ply_types[T_COUNT] = {{"char", "int8", 1, 1},     {"uchar", "uint8", 1, 1},
                        {"short", "int16", 2, 1},   {"ushort", "uint16", 2, 1},
                        {"int", "int32", 4, 1},     {"uint", "uint32", 4, 1},
                        {"float", "float32", 4, 0}, {"double", "float64", 8, 0}};

#define PLY_MAXELEM 32
#define PLY_MAXPROP 64
#define PLY_NAME 64

typedef struct {
  char name[PLY_NAME];
  int type;  /* value type (list items for a list) */
  int list;  /* nonzero for "property list" */
  int ctype; /* list count type */
} ply_prop;

typedef struct {
  char name[PLY_NAME];
  int64_t count;
  int nprop;
  ply_prop prop[PLY_MAXPROP];
} ply_elem;

typedef struct {
  vm_ctx *ctx;
  const char *name;
  int format;
  int nelem;
  ply_elem elem[PLY_MAXELEM];
  vm_surf_text t;               /* header, and ASCII data */
  const uint8_t *buf, *p, *end; /* binary data */
  const char *ename;            /* element being read, for messages */
  int64_t item;
} ply_reader;

static int data_fail(ply_reader *R, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int data_fail(ply_reader *R, const char *fmt, ...) {
  char msg[640];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (R->format == PLY_ASCII)
    return vm_error(R->ctx, VM_ERR_FORMAT, "%s: line %lld: %s %lld: %s", R->name,
                    (long long)R->t.line, R->ename, (long long)R->item, msg);
  return vm_error(R->ctx, VM_ERR_FORMAT, "%s: byte %lld: %s %lld: %s", R->name,
                  (long long)(R->p - R->buf), R->ename, (long long)R->item, msg);
}

static int find_type(const char *s, size_t n) {
  for (int i = 0; i < T_COUNT; i++)
    if (vm_surf_tok_is(s, n, ply_types[i].name) || vm_surf_tok_is(s, n, ply_types[i].alias))
      return i;
  return -1;
}

static int header_word(ply_reader *R, const char **s, size_t *n, const char *what) {
  if (vm_surf_tok_line(&R->t, s, n)) return VM_OK;
  return vm_surf_fail(&R->t, "expected %s", what);
}

static int copy_name(ply_reader *R, char *dst, const char *s, size_t n) {
  char show[40];
  if (n >= PLY_NAME) return vm_surf_fail(&R->t, "name '%s' too long", vm_surf_tok_show(s, n, show));
  memcpy(dst, s, n);
  dst[n] = 0;
  return VM_OK;
}

static int parse_header(ply_reader *R) {
  vm_surf_text *t = &R->t;
  const char *s;
  size_t n;
  char show[40];
  int st;
  if (!vm_surf_tok_line(t, &s, &n) || !vm_surf_tok_is(s, n, "ply") || vm_surf_tok_line(t, &s, &n))
    return vm_error(R->ctx, VM_ERR_FORMAT, "%s: not a PLY file (no 'ply' line at the start)",
                    R->name);
  R->format = -1;
  for (;;) {
    if (!vm_surf_next_line(t)) return vm_surf_fail(t, "the header has no 'end_header'");
    if (!vm_surf_tok_line(t, &s, &n)) continue;
    if (vm_surf_tok_is(s, n, "format")) {
      if ((st = header_word(R, &s, &n, "a format")) < 0) return st;
      if (vm_surf_tok_is(s, n, "ascii"))
        R->format = PLY_ASCII;
      else if (vm_surf_tok_is(s, n, "binary_little_endian"))
        R->format = PLY_LE;
      else if (vm_surf_tok_is(s, n, "binary_big_endian"))
        R->format = PLY_BE;
      else
        return vm_surf_fail(t, "unknown format '%s'", vm_surf_tok_show(s, n, show));
    } else if (vm_surf_tok_is(s, n, "comment") || vm_surf_tok_is(s, n, "obj_info")) {
      continue;
    } else if (vm_surf_tok_is(s, n, "element")) {
      if (R->nelem == PLY_MAXELEM) return vm_surf_fail(t, "more than %d elements", PLY_MAXELEM);
      ply_elem *E = &R->elem[R->nelem];
      memset(E, 0, sizeof *E);
      if ((st = header_word(R, &s, &n, "an element name")) < 0) return st;
      if ((st = copy_name(R, E->name, s, n)) < 0) return st;
      if ((st = header_word(R, &s, &n, "an element count")) < 0) return st;
      if (vm_surf_parse_int(s, n, &E->count) < 0 || E->count < 0)
        return vm_surf_fail(t, "bad element count '%s'", vm_surf_tok_show(s, n, show));
      R->nelem++;
    } else if (vm_surf_tok_is(s, n, "property")) {
      if (!R->nelem) return vm_surf_fail(t, "property before any element");
      ply_elem *E = &R->elem[R->nelem - 1];
      if (E->nprop == PLY_MAXPROP)
        return vm_surf_fail(t, "element '%s' has more than %d properties", E->name, PLY_MAXPROP);
      ply_prop *P = &E->prop[E->nprop];
      memset(P, 0, sizeof *P);
      if ((st = header_word(R, &s, &n, "a property type")) < 0) return st;
      if (vm_surf_tok_is(s, n, "list")) {
        P->list = 1;
        if ((st = header_word(R, &s, &n, "a list count type")) < 0) return st;
        if ((P->ctype = find_type(s, n)) < 0 || !ply_types[P->ctype].integral)
          return vm_surf_fail(t, "bad list count type '%s'", vm_surf_tok_show(s, n, show));
        if ((st = header_word(R, &s, &n, "a list item type")) < 0) return st;
      }
      if ((P->type = find_type(s, n)) < 0)
        return vm_surf_fail(t, "unknown property type '%s'", vm_surf_tok_show(s, n, show));
      if ((st = header_word(R, &s, &n, "a property name")) < 0) return st;
      if ((st = copy_name(R, P->name, s, n)) < 0) return st;
      E->nprop++;
    } else if (vm_surf_tok_is(s, n, "end_header")) {
      if (R->format < 0) return vm_surf_fail(t, "no 'format' line before 'end_header'");
      vm_surf_next_line(t);
      return VM_OK;
    } else {
      return vm_surf_fail(t, "unknown header keyword '%s'", vm_surf_tok_show(s, n, show));
    }
  }
}

static int read_value(ply_reader *R, int type, double *v) {
  if (R->format == PLY_ASCII) {
    const char *s;
    size_t n;
    char show[40];
    if (!vm_surf_tok(&R->t, &s, &n)) return data_fail(R, "unexpected end of file");
    if (vm_surf_parse_double(s, n, v) < 0 || (ply_types[type].integral && *v != floor(*v)))
      return data_fail(R, "expected %s, found '%s'",
                       ply_types[type].integral ? "an integer" : "a number",
                       vm_surf_tok_show(s, n, show));
    return VM_OK;
  }
  int size = ply_types[type].size;
  if (R->end - R->p < size) return data_fail(R, "unexpected end of file (truncated?)");
  uint64_t u = 0;
  for (int i = 0; i < size; i++) {
    int k = R->format == PLY_LE ? i : size - 1 - i;
    u |= (uint64_t)R->p[k] << (8 * i);
  }
  R->p += size;
  switch (type) {
  case T_I8: *v = (double)(int64_t)(u >= 0x80 ? (int64_t)u - 0x100 : (int64_t)u); break;
  case T_U8:
  case T_U16:
  case T_U32: *v = (double)u; break;
  case T_I16: *v = (double)(u >= 0x8000 ? (int64_t)u - 0x10000 : (int64_t)u); break;
  case T_I32: *v = (double)(u >= 0x80000000u ? (int64_t)u - 0x100000000 : (int64_t)u); break;
  case T_F32: {
    uint32_t b = (uint32_t)u;
    float f;
    memcpy(&f, &b, sizeof f);
    *v = (double)f;
    break;
  }
  default: memcpy(v, &u, sizeof *v); break;
  }
  return VM_OK;
}

static int find_prop(const ply_elem *E, const char *name, int list) {
  for (int j = 0; j < E->nprop; j++)
    if (!strcmp(E->prop[j].name, name) && !E->prop[j].list == !list) return j;
  return -1;
}

/* Append "name" to a comma-separated list for a warning. */
static void list_add(char *buf, size_t cap, const char *name) {
  size_t l = strlen(buf);
  if (l + strlen(name) + 8 >= cap) {
    if (l + 6 <= cap && !strstr(buf, "...")) strcat(buf, ", ...");
    return;
  }
  if (l) strcat(buf, ", ");
  strcat(buf, name);
}

static int read_data(ply_reader *R, vm_mesh *m, vm_surf_polys *P) {
  vm_ctx *ctx = R->ctx;
  int st = VM_OK, have_vertex = 0;
  char dropped_v[256] = "", dropped_f[256] = "", skipped[256] = "";
  int64_t *face = NULL, fcap = 0;
  for (int e = 0; e < R->nelem; e++) {
    ply_elem *E = &R->elem[e];
    int is_vertex = !strcmp(E->name, "vertex"), is_face = !strcmp(E->name, "face");
    int ix[3] = {-1, -1, -1}, iface = -1;
    if (is_vertex) {
      if (have_vertex++) {
        st = vm_error(ctx, VM_ERR_FORMAT, "%s: two 'vertex' elements", R->name);
        goto done;
      }
      for (int d = 0; d < 3; d++) {
        const char *xyz[3] = {"x", "y", "z"};
        if ((ix[d] = find_prop(E, xyz[d], 0)) < 0) {
          st = vm_error(ctx, VM_ERR_FORMAT, "%s: element 'vertex' has no scalar property '%s'",
                        R->name, xyz[d]);
          goto done;
        }
      }
      for (int j = 0; j < E->nprop; j++)
        if (j != ix[0] && j != ix[1] && j != ix[2])
          list_add(dropped_v, sizeof dropped_v, E->prop[j].name);
    } else if (is_face) {
      if ((iface = find_prop(E, "vertex_indices", 1)) < 0) iface = find_prop(E, "vertex_index", 1);
      if (iface < 0) {
        st = vm_error(ctx, VM_ERR_FORMAT, "%s: element 'face' has no 'vertex_indices' list",
                      R->name);
        goto done;
      }
      for (int j = 0; j < E->nprop; j++)
        if (j != iface) list_add(dropped_f, sizeof dropped_f, E->prop[j].name);
    } else if (E->count) {
      list_add(skipped, sizeof skipped, E->name);
    }
    /* the smallest item this element can have, against the bytes left */
    uint64_t min = 0;
    for (int j = 0; j < E->nprop; j++)
      min += R->format == PLY_ASCII
                 ? 2
                 : (uint64_t)ply_types[E->prop[j].list ? E->prop[j].ctype : E->prop[j].type].size;
    size_t left = R->format == PLY_ASCII ? (size_t)(R->t.end - R->t.p) : (size_t)(R->end - R->p);
    if (min && (uint64_t)E->count > ((uint64_t)left + 1) / min) {
      st = vm_error(ctx, VM_ERR_FORMAT,
                    "%s: element '%s': %lld items cannot fit in the %zu bytes left (truncated "
                    "file or wrong count)",
                    R->name, E->name, (long long)E->count, left);
      goto done;
    }
    if (!min) continue; /* no properties, no data */
    if (is_vertex) {
      if (E->count > INT32_MAX) {
        st = vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: %lld vertices", R->name, (long long)E->count);
        goto done;
      }
      if ((st = vm_mesh_set_vertices(m, E->count)) < 0) goto done;
    }
    R->ename = E->name;
    for (int64_t i = 0; i < E->count; i++) {
      R->item = i;
      for (int j = 0; j < E->nprop; j++) {
        const ply_prop *Q = &E->prop[j];
        double v;
        if (!Q->list) {
          if ((st = read_value(R, Q->type, &v)) < 0) goto done;
          for (int d = 0; d < 3; d++)
            if (j == ix[d]) m->xyz[3 * i + d] = v;
          continue;
        }
        if ((st = read_value(R, Q->ctype, &v)) < 0) goto done;
        if (v < 0) {
          st = data_fail(R, "negative list length %g", v);
          goto done;
        }
        size_t left2 =
            R->format == PLY_ASCII ? (size_t)(R->t.end - R->t.p) : (size_t)(R->end - R->p);
        uint64_t isz = R->format == PLY_ASCII ? 2 : (uint64_t)ply_types[Q->type].size;
        if (v > (double)(((uint64_t)left2 + 1) / isz)) {
          st = data_fail(R, "list of %.0f items runs past the end of the file", v);
          goto done;
        }
        int64_t k = (int64_t)v;
        if (j != iface) {
          for (int64_t q = 0; q < k; q++)
            if ((st = read_value(R, Q->type, &v)) < 0) goto done;
          continue;
        }
        if (k < 3) {
          st = data_fail(R, "face with %lld vertices%s", (long long)k,
                         R->format == PLY_ASCII ? "" : " (wrong counts or types in the header?)");
          goto done;
        }
        if (k > fcap) {
          int64_t *p = vm_realloc(ctx, face, (size_t)k * sizeof *p);
          if (!p) {
            st = VM_ERR_NOMEM;
            goto done;
          }
          face = p;
          fcap = k;
        }
        for (int64_t q = 0; q < k; q++) {
          if ((st = read_value(R, Q->type, &v)) < 0) goto done;
          /* a float-typed index must still be a whole number (1.7 was read as 1) */
          if (!(v >= -1e18 && v <= 1e18) || v != floor(v)) {
            st = data_fail(R, "bad vertex index %.17g", v);
            goto done;
          }
          face[q] = (int64_t)v;
        }
        int64_t rec = R->format == PLY_ASCII ? R->t.line : i;
        if ((st = vm_surf_polys_add(P, face, k, rec)) < 0) goto done;
      }
      if (is_vertex) {
        const double *x = m->xyz + 3 * i;
        if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2])) {
          st = data_fail(R, "coordinate is not finite");
          goto done;
        }
      }
    }
  }
  if (!have_vertex) {
    st = vm_error(ctx, VM_ERR_FORMAT, "%s: no 'vertex' element", R->name);
    goto done;
  }
  if (R->format == PLY_ASCII) {
    const char *s;
    size_t n;
    char show[40];
    if (vm_surf_tok(&R->t, &s, &n)) {
      st = vm_surf_fail(&R->t, "unexpected '%s' after the last element",
                        vm_surf_tok_show(s, n, show));
      goto done;
    }
  } else if (R->p != R->end) {
    st = vm_error(ctx, VM_ERR_FORMAT, "%s: %zu bytes after the last element", R->name,
                  (size_t)(R->end - R->p));
    goto done;
  }
  st = vm_surf_polys_build(P, R->name, R->format == PLY_ASCII ? "line" : "face", 0, m);
  if (st < 0) goto done;
  if (dropped_v[0])
    vm_log(ctx, VM_LOG_WARN, "%s: vertex properties dropped: %s", R->name, dropped_v);
  if (dropped_f[0]) vm_log(ctx, VM_LOG_WARN, "%s: face properties dropped: %s", R->name, dropped_f);
  if (skipped[0]) vm_log(ctx, VM_LOG_WARN, "%s: elements skipped: %s", R->name, skipped);
done:
  vm_free(ctx, face);
  return st;
}

int vm_read_ply(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  if (len == 0) return vm_error(ctx, VM_ERR_FORMAT, "%s: empty file", name);
  ply_reader *R = vm_calloc(ctx, 1, sizeof *R);
  if (!R) return VM_ERR_NOMEM;
  R->ctx = ctx;
  R->name = name;
  vm_surf_text_init(&R->t, ctx, name, buf, len, 0);
  vm_mesh *m = NULL;
  vm_surf_polys P;
  vm_surf_polys_init(&P, ctx);
  int st = parse_header(R);
  if (st >= 0) {
    R->buf = buf;
    R->p = (const uint8_t *)R->t.p;
    R->end = buf + len;
    st = vm_mesh_create(ctx, &m);
  }
  if (st >= 0) st = read_data(R, m, &P);
  if (st >= 0) st = vm_surf_report_topology(ctx, name, m);
  vm_surf_polys_free(&P);
  vm_free(ctx, R);
  if (st < 0) {
    vm_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return VM_OK;
}

static void put_le64(uint8_t *p, double x) {
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  for (int i = 0; i < 8; i++) p[i] = (uint8_t)(u >> (8 * i));
}

int vm_write_ply(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  int lossy;
  int64_t ntri, nquad;
  int st = vm_surf_write_prepare(ctx, m, path, "PLY", 0, &lossy, &ntri, &nquad);
  if (st < 0) return st;
  int binary = o && o->binary;
  vm_outfile *f;
  if ((st = vm_outfile_open(ctx, path, &f)) < 0) return st;
  FILE *fp = vm_outfile_fp(f);
  fprintf(fp,
          "ply\nformat %s 1.0\ncomment written by varmesh\nelement vertex %lld\n"
          "property double x\nproperty double y\nproperty double z\nelement face %lld\n"
          "property list uchar int vertex_indices\nend_header\n",
          binary ? "binary_little_endian" : "ascii", (long long)m->nv, (long long)(ntri + nquad));
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    if (binary) {
      uint8_t b[24];
      for (int d = 0; d < 3; d++) put_le64(b + 8 * d, p[d]);
      fwrite(b, 1, sizeof b, fp);
    } else {
      fprintf(fp, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
    }
  }
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    const int32_t *c = m->conn + m->eoff[e];
    int k = vm_elem_nverts(m->etype[e]);
    if (k > 4) continue; /* (a 2D element is a triangle or a quad) */
    if (binary) {
      uint8_t b[1 + 4 * 4];
      b[0] = (uint8_t)k;
      for (int i = 0; i < k; i++) vm_surf_put_le32(b + 1 + 4 * i, (uint32_t)c[i]);
      fwrite(b, 1, 1 + 4 * (size_t)k, fp);
    } else {
      fprintf(fp, "%d", k);
      for (int i = 0; i < k; i++) fprintf(fp, " %ld", (long)c[i]);
      fputc('\n', fp);
    }
  }
  return vm_surf_write_finish(ctx, &f, path, lossy);
}
