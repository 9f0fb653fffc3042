/* lib/io/src/stl.c: STL reader (binary and ASCII, exact merging of
 * identical corners into vertices) and writer (ASCII or binary). */
#include <float.h>
#include <math.h>
#include <string.h>

#include "surface_text_private.h"

/* ---- merging corners into vertices ---- */

/* Corners ordered by their coordinates (then by index): equal points are
 * neighbours. A sort, not a hash table: no file can make it slow (a fixed
 * hash let a crafted STL put every vertex in one slot: 8.9 MB in 39 s). */
static int cmp_corner(const double *xyz, int64_t a, int64_t b) {
  for (int d = 0; d < 3; d++) {
    double x = xyz[3 * a + d], y = xyz[3 * b + d];
    if (x != y) return x < y ? -1 : 1;
  }
  return (a > b) - (a < b);
}

/* Merge sort of idx[0..n) by cmp_corner, tmp scratch of n: O(n log n) on
 * any input, stable, deterministic. */
static void sort_corners(const double *xyz, int64_t *idx, int64_t *tmp, int64_t n) {
  for (int64_t w = 1; w < n; w *= 2) {
    for (int64_t lo = 0; lo < n; lo += 2 * w) {
      int64_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
      int64_t i = lo, j = mid, k = lo;
      while (i < mid && j < hi)
        tmp[k++] = cmp_corner(xyz, idx[i], idx[j]) <= 0 ? idx[i++] : idx[j++];
      while (i < mid) tmp[k++] = idx[i++];
      while (j < hi) tmp[k++] = idx[j++];
    }
    memcpy(idx, tmp, (size_t)n * sizeof *idx);
  }
}

/* xyz holds 3 finite corners per triangle (-0 already folded to +0); build
 * the vertices (numbered by first use) and the triangles of m. */
static int merge_corners(vm_ctx *ctx, const char *name, const double *xyz, int64_t ntri,
                         vm_mesh *m) {
  int64_t nc = 3 * ntri;
  int64_t *idx = vm_alloc_array(ctx, (size_t)nc + 1, sizeof *idx);
  int64_t *tmp = vm_alloc_array(ctx, (size_t)nc + 1, sizeof *tmp);
  int32_t *vid = vm_alloc_array(ctx, (size_t)nc + 1, sizeof *vid);
  int64_t *first = vm_alloc_array(ctx, (size_t)nc + 1, sizeof *first);
  int st = VM_OK;
  if (!idx || !tmp || !vid || !first) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t c = 0; c < nc; c++) idx[c] = c;
  sort_corners(xyz, idx, tmp, nc);
  /* tmp[c]: the first corner (smallest index) with c's coordinates */
  for (int64_t i = 0; i < nc; i++) {
    int64_t c = idx[i];
    const double *p = xyz + 3 * c;
    int64_t r = c;
    if (i > 0) {
      const double *q = xyz + 3 * idx[i - 1];
      if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) r = tmp[idx[i - 1]];
    }
    tmp[c] = r;
  }
  /* vertices numbered by first use */
  int64_t nv = 0;
  for (int64_t c = 0; c < nc; c++) {
    if (tmp[c] != c) {
      vid[c] = vid[tmp[c]];
      continue;
    }
    if (nv >= INT32_MAX) {
      st = vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: more than %d distinct vertices", name, INT32_MAX);
      goto done;
    }
    first[nv] = c;
    vid[c] = (int32_t)nv++;
  }
  st = vm_mesh_set_vertices(m, nv);
  if (st < 0) goto done;
  for (int64_t v = 0; v < nv; v++) memcpy(m->xyz + 3 * v, xyz + 3 * first[v], 3 * sizeof(double));
  st = vm_mesh_set_elements(m, ntri, nc);
  if (st < 0) goto done;
  for (int64_t t = 0; t < ntri; t++) {
    m->etype[t] = VM_TRI;
    m->eoff[t + 1] = 3 * (t + 1);
  }
  memcpy(m->conn, vid, (size_t)nc * sizeof *vid);
done:
  vm_free(ctx, idx);
  vm_free(ctx, tmp);
  vm_free(ctx, vid);
  vm_free(ctx, first);
  return st;
}

/* ---- binary ---- */

static double le_float(const uint8_t *p) {
  uint32_t b = vm_surf_le32(p);
  float f;
  memcpy(&f, &b, sizeof f);
  return (double)f;
}

/* The caller checked that len == 84 + 50 n. */
static int read_binary(vm_ctx *ctx, const char *name, const uint8_t *buf, vm_mesh *m) {
  int64_t n = vm_surf_le32(buf + 80);
  double *xyz = vm_alloc_array(ctx, 9 * (size_t)n + 1, sizeof *xyz);
  if (!xyz) return VM_ERR_NOMEM;
  int64_t nattr = 0, first_attr = -1;
  for (int64_t t = 0; t < n; t++) {
    const uint8_t *p = buf + 84 + 50 * t;
    for (int i = 0; i < 9; i++) {
      double x = le_float(p + 12 + 4 * i);
      if (!isfinite(x)) {
        vm_free(ctx, xyz);
        return vm_error(ctx, VM_ERR_FORMAT,
                        "%s: triangle %lld: vertex %d: coordinate is not finite", name,
                        (long long)t, i / 3);
      }
      xyz[9 * t + i] = x + 0.0; /* -0 -> +0 so the two merge */
    }
    if ((p[48] | p[49]) && !nattr++) first_attr = t;
  }
  if (nattr)
    vm_log(ctx, VM_LOG_WARN,
           "%s: attribute words (colors?) of %lld triangles dropped (first: triangle %lld)", name,
           (long long)nattr, (long long)first_attr);
  int st = merge_corners(ctx, name, xyz, n, m);
  vm_free(ctx, xyz);
  return st;
}

/* ---- ASCII ---- */

typedef struct {
  vm_surf_text t;
  int64_t facet;
} stl_text;

static int next_tok(stl_text *S, const char **s, size_t *n, const char *want) {
  if (vm_surf_tok(&S->t, s, n)) return VM_OK;
  if (S->facet >= 0)
    return vm_surf_fail(&S->t, "facet %lld: unexpected end of file, expected %s",
                        (long long)S->facet, want);
  return vm_surf_fail(&S->t, "unexpected end of file, expected %s", want);
}

static int expect(stl_text *S, const char *word) {
  const char *s;
  size_t n;
  char show[40], want[40];
  snprintf(want, sizeof want, "'%s'", word);
  int st = next_tok(S, &s, &n, want);
  if (st < 0) return st;
  if (vm_surf_tok_is(s, n, word)) return VM_OK;
  if (S->facet >= 0)
    return vm_surf_fail(&S->t, "facet %lld: expected '%s', found '%s'", (long long)S->facet, word,
                        vm_surf_tok_show(s, n, show));
  return vm_surf_fail(&S->t, "expected '%s', found '%s'", word, vm_surf_tok_show(s, n, show));
}

static int number(stl_text *S, double *x) {
  const char *s;
  size_t n;
  char show[40];
  int st = next_tok(S, &s, &n, "a number");
  if (st < 0) return st;
  if (vm_surf_parse_double(s, n, x) < 0)
    return vm_surf_fail(&S->t, "facet %lld: expected a number, found '%s'", (long long)S->facet,
                        vm_surf_tok_show(s, n, show));
  return VM_OK;
}

/* Skip a solid's name: the rest of the line, unless a keyword follows on the
 * same line (single-line files). */
static void skip_name(stl_text *S) {
  const char *s, *before = S->t.p;
  size_t n;
  while (vm_surf_tok_line(&S->t, &s, &n)) {
    if (vm_surf_tok_is(s, n, "facet") || vm_surf_tok_is(s, n, "endsolid") ||
        vm_surf_tok_is(s, n, "solid")) {
      S->t.p = before;
      return;
    }
    before = S->t.p;
  }
}

static int read_ascii(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh *m) {
  stl_text S;
  vm_surf_text_init(&S.t, ctx, name, buf, len, 0);
  S.facet = -1;
  double *xyz = NULL;
  int64_t ntri = 0, cap = 0;
  const char *s;
  size_t n;
  char show[40];
  int st = expect(&S, "solid");
  if (st < 0) return st;
  skip_name(&S);
  for (;;) {
    if ((st = next_tok(&S, &s, &n, "'facet' or 'endsolid'")) < 0) goto fail;
    if (vm_surf_tok_is(s, n, "endsolid")) {
      skip_name(&S);
      if (!vm_surf_tok(&S.t, &s, &n)) break;
      if (!vm_surf_tok_is(s, n, "solid")) {
        st = vm_surf_fail(&S.t, "unexpected '%s' after 'endsolid'", vm_surf_tok_show(s, n, show));
        goto fail;
      }
      skip_name(&S); /* another solid follows */
      continue;
    }
    if (!vm_surf_tok_is(s, n, "facet")) {
      st = vm_surf_fail(&S.t, "expected 'facet' or 'endsolid', found '%s'",
                        vm_surf_tok_show(s, n, show));
      goto fail;
    }
    S.facet = ntri;
    if ((st = next_tok(&S, &s, &n, "'normal' or 'outer'")) < 0) goto fail;
    if (vm_surf_tok_is(s, n, "normal")) {
      double nrm; /* normals are recomputed; "nan" is common here, accept it */
      for (int i = 0; i < 3; i++)
        if ((st = number(&S, &nrm)) < 0) goto fail;
      if ((st = expect(&S, "outer")) < 0) goto fail;
    } else if (!vm_surf_tok_is(s, n, "outer")) {
      st = vm_surf_fail(&S.t, "facet %lld: expected 'normal' or 'outer', found '%s'",
                        (long long)ntri, vm_surf_tok_show(s, n, show));
      goto fail;
    }
    if ((st = expect(&S, "loop")) < 0) goto fail;
    if (ntri + 1 > cap) {
      cap = cap ? 2 * cap : 1024;
      double *p = vm_realloc(ctx, xyz, (size_t)cap * 9 * sizeof *p);
      if (!p) {
        st = VM_ERR_NOMEM;
        goto fail;
      }
      xyz = p;
    }
    for (int k = 0; k < 3; k++) {
      if ((st = expect(&S, "vertex")) < 0) goto fail;
      for (int d = 0; d < 3; d++) {
        double x;
        if ((st = number(&S, &x)) < 0) goto fail;
        if (!isfinite(x)) {
          st = vm_surf_fail(&S.t, "facet %lld: vertex %d: coordinate is not finite",
                            (long long)ntri, k);
          goto fail;
        }
        xyz[9 * ntri + 3 * k + d] = x + 0.0;
      }
    }
    if ((st = next_tok(&S, &s, &n, "'endloop'")) < 0) goto fail;
    if (vm_surf_tok_is(s, n, "vertex")) {
      st = vm_surf_fail(&S.t, "facet %lld: more than 3 vertices (STL facets are triangles)",
                        (long long)ntri);
      goto fail;
    }
    if (!vm_surf_tok_is(s, n, "endloop")) {
      st = vm_surf_fail(&S.t, "facet %lld: expected 'endloop', found '%s'", (long long)ntri,
                        vm_surf_tok_show(s, n, show));
      goto fail;
    }
    if ((st = expect(&S, "endfacet")) < 0) goto fail;
    ntri++;
    S.facet = -1;
    if (ntri > INT32_MAX) {
      st = vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: more than %d facets", name, INT32_MAX);
      goto fail;
    }
  }
  st = merge_corners(ctx, name, xyz, ntri, m);
fail:
  vm_free(ctx, xyz);
  return st;
}

int vm_read_stl(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  if (len == 0) return vm_error(ctx, VM_ERR_FORMAT, "%s: empty file", name);
  size_t i = 0;
  while (i < len && (buf[i] == ' ' || buf[i] == '\t' || buf[i] == '\r' || buf[i] == '\n')) i++;
  int solid = len - i >= 5 && vm_surf_tok_is((const char *)buf + i, 5, "solid");
  int has_nul = memchr(buf, 0, len) != NULL;
  uint64_t expect_len = len >= 84 ? 84 + 50 * (uint64_t)vm_surf_le32(buf + 80) : 0;
  int binary;
  if (len >= 84 && expect_len == len)
    binary = 1;
  else if (solid && !has_nul)
    binary = 0;
  else if (len < 84)
    return vm_error(ctx, VM_ERR_FORMAT,
                    "%s: %zu bytes: too short for a binary STL and not an ASCII STL", name, len);
  else
    return vm_error(ctx, VM_ERR_FORMAT,
                    "%s: binary STL%s: the header says %u triangles (%llu bytes) but the file "
                    "has %zu bytes (truncated or not an STL file)",
                    name, solid ? " (starting with 'solid')" : "", (unsigned)vm_surf_le32(buf + 80),
                    (unsigned long long)expect_len, len);
  vm_mesh *m;
  int st = vm_mesh_create(ctx, &m);
  if (st < 0) return st;
  st = binary ? read_binary(ctx, name, buf, m) : read_ascii(ctx, name, buf, len, m);
  if (st >= 0) st = vm_surf_report_topology(ctx, name, m);
  if (st < 0) {
    vm_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return VM_OK;
}

/* ---- writer ---- */

static void tri_normal(const vm_mesh *m, const int32_t *c, double n[3]) {
  const double *a = m->xyz + 3 * (int64_t)c[0], *b = m->xyz + 3 * (int64_t)c[1],
               *d = m->xyz + 3 * (int64_t)c[2];
  double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double v[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
  double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (l > 0 && isfinite(l))
    for (int d2 = 0; d2 < 3; d2++) n[d2] /= l;
  else
    n[0] = n[1] = n[2] = 0;
}

static void put_float(uint8_t *p, double x) {
  float f = (float)x;
  uint32_t b;
  memcpy(&b, &f, sizeof b);
  vm_surf_put_le32(p, b);
}

/* Triangles of a surface element: 1 for a triangle, 2 for a quad. */
static int elem_tris(const vm_mesh *m, int64_t e, int32_t tri[2][3]) {
  const int32_t *c = m->conn + m->eoff[e];
  if (m->etype[e] == VM_TRI) {
    memcpy(tri[0], c, 3 * sizeof *c);
    return 1;
  }
  if (m->etype[e] == VM_QUAD) {
    int32_t t0[3] = {c[0], c[1], c[2]}, t1[3] = {c[0], c[2], c[3]};
    memcpy(tri[0], t0, sizeof t0);
    memcpy(tri[1], t1, sizeof t1);
    return 2;
  }
  return 0;
}

int vm_write_stl(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  int lossy;
  int64_t ntri, nquad;
  int st = vm_surf_write_prepare(ctx, m, path, "STL", 1, &lossy, &ntri, &nquad);
  if (st < 0) return st;
  int binary = o && o->binary;
  if (binary) {
    if (ntri + 2 * nquad > (int64_t)UINT32_MAX)
      return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: %lld triangles do not fit in a binary STL",
                      path, (long long)(ntri + 2 * nquad));
    for (int64_t i = 0; i < 3 * m->nv; i++)
      if (fabs(m->xyz[i]) > FLT_MAX)
        return vm_error(ctx, VM_ERR_UNSUPPORTED,
                        "%s: vertex %lld: coordinate %g does not fit in a binary STL's float32",
                        path, (long long)(i / 3), m->xyz[i]);
  }
  vm_outfile *f;
  if ((st = vm_outfile_open(ctx, path, &f)) < 0) return st;
  FILE *fp = vm_outfile_fp(f);
  int32_t tri[2][3];
  double nrm[3];
  if (binary) {
    uint8_t rec[50];
    char head[80];
    memset(head, ' ', sizeof head);
    memcpy(head, "varmesh binary STL", 18); /* never "solid": that would mislead readers */
    fwrite(head, 1, sizeof head, fp);
    uint8_t cnt[4];
    vm_surf_put_le32(cnt, (uint32_t)(ntri + 2 * nquad));
    fwrite(cnt, 1, 4, fp);
    for (int64_t e = 0; e < m->ne; e++) {
      int k = elem_tris(m, e, tri);
      for (int j = 0; j < k; j++) {
        tri_normal(m, tri[j], nrm);
        for (int d = 0; d < 3; d++) put_float(rec + 4 * d, nrm[d]);
        for (int i = 0; i < 3; i++)
          for (int d = 0; d < 3; d++)
            put_float(rec + 12 + 12 * i + 4 * d, m->xyz[3 * (int64_t)tri[j][i] + d]);
        rec[48] = rec[49] = 0;
        fwrite(rec, 1, sizeof rec, fp);
      }
    }
  } else {
    fprintf(fp, "solid varmesh\n");
    for (int64_t e = 0; e < m->ne; e++) {
      int k = elem_tris(m, e, tri);
      for (int j = 0; j < k; j++) {
        tri_normal(m, tri[j], nrm);
        fprintf(fp, "facet normal %.9g %.9g %.9g\n outer loop\n", nrm[0], nrm[1], nrm[2]);
        for (int i = 0; i < 3; i++) {
          const double *p = m->xyz + 3 * (int64_t)tri[j][i];
          fprintf(fp, "  vertex %.17g %.17g %.17g\n", p[0], p[1], p[2]);
        }
        fprintf(fp, " endloop\nendfacet\n");
      }
    }
    fprintf(fp, "endsolid varmesh\n");
  }
  return vm_surf_write_finish(ctx, &f, path, lossy);
}
