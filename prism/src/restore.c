/* prism/src/restore.c: phase 4: thickness restored to T wherever nothing
 * prevents it, and Laplace-Beltrami smoothing (mean-value weights) of the
 * offset surface near the contact zones left by cutting; outer vertices
 * move only along their prism side edges, every prism stays valid and the
 * layer free of self-intersections. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "state.h"

/* Mean-value (Floater) average of the outer neighbours of every vertex,
 * projected on its side edge: tp[v] = (q_v - wall_v) . d_v. */
static void mean_value_proj(const vm_prism *p, const double *d, double *tp) {
  const double *top = p->layer->xyz + 3 * p->nw;
#pragma omp parallel for schedule(static)
  for (int64_t v = 0; v < p->nw; v++) {
    double q[3] = {0, 0, 0}, ws = 0;
    const double *x = top + 3 * v;
    for (int64_t k = p->vt_off[v]; k < p->vt_off[v + 1]; k++) {
      const int32_t *c = p->tri + 3 * (int64_t)p->vt[k];
      int i = c[0] == v ? 0 : c[1] == v ? 1 : 2;
      const double *a = top + 3 * (int64_t)c[(i + 1) % 3], *b = top + 3 * (int64_t)c[(i + 2) % 3];
      double u[3], w[3];
      for (int r = 0; r < 3; r++) {
        u[r] = a[r] - x[r];
        w[r] = b[r] - x[r];
      }
      double lu = vm_norm3(u), lw = vm_norm3(w);
      if (!(lu > 0) || !(lw > 0)) continue;
      double cs = vm_dot3(u, w) / (lu * lw);
      cs = cs < -1 ? -1 : cs > 1 ? 1 : cs;
      double tn = tan(0.5 * acos(cs));
      for (int r = 0; r < 3; r++) q[r] += tn / lu * a[r] + tn / lw * b[r];
      ws += tn / lu + tn / lw;
    }
    if (!(ws > 0)) {
      tp[v] = vm_dist3(x, p->wall + 3 * v);
      continue;
    }
    double s = 0;
    for (int r = 0; r < 3; r++) s += (q[r] / ws - p->wall[3 * v + r]) * d[3 * v + r];
    tp[v] = s;
  }
}

/* The tops as they stand, for updates that touch only what moved: tq[v]
 * the height column v's top was last set from (the top is exactly wall +
 * tq d), dirty[v] set where it changed since the prisms' qualities were
 * last computed. On the aircraft at resolution 32 (511 k triangles) a
 * restoring pass took 44 s when every back-off round set every top and
 * measured every prism again. */
typedef struct {
  double *tq;
  uint8_t *dirty;
} top_state;

/* Set the tops whose height in t differs (bit for bit) from tq, and mark
 * them dirty. */
static void sync_top(vm_prism *p, const double *t, const double *d, top_state *ts) {
  double *top = p->layer->xyz + 3 * p->nw;
  for (int64_t v = 0; v < p->nw; v++) {
    if (!memcmp(t + v, ts->tq + v, sizeof *t)) continue;
    for (int k = 0; k < 3; k++) top[3 * v + k] = p->wall[3 * v + k] + t[v] * d[3 * v + k];
    ts->tq[v] = t[v];
    ts->dirty[v] = 1;
  }
}

/* Quality (geometric rule, pr_prism_quality) of the single layer's prism e. */
static double prism_q(const vm_prism *p, int64_t e) {
  const vm_mesh *m = p->layer;
  const int32_t *cc = m->conn + 6 * e;
  double x[18];
  for (int i = 0; i < 6; i++) memcpy(x + 3 * i, m->xyz + 3 * (int64_t)cc[i], 3 * sizeof *x);
  return pr_prism_quality(x);
}

/* Quality (geometric rule, pr_prism_quality) of the prisms with a dirty
 * top (all prisms if all is set); clears the marks. */
static void layer_quality(const vm_prism *p, top_state *ts, int all, double *q) {
  const uint8_t *dt = ts->dirty;
#pragma omp parallel for schedule(static)
  for (int64_t e = 0; e < p->nt; e++) {
    const int32_t *c = p->tri + 3 * e;
    if (!all && !dt[c[0]] && !dt[c[1]] && !dt[c[2]]) continue;
    q[e] = prism_q(p, e);
  }
  memset(ts->dirty, 0, (size_t)p->nw);
}

/* Set the top from t; where a prism became worse than a tenth of its
 * quality at the start q0 (k.restore_qshare), put its vertices back to
 * t_old and halve their step, until no prism is (t_old passed the same
 * test). A share rather than a fixed floor: a fan prism at a sharp
 * trailing edge starts near 0.01 and must lengthen, a good prism must not
 * fall to 0.03. */
static void apply_quality(vm_prism *p, double *t, const double *t_old, const double *d,
                          const double *q0, double *q, double *alpha, uint8_t *bad, top_state *ts) {
  for (int round = 0; round < p->k.restore_quality_rounds; round++) {
    sync_top(p, t, d, ts);
    layer_quality(p, ts, 0, q);
    memset(bad, 0, (size_t)p->nw);
    int64_t nbad = 0;
    for (int64_t e = 0; e < p->nt; e++) {
      if (q[e] >= p->k.restore_qshare * q0[e]) continue;
      nbad++;
      for (int i = 0; i < 3; i++) bad[p->tri[3 * e + i]] = 1;
    }
    if (!nbad) return;
    int64_t back = 0;
    for (int64_t v = 0; v < p->nw; v++)
      if (bad[v] && t[v] != t_old[v]) {
        t[v] = t_old[v];
        alpha[v] *= p->k.restore_backoff;
        back++;
      }
    if (!back) { /* cannot happen from a valid start; be safe */
      memcpy(t, t_old, (size_t)p->nw * sizeof *t);
      sync_top(p, t, d, ts);
      return;
    }
  }
}

/* Vertices within `rings` edges of a cut vertex. */
static void mark_zone(const vm_prism *p, int rings, uint8_t *zone, uint8_t *tmp) {
  for (int64_t v = 0; v < p->nw; v++) zone[v] = p->cut[v];
  for (int r = 0; r < rings; r++) {
    memcpy(tmp, zone, (size_t)p->nw);
    for (int64_t v = 0; v < p->nw; v++) {
      if (tmp[v]) continue;
      for (int64_t k = p->vv_off[v]; k < p->vv_off[v + 1]; k++)
        if (tmp[p->vv[k]]) {
          zone[v] = 1;
          break;
        }
    }
  }
}

/* Does every prism on v keep at least `share` of its quality q0? */
static int prisms_ok(const vm_prism *p, int64_t v, const double *q0, double share) {
  for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++)
    if (!(prism_q(p, p->vt[j]) >= share * q0[p->vt[j]])) return 0;
  return 1;
}

/* Slots opened. Where cutting stopped two parts' layers close to each
 * other (a wing's lower surface over a fuselage, plane.stl at 5 %: outer
 * surfaces 0.002-0.02 apart under triangles of 0.05-0.3), the fill has to
 * bridge the slot with flat tets. Each top whose outer surface faces
 * another part's (the ball touching it from outside is stopped by a
 * triangle facing back, within k.slot_face_deg of opposite) closer than
 * o.slot_clearance times its mean outer edge is lowered along its column by
 * what is missing, in rounds, down to k.slot_min of its aim; a lowering
 * that leaves a prism below k.slot_qshare of its quality is halved, up to
 * k.slot_halvings times, then not taken. */
static int open_slots(vm_prism *p, double *t, const double *d, top_state *ts, int64_t *np_io) {
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt;
  if (p->k.slot_rounds <= 0 || !(p->o.slot_clearance > 0) || nw <= 0 || nt <= 0) return VM_OK;
  double *top = p->layer->xyz + 3 * nw;
  const pr_surf ws = pr_wall_surf(p);
  double *fn = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *fn);
  double *vn = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *vn);
  double *sd = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *sd);
  double *el = vm_alloc_array(ctx, (size_t)nw, sizeof *el);
  double *r = vm_alloc_array(ctx, (size_t)nw, sizeof *r);
  double *q0 = vm_alloc_array(ctx, (size_t)nt, sizeof *q0);
  double *told = vm_alloc_array(ctx, (size_t)nw, sizeof *told);
  double *t0 = vm_alloc_array(ctx, (size_t)nw, sizeof *t0);
  int64_t *hit = vm_alloc_array(ctx, (size_t)nw, sizeof *hit);
  uint8_t *mark = vm_calloc(ctx, (size_t)nw, 1);
  int st = VM_OK;
  if (!fn || !vn || !sd || !el || !r || !q0 || !told || !t0 || !hit || !mark) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t e = 0; e < nt; e++) q0[e] = prism_q(p, e);
  memcpy(t0, t, (size_t)nw * sizeof *t);
  int64_t first = -1;
  int round;
  for (round = 0; round < p->k.slot_rounds; round++) {
    /* the outer surface's unit face and angle-weighted vertex normals
     * (sd: the directions the columns would take there, not used) and
     * each top's mean outer edge */
    pr_surface_dirs(ctx, &ws, &p->k.dir, top, fn, vn, sd, 0, NULL);
    memset(el, 0, (size_t)nw * sizeof *el);
    for (int64_t e = 0; e < nt; e++)
      for (int i = 0; i < 3; i++) {
        const int32_t *c = p->tri + 3 * e;
        el[c[i]] += vm_dist3(top + 3 * (int64_t)c[i], top + 3 * (int64_t)c[(i + 1) % 3]);
      }
    double hmax = 0;
    for (int64_t v = 0; v < nw; v++) {
      int64_t deg = p->vt_off[v + 1] - p->vt_off[v];
      el[v] = deg ? el[v] / (double)deg : 0;
      hmax = el[v] > hmax ? el[v] : hmax;
    }
    if ((st = pr_medial_radius_of(p, top, p->tri, fn, vn, el, nw, nt, p->o.slot_clearance * hmax, r,
                                  hit)))
      goto done;
    memcpy(told, t, (size_t)nw * sizeof *t);
    memset(mark, 0, (size_t)nw);
    int64_t n = 0;
    for (int64_t v = 0; v < nw; v++) {
      double want = p->o.slot_clearance * el[v];
      if (!(r[v] < want) || !pr_ball_faces_back(p, hit[v], fn, vn + 3 * v)) continue;
      double tn = t[v] - (want - r[v]), lo = p->k.slot_min * p->tv[v];
      if (tn < lo) tn = lo;
      if (!(tn < t[v])) continue;
      t[v] = tn;
      mark[v] = 1;
      n++;
    }
    if (first < 0) first = n;
    if (!n) break;
    /* prisms kept above their share: halve the lowering where one is not */
    for (int half = 0; half < p->k.slot_halvings; half++) {
      sync_top(p, t, d, ts);
      int64_t bad = 0;
      for (int64_t v = 0; v < nw; v++)
        if (mark[v] && !prisms_ok(p, v, q0, p->k.slot_qshare)) {
          t[v] = 0.5 * (t[v] + told[v]);
          bad++;
        }
      if (!bad) break;
      if (half == p->k.slot_halvings - 1)
        for (int64_t v = 0; v < nw; v++)
          if (mark[v] && !prisms_ok(p, v, q0, p->k.slot_qshare)) t[v] = told[v];
    }
    sync_top(p, t, d, ts);
    int64_t np = 0;
    if ((st = pr_layer_intersections(p, mark, &np))) goto done;
    if (np > *np_io) { /* cannot happen by lowering alone; be safe */
      memcpy(t, told, (size_t)nw * sizeof *t);
      sync_top(p, t, d, ts);
      if ((st = pr_layer_intersections(p, NULL, &np))) goto done;
      *np_io = np;
      break;
    }
    *np_io = np;
  }
  int64_t lowered = 0;
  double most = 0;
  for (int64_t v = 0; v < nw; v++)
    if (t[v] < t0[v]) {
      lowered++;
      most = t0[v] - t[v] > most ? t0[v] - t[v] : most;
    }
  p->rep.slots_lowered = lowered;
  if (first > 0)
    vm_log(ctx, VM_LOG_INFO,
           "prism: slots opened: %lld tops faced another part's outer surface closer than %.2f "
           "of their outer edges; %lld columns lowered in %d rounds, by at most %.3g T",
           (long long)first, p->o.slot_clearance, (long long)lowered, round, most / p->o.thickness);
done:
  vm_free(ctx, fn);
  vm_free(ctx, vn);
  vm_free(ctx, sd);
  vm_free(ctx, el);
  vm_free(ctx, r);
  vm_free(ctx, q0);
  vm_free(ctx, told);
  vm_free(ctx, t0);
  vm_free(ctx, hit);
  vm_free(ctx, mark);
  return st;
}

int vm_prism_restore(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 3) return vm_error(p->ctx, VM_ERR_ARG, "prism: restoring needs the cut layer");
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw;
  double T = p->o.thickness;
  double *d = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *d);
  double *t = vm_alloc_array(ctx, (size_t)nw, sizeof *t);
  double *told = vm_alloc_array(ctx, (size_t)nw, sizeof *told);
  double *tcut = vm_alloc_array(ctx, (size_t)nw, sizeof *tcut);
  double *tstart = vm_alloc_array(ctx, (size_t)nw, sizeof *tstart);
  double *tp = vm_alloc_array(ctx, (size_t)nw, sizeof *tp);
  double *alpha = vm_alloc_array(ctx, (size_t)nw, sizeof *alpha);
  double *q = vm_alloc_array(ctx, (size_t)p->nt, sizeof *q);
  double *qold = vm_alloc_array(ctx, (size_t)p->nt, sizeof *qold);
  uint8_t *zone = vm_alloc_array(ctx, (size_t)nw, sizeof *zone);
  uint8_t *tmp = vm_alloc_array(ctx, (size_t)nw, sizeof *tmp);
  top_state ts = {vm_alloc_array(ctx, (size_t)nw, sizeof *ts.tq),
                  vm_calloc(ctx, (size_t)nw, sizeof *ts.dirty)};
  int st = VM_OK;
  if (!d || !t || !told || !tcut || !tstart || !tp || !alpha || !q || !qold || !zone || !tmp ||
      !ts.tq || !ts.dirty) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  const double *x = p->layer->xyz;
  for (int64_t v = 0; v < nw; v++) {
    for (int k = 0; k < 3; k++) d[3 * v + k] = x[3 * (v + nw) + k] - x[3 * v + k];
    t[v] = vm_normalize3(d + 3 * v);
    tcut[v] = t[v] < p->tv[v] ? t[v] : p->tv[v];
    p->cap[v] = p->tv[v];
    alpha[v] = 1;
  }
  /* positions exactly wall + t d from here on, so going back to an old t
   * gives back the old prism bit for bit */
  pr_set_top(p, t, d);
  memcpy(ts.tq, t, (size_t)nw * sizeof *t);
  memcpy(tstart, t, (size_t)nw * sizeof *t);
  layer_quality(p, &ts, 1, qold);
  memcpy(q, qold, (size_t)p->nt * sizeof *q);
  mark_zone(p, p->k.restore_zone_rings, zone, tmp);
  for (int64_t v = 0; v < nw; v++)
    if (zone[v]) alpha[v] = p->k.restore_zone_alpha;
  /* pairs cutting left (it ran out of rounds): their columns stay where
   * they are, and only new pairs send columns back */
  int64_t np = 0, np0 = 0;
  if (p->rep.intersections > 0) {
    if ((st = pr_layer_intersections(p, tmp, &np0))) goto done;
    for (int64_t v = 0; v < nw; v++)
      if (tmp[v]) {
        p->cap[v] = t[v];
        alpha[v] = 0;
      }
  }
  for (int pass = 1; pass <= p->o.smooth_iter; pass++) {
    if (pr_time_left(p) <= 0) {
      st = VM_WARN_TIME;
      break;
    }
    mean_value_proj(p, d, tp);
    memcpy(told, t, (size_t)nw * sizeof *t);
    double change = 0;
    for (int64_t v = 0; v < nw; v++) {
      double goal = p->cap[v] < p->tv[v] ? p->cap[v] : p->tv[v];
      /* cut columns: one Laplace-Beltrami step (mean-value weights) of the
       * offset surface along the side edge; all: restoration towards T */
      double s = p->cut[v] ? p->k.restore_smooth_weight * (t[v] + tp[v]) : t[v];
      double nt = s + alpha[v] * (goal - s);
      if (nt > goal) nt = goal;
      /* never below the length cutting left: that layer is valid and free
       * of intersections already, and at sharp convex tips the projected
       * neighbours lie behind the vertex, so repeated smoothing would
       * shrink the column towards zero */
      if (nt < tcut[v]) nt = tcut[v];
      /* steps below k.restore_min_step T are not taken: the layer then
       * settles with few columns moving, and the intersection query only
       * looks at those (a full query every pass cost 0.6 s at T = 20 %) */
      if (fabs(nt - t[v]) >= p->k.restore_min_step * T) t[v] = nt;
    }
    /* no worse prisms and no new intersections: the columns involved go
     * back and halve their steps; after many halvings their cap is frozen
     * at the contact. Going back to t_old is always safe. */
    for (int round = 0;; round++) {
      apply_quality(p, t, told, d, qold, q, alpha, tmp, &ts);
      if ((st = pr_layer_intersections(p, tmp, &np))) goto done;
      if (np <= np0) break;
      int64_t back = 0;
      for (int64_t v = 0; v < nw; v++)
        if (tmp[v] && t[v] != told[v]) {
          t[v] = told[v];
          alpha[v] *= p->k.restore_backoff;
          if (alpha[v] < p->k.restore_freeze_alpha) p->cap[v] = told[v];
          back++;
        }
      if (!back || round >= p->k.restore_back_rounds) {
        memcpy(t, told, (size_t)nw * sizeof *t);
        sync_top(p, t, d, &ts);
        if ((st = pr_layer_intersections(p, NULL, &np))) goto done;
        break;
      }
    }
    double mean = 0;
    for (int64_t v = 0; v < nw; v++) {
      mean += t[v] / p->tv[v];
      double c = fabs(t[v] - told[v]);
      change = c > change ? c : change;
    }
    pr_progress(p, VM_PRISM_PHASE_RESTORE, pass, mean / (double)nw, np, 0);
    if (np > np0 || change < p->k.restore_stop_change * T) break;
  }
  /* slots opened (the tops set from t through ts, as above) */
  if (st >= 0) {
    int so = open_slots(p, t, d, &ts, &np);
    if (so < 0) {
      st = so;
      goto done;
    }
  }
  /* a sliver the restoration kept positive by pr_prism_quality but that
   * the solver's own rounding judges inverted (det C <= 0 at a node: prisms
   * of quality 1e-10 over needles; a public Cessna model) has its columns
   * sent back to where the restoration found them, until none is left: the
   * layer it found was valid and free of new intersections; one left
   * after 64 rounds ends the run */
  int64_t bad = 0;
  for (int round = 0; st >= 0; round++) {
    bad = pr_mark_inverted(p, tmp);
    if (bad < 0) st = (int)bad;
    if (bad <= 0 || round == 64) break;
    for (int64_t v = 0; v < nw; v++)
      if (tmp[v]) t[v] = tstart[v];
    sync_top(p, t, d, &ts);
    if (round == 0)
      vm_log(ctx, VM_LOG_INFO,
             "prism: restoring: %lld nodes of slivers the solver judges inverted; their "
             "columns go back to their length before the restoration",
             (long long)bad);
    if ((st = pr_layer_intersections(p, NULL, &np))) goto done;
  }
  p->rep.intersections = np;
  if (np && st == VM_OK) st = VM_WARN_MAXITER;
  if (st >= 0 && bad > 0)
    st =
        vm_error(ctx, VM_ERR_NUMERIC, "prism: %lld inverted nodes after restoring", (long long)bad);
done:
  vm_free(ctx, d);
  vm_free(ctx, t);
  vm_free(ctx, told);
  vm_free(ctx, tcut);
  vm_free(ctx, tstart);
  vm_free(ctx, tp);
  vm_free(ctx, alpha);
  vm_free(ctx, q);
  vm_free(ctx, qold);
  vm_free(ctx, zone);
  vm_free(ctx, tmp);
  vm_free(ctx, ts.tq);
  vm_free(ctx, ts.dirty);
  p->rep.time[VM_PRISM_PHASE_RESTORE] += omp_get_wtime() - t0;
  if (st >= 0) p->done = 4;
  return st;
}
