/* lib/geom/src/trimesh_private.h: what the triangle-surface operations of
 * lib/geom share (sliver removal in cleanup.c, graded remeshing in
 * graded.c): a hash map from 64-bit keys (directed or undirected edges) to
 * int64 values, and angles and normals of triangles given by vertex
 * indices into a coordinate array. */
#ifndef VARMESH_TRIMESH_PRIVATE_H
#define VARMESH_TRIMESH_PRIVATE_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "varmesh/ctx.h"
#include "varmesh/features.h"
#include "varmesh/mesh.h"
#include "vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- a hash map from 64-bit keys to int64 values (open addressing) ---- */

#define HM_EMPTY UINT64_MAX
#define HM_TOMB (UINT64_MAX - 1)

typedef struct {
  uint64_t *key;
  int64_t *val;
  size_t mask;
  size_t used; /* slots not empty (keys and tombstones) */
} hmap;

static inline size_t hm_hash(uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  k *= 0xc4ceb9fe1a85ec53ULL;
  k ^= k >> 33;
  return (size_t)k;
}

static inline int hm_init(vm_ctx *ctx, hmap *h, size_t n) {
  size_t cap = 64;
  while (cap < 4 * n) cap <<= 1;
  h->key = vm_alloc_array(ctx, cap, sizeof *h->key);
  h->val = vm_alloc_array(ctx, cap, sizeof *h->val);
  h->mask = cap - 1;
  h->used = 0;
  if (!h->key || !h->val) return VM_ERR_NOMEM;
  for (size_t i = 0; i < cap; i++) h->key[i] = HM_EMPTY;
  return VM_OK;
}

static inline void hm_free(vm_ctx *ctx, hmap *h) {
  vm_free(ctx, h->key);
  vm_free(ctx, h->val);
  memset(h, 0, sizeof *h);
}

static inline int64_t hm_get(const hmap *h, uint64_t k) {
  for (size_t i = hm_hash(k) & h->mask;; i = (i + 1) & h->mask) {
    if (h->key[i] == HM_EMPTY) return -1;
    if (h->key[i] == k) return h->val[i];
  }
}

static inline void hm_put(hmap *h, uint64_t k, int64_t v) {
  size_t tomb = SIZE_MAX;
  for (size_t i = hm_hash(k) & h->mask;; i = (i + 1) & h->mask) {
    if (h->key[i] == k) {
      h->val[i] = v;
      return;
    }
    if (h->key[i] == HM_TOMB && tomb == SIZE_MAX) tomb = i;
    if (h->key[i] == HM_EMPTY) {
      size_t at = tomb != SIZE_MAX ? tomb : i;
      if (at == i) h->used++;
      h->key[at] = k;
      h->val[at] = v;
      return;
    }
  }
}

static inline void hm_del(hmap *h, uint64_t k) {
  for (size_t i = hm_hash(k) & h->mask;; i = (i + 1) & h->mask) {
    if (h->key[i] == HM_EMPTY) return;
    if (h->key[i] == k) {
      h->key[i] = HM_TOMB;
      return;
    }
  }
}

static inline uint64_t dkey(int32_t a, int32_t b) {
  return (uint64_t)(uint32_t)a << 32 | (uint32_t)b;
}
static inline uint64_t ukey(int32_t a, int32_t b) { return a < b ? dkey(a, b) : dkey(b, a); }

/* ---- angles ---- */

static inline double corner_deg(const double *p, const double *q, const double *r) {
  double u[3], w[3], c[3];
  vm_sub3(q, p, u);
  vm_sub3(r, p, w);
  vm_cross3(u, w, c);
  return atan2(vm_norm3(c), vm_dot3(u, w)) * (180.0 / M_PI);
}

static inline double tri_min_deg(const double *x, int32_t a, int32_t b, int32_t c) {
  const double *p = x + 3 * (int64_t)a, *q = x + 3 * (int64_t)b, *r = x + 3 * (int64_t)c;
  double m = corner_deg(p, q, r), t = corner_deg(q, r, p);
  if (t < m) m = t;
  t = corner_deg(r, p, q);
  return t < m ? t : m;
}

static inline void tri_normal(const double *x, int32_t a, int32_t b, int32_t c, double n[3]) {
  double u[3], w[3];
  vm_sub3(x + 3 * (int64_t)b, x + 3 * (int64_t)a, u);
  vm_sub3(x + 3 * (int64_t)c, x + 3 * (int64_t)a, w);
  vm_cross3(u, w, n);
}

static inline double cos_between(const double *a, const double *b) {
  double la = vm_norm3(a), lb = vm_norm3(b);
  return la > 0 && lb > 0 ? vm_dot3(a, b) / (la * lb) : -1;
}

/* Do faces f and g of m carry the same values of every element field? */
static inline int vm_tm_same_fields(const vm_mesh *m, int64_t f, int64_t g) {
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *fl = &m->fields[i];
    if (fl->location != VM_FIELD_ELEMENT) continue;
    size_t sz = (size_t)fl->ncomp * (fl->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
    if (memcmp((const char *)fl->data + (size_t)f * sz, (const char *)fl->data + (size_t)g * sz,
               sz))
      return 0;
  }
  return 1;
}

/* Room for n more keys: the map is rebuilt, twice as large, when it
 * would be more than half full (tombstones counted). */
static inline int hm_reserve(vm_ctx *ctx, hmap *h, size_t n) {
  if (h->used + n <= (h->mask + 1) / 2) return VM_OK;
  size_t live = 0;
  for (size_t i = 0; i <= h->mask; i++) live += h->key[i] != HM_EMPTY && h->key[i] != HM_TOMB;
  hmap g;
  if (hm_init(ctx, &g, live + n)) {
    hm_free(ctx, &g);
    return VM_ERR_NOMEM;
  }
  for (size_t i = 0; i <= h->mask; i++)
    if (h->key[i] != HM_EMPTY && h->key[i] != HM_TOMB) hm_put(&g, h->key[i], h->val[i]);
  hm_free(ctx, h);
  *h = g;
  return VM_OK;
}

/* ---- a triangle surface being edited: faces, one face of each vertex,
 * directed edges -> halfedge 3 f + i (trimesh.c) ---- */

typedef struct vm_tm {
  int32_t *tri;   /* 3 per face */
  int32_t *vface; /* a face of each vertex, -1 if none */
  hmap he;
} vm_tm;

static inline int64_t vm_tm_he(const vm_tm *t, int32_t a, int32_t b) {
  return hm_get(&t->he, dkey(a, b));
}
static inline int vm_tm_index(const int32_t *t, int32_t v) {
  return t[0] == v ? 0 : t[1] == v ? 1 : 2;
}
static inline int vm_tm_contains(const int32_t *s, int n, int32_t v) {
  for (int i = 0; i < n; i++)
    if (s[i] == v) return 1;
  return 0;
}

/* Add (add != 0) or remove the directed edges of face f; adding returns
 * how many of them were there already (a non-manifold or inconsistently
 * oriented surface). */
int vm_tm_keys(vm_tm *t, int64_t f, int add);
/* Can the interior edge (a, b) of the faces (a, b, c) and (b, a, d) be
 * flipped to (c, d): c != d, (c, d) not an edge yet, the two new
 * triangles' normals within acos(min_cos) of each other and of the old
 * pair's mean? Then 1, cd = {c, d}, *dev the distance between the lines
 * ab and cd (how far the flip moves the surface), *lmax the longer of
 * |ab| and |cd|; else 0. Features and fields are the caller's. */
int vm_tm_flip_check(const vm_tm *t, const double *x, int32_t a, int32_t b, double min_cos,
                     int32_t cd[2], double *dev, double *lmax);
/* Flip the interior edge (a, b) of the faces (a, b, c) and (b, a, d) to
 * (c, d) (not checked: the caller has); cd = {c, d}; the duplicate edges
 * the new faces met, as vm_tm_keys. */
int vm_tm_flip(vm_tm *t, int32_t a, int32_t b, int32_t cd[2]);
/* Collapse u onto w (the link condition checked by the caller): the faces
 * fu (nu: u's ring) lose u's directed edges, the two on the edge (u, w)
 * (one if it is a border edge) are marked in fdead, the others take w for u; the duplicate edges
 * the new faces met, as vm_tm_keys. u's own state is the caller's. */
int vm_tm_collapse(vm_tm *t, uint8_t *fdead, const int64_t *fu, int nu, int32_t u, int32_t w);
/* The faces around v, in order (at most max; -1 if more). */
int vm_tm_ring(const vm_tm *t, int32_t v, int64_t *out, int max);
/* The vertices of the faces fs (n) other than v, each once. */
int vm_tm_neighbours(const vm_tm *t, int32_t v, const int64_t *fs, int n, int32_t *out);
/* Does every vertex's faces form one fan? big[v] = 1 where a vertex has
 * more than max faces (not walked). VM_ERR_ARG naming the first vertex
 * (`who`: the operation, for the message) if not, VM_ERR_NOMEM. */
int vm_tm_check_manifold(vm_ctx *ctx, const vm_tm *t, int64_t nv, int64_t nf, const double *xyz,
                         int max, uint8_t *big, const char *who);
/* Replace m by the edited surface: the vertices v < nv not dead (in their
 * order, coordinates from x), the faces not dead. Vertex flags, surface
 * ids and vertex fields follow the vertices of m (new vertices: zeros);
 * element fields follow the faces if keep_elem (no face was made), else
 * they are dropped with a warning. f becomes the features of the new mesh:
 * the feature edges in fe (keys: undirected edges) between surviving
 * vertices and the corners of f that survive. */
int vm_tm_output(vm_ctx *ctx, vm_mesh *m, const double *x, int64_t nv, const uint8_t *vdead,
                 const vm_tm *t, int64_t nf, const uint8_t *fdead, int keep_elem, const hmap *fe,
                 vm_surface_features *f, const char *who);

#endif
