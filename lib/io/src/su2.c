/* lib/io/src/su2.c: SU2's native mesh format (ASCII): cells plus one
 * marker per boundary-face family, or a surface mesh, read and written. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "families_private.h"
#include "varmesh/io.h"
#include "formats_private.h"
#include "lex_private.h"

int vm_write_su2(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  if (!m || !path) return vm_error(ctx, VM_ERR_ARG, "vm_write_su2: NULL argument");
  int st = ex_groups_check(ctx, m, path, "SU2");
  if (st) return st;
  ex_groups g;
  st = ex_groups_build(ctx, m, &g);
  if (st) {
    ex_groups_free(ctx, &g);
    return st < 0 ? st : VM_ERR_ARG;
  }
  vm_outfile *of = NULL;
  if ((st = vm_outfile_open(ctx, path, &of))) {
    ex_groups_free(ctx, &g);
    return st;
  }
  FILE *f = vm_outfile_fp(of);
  fprintf(f, "%% SU2 mesh written by varmesh %s\nNDIME= 3\nNELEM= %lld\n", vm_version(),
          (long long)g.ncell);
  for (int64_t c = 0; c < g.ncell; c++) {
    int32_t e = g.cell[c];
    fprintf(f, "%d", vm_elem_to_vtk(m->etype[e]));
    for (int64_t k = 0; k < m->eoff[e + 1] - m->eoff[e]; k++)
      fprintf(f, " %d", (int)m->conn[m->eoff[e] + vm_elem_vtk_node(m->etype[e], (int)k)]);
    fprintf(f, " %lld\n", (long long)c);
  }
  fprintf(f, "NPOIN= %lld\n", (long long)m->nv);
  for (int64_t v = 0; v < m->nv; v++)
    fprintf(f, "%.17g %.17g %.17g %lld\n", m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2],
            (long long)v);
  fprintf(f, "NMARK= %d\n", g.nfam);
  for (int fam = 0; fam < g.nfam; fam++) {
    fprintf(f, "MARKER_TAG= %s\nMARKER_ELEMS= %lld\n", g.name[fam],
            (long long)(g.fbeg[fam + 1] - g.fbeg[fam]));
    for (int64_t k = g.fbeg[fam]; k < g.fbeg[fam + 1]; k++) {
      fprintf(f, "%d", g.fnv[k] == 3 ? 5 : 9);
      for (int i = 0; i < g.fnv[k]; i++) fprintf(f, " %d", (int)g.fv[4 * k + i]);
      fputc('\n', f);
    }
  }
  ex_groups_free(ctx, &g);
  if (ferror(f)) {
    int e = errno ? errno : EIO;
    vm_outfile_abort(&of);
    return vm_error(ctx, VM_ERR_IO, "%s: write failed: %s", path, strerror(e));
  }
  if ((st = vm_outfile_commit(&of))) return st;
  if (ex_groups_surface(m))
    vm_log(ctx, VM_LOG_WARN,
           "%s: SU2's solvers need volume cells; the file holds a surface mesh (triangles and "
           "quadrilaterals as NELEM, NMARK= 0)",
           path);
  return ex_groups_lossy(ctx, m, path, "SU2", 0) ? VM_WARN_LOSSY : VM_OK;
}

/* Reading. The file is parsed line by line: "KEY= value" lines, then the
 * records a count announces, each on its own line (see varmesh/io.h). */

#define SU2_MAX_TOK 12 /* type + 8 vertices + trailing indices, and one more to detect excess */

typedef struct {
  vm_ctx *ctx;
  const char *name;
  vm_lex lx;
  vm_mesh *m;
  int dim;  /* 0 until NDIME */
  int cdim; /* dimension of the NELEM cells, 0 until the first (2 in NDIME= 3: a surface) */
  int have_elem, have_poin, have_mark;
  int64_t vmax, vmax_line; /* largest vertex index seen before NPOIN, and its line */
  int nmark;
  int64_t *mbeg;      /* elements of marker k: [mbeg[k], mbeg[k+1]) */
  int64_t nline;      /* line markers dropped */
  int64_t mface_line; /* line of the first triangle or quad of a marker, 0 if none */
  /* the tokens of the current record line */
  int ntok;
  const char *tok[SU2_MAX_TOK];
  size_t tlen[SU2_MAX_TOK];
  int64_t line;
} su2_rd;

static int su2_fail(su2_rd *r, int64_t line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int su2_fail(su2_rd *r, int64_t line, const char *fmt, ...) {
  char msg[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vm_error(r->ctx, VM_ERR_FORMAT, "%s: line %lld: %s", r->name, (long long)line, msg);
}

/* Split the next non-blank, non-comment line into tokens. */
static int su2_record(su2_rd *r, const char *what) {
  if (vm_lex_eof(&r->lx)) return vm_lex_fail(&r->lx, "unexpected end of file, expected %s", what);
  r->line = r->lx.line;
  const char *s, *e;
  size_t n;
  vm_lex_line(&r->lx, &s, &n);
  e = s + n;
  r->ntok = 0;
  while (s < e) {
    while (s < e && (*s == ' ' || *s == '\t' || *s == '\r' || *s == 0)) s++;
    if (s >= e) break;
    const char *b = s;
    while (s < e && *s != ' ' && *s != '\t' && *s != '\r' && *s != 0) s++;
    if (r->ntok == SU2_MAX_TOK) return su2_fail(r, r->line, "%s: too many numbers", what);
    r->tok[r->ntok] = b;
    r->tlen[r->ntok++] = (size_t)(s - b);
  }
  return VM_OK;
}

static int tok_int(su2_rd *r, int i, int64_t *v, const char *what) {
  char buf[32];
  size_t n = r->tlen[i];
  if (n == 0 || n >= sizeof buf || memchr(r->tok[i], 0, n))
    return su2_fail(r, r->line, "%s: '%.*s' is not an integer", what, (int)(n > 40 ? 40 : n),
                    r->tok[i]);
  memcpy(buf, r->tok[i], n);
  buf[n] = 0;
  char *e;
  errno = 0;
  long long x = strtoll(buf, &e, 10);
  if (*e || errno) return su2_fail(r, r->line, "%s: '%s' is not an integer", what, buf);
  *v = x;
  return VM_OK;
}

static int tok_double(su2_rd *r, int i, double *v, const char *what) {
  char buf[64];
  size_t n = r->tlen[i];
  if (n == 0 || n >= sizeof buf || memchr(r->tok[i], 0, n))
    return su2_fail(r, r->line, "%s: '%.*s' is not a number", what, (int)(n > 40 ? 40 : n),
                    r->tok[i]);
  memcpy(buf, r->tok[i], n);
  buf[n] = 0;
  char *e;
  double x = strtod(buf, &e);
  if (*e) return su2_fail(r, r->line, "%s: '%s' is not a number", what, buf);
  *v = x;
  return VM_OK;
}

/* A count, refused if the bytes left cannot hold that many records of at
 * least `ntok` tokens (each token and its separator take 2 bytes). */
static int su2_count(su2_rd *r, const char *key, int64_t x, int ntok) {
  int64_t left = (int64_t)(r->lx.end - r->lx.p);
  if (x < 0) return su2_fail(r, r->line, "%s= %lld is negative", key, (long long)x);
  if (x > (left + 1) / (2 * ntok))
    return su2_fail(r, r->line, "%s= %lld: that many records cannot fit in the %lld bytes left",
                    key, (long long)x, (long long)left);
  return VM_OK;
}

/* SU2 (VTK) element type id -> vm type; lines are -2, unknown -1. */
static int su2_type(int64_t id) {
  if (id == 3) return -2;
  return id >= 0 && id < 100 ? vm_elem_from_vtk((int)id) : -1;
}

/* Vertex indices of the record's tokens 1..k (file order) into v (vm order). */
static int su2_verts(su2_rd *r, int type, int k, int32_t *v, const char *what) {
  for (int j = 0; j < k; j++) {
    int64_t x = 0;
    int st = tok_int(r, 1 + j, &x, what);
    if (st) return st;
    int64_t nv = r->have_poin ? r->m->nv : INT32_MAX;
    if (x < 0 || x >= nv)
      return su2_fail(r, r->line, "%s: vertex index %lld is not in 0..%lld", what, (long long)x,
                      (long long)nv - 1);
    if (!r->have_poin && x > r->vmax) {
      r->vmax = x;
      r->vmax_line = r->line;
    }
    v[type >= 0 ? vm_elem_vtk_node(type, j) : j] = (int32_t)x;
  }
  return VM_OK;
}

/* Check the token count: k vertices after the type, then at most one
 * trailing integer (the element's index, ignored). */
static int su2_arity(su2_rd *r, int k, const char *what, int64_t id) {
  if (r->ntok < 1 + k || r->ntok > 2 + k)
    return su2_fail(
        r, r->line,
        "%s of type %lld: expected %d vertex indices and an optional index, found %d numbers", what,
        (long long)id, k, r->ntok - 1);
  if (r->ntok == 2 + k) {
    int64_t x;
    return tok_int(r, 1 + k, &x, what);
  }
  return VM_OK;
}

static int su2_elements(su2_rd *r, int64_t n) {
  int st = su2_count(r, "NELEM", n, 4);
  if (st) return st;
  if (r->m->ne + n > INT32_MAX) return su2_fail(r, r->line, "too many elements");
  for (int64_t i = 0; i < n; i++) {
    int64_t id;
    if ((st = su2_record(r, "an element")) || (r->ntok == 0) ||
        (st = tok_int(r, 0, &id, "element type")))
      return st ? st : su2_fail(r, r->line, "empty element line");
    int t = su2_type(id);
    if (t < 0 || vm_elem_dim(t) > r->dim || vm_elem_dim(t) < 2)
      return su2_fail(r, r->line, "element type %lld is not a %s (%s)", (long long)id,
                      r->dim == 2 ? "2D cell" : "3D cell or surface element",
                      r->dim == 2 ? "5 triangle, 9 quadrilateral"
                                  : "10 tetrahedron, 12 hexahedron, 13 prism, 14 pyramid; 5 "
                                    "triangle, 9 quadrilateral for a surface mesh");
    /* NDIME= 3 holds volume cells or, for a surface mesh, triangles and
     * quads: a mix of the two is refused */
    if (r->cdim && vm_elem_dim(t) != r->cdim)
      return su2_fail(r, r->line,
                      "element type %lld: a %s among %s (NELEM holds either volume cells or the "
                      "triangles and quadrilaterals of a surface mesh)",
                      (long long)id, r->cdim == 3 ? "surface element" : "volume cell",
                      r->cdim == 3 ? "volume cells" : "surface elements");
    r->cdim = vm_elem_dim(t);
    int k = vm_elem_nverts(t);
    int32_t v[VM_MAX_ELEM_VERTS];
    if ((st = su2_arity(r, k, "element", id)) || (st = su2_verts(r, t, k, v, "element")) ||
        (st = vm_mesh_add_element(r->m, t, v)))
      return st;
  }
  r->have_elem = 1;
  return VM_OK;
}

static int su2_points(su2_rd *r, int64_t n) {
  int st = su2_count(r, "NPOIN", n, r->dim);
  if (st) return st;
  if (n > INT32_MAX) return su2_fail(r, r->line, "NPOIN= %lld: too many points", (long long)n);
  if (r->vmax >= n)
    return su2_fail(r, r->vmax_line, "vertex index %lld is not in 0..%lld", (long long)r->vmax,
                    (long long)n - 1);
  if ((st = vm_mesh_set_vertices(r->m, n))) return st;
  for (int64_t i = 0; i < n; i++) {
    if ((st = su2_record(r, "a point"))) return st;
    /* dim coordinates, then up to two integers (the point's index and, in
     * partitioned files, a second one), ignored */
    if (r->ntok < r->dim || r->ntok > r->dim + 2)
      return su2_fail(r, r->line,
                      "point %lld: expected %d coordinates and an optional index, found %d numbers",
                      (long long)i, r->dim, r->ntok);
    double *x = r->m->xyz + 3 * i;
    for (int c = 0; c < r->dim; c++)
      if ((st = tok_double(r, c, &x[c], "coordinate"))) return st;
    for (int c = r->dim; c < r->ntok; c++) {
      int64_t idx;
      if ((st = tok_int(r, c, &idx, "point index"))) return st;
    }
    if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2]))
      return su2_fail(r, r->line, "point %lld: coordinate is not finite", (long long)i);
  }
  r->have_poin = 1;
  return VM_OK;
}

/* The value of a "KEY= value" line: the rest of the line, trimmed. */
typedef struct {
  const char *key, *val;
  size_t nkey, nval;
  int64_t line;
} su2_kv;

static int su2_keyline(su2_rd *r, su2_kv *kv) {
  vm_lex *lx = &r->lx;
  kv->line = lx->line;
  const char *s;
  size_t n;
  vm_lex_line(lx, &s, &n);
  const char *eq = memchr(s, '=', n), *e = s + n;
  r->line = kv->line;
  if (!eq) {
    size_t k = 0;
    while (k < n && k < 40 && s[k] != ' ' && s[k] != '\t') k++;
    return su2_fail(r, kv->line, "expected a KEY= line, found '%.*s'", (int)k, s);
  }
  const char *kb = s, *ke = eq;
  while (ke > kb && (ke[-1] == ' ' || ke[-1] == '\t')) ke--;
  const char *vb = eq + 1;
  while (vb < e && (*vb == ' ' || *vb == '\t')) vb++;
  while (e > vb && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r')) e--;
  kv->key = kb;
  kv->nkey = (size_t)(ke - kb);
  kv->val = vb;
  kv->nval = (size_t)(e - vb);
  return VM_OK;
}

/* One integer (and, if second != NULL, an optional second one) from a value. */
static int su2_kv_int(su2_rd *r, const su2_kv *kv, int64_t *v, int64_t *second) {
  r->line = kv->line;
  r->ntok = 0;
  const char *s = kv->val, *e = kv->val + kv->nval;
  while (s < e && r->ntok < 3) {
    const char *b = s;
    while (s < e && *s != ' ' && *s != '\t') s++;
    r->tok[r->ntok] = b;
    r->tlen[r->ntok++] = (size_t)(s - b);
    while (s < e && (*s == ' ' || *s == '\t')) s++;
  }
  if (r->ntok == 0 || r->ntok > (second ? 2 : 1))
    return su2_fail(r, kv->line, "%.*s= needs %s integer", (int)kv->nkey, kv->key,
                    second ? "one or two" : "one");
  int st = tok_int(r, 0, v, "value");
  if (!st && second && r->ntok == 2) st = tok_int(r, 1, second, "value");
  return st;
}

static int kv_is(const su2_kv *kv, const char *key) { return vm_tok_is(kv->key, kv->nkey, key); }

static int su2_markers(su2_rd *r, int64_t n) {
  int st = su2_count(r, "NMARK", n, 4);
  if (st) return st;
  r->mbeg = vm_alloc_array(r->ctx, (size_t)n + 1, sizeof *r->mbeg);
  if (!r->mbeg) return VM_ERR_NOMEM;
  /* the markers' names are the mesh's first attributes, their keys unique
   * (the marker's number): appended, not searched (many markers stay
   * linear) */
  int fresh = r->m->nattr == 0;
  if (fresh && n > 0 && !(r->m->attrs = vm_calloc(r->ctx, (size_t)n, sizeof *r->m->attrs)))
    return VM_ERR_NOMEM;
  for (int64_t k = 0; k < n; k++) {
    su2_kv kv;
    if (vm_lex_eof(&r->lx))
      return vm_lex_fail(&r->lx, "unexpected end of file, expected MARKER_TAG= of marker %lld",
                         (long long)k + 1);
    if ((st = su2_keyline(r, &kv))) return st;
    if (!kv_is(&kv, "MARKER_TAG"))
      return su2_fail(r, kv.line,
                      "expected MARKER_TAG= of marker %lld, found %.*s=", (long long)k + 1,
                      (int)(kv.nkey > 40 ? 40 : kv.nkey), kv.key);
    if (kv.nval == 0 || kv.nval > 200 || memchr(kv.val, 0, kv.nval))
      return su2_fail(r, kv.line, "MARKER_TAG= needs a name of 1 to 200 characters");
    char key[64], nm[201];
    memcpy(nm, kv.val, kv.nval);
    nm[kv.nval] = 0;
    snprintf(key, sizeof key, "gmsh:physical_name:2:%lld", (long long)k + 1);
    if (!fresh) {
      if ((st = vm_mesh_set_attr(r->m, key, nm))) return st;
    } else {
      vm_attr *a = &r->m->attrs[r->m->nattr];
      a->key = vm_strdup(r->ctx, key);
      a->value = vm_strdup(r->ctx, nm);
      if (!a->key || !a->value) {
        vm_free(r->ctx, a->key);
        vm_free(r->ctx, a->value);
        return VM_ERR_NOMEM;
      }
      r->m->nattr++;
    }
    if (vm_lex_eof(&r->lx))
      return vm_lex_fail(&r->lx, "unexpected end of file, expected MARKER_ELEMS= of marker '%s'",
                         nm);
    int64_t ne;
    if ((st = su2_keyline(r, &kv))) return st;
    if (!kv_is(&kv, "MARKER_ELEMS"))
      return su2_fail(r, kv.line, "expected MARKER_ELEMS= of marker '%s'", nm);
    if ((st = su2_kv_int(r, &kv, &ne, NULL)) || (st = su2_count(r, "MARKER_ELEMS", ne, 3)))
      return st;
    if (r->m->ne + ne > INT32_MAX) return su2_fail(r, kv.line, "too many elements");
    r->mbeg[k] = r->m->ne;
    for (int64_t i = 0; i < ne; i++) {
      int64_t id;
      if ((st = su2_record(r, "a marker element")) || (r->ntok == 0) ||
          (st = tok_int(r, 0, &id, "marker element type")))
        return st ? st : su2_fail(r, r->line, "empty marker element line");
      int t = su2_type(id);
      int ok = r->dim == 2 ? t == -2 : (t == -2 || t == VM_TRI || t == VM_QUAD);
      if (!ok)
        return su2_fail(r, r->line, "marker '%s': element type %lld is not a boundary %s", nm,
                        (long long)id,
                        r->dim == 2 ? "line (3)" : "element (3 line, 5 triangle, 9 quadrilateral)");
      int kv_n = t == -2 ? 2 : vm_elem_nverts(t);
      int32_t v[VM_MAX_ELEM_VERTS];
      if ((st = su2_arity(r, kv_n, "marker element", id)) ||
          (st = su2_verts(r, t, kv_n, v, "marker element")))
        return st;
      if (t == -2) {
        r->nline++;
        continue;
      }
      if (!r->mface_line) r->mface_line = r->line;
      if ((st = vm_mesh_add_element(r->m, t, v))) return st;
    }
    r->nmark++;
  }
  r->mbeg[r->nmark] = r->m->ne;
  r->have_mark = 1;
  return VM_OK;
}

static int su2_parse(su2_rd *r) {
  vm_lex *lx = &r->lx;
  for (;;) {
    if (vm_lex_eof(lx)) break;
    su2_kv kv;
    int64_t x, y = -1;
    int st = su2_keyline(r, &kv);
    if (st) return st;
    if (kv_is(&kv, "NDIME")) {
      if (r->dim) return su2_fail(r, kv.line, "a second NDIME=");
      if ((st = su2_kv_int(r, &kv, &x, NULL))) return st;
      if (x != 2 && x != 3) return su2_fail(r, kv.line, "NDIME= %lld is not 2 or 3", (long long)x);
      r->dim = (int)x;
      continue;
    }
    if (kv_is(&kv, "NZONE") || kv_is(&kv, "IZONE")) {
      if ((st = su2_kv_int(r, &kv, &x, NULL))) return st;
      if (x != 1) {
        vm_error(r->ctx, VM_ERR_UNSUPPORTED,
                 "%s: line %lld: %.*s= %lld: multi-zone SU2 files are not supported", r->name,
                 (long long)kv.line, (int)kv.nkey, kv.key, (long long)x);
        return VM_ERR_UNSUPPORTED;
      }
      continue;
    }
    if (kv_is(&kv, "FFD_NBOX") || kv_is(&kv, "FFD_NLEVEL")) {
      /* free-form deformation boxes (SU2_DEF): not part of the mesh */
      if ((st = su2_kv_int(r, &kv, &x, NULL))) return st;
      if (x < 0)
        return su2_fail(r, kv.line, "%.*s= %lld is negative", (int)kv.nkey, kv.key, (long long)x);
      if (x > 0) {
        vm_log(r->ctx, VM_LOG_WARN, "%s: line %lld: FFD boxes and the rest of the file ignored",
               r->name, (long long)kv.line);
        break;
      }
      continue;
    }
    int is_elem = kv_is(&kv, "NELEM"), is_poin = kv_is(&kv, "NPOIN"), is_mark = kv_is(&kv, "NMARK");
    if (!is_elem && !is_poin && !is_mark)
      return su2_fail(r, kv.line, "unknown keyword '%.*s='", (int)(kv.nkey > 40 ? 40 : kv.nkey),
                      kv.key);
    if (!r->dim) return su2_fail(r, kv.line, "%.*s= before NDIME=", (int)kv.nkey, kv.key);
    if ((is_elem && r->have_elem) || (is_poin && r->have_poin) || (is_mark && r->have_mark))
      return su2_fail(r, kv.line, "a second %.*s=", (int)kv.nkey, kv.key);
    if ((st = su2_kv_int(r, &kv, &x, is_poin ? &y : NULL))) return st;
    if (is_poin && y != -1 && (y < 0 || y > x))
      return su2_fail(r, kv.line, "NPOIN= %lld %lld: the second count is not in 0..%lld",
                      (long long)x, (long long)y, (long long)x);
    st = is_elem ? su2_elements(r, x) : is_poin ? su2_points(r, x) : su2_markers(r, x);
    if (st) return st;
  }
  if (!r->dim) return vm_lex_fail(lx, "no NDIME= (empty or not an SU2 file)");
  if (!r->have_elem) return vm_lex_fail(lx, "no NELEM= section");
  if (!r->have_poin) return vm_lex_fail(lx, "no NPOIN= section");
  if (r->dim == 3 && r->cdim == 2 && r->mface_line)
    return su2_fail(r, r->mface_line,
                    "a marker of triangles or quadrilaterals in a surface mesh (its NELEM "
                    "holds triangles and quadrilaterals; its markers can only hold lines)");
  return VM_OK;
}

int vm_read_su2(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  su2_rd r;
  memset(&r, 0, sizeof r);
  r.ctx = ctx;
  r.name = name;
  r.vmax = -1;
  vm_lex_init(&r.lx, ctx, name, buf, len);
  r.lx.comment = '%';
  int st = vm_mesh_create(ctx, &r.m);
  if (!st) st = su2_parse(&r);
  if (!st) {
    r.m->dim = r.dim;
    if (r.nmark > 0) {
      vm_field *f;
      st = vm_mesh_add_field(r.m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
      for (int k = 0; !st && k < r.nmark; k++)
        for (int64_t e = r.mbeg[k]; e < r.mbeg[k + 1]; e++) ((int32_t *)f->data)[e] = k + 1;
    }
    if (!st && r.nline)
      vm_log(ctx, VM_LOG_WARN, "%s: %lld line elements of markers dropped (no edge elements)", name,
             (long long)r.nline);
  }
  vm_free(ctx, r.mbeg);
  if (st < 0) {
    vm_mesh_destroy(&r.m);
    return vm_error_name_prefix(ctx, st, name);
  }
  *out = r.m;
  return VM_OK;
}
