/* prism/src/report.c: the result mesh of a run (the levels as prisms, the
 * wall and outer triangles, fields and names) and its measured figures. */
#include <math.h>
#include <stdio.h>
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

void pr_sym_settle(vm_prism *p) {
  if (p->sym_ax < 0) return;
  int nlev;
  const double *L = levels(p, &nlev);
  if (!L) return;
  double *X = (double *)L;
  int64_t nw = p->nw, snapped = 0, crossing = 0;
  int ax = p->sym_ax, top = nlev - 1;
  for (int k = 1; k < nlev; k++)
    for (int64_t v = 0; v < nw; v++) {
      double *x = X + 3 * ((int64_t)k * nw + v);
      if (pr_on_sym(p, v)) {
        if (x[ax] != p->sym_val) {
          x[ax] = p->sym_val;
          snapped++;
          if (k == top && p->done >= 5) p->layer->xyz[3 * (nw + v) + ax] = p->sym_val;
        }
      } else if (!pr_sym_inside(p, x)) {
        crossing++;
      }
    }
  p->rep.sym_snapped += snapped;
  p->rep.sym_crossing = crossing;
  if (snapped)
    vm_log(p->ctx, VM_LOG_WARN,
           "prism: %lld vertices of the columns in the symmetry plane had left it and were put "
           "back",
           (long long)snapped);
}

/* The face on a half model's symmetry plane of cell (t, k) of nl layers
 * over the wall's open edge a -> b: its nodes as columns and levels (a's
 * upwards, then b's downwards), how many (3 or 4; 0: the cell has no face
 * there, its layers ended at both). */
static int sym_face(const vm_prism *p, int64_t t, int k, int nl, int32_t a, int32_t b, int32_t *col,
                    int *lv) {
  int32_t cc[6];
  int ll[6];
  int type = pr_cell_nodes(p, t, k, nl, cc, ll);
  int nv = type == VM_PRISM ? 6 : type == VM_PYRAMID ? 5 : type == VM_TET ? 4 : 0, n = 0;
  for (int s = 0; s < 2; s++) {
    int32_t c = s ? b : a;
    int lo = INT32_MAX, hi = -1;
    for (int i = 0; i < nv; i++)
      if (cc[i] == c) {
        lo = ll[i] < lo ? ll[i] : lo;
        hi = ll[i] > hi ? ll[i] : hi;
      }
    if (hi < 0) continue;
    int l0 = s ? hi : lo, l1 = s ? lo : hi;
    col[n] = c;
    lv[n++] = l0;
    if (l1 != l0) {
      col[n] = c;
      lv[n++] = l1;
    }
  }
  return n >= 3 ? n : 0;
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
  /* where layers end (after marching), the levels above a column's top
   * are left out: vid[k * nw + v] is the vertex of level k of column v */
  int ends = p->done >= 5 && p->ended;
  int32_t *vid = NULL;
  int64_t nv = nlev * nw, ncell = nl * nt, nconn = 6 * nl * nt;
  if (ends) {
    vid = vm_alloc_array(ctx, (size_t)(nlev * nw), sizeof *vid);
    if (!vid) return VM_ERR_NOMEM;
    nv = 0;
    for (int64_t k = 0; k < nlev; k++)
      for (int64_t v = 0; v < nw; v++)
        vid[k * nw + v] = k <= pr_col_top(p, v, (int)nl) ? (int32_t)nv++ : -1;
    ncell = nconn = 0;
    for (int64_t k = 0; k < nl; k++)
      for (int64_t t = 0; t < nt; t++) {
        int32_t col[6];
        int lv[6];
        int type = pr_cell_nodes(p, t, (int)k, (int)nl, col, lv);
        if (type < 0) continue;
        ncell++;
        nconn += vm_elem_nverts(type);
      }
  }
  /* a half model's faces on its symmetry plane: one per cell over an
   * open edge of the wall */
  int64_t nsf = 0, nsc = 0;
  for (int64_t ed = 0; p->sym_ax >= 0 && ed < p->ned; ed++) {
    if (p->etri[2 * ed + 1] >= 0) continue;
    for (int k = 0; k < nl; k++) {
      int32_t col[4];
      int lv[4];
      int n =
          sym_face(p, p->etri[2 * ed], k, (int)nl, p->edge[2 * ed], p->edge[2 * ed + 1], col, lv);
      nsf += n > 0;
      nsc += n;
    }
  }
  int64_t ne = ncell + 2 * nt + nsf;
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) {
    vm_free(ctx, vid);
    return st;
  }
  if ((st = vm_mesh_set_vertices(m, nv)) ||
      (st = vm_mesh_set_elements(m, ne, nconn + 6 * nt + nsc)))
    goto fail;
  if (ends) {
    for (int64_t k = 0; k < nlev; k++)
      for (int64_t v = 0; v < nw; v++)
        if (vid[k * nw + v] >= 0)
          memcpy(m->xyz + 3 * (int64_t)vid[k * nw + v], L + 3 * (k * nw + v), 3 * sizeof *m->xyz);
  } else {
    memcpy(m->xyz, L, (size_t)(3 * nw * nlev) * sizeof *m->xyz);
  }
  memcpy(m->xyz, p->wall, (size_t)(3 * nw) * sizeof *m->xyz);
  for (int64_t v = 0; v < nw; v++) m->vflag[v] = VM_VERTEX_FIXED;
    /* the vertex of level k of column v */
#define VID(k, v) (ends ? vid[(int64_t)(k)*nw + (v)] : (int32_t)((v) + (int64_t)(k)*nw))
  int64_t e = 0, c = 0;
  int32_t *lay = NULL, *ph = NULL, *wf = NULL;
  /* vm_mesh_add_field may move the mesh's field table, so keep the data
   * pointers (separate allocations), never the vm_field pointers */
  vm_field *f;
  if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_LAYER, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f)))
    goto fail;
  lay = f->data;
  if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_PHYS, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f)))
    goto fail;
  ph = f->data;
  if (ends) {
    if ((st =
             vm_mesh_add_field(m, VM_PRISM_FIELD_WALL_FACE, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f)))
      goto fail;
    wf = f->data;
  }
  for (int64_t k = 0; k < nl; k++)
    for (int64_t t = 0; t < nt; t++) {
      int32_t col[6];
      int lv[6];
      int type = ends ? pr_cell_nodes(p, t, (int)k, (int)nl, col, lv) : VM_PRISM;
      if (type < 0) continue;
      m->etype[e] = (uint8_t)type;
      if (ends) {
        for (int i = 0; i < vm_elem_nverts(type); i++) m->conn[c + i] = VID(lv[i], col[i]);
      } else {
        for (int i = 0; i < 3; i++) m->conn[c + i] = (int32_t)(p->tri[3 * t + i] + k * nw);
        for (int i = 0; i < 3; i++)
          m->conn[c + 3 + i] = (int32_t)(p->tri[3 * t + i] + (k + 1) * nw);
      }
      c += vm_elem_nverts(type);
      m->eoff[e + 1] = c;
      lay[e] = (int32_t)k;
      ph[e] = VM_PRISM_TAG_VOLUME;
      if (wf) wf[e] = (int32_t)t;
      e++;
    }
  for (int s = 0; s < 2; s++)
    for (int64_t t = 0; t < nt; t++, e++) {
      m->etype[e] = VM_TRI;
      for (int i = 0; i < 3; i++) {
        int32_t v = p->tri[3 * t + i];
        m->conn[c + i] = s ? VID(pr_col_top(p, v, (int)nl), v) : v;
      }
      c += 3;
      m->eoff[e + 1] = c;
      lay[e] = -1;
      ph[e] = s ? VM_PRISM_TAG_OUTER : VM_PRISM_TAG_WALL;
      if (wf) wf[e] = (int32_t)t;
    }
  for (int64_t ed = 0; nsf && ed < p->ned; ed++) {
    if (p->etri[2 * ed + 1] >= 0) continue;
    int64_t t = p->etri[2 * ed];
    for (int k = 0; k < nl; k++) {
      int32_t col[4];
      int lv[4];
      int n = sym_face(p, t, k, (int)nl, p->edge[2 * ed], p->edge[2 * ed + 1], col, lv);
      if (!n) continue;
      /* facing out of the domain, to the mirror image's side: the area
       * vector of a face in the plane is along its axis */
      double area = 0;
      for (int i = 0; i < n; i++) {
        const double *x0 = L + 3 * ((int64_t)lv[i] * nw + col[i]),
                     *x1 = L + 3 * ((int64_t)lv[(i + 1) % n] * nw + col[(i + 1) % n]);
        int a1 = (p->sym_ax + 1) % 3, a2 = (p->sym_ax + 2) % 3;
        area += x0[a1] * x1[a2] - x1[a1] * x0[a2];
      }
      int rev = area * p->sym_side > 0;
      m->etype[e] = n == 4 ? VM_QUAD : VM_TRI;
      for (int i = 0; i < n; i++) {
        int j = rev ? n - 1 - i : i;
        m->conn[c + i] = VID(lv[j], col[j]);
      }
      c += n;
      m->eoff[e + 1] = c;
      lay[e] = -1;
      ph[e] = VM_PRISM_TAG_SYMMETRY;
      if (wf) wf[e] = (int32_t)t;
      e++;
    }
  }
  /* a vertex field with the value val(v) of its column on every level */
#define COLUMN_FIELD(dst, val)                                                                     \
  for (int64_t k_ = 0; k_ < nlev; k_++)                                                            \
    for (int64_t v = 0; v < nw; v++)                                                               \
      if (VID(k_, v) >= 0) (dst)[VID(k_, v)] = (val)
  double *th = NULL;
  if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_THICKNESS, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
    goto fail;
  th = f->data;
  double *len = vm_alloc_array(ctx, (size_t)nw, sizeof *len);
  if (!len) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  for (int64_t v = 0; v < nw; v++)
    len[v] = vm_dist3(p->wall + 3 * v, L + (size_t)(3 * nw) * (size_t)nl + 3 * v);
  COLUMN_FIELD(th, len[v]);
  if (ends) {
    int32_t *cv;
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_COLUMN, VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f)))
      goto fail_len;
    cv = f->data;
    COLUMN_FIELD(cv, (int32_t)v);
  }
  if (p->medial) {
    double *mr, *fl;
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_MEDIAL, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
      goto fail_len;
    mr = f->data;
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_FILL, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
      goto fail_len;
    fl = f->data;
    COLUMN_FIELD(mr, p->medial[v]);
    COLUMN_FIELD(fl, pr_fill(len[v], p->tv[v], p->medial[v]));
  }
  if (p->regional) {
    if ((st = vm_mesh_add_field(m, VM_PRISM_FIELD_TARGET, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f)))
      goto fail_len;
    double *tg = f->data;
    COLUMN_FIELD(tg, p->tv[v]);
  }
#undef COLUMN_FIELD
#undef VID
  vm_free(ctx, len);
  len = NULL;
  if ((st = vm_mesh_set_attr(m, "gmsh:physical_name:2:1", "wall")) ||
      (st = vm_mesh_set_attr(m, "gmsh:physical_name:2:2", "outer")) ||
      (st = vm_mesh_set_attr(m, "gmsh:physical_name:3:3", "layer")))
    goto fail;
  if (p->sym_ax >= 0 && ((st = vm_mesh_set_attr(m, "gmsh:physical_name:2:4", "symmetry")) ||
                         (st = vm_mesh_set_symmetry_plane(m, p->sym_ax, p->sym_val))))
    goto fail;
  vm_free(ctx, vid);
  *out = m;
  return VM_OK;
fail_len:
  vm_free(ctx, len);
fail:
  vm_free(ctx, vid);
  vm_mesh_destroy(&m);
  return st;
}

/* The least corner scaled Jacobian of a pyramid (at its base corners)
 * or a tet (x: 5 or 4 vertices), 1 on the ideal one (equal edges);
 * *inverted = 1 if a corner's determinant is not positive. */
static double cell_sj(int type, const double *x, int *inverted) {
  static const int tet[4][4] = {{0, 1, 2, 3}, {1, 2, 0, 3}, {2, 0, 1, 3}, {3, 2, 1, 0}};
  static const int pyr[4][4] = {{0, 1, 3, 4}, {1, 2, 0, 4}, {2, 3, 1, 4}, {3, 0, 2, 4}};
  const int(*cn)[4] = type == VM_TET ? tet : pyr;
  double q = INFINITY, norm = sqrt(2.0);
  *inverted = 0;
  for (int i = 0; i < 4; i++) {
    double e[3][3];
    for (int j = 0; j < 3; j++)
      for (int r = 0; r < 3; r++) e[j][r] = x[3 * cn[i][j + 1] + r] - x[3 * cn[i][0] + r];
    double n[3];
    vm_cross3(e[0], e[1], n);
    double det = vm_dot3(n, e[2]), l = vm_norm3(e[0]) * vm_norm3(e[1]) * vm_norm3(e[2]);
    double s = l > 0 ? norm * det / l : -1;
    if (!(det > 0)) *inverted = 1;
    q = s < q ? s : q;
  }
  return q;
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
    R.layers = nlev - 1;
    int64_t inv = 0, split = 0, cells = 0;
    double sj = INFINITY;
    for (int k = 0; k + 1 < nlev; k++)
      for (int64_t t = 0; t < nt; t++) {
        double x[18];
        int nv, bad;
        int type = pr_cell_at(p, L, t, k, nlev - 1, x, &nv);
        if (type < 0) continue;
        cells += type == VM_PRISM;
        double q = type == VM_PRISM ? pr_prism_corner_quality(x, &bad) : cell_sj(type, x, &bad);
        inv += bad;
        if (type == VM_PRISM) split += vm_prism_split_check(x, NULL) > 0;
        sj = q < sj ? q : sj;
      }
    R.prisms = cells;
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
      for (int k = 0; k + 2 <= pr_col_top(p, v, nlev - 1); k++) {
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
    int st =
        pr_foam_figures(p, L, nlev, &R.nonortho_over70, &R.nonortho_max, &R.skew_max, &R.det_small);
    if (st < 0) return st;
  }
  *r = R;
  return VM_OK;
}
