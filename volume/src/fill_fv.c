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

/* The measures of face j of tet e (an internal face): non-orthogonality
 * in degrees, skewness, weight, volume ratio. */
static void face_measures(const fv_state *S, int64_t e, int j, double *deg, double *skew, double *w,
                          double *vr) {
  int64_t b = S->nbr[6 * e + j];
  double y[12], c[3], s[3];
  tet_face(S, e, j, y, c, s);
  const double *cp = S->cc + 3 * e, *cn = S->cc + 3 * b;
  double cs = vm_foam_ortho_cos(c, s, cp, cn);
  *deg = acos(cs < -1 ? -1 : cs > 1 ? 1 : cs) * 180 / FV_PI;
  *skew = vm_foam_skew(y, 3, c, s, cp, cn);
  *w = vm_foam_weight(c, s, cp, cn);
  double va = fabs(S->vol[e]), vb = fabs(S->vol[b]);
  *vr = va < vb ? (vb > 0 ? va / vb : 0) : (va > 0 ? vb / va : 0);
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

static double face_penalty(const fv_state *S, int64_t e, int j, fv_worst *W) {
  double deg, skew, w, vr;
  face_measures(S, e, j, &deg, &skew, &w, &vr);
  if (W) {
    W->deg = fmax(W->deg, deg);
    W->skew = fmax(W->skew, skew);
    W->w = fmin(W->w, w);
    W->vr = fmin(W->vr, vr);
  }
  double p = sq_pos((deg - FV_ORTHO_DEG) / FV_ORTHO_SCALE) + sq_pos(skew - FV_SKEW);
  p += w > 0 ? sq_pos(FV_WEIGHT / w - 1) : 1e6;
  p += vr > 0 ? 4 * sq_pos(log10(FV_VOLRATIO / vr)) : 1e6;
  return isfinite(p) ? p : 1e6;
}

static double det_penalty(const fv_state *S, int64_t e, fv_worst *W) {
  double d = tet_det(S, e);
  if (W) W->det = fmin(W->det, d);
  return d > 0 ? 4 * sq_pos(log10(FV_DET / d)) : 1e6;
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

int vm_fill_fv_relief(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int sweeps,
                      vm_fill_fv_figures *before, vm_fill_fv_figures *after, int64_t *moved) {
  int st = VM_OK;
  fv_state S;
  memset(&S, 0, sizeof S);
  S.m = m;
  S.e0 = e0;
  S.first = first;
  *moved = 0;
  tface *T = NULL;
  int64_t nt = 0;
  int8_t *sign = NULL;
  uint8_t *act = NULL, *mv = NULL;
  S.nbr = vm_alloc_array(ctx, (size_t)m->ne * 6 + 1, sizeof *S.nbr);
  S.cc = vm_alloc_array(ctx, (size_t)m->ne * 3 + 1, sizeof *S.cc);
  S.vol = vm_alloc_array(ctx, (size_t)m->ne + 1, sizeof *S.vol);
  S.fixed = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  sign = vm_calloc(ctx, (size_t)m->ne + 1, 1);
  act = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  mv = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  if (!S.nbr || !S.cc || !S.vol || !S.fixed || !sign || !act || !mv) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if ((st = vm_mesh_vertex_elements(m, &S.rp, &S.ve))) goto done;
  int nfv[6];
  vm_elem_faces(VM_TET, S.tf, nfv);
  for (int64_t e = 0; e < m->ne; e++) {
    for (int j = 0; j < 6; j++) S.nbr[6 * e + j] = -1;
    if (vm_elem_dim(m->etype[e]) == 3) cell_update(&S, e);
  }
  /* the two cells of each interior triangle; a boundary face's vertices
   * stay (quads have no fill tet beside them) */
  if ((st = fill_tri_faces(ctx, m, &T, &nt))) goto done;
  for (int64_t i = 0; i < nt;) {
    int64_t k = i + 1;
    while (k < nt && fill_same_face(&T[k], &T[i])) k++;
    if (k - i == 2) {
      S.nbr[6 * (int64_t)T[i].cell + T[i].face] = T[i + 1].cell;
      S.nbr[6 * (int64_t)T[i + 1].cell + T[i + 1].face] = T[i].cell;
    } else if (k - i == 1) {
      for (int r = 0; r < 3; r++) S.fixed[T[i].v[r]] = 1;
    }
    i = k;
  }
  for (int64_t v = 0; v < first && v < m->nv; v++) S.fixed[v] = 1;
  /* a vertex moves only if every cell around it is a tet */
  for (int64_t v = first; v < m->nv; v++)
    for (int64_t k = S.rp[v]; k < S.rp[v + 1]; k++)
      if (m->etype[S.ve[k]] != VM_TET) S.fixed[v] = 1;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TET) continue;
    double x[12];
    cell_coords(m, e, x);
    sign[e] = mean_ratio(x) < 0 ? -1 : 1;
  }
  figures(&S, before);
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
      int near = !sw;
      const int32_t *c = m->conn + m->eoff[e];
      for (int i = 0; i < 4 && !near; i++) near = mv[c[i]] == sw;
      for (int j = 0; j < 4 && !near; j++) {
        int64_t b = S.nbr[6 * e + j];
        if (b < 0 || m->etype[b] != VM_TET) continue;
        const int32_t *d = m->conn + m->eoff[b];
        for (int i = 0; i < 4 && !near; i++) near = mv[d[i]] == sw;
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
  vm_free(ctx, S.nbr);
  vm_free(ctx, S.cc);
  vm_free(ctx, S.vol);
  vm_free(ctx, S.fixed);
  vm_free(ctx, S.rp);
  vm_free(ctx, S.ve);
  vm_free(ctx, T);
  vm_free(ctx, sign);
  vm_free(ctx, act);
  vm_free(ctx, mv);
  return st;
}
