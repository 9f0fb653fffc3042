/* lib/geom/src/ortho2d.c: the wall's finite-volume orthogonality relief
 * (varmesh/ortho2d.h). Vertices slide on the reference surface (or along
 * their feature line) by steps of gradient descent on a penalty of the
 * angles of the edges around them, one vertex at a time in vertex order;
 * the triangles stay as they are. */
#include "varmesh/ortho2d.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"
#include "varmesh/cleanup.h"
#include "varmesh/topology.h"

vm_ortho2d_opts vm_ortho2d_opts_default(void) {
  vm_ortho2d_opts o;
  o.sweeps = 8;
  o.relief_deg = 55;
  o.active_deg = 65;
  o.min_angle = 20;
  o.max_move = 0.5;
  o.feature_angle = 20;
  o.corner_angle = 50;
  o.cone_angle = 60;
  return o;
}

/* The cosine of the angle of vm_surface_edge_nonortho; 0 (90 degrees)
 * where a length or a normal vanishes. */
static double edge_cos(const double *a, const double *b, const double *p, const double *q) {
  double e[3], u[3], w[3], n1[3], n2[3], nn[3], s[3], d[3];
  vm_sub3(b, a, e);
  vm_sub3(p, a, u);
  vm_cross3(e, u, n1); /* (a, b, p) */
  vm_sub3(q, b, u);
  vm_sub3(a, b, w);
  vm_cross3(w, u, n2); /* (b, a, q) */
  double l1 = vm_norm3(n1), l2 = vm_norm3(n2);
  if (!(l1 > 0) || !(l2 > 0)) return 0;
  for (int r = 0; r < 3; r++) {
    nn[r] = n1[r] / l1 + n2[r] / l2;
    /* centroid of (b, a, q) minus centroid of (a, b, p) */
    d[r] = (q[r] - p[r]) / 3;
  }
  vm_cross3(e, nn, s);
  double ls = vm_norm3(s), ld = vm_norm3(d);
  if (!(ls > 0) || !(ld > 0)) return 0;
  double c = fabs(vm_dot3(s, d)) / (ls * ld);
  return c > 1 ? 1 : c;
}

double vm_surface_edge_nonortho(const double *a, const double *b, const double *p,
                                const double *q) {
  return acos(edge_cos(a, b, p, q)) * 180 / M_PI;
}

typedef struct {
  const vm_mesh *m;
  double *x;         /* m->xyz */
  const int32_t *tv; /* 3 nt: the triangles' vertices */
  int32_t *nbr;      /* 3 nt: the triangle across edge i (tv[i], tv[i + 1]); -1: none */
  int64_t *vt_off;   /* nv + 1 */
  int32_t *vt;       /* the triangles of each vertex */
  double *n0;        /* 3 nt: the triangles' unit normals before the relief */
} o2mesh;

/* The cosine of edge i of triangle t (0: none across, or degenerate). */
static double tri_edge_cos(const o2mesh *g, int64_t t, int i, int *interior) {
  int32_t u = g->nbr[3 * t + i];
  *interior = u >= 0;
  if (u < 0) return 1;
  const int32_t *a = g->tv + 3 * t, *b = g->tv + 3 * (int64_t)u;
  int32_t va = a[i], vb = a[(i + 1) % 3], vp = a[(i + 2) % 3], vq = -1;
  for (int k = 0; k < 3; k++)
    if (b[k] != va && b[k] != vb) vq = b[k];
  if (vq < 0) return 0;
  return edge_cos(g->x + 3 * (int64_t)va, g->x + 3 * (int64_t)vb, g->x + 3 * (int64_t)vp,
                  g->x + 3 * (int64_t)vq);
}

/* The penalty of the edges of v's triangles (an edge between two of them
 * counts twice) and their least cosine. */
static double penalty(const o2mesh *g, int32_t v, double c0, double *cmin) {
  double e = 0, cm = 1;
  for (int64_t k = g->vt_off[v]; k < g->vt_off[v + 1]; k++)
    for (int i = 0; i < 3; i++) {
      int in;
      double c = tri_edge_cos(g, g->vt[k], i, &in);
      if (!in) continue;
      cm = c < cm ? c : cm;
      if (c < c0) e += (c0 - c) * (c0 - c);
    }
  *cmin = cm;
  return e;
}

/* The smallest angle of v's triangles. */
static double star_min_angle(const o2mesh *g, int32_t v) {
  double mn = 180;
  for (int64_t k = g->vt_off[v]; k < g->vt_off[v + 1]; k++) {
    const int32_t *c = g->tv + 3 * (int64_t)g->vt[k];
    double a = tri_min_deg(g->x, c[0], c[1], c[2]);
    mn = a < mn ? a : mn;
  }
  return mn;
}

/* Do v's triangles keep their orientation (within 60 degrees of their
 * normals before the relief) and a smallest angle of at least `floor`? */
static int shapes_ok(const o2mesh *g, int32_t v, double floor) {
  for (int64_t k = g->vt_off[v]; k < g->vt_off[v + 1]; k++) {
    int64_t t = g->vt[k];
    const int32_t *c = g->tv + 3 * t;
    double n[3];
    tri_normal(g->x, c[0], c[1], c[2], n);
    double l = vm_norm3(n);
    if (!(l > 0) || vm_dot3(n, g->n0 + 3 * t) < 0.5 * l) return 0;
  }
  return star_min_angle(g, v) >= floor;
}

/* Edges beyond 70 and 60 degrees, and the least cosine. */
static void totals(const o2mesh *g, int64_t nt, int64_t *o70, int64_t *o60, int64_t *nedge,
                   double *cmin) {
  const double c70 = cos(70 * M_PI / 180), c60 = cos(60 * M_PI / 180);
  int64_t a = 0, b = 0, n = 0;
  double cm = 1;
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) {
      int32_t u = g->nbr[3 * t + i];
      if (u < t) continue; /* each interior edge once (and none across) */
      int in;
      double c = tri_edge_cos(g, t, i, &in);
      n++;
      a += c < c70;
      b += c < c60;
      cm = c < cm ? c : cm;
    }
  *o70 = a;
  *o60 = b;
  *nedge = n;
  *cmin = cm;
}

int vm_surface_ortho_relief(vm_mesh *m, vm_surface_projector *ref, const vm_ortho2d_opts *opts,
                            vm_ortho2d_result *res) {
  vm_ortho2d_result r;
  memset(&r, 0, sizeof r);
  if (res) *res = r;
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_ortho2d_opts o = opts ? *opts : vm_ortho2d_opts_default();
  if (o.sweeps < 0 || !(o.relief_deg > 0 && o.relief_deg < 90) ||
      !(o.active_deg > 0 && o.active_deg < 90) || !(o.min_angle >= 0 && o.min_angle < 60) ||
      !(o.max_move >= 0) || !isfinite(o.max_move))
    return vm_error(ctx, VM_ERR_ARG, "ortho2d: invalid options");
  double t0 = omp_get_wtime();
  if (m->dim != 3 || m->ne == 0) return VM_OK;
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] != VM_TRI) return VM_OK;
  const int64_t nv = m->nv, nt = m->ne;
  o2mesh g;
  memset(&g, 0, sizeof g);
  g.m = m;
  g.x = m->xyz;
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  vm_surface_projector *own = NULL;
  hmap hm;
  memset(&hm, 0, sizeof hm);
  /* triangles only: element t's vertices are conn[3 t ..] */
  const int32_t *tv = m->conn;
  g.tv = tv;
  g.nbr = vm_alloc_array(ctx, 3 * (size_t)nt, sizeof *g.nbr);
  g.n0 = vm_alloc_array(ctx, 3 * (size_t)nt, sizeof *g.n0);
  int32_t *vs = vm_alloc_array(ctx, (size_t)nv + 1, sizeof *vs);
  double *xs = vm_alloc_array(ctx, 3 * (size_t)nv + 1, sizeof *xs);
  double *h0 = vm_alloc_array(ctx, (size_t)nv + 1, sizeof *h0);
  uint8_t *act = vm_calloc(ctx, (size_t)nv + 1, 1);
  int st = VM_OK;
  if (!g.nbr || !g.n0 || !vs || !xs || !h0 || !act || (st = hm_init(ctx, &hm, 3 * (size_t)nt)) ||
      (st = vm_mesh_vertex_elements(m, &g.vt_off, &g.vt))) {
    st = st ? st : VM_ERR_NOMEM;
    goto done;
  }
  memcpy(xs, m->xyz, 3 * (size_t)nv * sizeof *xs);
  /* neighbours across each edge (a non-manifold edge: none) */
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) {
      uint64_t k = dkey(tv[3 * t + i], tv[3 * t + (i + 1) % 3]);
      /* a directed edge twice or more: -2, no neighbour there */
      hm_put(&hm, k, hm_get(&hm, k) == -1 ? 3 * t + i : -2);
    }
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) {
      int64_t a = hm_get(&hm, dkey(tv[3 * t + (i + 1) % 3], tv[3 * t + i]));
      int64_t b = hm_get(&hm, dkey(tv[3 * t + i], tv[3 * t + (i + 1) % 3]));
      g.nbr[3 * t + i] = a >= 0 && b >= 0 ? (int32_t)(a / 3) : -1;
    }
  hm_free(ctx, &hm); /* the neighbours are all it was for */
  /* the triangles' normals before the relief */
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = tv + 3 * t;
    double n[3];
    tri_normal(m->xyz, c[0], c[1], c[2], n);
    double l = vm_norm3(n);
    for (int k = 0; k < 3; k++) g.n0[3 * t + k] = l > 0 ? n[k] / l : 0;
  }
  /* each vertex's mean edge at the start: its length scale (an interior
   * edge counts twice, as its triangles see it) */
  double hsum = 0;
  int64_t hn = 0;
  memset(h0, 0, (size_t)nv * sizeof *h0);
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) {
      int32_t a = tv[3 * t + i], b = tv[3 * t + (i + 1) % 3];
      double l = vm_dist3(m->xyz + 3 * (int64_t)a, m->xyz + 3 * (int64_t)b);
      h0[a] += l;
      h0[b] += l;
      hsum += l;
      hn++;
    }
  for (int64_t v = 0; v < nv; v++) {
    int64_t d = 2 * (g.vt_off[v + 1] - g.vt_off[v]);
    h0[v] = d > 0 ? h0[v] / (double)d : 0;
  }
  double hmean = hn ? hsum / (double)hn : 0;

  const double c0 = cos(o.relief_deg * M_PI / 180), cact = cos(o.active_deg * M_PI / 180);
  double cmin;
  totals(&g, nt, &r.over70_before, &r.over60_before, &r.edges, &cmin);
  r.max_before = acos(cmin) * 180 / M_PI;
  r.over70_after = r.over70_before;
  r.over60_after = r.over60_before;
  r.max_after = r.max_before;
  if (o.sweeps == 0 || !(hmean > 0)) goto figures;

  /* vertex classes: fixed (-1), on the surface (0), on reference line k */
  if ((st = vm_surface_detect_features_cones(m, o.feature_angle, o.corner_angle, o.cone_angle, &f,
                                             NULL)))
    goto done;
  if (!ref) {
    if ((st = vm_surface_projector_create(ctx, m, &f, &own))) goto done;
    ref = own;
  }
  if ((st = vm_surface_projector_assign(ref, m, &f, 1e-3 * hmean, vs))) goto done;
  for (int64_t v = 0; v < nv; v++)
    if (m->vflag && m->vflag[v] == VM_VERTEX_FIXED) vs[v] = -1;
  vm_surface_ops ops = vm_surface_projector_ops(ref);

  int64_t last = r.over70_before;
  for (int sweep = 0; sweep < o.sweeps; sweep++) {
    /* the vertices of the triangles on an edge beyond the active angle */
    memset(act, 0, (size_t)nv);
    for (int64_t t = 0; t < nt; t++)
      for (int i = 0; i < 3; i++) {
        int in;
        if (tri_edge_cos(&g, t, i, &in) >= cact || !in) continue;
        int32_t u = g.nbr[3 * t + i];
        for (int k = 0; k < 3; k++) act[tv[3 * t + k]] = act[tv[3 * (int64_t)u + k]] = 1;
      }
    int64_t moves = 0;
    for (int64_t v = 0; v < nv; v++) {
      if ((v & 1023) == 0 && vm_ctx_interrupted(ctx)) {
        st = VM_ERR_INTERRUPTED;
        goto figures;
      }
      if (!act[v] || vs[v] < 0 || g.vt_off[v + 1] == g.vt_off[v]) continue;
      double *xv = m->xyz + 3 * v, xold[3], cm0, cm1;
      double e0 = penalty(&g, (int32_t)v, c0, &cm0);
      if (!(e0 > 0)) continue;
      double a0 = star_min_angle(&g, (int32_t)v), afloor = a0 < o.min_angle ? a0 : o.min_angle;
      memcpy(xold, xv, sizeof xold);
      /* the gradient by forward differences, within the surface's (or the
       * line's) tangent: the constraint normals of the projection removed */
      double fd = 1e-6 * h0[v], gr[3], q[3], nr[9];
      for (int k = 0; k < 3; k++) {
        xv[k] = xold[k] + fd;
        gr[k] = (penalty(&g, (int32_t)v, c0, &cm1) - e0) / fd;
        xv[k] = xold[k];
      }
      int nn = ops.project(ops.user, vs[v], xold, q, nr);
      if (nn < 0) {
        st = nn;
        goto done;
      }
      double basis[3][3];
      int nb = 0;
      for (int k = 0; k < nn && k < 3; k++) {
        double b[3];
        memcpy(b, nr + 3 * k, sizeof b);
        for (int j = 0; j < nb; j++) {
          double d = vm_dot3(b, basis[j]);
          for (int c = 0; c < 3; c++) b[c] -= d * basis[j][c];
        }
        double l = vm_norm3(b);
        if (!(l > 1e-12)) continue;
        for (int c = 0; c < 3; c++) basis[nb][c] = b[c] / l;
        nb++;
      }
      for (int j = 0; j < nb; j++) {
        double d = vm_dot3(gr, basis[j]);
        for (int c = 0; c < 3; c++) gr[c] -= d * basis[j][c];
      }
      double lg = vm_norm3(gr);
      if (!(lg > 0)) continue;
      double step = 0.25 * h0[v] / lg;
      double cfloor = cm0 < cact ? cm0 : cact;
      int kept = 0;
      for (int b = 0; b < 10 && !kept; b++, step *= 0.5) {
        double y[3];
        for (int c = 0; c < 3; c++) y[c] = xold[c] - step * gr[c];
        if (ops.project(ops.user, vs[v], y, q, nr) < 0) continue;
        if (vm_dist3(q, xs + 3 * v) > o.max_move * h0[v]) continue;
        memcpy(xv, q, sizeof q);
        double e1 = penalty(&g, (int32_t)v, c0, &cm1);
        kept = e1 < e0 && cm1 >= cfloor && shapes_ok(&g, (int32_t)v, afloor);
        if (!kept) memcpy(xv, xold, sizeof xold);
      }
      moves += kept;
    }
    r.moves += moves;
    r.sweeps = sweep + 1;
    int64_t o70, o60, ne;
    totals(&g, nt, &o70, &o60, &ne, &cmin);
    vm_log(ctx, VM_LOG_DEBUG, "ortho2d: sweep %d: %lld steps, %lld edges beyond 70 degrees",
           sweep + 1, (long long)moves, (long long)o70);
    if (!moves || (double)(last - o70) < 0.01 * (double)last) break;
    last = o70;
  }
figures:
  totals(&g, nt, &r.over70_after, &r.over60_after, &r.edges, &cmin);
  r.max_after = acos(cmin) * 180 / M_PI;
  for (int64_t v = 0; v < nv; v++) {
    double d = vm_dist3(m->xyz + 3 * v, xs + 3 * v);
    r.moved += d > 0;
    r.max_shift = d > r.max_shift ? d : r.max_shift;
  }
done:
  if (st < 0 && st != VM_ERR_INTERRUPTED && xs) memcpy(m->xyz, xs, 3 * (size_t)nv * sizeof *xs);
  hm_free(ctx, &hm);
  vm_surface_projector_destroy(&own);
  vm_surface_features_free(ctx, &f);
  vm_free(ctx, g.nbr);
  vm_free(ctx, g.vt_off);
  vm_free(ctx, g.vt);
  vm_free(ctx, g.n0);
  vm_free(ctx, vs);
  vm_free(ctx, xs);
  vm_free(ctx, h0);
  vm_free(ctx, act);
  r.elapsed = omp_get_wtime() - t0;
  if (res) *res = r;
  return st;
}
