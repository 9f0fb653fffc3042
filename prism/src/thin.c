/* prism/src/thin.c: phase 1, the thin layer: columns along the blended
 * directions, a small fraction of the local edge length high, halved
 * where a prism is degenerate or poor. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "state.h"

/* Phase 1: top_v = wall_v + h_v dir_v with h_v a small fraction of the local
 * edge length, halved where a prism is degenerate or poor. */
int vm_prism_thin(vm_prism *p) {
  if (!p) return VM_ERR_ARG;
  if (p->done != 0) return vm_error(p->ctx, VM_ERR_ARG, "prism: thin layer already built");
  double t0 = omp_get_wtime();
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt;
  int st = vm_mesh_create(ctx, &p->layer);
  if (st) return st;
  vm_mesh *m = p->layer;
  if ((st = vm_mesh_set_vertices(m, 2 * nw)) || (st = vm_mesh_set_elements(m, nt, 6 * nt)))
    return st;
  memcpy(m->xyz, p->wall, (size_t)(3 * nw) * sizeof *m->xyz);
  for (int64_t v = 0; v < nw; v++) {
    m->vflag[v] = VM_VERTEX_FIXED;
    m->vflag[nw + v] = pr_moving_flag(p, v);
  }
  for (int64_t t = 0; t < nt; t++) {
    m->etype[t] = VM_PRISM;
    m->eoff[t + 1] = 6 * (t + 1);
    for (int i = 0; i < 3; i++) {
      m->conn[6 * t + i] = p->tri[3 * t + i];
      m->conn[6 * t + 3 + i] = (int32_t)(p->tri[3 * t + i] + nw);
    }
  }
  double *hv = vm_alloc_array(ctx, (size_t)nw, sizeof *hv);
  uint8_t *bad = vm_alloc_array(ctx, (size_t)nw, sizeof *bad);
  if (!hv || !bad) {
    vm_free(ctx, hv);
    vm_free(ctx, bad);
    return VM_ERR_NOMEM;
  }
  for (int64_t v = 0; v < nw; v++) {
    double h = p->k.thin_height * p->elen[v];
    hv[v] = h < p->tv[v] ? h : p->tv[v];
  }
  /* the quality each prism tends to as its height goes to 0: the bound the
   * thin layer may approach but not reach */
  double *q0 = vm_alloc_array(ctx, (size_t)nt, sizeof *q0);
  if (!q0) {
    vm_free(ctx, hv);
    vm_free(ctx, bad);
    return VM_ERR_NOMEM;
  }
  for (int64_t v = 0; v < nw; v++) bad[v] = 0;
  {
    double *hs = vm_alloc_array(ctx, (size_t)nw, sizeof *hs);
    if (!hs) {
      vm_free(ctx, q0);
      vm_free(ctx, hv);
      vm_free(ctx, bad);
      return VM_ERR_NOMEM;
    }
    for (int64_t v = 0; v < nw; v++) hs[v] = p->k.thin_limit_height * hv[v];
    pr_set_top(p, hs, p->dir);
    vm_free(ctx, hs);
    for (int64_t t = 0; t < nt; t++) {
      double x[18];
      const int32_t *c = m->conn + 6 * t;
      for (int i = 0; i < 6; i++) memcpy(x + 3 * i, m->xyz + 3 * (int64_t)c[i], 3 * sizeof *x);
      q0[t] = pr_prism_quality(x);
    }
  }
  /* pass 0 halves the columns of the prisms poor in a round. Where that
   * leaves prisms poor after every round (a graded mesh's needles: the last
   * chordwise panel of a sharp trailing edge, 150 times shorter than the
   * spanwise edges, whose tops tilt when one column is halved beside
   * unchanged ones, so that the halvings chase each other along the edge),
   * pass 1 goes on from there, halving the neighbours too and keeping no
   * column more than thin_grade of an edge above a neighbour. A wall the first pass
   * serves is left exactly as it was. */
  int64_t nbad = 0, bad_t = 0;
  for (int pass = 0, round = 0; pass < 2; pass++, round = 0) {
    if (pass == 1) {
      if (!nbad) break;
      vm_log(ctx, VM_LOG_INFO,
             "prism: thin layer: %lld prisms still poor after %d halvings; halving their "
             "neighbourhoods, the columns graded",
             (long long)nbad, p->k.thin_rounds);
    }
    for (; round < p->k.thin_rounds; round++) {
      pr_set_top(p, hv, p->dir);
      memset(bad, 0, (size_t)nw);
      nbad = 0;
      for (int64_t t = 0; t < nt; t++) {
        double x[18];
        const int32_t *c = m->conn + 6 * t;
        for (int i = 0; i < 6; i++) memcpy(x + 3 * i, m->xyz + 3 * (int64_t)c[i], 3 * sizeof *x);
        double share = p->k.thin_quality_share * q0[t];
        double lim = share < p->k.thin_quality_cap ? share : p->k.thin_quality_cap;
        if (pr_prism_quality(x) > lim && lim > 0) continue;
        if (!nbad) bad_t = t;
        nbad++;
        for (int i = 0; i < 3; i++) bad[c[i]] = 1;
      }
      if (!nbad) break;
      if (pass == 1)
        for (int64_t v = 0; v < nw; v++)
          if (bad[v] == 1)
            for (int64_t i = p->vv_off[v]; i < p->vv_off[v + 1]; i++)
              if (!bad[p->vv[i]]) bad[p->vv[i]] = 2;
      for (int64_t v = 0; v < nw; v++)
        if (bad[v]) hv[v] *= p->k.thin_shrink;
      if (pass == 1) /* in index order: deterministic */
        for (int sweep = 0; sweep < p->k.thin_grade_sweeps; sweep++)
          for (int64_t v = 0; v < nw; v++)
            for (int64_t i = p->vv_off[v]; i < p->vv_off[v + 1]; i++) {
              int32_t u = p->vv[i];
              double lim =
                  hv[u] + p->k.thin_grade * vm_dist3(p->wall + 3 * v, p->wall + 3 * (int64_t)u);
              if (hv[v] > lim) hv[v] = lim;
            }
    }
  }
  double hmin = INFINITY, hmax = 0;
  for (int64_t v = 0; v < nw; v++) {
    hmin = hv[v] < hmin ? hv[v] : hmin;
    hmax = hv[v] > hmax ? hv[v] : hmax;
  }
  vm_free(ctx, hv);
  vm_free(ctx, bad);
  if (nbad) {
    /* where: the first one's wall triangle, and why */
    const int32_t *c = p->tri + 3 * bad_t;
    double g[3];
    for (int r = 0; r < 3; r++)
      g[r] = (p->wall[3 * (int64_t)c[0] + r] + p->wall[3 * (int64_t)c[1] + r] +
              p->wall[3 * (int64_t)c[2] + r]) /
             3;
    double q = q0[bad_t];
    vm_free(ctx, q0);
    return vm_error(ctx, VM_ERR_NUMERIC,
                    "prism: %lld thin prisms stay degenerate, e.g. over the wall triangle at "
                    "(%g, %g, %g)%s",
                    (long long)nbad, g[0], g[1], g[2],
                    q > 0 ? "" : " (degenerate however thin: its columns do not see it)");
  }
  vm_free(ctx, q0);
  vm_field *f;
  if ((st = vm_mesh_add_field(m, PRISM_TARGET_FIELD, VM_FIELD_ELEMENT, VM_FIELD_F64, 18, &f)))
    return st;
  p->rep.thin_min = hmin;
  p->rep.thin_max = hmax;
  p->rep.prisms = nt;
  p->done = 1;
  p->rep.time[VM_PRISM_PHASE_THIN] = omp_get_wtime() - t0;
  pr_progress(p, VM_PRISM_PHASE_THIN, 1, hmax, 0, 0);
  return VM_OK;
}
