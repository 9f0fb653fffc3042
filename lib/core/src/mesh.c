/* lib/core/src/mesh.c: the mesh model: element tables, storage, fields,
 * attributes, invariant checks. */
#include "varmesh/mesh.h"

#include "mesh_names.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const int nverts_tab[VM_NTYPES] = {3, 4, 4, 5, 6, 8};
static const int dim_tab[VM_NTYPES] = {2, 2, 3, 3, 3, 3};
static const char *name_tab[VM_NTYPES] = {"tri", "quad", "tet", "pyramid", "prism", "hex"};
static const int vtk_tab[VM_NTYPES] = {5, 9, 10, 14, 13, 12};

int vm_elem_nverts(int t) { return t >= 0 && t < VM_NTYPES ? nverts_tab[t] : 0; }
int vm_elem_dim(int t) { return t >= 0 && t < VM_NTYPES ? dim_tab[t] : 0; }
const char *vm_elem_name(int t) { return t >= 0 && t < VM_NTYPES ? name_tab[t] : "unknown"; }
int vm_elem_to_vtk(int t) { return t >= 0 && t < VM_NTYPES ? vtk_tab[t] : -1; }
int vm_elem_vtk_node(int t, int j) {
  static const int prism[6] = {0, 2, 1, 3, 5, 4};
  return t == VM_PRISM && j >= 0 && j < 6 ? prism[j] : j;
}
int vm_elem_from_vtk(int v) {
  for (int t = 0; t < VM_NTYPES; t++)
    if (vtk_tab[t] == v) return t;
  return -1;
}

int vm_elem_faces(int type, int faces[6][4], int nfv[6]) {
  /* outward by the right-hand rule, VTK ordering */
  static const int tet[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  static const int hex[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                {1, 2, 6, 5}, {2, 3, 7, 6}, {0, 4, 7, 3}};
  static const int pri_t[2][3] = {{0, 2, 1}, {3, 4, 5}};
  static const int pri_q[3][4] = {{0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};
  static const int pyr_t[4][3] = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  int n = 0;
  switch (type) {
  case VM_TRI:
  case VM_QUAD: {
    int k = vm_elem_nverts(type);
    for (int i = 0; i < k; i++, n++) {
      faces[n][0] = i;
      faces[n][1] = (i + 1) % k;
      nfv[n] = 2;
    }
    return n;
  }
  case VM_TET:
    for (; n < 4; n++) {
      memcpy(faces[n], tet[n], sizeof tet[n]);
      nfv[n] = 3;
    }
    return n;
  case VM_HEX:
    for (; n < 6; n++) {
      memcpy(faces[n], hex[n], sizeof hex[n]);
      nfv[n] = 4;
    }
    return n;
  case VM_PRISM:
    for (int i = 0; i < 2; i++, n++) {
      memcpy(faces[n], pri_t[i], sizeof pri_t[i]);
      nfv[n] = 3;
    }
    for (int i = 0; i < 3; i++, n++) {
      memcpy(faces[n], pri_q[i], sizeof pri_q[i]);
      nfv[n] = 4;
    }
    return n;
  case VM_PYRAMID:
    faces[0][0] = 0, faces[0][1] = 3, faces[0][2] = 2, faces[0][3] = 1;
    nfv[0] = 4;
    n = 1;
    for (int i = 0; i < 4; i++, n++) {
      memcpy(faces[n], pyr_t[i], sizeof pyr_t[i]);
      nfv[n] = 3;
    }
    return n;
  default: return 0;
  }
}

int vm_mesh_create(vm_ctx *ctx, vm_mesh **out) {
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_mesh_create: out is NULL");
  *out = NULL;
  vm_mesh *m = vm_calloc(ctx, 1, sizeof *m);
  if (!m) return VM_ERR_NOMEM;
  m->ctx = ctx;
  m->dim = 3;
  m->eoff = vm_calloc(ctx, 1, sizeof *m->eoff);
  if (!m->eoff) {
    vm_free(ctx, m);
    return VM_ERR_NOMEM;
  }
  *out = m;
  return VM_OK;
}

static void free_field(vm_ctx *ctx, vm_field *f) {
  vm_free(ctx, f->name);
  vm_free(ctx, f->data);
}

void vm_mesh_destroy(vm_mesh **p) {
  if (!p || !*p) return;
  vm_mesh *m = *p;
  vm_ctx *ctx = m->ctx;
  vm_free(ctx, m->xyz);
  vm_free(ctx, m->vflag);
  vm_free(ctx, m->vsurf);
  vm_free(ctx, m->etype);
  vm_free(ctx, m->eoff);
  vm_free(ctx, m->conn);
  for (int i = 0; i < m->nfield; i++) free_field(ctx, &m->fields[i]);
  vm_free(ctx, m->fields);
  for (int i = 0; i < m->nattr; i++) {
    vm_free(ctx, m->attrs[i].key);
    vm_free(ctx, m->attrs[i].value);
  }
  vm_free(ctx, m->attrs);
  vm_free(ctx, m);
  *p = NULL;
}

int vm_mesh_set_vertices(vm_mesh *m, int64_t nv) {
  vm_ctx *ctx = m->ctx;
  if (nv < 0 || nv > INT32_MAX)
    return vm_error(ctx, VM_ERR_ARG, "vertex count %lld out of range", (long long)nv);
  double *xyz = vm_calloc(ctx, (size_t)nv * 3, sizeof *xyz);
  uint8_t *fl = vm_calloc(ctx, (size_t)nv, 1);
  int32_t *sf = vm_alloc_array(ctx, (size_t)nv, sizeof *sf);
  if (!xyz || !fl || !sf) {
    vm_free(ctx, xyz);
    vm_free(ctx, fl);
    vm_free(ctx, sf);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < nv; i++) sf[i] = -1;
  vm_free(ctx, m->xyz);
  vm_free(ctx, m->vflag);
  vm_free(ctx, m->vsurf);
  m->xyz = xyz;
  m->vflag = fl;
  m->vsurf = sf;
  m->nv = m->vcap = nv;
  return VM_OK;
}

int vm_mesh_set_elements(vm_mesh *m, int64_t ne, int64_t nconn) {
  vm_ctx *ctx = m->ctx;
  if (ne < 0 || nconn < 0 || ne > INT32_MAX || nconn > (int64_t)VM_MAX_ELEM_VERTS * INT32_MAX)
    return vm_error(ctx, VM_ERR_ARG, "element count %lld out of range", (long long)ne);
  uint8_t *ty = vm_calloc(ctx, (size_t)ne, 1);
  int64_t *off = vm_calloc(ctx, (size_t)ne + 1, sizeof *off);
  int32_t *cn = vm_calloc(ctx, (size_t)nconn, sizeof *cn);
  if (!ty || !off || !cn) {
    vm_free(ctx, ty);
    vm_free(ctx, off);
    vm_free(ctx, cn);
    return VM_ERR_NOMEM;
  }
  vm_free(ctx, m->etype);
  vm_free(ctx, m->eoff);
  vm_free(ctx, m->conn);
  m->etype = ty;
  m->eoff = off;
  m->conn = cn;
  m->ne = m->ecap = ne;
  m->ccap = nconn;
  return VM_OK;
}

static int64_t grow_cap(int64_t need, int64_t cap) {
  if (cap >= need) return cap;
  int64_t c = cap < 16 ? 16 : cap;
  while (c < need) c *= 2;
  return c;
}

int vm_mesh_add_vertex(vm_mesh *m, double x, double y, double z, int64_t *index) {
  vm_ctx *ctx = m->ctx;
  int64_t n = m->nv;
  if (n >= INT32_MAX) return vm_error(ctx, VM_ERR_ARG, "too many vertices");
  if (n + 1 > m->vcap) {
    int64_t cap = grow_cap(n + 1, m->vcap);
    double *xyz = vm_realloc(ctx, m->xyz, (size_t)cap * 3 * sizeof *xyz);
    if (!xyz) return VM_ERR_NOMEM;
    m->xyz = xyz;
    uint8_t *fl = vm_realloc(ctx, m->vflag, (size_t)cap);
    if (!fl) return VM_ERR_NOMEM;
    m->vflag = fl;
    int32_t *sf = vm_realloc(ctx, m->vsurf, (size_t)cap * sizeof *sf);
    if (!sf) return VM_ERR_NOMEM;
    m->vsurf = sf;
    m->vcap = cap;
  }
  m->xyz[3 * n] = x;
  m->xyz[3 * n + 1] = y;
  m->xyz[3 * n + 2] = z;
  m->vflag[n] = VM_VERTEX_FREE;
  m->vsurf[n] = -1;
  if (index) *index = n;
  m->nv++;
  return VM_OK;
}

int vm_mesh_add_element(vm_mesh *m, int type, const int32_t *verts) {
  vm_ctx *ctx = m->ctx;
  int k = vm_elem_nverts(type);
  if (!k) return vm_error(ctx, VM_ERR_ARG, "unknown element type %d", type);
  int64_t ne = m->ne, nc = m->eoff[ne];
  if (ne >= INT32_MAX) return vm_error(ctx, VM_ERR_ARG, "too many elements");
  if (ne + 1 > m->ecap) {
    int64_t cap = grow_cap(ne + 1, m->ecap);
    uint8_t *ty = vm_realloc(ctx, m->etype, (size_t)cap);
    if (!ty) return VM_ERR_NOMEM;
    m->etype = ty;
    int64_t *off = vm_realloc(ctx, m->eoff, (size_t)(cap + 1) * sizeof *off);
    if (!off) return VM_ERR_NOMEM;
    m->eoff = off;
    m->ecap = cap;
  }
  if (nc + k > m->ccap) {
    int64_t cap = grow_cap(nc + k, m->ccap);
    int32_t *cn = vm_realloc(ctx, m->conn, (size_t)cap * sizeof *cn);
    if (!cn) return VM_ERR_NOMEM;
    m->conn = cn;
    m->ccap = cap;
  }
  m->etype[ne] = (uint8_t)type;
  memcpy(m->conn + nc, verts, (size_t)k * sizeof *verts);
  m->eoff[ne + 1] = nc + k;
  m->ne++;
  return VM_OK;
}

/* Duplicate names (fields per location, attribute keys), found by sorting so
 * a file with many names cannot make the check quadratic. */

typedef struct {
  const char *s;
  int group;
  int index;
} name_ref;

static int name_ref_cmp(const void *a, const void *b) {
  const name_ref *x = a, *y = b;
  if (x->group != y->group) return x->group < y->group ? -1 : 1;
  int c = strcmp(x->s, y->s);
  if (c) return c;
  return (x->index > y->index) - (x->index < y->index);
}

/* mesh_names.h */
int vm_mesh_first_duplicate(vm_ctx *ctx, const vm_mesh *m, int fields, int *dup) {
  int n = fields ? m->nfield : m->nattr;
  *dup = -1;
  if (n < 2) return VM_OK;
  name_ref *r = vm_alloc_array(ctx, (size_t)n, sizeof *r);
  if (!r) return VM_ERR_NOMEM;
  for (int i = 0; i < n; i++) {
    r[i].s = fields ? m->fields[i].name : m->attrs[i].key;
    r[i].group = fields ? m->fields[i].location : 0;
    r[i].index = i;
  }
  qsort(r, (size_t)n, sizeof *r, name_ref_cmp);
  for (int i = 1; i < n; i++)
    if (r[i].group == r[i - 1].group && !strcmp(r[i].s, r[i - 1].s) &&
        (*dup < 0 || r[i].index < *dup))
      *dup = r[i].index;
  vm_free(ctx, r);
  return VM_OK;
}

int32_t vm_mesh_repeated_vertex(const vm_mesh *m, int64_t e) {
  const int32_t *cv = m->conn + m->eoff[e];
  int64_t k = m->eoff[e + 1] - m->eoff[e];
  for (int64_t a = 0; a < k; a++)
    for (int64_t b = 0; b < a; b++)
      if (cv[a] == cv[b]) return cv[a];
  return -1;
}

int vm_mesh_check(const vm_mesh *m) {
  vm_ctx *ctx = m->ctx;
  if (m->dim != 2 && m->dim != 3)
    return vm_error(ctx, VM_ERR_FORMAT, "mesh dimension %d is not 2 or 3", m->dim);
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
      return vm_error(ctx, VM_ERR_FORMAT, "vertex %lld: coordinate is not finite", (long long)v);
    if (m->vflag[v] > VM_VERTEX_SLIP)
      return vm_error(ctx, VM_ERR_FORMAT, "vertex %lld: unknown flag %d", (long long)v,
                      m->vflag[v]);
  }
  if (m->eoff[0] != 0) return vm_error(ctx, VM_ERR_FORMAT, "element offsets do not start at 0");
  for (int64_t e = 0; e < m->ne; e++) {
    int k = vm_elem_nverts(m->etype[e]);
    if (!k)
      return vm_error(ctx, VM_ERR_FORMAT, "element %lld: unknown type %d", (long long)e,
                      m->etype[e]);
    if (m->eoff[e + 1] - m->eoff[e] != k)
      return vm_error(ctx, VM_ERR_FORMAT, "element %lld: %s with %lld vertices", (long long)e,
                      vm_elem_name(m->etype[e]), (long long)(m->eoff[e + 1] - m->eoff[e]));
    for (int i = 0; i < k; i++) {
      int32_t v = m->conn[m->eoff[e] + i];
      if (v < 0 || v >= m->nv)
        return vm_error(ctx, VM_ERR_FORMAT, "element %lld: vertex index %d out of range [0,%lld)",
                        (long long)e, v, (long long)m->nv);
    }
  }
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (f->ncomp < 1 || (f->type != VM_FIELD_F64 && f->type != VM_FIELD_I32) ||
        (f->location != VM_FIELD_VERTEX && f->location != VM_FIELD_ELEMENT))
      return vm_error(ctx, VM_ERR_FORMAT, "field '%s': bad description", f->name);
    /* a few fields: every pair, with no allocation (the writers' checks
     * cannot fail for memory); many: sorted (n log n whatever their count) */
    if (m->nfield <= 16)
      for (int j = 0; j < i; j++)
        if (m->fields[j].location == f->location && !strcmp(m->fields[j].name, f->name))
          return vm_error(ctx, VM_ERR_FORMAT, "field '%s' appears twice", f->name);
  }
  if (m->nfield > 16) {
    int d;
    if (vm_mesh_first_duplicate(ctx, m, 1, &d)) return VM_ERR_NOMEM;
    if (d >= 0) return vm_error(ctx, VM_ERR_FORMAT, "field '%s' appears twice", m->fields[d].name);
  }
  return VM_OK;
}

vm_field *vm_mesh_find_field(const vm_mesh *m, const char *name, int location) {
  for (int i = 0; i < m->nfield; i++)
    if (m->fields[i].location == location && !strcmp(m->fields[i].name, name)) return &m->fields[i];
  return NULL;
}

int64_t vm_field_count(const vm_mesh *m, const vm_field *f) {
  return f->location == VM_FIELD_VERTEX ? m->nv : m->ne;
}

int vm_mesh_add_field(vm_mesh *m, const char *name, int location, int type, int ncomp,
                      vm_field **out) {
  vm_ctx *ctx = m->ctx;
  if (out) *out = NULL;
  if (!name || !*name || ncomp < 1 || ncomp > 1 << 20 ||
      (type != VM_FIELD_F64 && type != VM_FIELD_I32) ||
      (location != VM_FIELD_VERTEX && location != VM_FIELD_ELEMENT))
    return vm_error(ctx, VM_ERR_ARG, "field '%s': bad description", name ? name : "");
  int64_t n = location == VM_FIELD_VERTEX ? m->nv : m->ne;
  size_t esz = type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t);
  if ((uint64_t)n > SIZE_MAX / (size_t)ncomp)
    return vm_error(ctx, VM_ERR_NOMEM, "field '%s' too large", name);
  void *data = vm_calloc(ctx, (size_t)n * (size_t)ncomp, esz);
  char *nm = vm_strdup(ctx, name);
  if (!data || !nm) {
    vm_free(ctx, data);
    vm_free(ctx, nm);
    return VM_ERR_NOMEM;
  }
  vm_field *f = vm_mesh_find_field(m, name, location);
  if (f) {
    free_field(ctx, f);
  } else {
    vm_field *fs = vm_realloc(ctx, m->fields, (size_t)(m->nfield + 1) * sizeof *fs);
    if (!fs) {
      vm_free(ctx, data);
      vm_free(ctx, nm);
      return VM_ERR_NOMEM;
    }
    m->fields = fs;
    f = &m->fields[m->nfield++];
  }
  f->name = nm;
  f->location = location;
  f->type = type;
  f->ncomp = ncomp;
  f->data = data;
  if (out) *out = f;
  return VM_OK;
}

int vm_mesh_remove_field(vm_mesh *m, const char *name, int location) {
  vm_field *f = vm_mesh_find_field(m, name, location);
  if (!f) return vm_error(m->ctx, VM_ERR_ARG, "no field '%s'", name);
  free_field(m->ctx, f);
  int i = (int)(f - m->fields);
  memmove(m->fields + i, m->fields + i + 1, (size_t)(m->nfield - i - 1) * sizeof *f);
  m->nfield--;
  return VM_OK;
}

int vm_mesh_set_attr(vm_mesh *m, const char *key, const char *value) {
  vm_ctx *ctx = m->ctx;
  char *v = vm_strdup(ctx, value);
  if (!v) return VM_ERR_NOMEM;
  for (int i = 0; i < m->nattr; i++)
    if (!strcmp(m->attrs[i].key, key)) {
      vm_free(ctx, m->attrs[i].value);
      m->attrs[i].value = v;
      return VM_OK;
    }
  char *k = vm_strdup(ctx, key);
  vm_attr *a = k ? vm_realloc(ctx, m->attrs, (size_t)(m->nattr + 1) * sizeof *a) : NULL;
  if (!a) {
    vm_free(ctx, k);
    vm_free(ctx, v);
    return VM_ERR_NOMEM;
  }
  m->attrs = a;
  a[m->nattr].key = k;
  a[m->nattr].value = v;
  m->nattr++;
  return VM_OK;
}

const char *vm_mesh_get_attr(const vm_mesh *m, const char *key) {
  for (int i = 0; i < m->nattr; i++)
    if (!strcmp(m->attrs[i].key, key)) return m->attrs[i].value;
  return NULL;
}

int vm_mesh_clone(const vm_mesh *src, vm_mesh **out) {
  vm_ctx *ctx = src->ctx;
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (st) return st;
  m->dim = src->dim;
  if ((st = vm_mesh_set_vertices(m, src->nv))) goto fail;
  memcpy(m->xyz, src->xyz, (size_t)src->nv * 3 * sizeof *m->xyz);
  memcpy(m->vflag, src->vflag, (size_t)src->nv);
  memcpy(m->vsurf, src->vsurf, (size_t)src->nv * sizeof *m->vsurf);
  if ((st = vm_mesh_set_elements(m, src->ne, src->eoff[src->ne]))) goto fail;
  memcpy(m->etype, src->etype, (size_t)src->ne);
  memcpy(m->eoff, src->eoff, (size_t)(src->ne + 1) * sizeof *m->eoff);
  memcpy(m->conn, src->conn, (size_t)src->eoff[src->ne] * sizeof *m->conn);
  /* fields and attributes copied as they are, in one allocation each (not
   * through vm_mesh_add_field's search by name: many fields stay linear) */
  if (src->nfield && !(m->fields = vm_calloc(ctx, (size_t)src->nfield, sizeof *m->fields))) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  for (int i = 0; i < src->nfield; i++) {
    const vm_field *f = &src->fields[i];
    size_t esz = f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t);
    size_t n = (size_t)vm_field_count(src, f) * (size_t)f->ncomp;
    vm_field *g = &m->fields[m->nfield];
    *g = *f;
    g->name = vm_strdup(ctx, f->name);
    g->data = vm_alloc_array(ctx, n ? n : 1, esz);
    if (!g->name || !g->data) {
      free_field(ctx, g);
      st = VM_ERR_NOMEM;
      goto fail;
    }
    memcpy(g->data, f->data, n * esz);
    m->nfield++;
  }
  if (src->nattr && !(m->attrs = vm_calloc(ctx, (size_t)src->nattr, sizeof *m->attrs))) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  for (int i = 0; i < src->nattr; i++) {
    vm_attr *a = &m->attrs[m->nattr];
    a->key = vm_strdup(ctx, src->attrs[i].key);
    a->value = vm_strdup(ctx, src->attrs[i].value);
    if (!a->key || !a->value) {
      vm_free(ctx, a->key);
      vm_free(ctx, a->value);
      st = VM_ERR_NOMEM;
      goto fail;
    }
    m->nattr++;
  }
  *out = m;
  return VM_OK;
fail:
  vm_mesh_destroy(&m);
  return st;
}

int vm_mesh_count_types(const vm_mesh *m, int64_t counts[VM_NTYPES]) {
  int maxdim = 0;
  for (int t = 0; t < VM_NTYPES; t++) counts[t] = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (t < VM_NTYPES) {
      counts[t]++;
      if (vm_elem_dim(t) > maxdim) maxdim = vm_elem_dim(t);
    }
  }
  return maxdim;
}

int64_t vm_mesh_apply_fixed_field(vm_mesh *m) {
  vm_field *f = vm_mesh_find_field(m, "fixed", VM_FIELD_VERTEX);
  if (!f) return 0;
  int64_t n = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int on = f->type == VM_FIELD_I32 ? ((int32_t *)f->data)[v * f->ncomp] != 0
                                     : ((double *)f->data)[v * f->ncomp] != 0.0;
    if (on) {
      m->vflag[v] = VM_VERTEX_FIXED;
      n++;
    }
  }
  return n;
}

double vm_mesh_bounds(const vm_mesh *m, double lo[3], double hi[3]) {
  for (int c = 0; c < 3; c++) {
    lo[c] = INFINITY;
    hi[c] = -INFINITY;
  }
  for (int64_t v = 0; v < m->nv; v++)
    for (int c = 0; c < 3; c++) {
      lo[c] = fmin(lo[c], m->xyz[3 * v + c]);
      hi[c] = fmax(hi[c], m->xyz[3 * v + c]);
    }
  if (m->nv == 0) return 0;
  return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
              (hi[2] - lo[2]) * (hi[2] - lo[2]));
}
