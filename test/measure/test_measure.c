/* test/measure/test_measure.c: distortion measures: finite-difference checks
 * of the scalar partials, gradient and Hessian; known values, invariance,
 * minimum at the isometry, domains, and the Hadamard-Legendre condition (3). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mtest_util.h"
#include "varmesh/ctx.h"
#include "varmesh/measure.h"
#include "vmtest.h"

enum { NSAMPLE = 60 };

typedef struct mcase {
  vm_measure_kind kind;
  const char *label;
  double theta, t, eps;
  int both_signs; /* sample det of both signs (penalty, barrier) */
} mcase;

static const mcase deriv_cases[] = {
    {VM_MEASURE_SHAPE, "shape", 0.8, 0, 0, 0},
    {VM_MEASURE_SHAPE_ALT, "shape-alt", 0.8, 0, 0, 0},
    {VM_MEASURE_BALANCED, "balanced", 0.8, 0, 0, 0},
    {VM_MEASURE_BALANCED, "balanced(th=0.3)", 0.3, 0, 0, 0},
    {VM_MEASURE_QUASI_ISO, "quasi-iso(t=0.3)", 0.8, 0.3, 0, 0},
    {VM_MEASURE_QUASI_ISO, "quasi-iso(t=0.6)", 0.8, 0.6, 0, 0},
    {VM_MEASURE_PENALTY, "penalty(eps=0.2)", 0.8, 0, 0.2, 1},
    {VM_MEASURE_PENALTY, "penalty(eps=0.01)", 0.8, 0, 0.01, 1},
    {VM_MEASURE_BARRIER, "barrier(eps=0)", 0.8, 0, 0, 0},
    {VM_MEASURE_BARRIER, "barrier(eps=0.1)", 0.8, 0, 0.1, 1},
};
enum { NCASE = (int)(sizeof deriv_cases / sizeof deriv_cases[0]) };

static vm_measure_params case_params(const mcase *c, int drop_chi2) {
  vm_measure_params p = vm_measure_params_default();
  p.theta = c->theta;
  p.t = c->t;
  p.eps = c->eps;
  p.drop_chi2 = drop_chi2;
  return p;
}

static void cofactor(int d, const double *C, double *K) {
  if (d == 2) {
    K[0] = C[3], K[1] = -C[2], K[2] = -C[1], K[3] = C[0];
    return;
  }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      K[i * 3 + j] = C[i1 * 3 + j1] * C[i2 * 3 + j2] - C[i1 * 3 + j2] * C[i2 * 3 + j1];
    }
}

/* Independent reference W(C) straight from the paper's formulas (pow, long
 * double for the penalty's chi so det < 0 does not cancel). */
static double w_reference(vm_measure_kind kind, const vm_measure_params *p, int d,
                          const double *C) {
  double s = mt_trace_ctc(d, C), D = mt_det(d, C);
  double sh = d == 3 ? pow(s / 3, 1.5) : s / 2;
  double phi = (1 - p->theta) * sh + 0.5 * p->theta * (1 + D * D);
  switch (kind) {
  case VM_MEASURE_SHAPE: return D > 0 ? sh / D : INFINITY;
  case VM_MEASURE_SHAPE_ALT:
    if (D <= 0) return INFINITY;
    return d == 3 ? (s / 3) / pow(D, 2.0 / 3) : (s / 2) / D;
  case VM_MEASURE_BALANCED: return D > 0 ? phi / D : INFINITY;
  case VM_MEASURE_QUASI_ISO:
    return D > 0 && D - p->t * phi > 0 ? (1 - p->t) * phi / (D - p->t * phi) : INFINITY;
  case VM_MEASURE_PENALTY: {
    long double e = p->eps, Dl = D;
    long double chi = 0.5L * (Dl + sqrtl(e * e + Dl * Dl));
    return chi > 0 ? (double)(phi / chi) : INFINITY;
  }
  case VM_MEASURE_BARRIER: return D + p->eps > 0 ? phi / (D + p->eps) : INFINITY;
  default: return NAN;
  }
}

static double w_of(const vm_measure_ops *ops, const vm_measure_params *p, int d, const double *C) {
  double W;
  vm_measure_eval(ops, p, d, C, &W, NULL, NULL);
  return W;
}

/* A random Jacobian inside the case's domain with some margin: singular
 * values log-uniform in [1/e, e]; for both_signs cases det is often of the
 * order of eps and of either sign. */
static void sample_jacobian(vm_ctx *ctx, const mcase *c, const vm_measure_ops *ops, int d,
                            double *C) {
  vm_measure_params p = case_params(c, 0);
  for (;;) {
    double sig[3];
    for (int i = 0; i < d; i++) sig[i] = exp(mt_uniform(ctx, -1, 1));
    if (c->both_signs) {
      double u = vm_ctx_rand_unit(ctx);
      if (u < 0.5) sig[0] = mt_uniform(ctx, 0, 2 * c->eps) / (d == 2 ? sig[1] : sig[1] * sig[2]);
      if (vm_ctx_rand_unit(ctx) < 0.5) sig[0] = -sig[0];
    }
    mt_from_singular(ctx, d, sig, C);
    double f[6], s = mt_trace_ctc(d, C), D = mt_det(d, C);
    if (ops->scalar(&p, d, s, D, 0, f)) continue;
    if (c->kind == VM_MEASURE_BARRIER && D + c->eps < 0.05 * (c->eps + 0.1)) continue;
    if (c->kind == VM_MEASURE_QUASI_ISO && D - c->t * vm_phi_theta(c->theta, d, s, D) < 1e-2 * D)
      continue;
    return;
  }
}

/* Fourth-order central difference from values at -2h, -h, +h, +2h. */
static double fd4(double m2, double m1, double p1, double p2, double h) {
  return (8 * (p1 - m1) - (p2 - m2)) / (12 * h);
}

/* Max relative error of the five scalar partials against central differences
 * of f and of the first partials. */
static double check_scalar(const vm_measure_ops *ops, const vm_measure_params *p, int d, double s,
                           double D) {
  double f[6], v[4][6], err = 0;
  static const double off[4] = {-2, -1, 1, 2};
  ops->scalar(p, d, s, D, 2, f);
  double hs = 1e-5 * s, hd = 1e-5 * fmax(fabs(D), 1e-2);
  for (int k = 0; k < 4; k++) ops->scalar(p, d, s + off[k] * hs, D, 1, v[k]);
  for (int n = 0; n < 3; n++) /* f_s, f_ss, f_sd from d/ds of f, f_s, f_d */
    err = fmax(err, mt_relerr(f[n == 0   ? 1
                                : n == 1 ? 3
                                         : 4],
                              fd4(v[0][n], v[1][n], v[2][n], v[3][n], hs)));
  for (int k = 0; k < 4; k++) ops->scalar(p, d, s, D + off[k] * hd, 1, v[k]);
  for (int n = 0; n < 3; n++) /* f_d, f_sd, f_dd from d/ddet of f, f_s, f_d */
    err = fmax(err, mt_relerr(f[n == 0   ? 2
                                : n == 1 ? 4
                                         : 5],
                              fd4(v[0][n], v[1][n], v[2][n], v[3][n], hd)));
  return err;
}

/* Gradient and Hessian of vm_measure_eval against central differences of
 * W and of G in each entry of C (4th order, step 1e-5 relative). */
static void check_full(const vm_measure_ops *ops, const vm_measure_params *p, int d,
                       const double *C, double *eg, double *eh) {
  int nn = d * d;
  double W, G[9], H[81], Cp[9], Wk[4], Gk[4][9];
  static const double off[4] = {-2, -1, 1, 2};
  vm_measure_eval(ops, p, d, C, &W, G, H);
  double cmax = 0;
  for (int a = 0; a < nn; a++) cmax = fmax(cmax, fabs(C[a]));
  double h = 1e-5 * fmax(1, cmax);
  for (int b = 0; b < nn; b++) {
    memcpy(Cp, C, sizeof(double) * nn);
    for (int k = 0; k < 4; k++) {
      Cp[b] = C[b] + off[k] * h;
      vm_measure_eval(ops, p, d, Cp, &Wk[k], Gk[k], NULL);
    }
    *eg = fmax(*eg, mt_relerr(G[b], fd4(Wk[0], Wk[1], Wk[2], Wk[3], h)));
    for (int a = 0; a < nn; a++)
      *eh = fmax(*eh, mt_relerr(H[a * nn + b], fd4(Gk[0][a], Gk[1][a], Gk[2][a], Gk[3][a], h)));
  }
}

/* drop_chi2: H must equal the full Hessian plus phi chi''/chi^2 cof (x) cof. */
static double check_drop_chi2(const vm_measure_ops *ops, const mcase *c, int d, const double *C) {
  vm_measure_params pf = case_params(c, 0), pd = case_params(c, 1);
  int nn = d * d;
  double Wf, Wd, Gf[9], Gd[9], Hf[81], Hd[81], K[9];
  vm_measure_eval(ops, &pf, d, C, &Wf, Gf, Hf);
  vm_measure_eval(ops, &pd, d, C, &Wd, Gd, Hd);
  double err = mt_relerr(Wf, Wd);
  for (int a = 0; a < nn; a++) err = fmax(err, mt_relerr(Gf[a], Gd[a]));
  double s = mt_trace_ctc(d, C), D = mt_det(d, C), e = c->eps;
  double sh = d == 3 ? pow(s / 3, 1.5) : s / 2;
  double phi = (1 - c->theta) * sh + 0.5 * c->theta * (1 + D * D);
  long double q = sqrtl((long double)e * e + (long double)D * D);
  double chi = (double)(0.5L * (D + q));
  double chi2 = (double)(e * e / (2 * q * q * q));
  double k = phi * chi2 / (chi * chi);
  cofactor(d, C, K);
  for (int a = 0; a < nn; a++)
    for (int b = 0; b < nn; b++)
      err = fmax(err, mt_relerr(Hd[a * nn + b], Hf[a * nn + b] + k * K[a] * K[b]));
  return err;
}

static void test_derivatives(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 20140101);
  fprintf(stderr, "%-20s %2s %17s %17s %17s %17s\n", "measure", "d", "max_rel_err_grad",
          "max_rel_err_hess", "max_rel_err_fsd", "max_rel_err_ref");
  for (int ci = 0; ci < NCASE; ci++) {
    const mcase *c = &deriv_cases[ci];
    const vm_measure_ops *ops = vm_measure_get(c->kind);
    vm_measure_params p = case_params(c, 0);
    for (int d = 2; d <= 3; d++) {
      double eg = 0, eh = 0, es = 0, eref = 0, edrop = 0;
      int npos = 0, nneg = 0;
      for (int n = 0; n < NSAMPLE; n++) {
        double C[9];
        sample_jacobian(ctx, c, ops, d, C);
        double s = mt_trace_ctc(d, C), D = mt_det(d, C);
        if (D > 0)
          npos++;
        else
          nneg++;
        es = fmax(es, check_scalar(ops, &p, d, s, D));
        check_full(ops, &p, d, C, &eg, &eh);
        double W = w_of(ops, &p, d, C), Wr = w_reference(c->kind, &p, d, C);
        eref = fmax(eref, fabs(W - Wr) / fmax(1, fabs(Wr)));
        if (c->kind == VM_MEASURE_PENALTY) edrop = fmax(edrop, check_drop_chi2(ops, c, d, C));
      }
      fprintf(stderr, "%-20s %2d %17.3e %17.3e %17.3e %17.3e\n", c->label, d, eg, eh, es, eref);
      CHECK(eg < 1e-5, "%s d=%d: gradient rel err %.3e", c->label, d, eg);
      CHECK(eh < 1e-5, "%s d=%d: Hessian rel err %.3e", c->label, d, eh);
      CHECK(es < 1e-5, "%s d=%d: scalar partials rel err %.3e", c->label, d, es);
      CHECK(eref < 1e-12, "%s d=%d: W vs the formula rel err %.3e", c->label, d, eref);
      if (c->both_signs)
        CHECK(npos > 5 && nneg > 5, "%s d=%d: det signs %d+ %d-", c->label, d, npos, nneg);
      if (c->kind == VM_MEASURE_PENALTY) {
        fprintf(stderr, "%-20s %2d drop_chi2: max rel err vs full + chi'' term %.3e\n", c->label, d,
                edrop);
        CHECK(edrop < 1e-12, "%s d=%d: drop_chi2 rel err %.3e", c->label, d, edrop);
      }
    }
  }
}

/* Registry, defaults, W(I) = 1, G(I) = 0, known values with eps > 0. */
static void test_known_values(void) {
  static const char *names[VM_MEASURE_COUNT] = {"shape",     "shape-alt", "balanced",
                                                "quasi-iso", "penalty",   "barrier"};
  for (int k = 0; k < VM_MEASURE_COUNT; k++) {
    const vm_measure_ops *ops = vm_measure_get((vm_measure_kind)k);
    CHECK(ops && (int)ops->kind == k && strcmp(ops->name, names[k]) == 0, "registry %d", k);
    CHECK(vm_measure_by_name(names[k]) == ops, "by name %s", names[k]);
  }
  CHECK(vm_measure_get(VM_MEASURE_COUNT) == NULL, "get out of range");
  CHECK(vm_measure_get((vm_measure_kind)-1) == NULL, "get negative");
  CHECK(vm_measure_by_name("nope") == NULL && vm_measure_by_name(NULL) == NULL, "by bad name");
  vm_measure_params p = vm_measure_params_default();
  CHECK(p.theta == 0.8 && p.t == 0 && p.eps == 0 && p.drop_chi2 == 1, "defaults");

  static const double I2[4] = {1, 0, 0, 1}, I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int d = 2; d <= 3; d++) {
    const double *I = d == 2 ? I2 : I3;
    for (double th = 0; th <= 1.0; th += 0.25)
      CHECK_NEAR(vm_phi_theta(th, d, d, 1), 1.0, 1e-15, "phi_theta(I)");
    for (int k = 0; k < VM_MEASURE_COUNT; k++) {
      const vm_measure_ops *ops = vm_measure_get((vm_measure_kind)k);
      for (int variant = 0; variant < 4; variant++) {
        vm_measure_params q = vm_measure_params_default();
        q.theta = variant == 1 ? 0.3 : variant == 2 ? 1.0 : 0.8;
        q.t = k == VM_MEASURE_QUASI_ISO ? 0.3 * variant : 0;
        q.drop_chi2 = variant & 1;
        double W, G[9], H[81];
        int rc = vm_measure_eval(ops, &q, d, I, &W, G, H);
        CHECK(rc == 0, "%s d=%d: I inside", ops->name, d);
        CHECK_NEAR(W, 1.0, 1e-14, "W(I)");
        for (int a = 0; a < d * d; a++) CHECK_NEAR(G[a], 0.0, 1e-14, "G(I) = 0");
      }
    }
    /* eps > 0: W(I) = 1/(1 + eps) for the barrier, 1/chi_eps(1) for the penalty */
    vm_measure_params q = vm_measure_params_default();
    q.eps = 0.3;
    double W;
    vm_measure_eval(vm_measure_get(VM_MEASURE_BARRIER), &q, d, I, &W, NULL, NULL);
    CHECK_NEAR(W, 1 / 1.3, 1e-15, "barrier W(I)");
    vm_measure_eval(vm_measure_get(VM_MEASURE_PENALTY), &q, d, I, &W, NULL, NULL);
    CHECK_NEAR(W, 2 / (1 + sqrt(1.09)), 1e-15, "penalty W(I)");
  }
  double W = 0;
  CHECK(vm_measure_eval(NULL, &p, 3, I3, &W, NULL, NULL) < 0 && W == INFINITY, "NULL ops");
  CHECK(vm_measure_eval(vm_measure_get(VM_MEASURE_SHAPE), &p, 4, I3, &W, NULL, NULL) < 0,
        "bad dimension");
}

/* W(R) = 1, W(U C V^T) = W(C), G(U C V^T) = U G(C) V^T. */
static void test_invariance(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 77);
  double worst_rot = 0, worst_inv = 0;
  for (int ci = 0; ci < NCASE; ci++) {
    const mcase *c = &deriv_cases[ci];
    const vm_measure_ops *ops = vm_measure_get(c->kind);
    vm_measure_params p = case_params(c, 0);
    for (int d = 2; d <= 3; d++)
      for (int n = 0; n < 50; n++) {
        double R[9], C[9], U[9], V[9], T[9], UCV[9], G[9], G2[9], UG[9], W, W2;
        mt_rotation(ctx, d, R);
        if (c->eps == 0) {
          double WR = w_of(ops, &p, d, R);
          worst_rot = fmax(worst_rot, fabs(WR - 1));
          CHECK_NEAR(WR, 1.0, 1e-13, "W(R) = 1");
        }
        sample_jacobian(ctx, c, ops, d, C);
        mt_rotation(ctx, d, U);
        mt_rotation(ctx, d, V);
        mt_mul(d, U, C, T);
        mt_mul_bt(d, T, V, UCV);
        vm_measure_eval(ops, &p, d, C, &W, G, NULL);
        vm_measure_eval(ops, &p, d, UCV, &W2, G2, NULL);
        double e = fabs(W - W2) / fmax(1, fabs(W));
        mt_mul(d, U, G, T);
        mt_mul_bt(d, T, V, UG);
        double gmax = 1;
        for (int a = 0; a < d * d; a++) gmax = fmax(gmax, fabs(G[a]));
        for (int a = 0; a < d * d; a++) e = fmax(e, fabs(UG[a] - G2[a]) / gmax);
        worst_inv = fmax(worst_inv, e);
        CHECK(e < 1e-10, "%s d=%d: invariance err %.3e", c->label, d, e);
      }
  }
  fprintf(stderr, "invariance: max |W(R) - 1| %.2e, max rel |W(UCV^T) - W(C)|, G %.2e\n", worst_rot,
          worst_inv);
}

/* Minimum at the isometry (balanced, quasi-iso, penalty / barrier with tiny
 * eps), at every conformal C for the shape measures. */
static void test_minimum(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 5);
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  static const mcase min_cases[] = {
      {VM_MEASURE_BALANCED, "balanced", 0.8, 0, 0, 0},
      {VM_MEASURE_BALANCED, "balanced(th=0.3)", 0.3, 0, 0, 0},
      {VM_MEASURE_QUASI_ISO, "quasi-iso(t=0.3)", 0.8, 0.3, 0, 0},
      {VM_MEASURE_PENALTY, "penalty(eps=1e-6)", 0.8, 0, 1e-6, 0},
      {VM_MEASURE_BARRIER, "barrier(eps=1e-6)", 0.8, 0, 1e-6, 0},
      {VM_MEASURE_SHAPE, "shape", 0.8, 0, 0, 0},
      {VM_MEASURE_SHAPE_ALT, "shape-alt", 0.8, 0, 0, 0},
  };
  for (size_t ci = 0; ci < sizeof min_cases / sizeof min_cases[0]; ci++) {
    const mcase *c = &min_cases[ci];
    const vm_measure_ops *ops = vm_measure_get(c->kind);
    vm_measure_params p = case_params(c, 1);
    int shape = c->kind == VM_MEASURE_SHAPE || c->kind == VM_MEASURE_SHAPE_ALT;
    for (int d = 2; d <= 3; d++) {
      double I[9];
      for (int a = 0; a < d * d; a++) I[a] = d == 2 ? (a == 0 || a == 3) : I3[a];
      double W0 = w_of(ops, &p, d, I), minexcess = INFINITY;
      for (int n = 0; n < 200; n++) {
        double C[9], delta = exp(mt_uniform(ctx, log(1e-3), log(0.5)));
        for (int a = 0; a < d * d; a++) C[a] = I[a] + delta * mt_uniform(ctx, -1, 1);
        double W = w_of(ops, &p, d, C);
        minexcess = fmin(minexcess, W - W0);
        CHECK(W >= W0, "%s d=%d: W(I + dP) = %.17g < W(I) = %.17g", c->label, d, W, W0);
      }
      if (shape)
        for (int n = 0; n < 50; n++) {
          double R[9], lam = exp(mt_uniform(ctx, log(0.1), log(10)));
          mt_rotation(ctx, d, R);
          for (int a = 0; a < d * d; a++) R[a] *= lam;
          CHECK_NEAR(w_of(ops, &p, d, R), 1.0, 1e-13, "shape W(lambda R) = 1");
        }
      CHECK(minexcess > 0, "%s d=%d: min excess %.3e", c->label, d, minexcess);
    }
  }
}

/* Outside the domain: nonzero status and W = +inf; the penalty finite everywhere. */
static void test_domains(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 11);
  for (int d = 2; d <= 3; d++) {
    int nn = d * d;
    double Z[9], Neg[9], Sing[9];
    for (int a = 0; a < nn; a++) Z[a] = Neg[a] = Sing[a] = 0;
    for (int i = 0; i < d; i++) Neg[i * d + i] = Sing[i * d + i] = 1 + i;
    Neg[0] = -1;
    Sing[0] = 0; /* a zero column: det exactly 0 */
    for (int k = 0; k < VM_MEASURE_COUNT; k++) {
      const vm_measure_ops *ops = vm_measure_get((vm_measure_kind)k);
      vm_measure_params p = vm_measure_params_default();
      p.t = k == VM_MEASURE_QUASI_ISO ? 0.2 : 0;
      double W = 0, G[9] = {0}, H[81] = {0};
      CHECK(vm_measure_eval(ops, &p, d, Neg, &W, G, H) != 0 && W == INFINITY, "%s det<0",
            ops->name);
      CHECK(vm_measure_eval(ops, &p, d, Sing, &W, G, H) != 0 && W == INFINITY, "%s det=0",
            ops->name);
      CHECK(vm_measure_eval(ops, &p, d, Z, &W, G, H) != 0 && W == INFINITY, "%s C=0", ops->name);
    }
    /* barrier: outside exactly at det <= -eps */
    vm_measure_params p = vm_measure_params_default();
    p.eps = 0.25;
    const vm_measure_ops *bar = vm_measure_get(VM_MEASURE_BARRIER);
    double D[9] = {0}, W;
    for (int i = 0; i < d; i++) D[i * d + i] = 1;
    D[0] = -0.25;
    CHECK(vm_measure_eval(bar, &p, d, D, &W, NULL, NULL) != 0, "barrier det = -eps");
    D[0] = -0.125;
    CHECK(vm_measure_eval(bar, &p, d, D, &W, NULL, NULL) == 0 && isfinite(W),
          "barrier det = -eps/2");
    D[0] = 0;
    CHECK(vm_measure_eval(bar, &p, d, D, &W, NULL, NULL) == 0 && isfinite(W), "barrier det = 0");

    /* penalty with eps > 0: finite (and nonzero Hessian) for every det */
    const vm_measure_ops *pen = vm_measure_get(VM_MEASURE_PENALTY);
    for (int drop = 0; drop < 2; drop++) {
      vm_measure_params q = vm_measure_params_default();
      q.eps = 1e-3;
      q.drop_chi2 = drop;
      static const double dets[] = {-1e8, -1e3, -1, -1e-3, 0, 1e-3, 1, 1e3};
      for (size_t m = 0; m < sizeof dets / sizeof dets[0]; m++) {
        double C[9] = {0}, G[9], H[81];
        for (int i = 0; i < d; i++) C[i * d + i] = 1;
        C[0] = dets[m];
        int ok = vm_measure_eval(pen, &q, d, C, &W, G, H) == 0 && isfinite(W) && W > 0;
        for (int a = 0; a < nn * nn; a++) ok = ok && isfinite(H[a]);
        CHECK(ok, "penalty finite at det %g (drop %d)", dets[m], drop);
      }
      double G[9], H[81];
      int ok = vm_measure_eval(pen, &q, d, Z, &W, G, H) == 0 && isfinite(W);
      for (int a = 0; a < nn * nn; a++) ok = ok && isfinite(H[a]);
      CHECK(ok, "penalty finite at C = 0 (drop %d)", drop);
    }

    /* quasi-iso: inside exactly where det > t phi */
    const vm_measure_ops *qi = vm_measure_get(VM_MEASURE_QUASI_ISO);
    int nin = 0, nout = 0;
    for (int n = 0; n < 400; n++) {
      vm_measure_params q = vm_measure_params_default();
      q.t = mt_uniform(ctx, 0.05, 0.9);
      double sig[3], C[9];
      for (int i = 0; i < d; i++) sig[i] = exp(mt_uniform(ctx, -1.5, 1.5));
      mt_from_singular(ctx, d, sig, C);
      double s = mt_trace_ctc(d, C), det = mt_det(d, C);
      double sh = d == 3 ? pow(s / 3, 1.5) : s / 2;
      double margin = det - q.t * ((1 - q.theta) * sh + 0.5 * q.theta * (1 + det * det));
      if (fabs(margin) < 1e-12) continue;
      int rc = vm_measure_eval(qi, &q, d, C, &W, NULL, NULL);
      if (margin > 0)
        nin++;
      else
        nout++;
      CHECK((rc == 0) == (margin > 0) && (rc == 0) == (W < INFINITY),
            "quasi-iso d=%d t=%g: rc %d, det - t phi = %g", d, q.t, rc, margin);
    }
    CHECK(nin > 20 && nout > 20, "quasi-iso domain samples %d in, %d out", nin, nout);
  }

  /* chi_eps: chi(x) chi(-x) = eps^2/4 exactly, no cancellation for x << 0 */
  double worst = 0;
  static const double epss[] = {1e-11, 1e-3, 1};
  for (size_t m = 0; m < 3; m++)
    for (double x = 1e-4; x < 1e9; x *= 3.7) {
      double e = epss[m], a = vm_chi_eps(x, e), b = vm_chi_eps(-x, e);
      double r = fabs(a * b / (0.25 * e * e) - 1);
      worst = fmax(worst, r);
      CHECK(b > 0 && r < 1e-14, "chi(%g, %g) chi(-x) = %.17g", x, e, a * b);
    }
  CHECK_NEAR(vm_chi_eps(2.0, 0), 2.0, 0, "chi_0(2)");
  CHECK(vm_chi_eps(-2.0, 0) == 0, "chi_0(-2)");
  fprintf(stderr, "chi_eps: max |chi(x) chi(-x)/(eps^2/4) - 1| = %.2e\n", worst);
}

/* Smallest eigenvalue of a symmetric d x d matrix (cyclic Jacobi). */
static double sym_min_eig(int d, double *A) {
  for (int sweep = 0; sweep < 50; sweep++) {
    double off = 0;
    for (int i = 0; i < d; i++)
      for (int j = i + 1; j < d; j++) off += A[i * d + j] * A[i * d + j];
    if (off < 1e-30) break;
    for (int p = 0; p < d; p++)
      for (int q = p + 1; q < d; q++) {
        double apq = A[p * d + q];
        if (apq == 0) continue;
        double th = (A[q * d + q] - A[p * d + p]) / (2 * apq);
        double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
        double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < d; k++) {
          double akp = A[k * d + p], akq = A[k * d + q];
          A[k * d + p] = c * akp - s * akq;
          A[k * d + q] = s * akp + c * akq;
        }
        for (int k = 0; k < d; k++) {
          double apk = A[p * d + k], aqk = A[q * d + k];
          A[p * d + k] = c * apk - s * aqk;
          A[q * d + k] = s * apk + c * aqk;
        }
      }
  }
  double m = A[0];
  for (int i = 1; i < d; i++) m = fmin(m, A[i * d + i]);
  return m;
}

/* (3): the acoustic tensor A_ik = sum_jl H_{ij,kl} r_j r_l is positive
 * semidefinite for every r, i.e. p^T (d2W) p >= 0 on rank-one p r^T. */
static void test_hadamard_legendre(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 3);
  static const mcase hl_cases[] = {
      {VM_MEASURE_BALANCED, "balanced", 0.8, 0, 0, 0},
      {VM_MEASURE_BALANCED, "balanced(th=0.3)", 0.3, 0, 0, 0},
      {VM_MEASURE_BARRIER, "barrier(eps=0)", 0.8, 0, 0, 0},
      {VM_MEASURE_BARRIER, "barrier(eps=0.1)", 0.8, 0, 0.1, 1},
      {VM_MEASURE_SHAPE, "shape", 0.8, 0, 0, 0},
      {VM_MEASURE_SHAPE_ALT, "shape-alt", 0.8, 0, 0, 0},
      {VM_MEASURE_QUASI_ISO, "quasi-iso(t=0.3)", 0.8, 0.3, 0, 0},
      {VM_MEASURE_PENALTY, "penalty(eps=0.2)", 0.8, 0, 0.2, 1},
  };
  fprintf(stderr, "%-20s %2s %28s\n", "measure", "d", "min lambda(acoustic)/max|A|");
  for (size_t ci = 0; ci < sizeof hl_cases / sizeof hl_cases[0]; ci++) {
    const mcase *c = &hl_cases[ci];
    const vm_measure_ops *ops = vm_measure_get(c->kind);
    vm_measure_params p = case_params(c, 0);
    int polyconvex = c->kind != VM_MEASURE_PENALTY;
    for (int d = 2; d <= 3; d++) {
      int nn = d * d;
      double worst = INFINITY;
      for (int n = 0; n < 200; n++) {
        double C[9], W, H[81];
        sample_jacobian(ctx, c, ops, d, C);
        vm_measure_eval(ops, &p, d, C, &W, NULL, H);
        for (int m = 0; m < 10; m++) {
          double r[3], A[9], amax = 0;
          for (int j = 0; j < d; j++) r[j] = mt_uniform(ctx, -1, 1);
          for (int i = 0; i < d; i++)
            for (int k = 0; k < d; k++) {
              double v = 0;
              for (int j = 0; j < d; j++)
                for (int l = 0; l < d; l++) v += H[(i * d + j) * nn + k * d + l] * r[j] * r[l];
              A[i * d + k] = v;
              amax = fmax(amax, fabs(v));
            }
          double lam = sym_min_eig(d, A) / amax;
          worst = fmin(worst, lam);
        }
      }
      fprintf(stderr, "%-20s %2d %28.3e%s\n", c->label, d, worst,
              polyconvex ? "" : "  (not polyconvex: informative)");
      if (polyconvex) CHECK(worst > -1e-12, "%s d=%d: (3) violated, %.3e", c->label, d, worst);
    }
  }
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx) != VM_OK) return 1;
  test_derivatives(ctx);
  test_known_values();
  test_invariance(ctx);
  test_minimum(ctx);
  test_domains(ctx);
  test_hadamard_legendre(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_measure");
}
