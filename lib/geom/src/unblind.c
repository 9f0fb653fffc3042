/* lib/geom/src/unblind.c: folds taken out of a triangle surface where no
 * direction sees every triangle at a vertex (vm_surface_unblind,
 * cleanup.h): single edge collapses and flips, each tried, measured and
 * undone, the one that changes the surface least kept. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"
#include "varmesh/cleanup.h"
#include "varmesh/repair.h"
#include "varmesh/surface_mesh.h"

#define URING 128 /* a vertex with more faces is neither worked on nor removed */
#define UJ (4 * URING)
#define KEXACT 24 /* the most faces the exact direction is solved for */

vm_unblind_opts vm_unblind_opts_default(void) {
  vm_unblind_opts o;
  o.margin = 1e-3;
  o.target = 0.02;
  o.reach = 1.0;
  o.rounds = 8;
  o.keep_clean = 1;
  o.cap_deg = 0.1;
  o.cap_dev = 1e-3;
  return o;
}

typedef struct {
  vm_ctx *ctx;
  const vm_mesh *m;
  const double *x;
  int64_t nv, nf;
  vm_tm t;
  uint8_t *fdead, *vdead, *vborder;
  double *err; /* how far the surface around each vertex has moved so far */
  double thr, target;
  int64_t bad_keys;
  /* the journal of one trial move: faces and vertices as they were */
  int nj, njv;
  int64_t jf[UJ];
  int32_t jtri[3 * UJ];
  uint8_t jdead[UJ];
  int32_t jv[UJ], jvface[UJ];
  uint8_t jvdead[UJ];
  /* scratch */
  int64_t ring[URING];
  double nrm[3 * URING];
} umesh;

/* The margin of vertex z: the best least n . e over its faces' unit
 * normals (a degenerate face counts as seen by no direction); a cheap
 * guess (the angle-weighted normal) where it is at least the target. */
static double margin(umesh *u, int32_t z) {
  int k = vm_tm_ring(&u->t, z, u->ring, URING);
  /* no faces, or more than a ring holds: not judged here (the prism
   * stage's own test sees such a vertex) */
  if (k <= 0) return INFINITY;
  double s[3] = {0, 0, 0};
  for (int i = 0; i < k; i++) {
    const int32_t *t = u->t.tri + 3 * u->ring[i];
    double *n = u->nrm + 3 * i;
    tri_normal(u->x, t[0], t[1], t[2], n);
    double l = vm_norm3(n);
    for (int r = 0; r < 3; r++) n[r] = l > 0 ? n[r] / l : 0;
    int j = vm_tm_index(t, z);
    double a = corner_deg(u->x + 3 * (int64_t)z, u->x + 3 * (int64_t)t[(j + 1) % 3],
                          u->x + 3 * (int64_t)t[(j + 2) % 3]);
    for (int r = 0; r < 3; r++) s[r] += a * n[r];
  }
  double guess = -INFINITY;
  if (vm_normalize3(s) > 0) {
    guess = INFINITY;
    for (int i = 0; i < k; i++) {
      double d = vm_dot3(u->nrm + 3 * i, s);
      if (d < guess) guess = d;
    }
  }
  /* the exact solve costs O(k^4): not above KEXACT faces (the prism
   * stage's own test sees such a vertex) */
  if (guess >= u->target || k > KEXACT) return guess;
  double e = vm_visible_direction(u->nrm, k, NULL);
  return e > guess ? e : guess;
}

/* ---- a trial move: journal, apply, undo ---- */

static void journal_face(umesh *u, int64_t f) {
  for (int i = 0; i < u->nj; i++)
    if (u->jf[i] == f) return;
  u->jf[u->nj] = f;
  memcpy(u->jtri + 3 * u->nj, u->t.tri + 3 * f, 3 * sizeof *u->jtri);
  u->jdead[u->nj] = u->fdead[f];
  u->nj++;
  for (int j = 0; j < 3; j++) {
    int32_t v = u->t.tri[3 * f + j];
    int seen = 0;
    for (int i = 0; i < u->njv && !seen; i++) seen = u->jv[i] == v;
    if (seen) continue;
    u->jv[u->njv] = v;
    u->jvface[u->njv] = u->t.vface[v];
    u->jvdead[u->njv] = u->vdead[v];
    u->njv++;
  }
}

static void undo(umesh *u) {
  for (int i = 0; i < u->nj; i++)
    if (!u->fdead[u->jf[i]]) vm_tm_keys(&u->t, u->jf[i], 0);
  for (int i = 0; i < u->nj; i++) {
    memcpy(u->t.tri + 3 * u->jf[i], u->jtri + 3 * i, 3 * sizeof *u->jtri);
    u->fdead[u->jf[i]] = u->jdead[i];
  }
  for (int i = 0; i < u->nj; i++)
    if (!u->fdead[u->jf[i]]) u->bad_keys += vm_tm_keys(&u->t, u->jf[i], 1);
  for (int i = 0; i < u->njv; i++) {
    u->t.vface[u->jv[i]] = u->jvface[i];
    u->vdead[u->jv[i]] = u->jvdead[i];
  }
}

/* collapse a onto b (a goes away): 1 if done (journaled), 0 if the
 * surface would not stay a manifold */
static int collapse(umesh *u, int32_t a, int32_t b) {
  if (u->vborder[a] || u->m->vflag[a] == VM_VERTEX_FIXED) return 0;
  int64_t h = vm_tm_he(&u->t, a, b), g = vm_tm_he(&u->t, b, a);
  if (h < 0 || g < 0) return 0;
  int64_t f0 = h / 3, f1 = g / 3;
  int32_t c0 = u->t.tri[3 * f0 + (h % 3 + 2) % 3], d0 = u->t.tri[3 * f1 + (g % 3 + 2) % 3];
  if (c0 == d0) return 0;
  int64_t fa[URING], fb[URING];
  int32_t na[3 * URING], nb[3 * URING];
  int ka = vm_tm_ring(&u->t, a, fa, URING), kb = vm_tm_ring(&u->t, b, fb, URING);
  if (ka < 3 || kb < 3 || ka + kb > URING + 2) return 0;
  int ma = vm_tm_neighbours(&u->t, a, fa, ka, na), mb = vm_tm_neighbours(&u->t, b, fb, kb, nb);
  /* the link condition: the common neighbours are exactly c0 and d0 */
  int common = 0;
  for (int i = 0; i < ma; i++)
    if (vm_tm_contains(nb, mb, na[i])) {
      if (na[i] != c0 && na[i] != d0) return 0;
      common++;
    }
  if (common != 2) return 0;
  /* b must keep at least three faces, and so must c0 and d0 */
  if (ka + kb - 4 < 3) return 0;
  for (int i = 0; i < ka; i++) journal_face(u, fa[i]);
  u->bad_keys += vm_tm_collapse(&u->t, u->fdead, fa, ka, a, b);
  u->vdead[a] = 1;
  return 1;
}

/* flip the edge (a, b): 1 if done (journaled), 0 if not a flippable
 * interior edge or its faces carry different element fields */
static int flip(umesh *u, int32_t a, int32_t b, int32_t cd[2]) {
  int64_t h = vm_tm_he(&u->t, a, b), g = vm_tm_he(&u->t, b, a);
  if (h < 0 || g < 0) return 0;
  int64_t f0 = h / 3, f1 = g / 3;
  int32_t c = u->t.tri[3 * f0 + (h % 3 + 2) % 3], d = u->t.tri[3 * f1 + (g % 3 + 2) % 3];
  if (c == d || vm_tm_he(&u->t, c, d) >= 0 || vm_tm_he(&u->t, d, c) >= 0) return 0;
  if (!vm_tm_same_fields(u->m, f0, f1)) return 0;
  journal_face(u, f0);
  journal_face(u, f1);
  u->bad_keys += vm_tm_flip(&u->t, a, b, cd);
  return 1;
}

/* The cap's apex: the corner of face e whose angle is within cap_deg of
 * 180 degrees, or -1. */
static int cap_corner(const umesh *u, int64_t e, double cap_deg) {
  const int32_t *t = u->t.tri + 3 * e;
  for (int i = 0; i < 3; i++) {
    const double *p = u->x + 3 * (int64_t)t[i];
    if (corner_deg(p, u->x + 3 * (int64_t)t[(i + 1) % 3], u->x + 3 * (int64_t)t[(i + 2) % 3]) >=
        180 - cap_deg)
      return i;
  }
  return -1;
}

/* Caps: a triangle whose largest angle is within cap_deg of 180 degrees
 * has its apex c within a hair of its long edge ab. Flipping ab (to c and
 * the far vertex d of the triangle across it) removes the cap and leaves
 * the surface where it was to within c's distance from ab, even where ab
 * is a crease: the crease then runs a-c-b, along the cap's two short
 * edges. Taken where c lies within dev_rel |ab| of the line ab, both new
 * triangles' smallest angle beats the two old ones', and none of the four
 * vertices falls below min(target, its margin before). 1 if taken. */
static int cap_flip(umesh *u, int64_t e, double cap_deg, double dev_rel) {
  const int32_t *t = u->t.tri + 3 * e;
  int k = cap_corner(u, e, cap_deg);
  if (k < 0) return 0;
  int32_t c = t[k], a = t[(k + 1) % 3], b = t[(k + 2) % 3];
  int64_t g = vm_tm_he(&u->t, b, a);
  if (g < 0) return 0;
  int32_t d = u->t.tri[3 * (g / 3) + (g % 3 + 2) % 3];
  /* c's distance from the line ab, against |ab| */
  double ab[3], ac[3], cr[3];
  vm_sub3(u->x + 3 * (int64_t)b, u->x + 3 * (int64_t)a, ab);
  vm_sub3(u->x + 3 * (int64_t)c, u->x + 3 * (int64_t)a, ac);
  vm_cross3(ab, ac, cr);
  double lab = vm_norm3(ab);
  if (!(lab > 0) || !(vm_norm3(cr) / lab <= dev_rel * lab)) return 0;
  double o0 = tri_min_deg(u->x, a, b, c), o1 = tri_min_deg(u->x, b, a, d);
  double oldmin = o0 < o1 ? o0 : o1;
  int32_t vs[4] = {a, b, c, d};
  double before[4];
  for (int i = 0; i < 4; i++) before[i] = margin(u, vs[i]);
  u->nj = u->njv = 0;
  int32_t cd[2];
  if (!flip(u, a, b, cd)) return 0;
  double n0 = tri_min_deg(u->x, a, d, c), n1 = tri_min_deg(u->x, d, b, c);
  int ok = (n0 < n1 ? n0 : n1) > oldmin;
  for (int i = 0; i < 4 && ok; i++) {
    double need = before[i] < u->target ? before[i] : u->target;
    ok = margin(u, vs[i]) >= need;
  }
  if (!ok) {
    undo(u);
    return 0;
  }
  double dev = vm_norm3(cr) / lab;
  for (int i = 0; i < 4; i++)
    if (dev > u->err[vs[i]]) u->err[vs[i]] = dev;
  return 1;
}

/* ---- how far a move changes the surface ---- */

/* distance from p to the triangle (a, b, c) */
static double point_tri(const double *p, const double *a, const double *b, const double *c) {
  double ab[3], ac[3], ap[3], q[3];
  vm_sub3(b, a, ab);
  vm_sub3(c, a, ac);
  vm_sub3(p, a, ap);
  double d1 = vm_dot3(ab, ap), d2 = vm_dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) return vm_dist3(p, a);
  double bp[3];
  vm_sub3(p, b, bp);
  double d3 = vm_dot3(ab, bp), d4 = vm_dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) return vm_dist3(p, b);
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    double v = d1 / (d1 - d3);
    for (int r = 0; r < 3; r++) q[r] = a[r] + v * ab[r];
    return vm_dist3(p, q);
  }
  double cp[3];
  vm_sub3(p, c, cp);
  double d5 = vm_dot3(ab, cp), d6 = vm_dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) return vm_dist3(p, c);
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    double w = d2 / (d2 - d6);
    for (int r = 0; r < 3; r++) q[r] = a[r] + w * ac[r];
    return vm_dist3(p, q);
  }
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    for (int r = 0; r < 3; r++) q[r] = b[r] + w * (c[r] - b[r]);
    return vm_dist3(p, q);
  }
  double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
  for (int r = 0; r < 3; r++) q[r] = a[r] + v * ab[r] + w * ac[r];
  return vm_dist3(p, q);
}

/* distance from p to the faces fs given by their corners (3 each) */
static double point_faces(const umesh *u, const double *p, const int32_t *tri, int n) {
  double d = INFINITY;
  for (int i = 0; i < n; i++) {
    const int32_t *t = tri + 3 * i;
    double e =
        point_tri(p, u->x + 3 * (int64_t)t[0], u->x + 3 * (int64_t)t[1], u->x + 3 * (int64_t)t[2]);
    if (e < d) d = e;
  }
  return d;
}

/* The change the journaled move made: the largest distance from the old
 * faces' vertices and centroids to the new faces and back. */
static double journal_dev(const umesh *u) {
  int32_t oldt[3 * UJ], newt[3 * UJ];
  int no = 0, nn = 0;
  for (int i = 0; i < u->nj; i++) {
    if (!u->jdead[i]) memcpy(oldt + 3 * no++, u->jtri + 3 * i, 3 * sizeof *oldt);
    if (!u->fdead[u->jf[i]]) memcpy(newt + 3 * nn++, u->t.tri + 3 * u->jf[i], 3 * sizeof *newt);
  }
  double dev = 0;
  for (int pass = 0; pass < 2; pass++) {
    const int32_t *from = pass ? newt : oldt, *to = pass ? oldt : newt;
    int nfrom = pass ? nn : no, nto = pass ? no : nn;
    for (int i = 0; i < nfrom; i++) {
      const int32_t *t = from + 3 * i;
      double c[3] = {0, 0, 0};
      for (int j = 0; j < 3; j++) {
        const double *p = u->x + 3 * (int64_t)t[j];
        double d = point_faces(u, p, to, nto);
        if (d > dev) dev = d;
        for (int r = 0; r < 3; r++) c[r] += p[r] / 3;
      }
      double d = point_faces(u, c, to, nto);
      if (d > dev) dev = d;
    }
  }
  return dev;
}

/* ---- the search ---- */

typedef struct {
  int kind; /* 0 none, 1 flip (a, b), 2 collapse a onto b */
  int32_t a, b;
  double dev, worst;
} umove;

/* The vertices of the journaled faces: those a move can touch. */
static int touched(const umesh *u, int32_t *vs) {
  for (int i = 0; i < u->njv; i++) vs[i] = u->jv[i];
  return u->njv;
}

/* Try the move, judge it, undo it: kept in *best if every vertex it
 * touches keeps min(target, its margin before) or was blind and the
 * blind among them are fewer, and it changes the surface less. */
static void trial(umesh *u, int kind, int32_t a, int32_t b, double reach, umove *best) {
  u->nj = u->njv = 0;
  int32_t cd[2];
  /* the margins before, of every vertex the move can touch: a's and b's
   * neighbours (a collapse) or the four corners (a flip) */
  int64_t fa[URING];
  int ka = vm_tm_ring(&u->t, a, fa, URING);
  if (ka < 0) return;
  int32_t vs[UJ];
  double before[UJ];
  int nvs = 0;
  /* journal first without changing anything, to learn the touched set */
  if (kind == 2)
    for (int i = 0; i < ka; i++) journal_face(u, fa[i]);
  else {
    int64_t h = vm_tm_he(&u->t, a, b), g = vm_tm_he(&u->t, b, a);
    if (h < 0 || g < 0) return;
    journal_face(u, h / 3);
    journal_face(u, g / 3);
  }
  nvs = touched(u, vs);
  int blind0 = 0;
  for (int i = 0; i < nvs; i++) {
    before[i] = margin(u, vs[i]);
    blind0 += before[i] < u->thr;
  }
  u->nj = u->njv = 0;
  int done = kind == 2 ? collapse(u, a, b) : flip(u, a, b, cd);
  if (!done) return;
  int blind1 = 0, ok = 1;
  double worst = INFINITY;
  for (int i = 0; i < nvs && ok; i++) {
    if (u->vdead[vs[i]]) continue;
    double mg = margin(u, vs[i]);
    if (mg < worst) worst = mg;
    if (mg < u->thr) blind1++;
    double need = before[i] < u->target ? before[i] : u->target;
    if (before[i] >= u->thr && mg < need) ok = 0;
  }
  if (ok && blind1 < blind0) {
    double e0 = 0;
    for (int i = 0; i < nvs; i++)
      if (u->err[vs[i]] > e0) e0 = u->err[vs[i]];
    double dev = journal_dev(u) + e0;
    if (dev <= reach &&
        (!best->kind || dev < best->dev || (dev == best->dev && worst > best->worst))) {
      best->kind = kind;
      best->a = a;
      best->b = b;
      best->dev = dev;
      best->worst = worst;
    }
  }
  undo(u);
}

/* the mean length of the edges at v */
static double local_edge(umesh *u, int32_t v) {
  int k = vm_tm_ring(&u->t, v, u->ring, URING);
  double s = 0;
  int n = 0;
  for (int i = 0; i < k; i++) {
    const int32_t *t = u->t.tri + 3 * u->ring[i];
    int j = vm_tm_index(t, v);
    s += vm_dist3(u->x + 3 * (int64_t)v, u->x + 3 * (int64_t)t[(j + 1) % 3]);
    n++;
  }
  return n ? s / n : 0;
}

/* The best move at the blind vertex v, applied: 1 if one was */
static int work_on(umesh *u, int32_t v, double reach_rel) {
  int64_t fs[URING];
  int k = vm_tm_ring(&u->t, v, fs, URING);
  if (k <= 0) return 0;
  double reach = reach_rel * local_edge(u, v);
  /* the edges of its faces, each once (an edge between two of them is
   * listed by both) */
  int32_t edges[6 * URING];
  int ne = 0;
  for (int i = 0; i < k; i++) {
    const int32_t *t = u->t.tri + 3 * fs[i];
    for (int j = 0; j < 3; j++) {
      int32_t a = t[j], b = t[(j + 1) % 3];
      int seen = 0;
      for (int e = 0; e < ne && !seen; e++) seen = edges[2 * e] == b && edges[2 * e + 1] == a;
      if (seen) continue;
      edges[2 * ne] = a;
      edges[2 * ne + 1] = b;
      ne++;
    }
  }
  umove best = {0, 0, 0, 0, 0};
  for (int i = 0; i < ne; i++) {
    int32_t a = edges[2 * i], b = edges[2 * i + 1];
    trial(u, 1, a, b, reach, &best);
    if (a == v || b == v) {
      trial(u, 2, a, b, reach, &best);
      trial(u, 2, b, a, reach, &best);
    }
  }
  if (!best.kind) return 0;
  u->nj = u->njv = 0;
  int32_t cd[2];
  if (best.kind == 2)
    collapse(u, best.a, best.b);
  else
    flip(u, best.a, best.b, cd);
  for (int i = 0; i < u->njv; i++)
    if (best.dev > u->err[u->jv[i]]) u->err[u->jv[i]] = best.dev;
  return best.kind;
}

static int64_t count_blind(umesh *u, double at[3]) {
  int64_t n = 0;
  for (int64_t v = 0; v < u->nv; v++) {
    if (u->vdead[v] || u->t.vface[v] < 0) continue;
    if (margin(u, (int32_t)v) < u->thr) {
      if (!n && at) memcpy(at, u->x + 3 * v, 3 * sizeof *at);
      n++;
    }
  }
  return n;
}

/* A first look, in two passes over the triangles and nothing but two
 * arrays over the vertices: how many vertices the angle-weighted normal
 * does not see every incident face of at `target` (the cheap guess of
 * margin(), which decides where it is at least the target), and how many
 * triangles are caps. 0: nothing for the step to do. */
static int64_t quick_suspects(const vm_mesh *m, double target, double cap_deg) {
  vm_ctx *ctx = m->ctx;
  const size_t nv1 = (size_t)(m->nv > 0 ? m->nv : 1);
  double *vn = vm_calloc(ctx, 3 * nv1, sizeof *vn), *low = vm_alloc_array(ctx, nv1, sizeof *low);
  if (!vn || !low) {
    vm_free(ctx, vn);
    vm_free(ctx, low);
    return VM_ERR_NOMEM;
  }
  const double *x = m->xyz;
  int64_t n = 0;
  for (int pass = 0; pass < 2; pass++) {
    for (int64_t e = 0; e < m->ne; e++) {
      const int32_t *t = m->conn + 3 * e;
      double f[3];
      tri_normal(x, t[0], t[1], t[2], f);
      double l = vm_norm3(f);
      for (int r = 0; r < 3; r++) f[r] = l > 0 ? f[r] / l : 0;
      for (int i = 0; i < 3; i++) {
        const double *p = x + 3 * (int64_t)t[i];
        double *w = vn + 3 * (int64_t)t[i];
        if (pass == 0) {
          double a =
              corner_deg(p, x + 3 * (int64_t)t[(i + 1) % 3], x + 3 * (int64_t)t[(i + 2) % 3]);
          for (int r = 0; r < 3; r++) w[r] += a * f[r];
          n += a >= 180 - cap_deg;
        } else {
          double d = vm_dot3(w, f);
          if (d < low[t[i]]) low[t[i]] = d;
        }
      }
    }
    /* a vertex whose normals cancel keeps a zero vector: seen at 0 */
    if (pass == 0)
      for (int64_t v = 0; v < m->nv; v++) {
        low[v] = INFINITY;
        vm_normalize3(vn + 3 * v);
      }
  }
  for (int64_t v = 0; v < m->nv; v++) n += low[v] < target;
  vm_free(ctx, vn);
  vm_free(ctx, low);
  return n;
}

int vm_surface_unblind(vm_mesh *m, const vm_unblind_opts *opts, vm_unblind_report *rep) {
  vm_unblind_report r;
  memset(&r, 0, sizeof r);
  if (rep) *rep = r;
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_unblind_opts o = opts ? *opts : vm_unblind_opts_default();
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] != VM_TRI)
      return vm_error(ctx, VM_ERR_ARG, "unblind: the surface must be made of triangles only");
  if (!(o.margin > -1 && o.margin < 1) || !(o.target >= o.margin) || !(o.reach >= 0) ||
      o.rounds < 0)
    return vm_error(ctx, VM_ERR_ARG, "unblind: margin %g, target %g, reach %g, %d rounds", o.margin,
                    o.target, o.reach, o.rounds);
  /* most surfaces have nothing to do: said without the edited structure */
  int64_t suspects = quick_suspects(m, o.target, o.cap_deg);
  if (suspects <= 0) return suspects < 0 ? (int)suspects : VM_OK;
  umesh *u = vm_calloc(ctx, 1, sizeof *u);
  if (!u) return VM_ERR_NOMEM;
  u->ctx = ctx;
  u->m = m;
  u->x = m->xyz;
  u->nv = m->nv;
  u->nf = m->ne;
  u->thr = o.margin;
  u->target = o.target;
  const size_t nv1 = (size_t)(u->nv > 0 ? u->nv : 1), nf1 = (size_t)(u->nf > 0 ? u->nf : 1);
  int st = VM_OK;
  hmap fe;
  memset(&fe, 0, sizeof fe);
  vm_surface_features feat;
  memset(&feat, 0, sizeof feat);
  vm_mesh *keep = NULL; /* the input, while the result is checked */
  u->t.tri = vm_alloc_array(ctx, 3 * nf1, sizeof *u->t.tri);
  u->fdead = vm_calloc(ctx, nf1, 1);
  u->vdead = vm_calloc(ctx, nv1, 1);
  u->vborder = vm_calloc(ctx, nv1, 1);
  u->t.vface = vm_alloc_array(ctx, nv1, sizeof *u->t.vface);
  u->err = vm_calloc(ctx, nv1, sizeof *u->err);
  if (!u->err || !u->t.tri || !u->fdead || !u->vdead || !u->vborder || !u->t.vface ||
      hm_init(ctx, &u->t.he, 3 * nf1) || hm_init(ctx, &fe, 1)) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t v = 0; v < u->nv; v++) u->t.vface[v] = -1;
  for (int64_t e = 0; e < u->nf; e++) {
    memcpy(u->t.tri + 3 * e, m->conn + m->eoff[e], 3 * sizeof *u->t.tri);
    for (int i = 0; i < 3; i++) u->t.vface[u->t.tri[3 * e + i]] = (int32_t)e;
    u->bad_keys += vm_tm_keys(&u->t, e, 1);
  }
  if (u->bad_keys) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "unblind: %lld edges are used twice in the same direction (not a manifold, "
                  "consistently oriented surface)",
                  (long long)u->bad_keys);
    goto done;
  }
  for (int64_t e = 0; e < u->nf; e++)
    for (int i = 0; i < 3; i++) {
      int32_t a = u->t.tri[3 * e + i], b = u->t.tri[3 * e + (i + 1) % 3];
      if (vm_tm_he(&u->t, b, a) < 0) u->vborder[a] = u->vborder[b] = 1;
    }
  /* a vertex with more faces than a ring holds is left alone (big = border) */
  if ((st = vm_tm_check_manifold(ctx, &u->t, u->nv, u->nf, m->xyz, URING, u->vborder, "unblind")))
    goto done;
  r.blind_in = count_blind(u, r.at_in);
  memcpy(r.at, r.at_in, sizeof r.at);
  r.blind = r.blind_in;
  for (int64_t e = 0; e < u->nf; e++) r.caps_in += cap_corner(u, e, o.cap_deg) >= 0;
  r.caps = r.caps_in;
  if (r.blind_in == 0 && r.caps_in == 0) goto done;
  /* caps first: their flips leave the surface where it was */
  for (int round = 0; round < o.rounds && r.caps > 0; round++) {
    int64_t changed = 0;
    for (int64_t e = 0; e < u->nf; e++)
      if (!u->fdead[e] && cap_flip(u, e, o.cap_deg, o.cap_dev)) changed++;
    r.cap_flips += changed;
    r.caps = 0;
    for (int64_t e = 0; e < u->nf; e++) r.caps += !u->fdead[e] && cap_corner(u, e, o.cap_deg) >= 0;
    if (!changed || vm_ctx_interrupted(ctx)) break;
  }
  if (r.cap_flips) r.blind = count_blind(u, r.at);
  for (int round = 0; round < o.rounds && r.blind > 0; round++) {
    int64_t changed = 0;
    for (int64_t v = 0; v < u->nv; v++) {
      if (u->vdead[v] || u->t.vface[v] < 0 || u->vborder[v]) continue;
      if (!(margin(u, (int32_t)v) < u->thr)) continue;
      int k = work_on(u, (int32_t)v, o.reach);
      if (k == 1) r.flips++;
      if (k == 2) r.collapses++;
      changed += k != 0;
    }
    r.rounds = round + 1;
    r.blind = count_blind(u, r.at);
    if (!changed || vm_ctx_interrupted(ctx)) break;
  }
  if (u->bad_keys) {
    st = vm_error(ctx, VM_ERR_BACKEND, "unblind: internal error (%lld duplicate edges)",
                  (long long)u->bad_keys);
    goto done;
  }
  for (int64_t v = 0; v < u->nv; v++)
    if (u->err[v] > r.max_dev) r.max_dev = u->err[v];
  if (r.flips + r.collapses + r.cap_flips == 0) goto done;
  feat.nv = m->nv;
  feat.vclass = vm_calloc(ctx, nv1, 1);
  if (!feat.vclass) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t n0 = 0, n1 = 0;
  if (o.keep_clean &&
      ((st = vm_surface_self_intersections(m, &n0, NULL)) || (st = vm_mesh_clone(m, &keep))))
    goto done;
  if ((st = vm_tm_output(ctx, m, m->xyz, u->nv, u->vdead, &u->t, u->nf, u->fdead, 1, &fe, &feat,
                         "unblind")))
    goto done;
  if (o.keep_clean && (st = vm_surface_self_intersections(m, &n1, NULL))) goto done;
  if (o.keep_clean && n1 > n0) {
    vm_mesh tmp = *m;
    *m = *keep;
    *keep = tmp;
    r.undone = 1;
    r.blind = r.blind_in;
    r.caps = r.caps_in;
    memcpy(r.at, r.at_in, sizeof r.at);
  }
done:
  vm_mesh_destroy(&keep);
  if (rep) *rep = r;
  vm_surface_features_free(ctx, &feat);
  hm_free(ctx, &fe);
  vm_free(ctx, u->t.tri);
  vm_free(ctx, u->fdead);
  vm_free(ctx, u->vdead);
  vm_free(ctx, u->vborder);
  vm_free(ctx, u->t.vface);
  vm_free(ctx, u->err);
  hm_free(ctx, &u->t.he);
  vm_free(ctx, u);
  return st;
}

int64_t vm_surface_count_blind(const vm_mesh *m, double thr, double at[3]) {
  if (!m) return VM_ERR_ARG;
  vm_mesh *c = NULL;
  vm_unblind_opts o = vm_unblind_opts_default();
  o.margin = thr;
  o.target = thr > o.target ? thr : o.target;
  o.rounds = 0;
  o.keep_clean = 0;
  vm_unblind_report r;
  /* zero rounds count and change nothing; a copy keeps m const */
  int st = vm_mesh_clone(m, &c);
  if (!st) st = vm_surface_unblind(c, &o, &r);
  vm_mesh_destroy(&c);
  if (st) return st;
  if (at && r.blind) memcpy(at, r.at, sizeof r.at);
  return r.blind;
}
