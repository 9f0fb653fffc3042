/* lib/core/src/quality.c: Table 1 quality figures (M, phi_min, psi_min) and
 * scaled Jacobians over the quadrature nodes of every element. */
#include "varmesh/quality.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "inline.h"
#include "vec3.h"

static double det3(const double *A) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static int inv3(const double *A, double *B) {
  double d = det3(A);
  if (d == 0) return 1;
  B[0] = (A[4] * A[8] - A[5] * A[7]) / d;
  B[1] = (A[2] * A[7] - A[1] * A[8]) / d;
  B[2] = (A[1] * A[5] - A[2] * A[4]) / d;
  B[3] = (A[5] * A[6] - A[3] * A[8]) / d;
  B[4] = (A[0] * A[8] - A[2] * A[6]) / d;
  B[5] = (A[2] * A[3] - A[0] * A[5]) / d;
  B[6] = (A[3] * A[7] - A[4] * A[6]) / d;
  B[7] = (A[1] * A[6] - A[0] * A[7]) / d;
  B[8] = (A[0] * A[4] - A[1] * A[3]) / d;
  return 0;
}

/* Columns of a node's edge matrix in 3D from element coordinates x[i*3+r]. */
static void node_cols(const vm_qnode *q, int d, const double *x, double col[3][3]) {
  for (int k = 0; k < d; k++)
    for (int r = 0; r < 3; r++) col[k][r] = x[q->head[k] * 3 + r] - x[q->tail[k] * 3 + r];
}

/* Per node: signed det of E, s = |E T^{-1}|^2, det of E T^{-1}, corner
 * scaled-Jacobian value. `Tinv` maps target to reference edges; `nrm` is the
 * reference normal for 2D elements (NULL for 3D). */
typedef struct {
  double det_c, s, sj_raw;
} node_val;

static node_val eval_node(const vm_qnode *q, int d, const double *x, const double *Tinv,
                          const double *nrm) {
  double col[3][3];
  node_cols(q, d, x, col);
  node_val r;
  if (d == 3) {
    double E[9];
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) E[i * 3 + k] = col[k][i];
    double C[9] = {0};
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        for (int k = 0; k < 3; k++) C[i * 3 + j] += E[i * 3 + k] * Tinv[k * 3 + j];
    double dE = det3(E);
    r.det_c = det3(C);
    r.s = 0;
    for (int i = 0; i < 9; i++) r.s += C[i] * C[i];
    double l = vm_norm3(col[0]) * vm_norm3(col[1]) * vm_norm3(col[2]);
    r.sj_raw = l > 0 ? dE / l : 0;
  } else {
    double c[3];
    vm_cross3(col[0], col[1], c);
    double dE = c[0] * nrm[0] + c[1] * nrm[1] + c[2] * nrm[2];
    /* C = E T^{-1} in the tangent frame: s from the 3x2 product, det scaled */
    double s = 0;
    for (int rr = 0; rr < 3; rr++)
      for (int j = 0; j < 2; j++) {
        double v = col[0][rr] * Tinv[0 * 2 + j] + col[1][rr] * Tinv[1 * 2 + j];
        s += v * v;
      }
    double dT = Tinv[0] * Tinv[3] - Tinv[1] * Tinv[2];
    r.det_c = dE * dT;
    r.s = s;
    double l = vm_norm3(col[0]) * vm_norm3(col[1]);
    r.sj_raw = l > 0 ? dE / l : 0;
  }
  return r;
}

/* T^{-1} for every node of a rule from reference coordinates `ref` (scaled
 * by `h`); d x d row-major, Tinv[q*9 ..]. */
static void rule_tinv(const vm_qrule *R, const double *ref, double h, double *Tinv) {
  for (int n = 0; n < R->nnodes; n++) {
    double col[3][3];
    node_cols(&R->nodes[n], R->dim, ref, col);
    if (R->dim == 3) {
      double T[9];
      for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) T[i * 3 + k] = h * col[k][i];
      inv3(T, Tinv + 9 * n);
    } else {
      /* ideal 2D elements lie in the xy plane */
      double a = h * col[0][0], b = h * col[1][0], c = h * col[0][1], dd = h * col[1][1];
      double det = a * dd - b * c;
      double *o = Tinv + 9 * n;
      o[0] = dd / det;
      o[1] = -b / det;
      o[2] = -c / det;
      o[3] = a / det;
    }
  }
}

/* A face of n > 3 vertices, as OpenFOAM takes it: the triangles from each
 * edge to the vertices' mean. Inlined with n a constant for quads (the
 * same operations, so the same bits). */
VM_INLINE void foam_polygon(const double *y, int n, double *c, double *s) {
  double pc[3] = {0, 0, 0}, sa = 0, sc[3] = {0, 0, 0};
  for (int i = 0; i < n; i++)
    for (int r = 0; r < 3; r++) pc[r] += y[3 * i + r];
  for (int r = 0; r < 3; r++) pc[r] /= n;
  s[0] = s[1] = s[2] = 0;
  for (int i = 0; i < n; i++) {
    const double *a = y + 3 * i, *b = y + 3 * ((i + 1) % n);
    double u[3], w[3], nn[3];
    vm_sub3(b, a, u);
    vm_sub3(pc, a, w);
    vm_cross3(u, w, nn);
    double an = vm_norm3(nn);
    for (int r = 0; r < 3; r++) {
      s[r] += 0.5 * nn[r];
      sc[r] += an * (a[r] + b[r] + pc[r]);
    }
    sa += an;
  }
  for (int r = 0; r < 3; r++) c[r] = sa > 0 ? sc[r] / (3 * sa) : pc[r];
}

void vm_foam_face(const double *y, int n, double *c, double *s) {
  if (n == 4) {
    foam_polygon(y, 4, c, s);
    return;
  }
  if (n == 3) {
    double u[3], w[3];
    vm_sub3(y + 3, y, u);
    vm_sub3(y + 6, y, w);
    vm_cross3(u, w, s);
    for (int r = 0; r < 3; r++) {
      s[r] *= 0.5;
      c[r] = (y[r] + y[3 + r] + y[6 + r]) / 3;
    }
    return;
  }
  foam_polygon(y, n, c, s);
}

/* vm_cell_foam, and the least face pyramid's volume over the cell's
 * (-INFINITY for a cell of volume 0). */
static int foam_cell(int type, const double *x, double *volume, double *margin, double *centre) {
  int fv[6][4], nfv[6];
  if (type < VM_TET || type >= VM_NTYPES) return -1;
  int nf = vm_elem_faces(type, fv, nfv);
  double fc[6][3], fs[6][3], est[3] = {0, 0, 0};
  for (int f = 0; f < nf; f++) {
    double y[12];
    for (int i = 0; i < nfv[f]; i++) memcpy(y + 3 * i, x + 3 * fv[f][i], 3 * sizeof *y);
    vm_foam_face(y, nfv[f], fc[f], fs[f]);
    for (int r = 0; r < 3; r++) est[r] += fc[f][r];
  }
  for (int r = 0; r < 3; r++) est[r] /= nf;
  double v3 = 0, sum[3] = {0, 0, 0}, cc[3];
  for (int f = 0; f < nf; f++) {
    double d[3];
    vm_sub3(fc[f], est, d);
    double v = vm_dot3(fs[f], d);
    for (int r = 0; r < 3; r++) sum[r] += v * (0.75 * fc[f][r] + 0.25 * est[r]);
    v3 += v;
  }
  for (int r = 0; r < 3; r++) cc[r] = fabs(v3) > 0 ? sum[r] / v3 : est[r];
  int bad = 0;
  double least = INFINITY;
  for (int f = 0; f < nf; f++) {
    double d[3];
    vm_sub3(fc[f], cc, d);
    double v = vm_dot3(fs[f], d);
    bad += !(v > 0);
    if (!(v >= least)) least = v;
  }
  if (volume) *volume = v3 / 3;
  if (centre) memcpy(centre, cc, sizeof cc);
  if (margin) *margin = fabs(v3) > 0 ? least / fabs(v3) : -INFINITY;
  return bad;
}

int vm_cell_foam(int type, const double *x, double *volume) {
  return foam_cell(type, x, volume, NULL, NULL);
}

int vm_cell_foam_centre(int type, const double *x, double *centre, double *volume) {
  return foam_cell(type, x, volume, NULL, centre);
}

double vm_foam_skew(const double *x, int n, const double *c, const double *s, const double *cp,
                    const double *cn) {
  double d[3], e[3], sv[3];
  vm_sub3(cn, cp, d);
  vm_sub3(c, cp, e);
  double sd = vm_dot3(s, d);
  if (!(fabs(sd) > 0)) return INFINITY;
  for (int r = 0; r < 3; r++) sv[r] = e[r] - vm_dot3(s, e) / sd * d[r];
  double l = vm_norm3(sv), fd = 0.2 * vm_norm3(d);
  for (int i = 0; i < n && l > 0; i++) {
    double a = fabs(vm_dot3(sv, x + 3 * i) - vm_dot3(sv, c)) / l;
    fd = a > fd ? a : fd;
  }
  return fd > 0 ? l / fd : INFINITY;
}

double vm_foam_ortho_cos(const double *c, const double *s, const double *cp, const double *cn) {
  double d[3], e[3];
  vm_sub3(cn, cp, d);
  vm_sub3(c, cp, e);
  double ls = vm_norm3(s), ld = vm_norm3(d);
  if (!(ls > 0) || !(ld > 0)) return -1;
  /* the face's orientation: away from cp (the face centre lies on cp's
   * outer side of a valid cell) */
  double sd = vm_dot3(s, d) / (ls * ld);
  return vm_dot3(s, e) < 0 ? -sd : sd;
}

double vm_foam_weight(const double *c, const double *s, const double *cp, const double *cn) {
  double dp = fabs(s[0] * (c[0] - cp[0]) + s[1] * (c[1] - cp[1]) + s[2] * (c[2] - cp[2]));
  double dn = fabs(s[0] * (cn[0] - c[0]) + s[1] * (cn[1] - c[1]) + s[2] * (cn[2] - c[2]));
  double w = dp + dn > 0 ? dn / (dp + dn) : 0;
  return w < 1 - w ? w : 1 - w;
}

double vm_foam_cell_determinant(int nf, const double (*s)[3]) {
  double avg = 0;
  for (int f = 0; f < nf; f++) avg += vm_norm3(s[f]);
  if (!nf || !(avg > 0)) return 0;
  avg /= nf;
  double t[6] = {0, 0, 0, 0, 0, 0}; /* xx xy xz yy yz zz */
  for (int f = 0; f < nf; f++) {
    double a[3] = {s[f][0] / avg, s[f][1] / avg, s[f][2] / avg};
    t[0] += a[0] * a[0], t[1] += a[0] * a[1], t[2] += a[0] * a[2];
    t[3] += a[1] * a[1], t[4] += a[1] * a[2], t[5] += a[2] * a[2];
  }
  double det = t[0] * (t[3] * t[5] - t[4] * t[4]) - t[1] * (t[1] * t[5] - t[4] * t[2]) +
               t[2] * (t[1] * t[4] - t[3] * t[2]);
  /* over 8, the cube's (eigenvalues 2, 2, 2): checkMesh's 0..1 */
  return fabs(det) / 8;
}

double vm_cell_foam_margin(int type, const double *x) {
  double m;
  return foam_cell(type, x, NULL, &m, NULL) < 0 ? NAN : m;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void tq_init(vm_type_quality *t) {
  memset(t, 0, sizeof *t);
  t->phi_min = t->psi_min = t->sj_min = INFINITY;
}

/* The figures of q, and per element (if esj / ephi are not NULL) the scaled
 * Jacobian and the minimum phi, NAN for elements not measured. */
static int measure(const vm_mesh *m, const vm_quality_opts *opts, vm_quality *q, double *esj,
                   double *ephi) {
  vm_ctx *ctx = m->ctx;
  vm_quality_opts o = {VM_RULE_CORNER, 0};
  if (opts) o = *opts;
  memset(q, 0, sizeof *q);
  for (int t = 0; t < VM_NTYPES; t++) tq_init(&q->type[t]);
  tq_init(&q->all);
  q->min_det = INFINITY;
  int64_t counts[VM_NTYPES];
  q->top_dim = vm_mesh_count_types(m, counts);
  const vm_field *tsz = vm_mesh_find_field(m, "target_size", VM_FIELD_ELEMENT);
  if (tsz && tsz->type != VM_FIELD_F64) tsz = NULL;
  /* a size the measures divide by: positive and finite, or the run is
   * meaningless (1e200, -1 or NaN made a valid mesh "inverted") */
  if (tsz && !(o.target_size > 0))
    for (int64_t e = 0; e < m->ne; e++) {
      double h = ((const double *)tsz->data)[e * tsz->ncomp];
      if (vm_elem_dim(m->etype[e]) == q->top_dim && !(isfinite(h) && h > 0 && h < 1e300))
        return vm_error(ctx, VM_ERR_FORMAT,
                        "element %lld: target_size %.17g is not a positive finite size",
                        (long long)e, h);
    }
  int have_size = o.target_size > 0 || tsz;

  /* per type: node rules, target inverse at unit size, ideal SJ normalizer */
  double tinv[VM_NTYPES][VM_QRULE_MAX_NODES * 9];
  double sj_ideal[VM_NTYPES];
  const vm_qrule *rules[VM_NTYPES], *corner[VM_NTYPES];
  double tinv_c[VM_NTYPES][8 * 9];
  for (int t = 0; t < VM_NTYPES; t++) {
    double ref[VM_MAX_ELEM_VERTS * 3];
    vm_elem_ideal(t, ref);
    rules[t] = vm_qrule_get(t, o.rule);
    corner[t] = vm_qrule_get(t, VM_RULE_CORNER);
    rule_tinv(rules[t], ref, 1.0, tinv[t]);
    rule_tinv(corner[t], ref, 1.0, tinv_c[t]);
    static const double zn[3] = {0, 0, 1};
    sj_ideal[t] = INFINITY;
    for (int n = 0; n < corner[t]->nnodes; n++) {
      node_val v = eval_node(&corner[t]->nodes[n], corner[t]->dim, ref, tinv_c[t] + 9 * n, zn);
      if (v.sj_raw < sj_ideal[t]) sj_ideal[t] = v.sj_raw;
    }
  }

  double *sj = vm_alloc_array(ctx, (size_t)(m->ne ? m->ne : 1), sizeof *sj);
  if (!sj) return VM_ERR_NOMEM;
  int64_t nsj = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    int d = vm_elem_dim(t);
    if (d != q->top_dim) {
      q->skipped++;
      if (esj) esj[e] = NAN;
      if (ephi) ephi[e] = NAN;
      continue;
    }
    int k = vm_elem_nverts(t);
    double x[VM_MAX_ELEM_VERTS * 3];
    /* scaled by the power of two nearest its extent: the figures do not
     * depend on units (a valid mesh scaled by 1e-120 had every det
     * underflow to 0: "inverted"), and a power of two changes no rounding:
     * at ordinary scales every sign is the one of the raw coordinates */
    const double *p0 = m->xyz + 3 * m->conn[m->eoff[e]];
    double ext = 0;
    for (int i = 0; i < k; i++) {
      const double *p = m->xyz + 3 * m->conn[m->eoff[e] + i];
      for (int c = 0; c < (m->dim == 2 ? 2 : 3); c++) ext = fmax(ext, fabs(p[c] - p0[c]));
    }
    int ex = 0;
    if (ext > 0 && isfinite(ext)) frexp(ext, &ex);
    double L = ldexp(1.0, ex);
    for (int i = 0; i < k; i++) {
      const double *p = m->xyz + 3 * m->conn[m->eoff[e] + i];
      x[3 * i] = ldexp(p[0], -ex);
      x[3 * i + 1] = ldexp(p[1], -ex);
      x[3 * i + 2] = m->dim == 2 ? 0 : ldexp(p[2], -ex);
    }
    double nrm[3] = {0, 0, 1};
    if (d == 2 && m->dim == 3) {
      /* Newell normal */
      nrm[0] = nrm[1] = nrm[2] = 0;
      for (int i = 0; i < k; i++) {
        const double *a = x + 3 * i, *b = x + 3 * ((i + 1) % k);
        nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
      }
      double l = vm_norm3(nrm);
      if (l > 0)
        for (int i = 0; i < 3; i++) nrm[i] /= l;
    }
    double h = o.target_size > 0 ? o.target_size : tsz ? ((double *)tsz->data)[e * tsz->ncomp] : 1;
    /* det C at size h = det C of the frame times (L/h)^d */
    double scale = pow(L / h, d);
    vm_type_quality *tq = &q->type[t];
    tq->count++;
    int inv = 0;
    double ephi_min = INFINITY;
    const vm_qrule *R = rules[t];
    for (int n = 0; n < R->nnodes; n++) {
      node_val v = eval_node(&R->nodes[n], d, x, tinv[t] + 9 * n, nrm);
      double detc = v.det_c * scale;
      tq->nodes++;
      /* the sign in the element's frame: no scale can flip or zero it */
      if (v.det_c <= 0) {
        tq->inverted_nodes++;
        inv = 1;
      }
      /* phi is scale-free: from the frame's values */
      double phi = v.s > 0 ? v.det_c / (d == 3 ? pow(v.s / 3, 1.5) : v.s / 2) : -INFINITY;
      if (phi < tq->phi_min) tq->phi_min = phi;
      if (phi < ephi_min) ephi_min = phi;
      if (have_size) {
        double psi = 2 * detc / (1 + detc * detc);
        if (psi < tq->psi_min) tq->psi_min = psi;
        if (detc < q->min_det) q->min_det = detc;
      } else if (v.det_c * pow(L, d) < q->min_det) {
        q->min_det = v.det_c * pow(L, d);
      }
    }
    double sjm = INFINITY;
    const vm_qrule *Cr = corner[t];
    for (int n = 0; n < Cr->nnodes; n++) {
      node_val v = eval_node(&Cr->nodes[n], d, x, tinv_c[t] + 9 * n, nrm);
      if (v.sj_raw < sjm) sjm = v.sj_raw;
    }
    sjm /= sj_ideal[t];
    if (sjm > 1) sjm = 1; /* rounding above the ideal */
    if (sjm < tq->sj_min) tq->sj_min = sjm;
    sj[nsj++] = sjm;
    if (esj) esj[e] = sjm;
    if (ephi) ephi[e] = ephi_min;
    if (inv) tq->inverted_elems++;
    if (d == 3) {
      double vol;
      q->foam_pyramid_errors += vm_cell_foam(t, x, &vol);
      q->foam_neg_volumes += !(vol > 0);
    }
    if (t == VM_PRISM) q->prism_split_negative += vm_prism_split_check(x, NULL) > 0;
  }
  for (int t = 0; t < VM_NTYPES; t++) {
    vm_type_quality *tq = &q->type[t];
    if (!have_size) tq->psi_min = NAN;
    q->all.count += tq->count;
    q->all.nodes += tq->nodes;
    q->all.inverted_nodes += tq->inverted_nodes;
    q->all.inverted_elems += tq->inverted_elems;
    if (tq->count) {
      if (tq->phi_min < q->all.phi_min) q->all.phi_min = tq->phi_min;
      if (have_size && tq->psi_min < q->all.psi_min) q->all.psi_min = tq->psi_min;
      if (tq->sj_min < q->all.sj_min) q->all.sj_min = tq->sj_min;
    }
  }
  if (!have_size) q->all.psi_min = NAN;
  q->measured = nsj;
  qsort(sj, (size_t)nsj, sizeof *sj, cmp_double);
  if (nsj) {
    q->sj_p01 = sj[(nsj - 1) / 100];
    q->sj_p05 = sj[(nsj - 1) * 5 / 100];
    q->sj_p25 = sj[(nsj - 1) / 4];
    q->sj_p50 = sj[(nsj - 1) / 2];
  }
  for (int64_t i = 0; i < nsj; i++) {
    int b = (int)floor((sj[i] + 1) / 2 * VM_QUALITY_NBINS);
    if (b < 0) b = 0;
    if (b >= VM_QUALITY_NBINS) b = VM_QUALITY_NBINS - 1;
    q->sj_hist[b]++;
  }
  vm_free(ctx, sj);
  return VM_OK;
}

/* The tets of a prism's 3-tet splits that are not corner tets, each
 * ordered to be positive on the right prism. */
static const int split_tets[6][4] = {{0, 1, 5, 4}, {0, 1, 5, 3}, {1, 2, 3, 4},
                                     {1, 2, 3, 5}, {0, 2, 3, 4}, {0, 2, 5, 4}};

int vm_prism_split_check(const double *x, double *q) {
  int bad = 0;
  for (int j = 0; j < 6; j++) {
    const double *a = x + 3 * split_tets[j][0];
    double c[3][3];
    for (int k = 0; k < 3; k++)
      for (int r = 0; r < 3; r++) c[k][r] = x[3 * split_tets[j][k + 1] + r] - a[r];
    double cr[3] = {c[1][1] * c[2][2] - c[1][2] * c[2][1], c[1][2] * c[2][0] - c[1][0] * c[2][2],
                    c[1][0] * c[2][1] - c[1][1] * c[2][0]};
    double det = c[0][0] * cr[0] + c[0][1] * cr[1] + c[0][2] * cr[2];
    if (!(det > 0)) bad++;
    if (q) {
      double l = sqrt(c[0][0] * c[0][0] + c[0][1] * c[0][1] + c[0][2] * c[0][2]) *
                 sqrt(c[1][0] * c[1][0] + c[1][1] * c[1][1] + c[1][2] * c[1][2]) *
                 sqrt(c[2][0] * c[2][0] + c[2][1] * c[2][1] + c[2][2] * c[2][2]);
      q[j] = l > 0 ? det / l : -1;
    }
  }
  return bad;
}

int vm_mesh_quality(const vm_mesh *m, const vm_quality_opts *opts, vm_quality *q) {
  return measure(m, opts, q, NULL, NULL);
}

int vm_mesh_element_quality(const vm_mesh *m, const vm_quality_opts *opts, vm_quality *q,
                            double *sj, double *phi) {
  vm_quality tmp;
  return measure(m, opts, q ? q : &tmp, sj, phi);
}
