/* lib/core/src/surface_mesh.c: triangles, edges and one-rings of a surface
 * mesh, shared by curvature, feature detection and adaptation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/surface_mesh.h"
#include "vec3.h"

int vm_surf_tris_build(vm_ctx *ctx, const vm_mesh *m, vm_surf_tris *t) {
  memset(t, 0, sizeof *t);
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++)
    n += m->etype[e] == VM_TRI ? 1 : m->etype[e] == VM_QUAD ? 4 : 0;
  size_t cap = n > 0 ? (size_t)n : 1;
  t->tri = vm_alloc_array(ctx, cap * 3, sizeof *t->tri);
  t->w = vm_alloc_array(ctx, cap, sizeof *t->w);
  t->elem = vm_alloc_array(ctx, cap, sizeof *t->elem);
  if (!t->tri || !t->w || !t->elem) {
    vm_surf_tris_free(ctx, t);
    return VM_ERR_NOMEM;
  }
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    if (m->etype[e] == VM_TRI) {
      memcpy(t->tri + 3 * k, c, 3 * sizeof *c);
      t->w[k] = 1.0;
      t->elem[k++] = (int32_t)e;
    } else if (m->etype[e] == VM_QUAD) {
      for (int a = 0; a < 4; a++) {
        t->tri[3 * k] = c[(a + 3) % 4];
        t->tri[3 * k + 1] = c[a];
        t->tri[3 * k + 2] = c[(a + 1) % 4];
        t->w[k] = 0.5;
        t->elem[k++] = (int32_t)e;
      }
    }
  }
  t->nt = k;
  return VM_OK;
}

void vm_surf_tris_free(vm_ctx *ctx, vm_surf_tris *t) {
  vm_free(ctx, t->tri);
  vm_free(ctx, t->w);
  vm_free(ctx, t->elem);
  memset(t, 0, sizeof *t);
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

int vm_surf_edges_build(vm_ctx *ctx, const vm_mesh *m, vm_surf_edges *E) {
  memset(E, 0, sizeof *E);
  int64_t nside = 0;
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 2) nside += vm_elem_nverts(m->etype[e]);
  size_t cap = nside > 0 ? (size_t)nside : 1;
  uint64_t *key = vm_alloc_array(ctx, cap, sizeof *key);
  if (!key) return VM_ERR_NOMEM;
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    int nv = vm_elem_nverts(m->etype[e]);
    const int32_t *c = m->conn + m->eoff[e];
    for (int a = 0; a < nv; a++) {
      uint32_t p = (uint32_t)c[a], q = (uint32_t)c[(a + 1) % nv];
      if (p > q) {
        uint32_t s = p;
        p = q;
        q = s;
      }
      key[k++] = (uint64_t)p << 32 | q;
    }
  }
  qsort(key, (size_t)nside, sizeof *key, cmp_u64);
  int64_t nu = 0;
  for (int64_t i = 0; i < nside; i++)
    if (i == 0 || key[i] != key[i - 1]) nu++;
  size_t ucap = nu > 0 ? (size_t)nu : 1;
  size_t vcap = m->nv > 0 ? (size_t)m->nv : 1;
  E->ev = vm_alloc_array(ctx, ucap * 2, sizeof *E->ev);
  E->nface = vm_calloc(ctx, ucap, sizeof *E->nface);
  E->rowptr = vm_calloc(ctx, vcap + 1, sizeof *E->rowptr);
  E->adj = vm_alloc_array(ctx, ucap * 2, sizeof *E->adj);
  E->onbnd = vm_calloc(ctx, vcap, sizeof *E->onbnd);
  int64_t *fill = vm_calloc(ctx, vcap, sizeof *fill);
  if (!E->ev || !E->nface || !E->rowptr || !E->adj || !E->onbnd || !fill) {
    vm_free(ctx, key);
    vm_free(ctx, fill);
    vm_surf_edges_free(ctx, E);
    return VM_ERR_NOMEM;
  }
  int64_t u = -1;
  for (int64_t i = 0; i < nside; i++) {
    if (i == 0 || key[i] != key[i - 1]) {
      u++;
      E->ev[2 * u] = (int32_t)(key[i] >> 32);
      E->ev[2 * u + 1] = (int32_t)(key[i] & 0xffffffffu);
    }
    E->nface[u]++;
  }
  E->ne = nu;
  vm_free(ctx, key);
  for (int64_t e = 0; e < nu; e++) {
    int32_t a = E->ev[2 * e], b = E->ev[2 * e + 1];
    E->rowptr[a + 1]++;
    E->rowptr[b + 1]++;
    if (E->nface[e] != 2) {
      E->onbnd[a] = E->onbnd[b] = 1;
      if (E->nface[e] == 1)
        E->nboundary++;
      else
        E->nnonmanifold++;
    }
  }
  for (int64_t v = 0; v < m->nv; v++) E->rowptr[v + 1] += E->rowptr[v];
  for (int64_t e = 0; e < nu; e++) {
    int32_t a = E->ev[2 * e], b = E->ev[2 * e + 1];
    E->adj[E->rowptr[a] + fill[a]++] = b;
    E->adj[E->rowptr[b] + fill[b]++] = a;
  }
  vm_free(ctx, fill);
  /* rows are short (the valence): insertion sort makes them ascending */
  for (int64_t v = 0; v < m->nv; v++) {
    int32_t *r = E->adj + E->rowptr[v];
    int64_t n = E->rowptr[v + 1] - E->rowptr[v];
    for (int64_t i = 1; i < n; i++) {
      int32_t x = r[i];
      int64_t j = i - 1;
      while (j >= 0 && r[j] > x) {
        r[j + 1] = r[j];
        j--;
      }
      r[j + 1] = x;
    }
  }
  return VM_OK;
}

void vm_surf_edges_free(vm_ctx *ctx, vm_surf_edges *E) {
  vm_free(ctx, E->ev);
  vm_free(ctx, E->nface);
  vm_free(ctx, E->rowptr);
  vm_free(ctx, E->adj);
  vm_free(ctx, E->onbnd);
  memset(E, 0, sizeof *E);
}

int64_t vm_surf_edge_find(const vm_surf_edges *E, int32_t a, int32_t b) {
  if (a > b) {
    int32_t s = a;
    a = b;
    b = s;
  }
  int64_t lo = 0, hi = E->ne;
  while (lo < hi) {
    int64_t mid = lo + (hi - lo) / 2;
    int32_t ma = E->ev[2 * mid], mb = E->ev[2 * mid + 1];
    if (ma < a || (ma == a && mb < b))
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo < E->ne && E->ev[2 * lo] == a && E->ev[2 * lo + 1] == b) return lo;
  return -1;
}

/* the least n_i . e over the k vectors */
static double least_seen(const double *n, int k, const double e[3]) {
  double m = INFINITY;
  for (int i = 0; i < k; i++) {
    double d = vm_dot3(n + 3 * i, e);
    if (d < m) m = d;
  }
  return m;
}

/* p as a candidate direction: kept in best/dir if it sees the n_i better */
static void try_direction(const double *n, int k, const double p[3], double *best, double dir[3]) {
  double e[3] = {p[0], p[1], p[2]};
  if (!(vm_normalize3(e) > 1e-300)) return;
  double m = least_seen(n, k, e);
  if (m > *best) {
    *best = m;
    memcpy(dir, e, sizeof e);
  }
}

double vm_visible_direction(const double *n, int k, double dir[3]) {
  double e[3] = {0, 0, 1}, best = -INFINITY;
  if (k <= 0) {
    if (dir) memcpy(dir, e, sizeof e);
    return -1;
  }
  for (int i = 0; i < k; i++) {
    const double *a = n + 3 * i;
    try_direction(n, k, a, &best, e);
    for (int j = i + 1; j < k; j++) {
      const double *b = n + 3 * j;
      double u[3], p[3];
      vm_sub3(b, a, u);
      double uu = vm_dot3(u, u);
      if (!(uu > 1e-24)) continue;
      double t = -vm_dot3(a, u) / uu;
      if (t > 0 && t < 1) {
        for (int r = 0; r < 3; r++) p[r] = a[r] + t * u[r];
        try_direction(n, k, p, &best, e);
      }
      for (int l = j + 1; l < k; l++) {
        double v[3];
        vm_sub3(n + 3 * l, a, v);
        double uv = vm_dot3(u, v), vv = vm_dot3(v, v), det = uu * vv - uv * uv;
        if (!(det > 1e-12 * uu * vv)) continue;
        double au = -vm_dot3(a, u), av = -vm_dot3(a, v);
        double s = (au * vv - av * uv) / det, w = (av * uu - au * uv) / det;
        if (!(s > 0 && w > 0 && s + w < 1)) continue;
        for (int r = 0; r < 3; r++) p[r] = a[r] + s * u[r] + w * v[r];
        try_direction(n, k, p, &best, e);
      }
    }
  }
  if (dir) memcpy(dir, e, sizeof e);
  return best;
}
