/* A planar 2D mesh to its plane's coordinates and back (varmesh/planar.h). */
#include "varmesh/planar.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static int unit3(double *a) {
  double l = sqrt(dot3(a, a));
  if (!(l > 0) || !isfinite(l)) return 0;
  for (int k = 0; k < 3; k++) a[k] /= l;
  return 1;
}

/* Newell's normal of every element summed, each element's about its own
 * first vertex (large offsets do not eat the digits): a tangled mesh's
 * folded elements cancel, the plane's normal stays. */
static void newell_normal(const vm_mesh *m, double *n) {
  n[0] = n[1] = n[2] = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int64_t b = m->eoff[e], k = m->eoff[e + 1] - b;
    const double *p0 = m->xyz + 3 * (int64_t)m->conn[b];
    for (int64_t i = 0; i < k; i++) {
      const double *a = m->xyz + 3 * (int64_t)m->conn[b + i];
      const double *c = m->xyz + 3 * (int64_t)m->conn[b + (i + 1) % k];
      double ax = a[0] - p0[0], ay = a[1] - p0[1], az = a[2] - p0[2];
      double cx = c[0] - p0[0], cy = c[1] - p0[1], cz = c[2] - p0[2];
      n[0] += (ay - cy) * (az + cz);
      n[1] += (az - cz) * (ax + cx);
      n[2] += (ax - cx) * (ay + cy);
    }
  }
}

/* The best plane's normal when Newell's cancels (a mesh folded onto
 * itself): the normal of the largest triangle of element corners. */
static void corner_normal(const vm_mesh *m, double *n) {
  double best = 0;
  n[0] = n[1] = 0;
  n[2] = 1;
  for (int64_t e = 0; e < m->ne; e++) {
    int64_t b = m->eoff[e], k = m->eoff[e + 1] - b;
    const double *p0 = m->xyz + 3 * (int64_t)m->conn[b];
    for (int64_t i = 1; i + 1 < k; i++) {
      const double *a = m->xyz + 3 * (int64_t)m->conn[b + i];
      const double *c = m->xyz + 3 * (int64_t)m->conn[b + i + 1];
      double u[3] = {a[0] - p0[0], a[1] - p0[1], a[2] - p0[2]};
      double v[3] = {c[0] - p0[0], c[1] - p0[1], c[2] - p0[2]}, w[3];
      cross3(u, v, w);
      double l = dot3(w, w);
      if (l > best) {
        best = l;
        memcpy(n, w, sizeof w);
      }
    }
  }
}

static int dbl_cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

int vm_mesh_plane_frame(const vm_mesh *m, double tol, vm_plane_frame *f) {
  if (!m || !f) return VM_ERR_ARG;
  memset(f, 0, sizeof *f);
  f->dim0 = m->dim;
  f->worst = -1;
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 2 || m->nv == 0)
    return vm_error(m->ctx, VM_ERR_ARG, "not a 2D mesh");
  /* an exact plane x, y or z = c: the others' coordinates as they are */
  for (int a = 2; a >= 0; a--) {
    double c = m->xyz[a];
    int64_t v = 1;
    while (v < m->nv && m->xyz[3 * v + a] == c) v++;
    if (v == m->nv) {
      f->axis = a;
      f->level = c;
      return VM_OK;
    }
  }
  f->axis = -1;
  double lo[3], hi[3], diag = vm_mesh_bounds(m, lo, hi);
  newell_normal(m, f->n);
  if (!unit3(f->n)) {
    corner_normal(m, f->n);
    if (!unit3(f->n)) return vm_error(m->ctx, VM_ERR_ARG, "no plane: every element is flat");
  }
  /* through the median vertex along n: one vertex off a plane is reported,
   * not the plane pulled towards it */
  double *h = vm_alloc_array(m->ctx, (size_t)m->nv, sizeof *h);
  if (!h) return VM_ERR_NOMEM;
  for (int64_t v = 0; v < m->nv; v++) h[v] = dot3(m->xyz + 3 * v, f->n);
  qsort(h, (size_t)m->nv, sizeof *h, dbl_cmp);
  double hm = h[m->nv / 2], hc;
  vm_free(m->ctx, h);
  for (int k = 0; k < 3; k++) f->o[k] = 0.5 * (lo[k] + hi[k]);
  hc = dot3(f->o, f->n);
  for (int k = 0; k < 3; k++) f->o[k] += (hm - hc) * f->n[k];
  /* u: the axis least along n, made orthogonal to it */
  int a = fabs(f->n[0]) <= fabs(f->n[1]) && fabs(f->n[0]) <= fabs(f->n[2]) ? 0
          : fabs(f->n[1]) <= fabs(f->n[2])                                 ? 1
                                                                           : 2;
  double e[3] = {0, 0, 0};
  e[a] = 1;
  for (int k = 0; k < 3; k++) f->u[k] = e[k] - dot3(e, f->n) * f->n[k];
  unit3(f->u);
  cross3(f->n, f->u, f->v);
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    double d[3] = {p[0] - f->o[0], p[1] - f->o[1], p[2] - f->o[2]};
    double off = fabs(dot3(d, f->n));
    if (off > f->offset || f->worst < 0) {
      f->offset = off;
      f->worst = v;
    }
  }
  if (!(f->offset <= tol * diag))
    return vm_error(m->ctx, VM_ERR_ARG, "vertex %lld is %.3g off the plane (%.3g of the diagonal)",
                    (long long)f->worst, f->offset, diag > 0 ? f->offset / diag : 0.0);
  return VM_OK;
}

double vm_mesh_signed_area_2d(const vm_mesh *m) {
  double s = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    int64_t b = m->eoff[e], k = m->eoff[e + 1] - b;
    const double *p0 = m->xyz + 3 * (int64_t)m->conn[b];
    double a = 0;
    for (int64_t i = 1; i + 1 < k; i++) {
      const double *p = m->xyz + 3 * (int64_t)m->conn[b + i];
      const double *q = m->xyz + 3 * (int64_t)m->conn[b + i + 1];
      a += (p[0] - p0[0]) * (q[1] - p0[1]) - (p[1] - p0[1]) * (q[0] - p0[0]);
    }
    s += 0.5 * a;
  }
  return s;
}

void vm_mesh_to_plane(vm_mesh *m, vm_plane_frame *f) {
  f->flip = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    double *p = m->xyz + 3 * v, x, y;
    if (f->axis >= 0) {
      /* cyclic: the plane's normal is +axis */
      x = p[(f->axis + 1) % 3];
      y = p[(f->axis + 2) % 3];
    } else {
      double d[3] = {p[0] - f->o[0], p[1] - f->o[1], p[2] - f->o[2]};
      x = dot3(d, f->u);
      y = dot3(d, f->v);
    }
    p[0] = x;
    p[1] = y;
    p[2] = 0;
  }
  m->dim = 2;
  if (vm_mesh_signed_area_2d(m) < 0) {
    f->flip = 1;
    for (int64_t v = 0; v < m->nv; v++) m->xyz[3 * v + 1] = -m->xyz[3 * v + 1];
  }
}

void vm_mesh_from_plane(vm_mesh *m, const vm_plane_frame *f, const double *x2d0,
                        const double *xyz0) {
  for (int64_t v = 0; v < m->nv; v++) {
    double *p = m->xyz + 3 * v;
    if (x2d0 && xyz0 && memcmp(p, x2d0 + 3 * v, 2 * sizeof *p) == 0) {
      memcpy(p, xyz0 + 3 * v, 3 * sizeof *p);
      continue;
    }
    double q[3] = {p[0], p[1], 0};
    vm_plane_to_space(f, q, p);
  }
  m->dim = f->dim0;
}

void vm_plane_to_space(const vm_plane_frame *f, const double q[3], double p[3]) {
  double x = q[0], y = f->flip ? -q[1] : q[1];
  if (f->axis >= 0) {
    p[f->axis] = f->level;
    p[(f->axis + 1) % 3] = x;
    p[(f->axis + 2) % 3] = y;
  } else {
    for (int k = 0; k < 3; k++) p[k] = f->o[k] + x * f->u[k] + y * f->v[k];
  }
}

typedef struct {
  int32_t lo, hi; /* the edge's vertices, lo < hi */
  int32_t e;      /* the element */
  int8_t up;      /* it runs lo -> hi */
} dedge;

static int dedge_cmp(const void *pa, const void *pb) {
  const dedge *a = pa, *b = pb;
  if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
  if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
  return a->e < b->e ? -1 : a->e > b->e;
}

int64_t vm_mesh_orientation_conflicts_2d(const vm_mesh *m, int64_t first[2], int32_t edge[2]) {
  first[0] = first[1] = -1;
  edge[0] = edge[1] = -1;
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 2) n += m->eoff[e + 1] - m->eoff[e];
  dedge *d = vm_alloc_array(m->ctx, (size_t)n + 1, sizeof *d);
  if (!d) return VM_ERR_NOMEM;
  n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    int64_t b = m->eoff[e], k = m->eoff[e + 1] - b;
    for (int64_t i = 0; i < k; i++) {
      int32_t a = m->conn[b + i], c = m->conn[b + (i + 1) % k];
      d[n++] = (dedge){a < c ? a : c, a < c ? c : a, (int32_t)e, (int8_t)(a < c)};
    }
  }
  qsort(d, (size_t)n, sizeof *d, dedge_cmp);
  int64_t bad = 0;
  for (int64_t i = 0; i < n;) {
    int64_t j = i + 1;
    while (j < n && d[j].lo == d[i].lo && d[j].hi == d[i].hi) j++;
    /* two elements on an edge run through it in opposite directions */
    if (j - i == 2 && d[i].up == d[i + 1].up) {
      if (!bad++) {
        first[0] = d[i].e;
        first[1] = d[i + 1].e;
        edge[0] = d[i].lo;
        edge[1] = d[i].hi;
      }
    }
    i = j;
  }
  vm_free(m->ctx, d);
  return bad;
}

double vm_mesh_signed_volume(const vm_mesh *m) {
  double s = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e], faces[6][4], nfv[6];
    if (vm_elem_dim(t) != 3) continue;
    const int32_t *c = m->conn + m->eoff[e];
    int nf = vm_elem_faces(t, faces, nfv);
    /* the faces' triangles (outward) seen from the first vertex, each
     * relative to it: the divergence theorem, exact for planar faces */
    const double *o = m->xyz + 3 * (int64_t)c[0];
    double v = 0;
    for (int f = 0; f < nf; f++)
      for (int k = 1; k + 1 < nfv[f]; k++) {
        const double *a = m->xyz + 3 * (int64_t)c[faces[f][0]];
        const double *b = m->xyz + 3 * (int64_t)c[faces[f][k]];
        const double *d = m->xyz + 3 * (int64_t)c[faces[f][k + 1]];
        double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
        double w[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
        double z[3] = {d[0] - o[0], d[1] - o[1], d[2] - o[2]}, x[3];
        cross3(w, z, x);
        v += dot3(u, x);
      }
    s += v / 6;
  }
  return s;
}
