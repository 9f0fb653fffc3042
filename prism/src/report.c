/* prism/src/report.c: the result mesh of a run (the levels as prisms, the
 * wall and outer triangles, fields and names) and its measured figures. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "state.h"
#include "varmesh/quality.h"

/* The layer's fill of what the geometry allows at a column of thickness
 * d: min(1, d / min(T, radius)) (1 where the radius is 0). */
static double pr_fill(double d, double T, double radius) {
  double allowed = radius < T ? radius : T;
  return allowed > 0 && d < allowed ? d / allowed : 1;
}

/* Levels of the current state: after marching the levels; before, the
 * single layer (2 levels, pointing into the layer mesh). */
static const double *levels(const vm_prism *p, int *nlev) {
  if (p->done >= 5) {
    *nlev = p->nlev;
    return p->lev;
  }
  *nlev = p->layer ? 2 : 0;
  return p->layer ? p->layer->xyz : NULL;
}

int vm_prism_result(vm_prism *p, vm_mesh **out) {
  if (!out) return VM_ERR_ARG;
  *out = NULL;
  if (!p) return VM_ERR_ARG;
  vm_ctx *ctx = p->ctx;
  int nlev;
  const double *L = levels(p, &nlev);
  if (nlev < 2) return vm_error(ctx, VM_ERR_ARG, "prism: no layer built yet");
  int64_t nw = p->nw, nt = p->nt, nl = nlev - 1;
  int64_t ne = nl * nt + 2 * nt;
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  if ((st = vm_mesh_set_vertices(m, nlev * nw)) ||
      (st = vm_mesh_set_elements(m, ne, 6 * nl * nt + 6 * nt)))
    goto fail;
  memcpy(m->xyz, L, (size_t)(3 * nw * nlev) * sizeof *m->xyz);
  memcpy(m->xyz, p->wall, (size_t)(3 * nw) * sizeof *m->xyz);
  for (int64_t v = 0; v < nw; v++) m->vflag[v] = VM_VERTEX_FIXED;
  int64_t e = 0, c = 0;
  for (int64_t k = 0; k < nl; k++)
    for (int64_t t = 0; t < nt; t++, e++) {
      m->etype[e] = VM_PRISM;
      for (int i = 0; i < 3; i++) m->conn[c + i] = (int32_t)(p->tri[3 * t + i] + k * nw);
      for (int i = 0; i < 3; i++) m->conn[c + 3 + i] = (int32_t)(p->tri[3 * t + i] + (k + 1) * nw);
      c += 6;
      m->eoff[e + 1] = c;
    }
  for (int s = 0; s < 2; s++)
    for (int64_t t = 0; t < nt; t++, e++) {
      m->etype[e] = VM_TRI;
      for (int i = 0; i < 3; i++) m->conn[c + i] = (int32_t)(p->tri[3 * t + i] + (s ? nl * nw : 0));
      c += 3;
      m->eoff[e + 1] = c;
    }
  /* vm_mesh_add_field may move the mesh's field table, so keep the data
   * pointers (separate allocations), never the vm_field pointers */
  vm_field *f;
  int32_t *lay = NULL, *ph = NULL;
  double *th = NULL;
  if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_LAYER, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f)))
    goto fail;
  lay = f->data;
  if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_PHYS, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f)))
    goto fail;
  ph = f->data;
  if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_THICKNESS, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
    goto fail;
  th = f->data;
  for (int64_t k = 0; k < ne; k++) {
    lay[k] = k < nl * nt ? (int32_t)(k / nt) : -1;
    ph[k] = k < nl * nt        ? VM_PRISM_TAG_VOLUME
            : k < nl * nt + nt ? VM_PRISM_TAG_WALL
                               : VM_PRISM_TAG_OUTER;
  }
  for (int64_t v = 0; v < nw; v++) {
    double d = vm_dist3(p->wall + 3 * v, L + (size_t)(3 * nw) * (size_t)nl + 3 * v);
    for (int64_t k = 0; k < nlev; k++) th[k * nw + v] = d;
  }
  if (p->medial) {
    double *mr, *fl;
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_MEDIAL, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
      goto fail;
    mr = f->data;
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_FILL, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
      goto fail;
    fl = f->data;
    for (int64_t v = 0; v < nw; v++) {
      double fill = pr_fill(th[v], p->tv[v], p->medial[v]);
      for (int64_t k = 0; k < nlev; k++) {
        mr[k * nw + v] = p->medial[v];
        fl[k * nw + v] = fill;
      }
    }
  }
  if (p->regional) {
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_TARGET, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
      goto fail;
    double *tg = f->data;
    for (int64_t v = 0; v < nw; v++)
      for (int64_t k = 0; k < nlev; k++) tg[k * nw + v] = p->tv[v];
  }
  if ((st = vm_mesh_set_attr(m, "gmsh:physical_name:2:1", "wall")) ||
      (st = vm_mesh_set_attr(m, "gmsh:physical_name:2:2", "outer")) ||
      (st = vm_mesh_set_attr(m, "gmsh:physical_name:3:3", "layer")))
    goto fail;
  *out = m;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The q-quantile (0 < q <= 1: the smallest value at or above a share q of
 * the n values; 1: the largest) of x, sorted in place; 0 if n == 0. */
double pr_percentile(double *x, int64_t n, double q) {
  if (n <= 0) return 0;
  qsort(x, (size_t)n, sizeof *x, cmp_double);
  int64_t k = (int64_t)ceil(q * (double)n) - 1;
  return x[k < 0 ? 0 : k >= n ? n - 1 : k];
}

int vm_prism_get_report(vm_prism *p, vm_prism_report *r) {
  if (!p || !r) return VM_ERR_ARG;
  int nlev;
  const double *L = levels(p, &nlev);
  vm_prism_report R = p->rep;
  R.time_total = pr_elapsed(p);
  if (nlev >= 2) {
    int64_t nw = p->nw, nt = p->nt;
    size_t lsz = (size_t)(3 * nw);
    const double *top = L + (size_t)(nlev - 1) * lsz;
    int64_t full = 0, room = 0, reach = 0;
    double tmin = INFINITY, tmax = 0, tsum = 0, fsum = 0, frest = 0;
    for (int64_t v = 0; v < nw; v++) {
      double len = vm_dist3(p->wall + 3 * v, top + 3 * v), d = len / p->tv[v];
      int at_full = d >= 1 - p->o.full_tol;
      full += at_full;
      tmin = d < tmin ? d : tmin;
      tmax = d > tmax ? d : tmax;
      tsum += d;
      if (!p->medial) continue;
      /* the room the geometry leaves (medial.c) */
      double fill = pr_fill(len, p->tv[v], p->medial[v]);
      fsum += fill;
      if (p->medial[v] >= p->k.medial_room * p->tv[v]) {
        room++;
        reach += at_full;
      } else {
        frest += fill;
      }
    }
    R.full_fraction = (double)full / (double)nw;
    if (p->medial) {
      R.medial_room = (double)room / (double)nw;
      R.medial_reach = room ? (double)reach / (double)room : 1;
      R.medial_short = room - reach;
      R.medial_fill = fsum / (double)nw;
      R.medial_fill_rest = room < nw ? frest / (double)(nw - room) : 1;
    }
    R.thick_min = tmin;
    R.thick_mean = tsum / (double)nw;
    R.thick_max = tmax;
    R.prisms = (nlev - 1) * nt;
    R.layers = nlev - 1;
    int64_t inv = 0, split = 0;
    double sj = INFINITY;
    for (int k = 0; k + 1 < nlev; k++)
      for (int64_t t = 0; t < nt; t++) {
        double x[18];
        for (int i = 0; i < 3; i++) {
          memcpy(x + 3 * i, L + k * lsz + 3 * (size_t)p->tri[3 * t + i], 3 * sizeof *x);
          memcpy(x + 9 + 3 * i, L + (k + 1) * lsz + 3 * (size_t)p->tri[3 * t + i], 3 * sizeof *x);
        }
        int bad;
        double q = pr_prism_corner_quality(x, &bad);
        inv += bad;
        split += vm_prism_split_check(x, NULL) > 0;
        sj = q < sj ? q : sj;
      }
    R.inverted = inv;
    R.split_negative = split;
    R.sj_min = sj;
    /* per column: the first side edge's tilt from the vertex normal (all
     * columns, and apart the smooth ones), the largest ratio of successive
     * heights, and whether every ratio lies in the growth band */
    double *dev = vm_alloc_array(p->ctx, 3 * (size_t)nw, sizeof *dev);
    if (!dev) return VM_ERR_NOMEM;
    double *dsm = dev + nw, *gcol = dev + 2 * nw;
    double dmax = 0, dsum = 0, gmax = 0;
    int64_t ns = 0, over = 0, inband = 0;
    const double band = 1.5, glo = p->rep.growth / band, ghi = p->rep.growth * band;
    for (int64_t v = 0; v < nw; v++) {
      double a = pr_tilt_deg(p->wall + 3 * v, L + lsz + 3 * v, p->vnrm + 3 * v);
      dev[v] = a;
      double gc = 0;
      int ok = 1;
      for (int k = 0; k + 2 < nlev; k++) {
        double h0 = vm_dist3(L + k * lsz + 3 * v, L + (k + 1) * lsz + 3 * v);
        double h1 = vm_dist3(L + (k + 1) * lsz + 3 * v, L + (k + 2) * lsz + 3 * v);
        /* a zero height (none is made) counts as out of the band, not
         * as an infinite ratio */
        if (!(h0 > 0)) {
          ok = 0;
          continue;
        }
        double g = h1 / h0;
        gc = g > gc ? g : gc;
        ok &= g >= glo && g <= ghi;
      }
      gcol[v] = gc;
      gmax = gc > gmax ? gc : gmax;
      inband += ok;
      if (!p->smooth[v]) continue;
      dmax = a > dmax ? a : dmax;
      dsum += a;
      dsm[ns++] = a;
      over += a > p->k.tilt_limit_deg;
    }
    R.normal_dev_over5 = over;
    R.normal_dev_max = dmax;
    R.normal_dev_mean = ns ? dsum / (double)ns : 0;
    R.smooth_vertices = ns;
    R.normal_dev_p99 = pr_percentile(dsm, ns, 0.99);
    R.normal_dev_all_p99 = pr_percentile(dev, nw, 0.99);
    R.normal_dev_all_max = pr_percentile(dev, nw, 1);
    R.growth_max = nlev > 2 ? gmax : 0;
    R.growth_p99 = nlev > 2 ? pr_percentile(gcol, nw, 0.99) : 0;
    R.growth_band_share = nlev > 2 ? (double)inband / (double)nw : 1;
    vm_free(p->ctx, dev);
    int st = pr_foam_figures(p, L, nlev, &R.nonortho_over70, &R.nonortho_max, &R.skew_max);
    if (st < 0) return st;
  }
  *r = R;
  return VM_OK;
}
