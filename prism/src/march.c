/* prism/src/march.c: phase 5, the marching split: the remaining layer is
 * split in two, the middle surface optimized by the explicit solver with
 * orthogonalizing targets and weights on the inner sublayer, the inner
 * sublayer kept; repeated until the schedule of layer heights is met. Then
 * the stack is made fit for a finite-volume solver (a variational
 * smoothing where it leans, every column's levels put back on the
 * schedule, both guarded by OpenFOAM's skewness), and the first layer is
 * made orthogonal at the wall on smooth parts: columns stood up
 * geometrically where their prisms allow it, the rest solved for with
 * their neighbours. Last the skewness relief and the non-orthogonality
 * relief (ortho.c) move levels where OpenFOAM's measures of a face are
 * beyond what checkMesh accepts. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "state.h"
#include "varmesh/quality.h"

/* Minimum corner quality of the prisms between levels a and b. */
static double level_quality(const vm_prism *p, const double *la, const double *lb) {
  double qm = INFINITY;
  for (int64_t t = 0; t < p->nt; t++) {
    double x[18];
    for (int i = 0; i < 3; i++) {
      memcpy(x + 3 * i, la + 3 * (int64_t)p->tri[3 * t + i], 3 * sizeof *x);
      memcpy(x + 9 + 3 * i, lb + 3 * (int64_t)p->tri[3 * t + i], 3 * sizeof *x);
    }
    double q = pr_prism_corner_quality(x, NULL);
    if (q < qm) qm = q;
  }
  return qm;
}

/* Quality of the prisms of layers k0..k1 of triangle t: the smallest
 * (INFINITY for none). */
static double layers_quality(const vm_prism *p, int64_t t, int k0, int k1) {
  size_t lsz = (size_t)(3 * p->nw);
  double q = INFINITY;
  for (int k = k0; k <= k1; k++) {
    double x[18];
    for (int i = 0; i < 3; i++) {
      memcpy(x + 3 * i, p->lev + k * lsz + 3 * (size_t)p->tri[3 * t + i], 3 * sizeof *x);
      memcpy(x + 9 + 3 * i, p->lev + (k + 1) * lsz + 3 * (size_t)p->tri[3 * t + i], 3 * sizeof *x);
    }
    double v = pr_prism_quality(x);
    q = v < q ? v : q;
  }
  return q;
}

/* Column v stood up at the wall (along its normal; a column at a sharp
 * edge or corner along its blended direction, p->dir): each of levels
 * 1..nm keeps its height above the wall's tangent plane (its component
 * along that direction) and
 * loses its lateral offset, all of it at level 1 and a share (k-1)/nm of
 * it kept at level k, so the column bends back to its old course over nm
 * layers. Keeping the heights keeps every side edge rising (putting level 1
 * at its old distance on the normal would overshoot level 2 on a column
 * tilted by more than about 60 degrees). Levels are taken from `old`
 * (levels 1..nmax). hs < 1 lowers level 1 to hs times its height, level k
 * to hs + (1 - hs)(k - 1)/nm times its own (1: heights kept). Returns 0 if
 * the column cannot stand up (a level at or below the tangent plane). */
static int stand_column(vm_prism *p, int64_t v, int nm, double tilt, double hs, const double *old) {
  size_t lsz = (size_t)(3 * p->nw);
  const double *o = p->wall + 3 * v, *nv = (p->smooth[v] ? p->vnrm : p->dir) + 3 * v;
  for (int k = 1; k <= nm; k++) {
    double e[3];
    for (int c = 0; c < 3; c++) e[c] = old[(size_t)(k - 1) * lsz + 3 * v + c] - o[c];
    if (!(vm_dot3(e, nv) > 0)) return 0;
  }
  /* s1: the share of level 1's lateral offset kept, so that its side edge
   * leans by at most atan(tilt) */
  double s1 = 0;
  if (tilt > 0) {
    const double *x1 = old + 3 * v;
    double e[3], l[3];
    for (int c = 0; c < 3; c++) e[c] = x1[c] - o[c];
    double a = vm_dot3(e, nv);
    for (int c = 0; c < 3; c++) l[c] = e[c] - a * nv[c];
    double ln = sqrt(vm_dot3(l, l));
    s1 = ln > tilt * a ? tilt * a / ln : 1;
  }
  for (int k = 1; k <= nm; k++) {
    const double *x0 = old + (size_t)(k - 1) * lsz + 3 * v;
    double *x = p->lev + (size_t)k * lsz + 3 * v, e[3];
    double keep = s1 + (1 - s1) * (double)(k - 1) / nm;
    double lower = hs + (1 - hs) * (double)(k - 1) / nm;
    for (int c = 0; c < 3; c++) e[c] = x0[c] - o[c];
    double a = vm_dot3(e, nv);
    for (int c = 0; c < 3; c++) x[c] = o[c] + lower * a * nv[c] + keep * (e[c] - a * nv[c]);
  }
  return 1;
}

/* Where column v's first level (in `old`) stands more than twice as high
 * (1 / k.ortho_high_ratio) above the tangent plane as its neighbours' (as
 * they are now) on average, the share of its height that brings it down
 * to that mean; else 1. */
static double first_level_share(const vm_prism *p, int64_t v, const double *old) {
  size_t lsz = (size_t)(3 * p->nw);
  double e[3], sum = 0;
  for (int c = 0; c < 3; c++) e[c] = old[3 * v + c] - p->wall[3 * v + c];
  double a = vm_dot3(e, p->vnrm + 3 * v);
  for (int64_t k = p->vv_off[v]; k < p->vv_off[v + 1]; k++) {
    int64_t u = p->vv[k];
    double f[3];
    for (int c = 0; c < 3; c++) f[c] = p->lev[lsz + 3 * u + c] - p->wall[3 * u + c];
    sum += vm_dot3(f, p->vnrm + 3 * u);
  }
  double mean = sum / (double)(p->vv_off[v + 1] - p->vv_off[v]);
  return a > 0 && mean > 0 && mean < p->k.ortho_high_ratio * a ? mean / a : 1;
}

static void restore_column(vm_prism *p, int64_t v, int nmax, const double *old) {
  size_t lsz = (size_t)(3 * p->nw);
  for (int k = 0; k < nmax; k++)
    memcpy(p->lev + (size_t)(k + 1) * lsz + 3 * v, old + (size_t)k * lsz + 3 * v, 3 * sizeof *old);
}

/* The quality a prism of quality q0 before may fall to: min(k.ortho_qmin,
 * share q0). */
static double quality_floor(const vm_prism *p, double q0, double share) {
  return share * q0 < p->k.ortho_qmin ? share * q0 : p->k.ortho_qmin;
}

/* Is every prism of layers 0..nm on column v better than 0.3 or a quarter
 * of its quality before (q0; k.ortho_qmin, k.ortho_alone_share)? The test
 * a column that stood up must pass. */
static int column_ok(const vm_prism *p, int64_t v, int nm, const double *q0) {
  for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
    int64_t t = p->vt[j];
    if (layers_quality(p, t, 0, nm) < quality_floor(p, q0[t], p->k.ortho_alone_share)) return 0;
  }
  return 1;
}

/* Column v and those of its neighbours that have not stood up (moved),
 * all stood up over `bend` layers, each with its first level lowered as
 * first_level_share says; kept if every prism on any of them is then
 * better than 0.3 or a quarter of its quality before (q0), else all go
 * back. Returns 1 if kept (the columns that moved are marked). */
static int stand_with_ring(vm_prism *p, int64_t v, int bend, int nm, const double *q0,
                           uint8_t *moved, const double *old) {
  int64_t j0 = p->vv_off[v], deg = p->vv_off[v + 1] - j0;
  if (deg + 1 > PR_RING_MAX) return 0;
  int64_t set[PR_RING_MAX], n = 0;
  uint8_t in[PR_RING_MAX];
  set[n++] = v;
  for (int64_t j = 0; j < deg; j++)
    if (!moved[p->vv[j0 + j]]) set[n++] = p->vv[j0 + j];
  /* every share is taken before any column moves: it compares a column's
   * first level with its neighbours' as they are */
  double hs[PR_RING_MAX];
  for (int64_t i = 0; i < n; i++) hs[i] = first_level_share(p, set[i], old);
  for (int64_t i = 0; i < n; i++) in[i] = (uint8_t)stand_column(p, set[i], bend, 0, hs[i], old);
  int ok = in[0];
  for (int64_t i = 0; i < n && ok; i++)
    if (in[i]) ok = column_ok(p, set[i], nm, q0);
  for (int64_t i = 0; i < n; i++) {
    if (!in[i]) continue;
    if (ok)
      moved[set[i]] = 1;
    else
      restore_column(p, set[i], nm, old);
  }
  return ok;
}

/* The first layer's side edges along the wall normal where the wall is
 * smooth (incident face normals within 10 degrees of the vertex normal):
 * every smooth column is stood up over 6 layers (stand_column); where a
 * prism of layers 0..nm (nm = min(24, layers - 1)) would then be worse than
 * both 0.3 and half its quality before, its columns go back, until no such
 * prism is left. Then each column that went back, in vertex order, tries
 * again alone, bending back over 6, 12, 9, 18, nm, 3, 2 or 1 layers, with
 * its neighbours as they are, and keeps the first that leaves every prism
 * it touches better than 0.3 or a quarter of its quality before (then the
 * same bends leaning by 4.5 degrees, then straight ones with the first
 * level lowered to its neighbours' mean height where it stood more than
 * twice as high, and last each straight bend together with the
 * neighbours that have not stood up); these passes repeat while a column
 * stands up (a neighbour standing up can make room). A column tilted far
 * over (next to a junction whose columns stay tilted) needs the long
 * bends: over 6 layers its lateral offset is taken up too steeply. While
 * the columns stand up over 6 layers, layers 7..nm keep their quality
 * (qup), so only layers 0..6 are measured again. The outer surface never
 * moves, so its intersections are untouched, and going back restores the
 * old prisms bit for bit. */
static int orthogonal_first_level(vm_prism *p) {
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt;
  const pr_params *kp = &p->k;
  int nm = p->nlev - 2 < kp->ortho_layers ? p->nlev - 2 : kp->ortho_layers;
  int nb = nm < kp->ortho_bend ? nm : kp->ortho_bend;
  size_t lsz = (size_t)(3 * nw);
  double *old = vm_alloc_array(ctx, (size_t)nm * lsz, sizeof *old);
  double *q0 = vm_alloc_array(ctx, (size_t)nt, sizeof *q0);
  double *qup = vm_alloc_array(ctx, (size_t)nt, sizeof *qup);
  uint8_t *back = vm_alloc_array(ctx, (size_t)nw, sizeof *back);
  uint8_t *moved = vm_calloc(ctx, (size_t)nw, sizeof *moved);
  if (!old || !q0 || !qup || !back || !moved) {
    vm_free(ctx, old);
    vm_free(ctx, q0);
    vm_free(ctx, qup);
    vm_free(ctx, back);
    vm_free(ctx, moved);
    return VM_ERR_NOMEM;
  }
  memcpy(old, p->lev + lsz, (size_t)nm * lsz * sizeof *old);
  /* q0: layers 0..nm before; qup: layers nb+1..nm, which standing up over
   * nb layers leaves as they are */
  for (int64_t t = 0; t < nt; t++) {
    double lo = layers_quality(p, t, 0, nb);
    qup[t] = layers_quality(p, t, nb + 1, nm);
    q0[t] = lo < qup[t] ? lo : qup[t];
  }
  for (int64_t v = 0; v < nw; v++)
    if (p->smooth[v]) moved[v] = (uint8_t)stand_column(p, v, nb, 0, 1, old);
  for (int round = 0; round < kp->ortho_rounds; round++) {
    memset(back, 0, (size_t)nw);
    int64_t nback = 0;
    for (int64_t t = 0; t < nt; t++) {
      double q = layers_quality(p, t, 0, nb);
      if ((q < qup[t] ? q : qup[t]) >= quality_floor(p, q0[t], kp->ortho_round_share)) continue;
      for (int i = 0; i < 3; i++) {
        int32_t v = p->tri[3 * t + i];
        if (moved[v]) {
          back[v] = 1;
          nback++;
        }
      }
    }
    if (!nback) break;
    for (int64_t v = 0; v < nw; v++)
      if (back[v]) {
        restore_column(p, v, nm, old);
        moved[v] = 0;
      }
  }
  /* bends tried in this order, each length once (nm may repeat one) */
  int tries[PR_NBENDS], ntry = 0;
  for (int k = 0; k < PR_NBENDS; k++) tries[k] = kp->ortho_bends[k] ? kp->ortho_bends[k] : nm;
  for (int k = 0; k < PR_NBENDS; k++) {
    int seen = tries[k] > nm;
    for (int j = 0; j < ntry && !seen; j++) seen = tries[j] == tries[k];
    if (!seen) tries[ntry++] = tries[k];
  }
  const double lean = tan(kp->ortho_lean_deg * PR_PI / 180);
  for (int pass = 0, again = 1; pass < kp->ortho_passes && again; pass++) {
    again = 0;
    for (int64_t v = 0; v < nw; v++) {
      if (!p->smooth[v] || moved[v]) continue;
      /* first straight up, then (a last resort) leaning by 4.5 degrees,
       * then straight up with the first level lowered to its neighbours'
       * mean height above the tangent plane where it stands well above
       * them (the marching's solve can leave one column's first level
       * many times the scheduled height) */
      double hs = first_level_share(p, v, old);
      int nfam = hs < 1 ? 3 : 2;
      for (int k = 0; k < nfam * ntry && !moved[v]; k++) {
        int fam = k / ntry;
        if (!stand_column(p, v, tries[k % ntry], fam == 1 ? lean : 0, fam == 2 ? hs : 1, old))
          continue;
        if (column_ok(p, v, nm, q0))
          moved[v] = again = 1;
        else
          restore_column(p, v, nm, old);
      }
      /* last, each straight bend again with the neighbours that have not
       * stood up (smooth ones along their normals, the others along their
       * column directions): a column tilted among tilted ones next to a
       * sharp edge, where none can stand up alone */
      for (int k = 0; k < ntry && !moved[v]; k++)
        if (stand_with_ring(p, v, tries[k], nm, q0, moved, old)) again = 1;
    }
  }
  vm_free(ctx, qup);
  vm_free(ctx, old);
  vm_free(ctx, q0);
  vm_free(ctx, back);
  vm_free(ctx, moved);
  return VM_OK;
}

/* Centre of the cell of triangle t in layer k: from cc (3 per cell, layer
 * by layer of each triangle: cc + 3 (nl t + k)) if given, else computed. */
static void cell_centre(const vm_prism *p, const double *cc, int64_t t, int k, double *c) {
  if (cc) {
    memcpy(c, cc + 3 * ((int64_t)(p->nlev - 1) * t + k), 3 * sizeof *c);
    return;
  }
  double x[18];
  pr_prism_at(p, p->lev, t, k, x);
  pr_foam_cell(x, c);
}

/* The side quad of prism x over its bottom edge i (vertices i, i + 1)
 * into f (12 values): bottom i, bottom i + 1, top i + 1, top i. */
static void side_quad(const double *x, int i, double *f) {
  memcpy(f, x + 3 * i, 3 * sizeof *f);
  memcpy(f + 3, x + 3 * ((i + 1) % 3), 3 * sizeof *f);
  memcpy(f + 6, x + 9 + 3 * ((i + 1) % 3), 3 * sizeof *f);
  memcpy(f + 9, x + 9 + 3 * i, 3 * sizeof *f);
}

/* The largest OpenFOAM skewness over the faces of triangle t's cells (every
 * layer) seen from t: the faces between layers, the outer face, the
 * side faces shared with the edge neighbours' cells (t's cell the owner)
 * and a half model's side faces on its symmetry plane.
 * cc: every cell's centre (cell_centre), or NULL. With o70 (not NULL), the
 * same pass also adds to *o70 the faces beyond 70 degrees of OpenFOAM's
 * non-orthogonality and lowers *cmin to their least cosine, each face of
 * the cells on column v once: not the outer faces (the fill's), and a side
 * face between two triangles of v's from the lower-numbered one. */
static double tri_faces(const vm_prism *p, int64_t t, const double *cc, int64_t v, int *o70,
                        double *cmin) {
  int nl = p->nlev - 1;
  const double c70 = cos(70 * PR_PI / 180);
  double worst = 0, cp[3], cu[3];
  int64_t nb[3];
  int ortho[3];
  for (int i = 0; i < 3; i++) {
    nb[i] = pr_tri_across(p, t, i);
    ortho[i] = o70 && nb[i] >= 0;
    if (ortho[i] && nb[i] < t) {
      const int32_t *c = p->tri + 3 * nb[i];
      ortho[i] = c[0] != v && c[1] != v && c[2] != v;
    }
  }
  cell_centre(p, cc, t, 0, cp);
  for (int k = 0; k < nl; k++) {
    double x[18], cn[3];
    pr_prism_at(p, p->lev, t, k, x);
    if (k + 1 < nl) {
      cell_centre(p, cc, t, k + 1, cu);
      double q = pr_foam_skew(x + 9, 3, cp, cu);
      worst = q > worst ? q : worst;
      if (o70) {
        double c = pr_foam_ortho_cos(x + 9, 3, cp, cu);
        *o70 += c < c70;
        *cmin = c < *cmin ? c : *cmin;
      }
    } else {
      double q = pr_foam_boundary_skew(x + 9, 3, cp);
      worst = q > worst ? q : worst;
    }
    for (int i = 0; i < 3; i++) {
      double f[12];
      side_quad(x, i, f);
      if (nb[i] < 0) { /* a half model's face on its symmetry plane: a boundary face */
        double q = pr_foam_boundary_skew(f, 4, cp);
        worst = q > worst ? q : worst;
        continue;
      }
      cell_centre(p, cc, nb[i], k, cn);
      double q = pr_foam_skew(f, 4, cp, cn);
      worst = q > worst ? q : worst;
      if (ortho[i]) {
        double c = pr_foam_ortho_cos(f, 4, cp, cn);
        *o70 += c < c70;
        *cmin = c < *cmin ? c : *cmin;
      }
    }
    if (k + 1 < nl) memcpy(cp, cu, sizeof cp);
  }
  return worst;
}

/* The largest OpenFOAM skewness over the faces of the cells on column v
 * (every layer of its triangles): faces between layers, side faces shared
 * with the neighbouring triangles' cells and the outer faces. */
static double column_skew(const vm_prism *p, int64_t v) {
  double worst = 0;
  for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
    double q = tri_faces(p, p->vt[j], NULL, v, NULL, NULL);
    worst = q > worst ? q : worst;
  }
  return worst;
}

/* column_skew of every column at once (sk[v], the same values bit for
 * bit): each cell's centre computed once, each triangle's faces once, in
 * parallel; about a tenth of the work of nw calls. */
static int all_column_skew(const vm_prism *p, double *sk) {
  int64_t nt = p->nt, nw = p->nw;
  int nl = p->nlev - 1;
  double *cc = vm_alloc_array(p->ctx, (size_t)(3 * nt * nl), sizeof *cc);
  double *tq = vm_alloc_array(p->ctx, (size_t)(nt ? nt : 1), sizeof *tq);
  if (!cc || !tq) {
    vm_free(p->ctx, cc);
    vm_free(p->ctx, tq);
    return VM_ERR_NOMEM;
  }
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < nt * nl; c++) {
    double x[18];
    pr_prism_at(p, p->lev, c / nl, (int)(c % nl), x);
    pr_foam_cell(x, cc + 3 * c);
  }
#pragma omp parallel for schedule(static)
  for (int64_t t = 0; t < nt; t++) tq[t] = tri_faces(p, t, cc, -1, NULL, NULL);
  for (int64_t v = 0; v < nw; v++) {
    double worst = 0;
    for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++)
      worst = tq[p->vt[j]] > worst ? tq[p->vt[j]] : worst;
    sk[v] = worst;
  }
  vm_free(p->ctx, cc);
  vm_free(p->ctx, tq);
  return VM_OK;
}

static double first_tilt(const vm_prism *p, int64_t v);

/* The schedule's shares frac[k] (k = 0..nl) of the thickness at which
 * levels stand, the same for every column at full thickness; returns the
 * thickness (the heights' sum). */
static double common_fractions(const vm_prism *p, int nl, double *frac) {
  double tot = 0;
  for (int k = 0; k < p->rep.layers_requested; k++) tot += p->sched[k];
  frac[0] = 0;
  for (int k = 1; k < nl; k++) frac[k] = frac[k - 1] + p->sched[k - 1] / tot;
  frac[nl] = 1;
  return tot;
}

/* The tilt smooth column v's first side edge may have after a move:
 * k.tilt_limit_deg, or its tilt now if beyond (level 1 moving along a
 * bent polyline turns it). */
static double tilt_allowed(const vm_prism *p, int64_t v) {
  double t = first_tilt(p, v);
  return t > p->k.tilt_limit_deg ? t : p->k.tilt_limit_deg;
}

/* Column v's own schedule: the shares frac_c[k] (k = 0..nl) of its length
 * `len` at which its levels stand. A column at the full thickness `tot`
 * (or beyond it) takes the schedule's shares `frac` (common_fractions),
 * unless its first height is its own (p->h1v: long wall edges; then it is
 * on its own schedule as a shortened column). A column the stage had to
 * shorten keeps its first height h1 (the schedule's, what the user asked
 * for with --first-height or --yplus: the wall's cells the same height
 * everywhere, as a solver's wall treatment assumes; or its own where
 * raised) and the growth law,
 * with its own ratio r_c in [1, r] so that h1 (1 + r_c + ... + r_c^(nl-1))
 * = len; where even equal heights of h1 exceed len, equal heights len/nl.
 * Scaling the whole schedule instead made a column shortened to a tenth of
 * T put its first cell at a tenth of h1 (aspect ratios 10 times the
 * others', OpenFOAM's small cell determinants). The same shares as `frac`
 * when there are fewer levels than the schedule's or the column is at full
 * thickness, so the change is continuous at len = T. Returns whether the
 * column has a schedule of its own. */
static int column_fractions(const vm_prism *p, int64_t v, int nl, double len, const double *frac,
                            double tot, double *frac_c) {
  memcpy(frac_c, frac, (size_t)(nl + 1) * sizeof *frac_c);
  double h1 = pr_first_height(p, v);
  if (nl != p->rep.layers_requested || nl < 2 || !(len > 0) ||
      (!(len < tot) && !(h1 > p->sched[0])))
    return 0;
  if (h1 * nl >= len) {
    for (int k = 1; k < nl; k++) frac_c[k] = (double)k / nl;
    return 1;
  }
  double rc = pr_growth_ratio(h1, nl, len, p->k.sched_bisect_iter), a = 0, h = h1;
  for (int k = 1; k < nl; k++) {
    a += h;
    h *= rc;
    frac_c[k] = a / len;
  }
  return 1;
}

/* Column v's levels 1..nl-1 put along its polyline `old` (levels 0..nl,
 * arc lengths `arc`) at the shares frac[k]^gamma of its length. */
static void place_levels(vm_prism *p, int64_t v, int nl, const double *old, const double *arc,
                         const double *frac, double gamma) {
  size_t lsz = (size_t)(3 * p->nw);
  for (int k = 1, s = 0; k < nl; k++) {
    double a = (gamma == 1 ? frac[k] : pow(frac[k], gamma)) * arc[nl];
    while (s + 1 < nl && arc[s + 1] < a) s++;
    double u = (a - arc[s]) / (arc[s + 1] - arc[s]);
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    for (int c = 0; c < 3; c++)
      p->lev[k * lsz + 3 * v + c] = old[3 * s + c] + u * (old[3 * (s + 1) + c] - old[3 * s + c]);
  }
}

/* Are the prisms of every layer around column v free of inverted corner
 * tets and at or above quality `floor`? */
static int column_valid(const vm_prism *p, int64_t v, double floor) {
  int nl = p->nlev - 1;
  for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++)
    for (int k = 0; k < nl; k++) {
      double x[18];
      int inv;
      pr_prism_at(p, p->lev, p->vt[j], k, x);
      pr_prism_corner_quality(x, &inv);
      if (inv || !(pr_prism_quality(x) >= floor)) return 0;
    }
  return 1;
}

/* How far the ratios of successive heights of the column whose levels
 * 0..nl are x + k * stride leave the growth band [r / 1.5, 1.5 r]: the sum
 * over its ratios of log(ratio / bound) outside it (0: in the band). */
static double band_excess(const vm_prism *p, const double *x, int nl, size_t stride) {
  double lo = p->rep.growth / 1.5, hi = p->rep.growth * 1.5, e = 0;
  for (int k = 0; k + 2 <= nl; k++) {
    double h0 = vm_dist3(x + k * stride, x + (k + 1) * stride);
    double h1 = vm_dist3(x + (k + 1) * stride, x + (k + 2) * stride);
    if (!(h0 > 0) || !(h1 > 0)) return INFINITY;
    double g = h1 / h0;
    e += g < lo ? log(lo / g) : g > hi ? log(g / hi) : 0;
  }
  return e;
}

/* Every column's levels 1..nlev-2 put back on the schedule: level k at the
 * share (h_0 + ... + h_{k-1}) / T of the column's length, measured along
 * the column's polyline (the levels move along it, so the column keeps its
 * course). The marching's solves can leave a level far from the schedule
 * (first levels of the fan columns at sharp edges 6-12 times the scheduled
 * height on the coarse aircraft, the next ones on it): the layer above
 * such a level is a wedge whose OpenFOAM cell centres jump sideways, and
 * its heights break the growth law. A column shorter than T takes its own
 * schedule (column_fractions: the first height kept). One column at a
 * time, in vertex order, up to k.redistribute_sweeps sweeps;
 * a column whose prisms would fall below min(k.ortho_qmin, a tenth of
 * their quality before) or lose a corner tet goes back bit for bit. Returns the
 * count of columns moved in *count. */
static int redistribute_columns(vm_prism *p, int64_t *count) {
  int64_t nw = p->nw, moved = 0;
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * nw);
  double *frac = vm_alloc_array(p->ctx, (size_t)(6 * (nl + 1)), sizeof *frac);
  if (!frac) return VM_ERR_NOMEM;
  double *arc = frac + nl + 1, *fc = arc + nl + 1, *old = fc + nl + 1;
  double tot = common_fractions(p, nl, frac);
  /* sweeps: a column refused beside neighbours still off their schedule
   * may fit once they are on it */
  int now = 1;
  for (int sweep = 0; sweep < p->k.redistribute_sweeps && now; sweep++) {
    now = 0;
    for (int64_t v = 0; v < nw; v++) {
      arc[0] = 0;
      for (int k = 0; k <= nl; k++) memcpy(old + 3 * k, p->lev + k * lsz + 3 * v, 3 * sizeof *old);
      for (int k = 1; k <= nl; k++) arc[k] = arc[k - 1] + vm_dist3(old + 3 * k, old + 3 * (k - 1));
      if (!(arc[nl] > 0)) continue;
      int own = column_fractions(p, v, nl, arc[nl], frac, tot, fc);
      /* the largest relative move off the column's own schedule and off
       * the common one: nothing to do where the column is on it already */
      double dev = 0, dev_common = 0;
      for (int k = 1; k < nl; k++) {
        double d = fabs(arc[k] / arc[nl] - fc[k]) / (fc[k] - fc[k - 1]);
        double e = fabs(arc[k] / arc[nl] - frac[k]) / (frac[k] - frac[k - 1]);
        dev = d > dev ? d : dev;
        dev_common = e > dev_common ? e : dev_common;
      }
      if (dev < p->k.redistribute_tol) continue;
      double q0 = INFINITY;
      for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
        double q = layers_quality(p, p->vt[j], 0, nl - 1);
        q0 = q < q0 ? q : q0;
      }
      /* the column's own schedule first; refused, a shortened column tries
       * the common one scaled to its length (its first height then
       * len/T of h1), as all columns did before */
      int ok = 0;
      for (int pass = own ? 0 : 1; pass < 2 && !ok; pass++) {
        if (pass == 1 && own && dev_common < p->k.redistribute_tol) break;
        /* a smooth column's first side edge may not tilt more than it did
         * or than k.tilt_limit_deg on its own schedule (its level 1,
         * higher, moving up a bent polyline turns it; the stand-up after
         * this could then no longer right it: 17.9 degrees on the demo
         * aircraft at 20 %). The common schedule is left to the stand-up,
         * as before (guarding it too refused 65 columns on the demo at 5 %
         * and broke their growth law) */
        int guard = pass == 0 && p->smooth[v];
        double tilt_max = guard ? tilt_allowed(p, v) : 0;
        place_levels(p, v, nl, old, arc, pass == 0 ? fc : frac, 1);
        ok = column_valid(p, v, quality_floor(p, q0, p->k.redistribute_qshare)) &&
             !(guard && first_tilt(p, v) > tilt_max);
        /* nor may the column raise the skewness of its cells' faces above
         * k.skew_limit (what checkMesh fails at, with a margin) */
        if (ok) {
          double after = column_skew(p, v);
          if (after > p->k.skew_limit) {
            for (int k = 1; k < nl; k++) {
              double tmp[3];
              memcpy(tmp, p->lev + k * lsz + 3 * v, sizeof tmp);
              memcpy(p->lev + k * lsz + 3 * v, old + 3 * k, sizeof tmp);
              memcpy(old + 3 * k, tmp, sizeof tmp);
            }
            double before = column_skew(p, v);
            for (int k = 1; k < nl; k++) {
              double tmp[3];
              memcpy(tmp, p->lev + k * lsz + 3 * v, sizeof tmp);
              memcpy(p->lev + k * lsz + 3 * v, old + 3 * k, sizeof tmp);
              memcpy(old + 3 * k, tmp, sizeof tmp);
            }
            ok = after <= before;
          }
        }
        if (!ok)
          for (int k = 1; k < nl; k++)
            memcpy(p->lev + k * lsz + 3 * v, old + 3 * k, 3 * sizeof *old);
      }
      if (ok) {
        moved++;
        now = 1;
      }
    }
  }
  vm_free(p->ctx, frac);
  *count = moved;
  return VM_OK;
}

/* The largest skewness over the faces of the cells on column v
 * (column_skew), and in *o70 their faces beyond 70 degrees of
 * non-orthogonality, each once (tri_faces), with the least cosine in
 * *cmin: one pass for both. */
static double column_faces(const vm_prism *p, int64_t v, int *o70, double *cmin) {
  double worst = 0;
  *o70 = 0;
  *cmin = 1;
  for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
    double q = tri_faces(p, p->vt[j], NULL, v, o70, cmin);
    worst = q > worst ? q : worst;
  }
  return worst;
}

/* What the growth relief guards in the prisms around column v (every
 * layer of its triangles), in one pass. */
typedef struct col_cells {
  double qmin;        /* least quality (pr_prism_quality) */
  int inverted;       /* prisms with a corner tet not positive */
  int split;          /* prisms not positive in every 3-tet split */
  double sj;          /* least scaled Jacobian (the corner rule's) */
  int ndet;           /* cells below checkMesh's determinant limit, over
                         their faces inside the hybrid mesh (all but the
                         wall's and an open edge's) ... */
  double det_deficit; /* ... and the sum of log10(limit / det) over them */
} col_cells;

static void column_cells(const vm_prism *p, int64_t v, col_cells *cs) {
  memset(cs, 0, sizeof *cs);
  cs->qmin = cs->sj = INFINITY;
  for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
    int64_t t = p->vt[j];
    int in[5] = {0, 1, pr_tri_across(p, t, 0) >= 0, pr_tri_across(p, t, 1) >= 0,
                 pr_tri_across(p, t, 2) >= 0};
    for (int k = 0; k < p->nlev - 1; k++) {
      double x[18], cc[3], fc[5][3], fs[5][3];
      int inv;
      pr_prism_at(p, p->lev, t, k, x);
      double q = pr_prism_quality(x), sj = pr_prism_corner_quality(x, &inv);
      cs->qmin = q < cs->qmin ? q : cs->qmin;
      cs->sj = sj < cs->sj ? sj : cs->sj;
      cs->inverted += inv;
      cs->split += vm_prism_split_check(x, NULL) > 0;
      in[0] = k > 0;
      pr_foam_cell_faces(x, cc, fc, fs);
      double d = pr_foam_cell_det((const double(*)[3])fs, in);
      if (d < PR_FOAM_DET_MIN) {
        cs->ndet++;
        cs->det_deficit += d > 1e-30 ? log10(PR_FOAM_DET_MIN / d) : 30;
      }
    }
  }
}

/* The growth law where the steps after the redistribution left a column's
 * heights off it (the first level stood up, the reliefs' moves across the
 * columns; 50 columns of 7,138 on the demo aircraft at T = 5 %): each
 * column whose ratios of successive heights leave the band [r / 1.5,
 * 1.5 r] has its levels 1..nlev-2 moved along its own polyline (its
 * course, the wall and the outer surface stay as they are) from their
 * shares of its length towards its own schedule's (column_fractions), the
 * whole way or, refused, a share k.growth_parts of it; the first move that
 * brings the ratios closer to the band is kept if, around the column,
 * every prism stays valid above min(k.ortho_qmin, k.redistribute_qshare
 * of its quality before), no more fail a 3-tet split, the least scaled
 * Jacobian does not fall below min(its value before, k.growth_sj_floor),
 * no more cells are below checkMesh's determinant limit nor further below
 * it (the sum of log10(0.001 / det) over them), no more faces
 * are beyond 70 degrees and the worst is no worse, the skewness stays
 * below k.skew_limit (or its value before) and a smooth column's first
 * side edge within k.tilt_limit_deg of its normal (or its tilt before).
 * k.growth_sweeps sweeps in vertex order (a neighbour moved can make
 * room), each column moved once at most; counts the columns moved. */
static int growth_relief(vm_prism *p, int64_t *count) {
  int64_t nw = p->nw, moved = 0;
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * nw);
  const pr_params *kp = &p->k;
  const int nparts = (int)(sizeof kp->growth_parts / sizeof *kp->growth_parts);
  const double c70 = cos(70 * PR_PI / 180);
  *count = 0;
  if (nl < 3) return VM_OK;
  double *frac = vm_alloc_array(p->ctx, (size_t)(7 * (nl + 1)), sizeof *frac);
  if (!frac) return VM_ERR_NOMEM;
  double *arc = frac + nl + 1, *fc = arc + nl + 1, *fb = fc + nl + 1, *old = fb + nl + 1;
  uint8_t *done = vm_calloc(p->ctx, (size_t)nw, sizeof *done);
  if (!done) {
    vm_free(p->ctx, frac);
    return VM_ERR_NOMEM;
  }
  double tot = common_fractions(p, nl, frac);
  for (int sweep = 0, again = 1; sweep < kp->growth_sweeps && again; sweep++) {
    again = 0;
    for (int64_t v = 0; v < nw; v++) {
      /* once per column: moved again along its new polyline it would cut
       * the corners of its course */
      if (done[v]) continue;
      for (int k = 0; k <= nl; k++)
        memcpy(old + 3 * k, p->lev + (size_t)k * lsz + 3 * v, 3 * sizeof *old);
      double band0 = band_excess(p, old, nl, 3);
      if (!(band0 > 0) || !isfinite(band0)) continue;
      arc[0] = 0;
      for (int k = 1; k <= nl; k++) arc[k] = arc[k - 1] + vm_dist3(old + 3 * k, old + 3 * (k - 1));
      if (!(arc[nl] > 0)) continue;
      column_fractions(p, v, nl, arc[nl], frac, tot, fc);
      col_cells c0, c1;
      column_cells(p, v, &c0);
      double cmin0, cmin1;
      int over0, over1;
      double skew0 = column_faces(p, v, &over0, &cmin0);
      double skew_max = skew0 > kp->skew_limit ? skew0 : kp->skew_limit;
      double sj_min = c0.sj < kp->growth_sj_floor ? c0.sj : kp->growth_sj_floor;
      double cos_min = cmin0 < c70 ? cmin0 : c70;
      double floor = quality_floor(p, c0.qmin, kp->redistribute_qshare);
      int guard = p->smooth[v];
      double tilt_max = guard ? tilt_allowed(p, v) : 0;
      int ok = 0;
      for (int b = 0; b < nparts && !ok; b++) {
        double w = kp->growth_parts[b];
        fb[0] = 0;
        fb[nl] = 1;
        for (int k = 1; k < nl; k++) fb[k] = (1 - w) * arc[k] / arc[nl] + w * fc[k];
        place_levels(p, v, nl, old, arc, fb, 1);
        if (!(band_excess(p, p->lev + 3 * v, nl, lsz) < band0) ||
            (guard && first_tilt(p, v) > tilt_max)) {
          ok = 0;
        } else {
          column_cells(p, v, &c1);
          ok = !c1.inverted && c1.qmin >= floor && c1.split <= c0.split && c1.sj >= sj_min &&
               c1.ndet <= c0.ndet && c1.det_deficit <= c0.det_deficit &&
               column_faces(p, v, &over1, &cmin1) <= skew_max && over1 <= over0 && cmin1 >= cos_min;
        }
        if (!ok)
          for (int k = 1; k < nl; k++)
            memcpy(p->lev + (size_t)k * lsz + 3 * v, old + 3 * k, 3 * sizeof *old);
      }
      if (ok) {
        done[v] = 1;
        moved++;
        again = 1;
      }
    }
  }
  vm_free(p->ctx, done);
  vm_free(p->ctx, frac);
  *count = moved;
  return VM_OK;
}

/* Skewness relief where a column's cells stay skewed beyond k.skew_limit:
 * at a sharp trailing edge the side face between the last prisms of the
 * upper and the lower surface is a strip as wide as the first layers are
 * high, while the cells' centres sit a third of the wall triangle's chord
 * upstream of it, so OpenFOAM's skewness of that face is about the
 * triangle's size over the layer's height (16 on the demo aircraft). The
 * column's levels 1..nlev-2 move along its own polyline (its course, the
 * wall and the outer surface stay as they are) to the shares
 * frac_k^gamma of its length, gamma < 1 thickening its first layers, which
 * widens the strip and draws the cells' centres towards it (gamma > 1,
 * thinning them, helps where a column stands in a concave corner). The gamma of
 * k.relief_gamma giving the smallest skewness of the column's cells is
 * kept if it lowers that skewness, every prism around the column stays
 * valid above min(k.ortho_qmin, k.redistribute_qshare of its quality
 * before) and a smooth column's first side edge stays within
 * k.tilt_limit_deg of its normal (or within its tilt before: level 1
 * moving up along a bent polyline turns it); k.relief_sweeps sweeps over the columns, in vertex
 * order (a trailing edge's two columns share the strip). Counts the columns moved and the largest
 * column skewness before and after. */
static int skew_relief(vm_prism *p, int64_t *count, double *before, double *after) {
  int64_t nw = p->nw, moved = 0;
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * nw);
  *count = 0;
  *before = *after = 0;
  if (nl < 2) return VM_OK;
  double *sk = vm_alloc_array(p->ctx, (size_t)nw, sizeof *sk);
  double *frac = vm_alloc_array(p->ctx, (size_t)(6 * (nl + 1)), sizeof *frac);
  if (!sk || !frac) {
    vm_free(p->ctx, sk);
    vm_free(p->ctx, frac);
    return VM_ERR_NOMEM;
  }
  double *arc = frac + nl + 1, *fc = arc + nl + 1, *old = fc + nl + 1;
  double tot = common_fractions(p, nl, frac);
  if (all_column_skew(p, sk) < 0) {
    vm_free(p->ctx, sk);
    vm_free(p->ctx, frac);
    return VM_ERR_NOMEM;
  }
  for (int64_t v = 0; v < nw; v++) *before = sk[v] > *before ? sk[v] : *before;
  const int ng = (int)(sizeof p->k.relief_gamma / sizeof *p->k.relief_gamma);
  for (int sweep = 0; sweep < p->k.relief_sweeps; sweep++) {
    int64_t moved_now = 0;
    for (int64_t v = 0; v < nw; v++) {
      if (!(sk[v] > p->k.skew_limit)) continue;
      if (pr_time_left(p) <= 0) break;
      double s0 = column_skew(p, v), best = s0, q0 = INFINITY;
      int bestg = -1;
      if (!(s0 > p->k.skew_limit)) {
        sk[v] = s0;
        continue;
      }
      for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
        double q = layers_quality(p, p->vt[j], 0, nl - 1);
        q0 = q < q0 ? q : q0;
      }
      double floor = quality_floor(p, q0, p->k.redistribute_qshare);
      /* a smooth column's first side edge may not tilt beyond the 5
       * degrees it is held to (its level 1 moving up along a bent
       * polyline turns it) */
      double tilt_max = p->smooth[v] ? tilt_allowed(p, v) : 0;
      arc[0] = 0;
      for (int k = 0; k <= nl; k++) memcpy(old + 3 * k, p->lev + k * lsz + 3 * v, 3 * sizeof *old);
      for (int k = 1; k <= nl; k++) arc[k] = arc[k - 1] + vm_dist3(old + 3 * k, old + 3 * (k - 1));
      if (!(arc[nl] > 0)) continue;
      column_fractions(p, v, nl, arc[nl], frac, tot, fc);
      for (int g = 0; g < ng; g++) {
        double gamma = p->k.relief_gamma[g];
        if (!(gamma > 0)) continue;
        place_levels(p, v, nl, old, arc, fc, gamma);
        if (!column_valid(p, v, floor) || (p->smooth[v] && first_tilt(p, v) > tilt_max)) continue;
        double s1 = column_skew(p, v);
        if (s1 < best * (1 - 1e-3)) {
          best = s1;
          bestg = g;
        }
      }
      if (bestg >= 0) {
        place_levels(p, v, nl, old, arc, fc, p->k.relief_gamma[bestg]);
        moved_now++;
        /* the neighbours' cells changed with this column's */
        for (int64_t j = p->vv_off[v]; j < p->vv_off[v + 1]; j++)
          sk[p->vv[j]] = column_skew(p, p->vv[j]);
        sk[v] = best;
      } else {
        for (int k = 1; k < nl; k++) memcpy(p->lev + k * lsz + 3 * v, old + 3 * k, 3 * sizeof *old);
        sk[v] = s0;
      }
    }
    moved += moved_now;
    if (!moved_now) break;
  }
  for (int64_t v = 0; v < nw; v++) {
    double s = sk[v] > p->k.skew_limit ? column_skew(p, v) : sk[v];
    *after = s > *after ? s : *after;
  }
  vm_free(p->ctx, sk);
  vm_free(p->ctx, frac);
  *count = moved;
  return VM_OK;
}

/* Tilt of column v's first side edge from its wall normal, in degrees. */
static double first_tilt(const vm_prism *p, int64_t v) {
  return pr_tilt_deg(p->wall + 3 * v, p->lev + 3 * (p->nw + v), p->vnrm + 3 * v);
}

/* One variational solve of the columns with ring[v] >= 0 (levels
 * 1..nlev-2 free; the wall, the outer surface and every other column
 * fixed) over all layers of the triangles that touch them. The first
 * layer's targets stand along the column's own direction (the vertex
 * normal on smooth parts, the blended direction at sharp edges) with the
 * column's present height above its tangent plane and weigh
 * k.solve_weight; the other layers' targets are their present shapes
 * where those are fair prisms (quality > k.dir.fair_quality), else
 * orthogonal ones on their base surface, as in marching. With stack > 0
 * (the stack smoothing) every layer's target is the orthogonal one and the
 * solve runs stack implicit iterations once; else it runs in chunks while
 * the count of tilted smooth columns falls. The result replaces the levels
 * (*applied = 1) only if every quadrature node and every corner tet of the
 * patch is positive. */
static int solve_patch(vm_prism *p, const int8_t *ring, int stack, int *applied) {
  vm_ctx *ctx = p->ctx;
  const pr_params *kp = &p->k;
  const pr_surf ws = pr_wall_surf(p);
  int64_t nw = p->nw, nt = p->nt;
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * nw);
  int st = VM_OK;
  *applied = 0;
  int32_t *vid = vm_alloc_array(ctx, (size_t)nw, sizeof *vid);
  int32_t *tl = vm_alloc_array(ctx, (size_t)nt, sizeof *tl);
  double *fn = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *fn);
  double *dn = vm_alloc_array(ctx, 2 * lsz, sizeof *dn);
  double *hv = vm_alloc_array(ctx, (size_t)nw, sizeof *hv);
  double *tg = vm_alloc_array(ctx, (size_t)(18 * nt), sizeof *tg);
  double *w = NULL;
  vm_mesh *m = NULL;
  vm_problem *pb = NULL;
  if (!vid || !tl || !fn || !dn || !hv || !tg) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  /* the patch's triangles (one with a free column) and their columns */
  int64_t ntl = 0, nc = 0;
  for (int64_t v = 0; v < nw; v++) vid[v] = -1;
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = p->tri + 3 * t;
    if (ring[c[0]] < 0 && ring[c[1]] < 0 && ring[c[2]] < 0) continue;
    tl[ntl++] = (int32_t)t;
    for (int i = 0; i < 3; i++)
      if (vid[c[i]] < 0) vid[c[i]] = (int32_t)nc++;
  }
  int64_t ne = ntl * nl;
  w = vm_alloc_array(ctx, (size_t)ne, sizeof *w);
  if (!w) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  vm_field *tf;
  if ((st = vm_mesh_create(ctx, &m)) || (st = vm_mesh_set_vertices(m, nc * (nl + 1))) ||
      (st = vm_mesh_set_elements(m, ne, 6 * ne)) ||
      (st = vm_mesh_add_field(m, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT, VM_FIELD_F64, 18, &tf)))
    goto done;
  for (int64_t v = 0; v < nw; v++) {
    if (vid[v] < 0) continue;
    for (int k = 0; k <= nl; k++) {
      int64_t i = k * nc + vid[v];
      memcpy(m->xyz + 3 * i, p->lev + k * lsz + 3 * v, 3 * sizeof *m->xyz);
      m->vflag[i] = k == 0 || k == nl || ring[v] < 0 ? VM_VERTEX_FIXED : pr_moving_flag(p, v);
    }
  }
  for (int k = 0; k < nl; k++) {
    const double *base = p->lev + k * lsz, *up = p->lev + (k + 1) * lsz;
    if (k == 0)
      for (int64_t v = 0; v < nw; v++)
        memcpy(dn + 3 * v, (p->smooth[v] ? p->vnrm : p->dir) + 3 * v, 3 * sizeof *dn);
    else
      pr_surface_dirs(ctx, &ws, &kp->dir, base, fn, dn, dn + lsz, 0, NULL);
    for (int64_t v = 0; v < nw; v++) {
      double e[3];
      for (int c = 0; c < 3; c++) e[c] = up[3 * v + c] - base[3 * v + c];
      hv[v] = k == 0 ? vm_dot3(e, dn + 3 * v) : vm_norm3(e);
      if (!(hv[v] >= kp->min_target_height * p->elen[v]))
        hv[v] = kp->min_target_height * p->elen[v];
    }
    pr_build_targets(nt, p->tri, &kp->dir, base, k == 0 ? p->fnrm : fn, dn, hv, tg);
    for (int64_t j = 0; j < ntl; j++) {
      int64_t t = tl[j], e = k * ntl + j;
      double x[18];
      m->etype[e] = VM_PRISM;
      m->eoff[e + 1] = 6 * (e + 1);
      for (int i = 0; i < 3; i++) {
        int32_t v = p->tri[3 * t + i];
        m->conn[6 * e + i] = (int32_t)(k * nc + vid[v]);
        m->conn[6 * e + 3 + i] = (int32_t)((k + 1) * nc + vid[v]);
        memcpy(x + 3 * i, base + 3 * v, 3 * sizeof *x);
        memcpy(x + 9 + 3 * i, up + 3 * v, 3 * sizeof *x);
      }
      int own = !stack && k > 0 && pr_prism_quality(x) > kp->dir.fair_quality;
      memcpy((double *)tf->data + 18 * e, own ? x : tg + 18 * t, sizeof x);
      w[e] = k == 0 ? kp->solve_weight : 1;
    }
  }
  vm_measure_params prm = vm_measure_params_default();
  prm.theta = p->o.theta;
  if ((st = vm_problem_create(ctx, m, &pb)) ||
      (st = vm_problem_set_measure(pb, VM_MEASURE_BALANCED, &prm)) ||
      (st = vm_problem_set_rule(pb, VM_RULE_GEOMETRIC)) || (st = vm_problem_set_weights(pb, w)) ||
      (st = vm_problem_set_target_field(pb, PRISM_TARGET_FIELD)))
    goto done;
  /* the problem holds its own copy of the targets (nothing else reads the
   * patch's field: 144 bytes a prism less at the marching's peak) */
  vm_mesh_remove_field(m, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT);
  /* in chunks of k.solve_iter iterations while the count of free smooth
   * columns tilted beyond k.tilt_limit_deg falls (restarting Newton gets further
   * than one long solve: on the demo aircraft read from STL at T = 20 %,
   * 300 iterations in one solve left 1 such column and took 13 s, chunks of
   * 50 left none in 4 s) */
  int64_t prev = INT64_MAX;
  if (stack) st = pr_solve(p, pb, m, VM_MINIMIZER_IMPLICIT, stack, VM_PRISM_PHASE_MARCH, NULL);
  for (int chunk = 0; chunk < kp->solve_chunks && !stack; chunk++) {
    int it = 0;
    st = pr_solve(p, pb, m, VM_MINIMIZER_IMPLICIT, kp->solve_iter, VM_PRISM_PHASE_MARCH, &it);
    if (st < 0 || it < kp->solve_iter) break;
    int64_t left = 0;
    for (int64_t v = 0; v < nw; v++)
      if (ring[v] >= 0 && p->smooth[v])
        left += pr_tilt_deg(p->wall + 3 * v, m->xyz + 3 * (nc + vid[v]), p->vnrm + 3 * v) >
                kp->tilt_limit_deg;
    if (!left || left >= prev) break;
    prev = left;
  }
  if (st < 0) {
    /* a solve that fails leaves the levels as they were */
    if (st != VM_ERR_NOMEM && st != VM_ERR_INTERRUPTED) st = VM_OK;
    goto done;
  }
  vm_node_stats ns;
  if ((st = vm_problem_node_stats(pb, m->xyz, &ns)) < 0) goto done;
  st = VM_OK;
  if (ns.inverted) goto done;
  for (int64_t e = 0; e < ne; e++) {
    double x[18];
    for (int q = 0; q < 6; q++)
      memcpy(x + 3 * q, m->xyz + 3 * (int64_t)m->conn[6 * e + q], 3 * sizeof *x);
    int inv;
    pr_prism_corner_quality(x, &inv);
    if (inv) goto done;
  }
  for (int64_t v = 0; v < nw; v++)
    if (vid[v] >= 0 && ring[v] >= 0)
      for (int k = 1; k < nl; k++)
        memcpy(p->lev + k * lsz + 3 * v, m->xyz + 3 * (k * nc + vid[v]), 3 * sizeof *p->lev);
  *applied = 1;
done:
  vm_problem_destroy(&pb);
  vm_mesh_destroy(&m);
  vm_free(ctx, w);
  vm_free(ctx, vid);
  vm_free(ctx, tl);
  vm_free(ctx, fn);
  vm_free(ctx, dn);
  vm_free(ctx, hv);
  vm_free(ctx, tg);
  return st;
}

/* The smooth columns that standing up left tilted (first_tilt above
 * k.tilt_solve_deg) and their neighbours up to k.solve_rings rings are
 * moved together by one variational solve (solve_patch), the paper's way:
 * the barrier keeps every prism valid while the first layer's orthogonal
 * targets pull the columns up, their upper layers making room. A smooth
 * column the solve tilts beyond k.tilt_limit_deg that was within it before
 * (a neighbour, or a selected one between the two angles) is held fixed
 * and the solve redone from the levels before, at most k.solve_tries
 * times; if that never comes out clean the levels stay as they were. */
static int orthogonal_solve(vm_prism *p) {
  vm_ctx *ctx = p->ctx;
  const pr_params *kp = &p->k;
  int64_t nw = p->nw;
  size_t nlsz = (size_t)p->nlev * (size_t)(3 * nw);
  int8_t *ring = vm_alloc_array(ctx, (size_t)nw, sizeof *ring);
  double *tilt = vm_alloc_array(ctx, (size_t)nw, sizeof *tilt);
  double *keep = vm_alloc_array(ctx, nlsz, sizeof *keep);
  int st = VM_OK;
  if (!ring || !tilt || !keep) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t ntilt = 0;
  for (int64_t v = 0; v < nw; v++) {
    tilt[v] = first_tilt(p, v);
    ring[v] = p->smooth[v] && tilt[v] > kp->tilt_solve_deg ? 0 : -1;
    ntilt += ring[v] == 0;
  }
  if (!ntilt || pr_time_left(p) <= 0) goto done;
  for (int r = 0; r < kp->solve_rings; r++)
    for (int64_t v = 0; v < nw; v++)
      if (ring[v] == r)
        for (int64_t j = p->vv_off[v]; j < p->vv_off[v + 1]; j++)
          if (ring[p->vv[j]] < 0) ring[p->vv[j]] = (int8_t)(r + 1);
  memcpy(keep, p->lev, nlsz * sizeof *keep);
  for (int attempt = 0; attempt < kp->solve_tries; attempt++) {
    int applied;
    if ((st = solve_patch(p, ring, 0, &applied)) < 0 || !applied) break;
    int64_t worse = 0;
    for (int64_t v = 0; v < nw; v++)
      if (ring[v] >= 0 && p->smooth[v] && tilt[v] <= kp->tilt_limit_deg &&
          first_tilt(p, v) > kp->tilt_limit_deg) {
        ring[v] = -1;
        worse++;
      }
    if (!worse) break;
    memcpy(p->lev, keep, nlsz * sizeof *keep);
  }
done:
  vm_free(ctx, ring);
  vm_free(ctx, tilt);
  vm_free(ctx, keep);
  return st;
}

/* Angle in degrees between prism x's bottom normal and the line joining
 * its bottom and top centroids: the OpenFOAM non-orthogonality of the face
 * between it and the layer below, nearly. */
static double prism_lean_deg(const double *x) {
  double e1[3], e2[3], nb[3], d[3];
  for (int c = 0; c < 3; c++) {
    e1[c] = x[3 + c] - x[c];
    e2[c] = x[6 + c] - x[c];
    d[c] = (x[9 + c] + x[12 + c] + x[15 + c] - x[c] - x[3 + c] - x[6 + c]) / 3;
  }
  vm_cross3(e1, e2, nb);
  double l = vm_norm3(nb) * vm_norm3(d), cs = l > 0 ? vm_dot3(nb, d) / l : -1;
  return acos(cs < -1 ? -1 : cs > 1 ? 1 : cs) * 180 / PR_PI;
}

/* The final variational smoothing of the layer stack where it leans: the
 * columns carrying a prism of layers 1..nlev-2 (every layer above the
 * first, the outermost included) that leans beyond
 * k.stack_lean_deg (prism_lean_deg), or of the outermost layer whose outer
 * face is skewed beyond k.skew_limit, and their neighbours up to
 * k.solve_rings rings move together in one implicit solve of (13) over all
 * layers of their triangles (solve_patch, every layer's target orthogonal
 * to its own base with the present side-edge lengths, the first layer's
 * along the wall normal with weight k.solve_weight; the wall, the outer
 * surface and every other column fixed; the barrier keeps every prism
 * valid, and the result is kept only if every node and corner tet is
 * positive). */
static int stack_smooth(vm_prism *p) {
  vm_ctx *ctx = p->ctx;
  const pr_params *kp = &p->k;
  int64_t nw = p->nw, nt = p->nt, nsel = 0;
  size_t lsz = (size_t)(3 * nw);
  if (kp->stack_iter <= 0 || pr_time_left(p) <= 0) return VM_OK;
  int8_t *ring = vm_alloc_array(ctx, (size_t)nw, sizeof *ring);
  if (!ring) return VM_ERR_NOMEM;
  memset(ring, -1, (size_t)nw);
  for (int64_t t = 0; t < nt; t++)
    for (int k = 1; k < p->nlev - 1; k++) {
      double x[18];
      for (int i = 0; i < 3; i++) {
        memcpy(x + 3 * i, p->lev + k * lsz + 3 * (size_t)p->tri[3 * t + i], 3 * sizeof *x);
        memcpy(x + 9 + 3 * i, p->lev + (k + 1) * lsz + 3 * (size_t)p->tri[3 * t + i],
               3 * sizeof *x);
      }
      double cc[3];
      if (k == p->nlev - 2) pr_foam_cell(x, cc);
      if (prism_lean_deg(x) > kp->stack_lean_deg ||
          (k == p->nlev - 2 && pr_foam_boundary_skew(x + 9, 3, cc) > kp->skew_limit)) {
        for (int i = 0; i < 3; i++) ring[p->tri[3 * t + i]] = 0;
        break;
      }
    }
  for (int64_t v = 0; v < nw; v++) nsel += ring[v] == 0;
  for (int r = 0; r < kp->solve_rings; r++)
    for (int64_t v = 0; v < nw; v++)
      if (ring[v] == r)
        for (int64_t j = p->vv_off[v]; j < p->vv_off[v + 1]; j++)
          if (ring[p->vv[j]] < 0) ring[p->vv[j]] = (int8_t)(r + 1);
  int applied = 0, st = VM_OK;
  int64_t nback = 0;
  size_t nlsz = (size_t)p->nlev * lsz;
  double *keep = nsel ? vm_alloc_array(ctx, nlsz, sizeof *keep) : NULL;
  double *sk0 = nsel ? vm_alloc_array(ctx, (size_t)nw, sizeof *sk0) : NULL;
  uint8_t *back = nsel ? vm_calloc(ctx, (size_t)nw, sizeof *back) : NULL;
  if (nsel && (!keep || !sk0 || !back)) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if (nsel) {
    memcpy(keep, p->lev, nlsz * sizeof *keep);
    if ((st = all_column_skew(p, sk0)) < 0) goto done;
    st = solve_patch(p, ring, kp->stack_iter, &applied);
  }
  if (st < 0 || !applied) goto done;
  /* the columns whose cells' faces the solve made skewed beyond
   * k.skew_limit go back, then those sharing a prism that the mix of old
   * and new levels leaves invalid, until none is */
  {
    double *sk1 = vm_alloc_array(ctx, (size_t)nw, sizeof *sk1);
    if (!sk1 || (st = all_column_skew(p, sk1)) < 0) {
      vm_free(ctx, sk1);
      st = st < 0 ? st : VM_ERR_NOMEM;
      goto done;
    }
    for (int64_t v = 0; v < nw; v++)
      if (ring[v] >= 0) back[v] = sk1[v] > kp->skew_limit && sk1[v] > sk0[v];
    vm_free(ctx, sk1);
  }
  for (int changed = 1; changed;) {
    changed = 0;
    for (int64_t v = 0; v < nw; v++)
      if (back[v] == 1) {
        for (int k = 1; k < p->nlev - 1; k++)
          memcpy(p->lev + k * lsz + 3 * v, keep + k * lsz + 3 * v, 3 * sizeof *keep);
        back[v] = 2;
        nback++;
      }
    for (int64_t t = 0; t < nt; t++) {
      const int32_t *c = p->tri + 3 * t;
      if (!(back[c[0]] == 2 || back[c[1]] == 2 || back[c[2]] == 2)) continue;
      if (back[c[0]] && back[c[1]] && back[c[2]]) continue;
      int bad = 0;
      for (int k = 0; k < p->nlev - 1 && !bad; k++) {
        double x[18];
        int inv;
        pr_prism_at(p, p->lev, t, k, x);
        pr_prism_corner_quality(x, &inv);
        bad = inv || !(pr_prism_quality(x) > 0);
      }
      if (bad)
        for (int i = 0; i < 3; i++)
          if (!back[c[i]]) {
            back[c[i]] = 1;
            changed = 1;
          }
    }
  }
done:
  vm_log(ctx, VM_LOG_INFO, "prism: stack smoothing of %lld leaning columns%s, %lld put back",
         (long long)nsel, nsel && !applied ? " not applied" : "", (long long)nback);
  vm_free(ctx, keep);
  vm_free(ctx, sk0);
  vm_free(ctx, back);
  vm_free(ctx, ring);
  return st;
}

int vm_prism_march(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 4) return vm_error(p->ctx, VM_ERR_ARG, "prism: marching needs the restored layer");
  /* the single layer's problem (springback, cutting, restoring) is done
   * with: its node targets and graph go before the marching's peak */
  vm_problem_destroy(&p->prob);
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  const pr_params *kp = &p->k;
  const pr_surf ws = pr_wall_surf(p);
  int64_t nw = p->nw, nt = p->nt;
  int n = p->rep.layers_requested;
  size_t lsz = (size_t)(3 * nw);
  int st = VM_OK, warn = VM_OK;
  vm_mesh *m2 = NULL;
  vm_problem *pb = NULL;
  double *own = NULL; /* per column shares, with regions (below) */
  double *fn = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *fn);
  double *vn = vm_alloc_array(ctx, lsz, sizeof *vn);
  double *dr = vm_alloc_array(ctx, lsz, sizeof *dr);
  double *hk = vm_alloc_array(ctx, (size_t)nw, sizeof *hk);
  double *w = vm_alloc_array(ctx, (size_t)(2 * nt), sizeof *w);
  p->lev = vm_alloc_array(ctx, (size_t)(n + 1) * lsz, sizeof *p->lev);
  if (!fn || !vn || !dr || !hk || !w || !p->lev) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(p->lev, p->wall, lsz * sizeof *p->lev);
  const double *outer = p->layer->xyz + lsz;
  /* the two-sublayer mesh: base (fixed), middle (free), outer (fixed) */
  if ((st = vm_mesh_create(ctx, &m2)) || (st = vm_mesh_set_vertices(m2, 3 * nw)) ||
      (st = vm_mesh_set_elements(m2, 2 * nt, 12 * nt)))
    goto done;
  for (int64_t v = 0; v < nw; v++) {
    m2->vflag[v] = VM_VERTEX_FIXED;
    m2->vflag[nw + v] = pr_moving_flag(p, v);
    m2->vflag[2 * nw + v] = VM_VERTEX_FIXED;
  }
  for (int64_t s = 0; s < 2; s++)
    for (int64_t t = 0; t < nt; t++) {
      int64_t e = s * nt + t;
      m2->etype[e] = VM_PRISM;
      m2->eoff[e + 1] = 6 * (e + 1);
      for (int i = 0; i < 3; i++) {
        m2->conn[6 * e + i] = (int32_t)(p->tri[3 * t + i] + s * nw);
        m2->conn[6 * e + 3 + i] = (int32_t)(p->tri[3 * t + i] + (s + 1) * nw);
      }
      w[e] = s == 0 ? p->o.ortho_weight : 1;
    }
  memcpy(m2->xyz + 2 * lsz, outer, lsz * sizeof *m2->xyz);
  vm_field *tf;
  if ((st = vm_mesh_add_field(m2, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT, VM_FIELD_F64, 18, &tf)))
    goto done;
  double *tg = tf->data;
  if ((st = vm_problem_create(ctx, m2, &pb))) goto done;
  vm_measure_params prm = vm_measure_params_default();
  prm.theta = p->o.theta;
  /* two sublayers: their node targets stay stored however large (a tenth
   * of the stack smoothing's patch at most, and freed before it; computing
   * them at every evaluation made the splits 18 % slower) */
  if ((st = vm_problem_set_measure(pb, VM_MEASURE_BALANCED, &prm)) ||
      (st = vm_problem_set_rule(pb, VM_RULE_GEOMETRIC)) || (st = vm_problem_set_weights(pb, w)) ||
      (st = vm_problem_set_target_store(pb, INT64_MAX)))
    goto done;
  int made = n; /* levels 0..made */
  double rem = 0;
  for (int k = 0; k < n; k++) rem += p->sched[k];
  /* with a thickness or a layer count per region, each column aiming
   * below T (and each column with a first height of its own, p->h1v)
   * splits at its own schedule's shares (column_fractions, from its length now): a
   * thinner region's first layer at the first height (the common shares
   * scaled to a short column made it len/T of the first height, and the
   * redistribution after the splits could not always move it back: 0.14
   * of it over vm-gen aircraft's fuselage at 10 of 20 layers). A column
   * whose layers end gets its own count in ends.c, along this course.
   * (Splitting such a column at its own count here, its other levels in
   * a thin band under its top, stopped the marching at split 15 of 19 on
   * the demo aircraft: wedges where a band meets a full column.) */
  if ((p->regional || p->h1v) && n >= 2) {
    own = vm_alloc_array(ctx, (size_t)(n + 1) * (size_t)nw + 2 * (size_t)(n + 1), sizeof *own);
    if (!own) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    double *frac = own + (size_t)(n + 1) * (size_t)nw, *fc = frac + n + 1;
    double tot = common_fractions(p, n, frac);
    /* a column aiming at T keeps the common split, as without regions
     * (bit for bit: its row starts with -1) */
    for (int64_t v = 0; v < nw; v++) {
      int mine = (p->tv[v] < p->o.thickness || pr_first_height(p, v) > p->sched[0]) &&
                 column_fractions(p, v, n, vm_dist3(outer + 3 * v, p->wall + 3 * v), frac, tot, fc);
      if (mine)
        memcpy(own + (size_t)(n + 1) * (size_t)v, fc, (size_t)(n + 1) * sizeof *fc);
      else
        own[(size_t)(n + 1) * (size_t)v] = -1;
    }
  }
  for (int k = 0; k + 1 < n; k++) {
    if (pr_time_left(p) <= 0) {
      made = k + 1;
      warn = VM_WARN_TIME;
      break;
    }
    double *base = p->lev + (size_t)k * lsz;
    /* the split at the schedule's fraction; where that straight split is
     * not valid (a twisted column: the sub-prisms' quadrature nodes fall
     * where the remainder's map folds between its own nodes), slightly
     * thinner or thicker splits are tried; the schedule's later layers
     * absorb the difference */
    const double *fmul = kp->split_mul;
    const int nmul = (int)(sizeof kp->split_mul / sizeof *kp->split_mul);
    double f0 = p->sched[k] / rem;
    rem -= p->sched[k];
    const char *why = NULL;
    vm_node_stats ns;
    int it = 0;
    pr_surface_dirs(ctx, &ws, &kp->dir, base, fn, vn, dr, 0, NULL);
    /* with shares of their own (regions, raised first heights), the
     * columns' own splits first; where none of those is valid, the
     * schedule's common split for every column, as without them (the
     * redistribution below puts the columns on their own shares where
     * that stays valid): on vm-gen aircraft remeshed by vm-surface --size
     * graded the raised first heights' own split was not valid at any
     * multiplier, and the marching stopped at its first split */
    int common = 0; /* the split taken is the common one, own shares refused */
    for (int jj = 0; jj < (own ? 2 : 1) * nmul; jj++) {
      int j = jj % nmul, use_own = own && jj < nmul;
      common = own && !use_own;
      double f = f0 * fmul[j];
      if (j > 0 && f > kp->split_max_frac) continue;
      memcpy(m2->xyz, base, lsz * sizeof *m2->xyz);
      for (int64_t v = 0; v < nw; v++) {
        double *mv = m2->xyz + lsz + 3 * v;
        double fv = f;
        if (use_own && own[(size_t)(n + 1) * (size_t)v] >= 0) {
          const double *fc = own + (size_t)(n + 1) * (size_t)v;
          fv = (fc[k + 1] - fc[k]) / (1 - fc[k]) * fmul[j];
          if (fv > kp->split_max_frac) fv = kp->split_max_frac;
        }
        for (int c = 0; c < 3; c++)
          mv[c] = base[3 * v + c] + fv * (outer[3 * v + c] - base[3 * v + c]);
        /* a column cut to (almost) nothing still gets a proper target */
        hk[v] = fv * vm_dist3(outer + 3 * v, base + 3 * v);
        if (!(hk[v] >= kp->min_target_height * p->elen[v]))
          hk[v] = kp->min_target_height * p->elen[v];
      }
      /* inner targets: orthogonal to the base surface (vertex normals,
       * bent towards the face normal only where needed); outer targets:
       * the shape at the split where it is a fair prism, else (a twisted
       * column split along straight side edges can give a flat or
       * inverted sub-prism) the inner target's shape, which is always
       * valid */
      pr_build_targets(nt, p->tri, &kp->dir, base, fn, vn, hk, tg);
      for (int64_t t = 0; t < nt; t++) {
        const int32_t *c = m2->conn + 6 * (nt + t);
        double x[18];
        for (int q = 0; q < 6; q++) memcpy(x + 3 * q, m2->xyz + 3 * (int64_t)c[q], 3 * sizeof *x);
        memcpy(tg + 18 * (nt + t), pr_prism_quality(x) > kp->dir.fair_quality ? x : tg + 18 * t,
               sizeof x);
      }
      /* a split that cannot be made valid ends the marching early (the
       * paper's option): levels 0..k are valid, and so is the remainder
       * from level k to the outer surface (checked with the previous
       * split) */
      why = NULL;
      if ((st = vm_problem_set_target_field(pb, PRISM_TARGET_FIELD)) < 0) {
        why = "degenerate target";
      } else if ((st = vm_problem_node_stats(pb, m2->xyz, &ns)) < 0) {
        why = "node statistics";
      } else if (ns.inverted) {
        why = "the straight split is not valid";
        continue;
      }
      break;
    }
    if (!why) {
      st = pr_solve(p, pb, m2, VM_MINIMIZER_EXPLICIT, p->o.march_iter, VM_PRISM_PHASE_MARCH, &it);
      if (st == VM_WARN_TIME) warn = st;
      if (st < 0) {
        why = "solver";
      } else if ((st = vm_problem_node_stats(pb, m2->xyz, &ns)) < 0) {
        why = "node statistics";
      } else if (ns.inverted) {
        why = "inverted nodes after the solve";
      }
    }
    if (why) {
      if (st == VM_ERR_NOMEM || st == VM_ERR_INTERRUPTED) goto done;
      vm_log(ctx, VM_LOG_WARN, "prism: marching stopped at split %d of %d (%s); %d layers", k + 1,
             n - 1, why, k + 1);
      made = k + 1;
      warn = VM_WARN_MAXITER;
      st = VM_OK;
      break;
    }
    if (common)
      vm_log(ctx, VM_LOG_INFO,
             "prism: split %d of %d: the columns' own shares are not valid; the schedule's "
             "common split taken",
             k + 1, n - 1);
    memcpy(p->lev + (size_t)(k + 1) * lsz, m2->xyz + lsz, lsz * sizeof *p->lev);
    pr_progress(p, VM_PRISM_PHASE_MARCH, k + 1, p->sched[k], 0, 0);
  }
  memcpy(p->lev + (size_t)made * lsz, outer, lsz * sizeof *p->lev);
  p->nlev = made + 1;
  /* the splits' problem and mesh go before the stack smoothing's patch
   * solve, the marching's peak */
  vm_problem_destroy(&pb);
  vm_mesh_destroy(&m2);
  /* seconds of the marching's steps: splits, stack smoothing,
   * redistribution, orthogonal first level, orthogonal solve, skewness
   * relief, non-orthogonality relief, growth relief */
  double ts[9];
  ts[0] = t0;
  ts[1] = omp_get_wtime();
  if (p->nlev > 2 && (st = stack_smooth(p)) < 0) goto done;
  ts[2] = omp_get_wtime();
  if (p->nlev > 2) {
    int64_t nr = 0;
    if ((st = redistribute_columns(p, &nr)) < 0) goto done;
    vm_log(ctx, VM_LOG_INFO, "prism: %lld columns put back on the schedule", (long long)nr);
  }
  ts[3] = omp_get_wtime();
  if (p->nlev > 2 && (st = orthogonal_first_level(p)) < 0) goto done;
  ts[4] = omp_get_wtime();
  if (p->nlev > 2 && (st = orthogonal_solve(p)) < 0) goto done;
  ts[5] = omp_get_wtime();
  if (p->nlev > 2) {
    int64_t nr = 0;
    double s0 = 0, s1 = 0;
    if ((st = skew_relief(p, &nr, &s0, &s1)) < 0) goto done;
    vm_log(ctx, VM_LOG_INFO,
           "prism: skewness relief: %lld columns re-spaced; largest OpenFOAM skewness %.3g -> %.3g",
           (long long)nr, s0, s1);
  }
  ts[6] = omp_get_wtime();
  if (p->nlev > 2) {
    pr_ortho_summary os;
    if ((st = pr_ortho_relief(p, &os)) < 0) goto done;
    vm_log(ctx, VM_LOG_INFO,
           "prism: non-orthogonality relief: %lld steps in %d sweeps (%lld of the outer surface, "
           "%d of its batches taken again); faces beyond 70 degrees %lld -> %lld, largest "
           "non-orthogonality %.1f -> %.1f degrees, cells with a determinant below 0.001 %lld "
           "-> %lld",
           (long long)os.moves, os.sweeps, (long long)os.outer_moves, os.outer_batches_undone,
           (long long)os.over70_before, (long long)os.over70_after,
           acos(os.cmin_before) * 180 / PR_PI, acos(os.cmin_after) * 180 / PR_PI,
           (long long)os.det_before, (long long)os.det_after);
    if (os.split_before)
      vm_log(ctx, VM_LOG_INFO,
             "prism: split repair: %lld steps in %d rounds (%d outer batches taken again "
             "step by step); prisms not positive in every 3-tet split %lld -> %lld (the least "
             "scaled Jacobian %.3g kept), %.2f s",
             (long long)os.split_moves, os.split_rounds, os.split_batches_undone,
             (long long)os.split_before, (long long)os.split_after, os.split_sj, os.split_time);
  }
  ts[7] = omp_get_wtime();
  if (p->nlev > 2 && p->o.growth_relief) {
    int64_t ng = 0;
    if ((st = growth_relief(p, &ng)) < 0) goto done;
    p->rep.growth_respaced = ng;
    vm_log(ctx, VM_LOG_INFO, "prism: growth relief: %lld columns re-spaced towards the growth law",
           (long long)ng);
  }
  ts[8] = omp_get_wtime();
  for (int k = 0; k < VM_PRISM_NMARCH_STEPS; k++) p->rep.march_time[k] += ts[k + 1] - ts[k];
  vm_log(ctx, VM_LOG_INFO,
         "prism: marching steps (s): splits %.2f, stack smoothing %.2f, redistribution %.2f, "
         "orthogonal first level %.2f, orthogonal solve %.2f, skewness relief %.2f, "
         "non-orthogonality relief %.2f, growth relief %.2f",
         ts[1] - ts[0], ts[2] - ts[1], ts[3] - ts[2], ts[4] - ts[3], ts[5] - ts[4], ts[6] - ts[5],
         ts[7] - ts[6], ts[8] - ts[7]);
  /* the paper's option: drop a skewed outermost remainder */
  if (p->o.drop_quality > 0 && p->nlev > 2 &&
      level_quality(p, p->lev + (size_t)(p->nlev - 2) * lsz, p->lev + (size_t)(p->nlev - 1) * lsz) <
          p->o.drop_quality)
    p->nlev--;
  /* layers that end where a region asks for fewer */
  if ((st = pr_end_layers(p)) < 0) goto done;
  p->rep.layers = p->nlev - 1;
  p->done = 5;
  st = warn;
done:
  vm_problem_destroy(&pb);
  vm_mesh_destroy(&m2);
  vm_free(ctx, own);
  vm_free(ctx, fn);
  vm_free(ctx, vn);
  vm_free(ctx, dr);
  vm_free(ctx, hk);
  vm_free(ctx, w);
  p->rep.time[VM_PRISM_PHASE_MARCH] += omp_get_wtime() - t0;
  return st;
}
