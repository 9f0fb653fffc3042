/* lib/geom/src/symmetry.c: half models: a triangle surface cut by an
 * axis-aligned plane, and the symmetry plane as a mesh attribute. */
#include "varmesh/symmetry.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"
#include "varmesh/surface_mesh.h"

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

int vm_mesh_cut_plane(vm_mesh *m, int axis, double c, int side, double snap_rel,
                      vm_cut_report *rep) {
  vm_ctx *ctx = m->ctx;
  vm_cut_report r;
  memset(&r, 0, sizeof r);
  if (axis < 0 || axis > 2 || !isfinite(c) || side < -1 || side > 1 || !(snap_rel >= 0) ||
      snap_rel >= 0.5)
    return vm_error(ctx, VM_ERR_ARG, "cut: axis %d, value %g, side %d, snap_rel %g", axis, c, side,
                    snap_rel);
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
  /* an edge the plane would cut within snap_rel of its length from an end:
   * that end onto the plane instead (no needle between it and the cut) */
  for (int64_t e = 0; snap_rel > 0 && e < nf0; e++) {
    const int32_t *t = m->conn + m->eoff[e];
    for (int i = 0; i < 3; i++) {
      int32_t a = t[i], q = t[(i + 1) % 3];
      if (k[a] * k[q] >= 0) continue;
      double *pa = b.x + 3 * (int64_t)a, *pq = b.x + 3 * (int64_t)q;
      double f = (c - pa[axis]) / (pq[axis] - pa[axis]);
      int32_t v = f <= 0.5 ? a : q;
      if ((f <= 0.5 ? f : 1 - f) >= snap_rel) continue;
      b.x[3 * (int64_t)v + axis] = c;
      k[v] = 0;
      r.snapped_near++;
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

/* ---- an open wall's symmetry plane ---- */

static int64_t uf_find(int64_t *p, int64_t v) {
  while (p[v] != v) {
    p[v] = p[p[v]];
    v = p[v];
  }
  return v;
}

static int cmp_f64(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static double orient2(const double *a, const double *b, const double *c, int u, int v) {
  return (b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u]);
}

/* c on the segment ab, given that the three are collinear */
static int on_seg(const double *a, const double *b, const double *c, int u, int v) {
  return fmin(a[u], b[u]) <= c[u] && c[u] <= fmax(a[u], b[u]) && fmin(a[v], b[v]) <= c[v] &&
         c[v] <= fmax(a[v], b[v]);
}

/* Do the segments ab and cd of the plane (coordinates u, v) meet? */
static int segs_meet(const double *a, const double *b, const double *c, const double *d, int u,
                     int v) {
  double d1 = orient2(a, b, c, u, v), d2 = orient2(a, b, d, u, v);
  double d3 = orient2(c, d, a, u, v), d4 = orient2(c, d, b, u, v);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return 1;
  return (d1 == 0 && on_seg(a, b, c, u, v)) || (d2 == 0 && on_seg(a, b, d, u, v)) ||
         (d3 == 0 && on_seg(c, d, a, u, v)) || (d4 == 0 && on_seg(c, d, b, u, v));
}

typedef struct {
  double lo, hi;
  int64_t e;
} span;

static int cmp_span(const void *a, const void *b) {
  const span *p = a, *q = b;
  if (p->lo != q->lo) return p->lo < q->lo ? -1 : 1;
  return p->e < q->e ? -1 : p->e > q->e;
}

/* The first pair of border edges (bv: 2 vertices each, nb) that meet in
 * the plane without sharing a vertex (a sweep along the first in-plane
 * coordinate); 1 and the pair in *e1, *e2, else 0, or VM_ERR_NOMEM. */
static int border_crossing(vm_ctx *ctx, const double *x, const int32_t *bv, int64_t nb, int axis,
                           int64_t *e1, int64_t *e2) {
  int u = (axis + 1) % 3, v = (axis + 2) % 3;
  span *s = vm_alloc_array(ctx, (size_t)(nb > 0 ? nb : 1), sizeof *s);
  if (!s) return VM_ERR_NOMEM;
  for (int64_t e = 0; e < nb; e++) {
    double p = x[3 * (int64_t)bv[2 * e] + u], q = x[3 * (int64_t)bv[2 * e + 1] + u];
    s[e] = (span){fmin(p, q), fmax(p, q), e};
  }
  qsort(s, (size_t)nb, sizeof *s, cmp_span);
  int found = 0;
  for (int64_t i = 0; i < nb && !found; i++)
    for (int64_t j = i + 1; j < nb && s[j].lo <= s[i].hi && !found; j++) {
      const int32_t *a = bv + 2 * s[i].e, *b = bv + 2 * s[j].e;
      if (a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]) continue;
      if (segs_meet(x + 3 * (int64_t)a[0], x + 3 * (int64_t)a[1], x + 3 * (int64_t)b[0],
                    x + 3 * (int64_t)b[1], u, v)) {
        found = 1;
        *e1 = s[i].e < s[j].e ? s[i].e : s[j].e;
        *e2 = s[i].e < s[j].e ? s[j].e : s[i].e;
      }
    }
  vm_free(ctx, s);
  return found;
}

double vm_symmetry_half_volume(const vm_mesh *m, int axis, double c) {
  double vol = 0;
  int p = (axis + 1) % 3, q = (axis + 2) % 3;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *cn = m->conn + m->eoff[e];
    int k = (int)(m->eoff[e + 1] - m->eoff[e]);
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    /* a polygon as the fan from its first vertex */
    for (int i = 1; i + 1 < k; i++) {
      const double *a = m->xyz + 3 * (int64_t)cn[0], *b = m->xyz + 3 * (int64_t)cn[i],
                   *d = m->xyz + 3 * (int64_t)cn[i + 1];
      double n = (b[p] - a[p]) * (d[q] - a[q]) - (b[q] - a[q]) * (d[p] - a[p]);
      vol += ((a[axis] + b[axis] + d[axis]) / 3 - c) * n / 2;
    }
  }
  return vol;
}

int vm_symmetry_keep(vm_mesh *m, int axis, double c, double tol, int64_t *snapped, double *max_off,
                     int64_t *off, double at[3]) {
  vm_surf_edges E;
  int st = vm_surf_edges_build(m->ctx, m, &E);
  if (st) return st;
  int64_t ns = 0, no = 0;
  double mx = 0;
  for (int64_t e = 0; e < E.ne; e++) {
    if (E.nface[e] != 1) continue;
    for (int i = 0; i < 2; i++) {
      double *p = m->xyz + 3 * (int64_t)E.ev[2 * e + i], d = fabs(p[axis] - c);
      if (d == 0) continue;
      if (d <= tol) {
        p[axis] = c;
        ns++;
        mx = fmax(mx, d);
      } else {
        if (!no && at) memcpy(at, p, 3 * sizeof *p);
        no++;
      }
    }
  }
  vm_surf_edges_free(m->ctx, &E);
  if (snapped) *snapped = ns;
  if (max_off) *max_off = mx;
  if (off) *off = no;
  return VM_OK;
}

int vm_symmetry_detect(vm_mesh *m, const vm_symmetry_opts *o, vm_symmetry_report *rep) {
  vm_ctx *ctx = m->ctx;
  vm_symmetry_report r;
  memset(&r, 0, sizeof r);
  double lo[3], hi[3], diag = vm_mesh_bounds(m, lo, hi);
  double tol = (o && o->tol_rel > 0 ? o->tol_rel : VM_SYMMETRY_DETECT_TOL) * diag;
  int axis = -1, given = 0;
  double c = 0;
  r.tol = tol;
  if (o && o->given) {
    if (o->axis < 0 || o->axis > 2 || !isfinite(o->value))
      return vm_error(ctx, VM_ERR_ARG, "symmetry plane: axis %d, value %g", o->axis, o->value);
    axis = o->axis;
    c = o->value;
    given = 1;
  } else {
    int k = vm_mesh_get_symmetry_plane(m, &axis, &c);
    if (k < 0) return k;
    if (k == 1) given = 2;
  }
  char pl[64] = "";
  if (given) vm_axis_plane_format(axis, c, pl, sizeof pl);
  const char *by = given == 1 ? "given" : "named by the attribute " VM_SYMMETRY_PLANE_ATTR;
  vm_surf_edges E;
  memset(&E, 0, sizeof E);
  int32_t *bv = NULL;
  int64_t *uf = NULL, *loop_of = NULL;
  double *vals = NULL;
  uint8_t *isb = NULL;
  int st = vm_surf_edges_build(ctx, m, &E);
  if (st) return st;
  int64_t nb = 0, nbv = 0;
  for (int64_t e = 0; e < E.ne; e++) nb += E.nface[e] == 1;
  r.border_edges = nb;
  if (nb == 0) {
    if (given)
      st = vm_error(ctx, VM_ERR_FORMAT,
                    "the symmetry plane %s is %s, but the surface is closed (a half model's wall "
                    "is open, its border in the plane)",
                    pl, by);
    goto done;
  }
  const size_t nv1 = (size_t)(m->nv > 0 ? m->nv : 1);
  bv = vm_alloc_array(ctx, 2 * (size_t)nb, sizeof *bv);
  uf = vm_alloc_array(ctx, nv1, sizeof *uf);
  loop_of = vm_alloc_array(ctx, nv1, sizeof *loop_of);
  vals = vm_alloc_array(ctx, nv1, sizeof *vals);
  isb = vm_calloc(ctx, nv1, 1);
  if (!bv || !uf || !loop_of || !vals || !isb) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  nb = 0;
  for (int64_t v = 0; v < m->nv; v++) uf[v] = v;
  for (int64_t e = 0; e < E.ne; e++) {
    if (E.nface[e] != 1) continue;
    int32_t a = E.ev[2 * e], b = E.ev[2 * e + 1];
    bv[2 * nb] = a;
    bv[2 * nb + 1] = b;
    nb++;
    isb[a] = isb[b] = 1;
    int64_t ra = uf_find(uf, a), rb = uf_find(uf, b);
    if (ra != rb) uf[ra > rb ? ra : rb] = ra < rb ? ra : rb;
  }
  /* the loops, numbered by their smallest vertex */
  for (int64_t v = 0; v < m->nv; v++) loop_of[v] = -1;
  for (int64_t v = 0; v < m->nv; v++) {
    if (!isb[v]) continue;
    nbv++;
    int64_t rt = uf_find(uf, v);
    if (loop_of[rt] < 0) loop_of[rt] = r.loops++;
    loop_of[v] = loop_of[rt];
  }
  r.border_vertices = nbv;
  if (!given) {
    /* the flattest axis of the border */
    double spread = INFINITY, blo = 0, bhi = 0;
    for (int a = 0; a < 3; a++) {
      double l = INFINITY, h = -INFINITY;
      for (int64_t v = 0; v < m->nv; v++)
        if (isb[v]) l = fmin(l, m->xyz[3 * v + a]), h = fmax(h, m->xyz[3 * v + a]);
      if (h - l < spread) spread = h - l, axis = a, blo = l, bhi = h;
    }
    if (spread > 2 * tol) {
      /* not planar: each loop in a plane but not the same one, or a loop
       * in none (said with its flattest axis) */
      int64_t first = -1, second = -1, bad = -1;
      int fa = 0, sa = 0, ba = 0;
      double fc = 0, sc = 0, bl = 0, bh = 0;
      for (int64_t L = 0; L < r.loops && bad < 0 && second < 0; L++) {
        int la = 0;
        double ls = INFINITY, ll = 0, lh = 0;
        for (int a = 0; a < 3; a++) {
          double l = INFINITY, h = -INFINITY;
          for (int64_t v = 0; v < m->nv; v++)
            if (isb[v] && loop_of[v] == L)
              l = fmin(l, m->xyz[3 * v + a]), h = fmax(h, m->xyz[3 * v + a]);
          if (h - l < ls) ls = h - l, la = a, ll = l, lh = h;
        }
        if (ls > 2 * tol)
          bad = L, ba = la, bl = ll, bh = lh;
        else if (first < 0)
          first = L, fa = la, fc = (ll + lh) / 2;
        else if (la != fa || fabs((ll + lh) / 2 - fc) > 2 * tol)
          second = L, sa = la, sc = (ll + lh) / 2;
      }
      const double *p1 = NULL, *p2 = NULL;
      int64_t n1 = 0, n2 = 0;
      for (int64_t v = 0; v < m->nv; v++) {
        if (!isb[v]) continue;
        if (loop_of[v] == (bad >= 0 ? bad : first)) n1++, p1 = p1 ? p1 : m->xyz + 3 * v;
        if (loop_of[v] == second) n2++, p2 = p2 ? p2 : m->xyz + 3 * v;
      }
      if (bad >= 0) {
        snprintf(r.why, sizeof r.why,
                 "its border is in no plane x, y or z = C: %s%lld vertices through (%g, %g, %g) "
                 "spans %c from %g to %g even along its flattest axis (%.3g of the model's "
                 "diagonal; tolerance %.3g)",
                 r.loops > 1 ? "a border loop of " : "the border loop of ", (long long)n1, p1[0],
                 p1[1], p1[2], 'x' + ba, bl, bh, diag > 0 ? (bh - bl) / diag : 0,
                 diag > 0 ? tol / diag : 0);
      } else if (second >= 0) {
        char s1[64], s2[64];
        snprintf(r.why, sizeof r.why,
                 "its %lld border loops lie in different planes: %s (%lld vertices, e.g. (%g, %g, "
                 "%g)) and %s (%lld vertices, e.g. (%g, %g, %g))",
                 (long long)r.loops, vm_axis_plane_format(fa, fc, s1, sizeof s1), (long long)n1,
                 p1[0], p1[1], p1[2], vm_axis_plane_format(sa, sc, s2, sizeof s2), (long long)n2,
                 p2[0], p2[1], p2[2]);
      } else {
        snprintf(r.why, sizeof r.why,
                 "its border loops lie in planes %.3g of the model's diagonal apart (tolerance "
                 "%.3g)",
                 diag > 0 ? spread / diag : 0, diag > 0 ? tol / diag : 0);
      }
      goto done;
    }
    /* the plane: the value most border vertices have exactly (the
     * smallest of equals), else the middle of their span */
    int64_t n = 0, best = 0;
    for (int64_t v = 0; v < m->nv; v++)
      if (isb[v]) vals[n++] = m->xyz[3 * v + axis];
    qsort(vals, (size_t)n, sizeof *vals, cmp_f64);
    c = vals[0];
    for (int64_t i = 0; i < n;) {
      int64_t j = i + 1;
      while (j < n && vals[j] == vals[i]) j++;
      if (j - i > best) best = j - i, c = vals[i];
      i = j;
    }
    if (fabs(bhi - c) > tol || fabs(c - blo) > tol) c = (blo + bhi) / 2;
    if (c == 0) c = 0; /* -0 -> +0 */
    vm_axis_plane_format(axis, c, pl, sizeof pl);
  } else {
    double far = -1;
    int64_t nfar = 0, fv = -1;
    for (int64_t v = 0; v < m->nv; v++) {
      if (!isb[v]) continue;
      double d = fabs(m->xyz[3 * v + axis] - c);
      nfar += d > tol;
      if (d > far) far = d, fv = v;
    }
    if (far > tol) {
      const double *p = m->xyz + 3 * fv;
      st = vm_error(ctx, VM_ERR_FORMAT,
                    "the border is not in the symmetry plane %s (%s): %lld of its %lld border "
                    "vertices are farther than %.3g from it, the farthest (%g, %g, %g) by %g",
                    pl, by, (long long)nfar, (long long)nbv, tol, p[0], p[1], p[2], far);
      goto done;
    }
  }
  /* the wall on one side of the plane, not in it */
  {
    int64_t npos = 0, nneg = 0, vpos = -1, vneg = -1, inplane = 0, fin = -1;
    double dpos = 0, dneg = 0;
    for (int64_t v = 0; v < m->nv; v++) {
      double d = m->xyz[3 * v + axis] - c;
      if (d > tol) {
        npos++;
        if (d > dpos) dpos = d, vpos = v;
      } else if (d < -tol) {
        nneg++;
        if (-d > dneg) dneg = -d, vneg = v;
      }
    }
    for (int64_t e = 0; e < m->ne; e++) {
      const int32_t *cn = m->conn + m->eoff[e];
      int k = (int)(m->eoff[e + 1] - m->eoff[e]), in = vm_elem_dim(m->etype[e]) == 2;
      for (int i = 0; i < k && in; i++) in = fabs(m->xyz[3 * (int64_t)cn[i] + axis] - c) <= tol;
      if (in && !inplane++) fin = e;
    }
    if (!npos && !nneg) {
      if (given)
        st = vm_error(ctx, VM_ERR_FORMAT,
                      "the whole surface lies in the symmetry plane %s (%s): no wall to keep", pl,
                      by);
      else
        snprintf(r.why, sizeof r.why, "the whole surface lies in its border's plane %s", pl);
      goto done;
    }
    if (npos && nneg) {
      const double *p = m->xyz + 3 * vpos, *q = m->xyz + 3 * vneg;
      st = vm_error(ctx, VM_ERR_FORMAT,
                    "half model (symmetry plane %s): the wall lies on both sides of the plane, "
                    "%lld vertices above it and %lld below, e.g. (%g, %g, %g) %g above and (%g, "
                    "%g, %g) %g below",
                    pl, (long long)npos, (long long)nneg, p[0], p[1], p[2], dpos, q[0], q[1], q[2],
                    dneg);
      goto done;
    }
    r.side = npos ? 1 : -1;
    if (inplane) {
      const int32_t *cn = m->conn + m->eoff[fin];
      const double *p = m->xyz + 3 * (int64_t)cn[0];
      st = vm_error(ctx, VM_ERR_FORMAT,
                    "half model (symmetry plane %s): %lld faces lie in the plane, e.g. the one at "
                    "(%g, %g, %g): a half model's wall has no face in its symmetry plane",
                    pl, (long long)inplane, p[0], p[1], p[2]);
      goto done;
    }
  }
  {
    int64_t e1 = -1, e2 = -1;
    int k = border_crossing(ctx, m->xyz, bv, nb, axis, &e1, &e2);
    if (k < 0) {
      st = k;
      goto done;
    }
    if (k) {
      const double *a = m->xyz + 3 * (int64_t)bv[2 * e1], *b = m->xyz + 3 * (int64_t)bv[2 * e1 + 1];
      const double *p = m->xyz + 3 * (int64_t)bv[2 * e2], *q = m->xyz + 3 * (int64_t)bv[2 * e2 + 1];
      st = vm_error(ctx, VM_ERR_FORMAT,
                    "half model (symmetry plane %s): its border loops cross each other in the "
                    "plane: the border edges (%g, %g, %g)-(%g, %g, %g) and (%g, %g, %g)-(%g, %g, "
                    "%g) meet",
                    pl, a[0], a[1], a[2], b[0], b[1], b[2], p[0], p[1], p[2], q[0], q[1], q[2]);
      goto done;
    }
  }
  /* a half model: its border onto the plane, bit for bit */
  for (int64_t v = 0; v < m->nv; v++) {
    if (!isb[v]) continue;
    double d = fabs(m->xyz[3 * v + axis] - c);
    if (d == 0) continue;
    r.snapped++;
    r.max_offset = fmax(r.max_offset, d);
    m->xyz[3 * v + axis] = c;
  }
  if ((st = vm_mesh_set_symmetry_plane(m, axis, c))) goto done;
  r.found = 1;
  r.given = given;
  r.axis = axis;
  r.value = c;
done:
  if (!r.found) {
    r.axis = given ? axis : -1;
    r.value = given ? c : 0;
  }
  if (rep) *rep = r;
  vm_surf_edges_free(ctx, &E);
  vm_free(ctx, bv);
  vm_free(ctx, uf);
  vm_free(ctx, loop_of);
  vm_free(ctx, vals);
  vm_free(ctx, isb);
  return st;
}
