/* prism/src/ortho.c: the non-orthogonality relief, the marching's last
 * step. A finite-volume solver measures a face by the angle between its
 * area vector and the line joining its two cells' centres (OpenFOAM's
 * checkMesh fails nothing below 70 degrees, and its schemes lose accuracy
 * and stability beyond). The marching's steps keep prisms valid and
 * shaped, not their centres aligned: where columns converge (a concave
 * junction, the upper layers over a wing root) or lean (tips, tails) the
 * lateral faces of neighbouring stacks reach 85 degrees.
 *
 * The relief moves the vertices of levels 1..nlev-2 (never the wall) one at
 * a time (level by level, in vertex order), across their column (a move
 * along the column would change the layer heights), and then those of the
 * outer surface at full thickness in its tangent plane, as one batch whose
 * crossings are queried after it (outer_pass): a few steps of gradient
 * descent on
 *
 *   E(x) = sum over the faces of the cells around x of max(0, c0 - cos)^2
 *        + sum over those cells of max(0, log10(d0 / det))^2,
 *
 * cos the face's non-orthogonality cosine and c0 that of
 * k.ortho_relief_deg, so faces within it weigh nothing; det the cell's
 * OpenFOAM determinant over its faces inside the hybrid mesh (checkMesh
 * -allGeometry fails a cell below 0.001: a thin cell sheared over a
 * stretched triangle, the first layers where a trailing edge's columns
 * fan out, the squeezed stacks of a concave junction) and d0
 * k.det_relief_limit, a margin above it. A step is kept only
 * if every prism around the vertex keeps its corner tets positive and its
 * quality above min(k.ortho_qmin, k.ortho_relief_qshare of its quality
 * before), no face around it becomes more skewed than k.skew_limit (or than
 * it was), its worst face gets no worse (or stays within
 * k.ortho_relief_active_deg), no more of its faces fail OpenFOAM's
 * face-tet decomposition and no more of its cells are concave or fail a
 * 3-tet split (vm_prism_split_check) and none that fails one fails it by
 * more (the sum of its split tets' squared negative det ratios: a cell
 * the relief twisted further was one the split repair could no longer
 * untwist, on plane.stl), their
 * smallest interpolation weight stays above k.ortho_relief_wmin (or where
 * it was), the ratios of the column's successive heights stay within
 * [G / b, b G] (G the growth ratio, b k.ortho_relief_growth_band; or where
 * they were), a smooth column's first side edge stays within
 * k.tilt_limit_deg of its normal (or its tilt before), and no more of
 * its cells have a determinant below 0.001 and their least stays above
 * it (or where it was). Vertices are visited where a face of their cells is beyond
 * k.ortho_relief_active_deg or a cell's determinant below d0; sweeps
 * repeat while one lowers the count of faces beyond 70 degrees and cells
 * below 0.001 by more than k.ortho_relief_gain of it. Each
 * level is visited in vertex order; levels five apart, which share
 * nothing, run on separate threads, so the result is the same on every run
 * and thread count. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "state.h"
#include "varmesh/quality.h"

/* Levels this far apart are relieved at the same time (see the sweep). */
#define PR_ORTHO_STRIDE 5

/* The cell across face f (0 bottom, 1 top, 2 + i the side over edge i) of
 * cell (t, k) in *u, *j; 0 where the face is on the boundary (wall, outer
 * surface, an open edge). */
static int across(const vm_prism *p, const int32_t *nbt, int64_t t, int k, int f, int64_t *u,
                  int *j) {
  int nl = p->nlev - 1;
  if (f == 0) {
    *u = t;
    *j = k - 1;
    return k > 0;
  }
  if (f == 1) {
    *u = t;
    *j = k + 1;
    return k + 1 < nl;
  }
  *u = nbt[3 * t + f - 2];
  *j = k;
  return *u >= 0;
}

/* Face f of prism x into y; its vertex count. */
static int face_of(const double *x, int f, double *y) {
  int n = pr_prism_faces[f][3] < 0 ? 3 : 4;
  for (int i = 0; i < n; i++) memcpy(y + 3 * i, x + 3 * pr_prism_faces[f][i], 3 * sizeof *y);
  return n;
}

/* The relief's penalty of a cell of determinant d below the limit dl:
 * (log10(dl / d))^2 (a degenerate cell: that of 1e-12). */
static double det_penalty(double d, double dl) {
  if (d >= dl) return 0;
  double r = log10(dl / (d > 1e-12 ? d : 1e-12));
  return r * r;
}

/* Each wall triangle's neighbour over each of its edges (-1: open). */
static void edge_neighbours(const vm_prism *p, int32_t *nbt) {
  for (int64_t t = 0; t < p->nt; t++)
    for (int i = 0; i < 3; i++) nbt[3 * t + i] = (int32_t)pr_tri_across(p, t, i);
}

/* The relief's view of the layer's faces: every cell's centre, and for
 * the internal faces a cell owns (its top, its sides towards later
 * triangles) which are beyond the active angle (bit f of bad[c] for face f)
 * and how many beyond 70 degrees (o70[c]), and the worst owned cosine
 * (cw[c]). Kept up to date cell by cell as vertices move. */
typedef struct facemap {
  double *cc; /* 3 nt nl: cell centres, cell c = t nl + k */
  uint8_t *bad;
  uint8_t *o70;
  double *cw;
  double *det;   /* nt nl: each cell's OpenFOAM determinant (pr_foam_cell_det) */
  uint8_t *mark; /* nt nl scratch: cells to update */
  double qworst; /* the least scaled Jacobian of the stack when the split
                    repair starts: the repair lowers no cell below it (the
                    figure the report gives) */
} facemap;

/* The determinant of cell (t, k) from its faces' area vectors fs: its
 * faces inside the hybrid mesh are all but the wall under layer 0 and the
 * sides over open wall edges (nbt: edge_neighbours). */
static double prism_det(const int32_t *nbt, int64_t t, int k, const double (*fs)[3]) {
  int in[5] = {k > 0, 1, nbt[3 * t] >= 0, nbt[3 * t + 1] >= 0, nbt[3 * t + 2] >= 0};
  return pr_foam_cell_det(fs, in);
}

/* Cell c = (t, k)'s centre and determinant into the facemap. */
static void cell_update(const vm_prism *p, const int32_t *nbt, facemap *fm, int64_t t, int k) {
  int64_t c = t * (p->nlev - 1) + k;
  double x[18], fc[5][3], fs[5][3];
  pr_prism_at(p, p->lev, t, k, x);
  pr_foam_cell_faces(x, fm->cc + 3 * c, fc, fs);
  fm->det[c] = prism_det(nbt, t, k, (const double(*)[3])fs);
}

/* The cells around level k of column v (layers k - 1 and k of v's
 * triangles) and, for each of their faces, the cell across: another cell
 * around (its centre moves with the vertex) or a fixed one, whose centre
 * the facemap keeps. */
typedef struct hood {
  int n;                      /* cells: 2 deg */
  int64_t t[2 * PR_RING_MAX]; /* triangle and layer of each */
  int j[2 * PR_RING_MAX];
  int nb[2 * PR_RING_MAX][5];           /* per face: -1 boundary, -2 fixed, else a cell around */
  const double *cn[2 * PR_RING_MAX][5]; /* a fixed neighbour's centre (in the facemap) */
} hood;

static void make_hood(const vm_prism *p, const int32_t *nbt, const facemap *fm, int64_t v, int k,
                      hood *h) {
  h->n = 0;
  for (int64_t m = p->vt_off[v]; m < p->vt_off[v + 1]; m++)
    for (int j = k - 1; j <= k; j++) {
      if (j < 0 || j >= p->nlev - 1) continue; /* the outer level: its one layer */
      h->t[h->n] = p->vt[m];
      h->j[h->n] = j;
      h->n++;
    }
  for (int c = 0; c < h->n; c++)
    for (int f = 0; f < 5; f++) {
      int64_t u;
      int jn;
      if (!across(p, nbt, h->t[c], h->j[c], f, &u, &jn)) {
        h->nb[c][f] = -1;
        continue;
      }
      h->nb[c][f] = -2;
      for (int d = 0; d < h->n && h->nb[c][f] == -2; d++)
        if (h->t[d] == u && h->j[d] == jn) h->nb[c][f] = d;
      if (h->nb[c][f] == -2) h->cn[c][f] = fm->cc + 3 * (u * (p->nlev - 1) + jn);
    }
}

/* What the relief weighs around the vertex. */
typedef struct around {
  double e;                   /* E: the penalty of the faces of the cells around */
  double cmin;                /* the worst face's non-orthogonality cosine */
  double skew;                /* the largest skewness of those faces (boundary faces too) */
  double wmin;                /* their smallest interpolation weight */
  int badtets;                /* those failing the face-tet decomposition */
  int splitbad;               /* cells not positive in every 3-tet split */
  double splitpen;            /* the sum of q^2 over the cells' split tets with q < 0 */
  int n70;                    /* faces beyond 70 degrees (counted twice
                                 between two cells around) */
  int concave;                /* cells concave as checkMesh sees them */
  double q[2 * PR_RING_MAX];  /* each cell's quality: the lesser of its scaled
                                Jacobian and its quadrature quality (-1 if
                                either is not positive) */
  double sj[2 * PR_RING_MAX]; /* each cell's scaled Jacobian (corner tets) */
  int ndet;                   /* cells with a determinant below checkMesh's limit */
  double detmin;              /* the least determinant of the cells */
} around;

/* The split penalty of prism x: the sum over its tets of two bottom and
 * two top vertices (vm_prism_split_check) of max(0, m - q)^2, q their
 * det / edge-length product, m = k.split_margin. */
static double split_penalty(const vm_prism *p, const double *x) {
  double q[6], e = 0;
  vm_prism_split_check(x, q);
  for (int j = 0; j < 6; j++)
    if (q[j] < p->k.split_margin) e += (p->k.split_margin - q[j]) * (p->k.split_margin - q[j]);
  return e;
}

/* The figures of hood h at the current coordinates: E alone (qfloor NULL,
 * for the gradient), or everything, stopping at the first cell below its
 * floor qfloor[c] (returns 0; else 1). With `split`, E is the split
 * penalty of the cells (split_penalty) instead of the faces'. */
static int eval_around(const vm_prism *p, const hood *h, double c0, const double *qfloor, int split,
                       around *a) {
  const int full = qfloor != NULL;
  double x[2 * PR_RING_MAX][18], cc[2 * PR_RING_MAX][3];
  double fc[2 * PR_RING_MAX][5][3], fs[2 * PR_RING_MAX][5][3];
  a->e = 0;
  a->cmin = 1;
  a->skew = 0;
  a->wmin = 0.5;
  a->badtets = 0;
  a->concave = 0;
  a->splitbad = 0;
  a->splitpen = 0;
  a->n70 = 0;
  a->ndet = 0;
  a->detmin = INFINITY;
  const double c70 = cos(70 * PR_PI / 180);
  for (int c = 0; c < h->n; c++) {
    pr_prism_at(p, p->lev, h->t[c], h->j[c], x[c]);
    if (full) {
      int inv;
      double q = pr_prism_corner_quality(x[c], &inv), qn = pr_prism_quality(x[c]);
      a->sj[c] = inv ? -1 : q;
      q = inv || !(qn > 0) ? -1 : q < qn ? q : qn;
      a->q[c] = q;
      if (!(q >= qfloor[c])) return 0;
      /* one split check: the count of failing cells and how far they fail */
      double qs[6];
      a->splitbad += vm_prism_split_check(x[c], qs) > 0;
      for (int j = 0; j < 6; j++)
        if (qs[j] < 0) a->splitpen += qs[j] * qs[j];
    }
    if (split) a->e += split_penalty(p, x[c]);
    pr_foam_cell_faces(x[c], cc[c], fc[c], fs[c]);
    /* the cell's determinant: its faces inside the hybrid mesh (every
     * face but a boundary one below or beside it) */
    int in[5];
    for (int f = 0; f < 5; f++) in[f] = f == 1 || h->nb[c][f] != -1;
    double d = pr_foam_cell_det((const double(*)[3])fs[c], in);
    a->ndet += d < PR_FOAM_DET_MIN;
    a->detmin = d < a->detmin ? d : a->detmin;
    if (!split) a->e += det_penalty(d, p->k.det_relief_limit);
    if (full)
      a->concave +=
          pr_foam_cell_concave((const double(*)[3])fc[c], (const double(*)[3])fs[c], cc[c]);
  }
  for (int c = 0; c < h->n; c++)
    for (int f = 0; f < 5; f++) {
      if (h->nb[c][f] == -1) {
        /* the wall, the outer surface and a half model's faces on its
         * symmetry plane: their skewness only */
        if (full) {
          double y[12];
          int n = face_of(x[c], f, y);
          double s = pr_foam_boundary_skew(y, n, cc[c]);
          a->skew = s > a->skew ? s : a->skew;
        }
        continue;
      }
      const double *cn = h->nb[c][f] >= 0 ? cc[h->nb[c][f]] : h->cn[c][f];
      double cs = vm_foam_ortho_cos(fc[c][f], fs[c][f], cc[c], cn);
      if (full) {
        double y[12];
        int n = face_of(x[c], f, y);
        double s = vm_foam_skew(y, n, fc[c][f], fs[c][f], cc[c], cn);
        a->skew = s > a->skew ? s : a->skew;
        double w = vm_foam_weight(fc[c][f], fs[c][f], cc[c], cn);
        a->wmin = w < a->wmin ? w : a->wmin;
        a->badtets += !pr_foam_face_tets_ok(y, n, fc[c][f], fs[c][f], cc[c], cn);
      }
      a->cmin = cs < a->cmin ? cs : a->cmin;
      a->n70 += cs < c70;
      if (cs < c0 && !split) a->e += (c0 - cs) * (c0 - cs);
    }
  return 1;
}

/* Centres of the marked cells (mark[c] & 1; all if mark is NULL), then
 * the faces owned by the cells marked 2 (all if NULL). */
static void update_faces(const vm_prism *p, const int32_t *nbt, double cact, facemap *fm,
                         const uint8_t *mark) {
  int64_t nt = p->nt;
  int nl = p->nlev - 1;
  const double c70 = cos(70 * PR_PI / 180);
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < nt * nl; c++) {
    if (mark && !(mark[c] & 1)) continue;
    cell_update(p, nbt, fm, c / nl, (int)(c % nl));
  }
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < nt * nl; c++) {
    if (mark && !(mark[c] & 2)) continue;
    int64_t t = c / nl;
    int k = (int)(c % nl);
    double x[18], worst = 1;
    pr_prism_at(p, p->lev, t, k, x);
    uint8_t b = 0, n70 = 0;
    for (int f = 1; f < 5; f++) {
      int64_t u;
      int j;
      if (!across(p, nbt, t, k, f, &u, &j) || (f >= 2 && u < t)) continue;
      double y[12];
      int n = face_of(x, f, y);
      double cs = pr_foam_ortho_cos(y, n, fm->cc + 3 * c, fm->cc + 3 * (u * nl + j));
      n70 += cs < c70;
      worst = cs < worst ? cs : worst;
      if (cs < cact) b |= (uint8_t)(1 << f);
    }
    fm->bad[c] = b;
    fm->o70[c] = n70;
    fm->cw[c] = worst;
  }
}

/* Faces beyond 70 degrees in *n70, the worst cosine in *cmin, cells
 * with a determinant below checkMesh's limit in *ndet. */
static void face_totals(const vm_prism *p, const facemap *fm, int64_t *n70, double *cmin,
                        int64_t *ndet) {
  int64_t n = p->nt * (p->nlev - 1), over = 0, nd = 0;
  double worst = 1;
#pragma omp parallel for schedule(static) reduction(+ : over, nd) reduction(min : worst)
  for (int64_t c = 0; c < n; c++) {
    over += fm->o70[c];
    nd += fm->det[c] < PR_FOAM_DET_MIN;
    worst = fm->cw[c] < worst ? fm->cw[c] : worst;
  }
  *n70 = over;
  *cmin = worst;
  *ndet = nd;
}

/* The vertices (v, k), k in 1..nl, of the two cells on every face beyond
 * the active angle, marked in act (nw per level). */
static void activate(const vm_prism *p, const int32_t *nbt, const facemap *fm, uint8_t *act) {
  int64_t nt = p->nt, nw = p->nw;
  int nl = p->nlev - 1;
  memset(act, 0, (size_t)(nw * (nl + 1)));
  for (int64_t c = 0; c < nt * nl; c++) {
    int64_t t = c / nl;
    int k = (int)(c % nl);
    if (fm->det[c] < p->k.det_relief_limit)
      for (int i = 0; i < 3; i++)
        for (int l = k; l <= k + 1; l++)
          if (l >= 1) act[(size_t)l * nw + p->tri[3 * t + i]] = 1;
    if (!fm->bad[c]) continue;
    for (int f = 1; f < 5; f++) {
      if (!(fm->bad[c] >> f & 1)) continue;
      int64_t u;
      int j;
      across(p, nbt, t, k, f, &u, &j);
      const int64_t cells[2][2] = {{t, k}, {u, j}};
      for (int s = 0; s < 2; s++)
        for (int i = 0; i < 3; i++)
          for (int l = (int)cells[s][1]; l <= cells[s][1] + 1; l++)
            if (l >= 1 && l <= nl) act[(size_t)l * nw + p->tri[3 * cells[s][0] + i]] = 1;
    }
  }
}

/* After vertices moved (moved: nw per level; relieve kept the centres of
 * the cells around them current): the faces of those cells, owned by them
 * or by the cells below and beside them, are measured again (bit 2). */
static void refresh(const vm_prism *p, const int32_t *nbt, double cact, facemap *fm,
                    const uint8_t *moved) {
  int64_t nt = p->nt, nw = p->nw;
  int nl = p->nlev - 1;
  memset(fm->mark, 0, (size_t)(nt * nl));
  for (int k = 1; k <= nl; k++)
    for (int64_t v = 0; v < nw; v++) {
      if (!moved[(size_t)k * nw + v]) continue;
      for (int64_t m = p->vt_off[v]; m < p->vt_off[v + 1]; m++)
        for (int j = k - 1; j <= k && j < nl; j++) fm->mark[p->vt[m] * nl + j] |= 1;
    }
  for (int64_t c = 0; c < nt * nl; c++) {
    if (!(fm->mark[c] & 1)) continue;
    int64_t t = c / nl;
    int k = (int)(c % nl);
    fm->mark[c] = (uint8_t)(fm->mark[c] | 2) & (uint8_t)~1u;
    for (int f = 0; f < 5; f++) {
      int64_t u;
      int j;
      if (across(p, nbt, t, k, f, &u, &j)) fm->mark[u * nl + j] |= 2;
    }
  }
  update_faces(p, nbt, cact, fm, fm->mark);
}

/* The smallest and largest ratio of successive side-edge lengths of
 * column v over the edges that level k ends or starts. */
static void growth_around(const vm_prism *p, int64_t v, int k, double *lo, double *hi) {
  size_t lsz = (size_t)(3 * p->nw);
  int nl = p->nlev - 1;
  double len[4];
  /* len[i]: the edge from level k - 2 + i to k - 1 + i (0: none) */
  for (int i = 0; i < 4; i++) {
    int a = k - 2 + i;
    len[i] = a >= 0 && a + 1 <= nl
                 ? vm_dist3(p->lev + a * lsz + 3 * v, p->lev + (a + 1) * lsz + 3 * v)
                 : 0;
  }
  *lo = INFINITY;
  *hi = 0;
  for (int i = 0; i + 1 < 4; i++) {
    if (!(len[i] > 0) || !(len[i + 1] > 0)) continue;
    double r = len[i + 1] / len[i];
    *lo = r < *lo ? r : *lo;
    *hi = r > *hi ? r : *hi;
  }
}

/* Is column v, its outer vertex at x, at full thickness? */
static int at_full(const vm_prism *p, int64_t v, const double *x) {
  return vm_dist3(x, p->wall + 3 * v) >= (1 - p->o.full_tol) * p->tv[v];
}

/* The smallest angle (degrees) of the outer triangles around column v. */
static double outer_min_angle(const vm_prism *p, int64_t v) {
  const double *L = p->lev + (size_t)(p->nlev - 1) * 3 * p->nw;
  double mn = 180;
  for (int64_t m = p->vt_off[v]; m < p->vt_off[v + 1]; m++) {
    const int32_t *c = p->tri + 3 * (int64_t)p->vt[m];
    for (int i = 0; i < 3; i++) {
      const double *a = L + 3 * (int64_t)c[i], *b = L + 3 * (int64_t)c[(i + 1) % 3],
                   *d = L + 3 * (int64_t)c[(i + 2) % 3];
      double u[3], w[3];
      vm_sub3(b, a, u);
      vm_sub3(d, a, w);
      double lu = vm_norm3(u), lw = vm_norm3(w);
      if (!(lu > 0) || !(lw > 0)) return 0;
      double cs = vm_dot3(u, w) / (lu * lw);
      double ang = acos(cs > 1 ? 1 : cs < -1 ? -1 : cs) * 180 / PR_PI;
      mn = ang < mn ? ang : mn;
    }
  }
  return mn;
}

/* One relief step at level k of column v; 1 if it moved. With `split`
 * the step lowers the split penalty of the cells around instead of their
 * faces' (split_repair), under the same guards; without `query` an outer
 * vertex's step is kept without querying the single layer's crossings
 * (the caller queries once for a batch of them, and undoes the batch if
 * it crosses). */
static int relieve(vm_prism *p, const int32_t *nbt, facemap *fm, const double *qinit, int64_t v,
                   int k, double c0, double cact, int split, int query) {
  const pr_params *kp = &p->k;
  size_t lsz = (size_t)(3 * p->nw);
  int nl = p->nlev - 1, top = k == nl; /* top: an outer vertex (the split repair) */
  double *xv = p->lev + k * lsz + 3 * v;
  const double *below = p->lev + (k - 1) * lsz + 3 * v,
               *above = top ? NULL : p->lev + (k + 1) * lsz + 3 * v;
  int64_t deg = p->vt_off[v + 1] - p->vt_off[v];
  if (deg > PR_RING_MAX) return 0;
  hood h;
  around a0, a1;
  make_hood(p, nbt, fm, v, k, &h);
  /* each cell's floor: from its quality before the relief, so steps do
   * not wear it down (the split repair may go further: a cell a split
   * inverts fails a solver, a poorer one does not) */
  double qfloor[2 * PR_RING_MAX];
  for (int c = 0; c < h.n; c++) {
    double qi = qinit[h.t[c] * (p->nlev - 1) + h.j[c]];
    double q =
        split ? fmax(kp->split_qshare * qi, fmin(qi, fm->qworst)) : kp->ortho_relief_qshare * qi;
    qfloor[c] = q < kp->ortho_qmin ? q : kp->ortho_qmin;
  }
  /* an invalid neighbourhood is left to the verifier */
  if (!eval_around(p, &h, c0, qfloor, split, &a0) || !(a0.e > 0)) return 0;
  double skew_max = a0.skew > kp->skew_limit ? a0.skew : kp->skew_limit;
  /* the relief keeps the worst face within its active angle (or where it
   * was); the split repair lets it go to checkMesh's 70 degrees, or a
   * fraction of a degree past where it was beyond, with no more faces
   * beyond 70 (a cell a split inverts fails a solver outright; a face at
   * 68 degrees does not) */
  const double c70 = cos(70 * PR_PI / 180);
  double cfloor = split ? fmin(a0.cmin - kp->split_cos_slack, c70) : fmin(a0.cmin, cact);
  double wfloor = a0.wmin < kp->ortho_relief_wmin ? a0.wmin : kp->ortho_relief_wmin;
  /* nor may the column's heights leave the growth band (or their ratios
   * before, where outside it) */
  double glo, ghi, band = kp->ortho_relief_growth_band;
  growth_around(p, v, k, &glo, &ghi);
  glo = glo < p->rep.growth / band ? glo : p->rep.growth / band;
  ghi = ghi > p->rep.growth * band ? ghi : p->rep.growth * band;
  double tilt_max = 0;
  if (k == 1 && p->smooth[v]) {
    double t0 = pr_tilt_deg(p->wall + 3 * v, xv, p->vnrm + 3 * v);
    tilt_max = t0 > kp->tilt_limit_deg ? t0 : kp->tilt_limit_deg;
  }
  /* the column's course here: moves go across it (an outer vertex: in
   * the outer surface's tangent plane, its area-weighted normal) */
  double tc[3], x0[3], g[3], lt;
  if (top) {
    tc[0] = tc[1] = tc[2] = 0;
    for (int64_t m = p->vt_off[v]; m < p->vt_off[v + 1]; m++) {
      const int32_t *c = p->tri + 3 * (int64_t)p->vt[m];
      const double *a = p->lev + k * lsz + 3 * (int64_t)c[0],
                   *b = p->lev + k * lsz + 3 * (int64_t)c[1],
                   *d = p->lev + k * lsz + 3 * (int64_t)c[2];
      double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
             e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]}, n[3];
      vm_cross3(e1, e2, n);
      for (int r = 0; r < 3; r++) tc[r] += n[r];
    }
    double ln = vm_norm3(tc);
    if (!(ln > 0)) return 0;
    for (int r = 0; r < 3; r++) tc[r] /= ln;
    lt = vm_dist3(xv, below);
  } else {
    for (int r = 0; r < 3; r++) tc[r] = above[r] - below[r];
    lt = vm_norm3(tc);
    if (!(lt > 0)) return 0;
    for (int r = 0; r < 3; r++) tc[r] /= lt;
  }
  /* a length scale: the shorter of the wall's edges here and the column's
   * span over the two cells */
  double hloc = p->elen[v] < lt ? p->elen[v] : lt;
  double fd = kp->ortho_relief_fd * hloc;
  memcpy(x0, xv, sizeof x0);
  for (int r = 0; r < 3; r++) {
    xv[r] = x0[r] + fd;
    eval_around(p, &h, c0, NULL, split, &a1);
    g[r] = (a1.e - a0.e) / fd;
    xv[r] = x0[r];
  }
  /* a column in a half model's symmetry plane moves in it: across its
   * course there (an outer vertex: in the plane and the outer surface's
   * tangent plane, which the mirror image makes symmetric) */
  int insym = pr_on_sym(p, v);
  if (insym) {
    tc[p->sym_ax] = 0;
    if (vm_normalize3(tc) == 0) return 0;
  }
  double gt = vm_dot3(g, tc);
  for (int r = 0; r < 3; r++) g[r] -= gt * tc[r];
  if (insym) g[p->sym_ax] = 0;
  double lg = vm_norm3(g);
  if (!(lg > 0)) return 0;
  double step = kp->ortho_relief_step * hloc / lg;
  /* the split repair tries a second direction where the gradient's is
   * refused: onto the segment between the levels below and above, at the
   * same share of the column (a kink straightened: where a twist sits in
   * one cell, this hands part of it to the next) */
  double kink[3];
  if (!top) {
    double a = vm_dist3(x0, below), b = vm_dist3(above, x0), f = a + b > 0 ? a / (a + b) : 0.5;
    for (int r = 0; r < 3; r++) kink[r] = x0[r] - (below[r] + f * (above[r] - below[r]));
  }
  /* the relief keeps the outer triangles' angles (the fill's tets grow
   * from them) */
  double afloor = -1;
  if (top && !split) {
    double a0 = outer_min_angle(p, v);
    afloor = a0 < kp->ortho_relief_outer_angle ? a0 : kp->ortho_relief_outer_angle;
  }
  int nb = split ? 2 * kp->ortho_relief_backtracks : kp->ortho_relief_backtracks;
  for (int b = 0; b < (split && !top ? 2 * nb : nb); b++, step *= 0.5) {
    if (b == nb) step = 1;
    const double *dg = b < nb ? g : kink;
    for (int r = 0; r < 3; r++) xv[r] = x0[r] - step * dg[r];
    /* nothing else reaches a half model's symmetry plane */
    if (!insym && !pr_sym_inside(p, xv)) continue;
    if (!eval_around(p, &h, c0, qfloor, split, &a1)) continue;
    if (!(a1.e < a0.e) || a1.skew > skew_max || a1.cmin < cfloor || a1.badtets > a0.badtets ||
        a1.concave > a0.concave || a1.wmin < wfloor || a1.splitbad > a0.splitbad ||
        a1.ndet > a0.ndet || a1.detmin < fmin(a0.detmin, PR_FOAM_DET_MIN) ||
        (!split && a1.splitpen > a0.splitpen) || (split && a1.n70 > a0.n70))
      continue;
    /* the split repair lowers no cell's scaled Jacobian below the stack's
     * least before the relief (or below its own, where lower) */
    int sjdown = 0;
    for (int c = 0; split && c < h.n && !sjdown; c++)
      sjdown = a1.sj[c] < fmin(a0.sj[c], fm->qworst);
    if (sjdown) continue;
    if (tilt_max > 0 && pr_tilt_deg(p->wall + 3 * v, xv, p->vnrm + 3 * v) > tilt_max) continue;
    double lo, hi;
    growth_around(p, v, k, &lo, &hi);
    if (lo < glo || hi > ghi) continue;
    if (afloor >= 0 && outer_min_angle(p, v) < afloor) continue;
    if (top) {
      /* a column at full thickness stays there */
      if (at_full(p, v, x0) && !at_full(p, v, xv)) continue;
      /* the outer surface may cross nothing it did not cross before: the
       * single layer's faces (its top is the outer level) queried again
       * around the move */
      double *lv = p->layer->xyz + 3 * (p->nw + v), keep[3];
      int64_t np;
      memcpy(keep, lv, sizeof keep);
      memcpy(lv, xv, sizeof keep);
      if (query && (pr_layer_intersections(p, NULL, &np) < 0 || np > p->rep.intersections)) {
        memcpy(lv, keep, sizeof keep);
        continue;
      }
    }
    /* the cells around keep their centres and determinants current for the
     * next hoods */
    for (int c = 0; c < h.n; c++) cell_update(p, nbt, fm, h.t[c], h.j[c]);
    return 1;
  }
  memcpy(xv, x0, sizeof x0);
  return 0;
}

/* Outer vertex v (level nl) back at x: in the levels, in the single
 * layer, and the centres and determinants of its top-layer cells. */
static void put_outer(vm_prism *p, const int32_t *nbt, facemap *fm, int64_t v, const double *x) {
  int nl = p->nlev - 1;
  memcpy(p->lev + (size_t)nl * 3 * p->nw + 3 * v, x, 3 * sizeof *x);
  memcpy(p->layer->xyz + 3 * (p->nw + v), x, 3 * sizeof *x);
  for (int64_t m = p->vt_off[v]; m < p->vt_off[v + 1]; m++)
    cell_update(p, nbt, fm, p->vt[m], nl - 1);
}

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

/* The split repair, after the relief's sweeps: the vertices of levels
 * 1..nl-1 of every prism not positive in all of its 3-tet splits (a tet of
 * two bottom and two top vertices with det <= 0: a twisted or sheared
 * thin cell) take steps that lower the split penalty of the cells around
 * them (relieve with `split`, the relief's guards, and no cell around
 * newly failing a split; a top-layer cell's outer vertices too, in the
 * outer surface's tangent plane, kept only if the single layer's faces
 * cross nothing new), in rounds, each in level and vertex order, until
 * none is left, a round moves nothing or k.split_stall_rounds rounds
 * bring no new least count (k.split_rounds at most). After
 * the first, a round looks only at the failing cells and those around the
 * vertices that moved. act and moved are work arrays (nw per level).
 * Serial: the cells are few. */
static int split_repair(vm_prism *p, const int32_t *nbt, facemap *fm, const double *qinit,
                        double c0, double cact, uint8_t *act, uint8_t *moved, pr_ortho_summary *s) {
  vm_ctx *ctx = p->ctx;
  int nl = p->nlev - 1;
  int64_t nt = p->nt, nw = p->nw, nc = nt * nl;
  size_t nv = (size_t)(nw * (nl + 1));
  memset(moved, 0, nv);
  memset(act, 0, nv);
  /* work lists: vertices to visit (vl), those that moved (ml), cells to
   * look at again (cl), deduplicated by act and cmark, so bounded by the
   * vertices and the cells */
  uint8_t *cmark = vm_calloc(ctx, (size_t)nc, 1);
  /* stuck[key]: the vertex's last step was refused and nothing around it
   * has moved since (trying it again would be refused again) */
  uint8_t *stuck = vm_calloc(ctx, nv, 1);
  int64_t *bad = vm_alloc_array(ctx, (size_t)nc, sizeof *bad);
  int64_t *cl = vm_alloc_array(ctx, (size_t)nc, sizeof *cl);
  int64_t *vl = vm_alloc_array(ctx, nv, sizeof *vl);
  int64_t *ml = vm_alloc_array(ctx, nv, sizeof *ml);
  /* the outer vertices' positions before the round's batch of steps */
  double *x0 = vm_alloc_array(ctx, 3 * (size_t)nw, sizeof *x0);
  int st = VM_OK;
  if (!cmark || !stuck || !bad || !cl || !vl || !ml || !x0) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  double sjmin = INFINITY;
#pragma omp parallel for schedule(static) reduction(min : sjmin)
  for (int64_t c = 0; c < nc; c++) {
    double x[18];
    int inv;
    pr_prism_at(p, p->lev, c / nl, (int)(c % nl), x);
    cmark[c] = vm_prism_split_check(x, NULL) > 0;
    double q = pr_prism_corner_quality(x, &inv);
    if (!inv && q < sjmin) sjmin = q;
  }
  fm->qworst = sjmin;
  s->split_sj = sjmin;
  int64_t nbad = 0;
  for (int64_t c = 0; c < nc; c++)
    if (cmark[c]) {
      bad[nbad++] = c;
      cmark[c] = 0;
    }
  s->split_before = nbad;
  int64_t best = nbad;
  int since_best = 0;
  for (int round = 0; round < p->k.split_rounds && nbad && pr_time_left(p) > 0 &&
                      since_best < p->k.split_stall_rounds;
       round++) {
    /* the failing cells' movable vertices, in level and vertex order */
    int64_t nvl = 0, nml = 0, ncl = 0;
    for (int64_t b = 0; b < nbad; b++) {
      int64_t t = bad[b] / nl;
      int k = (int)(bad[b] % nl);
      for (int i = 0; i < 3; i++)
        for (int l = k; l <= k + 1; l++) {
          size_t key = (size_t)l * nw + p->tri[3 * t + i];
          if (l < 1 || l > nl || act[key] || stuck[key]) continue;
          act[key] = 1;
          vl[nvl++] = (int64_t)key;
        }
    }
    qsort(vl, (size_t)nvl, sizeof *vl, cmp_i64);
    /* the outer vertices come last (the highest level): their steps go as
     * one batch, the single layer's crossings queried once after it (each
     * query rebuilds the layer's scene: once per step it was most of the
     * repair's time). If the batch crosses something new, it is undone in
     * reverse order (the state before it, exactly) and its steps are taken
     * again, each checked on its own. */
    int64_t top0 = nvl;
    while (top0 > 0 && vl[top0 - 1] / nw == nl) top0--;
    for (int64_t i = top0; i < nvl; i++) {
      int64_t v = vl[i] % nw;
      memcpy(x0 + 3 * v, p->lev + (size_t)nl * 3 * nw + 3 * v, 3 * sizeof *x0);
    }
    int64_t nml0 = 0;
    for (int pass = 0; pass < 2; pass++) {
      for (int64_t i = pass ? top0 : 0; i < nvl; i++) {
        act[vl[i]] = 0;
        int k = (int)(vl[i] / nw);
        int64_t v = vl[i] % nw;
        if (i == top0) nml0 = nml;
        if (relieve(p, nbt, fm, qinit, v, k, c0, cact, 1, pass || k < nl)) {
          moved[vl[i]] = 1;
          ml[nml++] = vl[i];
        } else {
          stuck[vl[i]] = 1;
        }
      }
      if (pass || nml == nml0 || top0 == nvl) break;
      int64_t np;
      if ((st = pr_layer_intersections(p, NULL, &np)) < 0) goto done;
      if (np <= p->rep.intersections) break;
      s->split_batches_undone++;
      for (int64_t i = nml; i-- > nml0;) put_outer(p, nbt, fm, ml[i] % nw, x0 + 3 * (ml[i] % nw));
      for (int64_t i = top0; i < nvl; i++) stuck[vl[i]] = 0;
      nml = nml0;
    }
    /* a vertex whose step reads what moved may go again: a step at (k, u)
     * reads the cells of u's triangles at layers k - 1 and k, the centres
     * of the cells beside them and u's heights at levels k - 2..k + 2, so
     * the columns within two rings of a moved vertex, levels k - 2..k + 2 */
    for (int64_t i = 0; i < nml; i++) {
      int k = (int)(ml[i] / nw);
      int64_t v = ml[i] % nw;
      for (int l = k - 2; l <= k + 2; l++) {
        if (l < 1 || l > nl) continue;
        size_t o = (size_t)l * nw;
        stuck[o + v] = 0;
        for (int64_t m = p->vv_off[v]; m < p->vv_off[v + 1]; m++) {
          int32_t u = p->vv[m];
          stuck[o + u] = 0;
          for (int64_t m2 = p->vv_off[u]; m2 < p->vv_off[u + 1]; m2++) stuck[o + p->vv[m2]] = 0;
        }
      }
    }
    s->split_moves += nml;
    s->split_rounds = round + 1;
    if (!nml) break;
    /* the cells to look at again: the failing ones and those around the
     * vertices that moved */
    for (int64_t b = 0; b < nbad; b++)
      if (!cmark[bad[b]]) {
        cmark[bad[b]] = 1;
        cl[ncl++] = bad[b];
      }
    for (int64_t i = 0; i < nml; i++) {
      int k = (int)(ml[i] / nw);
      int64_t v = ml[i] % nw;
      for (int64_t m = p->vt_off[v]; m < p->vt_off[v + 1]; m++)
        for (int j = k - 1; j <= k && j < nl; j++) {
          int64_t c = (int64_t)p->vt[m] * nl + j;
          if (!cmark[c]) {
            cmark[c] = 1;
            cl[ncl++] = c;
          }
        }
    }
    qsort(cl, (size_t)ncl, sizeof *cl, cmp_i64);
    nbad = 0;
    for (int64_t i = 0; i < ncl; i++) {
      double x[18];
      cmark[cl[i]] = 0;
      pr_prism_at(p, p->lev, cl[i] / nl, (int)(cl[i] % nl), x);
      if (vm_prism_split_check(x, NULL)) bad[nbad++] = cl[i];
    }
    if (nbad < best) {
      best = nbad;
      since_best = 0;
    } else {
      since_best++;
    }
  }
  /* the list is exact: every round ends by looking again at every cell
   * that could have changed */
  s->split_after = nbad;
  if (s->split_moves) refresh(p, nbt, cact, fm, moved);
done:
  vm_free(ctx, cmark);
  vm_free(ctx, stuck);
  vm_free(ctx, bad);
  vm_free(ctx, vl);
  vm_free(ctx, ml);
  vm_free(ctx, cl);
  vm_free(ctx, x0);
  return st;
}

/* The relief's steps at the outer vertices marked in act (level nl), in
 * vertex order, in the outer surface's tangent plane (relieve): the outer
 * surface is the layer's envelope, from which the far field's tets grow,
 * and its triangulation is the top layer's, so its faces lean as the
 * envelope's triangles are stretched. The steps go as one batch, the
 * single layer's crossings queried once after it; if the batch crosses
 * something new it is undone (every outer vertex exactly where it was)
 * and taken again without the steps of the columns that carry a crossing
 * face and their neighbours, at most k.ortho_relief_outer_tries times
 * (then not at all). Moved vertices are marked in moved; their count is
 * added to *nmoved. x0 and list are work arrays of 3 nw and nw; frozen
 * (nw) keeps the vertices held back, for the later sweeps too. */
static int outer_pass(vm_prism *p, const int32_t *nbt, facemap *fm, const double *qinit, double c0,
                      double cact, const uint8_t *act, uint8_t *moved, uint8_t *frozen, double *x0,
                      int64_t *list, uint8_t *mark, int64_t *nmoved, pr_ortho_summary *s) {
  int nl = p->nlev - 1;
  int64_t nw = p->nw;
  size_t lsz = (size_t)(3 * nw);
  for (int tries = 0; tries < p->k.ortho_relief_outer_tries; tries++) {
    int64_t n = 0;
    for (int64_t v = 0; v < nw; v++) {
      if (!act[(size_t)nl * nw + v] || frozen[v]) continue;
      /* only columns at full thickness: a shorter one ends at a contact
       * (or where restoring stopped), where the envelope faces another
       * part of itself across a gap the fill's tets must bridge */
      const double *xt = p->lev + nl * lsz + 3 * v;
      if (!at_full(p, v, xt)) continue;
      memcpy(x0 + 3 * v, xt, 3 * sizeof *x0);
      if (relieve(p, nbt, fm, qinit, v, nl, c0, cact, 0, 0)) list[n++] = v;
    }
    if (!n) return VM_OK;
    int64_t np;
    int st = pr_layer_intersections(p, mark, &np);
    if (st < 0) return st;
    if (np <= p->rep.intersections) {
      for (int64_t i = 0; i < n; i++) moved[(size_t)nl * nw + list[i]] = 1;
      *nmoved += n;
      s->outer_moves += n;
      return VM_OK;
    }
    /* undone in reverse order: each vertex moved once, so every one is
     * back where the batch found it, and so is every cell centre */
    s->outer_batches_undone++;
    for (int64_t i = n; i-- > 0;) put_outer(p, nbt, fm, list[i], x0 + 3 * list[i]);
    /* held back: the moved columns that carry a crossing face or are next
     * to one (a moved vertex's top triangles are its neighbours' too) */
    int64_t held = 0;
    for (int64_t i = 0; i < n; i++) {
      int64_t v = list[i];
      int near = mark[v];
      for (int64_t m = p->vv_off[v]; m < p->vv_off[v + 1] && !near; m++) near = mark[p->vv[m]];
      if (near) {
        frozen[v] = 1;
        held++;
      }
    }
    if (!held || tries + 1 == p->k.ortho_relief_outer_tries) {
      /* the crossing is not near a moved column (or the tries are spent):
       * the outer surface stays as it is */
      for (int64_t i = 0; i < n; i++) frozen[list[i]] = 1;
      /* the query's incremental state follows the undone batch */
      if ((st = pr_layer_intersections(p, NULL, &np)) < 0) return st;
      return VM_OK;
    }
  }
  return VM_OK;
}

int pr_ortho_relief(vm_prism *p, pr_ortho_summary *s) {
  memset(s, 0, sizeof *s);
  s->cmin_before = s->cmin_after = 1;
  int nl = p->nlev - 1;
  if (nl < 2) return VM_OK;
  vm_ctx *ctx = p->ctx;
  const pr_params *kp = &p->k;
  int64_t nt = p->nt, nw = p->nw, nc = nt * nl;
  size_t nv = (size_t)(nw * (nl + 1));
  int32_t *nbt = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *nbt);
  double *qinit = vm_alloc_array(ctx, (size_t)nc, sizeof *qinit);
  uint8_t *act = vm_alloc_array(ctx, nv, sizeof *act);
  uint8_t *moved = vm_alloc_array(ctx, nv, sizeof *moved);
  /* the outer pass's work arrays */
  uint8_t *frozen = vm_calloc(ctx, (size_t)nw, 1), *omark = vm_alloc_array(ctx, (size_t)nw, 1);
  double *ox0 = vm_alloc_array(ctx, 3 * (size_t)nw, sizeof *ox0);
  int64_t *olist = vm_alloc_array(ctx, (size_t)nw, sizeof *olist);
  facemap fm = {vm_alloc_array(ctx, (size_t)(3 * nc), sizeof *fm.cc),
                vm_alloc_array(ctx, (size_t)nc, 1),
                vm_alloc_array(ctx, (size_t)nc, 1),
                vm_alloc_array(ctx, (size_t)nc, sizeof *fm.cw),
                vm_alloc_array(ctx, (size_t)nc, sizeof *fm.det),
                vm_alloc_array(ctx, (size_t)nc, 1),
                INFINITY};
  int st = VM_OK;
  if (!nbt || !qinit || !act || !moved || !fm.cc || !fm.bad || !fm.o70 || !fm.cw || !fm.det ||
      !fm.mark || !frozen || !omark || !ox0 || !olist) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  edge_neighbours(p, nbt);
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < nc; c++) {
    double x[18];
    int inv;
    pr_prism_at(p, p->lev, c / nl, (int)(c % nl), x);
    double q = pr_prism_corner_quality(x, &inv), qn = pr_prism_quality(x);
    qinit[c] = inv || !(qn > 0) ? -1 : q < qn ? q : qn;
  }
  const double c0 = cos(kp->ortho_relief_deg * PR_PI / 180);
  const double cact = cos(kp->ortho_relief_active_deg * PR_PI / 180);
  update_faces(p, nbt, cact, &fm, NULL);
  face_totals(p, &fm, &s->over70_before, &s->cmin_before, &s->det_before);
  /* the sweeps go on while they lower the faces beyond 70 degrees and the
   * cells below the determinant's limit */
  int64_t n70 = s->over70_before, ndet = s->det_before, last = n70 + ndet;
  for (int sweep = 0; sweep < kp->ortho_relief_sweeps && pr_time_left(p) > 0; sweep++) {
    int64_t nmoved = 0;
    activate(p, nbt, &fm, act);
    memset(moved, 0, nv);
    /* a vertex at level k reads levels k - 2..k + 2 and the centres of
     * layers k - 2..k + 1, and writes its level and the centres of layers
     * k - 1 and k: levels PR_ORTHO_STRIDE apart never touch each other's,
     * so they run at once, each level in vertex order, the classes of
     * levels one after the other: the same result on any thread count */
    for (int r = 0; r < PR_ORTHO_STRIDE; r++) {
      int nk = (nl - 1 - r + PR_ORTHO_STRIDE - 1) / PR_ORTHO_STRIDE;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : nmoved)
      for (int i = 0; i < nk; i++) {
        int k = 1 + r + i * PR_ORTHO_STRIDE;
        for (int64_t v = 0; v < nw; v++)
          if (act[(size_t)k * nw + v] && relieve(p, nbt, &fm, qinit, v, k, c0, cact, 0, 1)) {
            moved[(size_t)k * nw + v] = 1;
            nmoved++;
          }
      }
    }
    /* then the outer surface (serial: one batch, one query) */
    if (kp->ortho_relief_outer_tries > 0 &&
        (st = outer_pass(p, nbt, &fm, qinit, c0, cact, act, moved, frozen, ox0, olist, omark,
                         &nmoved, s)) < 0)
      goto done;
    refresh(p, nbt, cact, &fm, moved);
    double cm;
    face_totals(p, &fm, &n70, &cm, &ndet);
    s->moves += nmoved;
    s->sweeps = sweep + 1;
    vm_log(ctx, VM_LOG_DEBUG,
           "prism: non-orthogonality relief sweep %d: %lld steps, %lld faces beyond 70 degrees, "
           "%lld cells below the determinant's limit",
           sweep + 1, (long long)nmoved, (long long)n70, (long long)ndet);
    /* done when a sweep gains less than k.ortho_relief_gain of the faces
     * beyond 70 degrees it started with */
    if (!nmoved || (double)(last - n70 - ndet) <= kp->ortho_relief_gain * (double)last) break;
    last = n70 + ndet;
  }
  double t0 = omp_get_wtime();
  if ((st = split_repair(p, nbt, &fm, qinit, c0, cact, act, moved, s)) < 0) goto done;
  s->split_time = omp_get_wtime() - t0;
  face_totals(p, &fm, &s->over70_after, &s->cmin_after, &s->det_after);
done:
  vm_free(ctx, nbt);
  vm_free(ctx, qinit);
  vm_free(ctx, act);
  vm_free(ctx, moved);
  vm_free(ctx, fm.cc);
  vm_free(ctx, fm.bad);
  vm_free(ctx, fm.o70);
  vm_free(ctx, fm.cw);
  vm_free(ctx, fm.det);
  vm_free(ctx, fm.mark);
  vm_free(ctx, frozen);
  vm_free(ctx, omark);
  vm_free(ctx, ox0);
  vm_free(ctx, olist);
  return st;
}

int pr_foam_figures(const vm_prism *p, const double *L, int nlev, int64_t *over70,
                    double *nonortho_max, double *skew_max, int64_t *det_small) {
  *over70 = 0;
  *det_small = 0;
  *nonortho_max = *skew_max = 0;
  int nl = nlev - 1;
  int64_t nt = p->nt, nc = nt * nl;
  if (nl < 1) return VM_OK;
  int32_t *nbt = vm_alloc_array(p->ctx, (size_t)(3 * nt), sizeof *nbt);
  double *cc = vm_alloc_array(p->ctx, (size_t)(3 * nc), sizeof *cc);
  if (!nbt || !cc) {
    vm_free(p->ctx, nbt);
    vm_free(p->ctx, cc);
    return VM_ERR_NOMEM;
  }
  edge_neighbours(p, nbt);
  /* the cell centres, and the cells' determinants (where layers end, the
   * pyramids' and tets' too: pr_end_layers) */
  int64_t nd = 0;
#pragma omp parallel for schedule(static) reduction(+ : nd)
  for (int64_t c = 0; c < nc; c++) {
    int64_t t = c / nl;
    int k = (int)(c % nl);
    double x[18], fc[5][3], fs[5][3];
    pr_prism_at(p, L, t, k, x);
    pr_foam_cell_faces(x, cc + 3 * c, fc, fs);
    const int32_t *tc = p->tri + 3 * t;
    if (pr_col_top(p, tc[0], nl) > k && pr_col_top(p, tc[1], nl) > k &&
        pr_col_top(p, tc[2], nl) > k)
      nd += prism_det(nbt, t, k, (const double(*)[3])fs) < PR_FOAM_DET_MIN;
    else
      nd += pr_cell_foam_det(p, L, t, k, nl) < PR_FOAM_DET_MIN; /* a transition cell */
  }
  const double c70 = cos(70 * PR_PI / 180);
  int64_t over = 0;
  double worst = 1, skew = 0;
#pragma omp parallel for schedule(static) reduction(+ : over) reduction(min : worst) \
    reduction(max : skew)
  for (int64_t c = 0; c < nc; c++) {
    int64_t t = c / nl;
    int k = (int)(c % nl);
    double x[18];
    /* where layers end (pr_end_layers): no cell where all three columns
     * have ended, no side face where both of its have, and the top of the
     * last cell of a stack is on the outer surface */
    const int32_t *tc = p->tri + 3 * t;
    int top_k[3];
    for (int i = 0; i < 3; i++) top_k[i] = pr_col_top(p, tc[i], nl);
    if (top_k[0] <= k && top_k[1] <= k && top_k[2] <= k) continue;
    int last = k == nl - 1 || (top_k[0] <= k + 1 && top_k[1] <= k + 1 && top_k[2] <= k + 1);
    pr_prism_at(p, L, t, k, x);
    for (int f = 0; f < 5; f++) {
      double y[12];
      if (f >= 2 && top_k[f - 2] <= k && top_k[(f - 1) % 3] <= k) continue;
      int n = face_of(x, f, y);
      /* the wall under layer 0 and the outer surface over the last */
      if ((f == 0 && k == 0) || (f == 1 && last)) {
        double sk = pr_foam_boundary_skew(y, n, cc + 3 * c);
        skew = sk > skew ? sk : skew;
        continue;
      }
      /* each internal face once: a cell's top, its sides towards later
       * triangles */
      int64_t u = f == 1 ? t : f >= 2 ? nbt[3 * t + f - 2] : -1;
      int j = f == 1 ? k + 1 : k;
      if (u < 0 && f >= 2) { /* a half model's face on its symmetry plane */
        double sk = pr_foam_boundary_skew(y, n, cc + 3 * c);
        skew = sk > skew ? sk : skew;
        continue;
      }
      if (u < 0 || (f >= 2 && u < t)) continue;
      const double *cn = cc + 3 * (u * nl + j);
      double cs = pr_foam_ortho_cos(y, n, cc + 3 * c, cn);
      over += cs < c70;
      worst = cs < worst ? cs : worst;
      double sk = pr_foam_skew(y, n, cc + 3 * c, cn);
      skew = sk > skew ? sk : skew;
    }
  }
  *over70 = over;
  *det_small = nd;
  *nonortho_max = acos(worst < -1 ? -1 : worst) * 180 / PR_PI;
  *skew_max = skew;
  vm_free(p->ctx, nbt);
  vm_free(p->ctx, cc);
  return VM_OK;
}
