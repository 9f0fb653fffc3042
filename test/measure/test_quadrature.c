/* test/measure/test_quadrature.c: quadrature rules: weights, ideal-element
 * volumes, exactness for det of the geometric rules (24), and the discrete
 * functional bound (21) F_h >= F on random trilinear hexes, prisms and quads. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mtest_util.h"
#include "varmesh/ctx.h"
#include "varmesh/measure.h"
#include "varmesh/mesh.h"
#include "varmesh/quadrature.h"
#include "vmtest.h"

/* hex vertex of unit-cube corner (i, j, k) in VTK order */
static int hexv(int i, int j, int k) {
  static const int v[2][2][2] = {{{0, 4}, {3, 7}}, {{1, 5}, {2, 6}}};
  return v[i][j][k];
}

static double bern(int a, double t) { return a ? t : 1 - t; }

/* Jacobian (row-major, column k = dx/dxi_k) of the trilinear map (29) at xi. */
static void hex_jacobian(const double *x, const double *xi, double *J) {
  memset(J, 0, 9 * sizeof(double));
  for (int a = 0; a < 2; a++)
    for (int b = 0; b < 2; b++) {
      double w1 = bern(a, xi[1]) * bern(b, xi[2]); /* xi1-edge at (a, b) */
      double w2 = bern(a, xi[0]) * bern(b, xi[2]); /* xi2-edge at (a, b) */
      double w3 = bern(a, xi[0]) * bern(b, xi[1]); /* xi3-edge at (a, b) */
      for (int r = 0; r < 3; r++) {
        J[r * 3 + 0] += w1 * (x[hexv(1, a, b) * 3 + r] - x[hexv(0, a, b) * 3 + r]);
        J[r * 3 + 1] += w2 * (x[hexv(a, 1, b) * 3 + r] - x[hexv(a, 0, b) * 3 + r]);
        J[r * 3 + 2] += w3 * (x[hexv(a, b, 1) * 3 + r] - x[hexv(a, b, 0) * 3 + r]);
      }
    }
}

/* Jacobian of the prism map x = sum_i lambda_i ((1 - xi3) x_i + xi3 x_{i+3}),
 * lambda = (1 - xi1 - xi2, xi1, xi2). */
static void prism_jacobian(const double *x, const double *xi, double *J) {
  double lam[3] = {1 - xi[0] - xi[1], xi[0], xi[1]};
  for (int r = 0; r < 3; r++) {
    J[r * 3 + 0] = (1 - xi[2]) * (x[3 + r] - x[r]) + xi[2] * (x[12 + r] - x[9 + r]);
    J[r * 3 + 1] = (1 - xi[2]) * (x[6 + r] - x[r]) + xi[2] * (x[15 + r] - x[9 + r]);
    J[r * 3 + 2] = 0;
    for (int i = 0; i < 3; i++) J[r * 3 + 2] += lam[i] * (x[(i + 3) * 3 + r] - x[i * 3 + r]);
  }
}

/* Jacobian of the bilinear quad map. */
static void quad_jacobian(const double *x, const double *xi, double *J) {
  for (int r = 0; r < 2; r++) {
    J[r * 2 + 0] = (1 - xi[1]) * (x[3 + r] - x[r]) + xi[1] * (x[6 + r] - x[9 + r]);
    J[r * 2 + 1] = (1 - xi[0]) * (x[9 + r] - x[r]) + xi[0] * (x[6 + r] - x[3 + r]);
  }
}

static void inv3(const double *A, double *B) {
  double d = mt_det(3, A);
  B[0] = (A[4] * A[8] - A[5] * A[7]) / d;
  B[1] = (A[2] * A[7] - A[1] * A[8]) / d;
  B[2] = (A[1] * A[5] - A[2] * A[4]) / d;
  B[3] = (A[5] * A[6] - A[3] * A[8]) / d;
  B[4] = (A[0] * A[8] - A[2] * A[6]) / d;
  B[5] = (A[2] * A[3] - A[0] * A[5]) / d;
  B[6] = (A[3] * A[7] - A[4] * A[6]) / d;
  B[7] = (A[1] * A[6] - A[0] * A[7]) / d;
  B[8] = (A[0] * A[4] - A[1] * A[3]) / d;
}

/* sum_q beta_q kappa det(E_q) */
static double rule_volume(const vm_qrule *R, const double *x) {
  double v = 0, E[9];
  for (int q = 0; q < R->nnodes; q++) {
    vm_qnode_edges(&R->nodes[q], R->dim, x, E);
    v += R->nodes[q].beta * mt_det(R->dim, E);
  }
  return R->kappa * v;
}

/* First use from many threads at once: every thread must see complete tables. */
static void test_concurrent_first_use(void) {
  int bad = 0;
#ifdef _OPENMP
#pragma omp parallel num_threads(8) reduction(+ : bad)
#endif
  {
    const vm_qrule *h = vm_qrule_get(VM_HEX, VM_RULE_GEOMETRIC);
    const vm_qrule *p = vm_qrule_get(VM_PRISM, VM_RULE_GEOMETRIC);
    bad += !h || h->nnodes != 64 || !h->nodes || h->nodes[63].beta <= 0;
    bad += !p || p->nnodes != 12 || !p->nodes || p->nodes[11].beta <= 0;
  }
  CHECK(bad == 0, "%d threads saw incomplete rule tables", bad);
}

static void test_weights_and_ideal(void) {
  static const int nn[VM_NTYPES][2] = {{1, 1}, {4, 4}, {1, 1}, {4, 4}, {6, 12}, {8, 64}};
  const double vol[VM_NTYPES] = {sqrt(3.0) / 4, 1, 1 / (6 * sqrt(2.0)), sqrt(2.0) / 6,
                                 sqrt(3.0) / 4, 1};
  CHECK(vm_qrule_get(-1, 0) == NULL && vm_qrule_get(VM_NTYPES, 0) == NULL, "unknown type");
  for (int type = 0; type < VM_NTYPES; type++)
    for (int rule = 0; rule < 2; rule++) {
      const vm_qrule *R = vm_qrule_get(type, rule);
      const char *nm = vm_elem_name(type);
      CHECK(R && R->type == type && R->dim == vm_elem_dim(type), "%s rule %d", nm, rule);
      if (!R) continue;
      CHECK(R->nnodes == nn[type][rule], "%s rule %d: %d nodes", nm, rule, R->nnodes);
      int geo = rule == VM_RULE_GEOMETRIC && (type == VM_HEX || type == VM_PRISM);
      CHECK(R->rule == (geo ? VM_RULE_GEOMETRIC : VM_RULE_CORNER), "%s rule id", nm);
      double sb = 0;
      int nv = vm_elem_nverts(type), idx_ok = 1;
      for (int q = 0; q < R->nnodes; q++) {
        sb += R->nodes[q].beta;
        for (int k = 0; k < R->dim; k++)
          idx_ok = idx_ok && R->nodes[q].head[k] >= 0 && R->nodes[q].head[k] < nv &&
                   R->nodes[q].tail[k] >= 0 && R->nodes[q].tail[k] < nv &&
                   R->nodes[q].head[k] != R->nodes[q].tail[k];
      }
      CHECK(idx_ok, "%s rule %d: vertex indices", nm, rule);
      CHECK_NEAR(sb, 1.0, 1e-15, "sum of beta");
      double x[VM_MAX_ELEM_VERTS * 3], E[9];
      vm_elem_ideal(type, x);
      int pos = 1;
      for (int q = 0; q < R->nnodes; q++) {
        vm_qnode_edges(&R->nodes[q], R->dim, x, E);
        pos = pos && mt_det(R->dim, E) > 0;
      }
      CHECK(pos, "%s rule %d: a node of the ideal element has det <= 0", nm, rule);
      double v = rule_volume(R, x);
      CHECK(fabs(v - vol[type]) < 1e-15, "%s rule %d: ideal volume %.17g, exact %.17g", nm, rule, v,
            vol[type]);
    }
}

/* Random affine images A x of the ideal elements: every rule gives det A
 * times the ideal volume. */
static void test_affine(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 99);
  double worst = 0;
  for (int type = 0; type < VM_NTYPES; type++)
    for (int rule = 0; rule < 2; rule++) {
      const vm_qrule *R = vm_qrule_get(type, rule);
      int d = R->dim, nv = vm_elem_nverts(type);
      double ref[VM_MAX_ELEM_VERTS * 3], x[VM_MAX_ELEM_VERTS * 3];
      vm_elem_ideal(type, ref);
      double v0 = rule_volume(R, ref);
      for (int n = 0; n < 20; n++) {
        double sig[3] = {0}, A[9], off[3];
        for (int i = 0; i < d; i++) {
          sig[i] = exp(mt_uniform(ctx, -1, 1));
          off[i] = mt_uniform(ctx, -5, 5);
        }
        mt_from_singular(ctx, d, sig, A);
        memset(x, 0, sizeof x);
        for (int v = 0; v < nv; v++)
          for (int r = 0; r < d; r++) {
            double s = off[r];
            for (int k = 0; k < d; k++) s += A[r * d + k] * ref[v * 3 + k];
            x[v * 3 + r] = s;
          }
        double e = fabs(rule_volume(R, x) / (mt_det(d, A) * v0) - 1);
        worst = fmax(worst, e);
        CHECK(e < 1e-13, "%s rule %d: affine volume rel err %.3e", vm_elem_name(type), rule, e);
      }
    }
  fprintf(stderr, "affine images: max rel volume error %.2e\n", worst);
}

/* unit cube (or ideal prism / square) + uniform vertex perturbation of size a */
static void perturbed(vm_ctx *ctx, int type, double a, double *x) {
  vm_elem_ideal(type, x);
  int d = vm_elem_dim(type);
  for (int v = 0; v < vm_elem_nverts(type); v++)
    for (int r = 0; r < d; r++) x[v * 3 + r] += mt_uniform(ctx, -a, a);
}

/* Exactness for det: geometric hex (64 nodes) and prism (12) rules against
 * Gauss quadrature of det of the trilinear / prism map; the quad rule against
 * the shoelace area. */
static void test_exact_det(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 1234);
  double gx[4], gw[4], J[9];
  mt_gauss(4, gx, gw);
  double ehex = 0, eprism = 0, equad = 0, ecorner = 0;
  const vm_qrule *Rh = vm_qrule_get(VM_HEX, VM_RULE_GEOMETRIC);
  const vm_qrule *Rc = vm_qrule_get(VM_HEX, VM_RULE_CORNER);
  const vm_qrule *Rp = vm_qrule_get(VM_PRISM, VM_RULE_GEOMETRIC);
  const vm_qrule *Rq = vm_qrule_get(VM_QUAD, VM_RULE_GEOMETRIC);
  for (int n = 0; n < 200; n++) {
    double x[VM_MAX_ELEM_VERTS * 3], vol = 0;
    perturbed(ctx, VM_HEX, 0.45, x);
    for (int a = 0; a < 4; a++)
      for (int b = 0; b < 4; b++)
        for (int c = 0; c < 4; c++) {
          double xi[3] = {gx[a], gx[b], gx[c]};
          hex_jacobian(x, xi, J);
          vol += gw[a] * gw[b] * gw[c] * mt_det(3, J);
        }
    double e = fabs(rule_volume(Rh, x) - vol) / fabs(vol);
    ehex = fmax(ehex, e);
    ecorner = fmax(ecorner, fabs(rule_volume(Rc, x) - vol) / fabs(vol));
    CHECK(e < 1e-13, "hex geometric volume rel err %.3e", e);

    double y[VM_MAX_ELEM_VERTS * 3], pvol = 0;
    perturbed(ctx, VM_PRISM, 0.3, y);
    for (int a = 0; a < 4; a++)
      for (int b = 0; b < 4; b++)
        for (int c = 0; c < 4; c++) {
          /* collapsed (Duffy) coordinates on the triangle */
          double xi[3] = {gx[a], (1 - gx[a]) * gx[b], gx[c]};
          prism_jacobian(y, xi, J);
          pvol += gw[a] * gw[b] * gw[c] * (1 - gx[a]) * mt_det(3, J);
        }
    e = fabs(rule_volume(Rp, y) - pvol) / fabs(pvol);
    eprism = fmax(eprism, e);
    CHECK(e < 1e-13, "prism geometric volume rel err %.3e", e);

    double z[VM_MAX_ELEM_VERTS * 3], area = 0;
    perturbed(ctx, VM_QUAD, 0.3, z);
    for (int v = 0; v < 4; v++) {
      int w = (v + 1) % 4;
      area += 0.5 * (z[v * 3] * z[w * 3 + 1] - z[w * 3] * z[v * 3 + 1]);
    }
    e = fabs(rule_volume(Rq, z) - area) / fabs(area);
    equad = fmax(equad, e);
    CHECK(e < 1e-13, "quad area rel err %.3e", e);
  }
  fprintf(stderr,
          "exact det: max rel volume error hex-64 %.2e, prism-12 %.2e, quad-4 %.2e "
          "(hex corner-8, not exact: %.2e)\n",
          ehex, eprism, equad, ecorner);
}

typedef struct fcase {
  vm_measure_kind kind;
  const char *label;
  double t, eps;
} fcase;

static const fcase f_cases[] = {
    {VM_MEASURE_BALANCED, "balanced", 0, 0},
    {VM_MEASURE_SHAPE, "shape", 0, 0},
    {VM_MEASURE_SHAPE_ALT, "shape-alt", 0, 0},
    {VM_MEASURE_QUASI_ISO, "quasi-iso(t=0.2)", 0.2, 0},
    {VM_MEASURE_BARRIER, "barrier(eps=0.1)", 0, 0.1},
};
enum { NF = (int)(sizeof f_cases / sizeof f_cases[0]) };

/* (21): sum_q beta_q W(C_q) >= (1/vol U) int_U W(grad x T^{-1}). Returns 0 if
 * some compound matrix is outside the measure's domain (sample skipped). */
static int functional_pair(int type, const vm_measure_ops *ops, const vm_measure_params *p,
                           const double *x, const double *Tinv, int ng, const double *gx,
                           const double *gw, double *Fh, double *F, double *Fc) {
  const vm_qrule *R = vm_qrule_get(type, VM_RULE_GEOMETRIC);
  int d = R->dim;
  double E[9], C[9], W, J[9];
  *Fh = 0;
  for (int q = 0; q < R->nnodes; q++) {
    vm_qnode_edges(&R->nodes[q], d, x, E);
    if (Tinv)
      mt_mul(d, E, Tinv, C);
    else
      memcpy(C, E, sizeof(double) * d * d);
    if (vm_measure_eval(ops, p, d, C, &W, NULL, NULL)) return 0;
    *Fh += R->nodes[q].beta * W;
  }
  *F = 0;
  if (type == VM_QUAD) {
    for (int a = 0; a < ng; a++)
      for (int b = 0; b < ng; b++) {
        double xi[2] = {gx[a], gx[b]};
        quad_jacobian(x, xi, J);
        vm_measure_eval(ops, p, 2, J, &W, NULL, NULL);
        *F += gw[a] * gw[b] * W;
      }
  } else {
    for (int a = 0; a < ng; a++)
      for (int b = 0; b < ng; b++)
        for (int c = 0; c < ng; c++) {
          double wt = gw[a] * gw[b] * gw[c];
          if (type == VM_HEX) {
            double xi[3] = {gx[a], gx[b], gx[c]};
            hex_jacobian(x, xi, J);
          } else {
            double xi[3] = {gx[a], (1 - gx[a]) * gx[b], gx[c]};
            prism_jacobian(x, xi, J);
            wt *= 2 * (1 - gx[a]); /* Duffy factor over vol U = 1/2 */
          }
          mt_mul(3, J, Tinv, C);
          if (vm_measure_eval(ops, p, 3, C, &W, NULL, NULL)) W = INFINITY;
          *F += wt * W;
        }
  }
  if (Fc) {
    const vm_qrule *Rc = vm_qrule_get(type, VM_RULE_CORNER);
    *Fc = 0;
    for (int q = 0; q < Rc->nnodes; q++) {
      vm_qnode_edges(&Rc->nodes[q], d, x, E);
      vm_measure_eval(ops, p, d, E, &W, NULL, NULL);
      *Fc += Rc->nodes[q].beta * W;
    }
  }
  return 1;
}

static void test_functional_bound(vm_ctx *ctx) {
  enum { NHEX = 200, NG = 8 };
  double gx[NG], gw[NG];
  mt_gauss(NG, gx, gw);
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  /* the ideal prism's (common) compound edge matrix */
  double ref[VM_MAX_ELEM_VERTS * 3], T0[9], T0inv[9];
  vm_elem_ideal(VM_PRISM, ref);
  vm_qnode_edges(&vm_qrule_get(VM_PRISM, VM_RULE_GEOMETRIC)->nodes[0], 3, ref, T0);
  inv3(T0, T0inv);
  static const int types[3] = {VM_HEX, VM_PRISM, VM_QUAD};
  fprintf(stderr, "(21) F_h/F, geometric rule vs %d-point tensor Gauss:\n", NG);
  fprintf(stderr, "%-8s %-18s %5s %14s %14s %24s\n", "element", "measure", "n", "min ratio",
          "max ratio", "hex corner-8 ratio range");
  for (int ti = 0; ti < 3; ti++) {
    int type = types[ti];
    for (int fi = 0; fi < NF; fi++) {
      const fcase *c = &f_cases[fi];
      const vm_measure_ops *ops = vm_measure_get(c->kind);
      vm_measure_params p = vm_measure_params_default();
      p.t = c->t;
      p.eps = c->eps;
      vm_ctx_seed(ctx, 2100 + 10 * (uint64_t)ti);
      double rmin = INFINITY, rmax = 0, cmin = INFINITY, cmax = 0;
      int used = 0;
      for (int n = 0; n < NHEX; n++) {
        double x[VM_MAX_ELEM_VERTS * 3], A[9], sig[3], Fh, F, Fc;
        perturbed(ctx, type, mt_uniform(ctx, 0.02, type == VM_QUAD ? 0.35 : 0.25), x);
        /* a random stretch so W is far from its minimum too */
        int d = vm_elem_dim(type);
        for (int i = 0; i < d; i++) sig[i] = exp(mt_uniform(ctx, -0.4, 0.4));
        mt_from_singular(ctx, d, sig, A);
        for (int v = 0; v < vm_elem_nverts(type); v++) {
          double y[3] = {0, 0, 0};
          for (int r = 0; r < d; r++)
            for (int k = 0; k < d; k++) y[r] += A[r * d + k] * x[v * 3 + k];
          for (int r = 0; r < d; r++) x[v * 3 + r] = y[r];
        }
        const double *Tinv = type == VM_HEX ? I3 : type == VM_PRISM ? T0inv : NULL;
        if (!functional_pair(type, ops, &p, x, Tinv, NG, gx, gw, &Fh, &F,
                             type == VM_HEX ? &Fc : NULL))
          continue;
        used++;
        double r = Fh / F;
        rmin = fmin(rmin, r);
        rmax = fmax(rmax, r);
        if (type == VM_HEX) {
          cmin = fmin(cmin, Fc / F);
          cmax = fmax(cmax, Fc / F);
        }
        CHECK(r >= 1 - 1e-12, "%s %s: F_h/F = %.17g < 1", vm_elem_name(type), c->label, r);
      }
      CHECK(used >= NHEX / 2, "%s %s: only %d admissible samples", vm_elem_name(type), c->label,
            used);
      if (type == VM_HEX)
        fprintf(stderr, "%-8s %-18s %5d %14.10f %14.10f %11.6f..%-11.6f\n", vm_elem_name(type),
                c->label, used, rmin, rmax, cmin, cmax);
      else
        fprintf(stderr, "%-8s %-18s %5d %14.10f %14.10f\n", vm_elem_name(type), c->label, used,
                rmin, rmax);
    }
  }
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx) != VM_OK) return 1;
  test_concurrent_first_use();
  test_weights_and_ideal();
  test_affine(ctx);
  test_exact_det(ctx);
  test_functional_bound(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_quadrature");
}
