/* lib/io/src/obj.c: Wavefront OBJ reader (v and f records; the rest is
 * reported and skipped) and writer (v and f). */
#include <math.h>
#include <string.h>

#include "surface_text_private.h"

/* What a read skipped, reported once per kind at the end. */
typedef struct {
  int64_t n;
  int64_t line;
} obj_skip;

static void note(obj_skip *k, int64_t line) {
  if (!k->n++) k->line = line;
}

static void warn(vm_ctx *ctx, const char *name, const obj_skip *k, const char *what) {
  if (k->n)
    vm_log(ctx, VM_LOG_WARN, "%s: %lld %s dropped (first at line %lld)", name, (long long)k->n,
           what, (long long)k->line);
}

/* Parse one "v", "v/vt", "v//vn" or "v/vt/vn" reference; returns the
 * 0-based vertex index (unchecked against the final count). */
static int face_ref(vm_surf_text *t, const char *s, size_t n, int64_t nv, int64_t *v) {
  char show[40];
  const char *slash = memchr(s, '/', n);
  size_t k = slash ? (size_t)(slash - s) : n;
  int64_t i;
  if (vm_surf_parse_int(s, k, &i) < 0)
    return vm_surf_fail(t, "bad vertex reference '%s'", vm_surf_tok_show(s, n, show));
  /* texture and normal indices are not used, but must be numbers */
  for (const char *p = slash; p;) {
    const char *q = p + 1, *e = s + n;
    const char *nx = memchr(q, '/', (size_t)(e - q));
    size_t len = (size_t)((nx ? nx : e) - q);
    int64_t dummy;
    if (len && vm_surf_parse_int(q, len, &dummy) < 0)
      return vm_surf_fail(t, "bad vertex reference '%s'", vm_surf_tok_show(s, n, show));
    p = nx;
  }
  if (i == 0) return vm_surf_fail(t, "vertex index 0 (OBJ indices start at 1)");
  if (i < 0) {
    if (nv + i < 0)
      return vm_surf_fail(t, "relative vertex index %lld refers before the first vertex",
                          (long long)i);
    *v = nv + i;
  } else {
    *v = i - 1;
  }
  return VM_OK;
}

static int read_obj(vm_surf_text *t, vm_mesh *m, vm_surf_polys *P) {
  vm_ctx *ctx = t->ctx;
  const char *name = t->name;
  obj_skip extra = {0, 0}, normals = {0, 0}, texcoords = {0, 0}, params = {0, 0}, lines = {0, 0},
           groups = {0, 0}, other = {0, 0};
  char other_kw[40] = "";
  int64_t *face = NULL, fcap = 0;
  int st = VM_OK;
  const char *s;
  size_t n;
  char show[40];
  do {
    if (!vm_surf_tok_line(t, &s, &n)) continue;
    if (vm_surf_tok_is(s, n, "v")) {
      double x[3];
      for (int d = 0; d < 3; d++) {
        if (!vm_surf_tok_line(t, &s, &n)) {
          st = vm_surf_fail(t, "vertex with %d coordinates", d);
          goto done;
        }
        if (vm_surf_parse_double(s, n, &x[d]) < 0) {
          st = vm_surf_fail(t, "expected a coordinate, found '%s'", vm_surf_tok_show(s, n, show));
          goto done;
        }
        if (!isfinite(x[d])) {
          st = vm_surf_fail(t, "vertex %lld: coordinate is not finite", (long long)m->nv + 1);
          goto done;
        }
      }
      int next = 0;
      while (vm_surf_tok_line(t, &s, &n)) {
        double y;
        if (vm_surf_parse_double(s, n, &y) < 0) {
          st = vm_surf_fail(t, "expected a number, found '%s'", vm_surf_tok_show(s, n, show));
          goto done;
        }
        next++;
      }
      if (next) note(&extra, t->line);
      if ((st = vm_mesh_add_vertex(m, x[0], x[1], x[2], NULL)) < 0) goto done;
    } else if (vm_surf_tok_is(s, n, "f") || vm_surf_tok_is(s, n, "fo")) {
      int64_t k = 0;
      while (vm_surf_tok_line(t, &s, &n)) {
        if (k + 1 > fcap) {
          int64_t cap = fcap ? 2 * fcap : 16;
          int64_t *p = vm_realloc(ctx, face, (size_t)cap * sizeof *p);
          if (!p) {
            st = VM_ERR_NOMEM;
            goto done;
          }
          face = p;
          fcap = cap;
        }
        if ((st = face_ref(t, s, n, m->nv, &face[k])) < 0) goto done;
        k++;
      }
      if (k < 3) {
        st = vm_surf_fail(t, "face with %lld vertices", (long long)k);
        goto done;
      }
      if ((st = vm_surf_polys_add(P, face, k, t->line)) < 0) goto done;
    } else if (vm_surf_tok_is(s, n, "vn")) {
      note(&normals, t->line);
    } else if (vm_surf_tok_is(s, n, "vt")) {
      note(&texcoords, t->line);
    } else if (vm_surf_tok_is(s, n, "vp")) {
      note(&params, t->line);
    } else if (vm_surf_tok_is(s, n, "l") || vm_surf_tok_is(s, n, "p")) {
      note(&lines, t->line);
    } else if (vm_surf_tok_is(s, n, "g") || vm_surf_tok_is(s, n, "o") ||
               vm_surf_tok_is(s, n, "s") || vm_surf_tok_is(s, n, "usemtl") ||
               vm_surf_tok_is(s, n, "mtllib") || vm_surf_tok_is(s, n, "usemap") ||
               vm_surf_tok_is(s, n, "maplib") || vm_surf_tok_is(s, n, "mg")) {
      note(&groups, t->line);
    } else {
      if (!other.n) vm_surf_tok_show(s, n, other_kw);
      note(&other, t->line);
    }
  } while (vm_surf_next_line(t));
  /* nothing an OBJ file is made of: random bytes, a renamed binary file */
  if (m->nv == 0 && P->n == 0 && other.n) {
    st = vm_error(ctx, VM_ERR_FORMAT,
                  "%s: line %lld: not an OBJ file: no vertex or face, and '%s' is no OBJ "
                  "statement",
                  name, (long long)other.line, other_kw);
    goto done;
  }
  if ((st = vm_surf_polys_build(P, name, "line", 1, m)) < 0) goto done;
  warn(ctx, name, &extra, "extra vertex values (colors or weights)");
  warn(ctx, name, &normals, "vertex normals (vn)");
  warn(ctx, name, &texcoords, "texture coordinates (vt)");
  warn(ctx, name, &params, "parameter-space vertices (vp)");
  warn(ctx, name, &lines, "line and point elements (l, p)");
  warn(ctx, name, &groups, "group, smoothing and material statements");
  if (other.n)
    vm_log(ctx, VM_LOG_WARN, "%s: %lld unsupported statements skipped (first: '%s' at line %lld)",
           name, (long long)other.n, other_kw, (long long)other.line);
done:
  vm_free(ctx, face);
  return st;
}

int vm_read_obj(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  return vm_surf_read_text(ctx, name, buf, len, '#', read_obj, out);
}

int vm_write_obj(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  int lossy;
  int64_t ntri, nquad;
  int st = vm_surf_write_prepare(ctx, m, path, "OBJ", 0, &lossy, &ntri, &nquad);
  if (st < 0) return st;
  vm_outfile *f;
  if ((st = vm_outfile_open(ctx, path, &f)) < 0) return st;
  FILE *fp = vm_outfile_fp(f);
  fprintf(fp, "# varmesh: %lld vertices, %lld faces\n", (long long)m->nv,
          (long long)(ntri + nquad));
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    fprintf(fp, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    const int32_t *c = m->conn + m->eoff[e];
    if (m->etype[e] == VM_TRI)
      fprintf(fp, "f %ld %ld %ld\n", (long)c[0] + 1, (long)c[1] + 1, (long)c[2] + 1);
    else
      fprintf(fp, "f %ld %ld %ld %ld\n", (long)c[0] + 1, (long)c[1] + 1, (long)c[2] + 1,
              (long)c[3] + 1);
  }
  return vm_surf_write_finish(ctx, &f, path, lossy);
}
