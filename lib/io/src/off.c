/* lib/io/src/off.c: Geomview OFF reader (OFF, COFF, NOFF, CNOFF, STOFF
 * ASCII variants) and writer. */
#include <math.h>
#include <string.h>

#include "surface_text_private.h"

/* The next line holding a record (blank and comment lines skipped): returns
 * its first token, or fails with "expected <what>". */
static int record(vm_surf_text *t, const char **s, size_t *n, const char *what) {
  for (;;) {
    if (vm_surf_tok_line(t, s, n)) return VM_OK;
    if (!vm_surf_next_line(t)) return vm_surf_fail(t, "unexpected end of file, expected %s", what);
  }
}

static int count(vm_surf_text *t, int64_t *v, const char *what) {
  const char *s;
  size_t n;
  char show[40];
  if (!vm_surf_tok(t, &s, &n)) return vm_surf_fail(t, "unexpected end of file, expected %s", what);
  if (vm_surf_parse_int(s, n, v) < 0 || *v < 0 || *v > INT32_MAX)
    return vm_surf_fail(t, "bad %s '%s'", what, vm_surf_tok_show(s, n, show));
  return VM_OK;
}

static int read_off(vm_surf_text *t, vm_mesh *m, vm_surf_polys *P) {
  vm_ctx *ctx = t->ctx;
  const char *name = t->name, *s;
  size_t n;
  char show[40];
  int64_t nv, nf, ne;
  int st;
  if (!vm_surf_tok(t, &s, &n)) return vm_surf_fail(t, "no OFF header");
  int keyword = n >= 3 && !memcmp(s + n - 3, "OFF", 3);
  if (keyword) {
    /* [ST][C][N][4][n]OFF */
    const char *p = s, *e = s + n - 3;
    if (e - p >= 2 && !memcmp(p, "ST", 2)) p += 2;
    if (p < e && *p == 'C') p++;
    if (p < e && *p == 'N') p++;
    if (p < e && (*p == '4' || *p == 'n')) {
      return vm_error(ctx, VM_ERR_UNSUPPORTED,
                      "%s: line %lld: '%s': 4-D and n-D OFF vertices are not supported", name,
                      (long long)t->line, vm_surf_tok_show(s, n, show));
    }
    if (p != e) return vm_surf_fail(t, "unknown OFF variant '%s'", vm_surf_tok_show(s, n, show));
    const char *s2;
    size_t n2;
    const char *save = t->p;
    if (vm_surf_tok_line(t, &s2, &n2) && vm_surf_tok_is(s2, n2, "BINARY"))
      return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: line %lld: binary OFF is not supported", name,
                      (long long)t->line);
    t->p = save;
    if ((st = count(t, &nv, "vertex count")) < 0) return st;
  } else {
    /* the keyword is optional: the file may start with the counts */
    if (vm_surf_parse_int(s, n, &nv) < 0)
      return vm_surf_fail(t, "not an OFF file: expected 'OFF', found '%s'",
                          vm_surf_tok_show(s, n, show));
    if (nv < 0 || nv > INT32_MAX) return vm_surf_fail(t, "bad vertex count %lld", (long long)nv);
  }
  if ((st = count(t, &nf, "face count")) < 0) return st;
  if ((st = count(t, &ne, "edge count")) < 0) return st;
  if (vm_surf_tok_line(t, &s, &n))
    return vm_surf_fail(t, "unexpected '%s' after the counts", vm_surf_tok_show(s, n, show));
  /* each vertex takes at least "0 0 0\n", each face "3 0 1 2\n" */
  size_t left = (size_t)(t->end - t->p);
  if ((uint64_t)nv * 6 + (uint64_t)nf * 8 > (uint64_t)left + 1)
    return vm_surf_fail(t,
                        "the header claims %lld vertices and %lld faces; the remaining %zu "
                        "bytes cannot hold them",
                        (long long)nv, (long long)nf, left);
  vm_surf_next_line(t);
  int64_t extra_v = 0, extra_f = 0, line_v = 0, line_f = 0;
  if ((st = vm_mesh_set_vertices(m, nv)) < 0) return st;
  for (int64_t v = 0; v < nv; v++) {
    char what[64];
    snprintf(what, sizeof what, "vertex %lld", (long long)v);
    if ((st = record(t, &s, &n, what)) < 0) return st;
    double *x = m->xyz + 3 * v;
    for (int d = 0; d < 3; d++) {
      if (d && !vm_surf_tok_line(t, &s, &n))
        return vm_surf_fail(t, "vertex %lld: %d coordinates", (long long)v, d);
      if (vm_surf_parse_double(s, n, &x[d]) < 0)
        return vm_surf_fail(t, "vertex %lld: expected a coordinate, found '%s'", (long long)v,
                            vm_surf_tok_show(s, n, show));
      if (!isfinite(x[d]))
        return vm_surf_fail(t, "vertex %lld: coordinate is not finite", (long long)v);
    }
    int extra = 0;
    while (vm_surf_tok_line(t, &s, &n)) {
      double y;
      if (vm_surf_parse_double(s, n, &y) < 0)
        return vm_surf_fail(t, "vertex %lld: expected a number, found '%s'", (long long)v,
                            vm_surf_tok_show(s, n, show));
      extra = 1;
    }
    if (extra && !extra_v++) line_v = t->line;
    vm_surf_next_line(t);
  }
  int64_t *face = NULL, fcap = 0;
  for (int64_t f = 0; f < nf; f++) {
    char what[64];
    snprintf(what, sizeof what, "face %lld", (long long)f);
    int64_t k;
    if ((st = record(t, &s, &n, what)) < 0) goto done;
    if (vm_surf_parse_int(s, n, &k) < 0 || k < 3 || k > INT32_MAX) {
      st = vm_surf_fail(t, "face %lld: bad vertex count '%s'", (long long)f,
                        vm_surf_tok_show(s, n, show));
      goto done;
    }
    if ((size_t)k > (size_t)(t->end - t->p) / 2 + 1) {
      st = vm_surf_fail(t, "face %lld: %lld vertices do not fit in the file", (long long)f,
                        (long long)k);
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
    for (int64_t i = 0; i < k; i++) {
      if (!vm_surf_tok_line(t, &s, &n)) {
        st = vm_surf_fail(t, "face %lld: %lld of %lld vertex indices", (long long)f, (long long)i,
                          (long long)k);
        goto done;
      }
      if (vm_surf_parse_int(s, n, &face[i]) < 0 || face[i] < 0 || face[i] >= nv) {
        st = vm_surf_fail(t, "face %lld: bad vertex index '%s' (the file has %lld vertices)",
                          (long long)f, vm_surf_tok_show(s, n, show), (long long)nv);
        goto done;
      }
    }
    int extra = 0;
    while (vm_surf_tok_line(t, &s, &n)) {
      double y;
      if (vm_surf_parse_double(s, n, &y) < 0) {
        st = vm_surf_fail(t, "face %lld: expected a color value, found '%s'", (long long)f,
                          vm_surf_tok_show(s, n, show));
        goto done;
      }
      extra = 1;
    }
    if (extra && !extra_f++) line_f = t->line;
    if ((st = vm_surf_polys_add(P, face, k, t->line)) < 0) goto done;
    vm_surf_next_line(t);
  }
  if (vm_surf_tok(t, &s, &n)) {
    st = vm_surf_fail(t, "unexpected '%s' after the last face (the header says %lld faces)",
                      vm_surf_tok_show(s, n, show), (long long)nf);
    goto done;
  }
  if ((st = vm_surf_polys_build(P, name, "line", 0, m)) < 0) goto done;
  if (extra_v)
    vm_log(ctx, VM_LOG_WARN,
           "%s: extra values (normals, colors or texture coordinates) of %lld vertices dropped "
           "(first at line %lld)",
           name, (long long)extra_v, (long long)line_v);
  if (extra_f)
    vm_log(ctx, VM_LOG_WARN, "%s: colors of %lld faces dropped (first at line %lld)", name,
           (long long)extra_f, (long long)line_f);
done:
  vm_free(ctx, face);
  return st;
}

int vm_read_off(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  return vm_surf_read_text(ctx, name, buf, len, '#', read_off, out);
}

int vm_write_off(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  int lossy;
  int64_t ntri, nquad;
  int st = vm_surf_write_prepare(ctx, m, path, "OFF", 0, &lossy, &ntri, &nquad);
  if (st < 0) return st;
  vm_outfile *f;
  if ((st = vm_outfile_open(ctx, path, &f)) < 0) return st;
  FILE *fp = vm_outfile_fp(f);
  fprintf(fp, "OFF\n%lld %lld 0\n", (long long)m->nv, (long long)(ntri + nquad));
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    fprintf(fp, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    const int32_t *c = m->conn + m->eoff[e];
    if (m->etype[e] == VM_TRI)
      fprintf(fp, "3 %ld %ld %ld\n", (long)c[0], (long)c[1], (long)c[2]);
    else
      fprintf(fp, "4 %ld %ld %ld %ld\n", (long)c[0], (long)c[1], (long)c[2], (long)c[3]);
  }
  return vm_surf_write_finish(ctx, &f, path, lossy);
}
