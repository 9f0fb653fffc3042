/* volume/src/fill.c: the fill stage (varmesh/fill.h): envelope, size field,
 * far field, Gmsh's Delaunay mesher in memory, the merged mesh, and the
 * variational optimization of the tetrahedra next to the layer. */
#include "varmesh/fill.h"
#include "varmesh/quality.h"

#include <gmshc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "fill_private.h"
#include "varmesh/topology.h"
#include "varmesh/volume.h"
#include "vec3.h"

#define PI 3.14159265358979323846
#define VM_FILL_OFF 0.5

vm_fill_opts vm_fill_opts_default(void) {
  vm_fill_opts o;
  memset(&o, 0, sizeof o);
  o.farfield = 20;
  o.shape = VM_FAR_BOX;
  o.growth = 1.2;
  o.opt_iter = 30;
  o.opt_rings = 3;
  o.fv_sweeps = 8;
  o.algorithm = 1;
  return o;
}

double fill_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---------- triangular faces shared by cells ---------- */

static int cmp_tface(const void *a, const void *b) {
  const tface *x = a, *y = b;
  for (int i = 0; i < 3; i++)
    if (x->v[i] != y->v[i]) return x->v[i] < y->v[i] ? -1 : 1;
  return (x->cell > y->cell) - (x->cell < y->cell);
}

void fill_sort3(int32_t v[3]) {
  int32_t t;
  if (v[0] > v[1]) t = v[0], v[0] = v[1], v[1] = t;
  if (v[1] > v[2]) t = v[1], v[1] = v[2], v[2] = t;
  if (v[0] > v[1]) t = v[0], v[0] = v[1], v[1] = t;
}

int fill_tri_faces(vm_ctx *ctx, const vm_mesh *m, tface **out, int64_t *n) {
  int64_t cap = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    cap += t == VM_TET ? 4 : t == VM_PYRAMID ? 4 : t == VM_PRISM ? 2 : 0;
  }
  tface *f = vm_alloc_array(ctx, (size_t)(cap ? cap : 1), sizeof *f);
  if (!f) return VM_ERR_NOMEM;
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 3) continue;
    int fl[6][4], nfv[6];
    int nf = vm_elem_faces(m->etype[e], fl, nfv);
    const int32_t *c = m->conn + m->eoff[e];
    for (int j = 0; j < nf; j++) {
      if (nfv[j] != 3) continue;
      for (int i = 0; i < 3; i++) f[k].v[i] = c[fl[j][i]];
      fill_sort3(f[k].v);
      f[k].face = j;
      f[k++].cell = (int32_t)e;
    }
  }
  qsort(f, (size_t)k, sizeof *f, cmp_tface);
  *out = f;
  *n = k;
  return VM_OK;
}

int fill_same_face(const tface *a, const tface *b) {
  return a->v[0] == b->v[0] && a->v[1] == b->v[1] && a->v[2] == b->v[2];
}

/* Index of the triangle tri (any vertex order) in f[0..n) sorted by
 * cmp_tface, or -1. */
static int64_t find_face(const tface *f, int64_t n, const int32_t *tri) {
  tface key;
  memcpy(key.v, tri, sizeof key.v);
  fill_sort3(key.v);
  key.cell = -1;
  int64_t lo = 0, hi = n;
  while (lo < hi) {
    int64_t mid = (lo + hi) / 2;
    if (cmp_tface(&f[mid], &key) < 0)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < n && fill_same_face(&f[lo], &key) ? lo : -1;
}

/* ---------- cell volumes and tet angles ---------- */

static double tet_vol(const double *a, const double *b, const double *c, const double *d) {
  double u[3], v[3], w[3], x[3];
  vm_sub3(b, a, u);
  vm_sub3(c, a, v);
  vm_sub3(d, a, w);
  vm_cross3(u, v, x);
  return vm_dot3(x, w) / 6;
}

/* Volume of a cell as the sum of tets from its centroid to its faces (faces
 * of 4 split by their centroid): exact for tets and planar-faced cells. */
static double cell_volume(const vm_mesh *m, int64_t e) {
  const int32_t *c = m->conn + m->eoff[e];
  int n = vm_elem_nverts(m->etype[e]);
  if (m->etype[e] == VM_TET)
    return tet_vol(m->xyz + 3 * c[0], m->xyz + 3 * c[1], m->xyz + 3 * c[2], m->xyz + 3 * c[3]);
  double g[3] = {0, 0, 0};
  for (int i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) g[k] += m->xyz[3 * c[i] + k] / n;
  int fl[6][4], nfv[6];
  int nf = vm_elem_faces(m->etype[e], fl, nfv);
  double vol = 0;
  for (int j = 0; j < nf; j++) {
    const double *p[4];
    for (int i = 0; i < nfv[j]; i++) p[i] = m->xyz + 3 * c[fl[j][i]];
    if (nfv[j] == 3) {
      vol += tet_vol(p[0], p[1], p[2], g);
    } else {
      double q[3];
      for (int k = 0; k < 3; k++) q[k] = (p[0][k] + p[1][k] + p[2][k] + p[3][k]) / 4;
      for (int i = 0; i < 4; i++) vol += tet_vol(p[i], p[(i + 1) % 4], q, g);
    }
  }
  return vol;
}

/* The six dihedral angles of a tet (radians) into lo/hi, its scaled
 * Jacobian (min over corners of det/(|e1||e2||e3|), times sqrt 2) returned. */
static double tet_angles(const double *p[4], double *lo, double *hi) {
  static const int edge[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                                 {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  *lo = PI;
  *hi = 0;
  for (int k = 0; k < 6; k++) {
    const double *a = p[edge[k][0]], *b = p[edge[k][1]], *c = p[edge[k][2]], *d = p[edge[k][3]];
    double e[3], u[3], w[3], n1[3], n2[3];
    vm_sub3(b, a, e);
    vm_sub3(c, a, u);
    vm_sub3(d, a, w);
    vm_cross3(e, u, n1);
    vm_cross3(e, w, n2);
    double l1 = vm_norm3(n1), l2 = vm_norm3(n2);
    double cs = l1 > 0 && l2 > 0 ? vm_dot3(n1, n2) / (l1 * l2) : 1;
    double ang = acos(cs < -1 ? -1 : cs > 1 ? 1 : cs);
    if (ang < *lo) *lo = ang;
    if (ang > *hi) *hi = ang;
  }
  double sj = INFINITY;
  static const int corner[4][3] = {{1, 2, 3}, {2, 0, 3}, {0, 1, 3}, {1, 0, 2}};
  for (int i = 0; i < 4; i++) {
    double e1[3], e2[3], e3[3], x[3];
    vm_sub3(p[corner[i][0]], p[i], e1);
    vm_sub3(p[corner[i][1]], p[i], e2);
    vm_sub3(p[corner[i][2]], p[i], e3);
    vm_cross3(e1, e2, x);
    double den = vm_norm3(e1) * vm_norm3(e2) * vm_norm3(e3);
    double s = den > 0 ? vm_dot3(x, e3) / den * 1.41421356237309504880 : 0;
    if (s < sj) sj = s;
  }
  return sj;
}

/* vm_fill_tet_quality_of over the tets from element e0 on (the fill's own,
 * after the input's cells: a layer's tets where its layers end are not the
 * fill's); a face counts where one of its cells is such a tet. */
static int tet_quality_from(vm_ctx *ctx, const vm_mesh *m, int64_t e0, vm_fill_tet_quality *q) {
  memset(q, 0, sizeof *q);
  q->min_dihedral = 180;
  q->sj_min = 1;
  for (int64_t e = e0; e < m->ne; e++) {
    if (m->etype[e] != VM_TET) continue;
    const int32_t *c = m->conn + m->eoff[e];
    const double *p[4] = {m->xyz + 3 * c[0], m->xyz + 3 * c[1], m->xyz + 3 * c[2],
                          m->xyz + 3 * c[3]};
    double lo, hi;
    double sj = tet_angles(p, &lo, &hi);
    if (lo * 180 / PI < q->min_dihedral) q->min_dihedral = lo * 180 / PI;
    if (hi * 180 / PI > q->max_dihedral) q->max_dihedral = hi * 180 / PI;
    if (sj < q->sj_min) q->sj_min = sj;
    if (tet_vol(p[0], p[1], p[2], p[3]) <= 0) q->inverted++;
  }
  tface *f;
  int64_t nf;
  int st = fill_tri_faces(ctx, m, &f, &nf);
  if (st) return st;
  for (int64_t i = 0; i + 1 < nf; i++) {
    if (!fill_same_face(&f[i], &f[i + 1])) continue;
    int32_t a = f[i].cell, b = f[i + 1].cell;
    int ta = m->etype[a] == VM_TET && a >= e0, tb = m->etype[b] == VM_TET && b >= e0;
    if (!ta && !tb) continue;
    double va = fabs(cell_volume(m, a)), vb = fabs(cell_volume(m, b));
    double r = va > vb ? (vb > 0 ? va / vb : INFINITY) : (va > 0 ? vb / va : INFINITY);
    if (ta && tb) {
      if (r > q->vol_ratio_tets) q->vol_ratio_tets = r;
    } else if (r > q->vol_ratio_env) {
      q->vol_ratio_env = r;
    }
    i++;
  }
  vm_free(ctx, f);
  return VM_OK;
}

int vm_fill_tet_quality_of(vm_ctx *ctx, const vm_mesh *m, vm_fill_tet_quality *q) {
  return tet_quality_from(ctx, m, 0, q);
}

/* ---------- the size field: a kd-tree over the envelope's vertices ---------- */

typedef struct {
  double lo[3], hi[3];
  double hmin;  /* smallest h_v below */
  int32_t a, b; /* points [a, b) of the permuted order */
} kd_node;

typedef struct {
  int64_t n;
  double *p;   /* 3 per point, permuted */
  double *h;   /* h_v, permuted */
  kd_node *nd; /* implicit binary tree, node i has children 2i+1, 2i+2 */
  int64_t nnodes;
  int32_t *id;  /* original index of each permuted point */
  double slope; /* growth - 1 */
  double hmax;  /* cap (far size) */
  const vm_fill_opts *o;
} size_field;

enum { KD_LEAF = 8 };

/* Reorder idx[a, b) so that idx[mid] has the median coordinate along ax,
 * the smaller ones before it (quickselect; ties by index: deterministic). */
static int kd_less(const double *pts, int ax, int32_t i, int32_t j) {
  double x = pts[3 * i + ax], y = pts[3 * j + ax];
  return x < y || (x == y && i < j);
}

static void kd_select(int32_t *idx, const double *pts, int ax, int32_t a, int32_t b, int32_t mid) {
  while (b - a > 1) {
    int32_t pv = idx[a + (b - a) / 2], lo = a, hi = b - 1;
    while (lo <= hi) {
      while (kd_less(pts, ax, idx[lo], pv)) lo++;
      while (kd_less(pts, ax, pv, idx[hi])) hi--;
      if (lo <= hi) {
        int32_t t = idx[lo];
        idx[lo++] = idx[hi];
        idx[hi--] = t;
      }
    }
    if (mid <= hi)
      b = hi + 1;
    else if (mid >= lo)
      a = lo;
    else
      return;
  }
}

static void kd_build(size_field *S, int32_t *idx, const double *pts, const double *h, int64_t i,
                     int32_t a, int32_t b) {
  kd_node *n = &S->nd[i];
  n->a = a;
  n->b = b;
  n->hmin = INFINITY;
  for (int k = 0; k < 3; k++) n->lo[k] = INFINITY, n->hi[k] = -INFINITY;
  for (int32_t j = a; j < b; j++) {
    const double *x = pts + 3 * idx[j];
    for (int k = 0; k < 3; k++) {
      if (x[k] < n->lo[k]) n->lo[k] = x[k];
      if (x[k] > n->hi[k]) n->hi[k] = x[k];
    }
    if (h[idx[j]] < n->hmin) n->hmin = h[idx[j]];
  }
  if (b - a <= KD_LEAF || 2 * i + 2 >= S->nnodes) return;
  int ax = 0;
  for (int k = 1; k < 3; k++)
    if (n->hi[k] - n->lo[k] > n->hi[ax] - n->lo[ax]) ax = k;
  int32_t mid = a + (b - a) / 2;
  kd_select(idx, pts, ax, a, b, mid);
  kd_build(S, idx, pts, h, 2 * i + 1, a, mid);
  kd_build(S, idx, pts, h, 2 * i + 2, mid, b);
}

static double box_dist(const kd_node *n, const double *x) {
  double s = 0;
  for (int k = 0; k < 3; k++) {
    double d = x[k] < n->lo[k] ? n->lo[k] - x[k] : x[k] > n->hi[k] ? x[k] - n->hi[k] : 0;
    s += d * d;
  }
  return sqrt(s);
}

static void kd_query(const size_field *S, int64_t i, const double *x, double *best) {
  const kd_node *n = &S->nd[i];
  if (n->hmin + S->slope * box_dist(n, x) >= *best) return;
  int64_t l = 2 * i + 1, r = 2 * i + 2;
  if (n->b - n->a <= KD_LEAF || r >= S->nnodes) {
    for (int32_t j = n->a; j < n->b; j++) {
      double v = S->h[j] + S->slope * vm_dist3(S->p + 3 * j, x);
      if (v < *best) *best = v;
    }
    return;
  }
  double dl = S->nd[l].hmin + S->slope * box_dist(&S->nd[l], x);
  double dr = S->nd[r].hmin + S->slope * box_dist(&S->nd[r], x);
  if (dl <= dr) {
    kd_query(S, l, x, best);
    kd_query(S, r, x, best);
  } else {
    kd_query(S, r, x, best);
    kd_query(S, l, x, best);
  }
}

static double size_at(const size_field *S, const double *x) {
  double best = S->hmax;
  kd_query(S, 0, x, &best);
  const vm_fill_opts *o = S->o;
  if (o->refine_size > 0 && best > o->refine_size && x[0] >= o->refine_lo[0] &&
      x[0] <= o->refine_hi[0] && x[1] >= o->refine_lo[1] && x[1] <= o->refine_hi[1] &&
      x[2] >= o->refine_lo[2] && x[2] <= o->refine_hi[2])
    best = o->refine_size;
  return best;
}

/* Nonzero if a point of S within r of x (other than `self`) is marked. */
static int kd_any_marked(const size_field *S, int64_t i, const double *x, double r,
                         const uint8_t *mark, int32_t self) {
  const kd_node *n = &S->nd[i];
  if (n->b <= n->a || box_dist(n, x) > r) return 0;
  if (n->b - n->a <= KD_LEAF || 2 * i + 2 >= S->nnodes) {
    for (int32_t j = n->a; j < n->b; j++)
      if (S->id[j] != self && mark[S->id[j]] && vm_dist3(S->p + 3 * j, x) <= r) return 1;
    return 0;
  }
  return kd_any_marked(S, 2 * i + 1, x, r, mark, self) ||
         kd_any_marked(S, 2 * i + 2, x, r, mark, self);
}

static double gmsh_size_cb(int dim, int tag, double x, double y, double z, void *data) {
  (void)dim;
  (void)tag;
  double p[3] = {x, y, z};
  return size_at(data, p);
}

static void size_free(vm_ctx *ctx, size_field *S) {
  vm_free(ctx, S->p);
  vm_free(ctx, S->h);
  vm_free(ctx, S->nd);
  vm_free(ctx, S->id);
}

/* pts: 3*n coordinates, h: n sizes. */
static int size_build(vm_ctx *ctx, size_field *S, const double *pts, const double *h, int64_t n) {
  S->n = n;
  S->nnodes = 1;
  while (S->nnodes * KD_LEAF < 2 * n) S->nnodes *= 2;
  S->nnodes = 2 * S->nnodes - 1;
  S->p = vm_alloc_array(ctx, (size_t)(3 * n), sizeof *S->p);
  S->h = vm_alloc_array(ctx, (size_t)n, sizeof *S->h);
  S->nd = vm_calloc(ctx, (size_t)S->nnodes, sizeof *S->nd);
  int32_t *idx = vm_alloc_array(ctx, (size_t)n, sizeof *idx);
  if (!S->p || !S->h || !S->nd || !idx) {
    vm_free(ctx, idx);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < n; i++) idx[i] = (int32_t)i;
  kd_build(S, idx, pts, h, 0, 0, (int32_t)n);
  for (int64_t i = 0; i < n; i++) {
    memcpy(S->p + 3 * i, pts + 3 * idx[i], 3 * sizeof(double));
    S->h[i] = h[idx[i]];
  }
  S->id = idx;
  return VM_OK;
}

/* ---------- the envelope ---------- */

typedef struct {
  int64_t nf;
  int32_t *fv;    /* 3 per face, oriented away from the layer (into the fill) */
  int32_t *felem; /* the face's element in the input (an "outer" triangle), or -1 */
  int surface;    /* the input is a surface: its triangles */
} envelope;

static void envelope_free(vm_ctx *ctx, envelope *E) {
  vm_free(ctx, E->fv);
  vm_free(ctx, E->felem);
}

/* The tag named `name` by "gmsh:physical_name:2:<tag>", or -1. */
static int32_t tag_named(const vm_mesh *m, const char *name) {
  for (int i = 0; i < m->nattr; i++) {
    const char *k = m->attrs[i].key;
    if (!strncmp(k, "gmsh:physical_name:2:", 21) && !strcmp(m->attrs[i].value, name))
      return (int32_t)atol(k + 21);
  }
  return -1;
}

static int find_envelope(vm_ctx *ctx, const vm_mesh *m, envelope *E) {
  memset(E, 0, sizeof *E);
  int64_t counts[VM_NTYPES];
  int top = vm_mesh_count_types(m, counts);
  if (top == 2) {
    if (counts[VM_QUAD])
      return vm_error(ctx, VM_ERR_ARG,
                      "the surface has %lld quadrilaterals: the fill needs a triangulated "
                      "envelope",
                      (long long)counts[VM_QUAD]);
    E->surface = 1;
    E->nf = counts[VM_TRI];
    E->fv = vm_alloc_array(ctx, (size_t)(3 * E->nf + 1), sizeof *E->fv);
    E->felem = vm_alloc_array(ctx, (size_t)(E->nf + 1), sizeof *E->felem);
    if (!E->fv || !E->felem) return VM_ERR_NOMEM;
    int64_t k = 0;
    for (int64_t e = 0; e < m->ne; e++) {
      if (m->etype[e] != VM_TRI) continue;
      memcpy(E->fv + 3 * k, m->conn + m->eoff[e], 3 * sizeof(int32_t));
      E->felem[k++] = (int32_t)e;
    }
    return VM_OK;
  }
  if (top != 3)
    return vm_error(ctx, VM_ERR_ARG, "the mesh has no cells and no surface to fill around");
  /* the boundary of the cells, oriented outward */
  int64_t nb;
  int32_t *bfv = NULL;
  uint8_t *bnv = NULL;
  int st = vm_mesh_boundary(m, &nb, &bfv, &bnv, NULL, NULL);
  if (st) return st;
  /* the faces named "outer", matched to the boundary by vertex set */
  const vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  int32_t outer = ph && ph->type == VM_FIELD_I32 && ph->ncomp == 1 ? tag_named(m, "outer") : -1;
  uint8_t *pick = vm_calloc(ctx, (size_t)(nb + 1), 1);
  tface *bf = vm_alloc_array(ctx, (size_t)(nb + 1), sizeof *bf);
  int32_t *fel = vm_alloc_array(ctx, (size_t)(nb + 1), sizeof *fel);
  if (!pick || !bf || !fel) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t nq = 0;
  for (int64_t f = 0; f < nb; f++) {
    if (bnv[f] != 3) {
      bf[f].v[0] = bf[f].v[1] = bf[f].v[2] = -1;
    } else {
      memcpy(bf[f].v, bfv + 4 * f, sizeof bf[f].v);
      fill_sort3(bf[f].v);
    }
    bf[f].cell = (int32_t)f;
  }
  qsort(bf, (size_t)nb, sizeof *bf, cmp_tface);
  for (int64_t f = 0; f < nb; f++) fel[f] = -1;
  int64_t npick = 0;
  if (outer >= 0) {
    const int32_t *tag = ph->data;
    for (int64_t e = 0; e < m->ne; e++) {
      if (vm_elem_dim(m->etype[e]) != 2 || tag[e] != outer) continue;
      if (m->etype[e] == VM_QUAD) {
        nq++;
        continue;
      }
      int64_t i = find_face(bf, nb, m->conn + m->eoff[e]);
      if (i >= 0) {
        int32_t f = bf[i].cell;
        if (!pick[f]) npick++;
        pick[f] = 1;
        fel[f] = (int32_t)e; /* the face's own element: interior after the fill */
      } else {
        st = vm_error(ctx, VM_ERR_FORMAT,
                      "element %lld: a triangle named 'outer' that is not a boundary face of "
                      "the cells",
                      (long long)e);
        goto done;
      }
    }
    if (nq) {
      st = vm_error(ctx, VM_ERR_ARG,
                    "the envelope ('outer') has %lld quadrilaterals: the fill needs triangles "
                    "(a prism layer's top)",
                    (long long)nq);
      goto done;
    }
  }
  if (!npick) {
    /* no "outer" faces: the boundary component reaching farthest out */
    int32_t *comp = vm_alloc_array(ctx, (size_t)(m->nv + 1), sizeof *comp);
    if (!comp) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    /* union-find over the vertices of boundary faces */
    for (int64_t v = 0; v < m->nv; v++) comp[v] = (int32_t)v;
    for (int64_t f = 0; f < nb; f++)
      for (int i = 1; i < bnv[f]; i++) {
        int32_t a = bfv[4 * f], b = bfv[4 * f + i];
        while (comp[a] != a) a = comp[a] = comp[comp[a]];
        while (comp[b] != b) b = comp[b] = comp[comp[b]];
        if (a != b) comp[a > b ? a : b] = a < b ? a : b;
      }
    /* the component holding the vertex of largest x (ties: smallest index) */
    int32_t far = -1;
    for (int64_t f = 0; f < nb; f++)
      for (int i = 0; i < bnv[f]; i++) {
        int32_t v = bfv[4 * f + i];
        if (far < 0 || m->xyz[3 * v] > m->xyz[3 * far]) far = v;
      }
    int32_t root = far;
    while (comp[root] != root) root = comp[root];
    for (int64_t f = 0; f < nb; f++) {
      int32_t a = bfv[4 * f];
      while (comp[a] != a) a = comp[a];
      if (a != root) continue;
      if (bnv[f] != 3) nq++;
      pick[f] = 1;
      npick++;
    }
    vm_free(ctx, comp);
    if (nq) {
      st = vm_error(ctx, VM_ERR_ARG,
                    "the outer boundary has %lld quadrilaterals: the fill needs triangles "
                    "(name the envelope 'outer')",
                    (long long)nq);
      goto done;
    }
    if (npick == nb) {
      st = vm_error(ctx, VM_ERR_ARG,
                    "the cells have one boundary only: no inner wall and outer envelope "
                    "(a layer around a wall, or a closed surface, is needed)");
      goto done;
    }
  }
  E->nf = npick;
  E->fv = vm_alloc_array(ctx, (size_t)(3 * npick), sizeof *E->fv);
  E->felem = vm_alloc_array(ctx, (size_t)npick, sizeof *E->felem);
  if (!E->fv || !E->felem) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t k = 0;
  for (int64_t f = 0; f < nb; f++) {
    if (!pick[f]) continue;
    memcpy(E->fv + 3 * k, bfv + 4 * f, 3 * sizeof(int32_t));
    E->felem[k++] = fel[f];
  }
done:
  vm_free(ctx, pick);
  vm_free(ctx, fel);
  vm_free(ctx, bf);
  vm_free(ctx, bfv);
  vm_free(ctx, bnv);
  return st;
}

/* A half model's symmetry plane x[ax] = c, the layer on the side `side`
 * (+1 or -1) of it; ax -1: a closed envelope. */
typedef struct {
  int ax;
  double c, side;
} sym_plane;

/* The envelope must be a closed, manifold triangulation: every edge on
 * exactly two of its triangles; or a half model's, whose edges on one
 * triangle (its border, returned in *bed as nb pairs a -> b, in their
 * triangle's order) all lie in the symmetry plane (the input's attribute
 * VM_SYMMETRY_PLANE_ATTR, "y=0", or the plane x, y or z = const they all
 * lie in, bit for bit): *sp, the layer on one side of it. */
static int check_closed(vm_ctx *ctx, const vm_mesh *m, const envelope *E, sym_plane *sp,
                        int32_t **bed, int64_t *nb) {
  sp->ax = -1;
  sp->c = 0;
  sp->side = 1;
  *bed = NULL;
  *nb = 0;
  int64_t ne = 3 * E->nf;
  tface *ed = vm_alloc_array(ctx, (size_t)(ne + 1), sizeof *ed);
  if (!ed) return VM_ERR_NOMEM;
  for (int64_t f = 0; f < E->nf; f++)
    for (int i = 0; i < 3; i++) {
      int32_t a = E->fv[3 * f + i], b = E->fv[3 * f + (i + 1) % 3];
      tface *t = &ed[3 * f + i];
      t->v[0] = a < b ? a : b;
      t->v[1] = a < b ? b : a;
      t->v[2] = 0;
      t->cell = (int32_t)(3 * f + i);
    }
  qsort(ed, (size_t)ne, sizeof *ed, cmp_tface);
  int64_t bad = 0, open = 0;
  int32_t fa = -1, fb = -1;
  for (int64_t i = 0; i < ne;) {
    int64_t j = i + 1;
    while (j < ne && fill_same_face(&ed[i], &ed[j])) j++;
    if (j - i == 1 && !E->surface) {
      ed[open++].cell = ed[i].cell; /* (open <= i: the border's corners, in order) */
    } else if (j - i != 2) {
      if (!bad++) fa = ed[i].v[0], fb = ed[i].v[1];
    }
    i = j;
  }
  int st = VM_OK;
  if (bad) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "the envelope is not closed: %lld edges are on %s (the first: vertices %d and "
                  "%d)",
                  (long long)bad,
                  E->surface ? "one triangle or on more than two" : "more than two triangles",
                  (int)fa, (int)fb);
    goto done;
  }
  if (!open) goto done;
  /* a half model: its border edges, in their triangles' order */
  int32_t *b = vm_alloc_array(ctx, (size_t)(2 * open), sizeof *b);
  if (!b) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t k = 0; k < open; k++) {
    int32_t c = ed[k].cell;
    b[2 * k] = E->fv[c];
    b[2 * k + 1] = E->fv[3 * (c / 3) + (c % 3 + 1) % 3];
  }
  const char *axn = "xyz";
  if (vm_mesh_get_symmetry_plane(m, &sp->ax, &sp->c) <= 0) {
    vm_ctx_clear_error(ctx);
    sp->ax = -1;
  }
  for (int x = 0; x < 3 && sp->ax < 0; x++) {
    int all = 1;
    for (int64_t k = 0; k < 2 * open && all; k++)
      all = m->xyz[3 * b[k] + x] == m->xyz[3 * b[0] + x];
    if (all) {
      sp->ax = x;
      sp->c = m->xyz[3 * b[0] + x];
    }
  }
  if (sp->ax < 0) {
    const double *x = m->xyz + 3 * b[0];
    st = vm_error(ctx, VM_ERR_ARG,
                  "the envelope is not closed (%lld edges on one triangle) and its border is not "
                  "in a plane x, y or z = const, as a half model's (e.g. the vertex %d at %g %g "
                  "%g)",
                  (long long)open, (int)b[0], x[0], x[1], x[2]);
    vm_free(ctx, b);
    goto done;
  }
  for (int64_t k = 0; k < 2 * open; k++) {
    const double *x = m->xyz + 3 * b[k];
    if (x[sp->ax] == sp->c) continue;
    st = vm_error(ctx, VM_ERR_ARG,
                  "the envelope's border is not on the symmetry plane %c = %g: its vertex %d "
                  "at %g %g %g is %g off it",
                  axn[sp->ax], sp->c, (int)b[k], x[0], x[1], x[2], fabs(x[sp->ax] - sp->c));
    vm_free(ctx, b);
    goto done;
  }
  /* the side: the farthest envelope vertex's; none beyond the plane */
  int64_t far = -1;
  double dmax = 0;
  for (int64_t i = 0; i < ne; i++) {
    double d = fabs(m->xyz[3 * E->fv[i] + sp->ax] - sp->c);
    if (d > dmax) dmax = d, far = E->fv[i];
  }
  sp->side = far >= 0 && m->xyz[3 * far + sp->ax] < sp->c ? -1 : 1;
  for (int64_t i = 0; i < ne; i++) {
    const double *x = m->xyz + 3 * E->fv[i];
    if ((x[sp->ax] - sp->c) * sp->side >= 0) continue;
    st = vm_error(ctx, VM_ERR_ARG,
                  "the envelope crosses its symmetry plane %c = %g at its vertex %d (%g %g %g)",
                  axn[sp->ax], sp->c, (int)E->fv[i], x[0], x[1], x[2]);
    vm_free(ctx, b);
    goto done;
  }
  *bed = b;
  *nb = open;
done:
  vm_free(ctx, ed);
  return st;
}

/* ---------- the far field ---------- */

typedef struct {
  int64_t nv, nf;
  double *xyz;
  int32_t *fv; /* 3 per triangle, outward (away from the fill): >= 0 a local vertex, < 0
                  the input's vertex -1 - fv (a half model's envelope border) */
  /* a half model: the far field is the half on the layer's side of the
   * symmetry plane, closed by the plane's own triangles (the last nsym);
   * rim: its 4 n vertices in the plane, in order around */
  int64_t nsym, nrim;
  int32_t *rim;
} far_surface;

/* The output vertex of far-field corner value i (base: the input's vertex
 * count). */
static inline int64_t far_vertex(int32_t i, int64_t base) {
  return i >= 0 ? base + i : -1 - (int64_t)i;
}

static void far_free(vm_ctx *ctx, far_surface *F) {
  vm_free(ctx, F->xyz);
  vm_free(ctx, F->fv);
  vm_free(ctx, F->rim);
}

/* A cube of half-width H about c, n x n quads per side, each split in two
 * triangles along alternating diagonals; or the sphere of radius H, the
 * same cube's vertices projected onto it (a cube-sphere). */
static int far_build(vm_ctx *ctx, far_surface *F, const double c[3], double H, int n, int sphere,
                     const sym_plane *sp) {
  /* a (n+1)^3 lattice's surface vertices, numbered through a lattice index;
   * a half model's (n even, c in the plane) only those on the layer's
   * side of the plane (g[ax] = n / 2 is in it, exactly) */
  int64_t N = n + 1, h = n / 2;
  int hax = sp->ax;
  int32_t *id = vm_alloc_array(ctx, (size_t)(N * N * N), sizeof *id);
  if (!id) return VM_ERR_NOMEM;
  int64_t nv = 0;
#define FAR_KEEP(g) (hax < 0 || (sp->side > 0 ? (g)[hax] >= h : (g)[hax] <= h))
  for (int64_t i = 0; i < N * N * N; i++) {
    int64_t g[3] = {i % N, (i / N) % N, i / (N * N)};
    int on = g[0] == 0 || g[1] == 0 || g[2] == 0 || g[0] == n || g[1] == n || g[2] == n;
    id[i] = on && FAR_KEEP(g) ? (int32_t)nv++ : -1;
  }
  F->nv = nv;
  F->nf = (hax < 0 ? 12 : 8) * (int64_t)n * n;
  F->xyz = vm_alloc_array(ctx, (size_t)(3 * nv), sizeof *F->xyz);
  F->fv = vm_alloc_array(ctx, (size_t)(3 * F->nf), sizeof *F->fv);
  if (!F->xyz || !F->fv) {
    vm_free(ctx, id);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < N * N * N; i++) {
    if (id[i] < 0) continue;
    double q[3] = {(double)(i % N), (double)((i / N) % N), (double)(i / (N * N))};
    for (int k = 0; k < 3; k++) q[k] = 2 * q[k] / n - 1;
    if (sphere) {
      /* equal-angle cube-sphere: tan of the face angle, then onto the sphere */
      double t[3];
      for (int k = 0; k < 3; k++) t[k] = tan(q[k] * PI / 4);
      double r = vm_norm3(t);
      for (int k = 0; k < 3; k++) q[k] = t[k] / r;
    }
    for (int k = 0; k < 3; k++) F->xyz[3 * id[i] + k] = c[k] + H * q[k];
  }
  int64_t f = 0;
  for (int ax = 0; ax < 3; ax++)
    for (int side = 0; side < 2; side++) {
      int a1 = (ax + 1) % 3, a2 = (ax + 2) % 3;
      if (ax == hax && (side ? -1 : 1) == sp->side) continue; /* the mirror image's side */
      for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
          int32_t v[4];
          int64_t gc[3]; /* the quad's lower corner */
          gc[ax] = side ? n : 0;
          gc[a1] = i;
          gc[a2] = j;
          if (hax >= 0 && hax != ax && (sp->side > 0 ? gc[hax] < h : gc[hax] >= h)) continue;
          for (int k = 0; k < 4; k++) {
            int64_t g[3];
            g[ax] = side ? n : 0;
            g[a1] = i + (k == 1 || k == 2);
            g[a2] = j + (k >= 2);
            v[k] = id[g[0] + N * g[1] + N * N * g[2]];
          }
          /* (a1, a2) is right-handed about +ax: outward on the + side */
          if (!side) {
            int32_t t = v[1];
            v[1] = v[3];
            v[3] = t;
          }
          int diag = (i + j) % 2;
          int32_t t1[3] = {v[0], v[1], v[2]}, t2[3] = {v[0], v[2], v[3]};
          if (diag) {
            t1[2] = v[3];
            t2[0] = v[1];
          }
          memcpy(F->fv + 3 * f++, t1, sizeof t1);
          memcpy(F->fv + 3 * f++, t2, sizeof t2);
        }
    }
  F->nf = f;
  if (hax >= 0) {
    /* the rim: the lattice's vertices in the plane on the box's edges, in
     * order around (a1 up, a2 up, a1 down, a2 down) */
    int a1 = (hax + 1) % 3, a2 = (hax + 2) % 3;
    F->nrim = 4 * (int64_t)n;
    F->rim = vm_alloc_array(ctx, (size_t)F->nrim, sizeof *F->rim);
    if (!F->rim) {
      vm_free(ctx, id);
      return VM_ERR_NOMEM;
    }
    int64_t r = 0;
    for (int leg = 0; leg < 4; leg++)
      for (int64_t t = 0; t < n; t++) {
        int64_t g[3];
        g[hax] = h;
        g[a1] = leg == 0 ? t : leg == 1 ? n : leg == 2 ? n - t : 0;
        g[a2] = leg == 0 ? 0 : leg == 1 ? t : leg == 2 ? n : n - t;
        F->rim[r++] = id[g[0] + N * g[1] + N * N * g[2]];
      }
  }
#undef FAR_KEEP
  vm_free(ctx, id);
  return VM_OK;
}

/* ---------- a half model's symmetry plane ---------- */

static int gmsh_status(vm_ctx *ctx, int ierr, const char *what);

/* The far field's triangles in the symmetry plane, appended to F: the
 * region between the far field's rim (F->rim) and the envelope's border
 * loops (bed: nb edges a -> b), meshed by Gmsh in 2D with the size field
 * S; every border edge and every rim edge kept whole (its two vertices,
 * no point between), the new vertices appended to F's, the triangles
 * facing out of the fill (to the mirror image's side). */
static int sym_face(vm_ctx *ctx, const vm_mesh *m, const int32_t *bed, int64_t nb,
                    const sym_plane *sp, size_field *S, far_surface *F) {
  int st = VM_OK, ierr = 0;
  /* the border's loops: next[a] = b, each border vertex once in and out */
  int32_t *next = vm_alloc_array(ctx, (size_t)m->nv + 1, sizeof *next);
  uint8_t *seen = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  int *ptag = vm_alloc_array(ctx, (size_t)(nb + F->nrim) + 1, sizeof *ptag);
  int32_t *pref = vm_alloc_array(ctx, (size_t)(nb + F->nrim) + 1, sizeof *pref);
  int *ltag = vm_alloc_array(ctx, (size_t)(nb + F->nrim) + 1, sizeof *ltag);
  int *loops = vm_alloc_array(ctx, (size_t)nb + 2, sizeof *loops);
  size_t *ntag = NULL, *etag = NULL, *enode = NULL, nn = 0, ncoord = 0, npc = 0, ne = 0, nen = 0;
  double *coord = NULL, *pc = NULL;
  int gmsh_up = 0;
  if (!next || !seen || !ptag || !pref || !ltag || !loops) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t v = 0; v < m->nv; v++) next[v] = -1;
  for (int64_t k = 0; k < nb; k++) {
    int32_t a = bed[2 * k], b = bed[2 * k + 1];
    if (next[a] >= 0 || seen[b]) {
      const double *x = m->xyz + 3 * (next[a] >= 0 ? a : b);
      st = vm_error(ctx, VM_ERR_ARG,
                    "the envelope's border in the symmetry plane is not a set of simple loops "
                    "(at %g %g %g)",
                    x[0], x[1], x[2]);
      goto done;
    }
    next[a] = b;
    seen[b] = 1;
  }
  gmshInitialize(0, NULL, 0, &ierr);
  if (ierr) {
    st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh could not be initialized");
    goto done;
  }
  gmsh_up = 1;
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshOptionSetNumber("General.Verbosity", 2, &ierr);
  gmshModelAdd("varmesh-symmetry", &ierr);
  int64_t np = 0, nl = 0, nloop = 0;
  /* the rim, then each border loop: points, segments, a curve loop */
  for (int64_t i = 0; i < F->nrim && !ierr; i++) {
    const double *x = F->xyz + 3 * F->rim[i];
    pref[np] = F->rim[i];
    ptag[np++] = gmshModelGeoAddPoint(x[0], x[1], x[2], 0, -1, &ierr);
  }
  for (int64_t i = 0; i < F->nrim && !ierr; i++)
    ltag[nl++] = gmshModelGeoAddLine(ptag[i], ptag[(i + 1) % F->nrim], -1, &ierr);
  if (!ierr) loops[nloop++] = gmshModelGeoAddCurveLoop(ltag, (size_t)F->nrim, -1, 1, &ierr);
  memset(seen, 0, (size_t)m->nv + 1);
  for (int64_t k = 0; k < nb && !ierr; k++) {
    int32_t a0 = bed[2 * k];
    if (seen[a0]) continue;
    int64_t p0 = np, l0 = nl;
    for (int32_t a = a0; !seen[a] && !ierr; a = next[a]) {
      if (next[a] < 0) {
        const double *x = m->xyz + 3 * a;
        st = vm_error(ctx, VM_ERR_ARG,
                      "the envelope's border in the symmetry plane does not close (at %g %g %g)",
                      x[0], x[1], x[2]);
        goto done;
      }
      seen[a] = 1;
      pref[np] = -1 - a;
      ptag[np++] =
          gmshModelGeoAddPoint(m->xyz[3 * a], m->xyz[3 * a + 1], m->xyz[3 * a + 2], 0, -1, &ierr);
    }
    for (int64_t i = p0; i < np && !ierr; i++)
      ltag[nl++] = gmshModelGeoAddLine(ptag[i], ptag[i + 1 < np ? i + 1 : p0], -1, &ierr);
    if (!ierr)
      loops[nloop++] = gmshModelGeoAddCurveLoop(ltag + l0, (size_t)(nl - l0), -1, 1, &ierr);
  }
  int surf = 0;
  if (!ierr) surf = gmshModelGeoAddPlaneSurface(loops, (size_t)nloop, -1, &ierr);
  for (int64_t i = 0; i < nl && !ierr; i++)
    gmshModelGeoMeshSetTransfiniteCurve(ltag[i], 2, "Progression", 1.0, &ierr);
  if (!ierr) gmshModelGeoSynchronize(&ierr);
  if ((st = gmsh_status(ctx, ierr, "setting up the symmetry plane"))) goto done;
  gmshOptionSetNumber("Mesh.MeshSizeExtendFromBoundary", 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromPoints", 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 0, &ierr);
  gmshModelMeshSetSizeCallback(gmsh_size_cb, S, &ierr);
  gmshModelMeshGenerate(2, &ierr);
  if ((st = gmsh_status(
           ctx, ierr, "meshing the symmetry plane (does the layer's border in it cross itself?)")))
    goto done;
  /* no node on a segment: every border and rim edge kept whole */
  gmshModelMeshGetNodes(&ntag, &nn, &coord, &ncoord, &pc, &npc, 1, -1, 0, 0, &ierr);
  if (!ierr && nn) {
    st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh split %zu edges of the symmetry plane's border", nn);
    goto done;
  }
  gmshFree(ntag), gmshFree(coord), gmshFree(pc);
  ntag = NULL, coord = pc = NULL;
  /* node tag -> vertex: the points', then the surface's own */
  size_t maxtag = 0;
  gmshModelMeshGetNodes(&ntag, &nn, &coord, &ncoord, &pc, &npc, 2, surf, 1, 0, &ierr);
  if ((st = gmsh_status(ctx, ierr, "returning the symmetry plane's mesh"))) goto done;
  for (size_t i = 0; i < nn; i++) maxtag = ntag[i] > maxtag ? ntag[i] : maxtag;
  int64_t *map = vm_alloc_array(ctx, maxtag + 1, sizeof *map);
  if (!map) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (size_t t = 0; t <= maxtag; t++) map[t] = INT64_MIN;
  for (int64_t i = 0; i < np && !ierr; i++) {
    size_t *pt = NULL, pn = 0, pnc = 0, ppn = 0;
    double *pcoord = NULL, *ppc = NULL;
    gmshModelMeshGetNodes(&pt, &pn, &pcoord, &pnc, &ppc, &ppn, 0, ptag[i], 0, 0, &ierr);
    if (!ierr && pn == 1 && pt[0] <= maxtag) {
      const double *x = pref[i] >= 0 ? F->xyz + 3 * pref[i] : m->xyz + 3 * (-1 - (int64_t)pref[i]);
      if (memcmp(pcoord, x, 3 * sizeof *x)) ierr = -1;
      map[pt[0]] = pref[i];
    } else if (!ierr) {
      ierr = -1;
    }
    gmshFree(pt), gmshFree(pcoord), gmshFree(ppc);
  }
  int64_t nnew = 0;
  for (size_t i = 0; i < nn && !ierr; i++)
    if (map[ntag[i]] == INT64_MIN) nnew++;
  double *xyz = ierr ? NULL : vm_realloc(ctx, F->xyz, (size_t)(3 * (F->nv + nnew)) * sizeof *xyz);
  if (!xyz) {
    vm_free(ctx, map);
    st = ierr ? vm_error(ctx, VM_ERR_BACKEND, "Gmsh moved a point of the symmetry plane's border")
              : VM_ERR_NOMEM;
    goto done;
  }
  F->xyz = xyz;
  for (size_t i = 0; i < nn; i++) {
    if (map[ntag[i]] != INT64_MIN) continue;
    memcpy(F->xyz + 3 * F->nv, coord + 3 * i, 3 * sizeof *coord);
    F->xyz[3 * F->nv + sp->ax] = sp->c; /* in the plane, bit for bit */
    map[ntag[i]] = F->nv++;
  }
  gmshModelMeshGetElementsByType(2, &etag, &ne, &enode, &nen, surf, 0, 1, &ierr);
  int32_t *fv =
      ierr ? NULL : vm_realloc(ctx, F->fv, (size_t)(3 * (F->nf + (int64_t)ne)) * sizeof *fv);
  if (!fv) {
    vm_free(ctx, map);
    st = ierr ? gmsh_status(ctx, ierr, "returning the symmetry plane's triangles") : VM_ERR_NOMEM;
    goto done;
  }
  F->fv = fv;
  int a1 = (sp->ax + 1) % 3, a2 = (sp->ax + 2) % 3;
  for (size_t t = 0; t < ne; t++) {
    int32_t *c = F->fv + 3 * (F->nf + (int64_t)t);
    const double *x[3];
    for (int i = 0; i < 3; i++) {
      size_t g = enode[3 * t + i];
      int64_t v = g <= maxtag ? map[g] : INT64_MIN;
      if (v == INT64_MIN) {
        vm_free(ctx, map);
        st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh's symmetry-plane triangle names node %zu", g);
        goto done;
      }
      c[i] = (int32_t)v;
      x[i] = v >= 0 ? F->xyz + 3 * v : m->xyz + 3 * (-1 - v);
    }
    /* facing out of the fill: its area vector against the layer's side */
    double a = (x[1][a1] - x[0][a1]) * (x[2][a2] - x[0][a2]) -
               (x[1][a2] - x[0][a2]) * (x[2][a1] - x[0][a1]);
    if (a * sp->side > 0) {
      int32_t s1 = c[1];
      c[1] = c[2];
      c[2] = s1;
    }
  }
  F->nf += (int64_t)ne;
  F->nsym = (int64_t)ne;
  vm_free(ctx, map);
done:
  gmshFree(ntag), gmshFree(coord), gmshFree(pc), gmshFree(etag), gmshFree(enode);
  if (gmsh_up) gmshFinalize(&ierr);
  vm_free(ctx, next);
  vm_free(ctx, seen);
  vm_free(ctx, ptag);
  vm_free(ctx, pref);
  vm_free(ctx, ltag);
  vm_free(ctx, loops);
  return st;
}

/* ---------- points off the envelope ---------- */

/* Points about one tet height off the envelope along its vertex normals,
 * where the envelope is smooth and nothing else is near: Gmsh's boundary
 * recovery then finds a vertex above each face instead of making flat tets
 * of four envelope vertices (in concave regions, it did). env: the
 * envelope's vertices (tree with h = 0), vid: input vertex -> point index,
 * hs: sizes by point index. Returns the points in *q (3 each). */
static int offset_points(vm_ctx *ctx, const vm_mesh *m, const envelope *E, const int32_t *vid,
                         const double *hs, int64_t nenv, double *nrm, double **q, int64_t *nq) {
  int st = VM_OK;
  *q = NULL;
  *nq = 0;
  double *dmin = vm_alloc_array(ctx, (size_t)nenv + 1, sizeof *dmin);
  double *cand = vm_alloc_array(ctx, (size_t)(3 * nenv + 3), sizeof *cand);
  double *zero = vm_calloc(ctx, (size_t)nenv + 1, sizeof *zero);
  double *pts = vm_alloc_array(ctx, (size_t)(3 * nenv + 3), sizeof *pts);
  uint8_t *ok = vm_calloc(ctx, (size_t)nenv + 1, 1), *acc = vm_calloc(ctx, (size_t)nenv + 1, 1);
  size_field T, C;
  memset(&T, 0, sizeof T);
  memset(&C, 0, sizeof C);
  if (!dmin || !cand || !zero || !pts || !ok || !acc) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  /* a closed surface given as input: its normals point out if it encloses
   * a positive volume, and the fill is outside */
  double vol = 0;
  for (int64_t f = 0; f < E->nf; f++) {
    const double *a = m->xyz + 3 * E->fv[3 * f], *b = m->xyz + 3 * E->fv[3 * f + 1],
                 *c = m->xyz + 3 * E->fv[3 * f + 2];
    double x[3];
    vm_cross3(b, c, x);
    vol += vm_dot3(a, x) / 6;
  }
  double sgn = E->surface && vol < 0 ? -1 : 1;
  for (int64_t v = 0; v < m->nv; v++)
    if (vid[v] >= 0) memcpy(pts + 3 * vid[v], m->xyz + 3 * v, 3 * sizeof(double));
  for (int pass = 0; pass < 2; pass++)
    for (int64_t f = 0; f < E->nf; f++) {
      const int32_t *t = E->fv + 3 * f;
      double u[3], w[3], x[3];
      vm_sub3(m->xyz + 3 * t[1], m->xyz + 3 * t[0], u);
      vm_sub3(m->xyz + 3 * t[2], m->xyz + 3 * t[0], w);
      vm_cross3(u, w, x);
      for (int k = 0; k < 3; k++) x[k] *= sgn;
      for (int i = 0; i < 3; i++) {
        int32_t p = vid[t[i]];
        if (pass == 0) {
          for (int k = 0; k < 3; k++) nrm[3 * p + k] += x[k];
          dmin[p] = 1;
        } else {
          double l = vm_norm3(x), d = l > 0 ? vm_dot3(x, nrm + 3 * p) / l : -1;
          if (d < dmin[p]) dmin[p] = d;
        }
      }
      if (pass == 0 && f == E->nf - 1)
        for (int64_t p = 0; p < nenv; p++) vm_normalize3(nrm + 3 * p);
    }
  /* candidates where the envelope is smooth */
  for (int64_t p = 0; p < nenv; p++) {
    ok[p] = dmin[p] > 0.7;
    for (int k = 0; k < 3; k++)
      cand[3 * p + k] = pts[3 * p + k] + VM_FILL_OFF * hs[p] * nrm[3 * p + k];
  }
  /* ... whose nearest envelope vertex is their own */
  T.slope = 1;
  T.hmax = INFINITY;
  if ((st = size_build(ctx, &T, pts, zero, nenv))) goto done;
  for (int64_t p = 0; p < nenv; p++) {
    if (!ok[p]) continue;
    double best = INFINITY;
    kd_query(&T, 0, cand + 3 * p, &best);
    ok[p] = best >= 0.95 * VM_FILL_OFF * hs[p];
  }
  /* ... and no accepted one near (in vertex order: deterministic) */
  C.slope = 1;
  C.hmax = INFINITY;
  if ((st = size_build(ctx, &C, cand, zero, nenv))) goto done;
  int64_t n = 0;
  for (int64_t p = 0; p < nenv; p++) {
    if (!ok[p] || kd_any_marked(&C, 0, cand + 3 * p, 0.5 * hs[p], acc, (int32_t)p)) continue;
    acc[p] = 1;
    n++;
  }
  *q = vm_alloc_array(ctx, (size_t)(3 * n + 3), sizeof **q);
  if (!*q) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t p = 0; p < nenv; p++)
    if (acc[p]) memcpy(*q + 3 * (*nq)++, cand + 3 * p, 3 * sizeof(double));
done:
  size_free(ctx, &T);
  size_free(ctx, &C);
  vm_free(ctx, dmin);
  vm_free(ctx, cand);
  vm_free(ctx, zero);
  vm_free(ctx, pts);
  vm_free(ctx, ok);
  vm_free(ctx, acc);
  return st;
}

/* Meshing passes with points in the slivers, at most; a tet of four
 * envelope vertices is flat below this least dihedral angle (degrees) */
enum { FILL_SLIVER_PASSES = 4, FILL_FLAT_DEG = 5 };
/* Of those, the first ones mesh the whole region again with Gmsh (about
 * 6.5 s each on the demo aircraft); the later ones insert their points
 * locally (insert_points, 0.1 s). The last Gmsh pass made local: the
 * demo's fill 41-49 -> 39-43 s, a CAD wing's (test fill_slivers) 32 -> 28 s,
 * checkMesh's figures as before (flat tets of envelope vertices 2 -> 0
 * and 7 -> 5); the last two: 27-32 s and 21 s, but the wing's small
 * determinants 72 -> 105 and weights below 0.05 51 -> 99 */
enum { FILL_GMSH_PASSES = 3 };

typedef struct {
  int32_t v[4]; /* ascending */
} quad_key;

static int int32_cmp(const void *a, const void *b) {
  int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return x < y ? -1 : x > y;
}

static int quad_cmp(const void *a, const void *b) {
  const int32_t *x = ((const quad_key *)a)->v, *y = ((const quad_key *)b)->v;
  for (int i = 0; i < 4; i++)
    if (x[i] != y[i]) return x[i] < y[i] ? -1 : 1;
  return 0;
}

/* A tet of four envelope vertices is a sliver below this OpenFOAM cell
 * determinant too (twice checkMesh's limit: the tet's faces are all
 * internal once merged); the demo aircraft at 5 %: two tets of 10.3 and
 * 10.9 degrees, each on two envelope faces in a shallow concave crease,
 * at 5.6e-4 and 8.0e-4 */
#define FILL_SLIVER_DET 0.002

/* OpenFOAM's determinant of tet p over its four faces. */
static double tet_foam_det(const double *p[4]) {
  static const int fc[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  double s[4][3], y[9], c[3];
  for (int f = 0; f < 4; f++) {
    for (int i = 0; i < 3; i++) memcpy(y + 3 * i, p[fc[f][i]], 3 * sizeof *y);
    vm_foam_face(y, 3, c, s[f]);
  }
  return vm_foam_cell_determinant(4, (const double(*)[3])s);
}

/* Points that break Gmsh's slivers of four envelope vertices (flat tets in
 * slightly concave kinks of the envelope, which Delaunay keeps: no other
 * point is in their small circumsphere): one off the envelope above each,
 * inside that sphere. Appended to *q (3 each, *nq of them). The fill's
 * tets are elements e0.. of the merged mesh o (merge: the input's kept
 * elements come first: a layer's own tets, where its layers end, are not
 * the fill's). The slivers the passes before had a point for are sorted
 * in seen[0..*nseen): one that is still there gets none again (the same
 * point twice made Gmsh's Delaunay fail; *nrepeat counts them); this
 * pass's are added to seen. *nsliver: every sliver found. *src: each
 * point's sliver too: its four Gmsh node tags (input index + 1), 4 per
 * point in (*src)[4 * i..], for the local insertion (insert_points). */
static int sliver_points(vm_ctx *ctx, const vm_mesh *o, int64_t e0, int64_t nin, const int32_t *vid,
                         const double *nrm, double min_deg, double **q, int64_t *nq,
                         int64_t *nsliver, quad_key **seen, int64_t *nseen, int64_t *nrepeat,
                         size_t **src) {
  *nsliver = *nrepeat = 0;
  int64_t n = *nq, ns0 = *nseen;
  for (int64_t e = e0; e < o->ne; e++) {
    if (o->etype[e] != VM_TET) continue;
    const int32_t *c = o->conn + o->eoff[e];
    if (c[0] >= nin || c[1] >= nin || c[2] >= nin || c[3] >= nin) continue;
    const double *p[4] = {o->xyz + 3 * c[0], o->xyz + 3 * c[1], o->xyz + 3 * c[2],
                          o->xyz + 3 * c[3]};
    double lo, hi;
    tet_angles(p, &lo, &hi);
    if (lo * 180 / PI >= min_deg && tet_foam_det(p) >= FILL_SLIVER_DET) continue;
    (*nsliver)++;
    quad_key key;
    memcpy(key.v, c, sizeof key.v);
    qsort(key.v, 4, sizeof *key.v, int32_cmp);
    if (ns0 && bsearch(&key, *seen, (size_t)ns0, sizeof key, quad_cmp)) {
      (*nrepeat)++;
      continue;
    }
    quad_key *sk = vm_realloc(ctx, *seen, (size_t)(*nseen + 1) * sizeof *sk);
    if (!sk) return VM_ERR_NOMEM;
    *seen = sk;
    sk[(*nseen)++] = key;
    double g[3] = {0, 0, 0}, nv[3] = {0, 0, 0}, lmax = 0;
    for (int i = 0; i < 4; i++) {
      for (int k = 0; k < 3; k++) {
        g[k] += p[i][k] / 4;
        nv[k] += vid[c[i]] >= 0 ? nrm[3 * vid[c[i]] + k] : 0;
      }
      for (int j = i + 1; j < 4; j++) {
        double l = vm_dist3(p[i], p[j]);
        lmax = l > lmax ? l : lmax;
      }
    }
    if (!(vm_normalize3(nv) > 0)) continue;
    /* how far above the centroid the circumsphere reaches: the point goes
     * halfway there (Delaunay then cannot keep the sliver), at most a
     * quarter of its longest edge up */
    double a[3], b[3], cc[3], bc[3], ca[3], ab[3], up = 0.25 * lmax;
    for (int k = 0; k < 3; k++) {
      a[k] = p[1][k] - p[0][k];
      b[k] = p[2][k] - p[0][k];
      cc[k] = p[3][k] - p[0][k];
    }
    vm_cross3(b, cc, bc);
    vm_cross3(cc, a, ca);
    vm_cross3(a, b, ab);
    double den = 2 * vm_dot3(a, bc);
    if (den != 0) {
      double o[3], u[3], r2 = 0, uu = 0, un = 0;
      for (int k = 0; k < 3; k++) {
        o[k] = (vm_dot3(a, a) * bc[k] + vm_dot3(b, b) * ca[k] + vm_dot3(cc, cc) * ab[k]) / den;
        r2 += o[k] * o[k];
        u[k] = g[k] - (p[0][k] + o[k]);
        uu += u[k] * u[k];
        un += u[k] * nv[k];
      }
      double disc = un * un - uu + r2;
      if (isfinite(disc) && disc > 0) {
        double tp = -un + sqrt(disc);
        if (tp > 0 && 0.5 * tp < up) up = 0.5 * tp;
      }
    }
    double *t = vm_realloc(ctx, *q, (size_t)(3 * (n + 1)) * sizeof *t);
    if (!t) return VM_ERR_NOMEM;
    *q = t;
    for (int k = 0; k < 3; k++) t[3 * n + k] = g[k] + up * nv[k];
    size_t *sr = vm_realloc(ctx, *src, (size_t)(4 * (n + 1)) * sizeof *sr);
    if (!sr) return VM_ERR_NOMEM;
    *src = sr;
    for (int k = 0; k < 4; k++) sr[4 * n + k] = (size_t)c[k] + 1; /* Gmsh's tags */
    n++;
  }
  *nq = n;
  if (*nseen > 1) qsort(*seen, (size_t)*nseen, sizeof **seen, quad_cmp);
  return VM_OK;
}

/* ---------- Gmsh ---------- */

/* Gmsh's log lines to ours; its last error into the context. */
static int gmsh_status(vm_ctx *ctx, int ierr, const char *what) {
  char **log = NULL;
  size_t n = 0;
  int e2;
  gmshLoggerGet(&log, &n, &e2);
  for (size_t i = 0; i < n; i++) {
    if (!e2) vm_log(ctx, VM_LOG_DEBUG, "gmsh: %s", log[i]);
    gmshFree(log[i]);
  }
  gmshFree(log);
  if (!ierr) return VM_OK;
  char *last = NULL;
  gmshLoggerGetLastError(&last, &e2);
  int st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh failed %s: %s", what,
                    last && *last ? last : "(no message)");
  gmshFree(last);
  return st;
}

typedef struct {
  size_t nn;
  size_t *ntag;
  double *coord;
  size_t nt;
  size_t *tnode; /* 4 per tet */
} gmsh_result;

/* A copy of R in Gmsh's allocations (freed by gmsh_result_free). */
static int gmsh_result_copy(const gmsh_result *R, gmsh_result *C) {
  memset(C, 0, sizeof *C);
  C->ntag = gmshMalloc((R->nn + 1) * sizeof *C->ntag);
  C->coord = gmshMalloc((3 * R->nn + 1) * sizeof *C->coord);
  C->tnode = gmshMalloc((4 * R->nt + 1) * sizeof *C->tnode);
  if (!C->ntag || !C->coord || !C->tnode) {
    gmshFree(C->ntag);
    gmshFree(C->coord);
    gmshFree(C->tnode);
    memset(C, 0, sizeof *C);
    return VM_ERR_NOMEM;
  }
  C->nn = R->nn;
  C->nt = R->nt;
  memcpy(C->ntag, R->ntag, R->nn * sizeof *C->ntag);
  memcpy(C->coord, R->coord, 3 * R->nn * sizeof *C->coord);
  memcpy(C->tnode, R->tnode, 4 * R->nt * sizeof *C->tnode);
  return VM_OK;
}

static void gmsh_result_free(gmsh_result *R) {
  gmshFree(R->ntag);
  gmshFree(R->coord);
  gmshFree(R->tnode);
  memset(R, 0, sizeof *R);
}

/* ---------- edge removal on slivers of envelope vertices ---------- */

/* Rounds of edge removal at most, and the largest ring taken */
enum { FLIP_ROUNDS = 4, FLIP_RING_MAX = FILL_RING_MAX };

int fill_ring_cycle(int n, const int64_t (*pr)[2], int64_t *w) {
  uint8_t used[FILL_RING_MAX + 1] = {0};
  w[0] = pr[0][0];
  w[1] = pr[0][1];
  used[0] = 1;
  int len = 2;
  for (;;) {
    int64_t last = w[len - 1];
    int found = -1;
    for (int k = 0; k < n && found < 0; k++)
      if (!used[k] && (pr[k][0] == last || pr[k][1] == last)) found = k;
    if (found < 0) return 0;
    used[found] = 1;
    int64_t nx = pr[found][0] == last ? pr[found][1] : pr[found][0];
    if (nx == w[0]) return len == n;
    if (len == n) return 0;
    w[len++] = nx;
  }
}

/* (fill_private.h) */
int fill_polygon_triangulations(int n, int tri[][FILL_RING_MAX - 2][3]) {
  /* depth first over the choices: the pending edge (lo, hi) with the
   * least depth takes apex lo + 1 + choice[depth]; the choice vectors in
   * lexicographic order give every triangulation once */
  int cnt = 0, choice[FLIP_RING_MAX] = {0};
  for (;;) {
    int pend[FLIP_RING_MAX][2], np = 1, nt = 0, depth = 0, last_open = -1;
    int cur[FLIP_RING_MAX - 2][3];
    pend[0][0] = 0;
    pend[0][1] = n - 1;
    while (np > 0) {
      np--;
      int lo = pend[np][0], hi = pend[np][1];
      if (hi - lo < 2) continue;
      int opts = hi - lo - 1;
      if (choice[depth] + 1 < opts) last_open = depth;
      int m = lo + 1 + choice[depth++];
      cur[nt][0] = lo;
      cur[nt][1] = m;
      cur[nt][2] = hi;
      nt++;
      pend[np][0] = lo;
      pend[np++][1] = m;
      pend[np][0] = m;
      pend[np++][1] = hi;
    }
    memcpy(tri[cnt++], cur, sizeof cur);
    if (last_open < 0) break;
    choice[last_open]++;
    for (int k = last_open + 1; k < FLIP_RING_MAX; k++) choice[k] = 0;
  }
  return cnt;
}

/* Room in the list of new tets nw (4 tags each, *cap of them) for need. */
static int tets_room(vm_ctx *ctx, size_t **nw, size_t *cap, size_t need, size_t step) {
  if (need <= *cap) return VM_OK;
  size_t c = 2 * *cap + step;
  if (c < need) c = need;
  size_t *t = vm_realloc(ctx, *nw, 4 * c * sizeof *t);
  if (!t) return VM_ERR_NOMEM;
  *nw = t;
  *cap = c;
  return VM_OK;
}

/* R's tets 0..nt-1 not marked dead, then the nnew tets of nw. */
static int tets_replace(gmsh_result *R, size_t nt, const uint8_t *dead, const size_t *nw,
                        size_t nnew) {
  size_t keep = 0;
  for (size_t t = 0; t < nt; t++) keep += !dead[t];
  size_t *out = gmshMalloc(4 * (keep + nnew + 1) * sizeof *out);
  if (!out) return VM_ERR_NOMEM;
  size_t o = 0;
  for (size_t t = 0; t < nt; t++)
    if (!dead[t]) memcpy(out + 4 * o++, R->tnode + 4 * t, 4 * sizeof *out);
  if (nnew) memcpy(out + 4 * o, nw, 4 * nnew * sizeof *out);
  gmshFree(R->tnode);
  R->tnode = out;
  R->nt = keep + nnew;
  return VM_OK;
}

/* The orientation of R's tets (at: node index of each tag): the sign of
 * the first one's volume that is not 0. */
static double tets_sign(const gmsh_result *R, const int64_t *at) {
  for (size_t t = 0; t < R->nt; t++) {
    const size_t *c = R->tnode + 4 * t;
    double o = tet_vol(R->coord + 3 * at[c[0]], R->coord + 3 * at[c[1]], R->coord + 3 * at[c[2]],
                       R->coord + 3 * at[c[3]]);
    if (o != 0) return o > 0 ? 1 : -1;
  }
  return 0;
}

/* The largest node tag of R (*maxtag) and each tag's node index (*at,
 * -1 for none), after checking Gmsh's tags: at most 4 (nn + nbase) + 16
 * (nbase: the input's vertices, whose tags Gmsh keeps), and every tet's
 * known. */
static int tet_nodes(vm_ctx *ctx, const gmsh_result *R, size_t nbase, size_t *maxtag,
                     int64_t **at) {
  size_t mt = 0;
  *at = NULL;
  for (size_t i = 0; i < R->nn; i++)
    if (R->ntag[i] > mt) mt = R->ntag[i];
  if (mt > 4 * (R->nn + nbase) + 16)
    return vm_error(ctx, VM_ERR_BACKEND, "Gmsh returned node tags up to %zu for %zu nodes", mt,
                    R->nn);
  int64_t *a = vm_alloc_array(ctx, mt + 1, sizeof *a);
  if (!a) return VM_ERR_NOMEM;
  for (size_t t = 0; t <= mt; t++) a[t] = -1;
  for (size_t i = 0; i < R->nn; i++) a[R->ntag[i]] = (int64_t)i;
  for (size_t i = 0; i < 4 * R->nt; i++)
    if (R->tnode[i] > mt || a[R->tnode[i]] < 0) {
      vm_free(ctx, a);
      return vm_error(ctx, VM_ERR_BACKEND, "Gmsh returned a tet with an unknown node %zu",
                      R->tnode[i]);
    }
  *maxtag = mt;
  *at = a;
  return VM_OK;
}

/* The tets around each node tag t: adj[cnt[t]..cnt[t + 1]) (both
 * allocated here, the previous ones freed). */
static int tet_csr(vm_ctx *ctx, const gmsh_result *R, size_t maxtag, size_t **cnt, size_t **adj) {
  vm_free(ctx, *cnt);
  vm_free(ctx, *adj);
  *cnt = vm_calloc(ctx, maxtag + 2, sizeof **cnt);
  *adj = vm_alloc_array(ctx, 4 * R->nt + 1, sizeof **adj);
  size_t *fp = vm_alloc_array(ctx, maxtag + 1, sizeof *fp);
  if (!*cnt || !*adj || !fp) {
    vm_free(ctx, fp);
    return VM_ERR_NOMEM;
  }
  size_t *c = *cnt, *a = *adj;
  for (size_t i = 0; i < 4 * R->nt; i++) c[R->tnode[i] + 1]++;
  for (size_t t = 1; t <= maxtag + 1; t++) c[t] += c[t - 1];
  memcpy(fp, c, (maxtag + 1) * sizeof *fp);
  for (size_t t = 0; t < R->nt; t++)
    for (int k = 0; k < 4; k++) a[fp[R->tnode[4 * t + k]]++] = t;
  vm_free(ctx, fp);
  return VM_OK;
}

/* Edge removal (Shewchuk's) on Gmsh's flat tets of four envelope vertices
 * (node tags 1..nenv): for each such tet (min dihedral below 5 degrees),
 * each of its edges whose tets close a ring of 3..FLIP_RING_MAX around it
 * (an edge of the envelope or the far field has an open fan) is replaced,
 * with its ring, by the triangulation of the ring's polygon that gives
 * the best least dihedral angle, when that is better than the ring's own:
 * 2(n - 2) tets for n. The ring's outer faces stay, so every envelope
 * triangle is still a face. The new tets keep Gmsh's orientation; a
 * triangulation whose tets do not all have it, or do not fill the ring's
 * volume, is not taken. In rounds (a ring's vertices wait for the next
 * round once a ring around them changed), in tet order: deterministic. */
static int flip_slivers(vm_ctx *ctx, gmsh_result *R, size_t nenv, int64_t *nflips) {
  *nflips = 0;
  if (R->nt == 0) return VM_OK;
  size_t maxtag = 0;
  int64_t *at = NULL;
  int st = tet_nodes(ctx, R, nenv, &maxtag, &at);
  if (st) return st;
  uint8_t *lock = vm_calloc(ctx, maxtag + 1, 1);
  int(*tris_n)[42][FLIP_RING_MAX - 2][3] = vm_alloc_array(ctx, FLIP_RING_MAX + 1, sizeof *tris_n);
  size_t *cnt = NULL, *adj = NULL, *nw = NULL;
  uint8_t *dead = NULL;
  if (!lock || !tris_n) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int ntri[FLIP_RING_MAX + 1] = {0};
  for (int n = 3; n <= FLIP_RING_MAX; n++) ntri[n] = fill_polygon_triangulations(n, tris_n[n]);
  /* the orientation of Gmsh's tets */
  double sgn = tets_sign(R, at);
  for (int round = 0; round < FLIP_ROUNDS; round++) {
    size_t nt = R->nt;
    /* vertex -> tets */
    vm_free(ctx, dead);
    vm_free(ctx, nw);
    size_t cap = nt + 64, nnew = 0;
    dead = vm_calloc(ctx, nt + 1, 1);
    nw = vm_alloc_array(ctx, 4 * cap, sizeof *nw);
    if (!dead || !nw) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    if ((st = tet_csr(ctx, R, maxtag, &cnt, &adj))) goto done;
    memset(lock, 0, maxtag + 1);
    int64_t flips = 0;
    for (size_t t = 0; t < nt; t++) {
      if (dead[t]) continue;
      const size_t *c = R->tnode + 4 * t;
      if (c[0] > nenv || c[1] > nenv || c[2] > nenv || c[3] > nenv) continue;
      if (lock[c[0]] || lock[c[1]] || lock[c[2]] || lock[c[3]]) continue;
      const double *p[4];
      for (int k = 0; k < 4; k++) p[k] = R->coord + 3 * at[c[k]];
      double lo, hi;
      tet_angles(p, &lo, &hi);
      if (lo * 180 / PI >= FILL_FLAT_DEG) continue;
      static const int ed[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
      for (int e = 0; e < 6; e++) {
        size_t u = c[ed[e][0]], v = c[ed[e][1]];
        /* the ring: tets holding both u and v */
        size_t ring[FLIP_RING_MAX + 1], pr[FLIP_RING_MAX + 1][2];
        int n = 0, over = 0;
        for (size_t j = cnt[u]; j < cnt[u + 1]; j++) {
          size_t s2 = adj[j];
          const size_t *d = R->tnode + 4 * s2;
          int hv = d[0] == v || d[1] == v || d[2] == v || d[3] == v;
          if (!hv) continue;
          if (n == FLIP_RING_MAX + 1 || dead[s2]) {
            over = 1;
            break;
          }
          int q = 0;
          for (int k = 0; k < 4; k++)
            if (d[k] != u && d[k] != v) pr[n][q++] = d[k];
          ring[n++] = s2;
        }
        if (over || n < 3 || n > FLIP_RING_MAX) continue;
        /* chain the pairs into a cycle w[0..n-1] */
        int64_t pq[FLIP_RING_MAX + 1][2], wq[FLIP_RING_MAX];
        for (int k = 0; k < n; k++) pq[k][0] = (int64_t)pr[k][0], pq[k][1] = (int64_t)pr[k][1];
        if (!fill_ring_cycle(n, (const int64_t(*)[2])pq, wq)) continue;
        size_t w[FLIP_RING_MAX];
        for (int k = 0; k < n; k++) w[k] = (size_t)wq[k];
        /* the ring's own least angle and volume */
        double old = PI, vol0 = 0;
        for (int k = 0; k < n; k++) {
          const size_t *d = R->tnode + 4 * ring[k];
          const double *q[4];
          for (int i = 0; i < 4; i++) q[i] = R->coord + 3 * at[d[i]];
          double l2, h2;
          tet_angles(q, &l2, &h2);
          if (l2 < old) old = l2;
          vol0 += fabs(tet_vol(q[0], q[1], q[2], q[3]));
        }
        const double *pu = R->coord + 3 * at[u], *pv = R->coord + 3 * at[v];
        int best = -1;
        double bq = old;
        for (int k = 0; k < ntri[n]; k++) {
          double qmin = PI, vol = 0;
          int ok = 1;
          for (int j = 0; j < n - 2 && ok; j++) {
            const int *tr = tris_n[n][k][j];
            const double *a = R->coord + 3 * at[w[tr[0]]], *b = R->coord + 3 * at[w[tr[1]]],
                         *cc = R->coord + 3 * at[w[tr[2]]];
            double ou = tet_vol(a, b, cc, pu), ov = tet_vol(a, b, cc, pv);
            if (!(ou * ov < 0)) {
              ok = 0;
              break;
            }
            const double *q1[4] = {a, b, cc, pu}, *q2[4] = {a, b, cc, pv};
            double l1, h1, l2, h2;
            tet_angles(q1, &l1, &h1);
            tet_angles(q2, &l2, &h2);
            qmin = fmin(qmin, fmin(l1, l2));
            vol += fabs(ou) + fabs(ov);
          }
          if (!ok || !(fabs(vol - vol0) <= 1e-9 * vol0)) continue;
          if (qmin > bq) {
            bq = qmin;
            best = k;
          }
        }
        if (best < 0) continue;
        /* applied */
        if ((st = tets_room(ctx, &nw, &cap, nnew + 2 * (size_t)(n - 2), 2 * FLIP_RING_MAX)))
          goto done;
        for (int j = 0; j < n - 2; j++) {
          const int *tr = tris_n[n][best][j];
          size_t tv[2][4] = {{w[tr[0]], w[tr[1]], w[tr[2]], u}, {w[tr[0]], w[tr[1]], w[tr[2]], v}};
          for (int h = 0; h < 2; h++) {
            const double *a = R->coord + 3 * at[tv[h][0]], *b = R->coord + 3 * at[tv[h][1]],
                         *cc = R->coord + 3 * at[tv[h][2]], *d = R->coord + 3 * at[tv[h][3]];
            if (tet_vol(a, b, cc, d) * sgn < 0) {
              size_t x = tv[h][0];
              tv[h][0] = tv[h][1];
              tv[h][1] = x;
            }
            memcpy(nw + 4 * nnew++, tv[h], sizeof tv[h]);
          }
        }
        for (int k = 0; k < n; k++) {
          dead[ring[k]] = 1;
          const size_t *d = R->tnode + 4 * ring[k];
          for (int i = 0; i < 4; i++) lock[d[i]] = 1;
        }
        flips++;
        break;
      }
    }
    if (flips) {
      if ((st = tets_replace(R, nt, dead, nw, nnew))) goto done;
      *nflips += flips;
    }
    if (!flips) break;
  }
done:
  vm_free(ctx, at);
  vm_free(ctx, lock);
  vm_free(ctx, tris_n);
  vm_free(ctx, cnt);
  vm_free(ctx, adj);
  vm_free(ctx, dead);
  vm_free(ctx, nw);
  return st;
}

/* Local insertion of the sliver points, the passes after the first
 * FILL_GMSH_PASSES (instead of meshing the whole region again with them):
 * point i goes into the Delaunay cavity of the sliver it was made for
 * (src[i], the sliver's four node tags): the tets whose circumsphere holds
 * it, grown from the sliver across faces that have a tet on their other
 * side (a boundary's triangles stay faces), then shrunk until every face
 * of its boundary sees the point by a margin (a star-shaped cavity: the
 * tet behind a face that does not is left out; the sliver itself stays in
 * or the point is not taken), and filled with the tets of the point and
 * those faces, oriented as Gmsh's. The point is tried at several heights
 * on its line from the sliver's centroid (insert_heights) and the height
 * whose new tets have the largest least dihedral angle is taken, if that
 * beats the least angle of the tets it replaces and the cavity keeps every
 * vertex on its boundary. A point whose cavity meets one an earlier point
 * of the same round replaced waits for the next round (insert_round), on
 * the mesh that round leaves (4 rounds at most). New nodes get tags after
 * the largest (nbase: the input's vertex count, for the check of Gmsh's
 * tags); *ninserted counts the points taken. The merge checks the result
 * again (conformity, the boundary's triangles). */
enum { INSERT_CAVITY_MAX = 96 };

/* p inside the circumsphere of a, b, c, d (of orientation sign sgn)? */
static int in_sphere(const double *a, const double *b, const double *c, const double *d,
                     const double *p, double sgn) {
  double m[4][4];
  const double *q[4] = {a, b, c, d};
  for (int i = 0; i < 4; i++) {
    double x = q[i][0] - p[0], y = q[i][1] - p[1], z = q[i][2] - p[2];
    m[i][0] = x, m[i][1] = y, m[i][2] = z, m[i][3] = x * x + y * y + z * z;
  }
  double d0 = m[1][1] * (m[2][2] * m[3][3] - m[2][3] * m[3][2]) -
              m[1][2] * (m[2][1] * m[3][3] - m[2][3] * m[3][1]) +
              m[1][3] * (m[2][1] * m[3][2] - m[2][2] * m[3][1]);
  double d1 = m[0][1] * (m[2][2] * m[3][3] - m[2][3] * m[3][2]) -
              m[0][2] * (m[2][1] * m[3][3] - m[2][3] * m[3][1]) +
              m[0][3] * (m[2][1] * m[3][2] - m[2][2] * m[3][1]);
  double d2 = m[0][1] * (m[1][2] * m[3][3] - m[1][3] * m[3][2]) -
              m[0][2] * (m[1][1] * m[3][3] - m[1][3] * m[3][1]) +
              m[0][3] * (m[1][1] * m[3][2] - m[1][2] * m[3][1]);
  double d3 = m[0][1] * (m[1][2] * m[2][3] - m[1][3] * m[2][2]) -
              m[0][2] * (m[1][1] * m[2][3] - m[1][3] * m[2][1]) +
              m[0][3] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]);
  double det = m[0][0] * d0 - m[1][0] * d1 + m[2][0] * d2 - m[3][0] * d3;
  /* for a positively oriented tet the lifted determinant is negative
   * inside (the sign convention of the 4x4 form without the column of 1s
   * relative to p) */
  return -det * sgn > 0;
}

/* The tets of R around nodes (CSR by tag: tets cnt[t]..cnt[t+1]-1 in adj)
 * and the node index of each tag (at). */
typedef struct {
  const gmsh_result *R;
  const int64_t *at;
  const size_t *cnt, *adj;
  const uint8_t *dead;
  double sgn;
} tet_index;

/* The faces of a tet: face k leaves out vertex k, its three in the order
 * that keeps the tet's orientation with vertex k (or a new point) fourth. */
static const int tet_face[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};

enum { CAV_OK, CAV_NO_SLIVER, CAV_CONFLICT, CAV_STAR, CAV_VERTEX, CAV_WORSE };

/* The cavity of point p grown from tet t0 (see insert_points): its tets
 * cav[0..*nc), its boundary faces bf[0..*nbf) oriented so that p fourth
 * keeps the orientation, the least dihedral angle of the tets it replaces
 * (*old) and of the new ones (*neu). */
static int cavity(const tet_index *X, size_t t0, const double *p, size_t *cav, int *nc_out,
                  size_t (*bf)[3], int *nbf_out, double *old, double *neu) {
  const gmsh_result *R = X->R;
  const int64_t *at = X->at;
  int nc = 1;
  cav[0] = t0;
  const size_t *d0 = R->tnode + 4 * t0;
  if (!in_sphere(R->coord + 3 * at[d0[0]], R->coord + 3 * at[d0[1]], R->coord + 3 * at[d0[2]],
                 R->coord + 3 * at[d0[3]], p, X->sgn))
    return CAV_NO_SLIVER;
  /* grown across the faces no boundary holds (a boundary face has no tet
   * on its other side) to the tets whose circumsphere holds p */
  for (int c = 0; c < nc; c++) {
    const size_t *d = R->tnode + 4 * cav[c];
    for (int k = 0; k < 4; k++) {
      size_t a = d[tet_face[k][0]], b = d[tet_face[k][1]], e = d[tet_face[k][2]], nb = (size_t)-1;
      for (size_t j = X->cnt[a]; j < X->cnt[a + 1]; j++) {
        size_t u = X->adj[j];
        if (u == cav[c]) continue;
        const size_t *g = R->tnode + 4 * u;
        int hb = 0, he = 0;
        for (int q = 0; q < 4; q++) hb |= g[q] == b, he |= g[q] == e;
        if (hb && he) {
          nb = u;
          break;
        }
      }
      if (nb == (size_t)-1) continue;
      int in = 0;
      for (int q = 0; q < nc && !in; q++) in = cav[q] == nb;
      if (in) continue;
      const size_t *g = R->tnode + 4 * nb;
      if (!in_sphere(R->coord + 3 * at[g[0]], R->coord + 3 * at[g[1]], R->coord + 3 * at[g[2]],
                     R->coord + 3 * at[g[3]], p, X->sgn))
        continue;
      if (X->dead[nb] || nc == INSERT_CAVITY_MAX) return CAV_CONFLICT;
      cav[nc++] = nb;
    }
  }
  /* shrunk until every boundary face sees p (by a margin): a face is on
   * the boundary when no other tet of the cavity holds it; the sliver
   * itself stays */
  int nbf = 0;
  for (;;) {
    nbf = 0;
    int drop = -1;
    for (int c = 0; c < nc && drop < 0; c++) {
      const size_t *d = R->tnode + 4 * cav[c];
      for (int k = 0; k < 4; k++) {
        size_t a = d[tet_face[k][0]], b = d[tet_face[k][1]], e = d[tet_face[k][2]];
        int shared = 0;
        for (int q = 0; q < nc && !shared; q++) {
          if (q == c) continue;
          const size_t *g = R->tnode + 4 * cav[q];
          int h = 0;
          for (int r = 0; r < 4; r++) h += g[r] == a || g[r] == b || g[r] == e;
          shared = h == 3;
        }
        if (shared) continue;
        const double *pa = R->coord + 3 * at[a], *pb = R->coord + 3 * at[b],
                     *pe = R->coord + 3 * at[e], *pd = R->coord + 3 * at[d[k]];
        double vt = tet_vol(pa, pb, pe, pd), vp = tet_vol(pa, pb, pe, p);
        if (!(vp * vt > 0 && fabs(vp) > 1e-3 * fabs(vt))) {
          drop = c;
          break;
        }
        bf[nbf][0] = a, bf[nbf][1] = b, bf[nbf][2] = e;
        nbf++;
      }
    }
    if (drop < 0) break;
    if (drop == 0) return CAV_STAR;
    cav[drop] = cav[--nc];
  }
  /* every vertex of the cavity on its boundary (else it would be lost) */
  for (int c = 0; c < nc; c++) {
    const size_t *d = R->tnode + 4 * cav[c];
    for (int k = 0; k < 4; k++) {
      int on = 0;
      for (int f = 0; f < nbf && !on; f++)
        on = bf[f][0] == d[k] || bf[f][1] == d[k] || bf[f][2] == d[k];
      if (!on) return CAV_VERTEX;
    }
  }
  *old = *neu = PI;
  for (int c = 0; c < nc; c++) {
    const size_t *d = R->tnode + 4 * cav[c];
    const double *q[4] = {R->coord + 3 * at[d[0]], R->coord + 3 * at[d[1]], R->coord + 3 * at[d[2]],
                          R->coord + 3 * at[d[3]]};
    double lo, hi;
    tet_angles(q, &lo, &hi);
    *old = fmin(*old, lo);
  }
  for (int f = 0; f < nbf; f++) {
    const double *q[4] = {R->coord + 3 * at[bf[f][0]], R->coord + 3 * at[bf[f][1]],
                          R->coord + 3 * at[bf[f][2]], p};
    double lo, hi;
    tet_angles(q, &lo, &hi);
    *neu = fmin(*neu, lo);
  }
  *nc_out = nc;
  *nbf_out = nbf;
  return *neu > *old ? CAV_OK : CAV_WORSE;
}

/* Heights tried for a sliver's point, as shares of the way from the
 * sliver's centroid to the point sliver_points made: the best kept. */
static const double insert_heights[] = {1, 0.6, 1.5, 0.35, 2, 0.8, 1.2};

/* One round of insert_points over the points todo[0..*ntodo); *ntodo
 * becomes the count of those left to try again, first in todo (their
 * cavities met one this round replaced). */
static int insert_round(vm_ctx *ctx, gmsh_result *R, size_t nbase, const double *pts,
                        const size_t *src, int64_t *todo, int64_t *ntodo, int64_t *ninserted,
                        int64_t why[6]) {
  *ninserted = 0;
  int64_t np = *ntodo, nretry = 0;
  *ntodo = 0;
  size_t maxtag = 0, nt = R->nt;
  int64_t *at = NULL;
  size_t *cnt = NULL, *adj = NULL, *nw = NULL, nnew = 0, cap = 0;
  int st = tet_nodes(ctx, R, nbase, &maxtag, &at);
  if (st) return st;
  uint8_t *dead = vm_calloc(ctx, nt + 1, 1);
  double *np_xyz = vm_alloc_array(ctx, 3 * (size_t)np + 1, sizeof *np_xyz);
  if (!dead || !np_xyz) st = VM_ERR_NOMEM;
  if (!st) st = tet_csr(ctx, R, maxtag, &cnt, &adj);
  if (st) goto done;
  tet_index X = {R, at, cnt, adj, dead, tets_sign(R, at)};
  int64_t nins = 0;
  for (int64_t k0 = 0; k0 < np; k0++) {
    const int64_t i = todo[k0];
    const size_t *s = src + 4 * i;
    /* the sliver */
    size_t t0 = (size_t)-1;
    for (size_t j = cnt[s[0]]; j < cnt[s[0] + 1] && t0 == (size_t)-1; j++) {
      const size_t *d = R->tnode + 4 * adj[j];
      int h = 0;
      for (int a = 1; a < 4; a++)
        for (int b = 0; b < 4; b++) h += d[b] == s[a];
      if (h == 3) t0 = adj[j];
    }
    if (t0 == (size_t)-1 || dead[t0]) {
      why[CAV_NO_SLIVER]++;
      continue;
    }
    double g[3] = {0, 0, 0};
    for (int k = 0; k < 4; k++)
      for (int r = 0; r < 3; r++) g[r] += R->coord[3 * at[s[k]] + r] / 4;
    size_t cav[INSERT_CAVITY_MAX], bcav[INSERT_CAVITY_MAX], bf[4 * INSERT_CAVITY_MAX][3],
        bbf[4 * INSERT_CAVITY_MAX][3];
    int nc = 0, nbf = 0, bnc = 0, bnbf = 0, conflict = 0, last = CAV_NO_SLIVER;
    double best = -1, bp[3];
    const size_t nh = sizeof insert_heights / sizeof *insert_heights;
    for (size_t h = 0; h < nh; h++) {
      double p[3], old, neu;
      for (int r = 0; r < 3; r++) p[r] = g[r] + insert_heights[h] * (pts[3 * i + r] - g[r]);
      int c = cavity(&X, t0, p, cav, &nc, bf, &nbf, &old, &neu);
      conflict |= c == CAV_CONFLICT;
      if (c != CAV_OK) {
        last = c;
        continue;
      }
      if (neu > best) {
        best = neu;
        memcpy(bp, p, sizeof bp);
        memcpy(bcav, cav, (size_t)nc * sizeof *cav);
        memcpy(bbf, bf, (size_t)nbf * sizeof *bf);
        bnc = nc;
        bnbf = nbf;
      }
    }
    if (best < 0) {
      why[conflict ? CAV_CONFLICT : last]++;
      if (conflict) todo[nretry++] = i;
      continue;
    }
    /* applied: the point's tag, the new tets */
    if ((st = tets_room(ctx, &nw, &cap, nnew + (size_t)bnbf, 4 * INSERT_CAVITY_MAX))) goto done;
    size_t tag = maxtag + 1 + (size_t)nins;
    for (int f = 0; f < bnbf; f++) {
      size_t *o = nw + 4 * nnew++;
      o[0] = bbf[f][0], o[1] = bbf[f][1], o[2] = bbf[f][2], o[3] = tag;
    }
    for (int c = 0; c < bnc; c++) dead[bcav[c]] = 1;
    memcpy(np_xyz + 3 * nins, bp, sizeof bp);
    nins++;
  }
  if (nins) {
    size_t *tags = gmshMalloc((R->nn + (size_t)nins) * sizeof *tags);
    double *xyz = gmshMalloc(3 * (R->nn + (size_t)nins) * sizeof *xyz);
    if (!tags || !xyz || tets_replace(R, nt, dead, nw, nnew)) {
      gmshFree(tags);
      gmshFree(xyz);
      st = VM_ERR_NOMEM;
      goto done;
    }
    memcpy(tags, R->ntag, R->nn * sizeof *tags);
    memcpy(xyz, R->coord, 3 * R->nn * sizeof *xyz);
    for (int64_t j = 0; j < nins; j++) {
      tags[R->nn + (size_t)j] = maxtag + 1 + (size_t)j;
      memcpy(xyz + 3 * (R->nn + (size_t)j), np_xyz + 3 * j, 3 * sizeof *xyz);
    }
    gmshFree(R->ntag);
    gmshFree(R->coord);
    R->ntag = tags;
    R->coord = xyz;
    R->nn += (size_t)nins;
  }
  *ninserted = nins;
  *ntodo = nretry;
done:
  vm_free(ctx, at);
  vm_free(ctx, cnt);
  vm_free(ctx, adj);
  vm_free(ctx, dead);
  vm_free(ctx, nw);
  vm_free(ctx, np_xyz);
  return st;
}

static int insert_points(vm_ctx *ctx, gmsh_result *R, size_t nbase, const double *pts,
                         const size_t *src, int64_t np, int64_t *ninserted) {
  *ninserted = 0;
  if (R->nt == 0 || np == 0) return VM_OK;
  int64_t *todo = vm_alloc_array(ctx, (size_t)np, sizeof *todo), ntodo = np;
  if (!todo) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < np; i++) todo[i] = i;
  int st = VM_OK;
  /* rounds: a point whose cavity met one an earlier point of the round
   * replaced goes again in the next, on the mesh that round left */
  for (int round = 0; !st && ntodo > 0 && round < 4; round++) {
    int64_t ni = 0, why[6] = {0};
    st = insert_round(ctx, R, nbase, pts, src, todo, &ntodo, &ni, why);
    *ninserted += ni;
    vm_log(ctx, VM_LOG_DEBUG,
           "fill: local insertion round %d: %lld points in; left: sliver gone %lld, meeting a "
           "cavity of this round %lld, no star-shaped cavity %lld, no better %lld",
           round + 1, (long long)ni, (long long)why[CAV_NO_SLIVER], (long long)why[CAV_CONFLICT],
           (long long)(why[CAV_STAR] + why[CAV_VERTEX]), (long long)why[CAV_WORSE]);
    if (!ni) break;
  }
  vm_free(ctx, todo);
  return st;
}

/* Mesh the region between the envelope (node tags = input index + 1) and
 * the far field (node tags base + 1 ...) with the size field S; the
 * envelope's triangles (and so its nodes) given to Gmsh in their order, or
 * in the reverse order if `reverse` (Gmsh's boundary recovery depends on
 * the order: an envelope it aborts on one way it may mesh the other). */
static int gmsh_fill(vm_ctx *ctx, const vm_mesh *m, const envelope *E, const far_surface *F,
                     int64_t base, const double *q, int64_t nq, size_field *S,
                     const vm_fill_opts *o, int reverse, gmsh_result *R) {
  memset(R, 0, sizeof *R);
  int ierr = 0, st = VM_OK;
  gmshInitialize(0, NULL, 0, &ierr);
  if (ierr) return vm_error(ctx, VM_ERR_BACKEND, "Gmsh could not be initialized");
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshLoggerStart(&ierr);
  gmshOptionSetNumber("General.Verbosity", 5, &ierr);
  int threads = o->threads > 0 ? o->threads : vm_ctx_threads(ctx);
  gmshOptionSetNumber("General.NumThreads", threads > 0 ? threads : 1, &ierr);
  gmshModelAdd("varmesh-fill", &ierr);
  /* the envelope: its vertices with their own (1-based) indices as tags */
  size_t *tags = NULL, *tri = NULL;
  double *xyz = NULL;
  uint8_t *used = vm_calloc(ctx, (size_t)m->nv + 1, 1);
  size_t nmax = (size_t)(E->nf * 3 > F->nv ? E->nf * 3 : F->nv);
  size_t fmax = (size_t)(E->nf > F->nf ? E->nf : F->nf);
  tags = vm_alloc_array(ctx, nmax + 1, sizeof *tags);
  xyz = vm_alloc_array(ctx, 3 * nmax + 3, sizeof *xyz);
  tri = vm_alloc_array(ctx, 3 * fmax + 3, sizeof *tri);
  if (!used || !tags || !xyz || !tri) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  size_t k = 0;
  /* the i-th corner given to Gmsh: corner i of the envelope's list, or of
   * its triangles in reverse order */
#define FILL_CORNER(i) (reverse ? 3 * (E->nf - 1 - (i) / 3) + (i) % 3 : (i))
  for (int64_t i = 0; i < 3 * E->nf; i++) {
    int32_t v = E->fv[FILL_CORNER(i)];
    if (used[v]) continue;
    used[v] = 1;
    tags[k] = (size_t)v + 1;
    memcpy(xyz + 3 * k++, m->xyz + 3 * v, 3 * sizeof(double));
  }
  int s1 = gmshModelAddDiscreteEntity(2, -1, NULL, 0, &ierr);
  if (!ierr) gmshModelMeshAddNodes(2, s1, tags, k, xyz, 3 * k, NULL, 0, &ierr);
  for (int64_t i = 0; i < 3 * E->nf; i++) tri[i] = (size_t)E->fv[FILL_CORNER(i)] + 1;
#undef FILL_CORNER
  if (!ierr) gmshModelMeshAddElementsByType(s1, 2, NULL, 0, tri, (size_t)(3 * E->nf), &ierr);
  if ((st = gmsh_status(ctx, ierr, "adding the envelope"))) goto done;
  /* a half model's far field and symmetry plane close the envelope: one
   * surface with it (their triangles share its border's vertices) */
  for (int64_t i = 0; i < F->nv; i++) tags[i] = (size_t)(base + i + 1);
  int s2 = F->nsym ? s1 : gmshModelAddDiscreteEntity(2, -1, NULL, 0, &ierr);
  if (!ierr)
    gmshModelMeshAddNodes(2, s2, tags, (size_t)F->nv, F->xyz, (size_t)(3 * F->nv), NULL, 0, &ierr);
  for (int64_t i = 0; i < 3 * F->nf; i++) tri[i] = (size_t)far_vertex(F->fv[i], base) + 1;
  if (!ierr) gmshModelMeshAddElementsByType(s2, 2, NULL, 0, tri, (size_t)(3 * F->nf), &ierr);
  int loops[2] = {s1, s2}, shell = 0, vol = 0;
  int *ptag = vm_alloc_array(ctx, (size_t)nq + 1, sizeof *ptag);
  if (!ptag) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t i = 0; i < nq && !ierr; i++)
    ptag[i] = gmshModelGeoAddPoint(q[3 * i], q[3 * i + 1], q[3 * i + 2], 0, -1, &ierr);
  if (!ierr) shell = gmshModelGeoAddSurfaceLoop(loops, F->nsym ? 1 : 2, -1, &ierr);
  if (!ierr) vol = gmshModelGeoAddVolume(&shell, 1, -1, &ierr);
  if (!ierr) gmshModelGeoSynchronize(&ierr);
  if (!ierr && nq) gmshModelMeshEmbed(0, ptag, (size_t)nq, 3, vol, &ierr);
  vm_free(ctx, ptag);
  if ((st = gmsh_status(ctx, ierr, "setting up the volume"))) goto done;
  gmshOptionSetNumber("Mesh.MeshSizeExtendFromBoundary", 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromPoints", 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 0, &ierr);
  gmshOptionSetNumber("Mesh.Renumber", 0, &ierr);
  gmshOptionSetNumber("Mesh.Algorithm3D", o->algorithm, &ierr);
  gmshOptionSetNumber("Mesh.Optimize", 1, &ierr);
  gmshModelMeshSetSizeCallback(gmsh_size_cb, S, &ierr);
  gmshModelMeshGenerate(3, &ierr);
  if ((st = gmsh_status(
           ctx, ierr, "meshing the volume (does the envelope intersect itself or the far field?)")))
    goto done;
  double *pc = NULL;
  size_t npc = 0, ncoord = 0, *etag = NULL, ne = 0, ntn = 0;
  gmshModelMeshGetNodes(&R->ntag, &R->nn, &R->coord, &ncoord, &pc, &npc, -1, -1, 0, 0, &ierr);
  gmshFree(pc);
  if (!ierr) gmshModelMeshGetElementsByType(4, &etag, &ne, &R->tnode, &ntn, -1, 0, 1, &ierr);
  gmshFree(etag);
  R->nt = ntn / 4;
  if ((st = gmsh_status(ctx, ierr, "returning the mesh"))) goto done;
  if (ncoord != 3 * R->nn || ntn != 4 * R->nt || !R->nt) {
    st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh returned no tetrahedra (%zu nodes, %zu values)", R->nn,
                  ntn);
    goto done;
  }
done:
  if (st) gmsh_result_free(R);
  gmshLoggerStop(&ierr);
  gmshFinalize(&ierr);
  vm_free(ctx, used);
  vm_free(ctx, tags);
  vm_free(ctx, xyz);
  vm_free(ctx, tri);
  return st;
}

/* Gmsh in a child process: an assertion or a crash inside Gmsh (its
 * boundary recovery aborts on some inputs) becomes one error line here
 * instead of ending the caller's process. The child sends its result
 * through a pipe; its stderr (where an assertion is printed) through
 * another. */
static int write_all(int fd, const void *buf, size_t n) {
  const char *p = buf;
  while (n) {
    ssize_t k = write(fd, p, n);
    if (k <= 0) return -1;
    p += k;
    n -= (size_t)k;
  }
  return 0;
}

static int read_all(int fd, void *buf, size_t n) {
  char *p = buf;
  while (n) {
    ssize_t k = read(fd, p, n);
    if (k <= 0) return -1;
    p += k;
    n -= (size_t)k;
  }
  return 0;
}

typedef struct {
  int status;
  size_t nn, nt;
  char msg[480];
} gmsh_header;

static int gmsh_fill_isolated(vm_ctx *ctx, const vm_mesh *m, const envelope *E,
                              const far_surface *F, int64_t base, const double *q, int64_t nq,
                              size_field *S, const vm_fill_opts *o, int reverse, gmsh_result *R,
                              int *crashed) {
  memset(R, 0, sizeof *R);
  if (crashed) *crashed = 0;
  /* VM_FILL_GMSH_ABORT=N (for tests of the fallbacks): the process's first N
   * Gmsh processes abort, as Gmsh's boundary recovery does on some
   * envelopes */
  static int runs = 0;
  const char *ab = getenv("VM_FILL_GMSH_ABORT");
  int inject = ab && runs++ < atoi(ab);
  int pd[2], ed[2];
  if (pipe(pd)) return vm_error(ctx, VM_ERR_IO, "fill: cannot make a pipe for Gmsh");
  if (pipe(ed)) {
    close(pd[0]);
    close(pd[1]);
    return vm_error(ctx, VM_ERR_IO, "fill: cannot make a pipe for Gmsh");
  }
  fflush(NULL);
  pid_t pid = fork();
  if (pid < 0) {
    close(pd[0]), close(pd[1]), close(ed[0]), close(ed[1]);
    return vm_error(ctx, VM_ERR_IO, "fill: cannot start Gmsh's process");
  }
  if (pid == 0) {
    close(pd[0]);
    close(ed[0]);
    dup2(ed[1], 2);
    if (inject) {
      fprintf(stderr, "VM_FILL_GMSH_ABORT: aborted\n");
      abort();
    }
    gmsh_header h;
    memset(&h, 0, sizeof h);
    h.status = gmsh_fill(ctx, m, E, F, base, q, nq, S, o, reverse, R);
    if (h.status) snprintf(h.msg, sizeof h.msg, "%s", vm_ctx_error(ctx));
    h.nn = R->nn;
    h.nt = R->nt;
    int bad = write_all(pd[1], &h, sizeof h);
    if (!bad && !h.status)
      bad = write_all(pd[1], R->ntag, R->nn * sizeof *R->ntag) ||
            write_all(pd[1], R->coord, 3 * R->nn * sizeof *R->coord) ||
            write_all(pd[1], R->tnode, 4 * R->nt * sizeof *R->tnode);
    _exit(bad ? 3 : 0);
  }
  close(pd[1]);
  close(ed[1]);
  gmsh_header h;
  int st = VM_OK, lost = 0; /* lost: the child's answer did not arrive whole */
  if (read_all(pd[0], &h, sizeof h)) {
    lost = 1;
  } else if (h.status) {
    st = vm_error(ctx, h.status, "%s", h.msg);
  } else {
    R->nn = h.nn;
    R->nt = h.nt;
    R->ntag = malloc(h.nn * sizeof *R->ntag + 1);
    R->coord = malloc(3 * h.nn * sizeof *R->coord + 1);
    R->tnode = malloc(4 * h.nt * sizeof *R->tnode + 1);
    if (!R->ntag || !R->coord || !R->tnode)
      st = vm_error(ctx, VM_ERR_NOMEM, "fill: out of memory reading Gmsh's mesh");
    else if (read_all(pd[0], R->ntag, h.nn * sizeof *R->ntag) ||
             read_all(pd[0], R->coord, 3 * h.nn * sizeof *R->coord) ||
             read_all(pd[0], R->tnode, 4 * h.nt * sizeof *R->tnode))
      lost = 1;
  }
  close(pd[0]);
  /* the child's last line on stderr: an assertion's message */
  char buf[4096], last[512] = "";
  size_t got = 0;
  ssize_t k;
  while ((k = read(ed[0], buf + got, sizeof buf - 1 - got)) > 0) {
    got += (size_t)k;
    if (got >= sizeof buf - 1) {
      buf[got] = 0;
      memmove(buf, buf + got / 2, got - got / 2 + 1);
      got -= got / 2;
    }
  }
  close(ed[0]);
  buf[got] = 0;
  while (got && (buf[got - 1] == '\n' || buf[got - 1] == '\r')) buf[--got] = 0;
  const char *nl = strrchr(buf, '\n');
  snprintf(last, sizeof last, "%.500s", nl ? nl + 1 : buf);
  int ws = 0;
  waitpid(pid, &ws, 0);
  if (lost || (st == VM_OK && !(WIFEXITED(ws) && WEXITSTATUS(ws) == 0))) {
    gmsh_result_free(R);
    if (WIFSIGNALED(ws))
      st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh crashed (signal %d)%s%s", WTERMSIG(ws),
                    *last ? ": " : "", last);
    else
      st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh's process failed%s%s", *last ? ": " : "", last);
    if (crashed) *crashed = 1;
  }
  if (st) gmsh_result_free(R);
  return st;
}

/* ---------- the merged mesh ---------- */

/* Largest "gmsh:physical" tag in use (0 if none). */
static int32_t max_tag(const vm_mesh *m) {
  int32_t t = 0;
  const vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  if (ph && ph->type == VM_FIELD_I32 && ph->ncomp == 1)
    for (int64_t e = 0; e < m->ne; e++)
      if (((const int32_t *)ph->data)[e] > t) t = ((const int32_t *)ph->data)[e];
  for (int i = 0; i < m->nattr; i++) {
    const char *k = m->attrs[i].key;
    if (!strncmp(k, "gmsh:physical_name:", 19) && k[19] && k[20] == ':') {
      long v = atol(k + 21);
      if (v > t && v < INT32_MAX) t = (int32_t)v;
    }
  }
  return t;
}

static int set_name(vm_mesh *m, int dim, int32_t tag, const char *name) {
  char key[64];
  snprintf(key, sizeof key, "gmsh:physical_name:%d:%d", dim, (int)tag);
  return vm_mesh_set_attr(m, key, name);
}

/* Build *out from the input, the envelope, the far field and Gmsh's tets;
 * check that Gmsh kept every envelope and far-field triangle and vertex. */
static int merge(vm_ctx *ctx, const vm_mesh *m, const envelope *E, const far_surface *F,
                 const gmsh_result *R, vm_mesh **out) {
  int st = VM_OK;
  int64_t base = m->nv, nfar = F->nv;
  size_t maxtag = 0;
  for (size_t i = 0; i < R->nn; i++)
    if (R->ntag[i] > maxtag) maxtag = R->ntag[i];
  if (maxtag > 4 * (R->nn + (size_t)base + (size_t)nfar) + 16)
    return vm_error(ctx, VM_ERR_BACKEND, "Gmsh returned node tags up to %zu for %zu nodes", maxtag,
                    R->nn);
  int64_t *map = vm_alloc_array(ctx, maxtag + 1, sizeof *map);
  uint8_t *onenv = vm_calloc(ctx, (size_t)base + 1, 1);
  vm_mesh *o = NULL;
  tface *tf = NULL;
  if (!map || !onenv) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t i = 0; i < 3 * E->nf; i++) onenv[E->fv[i]] = 1;
  for (size_t t = 0; t <= maxtag; t++) map[t] = -1;
  int64_t nnew = 0, nseen_env = 0;
  for (size_t i = 0; i < R->nn; i++) {
    size_t t = R->ntag[i];
    const double *x = R->coord + 3 * i;
    if (t == 0 || map[t] >= 0) {
      st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh returned node tag %zu twice (or 0)", t);
      goto done;
    }
    if (t <= (size_t)base) {
      if (!onenv[t - 1] || memcmp(x, m->xyz + 3 * (t - 1), 3 * sizeof(double))) {
        st = vm_error(ctx, VM_ERR_BACKEND,
                      "Gmsh moved envelope vertex %zu: the layer would not match the fill", t - 1);
        goto done;
      }
      map[t] = (int64_t)t - 1;
      nseen_env++;
    } else if (t <= (size_t)(base + nfar)) {
      if (memcmp(x, F->xyz + 3 * (t - base - 1), 3 * sizeof(double))) {
        st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh moved far-field vertex %zu",
                      (size_t)(t - base - 1));
        goto done;
      }
      map[t] = (int64_t)t - 1;
    } else {
      map[t] = -2; /* numbered below, in tag order */
    }
  }
  /* new nodes no tet uses (an embedded point Gmsh left out) are dropped */
  uint8_t *usedt = vm_calloc(ctx, maxtag + 1, 1);
  if (!usedt) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (size_t i = 0; i < 4 * R->nt; i++)
    if (R->tnode[i] <= maxtag) usedt[R->tnode[i]] = 1;
  int64_t nunused = 0;
  for (size_t t = (size_t)(base + nfar) + 1; t <= maxtag; t++) {
    if (map[t] != -2) continue;
    if (usedt[t])
      map[t] = base + nfar + nnew++;
    else
      nunused++;
  }
  vm_free(ctx, usedt);
  if (nunused)
    vm_log(ctx, VM_LOG_INFO, "fill: %lld points Gmsh did not use (outside the region) dropped",
           (long long)nunused);
  /* the output: the input's vertices, the far field's, the new ones */
  int64_t nin_env = 0;
  for (int64_t v = 0; v < base; v++) nin_env += onenv[v];
  if (nseen_env != nin_env) {
    st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh dropped %lld envelope vertices",
                  (long long)(nin_env - nseen_env));
    goto done;
  }
  if ((st = vm_mesh_create(ctx, &o))) goto done;
  o->dim = 3;
  if ((st = vm_mesh_set_vertices(o, base + nfar + nnew))) goto done;
  memcpy(o->xyz, m->xyz, (size_t)(3 * base) * sizeof(double));
  memcpy(o->vflag, m->vflag, (size_t)base);
  memcpy(o->vsurf, m->vsurf, (size_t)base * sizeof(int32_t));
  memcpy(o->xyz + 3 * base, F->xyz, (size_t)(3 * nfar) * sizeof(double));
  for (size_t i = 0; i < R->nn; i++) {
    int64_t v = map[R->ntag[i]];
    if (v >= base + nfar && v >= 0) memcpy(o->xyz + 3 * v, R->coord + 3 * i, 3 * sizeof(double));
  }
  /* elements: the input's but the envelope's own triangles, the tets, the far field */
  uint8_t *drop = vm_calloc(ctx, (size_t)m->ne + 1, 1);
  if (!drop) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t ndrop = 0;
  if (!E->surface)
    for (int64_t i = 0; i < E->nf; i++)
      if (E->felem[i] >= 0 && !drop[E->felem[i]]) drop[E->felem[i]] = 1, ndrop++;
  int64_t nkeep = m->ne - ndrop, nt = (int64_t)R->nt;
  int64_t ne = nkeep + nt + F->nf;
  int64_t nconn = m->eoff[m->ne] + 4 * nt + 3 * F->nf;
  for (int64_t e = 0; e < m->ne; e++)
    if (drop[e]) nconn -= vm_elem_nverts(m->etype[e]);
  if ((st = vm_mesh_set_elements(o, ne, nconn))) {
    vm_free(ctx, drop);
    goto done;
  }
  int64_t *emap = vm_alloc_array(ctx, (size_t)m->ne + 1, sizeof *emap);
  if (!emap) {
    vm_free(ctx, drop);
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t k = 0, c = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    emap[e] = -1;
    if (drop[e]) continue;
    int n = vm_elem_nverts(m->etype[e]);
    o->etype[k] = m->etype[e];
    memcpy(o->conn + c, m->conn + m->eoff[e], (size_t)n * sizeof(int32_t));
    c += n;
    emap[e] = k++;
    o->eoff[k] = c;
  }
  vm_free(ctx, drop);
  int64_t ninv = 0;
  for (int64_t t = 0; t < nt; t++) {
    int32_t q[4];
    for (int i = 0; i < 4; i++) {
      size_t tag = R->tnode[4 * t + i];
      if (tag > maxtag || map[tag] < 0) {
        vm_free(ctx, emap);
        st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh tet %lld names node %zu, which it did not return",
                      (long long)t, tag);
        goto done;
      }
      q[i] = (int32_t)map[tag];
    }
    double vol =
        tet_vol(o->xyz + 3 * q[0], o->xyz + 3 * q[1], o->xyz + 3 * q[2], o->xyz + 3 * q[3]);
    if (vol < 0) {
      int32_t s = q[1];
      q[1] = q[2];
      q[2] = s;
    }
    ninv += vol == 0;
    o->etype[k] = VM_TET;
    memcpy(o->conn + c, q, sizeof q);
    c += 4;
    o->eoff[++k] = c;
  }
  for (int64_t f = 0; f < F->nf; f++) {
    o->etype[k] = VM_TRI;
    for (int i = 0; i < 3; i++) o->conn[c++] = (int32_t)far_vertex(F->fv[3 * f + i], base);
    o->eoff[++k] = c;
  }
  if (ninv) {
    vm_free(ctx, emap);
    st = vm_error(ctx, VM_ERR_BACKEND, "Gmsh made %lld flat tetrahedra", (long long)ninv);
    goto done;
  }
  /* fields: the input's, new items 0 (-1 for int element fields) */
  for (int i = 0; i < m->nfield && !st; i++) {
    const vm_field *f = &m->fields[i];
    vm_field *g;
    if ((st = vm_mesh_add_field(o, f->name, f->location, f->type, f->ncomp, &g))) break;
    size_t w = (f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t)) * (size_t)f->ncomp;
    if (f->location == VM_FIELD_VERTEX) {
      memcpy(g->data, f->data, w * (size_t)base);
      continue;
    }
    if (f->type == VM_FIELD_I32 && strcmp(f->name, "gmsh:physical"))
      for (int64_t j = 0; j < ne * f->ncomp; j++) ((int32_t *)g->data)[j] = -1;
    for (int64_t e = 0; e < m->ne; e++)
      if (emap[e] >= 0)
        memcpy((char *)g->data + w * (size_t)emap[e], (const char *)f->data + w * (size_t)e, w);
  }
  vm_free(ctx, emap);
  for (int i = 0; i < m->nattr && !st; i++)
    st = vm_mesh_set_attr(o, m->attrs[i].key, m->attrs[i].value);
  if (st) goto done;
  /* names: the wall (a surface input), the far field, the fill */
  vm_field *ph = vm_mesh_find_field(o, "gmsh:physical", VM_FIELD_ELEMENT);
  if (ph && (ph->type != VM_FIELD_I32 || ph->ncomp != 1)) {
    st = vm_error(ctx, VM_ERR_FORMAT, "the field 'gmsh:physical' is not one int per element");
    goto done;
  }
  if (!ph && (st = vm_mesh_add_field(o, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &ph)))
    goto done;
  int32_t top = max_tag(m), *tag = ph->data;
  int32_t t_far = top + 1, t_fill = top + 2, t_wall = top + 3;
  if (E->surface) {
    int32_t named = tag_named(m, "wall");
    if (named < 0 && (st = set_name(o, 2, t_wall, "wall"))) goto done;
    for (int64_t e = 0; e < nkeep; e++)
      if (o->etype[e] == VM_TRI && tag[e] <= 0) tag[e] = named >= 0 ? named : t_wall;
  }
  for (int64_t e = nkeep; e < nkeep + nt; e++) tag[e] = t_fill;
  for (int64_t e = nkeep + nt; e < ne; e++) tag[e] = t_far;
  if ((st = set_name(o, 2, t_far, "farfield")) || (st = set_name(o, 3, t_fill, "fill"))) goto done;
  if (F->nsym) {
    /* a half model's symmetry plane: the layer's faces there are named so */
    int32_t t_sym = tag_named(m, "symmetry");
    if (t_sym < 0 && (st = set_name(o, 2, t_sym = top + 4, "symmetry"))) goto done;
    for (int64_t e = ne - F->nsym; e < ne; e++) tag[e] = t_sym;
  }
  /* Gmsh kept the boundary: the tets' unshared faces are exactly the
   * envelope's and the far field's triangles */
  tf = vm_alloc_array(ctx, (size_t)(4 * nt + E->nf + F->nf), sizeof *tf);
  if (!tf) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t nf = 0;
  static const int tf4[4][3] = {{0, 1, 2}, {0, 1, 3}, {1, 2, 3}, {0, 2, 3}};
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *q = o->conn + o->eoff[nkeep + t];
    for (int j = 0; j < 4; j++) {
      for (int i = 0; i < 3; i++) tf[nf].v[i] = q[tf4[j][i]];
      fill_sort3(tf[nf].v);
      tf[nf++].cell = 0;
    }
  }
  for (int64_t f = 0; f < E->nf + F->nf; f++) {
    for (int i = 0; i < 3; i++)
      tf[nf].v[i] =
          f < E->nf ? E->fv[3 * f + i] : (int32_t)far_vertex(F->fv[3 * (f - E->nf) + i], base);
    fill_sort3(tf[nf].v);
    tf[nf++].cell = 1; /* a boundary triangle: sorts after the tets' faces */
  }
  qsort(tf, (size_t)nf, sizeof *tf, cmp_tface);
  int64_t bad = 0, first = -1;
  for (int64_t i = 0; i < nf;) {
    int64_t j = i + 1;
    while (j < nf && fill_same_face(&tf[i], &tf[j])) j++;
    int tets = 0, bnd = 0;
    for (int64_t q = i; q < j; q++) tets += tf[q].cell == 0, bnd += tf[q].cell == 1;
    /* interior: 2 tets; boundary: 1 tet and the triangle */
    if (!((tets == 2 && bnd == 0) || (tets == 1 && bnd == 1))) {
      if (first < 0) first = i;
      bad++;
    }
    i = j;
  }
  if (bad) {
    st = vm_error(ctx, VM_ERR_BACKEND,
                  "Gmsh did not keep the boundary: %lld faces (vertices %d %d %d first) are not "
                  "one envelope or far-field triangle on one tet or shared by two tets",
                  (long long)bad, tf[first].v[0], tf[first].v[1], tf[first].v[2]);
    goto done;
  }
done:
  vm_free(ctx, tf);
  vm_free(ctx, map);
  vm_free(ctx, onenv);
  if (st)
    vm_mesh_destroy(&o);
  else
    *out = o;
  return st;
}

/* ---------- optimization of the tets next to the layer ---------- */

/* Vertices within `rings` tet-edge rings of the envelope or the far field that Gmsh made
 * (index >= first_new) move; the tets touching them are optimized with the
 * shape measure, everything else fixed. */
static int optimize_band(vm_ctx *ctx, vm_mesh *o, const envelope *E, int64_t first_new,
                         int64_t nfar, const vm_fill_opts *opts, int64_t *nfree) {
  int st = VM_OK;
  *nfree = 0;
  int64_t *rp = NULL;
  int32_t *ve = NULL, *lv = NULL;
  uint8_t *ring = vm_calloc(ctx, (size_t)o->nv + 1, 1);
  uint8_t *tsel = vm_calloc(ctx, (size_t)o->ne + 1, 1);
  vm_mesh *sub = NULL;
  if (!ring || !tsel) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if ((st = vm_mesh_vertex_elements(o, &rp, &ve))) goto done;
  for (int64_t i = 0; i < 3 * E->nf; i++) ring[E->fv[i]] = 1;
  /* and next to the far field (its vertices come just before first_new):
   * the shell inside it is Gmsh's too */
  for (int64_t v = first_new - nfar; v < first_new; v++) ring[v] = 1;
  for (int r = 1; r <= opts->opt_rings; r++)
    for (int64_t v = 0; v < o->nv; v++) {
      if (ring[v] != r) continue;
      for (int64_t j = rp[v]; j < rp[v + 1]; j++) {
        int64_t e = ve[j];
        if (o->etype[e] != VM_TET) continue;
        for (int i = 0; i < 4; i++) {
          int32_t w = o->conn[o->eoff[e] + i];
          if (!ring[w]) ring[w] = (uint8_t)(r + 1);
        }
      }
    }
  lv = vm_alloc_array(ctx, (size_t)o->nv + 1, sizeof *lv);
  if (!lv) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t nsel = 0, nsv = 0;
  for (int64_t v = 0; v < o->nv; v++) lv[v] = -1;
  for (int64_t e = 0; e < o->ne; e++) {
    if (o->etype[e] != VM_TET) continue;
    const int32_t *q = o->conn + o->eoff[e];
    for (int i = 0; i < 4; i++)
      if (q[i] >= first_new && ring[q[i]] > 1) tsel[e] = 1;
    if (!tsel[e]) continue;
    nsel++;
    for (int i = 0; i < 4; i++)
      if (lv[q[i]] < 0) lv[q[i]] = (int32_t)nsv++;
  }
  if (!nsel) goto done;
  if ((st = vm_mesh_create(ctx, &sub)) || (st = vm_mesh_set_vertices(sub, nsv)) ||
      (st = vm_mesh_set_elements(sub, nsel, 4 * nsel)))
    goto done;
  for (int64_t v = 0; v < o->nv; v++) {
    if (lv[v] < 0) continue;
    memcpy(sub->xyz + 3 * lv[v], o->xyz + 3 * v, 3 * sizeof(double));
    int moves = v >= first_new && ring[v] > 1;
    sub->vflag[lv[v]] = moves ? VM_VERTEX_FREE : VM_VERTEX_FIXED;
    *nfree += moves;
  }
  int64_t k = 0;
  for (int64_t e = 0; e < o->ne; e++) {
    if (!tsel[e]) continue;
    sub->etype[k] = VM_TET;
    for (int i = 0; i < 4; i++) sub->conn[4 * k + i] = lv[o->conn[o->eoff[e] + i]];
    k++;
    sub->eoff[k] = 4 * k;
  }
  vm_volume_opts vo = vm_volume_opts_default();
  vo.measure = VM_MEASURE_SHAPE;
  vo.opt_iter = opts->opt_iter;
  vm_volume_report rep;
  int rs = vm_volume_run(ctx, sub, NULL, &vo, &rep);
  if (rs < 0) {
    st = rs;
    goto done;
  }
  if (rs != VM_OK || !rep.valid) {
    vm_log(ctx, VM_LOG_WARN, "fill: the optimization did not keep the tets valid; not applied");
    goto done;
  }
  for (int64_t v = 0; v < o->nv; v++)
    if (lv[v] >= 0 && v >= first_new && ring[v] > 1)
      memcpy(o->xyz + 3 * v, sub->xyz + 3 * lv[v], 3 * sizeof(double));
done:
  vm_mesh_destroy(&sub);
  vm_free(ctx, rp);
  vm_free(ctx, ve);
  vm_free(ctx, lv);
  vm_free(ctx, ring);
  vm_free(ctx, tsel);
  return st;
}

/* ---------- the stage ---------- */

int vm_fill_run(vm_ctx *ctx, const vm_mesh *in, const vm_fill_opts *opts, vm_mesh **out,
                vm_fill_report *report) {
  vm_fill_opts o = opts ? *opts : vm_fill_opts_default();
  vm_fill_report rep;
  memset(&rep, 0, sizeof rep);
  *out = NULL;
  double t0 = fill_now();
  if (!(o.farfield > 0) || !(o.growth > 1) || o.opt_rings < 0 || o.opt_iter < 0 || o.fv_sweeps < 0)
    return vm_error(ctx, VM_ERR_ARG,
                    "fill: farfield > 0, growth > 1, rings, iterations and sweeps >= 0 needed");
  if (in->dim != 3) return vm_error(ctx, VM_ERR_ARG, "the fill needs a 3D mesh or surface");
  envelope E;
  far_surface F;
  size_field S;
  gmsh_result R;
  memset(&F, 0, sizeof F);
  memset(&S, 0, sizeof S);
  memset(&R, 0, sizeof R);
  double *hv = NULL, *pts = NULL, *hs = NULL, *nrm = NULL;
  int32_t *vid = NULL;
  vm_mesh *res = NULL;
  sym_plane sp;
  int32_t *bed = NULL;
  int64_t nbed = 0, nshell = 0;
  int st = find_envelope(ctx, in, &E);
  if (st || (st = check_closed(ctx, in, &E, &sp, &bed, &nbed))) goto done;
  rep.sym_axis = sp.ax;
  rep.sym_value = sp.c;
  int64_t counts[VM_NTYPES];
  rep.surface_input = E.surface;
  vm_mesh_count_types(in, counts);
  rep.layer_cells = counts[VM_TET] + counts[VM_PYRAMID] + counts[VM_PRISM] + counts[VM_HEX];
  rep.env_faces = E.nf;
  /* the model: the wall's faces if named, else the envelope */
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  int32_t wall = tag_named(in, "wall");
  const vm_field *ph = vm_mesh_find_field(in, "gmsh:physical", VM_FIELD_ELEMENT);
  int any = 0;
  if (!E.surface && wall >= 0 && ph && ph->type == VM_FIELD_I32 && ph->ncomp == 1)
    for (int64_t e = 0; e < in->ne; e++) {
      if (vm_elem_dim(in->etype[e]) != 2 || ((const int32_t *)ph->data)[e] != wall) continue;
      for (int64_t j = in->eoff[e]; j < in->eoff[e + 1]; j++)
        for (int k = 0; k < 3; k++) {
          double x = in->xyz[3 * in->conn[j] + k];
          lo[k] = x < lo[k] ? x : lo[k];
          hi[k] = x > hi[k] ? x : hi[k];
        }
      any = 1;
    }
  if (!any)
    for (int64_t i = 0; i < 3 * E.nf; i++)
      for (int k = 0; k < 3; k++) {
        double x = in->xyz[3 * E.fv[i] + k];
        lo[k] = x < lo[k] ? x : lo[k];
        hi[k] = x > hi[k] ? x : hi[k];
      }
  /* (a half model's: the whole model's, its mirror image included) */
  if (sp.ax >= 0) {
    double r = fmax(fabs(hi[sp.ax] - sp.c), fabs(lo[sp.ax] - sp.c));
    lo[sp.ax] = sp.c - r;
    hi[sp.ax] = sp.c + r;
  }
  double c[3], L = 0;
  for (int k = 0; k < 3; k++) {
    c[k] = (lo[k] + hi[k]) / 2;
    if (hi[k] - lo[k] > L) L = hi[k] - lo[k];
  }
  if (sp.ax >= 0) c[sp.ax] = sp.c;
  if (!(L > 0) || !isfinite(L)) {
    st = vm_error(ctx, VM_ERR_ARG, "the model has no extent (length %g)", L);
    goto done;
  }
  double H = o.farfield * L, reach = 0;
  rep.model_length = L;
  rep.far_distance = H;
  /* sizes at the envelope's vertices: the mean length of their edges */
  vid = vm_alloc_array(ctx, (size_t)in->nv + 1, sizeof *vid);
  hv = vm_calloc(ctx, (size_t)in->nv + 1, sizeof *hv);
  double *cnt = vm_calloc(ctx, (size_t)in->nv + 1, sizeof *cnt);
  if (!vid || !hv || !cnt) {
    vm_free(ctx, cnt);
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int64_t f = 0; f < E.nf; f++)
    for (int i = 0; i < 3; i++) {
      int32_t a = E.fv[3 * f + i], b = E.fv[3 * f + (i + 1) % 3];
      double l = vm_dist3(in->xyz + 3 * a, in->xyz + 3 * b);
      hv[a] += l, hv[b] += l, cnt[a] += 1, cnt[b] += 1;
    }
  int64_t nenv = 0;
  for (int64_t v = 0; v < in->nv; v++) vid[v] = cnt[v] > 0 ? (int32_t)nenv++ : -1;
  pts = vm_alloc_array(ctx, (size_t)(3 * nenv + 3), sizeof *pts);
  hs = vm_alloc_array(ctx, (size_t)nenv + 1, sizeof *hs);
  if (!pts || !hs) {
    vm_free(ctx, cnt);
    st = VM_ERR_NOMEM;
    goto done;
  }
  rep.env_size_min = INFINITY;
  for (int64_t v = 0; v < in->nv; v++) {
    if (vid[v] < 0) continue;
    double h = hv[v] / cnt[v];
    hs[vid[v]] = h;
    memcpy(pts + 3 * vid[v], in->xyz + 3 * v, 3 * sizeof(double));
    rep.env_size_min = h < rep.env_size_min ? h : rep.env_size_min;
    rep.env_size_max = h > rep.env_size_max ? h : rep.env_size_max;
    double d = 0;
    for (int k = 0; k < 3; k++) {
      double x = fabs(in->xyz[3 * v + k] - c[k]);
      d = o.shape == VM_FAR_SPHERE ? d + x * x : (x > d ? x : d);
    }
    d = o.shape == VM_FAR_SPHERE ? sqrt(d) : d;
    reach = d > reach ? d : reach;
  }
  vm_free(ctx, cnt);
  if (!(rep.env_size_min > 0)) {
    st = vm_error(ctx, VM_ERR_FORMAT, "the envelope has an edge of length 0");
    goto done;
  }
  if (reach >= 0.9 * H) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "the far field (%s %g from the centre, %g model lengths) cuts the layer or "
                  "comes too close to it (it reaches %g): raise --farfield",
                  o.shape == VM_FAR_SPHERE ? "radius" : "half-width", H, o.farfield, reach);
    goto done;
  }
  S.slope = o.growth - 1;
  S.hmax = o.far_size > 0 ? o.far_size : INFINITY;
  S.o = &o;
  if ((st = size_build(ctx, &S, pts, hs, nenv))) goto done;
  /* the far field's triangle size: the size field at its nearest points */
  double hfar = INFINITY;
  for (int ax = 0; ax < 3; ax++)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      double x[3] = {c[0], c[1], c[2]};
      x[ax] += sgn * H;
      double h = size_at(&S, x);
      hfar = h < hfar ? h : hfar;
    }
  int n = (int)ceil(2 * H / hfar);
  n = n < 2 ? 2 : n > 400 ? 400 : n;
  if (sp.ax >= 0 && n % 2) n++; /* a row of vertices in the symmetry plane */
  rep.far_size = 2 * H / n;
  if ((st = far_build(ctx, &F, c, H, n, o.shape == VM_FAR_SPHERE, &sp))) goto done;
  nshell = F.nv;
  if (sp.ax >= 0) {
    double ts = fill_now();
    if ((st = sym_face(ctx, in, bed, nbed, &sp, &S, &F))) goto done;
    vm_log(ctx, VM_LOG_INFO,
           "fill: a half model: the symmetry plane %c = %g between the far field and the layer's "
           "%lld border edges in it, %lld triangles, %.2f s",
           "xyz"[sp.ax], sp.c, (long long)nbed, (long long)F.nsym, fill_now() - ts);
  }
  rep.far_faces = F.nf - F.nsym;
  rep.sym_faces = F.nsym;
  vm_log(ctx, VM_LOG_INFO,
         "fill: envelope %lld triangles (sizes %.3g to %.3g), far field %s at %g (%g model "
         "lengths of %g), %lld triangles of %.3g; Gmsh %s, growth %g",
         (long long)E.nf, rep.env_size_min, rep.env_size_max,
         o.shape == VM_FAR_SPHERE ? "sphere" : "box", H, o.farfield, L, (long long)F.nf,
         rep.far_size, o.algorithm == 10 ? "HXT" : "Delaunay", o.growth);
  double t1 = fill_now();
  double *q = NULL;
  int64_t nq = 0;
  nrm = vm_calloc(ctx, (size_t)(3 * nenv + 3), sizeof *nrm);
  if (!nrm) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if ((st = offset_points(ctx, in, &E, vid, hs, nenv, nrm, &q, &nq))) goto done;
  if (sp.ax >= 0) {
    /* a half model: only points well inside its side of the plane */
    int64_t kept = 0;
    for (int64_t i = 0; i < nq; i++)
      if ((q[3 * i + sp.ax] - sp.c) * sp.side > 0.5 * size_at(&S, q + 3 * i))
        memmove(q + 3 * kept++, q + 3 * i, 3 * sizeof *q);
    nq = kept;
  }
  /* a shell just inside the far field (its vertices moved in by half a
   * triangle size): without it Delaunay leaves tets with two or three faces
   * on the far field along the box's edges, and OpenFOAM's cell
   * determinant, made of a cell's interior faces only, is 0 there */
  {
    double *t = vm_realloc(ctx, q, (size_t)(3 * (nq + nshell)) * sizeof *t);
    if (!t) {
      vm_free(ctx, q);
      st = VM_ERR_NOMEM;
      goto done;
    }
    q = t;
    double f = (H - 0.5 * rep.far_size) / H;
    for (int64_t i = 0; i < nshell; i++, nq++) {
      for (int k = 0; k < 3; k++) q[3 * nq + k] = c[k] + f * (F.xyz[3 * i + k] - c[k]);
      /* (a half model's rim: moved off the symmetry plane as well) */
      if (sp.ax >= 0 && F.xyz[3 * i + sp.ax] == sp.c)
        q[3 * nq + sp.ax] = sp.c + sp.side * 0.5 * rep.far_size;
    }
  }
  vm_log(ctx, VM_LOG_INFO,
         "fill: %lld points off the envelope and %lld inside the far field embedded",
         (long long)(nq - nshell), (long long)nshell);
  /* Gmsh; if its process crashes (its boundary recovery aborts on some
   * envelopes) with the points off the envelope, once more without them,
   * then with the envelope's triangles in the reverse order (the recovery
   * depends on the order: a layer of the demo aircraft at T = 20 % it had
   * aborted on, with and without the points, meshed so); then again with
   * a point in each sliver of envelope vertices, kept only if Gmsh
   * succeeds. An error Gmsh reports (the envelope intersects itself) ends
   * the run. */
  int crashed = 0, reverse = 0;
  st = gmsh_fill_isolated(ctx, in, &E, &F, in->nv, q, nq, &S, &o, reverse, &R, &crashed);
  if (st == VM_ERR_BACKEND && crashed && nq > nshell) {
    vm_log(ctx, VM_LOG_WARN, "fill: %s; meshing again without the points off the envelope",
           vm_ctx_error(ctx));
    vm_ctx_clear_error(ctx);
    int64_t noff = nq - nshell;
    memmove(q, q + 3 * noff, (size_t)(3 * nshell) * sizeof *q);
    nq = nshell;
    st = gmsh_fill_isolated(ctx, in, &E, &F, in->nv, q, nq, &S, &o, reverse, &R, &crashed);
  }
  if (st == VM_ERR_BACKEND && crashed) {
    vm_log(ctx, VM_LOG_WARN, "fill: %s; meshing again with the envelope given in reverse order",
           vm_ctx_error(ctx));
    vm_ctx_clear_error(ctx);
    reverse = 1;
    st = gmsh_fill_isolated(ctx, in, &E, &F, in->nv, q, nq, &S, &o, reverse, &R, NULL);
  }
  if (!st) st = merge(ctx, in, &E, &F, &R, &res);
  /* passes while they leave fewer slivers (each keeps the points of the
   * ones before): a point breaks its sliver but may leave a flatter one
   * beside it (a Gmsh-meshed wing at 5 %: 2,160 slivers, then 941 flat
   * tets after one pass) */
  int64_t ns = 0, ns_prev = INT64_MAX, nseen = 0, nrep = 0;
  quad_key *seen = NULL;
  size_t *src = NULL;
  for (int pass = 0; !st && pass < FILL_SLIVER_PASSES; pass++) {
    int64_t nq0 = nq;
    if ((st = sliver_points(ctx, res, res->ne - F.nf - (int64_t)R.nt, in->nv, vid, nrm, 10, &q, &nq,
                            &ns, &seen, &nseen, &nrep, &src)) ||
        nq == nq0)
      break;
    if (ns >= ns_prev) {
      nq = nq0; /* no better than the pass before: that mesh stays */
      break;
    }
    ns_prev = ns;
    vm_log(ctx, VM_LOG_INFO,
           "fill: %lld slivers of envelope vertices (%lld of them left by a point before): "
           "meshing again with a point in each of the others",
           (long long)ns, (long long)nrep);
    gmsh_result R2;
    vm_mesh *res2 = NULL;
    int st2;
    double tp = fill_now();
    if (pass >= FILL_GMSH_PASSES) {
      int64_t nins = 0;
      st2 = gmsh_result_copy(&R, &R2);
      if (!st2)
        st2 = insert_points(ctx, &R2, (size_t)in->nv, q + 3 * nq0, src + 4 * nq0, nq - nq0, &nins);
      vm_log(ctx, VM_LOG_INFO,
             "fill: %lld of the %lld points inserted in their slivers' cavities (the others "
             "made no better tets or had no star-shaped cavity), %.2f s",
             (long long)nins, (long long)(nq - nq0), fill_now() - tp);
    } else {
      st2 = gmsh_fill_isolated(ctx, in, &E, &F, in->nv, q, nq, &S, &o, reverse, &R2, NULL);
      vm_log(ctx, VM_LOG_DEBUG, "fill: Gmsh again with %lld points, %.2f s", (long long)nq,
             fill_now() - tp);
    }
    if (!st2) st2 = merge(ctx, in, &E, &F, &R2, &res2);
    if (st2 == VM_OK) {
      vm_mesh_destroy(&res);
      gmsh_result_free(&R);
      res = res2;
      R = R2;
    } else if (st2 == VM_ERR_BACKEND) {
      vm_log(ctx, VM_LOG_WARN, "fill: %s; the mesh before is kept", vm_ctx_error(ctx));
      vm_ctx_clear_error(ctx);
      gmsh_result_free(&R2);
      break;
    } else {
      st = st2;
      gmsh_result_free(&R2);
    }
  }
  /* the slivers the points left: edge removal, then the merge again (its
   * checks failing, Gmsh's tets as they were) */
  if (!st) {
    int64_t nflip = 0;
    size_t nt0 = R.nt, *t0 = gmshMalloc(4 * (nt0 ? nt0 : 1) * sizeof *t0);
    if (!t0) st = VM_ERR_NOMEM;
    if (!st) {
      if (nt0) memcpy(t0, R.tnode, 4 * nt0 * sizeof *t0);
      st = flip_slivers(ctx, &R, (size_t)in->nv, &nflip);
    }
    vm_mesh *res2 = NULL;
    if (!st && nflip && (st = merge(ctx, in, &E, &F, &R, &res2)) == VM_ERR_BACKEND) {
      vm_log(ctx, VM_LOG_WARN, "fill: %s; the edge removal around slivers is undone",
             vm_ctx_error(ctx));
      vm_ctx_clear_error(ctx);
      gmshFree(R.tnode);
      R.tnode = t0;
      R.nt = nt0;
      t0 = NULL;
      st = VM_OK;
    } else if (!st && nflip) {
      vm_log(ctx, VM_LOG_INFO,
             "fill: %lld edges around slivers of envelope vertices removed (their rings "
             "triangulated anew)",
             (long long)nflip);
      vm_mesh_destroy(&res);
      res = res2;
    }
    gmshFree(t0);
  }
  vm_free(ctx, q);
  vm_free(ctx, seen);
  vm_free(ctx, src);
  if (st) goto done;
  rep.time_mesh = fill_now() - t1;
  if (vm_ctx_interrupted(ctx)) {
    st = vm_error(ctx, VM_ERR_INTERRUPTED, "interrupted");
    goto done;
  }
  rep.tets = (int64_t)R.nt;
  /* flat tets of four envelope vertices that stayed: the envelope comes
   * closer to itself there than a tet can bridge well (the layer's top
   * nearly touches another part of the layer); no vertex of theirs may move */
  {
    int64_t nflat = 0;
    double worst = 180, at[3] = {0, 0, 0};
    /* the fill's own tets (merge puts them after the input's cells) */
    for (int64_t e = res->ne - F.nf - (int64_t)R.nt; e < res->ne; e++) {
      if (res->etype[e] != VM_TET) continue;
      const int32_t *cv = res->conn + res->eoff[e];
      if (cv[0] >= in->nv || cv[1] >= in->nv || cv[2] >= in->nv || cv[3] >= in->nv) continue;
      const double *p[4] = {res->xyz + 3 * cv[0], res->xyz + 3 * cv[1], res->xyz + 3 * cv[2],
                            res->xyz + 3 * cv[3]};
      double lo, hi;
      tet_angles(p, &lo, &hi);
      lo *= 180 / PI;
      if (lo >= FILL_FLAT_DEG) continue;
      nflat++;
      if (lo < worst) {
        worst = lo;
        for (int k = 0; k < 3; k++) at[k] = (p[0][k] + p[1][k] + p[2][k] + p[3][k]) / 4;
      }
    }
    rep.flat_env_tets = nflat;
    if (nflat)
      vm_log(ctx, VM_LOG_WARN,
             "fill: %lld tets of four envelope vertices are flat (min dihedral < 5 deg, worst "
             "%.3g deg at %.4g %.4g %.4g): the envelope comes closer to itself there than a tet "
             "can bridge; no vertex of theirs may move (a thinner layer there would help)",
             (long long)nflat, worst, at[0], at[1], at[2]);
  }
  rep.new_vertices = res->nv - in->nv;
  int64_t e0 = res->ne - F.nf - (int64_t)R.nt; /* the fill's first tet */
  if ((st = tet_quality_from(ctx, res, e0, &rep.before))) goto done;
  vm_log(ctx, VM_LOG_INFO,
         "fill: %lld tets, %lld new vertices in %.2f s; tets: min dihedral %.2f deg, min "
         "scaled Jacobian %.3f; volume ratio across the envelope %.3g, between tets %.3g",
         (long long)rep.tets, (long long)rep.new_vertices, rep.time_mesh, rep.before.min_dihedral,
         rep.before.sj_min, rep.before.vol_ratio_env, rep.before.vol_ratio_tets);
  rep.after = rep.before;
  if (o.opt_iter > 0 && o.opt_rings > 0) {
    double t2 = fill_now();
    if ((st = optimize_band(ctx, res, &E, in->nv + F.nv, F.nv, &o, &rep.opt_free))) goto done;
    rep.time_opt = fill_now() - t2;
    if ((st = tet_quality_from(ctx, res, e0, &rep.after))) goto done;
    vm_log(ctx, VM_LOG_INFO,
           "fill: optimized %lld vertices within %d rings of the envelope in %.2f s: min "
           "dihedral %.2f deg, min scaled Jacobian %.3f; volume ratio across the envelope %.3g, "
           "between tets %.3g",
           (long long)rep.opt_free, o.opt_rings, rep.time_opt, rep.after.min_dihedral,
           rep.after.sj_min, rep.after.vol_ratio_env, rep.after.vol_ratio_tets);
  }
  {
    /* with no sweep, the figures alone (before = after) */
    double t3 = fill_now();
    if ((st = vm_fill_fv_relief(ctx, res, e0, in->nv + F.nv, o.fv_sweeps, &rep.fv_before,
                                &rep.fv_after, &rep.fv_moved)))
      goto done;
    /* what moving vertices left: flips, then the relief again around them */
    const vm_fill_fv_figures *b = &rep.fv_after;
    if (o.fv_sweeps > 0 && (b->det_under || b->nonortho_over70 || b->skew_over4 ||
                            b->weight_under || b->volratio_under)) {
      double t4 = fill_now();
      int64_t moved = 0, ntet = 0;
      if ((st = fill_fv_flips_relief(ctx, res, e0, in->nv + F.nv, o.fv_sweeps, &rep.fv_flips,
                                     &rep.fv_after, &moved)))
        goto done;
      for (int64_t e = e0; e < res->ne; e++) ntet += res->etype[e] == VM_TET;
      rep.fv_moved += moved;
      rep.tets = ntet;
      rep.new_vertices = res->nv - in->nv;
      vm_log(ctx, VM_LOG_DEBUG, "fill: relief %.2f s, flips and the relief after them %.2f s",
             t4 - t3, fill_now() - t4);
    }
    rep.time_fv = fill_now() - t3;
    const vm_fill_fv_figures *a = &rep.fv_before;
    vm_log(ctx, VM_LOG_INFO,
           "fill: finite-volume relief moved %lld vertices and made %lld flips in %.2f s; faces "
           "beyond 70 degrees "
           "%lld -> %lld (largest %.1f -> %.1f), skewness > 4 %lld -> %lld (largest %.2f -> "
           "%.2f), weights < 0.05 %lld -> %lld, volume ratios < 0.01 %lld -> %lld, "
           "determinants < 0.001 %lld -> %lld",
           (long long)rep.fv_moved, (long long)rep.fv_flips, rep.time_fv,
           (long long)a->nonortho_over70, (long long)b->nonortho_over70, a->nonortho_max,
           b->nonortho_max, (long long)a->skew_over4, (long long)b->skew_over4, a->skew_max,
           b->skew_max, (long long)a->weight_under, (long long)b->weight_under,
           (long long)a->volratio_under, (long long)b->volratio_under, (long long)a->det_under,
           (long long)b->det_under);
    if ((st = tet_quality_from(ctx, res, e0, &rep.after))) goto done;
  }
  rep.time_total = fill_now() - t0;
  *out = res;
  res = NULL;
done:
  vm_mesh_destroy(&res);
  gmsh_result_free(&R);
  vm_free(ctx, bed);
  far_free(ctx, &F);
  size_free(ctx, &S);
  envelope_free(ctx, &E);
  vm_free(ctx, hv);
  vm_free(ctx, pts);
  vm_free(ctx, hs);
  vm_free(ctx, nrm);
  vm_free(ctx, vid);
  if (report) *report = rep;
  return st;
}
