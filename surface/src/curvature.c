/* surface/src/curvature.c: mean curvature from the finite-volume (dual
 * cell) Laplace-Beltrami operator, its filter (Section 6.1), normals. */
#include "varmesh/curvature.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "varmesh/surface_mesh.h"
#include "vec3.h"

/* A triangle whose doubled area is below this fraction of its squared
 * longest edge is degenerate: its cotangents are meaningless. */
#define DEGENERATE_REL 1e-12

static int has_2d(const vm_mesh *m) {
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 2) return 1;
  return 0;
}

/* Geometry of triangle (a, b, c): edge vectors, doubled area, unit normal;
 * returns 0 if degenerate. */
typedef struct {
  double e[3][3]; /* e[k] = edge opposite corner k: e[0] = c - b, e[1] = a - c, e[2] = b - a */
  double l2[3];   /* squared lengths */
  double area2;   /* |(b - a) x (c - a)| */
  double n[3];    /* unit normal */
} tri_geom;

static int tri_geometry(const double *xyz, const int32_t *t, tri_geom *g) {
  const double *p[3] = {xyz + 3 * (int64_t)t[0], xyz + 3 * (int64_t)t[1], xyz + 3 * (int64_t)t[2]};
  vm_sub3(p[2], p[1], g->e[0]);
  vm_sub3(p[0], p[2], g->e[1]);
  vm_sub3(p[1], p[0], g->e[2]);
  double lmax = 0;
  for (int k = 0; k < 3; k++) {
    g->l2[k] = vm_dot3(g->e[k], g->e[k]);
    if (g->l2[k] > lmax) lmax = g->l2[k];
  }
  double c[3];
  vm_cross3(g->e[2], g->e[1], c); /* (b - a) x (a - c) = -(b - a) x (c - a) */
  g->area2 = vm_norm3(c);
  if (!(g->area2 > DEGENERATE_REL * lmax) || !isfinite(g->area2)) return 0;
  for (int k = 0; k < 3; k++) g->n[k] = -c[k] / g->area2;
  return 1;
}

/* Angle at corner k: between -e[k+2] ... expressed with the two edges at k:
 * u = e[(k+2)%3] (from k to k+1), v = -e[(k+1)%3] (from k to k+2). */
static double corner_dot(const tri_geom *g, int k) {
  return -vm_dot3(g->e[(k + 2) % 3], g->e[(k + 1) % 3]);
}

static void accumulate_normals(const vm_mesh *m, const vm_surf_tris *T, double *nrm,
                               int64_t *ndeg) {
  memset(nrm, 0, 3 * (size_t)m->nv * sizeof *nrm);
  int64_t deg = 0;
  for (int64_t t = 0; t < T->nt; t++) {
    tri_geom g;
    const int32_t *tv = T->tri + 3 * t;
    if (!tri_geometry(m->xyz, tv, &g)) {
      deg++;
      continue;
    }
    for (int k = 0; k < 3; k++) {
      double ang = atan2(g.area2, corner_dot(&g, k));
      double *n = nrm + 3 * (int64_t)tv[k];
      for (int r = 0; r < 3; r++) n[r] += T->w[t] * ang * g.n[r];
    }
  }
  for (int64_t v = 0; v < m->nv; v++) {
    double *n = nrm + 3 * v;
    double l = vm_norm3(n);
    if (l > 0)
      for (int r = 0; r < 3; r++) n[r] /= l;
  }
  if (ndeg) *ndeg = deg;
}

int vm_surface_normals(const vm_mesh *m, double *normals) {
  if (!m || !normals) return VM_ERR_ARG;
  if (!has_2d(m)) return vm_error(m->ctx, VM_ERR_ARG, "normals: the mesh has no surface elements");
  vm_surf_tris T;
  int st = vm_surf_tris_build(m->ctx, m, &T);
  if (st) return st;
  accumulate_normals(m, &T, normals, NULL);
  vm_surf_tris_free(m->ctx, &T);
  return VM_OK;
}

/* Mixed (Voronoi / obtuse-corrected) area of each corner of a triangle. */
static void mixed_areas(const tri_geom *g, const double cot[3], double a[3]) {
  double area = 0.5 * g->area2;
  int obtuse = -1;
  for (int k = 0; k < 3; k++)
    if (cot[k] < 0) obtuse = k;
  if (obtuse < 0) {
    /* corner k touches the edges opposite k+1 and k+2 */
    for (int k = 0; k < 3; k++)
      a[k] = (g->l2[(k + 1) % 3] * cot[(k + 1) % 3] + g->l2[(k + 2) % 3] * cot[(k + 2) % 3]) / 8;
  } else {
    for (int k = 0; k < 3; k++) a[k] = k == obtuse ? area / 2 : area / 4;
  }
}

int vm_surface_mean_curvature(const vm_mesh *m, double *H, double *normals, double *area,
                              vm_curvature_stats *st_out) {
  if (!m || !H) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  if (!has_2d(m)) return vm_error(ctx, VM_ERR_ARG, "curvature: the mesh has no surface elements");
  const int64_t nv = m->nv;
  const size_t n1 = nv > 0 ? (size_t)nv : 1;
  vm_surf_tris T;
  vm_surf_edges E;
  memset(&E, 0, sizeof E);
  int st = vm_surf_tris_build(ctx, m, &T);
  if (st) return st;
  st = vm_surf_edges_build(ctx, m, &E);
  double *lap = vm_calloc(ctx, 3 * n1, sizeof *lap);
  double *A = area ? area : vm_alloc_array(ctx, n1, sizeof *A);
  double *nrm = normals ? normals : vm_alloc_array(ctx, 3 * n1, sizeof *nrm);
  if (st || !lap || !A || !nrm) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memset(A, 0, n1 * sizeof *A);
  int64_t ndeg = 0;
  accumulate_normals(m, &T, nrm, &ndeg);
  /* flux of grad y through the dual cell boundary: per triangle, the part
   * of the dual edge of (i, j) inside it carries cot(angle opposite)/2 */
  for (int64_t t = 0; t < T.nt; t++) {
    tri_geom g;
    const int32_t *tv = T.tri + 3 * t;
    if (!tri_geometry(m->xyz, tv, &g)) continue;
    double cot[3], ca[3];
    for (int k = 0; k < 3; k++) cot[k] = corner_dot(&g, k) / g.area2;
    mixed_areas(&g, cot, ca);
    const double w = T.w[t];
    for (int k = 0; k < 3; k++) {
      int i = tv[k], j = tv[(k + 1) % 3];
      /* edge i -> j is e[(k+2)%3], opposite corner k+2 */
      const double *eij = g.e[(k + 2) % 3];
      double c = 0.5 * w * cot[(k + 2) % 3];
      for (int r = 0; r < 3; r++) {
        lap[3 * (int64_t)i + r] += c * eij[r];
        lap[3 * (int64_t)j + r] -= c * eij[r];
      }
      A[i] += w * ca[k];
    }
  }
  for (int64_t v = 0; v < nv; v++)
    H[v] = A[v] > 0 ? -vm_dot3(lap + 3 * v, nrm + 3 * v) / (2 * A[v]) : 0.0;
  /* open dual cells: take the mean of the interior neighbours */
  int64_t nb = 0;
  for (int64_t v = 0; v < nv; v++) {
    if (!E.onbnd[v]) continue;
    nb++;
    double s = 0;
    int cnt = 0;
    for (int64_t k = E.rowptr[v]; k < E.rowptr[v + 1]; k++)
      if (!E.onbnd[E.adj[k]]) {
        s += H[E.adj[k]];
        cnt++;
      }
    lap[3 * v] = cnt ? s / cnt : 0.0;
  }
  for (int64_t v = 0; v < nv; v++)
    if (E.onbnd[v]) H[v] = lap[3 * v];
  if (st_out) {
    vm_curvature_stats s;
    memset(&s, 0, sizeof s);
    s.degenerate = ndeg;
    s.boundary = nb;
    s.min = INFINITY;
    s.max = -INFINITY;
    double sa = 0, sh = 0;
    for (int64_t v = 0; v < nv; v++) {
      if (H[v] < s.min) s.min = H[v];
      if (H[v] > s.max) s.max = H[v];
      sa += A[v];
      sh += A[v] * fabs(H[v]);
    }
    s.mean_abs = sa > 0 ? sh / sa : 0;
    if (nv == 0) s.min = s.max = 0;
    *st_out = s;
  }
done:
  vm_surf_tris_free(ctx, &T);
  vm_surf_edges_free(ctx, &E);
  vm_free(ctx, lap);
  if (A != area) vm_free(ctx, A);
  if (nrm != normals) vm_free(ctx, nrm);
  return st;
}

vm_curvature_filter vm_curvature_filter_default(void) {
  vm_curvature_filter f = {0.0, 0.0, 0};
  return f;
}

int vm_curvature_filter_apply(const vm_mesh *m, const vm_curvature_filter *f, double *H) {
  if (!m || !f || !H) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  if (!(f->threshold >= 0) || !(f->cap >= 0) || f->smooth < 0)
    return vm_error(ctx, VM_ERR_ARG, "curvature filter: threshold %g, cap %g, passes %d",
                    f->threshold, f->cap, f->smooth);
  const int64_t nv = m->nv;
  if (f->cap > 0 && isfinite(f->cap))
    for (int64_t v = 0; v < nv; v++)
      if (fabs(H[v]) > f->cap) H[v] = H[v] > 0 ? f->cap : -f->cap;
  if (f->smooth > 0) {
    const size_t n1 = nv > 0 ? (size_t)nv : 1;
    vm_surf_tris T;
    vm_surf_edges E;
    int st = vm_surf_tris_build(ctx, m, &T);
    if (st) return st;
    st = vm_surf_edges_build(ctx, m, &E);
    if (st) {
      vm_surf_tris_free(ctx, &T);
      return st;
    }
    double *A = vm_calloc(ctx, n1, sizeof *A);
    double *tmp = vm_alloc_array(ctx, n1, sizeof *tmp);
    if (!A || !tmp) {
      vm_free(ctx, A);
      vm_free(ctx, tmp);
      vm_surf_tris_free(ctx, &T);
      vm_surf_edges_free(ctx, &E);
      return VM_ERR_NOMEM;
    }
    /* barycentric areas as weights: robust on any triangle */
    for (int64_t t = 0; t < T.nt; t++) {
      tri_geom g;
      if (!tri_geometry(m->xyz, T.tri + 3 * t, &g)) continue;
      for (int k = 0; k < 3; k++) A[T.tri[3 * t + k]] += T.w[t] * g.area2 / 6;
    }
    for (int pass = 0; pass < f->smooth; pass++) {
      for (int64_t v = 0; v < nv; v++) {
        double s = A[v] * H[v], sw = A[v];
        for (int64_t k = E.rowptr[v]; k < E.rowptr[v + 1]; k++) {
          s += A[E.adj[k]] * H[E.adj[k]];
          sw += A[E.adj[k]];
        }
        tmp[v] = sw > 0 ? s / sw : H[v];
      }
      memcpy(H, tmp, (size_t)nv * sizeof *H);
    }
    vm_free(ctx, A);
    vm_free(ctx, tmp);
    vm_surf_tris_free(ctx, &T);
    vm_surf_edges_free(ctx, &E);
  }
  if (f->threshold > 0)
    for (int64_t v = 0; v < nv; v++)
      if (fabs(H[v]) < f->threshold) H[v] = 0;
  return VM_OK;
}

int vm_surface_curvature(vm_mesh *m, const vm_curvature_filter *f, vm_curvature_stats *st) {
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  const size_t n1 = m->nv > 0 ? (size_t)m->nv : 1;
  double *H = vm_alloc_array(ctx, n1, sizeof *H);
  if (!H) return VM_ERR_NOMEM;
  int rc = vm_surface_mean_curvature(m, H, NULL, NULL, st);
  vm_field *fr = NULL, *ff = NULL;
  if (!rc)
    rc = vm_mesh_add_field(m, VM_FIELD_MEAN_CURVATURE, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &fr);
  if (!rc) {
    memcpy(fr->data, H, (size_t)m->nv * sizeof *H);
    if (f) rc = vm_curvature_filter_apply(m, f, H);
  }
  if (!rc)
    rc = vm_mesh_add_field(m, VM_FIELD_MEAN_CURVATURE_FILTERED, VM_FIELD_VERTEX, VM_FIELD_F64, 1,
                           &ff);
  if (!rc) memcpy(ff->data, H, (size_t)m->nv * sizeof *H);
  vm_free(ctx, H);
  return rc;
}
