/* lib/geom/src/trimesh.c: the triangle surface being edited that the
 * sliver removal (cleanup.c) and the graded remeshing (graded.c) share:
 * half-edge walks, the manifold check, the edited mesh written back. */
#include <stdlib.h>
#include <string.h>

#include "trimesh_private.h"

int vm_tm_keys(vm_tm *t, int64_t f, int add) {
  const int32_t *v = t->tri + 3 * f;
  int dup = 0;
  for (int i = 0; i < 3; i++) {
    uint64_t k = dkey(v[i], v[(i + 1) % 3]);
    if (add) {
      dup += hm_get(&t->he, k) >= 0;
      hm_put(&t->he, k, 3 * f + i);
    } else
      hm_del(&t->he, k);
  }
  return dup;
}

int vm_tm_flip(vm_tm *t, int32_t a, int32_t b, int32_t cd[2]) {
  int64_t h = vm_tm_he(t, a, b), w = vm_tm_he(t, b, a);
  int64_t f0 = h / 3, f1 = w / 3;
  int32_t c = t->tri[3 * f0 + (h % 3 + 2) % 3], d = t->tri[3 * f1 + (w % 3 + 2) % 3];
  vm_tm_keys(t, f0, 0);
  vm_tm_keys(t, f1, 0);
  int32_t *t0 = t->tri + 3 * f0, *t1 = t->tri + 3 * f1;
  t0[0] = a, t0[1] = d, t0[2] = c;
  t1[0] = d, t1[1] = b, t1[2] = c;
  int dup = vm_tm_keys(t, f0, 1) + vm_tm_keys(t, f1, 1);
  t->vface[a] = (int32_t)f0;
  t->vface[b] = (int32_t)f1;
  t->vface[c] = (int32_t)f0;
  t->vface[d] = (int32_t)f1;
  cd[0] = c;
  cd[1] = d;
  return dup;
}

int vm_tm_collapse(vm_tm *t, uint8_t *fdead, const int64_t *fu, int nu, int32_t u, int32_t w) {
  /* a border edge (u, w) has one face */
  int64_t hu = vm_tm_he(t, u, w), hw = vm_tm_he(t, w, u);
  int64_t f0 = hu >= 0 ? hu / 3 : -1, f1 = hw >= 0 ? hw / 3 : -1;
  for (int i = 0; i < nu; i++) vm_tm_keys(t, fu[i], 0);
  if (f0 >= 0) fdead[f0] = 1;
  if (f1 >= 0) fdead[f1] = 1;
  int dup = 0;
  for (int i = 0; i < nu; i++) {
    int64_t g = fu[i];
    if (g == f0 || g == f1) continue;
    int32_t *x = t->tri + 3 * g;
    x[vm_tm_index(x, u)] = w;
    dup += vm_tm_keys(t, g, 1);
    for (int j = 0; j < 3; j++) t->vface[x[j]] = (int32_t)g;
  }
  return dup;
}

int vm_tm_flip_check(const vm_tm *t, const double *x, int32_t a, int32_t b, double min_cos,
                     int32_t cd[2], double *dev, double *lmax) {
  int64_t h = vm_tm_he(t, a, b), w = vm_tm_he(t, b, a);
  if (h < 0 || w < 0) return 0;
  int32_t c = t->tri[3 * (h / 3) + (h % 3 + 2) % 3], d = t->tri[3 * (w / 3) + (w % 3 + 2) % 3];
  if (c == d || vm_tm_he(t, c, d) >= 0 || vm_tm_he(t, d, c) >= 0) return 0;
  double n0[3], n1[3], m0[3], m1[3], ns[3];
  tri_normal(x, a, b, c, n0);
  tri_normal(x, b, a, d, n1);
  tri_normal(x, a, d, c, m0);
  tri_normal(x, d, b, c, m1);
  vm_normalize3(n0);
  vm_normalize3(n1);
  for (int r = 0; r < 3; r++) ns[r] = n0[r] + n1[r];
  if (cos_between(m0, m1) < min_cos || cos_between(m0, ns) < min_cos ||
      cos_between(m1, ns) < min_cos)
    return 0;
  /* how far the surface moves: the distance between the lines ab and cd */
  double ab[3], dc[3], ca[3], nn[3];
  vm_sub3(x + 3 * (int64_t)b, x + 3 * (int64_t)a, ab);
  vm_sub3(x + 3 * (int64_t)d, x + 3 * (int64_t)c, dc);
  vm_sub3(x + 3 * (int64_t)c, x + 3 * (int64_t)a, ca);
  vm_cross3(ab, dc, nn);
  double ln = vm_norm3(nn);
  if (!(ln > 0)) return 0;
  double lab = vm_norm3(ab), lcd = vm_norm3(dc);
  *dev = fabs(vm_dot3(ca, nn)) / ln;
  *lmax = lab > lcd ? lab : lcd;
  cd[0] = c;
  cd[1] = d;
  return 1;
}

int vm_tm_ring(const vm_tm *t, int32_t v, int64_t *out, int max) {
  int n = 0;
  int64_t f0 = t->vface[v], f = f0;
  if (f0 < 0) return 0;
  for (;;) {
    if (n == max) return -1;
    out[n++] = f;
    const int32_t *x = t->tri + 3 * f;
    int32_t w = x[(vm_tm_index(x, v) + 2) % 3];
    int64_t h = vm_tm_he(t, v, w);
    if (h < 0) break; /* a border: walk the other way below */
    f = h / 3;
    if (f == f0) return n;
  }
  f = f0;
  for (;;) {
    const int32_t *x = t->tri + 3 * f;
    int32_t u = x[(vm_tm_index(x, v) + 1) % 3];
    int64_t h = vm_tm_he(t, u, v);
    if (h < 0) return n;
    f = h / 3;
    if (n == max) return -1;
    out[n++] = f;
  }
}

int vm_tm_neighbours(const vm_tm *t, int32_t v, const int64_t *fs, int n, int32_t *out) {
  int k = 0;
  for (int i = 0; i < n; i++) {
    const int32_t *x = t->tri + 3 * fs[i];
    for (int j = 0; j < 3; j++)
      if (x[j] != v && !vm_tm_contains(out, k, x[j])) out[k++] = x[j];
  }
  return k;
}

int vm_tm_check_manifold(vm_ctx *ctx, const vm_tm *t, int64_t nv, int64_t nf, const double *xyz,
                         int max, uint8_t *big, const char *who) {
  int32_t *deg = vm_calloc(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *deg);
  int64_t *fs = vm_alloc_array(ctx, (size_t)max, sizeof *fs);
  if (!deg || !fs) {
    vm_free(ctx, deg);
    vm_free(ctx, fs);
    return VM_ERR_NOMEM;
  }
  for (int64_t e = 0; e < 3 * nf; e++) deg[t->tri[e]]++;
  int64_t bad = -1;
  for (int64_t v = 0; v < nv && bad < 0; v++) {
    if (deg[v] == 0) continue;
    int n = vm_tm_ring(t, (int32_t)v, fs, max);
    if (n < 0)
      big[v] = 1;
    else if (n != deg[v])
      bad = v;
  }
  vm_free(ctx, deg);
  vm_free(ctx, fs);
  if (bad < 0) return VM_OK;
  const double *p = xyz + 3 * bad;
  return vm_error(ctx, VM_ERR_ARG,
                  "%s: vertex %lld at (%g, %g, %g) is not manifold (its triangles do not form "
                  "one fan)",
                  who, (long long)bad, p[0], p[1], p[2]);
}

int vm_tm_output(vm_ctx *ctx, vm_mesh *m, const double *x, int64_t nv, const uint8_t *vdead,
                 const vm_tm *t, int64_t nf, const uint8_t *fdead, int keep_elem, const hmap *fe,
                 vm_surface_features *f, const char *who) {
  int st = VM_OK;
  vm_mesh *n = NULL;
  int32_t *idx = vm_alloc_array(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *idx);
  int32_t *fev = NULL;
  uint8_t *corner = NULL;
  if (!idx) return VM_ERR_NOMEM;
  int64_t nk = 0, fk = 0;
  for (int64_t v = 0; v < nv; v++) idx[v] = vdead[v] ? -1 : (int32_t)nk++;
  for (int64_t e = 0; e < nf; e++) fk += !fdead[e];
  if ((st = vm_mesh_create(ctx, &n))) goto done;
  n->dim = m->dim;
  if ((st = vm_mesh_set_vertices(n, nk)) || (st = vm_mesh_set_elements(n, fk, 3 * fk))) goto done;
  for (int64_t v = 0; v < nv; v++) {
    if (idx[v] < 0) continue;
    memcpy(n->xyz + 3 * (int64_t)idx[v], x + 3 * v, 3 * sizeof *x);
    n->vflag[idx[v]] = v < m->nv ? m->vflag[v] : 0;
    n->vsurf[idx[v]] = v < m->nv ? m->vsurf[v] : 0;
  }
  fk = 0;
  for (int64_t e = 0; e < nf; e++) {
    if (fdead[e]) continue;
    n->etype[fk] = VM_TRI;
    n->eoff[fk + 1] = n->eoff[fk] + 3;
    for (int i = 0; i < 3; i++) n->conn[3 * fk + i] = idx[t->tri[3 * e + i]];
    fk++;
  }
  for (int i = 0; i < m->nattr; i++)
    if ((st = vm_mesh_set_attr(n, m->attrs[i].key, m->attrs[i].value))) goto done;
  int dropped = 0;
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *src = &m->fields[i];
    int vert = src->location == VM_FIELD_VERTEX;
    if (!vert && !keep_elem) {
      dropped++;
      continue;
    }
    vm_field *dst = NULL;
    if ((st = vm_mesh_add_field(n, src->name, src->location, src->type, src->ncomp, &dst)))
      goto done;
    size_t sz = (size_t)src->ncomp * (src->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
    int64_t cnt = vert ? nv : nf, j = 0;
    for (int64_t k = 0; k < cnt; k++) {
      if (vert ? vdead[k] : fdead[k]) continue;
      if (k < (vert ? m->nv : m->ne))
        memcpy((char *)dst->data + (size_t)j * sz, (const char *)src->data + (size_t)k * sz, sz);
      else
        memset((char *)dst->data + (size_t)j * sz, 0, sz);
      j++;
    }
  }
  if (dropped)
    vm_log(ctx, VM_LOG_WARN, "%s: %d element fields dropped (the triangles are new)", who, dropped);
  {
    /* the new features: the feature edges left, the corners left */
    int64_t nfe = 0, cap = 0;
    for (size_t s = 0; s <= fe->mask; s++) cap += fe->key[s] != HM_EMPTY && fe->key[s] != HM_TOMB;
    fev = vm_alloc_array(ctx, 2 * (size_t)(cap + 1), sizeof *fev);
    corner = vm_calloc(ctx, (size_t)(nk > 0 ? nk : 1), 1);
    if (!fev || !corner) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    for (size_t s = 0; s <= fe->mask; s++) {
      uint64_t k = fe->key[s];
      if (k == HM_EMPTY || k == HM_TOMB) continue;
      int32_t a = (int32_t)(k >> 32), b = (int32_t)(k & 0xffffffffu);
      if (idx[a] < 0 || idx[b] < 0) continue;
      fev[2 * nfe] = idx[a];
      fev[2 * nfe + 1] = idx[b];
      nfe++;
    }
    for (int64_t v = 0; v < m->nv && v < nv; v++)
      if (idx[v] >= 0 && f->vclass[v] == VM_FEATURE_CORNER) corner[idx[v]] = 1;
    vm_surface_features nfeat;
    if ((st = vm_surface_features_from_edges(n, nfe, fev, corner, 180, &nfeat))) goto done;
    vm_surface_features_free(ctx, f);
    *f = nfeat;
  }
  {
    vm_mesh tmp = *m;
    *m = *n;
    *n = tmp;
  }
done:
  vm_free(ctx, fev);
  vm_free(ctx, corner);
  vm_free(ctx, idx);
  vm_mesh_destroy(&n);
  return st;
}
