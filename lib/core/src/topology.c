/* lib/core/src/topology.c: boundary faces by sorted face keys, boundary marking,
 * vertex-to-element adjacency. */
#include "varmesh/topology.h"

#include <stdlib.h>
#include <string.h>

typedef struct {
  int32_t key[4]; /* sorted vertex ids, -1 padded */
  int32_t elem;
  int8_t local; /* face index within the element */
} face_rec;

static int cmp_face(const void *a, const void *b) {
  const face_rec *x = a, *y = b;
  for (int i = 0; i < 4; i++)
    if (x->key[i] != y->key[i]) return x->key[i] < y->key[i] ? -1 : 1;
  if (x->elem != y->elem) return x->elem < y->elem ? -1 : 1;
  return x->local - y->local;
}

static void sort4(int32_t *k, int n) {
  for (int i = 1; i < n; i++)
    for (int j = i; j > 0 && k[j - 1] > k[j]; j--) {
      int32_t t = k[j];
      k[j] = k[j - 1];
      k[j - 1] = t;
    }
}

int vm_mesh_boundary(const vm_mesh *m, int64_t *nface, int32_t **fverts, uint8_t **fnv,
                     int32_t **felem, int64_t *nonmanifold) {
  vm_ctx *ctx = m->ctx;
  int64_t counts[VM_NTYPES];
  int top = vm_mesh_count_types(m, counts);
  if (nface) *nface = 0;
  if (fverts) *fverts = NULL;
  if (fnv) *fnv = NULL;
  if (felem) *felem = NULL;
  if (nonmanifold) *nonmanifold = 0;
  int64_t nrec = 0;
  int faces[6][4], nfv[6];
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == top) nrec += vm_elem_faces(m->etype[e], faces, nfv);
  face_rec *rec = vm_alloc_array(ctx, (size_t)(nrec ? nrec : 1), sizeof *rec);
  if (!rec) return VM_ERR_NOMEM;
  int64_t r = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != top) continue;
    const int32_t *cv = m->conn + m->eoff[e];
    int nf = vm_elem_faces(m->etype[e], faces, nfv);
    for (int f = 0; f < nf; f++, r++) {
      for (int i = 0; i < 4; i++) rec[r].key[i] = i < nfv[f] ? cv[faces[f][i]] : INT32_MAX;
      sort4(rec[r].key, nfv[f]);
      rec[r].elem = (int32_t)e;
      rec[r].local = (int8_t)f;
    }
  }
  qsort(rec, (size_t)nrec, sizeof *rec, cmp_face);
  /* count singletons */
  int64_t nb = 0, nm = 0;
  for (int64_t i = 0; i < nrec;) {
    int64_t j = i + 1;
    while (j < nrec && !memcmp(rec[j].key, rec[i].key, sizeof rec[i].key)) j++;
    if (j - i == 1) nb++;
    if (j - i > 2) nm++;
    i = j;
  }
  int32_t *fv = fverts ? vm_alloc_array(ctx, (size_t)(nb ? nb : 1) * 4, sizeof *fv) : NULL;
  uint8_t *fn = fnv ? vm_alloc_array(ctx, (size_t)(nb ? nb : 1), 1) : NULL;
  int32_t *fe = felem ? vm_alloc_array(ctx, (size_t)(nb ? nb : 1), sizeof *fe) : NULL;
  if ((fverts && !fv) || (fnv && !fn) || (felem && !fe)) {
    vm_free(ctx, fv);
    vm_free(ctx, fn);
    vm_free(ctx, fe);
    vm_free(ctx, rec);
    return VM_ERR_NOMEM;
  }
  int64_t k = 0;
  for (int64_t i = 0; i < nrec;) {
    int64_t j = i + 1;
    while (j < nrec && !memcmp(rec[j].key, rec[i].key, sizeof rec[i].key)) j++;
    if (j - i == 1) {
      int32_t e = rec[i].elem;
      int nf = vm_elem_faces(m->etype[e], faces, nfv);
      (void)nf;
      int f = rec[i].local;
      const int32_t *cv = m->conn + m->eoff[e];
      if (fv)
        for (int q = 0; q < 4; q++) fv[4 * k + q] = q < nfv[f] ? cv[faces[f][q]] : -1;
      if (fn) fn[k] = (uint8_t)nfv[f];
      if (fe) fe[k] = e;
      k++;
    }
    i = j;
  }
  vm_free(ctx, rec);
  if (nface) *nface = nb;
  if (fverts) *fverts = fv;
  if (fnv) *fnv = fn;
  if (felem) *felem = fe;
  if (nonmanifold) *nonmanifold = nm;
  return VM_OK;
}

int vm_mesh_mark_boundary(vm_mesh *m, int flag, int64_t *count) {
  int64_t nb;
  int32_t *fv;
  uint8_t *fn;
  int st = vm_mesh_boundary(m, &nb, &fv, &fn, NULL, NULL);
  if (st) return st;
  int64_t c = 0;
  uint8_t *seen = vm_calloc(m->ctx, (size_t)(m->nv ? m->nv : 1), 1);
  if (!seen) {
    vm_free(m->ctx, fv);
    vm_free(m->ctx, fn);
    return VM_ERR_NOMEM;
  }
  for (int64_t f = 0; f < nb; f++)
    for (int q = 0; q < fn[f]; q++) {
      int32_t v = fv[4 * f + q];
      if (seen[v]) continue;
      seen[v] = 1;
      c++;
      if (m->vflag[v] != VM_VERTEX_FIXED) m->vflag[v] = (uint8_t)flag;
    }
  vm_free(m->ctx, seen);
  vm_free(m->ctx, fv);
  vm_free(m->ctx, fn);
  if (count) *count = c;
  return VM_OK;
}

int vm_mesh_vertex_elements(const vm_mesh *m, int64_t **rowptr, int32_t **elems) {
  vm_ctx *ctx = m->ctx;
  int64_t *rp = vm_calloc(ctx, (size_t)m->nv + 1, sizeof *rp);
  int32_t *el = vm_alloc_array(ctx, (size_t)(m->eoff[m->ne] ? m->eoff[m->ne] : 1), sizeof *el);
  if (!rp || !el) {
    vm_free(ctx, rp);
    vm_free(ctx, el);
    return VM_ERR_NOMEM;
  }
  for (int64_t k = 0; k < m->eoff[m->ne]; k++) rp[m->conn[k] + 1]++;
  for (int64_t v = 0; v < m->nv; v++) rp[v + 1] += rp[v];
  int64_t *fill = vm_alloc_array(ctx, (size_t)(m->nv ? m->nv : 1), sizeof *fill);
  if (!fill) {
    vm_free(ctx, rp);
    vm_free(ctx, el);
    return VM_ERR_NOMEM;
  }
  memcpy(fill, rp, (size_t)m->nv * sizeof *fill);
  for (int64_t e = 0; e < m->ne; e++)
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) {
      int32_t v = m->conn[k];
      /* an element listing a vertex twice appears once */
      if (fill[v] > rp[v] && el[fill[v] - 1] == (int32_t)e) continue;
      el[fill[v]++] = (int32_t)e;
    }
  /* compact away duplicates' unused slots */
  int64_t w = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int64_t b = rp[v];
    rp[v] = w;
    for (int64_t k = b; k < fill[v]; k++) el[w++] = el[k];
  }
  rp[m->nv] = w;
  vm_free(ctx, fill);
  *rowptr = rp;
  *elems = el;
  return VM_OK;
}
