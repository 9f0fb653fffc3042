/* lib/geom/src/graded.c: graded isotropic remeshing (varmesh/graded.h) on
 * a half-edge view of the surface (directed edges in a hash map), the
 * rounds of Botsch and Kobbelt's remeshing with a size field: split edges
 * longer than 4/3 h, collapse edges shorter than 4/5 h, flip edges where
 * that raises the smallest angle (Delaunay on a plane), move vertices to
 * the size-weighted centroid of their triangles in their tangent plane and
 * project them onto the input surface. */
#include "varmesh/graded.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"
#include "varmesh/cleanup.h"
#include "varmesh/project.h"
#include "varmesh/surface_mesh.h"

vm_graded_opts vm_graded_opts_default(void) {
  vm_graded_opts o;
  o.sizing = VM_GRADED_INPUT;
  o.triangles = 0;
  o.growth = 0.25;
  o.max_size = 0.05;
  o.max_turn = 30;
  o.iterations = 12;
  o.smooth_keep = 30;
  return o;
}

#define RING_MAX 256

typedef struct {
  vm_ctx *ctx;
  int64_t nv, nf, capv, capf;
  double *x, *h;
  uint8_t *vclass, *vdead, *vborder, *fdead;
  int32_t *vline;
  int64_t *hint; /* per vertex: the projector's hint (vm_surface_ops.project_hinted) */
  vm_tm t;       /* faces, a face of each vertex, directed edges */
  hmap fe;       /* feature edge (undirected) -> its line */
  vm_surface_ops ops;
  vm_surface_projector *proj;
  double *href; /* the size field at the input's vertices */
  double keep;
  int merge; /* the first rounds: a collapse may make an edge longer than
                4/3 h if it is hardly longer than the one it replaces (strips of
                a stretched input narrower than the size merge before the
                splits cut their long edges) */
  int64_t fr[RING_MAX];
  int32_t nb[3 * RING_MAX];
  int64_t splits, collapses, flips, moves;
} gmesh;

static int64_t he_find(const gmesh *g, int32_t a, int32_t b) { return vm_tm_he(&g->t, a, b); }
static int32_t fline(const gmesh *g, int32_t a, int32_t b) {
  int64_t k = hm_get(&g->fe, ukey(a, b));
  return k < 0 ? 0 : (int32_t)k;
}
static void keys(gmesh *g, int64_t f, int add) { vm_tm_keys(&g->t, f, add); }

static int grow_arr(vm_ctx *ctx, void **p, size_t n, size_t sz) {
  void *q = vm_realloc(ctx, *p, n * sz);
  if (!q) return VM_ERR_NOMEM;
  *p = q;
  return VM_OK;
}

/* room for one more vertex and two more faces */
static int reserve(gmesh *g) {
  if (g->nv + 1 > g->capv) {
    size_t c = (size_t)g->capv * 2;
    if (grow_arr(g->ctx, (void **)&g->x, c, 3 * sizeof *g->x) ||
        grow_arr(g->ctx, (void **)&g->h, c, sizeof *g->h) ||
        grow_arr(g->ctx, (void **)&g->vclass, c, 1) || grow_arr(g->ctx, (void **)&g->vdead, c, 1) ||
        grow_arr(g->ctx, (void **)&g->vborder, c, 1) ||
        grow_arr(g->ctx, (void **)&g->vline, c, sizeof *g->vline) ||
        grow_arr(g->ctx, (void **)&g->hint, c, sizeof *g->hint) ||
        grow_arr(g->ctx, (void **)&g->t.vface, c, sizeof *g->t.vface))
      return VM_ERR_NOMEM;
    g->capv = (int64_t)c;
  }
  if (g->nf + 2 > g->capf) {
    size_t c = (size_t)g->capf * 2;
    if (grow_arr(g->ctx, (void **)&g->t.tri, c, 3 * sizeof *g->t.tri) ||
        grow_arr(g->ctx, (void **)&g->fdead, c, 1))
      return VM_ERR_NOMEM;
    g->capf = (int64_t)c;
  }
  if (hm_reserve(g->ctx, &g->t.he, 8) || hm_reserve(g->ctx, &g->fe, 2)) return VM_ERR_NOMEM;
  return VM_OK;
}

static int ring(const gmesh *g, int32_t v, int64_t *out) {
  return vm_tm_ring(&g->t, v, out, RING_MAX);
}

static double len(const gmesh *g, int32_t a, int32_t b) {
  return vm_dist3(g->x + 3 * (int64_t)a, g->x + 3 * (int64_t)b);
}
static double hab(const gmesh *g, int32_t a, int32_t b) { return 0.5 * (g->h[a] + g->h[b]); }

/* Project p onto the input (its feature line `line` if > 0): the closest
 * point, unless it is farther than `reach` or (on the surface) its normal
 * disagrees with n (then p itself is taken: a thin part's other side is
 * never the answer). Returns 1 if projected. */
static int project(const gmesh *g, int64_t *hint, int line, const double p[3], const double n[3],
                   double reach, double out[3]) {
  double q[3], nr[9];
  int k = line == 0 ? g->ops.project_hinted(g->ops.user, 0, p, hint, q, nr)
                    : g->ops.project(g->ops.user, line, p, q, nr);
  if (k < 0 || !(vm_dist3(p, q) <= reach) || (line == 0 && n && cos_between(nr, n) < 0.5)) {
    memcpy(out, p, 3 * sizeof *out);
    return 0;
  }
  memcpy(out, q, 3 * sizeof *out);
  return 1;
}

/* Does the triangle (a, b, c) face the way the input does where its
 * centroid projects (within 60 degrees)? A fold could otherwise build up
 * from moves that each turn a triangle only a little. */
static int faces_input(const gmesh *g, int32_t a, int32_t b, int32_t c) {
  double n[3], ctr[3], q[3], nr[9];
  tri_normal(g->x, a, b, c, n);
  for (int r = 0; r < 3; r++)
    ctr[r] = (g->x[3 * (int64_t)a + r] + g->x[3 * (int64_t)b + r] + g->x[3 * (int64_t)c + r]) / 3;
  int64_t hint = g->hint[a]; /* a's, not updated: near the centroid */
  if (g->ops.project_hinted(g->ops.user, 0, ctr, &hint, q, nr) < 0) return 0;
  return cos_between(n, nr) >= 0.5;
}

/* The size field where p lies: interpolated on the input at p's closest
 * point (fallback if that fails). */
static double size_at(const gmesh *g, int32_t v, const double p[3], double fallback) {
  double h;
  int64_t hint = g->hint[v];
  if (!g->href || vm_surface_projector_interpolate_hinted(g->proj, g->href, p, &hint, &h) ||
      !(h > 0))
    return fallback;
  return h;
}

/* ---- split ---- */

static int split(gmesh *g, int32_t a, int32_t b) {
  int64_t h = he_find(g, a, b), t = he_find(g, b, a);
  if (h < 0) {
    int32_t s = a;
    a = b;
    b = s;
    h = t;
    t = -1;
  }
  if (h < 0) return 0;
  int st = reserve(g);
  if (st) return st;
  int64_t f0 = h / 3, f1 = t >= 0 ? t / 3 : -1;
  int32_t c = g->t.tri[3 * f0 + (h % 3 + 2) % 3];
  int32_t d = f1 >= 0 ? g->t.tri[3 * f1 + (t % 3 + 2) % 3] : -1;
  int32_t line = fline(g, a, b);
  const double *pa = g->x + 3 * (int64_t)a, *pb = g->x + 3 * (int64_t)b;
  double mid[3], p[3], n[3], n1[3];
  for (int r = 0; r < 3; r++) mid[r] = 0.5 * (pa[r] + pb[r]);
  tri_normal(g->x, a, b, c, n);
  vm_normalize3(n);
  if (d >= 0) {
    tri_normal(g->x, b, a, d, n1);
    vm_normalize3(n1);
    for (int r = 0; r < 3; r++) n[r] += n1[r];
  }
  double l = len(g, a, b);
  int32_t m = (int32_t)g->nv++;
  g->hint[m] = g->hint[a];
  project(g, g->hint + m, line, mid, line ? NULL : n, 0.25 * l, p);
  memcpy(g->x + 3 * (int64_t)m, p, 3 * sizeof *p);
  /* the projected point must not turn the new triangles over */
  double q[3];
  tri_normal(g->x, a, m, c, q);
  int ok = cos_between(q, n) > 0.5;
  tri_normal(g->x, m, b, c, q);
  ok = ok && cos_between(q, n) > 0.5;
  if (d >= 0) {
    tri_normal(g->x, b, m, d, q);
    ok = ok && cos_between(q, n) > 0.5;
    tri_normal(g->x, m, a, d, q);
    ok = ok && cos_between(q, n) > 0.5;
  }
  ok = ok && faces_input(g, a, m, c) && faces_input(g, m, b, c) &&
       (d < 0 || (faces_input(g, b, m, d) && faces_input(g, m, a, d)));
  if (!ok) memcpy(g->x + 3 * (int64_t)m, mid, sizeof mid);
  g->h[m] = size_at(g, m, g->x + 3 * (int64_t)m, hab(g, a, b));
  g->vclass[m] = line ? VM_FEATURE_LINE : VM_FEATURE_SMOOTH;
  g->vline[m] = line;
  g->vdead[m] = 0;
  g->vborder[m] = f1 < 0;
  keys(g, f0, 0);
  int32_t *t0 = g->t.tri + 3 * f0;
  t0[vm_tm_index(t0, b)] = m;
  int64_t f2 = g->nf++;
  g->fdead[f2] = 0;
  int32_t *t2 = g->t.tri + 3 * f2;
  t2[0] = m, t2[1] = b, t2[2] = c;
  keys(g, f0, 1);
  keys(g, f2, 1);
  g->t.vface[a] = (int32_t)f0;
  g->t.vface[c] = (int32_t)f0;
  g->t.vface[m] = (int32_t)f0;
  g->t.vface[b] = (int32_t)f2;
  if (f1 >= 0) {
    keys(g, f1, 0);
    int32_t *t1 = g->t.tri + 3 * f1;
    t1[vm_tm_index(t1, a)] = m; /* (b, m, d) */
    int64_t f3 = g->nf++;
    g->fdead[f3] = 0;
    int32_t *t3 = g->t.tri + 3 * f3;
    t3[0] = m, t3[1] = a, t3[2] = d;
    keys(g, f1, 1);
    keys(g, f3, 1);
    g->t.vface[d] = (int32_t)f1;
  }
  if (line) {
    hm_del(&g->fe, ukey(a, b));
    hm_put(&g->fe, ukey(a, m), line);
    hm_put(&g->fe, ukey(m, b), line);
  }
  g->splits++;
  return 1;
}

/* One pass: every face that exists at its start splits its longest edge if
 * that is longer than 4/3 h (faces made by the pass wait for the next
 * round), so a long edge is halved once per round and the collapses and
 * flips between rounds merge the needles a stretched input would
 * otherwise multiply. */
static int split_long(gmesh *g) {
  int64_t done = 0, nf0 = g->nf;
  for (int64_t f = 0; f < nf0; f++) {
    if ((f & 4095) == 0 && vm_ctx_interrupted(g->ctx)) return VM_ERR_INTERRUPTED;
    if (g->fdead[f]) continue;
    const int32_t *t = g->t.tri + 3 * f;
    int best = -1;
    double worst = 4.0 / 3.0;
    for (int i = 0; i < 3; i++) {
      double r = len(g, t[i], t[(i + 1) % 3]) / hab(g, t[i], t[(i + 1) % 3]);
      if (r > worst) worst = r, best = i;
    }
    if (best < 0) continue;
    int st = split(g, t[best], t[(best + 1) % 3]);
    if (st < 0) return st;
    done += st;
  }
  return done > 0;
}

/* ---- collapse u onto w ---- */

static int try_collapse(gmesh *g, int32_t u, int32_t w) {
  if (g->vclass[u] == VM_FEATURE_CORNER) return 0;
  int32_t line = fline(g, u, w);
  if (g->vclass[u] == VM_FEATURE_LINE) {
    /* along its own line only */
    if (!line || line != g->vline[u]) return 0;
  } else if (g->vborder[u])
    return 0;
  int64_t h = he_find(g, u, w), t = he_find(g, w, u);
  if (h < 0 && t < 0) return 0;
  int32_t c0 = h >= 0 ? g->t.tri[3 * (h / 3) + (h % 3 + 2) % 3] : -1;
  int32_t d0 = t >= 0 ? g->t.tri[3 * (t / 3) + (t % 3 + 2) % 3] : -1;
  int64_t Fu[RING_MAX];
  int nu = ring(g, u, Fu), nw = ring(g, w, g->fr);
  if (nu <= 0 || nw <= 0) return 0;
  int32_t Nu[3 * RING_MAX], *Nw = g->nb;
  int ku = vm_tm_neighbours(&g->t, u, Fu, nu, Nu), kw = vm_tm_neighbours(&g->t, w, g->fr, nw, Nw);
  if (ku < 3 || kw < 3) return 0;
  int common = 0;
  for (int i = 0; i < ku; i++)
    if (vm_tm_contains(Nw, kw, Nu[i])) {
      if (Nu[i] != c0 && Nu[i] != d0) return 0;
      common++;
    }
  if (common != (c0 >= 0) + (d0 >= 0) || c0 == d0) return 0;
  /* a line vertex's other line edge becomes w's: w must not be on a
   * feature already joined to that neighbour (link condition covers it) */
  const double *x = g->x;
  double oldmin = 180, newmin = 180;
  for (int i = 0; i < nu; i++) {
    const int32_t *tt = g->t.tri + 3 * Fu[i];
    double a = tri_min_deg(x, tt[0], tt[1], tt[2]);
    if (a < oldmin) oldmin = a;
    if (tt[0] == w || tt[1] == w || tt[2] == w) continue;
    int32_t nt[3] = {tt[0], tt[1], tt[2]};
    double no[3], nn[3];
    tri_normal(x, nt[0], nt[1], nt[2], no);
    nt[vm_tm_index(nt, u)] = w;
    tri_normal(x, nt[0], nt[1], nt[2], nn);
    if (cos_between(no, nn) < 0.7 || !faces_input(g, nt[0], nt[1], nt[2])) return 0;
    for (int j = 0; j < 3; j++)
      if (nt[j] != w && len(g, w, nt[j]) > 4.0 / 3.0 * hab(g, w, nt[j]) &&
          !(g->merge && len(g, w, nt[j]) <= 1.05 * len(g, u, nt[j])))
        return 0;
    a = tri_min_deg(x, nt[0], nt[1], nt[2]);
    if (a < newmin) newmin = a;
  }
  double floor_deg = oldmin < 15 ? oldmin : 15;
  if (newmin < floor_deg - 1e-9) return 0;
  /* apply */
  for (int i = 0; i < nu; i++) keys(g, Fu[i], 0);
  if (line) {
    /* u's other edge on its line moves to w */
    for (int i = 0; i < ku; i++) {
      int32_t z = Nu[i];
      if (z == w) continue;
      int32_t lz = fline(g, u, z);
      if (lz) {
        hm_del(&g->fe, ukey(u, z));
        hm_put(&g->fe, ukey(w, z), lz);
      }
    }
    hm_del(&g->fe, ukey(u, w));
  }
  for (int i = 0; i < nu; i++) {
    int32_t *tt = g->t.tri + 3 * Fu[i];
    if (tt[0] == w || tt[1] == w || tt[2] == w) {
      g->fdead[Fu[i]] = 1;
      continue;
    }
    tt[vm_tm_index(tt, u)] = w;
  }
  for (int i = 0; i < nu; i++) {
    if (g->fdead[Fu[i]]) continue;
    keys(g, Fu[i], 1);
    const int32_t *tt = g->t.tri + 3 * Fu[i];
    for (int j = 0; j < 3; j++) g->t.vface[tt[j]] = (int32_t)Fu[i];
  }
  g->vdead[u] = 1;
  g->t.vface[u] = -1;
  g->collapses++;
  return 1;
}

static int collapse_short(gmesh *g) {
  int64_t done = 0;
  for (int64_t f = 0; f < g->nf; f++) {
    if ((f & 4095) == 0 && vm_ctx_interrupted(g->ctx)) return VM_ERR_INTERRUPTED;
    if (g->fdead[f]) continue;
    const int32_t *t = g->t.tri + 3 * f;
    int best = -1;
    double shortest = 4.0 / 5.0;
    for (int i = 0; i < 3; i++) {
      double r = len(g, t[i], t[(i + 1) % 3]) / hab(g, t[i], t[(i + 1) % 3]);
      if (r < shortest) shortest = r, best = i;
    }
    if (best < 0) continue;
    int32_t a = t[best], b = t[(best + 1) % 3];
    /* the vertex of lower rank goes: smooth before line, never a corner */
    int ok = g->vclass[a] <= g->vclass[b] ? try_collapse(g, a, b) : try_collapse(g, b, a);
    if (!ok && !g->fdead[f])
      ok = g->vclass[a] <= g->vclass[b] ? try_collapse(g, b, a) : try_collapse(g, a, b);
    done += ok;
  }
  return done > 0;
}

/* ---- flips ---- */

static int try_flip(gmesh *g, int32_t a, int32_t b) {
  if (fline(g, a, b)) return 0;
  int32_t opp[2];
  double dev, lmax;
  /* new normals within 30 degrees, the surface moved by at most 5 % of
   * the longer diagonal */
  if (!vm_tm_flip_check(&g->t, g->x, a, b, 0.8660254037844386, opp, &dev, &lmax) ||
      dev > 0.05 * lmax)
    return 0;
  int32_t c = opp[0], d = opp[1];
  const double *x = g->x;
  double o0 = tri_min_deg(x, a, b, c), o1 = tri_min_deg(x, b, a, d);
  double w0 = tri_min_deg(x, a, d, c), w1 = tri_min_deg(x, d, b, c);
  if (!((w0 < w1 ? w0 : w1) > (o0 < o1 ? o0 : o1) + 1e-6)) return 0;
  if (!faces_input(g, a, d, c) || !faces_input(g, d, b, c)) return 0;
  vm_tm_flip(&g->t, a, b, opp);
  g->flips++;
  return 1;
}

static int flip_all(gmesh *g) {
  int64_t total = 0;
  for (int sweep = 0; sweep < 8; sweep++) {
    int64_t done = 0;
    for (int64_t f = 0; f < g->nf; f++) {
      if ((f & 4095) == 0 && vm_ctx_interrupted(g->ctx)) return VM_ERR_INTERRUPTED;
      if (g->fdead[f]) continue;
      for (int i = 0; i < 3; i++) {
        const int32_t *t = g->t.tri + 3 * f;
        if (try_flip(g, t[i], t[(i + 1) % 3])) {
          done++;
          break;
        }
      }
    }
    total += done;
    if (!done) break;
  }
  return total > 0;
}

/* ---- tangential smoothing ---- */

static double ring_min(const gmesh *g, const int64_t *fs, int n) {
  double m = 180;
  for (int i = 0; i < n; i++) {
    const int32_t *t = g->t.tri + 3 * fs[i];
    double a = tri_min_deg(g->x, t[0], t[1], t[2]);
    if (a < m) m = a;
  }
  return m;
}

static int smooth_vertex(gmesh *g, int32_t v) {
  if (g->vdead[v] || g->vclass[v] == VM_FEATURE_CORNER) return 0;
  int64_t *F = g->fr;
  int n = ring(g, v, F);
  if (n < 3) return 0;
  double *p = g->x + 3 * (int64_t)v, old[3], target[3] = {0, 0, 0}, nv[3] = {0, 0, 0};
  memcpy(old, p, sizeof old);
  double wsum = 0, elen = 0;
  double nold[3 * RING_MAX];
  for (int i = 0; i < n; i++) {
    const int32_t *t = g->t.tri + 3 * F[i];
    double nt[3];
    tri_normal(g->x, t[0], t[1], t[2], nt);
    memcpy(nold + 3 * i, nt, sizeof nt);
    double area = 0.5 * vm_norm3(nt);
    for (int r = 0; r < 3; r++) nv[r] += nt[r];
    double hm = (g->h[t[0]] + g->h[t[1]] + g->h[t[2]]) / 3, w = area / (hm * hm * hm * hm);
    for (int r = 0; r < 3; r++)
      target[r] += w *
                   (g->x[3 * (int64_t)t[0] + r] + g->x[3 * (int64_t)t[1] + r] +
                    g->x[3 * (int64_t)t[2] + r]) /
                   3;
    wsum += w;
    elen += len(g, t[0], t[1]) + len(g, t[1], t[2]) + len(g, t[2], t[0]);
  }
  elen /= 3 * n;
  if (!(wsum > 0) || !(vm_norm3(nv) > 0)) return 0;
  vm_normalize3(nv);
  for (int r = 0; r < 3; r++) target[r] /= wsum;
  int line = 0;
  if (g->vclass[v] == VM_FEATURE_LINE) {
    /* along the line: between its two neighbours on it, by their sizes */
    line = g->vline[v];
    int32_t nb[3 * RING_MAX];
    int k = vm_tm_neighbours(&g->t, v, F, n, nb), cnt = 0;
    int32_t on[2] = {-1, -1};
    for (int i = 0; i < k; i++)
      if (fline(g, v, nb[i]) == line) {
        if (cnt < 2) on[cnt] = nb[i];
        cnt++;
      }
    if (cnt != 2) return 0;
    double ha = g->h[on[0]], hb = g->h[on[1]], s = ha / (ha + hb);
    for (int r = 0; r < 3; r++)
      target[r] = g->x[3 * (int64_t)on[0] + r] +
                  s * (g->x[3 * (int64_t)on[1] + r] - g->x[3 * (int64_t)on[0] + r]);
  } else {
    if (g->vborder[v]) return 0;
    double dlt[3];
    vm_sub3(target, old, dlt);
    double dn = vm_dot3(dlt, nv);
    for (int r = 0; r < 3; r++) target[r] = old[r] + dlt[r] - dn * nv[r];
  }
  double q[3];
  if (!project(g, g->hint + v, line, target, line ? NULL : nv, 0.5 * elen, q)) return 0;
  double before = ring_min(g, F, n);
  memcpy(p, q, sizeof q);
  int ok = 1;
  for (int i = 0; i < n && ok; i++) {
    const int32_t *t = g->t.tri + 3 * F[i];
    double nt[3];
    tri_normal(g->x, t[0], t[1], t[2], nt);
    ok = cos_between(nt, nold + 3 * i) > 0.7 && faces_input(g, t[0], t[1], t[2]);
  }
  double after = ok ? ring_min(g, F, n) : 0;
  double need = before < g->keep ? before : g->keep;
  if (!ok || after < need - 1e-9) {
    memcpy(p, old, sizeof old);
    return 0;
  }
  g->h[v] = size_at(g, v, q, g->h[v]);
  g->moves++;
  return 1;
}

static int smooth_all(gmesh *g) {
  for (int64_t v = 0; v < g->nv; v++) {
    if ((v & 4095) == 0 && vm_ctx_interrupted(g->ctx)) return VM_ERR_INTERRUPTED;
    smooth_vertex(g, (int32_t)v);
  }
  return VM_OK;
}

/* ---- the size field ---- */

/* Bounded growth, h(w) <= h(v) + growth |vw| over the edges of E, by
 * relaxation from a FIFO work list (each change lowers a value, so it
 * ends; first-in first-out keeps it deterministic). */
static int limit_growth(gmesh *g, const vm_surf_edges *E, double growth) {
  const int64_t nv = g->nv;
  int32_t *q = vm_alloc_array(g->ctx, (size_t)nv, sizeof *q);
  uint8_t *inq = vm_calloc(g->ctx, (size_t)nv, 1);
  if (!q || !inq) {
    vm_free(g->ctx, q);
    vm_free(g->ctx, inq);
    return VM_ERR_NOMEM;
  }
  for (int64_t v = 0; v < nv; v++) q[v] = (int32_t)v, inq[v] = 1;
  int64_t head = 0, count = nv;
  while (count > 0) {
    int32_t v = q[head];
    head = head + 1 == nv ? 0 : head + 1;
    count--;
    inq[v] = 0;
    for (int64_t k = E->rowptr[v]; k < E->rowptr[v + 1]; k++) {
      int32_t w = E->adj[k];
      double lim = g->h[v] + growth * len(g, v, w);
      if (lim < g->h[w] * (1 - 1e-12)) {
        g->h[w] = lim;
        if (!inq[w]) {
          inq[w] = 1;
          q[(head + count) % nv] = w;
          count++;
        }
      }
    }
  }
  vm_free(g->ctx, q);
  vm_free(g->ctx, inq);
  return VM_OK;
}

/* Triangles of size h (equilateral, 1 / h^2 the mean of the corners')
 * that cover the input's triangles. */
static double estimate_count(const gmesh *g) {
  double n = 0;
  for (int64_t f = 0; f < g->nf; f++) {
    const int32_t *t = g->t.tri + 3 * f;
    double nt[3], w = 0;
    for (int i = 0; i < 3; i++) w += 1 / (3 * g->h[t[i]] * g->h[t[i]]);
    tri_normal(g->x, t[0], t[1], t[2], nt);
    n += 0.5 * vm_norm3(nt) * w / 0.4330127018922193;
  }
  return n;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static int size_field(gmesh *g, const vm_graded_opts *o, const vm_surf_edges *E, double diag) {
  vm_ctx *ctx = g->ctx;
  const int64_t nv = g->nv;
  double *raw = vm_calloc(ctx, (size_t)nv, sizeof *raw);
  double *kappa = vm_calloc(ctx, (size_t)nv, sizeof *kappa);
  int32_t *deg = vm_calloc(ctx, (size_t)nv, sizeof *deg);
  int32_t *kdeg = vm_calloc(ctx, (size_t)nv, sizeof *kdeg);
  double *kmax = vm_calloc(ctx, (size_t)nv, sizeof *kmax);
  int st = VM_OK;
  if (!raw || !kappa || !deg || !kdeg || !kmax) {
    st = VM_ERR_NOMEM;
    goto out;
  }
  /* the input's local size: the mean length of a vertex's edges; its
   * curvature: the mean over its edges that are not features of the
   * turning of the normal across the edge over the distance of the two
   * triangles' centroids */
  for (int64_t f = 0; f < g->nf; f++)
    for (int i = 0; i < 3; i++) {
      int32_t a = g->t.tri[3 * f + i], b = g->t.tri[3 * f + (i + 1) % 3];
      double l = len(g, a, b);
      raw[a] += l;
      raw[b] += l;
      deg[a]++;
      deg[b]++;
      int64_t t = he_find(g, b, a);
      if (t < 0 || a > b || fline(g, a, b)) continue;
      const int32_t *t0 = g->t.tri + 3 * f, *t1 = g->t.tri + 3 * (t / 3);
      double n0[3], n1[3];
      tri_normal(g->x, t0[0], t0[1], t0[2], n0);
      tri_normal(g->x, t1[0], t1[1], t1[2], n1);
      double cs = cos_between(n0, n1);
      double th = acos(cs < -1 ? -1 : cs > 1 ? 1 : cs);
      /* across the edge: a third of the two triangles' heights over it
       * (the centroids' distance would count a stretched triangle's length) */
      double d = (vm_norm3(n0) + vm_norm3(n1)) / (3 * l);
      if (!(d > 0)) continue;
      kappa[a] += th / d;
      kappa[b] += th / d;
      if (th / d > kmax[a]) kmax[a] = th / d;
      if (th / d > kmax[b]) kmax[b] = th / d;
      kdeg[a]++;
      kdeg[b]++;
    }
  const double hmax = o->max_size * diag, hmin = 1e-3 * hmax;
  /* raw: the input's mean edge length; curv: 1 / sqrt(k) over its median
   * (the chord error of an edge h on a curvature k is h^2 k / 8: one
   * error everywhere asks for h ~ 1 / sqrt(k)), infinite where flat */
  int64_t ncurv = 0;
  for (int64_t v = 0; v < nv; v++) {
    raw[v] = deg[v] ? raw[v] / deg[v] : 0;
    /* the input's size, but no more than the normal may turn by max_turn
     * along an edge */
    if (kmax[v] > 0 && o->max_turn * (M_PI / 180) / kmax[v] < raw[v])
      raw[v] = o->max_turn * (M_PI / 180) / kmax[v];
    double k = kdeg[v] ? kappa[v] / kdeg[v] : 0;
    kappa[v] = k > 0 ? 1 / sqrt(k) : INFINITY;
    if (k > 0) deg[ncurv++] = (int32_t)v;
  }
  if (ncurv > 0) {
    double *tmp = vm_alloc_array(ctx, (size_t)ncurv, sizeof *tmp);
    if (!tmp) {
      st = VM_ERR_NOMEM;
      goto out;
    }
    for (int64_t i = 0; i < ncurv; i++) tmp[i] = kappa[deg[i]];
    qsort(tmp, (size_t)ncurv, sizeof *tmp, cmp_double);
    double med = tmp[ncurv / 2];
    vm_free(ctx, tmp);
    for (int64_t v = 0; v < nv; v++) kappa[v] /= med;
  }
  /* the sizes at scale s: INPUT min(t raw, s curv), CURVATURE s curv within
   * [hmin, hmax]; then the growth bound */
  const int curvature = o->sizing == VM_GRADED_CURVATURE;
  double t = 1, s_inf = INFINITY;
  double target = o->triangles > 0 ? (double)o->triangles : (double)g->nf;
#define SIZES(S)                                                                                   \
  do {                                                                                             \
    for (int64_t v = 0; v < nv; v++) {                                                             \
      double h_ = (S)*kappa[v];                                                                    \
      if (curvature) {                                                                             \
        if (!(h_ <= hmax)) h_ = hmax;                                                              \
        if (h_ < hmin) h_ = hmin;                                                                  \
      } else if (!(h_ <= t * raw[v]))                                                              \
        h_ = t * raw[v];                                                                           \
      g->h[v] = h_;                                                                                \
    }                                                                                              \
    if ((st = limit_growth(g, E, o->growth))) goto out;                                            \
  } while (0)
  double n = 0;
  if (!curvature) {
    /* the input's own sizes, bounded by the growth; scaled to a count if
     * one is asked for */
    SIZES(s_inf);
    n = estimate_count(g);
    if (o->triangles > 0 && n > 0) {
      for (int step = 0; step < 4; step++) {
        t *= sqrt(n / target);
        SIZES(s_inf);
        n = estimate_count(g);
      }
    }
    goto out;
  }
  /* bisection in log s: the count falls as s grows */
  double lo = log(1e-7 * diag), hi = log(10 * diag);
  for (int step = 0; step < 48; step++) {
    double mid = 0.5 * (lo + hi);
    SIZES(exp(mid));
    n = estimate_count(g);
    if (n > target)
      lo = mid;
    else
      hi = mid;
  }
  SIZES(exp(hi));
  n = estimate_count(g);
#undef SIZES
out:
  if (!st)
    vm_log(ctx, VM_LOG_DEBUG, "graded remeshing: sizes for about %.0f triangles (target %.0f)", n,
           target);
  vm_free(ctx, raw);
  vm_free(ctx, kappa);
  vm_free(ctx, deg);
  vm_free(ctx, kdeg);
  vm_free(ctx, kmax);
  return st;
}

/* ---- driver ---- */

static void gfree(gmesh *g) {
  vm_ctx *ctx = g->ctx;
  vm_free(ctx, g->x);
  vm_free(ctx, g->h);
  vm_free(ctx, g->href);
  vm_free(ctx, g->vclass);
  vm_free(ctx, g->vdead);
  vm_free(ctx, g->vborder);
  vm_free(ctx, g->fdead);
  vm_free(ctx, g->vline);
  vm_free(ctx, g->hint);
  vm_free(ctx, g->t.vface);
  vm_free(ctx, g->t.tri);
  hm_free(ctx, &g->t.he);
  hm_free(ctx, &g->fe);
}

int vm_surface_remesh_graded(vm_mesh *m, vm_surface_features *f, const vm_graded_opts *opts,
                             vm_graded_report *rep) {
  if (!m || !f) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_graded_opts o = opts ? *opts : vm_graded_opts_default();
  vm_graded_report r;
  memset(&r, 0, sizeof r);
  if (rep) *rep = r;
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] != VM_TRI)
      return vm_error(ctx, VM_ERR_ARG, "graded remeshing: the surface must be made of triangles");
  if (m->ne == 0 || f->nv != m->nv)
    return vm_error(ctx, VM_ERR_ARG, "graded remeshing: %s",
                    m->ne ? "the features belong to another mesh" : "no triangles");
  if (!(o.growth > 0) || !(o.max_size > 0 && o.max_size <= 10) || o.triangles < 0 ||
      !(o.max_turn > 0 && o.max_turn <= 180) ||
      (o.sizing != VM_GRADED_INPUT && o.sizing != VM_GRADED_CURVATURE) || o.iterations < 0 ||
      !(o.smooth_keep >= 0 && o.smooth_keep < 60))
    return vm_error(ctx, VM_ERR_ARG,
                    "graded remeshing: sizing %d, %lld triangles, growth %g, largest size %g, %d "
                    "iterations, smoothing angle %g",
                    o.sizing, (long long)o.triangles, o.growth, o.max_size, o.iterations,
                    o.smooth_keep);
  gmesh g;
  memset(&g, 0, sizeof g);
  g.ctx = ctx;
  g.keep = o.smooth_keep;
  g.nv = m->nv;
  g.nf = m->ne;
  g.capv = 2 * m->nv + 16;
  g.capf = 2 * m->ne + 16;
  int st = VM_OK;
  vm_surface_projector *proj = NULL;
  vm_surf_edges E;
  memset(&E, 0, sizeof E);
  g.x = vm_alloc_array(ctx, (size_t)g.capv, 3 * sizeof *g.x);
  g.h = vm_alloc_array(ctx, (size_t)g.capv, sizeof *g.h);
  g.vclass = vm_calloc(ctx, (size_t)g.capv, 1);
  g.vdead = vm_calloc(ctx, (size_t)g.capv, 1);
  g.vborder = vm_calloc(ctx, (size_t)g.capv, 1);
  g.vline = vm_calloc(ctx, (size_t)g.capv, sizeof *g.vline);
  g.hint = vm_alloc_array(ctx, (size_t)g.capv, sizeof *g.hint);
  g.t.vface = vm_alloc_array(ctx, (size_t)g.capv, sizeof *g.t.vface);
  g.t.tri = vm_alloc_array(ctx, (size_t)g.capf, 3 * sizeof *g.t.tri);
  g.fdead = vm_calloc(ctx, (size_t)g.capf, 1);
  if (!g.x || !g.h || !g.vclass || !g.vdead || !g.vborder || !g.vline || !g.hint || !g.t.vface ||
      !g.t.tri || !g.fdead || hm_init(ctx, &g.t.he, 3 * (size_t)g.nf) ||
      hm_init(ctx, &g.fe, (size_t)f->nedge + 1)) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(g.x, m->xyz, 3 * (size_t)m->nv * sizeof *g.x);
  memcpy(g.vclass, f->vclass, (size_t)m->nv);
  for (int64_t v = 0; v < g.nv; v++) {
    g.vline[v] = f->vclass[v] == VM_FEATURE_LINE ? f->vline[v] : 0;
    g.t.vface[v] = -1;
    g.hint[v] = -1;
  }
  int64_t dup = 0;
  for (int64_t e = 0; e < g.nf; e++) {
    memcpy(g.t.tri + 3 * e, m->conn + m->eoff[e], 3 * sizeof *g.t.tri);
    for (int i = 0; i < 3; i++) g.t.vface[g.t.tri[3 * e + i]] = (int32_t)e;
    dup += vm_tm_keys(&g.t, e, 1);
  }
  if (dup) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "graded remeshing: %lld edges are used twice in the same direction (not a "
                  "manifold, consistently oriented surface)",
                  (long long)dup);
    goto done;
  }
  for (int64_t e = 0; e < g.nf; e++)
    for (int i = 0; i < 3; i++) {
      int32_t a = g.t.tri[3 * e + i], b = g.t.tri[3 * e + (i + 1) % 3];
      if (he_find(&g, b, a) < 0) g.vborder[a] = g.vborder[b] = 1;
    }
  {
    /* every vertex's faces must form one fan; one with more faces than a
     * ring holds is kept as it is (a corner) */
    uint8_t *big = vm_calloc(ctx, (size_t)g.nv, 1);
    if (!big) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    st = vm_tm_check_manifold(ctx, &g.t, g.nv, g.nf, m->xyz, RING_MAX, big, "graded remeshing");
    for (int64_t v = 0; v < g.nv; v++)
      if (big[v]) g.vclass[v] = VM_FEATURE_CORNER;
    vm_free(ctx, big);
    if (st) goto done;
  }
  for (int64_t k = 0; k < f->nedge; k++)
    hm_put(&g.fe, ukey(f->edge[2 * k], f->edge[2 * k + 1]), f->eline[k]);
  {
    double lo[3], hi[3], diag = vm_mesh_bounds(m, lo, hi);
    if ((st = vm_surf_edges_build(ctx, m, &E)) || (st = size_field(&g, &o, &E, diag))) goto done;
  }
  r.h_min = INFINITY;
  r.h_max = 0;
  for (int64_t v = 0; v < g.nv; v++) {
    if (g.h[v] < r.h_min) r.h_min = g.h[v];
    if (g.h[v] > r.h_max) r.h_max = g.h[v];
  }
  if ((st = vm_surface_projector_create(ctx, m, f, &proj))) goto done;
  g.ops = vm_surface_projector_ops(proj);
  g.proj = proj;
  g.href = vm_alloc_array(ctx, (size_t)(g.nv > 0 ? g.nv : 1), sizeof *g.href);
  if (!g.href) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(g.href, g.h, (size_t)g.nv * sizeof *g.href);
  r.nv_in = m->nv;
  r.nf_in = m->ne;
  r.min_angle_free_in = vm_surface_min_angle_free(m, f, &r.min_angle_in);

  for (int it = 0; it < o.iterations; it++) {
    /* collapses first: a strip of the input narrower than the size (a
     * stretched leading edge) is merged before its long edges are split,
     * not split into a fan of needles first */
    g.merge = it < 2;
    int b = collapse_short(&g);
    int a = b < 0 ? b : split_long(&g);
    int c = a < 0 ? a : flip_all(&g);
    if (a < 0 || b < 0 || c < 0) {
      st = b < 0 ? b : a < 0 ? a : c;
      goto done;
    }
    if ((st = smooth_all(&g))) goto done;
    vm_log(ctx, VM_LOG_DEBUG,
           "graded remeshing: round %d: %lld splits, %lld collapses, %lld flips, %lld moves",
           it + 1, (long long)g.splits, (long long)g.collapses, (long long)g.flips,
           (long long)g.moves);
  }
  for (int it = 0; it < 3; it++) {
    int c = flip_all(&g);
    if (c < 0) {
      st = c;
      goto done;
    }
    if ((st = smooth_all(&g))) goto done;
  }

  /* the new mesh: surviving vertices in their order, surviving faces */
  for (int64_t v = 0; v < g.nv; v++)
    if (g.t.vface[v] < 0) g.vdead[v] = 1;
  if ((st = vm_tm_output(ctx, m, g.x, g.nv, g.vdead, &g.t, g.nf, g.fdead, 0, &g.fe, f,
                         "graded remeshing")))
    goto done;
  r.nv = m->nv;
  r.nf = m->ne;
  r.splits = g.splits;
  r.collapses = g.collapses;
  r.flips = g.flips;
  r.moves = g.moves;
  r.min_angle_free = vm_surface_min_angle_free(m, f, &r.min_angle);
  if (rep) *rep = r;
done:
  vm_surface_projector_destroy(&proj);
  vm_surf_edges_free(ctx, &E);
  gfree(&g);
  return st;
}
