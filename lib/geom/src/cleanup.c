/* lib/geom/src/cleanup.c: sliver removal by edge flips and collapses on a
 * half-edge view of a triangle surface (directed edges in a hash map), and
 * cone-point detection. Nothing moves: every accepted operation only
 * changes which input vertices the triangles join. */
#include "varmesh/cleanup.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"
#include "varmesh/surface_mesh.h"

vm_cleanup_opts vm_cleanup_opts_default(void) {
  vm_cleanup_opts o;
  o.angle = 15;
  o.max_dev = 0;
  o.max_dev_rel = 0.05;
  o.rounds = 20;
  o.border_collapse = 0;
  return o;
}

static int tris_only(const vm_mesh *m) {
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] != VM_TRI) return 0;
  return m->ne > 0;
}

double vm_surface_elem_min_angle(const vm_mesh *m, const double *x, int64_t e) {
  int k = vm_elem_nverts(m->etype[e]);
  const int32_t *c = m->conn + m->eoff[e];
  double mn = 180;
  for (int a = 0; a < k; a++) {
    double d = corner_deg(x + 3 * (int64_t)c[a], x + 3 * (int64_t)c[(a + 1) % k],
                          x + 3 * (int64_t)c[(a + k - 1) % k]);
    if (d < mn) mn = d;
  }
  return mn;
}

double vm_surface_elem_area(const vm_mesh *m, const double *x, int64_t e) {
  int k = vm_elem_nverts(m->etype[e]);
  const int32_t *c = m->conn + m->eoff[e];
  double a = 0;
  for (int i = 1; i + 1 < k; i++) {
    double n[3];
    tri_normal(x, c[0], c[i], c[i + 1], n);
    a += 0.5 * vm_norm3(n);
  }
  return a;
}

int64_t vm_surface_count_opposing(const vm_mesh *m, vm_surface_projector *ref, double at[3]) {
  if (!m || !ref) return VM_ERR_ARG;
  vm_surface_ops ops = vm_surface_projector_ops(ref);
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI) continue;
    const int32_t *c = m->conn + m->eoff[e];
    double n[3], ctr[3], q[3], nr[9];
    tri_normal(m->xyz, c[0], c[1], c[2], n);
    for (int r = 0; r < 3; r++)
      ctr[r] = (m->xyz[3 * (int64_t)c[0] + r] + m->xyz[3 * (int64_t)c[1] + r] +
                m->xyz[3 * (int64_t)c[2] + r]) /
               3;
    int nn = ops.project(ops.user, 0, ctr, q, nr);
    if (nn < 0) return nn;
    if (vm_dot3(n, nr) <= 0) {
      if (!k && at) memcpy(at, ctr, sizeof ctr);
      k++;
    }
  }
  return k;
}

double vm_surface_min_angle_free(const vm_mesh *m, const vm_surface_features *f, double *min_all) {
  double mf = 180, ma = 180;
  if (m)
    for (int64_t e = 0; e < m->ne; e++) {
      if (m->etype[e] != VM_TRI) continue;
      const int32_t *c = m->conn + m->eoff[e];
      for (int i = 0; i < 3; i++) {
        double a = corner_deg(m->xyz + 3 * (int64_t)c[i], m->xyz + 3 * (int64_t)c[(i + 1) % 3],
                              m->xyz + 3 * (int64_t)c[(i + 2) % 3]);
        if (a < ma) ma = a;
        if (a < mf && !(f && f->nv == m->nv && f->vclass[c[i]] == VM_FEATURE_CORNER)) mf = a;
      }
    }
  if (min_all) *min_all = ma;
  return mf;
}

/* ---- cone points ---- */

int64_t vm_surface_mark_cones(const vm_mesh *m, vm_surface_features *f, double cone_deg) {
  if (!m || !f || f->nv != m->nv || !(cone_deg > 0)) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  const int64_t nv = m->nv;
  vm_surf_edges E;
  int st = vm_surf_edges_build(ctx, m, &E);
  if (st) return st;
  double *sum = vm_calloc(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *sum);
  if (!sum) {
    vm_surf_edges_free(ctx, &E);
    return VM_ERR_NOMEM;
  }
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI) continue;
    const int32_t *c = m->conn + m->eoff[e];
    for (int i = 0; i < 3; i++)
      sum[c[i]] += corner_deg(m->xyz + 3 * (int64_t)c[i], m->xyz + 3 * (int64_t)c[(i + 1) % 3],
                              m->xyz + 3 * (int64_t)c[(i + 2) % 3]);
  }
  int64_t marked = 0;
  for (int64_t v = 0; v < nv; v++) {
    if (f->vclass[v] == VM_FEATURE_CORNER || E.onbnd[v] || E.rowptr[v + 1] == E.rowptr[v]) continue;
    /* the angle deficit: 0 where the surface is developable (a plane, a
     * cylinder, a ridge), 2 pi (1 - sin a) at the tip of a cone of
     * half-angle a */
    if (fabs(360.0 - sum[v]) < cone_deg) continue;
    f->vclass[v] = VM_FEATURE_CORNER;
    f->vline[v] = -1;
    f->ncorner++;
    marked++;
  }
  vm_free(ctx, sum);
  vm_surf_edges_free(ctx, &E);
  return marked;
}

/* Do triangles e and g of m differ in an int element field (a region:
 * vm-gen's component, gmsh:physical, ...)? */
static int other_region(const vm_mesh *m, int64_t e, int64_t g) {
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *fl = &m->fields[i];
    if (fl->location != VM_FIELD_ELEMENT || fl->type != VM_FIELD_I32) continue;
    const int32_t *d = fl->data;
    if (memcmp(d + (int64_t)fl->ncomp * e, d + (int64_t)fl->ncomp * g,
               (size_t)fl->ncomp * sizeof *d))
      return 1;
  }
  return 0;
}

typedef struct {
  uint64_t key; /* smaller vertex << 32 | larger */
  int64_t face;
} edge_face;

static int cmp_edge_face(const void *a, const void *b) {
  const edge_face *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return (x->face > y->face) - (x->face < y->face);
}

/* f plus the borders between the regions of m's int element fields as
 * feature edges (its corners kept as corners): a remeshing keeps them as
 * lines, so every new triangle lies in one region. Nothing to do (VM_OK, f
 * unchanged) without such fields. */
static int add_region_borders(const vm_mesh *m, double corner_deg, vm_surface_features *f) {
  vm_ctx *ctx = m->ctx;
  int any = 0;
  for (int i = 0; i < m->nfield; i++)
    any |= m->fields[i].location == VM_FIELD_ELEMENT && m->fields[i].type == VM_FIELD_I32;
  if (!any || !tris_only(m) || m->ne == 0) return VM_OK;
  edge_face *ef = vm_alloc_array(ctx, 3 * (size_t)m->ne, sizeof *ef);
  int32_t *edges = vm_alloc_array(ctx, 2 * (size_t)f->nedge + 3 * (size_t)m->ne, sizeof *edges);
  uint8_t *corner = vm_calloc(ctx, (size_t)(m->nv > 0 ? m->nv : 1), 1);
  int st = ef && edges && corner ? VM_OK : VM_ERR_NOMEM;
  int64_t n = 2 * f->nedge, nb = 0;
  if (!st) {
    for (int64_t e = 0; e < m->ne; e++) {
      const int32_t *c = m->conn + m->eoff[e];
      for (int i = 0; i < 3; i++) {
        uint32_t a = (uint32_t)c[i], b = (uint32_t)c[(i + 1) % 3];
        ef[3 * e + i].key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        ef[3 * e + i].face = e;
      }
    }
    qsort(ef, 3 * (size_t)m->ne, sizeof *ef, cmp_edge_face);
    memcpy(edges, f->edge, 2 * (size_t)f->nedge * sizeof *edges);
    for (int64_t k = 0; k + 1 < 3 * m->ne; k++) {
      if (ef[k].key != ef[k + 1].key || !other_region(m, ef[k].face, ef[k + 1].face)) continue;
      edges[n++] = (int32_t)(ef[k].key >> 32);
      edges[n++] = (int32_t)(ef[k].key & 0xffffffffu);
      nb++;
      while (k + 1 < 3 * m->ne && ef[k + 1].key == ef[k].key) k++;
    }
    for (int64_t v = 0; v < m->nv && v < f->nv; v++) corner[v] = f->vclass[v] == VM_FEATURE_CORNER;
  }
  if (!st && nb > 0) {
    vm_surface_features g;
    memset(&g, 0, sizeof g);
    st = vm_surface_features_from_edges(m, n / 2, edges, corner, corner_deg, &g);
    if (!st) {
      vm_surface_features_free(ctx, f);
      *f = g;
    }
  }
  vm_free(ctx, ef);
  vm_free(ctx, edges);
  vm_free(ctx, corner);
  return st;
}

int vm_surface_detect_features_cones(const vm_mesh *m, double angle_deg, double corner_deg,
                                     double cone_deg, vm_surface_features *f, int64_t *ncones) {
  if (ncones) *ncones = 0;
  int st = vm_surface_detect_features(m, angle_deg, corner_deg, f);
  if (st) return st;
  if (cone_deg < 360) {
    int64_t nc = vm_surface_mark_cones(m, f, cone_deg);
    if (nc < 0) {
      vm_surface_features_free(m->ctx, f);
      return (int)nc;
    }
    if (ncones) *ncones = nc;
  }
  if ((st = add_region_borders(m, corner_deg, f))) vm_surface_features_free(m->ctx, f);
  return st;
}

/* ---- the working mesh ---- */

#define RING_MAX 512

typedef struct {
  vm_ctx *ctx;
  const vm_mesh *m;
  const double *x;
  int64_t nv, nf;
  vm_tm t; /* faces, a face of each vertex, directed edges */
  uint8_t *fdead, *vdead, *vborder;
  double *err; /* how far the surface around each vertex has moved so far */
  hmap fe;     /* feature edges */
  const uint8_t *vclass;
  double tol_abs, tol_rel, thr;
  int border_collapse;
  int64_t bad_keys;
  /* scratch: the rings and neighbours of a collapse */
  int64_t fu[RING_MAX], fw[RING_MAX];
  int32_t nu[3 * RING_MAX], nw[3 * RING_MAX];
} cmesh;

static int64_t he_find(const cmesh *c, int32_t a, int32_t b) { return vm_tm_he(&c->t, a, b); }

static void face_keys(cmesh *c, int64_t f, int add) { c->bad_keys += vm_tm_keys(&c->t, f, add); }

static int ring(const cmesh *c, int32_t v, int64_t *out) {
  return vm_tm_ring(&c->t, v, out, RING_MAX);
}

/* Smallest angle of the faces fs, and how many are under the sliver angle. */
static double faces_min(const cmesh *c, const int64_t *fs, int n, int *bad) {
  double m = 180;
  *bad = 0;
  for (int i = 0; i < n; i++) {
    const int32_t *t = c->t.tri + 3 * fs[i];
    double a = tri_min_deg(c->x, t[0], t[1], t[2]);
    if (a < m) m = a;
    *bad += a < c->thr;
  }
  return m;
}

static int is_feature(const cmesh *c, int32_t a, int32_t b) {
  return hm_get(&c->fe, ukey(a, b)) >= 0;
}

typedef struct {
  int kind; /* 0 none, 1 flip (a, b), 2 collapse a -> b */
  int32_t a, b;
  double oldmin, newmin, dev;
  int oldbad, newbad; /* changed triangles under the sliver angle, before and after */
} move;

/* Is the move an improvement: the smallest angle of what it changes
 * rises, or stays and fewer of those triangles are slivers? Either way
 * the surface's smallest angle cannot fall, and the first, or the count
 * of slivers, strictly improves, so the passes end. */
static int improves(const move *mv) {
  if (mv->newmin > mv->oldmin + 1e-9) return 1;
  return mv->newmin >= mv->oldmin && mv->newbad < mv->oldbad;
}

/* Is move a better than move b (b may be none)? */
static int better(const move *a, const move *b) {
  if (!b->kind) return 1;
  if (a->newmin != b->newmin) return a->newmin > b->newmin;
  return a->newbad - a->oldbad < b->newbad - b->oldbad;
}

static double tol_for(const cmesh *c, double len) {
  double t = c->tol_rel * len;
  return t < c->tol_abs ? t : c->tol_abs;
}

static void eval_flip(const cmesh *c, int32_t a, int32_t b, move *mv) {
  mv->kind = 0;
  if (is_feature(c, a, b)) return;
  int32_t opp[2];
  double dev, lmax;
  if (!vm_tm_flip_check(&c->t, c->x, a, b, 0.5, opp, &dev, &lmax)) return;
  int32_t cc = opp[0], d = opp[1];
  if (!vm_tm_same_fields(c->m, he_find(c, a, b) / 3, he_find(c, b, a) / 3)) return;
  const double *x = c->x;
  /* what earlier moves there changed adds up */
  double e0 = c->err[a] > c->err[b] ? c->err[a] : c->err[b];
  double e1 = c->err[cc] > c->err[d] ? c->err[cc] : c->err[d];
  dev += e0 > e1 ? e0 : e1;
  if (dev > tol_for(c, lmax)) return;
  double o0 = tri_min_deg(x, a, b, cc), o1 = tri_min_deg(x, b, a, d);
  double w0 = tri_min_deg(x, a, d, cc), w1 = tri_min_deg(x, d, b, cc);
  mv->kind = 1;
  mv->a = a;
  mv->b = b;
  mv->oldmin = o0 < o1 ? o0 : o1;
  mv->newmin = w0 < w1 ? w0 : w1;
  mv->oldbad = (o0 < c->thr) + (o1 < c->thr);
  mv->newbad = (w0 < c->thr) + (w1 < c->thr);
  mv->dev = dev;
}

static void eval_collapse_border(cmesh *c, int32_t u, int32_t w, move *mv);

/* u collapsed onto w, judged on u's faces but f0 and f1 (those that go):
 * none turned by 60 degrees or more, none moved beyond the tolerance
 * (the deviation from dev0 up); if so, mv becomes the move of `kind`
 * with the smallest angles of those faces before and after and their
 * counts below the threshold. */
static void judge_collapse(cmesh *c, int32_t u, int32_t w, const int64_t *Fu, int nu, int64_t f0,
                           int64_t f1, double dev0, int kind, move *mv) {
  const double *x = c->x;
  double uw[3];
  vm_sub3(x + 3 * (int64_t)u, x + 3 * (int64_t)w, uw);
  double newmin = 180, dev = dev0;
  int newbad = 0;
  for (int i = 0; i < nu; i++) {
    int64_t g = Fu[i];
    if (g == f0 || g == f1) continue;
    int32_t nt[3];
    memcpy(nt, c->t.tri + 3 * g, sizeof nt);
    double no[3], nn[3];
    tri_normal(x, nt[0], nt[1], nt[2], no);
    nt[vm_tm_index(nt, u)] = w;
    tri_normal(x, nt[0], nt[1], nt[2], nn);
    if (cos_between(no, nn) < 0.5) return;
    double d = fabs(vm_dot3(uw, nn)) / vm_norm3(nn), lmax = 0;
    for (int j = 0; j < 3; j++) {
      double l = vm_dist3(x + 3 * (int64_t)nt[j], x + 3 * (int64_t)nt[(j + 1) % 3]);
      if (l > lmax) lmax = l;
    }
    d += c->err[u] > c->err[w] ? c->err[u] : c->err[w];
    if (d > tol_for(c, lmax)) return;
    if (d > dev) dev = d;
    double a = tri_min_deg(x, nt[0], nt[1], nt[2]);
    if (a < newmin) newmin = a;
    newbad += a < c->thr;
  }
  /* the faces that change: u's (w's others stay as they are, so the
   * smallest angle of the whole surface cannot fall if these improve) */
  int oldbad = 0;
  double oldmin = faces_min(c, Fu, nu, &oldbad);
  mv->kind = kind;
  mv->a = u;
  mv->b = w;
  mv->oldmin = oldmin;
  mv->newmin = newmin;
  mv->oldbad = oldbad;
  mv->newbad = newbad;
  mv->dev = dev;
}

/* collapse u onto w (u goes away, w stays where it is) */
static void eval_collapse(cmesh *c, int32_t u, int32_t w, move *mv) {
  mv->kind = 0;
  if (c->border_collapse && c->vborder[u] && c->vclass[u] == VM_FEATURE_LINE) {
    eval_collapse_border(c, u, w, mv);
    return;
  }
  /* corners, feature-line and border vertices stay: the features keep
   * every vertex they have (removing one from a sharp trailing edge
   * changes its shape, and the layers built on it, more than the angle
   * gained) */
  if (c->vclass[u] != VM_FEATURE_SMOOTH || c->vborder[u]) return;
  int64_t h = he_find(c, u, w), t = he_find(c, w, u);
  if (h < 0 || t < 0) return;
  int64_t f0 = h / 3, f1 = t / 3;
  int32_t c0 = c->t.tri[3 * f0 + (h % 3 + 2) % 3], d0 = c->t.tri[3 * f1 + (t % 3 + 2) % 3];
  int64_t *Fu = c->fu, *Fw = c->fw;
  int nu = ring(c, u, Fu), nw = ring(c, w, Fw);
  if (nu < 0 || nw < 0) return;
  int32_t *Nu = c->nu, *Nw = c->nw;
  int ku = vm_tm_neighbours(&c->t, u, Fu, nu, Nu), kw = vm_tm_neighbours(&c->t, w, Fw, nw, Nw);
  /* link condition: the common neighbours are exactly c0 and d0 */
  int common = 0;
  for (int i = 0; i < ku; i++)
    if (vm_tm_contains(Nw, kw, Nu[i])) {
      if (Nu[i] != c0 && Nu[i] != d0) return;
      common++;
    }
  if (common != 2 || c0 == d0) return;
  if (ku < 3 || kw < 3) return;
  judge_collapse(c, u, w, Fu, nu, f0, f1, 0, 2, mv);
}

/* The other end p of u's border edge that is not (u, w), or -1. */
static int32_t border_other(const cmesh *c, const int64_t *Fu, int nu, int32_t u, int32_t w) {
  for (int i = 0; i < nu; i++) {
    const int32_t *x = c->t.tri + 3 * Fu[i];
    for (int j = 0; j < 3; j++) {
      int32_t a = x[j], b = x[(j + 1) % 3];
      if (a == u && b != w && he_find(c, b, a) < 0) return b;
      if (b == u && a != w && he_find(c, b, a) < 0) return a;
    }
  }
  return -1;
}

/* collapse the border line vertex u onto its border neighbour w: the
 * border p-u-w becomes p-w (it moves by u's distance from that segment,
 * within the tolerances; in a plane if it was); u's one face on (u, w)
 * goes */
static void eval_collapse_border(cmesh *c, int32_t u, int32_t w, move *mv) {
  int64_t h = he_find(c, u, w), t = he_find(c, w, u);
  if ((h >= 0) == (t >= 0)) return; /* (u, w) must be a border edge */
  if (!c->vborder[w]) return;
  int64_t f0 = (h >= 0 ? h : t) / 3, hh = h >= 0 ? h : t;
  int32_t c0 = c->t.tri[3 * f0 + (hh % 3 + 2) % 3];
  int64_t *Fu = c->fu, *Fw = c->fw;
  int nu = ring(c, u, Fu), nw = ring(c, w, Fw);
  if (nu < 2 || nw < 0) return; /* u on one face only: its removal opens a hole */
  int32_t *Nu = c->nu, *Nw = c->nw;
  int ku = vm_tm_neighbours(&c->t, u, Fu, nu, Nu), kw = vm_tm_neighbours(&c->t, w, Fw, nw, Nw);
  /* link condition for a border edge: the only common neighbour is c0 */
  for (int i = 0; i < ku; i++)
    if (Nu[i] != c0 && vm_tm_contains(Nw, kw, Nu[i])) return;
  if (!vm_tm_contains(Nw, kw, c0)) return;
  int32_t p = border_other(c, Fu, nu, u, w);
  if (p < 0 || p == w) return;
  const double *x = c->x;
  /* how far the border moves: u's distance from the segment p-w */
  double pw[3], pu[3];
  vm_sub3(x + 3 * (int64_t)w, x + 3 * (int64_t)p, pw);
  vm_sub3(x + 3 * (int64_t)u, x + 3 * (int64_t)p, pu);
  double l2 = vm_dot3(pw, pw), s = l2 > 0 ? vm_dot3(pu, pw) / l2 : 0;
  if (s <= 0 || s >= 1) return; /* u must lie between p and w along the border */
  double q[3] = {pu[0] - s * pw[0], pu[1] - s * pw[1], pu[2] - s * pw[2]};
  double bdev = vm_norm3(q) + (c->err[u] > c->err[w] ? c->err[u] : c->err[w]);
  if (bdev > tol_for(c, sqrt(l2))) return;
  judge_collapse(c, u, w, Fu, nu, f0, -1, bdev, 3, mv);
}

static void raise_err(cmesh *c, int32_t v, double e) {
  if (e > c->err[v]) c->err[v] = e;
}

static void apply_flip(cmesh *c, int32_t a, int32_t b, double dev) {
  int32_t cd[2];
  c->bad_keys += vm_tm_flip(&c->t, a, b, cd);
  raise_err(c, a, dev);
  raise_err(c, b, dev);
  raise_err(c, cd[0], dev);
  raise_err(c, cd[1], dev);
}

static void apply_collapse(cmesh *c, int32_t u, int32_t w, double dev) {
  int64_t h = he_find(c, u, w), t = he_find(c, w, u);
  int64_t f0 = h >= 0 ? h / 3 : -1, f1 = t >= 0 ? t / 3 : -1;
  int64_t *Fu = c->fu;
  int nu = ring(c, u, Fu);
  if (f0 < 0 || f1 < 0) { /* along the border: its edge p-u becomes p-w, a feature */
    int32_t p = border_other(c, Fu, nu, u, w);
    if (p >= 0 && hm_reserve(c->ctx, &c->fe, 1) == VM_OK) hm_put(&c->fe, ukey(p, w), 1);
  }
  c->bad_keys += vm_tm_collapse(&c->t, c->fdead, Fu, nu, u, w);
  for (int i = 0; i < nu; i++)
    if (Fu[i] != f0 && Fu[i] != f1)
      for (int j = 0; j < 3; j++) raise_err(c, c->t.tri[3 * Fu[i] + j], dev);
  c->vdead[u] = 1;
}

int vm_surface_cleanup(vm_mesh *m, vm_surface_features *f, const vm_cleanup_opts *opts,
                       vm_cleanup_report *rep) {
  if (!m || !f) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_cleanup_opts o = opts ? *opts : vm_cleanup_opts_default();
  vm_cleanup_report r;
  memset(&r, 0, sizeof r);
  if (rep) *rep = r;
  if (!tris_only(m))
    return vm_error(ctx, VM_ERR_ARG, "cleanup: the surface must be made of triangles only");
  if (f->nv != m->nv)
    return vm_error(ctx, VM_ERR_ARG, "cleanup: the features belong to another mesh");
  if (!(o.angle > 0 && o.angle < 60) || !(o.max_dev_rel >= 0) || o.rounds < 0)
    return vm_error(ctx, VM_ERR_ARG, "cleanup: angle %g, relative deviation %g, %d rounds", o.angle,
                    o.max_dev_rel, o.rounds);
  cmesh c;
  memset(&c, 0, sizeof c);
  c.ctx = ctx;
  c.m = m;
  c.x = m->xyz;
  c.nv = m->nv;
  c.nf = m->ne;
  c.vclass = f->vclass;
  double lo[3], hi[3], diag = vm_mesh_bounds(m, lo, hi);
  c.tol_abs = o.max_dev > 0 ? o.max_dev : 2.5e-4 * diag;
  c.tol_rel = o.max_dev_rel;
  c.thr = o.angle;
  c.border_collapse = o.border_collapse;
  const size_t nv1 = (size_t)(c.nv > 0 ? c.nv : 1), nf1 = (size_t)c.nf;
  int st = VM_OK;
  c.t.tri = vm_alloc_array(ctx, 3 * nf1, sizeof *c.t.tri);
  c.fdead = vm_calloc(ctx, nf1, 1);
  c.vdead = vm_calloc(ctx, nv1, 1);
  c.vborder = vm_calloc(ctx, nv1, 1);
  c.t.vface = vm_alloc_array(ctx, nv1, sizeof *c.t.vface);
  c.err = vm_calloc(ctx, nv1, sizeof *c.err);
  if (!c.err || !c.t.tri || !c.fdead || !c.vdead || !c.vborder || !c.t.vface ||
      hm_init(ctx, &c.t.he, 3 * nf1) || hm_init(ctx, &c.fe, (size_t)f->nedge + 1)) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t v = 0; v < c.nv; v++) c.t.vface[v] = -1;
  for (int64_t e = 0; e < c.nf; e++) {
    memcpy(c.t.tri + 3 * e, m->conn + m->eoff[e], 3 * sizeof *c.t.tri);
    for (int i = 0; i < 3; i++) c.t.vface[c.t.tri[3 * e + i]] = (int32_t)e;
    face_keys(&c, e, 1);
  }
  if (c.bad_keys) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "cleanup: %lld edges are used twice in the same direction (not a manifold, "
                  "consistently oriented surface)",
                  (long long)c.bad_keys);
    goto done;
  }
  for (int64_t e = 0; e < c.nf; e++)
    for (int i = 0; i < 3; i++) {
      int32_t a = c.t.tri[3 * e + i], b = c.t.tri[3 * e + (i + 1) % 3];
      if (he_find(&c, b, a) < 0) c.vborder[a] = c.vborder[b] = 1;
    }
  /* every vertex's faces must form one fan; a vertex with more faces than
   * a ring holds is left alone */
  if ((st = vm_tm_check_manifold(ctx, &c.t, c.nv, c.nf, m->xyz, RING_MAX, c.vborder, "cleanup")))
    goto done;
  for (int64_t k = 0; k < f->nedge; k++) hm_put(&c.fe, ukey(f->edge[2 * k], f->edge[2 * k + 1]), 1);

  r.nv_in = m->nv;
  r.nf_in = m->ne;
  r.min_angle_free_in = vm_surface_min_angle_free(m, f, &r.min_angle_in);
  for (int64_t e = 0; e < c.nf; e++)
    if (tri_min_deg(c.x, c.t.tri[3 * e], c.t.tri[3 * e + 1], c.t.tri[3 * e + 2]) < o.angle)
      r.below_in++;

  for (int round = 0; round < o.rounds; round++) {
    int64_t changed = 0;
    for (int64_t e = 0; e < c.nf; e++) {
      if (c.fdead[e]) continue;
      if (tri_min_deg(c.x, c.t.tri[3 * e], c.t.tri[3 * e + 1], c.t.tri[3 * e + 2]) >= o.angle)
        continue;
      if ((e & 1023) == 0 && vm_ctx_interrupted(ctx)) break;
      move best = {0, 0, 0, 0, 0, 0, 0, 0}, mv;
      for (int i = 0; i < 3; i++) {
        int32_t a = c.t.tri[3 * e + i], b = c.t.tri[3 * e + (i + 1) % 3];
        for (int k = 0; k < 3; k++) {
          if (k == 0) eval_flip(&c, a, b, &mv);
          if (k == 1) eval_collapse(&c, a, b, &mv);
          if (k == 2) eval_collapse(&c, b, a, &mv);
          if (mv.kind && improves(&mv) && better(&mv, &best)) best = mv;
        }
      }
      if (!best.kind) continue;
      if (best.kind == 1) {
        apply_flip(&c, best.a, best.b, best.dev);
        r.flips++;
      } else {
        if (best.kind == 3) r.border_collapses++;
        apply_collapse(&c, best.a, best.b, best.dev);
        r.collapses++;
      }
      if (best.dev > r.max_dev) r.max_dev = best.dev;
      changed++;
    }
    r.rounds = round + 1;
    if (!changed || vm_ctx_interrupted(ctx)) break;
  }
  if (c.bad_keys) {
    st = vm_error(ctx, VM_ERR_BACKEND, "cleanup: internal error (%lld duplicate edges)",
                  (long long)c.bad_keys);
    goto done;
  }

  /* the new mesh: surviving vertices in their order, surviving faces */
  if ((st = vm_tm_output(ctx, m, m->xyz, c.nv, c.vdead, &c.t, c.nf, c.fdead, 1, &c.fe, f,
                         "cleanup")))
    goto done;
  r.nv = m->nv;
  r.nf = m->ne;
  r.min_angle_free = vm_surface_min_angle_free(m, f, &r.min_angle);
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *t = m->conn + 3 * e;
    if (tri_min_deg(m->xyz, t[0], t[1], t[2]) < o.angle) r.below++;
  }
  if (rep) *rep = r;
done:
  vm_free(ctx, c.t.tri);
  vm_free(ctx, c.fdead);
  vm_free(ctx, c.vdead);
  vm_free(ctx, c.vborder);
  vm_free(ctx, c.t.vface);
  vm_free(ctx, c.err);
  hm_free(ctx, &c.t.he);
  hm_free(ctx, &c.fe);
  return st;
}
