/* lib/core/src/problem.c: setup of the discrete functional (13)/(20): active
 * elements, quadrature nodes, targets, metric, weights, normals, the vertex
 * graph and the element colouring the assembly runs on. */
#include "varmesh/problem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "problem_private.h"
#include "vec3.h"

static double det3(const double *A) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

/* B = A^{-1} given det A != 0. */
static void inv3(const double *A, double det, double *B) {
  double r = 1 / det;
  B[0] = (A[4] * A[8] - A[5] * A[7]) * r;
  B[1] = (A[2] * A[7] - A[1] * A[8]) * r;
  B[2] = (A[1] * A[5] - A[2] * A[4]) * r;
  B[3] = (A[5] * A[6] - A[3] * A[8]) * r;
  B[4] = (A[0] * A[8] - A[2] * A[6]) * r;
  B[5] = (A[2] * A[3] - A[0] * A[5]) * r;
  B[6] = (A[3] * A[7] - A[4] * A[6]) * r;
  B[7] = (A[1] * A[6] - A[0] * A[7]) * r;
  B[8] = (A[0] * A[4] - A[1] * A[3]) * r;
}

/* Newell normal of a polygon (not normalized): twice its vector area. */
static void newell(const double *x, int k, double *n) {
  n[0] = n[1] = n[2] = 0;
  for (int i = 0; i < k; i++) {
    const double *a = x + 3 * i, *b = x + 3 * ((i + 1) % k);
    n[0] += (a[1] - b[1]) * (a[2] + b[2]);
    n[1] += (a[2] - b[2]) * (a[0] + b[0]);
    n[2] += (a[0] - b[0]) * (a[1] + b[1]);
  }
}

/* vertices per element type (vm_elem_nverts, inlined for the setup loops) */
static const int nverts_of[VM_NTYPES] = {3, 4, 4, 5, 6, 8};

static const int32_t *elem_verts(const vm_problem *p, int64_t i) {
  return p->m->conn + p->m->eoff[p->ael[i]];
}

static int elem_type(const vm_problem *p, int64_t i) { return p->m->etype[p->ael[i]]; }

/* Element coordinates from a 3*nv array (z = 0 for plane meshes). */
static void gather(const vm_problem *p, int64_t i, const double *xyz, double *x) {
  const int32_t *cv = elem_verts(p, i);
  int k = nverts_of[elem_type(p, i)];
  for (int a = 0; a < k; a++) {
    const double *s = xyz + 3 * (int64_t)cv[a];
    x[3 * a] = s[0];
    x[3 * a + 1] = s[1];
    x[3 * a + 2] = p->kind == VM_PK_PLANE ? 0 : s[2];
  }
}

static void build_patterns(vm_problem *p) {
  memset(p->pat, 0, sizeof p->pat);
  memset(p->npair, 0, sizeof p->npair);
  for (int t = 0; t < VM_NTYPES; t++) {
    const vm_qrule *R = p->qr[t];
    signed char idx[VM_MAX_ELEM_VERTS][VM_MAX_ELEM_VERTS];
    memset(idx, -1, sizeof idx);
    for (int j = 0; j < R->nnodes; j++) {
      const vm_qnode *q = &R->nodes[j];
      vm_nodepat *pt = &p->pat[t][j];
      for (int k = 0; k < R->dim; k++)
        for (int side = 0; side < 2; side++) {
          int v = side ? q->tail[k] : q->head[k];
          int u = 0;
          while (u < pt->nloc && pt->loc[u] != v) u++;
          if (u == pt->nloc) pt->loc[pt->nloc++] = (signed char)v;
          pt->a[u][k] = (signed char)(side ? -1 : 1);
          pt->ad[u][k] = side ? -1.0 : 1.0;
        }
      int np = 0;
      for (int u = 0; u < pt->nloc; u++)
        for (int w = u + 1; w < pt->nloc; w++) {
          int a = pt->loc[u] < pt->loc[w] ? pt->loc[u] : pt->loc[w];
          int b = pt->loc[u] ^ pt->loc[w] ^ a;
          if (idx[a][b] < 0) {
            idx[a][b] = (signed char)p->npair[t];
            p->pair[t][p->npair[t]][0] = (signed char)a;
            p->pair[t][p->npair[t]][1] = (signed char)b;
            p->npair[t]++;
          }
          pt->pidx[np++] = idx[a][b];
        }
    }
  }
}

/* Node offsets and node elements for the current rules. */
static int build_nodes(vm_problem *p, int64_t **noff_out, int32_t **nelem_out, int64_t *nn_out) {
  vm_ctx *ctx = p->ctx;
  int64_t *noff = vm_alloc_array(ctx, (size_t)p->nae + 1, sizeof *noff);
  if (!noff) return VM_ERR_NOMEM;
  noff[0] = 0;
  for (int64_t i = 0; i < p->nae; i++) noff[i + 1] = noff[i] + p->qr[elem_type(p, i)]->nnodes;
  int64_t nn = noff[p->nae];
  int32_t *nelem = vm_alloc_array(ctx, (size_t)(nn ? nn : 1), sizeof *nelem);
  if (!nelem) {
    vm_free(ctx, noff);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < p->nae; i++)
    for (int64_t n = noff[i]; n < noff[i + 1]; n++) nelem[n] = p->ael[i];
  *noff_out = noff;
  *nelem_out = nelem;
  *nn_out = nn;
  return VM_OK;
}

/* Orientation normal of a 2D target element: none (0) for plane meshes and
 * ideal elements, which lie in the xy plane; else the target's own Newell
 * normal. Nonzero return: degenerate target. */
static int target_normal(const vm_problem *p, const double *tc, int k, double *n) {
  n[0] = n[1] = n[2] = 0;
  if (p->kind != VM_PK_SURF || p->tgt == VM_TGT_IDEAL) return 0;
  newell(tc, k, n);
  return !(vm_dot3(n, n) > 0) || !isfinite(vm_dot3(n, n));
}

/* T of rule node q from element coordinates tc; writes S = T^{-1}
 * (d x d) if det T != 0 and returns det T. 2D nodes in 3D (n != 0) use the
 * node's own plane: T is the R factor of the 3 x 2 edge matrix, so
 * T^T T is its Gram matrix, with the sign of n . (c0 x c1). */
static double node_target(const vm_qnode *q, int d, const double *tc, const double *n, double *S) {
  double col[3][3];
  for (int k = 0; k < d; k++)
    for (int r = 0; r < 3; r++) col[k][r] = tc[3 * q->head[k] + r] - tc[3 * q->tail[k] + r];
  if (d == 3) {
    double T[9];
    for (int r = 0; r < 3; r++)
      for (int k = 0; k < 3; k++) T[3 * r + k] = col[k][r];
    double dt = det3(T);
    if (dt != 0) inv3(T, dt, S);
    return dt;
  }
  double a, b, c, e;
  if (n[0] == 0 && n[1] == 0 && n[2] == 0) {
    a = col[0][0], b = col[1][0], c = col[0][1], e = col[1][1];
  } else {
    double x[3], l0 = sqrt(vm_dot3(col[0], col[0]));
    vm_cross3(col[0], col[1], x);
    double area = sqrt(vm_dot3(x, x));
    if (!(l0 > 0)) return 0;
    a = l0;
    b = vm_dot3(col[0], col[1]) / l0;
    c = 0;
    e = (vm_dot3(n, x) < 0 ? -area : area) / l0;
  }
  double dt = a * e - b * c;
  if (dt != 0) {
    S[0] = e / dt;
    S[1] = -b / dt;
    S[2] = -c / dt;
    S[3] = a / dt;
  }
  return dt;
}

/* Target coordinates of active element i (reference or field targets). */
static void target_coords(const vm_problem *p, int64_t i, double *tc) {
  if (p->tgt == VM_TGT_REFERENCE) {
    gather(p, i, p->tgt_ref, tc);
    return;
  }
  int k = nverts_of[elem_type(p, i)];
  const double *s = p->tgt_fld + 3 * p->m->eoff[p->ael[i]];
  for (int a = 0; a < k; a++) {
    tc[3 * a] = s[3 * a];
    tc[3 * a + 1] = s[3 * a + 1];
    tc[3 * a + 2] = p->kind == VM_PK_PLANE ? 0 : s[3 * a + 2];
  }
}

/* The sum of wb over active element i's n nodes, in node order. */
static double wb_sum(const double *wb, int n) {
  double s = 0;
  for (int j = 0; j < n; j++) s += wb[j];
  return s;
}

static void update_tvol(vm_problem *p) {
  double tv = 0;
  for (int64_t i = 0; i < p->nae; i++) {
    int t = elem_type(p, i);
    const double *wb = p->wnode ? p->wnode + p->noff[i] : p->wid[t];
    tv += p->wel[i] * (p->wsum ? p->wsum[i] : wb_sum(wb, p->qr[t]->nnodes));
  }
  p->tvol = tv;
}

int vm_problem_elem_targets(const vm_problem *p, int64_t i, double *S, double *wb, double *fdet) {
  int d = p->tdim, dd = d * d;
  double tc[VM_MAX_ELEM_VERTS * 3], n[3] = {0, 0, 0};
  int t = elem_type(p, i);
  const vm_qrule *R = p->qr[t];
  target_coords(p, i, tc);
  *fdet = 0;
  if (d == 2 && target_normal(p, tc, vm_elem_nverts(t), n)) return 0;
  for (int j = 0; j < R->nnodes; j++) {
    double dt = node_target(&R->nodes[j], d, tc, n, S + dd * j);
    wb[j] = R->nodes[j].beta * R->kappa * dt;
    if (!(dt > 0) || !isfinite(dt)) {
      *fdet = dt;
      return j;
    }
  }
  return -1;
}

/* Keep S and wb of every node (nn (d^2 + 1) doubles) or compute them from
 * the element's target coordinates whenever it is evaluated: the same
 * arithmetic, so the same bits either way. Stored while they take at most
 * p->tgt_store bytes (vm_problem_set_target_store), computed beyond. */
static int targets_lazy(const vm_problem *p) {
  double bytes = (double)p->nn * (double)(p->tdim * p->tdim + 1) * (double)sizeof(double);
  return bytes > (double)p->tgt_store;
}

/* (Re)build S and wb of every node from the target description in p (or,
 * when they are computed at evaluation, check them and sum wb per
 * element). On failure p is unchanged. */
static int compute_targets(vm_problem *p) {
  vm_ctx *ctx = p->ctx;
  int d = p->tdim, dd = d * d;
  static const double none[3] = {0, 0, 0};
  if (p->tgt == VM_TGT_IDEAL) {
    for (int t = 0; t < VM_NTYPES; t++) {
      if (vm_elem_dim(t) != d) continue;
      double ref[VM_MAX_ELEM_VERTS * 3];
      vm_elem_ideal(t, ref);
      for (int a = 0; a < VM_MAX_ELEM_VERTS * 3; a++) ref[a] *= p->tgt_size;
      const vm_qrule *R = p->qr[t];
      p->sdiag[t] = 1;
      for (int j = 0; j < R->nnodes; j++) {
        double *S = p->Sid[t] + dd * j;
        double dt = node_target(&R->nodes[j], d, ref, none, S);
        p->wid[t][j] = R->nodes[j].beta * R->kappa * dt;
        for (int k = 0; k < dd; k++)
          if (k % (d + 1) && S[k] != 0) p->sdiag[t] = 0;
      }
    }
    vm_free(ctx, p->Snode);
    vm_free(ctx, p->wnode);
    vm_free(ctx, p->wsum);
    p->Snode = p->wnode = p->wsum = NULL;
    update_tvol(p);
    return VM_OK;
  }
  int lazy = targets_lazy(p);
  double *S = NULL, *w = NULL, *ws = NULL;
  if (lazy) {
    ws = vm_alloc_array(ctx, (size_t)(p->nae ? p->nae : 1), sizeof *ws);
  } else {
    S = vm_alloc_array(ctx, (size_t)(p->nn ? p->nn : 1) * (size_t)dd, sizeof *S);
    w = vm_alloc_array(ctx, (size_t)(p->nn ? p->nn : 1), sizeof *w);
  }
  if (lazy ? !ws : !S || !w) {
    vm_free(ctx, S);
    vm_free(ctx, w);
    return VM_ERR_NOMEM;
  }
  int64_t bad = p->nae;
  int badnode = 0;
  double baddet = 0;
#pragma omp parallel for schedule(static) num_threads(vm_problem_threads(p))
  for (int64_t i = 0; i < p->nae; i++) {
    double Sl[VM_QRULE_MAX_NODES * 9], wl[VM_QRULE_MAX_NODES], fdet;
    int64_t n0 = p->noff[i];
    double *Si = lazy ? Sl : S + dd * n0, *wi = lazy ? wl : w + n0;
    int fail = vm_problem_elem_targets(p, i, Si, wi, &fdet);
    if (fail < 0 && lazy) ws[i] = wb_sum(wi, p->qr[elem_type(p, i)]->nnodes);
    if (fail >= 0) {
#pragma omp critical(vm_problem_target_fail)
      if (i < bad) {
        bad = i;
        badnode = fail;
        baddet = fdet;
      }
    }
  }
  if (bad < p->nae) {
    vm_free(ctx, S);
    vm_free(ctx, w);
    vm_free(ctx, ws);
    return vm_error(ctx, VM_ERR_ARG,
                    "element %d: target of quadrature node %d is degenerate or inverted "
                    "(det T = %g)",
                    p->ael[bad], badnode, baddet);
  }
  vm_free(ctx, p->Snode);
  vm_free(ctx, p->wnode);
  vm_free(ctx, p->wsum);
  p->Snode = S;
  p->wnode = w;
  p->wsum = ws;
  update_tvol(p);
  return VM_OK;
}

int vm_problem_set_target_store(vm_problem *p, int64_t max_bytes) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (max_bytes < 0)
    return vm_error(p->ctx, VM_ERR_ARG, "target store of %lld bytes", (long long)max_bytes);
  int64_t old = p->tgt_store;
  p->tgt_store = max_bytes;
  int st = p->tgt == VM_TGT_IDEAL ? VM_OK : compute_targets(p);
  if (st) p->tgt_store = old;
  return st;
}

/* Signed volume (area) of active element i at coordinates xyz by the
 * geometric rule, exact for the multilinear map (24). */
static double elem_volume(const vm_problem *p, int64_t i, const double *xyz) {
  double x[VM_MAX_ELEM_VERTS * 3];
  int t = elem_type(p, i);
  const vm_qrule *R = vm_qrule_get(t, VM_RULE_GEOMETRIC);
  gather(p, i, xyz, x);
  double v = 0;
  for (int j = 0; j < R->nnodes; j++) {
    const vm_qnode *q = &R->nodes[j];
    double col[3][3];
    for (int k = 0; k < R->dim; k++)
      for (int r = 0; r < 3; r++) col[k][r] = x[3 * q->head[k] + r] - x[3 * q->tail[k] + r];
    double det;
    if (R->dim == 3) {
      double c[3];
      vm_cross3(col[1], col[2], c);
      det = vm_dot3(col[0], c);
    } else if (p->kind == VM_PK_SURF) {
      double c[3];
      vm_cross3(col[0], col[1], c);
      det = vm_dot3(p->nrm + 3 * i, c);
    } else {
      det = col[0][0] * col[1][1] - col[0][1] * col[1][0];
    }
    v += q->beta * R->kappa * det;
  }
  return v;
}

/* Edge length of ideal targets whose total volume is the mesh's. */
static int auto_size(vm_problem *p, double *size) {
  int d = p->tdim;
  double unit[VM_NTYPES];
  for (int t = 0; t < VM_NTYPES; t++) {
    unit[t] = 0;
    if (vm_elem_dim(t) != d) continue;
    double ref[VM_MAX_ELEM_VERTS * 3], S[9];
    static const double none[3] = {0, 0, 0};
    vm_elem_ideal(t, ref);
    const vm_qrule *R = vm_qrule_get(t, VM_RULE_GEOMETRIC);
    for (int j = 0; j < R->nnodes; j++)
      unit[t] += R->nodes[j].beta * R->kappa * node_target(&R->nodes[j], d, ref, none, S);
  }
  /* fixed blocks summed in order: the same bits for any thread count */
  double vm = 0, vi = 0;
#pragma omp parallel for schedule(static) num_threads(vm_problem_threads(p))
  for (int64_t b = 0; b < p->nblock; b++) {
    int64_t i1 = (b + 1) * VM_PROBLEM_FBLOCK < p->nae ? (b + 1) * VM_PROBLEM_FBLOCK : p->nae;
    double s = 0;
    for (int64_t i = b * VM_PROBLEM_FBLOCK; i < i1; i++) s += elem_volume(p, i, p->m->xyz);
    p->part[b] = s;
  }
  for (int64_t b = 0; b < p->nblock; b++) vm += p->part[b];
  for (int64_t i = 0; i < p->nae; i++) vi += unit[elem_type(p, i)];
  double r = fabs(vm) / vi;
  if (!isfinite(vm) || !isfinite(r))
    return vm_error(p->ctx, VM_ERR_ARG,
                    "the mesh volume overflows (the coordinates are too large for double "
                    "precision volumes): cannot size ideal targets; scale the mesh down or "
                    "give a target size");
  if (!(r > 0))
    return vm_error(p->ctx, VM_ERR_ARG,
                    "the mesh volume is %s: cannot size ideal targets (give a target size)",
                    vm == 0 ? "zero" : "below the smallest double");
  *size = d == 3 ? cbrt(r) : sqrt(r);
  return VM_OK;
}

int vm_problem_set_target_ideal(vm_problem *p, double size) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (!isfinite(size)) return vm_error(p->ctx, VM_ERR_ARG, "target size %g is not finite", size);
  if (size <= 0) {
    int st = auto_size(p, &size);
    if (st) return st;
  }
  p->tgt = VM_TGT_IDEAL;
  p->tgt_size = size;
  vm_free(p->ctx, p->tgt_ref);
  vm_free(p->ctx, p->tgt_fld);
  p->tgt_ref = p->tgt_fld = NULL;
  return compute_targets(p);
}

/* Switch to non-ideal targets described by ref or fld (owned on success). */
static int set_target_data(vm_problem *p, int kind, double *ref, double *fld) {
  int old = p->tgt;
  double *oref = p->tgt_ref, *ofld = p->tgt_fld;
  p->tgt = kind;
  p->tgt_ref = ref;
  p->tgt_fld = fld;
  int st = compute_targets(p);
  if (st) {
    p->tgt = old;
    p->tgt_ref = oref;
    p->tgt_fld = ofld;
    vm_free(p->ctx, ref);
    vm_free(p->ctx, fld);
    return st;
  }
  vm_free(p->ctx, oref);
  vm_free(p->ctx, ofld);
  return VM_OK;
}

int vm_problem_set_target_reference(vm_problem *p, const double *xyz_ref) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (!xyz_ref) return vm_error(p->ctx, VM_ERR_ARG, "reference coordinates are NULL");
  size_t n = (size_t)p->m->nv * 3;
  double *ref = vm_alloc_array(p->ctx, n ? n : 1, sizeof *ref);
  if (!ref) return VM_ERR_NOMEM;
  memcpy(ref, xyz_ref, n * sizeof *ref);
  return set_target_data(p, VM_TGT_REFERENCE, ref, NULL);
}

int vm_problem_set_target_field(vm_problem *p, const char *field_name) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  const vm_mesh *m = p->m;
  const vm_field *f = field_name ? vm_mesh_find_field(m, field_name, VM_FIELD_ELEMENT) : NULL;
  if (!f || f->type != VM_FIELD_F64)
    return vm_error(p->ctx, VM_ERR_ARG, "no f64 element field '%s' for targets",
                    field_name ? field_name : "(null)");
  for (int64_t i = 0; i < p->nae; i++)
    if (f->ncomp < 3 * nverts_of[elem_type(p, i)])
      return vm_error(p->ctx, VM_ERR_ARG,
                      "target field '%s' has %d components, element %d needs %d", field_name,
                      f->ncomp, p->ael[i], 3 * nverts_of[elem_type(p, i)]);
  size_t n = (size_t)m->eoff[m->ne] * 3;
  double *fld = vm_calloc(p->ctx, n ? n : 1, sizeof *fld);
  if (!fld) return VM_ERR_NOMEM;
  const double *src = f->data;
  for (int64_t i = 0; i < p->nae; i++) {
    int32_t e = p->ael[i];
    int k = 3 * vm_elem_nverts(m->etype[e]);
    memcpy(fld + 3 * m->eoff[e], src + (size_t)e * (size_t)f->ncomp, (size_t)k * sizeof *fld);
  }
  return set_target_data(p, VM_TGT_FIELD, NULL, fld);
}

int vm_problem_set_rule(vm_problem *p, vm_rule rule) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (rule < VM_RULE_CORNER || rule > VM_RULE_GEOMETRIC_SPLIT)
    return vm_error(p->ctx, VM_ERR_ARG, "unknown quadrature rule %d", (int)rule);
  int64_t *noff, nn;
  int32_t *nelem;
  int oldrule = p->rule;
  p->rule = rule;
  for (int t = 0; t < VM_NTYPES; t++) p->qr[t] = vm_qrule_get(t, rule);
  int st = build_nodes(p, &noff, &nelem, &nn);
  if (!st) {
    int64_t *on = p->noff, onn = p->nn;
    int32_t *oe = p->nelem;
    p->noff = noff;
    p->nelem = nelem;
    p->nn = nn;
    st = compute_targets(p);
    if (st) {
      p->noff = on;
      p->nelem = oe;
      p->nn = onn;
      vm_free(p->ctx, noff);
      vm_free(p->ctx, nelem);
    } else {
      vm_free(p->ctx, on);
      vm_free(p->ctx, oe);
    }
  }
  if (st) {
    p->rule = oldrule;
    for (int t = 0; t < VM_NTYPES; t++) p->qr[t] = vm_qrule_get(t, oldrule);
    return st;
  }
  build_patterns(p);
  vm_free(p->ctx, p->eps_node);
  vm_free(p->ctx, p->node_w);
  vm_free(p->ctx, p->ppos);
  p->eps_node = NULL;
  p->node_w = NULL;
  p->ppos = NULL;
  p->ppos_stride = 0;
  return VM_OK;
}

static int check_params(vm_ctx *ctx, const vm_measure_params *q) {
  if (!(q->theta >= 0 && q->theta <= 1))
    return vm_error(ctx, VM_ERR_ARG, "theta %g is not in [0, 1]", q->theta);
  if (!(q->t >= 0 && q->t < 1)) return vm_error(ctx, VM_ERR_ARG, "t %g is not in [0, 1)", q->t);
  if (!(q->eps >= 0) || !isfinite(q->eps))
    return vm_error(ctx, VM_ERR_ARG, "eps %g is not finite and >= 0", q->eps);
  return VM_OK;
}

int vm_problem_set_measure(vm_problem *p, vm_measure_kind kind, const vm_measure_params *prm) {
  vm_problem_touch(p);
  if (!p) return VM_ERR_ARG;
  const vm_measure_ops *ops = vm_measure_get(kind);
  if (!ops) return vm_error(p->ctx, VM_ERR_ARG, "unknown measure %d", (int)kind);
  vm_measure_params q = prm ? *prm : vm_measure_params_default();
  int st = check_params(p->ctx, &q);
  if (st) return st;
  p->ops = ops;
  p->prm = q;
  return VM_OK;
}

int vm_problem_set_params(vm_problem *p, const vm_measure_params *prm) {
  vm_problem_touch(p);
  if (!p || !prm) return p ? vm_error(p->ctx, VM_ERR_ARG, "parameters are NULL") : VM_ERR_ARG;
  int st = check_params(p->ctx, prm);
  if (st) return st;
  p->prm = *prm;
  return VM_OK;
}

const vm_measure_params *vm_problem_params(const vm_problem *p) { return p ? &p->prm : NULL; }

static void free_metric(vm_problem *p) {
  vm_free(p->ctx, p->mg);
  vm_free(p->ctx, p->mG);
  vm_free(p->ctx, p->mdq);
  p->mg = p->mG = p->mdq = NULL;
  p->metric = VM_METRIC_IDENTITY;
}

int vm_problem_set_metric_scalar(vm_problem *p, const double *g) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (!g) {
    free_metric(p);
    return VM_OK;
  }
  for (int64_t i = 0; i < p->nae; i++) {
    const int32_t *cv = elem_verts(p, i);
    for (int a = 0; a < nverts_of[elem_type(p, i)]; a++)
      if (!(g[cv[a]] > 0) || !isfinite(g[cv[a]]))
        return vm_error(p->ctx, VM_ERR_ARG, "metric at vertex %d is %g, not finite and > 0", cv[a],
                        g[cv[a]]);
  }
  double *mg = vm_alloc_array(p->ctx, (size_t)p->nae, sizeof *mg);
  double *dq = vm_alloc_array(p->ctx, (size_t)p->nae, sizeof *dq);
  if (!mg || !dq) {
    vm_free(p->ctx, mg);
    vm_free(p->ctx, dq);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < p->nae; i++) {
    const int32_t *cv = elem_verts(p, i);
    int k = nverts_of[elem_type(p, i)];
    double s = 0;
    for (int a = 0; a < k; a++) s += g[cv[a]];
    s /= k;
    mg[i] = s;
    /* det Q for Q = sqrt(g) I */
    dq[i] = p->tdim == 3 ? s * sqrt(s) : s;
  }
  free_metric(p);
  p->mg = mg;
  p->mdq = dq;
  p->metric = VM_METRIC_SCALAR;
  return VM_OK;
}

int vm_problem_set_metric_tensor(vm_problem *p, const double *G) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (!G) {
    free_metric(p);
    return VM_OK;
  }
  if (p->kind == VM_PK_SURF)
    return vm_error(p->ctx, VM_ERR_UNSUPPORTED,
                    "surface meshes take a scalar metric only (G_x = g I)");
  double *mG = vm_alloc_array(p->ctx, (size_t)p->nae * 6, sizeof *mG);
  double *dq = vm_alloc_array(p->ctx, (size_t)p->nae, sizeof *dq);
  if (!mG || !dq) {
    vm_free(p->ctx, mG);
    vm_free(p->ctx, dq);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < p->nae; i++) {
    const int32_t *cv = elem_verts(p, i);
    int k = nverts_of[elem_type(p, i)];
    double a[6] = {0, 0, 0, 0, 0, 0};
    for (int v = 0; v < k; v++)
      for (int c = 0; c < 6; c++) a[c] += G[6 * (int64_t)cv[v] + c];
    for (int c = 0; c < 6; c++) a[c] /= k;
    if (p->tdim == 2) a[2] = a[4] = a[5] = 0;
    double m2 = a[0] * a[1] - a[3] * a[3];
    double m3 = a[0] * (a[1] * a[2] - a[4] * a[4]) - a[3] * (a[3] * a[2] - a[4] * a[5]) +
                a[5] * (a[3] * a[4] - a[1] * a[5]);
    double det = p->tdim == 2 ? m2 : m3;
    if (!(a[0] > 0) || !(m2 > 0) || !(det > 0) || !isfinite(det)) {
      vm_free(p->ctx, mG);
      vm_free(p->ctx, dq);
      return vm_error(p->ctx, VM_ERR_ARG, "element %d: metric tensor is not positive definite",
                      p->ael[i]);
    }
    memcpy(mG + 6 * i, a, sizeof a);
    dq[i] = sqrt(det); /* det Q for any Q with Q^T Q = G */
  }
  free_metric(p);
  p->mG = mG;
  p->mdq = dq;
  p->metric = VM_METRIC_TENSOR;
  return VM_OK;
}

int vm_problem_set_weights(vm_problem *p, const double *w) {
  vm_problem_touch(p);
  if (!p) return VM_ERR_ARG;
  if (w)
    for (int64_t i = 0; i < p->nae; i++)
      if (!(w[p->ael[i]] >= 0) || !isfinite(w[p->ael[i]]))
        return vm_error(p->ctx, VM_ERR_ARG, "weight of element %d is %g, not finite and >= 0",
                        p->ael[i], w[p->ael[i]]);
  for (int64_t i = 0; i < p->nae; i++) p->wel[i] = w ? w[p->ael[i]] : 1.0;
  update_tvol(p);
  return VM_OK;
}

int vm_problem_update_normals(vm_problem *p, const double *vertex_normals) {
  vm_problem_touch_geometry(p);
  if (!p) return VM_ERR_ARG;
  if (p->kind != VM_PK_SURF) return VM_OK;
  double *nrm = vm_alloc_array(p->ctx, (size_t)p->nae * 3, sizeof *nrm);
  if (!nrm) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < p->nae; i++) {
    int k = nverts_of[elem_type(p, i)];
    double n[3] = {0, 0, 0};
    if (vertex_normals) {
      const int32_t *cv = elem_verts(p, i);
      for (int a = 0; a < k; a++)
        for (int r = 0; r < 3; r++) n[r] += vertex_normals[3 * (int64_t)cv[a] + r];
    } else {
      double x[VM_MAX_ELEM_VERTS * 3];
      gather(p, i, p->m->xyz, x);
      newell(x, k, n);
    }
    double l = sqrt(vm_dot3(n, n));
    if (!(l > 0) || !isfinite(l)) {
      vm_free(p->ctx, nrm);
      return vm_error(p->ctx, VM_ERR_ARG, "element %d: no normal (degenerate %s)", p->ael[i],
                      vertex_normals ? "vertex normals" : "element");
    }
    for (int r = 0; r < 3; r++) nrm[3 * i + r] = n[r] / l;
  }
  vm_free(p->ctx, p->nrm);
  p->nrm = nrm;
  return VM_OK;
}

/* Vertex -> active elements (ascending) in CSR form. */
static int build_v2e(vm_problem *p, int64_t **rp_out, int32_t **el_out) {
  vm_ctx *ctx = p->ctx;
  int64_t nv = p->m->nv;
  int64_t *rp = vm_calloc(ctx, (size_t)nv + 1, sizeof *rp);
  if (!rp) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < p->nae; i++) {
    const int32_t *cv = elem_verts(p, i);
    for (int a = 0; a < nverts_of[elem_type(p, i)]; a++) rp[cv[a] + 1]++;
  }
  for (int64_t v = 0; v < nv; v++) rp[v + 1] += rp[v];
  int32_t *el = vm_alloc_array(ctx, (size_t)(rp[nv] ? rp[nv] : 1), sizeof *el);
  int64_t *fill = vm_alloc_array(ctx, (size_t)(nv ? nv : 1), sizeof *fill);
  if (!el || !fill) {
    vm_free(ctx, rp);
    vm_free(ctx, el);
    vm_free(ctx, fill);
    return VM_ERR_NOMEM;
  }
  memcpy(fill, rp, (size_t)nv * sizeof *fill);
  for (int64_t i = 0; i < p->nae; i++) {
    const int32_t *cv = elem_verts(p, i);
    for (int a = 0; a < nverts_of[elem_type(p, i)]; a++) el[fill[cv[a]]++] = (int32_t)i;
  }
  vm_free(ctx, fill);
  *rp_out = rp;
  *el_out = el;
  return VM_OK;
}

/* Sorted neighbours of v (without v) into out, or only their count when
 * out is NULL; mark[] holds stamps, -1 initially. */
static int64_t vertex_row(const vm_problem *p, const int64_t *vrp, const int32_t *vel, int64_t v,
                          int32_t *mark, int32_t *out) {
  int64_t c = 0;
  mark[v] = (int32_t)v;
  for (int64_t k = vrp[v]; k < vrp[v + 1]; k++) {
    const int32_t *cv = elem_verts(p, vel[k]);
    for (int a = 0; a < nverts_of[elem_type(p, vel[k])]; a++)
      if (mark[cv[a]] != (int32_t)v) {
        mark[cv[a]] = (int32_t)v;
        if (out) {
          int64_t j = c;
          for (; j > 0 && out[j - 1] > cv[a]; j--) out[j] = out[j - 1];
          out[j] = cv[a];
        }
        c++;
      }
  }
  return c;
}

static int build_graph(vm_problem *p, const int64_t *vrp, const int32_t *vel) {
  vm_ctx *ctx = p->ctx;
  int64_t nv = p->m->nv;
  int nt = vm_problem_threads(p);
  int64_t *rp = vm_alloc_array(ctx, (size_t)nv + 1, sizeof *rp);
  int32_t *mark = vm_alloc_array(ctx, (size_t)(nv ? nv : 1) * (size_t)nt, sizeof *mark);
  if (!rp || !mark) {
    vm_free(ctx, rp);
    vm_free(ctx, mark);
    return VM_ERR_NOMEM;
  }
  rp[0] = 0;
#pragma omp parallel num_threads(nt)
  {
    int32_t *mk = mark;
#ifdef _OPENMP
    mk += (size_t)nv * (size_t)omp_get_thread_num();
#endif
    for (int64_t v = 0; v < nv; v++) mk[v] = -1;
#pragma omp for schedule(static)
    for (int64_t v = 0; v < nv; v++) rp[v + 1] = vertex_row(p, vrp, vel, v, mk, NULL);
  }
  for (int64_t v = 0; v < nv; v++) rp[v + 1] += rp[v];
  int32_t *adj = vm_alloc_array(ctx, (size_t)(rp[nv] ? rp[nv] : 1), sizeof *adj);
  if (!adj) {
    vm_free(ctx, rp);
    vm_free(ctx, mark);
    return VM_ERR_NOMEM;
  }
#pragma omp parallel num_threads(nt)
  {
    int32_t *mk = mark;
#ifdef _OPENMP
    mk += (size_t)nv * (size_t)omp_get_thread_num();
#endif
    for (int64_t v = 0; v < nv; v++) mk[v] = -1;
#pragma omp for schedule(static)
    for (int64_t v = 0; v < nv; v++) vertex_row(p, vrp, vel, v, mk, adj + rp[v]);
  }
  vm_free(ctx, mark);
  p->rowptr = rp;
  p->adj = adj;
  return VM_OK;
}

/* Greedy colouring of chunks of `chunk` consecutive active elements in
 * order; returns the number of colours in *ncolor, colours in color[]. */
static void color_chunks(const vm_problem *p, const int64_t *vrp, const int32_t *vel, int64_t chunk,
                         int32_t *color, int64_t *forb, int *ncolor) {
  int64_t nchunk = (p->nae + chunk - 1) / chunk;
  int nc = 0;
  for (int64_t c = 0; c < nchunk; c++) {
    int64_t i1 = (c + 1) * chunk < p->nae ? (c + 1) * chunk : p->nae;
    for (int64_t i = c * chunk; i < i1; i++) {
      const int32_t *cv = elem_verts(p, i);
      for (int a = 0; a < nverts_of[elem_type(p, i)]; a++)
        for (int64_t k = vrp[cv[a]]; k < vrp[cv[a] + 1] && vel[k] < c * chunk; k++)
          forb[color[vel[k] / chunk]] = c;
    }
    int col = 0;
    while (forb[col] == c) col++;
    color[c] = col;
    if (col + 1 > nc) nc = col + 1;
  }
  *ncolor = nc;
}

/* Colour chunks of elements, no two chunks of a colour sharing a vertex.
 * Chunks keep each thread's work contiguous in memory; the chunk size is the
 * largest power of two up to 256 that leaves at least 8 chunks per colour,
 * chosen from the mesh alone so the summation order is the same for any
 * number of threads. */
static int build_colors(vm_problem *p, const int64_t *vrp, const int32_t *vel) {
  vm_ctx *ctx = p->ctx;
  int64_t nae = p->nae;
  int32_t *color = vm_alloc_array(ctx, (size_t)nae, sizeof *color);
  int64_t *forb = vm_alloc_array(ctx, (size_t)nae + 1, sizeof *forb);
  if (!color || !forb) {
    vm_free(ctx, color);
    vm_free(ctx, forb);
    return VM_ERR_NOMEM;
  }
  int64_t chunk = 256;
  int ncolor = 0;
  for (;; chunk /= 2) {
    for (int64_t c = 0; c <= nae; c++) forb[c] = -1;
    color_chunks(p, vrp, vel, chunk, color, forb, &ncolor);
    if (chunk == 1 || (nae + chunk - 1) / chunk >= 8 * (int64_t)ncolor) break;
  }
  vm_free(ctx, forb);
  int64_t nchunk = (nae + chunk - 1) / chunk;
  int64_t *coff = vm_calloc(ctx, (size_t)ncolor + 1, sizeof *coff);
  int32_t *clist = vm_alloc_array(ctx, (size_t)nchunk, sizeof *clist);
  if (!coff || !clist) {
    vm_free(ctx, color);
    vm_free(ctx, coff);
    vm_free(ctx, clist);
    return VM_ERR_NOMEM;
  }
  for (int64_t c = 0; c < nchunk; c++) coff[color[c] + 1]++;
  for (int c = 0; c < ncolor; c++) coff[c + 1] += coff[c];
  for (int64_t c = 0; c < nchunk; c++) clist[coff[color[c]]++] = (int32_t)c;
  for (int c = ncolor; c > 0; c--) coff[c] = coff[c - 1];
  coff[0] = 0;
  vm_free(ctx, color);
  p->chunk = chunk;
  p->nchunk = nchunk;
  p->ncolor = ncolor;
  p->coff = coff;
  p->clist = clist;
  return VM_OK;
}

int vm_problem_create(vm_ctx *ctx, vm_mesh *m, vm_problem **out) {
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_problem_create: out is NULL");
  *out = NULL;
  if (!m) return vm_error(ctx, VM_ERR_ARG, "vm_problem_create: mesh is NULL");
  int64_t counts[VM_NTYPES];
  int tdim = vm_mesh_count_types(m, counts);
  if (tdim != 2 && tdim != 3) return vm_error(ctx, VM_ERR_ARG, "mesh has no 2D or 3D elements");
  if (tdim == 3 && m->dim != 3)
    return vm_error(ctx, VM_ERR_ARG, "3D elements in a mesh of dimension %d", m->dim);
  vm_problem *p = vm_calloc(ctx, 1, sizeof *p);
  if (!p) return VM_ERR_NOMEM;
  p->ctx = ctx;
  p->m = m;
  p->tdim = tdim;
  p->kind = tdim == 3 ? VM_PK_VOL3 : m->dim == 2 ? VM_PK_PLANE : VM_PK_SURF;
  p->ops = vm_measure_get(VM_MEASURE_BALANCED);
  p->prm = vm_measure_params_default();
  p->rule = VM_RULE_CORNER;
  p->tgt_store = VM_PROBLEM_TARGET_STORE;
  p->gen = 1;
  p->ggen = 1;
  p->fix_sd_rule = -1;
  for (int t = 0; t < VM_NTYPES; t++) p->qr[t] = vm_qrule_get(t, VM_RULE_CORNER);
  build_patterns(p);
  int st = VM_OK;
  int64_t *vrp = NULL;
  int32_t *vel = NULL;

  for (int t = 0; t < VM_NTYPES; t++)
    if (vm_elem_dim(t) == tdim) p->nae += counts[t];
  p->ael = vm_alloc_array(ctx, (size_t)p->nae, sizeof *p->ael);
  p->wel = vm_alloc_array(ctx, (size_t)p->nae, sizeof *p->wel);
  p->Fe = vm_calloc(ctx, (size_t)p->nae, sizeof *p->Fe);
  p->nblock = (p->nae + VM_PROBLEM_FBLOCK - 1) / VM_PROBLEM_FBLOCK;
  p->part = vm_calloc(ctx, (size_t)p->nblock, sizeof *p->part);
  if (!p->ael || !p->wel || !p->Fe || !p->part) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != tdim) continue;
    const int32_t *cv = m->conn + m->eoff[e];
    int k = vm_elem_nverts(t);
    for (int a = 0; a < k; a++) {
      if (cv[a] < 0 || cv[a] >= m->nv) {
        st = vm_error(ctx, VM_ERR_ARG, "element %lld: vertex %d out of range", (long long)e, cv[a]);
        goto fail;
      }
    }
    int32_t rv = vm_mesh_repeated_vertex(m, e);
    if (rv >= 0) {
      st = vm_error(ctx, VM_ERR_ARG,
                    "element %lld (%s) uses vertex %d at two of its corners: a collapsed "
                    "element, which has no valid shape to optimize towards",
                    (long long)e, vm_elem_name(t), rv);
      goto fail;
    }
    p->ael[n] = (int32_t)e;
    p->wel[n] = 1.0;
    n++;
  }
  if ((st = build_nodes(p, &p->noff, &p->nelem, &p->nn))) goto fail;
  if ((st = build_v2e(p, &vrp, &vel))) goto fail;
  if ((st = build_graph(p, vrp, vel))) goto fail;
  if ((st = build_colors(p, vrp, vel))) goto fail;
  vm_free(ctx, vrp);
  vm_free(ctx, vel);
  vrp = NULL;
  vel = NULL;
  if ((st = vm_problem_update_normals(p, NULL))) goto fail;
  if ((st = vm_problem_set_target_ideal(p, 0))) goto fail;
  *out = p;
  return VM_OK;
fail:
  vm_free(ctx, vrp);
  vm_free(ctx, vel);
  vm_problem_destroy(&p);
  return st;
}

void vm_problem_destroy(vm_problem **pp) {
  if (!pp || !*pp) return;
  vm_problem *p = *pp;
  vm_ctx *ctx = p->ctx;
  vm_free(ctx, p->coff);
  vm_free(ctx, p->clist);
  vm_free(ctx, p->amask);
  vm_free(ctx, p->rowptr);
  vm_free(ctx, p->adj);
  vm_free(ctx, p->ppos);
  vm_free(ctx, p->ael);
  vm_free(ctx, p->noff);
  vm_free(ctx, p->nelem);
  vm_free(ctx, p->tgt_ref);
  vm_free(ctx, p->tgt_fld);
  vm_free(ctx, p->Snode);
  vm_free(ctx, p->wnode);
  vm_free(ctx, p->wsum);
  vm_free(ctx, p->mg);
  vm_free(ctx, p->mG);
  vm_free(ctx, p->mdq);
  vm_free(ctx, p->wel);
  vm_free(ctx, p->nrm);
  vm_free(ctx, p->eps_node);
  vm_free(ctx, p->node_w);
  vm_free(ctx, p->bern_w);
  vm_free(ctx, p->bern_eps);
  vm_free(ctx, p->Fe);
  vm_free(ctx, p->part);
  vm_problem_fix_free(p);
  vm_problem_nsd_free(p);
  vm_free(ctx, p);
  *pp = NULL;
}

int64_t vm_problem_num_nodes(const vm_problem *p) { return p ? p->nn : 0; }
int vm_problem_dim(const vm_problem *p) { return p ? p->tdim : 0; }
const vm_mesh *vm_problem_mesh(const vm_problem *p) { return p ? p->m : NULL; }
double vm_problem_target_volume(const vm_problem *p) { return p ? p->tvol : 0; }
double vm_problem_target_size(const vm_problem *p) {
  return p && p->tgt == VM_TGT_IDEAL ? p->tgt_size : 0;
}

void vm_problem_graph(const vm_problem *p, const int64_t **rowptr, const int32_t **adj) {
  if (rowptr) *rowptr = p ? p->rowptr : NULL;
  if (adj) *adj = p ? p->adj : NULL;
}

const int32_t *vm_problem_node_elements(const vm_problem *p) { return p ? p->nelem : NULL; }

int vm_problem_set_active(vm_problem *p, const uint8_t *mask) {
  vm_problem_touch(p);
  if (!p) return VM_ERR_ARG;
  uint8_t *am = NULL;
  if (mask) {
    am = vm_alloc_array(p->ctx, (size_t)p->nae, 1);
    if (!am) return VM_ERR_NOMEM;
    for (int64_t i = 0; i < p->nae; i++) am[i] = mask[p->ael[i]] != 0;
  }
  vm_free(p->ctx, p->amask);
  p->amask = am;
  return VM_OK;
}

int vm_problem_set_node_eps(vm_problem *p, const double *eps_node) {
  vm_problem_touch(p);
  if (!p) return VM_ERR_ARG;
  if (!eps_node) {
    vm_free(p->ctx, p->eps_node);
    p->eps_node = NULL;
    return VM_OK;
  }
  for (int64_t q = 0; q < p->nn; q++)
    if (!(eps_node[q] >= 0) || !isfinite(eps_node[q]))
      return vm_error(p->ctx, VM_ERR_ARG, "eps of node %lld is %g, not finite and >= 0",
                      (long long)q, eps_node[q]);
  double *e = vm_alloc_array(p->ctx, (size_t)(p->nn ? p->nn : 1), sizeof *e);
  if (!e) return VM_ERR_NOMEM;
  memcpy(e, eps_node, (size_t)p->nn * sizeof *e);
  vm_free(p->ctx, p->eps_node);
  p->eps_node = e;
  return VM_OK;
}

int vm_problem_set_node_weights(vm_problem *p, const double *w_node) {
  vm_problem_touch(p);
  if (!p) return VM_ERR_ARG;
  if (!w_node) {
    vm_free(p->ctx, p->node_w);
    p->node_w = NULL;
    return VM_OK;
  }
  for (int64_t q = 0; q < p->nn; q++)
    if (!(w_node[q] >= 0) || !isfinite(w_node[q]))
      return vm_error(p->ctx, VM_ERR_ARG, "weight of node %lld is %g, not finite and >= 0",
                      (long long)q, w_node[q]);
  double *w = vm_alloc_array(p->ctx, (size_t)(p->nn ? p->nn : 1), sizeof *w);
  if (!w) return VM_ERR_NOMEM;
  memcpy(w, w_node, (size_t)p->nn * sizeof *w);
  vm_free(p->ctx, p->node_w);
  p->node_w = w;
  return VM_OK;
}

int vm_problem_set_bernstein(vm_problem *p, const double *w_elem, const double *eps_coef,
                             double scale) {
  vm_problem_touch(p);
  if (!p) return VM_ERR_ARG;
  vm_free(p->ctx, p->bern_w);
  vm_free(p->ctx, p->bern_eps);
  p->bern_w = p->bern_eps = NULL;
  if (!w_elem) return VM_OK;
  if (!(scale > 0) || !isfinite(scale))
    return vm_error(p->ctx, VM_ERR_ARG, "Bernstein scale %g is not finite and > 0", scale);
  size_t n = (size_t)(p->nae ? p->nae : 1);
  double *w = vm_alloc_array(p->ctx, n, sizeof *w);
  double *e = eps_coef ? vm_alloc_array(p->ctx, 27 * n, sizeof *e) : NULL;
  if (!w || (eps_coef && !e)) {
    vm_free(p->ctx, w);
    vm_free(p->ctx, e);
    return VM_ERR_NOMEM;
  }
  for (int64_t i = 0; i < p->nae; i++) {
    int32_t el = p->ael[i];
    w[i] = p->m->etype[el] == VM_HEX ? w_elem[el] : 0;
    if (!(w[i] >= 0) || !isfinite(w[i])) {
      vm_free(p->ctx, w);
      vm_free(p->ctx, e);
      return vm_error(p->ctx, VM_ERR_ARG, "Bernstein weight of element %lld is %g", (long long)el,
                      w_elem[el]);
    }
    for (int c = 0; e && c < 27; c++) {
      double v = eps_coef[27 * (int64_t)el + c];
      if (w[i] > 0 && !(v > 0 && isfinite(v))) {
        vm_free(p->ctx, w);
        vm_free(p->ctx, e);
        return vm_error(p->ctx, VM_ERR_ARG, "Bernstein eps %g of element %lld is not > 0", v,
                        (long long)el);
      }
      e[27 * i + c] = v;
    }
  }
  p->bern_w = w;
  p->bern_eps = e;
  p->bern_scale = scale;
  return VM_OK;
}

int vm_problem_set_fixed_derivatives(vm_problem *p, int want) {
  if (!p) return VM_ERR_ARG;
  p->skip_fixed = !want;
  return VM_OK;
}
