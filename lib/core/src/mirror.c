/* lib/core/src/mirror.c: half models (varmesh/mesh.h): the symmetry plane
 * as a mesh attribute and its syntax, and a half model and its mirror
 * image as one mesh (vm_mesh_mirror). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/mesh.h"

int vm_axis_plane_parse(vm_ctx *ctx, const char *s, int *axis, double *value, int *side) {
  const char *what = side ? "x=C, y=C or z=C, optionally :+ or :-" : "x=C, y=C or z=C";
  if (!s) s = "";
  int a = tolower((unsigned char)s[0]) - 'x';
  if (a < 0 || a > 2 || s[1] != '=')
    return ctx ? vm_error(ctx, VM_ERR_ARG, "'%s': expected %s", s, what) : VM_ERR_ARG;
  char *end = NULL;
  double c = strtod(s + 2, &end);
  int sd = 0;
  if (end != s + 2 && side && end[0] == ':' && (end[1] == '+' || end[1] == '-') && !end[2]) {
    sd = end[1] == '+' ? 1 : -1;
    end += 2;
  }
  if (end == s + 2 || *end || !isfinite(c))
    return ctx ? vm_error(ctx, VM_ERR_ARG, "'%s': expected %s", s, what) : VM_ERR_ARG;
  *axis = a;
  *value = c;
  if (side) *side = sd;
  return VM_OK;
}

char *vm_axis_plane_format(int axis, double value, char *buf, size_t n) {
  char ax = (char)('x' + (axis >= 0 && axis <= 2 ? axis : 0));
  for (int prec = 1; prec <= 17; prec++) {
    snprintf(buf, n, "%c=%.*g", ax, prec, value == 0 ? 0.0 : value);
    if (strtod(buf + 2, NULL) == value) break;
  }
  return buf;
}

int vm_mesh_get_symmetry_plane(const vm_mesh *m, int *axis, double *value) {
  const char *s = vm_mesh_get_attr(m, VM_SYMMETRY_PLANE_ATTR);
  if (!s) return 0;
  if (vm_axis_plane_parse(NULL, s, axis, value, NULL))
    return vm_error(m->ctx, VM_ERR_FORMAT, "attribute %s = '%s': expected x=C, y=C or z=C",
                    VM_SYMMETRY_PLANE_ATTR, s);
  return 1;
}

int vm_mesh_set_symmetry_plane(vm_mesh *m, int axis, double value) {
  if (axis < 0 || axis > 2 || !isfinite(value))
    return vm_error(m->ctx, VM_ERR_ARG, "symmetry plane: axis %d, value %g", axis, value);
  char buf[64];
  return vm_mesh_set_attr(m, VM_SYMMETRY_PLANE_ATTR, vm_axis_plane_format(axis, value, buf, 64));
}

/* The corner order of each type's mirror image that keeps its orientation
 * (a reflection turns it): the image of corner i is corner perm[i]. */
static const int *turned(int type) {
  static const int tri[] = {0, 2, 1}, quad[] = {0, 3, 2, 1}, tet[] = {0, 2, 1, 3},
                   pyr[] = {0, 3, 2, 1, 4}, pri[] = {0, 2, 1, 3, 5, 4},
                   hex[] = {0, 3, 2, 1, 4, 7, 6, 5};
  switch (type) {
  case VM_TRI: return tri;
  case VM_QUAD: return quad;
  case VM_TET: return tet;
  case VM_PYRAMID: return pyr;
  case VM_PRISM: return pri;
  default: return hex;
  }
}

int vm_mesh_mirror(vm_ctx *ctx, const vm_mesh *m, vm_mesh **out) {
  *out = NULL;
  int ax;
  double c;
  int got = vm_mesh_get_symmetry_plane(m, &ax, &c);
  if (got < 0) return got;
  if (!got)
    return vm_error(ctx, VM_ERR_ARG,
                    "mirror: the mesh names no symmetry plane (attribute '%s' = 'y=0' or the "
                    "like): it is not a half model",
                    VM_SYMMETRY_PLANE_ATTR);
  int64_t nv = m->nv, ne = m->ne;
  /* the image of vertex v: itself in the plane, else nv + (its rank
   * among those off it) */
  int64_t *img = vm_alloc_array(ctx, (size_t)(nv + 1), sizeof *img);
  uint8_t *drop = vm_calloc(ctx, (size_t)ne + 1, 1);
  if (!img || !drop) {
    vm_free(ctx, img);
    vm_free(ctx, drop);
    return VM_ERR_NOMEM;
  }
  int64_t noff = 0;
  for (int64_t v = 0; v < nv; v++) img[v] = m->xyz[3 * v + ax] == c ? v : nv + noff++;
  /* faces in the plane are inside the whole: dropped, and not mirrored */
  int64_t nkeep = 0, nconn = 0;
  for (int64_t e = 0; e < ne; e++) {
    int in = vm_elem_dim(m->etype[e]) <= 2;
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1] && in; k++) in = img[m->conn[k]] < nv;
    drop[e] = (uint8_t)in;
    if (!in) nkeep++, nconn += m->eoff[e + 1] - m->eoff[e];
  }
  vm_mesh *o = NULL;
  int st = vm_mesh_create(ctx, &o);
  if (!st) st = vm_mesh_set_vertices(o, nv + noff);
  if (!st) st = vm_mesh_set_elements(o, 2 * nkeep, 2 * nconn);
  if (st) goto fail;
  o->dim = m->dim;
  memcpy(o->xyz, m->xyz, sizeof *o->xyz * (size_t)(3 * nv));
  memcpy(o->vflag, m->vflag, (size_t)nv);
  memcpy(o->vsurf, m->vsurf, sizeof *o->vsurf * (size_t)nv);
  for (int64_t v = 0; v < nv; v++) {
    if (img[v] == v) continue;
    double *x = o->xyz + 3 * img[v];
    memcpy(x, m->xyz + 3 * v, 3 * sizeof *x);
    x[ax] = 2 * c - x[ax];
    o->vflag[img[v]] = m->vflag[v];
    o->vsurf[img[v]] = m->vsurf[v];
  }
  /* elements: the half as it is, then the images, turned */
  int64_t *src = vm_alloc_array(ctx, (size_t)(2 * nkeep + 1), sizeof *src);
  if (!src) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  int64_t k = 0, cc = 0;
  for (int side = 0; side < 2; side++)
    for (int64_t e = 0; e < ne; e++) {
      if (drop[e]) continue;
      int n = (int)(m->eoff[e + 1] - m->eoff[e]);
      const int32_t *cv = m->conn + m->eoff[e];
      const int *p = turned(m->etype[e]);
      o->etype[k] = m->etype[e];
      for (int i = 0; i < n; i++) o->conn[cc + i] = side ? (int32_t)img[cv[p[i]]] : cv[i];
      cc += n;
      src[k] = e;
      o->eoff[++k] = cc;
    }
  /* fields: each item's image carries its values */
  for (int i = 0; i < m->nfield && !st; i++) {
    const vm_field *f = &m->fields[i];
    vm_field *g;
    if ((st = vm_mesh_add_field(o, f->name, f->location, f->type, f->ncomp, &g))) break;
    size_t w = (f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t)) * (size_t)f->ncomp;
    if (f->location == VM_FIELD_VERTEX) {
      memcpy(g->data, f->data, w * (size_t)nv);
      for (int64_t v = 0; v < nv; v++)
        if (img[v] != v)
          memcpy((char *)g->data + w * (size_t)img[v], (const char *)f->data + w * (size_t)v, w);
    } else {
      for (int64_t j = 0; j < 2 * nkeep; j++)
        memcpy((char *)g->data + w * (size_t)j, (const char *)f->data + w * (size_t)src[j], w);
    }
  }
  vm_free(ctx, src);
  for (int i = 0; i < m->nattr && !st; i++)
    if (strcmp(m->attrs[i].key, VM_SYMMETRY_PLANE_ATTR))
      st = vm_mesh_set_attr(o, m->attrs[i].key, m->attrs[i].value);
  if (st) goto fail;
  vm_free(ctx, img);
  vm_free(ctx, drop);
  *out = o;
  return VM_OK;
fail:
  vm_free(ctx, img);
  vm_free(ctx, drop);
  vm_mesh_destroy(&o);
  return st;
}
