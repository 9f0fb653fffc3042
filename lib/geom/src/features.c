/* lib/geom/src/features.c: feature edges by dihedral angle (through the
 * OpenMesh adapter), their chaining into feature lines between corners,
 * and the vertex classes handed to the minimizer. */
#include "varmesh/features.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "adapter_private.h"
#include "varmesh/surface_mesh.h"
#include "vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void vm_surface_features_free(vm_ctx *ctx, vm_surface_features *f) {
  if (!f) return;
  vm_free(ctx, f->edge);
  vm_free(ctx, f->eline);
  vm_free(ctx, f->vclass);
  vm_free(ctx, f->vline);
  memset(f, 0, sizeof *f);
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

double vm_surface_turning_deg(const double *xyz, int32_t v, int32_t a, int32_t b) {
  double da[3], db[3];
  vm_sub3(xyz + 3 * (int64_t)v, xyz + 3 * (int64_t)a, da); /* incoming direction a -> v */
  vm_sub3(xyz + 3 * (int64_t)b, xyz + 3 * (int64_t)v, db); /* outgoing direction v -> b */
  double la = vm_norm3(da), lb = vm_norm3(db);
  if (!(la > 0) || !(lb > 0)) return 180.0;
  double c = vm_dot3(da, db) / (la * lb);
  c = c > 1 ? 1 : c < -1 ? -1 : c;
  return acos(c) * 180.0 / M_PI;
}

int vm_surface_features_from_edges(const vm_mesh *m, int64_t nedge, const int32_t *edges,
                                   const uint8_t *corner, double corner_deg,
                                   vm_surface_features *f) {
  if (!m || !f || nedge < 0 || (nedge > 0 && !edges)) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  memset(f, 0, sizeof *f);
  const int64_t nv = m->nv;
  const size_t n1 = nv > 0 ? (size_t)nv : 1;
  vm_surf_edges E;
  int st = vm_surf_edges_build(ctx, m, &E);
  if (st) return st;
  uint64_t *key = vm_alloc_array(ctx, nedge > 0 ? (size_t)nedge : 1, sizeof *key);
  int64_t *rp = vm_calloc(ctx, n1 + 1, sizeof *rp);
  int64_t *fill = vm_calloc(ctx, n1, sizeof *fill);
  int64_t *adj_e = NULL;
  f->vclass = vm_calloc(ctx, n1, sizeof *f->vclass);
  f->vline = vm_calloc(ctx, n1, sizeof *f->vline);
  if (!key || !rp || !fill || !f->vclass || !f->vline) goto nomem;
  for (int64_t k = 0; k < nedge; k++) {
    int32_t a = edges[2 * k], b = edges[2 * k + 1];
    if (a < 0 || b < 0 || a >= nv || b >= nv || a == b || vm_surf_edge_find(&E, a, b) < 0) {
      st = vm_error(ctx, VM_ERR_ARG, "feature edge %lld (%d, %d) is not an edge of the mesh",
                    (long long)k, a, b);
      goto fail;
    }
    uint32_t p = (uint32_t)(a < b ? a : b), q = (uint32_t)(a < b ? b : a);
    key[k] = (uint64_t)p << 32 | q;
  }
  qsort(key, (size_t)nedge, sizeof *key, cmp_u64);
  int64_t ne = 0;
  for (int64_t k = 0; k < nedge; k++)
    if (k == 0 || key[k] != key[k - 1]) key[ne++] = key[k];
  f->nv = nv;
  f->nedge = ne;
  f->edge = vm_alloc_array(ctx, 2 * (ne > 0 ? (size_t)ne : 1), sizeof *f->edge);
  f->eline = vm_calloc(ctx, ne > 0 ? (size_t)ne : 1, sizeof *f->eline);
  adj_e = vm_alloc_array(ctx, 2 * (ne > 0 ? (size_t)ne : 1), sizeof *adj_e);
  if (!f->edge || !f->eline || !adj_e) goto nomem;
  for (int64_t k = 0; k < ne; k++) {
    f->edge[2 * k] = (int32_t)(key[k] >> 32);
    f->edge[2 * k + 1] = (int32_t)(key[k] & 0xffffffffu);
    rp[f->edge[2 * k] + 1]++;
    rp[f->edge[2 * k + 1] + 1]++;
    int64_t ei = vm_surf_edge_find(&E, f->edge[2 * k], f->edge[2 * k + 1]);
    if (E.nface[ei] == 1) f->nboundary++;
  }
  for (int64_t v = 0; v < nv; v++) rp[v + 1] += rp[v];
  for (int64_t k = 0; k < ne; k++) {
    int32_t a = f->edge[2 * k], b = f->edge[2 * k + 1];
    adj_e[rp[a] + fill[a]++] = k;
    adj_e[rp[b] + fill[b]++] = k;
  }
  /* classes: corners by degree, turning angle, or the caller's mark */
  for (int64_t v = 0; v < nv; v++) {
    int64_t deg = rp[v + 1] - rp[v];
    int c = VM_FEATURE_SMOOTH;
    if (deg > 0) c = VM_FEATURE_LINE;
    if (deg == 1 || deg >= 3 || (corner && corner[v])) c = VM_FEATURE_CORNER;
    if (deg == 2 && corner_deg < 180) {
      int64_t e0 = adj_e[rp[v]], e1 = adj_e[rp[v] + 1];
      int32_t a = f->edge[2 * e0] == v ? f->edge[2 * e0 + 1] : f->edge[2 * e0];
      int32_t b = f->edge[2 * e1] == v ? f->edge[2 * e1 + 1] : f->edge[2 * e1];
      if (vm_surface_turning_deg(m->xyz, (int32_t)v, a, b) > corner_deg) c = VM_FEATURE_CORNER;
    }
    f->vclass[v] = (uint8_t)c;
    f->vline[v] = c == VM_FEATURE_CORNER ? -1 : 0;
    if (c == VM_FEATURE_CORNER) f->ncorner++;
  }
  /* lines: walk from every corner along each unvisited edge, then the
   * closed loops that are left */
  int32_t nline = 0;
  for (int pass = 0; pass < 2; pass++) {
    for (int64_t v = 0; v < nv; v++) {
      if (pass == 0 && f->vclass[v] != VM_FEATURE_CORNER) continue;
      if (pass == 1 && f->vclass[v] != VM_FEATURE_LINE) continue;
      for (int64_t j = rp[v]; j < rp[v + 1]; j++) {
        int64_t e = adj_e[j];
        if (f->eline[e]) continue;
        int32_t id = ++nline;
        int32_t cur = (int32_t)v;
        for (;;) {
          f->eline[e] = id;
          int32_t nxt = f->edge[2 * e] == cur ? f->edge[2 * e + 1] : f->edge[2 * e];
          cur = nxt;
          if (f->vclass[cur] == VM_FEATURE_CORNER) break;
          f->vline[cur] = id;
          /* degree 2: the other edge */
          int64_t e2 = adj_e[rp[cur]] == e ? adj_e[rp[cur] + 1] : adj_e[rp[cur]];
          if (f->eline[e2]) break; /* closed loop done */
          e = e2;
        }
      }
    }
  }
  f->nline = nline;
  for (int64_t v = 0; v < nv; v++)
    if (f->vclass[v] == VM_FEATURE_LINE) f->nline_vertices++;
  vm_free(ctx, key);
  vm_free(ctx, rp);
  vm_free(ctx, fill);
  vm_free(ctx, adj_e);
  vm_surf_edges_free(ctx, &E);
  return VM_OK;
nomem:
  st = VM_ERR_NOMEM;
fail:
  vm_free(ctx, key);
  vm_free(ctx, rp);
  vm_free(ctx, fill);
  vm_free(ctx, adj_e);
  vm_surf_edges_free(ctx, &E);
  vm_surface_features_free(ctx, f);
  return st;
}

int vm_surface_detect_features(const vm_mesh *m, double angle_deg, double corner_deg,
                               vm_surface_features *f) {
  if (!m || !f) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  memset(f, 0, sizeof *f);
  if (!(angle_deg > 0 && angle_deg <= 180) || !(corner_deg > 0))
    return vm_error(ctx, VM_ERR_ARG, "features: angle %g, corner angle %g out of range", angle_deg,
                    corner_deg);
  int64_t ne = 0, nref = 0, first = -1;
  int32_t *ev = NULL;
  double *ang = NULL;
  uint8_t *bnd = NULL;
  int st = vm_om_edge_angles(m, &ne, &ev, &ang, &bnd, &nref, &first);
  if (st) return st;
  if (nref > 0) {
    const int32_t *c = m->conn + m->eoff[first];
    const double *p = m->xyz + 3 * (int64_t)c[0];
    st = vm_error(ctx, VM_ERR_FORMAT,
                  "%lld faces do not fit a manifold, consistently oriented surface; the first "
                  "is element %lld at (%g, %g, %g) (non-manifold edge or vertex, or flipped)",
                  (long long)nref, (long long)first, p[0], p[1], p[2]);
  } else {
    double thr = angle_deg * M_PI / 180.0;
    int64_t k = 0;
    for (int64_t e = 0; e < ne; e++)
      if (bnd[e] || fabs(ang[e]) >= thr) {
        ev[2 * k] = ev[2 * e];
        ev[2 * k + 1] = ev[2 * e + 1];
        k++;
      }
    st = vm_surface_features_from_edges(m, k, ev, NULL, corner_deg, f);
  }
  vm_free(ctx, ev);
  vm_free(ctx, ang);
  vm_free(ctx, bnd);
  return st;
}

int vm_surface_features_apply(vm_mesh *m, const vm_surface_features *f, const int32_t *line_map) {
  if (!m || !f || f->nv != m->nv)
    return vm_error(m ? m->ctx : NULL, VM_ERR_ARG, "features do not belong to this mesh");
  vm_ctx *ctx = m->ctx;
  uint8_t *used = vm_calloc(ctx, m->nv > 0 ? (size_t)m->nv : 1, 1);
  if (!used) return VM_ERR_NOMEM;
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 2)
      for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) used[m->conn[k]] = 1;
  for (int64_t v = 0; v < m->nv; v++) {
    if (m->vflag[v] == VM_VERTEX_FIXED) continue;
    if (!used[v] || f->vclass[v] == VM_FEATURE_CORNER) {
      m->vflag[v] = VM_VERTEX_FIXED;
      m->vsurf[v] = -1;
    } else {
      m->vflag[v] = VM_VERTEX_SLIP;
      int32_t l = f->vline[v];
      m->vsurf[v] = l > 0 && line_map ? line_map[l] : l;
    }
  }
  vm_free(ctx, used);
  return VM_OK;
}
