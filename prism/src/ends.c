/* prism/src/ends.c: layers that end where a region asks for fewer of
 * them. The marching builds every column with the stack's layer count;
 * here a column with a count n of its own (prism.c's region_counts: the
 * least of its faces', at most what fits its aim) takes n layers along
 * its course: level k at h1 (1 + r_c + ... + r_c^(k-1)) of its length, h1
 * the schedule's first height and r_c the ratio that makes n such heights
 * fill the column (as a shortened column's own schedule in march.c), and
 * its levels n..N at its top. A face whose columns' counts differ gets, in
 * the layers above the smaller counts, pyramids (one column ended) and
 * tetrahedra (two ended): the stack stays conformal and its outer surface
 * is still one triangle per wall face. Every cell on a face with an ended
 * column is checked as a solver checks it, and the face's skewness as
 * OpenFOAM measures it; where one fails, the smallest count on that face
 * goes up by one (at the stack's count, the column's levels are the
 * marching's again, bit for bit), and the check runs again until none
 * fails. It stops: counts only rise, and a stack with no column ended is
 * the marching's, which is valid.
 *
 * Short columns (vm_prism_opts.end_short): where the layer has cells below
 * OpenFOAM's determinant limit (checkMesh -allGeometry), each column
 * shorter than its aim is first given the schedule's layers that fit its
 * length (fit_counts: heights h1 r^k, as a full column's first layers),
 * so that a squeeze does not put all the layers into a fraction of T
 * (two spheres 0.03 apart at T = 0.10: 20 layers in 0.015, every cell 80
 * times wider than high). After the checks above, each patch of such
 * columns is kept only where it lowers the cells below the limit on its
 * faces to at most k.end_short_gain of what they were (keep_patches); the
 * others go back to the marching's stack, bit for bit. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "state.h"
#include "varmesh/jacobian.h"
#include "varmesh/quality.h"

/* Column v's levels 1..n-1 on its own schedule along its polyline (levels
 * 0..nl of `old`, by arc length), levels n..nl at its top. Level 1 keeps
 * the direction of the marching's first side edge (stood up along the wall
 * normal; by arc length alone it could slide onto the next, leaning
 * segment: 5-40 degrees off the normal on vm-gen aircraft), at the own
 * schedule's first height. */
static void end_column(vm_prism *p, int64_t v, int n, int nl, const double *old) {
  size_t lsz = (size_t)(3 * p->nw);
  double arc[1001];
  arc[0] = 0;
  for (int k = 1; k <= nl; k++)
    arc[k] = arc[k - 1] + vm_dist3(old + k * lsz + 3 * v, old + (k - 1) * lsz + 3 * v);
  double len = arc[nl], h1 = pr_first_height(p, v);
  const double *top = old + (size_t)nl * lsz + 3 * v, *w = old + 3 * v, *o1 = old + lsz + 3 * v;
  int equal = !(h1 * n < len);
  double rc = equal ? 1 : pr_growth_ratio(h1, n, len, p->k.sched_bisect_iter), a = 0, h = h1;
  for (int k = 1, s = 0; k < n; k++) {
    a = equal ? len * k / n : a + h;
    h *= rc;
    if (k == 1 && arc[1] > 0) {
      for (int c = 0; c < 3; c++) p->lev[lsz + 3 * v + c] = w[c] + a / arc[1] * (o1[c] - w[c]);
      continue;
    }
    while (s + 1 < nl && arc[s + 1] < a) s++;
    double u = arc[s + 1] > arc[s] ? (a - arc[s]) / (arc[s + 1] - arc[s]) : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    const double *x0 = old + s * lsz + 3 * v, *x1 = old + (s + 1) * lsz + 3 * v;
    for (int c = 0; c < 3; c++) p->lev[k * lsz + 3 * v + c] = x0[c] + u * (x1[c] - x0[c]);
  }
  for (int k = n; k <= nl; k++) memcpy(p->lev + k * lsz + 3 * v, top, 3 * sizeof *top);
}

/* Does cell (t, k) pass what a solver checks? A prism: every corner tet
 * positive, and every 3-tet split unless the marching's prism failed one
 * already (split_before); a pyramid: certified det J > 0 everywhere
 * (vm_jacobian_certify) and no wrong face pyramid (vm_cell_foam); a tet:
 * positive volume. */
/* Does cell (t, k) pass what a solver checks? A prism: every corner tet
 * positive, and every 3-tet split unless the marching's prism failed one
 * already (split_before); a pyramid: certified det J > 0 everywhere
 * (vm_jacobian_certify); every cell: no wrong face pyramid and a positive
 * volume (vm_cell_foam). */
static int cell_ok(const vm_prism *p, int64_t t, int k, int nl, int split_before) {
  double x[18];
  int nv;
  int type = pr_cell_at(p, p->lev, t, k, nl, x, &nv);
  if (type < 0) return 1;
  if (type == VM_PRISM) {
    int inv;
    pr_prism_corner_quality(x, &inv);
    if (inv) return 0;
    if (!split_before && vm_prism_split_check(x, NULL) > 0) return 0;
  } else if (type == VM_PYRAMID &&
             vm_jacobian_certify(type, x, p->k.end_certify_depth, NULL) != VM_JAC_VALID) {
    return 0;
  }
  double vol = 0;
  return vm_cell_foam(type, x, &vol) == 0 && vol > 0;
}

/* OpenFOAM's centre of cell (t, k) at levels L (its prism's coordinates,
 * ended columns' levels coinciding: their faces of zero area weigh
 * nothing). */
static void centre(const vm_prism *p, const double *L, int64_t t, int k, double *c) {
  double x[18];
  pr_prism_at(p, L, t, k, x);
  pr_foam_cell(x, c);
}

/* The largest OpenFOAM skewness over the faces of triangle t's cells at
 * levels L, as pr_foam_figures counts them (no cell where its three
 * columns have ended, no side face where its two have). */
static double tri_skew(const vm_prism *p, const double *L, int64_t t, int nl) {
  const int32_t *tc = p->tri + 3 * t;
  int top[3];
  for (int i = 0; i < 3; i++) top[i] = pr_col_top(p, tc[i], nl);
  double worst = 0;
  for (int k = 0; k < nl; k++) {
    if (top[0] <= k && top[1] <= k && top[2] <= k) break;
    double x[18], cp[3], cn[3], y[12];
    pr_prism_at(p, L, t, k, x);
    pr_foam_cell(x, cp);
    int last = k == nl - 1 || (top[0] <= k + 1 && top[1] <= k + 1 && top[2] <= k + 1);
    for (int f = 0; f < 5; f++) {
      if (f >= 2 && top[f - 2] <= k && top[(f - 1) % 3] <= k) continue;
      int n = pr_prism_faces[f][3] < 0 ? 3 : 4;
      for (int i = 0; i < n; i++) memcpy(y + 3 * i, x + 3 * pr_prism_faces[f][i], 3 * sizeof *y);
      double sk;
      if ((f == 0 && k == 0) || (f == 1 && last)) {
        sk = pr_foam_boundary_skew(y, n, cp);
      } else {
        int64_t u = f <= 1 ? t : pr_tri_across(p, t, f - 2);
        if (u < 0) { /* a half model's face on its symmetry plane */
          sk = pr_foam_boundary_skew(y, n, cp);
        } else {
          centre(p, L, u, f == 0 ? k - 1 : f == 1 ? k + 1 : k, cn);
          sk = pr_foam_skew(y, n, cp, cn);
        }
      }
      worst = sk > worst ? sk : worst;
    }
  }
  return worst;
}

double pr_cell_foam_det(const vm_prism *p, const double *L, int64_t t, int k, int nl) {
  double x[18], s[6][3];
  int nv, fv[6][4], nfv[6], n = 0;
  int type = pr_cell_at(p, L, t, k, nl, x, &nv);
  if (type < 0) return INFINITY;
  int nf = vm_elem_faces(type, fv, nfv);
  for (int f = 0; f < nf; f++) {
    if (type == VM_PRISM && k == 0 && nfv[f] == 3 && fv[f][0] < 3 && fv[f][1] < 3 && fv[f][2] < 3)
      continue;
    double y[12], c[3];
    for (int i = 0; i < nfv[f]; i++) memcpy(y + 3 * i, x + 3 * fv[f][i], 3 * sizeof *y);
    vm_foam_face(y, nfv[f], c, s[n++]);
  }
  return vm_foam_cell_determinant(n, (const double(*)[3])s);
}

/* The cells of triangle t's stack below OpenFOAM's determinant limit. */
static int tri_flat(const vm_prism *p, int64_t t, int nl) {
  int n = 0;
  for (int k = 0; k < nl; k++) n += pr_cell_foam_det(p, p->lev, t, k, nl) < PR_FOAM_DET_MIN;
  return n;
}

/* Each column shorter than its aim (a squeeze: contact, a gap) given the
 * schedule's layers that fit its length: the count n of heights h1 r^k
 * (its first height, the growth ratio) whose sum reaches its length, or
 * passes it by less than half the next height. Returns the columns whose
 * count fell. */
static int64_t fit_counts(vm_prism *p, const double *old) {
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * p->nw);
  int64_t nf = 0;
  for (int64_t v = 0; v < p->nw; v++) {
    double len = 0;
    for (int k = 1; k <= nl; k++)
      len += vm_dist3(old + k * lsz + 3 * v, old + (k - 1) * lsz + 3 * v);
    if (!(len < (1 - p->o.full_tol) * p->tv[v])) continue;
    double h = pr_first_height(p, v), sum = 0;
    int n = 1;
    for (; n < nl; n++) {
      sum += h;
      h *= p->rep.growth;
      if (sum + 0.5 * h >= len) break;
    }
    if (n < p->nlv[v]) {
      p->nlv[v] = n;
      nf++;
    }
  }
  return nf;
}

/* OpenFOAM's centre c and volume *v of cell (t, k) at levels L (its
 * prism's coordinates, ended columns' levels coinciding). */
static void centre_volume(const vm_prism *p, const double *L, int64_t t, int k, double *c,
                          double *v) {
  double x[18], fc[5][3], fs[5][3];
  pr_prism_at(p, L, t, k, x);
  pr_foam_cell_faces(x, c, fc, fs);
  *v = 0;
  for (int f = 0; f < 5; f++) {
    double d[3];
    for (int r = 0; r < 3; r++) d[r] = fc[f][r] - c[r];
    *v += vm_dot3(fs[f], d) / 3;
  }
}

/* The faces of triangle t's cells at levels L inside the hybrid mesh (each
 * seen from this side) whose OpenFOAM interpolation weight is below 0.05
 * (*nw) and whose cells' volume ratio is below 0.01 (*nv), as checkMesh
 * -allGeometry counts them; faces as tri_skew takes them; over the outer
 * surface, a regular tet on the outer face stands for the fill's. */
static void tri_weights(const vm_prism *p, const double *L, int64_t t, int nl, int *nw, int *nv) {
  const int32_t *tc = p->tri + 3 * t;
  int top[3];
  for (int i = 0; i < 3; i++) top[i] = pr_col_top(p, tc[i], nl);
  *nw = *nv = 0;
  for (int k = 0; k < nl; k++) {
    if (top[0] <= k && top[1] <= k && top[2] <= k) break;
    double x[18], cp[3], cn[3], y[12], vp, vn;
    pr_prism_at(p, L, t, k, x);
    centre_volume(p, L, t, k, cp, &vp);
    int last = k == nl - 1 || (top[0] <= k + 1 && top[1] <= k + 1 && top[2] <= k + 1);
    for (int f = 0; f < 5; f++) {
      if (f >= 2 && top[f - 2] <= k && top[(f - 1) % 3] <= k) continue;
      if (f == 0 && k == 0) continue;
      int outer = f == 1 && last;
      int64_t u = f <= 1 ? t : pr_tri_across(p, t, f - 2);
      if (u < 0) continue;
      int n = pr_prism_faces[f][3] < 0 ? 3 : 4;
      for (int i = 0; i < n; i++) memcpy(y + 3 * i, x + 3 * pr_prism_faces[f][i], 3 * sizeof *y);
      double fc[3], fs[3];
      vm_foam_face(y, n, fc, fs);
      if (outer) {
        /* the fill's tet over the outer face, as a regular one on it (the
         * fill grades its tets from the envelope's triangles) */
        double ls = vm_norm3(fs), e = sqrt(4 * ls / sqrt(3.0)), h = e * sqrt(2.0 / 3.0);
        if (!(ls > 0)) continue;
        double sg = vm_dot3(fs, fc) - vm_dot3(fs, cp) > 0 ? 1 : -1;
        for (int r = 0; r < 3; r++) cn[r] = fc[r] + sg * fs[r] / ls * h / 4;
        vn = e * e * e / (6 * sqrt(2.0));
      } else {
        centre_volume(p, L, u, f == 0 ? k - 1 : f == 1 ? k + 1 : k, cn, &vn);
      }
      *nw += !(vm_foam_weight(fc, fs, cp, cn) >= 0.05);
      double lo = fabs(vp) < fabs(vn) ? fabs(vp) : fabs(vn),
             hi = fabs(vp) < fabs(vn) ? fabs(vn) : fabs(vp);
      *nv += !(lo >= 0.01 * hi);
    }
  }
}

/* The patches of columns that end below their count n0 after the fit
 * (connected along wall edges), each judged by the faces around its
 * columns: kept if their cells below the determinant limit (fl0 before,
 * per face) are at most half of what they were, else its columns go back
 * to the marching's levels. Two columns of one face are neighbours, so
 * the faces around different patches are different and each patch is
 * judged alone. *ncols, *npatch, *nkept: the columns kept, the patches,
 * those kept. */
static int keep_patches(vm_prism *p, const double *old, const int32_t *n0, const int32_t *fl0,
                        int64_t *ncols, int64_t *npatch, int64_t *nkept) {
  int64_t nw = p->nw, nt = p->nt;
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * nw);
  uint8_t *seen = vm_calloc(p->ctx, (size_t)nw, 1), *mark = vm_calloc(p->ctx, (size_t)nt, 1);
  int32_t *cols = vm_alloc_array(p->ctx, (size_t)nw, sizeof *cols);
  int32_t *faces = vm_alloc_array(p->ctx, (size_t)nt, sizeof *faces);
  *ncols = *npatch = *nkept = 0;
  if (!seen || !mark || !cols || !faces) {
    vm_free(p->ctx, seen);
    vm_free(p->ctx, mark);
    vm_free(p->ctx, cols);
    vm_free(p->ctx, faces);
    return VM_ERR_NOMEM;
  }
  for (int64_t s = 0; s < nw; s++) {
    if (seen[s] || !(p->nlv[s] < n0[s])) continue;
    int64_t nc = 0, nf = 0, before = 0, after = 0;
    cols[nc++] = (int32_t)s;
    seen[s] = 1;
    for (int64_t h = 0; h < nc; h++) {
      int32_t v = cols[h];
      for (int64_t j = p->vv_off[v]; j < p->vv_off[v + 1]; j++) {
        int32_t u = p->vv[j];
        if (!seen[u] && p->nlv[u] < n0[u]) {
          seen[u] = 1;
          cols[nc++] = u;
        }
      }
      for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++)
        if (!mark[p->vt[j]]) {
          mark[p->vt[j]] = 1;
          faces[nf++] = p->vt[j];
        }
    }
    int64_t w0 = 0, w1 = 0, r0 = 0, r1 = 0;
    for (int64_t i = 0; i < nf; i++) {
      before += fl0[faces[i]];
      after += tri_flat(p, faces[i], nl);
      mark[faces[i]] = 0;
      int a, b;
      tri_weights(p, p->lev, faces[i], nl, &a, &b);
      w1 += a;
      r1 += b;
    }
    /* the same faces' weights and volume ratios in the marching's stack */
    int ended = p->ended;
    p->ended = 0;
    for (int64_t i = 0; i < nf; i++) {
      int a, b;
      tri_weights(p, old, faces[i], nl, &a, &b);
      w0 += a;
      r0 += b;
    }
    p->ended = ended;
    (*npatch)++;
    if (after < before && after <= p->k.end_short_gain * before && w1 <= w0 && r1 <= r0) {
      (*nkept)++;
      *ncols += nc;
      continue;
    }
    for (int64_t i = 0; i < nc; i++) {
      int32_t v = cols[i];
      p->nlv[v] = n0[v];
      if (n0[v] < nl) {
        end_column(p, v, n0[v], nl, old);
        continue;
      }
      for (int k = 0; k <= nl; k++)
        memcpy(p->lev + k * lsz + 3 * (size_t)v, old + k * lsz + 3 * (size_t)v, 3 * sizeof *old);
    }
  }
  vm_free(p->ctx, seen);
  vm_free(p->ctx, mark);
  vm_free(p->ctx, cols);
  vm_free(p->ctx, faces);
  return VM_OK;
}

int pr_end_layers(vm_prism *p) {
  if (p->nlev < 2) return VM_OK;
  /* short columns given the layers that fit them (end_short): tried
   * where the layer has cells below OpenFOAM's determinant limit, not
   * with a count per region */
  int fit = p->o.end_short && !p->regional && p->nlev > 2;
  if (!p->nlv && !fit) return VM_OK;
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt;
  int nl = p->nlev - 1;
  size_t lsz = (size_t)(3 * nw);
  int64_t f0 = 0, nfit = 0, kept = 0, raised = 0, checks = 0;
  int st = VM_OK;
  int32_t *fl0 = NULL, *n0 = NULL, *queue = NULL;
  double *old = NULL, *sk0 = NULL;
  uint8_t *touch = NULL, *split0 = NULL;
  if (fit) {
    if (!(fl0 = vm_alloc_array(ctx, (size_t)nt, sizeof *fl0))) return VM_ERR_NOMEM;
#pragma omp parallel for schedule(static) reduction(+ : f0)
    for (int64_t t = 0; t < nt; t++) f0 += fl0[t] = tri_flat(p, t, nl);
    fit = f0 > 0;
  }
  if (!p->nlv && !fit) goto done;
  if (!p->nlv) {
    if (!(p->nlv = vm_alloc_array(ctx, (size_t)nw, sizeof *p->nlv))) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    for (int64_t v = 0; v < nw; v++) p->nlv[v] = nl;
  }
  int64_t ended = 0;
  for (int64_t v = 0; v < nw; v++) {
    if (p->nlv[v] > nl) p->nlv[v] = nl;
    ended += p->nlv[v] < nl;
  }
  if (!ended && !fit) goto done;
  old = vm_alloc_array(ctx, (size_t)(nl + 1) * lsz, sizeof *old);
  touch = vm_calloc(ctx, (size_t)nt, 1);
  split0 = vm_calloc(ctx, (size_t)(nt * nl), 1);
  sk0 = vm_alloc_array(ctx, (size_t)nt, sizeof *sk0);
  queue = vm_alloc_array(ctx, (size_t)nt, sizeof *queue);
  n0 = vm_alloc_array(ctx, (size_t)nw, sizeof *n0);
  if (!old || !touch || !split0 || !sk0 || !queue || !n0) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(old, p->lev, (size_t)(nl + 1) * lsz * sizeof *old);
  memcpy(n0, p->nlv, (size_t)nw * sizeof *n0);
  if (fit) nfit = fit_counts(p, old);
  /* the faces with an ended column, and which of their prisms failed a
   * 3-tet split before */
  for (int64_t t = 0; t < nt; t++) {
    for (int i = 0; i < 3; i++) touch[t] |= p->nlv[p->tri[3 * t + i]] < nl;
    if (!touch[t]) continue;
    for (int k = 0; k < nl; k++) {
      double x[18];
      pr_prism_at(p, old, t, k, x);
      split0[t * nl + k] = vm_prism_split_check(x, NULL) > 0;
    }
  }
  /* the largest skewness of each such face's cells before */
  for (int64_t t = 0; t < nt; t++) sk0[t] = touch[t] ? tri_skew(p, old, t, nl) : 0;
  for (int64_t v = 0; v < nw; v++)
    if (p->nlv[v] < nl) end_column(p, v, p->nlv[v], nl, old);
  p->ended = 1; /* the cells from here on are the ended ones */
  /* a face whose cells fail a check, or whose faces are more skewed than
   * k.skew_limit and than before: the smallest count among its ended
   * columns goes up by one (at the stack's count, the column is the
   * marching's again), until no face fails */
  /* a FIFO of the faces to check (touch[t] bit 1: queued), first every
   * face with an ended column in order, then the faces around each raised
   * column: the work is linear in the layers given back */
  int64_t qh = 0, qn = 0;
  for (int64_t t = 0; t < nt; t++)
    if (touch[t]) {
      queue[qn++] = (int32_t)t;
      touch[t] |= 2;
    }
  while (qn > 0) {
    int64_t t = queue[qh];
    qh = (qh + 1) % nt;
    qn--;
    touch[t] &= (uint8_t)~2;
    checks++;
    int ok = 1;
    for (int k = 0; k < nl && ok; k++) ok = cell_ok(p, t, k, nl, split0[t * nl + k]);
    if (ok) {
      double sk = tri_skew(p, p->lev, t, nl);
      ok = sk <= p->k.skew_limit || sk <= sk0[t];
    }
    if (ok) continue;
    int nmin = nl;
    for (int i = 0; i < 3; i++) {
      int n = p->nlv[p->tri[3 * t + i]];
      nmin = n < nmin ? n : nmin;
    }
    for (int i = 0; i < 3; i++) {
      int32_t v = p->tri[3 * t + i];
      if (p->nlv[v] != nmin) continue;
      p->nlv[v]++;
      raised++;
      if (p->nlv[v] < nl) {
        end_column(p, v, p->nlv[v], nl, old);
      } else {
        kept++;
        for (int k = 0; k <= nl; k++)
          memcpy(p->lev + k * lsz + 3 * (size_t)v, old + k * lsz + 3 * (size_t)v, 3 * sizeof *old);
      }
      for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++) {
        int32_t u = p->vt[j];
        if (touch[u] & 2) continue;
        touch[u] |= 2;
        queue[(qh + qn++) % nt] = u;
      }
    }
  }
  if (fit) {
    int64_t nk = 0, np = 0, npk = 0, f1 = 0;
    if ((st = keep_patches(p, old, n0, fl0, &nk, &np, &npk)) < 0) goto done;
#pragma omp parallel for schedule(static) reduction(+ : f1)
    for (int64_t t = 0; t < nt; t++) f1 += tri_flat(p, t, nl);
    p->rep.short_ended = nk;
    vm_log(ctx, VM_LOG_INFO,
           "prism: short columns: %lld given the layers that fit them, in %lld patches; %lld of "
           "the patches (%lld columns) kept, where that halves the cells below OpenFOAM's "
           "determinant limit around them; such cells in the layer %lld -> %lld",
           (long long)nfit, (long long)np, (long long)npk, (long long)nk, (long long)f0,
           (long long)f1);
  }
  int64_t pyr = 0, tet = 0, still = 0;
  for (int64_t v = 0; v < nw; v++) still += p->nlv[v] < nl;
  for (int64_t t = 0; t < nt; t++)
    for (int k = 0; touch[t] && k < nl; k++) {
      int32_t col[6];
      int lv[6];
      int type = pr_cell_nodes(p, t, k, nl, col, lv);
      pyr += type == VM_PYRAMID;
      tet += type == VM_TET;
    }
  p->ended = still > 0;
  p->rep.ended_columns = still;
  p->rep.ended_kept = kept;
  p->rep.pyramids = pyr;
  p->rep.tets = tet;
  if (still || ended)
    vm_log(ctx, VM_LOG_INFO,
           "prism: layers end on %lld columns (%lld pyramids, %lld tets between the counts); "
           "%lld layers given back where ending them made a cell invalid or skewed, %lld "
           "columns keep all %d layers (%lld face checks, %.2f s)",
           (long long)still, (long long)pyr, (long long)tet, (long long)raised, (long long)kept, nl,
           (long long)checks, omp_get_wtime() - t0);
done:
  vm_free(ctx, fl0);
  vm_free(ctx, n0);
  vm_free(ctx, queue);
  vm_free(ctx, sk0);
  vm_free(ctx, old);
  vm_free(ctx, touch);
  vm_free(ctx, split0);
  return st;
}
