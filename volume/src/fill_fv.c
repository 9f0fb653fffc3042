/* volume/src/fill_fv.c: the fill's finite-volume relief. A finite-volume
 * solver (OpenFOAM's checkMesh) judges the tets by their faces and centres,
 * not by their shape alone: non-orthogonality (fails the schemes beyond
 * 70 degrees), skewness (fails beyond 4), interpolation weights (below
 * 0.05), the volume ratio of neighbours (below 0.01) and the cell
 * determinant (below 0.001). The shape optimization (optimize_band) makes
 * tets round; it does not see a round tet beside a flat top prism, or a
 * centre that a face's plane nearly holds.
 *
 * The relief moves the fill's own vertices (those Gmsh made, never the
 * envelope's, the layer's or the far field's) one at a time, in index
 * order, where a face or cell around them is near such a limit: a few
 * steps of gradient descent (central differences) on the sum over the
 * faces and cells that depend on the vertex of
 *
 *   ((theta - 60 deg) / 10 deg)^2 + (skew - 2)^2 + (0.1 / w - 1)^2
 *     + 4 log10(0.05 / volume ratio)^2 + 4 log10(0.005 / det)^2
 *
 * each term only where positive, so a face well within every limit weighs
 * nothing. A step is kept only if it lowers that sum, no measure's worst
 * around the vertex goes beyond checkMesh's limit or, if it was beyond,
 * gets worse, every tet around the vertex keeps its orientation and their
 * least mean ratio stays at or above min(0.1, what it was). The first
 * sweep visits every vertex of a tet that weighs, the next ones only
 * those around the vertices the sweep before moved (nothing else
 * changed); sweeps repeat while one lowers the sum by more than a
 * hundredth. Sequential, in vertex order: the same result on every run. */
#include "varmesh/fill.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fill_private.h"
#include "varmesh/quality.h"
#include "varmesh/topology.h"
#include "vec3.h"

#define FV_PI 3.14159265358979323846
/* the penalty's thresholds: where a face or cell starts to weigh */
#define FV_ORTHO_DEG 60.0
#define FV_ORTHO_SCALE 10.0
#define FV_SKEW 2.0
#define FV_WEIGHT 0.1
#define FV_VOLRATIO 0.05
#define FV_DET 0.005
/* the least mean ratio a moved tet may fall to (or its own before) */
#define FV_QMIN 0.1
/* steps per vertex per sweep, halvings per step */
#define FV_STEPS 4
#define FV_HALVINGS 10

typedef struct {
  vm_mesh *m;
  int64_t e0;    /* first tet of the fill */
  int64_t first; /* first vertex that may move */
  int64_t e1;    /* the flips: the end of the tets from e0 (dead[] covers e0..e1) */
  int32_t *nbr;  /* per cell, per face (6): the cell across a triangle, -1 none */
  int tf[6][4];  /* a tet's faces (vm_elem_faces) */
  double *cc;    /* cell centres */
  double *vol;   /* cell volumes */
  int64_t *rp;   /* vertex -> cells */
  int32_t *ve;
  uint8_t *fixed; /* vertices that may not move (below first, or on the boundary) */
} fv_state;

static void cell_coords(const vm_mesh *m, int64_t e, double *x) {
  int n = vm_elem_nverts(m->etype[e]);
  const int32_t *c = m->conn + m->eoff[e];
  for (int i = 0; i < n; i++) memcpy(x + 3 * i, m->xyz + 3 * (int64_t)c[i], 3 * sizeof *x);
}

static void cell_update(fv_state *S, int64_t e) {
  double x[24];
  cell_coords(S->m, e, x);
  vm_cell_foam_centre(S->m->etype[e], x, S->cc + 3 * e, S->vol + e);
}

/* Face j of tet e: its 3 vertices into y, its centre and area vector. */
static void tet_face(const fv_state *S, int64_t e, int j, double *y, double *c, double *s) {
  const int32_t *q = S->m->conn + S->m->eoff[e];
  for (int i = 0; i < 3; i++)
    memcpy(y + 3 * i, S->m->xyz + 3 * (int64_t)q[S->tf[j][i]], 3 * sizeof *y);
  vm_foam_face(y, 3, c, s);
}

/* OpenFOAM's determinant of tet e over its internal faces. */
static double tet_det(const fv_state *S, int64_t e) {
  double s[4][3], y[12], c[3];
  int k = 0;
  for (int j = 0; j < 4; j++) {
    if (S->nbr[6 * e + j] < 0) continue;
    tet_face(S, e, j, y, c, s[k]);
    k++;
  }
  return vm_foam_cell_determinant(k, (const double(*)[3])s);
}

/* The measures of triangle y (centre c, area vector s) between the cells
 * centred at cp and cn of volumes vp and vn: non-orthogonality in
 * degrees, skewness, weight, volume ratio. */
static void tri_measures(const double *y, const double *c, const double *s, const double *cp,
                         const double *cn, double vp, double vn, double *deg, double *skew,
                         double *w, double *vr) {
  double cs = vm_foam_ortho_cos(c, s, cp, cn);
  *deg = acos(cs < -1 ? -1 : cs > 1 ? 1 : cs) * 180 / FV_PI;
  *skew = vm_foam_skew(y, 3, c, s, cp, cn);
  *w = vm_foam_weight(c, s, cp, cn);
  double va = fabs(vp), vb = fabs(vn);
  *vr = va < vb ? (vb > 0 ? va / vb : 0) : (va > 0 ? vb / va : 0);
}

/* The measures of face j of tet e (an internal face). */
static void face_measures(const fv_state *S, int64_t e, int j, double *deg, double *skew, double *w,
                          double *vr) {
  int64_t b = S->nbr[6 * e + j];
  double y[12], c[3], s[3];
  tet_face(S, e, j, y, c, s);
  tri_measures(y, c, s, S->cc + 3 * e, S->cc + 3 * b, S->vol[e], S->vol[b], deg, skew, w, vr);
}

static double sq_pos(double x) { return x > 0 ? x * x : 0; }

/* The worst of each measure over the faces and cells of a vertex. */
typedef struct {
  double deg, skew, w, vr, det;
} fv_worst;

static void worst_init(fv_worst *W) {
  W->deg = W->skew = 0;
  W->w = W->vr = W->det = INFINITY;
}

/* May the worst measures W1 after a move replace W0 before: none beyond
 * checkMesh's limit that was within it, none beyond it worse than it was? */
static int worst_ok(const fv_worst *W1, const fv_worst *W0) {
  return W1->deg <= fmax(W0->deg, 70) && W1->skew <= fmax(W0->skew, 4) &&
         W1->w >= fmin(W0->w, 0.05) && W1->vr >= fmin(W0->vr, 0.01) &&
         W1->det >= fmin(W0->det, 0.001);
}

/* The penalty of a face with these measures, and of a cell with this
 * determinant. */
static double face_pen(double deg, double skew, double w, double vr) {
  double p = sq_pos((deg - FV_ORTHO_DEG) / FV_ORTHO_SCALE) + sq_pos(skew - FV_SKEW);
  p += w > 0 ? sq_pos(FV_WEIGHT / w - 1) : 1e6;
  p += vr > 0 ? 4 * sq_pos(log10(FV_VOLRATIO / vr)) : 1e6;
  return isfinite(p) ? p : 1e6;
}

static double det_pen(double d) { return d > 0 ? 4 * sq_pos(log10(FV_DET / d)) : 1e6; }

static void worst_face(fv_worst *W, double deg, double skew, double w, double vr) {
  W->deg = fmax(W->deg, deg);
  W->skew = fmax(W->skew, skew);
  W->w = fmin(W->w, w);
  W->vr = fmin(W->vr, vr);
}

static double face_penalty(const fv_state *S, int64_t e, int j, fv_worst *W) {
  double deg, skew, w, vr;
  face_measures(S, e, j, &deg, &skew, &w, &vr);
  if (W) worst_face(W, deg, skew, w, vr);
  return face_pen(deg, skew, w, vr);
}

static double det_penalty(const fv_state *S, int64_t e, fv_worst *W) {
  double d = tet_det(S, e);
  if (W) W->det = fmin(W->det, d);
  return det_pen(d);
}

/* Mean ratio of tet x (1 regular, 0 flat), signed by its volume. */
static double mean_ratio(const double *x) {
  double u[3], v[3], w[3], n[3], l2 = 0;
  vm_sub3(x + 3, x, u);
  vm_sub3(x + 6, x, v);
  vm_sub3(x + 9, x, w);
  vm_cross3(u, v, n);
  double vol6 = vm_dot3(n, w);
  static const int E[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (int k = 0; k < 6; k++) {
    double d[3];
    vm_sub3(x + 3 * E[k][1], x + 3 * E[k][0], d);
    l2 += vm_dot3(d, d);
  }
  if (!(l2 > 0)) return -1;
  double a = fabs(vol6) / 6;
  double q = 12 * pow(3 * a, 2.0 / 3.0) / l2;
  return vol6 > 0 ? q : -q;
}

/* The sum of the penalties that vertex v's position changes: the faces of
 * its cells (each face once per cell of v's around it) and the
 * determinants of its cells and of their neighbours across its faces. */
static double local_penalty(const fv_state *S, int64_t v, fv_worst *W) {
  double p = 0;
  if (W) worst_init(W);
  for (int64_t k = S->rp[v]; k < S->rp[v + 1]; k++) {
    int64_t e = S->ve[k];
    if (S->m->etype[e] != VM_TET) continue;
    for (int j = 0; j < 4; j++) {
      int64_t b = S->nbr[6 * e + j];
      if (b < 0) continue;
      p += face_penalty(S, e, j, W);
      if (S->m->etype[b] == VM_TET) p += det_penalty(S, b, W);
    }
    p += det_penalty(S, e, W);
  }
  return p;
}

/* The least mean ratio of v's tets (orientation sign s0: +1 or -1). */
static double local_quality(const fv_state *S, int64_t v, const int8_t *sign) {
  double q = INFINITY, x[12];
  for (int64_t k = S->rp[v]; k < S->rp[v + 1]; k++) {
    int64_t e = S->ve[k];
    cell_coords(S->m, e, x);
    double r = sign[e] * mean_ratio(x);
    q = r < q ? r : q;
  }
  return q;
}

static void move_to(fv_state *S, int64_t v, const double *x) {
  memcpy(S->m->xyz + 3 * v, x, 3 * sizeof *x);
  for (int64_t k = S->rp[v]; k < S->rp[v + 1]; k++) cell_update(S, S->ve[k]);
}

/* Up to FV_STEPS descent steps for vertex v; the penalty lowered by (*p0
 * the penalty before). */
static double relieve_vertex(fv_state *S, int64_t v, const int8_t *sign, double q0, double *p0out) {
  double *x = S->m->xyz + 3 * v, x0[3], best[3];
  memcpy(x0, x, sizeof x0);
  memcpy(best, x, sizeof best);
  fv_worst W0, W1;
  double p0 = local_penalty(S, v, &W0), p = p0;
  *p0out = p0;
  if (!(p > 0)) return 0;
  double lmin = INFINITY;
  for (int64_t k = S->rp[v]; k < S->rp[v + 1]; k++) {
    const int32_t *c = S->m->conn + S->m->eoff[S->ve[k]];
    for (int i = 0; i < 4; i++)
      if (c[i] != v) {
        double l = vm_dist3(x0, S->m->xyz + 3 * (int64_t)c[i]);
        lmin = l < lmin ? l : lmin;
      }
  }
  if (!(lmin > 0) || !isfinite(lmin)) return 0;
  double qfloor = q0 < FV_QMIN ? q0 : FV_QMIN;
  for (int it = 0; it < FV_STEPS; it++) {
    double g[3], h = 1e-4 * lmin, y[3];
    for (int r = 0; r < 3; r++) {
      memcpy(y, best, sizeof y);
      y[r] = best[r] + h;
      move_to(S, v, y);
      double pp = local_penalty(S, v, NULL);
      y[r] = best[r] - h;
      move_to(S, v, y);
      double pm = local_penalty(S, v, NULL);
      g[r] = (pp - pm) / (2 * h);
    }
    double gn = vm_norm3(g);
    if (!(gn > 0) || !isfinite(gn)) break;
    double a = 0.25 * lmin / gn;
    int taken = 0;
    for (int k = 0; k < FV_HALVINGS && !taken; k++, a *= 0.5) {
      for (int r = 0; r < 3; r++) y[r] = best[r] - a * g[r];
      move_to(S, v, y);
      double pn = local_penalty(S, v, &W1);
      if (pn < p && worst_ok(&W1, &W0) && local_quality(S, v, sign) >= qfloor) {
        p = pn;
        memcpy(best, y, sizeof best);
        taken = 1;
      }
    }
    if (!taken) break;
  }
  move_to(S, v, best);
  return p0 - p;
}

/* The figures over the internal faces with a fill tet on a side and the
 * fill's tets. */
static void figures(const fv_state *S, vm_fill_fv_figures *F) {
  memset(F, 0, sizeof *F);
  F->weight_min = F->volratio_min = F->det_min = INFINITY;
  const vm_mesh *m = S->m;
  for (int64_t e = S->e0; e < m->ne; e++) {
    if (m->etype[e] != VM_TET) continue;
    double d = tet_det(S, e);
    F->tets++;
    F->det_under += d < 0.001;
    F->det_min = d < F->det_min ? d : F->det_min;
    for (int j = 0; j < 4; j++) {
      int64_t b = S->nbr[6 * e + j];
      if (b < 0) continue;
      /* a face between two fill tets once (from the lower index) */
      if (b >= S->e0 && m->etype[b] == VM_TET && b < e) continue;
      double deg, skew, w, vr;
      face_measures(S, e, j, &deg, &skew, &w, &vr);
      F->faces++;
      F->nonortho_over70 += deg > 70;
      F->nonortho_max = deg > F->nonortho_max ? deg : F->nonortho_max;
      F->skew_over4 += skew > 4;
      F->skew_max = skew > F->skew_max ? skew : F->skew_max;
      F->weight_under += w < 0.05;
      F->weight_min = w < F->weight_min ? w : F->weight_min;
      F->volratio_under += vr < 0.01;
      F->volratio_min = vr < F->volratio_min ? vr : F->volratio_min;
    }
  }
}

/* Does tet e (or a neighbour's face with it) weigh in the penalty? */
static int tet_active(const fv_state *S, int64_t e) {
  if (det_penalty(S, e, NULL) > 0) return 1;
  for (int j = 0; j < 4; j++)
    if (S->nbr[6 * e + j] >= 0 && face_penalty(S, e, j, NULL) > 0) return 1;
  return 0;
}

static void fv_release(vm_ctx *ctx, fv_state *S) {
  vm_free(ctx, S->nbr);
  vm_free(ctx, S->cc);
  vm_free(ctx, S->vol);
  vm_free(ctx, S->fixed);
  vm_free(ctx, S->rp);
  vm_free(ctx, S->ve);
  memset(S, 0, sizeof *S);
}

/* The state of m: cell centres and volumes, each tet face's neighbour,
 * the vertices' cells, and the vertices that may not move (below first,
 * on a boundary face, or with a cell around them that is not a tet). */
static int fv_setup(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, fv_state *S) {
  memset(S, 0, sizeof *S);
  S->m = m;
  S->e0 = e0;
  S->first = first;
  S->e1 = m->ne;
  tface *T = NULL;
  int64_t nt = 0;
  int st = VM_OK;
  S->nbr = vm_alloc_array(ctx, (size_t)m->ne * 6 + 1, sizeof *S->nbr);
  S->cc = vm_alloc_array(ctx, (size_t)m->ne * 3 + 1, sizeof *S->cc);
  S->vol = vm_alloc_array(ctx, (size_t)m->ne + 1, sizeof *S->vol);
  S->fixed = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  if (!S->nbr || !S->cc || !S->vol || !S->fixed) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if ((st = vm_mesh_vertex_elements(m, &S->rp, &S->ve))) goto done;
  int nfv[6];
  vm_elem_faces(VM_TET, S->tf, nfv);
  for (int64_t e = 0; e < m->ne; e++) {
    for (int j = 0; j < 6; j++) S->nbr[6 * e + j] = -1;
    if (vm_elem_dim(m->etype[e]) == 3) cell_update(S, e);
  }
  /* the two cells of each interior triangle; a boundary face's vertices
   * stay (quads have no fill tet beside them) */
  if ((st = fill_tri_faces(ctx, m, &T, &nt))) goto done;
  for (int64_t i = 0; i < nt;) {
    int64_t k = i + 1;
    while (k < nt && fill_same_face(&T[k], &T[i])) k++;
    if (k - i == 2) {
      S->nbr[6 * (int64_t)T[i].cell + T[i].face] = T[i + 1].cell;
      S->nbr[6 * (int64_t)T[i + 1].cell + T[i + 1].face] = T[i].cell;
    } else if (k - i == 1) {
      for (int r = 0; r < 3; r++) S->fixed[T[i].v[r]] = 1;
    }
    i = k;
  }
  for (int64_t v = 0; v < first && v < m->nv; v++) S->fixed[v] = 1;
  /* a vertex moves only if every cell around it is a tet */
  for (int64_t v = first; v < m->nv; v++)
    for (int64_t k = S->rp[v]; k < S->rp[v + 1]; k++)
      if (m->etype[S->ve[k]] != VM_TET) S->fixed[v] = 1;
done:
  vm_free(ctx, T);
  if (st) fv_release(ctx, S);
  return st;
}

/* The relief; seed (if not NULL, per vertex): the first sweep takes only
 * the tets with a seeded vertex and their neighbours (what changed since
 * a relief before); before may be NULL. */
static int relief_run(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int sweeps,
                      const uint8_t *seed, vm_fill_fv_figures *before, vm_fill_fv_figures *after,
                      int64_t *moved) {
  fv_state S;
  *moved = 0;
  if (e0 < 0 || e0 > m->ne || first < 0)
    return vm_error(ctx, VM_ERR_ARG,
                    "finite-volume relief: first tet %lld or vertex %lld out of range",
                    (long long)e0, (long long)first);
  int8_t *sign = NULL;
  uint8_t *act = NULL, *mv = NULL;
  int st = fv_setup(ctx, m, e0, first, &S);
  if (st) return st;
  sign = vm_calloc(ctx, (size_t)m->ne + 1, 1);
  act = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  mv = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  if (!sign || !act || !mv) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TET) continue;
    double x[12];
    cell_coords(m, e, x);
    sign[e] = mean_ratio(x) < 0 ? -1 : 1;
  }
  if (before) figures(&S, before);
  for (int sw = 0; sw < sweeps; sw++) {
    if (vm_ctx_interrupted(ctx)) {
      st = vm_error(ctx, VM_ERR_INTERRUPTED, "interrupted");
      goto done;
    }
    /* the free vertices of the tets that weigh: all of them at first, then
     * those of the tets around the vertices the sweep before moved and of
     * their neighbours (nothing else changed) */
    memset(act, 0, (size_t)m->nv);
    int64_t nact = 0;
    for (int64_t e = e0; e < m->ne; e++) {
      if (m->etype[e] != VM_TET) continue;
      /* the first sweep: every tet, or those at a seeded vertex or beside
       * one (the seed stands for a sweep before's moves) */
      int near = !sw && !seed;
      const uint8_t *by = sw ? mv : seed;
      uint8_t at = sw ? (uint8_t)sw : 1;
      const int32_t *c = m->conn + m->eoff[e];
      for (int i = 0; i < 4 && !near; i++) near = by[c[i]] == at;
      for (int j = 0; j < 4 && !near; j++) {
        int64_t b = S.nbr[6 * e + j];
        if (b < 0 || m->etype[b] != VM_TET) continue;
        const int32_t *d = m->conn + m->eoff[b];
        for (int i = 0; i < 4 && !near; i++) near = by[d[i]] == at;
      }
      if (!near || !tet_active(&S, e)) continue;
      for (int i = 0; i < 4; i++)
        if (!S.fixed[c[i]] && !act[c[i]]) act[c[i]] = 1, nact++;
    }
    if (!nact) break;
    double gain = 0, sum = 0;
    int64_t nmoved = 0;
    for (int64_t v = first; v < m->nv; v++) {
      if (!act[v]) continue;
      double p, g = relieve_vertex(&S, v, sign, local_quality(&S, v, sign), &p);
      sum += p;
      gain += g;
      if (g > 0) {
        nmoved++;
        *moved += !mv[v];
        mv[v] = (uint8_t)(sw + 1);
      }
    }
    vm_log(ctx, VM_LOG_DEBUG,
           "fill: finite-volume relief sweep %d: %lld vertices, %lld moved, penalty %.4g -> %.4g",
           sw + 1, (long long)nact, (long long)nmoved, sum, sum - gain);
    if (!nmoved || !(gain > 1e-2 * sum)) break;
  }
  figures(&S, after);
done:
  fv_release(ctx, &S);
  vm_free(ctx, sign);
  vm_free(ctx, act);
  vm_free(ctx, mv);
  return st;
}

int vm_fill_fv_relief(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int sweeps,
                      vm_fill_fv_figures *before, vm_fill_fv_figures *after, int64_t *moved) {
  return relief_run(ctx, m, e0, first, sweeps, NULL, before, after, moved);
}

/* ---------- flips ----------
 *
 * Where moving vertices cannot help (a tet whose four vertices are the
 * envelope's, or a vertex in a gap so narrow that every place for it
 * leaves a flat tet), the connectivity changes: for each fill tet that
 * fails one of checkMesh's checks (its determinant below 0.001, or one of
 * its faces beyond 70 degrees, skewness 4, weight 0.05 or volume ratio
 * 0.01), each of its six edges whose tets close a ring of 3..FILL_RING_MAX
 * fill tets is tried by edge removal (every triangulation of the ring's
 * polygon, 2(n - 2) tets for n; n = 3 is the 3-2 flip) and each of its
 * faces shared with another fill tet by the 2-3 flip. The candidates must
 * keep the ring's outer faces (every outer face of the new tets one of
 * the ring's, each once; the inner ones shared by two new tets), its
 * volume and the fill's orientation; their cells and faces (the outer
 * faces' neighbours as they are) are judged by checkMesh's measures: the
 * one taken has fewer failures than the ring (or as many and half its
 * penalty), no worst measure beyond a limit that was within it or worse
 * than it was, and no tet below min(0.1, the ring's least mean ratio).
 * In rounds: a ring's vertices wait for the next round once a ring around
 * them changed; tets in index order, so the same result on every run. */

/* rounds at most; the most tets a candidate has or a collapsed vertex's
 * star may hold */
enum { FV_FLIP_ROUNDS = 8, FV_CAND_MAX = 40 };

/* An outer face of a ring: its vertices sorted, the cell beyond (-1: a
 * boundary face), whether a new tet took it. */
typedef struct {
  int32_t v[3];
  int64_t nb;
  int used;
} ring_face;

/* The failures, penalty, worst measures and least mean ratio of a set of
 * cells and their faces. */
typedef struct {
  int fails;
  double pen, q;
  fv_worst W;
} fv_judge;

static void judge_init(fv_judge *J) {
  J->fails = 0;
  J->pen = 0;
  J->q = INFINITY;
  worst_init(&J->W);
}

static void judge_face(fv_judge *J, double deg, double skew, double w, double vr) {
  J->fails += deg > 70 || skew > 4 || w < 0.05 || vr < 0.01;
  J->pen += face_pen(deg, skew, w, vr);
  worst_face(&J->W, deg, skew, w, vr);
}

static void judge_det(fv_judge *J, double d) {
  J->fails += d < 0.001;
  J->pen += det_pen(d);
  J->W.det = fmin(J->W.det, d);
}

/* Is tet e a fill tet that fails a check? */
static int tet_fails(const fv_state *S, int64_t e) {
  if (e < S->e0 || e >= S->e1 || S->m->etype[e] != VM_TET) return 0;
  if (tet_det(S, e) < 0.001) return 1;
  for (int j = 0; j < 4; j++) {
    if (S->nbr[6 * e + j] < 0) continue;
    double deg, skew, w, vr;
    face_measures(S, e, j, &deg, &skew, &w, &vr);
    if (deg > 70 || skew > 4 || w < 0.05 || vr < 0.01) return 1;
  }
  return 0;
}

/* The ring's judge: its tets and their faces (a face between two of them
 * once); its outer faces into F (*nf), its volume and orientation. */
static void judge_ring(const fv_state *S, const int64_t *ring, int n, fv_judge *J, ring_face *F,
                       int *nf, double *vol) {
  judge_init(J);
  *nf = 0;
  *vol = 0;
  for (int r = 0; r < n; r++) {
    int64_t e = ring[r];
    double x[12];
    cell_coords(S->m, e, x);
    J->q = fmin(J->q, fabs(mean_ratio(x)));
    *vol += fabs(S->vol[e]);
    judge_det(J, tet_det(S, e));
    const int32_t *c = S->m->conn + S->m->eoff[e];
    for (int j = 0; j < 4; j++) {
      int64_t b = S->nbr[6 * e + j];
      int inner = 0;
      for (int k = 0; k < n && !inner; k++) inner = ring[k] == b;
      if (inner) {
        if (b < e) continue;
      } else {
        ring_face *f = &F[(*nf)++];
        for (int i = 0; i < 3; i++) f->v[i] = c[S->tf[j][i]];
        fill_sort3(f->v);
        f->nb = b;
        f->used = 0;
      }
      if (b < 0) continue;
      double deg, skew, w, vr;
      face_measures(S, e, j, &deg, &skew, &w, &vr);
      judge_face(J, deg, skew, w, vr);
    }
  }
}

/* The judge of the new tets t[0..k) (4 vertices each, oriented as the
 * fill) in place of a ring with outer faces F[0..nf) and volume vol0;
 * 0 if they do not fill the ring (an outer face not the ring's or taken
 * twice, an inner face not shared by two, another volume). */
static int judge_new(const fv_state *S, const int32_t (*t)[4], int k, ring_face *F, int nf,
                     double vol0, fv_judge *J) {
  const vm_mesh *m = S->m;
  double cc[FV_CAND_MAX][3], vol[FV_CAND_MAX], vsum = 0;
  judge_init(J);
  for (int i = 0; i < nf; i++) F[i].used = 0;
  for (int i = 0; i < k; i++) {
    double x[12];
    for (int a = 0; a < 4; a++) memcpy(x + 3 * a, m->xyz + 3 * (int64_t)t[i][a], 3 * sizeof *x);
    vm_cell_foam_centre(VM_TET, x, cc[i], &vol[i]);
    vsum += fabs(vol[i]);
    J->q = fmin(J->q, fabs(mean_ratio(x)));
  }
  if (!(J->q > 0) || !(fabs(vsum - vol0) <= 1e-9 * vol0)) return 0;
  /* per tet, per face: the other side (new tet i2 >= 0, or -2 - outer
   * face index) */
  int side[FV_CAND_MAX][4];
  for (int i = 0; i < k; i++) {
    for (int j = 0; j < 4; j++) {
      int32_t fv[3];
      for (int a = 0; a < 3; a++) fv[a] = t[i][S->tf[j][a]];
      fill_sort3(fv);
      int found = -1, hits = 0;
      for (int i2 = 0; i2 < k; i2++) {
        if (i2 == i) continue;
        for (int j2 = 0; j2 < 4; j2++) {
          int32_t gv[3];
          for (int a = 0; a < 3; a++) gv[a] = t[i2][S->tf[j2][a]];
          fill_sort3(gv);
          if (!memcmp(fv, gv, sizeof fv)) found = i2, hits++;
        }
      }
      if (hits > 1) return 0;
      if (hits == 1) {
        side[i][j] = found;
        continue;
      }
      int o = -1;
      for (int q = 0; q < nf && o < 0; q++)
        if (!memcmp(fv, F[q].v, sizeof fv)) o = q;
      if (o < 0 || F[o].used) return 0;
      F[o].used = 1;
      side[i][j] = -2 - o;
    }
  }
  for (int q = 0; q < nf; q++)
    if (!F[q].used) return 0;
  for (int i = 0; i < k; i++) {
    double s[4][3];
    int ns = 0;
    for (int j = 0; j < 4; j++) {
      const int64_t nb = side[i][j] >= 0 ? -1 : F[-2 - side[i][j]].nb;
      if (side[i][j] < 0 && nb < 0) continue; /* a boundary face */
      double y[9], c[3];
      for (int a = 0; a < 3; a++)
        memcpy(y + 3 * a, m->xyz + 3 * (int64_t)t[i][S->tf[j][a]], 3 * sizeof *y);
      vm_foam_face(y, 3, c, s[ns]);
      const double *cn = side[i][j] >= 0 ? cc[side[i][j]] : S->cc + 3 * nb;
      double vn = side[i][j] >= 0 ? vol[side[i][j]] : S->vol[nb];
      if (side[i][j] < 0 || side[i][j] > i) {
        double deg, skew, w, vr;
        tri_measures(y, c, s[ns], cc[i], cn, vol[i], vn, &deg, &skew, &w, &vr);
        judge_face(J, deg, skew, w, vr);
      }
      ns++;
    }
    judge_det(J, vm_foam_cell_determinant(ns, (const double(*)[3])s));
  }
  return 1;
}

/* Is judge N (the new tets) better than O (the ring's)? */
static int judge_better(const fv_judge *N, const fv_judge *O) {
  if (!worst_ok(&N->W, &O->W) || N->q < fmin(O->q, FV_QMIN)) return 0;
  return N->fails < O->fails || (N->fails == O->fails && N->fails > 0 && N->pen < 0.5 * O->pen);
}

/* Of two candidates both better than the ring, is N the better one
 * (fewer failures, else a lower penalty)? */
static int judge_less(const fv_judge *N, const fv_judge *B) {
  return N->fails < B->fails || (N->fails == B->fails && N->pen < B->pen);
}

/* The orientation of tet t (the sign of its mean ratio; 0 flat). */
static int tet_sign(const vm_mesh *m, const int32_t *t) {
  double x[12];
  for (int a = 0; a < 4; a++) memcpy(x + 3 * a, m->xyz + 3 * (int64_t)t[a], 3 * sizeof *x);
  double r = mean_ratio(x);
  return r > 0 ? 1 : r < 0 ? -1 : 0;
}

/* Tet t of orientation s turned to the fill's (sgn). */
static void orient_tet(int32_t *t, int s, int sgn) {
  if (s == sgn) return;
  int32_t x = t[0];
  t[0] = t[1];
  t[1] = x;
}

/* The tets of m around vertex u that hold vertex v too, into ring (at
 * most FILL_RING_MAX + 1); -1 if one is not a fill tet or is dead. */
static int edge_ring(const fv_state *S, const uint8_t *dead, int32_t u, int32_t v, int64_t *ring) {
  int n = 0;
  for (int64_t k = S->rp[u]; k < S->rp[u + 1]; k++) {
    int64_t e = S->ve[k];
    const int32_t *c = S->m->conn + S->m->eoff[e];
    int nv = vm_elem_nverts(S->m->etype[e]), hv = 0;
    for (int i = 0; i < nv; i++) hv |= c[i] == v;
    if (!hv) continue;
    if (S->m->etype[e] != VM_TET || e < S->e0 || e >= S->e1 || dead[e - S->e0] || n > FILL_RING_MAX)
      return -1;
    ring[n++] = e;
  }
  return n;
}

/* The best flip for failing tet e: the ring into ring (*nring), the new
 * tets into t (*nt); 0 if none is better. */
static int best_flip(const fv_state *S, const uint8_t *dead, int64_t e,
                     int (*tris)[42][FILL_RING_MAX - 2][3], const int *ntri, int64_t *ring,
                     int *nring, int32_t (*t)[4], int *nt) {
  const vm_mesh *m = S->m;
  const int32_t *c = m->conn + m->eoff[e];
  double x[12];
  cell_coords(m, e, x);
  int sgn = mean_ratio(x) < 0 ? -1 : 1;
  fv_judge best;
  judge_init(&best);
  int found = 0;
  ring_face F[4 * FV_CAND_MAX];
  int32_t cand[FV_CAND_MAX][4];
  /* edge removal */
  static const int ed[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (int q = 0; q < 6; q++) {
    int32_t u = c[ed[q][0]], v = c[ed[q][1]];
    int64_t rg[FILL_RING_MAX + 1];
    int n = edge_ring(S, dead, u, v, rg);
    if (n < 3 || n > FILL_RING_MAX) continue;
    /* the ring's other vertices, chained into a cycle w[0..n-1] */
    int64_t pr[FILL_RING_MAX][2], w[FILL_RING_MAX];
    int two = 1;
    for (int r = 0; r < n && two; r++) {
      const int32_t *d = m->conn + m->eoff[rg[r]];
      int h = 0;
      for (int i = 0; i < 4; i++)
        if (d[i] != u && d[i] != v && h < 2) pr[r][h++] = d[i];
      two = h == 2; /* not a tet with a repeated vertex */
    }
    if (!two || !fill_ring_cycle(n, (const int64_t(*)[2])pr, w)) continue;
    fv_judge O, N;
    int nf;
    double vol0;
    judge_ring(S, rg, n, &O, F, &nf, &vol0);
    for (int k = 0; k < ntri[n]; k++) {
      int ok = 1, nc = 0;
      for (int j = 0; j < n - 2 && ok; j++) {
        const int *tr = tris[n][k][j];
        int32_t a[4] = {(int32_t)w[tr[0]], (int32_t)w[tr[1]], (int32_t)w[tr[2]], u},
                b[4] = {(int32_t)w[tr[0]], (int32_t)w[tr[1]], (int32_t)w[tr[2]], v};
        /* u and v on either side of the triangle */
        int sa = tet_sign(m, a), sb = tet_sign(m, b);
        ok = sa * sb < 0;
        orient_tet(a, sa, sgn);
        orient_tet(b, sb, sgn);
        memcpy(cand[nc++], a, sizeof a);
        memcpy(cand[nc++], b, sizeof b);
      }
      if (!ok || !judge_new(S, (const int32_t(*)[4])cand, nc, F, nf, vol0, &N)) continue;
      if (!judge_better(&N, &O) || (found && !judge_less(&N, &best))) continue;
      best = N;
      found = 1;
      memcpy(t, cand, (size_t)nc * sizeof *cand);
      *nt = nc;
      memcpy(ring, rg, (size_t)n * sizeof *rg);
      *nring = n;
    }
  }
  /* 2-3 flips */
  for (int j = 0; j < 4; j++) {
    int64_t b = S->nbr[6 * e + j];
    if (b < S->e0 || b >= S->e1 || m->etype[b] != VM_TET || dead[b - S->e0]) continue;
    int32_t f[3], d = -1, g = -1;
    for (int i = 0; i < 3; i++) f[i] = c[S->tf[j][i]];
    for (int i = 0; i < 4; i++) {
      int in = 0;
      for (int a = 0; a < 3; a++) in |= c[i] == f[a];
      if (!in) d = c[i];
    }
    const int32_t *cb = m->conn + m->eoff[b];
    for (int i = 0; i < 4; i++) {
      int in = 0;
      for (int a = 0; a < 3; a++) in |= cb[i] == f[a];
      if (!in) g = cb[i];
    }
    if (d < 0 || g < 0) continue;
    int64_t rg[2] = {e, b};
    fv_judge O, N;
    int nf;
    double vol0;
    judge_ring(S, rg, 2, &O, F, &nf, &vol0);
    /* the segment from d to g through the face's inside: the three tets
     * around it turn the same way */
    int ok = 1, s0 = 0;
    for (int i = 0; i < 3 && ok; i++) {
      int32_t a[4] = {f[i], f[(i + 1) % 3], d, g};
      int sa = tet_sign(m, a);
      if (!i) s0 = sa;
      ok = sa != 0 && sa == s0;
      orient_tet(a, sa, sgn);
      memcpy(cand[i], a, sizeof a);
    }
    if (!ok || !judge_new(S, (const int32_t(*)[4])cand, 3, F, nf, vol0, &N)) continue;
    if (!judge_better(&N, &O) || (found && !judge_less(&N, &best))) continue;
    best = N;
    found = 1;
    memcpy(t, cand, 3 * sizeof *cand);
    *nt = 3;
    memcpy(ring, rg, sizeof rg);
    *nring = 2;
  }
  /* collapses: a free vertex p of e onto a neighbour q; the tets around
   * p holding q go, the others take q for p (so keep their orientation) */
  for (int i = 0; i < 4; i++) {
    int32_t p = c[i];
    if (S->fixed[p]) continue;
    int64_t n = S->rp[p + 1] - S->rp[p], rg[FV_CAND_MAX];
    if (n > FV_CAND_MAX) continue;
    int ok = 1;
    for (int64_t k = 0; k < n && ok; k++) {
      rg[k] = S->ve[S->rp[p] + k];
      ok = m->etype[rg[k]] == VM_TET && rg[k] >= S->e0 && rg[k] < S->e1 && !dead[rg[k] - S->e0];
    }
    if (!ok) continue;
    fv_judge O, N;
    int nf;
    double vol0;
    judge_ring(S, rg, (int)n, &O, F, &nf, &vol0);
    for (int64_t k = 0; k < n; k++) {
      const int32_t *d = m->conn + m->eoff[rg[k]];
      for (int a = 0; a < 4; a++) {
        int32_t q = d[a];
        if (q == p) continue;
        /* each neighbour once: at its first tet */
        int seen = 0;
        for (int64_t k2 = 0; k2 < k && !seen; k2++) {
          const int32_t *d2 = m->conn + m->eoff[rg[k2]];
          for (int b2 = 0; b2 < 4; b2++) seen |= d2[b2] == q;
        }
        if (seen) continue;
        int nc = 0, good = 1;
        for (int64_t k2 = 0; k2 < n && good; k2++) {
          const int32_t *d2 = m->conn + m->eoff[rg[k2]];
          int hq = 0;
          for (int b2 = 0; b2 < 4; b2++) hq |= d2[b2] == q;
          if (hq) continue;
          for (int b2 = 0; b2 < 4; b2++) cand[nc][b2] = d2[b2] == p ? q : d2[b2];
          good = tet_sign(m, cand[nc]) == sgn;
          nc++;
        }
        if (!good || !judge_new(S, (const int32_t(*)[4])cand, nc, F, nf, vol0, &N)) continue;
        if (!judge_better(&N, &O) || (found && !judge_less(&N, &best))) continue;
        best = N;
        found = 1;
        memcpy(t, cand, (size_t)nc * sizeof *cand);
        *nt = nc;
        memcpy(ring, rg, (size_t)n * sizeof *rg);
        *nring = (int)n;
      }
    }
  }
  return found;
}

/* m's elements from e0 on: the live ones of [e0, e0 + ntet) (dead[]),
 * then the new tets nw[0..nnew) (each taking its element fields from
 * parent[]), then the rest, in order; the elements before e0 stay. */
static int replace_tets(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t ntet, const uint8_t *dead,
                        const int32_t (*nw)[4], const int64_t *parent, int64_t nnew) {
  int64_t ndead = 0;
  for (int64_t i = 0; i < ntet; i++) ndead += dead[i];
  int64_t ne = m->ne - ndead + nnew, nconn = m->eoff[m->ne] - 4 * ndead + 4 * nnew;
  int64_t *from = vm_alloc_array(ctx, (size_t)ne + 1, sizeof *from); /* >= 0: an old element */
  uint8_t *ty = vm_alloc_array(ctx, (size_t)ne + 1, 1);
  int64_t *off = vm_alloc_array(ctx, (size_t)ne + 1, sizeof *off);
  int32_t *cn = vm_alloc_array(ctx, (size_t)nconn + 1, sizeof *cn);
  void **fd = vm_calloc(ctx, (size_t)m->nfield + 1, sizeof *fd);
  int st = VM_OK;
  if (!from || !ty || !off || !cn || !fd) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t n = 0;
  for (int64_t e = 0; e < e0 + ntet; e++)
    if (e < e0 || !dead[e - e0]) from[n++] = e;
  for (int64_t i = 0; i < nnew; i++) from[n++] = -1 - i;
  for (int64_t e = e0 + ntet; e < m->ne; e++) from[n++] = e;
  off[0] = 0;
  for (int64_t i = 0; i < ne; i++) {
    int64_t e = from[i];
    if (e >= 0) {
      int k = vm_elem_nverts(m->etype[e]);
      ty[i] = m->etype[e];
      memcpy(cn + off[i], m->conn + m->eoff[e], (size_t)k * sizeof *cn);
      off[i + 1] = off[i] + k;
    } else {
      ty[i] = VM_TET;
      memcpy(cn + off[i], nw[-1 - e], 4 * sizeof *cn);
      off[i + 1] = off[i] + 4;
    }
  }
  for (int f = 0; f < m->nfield; f++) {
    const vm_field *fl = &m->fields[f];
    if (fl->location != VM_FIELD_ELEMENT) continue;
    size_t isz = (size_t)fl->ncomp * (fl->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
    char *d = vm_alloc_array(ctx, (size_t)ne + 1, isz);
    if (!d) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    fd[f] = d;
    for (int64_t i = 0; i < ne; i++) {
      int64_t e = from[i] >= 0 ? from[i] : parent[-1 - from[i]];
      memcpy(d + (size_t)i * isz, (const char *)fl->data + (size_t)e * isz, isz);
    }
  }
  /* every allocation made: the mesh takes the new arrays */
  for (int f = 0; f < m->nfield; f++)
    if (fd[f]) {
      vm_free(ctx, m->fields[f].data);
      m->fields[f].data = fd[f];
      fd[f] = NULL;
    }
  vm_free(ctx, m->etype);
  vm_free(ctx, m->eoff);
  vm_free(ctx, m->conn);
  m->etype = ty;
  m->eoff = off;
  m->conn = cn;
  m->ne = m->ecap = ne;
  m->ccap = nconn;
  ty = NULL;
  off = NULL;
  cn = NULL;
done:
  if (fd)
    for (int f = 0; f < m->nfield; f++) vm_free(ctx, fd[f]);
  vm_free(ctx, fd);
  vm_free(ctx, from);
  vm_free(ctx, ty);
  vm_free(ctx, off);
  vm_free(ctx, cn);
  return st;
}

/* The vertices from `first` on that no element uses (a collapse's)
 * dropped, the others renumbered in order (with their flags, surface ids
 * and vertex fields, and mask if not NULL); *ndrop of them. */
static int drop_unused(vm_ctx *ctx, vm_mesh *m, int64_t first, uint8_t *mask, int64_t *ndrop) {
  *ndrop = 0;
  int64_t *to = vm_alloc_array(ctx, (size_t)m->nv + 1, sizeof *to);
  if (!to) return VM_ERR_NOMEM;
  for (int64_t v = 0; v < m->nv; v++) to[v] = v < first ? v : -1;
  for (int64_t i = 0; i < m->eoff[m->ne]; i++) to[m->conn[i]] = m->conn[i];
  int64_t n = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    if (to[v] < 0) continue;
    to[v] = n;
    if (n != v) {
      memcpy(m->xyz + 3 * n, m->xyz + 3 * v, 3 * sizeof *m->xyz);
      if (m->vflag) m->vflag[n] = m->vflag[v];
      if (mask) mask[n] = mask[v];
      if (m->vsurf) m->vsurf[n] = m->vsurf[v];
      for (int f = 0; f < m->nfield; f++) {
        vm_field *fl = &m->fields[f];
        if (fl->location != VM_FIELD_VERTEX) continue;
        size_t isz =
            (size_t)fl->ncomp * (fl->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
        memmove((char *)fl->data + (size_t)n * isz, (char *)fl->data + (size_t)v * isz, isz);
      }
    }
    n++;
  }
  for (int64_t i = 0; i < m->eoff[m->ne]; i++) m->conn[i] = (int32_t)to[m->conn[i]];
  *ndrop = m->nv - n;
  m->nv = n;
  vm_free(ctx, to);
  return VM_OK;
}

/* The flips; *touched (if touched is not NULL; freed by the caller): per
 * vertex of the mesh after, 1 on the vertices of every ring changed. */
static int flips_run(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int64_t *nflips,
                     uint8_t **touched) {
  *nflips = 0;
  if (touched) *touched = NULL;
  if (e0 < 0 || e0 > m->ne || first < 0)
    return vm_error(ctx, VM_ERR_ARG, "flips: first tet %lld or vertex %lld out of range",
                    (long long)e0, (long long)first);
  int(*tris)[42][FILL_RING_MAX - 2][3] = vm_alloc_array(ctx, FILL_RING_MAX + 1, sizeof *tris);
  if (!tris) return VM_ERR_NOMEM;
  int ntri[FILL_RING_MAX + 1] = {0};
  for (int n = 3; n <= FILL_RING_MAX; n++) ntri[n] = fill_polygon_triangulations(n, tris[n]);
  int st = VM_OK;
  uint8_t *tv = touched ? vm_calloc(ctx, (size_t)m->nv + 1, 1) : NULL;
  if (touched && !tv) {
    vm_free(ctx, tris);
    return VM_ERR_NOMEM;
  }
  int64_t first_flips = 0;
  for (int round = 0; round < FV_FLIP_ROUNDS && !st; round++) {
    if (vm_ctx_interrupted(ctx)) {
      st = vm_error(ctx, VM_ERR_INTERRUPTED, "interrupted");
      break;
    }
    /* the fill's tets: e0 up to the first element that is not a tet */
    int64_t ntet = 0;
    while (e0 + ntet < m->ne && m->etype[e0 + ntet] == VM_TET) ntet++;
    fv_state S;
    double t0 = fill_now();
    if ((st = fv_setup(ctx, m, e0, first, &S))) break;
    double t1 = fill_now();
    S.e1 = e0 + ntet;
    uint8_t *dead = vm_calloc(ctx, (size_t)ntet + 1, 1),
            *lock = vm_calloc(ctx, (size_t)m->nv + 1, 1);
    int32_t(*nw)[4] = NULL;
    int64_t *parent = NULL, nnew = 0, cap = 0, flips = 0, tried = 0;
    if (!dead || !lock) st = VM_ERR_NOMEM;
    for (int64_t e = e0; e < e0 + ntet && !st; e++) {
      if (dead[e - e0] || !tet_fails(&S, e)) continue;
      const int32_t *c = m->conn + m->eoff[e];
      if (lock[c[0]] || lock[c[1]] || lock[c[2]] || lock[c[3]]) continue;
      tried++;
      int64_t ring[FV_CAND_MAX];
      int32_t t[FV_CAND_MAX][4];
      int nring = 0, nt = 0;
      if (!best_flip(&S, dead, e, tris, ntri, ring, &nring, t, &nt)) continue;
      /* a ring with a locked vertex waits for the next round */
      int locked = 0;
      for (int r = 0; r < nring && !locked; r++) {
        const int32_t *d = m->conn + m->eoff[ring[r]];
        for (int i = 0; i < 4; i++) locked |= lock[d[i]];
      }
      if (locked) continue;
      if (nnew + nt > cap) {
        int64_t c2 = 2 * cap + 64;
        int32_t(*n2)[4] = vm_realloc(ctx, nw, (size_t)c2 * sizeof *nw);
        if (n2) nw = n2;
        int64_t *p2 = n2 ? vm_realloc(ctx, parent, (size_t)c2 * sizeof *p2) : NULL;
        if (!n2 || !p2) {
          st = VM_ERR_NOMEM;
          break;
        }
        parent = p2;
        cap = c2;
      }
      for (int i = 0; i < nt; i++) {
        memcpy(nw[nnew], t[i], sizeof t[i]);
        parent[nnew++] = ring[0];
      }
      for (int r = 0; r < nring; r++) {
        dead[ring[r] - e0] = 1;
        const int32_t *d = m->conn + m->eoff[ring[r]];
        for (int i = 0; i < 4; i++) lock[d[i]] = 1;
        if (tv)
          for (int i = 0; i < 4; i++) tv[d[i]] = 1;
      }
      flips++;
    }
    fv_release(ctx, &S);
    if (!st && flips)
      st = replace_tets(ctx, m, e0, ntet, dead, (const int32_t(*)[4])nw, parent, nnew);
    vm_log(ctx, VM_LOG_DEBUG,
           "fill: flips round %d: %lld failing tets tried, %lld flips (%.2f s, %.2f s of it the "
           "neighbours)",
           round + 1, (long long)tried, (long long)flips, fill_now() - t0, t1 - t0);
    vm_free(ctx, dead);
    vm_free(ctx, lock);
    vm_free(ctx, nw);
    vm_free(ctx, parent);
    *nflips += flips;
    /* rounds while they make at least a tenth of the first's flips */
    if (!round) first_flips = flips;
    if (!flips || 10 * flips < first_flips) break;
  }
  vm_free(ctx, tris);
  int64_t ndrop = 0;
  if (!st && *nflips && (st = drop_unused(ctx, m, first, tv, &ndrop)) == VM_OK && ndrop)
    vm_log(ctx, VM_LOG_DEBUG, "fill: flips: %lld vertices collapsed", (long long)ndrop);
  if (st || !touched)
    vm_free(ctx, tv);
  else
    *touched = tv;
  return st;
}

int vm_fill_fv_flips(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int64_t *nflips) {
  return flips_run(ctx, m, e0, first, nflips, NULL);
}

int fill_fv_flips_relief(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int sweeps,
                         int64_t *nflips, vm_fill_fv_figures *after, int64_t *moved) {
  uint8_t *touched = NULL;
  *moved = 0;
  int st = flips_run(ctx, m, e0, first, nflips, &touched);
  if (!st && *nflips) st = relief_run(ctx, m, e0, first, sweeps, touched, NULL, after, moved);
  vm_free(ctx, touched);
  return st;
}
