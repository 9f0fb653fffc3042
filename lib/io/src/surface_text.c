/* lib/io/src/surface_text.c: what the surface formats (STL, OBJ, OFF,
 * PLY) share: text scanning, polygon soup to elements (with ear
 * clipping), topology warnings, writer checks. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "surface_text_private.h"

/* ---- text scanning ---- */

void vm_surf_text_init(vm_surf_text *t, vm_ctx *ctx, const char *name, const uint8_t *buf,
                       size_t len, char comment) {
  t->ctx = ctx;
  t->name = name;
  t->p = (const char *)buf;
  t->end = (const char *)buf + len;
  t->line = 1;
  t->comment = comment;
}

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

int vm_surf_tok_line(vm_surf_text *t, const char **s, size_t *n) {
  const char *p = t->p, *end = t->end;
  while (p < end && is_blank(*p)) p++;
  if (p < end && t->comment && *p == t->comment)
    while (p < end && *p != '\n') p++;
  t->p = p;
  if (p == end || *p == '\n') return 0;
  const char *b = p;
  while (p < end && !is_blank(*p) && *p != '\n') p++;
  t->p = p;
  *s = b;
  *n = (size_t)(p - b);
  return 1;
}

int vm_surf_next_line(vm_surf_text *t) {
  const char *p = memchr(t->p, '\n', (size_t)(t->end - t->p));
  if (!p) {
    t->p = t->end;
    return 0;
  }
  t->p = p + 1;
  t->line++;
  return t->p < t->end;
}

int vm_surf_tok(vm_surf_text *t, const char **s, size_t *n) {
  for (;;) {
    if (vm_surf_tok_line(t, s, n)) return 1;
    if (t->p == t->end) return 0;
    t->p++; /* the newline */
    t->line++;
  }
}

int vm_surf_fail(vm_surf_text *t, const char *fmt, ...) {
  char msg[768];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vm_error(t->ctx, VM_ERR_FORMAT, "%s: line %lld: %s", t->name, (long long)t->line, msg);
}

int vm_surf_tok_is(const char *s, size_t n, const char *word) {
  size_t k = strlen(word);
  if (k != n) return 0;
  for (size_t i = 0; i < n; i++) {
    char a = s[i], b = word[i];
    if (a >= 'A' && a <= 'Z') a = (char)(a - 'A' + 'a');
    if (b >= 'A' && b <= 'Z') b = (char)(b - 'A' + 'a');
    if (a != b) return 0;
  }
  return 1;
}

int vm_surf_parse_double(const char *s, size_t n, double *v) {
  char buf[128];
  if (n == 0 || n >= sizeof buf) return -1;
  memcpy(buf, s, n);
  buf[n] = 0;
  char *e;
  *v = strtod(buf, &e);
  return e == buf + n ? 0 : -1;
}

int vm_surf_parse_int(const char *s, size_t n, int64_t *v) {
  char buf[32];
  if (n == 0 || n >= sizeof buf) return -1;
  memcpy(buf, s, n);
  buf[n] = 0;
  char *e;
  errno = 0;
  long long x = strtoll(buf, &e, 10);
  if (e != buf + n || errno == ERANGE) return -1;
  *v = x;
  return 0;
}

const char *vm_surf_tok_show(const char *s, size_t n, char buf[40]) {
  size_t k = n > 32 ? 32 : n;
  for (size_t i = 0; i < k; i++) {
    unsigned char c = (unsigned char)s[i];
    buf[i] = c >= 32 && c < 127 ? (char)c : '?';
  }
  if (k < n) {
    memcpy(buf + k, "...", 3);
    k += 3;
  }
  buf[k] = 0;
  return buf;
}

/* ---- polygon soup ---- */

void vm_surf_polys_init(vm_surf_polys *P, vm_ctx *ctx) {
  memset(P, 0, sizeof *P);
  P->ctx = ctx;
}

void vm_surf_polys_free(vm_surf_polys *P) {
  vm_free(P->ctx, P->off);
  vm_free(P->ctx, P->rec);
  vm_free(P->ctx, P->idx);
  vm_surf_polys_init(P, P->ctx);
}

int vm_surf_polys_add(vm_surf_polys *P, const int64_t *v, int64_t k, int64_t rec) {
  vm_ctx *ctx = P->ctx;
  if (P->n + 1 > P->cap) {
    int64_t cap = P->cap ? 2 * P->cap : 64;
    int64_t *off = vm_realloc(ctx, P->off, (size_t)(cap + 1) * sizeof *off);
    if (!off) return VM_ERR_NOMEM;
    if (!P->off) off[0] = 0;
    P->off = off;
    int64_t *r = vm_realloc(ctx, P->rec, (size_t)cap * sizeof *r);
    if (!r) return VM_ERR_NOMEM;
    P->rec = r;
    P->cap = cap;
  }
  int64_t used = P->off[P->n];
  if (used + k > P->icap) {
    int64_t cap = P->icap ? 2 * P->icap : 256;
    while (cap < used + k) cap *= 2;
    int64_t *idx = vm_realloc(ctx, P->idx, (size_t)cap * sizeof *idx);
    if (!idx) return VM_ERR_NOMEM;
    P->idx = idx;
    P->icap = cap;
  }
  memcpy(P->idx + used, v, (size_t)k * sizeof *v);
  P->rec[P->n] = rec;
  P->off[P->n + 1] = used + k;
  P->n++;
  return VM_OK;
}

/* Largest polygon read (triangulated in time linear in its size: convex
 * ones as fans, others by ear clipping within a linear budget). */
#define VM_SURF_MAX_POLYGON 1024

static double cross2(const double *a, const double *b, const double *c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Ear clipping of polygon v[0..k-1] projected on the plane of its Newell
 * normal; emits k-2 triangles with the polygon's orientation. uv and link
 * are scratch arrays of 2k doubles and 2k ints. *forced counts ears taken
 * without passing the test (self-intersecting or degenerate polygons). */
static int earclip(vm_mesh *m, const int32_t *v, int k, double *uv, int *link, int64_t *forced) {
  double nrm[3] = {0, 0, 0};
  for (int i = 0; i < k; i++) {
    const double *p = m->xyz + 3 * (int64_t)v[i], *q = m->xyz + 3 * (int64_t)v[(i + 1) % k];
    nrm[0] += (p[1] - q[1]) * (p[2] + q[2]);
    nrm[1] += (p[2] - q[2]) * (p[0] + q[0]);
    nrm[2] += (p[0] - q[0]) * (p[1] + q[1]);
  }
  int ax = 0;
  for (int d = 1; d < 3; d++)
    if (fabs(nrm[d]) > fabs(nrm[ax])) ax = d;
  int a0 = (ax + 1) % 3, a1 = (ax + 2) % 3;
  /* with (a0, a1, ax) cyclic the projection's signed area has the sign of
   * nrm[ax]: flip u so the polygon runs counter-clockwise */
  double sgn = nrm[ax] < 0 ? -1.0 : 1.0;
  for (int i = 0; i < k; i++) {
    uv[2 * i] = sgn * m->xyz[3 * (int64_t)v[i] + a0];
    uv[2 * i + 1] = m->xyz[3 * (int64_t)v[i] + a1];
  }
  int *nxt = link, *prv = link + k;
  for (int i = 0; i < k; i++) {
    nxt[i] = (i + 1) % k;
    prv[i] = (i + k - 1) % k;
  }
  /* a convex polygon (every corner turning left) is a fan: linear time */
  int convex = 1;
  for (int i = 0; i < k && convex; i++)
    convex = cross2(uv + 2 * prv[i], uv + 2 * i, uv + 2 * nxt[i]) > 0;
  /* ear clipping costs k^2 to k^3 steps: past a budget linear in k (a
   * hostile file's huge non-convex polygons) the rest becomes a fan, its
   * triangles counted as forced, so reading stays linear in the file */
  long budget = convex ? 0 : 64L * k + 4096;
  int rem = k, cur = 0;
  while (rem > 3) {
    int found = -1;
    for (int tries = 0, c = cur; tries < rem && budget > 0; tries++, c = nxt[c]) {
      int a = prv[c], b = nxt[c];
      const double *pa = uv + 2 * a, *pc = uv + 2 * c, *pb = uv + 2 * b;
      budget--;
      if (cross2(pa, pc, pb) <= 0) continue;
      int ok = 1;
      for (int j = nxt[b]; j != a && ok; j = nxt[j]) {
        const double *pj = uv + 2 * j;
        budget--;
        if ((pj[0] == pa[0] && pj[1] == pa[1]) || (pj[0] == pb[0] && pj[1] == pb[1]) ||
            (pj[0] == pc[0] && pj[1] == pc[1]))
          continue;
        if (cross2(pa, pc, pj) >= 0 && cross2(pc, pb, pj) >= 0 && cross2(pb, pa, pj) >= 0) ok = 0;
      }
      if (ok) {
        found = c;
        break;
      }
    }
    if (found < 0) {
      found = cur;
      if (!convex) (*forced)++;
    }
    int a = prv[found], b = nxt[found];
    int32_t tri[3] = {v[a], v[found], v[b]};
    int st = vm_mesh_add_element(m, VM_TRI, tri);
    if (st < 0) return st;
    nxt[a] = b;
    prv[b] = a;
    cur = b;
    rem--;
  }
  int32_t tri[3] = {v[prv[cur]], v[cur], v[nxt[cur]]};
  return vm_mesh_add_element(m, VM_TRI, tri);
}

int vm_surf_polys_build(vm_surf_polys *P, const char *name, const char *rec_kind, int base,
                        vm_mesh *m) {
  vm_ctx *ctx = P->ctx;
  int64_t kmax = 0, nbig = 0, forced = 0, firstbig = -1;
  for (int64_t f = 0; f < P->n; f++) {
    int64_t k = P->off[f + 1] - P->off[f];
    if (k < 3)
      return vm_error(ctx, VM_ERR_FORMAT, "%s: %s %lld: face with %lld vertices", name, rec_kind,
                      (long long)P->rec[f], (long long)k);
    if (k > VM_SURF_MAX_POLYGON)
      return vm_error(ctx, VM_ERR_UNSUPPORTED,
                      "%s: %s %lld: face with %lld vertices (at most %d are supported)", name,
                      rec_kind, (long long)P->rec[f], (long long)k, VM_SURF_MAX_POLYGON);
    for (int64_t i = P->off[f]; i < P->off[f + 1]; i++)
      if (P->idx[i] < 0 || P->idx[i] >= m->nv)
        return vm_error(ctx, VM_ERR_FORMAT,
                        "%s: %s %lld: vertex index %lld out of range (%d..%lld)", name, rec_kind,
                        (long long)P->rec[f], (long long)(P->idx[i] + base), base,
                        (long long)(m->nv - 1 + base));
    if (k > kmax) kmax = k;
  }
  int32_t *v = vm_alloc_array(ctx, (size_t)kmax + 1, sizeof *v);
  double *uv = vm_alloc_array(ctx, 2 * (size_t)kmax + 1, sizeof *uv);
  int *link = vm_alloc_array(ctx, 2 * (size_t)kmax + 1, sizeof *link);
  int st = v && uv && link ? VM_OK : VM_ERR_NOMEM;
  for (int64_t f = 0; f < P->n && st == VM_OK; f++) {
    int k = (int)(P->off[f + 1] - P->off[f]);
    for (int i = 0; i < k; i++) v[i] = (int32_t)P->idx[P->off[f] + i];
    if (k <= 4) {
      st = vm_mesh_add_element(m, k == 3 ? VM_TRI : VM_QUAD, v);
    } else {
      if (!nbig++) firstbig = P->rec[f];
      st = earclip(m, v, k, uv, link, &forced);
    }
  }
  vm_free(ctx, v);
  vm_free(ctx, uv);
  vm_free(ctx, link);
  if (st < 0) return st;
  if (nbig)
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld faces with more than 4 vertices split into triangles (first at %s %lld)%s",
           name, (long long)nbig, rec_kind, (long long)firstbig,
           forced ? "; some are self-intersecting or degenerate" : "");
  return VM_OK;
}

typedef struct {
  uint64_t key;
  int64_t elem;
} edge_use;

static int cmp_edge_use(const void *a, const void *b) {
  const edge_use *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->elem < y->elem ? -1 : x->elem > y->elem;
}

int vm_surf_read_text(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, char comment,
                      vm_surf_parse_fn parse, vm_mesh **out) {
  *out = NULL;
  if (len == 0) return vm_error(ctx, VM_ERR_FORMAT, "%s: empty file", name);
  vm_mesh *m;
  int st = vm_mesh_create(ctx, &m);
  if (st < 0) return st;
  vm_surf_text t;
  vm_surf_text_init(&t, ctx, name, buf, len, comment);
  vm_surf_polys P;
  vm_surf_polys_init(&P, ctx);
  st = parse(&t, m, &P);
  vm_surf_polys_free(&P);
  if (st >= 0) st = vm_surf_report_topology(ctx, name, m);
  if (st < 0) {
    vm_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return VM_OK;
}

int vm_surf_report_topology(vm_ctx *ctx, const char *name, const vm_mesh *m) {
  int64_t nrep = 0, firstrep = -1, nuse = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 2) continue;
    int k = vm_elem_nverts(t);
    const int32_t *c = m->conn + m->eoff[e];
    int rep = 0;
    for (int i = 0; i < k; i++)
      for (int j = i + 1; j < k; j++) rep |= c[i] == c[j];
    if (rep && !nrep++) firstrep = e;
    nuse += k;
  }
  if (nrep)
    vm_log(ctx, VM_LOG_WARN, "%s: %lld faces have a repeated vertex (first: element %lld); kept",
           name, (long long)nrep, (long long)firstrep);
  if (!nuse) return VM_OK;
  edge_use *u = vm_alloc_array(ctx, (size_t)nuse, sizeof *u);
  if (!u) return VM_ERR_NOMEM;
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 2) continue;
    int k = vm_elem_nverts(t);
    const int32_t *c = m->conn + m->eoff[e];
    for (int i = 0; i < k; i++) {
      uint32_t a = (uint32_t)c[i], b = (uint32_t)c[(i + 1) % k];
      if (a > b) {
        uint32_t s = a;
        a = b;
        b = s;
      }
      u[n].key = (uint64_t)a << 32 | b;
      u[n].elem = e;
      n++;
    }
  }
  qsort(u, (size_t)n, sizeof *u, cmp_edge_use);
  int64_t nbad = 0, bad_elem = -1;
  uint64_t bad_key = 0;
  for (int64_t i = 0; i < n;) {
    int64_t j = i + 1;
    while (j < n && u[j].key == u[i].key) j++;
    if (j - i > 2 && !nbad++) {
      bad_key = u[i].key;
      bad_elem = u[i].elem;
    }
    i = j;
  }
  vm_free(ctx, u);
  if (nbad)
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld edges are shared by more than two faces (first: vertices %u-%u, element "
           "%lld); kept as read",
           name, (long long)nbad, (unsigned)(bad_key >> 32), (unsigned)(bad_key & 0xffffffffu),
           (long long)bad_elem);
  return VM_OK;
}

/* ---- writers ---- */

int vm_surf_write_prepare(vm_ctx *ctx, const vm_mesh *m, const char *path, const char *fmt,
                          int split_quads, int *lossy, int64_t *ntri, int64_t *nquad) {
  int64_t counts[VM_NTYPES];
  vm_mesh_count_types(m, counts);
  int64_t n3 = 0;
  for (int t = 0; t < VM_NTYPES; t++)
    if (vm_elem_dim(t) == 3) n3 += counts[t];
  *ntri = counts[VM_TRI];
  *nquad = counts[VM_QUAD];
  *lossy = 0;
  if (n3 && !*ntri && !*nquad)
    return vm_error(ctx, VM_ERR_UNSUPPORTED,
                    "%s: the mesh has only volume elements (%lld); %s holds triangles and "
                    "quads: extract the boundary first",
                    path, (long long)n3, fmt);
  if (n3) {
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld volume elements not written: %s holds only triangles and quads", path,
           (long long)n3, fmt);
    *lossy = 1;
  }
  if (split_quads && *nquad) {
    vm_log(ctx, VM_LOG_WARN, "%s: %lld quads written as two triangles each: %s has no quads", path,
           (long long)*nquad, fmt);
    *lossy = 1;
  }
  if (m->nfield) {
    vm_log(ctx, VM_LOG_WARN, "%s: %d fields not written (first: '%s'): %s cannot carry fields",
           path, m->nfield, m->fields[0].name, fmt);
    *lossy = 1;
  }
  int64_t nflag = 0;
  for (int64_t v = 0; v < m->nv; v++) nflag += m->vflag[v] != VM_VERTEX_FREE || m->vsurf[v] != -1;
  if (nflag) {
    vm_log(ctx, VM_LOG_WARN,
           "%s: flags of %lld fixed/slip vertices not written: %s cannot carry vertex flags", path,
           (long long)nflag, fmt);
    *lossy = 1;
  }
  if (m->nattr) {
    vm_log(ctx, VM_LOG_WARN,
           "%s: %d attributes not written (first: '%s'): %s cannot carry attributes", path,
           m->nattr, m->attrs[0].key, fmt);
    *lossy = 1;
  }
  return VM_OK;
}

int vm_surf_write_finish(vm_ctx *ctx, vm_outfile **f, const char *path, int lossy) {
  if (ferror(vm_outfile_fp(*f))) {
    int e = errno ? errno : EIO;
    vm_outfile_abort(f);
    return vm_error(ctx, VM_ERR_IO, "%s: write failed: %s", path, strerror(e));
  }
  int st = vm_outfile_commit(f);
  if (st < 0) return st;
  return lossy ? VM_WARN_LOSSY : VM_OK;
}
