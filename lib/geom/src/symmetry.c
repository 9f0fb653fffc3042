/* lib/geom/src/symmetry.c: half models: a triangle surface cut by an
 * axis-aligned plane, and the symmetry plane as a mesh attribute. */
#include "varmesh/symmetry.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"

int vm_axis_plane_parse(vm_ctx *ctx, const char *s, int *axis, double *value, int *side) {
  const char *what = side ? "x=C, y=C or z=C, optionally :+ or :-" : "x=C, y=C or z=C";
  if (!s) s = "";
  int a = tolower((unsigned char)s[0]) - 'x';
  if (a < 0 || a > 2 || s[1] != '=')
    return ctx ? vm_error(ctx, VM_ERR_ARG, "'%s': expected %s", s, what) : VM_ERR_ARG;
  char *end = NULL;
  double c = strtod(s + 2, &end);
  int sd = 0;
  if (end != s + 2 && side && end[0] == ':' && (end[1] == '+' || end[1] == '-') && !end[2]) {
    sd = end[1] == '+' ? 1 : -1;
    end += 2;
  }
  if (end == s + 2 || *end || !isfinite(c))
    return ctx ? vm_error(ctx, VM_ERR_ARG, "'%s': expected %s", s, what) : VM_ERR_ARG;
  *axis = a;
  *value = c;
  if (side) *side = sd;
  return VM_OK;
}

char *vm_axis_plane_format(int axis, double value, char *buf, size_t n) {
  char ax = (char)('x' + (axis >= 0 && axis <= 2 ? axis : 0));
  for (int prec = 1; prec <= 17; prec++) {
    snprintf(buf, n, "%c=%.*g", ax, prec, value == 0 ? 0.0 : value);
    if (strtod(buf + 2, NULL) == value) break;
  }
  return buf;
}

int vm_mesh_get_symmetry_plane(const vm_mesh *m, int *axis, double *value) {
  const char *s = vm_mesh_get_attr(m, VM_SYMMETRY_PLANE_ATTR);
  if (!s) return 0;
  if (vm_axis_plane_parse(NULL, s, axis, value, NULL))
    return vm_error(m->ctx, VM_ERR_FORMAT, "attribute %s = '%s': expected x=C, y=C or z=C",
                    VM_SYMMETRY_PLANE_ATTR, s);
  return 1;
}

int vm_mesh_set_symmetry_plane(vm_mesh *m, int axis, double value) {
  if (axis < 0 || axis > 2 || !isfinite(value))
    return vm_error(m->ctx, VM_ERR_ARG, "symmetry plane: axis %d, value %g", axis, value);
  char buf[64];
  return vm_mesh_set_attr(m, VM_SYMMETRY_PLANE_ATTR, vm_axis_plane_format(axis, value, buf, 64));
}

/* ---- the cut ---- */

typedef struct {
  int32_t a, b; /* the edge's ends, a < b */
  double t;     /* the new vertex at a + t (b - a) */
} split;

typedef struct {
  vm_ctx *ctx;
  double *x; /* coordinates: m's (snapped), then the new vertices' */
  int64_t nv, cap;
  split *sp;
  int32_t *tri, *parent;
  int64_t nt, tcap;
} cutbuf;

static int add_tri(cutbuf *b, int32_t p, int32_t q, int32_t r, int32_t parent) {
  if (b->nt == b->tcap) {
    int64_t cap = b->tcap ? 2 * b->tcap : 1024;
    int32_t *t = vm_realloc(b->ctx, b->tri, 3 * (size_t)cap * sizeof *t);
    if (!t) return VM_ERR_NOMEM;
    b->tri = t;
    int32_t *pa = vm_realloc(b->ctx, b->parent, (size_t)cap * sizeof *pa);
    if (!pa) return VM_ERR_NOMEM;
    b->parent = pa;
    b->tcap = cap;
  }
  b->tri[3 * b->nt] = p;
  b->tri[3 * b->nt + 1] = q;
  b->tri[3 * b->nt + 2] = r;
  b->parent[b->nt++] = parent;
  return VM_OK;
}

/* The vertex on the edge (a, b), made once: computed from the lower
 * index so that both triangles of the edge get the same point. */
static int32_t split_vertex(cutbuf *b, hmap *h, int64_t nv0, int axis, double c, int32_t a,
                            int32_t e) {
  uint64_t k = ukey(a, e);
  int64_t got = hm_get(h, k);
  if (got >= 0) return (int32_t)got;
  if (b->nv == b->cap) {
    int64_t cap = 2 * b->cap;
    double *x = vm_realloc(b->ctx, b->x, 3 * (size_t)cap * sizeof *x);
    if (!x) return VM_ERR_NOMEM;
    b->x = x;
    split *s = vm_realloc(b->ctx, b->sp, (size_t)(cap - nv0) * sizeof *s);
    if (!s) return VM_ERR_NOMEM;
    b->sp = s;
    b->cap = cap;
  }
  int32_t lo = a < e ? a : e, hi = a < e ? e : a;
  const double *p = b->x + 3 * (int64_t)lo, *q = b->x + 3 * (int64_t)hi;
  double t = (c - p[axis]) / (q[axis] - p[axis]);
  double *n = b->x + 3 * b->nv;
  for (int j = 0; j < 3; j++) n[j] = p[j] + t * (q[j] - p[j]);
  n[axis] = c;
  b->sp[b->nv - nv0] = (split){lo, hi, t};
  if (hm_reserve(b->ctx, h, 1)) return VM_ERR_NOMEM;
  hm_put(h, k, b->nv);
  return (int32_t)b->nv++;
}

static int zero_area(const double *x, int32_t p, int32_t q, int32_t r) {
  double n[3];
  tri_normal(x, p, q, r, n);
  return n[0] == 0 && n[1] == 0 && n[2] == 0;
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Border edges of the triangles (3 each, nt): how many, and how many of
 * them have an end off the plane. */
static int count_border(vm_ctx *ctx, const int32_t *tri, int64_t nt, const double *x, int axis,
                        double c, int64_t *nb, int64_t *off) {
  uint64_t *key = vm_alloc_array(ctx, 3 * (size_t)(nt > 0 ? nt : 1), sizeof *key);
  if (!key) return VM_ERR_NOMEM;
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) key[3 * t + i] = ukey(tri[3 * t + i], tri[3 * t + (i + 1) % 3]);
  size_t n = 3 * (size_t)nt;
  qsort(key, n, sizeof *key, cmp_u64);
  *nb = *off = 0;
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && key[j] == key[i]) j++;
    if (j == i + 1) {
      int32_t a = (int32_t)(key[i] >> 32), b = (int32_t)(key[i] & 0xffffffffu);
      (*nb)++;
      *off += x[3 * (int64_t)a + axis] != c || x[3 * (int64_t)b + axis] != c;
    }
    i = j;
  }
  vm_free(ctx, key);
  return VM_OK;
}

int vm_mesh_cut_plane(vm_mesh *m, int axis, double c, int side, vm_cut_report *rep) {
  vm_ctx *ctx = m->ctx;
  vm_cut_report r;
  memset(&r, 0, sizeof r);
  if (axis < 0 || axis > 2 || !isfinite(c) || side < -1 || side > 1)
    return vm_error(ctx, VM_ERR_ARG, "cut: axis %d, value %g, side %d", axis, c, side);
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] != VM_TRI)
      return vm_error(ctx, VM_ERR_ARG, "cut: element %lld is a %s; only triangle surfaces are cut",
                      (long long)e, vm_elem_name(m->etype[e]));
  const int64_t nv0 = m->nv, nf0 = m->ne;
  double lo[3], hi[3], diag = vm_mesh_bounds(m, lo, hi);
  r.axis = axis;
  r.value = c;
  r.tol = VM_SYMMETRY_TOL_REL * diag;
  r.nv_in = nv0;
  r.nf_in = nf0;
  if (side == 0) side = nv0 == 0 || hi[axis] - c >= c - lo[axis] ? 1 : -1;
  r.side = side;
  const char ax = (char)('x' + axis);

  cutbuf b = {ctx, NULL, nv0, nv0 + 64, NULL, NULL, NULL, 0, 0};
  hmap h = {0};
  int8_t *k = vm_alloc_array(ctx, (size_t)(nv0 > 0 ? nv0 : 1), sizeof *k);
  int32_t *idx = NULL;
  vm_mesh *n = NULL;
  b.x = vm_alloc_array(ctx, 3 * (size_t)b.cap, sizeof *b.x);
  b.sp = vm_alloc_array(ctx, (size_t)(b.cap - nv0), sizeof *b.sp);
  int st = k && b.x && b.sp ? hm_init(ctx, &h, 1024) : VM_ERR_NOMEM;
  if (st) goto done;
  if (nv0) memcpy(b.x, m->xyz, 3 * (size_t)nv0 * sizeof *b.x);
  /* which side each vertex is on, relative to the side kept; the ones
   * within the tolerance put on the plane */
  for (int64_t v = 0; v < nv0; v++) {
    double *p = b.x + 3 * v, s = p[axis] - c;
    if (fabs(s) <= r.tol) {
      r.snapped += p[axis] != c;
      p[axis] = c;
      k[v] = 0;
    } else {
      k[v] = (int8_t)((s > 0 ? 1 : -1) * side);
    }
  }
  for (int64_t e = 0; e < nf0 && !st; e++) {
    const int32_t *t = m->conn + m->eoff[e];
    int np = 0, neg = 0, pos = 0;
    for (int i = 0; i < 3; i++) neg += k[t[i]]<0, pos += k[t[i]]> 0;
    if (!pos) continue; /* on the other side, or in the plane */
    if (!neg) {
      if (zero_area(b.x, t[0], t[1], t[2]))
        r.degenerate++;
      else
        st = add_tri(&b, t[0], t[1], t[2], (int32_t)e);
      continue;
    }
    r.clipped++;
    int32_t poly[4];
    for (int i = 0; i < 3 && !st; i++) {
      int32_t p = t[i], q = t[(i + 1) % 3];
      if (k[p] >= 0) poly[np++] = p;
      if (k[p] * k[q] < 0) {
        int32_t s = split_vertex(&b, &h, nv0, axis, c, p, q);
        if (s < 0)
          st = s;
        else
          poly[np++] = s;
      }
    }
    if (st) break;
    int32_t tr[2][3] = {{poly[0], poly[1], poly[2]}, {-1, -1, -1}};
    if (np == 4) {
      /* the diagonal whose triangles have the larger smallest angle */
      double qa = fmin(tri_min_deg(b.x, poly[0], poly[1], poly[2]),
                       tri_min_deg(b.x, poly[0], poly[2], poly[3]));
      double qb = fmin(tri_min_deg(b.x, poly[1], poly[2], poly[3]),
                       tri_min_deg(b.x, poly[1], poly[3], poly[0]));
      int d = qb > qa;
      for (int i = 0; i < 3; i++) {
        tr[0][i] = poly[(d + (i == 0 ? 0 : i)) % 4];
        tr[1][i] = poly[(d + (i == 0 ? 0 : i + 1)) % 4];
      }
    }
    for (int j = 0; j < 2 && !st; j++) {
      if (tr[j][0] < 0) continue;
      if (zero_area(b.x, tr[j][0], tr[j][1], tr[j][2]))
        r.degenerate++;
      else
        st = add_tri(&b, tr[j][0], tr[j][1], tr[j][2], (int32_t)e);
    }
  }
  if (st) goto done;
  r.split_edges = b.nv - nv0;
  if (b.nt == 0) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "cut: nothing of the model lies on the %s side of %c=%g (it spans %c from %g "
                  "to %g)",
                  side > 0 ? "+" : "-", ax, c, ax, lo[axis], hi[axis]);
    goto done;
  }
  /* the vertices used, in order: m's, then the new ones */
  idx = vm_alloc_array(ctx, (size_t)b.nv, sizeof *idx);
  if (!idx) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t v = 0; v < b.nv; v++) idx[v] = -1;
  for (int64_t i = 0; i < 3 * b.nt; i++) idx[b.tri[i]] = 0;
  int64_t nk = 0;
  for (int64_t v = 0; v < b.nv; v++)
    if (idx[v] == 0) idx[v] = (int32_t)nk++;
  if ((st = vm_mesh_create(ctx, &n))) goto done;
  n->dim = m->dim;
  if ((st = vm_mesh_set_vertices(n, nk)) || (st = vm_mesh_set_elements(n, b.nt, 3 * b.nt)))
    goto done;
  for (int64_t v = 0; v < b.nv; v++) {
    int32_t i = idx[v];
    if (i < 0) continue;
    memcpy(n->xyz + 3 * (int64_t)i, b.x + 3 * v, 3 * sizeof *b.x);
    if (v < nv0) {
      n->vflag[i] = m->vflag[v];
      n->vsurf[i] = m->vsurf[v];
    } else {
      const split *s = &b.sp[v - nv0];
      n->vflag[i] = m->vflag[s->a] == m->vflag[s->b] ? m->vflag[s->a] : VM_VERTEX_FREE;
      n->vsurf[i] = m->vsurf[s->a] == m->vsurf[s->b] ? m->vsurf[s->a] : -1;
    }
  }
  for (int64_t t = 0; t < b.nt; t++) {
    n->etype[t] = VM_TRI;
    n->eoff[t + 1] = n->eoff[t] + 3;
    for (int i = 0; i < 3; i++) n->conn[3 * t + i] = idx[b.tri[3 * t + i]];
  }
  for (int i = 0; i < m->nattr && !st; i++)
    st = vm_mesh_set_attr(n, m->attrs[i].key, m->attrs[i].value);
  for (int i = 0; i < m->nfield && !st; i++) {
    const vm_field *src = &m->fields[i];
    vm_field *dst = NULL;
    const int nc = src->ncomp;
    if ((st = vm_mesh_add_field(n, src->name, src->location, src->type, nc, &dst))) break;
    if (src->location == VM_FIELD_ELEMENT) {
      size_t sz = (size_t)nc * (src->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
      for (int64_t t = 0; t < b.nt; t++)
        memcpy((char *)dst->data + (size_t)t * sz, (const char *)src->data + b.parent[t] * sz, sz);
      continue;
    }
    for (int64_t v = 0; v < b.nv; v++) {
      int64_t i2 = idx[v];
      if (i2 < 0) continue;
      const split *s = v < nv0 ? NULL : &b.sp[v - nv0];
      for (int j = 0; j < nc; j++) {
        if (src->type == VM_FIELD_F64) {
          const double *sd = src->data;
          ((double *)dst->data)[i2 * nc + j] =
              s ? (1 - s->t) * sd[(int64_t)s->a * nc + j] + s->t * sd[(int64_t)s->b * nc + j]
                : sd[v * nc + j];
        } else {
          const int32_t *sd = src->data;
          int32_t va = s ? sd[(int64_t)s->a * nc + j] : sd[v * nc + j];
          ((int32_t *)dst->data)[i2 * nc + j] = !s || va == sd[(int64_t)s->b * nc + j] ? va : 0;
        }
      }
    }
  }
  if (st) goto done;
  if ((st = count_border(ctx, n->conn, n->ne, n->xyz, axis, c, &r.border_edges, &r.border_off)))
    goto done;
  r.nv = n->nv;
  r.nf = n->ne;
  {
    vm_mesh tmp = *m;
    *m = *n;
    *n = tmp;
  }
done:
  if (rep) *rep = r;
  hm_free(ctx, &h);
  vm_free(ctx, k);
  vm_free(ctx, idx);
  vm_free(ctx, b.x);
  vm_free(ctx, b.sp);
  vm_free(ctx, b.tri);
  vm_free(ctx, b.parent);
  vm_mesh_destroy(&n);
  return st;
}
