/* prism/src/geom.c: prism validity and quality over quadrature simplices,
 * blended column directions and per-prism target shapes, on plain arrays. */
#include "geom.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "varmesh/quadrature.h"
#include "varmesh/quality.h"
#include "varmesh/surface_mesh.h"

/* det(c0, c1, c2) over the product l of their lengths (+-1 where l is 0). */
static double edge_ratio(const double *c0, const double *c1, const double *c2, double l) {
  double cr[3];
  vm_cross3(c1, c2, cr);
  double det = vm_dot3(c0, cr);
  if (!(l > 0)) return det > 0 ? 1 : -1;
  return det / l;
}

static double node_ratio(const vm_qnode *q, const double *x) {
  double c[3][3];
  for (int k = 0; k < 3; k++)
    for (int r = 0; r < 3; r++) c[k][r] = x[3 * q->head[k] + r] - x[3 * q->tail[k] + r];
  return edge_ratio(c[0], c[1], c[2], vm_norm3(c[0]) * vm_norm3(c[1]) * vm_norm3(c[2]));
}

/* The geometric rule's 12 nodes use 7 edges of the prism between them:
 * each edge's vector and length is taken once (ev[6 head + tail], el),
 * the same values node_ratio would take at every node. */
double pr_prism_quality(const double *x) {
  const vm_qrule *R = vm_qrule_get(VM_PRISM, VM_RULE_GEOMETRIC);
  double ev[36][3], el[36];
  uint64_t have = 0;
  double q = INFINITY;
  for (int j = 0; j < R->nnodes; j++) {
    const vm_qnode *nd = &R->nodes[j];
    const double *c[3];
    double l[3];
    for (int k = 0; k < 3; k++) {
      int e = 6 * nd->head[k] + nd->tail[k];
      if (!(have >> e & 1)) {
        for (int r = 0; r < 3; r++) ev[e][r] = x[3 * nd->head[k] + r] - x[3 * nd->tail[k] + r];
        el[e] = vm_norm3(ev[e]);
        have |= (uint64_t)1 << e;
      }
      c[k] = ev[e];
      l[k] = el[e];
    }
    double v = edge_ratio(c[0], c[1], c[2], l[0] * l[1] * l[2]);
    if (v < q) q = v;
  }
  return q / (sqrt(3.0) / 2);
}

double pr_prism_corner_quality(const double *x, int *inverted) {
  const vm_qrule *R = vm_qrule_get(VM_PRISM, VM_RULE_CORNER);
  double q = INFINITY;
  int bad = 0;
  for (int j = 0; j < R->nnodes; j++) {
    const vm_qnode *nd = &R->nodes[j];
    double c[3][3];
    for (int k = 0; k < 3; k++)
      for (int r = 0; r < 3; r++) c[k][r] = x[3 * nd->head[k] + r] - x[3 * nd->tail[k] + r];
    double cr[3];
    vm_cross3(c[1], c[2], cr);
    if (!(vm_dot3(c[0], cr) > 0)) bad++;
    double v = node_ratio(nd, x);
    if (v < q) q = v;
  }
  if (inverted) *inverted = bad;
  return q / (sqrt(3.0) / 2);
}

double pr_tilt_deg(const double *o, const double *x, const double *n) {
  double e[3] = {x[0] - o[0], x[1] - o[1], x[2] - o[2]};
  double l = vm_norm3(e), cs = l > 0 ? vm_dot3(e, n) / l : -1;
  return acos(cs < -1 ? -1 : cs > 1 ? 1 : cs) * 180 / PR_PI;
}

/* Vertex v's incident face normals as the visibility tests see them: its
 * triangles', and on a half model's symmetry plane their mirror images
 * too (the whole model's star). How many; normal j into f. */
static int64_t star_count(const pr_surf *p, int64_t v) {
  int64_t d = p->vt_off[v + 1] - p->vt_off[v];
  return p->onsym && p->onsym[v] ? 2 * d : d;
}
static void star_normal(const pr_surf *p, int64_t v, const double *fn, int64_t j, double *f) {
  int64_t d = p->vt_off[v + 1] - p->vt_off[v];
  memcpy(f, fn + 3 * (int64_t)p->vt[p->vt_off[v] + j % d], 3 * sizeof *f);
  if (j >= d) f[p->sym_ax] = -f[p->sym_ax];
}

/* min over the incident faces of n . f */
static double min_visibility(const pr_surf *p, int64_t v, const double *fn, const double *n) {
  double m = INFINITY, f[3];
  for (int64_t j = 0, nj = star_count(p, v); j < nj; j++) {
    star_normal(p, v, fn, j, f);
    double d = vm_dot3(n, f);
    if (d < m) m = d;
  }
  return m;
}

/* Direction maximizing the minimum of n . f over the incident faces: the
 * centre of the smallest spherical cap holding them (Badoiu-Clarkson). */
static double best_visible(const pr_surf *p, int64_t v, const double *fn, int iters, double *n) {
  double best[3] = {n[0], n[1], n[2]};
  double bm = min_visibility(p, v, fn, n);
  double c[3] = {n[0], n[1], n[2]}, f[3], fw[3] = {0, 0, 0};
  int64_t nj = star_count(p, v);
  for (int it = 1; it <= iters; it++) {
    double wm = INFINITY;
    int found = 0;
    for (int64_t j = 0; j < nj; j++) {
      star_normal(p, v, fn, j, f);
      double d = vm_dot3(c, f);
      if (d < wm) {
        wm = d;
        memcpy(fw, f, sizeof fw);
        found = 1;
      }
    }
    if (wm > bm) {
      bm = wm;
      memcpy(best, c, sizeof best);
    }
    if (!found) break;
    for (int k = 0; k < 3; k++) c[k] += (fw[k] - c[k]) / (it + 1);
    double u[3] = {c[0], c[1], c[2]};
    if (vm_normalize3(u) == 0) break;
    double d = min_visibility(p, v, fn, u);
    if (d > bm) {
      bm = d;
      memcpy(best, u, sizeof best);
    }
  }
  memcpy(n, best, sizeof best);
  return bm;
}

/* Where the iterations found no direction: the exact one
 * (vm_visible_direction, O(k^4)) over up to 24 incident faces, taken into
 * n if it sees them all; 1 then, else 0 (n unchanged). */
static int exact_visible(const pr_surf *p, int64_t v, const double *fn, double *n) {
  enum { KMAX = 24 };
  double f[3 * KMAX], e[3];
  int64_t nj = star_count(p, v);
  if (nj > KMAX) return 0;
  for (int64_t j = 0; j < nj; j++) star_normal(p, v, fn, j, f + 3 * j);
  if (!(vm_visible_direction(f, (int)nj, e) > 0)) return 0;
  memcpy(n, e, sizeof e);
  return 1;
}

/* A direction of a vertex in the symmetry plane taken into the plane (the
 * whole model's is symmetric): over its star with the mirror images, the
 * projection sees every face at least as well as n did, and the
 * normalization only raises that. 0 if nothing is left. */
static int into_plane(const pr_surf *p, int64_t v, double *n) {
  if (!p->onsym || !p->onsym[v]) return 1;
  n[p->sym_ax] = 0;
  return vm_normalize3(n) > 0;
}

int64_t pr_surface_dirs(vm_ctx *ctx, const pr_surf *p, const pr_dir_params *kp, const double *xyz,
                        double *fn, double *vnrm, double *dir, int blend_passes,
                        int64_t *first_blind) {
  int64_t nw = p->nv, nt = p->nt;
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = p->tri + 3 * t;
    const double *a = xyz + 3 * (int64_t)c[0], *b = xyz + 3 * (int64_t)c[1],
                 *d = xyz + 3 * (int64_t)c[2];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
      e1[k] = b[k] - a[k];
      e2[k] = d[k] - a[k];
    }
    vm_cross3(e1, e2, fn + 3 * t);
    vm_normalize3(fn + 3 * t);
  }
  memset(dir, 0, (size_t)(3 * nw) * sizeof *dir);
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = p->tri + 3 * t;
    for (int i = 0; i < 3; i++) {
      const double *x0 = xyz + 3 * (int64_t)c[i], *x1 = xyz + 3 * (int64_t)c[(i + 1) % 3],
                   *x2 = xyz + 3 * (int64_t)c[(i + 2) % 3];
      double u[3], w[3];
      for (int k = 0; k < 3; k++) {
        u[k] = x1[k] - x0[k];
        w[k] = x2[k] - x0[k];
      }
      double cu = vm_dot3(u, w) / (vm_norm3(u) * vm_norm3(w));
      double ang = acos(cu < -1 ? -1 : cu > 1 ? 1 : cu);
      for (int k = 0; k < 3; k++) dir[3 * (int64_t)c[i] + k] += ang * fn[3 * t + k];
    }
  }
  int64_t blind = 0;
  for (int64_t v = 0; v < nw; v++) {
    double *n = dir + 3 * v;
    if (!into_plane(p, v, n) || vm_normalize3(n) == 0) {
      memset(n, 0, 3 * sizeof *n);
      n[p->onsym && p->onsym[v] && p->sym_ax == 2 ? 0 : 2] = 1;
    }
    if (vnrm) memcpy(vnrm + 3 * v, n, 3 * sizeof *n);
    if (min_visibility(p, v, fn, n) < kp->visible_min &&
        best_visible(p, v, fn, kp->visible_iter, n) <= 0 && !exact_visible(p, v, fn, n)) {
      if (!blind && first_blind) *first_blind = v;
      blind++;
    }
    if (!into_plane(p, v, n)) {
      if (!blind && first_blind) *first_blind = v;
      blind++;
    }
  }
  /* blend near sharp edges: Jacobi averaging with the neighbours, kept only
   * where every incident face still sees the new direction well */
  double *tmp = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *tmp);
  if (!tmp) return blind;
  for (int pass = 0; pass < blend_passes; pass++) {
    memcpy(tmp, dir, (size_t)(3 * nw) * sizeof *tmp);
    for (int64_t v = 0; v < nw; v++) {
      double m0 = min_visibility(p, v, fn, dir + 3 * v);
      int sharp = m0 < kp->sharp_visibility;
      for (int64_t k = p->vv_off[v]; k < p->vv_off[v + 1] && !sharp; k++)
        sharp = min_visibility(p, p->vv[k], fn, dir + 3 * (int64_t)p->vv[k]) < kp->sharp_visibility;
      if (!sharp) continue;
      double s[3] = {dir[3 * v], dir[3 * v + 1], dir[3 * v + 2]};
      for (int64_t k = p->vv_off[v]; k < p->vv_off[v + 1]; k++)
        for (int c = 0; c < 3; c++)
          s[c] += kp->blend_weight * dir[3 * (int64_t)p->vv[k] + c] /
                  (double)(p->vv_off[v + 1] - p->vv_off[v]);
      if (!into_plane(p, v, s) || vm_normalize3(s) == 0) continue;
      double m1 = min_visibility(p, v, fn, s);
      if (m1 >= kp->blend_keep || m1 >= m0) memcpy(tmp + 3 * v, s, sizeof s);
    }
    memcpy(dir, tmp, (size_t)(3 * nw) * sizeof *tmp);
  }
  vm_free(ctx, tmp);
  return blind;
}

/* Is prism x's top triangle larger than its bottom one? */
static int widens(const double *x) {
  double e1[3], e2[3], f1[3], f2[3], nb[3], nt[3];
  for (int k = 0; k < 3; k++) {
    e1[k] = x[3 + k] - x[k];
    e2[k] = x[6 + k] - x[k];
    f1[k] = x[12 + k] - x[9 + k];
    f2[k] = x[15 + k] - x[9 + k];
  }
  vm_cross3(e1, e2, nb);
  vm_cross3(f1, f2, nt);
  return vm_dot3(nt, nt) >= vm_dot3(nb, nb);
}

void pr_build_targets(int64_t nt, const int32_t *tri, const pr_dir_params *k, const double *base,
                      const double *fn, const double *dir, const double *h, double *tgt) {
  const double *blend = k->target_blend;
  const int nblend = (int)(sizeof k->target_blend / sizeof *k->target_blend);
#pragma omp parallel for schedule(static)
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = tri + 3 * t;
    double x[18], bx[18];
    double bq = -INFINITY;
    for (int i = 0; i < 3; i++) memcpy(x + 3 * i, base + 3 * (int64_t)c[i], 3 * sizeof *x);
    int taken = 0;
    for (int s = 0; s < nblend && !taken; s++) {
      for (int i = 0; i < 3; i++) {
        double u[3];
        for (int r = 0; r < 3; r++)
          u[r] = (1 - blend[s]) * dir[3 * (int64_t)c[i] + r] + blend[s] * fn[3 * t + r];
        if (blend[s] == 1 || vm_normalize3(u) == 0) memcpy(u, fn + 3 * t, sizeof u);
        for (int r = 0; r < 3; r++) x[9 + 3 * i + r] = x[3 * i + r] + h[c[i]] * u[r];
      }
      double q = pr_prism_quality(x);
      if (q >= k->target_quality || (s == 0 && q > k->fair_quality && widens(x))) taken = 1;
      if (taken || q > bq) {
        bq = q;
        memcpy(bx, x, sizeof bx);
      }
    }
    if (!(bq > 0)) {
      /* the face-normal extrusion is valid in exact arithmetic */
      memcpy(bx, x, 9 * sizeof *bx);
      for (int i = 0; i < 3; i++)
        for (int r = 0; r < 3; r++) bx[9 + 3 * i + r] = bx[3 * i + r] + h[c[i]] * fn[3 * t + r];
    }
    memcpy(tgt + 18 * t, bx, sizeof bx);
  }
}

/* The prism's faces in its 18 coordinates: bottom, top, three quads. */
const int pr_prism_faces[5][4] = {
    {0, 1, 2, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};

/* OpenFOAM's cell centre of prism x: the pyramids on its faces around the
 * face centres' mean, volume-weighted. */
void pr_foam_cell(const double *x, double *cc) {
  double fc[5][3], fs[5][3];
  pr_foam_cell_faces(x, cc, fc, fs);
}

void pr_foam_cell_faces(const double *x, double *cc, double (*fc)[3], double (*fs)[3]) {
  double est[3] = {0, 0, 0};
  for (int f = 0; f < 5; f++) {
    double y[12];
    int n = pr_prism_faces[f][3] < 0 ? 3 : 4;
    for (int i = 0; i < n; i++) memcpy(y + 3 * i, x + 3 * pr_prism_faces[f][i], 3 * sizeof *y);
    vm_foam_face(y, n, fc[f], fs[f]);
    for (int r = 0; r < 3; r++) est[r] += fc[f][r] / 5;
  }
  double sv = 0, sum[3] = {0, 0, 0};
  for (int f = 0; f < 5; f++) {
    double d[3] = {fc[f][0] - est[0], fc[f][1] - est[1], fc[f][2] - est[2]};
    double v = fabs(vm_dot3(fs[f], d));
    for (int r = 0; r < 3; r++) sum[r] += v * (0.75 * fc[f][r] + 0.25 * est[r]);
    sv += v;
  }
  for (int r = 0; r < 3; r++) cc[r] = sv > 0 ? sum[r] / sv : est[r];
}

double pr_foam_cell_det(const double (*fs)[3], const int *internal) {
  double s[5][3];
  int n = 0;
  for (int f = 0; f < 5; f++)
    if (internal[f]) memcpy(s[n++], fs[f], sizeof s[0]);
  return vm_foam_cell_determinant(n, (const double(*)[3])s);
}

/* OpenFOAM's skewness of face x (n vertices) between the cells centred at
 * cp and cn: the distance from the face centre to where the line joining
 * the centres meets the face, over the face's extent that way (at least a
 * fifth of the centres' distance). */
double pr_foam_skew(const double *x, int n, const double *cp, const double *cn) {
  double c[3], s[3];
  vm_foam_face(x, n, c, s);
  return vm_foam_skew(x, n, c, s, cp, cn);
}

/* OpenFOAM's skewness of boundary face x (n vertices) of the cell centred
 * at cp: the offset of the face centre from the cell centre along the
 * face, over the face's extent that way (at least 0.4 times the centre's
 * distance from the face, as OpenFOAM's boundaryFaceSkewness; until
 * session 41 a fifth of it, which read a tall cell on a small wall face as
 * twice as skewed as checkMesh does: 5.08 where checkMesh says 3.59). */
double pr_foam_boundary_skew(const double *x, int n, const double *cp) {
  double c[3], s[3], e[3], sv[3];
  vm_foam_face(x, n, c, s);
  double ls = vm_norm3(s);
  if (!(ls > 0)) return INFINITY;
  for (int r = 0; r < 3; r++) e[r] = c[r] - cp[r];
  double a = vm_dot3(s, e) / ls;
  for (int r = 0; r < 3; r++) sv[r] = e[r] - a * s[r] / ls;
  double l = vm_norm3(sv), fd = 0.4 * fabs(a);
  for (int i = 0; i < n && l > 0; i++) {
    double b = fabs(vm_dot3(sv, x + 3 * i) - vm_dot3(sv, c)) / l;
    fd = b > fd ? b : fd;
  }
  return fd > 0 ? l / fd : INFINITY;
}

double pr_foam_ortho_cos(const double *x, int n, const double *cp, const double *cn) {
  double c[3], s[3];
  vm_foam_face(x, n, c, s);
  return vm_foam_ortho_cos(c, s, cp, cn);
}

/* Signed volume (times 6) of tet (a, b, c, d). */
static double tet6(const double *a, const double *b, const double *c, const double *d) {
  double u[3], v[3], w[3], x[3];
  for (int r = 0; r < 3; r++) {
    u[r] = b[r] - a[r];
    v[r] = c[r] - a[r];
    w[r] = d[r] - a[r];
  }
  vm_cross3(u, v, x);
  return vm_dot3(x, w);
}

int pr_foam_face_tets_ok(const double *x, int n, const double *c, const double *s, const double *cp,
                         const double *cn) {
  /* the face turned to point from cp to cn: sg */
  double sg = (s[0] * (c[0] - cp[0]) + s[1] * (c[1] - cp[1]) + s[2] * (c[2] - cp[2])) < 0 ? -1 : 1;
  double l = 0;
  for (int r = 0; r < 3; r++) l += (cn[r] - cp[r]) * (cn[r] - cp[r]);
  double tol = 1e-12 * l * sqrt(l);
  for (int b = 0; b < n; b++) {
    int ok = 1;
    const double *pb = x + 3 * b;
    for (int j = 1; j + 1 < n && ok; j++) {
      const double *p1 = x + 3 * ((b + j) % n), *p2 = x + 3 * ((b + j + 1) % n);
      /* the owner's tet is positive where its centre lies behind the
       * triangle (triple product of the triangle's edges and the centre
       * negative along sg), the neighbour's where its centre lies in front */
      ok = -sg * tet6(pb, p1, p2, cp) > tol && sg * tet6(pb, p1, p2, cn) > tol;
    }
    if (ok) return 1;
  }
  return 0;
}

int pr_foam_cell_concave(const double (*fc)[3], const double (*fs)[3], const double *cc) {
  for (int f = 0; f < 5; f++) {
    double n[3], e[3];
    for (int r = 0; r < 3; r++) e[r] = fc[f][r] - cc[r];
    double l = vm_norm3(fs[f]);
    if (!(l > 0)) return 1;
    /* the face's normal turned out of the cell */
    double sg = vm_dot3(fs[f], e) < 0 ? -1 : 1;
    for (int r = 0; r < 3; r++) n[r] = sg * fs[f][r] / l;
    for (int g = 0; g < 5; g++) {
      if (g == f) continue;
      double d[3];
      for (int r = 0; r < 3; r++) d[r] = fc[g][r] - fc[f][r];
      double ld = vm_norm3(d);
      if (ld > 0 && vm_dot3(d, n) / ld > -1e-6) return 1;
    }
  }
  return 0;
}
