/* test/assembly/test_assembly.c: the discrete functional: gradient and
 * Hessian blocks against finite differences for every element type, rule
 * and measure; invariances, known values, node statistics, subsets, errors
 * and bit-identical results for 1 and 2 threads and for node targets kept
 * or computed at evaluation; the kept F of all-fixed elements. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshgen.h"
#include "varmesh/jacobian.h"
#include "varmesh/problem.h"
#include "varmesh/quadrature.h"
#include "vmtest.h"

enum {
  MS_BAL,
  MS_SHAPE,
  MS_SHAPE_ALT,
  MS_QISO,
  MS_BARRIER,
  MS_PEN_POS,
  MS_PEN_NEG,
  MS_BAR_NEG,
  MS_COUNT
};
static const char *ms_name[MS_COUNT] = {"balanced", "shape",    "shape-alt", "quasi-iso",
                                        "barrier",  "penalty+", "penalty-",  "barrier-"};

typedef struct {
  int type, rule, surf, n[3];
  const char *name;
} ecase;

static const ecase ecases[] = {
    {VM_TRI, 0, 0, {2, 2, 1}, "tri"},      {VM_QUAD, 0, 0, {2, 2, 1}, "quad"},
    {VM_TRI, 0, 1, {2, 2, 1}, "tri-surf"}, {VM_QUAD, 0, 1, {2, 2, 1}, "quad-surf"},
    {VM_TET, 0, 0, {1, 1, 1}, "tet"},      {VM_PYRAMID, 0, 0, {1, 1, 1}, "pyramid"},
    {VM_PRISM, 0, 0, {2, 1, 1}, "prism"},  {VM_PRISM, 1, 0, {2, 1, 1}, "prism"},
    {VM_HEX, 0, 0, {2, 1, 1}, "hex"},      {VM_HEX, 1, 0, {2, 1, 1}, "hex"},
};
#define NCASE ((int)(sizeof ecases / sizeof ecases[0]))

static double *dup(const double *x, size_t n) {
  double *y = malloc(n * sizeof *y);
  memcpy(y, x, n * sizeof *y);
  return y;
}

static int64_t find_pos(const int64_t *rp, const int32_t *adj, int32_t u, int32_t v) {
  for (int64_t k = rp[u]; k < rp[u + 1]; k++)
    if (adj[k] == v) return k;
  return -1;
}

static int set_ms(vm_problem *p, int ms, double mindet) {
  vm_measure_params q = vm_measure_params_default();
  vm_measure_kind kind = VM_MEASURE_BALANCED;
  switch (ms) {
  case MS_SHAPE: kind = VM_MEASURE_SHAPE; break;
  case MS_SHAPE_ALT: kind = VM_MEASURE_SHAPE_ALT; break;
  case MS_QISO:
    kind = VM_MEASURE_QUASI_ISO;
    q.t = 0.1;
    break;
  case MS_BARRIER:
    kind = VM_MEASURE_BARRIER;
    q.eps = 0.05;
    break;
  case MS_PEN_POS:
    kind = VM_MEASURE_PENALTY;
    q.eps = 0.05;
    q.drop_chi2 = 0;
    break;
  case MS_PEN_NEG:
    kind = VM_MEASURE_PENALTY;
    q.eps = 0.3;
    q.drop_chi2 = 0;
    break;
  case MS_BAR_NEG:
    kind = VM_MEASURE_BARRIER;
    q.eps = 1.5 * fabs(mindet);
    break;
  default: break;
  }
  return vm_problem_set_measure(p, kind, &q);
}

/* Max relative errors of the gradient (vs central differences of F) and of
 * hdiag and hoff (vs central differences of the gradient) at x0. */
static int fd_errors(vm_problem *p, const double *x0, double *eg, double *eh) {
  const vm_mesh *m = vm_problem_mesh(p);
  int64_t nv = m->nv;
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  int64_t nnz = rp[nv];
  double F, Fp, Fm;
  double *g = calloc(3 * nv, sizeof *g), *hd = calloc(9 * nv, sizeof *hd);
  double *ho = calloc(3 * nnz + 1, sizeof *ho);
  double *gp = calloc(3 * nv, sizeof *gp), *gm = calloc(3 * nv, sizeof *gm);
  double *x = dup(x0, 3 * nv);
  vm_eval ev = {&F, g, hd, ho};
  int st = vm_problem_eval(p, x, &ev);
  double hs = 1e-5, mg = 0, erg = 0, mh = 0, erh = 0;
  for (int64_t k = 0; k < 3 * nv; k++) mg = fmax(mg, fabs(g[k]));
  int nc = m->dim;
  for (int64_t v = 0; v < nv && !st; v++)
    for (int c = 0; c < nc; c++) {
      vm_eval ep = {&Fp, gp, NULL, NULL}, em = {&Fm, gm, NULL, NULL};
      x[3 * v + c] = x0[3 * v + c] + hs;
      st |= vm_problem_eval(p, x, &ep);
      x[3 * v + c] = x0[3 * v + c] - hs;
      st |= vm_problem_eval(p, x, &em);
      x[3 * v + c] = x0[3 * v + c];
      erg = fmax(erg, fabs(g[3 * v + c] - (Fp - Fm) / (2 * hs)));
      for (int r = 0; r < nc; r++) {
        double ref = (gp[3 * v + r] - gm[3 * v + r]) / (2 * hs);
        mh = fmax(mh, fabs(ref));
        erh = fmax(erh, fabs(hd[9 * v + 3 * r + c] - ref));
      }
      for (int64_t k = rp[v]; k < rp[v + 1]; k++) {
        int32_t u = adj[k];
        double ref = (gp[3 * u + c] - gm[3 * u + c]) / (2 * hs);
        mh = fmax(mh, fabs(ref));
        erh = fmax(erh, fabs(ho[3 * find_pos(rp, adj, u, (int32_t)v) + c] - ref));
      }
    }
  *eg = erg / fmax(mg, 1e-300);
  *eh = erh / fmax(mh, 1e-300);
  free(g);
  free(hd);
  free(ho);
  free(gp);
  free(gm);
  free(x);
  return st;
}

/* Move vertex 0 past the centroid of element 0 until some nodes invert
 * while every |det C| stays clear of 0; returns min det or 0 on failure. */
static double invert_some(vm_problem *p, double *x) {
  const vm_mesh *m = vm_problem_mesh(p);
  int k = vm_elem_nverts(m->etype[0]);
  int32_t v0 = m->conn[0];
  double c[3] = {0, 0, 0}, x0[3];
  for (int a = 0; a < k; a++)
    for (int r = 0; r < 3; r++) c[r] += x[3 * m->conn[a] + r] / k;
  memcpy(x0, x + 3 * v0, sizeof x0);
  int64_t nn = vm_problem_num_nodes(p);
  double *det = malloc(nn * sizeof *det);
  double res = 0;
  for (double f = 1.3; f < 3 && res == 0; f += 0.1) {
    for (int r = 0; r < m->dim; r++) x[3 * v0 + r] = x0[r] + f * (c[r] - x0[r]);
    vm_problem_node_dets(p, x, det);
    double mn = INFINITY, ma = INFINITY;
    for (int64_t q = 0; q < nn; q++) {
      mn = fmin(mn, det[q]);
      ma = fmin(ma, fabs(det[q]));
    }
    if (mn < -0.05 && ma > 0.02) res = mn;
  }
  free(det);
  return res;
}

/* Per-vertex SPD tensors (variant runs), scalar metrics, weights, eps. */
static void rand_tensor(vm_ctx *ctx, int64_t nv, double *G) {
  for (int64_t v = 0; v < nv; v++) {
    for (int c = 0; c < 3; c++) G[6 * v + c] = 1 + 0.5 * vm_ctx_rand_unit(ctx);
    for (int c = 3; c < 6; c++) G[6 * v + c] = 0.3 * (2 * vm_ctx_rand_unit(ctx) - 1);
  }
}

static void test_fd(vm_ctx *ctx) {
  fprintf(stderr, "%-10s %-9s %-10s %-8s %-16s %-16s\n", "element", "rule", "measure", "variant",
          "max_rel_err_grad", "max_rel_err_hess");
  for (int ci = 0; ci < NCASE; ci++) {
    const ecase *ec = &ecases[ci];
    for (int variant = 0; variant < 2; variant++)
      for (int ms = 0; ms < MS_COUNT; ms++) {
        if (variant && ms != MS_BAL && ms != MS_PEN_NEG && ms != MS_SHAPE) continue;
        vm_ctx_seed(ctx, 1000 + 31 * ci + 7 * ms + variant);
        vm_mesh *m = mg_build(ctx, ec->type, ec->surf, ec->n[0], ec->n[1], ec->n[2], 1.0);
        CHECK(m != NULL, "mesh %s", ec->name);
        if (!m) continue;
        double *base = dup(m->xyz, 3 * m->nv);
        mg_jitter(ctx, m, 0.12);
        vm_problem *p = NULL;
        int st = vm_problem_create(ctx, m, &p);
        CHECK(st == 0, "create %s: %s", ec->name, vm_ctx_error(ctx));
        if (st) {
          free(base);
          vm_mesh_destroy(&m);
          continue;
        }
        CHECK(vm_problem_set_rule(p, ec->rule) == 0, "rule");
        double *G = NULL, *w = NULL, *eps = NULL;
        if (variant) {
          /* reference targets from another jitter, metric, weights */
          double *ref = dup(base, 3 * m->nv);
          for (int64_t k = 0; k < 3 * m->nv; k++)
            if (m->dim == 3 || k % 3 < 2) ref[k] += 0.1 * (2 * vm_ctx_rand_unit(ctx) - 1);
          CHECK(vm_problem_set_target_reference(p, ref) == 0, "ref: %s", vm_ctx_error(ctx));
          free(ref);
          G = malloc(6 * m->nv * sizeof *G);
          if (ec->surf) {
            for (int64_t v = 0; v < m->nv; v++) G[v] = 1 + vm_ctx_rand_unit(ctx);
            CHECK(vm_problem_set_metric_scalar(p, G) == 0, "metric: %s", vm_ctx_error(ctx));
          } else {
            rand_tensor(ctx, m->nv, G);
            CHECK(vm_problem_set_metric_tensor(p, G) == 0, "metric: %s", vm_ctx_error(ctx));
          }
          w = malloc(m->ne * sizeof *w);
          for (int64_t e = 0; e < m->ne; e++) w[e] = 0.5 + vm_ctx_rand_unit(ctx);
          CHECK(vm_problem_set_weights(p, w) == 0, "weights");
        }
        double *x = dup(m->xyz, 3 * m->nv), mindet = 0;
        if (ms == MS_PEN_NEG || ms == MS_BAR_NEG) {
          mindet = invert_some(p, x);
          CHECK(mindet < 0, "%s: could not invert a node", ec->name);
        }
        CHECK(set_ms(p, ms, mindet) == 0, "measure: %s", vm_ctx_error(ctx));
        if (variant && ms == MS_PEN_NEG) {
          int64_t nn = vm_problem_num_nodes(p);
          eps = malloc(nn * sizeof *eps);
          for (int64_t q = 0; q < nn; q++) eps[q] = 0.2 + 0.2 * vm_ctx_rand_unit(ctx);
          CHECK(vm_problem_set_node_eps(p, eps) == 0, "node eps");
        }
        double eg = 1, eh = 1;
        st = fd_errors(p, x, &eg, &eh);
        CHECK(st == 0, "%s %s: eval status %d", ec->name, ms_name[ms], st);
        fprintf(stderr, "%-10s %-9s %-10s %-8s %-16.2e %-16.2e\n", ec->name,
                ec->rule ? "geometric" : "corner", ms_name[ms], variant ? "ref+G+w" : "ideal", eg,
                eh);
        CHECK(eg < 1e-6, "%s %s grad rel err %g", ec->name, ms_name[ms], eg);
        CHECK(eh < 1e-5, "%s %s hess rel err %g", ec->name, ms_name[ms], eh);
        free(G);
        free(w);
        free(eps);
        free(x);
        free(base);
        vm_problem_destroy(&p);
        vm_mesh_destroy(&m);
      }
  }
}

/* A mixed mesh (hex, pyramid, prism, tet sharing faces) and a plane fan
 * whose centre has 260 neighbours (hoff positions by binary search). */
static void test_fd_special(vm_ctx *ctx) {
  static const double X[12][3] = {{0, 0, 0},       {1, 0, 0},     {1, 1, 0},     {0, 1, 0},
                                  {0, 0, 1},       {1, 0, 1},     {1, 1, 1},     {0, 1, 1},
                                  {0.5, 0.5, 1.7}, {1.8, 0.5, 0}, {1.8, 0.5, 1}, {-0.8, 0.5, 0.5}};
  static const int32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7}, pyr[5] = {4, 5, 6, 7, 8},
                       pri[6] = {1, 9, 2, 5, 10, 6};
  int32_t tet[4] = {0, 3, 4, 11};
  for (int rule = 0; rule < 2; rule++)
    for (int ms = 0; ms < 2; ms++) {
      vm_mesh *m = NULL;
      vm_mesh_create(ctx, &m);
      for (int v = 0; v < 12; v++) vm_mesh_add_vertex(m, X[v][0], X[v][1], X[v][2], NULL);
      if (mg_tet_vol(m->xyz, tet) < 0) {
        int32_t t = tet[1];
        tet[1] = tet[2];
        tet[2] = t;
      }
      vm_mesh_add_element(m, VM_HEX, hex);
      vm_mesh_add_element(m, VM_PYRAMID, pyr);
      vm_mesh_add_element(m, VM_PRISM, pri);
      vm_mesh_add_element(m, VM_TET, tet);
      vm_ctx_seed(ctx, 40 + ms);
      mg_jitter(ctx, m, 0.1);
      vm_problem *p = NULL;
      CHECK(vm_problem_create(ctx, m, &p) == 0, "mixed: %s", vm_ctx_error(ctx));
      vm_problem_set_rule(p, rule);
      double *x = dup(m->xyz, 3 * m->nv), mindet = 0;
      if (ms) mindet = invert_some(p, x);
      set_ms(p, ms ? MS_PEN_NEG : MS_BAL, mindet);
      double eg = 1, eh = 1;
      CHECK(fd_errors(p, x, &eg, &eh) == 0, "mixed eval");
      fprintf(stderr, "%-10s %-9s %-10s %-8s %-16.2e %-16.2e\n", "mixed",
              rule ? "geometric" : "corner", ms ? "penalty-" : "balanced", "ideal", eg, eh);
      CHECK(eg < 1e-6 && eh < 1e-5, "mixed: errors %g %g", eg, eh);
      free(x);
      vm_problem_destroy(&p);
      vm_mesh_destroy(&m);
    }
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  m->dim = 2;
  const int nfan = 260;
  vm_mesh_add_vertex(m, 0, 0, 0, NULL);
  for (int k = 0; k < nfan; k++)
    vm_mesh_add_vertex(m, cos(6.283185307179586 * k / nfan), sin(6.283185307179586 * k / nfan), 0,
                       NULL);
  for (int k = 0; k < nfan; k++) {
    int32_t t[3] = {0, 1 + k, 1 + (k + 1) % nfan};
    vm_mesh_add_element(m, VM_TRI, t);
  }
  vm_ctx_seed(ctx, 5);
  mg_jitter(ctx, m, 0.002);
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "fan: %s", vm_ctx_error(ctx));
  double eg = 1, eh = 1;
  CHECK(fd_errors(p, m->xyz, &eg, &eh) == 0, "fan eval");
  fprintf(stderr, "%-10s %-9s %-10s %-8s %-16.2e %-16.2e\n", "tri-fan260", "corner", "balanced",
          "ideal", eg, eh);
  CHECK(eg < 1e-6 && eh < 1e-5, "fan: errors %g %g", eg, eh);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* F is invariant under rotation and translation of all vertices. */
static void test_invariance(vm_ctx *ctx) {
  const double ang = 0.7, ax[3] = {0.36, 0.48, 0.8}; /* unit axis */
  double R[9], c = cos(ang), s = sin(ang);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) R[3 * i + j] = (i == j ? c : 0) + (1 - c) * ax[i] * ax[j];
  R[1] -= s * ax[2], R[2] += s * ax[1], R[3] += s * ax[2];
  R[5] -= s * ax[0], R[6] -= s * ax[1], R[7] += s * ax[0];
  for (int ci = 0; ci < NCASE; ci++) {
    const ecase *ec = &ecases[ci];
    vm_ctx_seed(ctx, 77 + ci);
    vm_mesh *m = mg_build(ctx, ec->type, ec->surf, 2, 2, 2, 1.0);
    mg_jitter(ctx, m, 0.15);
    vm_problem *p = NULL;
    CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
    vm_problem_set_rule(p, ec->rule);
    double F0, F1;
    CHECK(vm_problem_value(p, m->xyz, &F0) == 0, "value");
    for (int64_t v = 0; v < m->nv; v++) {
      double *y = m->xyz + 3 * v, z[3];
      if (m->dim == 2) {
        z[0] = c * y[0] - s * y[1] + 3.5;
        z[1] = s * y[0] + c * y[1] - 1.25;
        z[2] = 0;
      } else {
        for (int i = 0; i < 3; i++)
          z[i] = R[3 * i] * y[0] + R[3 * i + 1] * y[1] + R[3 * i + 2] * y[2];
        z[0] += 3.5, z[1] -= 1.25, z[2] += 10;
      }
      memcpy(y, z, sizeof z);
    }
    CHECK(vm_problem_update_normals(p, NULL) == 0, "normals");
    CHECK(vm_problem_value(p, m->xyz, &F1) == 0, "value");
    CHECK(fabs(F1 - F0) <= 1e-12 * fabs(F0), "%s %s: F %.17g rotated %.17g", ec->name,
          ec->rule ? "geometric" : "corner", F0, F1);
    vm_problem_destroy(&p);
    vm_mesh_destroy(&m);
  }
}

/* F equals the total target volume where the mesh is its own target, the
 * gradient vanishes there; targets from a field give the same. */
static void test_known_values(vm_ctx *ctx) {
  for (int ci = 0; ci < NCASE; ci++) {
    const ecase *ec = &ecases[ci];
    vm_ctx_seed(ctx, 500 + ci);
    /* surfaces: a jittered plane mesh tilted into 3D, so quads are planar
     * and "the mesh is its target" holds exactly */
    vm_mesh *m = mg_build(ctx, ec->type, 0, 2, 2, 2, 1.0);
    mg_jitter(ctx, m, 0.15);
    if (ec->surf) {
      m->dim = 3;
      for (int64_t v = 0; v < m->nv; v++) {
        double *y = m->xyz + 3 * v;
        y[2] = 0.6 * y[1];
        y[1] *= 0.8;
      }
      CHECK(vm_problem_update_normals(NULL, NULL) == VM_ERR_ARG, "NULL problem");
    }
    vm_problem *p = NULL;
    CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
    vm_problem_set_rule(p, ec->rule);
    CHECK(vm_problem_set_target_reference(p, m->xyz) == 0, "ref %s", vm_ctx_error(ctx));
    double F, tv = vm_problem_target_volume(p);
    double *g = calloc(3 * m->nv, sizeof *g);
    vm_eval ev = {&F, g, NULL, NULL};
    CHECK(vm_problem_eval(p, m->xyz, &ev) == 0, "eval");
    CHECK(fabs(F - tv) <= 1e-13 * tv, "%s: F %.17g target volume %.17g", ec->name, F, tv);
    double gm = 0;
    for (int64_t k = 0; k < 3 * m->nv; k++) gm = fmax(gm, fabs(g[k]));
    CHECK(gm < 1e-12, "%s: |grad| %g at the target", ec->name, gm);
    /* the same targets through an element field */
    vm_field *f = NULL;
    CHECK(vm_mesh_add_field(m, "target", VM_FIELD_ELEMENT, VM_FIELD_F64, 24, &f) == 0, "field");
    for (int64_t e = 0; e < m->ne; e++)
      for (int64_t a = m->eoff[e]; a < m->eoff[e + 1]; a++)
        memcpy((double *)f->data + 24 * e + 3 * (a - m->eoff[e]), m->xyz + 3 * m->conn[a],
               3 * sizeof(double));
    CHECK(vm_problem_set_target_field(p, "target") == 0, "field: %s", vm_ctx_error(ctx));
    double F2;
    CHECK(vm_problem_value(p, m->xyz, &F2) == 0, "value");
    CHECK(fabs(F2 - tv) <= 1e-13 * tv, "%s: field F %.17g vs %.17g", ec->name, F2, tv);
    free(g);
    vm_problem_destroy(&p);
    vm_mesh_destroy(&m);
  }
  /* uniform Cartesian hexes with ideal targets: the minimum */
  for (int rule = 0; rule < 2; rule++) {
    vm_mesh *m = mg_build(ctx, VM_HEX, 0, 4, 3, 2, 0.5);
    vm_problem *p = NULL;
    CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
    vm_problem_set_rule(p, rule);
    CHECK(fabs(vm_problem_target_size(p) - 0.5) < 1e-15, "size %.17g", vm_problem_target_size(p));
    double F, *g = calloc(3 * m->nv, sizeof *g);
    vm_eval ev = {&F, g, NULL, NULL};
    CHECK(vm_problem_eval(p, m->xyz, &ev) == 0, "eval");
    double gm = 0;
    for (int64_t k = 0; k < 3 * m->nv; k++) gm = fmax(gm, fabs(g[k]));
    CHECK(gm < 1e-13, "Cartesian hex (%s): |grad| %g", rule ? "geometric" : "corner", gm);
    CHECK(fabs(F - 0.125 * 24) < 1e-13, "Cartesian hex: F %.17g, volume 3", F);
    free(g);
    vm_problem_destroy(&p);
    vm_mesh_destroy(&m);
  }
}

static int same_bits(const double *a, const double *b, size_t n) {
  return memcmp(a, b, n * sizeof *a) == 0;
}

/* 1 and 2 threads give the same bits. */
static void test_threads(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 12);
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, 12, 12, 12, 1.0);
  mg_jitter(ctx, m, 0.15);
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  size_t nv = (size_t)m->nv, nnz = (size_t)rp[nv];
  for (int rule = 0; rule < 2; rule++) {
    vm_problem_set_rule(p, rule);
    double F[2], Fv[2], *g[2], *hd[2], *ho[2];
    vm_node_stats ns[2];
    for (int t = 0; t < 2; t++) {
      vm_ctx_set_threads(ctx, t + 1);
      g[t] = malloc(3 * nv * sizeof(double));
      hd[t] = malloc(9 * nv * sizeof(double));
      ho[t] = malloc(3 * nnz * sizeof(double));
      vm_eval ev = {&F[t], g[t], hd[t], ho[t]};
      CHECK(vm_problem_eval(p, m->xyz, &ev) == 0, "eval");
      CHECK(vm_problem_value(p, m->xyz, &Fv[t]) == 0, "value");
      vm_problem_node_stats(p, m->xyz, &ns[t]);
    }
    CHECK(same_bits(F, F + 1, 1), "F %.17g vs %.17g", F[0], F[1]);
    CHECK(same_bits(Fv, F, 1) && same_bits(Fv + 1, F, 1), "value %.17g vs eval %.17g", Fv[0], F[0]);
    CHECK(same_bits(g[0], g[1], 3 * nv), "gradient differs between 1 and 2 threads");
    CHECK(same_bits(hd[0], hd[1], 9 * nv), "hdiag differs between 1 and 2 threads");
    CHECK(same_bits(ho[0], ho[1], 3 * nnz), "hoff differs between 1 and 2 threads");
    CHECK(!memcmp(&ns[0], &ns[1], sizeof ns[0]), "node stats differ");
    for (int t = 0; t < 2; t++) {
      free(g[t]);
      free(hd[t]);
      free(ho[t]);
    }
  }
  vm_ctx_set_threads(ctx, 0);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* Node targets kept in memory or computed at every evaluation
 * (vm_problem_set_target_store): the same bits for F, the gradient, both
 * Hessian forms, node statistics and determinants, for reference and field
 * targets on every element type (2D plane and surface meshes included)
 * and both rules; a bad store or a degenerate target is refused with the
 * problem as it was. */
static void test_target_store(vm_ctx *ctx) {
  for (int ci = 0; ci < NCASE; ci++) {
    const ecase *ec = &ecases[ci];
    for (int field = 0; field < 2; field++) {
      vm_ctx_seed(ctx, 77 + 5 * ci + field);
      vm_mesh *m = mg_build(ctx, ec->type, ec->surf, ec->n[0] + 1, ec->n[1] + 1, ec->n[2], 1.0);
      CHECK(m != NULL, "mesh %s", ec->name);
      if (!m) continue;
      double *ref = dup(m->xyz, 3 * m->nv);
      for (int64_t k = 0; k < 3 * m->nv; k++)
        if (m->dim == 3 || k % 3 < 2) ref[k] += 0.08 * (2 * vm_ctx_rand_unit(ctx) - 1);
      mg_jitter(ctx, m, 0.1);
      vm_problem *p = NULL;
      CHECK(vm_problem_create(ctx, m, &p) == 0, "create %s", ec->name);
      CHECK(vm_problem_set_rule(p, ec->rule) == 0, "rule");
      int st;
      if (field) {
        vm_field *f = NULL;
        int nc = 3 * vm_elem_nverts(ec->type);
        CHECK(vm_mesh_add_field(m, "tgt", VM_FIELD_ELEMENT, VM_FIELD_F64, nc, &f) == 0, "field");
        for (int64_t e = 0; e < m->ne; e++)
          for (int a = 0; a < nc / 3; a++)
            memcpy((double *)f->data + (size_t)e * nc + 3 * a,
                   ref + 3 * (int64_t)m->conn[m->eoff[e] + a], 3 * sizeof(double));
        st = vm_problem_set_target_field(p, "tgt");
      } else {
        st = vm_problem_set_target_reference(p, ref);
      }
      CHECK(st == 0, "%s targets: %s", ec->name, vm_ctx_error(ctx));
      const int64_t *rp;
      const int32_t *adj;
      vm_problem_graph(p, &rp, &adj);
      size_t nv = (size_t)m->nv, nnz = (size_t)rp[nv], nn = (size_t)vm_problem_num_nodes(p);
      double F[2], Fb[2], Fv[2], *g[2], *hd[2], *ho[2], *hb[2], *dt[2];
      vm_node_stats ns[2];
      for (int lazy = 0; lazy < 2; lazy++) {
        if (lazy) CHECK(vm_problem_set_target_store(p, 0) == 0, "store 0");
        g[lazy] = malloc(3 * nv * sizeof(double));
        hd[lazy] = malloc(9 * nv * sizeof(double));
        ho[lazy] = malloc(3 * nnz * sizeof(double));
        hb[lazy] = malloc(9 * nnz * sizeof(double));
        dt[lazy] = malloc(nn * sizeof(double));
        double *gb = malloc(3 * nv * sizeof(double)), *hdb = malloc(9 * nv * sizeof(double));
        vm_eval ev = {&F[lazy], g[lazy], hd[lazy], ho[lazy]};
        vm_eval_blocks eb = {&Fb[lazy], gb, hdb, hb[lazy], 1};
        CHECK(vm_problem_eval(p, m->xyz, &ev) == 0, "eval");
        CHECK(vm_problem_eval_blocks(p, m->xyz, &eb) == 0, "eval blocks");
        CHECK(vm_problem_value(p, m->xyz, &Fv[lazy]) == 0, "value");
        CHECK(vm_problem_node_stats(p, m->xyz, &ns[lazy]) == 0, "node stats");
        CHECK(vm_problem_node_dets(p, m->xyz, dt[lazy]) == 0, "node dets");
        free(gb);
        free(hdb);
      }
      CHECK(isfinite(F[0]) && F[0] > 0, "%s F %g", ec->name, F[0]);
      CHECK(same_bits(F, F + 1, 1) && same_bits(Fb, Fb + 1, 1) && same_bits(Fv, Fv + 1, 1),
            "%s %s: F %.17g vs %.17g computed at evaluation", ec->name, field ? "field" : "ref",
            F[0], F[1]);
      CHECK(same_bits(g[0], g[1], 3 * nv) && same_bits(hd[0], hd[1], 9 * nv) &&
                same_bits(ho[0], ho[1], 3 * nnz) && same_bits(hb[0], hb[1], 9 * nnz),
            "%s: derivatives differ with targets computed at evaluation", ec->name);
      CHECK(!memcmp(&ns[0], &ns[1], sizeof ns[0]) && same_bits(dt[0], dt[1], nn),
            "%s: node statistics differ", ec->name);
      for (int t = 0; t < 2; t++) {
        free(g[t]);
        free(hd[t]);
        free(ho[t]);
        free(hb[t]);
        free(dt[t]);
      }
      /* a degenerate target refused in either mode; the problem as it was */
      if (!field && vm_elem_dim(ec->type) == 3) {
        CHECK(vm_problem_set_target_store(p, -1) == VM_ERR_ARG, "negative store refused");
        vm_ctx_clear_error(ctx);
        double *flat = dup(ref, 3 * m->nv);
        for (int64_t v = 0; v < m->nv; v++) flat[3 * v + 2] = 0;
        CHECK(vm_problem_set_target_reference(p, flat) == VM_ERR_ARG, "%s flat target", ec->name);
        vm_ctx_clear_error(ctx);
        double F2;
        CHECK(vm_problem_value(p, m->xyz, &F2) == 0 && same_bits(&F2, F, 1),
              "%s: the old targets kept", ec->name);
        CHECK(vm_problem_set_target_store(p, (int64_t)1 << 40) == 0, "store back");
        CHECK(vm_problem_value(p, m->xyz, &F2) == 0 && same_bits(&F2, F, 1),
              "%s: stored again, the same F", ec->name);
        free(flat);
      }
      free(ref);
      vm_problem_destroy(&p);
      vm_mesh_destroy(&m);
    }
  }
}

/* One mirrored hex inverts exactly its 8 (corner) or 64 (geometric) nodes;
 * one tet with two vertices swapped, exactly its node. */
static void test_node_stats(vm_ctx *ctx) {
  for (int rule = 0; rule < 2; rule++) {
    vm_ctx_seed(ctx, 3);
    vm_mesh *m = mg_build(ctx, VM_HEX, 0, 3, 3, 3, 1.0);
    mg_jitter(ctx, m, 0.05);
    int32_t *c = m->conn + m->eoff[13];
    for (int a = 0; a < 4; a++) {
      int32_t t = c[a];
      c[a] = c[a + 4];
      c[a + 4] = t;
    }
    vm_problem *p = NULL;
    CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
    vm_problem_set_rule(p, rule);
    vm_node_stats ns;
    CHECK(vm_problem_node_stats(p, m->xyz, &ns) == 0, "stats");
    int64_t want = rule ? 64 : 8, nn = vm_problem_num_nodes(p);
    CHECK(ns.inverted == want, "mirrored hex: %lld inverted nodes, want %lld",
          (long long)ns.inverted, (long long)want);
    double *det = malloc(nn * sizeof *det), mn = INFINITY;
    vm_problem_node_dets(p, m->xyz, det);
    const int32_t *ne = vm_problem_node_elements(p);
    int64_t cnt = 0, wrong = 0;
    for (int64_t q = 0; q < nn; q++) {
      mn = fmin(mn, det[q]);
      if (det[q] <= 0) {
        cnt++;
        wrong += ne[q] != 13;
      }
    }
    CHECK(cnt == want && wrong == 0, "node dets: %lld inverted, %lld elsewhere", (long long)cnt,
          (long long)wrong);
    CHECK(mn == ns.min_det && ns.phi_min < 0 && ns.psi_min < 0, "min det %g vs %g", mn, ns.min_det);
    double F = 0;
    CHECK(vm_problem_value(p, m->xyz, &F) == VM_WARN_INVERTED && F == INFINITY, "value %g", F);
    double *g = malloc(3 * m->nv * sizeof *g);
    vm_eval ev = {&F, g, NULL, NULL};
    F = 0;
    CHECK(vm_problem_eval(p, m->xyz, &ev) == VM_WARN_INVERTED && F == INFINITY, "eval %g", F);
    free(g);
    free(det);
    vm_problem_destroy(&p);
    vm_mesh_destroy(&m);
  }
  vm_mesh *m = mg_build(ctx, VM_TET, 0, 2, 2, 2, 1.0);
  int32_t *c = m->conn + m->eoff[20], t = c[1];
  c[1] = c[2];
  c[2] = t;
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  vm_node_stats ns;
  vm_problem_node_stats(p, m->xyz, &ns);
  CHECK(ns.inverted == 1, "swapped tet: %lld inverted", (long long)ns.inverted);
  /* an ideal-size Kuhn tet is not regular but has phi in (0, 1] */
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* Subsets add up; per-node eps equal to eps changes nothing. */
static void test_subsets(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 9);
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, 3, 3, 3, 1.0);
  mg_jitter(ctx, m, 0.1);
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  size_t nv = (size_t)m->nv;
  double F, Fa, Fb, Fall;
  double *g = malloc(3 * nv * sizeof *g), *ga = malloc(3 * nv * sizeof *ga);
  double *gb = malloc(3 * nv * sizeof *gb), *gall = malloc(3 * nv * sizeof *gall);
  uint8_t *mask = malloc(m->ne);
  vm_eval e0 = {&F, g, NULL, NULL}, ea = {&Fa, ga, NULL, NULL}, eb = {&Fb, gb, NULL, NULL},
          eall = {&Fall, gall, NULL, NULL};
  vm_problem_eval(p, m->xyz, &e0);
  for (int64_t e = 0; e < m->ne; e++) mask[e] = 1;
  vm_problem_set_active(p, mask);
  vm_problem_eval(p, m->xyz, &eall);
  CHECK(Fall == F && same_bits(g, gall, 3 * nv), "full mask differs");
  for (int64_t e = 0; e < m->ne; e++) mask[e] = e % 3 == 0;
  vm_problem_set_active(p, mask);
  vm_problem_eval(p, m->xyz, &ea);
  double Fv;
  vm_problem_value(p, m->xyz, &Fv);
  CHECK(Fv == Fa, "masked value %.17g vs eval %.17g", Fv, Fa);
  for (int64_t e = 0; e < m->ne; e++) mask[e] = e % 3 != 0;
  vm_problem_set_active(p, mask);
  vm_problem_eval(p, m->xyz, &eb);
  CHECK(fabs(Fa + Fb - F) <= 1e-13 * F, "subsets: %.17g + %.17g vs %.17g", Fa, Fb, F);
  double err = 0;
  for (size_t k = 0; k < 3 * nv; k++) err = fmax(err, fabs(ga[k] + gb[k] - g[k]));
  CHECK(err < 1e-13, "subset gradients add up to within %g", err);
  vm_problem_set_active(p, NULL);
  vm_problem_eval(p, m->xyz, &eall);
  CHECK(Fall == F && same_bits(g, gall, 3 * nv), "mask removal");
  /* per-node eps */
  vm_measure_params q = vm_measure_params_default();
  q.eps = 0.25;
  vm_problem_set_measure(p, VM_MEASURE_PENALTY, &q);
  vm_problem_eval(p, m->xyz, &e0);
  int64_t nn = vm_problem_num_nodes(p);
  double *eps = malloc(nn * sizeof *eps);
  for (int64_t k = 0; k < nn; k++) eps[k] = 0.25;
  CHECK(vm_problem_set_node_eps(p, eps) == 0, "node eps");
  vm_problem_eval(p, m->xyz, &eall);
  CHECK(Fall == F && same_bits(g, gall, 3 * nv), "node eps = eps differs");
  free(eps);
  free(mask);
  free(g);
  free(ga);
  free(gb);
  free(gall);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* Per-node weights: all 1 changes nothing; weights w and 1 - w add up to
 * the whole; a node of weight 0 may be outside the domain (a barrier
 * measure at an inverted node); gradient and Hessian pieces by finite
 * differences on the hex's 70 nodes of VM_RULE_GEOMETRIC_SPLIT. */
static void test_node_weights(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 11);
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, 2, 2, 2, 1.0);
  mg_jitter(ctx, m, 0.15);
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  CHECK(vm_problem_set_rule(p, VM_RULE_GEOMETRIC_SPLIT) == 0, "rule");
  vm_measure_params q = vm_measure_params_default();
  q.eps = 0.3;
  q.drop_chi2 = 0; /* the exact Hessian */
  vm_problem_set_measure(p, VM_MEASURE_PENALTY, &q);
  size_t nv = (size_t)m->nv;
  int64_t nn = vm_problem_num_nodes(p);
  double F, Fa, Fb, Fall;
  double *g = malloc(3 * nv * sizeof *g), *ga = malloc(3 * nv * sizeof *ga);
  double *gb = malloc(3 * nv * sizeof *gb), *gall = malloc(3 * nv * sizeof *gall);
  double *w = malloc(nn * sizeof *w), *w1 = malloc(nn * sizeof *w1);
  vm_eval e0 = {&F, g, NULL, NULL}, ea = {&Fa, ga, NULL, NULL}, eb = {&Fb, gb, NULL, NULL},
          eall = {&Fall, gall, NULL, NULL};
  vm_problem_eval(p, m->xyz, &e0);
  for (int64_t k = 0; k < nn; k++) w[k] = 1;
  CHECK(vm_problem_set_node_weights(p, w) == 0, "weights");
  vm_problem_eval(p, m->xyz, &eall);
  CHECK(Fall == F && same_bits(g, gall, 3 * nv), "weights 1 differ");
  for (int64_t k = 0; k < nn; k++) {
    w[k] = k % 5 == 0 ? 0 : (double)(k % 7) / 7;
    w1[k] = 1 - w[k];
  }
  vm_problem_set_node_weights(p, w);
  vm_problem_eval(p, m->xyz, &ea);
  double eg = 1, eh = 1;
  CHECK(fd_errors(p, m->xyz, &eg, &eh) == 0, "weighted eval");
  CHECK(eg < 1e-6 && eh < 1e-5, "weighted nodes: gradient error %.2e, Hessian %.2e", eg, eh);
  vm_problem_set_node_weights(p, w1);
  vm_problem_eval(p, m->xyz, &eb);
  CHECK(fabs(Fa + Fb - F) <= 1e-13 * F, "weights: %.17g + %.17g vs %.17g", Fa, Fb, F);
  double err = 0;
  for (size_t k = 0; k < 3 * nv; k++) err = fmax(err, fabs(ga[k] + gb[k] - g[k]));
  CHECK(err < 1e-12, "weighted gradients add up to within %g", err);
  /* an inverted node of weight 0 under a barrier measure: left out */
  double *x = dup(m->xyz, 3 * nv);
  double *det = malloc(nn * sizeof *det);
  vm_problem_set_node_weights(p, NULL);
  CHECK(invert_some(p, x) < 0, "could not invert a node");
  vm_problem_set_measure(p, VM_MEASURE_BALANCED, &q);
  vm_problem_node_dets(p, x, det);
  int64_t ninv = 0;
  for (int64_t k = 0; k < nn; k++) {
    w[k] = det[k] > 0;
    ninv += det[k] <= 0;
  }
  CHECK(ninv > 0, "no node inverted");
  CHECK(vm_problem_eval(p, x, &e0) == VM_WARN_INVERTED, "barrier at inverted nodes");
  vm_problem_set_node_weights(p, w);
  CHECK(vm_problem_eval(p, x, &e0) == 0 && isfinite(F), "inverted nodes left out");
  vm_node_stats ns;
  vm_problem_node_stats(p, x, &ns);
  CHECK(ns.inverted == 0 && ns.min_det > 0, "stats count left-out nodes: %lld",
        (long long)ns.inverted);
  w[0] = -1;
  CHECK(vm_problem_set_node_weights(p, w) == VM_ERR_ARG, "negative weight accepted");
  free(det);
  free(x);
  free(w);
  free(w1);
  free(g);
  free(ga);
  free(gb);
  free(gall);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* det J of the trilinear hex x (8 x 3) at (u, v, w), from its derivatives. */
static double hex_det(const double *x, double u, double v, double w) {
  static const int cu[8] = {0, 1, 1, 0, 0, 1, 1, 0}, cv[8] = {0, 0, 1, 1, 0, 0, 1, 1},
                   cw[8] = {0, 0, 0, 0, 1, 1, 1, 1};
  double J[3][3] = {{0}};
  for (int a = 0; a < 8; a++) {
    double fu = cu[a] ? u : 1 - u, fv = cv[a] ? v : 1 - v, fw = cw[a] ? w : 1 - w;
    double d[3] = {(cu[a] ? 1 : -1) * fv * fw, (cv[a] ? 1 : -1) * fu * fw,
                   (cw[a] ? 1 : -1) * fu * fv};
    for (int r = 0; r < 3; r++)
      for (int l = 0; l < 3; l++) J[r][l] += x[3 * a + r] * d[l];
  }
  return J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
         J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
         J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
}

/* vm_hex_bernstein against det J itself, its gradient against finite
 * differences; the problem's Bernstein term: value, gradient against finite
 * differences, Hessian blocks against the Gauss-Newton formula, weights,
 * eps 0 as a barrier. */
static void test_bernstein(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 23);
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, 2, 2, 2, 1.0);
  mg_jitter(ctx, m, 0.3);
  /* the polynomial: det J at 27 points of the cell from the coefficients */
  double worst = 0, gerr = 0, gmax = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    double x[24], b[27], G[27 * 24];
    for (int a = 0; a < 8; a++)
      memcpy(x + 3 * a, m->xyz + 3 * (int64_t)m->conn[m->eoff[e] + a], 3 * sizeof *x);
    vm_hex_bernstein(x, b, G);
    for (int pt = 0; pt < 27; pt++) {
      double t[3] = {0.1 + 0.4 * (pt / 9), 0.1 + 0.4 * (pt / 3 % 3), 0.1 + 0.4 * (pt % 3)};
      double B[3][3];
      for (int d = 0; d < 3; d++) {
        B[d][0] = (1 - t[d]) * (1 - t[d]);
        B[d][1] = 2 * t[d] * (1 - t[d]);
        B[d][2] = t[d] * t[d];
      }
      double sum = 0;
      for (int c = 0; c < 27; c++) sum += b[c] * B[0][c / 9] * B[1][c / 3 % 3] * B[2][c % 3];
      worst = fmax(worst, fabs(sum - hex_det(x, t[0], t[1], t[2])));
    }
    for (int k = 0; k < 24; k++) {
      double xp[24], xm[24], bp[27], bm[27], h = 1e-6;
      memcpy(xp, x, sizeof xp);
      memcpy(xm, x, sizeof xm);
      xp[k] += h;
      xm[k] -= h;
      vm_hex_bernstein(xp, bp, NULL);
      vm_hex_bernstein(xm, bm, NULL);
      for (int c = 0; c < 27; c++) {
        gmax = fmax(gmax, fabs(G[24 * c + k]));
        gerr = fmax(gerr, fabs(G[24 * c + k] - (bp[c] - bm[c]) / (2 * h)));
      }
    }
  }
  CHECK(worst < 1e-12, "Bernstein coefficients miss det J by %.2e", worst);
  CHECK(gerr < 1e-8 * gmax, "Bernstein gradient off by %.2e (max %.2e)", gerr, gmax);

  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  /* the geometric rule couples every pair of a hex's vertices, so every
   * block of the Gauss-Newton part is there */
  CHECK(vm_problem_set_rule(p, VM_RULE_GEOMETRIC) == 0, "rule");
  vm_measure_params q = vm_measure_params_default();
  q.eps = 0.05;
  vm_problem_set_measure(p, VM_MEASURE_PENALTY, &q);
  int64_t nn = vm_problem_num_nodes(p), nv = m->nv;
  double *w = calloc((size_t)nn, sizeof *w), *we = malloc((size_t)m->ne * sizeof *we);
  double *eps = malloc(27 * (size_t)m->ne * sizeof *eps);
  /* the nodes left out: F is the Bernstein term alone */
  vm_problem_set_node_weights(p, w);
  for (int64_t e = 0; e < m->ne; e++) {
    we[e] = e % 3 == 2 ? 0 : 0.5 + 0.25 * (double)(e % 2);
    for (int c = 0; c < 27; c++) eps[27 * e + c] = 0.02 + 0.01 * c;
  }
  double scale = 1.7;
  CHECK(vm_problem_set_bernstein(p, we, eps, scale) == 0, "set Bernstein");
  double F = 0;
  double *g = calloc(3 * (size_t)nv, sizeof *g), *hd = calloc(9 * (size_t)nv, sizeof *hd);
  const int64_t *rp;
  const int32_t *adj;
  vm_problem_graph(p, &rp, &adj);
  double *ho = calloc(3 * (size_t)rp[nv] + 1, sizeof *ho);
  vm_eval ev = {&F, g, hd, ho};
  CHECK(vm_problem_eval(p, m->xyz, &ev) == 0, "eval");
  /* the same sums here: value, diagonal blocks, off-diagonal diagonals */
  double Fr = 0, *hdr = calloc(9 * (size_t)nv, sizeof *hdr);
  double *hor = calloc(3 * (size_t)rp[nv] + 1, sizeof *hor);
  const vm_qrule *R = vm_qrule_get(VM_HEX, VM_RULE_GEOMETRIC);
  /* the node weights of an ideal hex summed (every hex has the same) */
  double tv = vm_problem_target_volume(p) / (double)m->ne;
  for (int64_t e = 0; e < m->ne; e++) {
    if (we[e] == 0) continue;
    double x[24], b[27], G[27 * 24];
    const int32_t *cv = m->conn + m->eoff[e];
    for (int a = 0; a < 8; a++) memcpy(x + 3 * a, m->xyz + 3 * (int64_t)cv[a], 3 * sizeof *x);
    vm_hex_bernstein(x, b, G);
    for (int c = 0; c < 27; c++) {
      double ep = eps[27 * e + c], d = scale * b[c], qq = sqrt(ep * ep + d * d);
      double chi = 0.5 * (d + qq), wq = we[e] * tv / R->nnodes;
      Fr += wq / chi;
      double r2 = wq * 2 / (qq * qq * qq) * scale * scale;
      for (int a = 0; a < 8; a++)
        for (int a2 = 0; a2 < 8; a2++) {
          const double *u = G + 24 * c + 3 * a, *v = G + 24 * c + 3 * a2;
          if (a == a2) {
            for (int r = 0; r < 3; r++)
              for (int t = 0; t < 3; t++) hdr[9 * (int64_t)cv[a] + 3 * r + t] += r2 * u[r] * v[t];
          } else {
            int64_t k = find_pos(rp, adj, cv[a], cv[a2]);
            if (k >= 0 && adj[k] == cv[a2])
              for (int r = 0; r < 3; r++) hor[3 * k + r] += r2 * u[r] * v[r];
          }
        }
    }
  }
  CHECK(fabs(F - Fr) <= 1e-12 * Fr, "Bernstein term %.17g, by hand %.17g", F, Fr);
  double eh = 0, mh = 0;
  for (int64_t k = 0; k < 9 * nv; k++) {
    eh = fmax(eh, fabs(hd[k] - hdr[k]));
    mh = fmax(mh, fabs(hdr[k]));
  }
  for (int64_t k = 0; k < 3 * rp[nv]; k++) eh = fmax(eh, fabs(ho[k] - hor[k]));
  CHECK(mh > 0 && eh <= 1e-12 * mh, "Gauss-Newton blocks off by %.2e (max %.2e)", eh, mh);
  /* the gradient against finite differences of F */
  double ge = 0, gm = 0, *x = dup(m->xyz, 3 * (size_t)nv);
  for (int64_t k = 0; k < 3 * nv; k++) {
    double Fp, Fm, h = 1e-6;
    x[k] = m->xyz[k] + h;
    vm_problem_value(p, x, &Fp);
    x[k] = m->xyz[k] - h;
    vm_problem_value(p, x, &Fm);
    x[k] = m->xyz[k];
    gm = fmax(gm, fabs(g[k]));
    ge = fmax(ge, fabs(g[k] - (Fp - Fm) / (2 * h)));
  }
  CHECK(gm > 0 && ge < 1e-6 * gm, "Bernstein gradient vs finite differences: %.2e of %.2e", ge, gm);
  /* eps 0 (params, no per-coefficient eps): a barrier, outside at b <= 0 */
  q.eps = 0;
  vm_problem_set_params(p, &q);
  CHECK(vm_problem_set_bernstein(p, we, NULL, scale) == 0, "barrier");
  CHECK(vm_problem_value(p, m->xyz, &F) == 0 && isfinite(F), "barrier at a valid mesh");
  /* push vertex 0's hex inside out */
  x[0] = 1.6;
  x[1] = 1.6;
  x[2] = 1.6;
  CHECK(vm_problem_value(p, x, &F) == VM_WARN_INVERTED, "barrier at a negative coefficient");
  CHECK(vm_problem_set_bernstein(p, NULL, NULL, 1) == 0 && vm_problem_value(p, x, &F) == 0 &&
            F == 0,
        "term off: F %g", F);
  we[1] = -1;
  CHECK(vm_problem_set_bernstein(p, we, NULL, 1) == VM_ERR_ARG, "negative weight accepted");
  we[1] = 1;
  eps[27] = 0;
  CHECK(vm_problem_set_bernstein(p, we, eps, 1) == VM_ERR_ARG, "eps 0 accepted");
  CHECK(vm_problem_set_bernstein(p, we, NULL, 0) == VM_ERR_ARG, "scale 0 accepted");
  free(x);
  free(w);
  free(we);
  free(eps);
  free(g);
  free(hd);
  free(ho);
  free(hdr);
  free(hor);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

/* Bad input is refused with the problem unchanged; every allocation
 * failure is reported and leaks nothing. */
static void test_errors(vm_ctx *ctx) {
  vm_mesh *m = mg_build(ctx, VM_TET, 0, 2, 1, 1, 1.0);
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  double F0, F1;
  vm_problem_value(p, m->xyz, &F0);
  double *ref = dup(m->xyz, 3 * m->nv);
  for (int64_t v = 0; v < m->nv; v++) ref[3 * v + 2] = -ref[3 * v + 2];
  CHECK(vm_problem_set_target_reference(p, ref) == VM_ERR_ARG, "mirrored reference accepted");
  vm_problem_value(p, m->xyz, &F1);
  CHECK(F0 == F1, "failed set_target changed F");
  double g[64];
  for (int k = 0; k < 64; k++) g[k] = k == 5 ? -1 : 1;
  CHECK(vm_problem_set_metric_scalar(p, g) == VM_ERR_ARG, "negative metric accepted");
  CHECK(vm_problem_set_rule(p, (vm_rule)7) == VM_ERR_ARG, "bad rule accepted");
  CHECK(vm_problem_set_measure(p, VM_MEASURE_COUNT, NULL) == VM_ERR_ARG, "bad measure accepted");
  free(ref);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
  m = mg_build(ctx, VM_QUAD, 1, 2, 2, 1, 1.0);
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  double G[6 * 9] = {0};
  CHECK(vm_problem_set_metric_tensor(p, G) == VM_ERR_UNSUPPORTED, "surface tensor metric");
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);

  m = mg_build(ctx, VM_PRISM, 0, 2, 2, 1, 1.0);
  ref = dup(m->xyz, 3 * m->nv);
  double *ones = malloc(m->nv * sizeof *ones);
  for (int64_t v = 0; v < m->nv; v++) ones[v] = 1;
  long live = vm_ctx_alloc_live(ctx);
  int done = 0, n;
  for (n = 1; n < 200 && !done; n++) {
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_problem_create(ctx, m, &p);
    if (!st) st = vm_problem_set_rule(p, VM_RULE_GEOMETRIC);
    if (!st) st = vm_problem_set_target_reference(p, ref);
    if (!st) st = vm_problem_set_metric_scalar(p, ones);
    vm_ctx_set_alloc_fail(ctx, 0);
    CHECK(st == 0 || st == VM_ERR_NOMEM, "failure %d: status %d", n, st);
    if (!st) {
      done = 1;
      double F;
      CHECK(vm_problem_value(p, m->xyz, &F) == 0, "value after injected failures");
    }
    vm_problem_destroy(&p);
    CHECK(vm_ctx_alloc_live(ctx) == live, "failure %d leaks %ld blocks", n,
          vm_ctx_alloc_live(ctx) - live);
  }
  CHECK(done && n > 5, "allocation failure loop ended after %d", n);
  free(ones);
  free(ref);
  vm_mesh_destroy(&m);
}

/* Elements all of whose vertices are fixed: their F kept between
 * evaluations (the same bits as computed afresh, whatever changed: the
 * measure's parameters, node eps, a fixed vertex moved) and, with
 * vm_problem_set_fixed_derivatives(p, 0), their derivatives left out of
 * the rows of fixed vertices only. */
static void test_fixed_cache(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 21);
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, 4, 4, 4, 1.0);
  mg_jitter(ctx, m, 0.1);
  size_t nv = (size_t)m->nv, n3 = 3 * nv;
  /* the reference: a problem that saw no fixed vertex at its first
   * evaluation, so it keeps nothing */
  vm_problem *pr = NULL, *p = NULL;
  CHECK(vm_problem_create(ctx, m, &pr) == 0, "create");
  double Fr, F;
  CHECK(vm_problem_value(pr, m->xyz, &Fr) == 0, "value");
  /* half the block fixed: x < 2 (nodes at 0..4 before the jitter) */
  int64_t nfix = 0;
  for (size_t v = 0; v < nv; v++)
    if (m->xyz[3 * v] < 1.5) {
      m->vflag[v] = VM_VERTEX_FIXED;
      nfix++;
    }
  CHECK(nfix > 0 && nfix < (int64_t)nv, "fixed %lld of %zu", (long long)nfix, nv);
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  double *g = malloc(n3 * sizeof *g), *gr = malloc(n3 * sizeof *gr);
  double *h = malloc(3 * n3 * sizeof *h), *hr = malloc(3 * n3 * sizeof *hr);
  double *x = dup(m->xyz, n3);
  vm_measure_params q = vm_measure_params_default();
  for (int round = 0; round < 8; round++) {
    /* what changes between rounds: nothing, eps, the measure, node eps, a
     * fixed vertex moved, a free one, the rule, the targets */
    if (round == 1 || round == 2) {
      q.eps = round == 1 ? 0.3 : 0.05;
      CHECK(vm_problem_set_measure(p, VM_MEASURE_PENALTY, &q) == 0, "measure");
      CHECK(vm_problem_set_measure(pr, VM_MEASURE_PENALTY, &q) == 0, "measure");
    } else if (round == 3) {
      int64_t nn = vm_problem_num_nodes(p);
      double *eps = malloc((size_t)nn * sizeof *eps);
      for (int64_t k = 0; k < nn; k++) eps[k] = 0.01 + 0.001 * (double)(k % 7);
      CHECK(vm_problem_set_node_eps(p, eps) == 0 && vm_problem_set_node_eps(pr, eps) == 0,
            "node eps");
      free(eps);
    } else if (round == 4) {
      x[0] += 1e-3; /* vertex 0, at the corner: fixed */
      CHECK(m->vflag[0] == VM_VERTEX_FIXED, "vertex 0 fixed");
    } else if (round == 5) {
      x[3 * (nv - 1) + 1] -= 1e-3;
    } else if (round == 6) {
      CHECK(vm_problem_set_rule(p, VM_RULE_GEOMETRIC) == 0 &&
                vm_problem_set_rule(pr, VM_RULE_GEOMETRIC) == 0,
            "rule");
    } else if (round == 7) {
      CHECK(vm_problem_set_target_ideal(p, 0.9) == 0 && vm_problem_set_target_ideal(pr, 0.9) == 0,
            "targets");
    }
    int64_t nn = vm_problem_num_nodes(p);
    double *d = malloc((size_t)nn * sizeof *d), *dr = malloc((size_t)nn * sizeof *dr);
    for (int rep = 0; rep < 2; rep++) {
      CHECK(vm_problem_value(pr, x, &Fr) == 0 && vm_problem_value(p, x, &F) == 0, "value");
      CHECK(F == Fr, "round %d: kept F %.17g vs %.17g", round, F, Fr);
      vm_eval er = {&Fr, gr, hr, NULL}, e = {&F, g, h, NULL};
      CHECK(vm_problem_eval(pr, x, &er) == 0 && vm_problem_eval(p, x, &e) == 0, "eval");
      CHECK(F == Fr && same_bits(g, gr, n3) && same_bits(h, hr, 3 * n3),
            "round %d: complete derivatives differ", round);
      CHECK(vm_problem_set_fixed_derivatives(p, 0) == 0, "skip");
      CHECK(vm_problem_eval(p, x, &e) == 0, "eval");
      CHECK(F == Fr, "round %d: F without the fixed derivatives %.17g vs %.17g", round, F, Fr);
      int free_same = 1, fixed_differ = 0;
      for (size_t v = 0; v < nv; v++) {
        int same = same_bits(g + 3 * v, gr + 3 * v, 3) && same_bits(h + 9 * v, hr + 9 * v, 9);
        if (m->vflag[v] != VM_VERTEX_FIXED && !same) free_same = 0;
        if (m->vflag[v] == VM_VERTEX_FIXED && !same) fixed_differ = 1;
      }
      CHECK(free_same, "round %d: a free vertex's row changed", round);
      CHECK(fixed_differ, "round %d: the fixed elements' derivatives were computed", round);
      CHECK(vm_problem_set_fixed_derivatives(p, 1) == 0, "complete");
      /* the nodes' determinants and statistics, kept the same way */
      CHECK(vm_problem_node_dets(p, x, d) == 0 && vm_problem_node_dets(pr, x, dr) == 0, "dets");
      CHECK(same_bits(d, dr, (size_t)nn), "round %d: kept node dets differ", round);
      vm_node_stats ns, nsr;
      CHECK(vm_problem_node_stats(p, x, &ns) == 0 && vm_problem_node_stats(pr, x, &nsr) == 0,
            "stats");
      CHECK(ns.inverted == nsr.inverted && ns.min_det == nsr.min_det && ns.phi_min == nsr.phi_min &&
                ns.psi_min == nsr.psi_min,
            "round %d: kept node statistics differ", round);
    }
    free(d);
    free(dr);
  }
  free(g);
  free(gr);
  free(h);
  free(hr);
  free(x);
  vm_problem_destroy(&p);
  vm_problem_destroy(&pr);
  vm_mesh_destroy(&m);
}

/* The kept node values (the second statistics pass at a point reads the
 * first's): every answer is the same bits as a new problem's, which keeps
 * nothing yet, with the same rule and targets, through a hit at the same
 * array, a hit at another array with the same contents, a moved vertex,
 * new targets and a new rule at the same positions, and a new eps. */
static void node_cache_check(vm_ctx *ctx, vm_mesh *m, vm_problem *p, const double *x, int rule,
                             double target, const char *what) {
  vm_problem *f = NULL;
  CHECK(vm_problem_create(ctx, m, &f) == 0 && vm_problem_set_rule(f, rule) == 0, "fresh");
  if (target > 0) CHECK(vm_problem_set_target_ideal(f, target) == 0, "fresh targets");
  int64_t nn = vm_problem_num_nodes(p);
  CHECK(nn == vm_problem_num_nodes(f), "%s: node counts", what);
  double *d = malloc((size_t)nn * sizeof *d), *df = malloc((size_t)nn * sizeof *df);
  vm_node_stats ns, nf;
  for (int rep = 0; rep < 2; rep++) {
    CHECK(vm_problem_node_dets(p, x, d) == 0 && vm_problem_node_dets(f, x, df) == 0, "dets");
    CHECK(same_bits(d, df, (size_t)nn), "%s (pass %d): node dets differ from a new problem's", what,
          rep);
    CHECK(vm_problem_node_stats(p, x, &ns) == 0 && vm_problem_node_stats(f, x, &nf) == 0, "stats");
    CHECK(ns.inverted == nf.inverted && ns.min_det == nf.min_det && ns.phi_min == nf.phi_min &&
              ns.psi_min == nf.psi_min,
          "%s (pass %d): node statistics differ from a new problem's", what, rep);
  }
  free(d);
  free(df);
  vm_problem_destroy(&f);
}

static void test_node_cache(vm_ctx *ctx) {
  vm_ctx_seed(ctx, 22);
  vm_mesh *m = mg_build(ctx, VM_HEX, 0, 4, 4, 4, 1.0);
  mg_jitter(ctx, m, 0.2);
  size_t n3 = 3 * (size_t)m->nv;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->xyz[3 * v + 2] < 0.5) m->vflag[v] = VM_VERTEX_FIXED;
  vm_problem *p = NULL;
  CHECK(vm_problem_create(ctx, m, &p) == 0, "create");
  double *x = dup(m->xyz, n3), *y = dup(m->xyz, n3);
  node_cache_check(ctx, m, p, x, VM_RULE_CORNER, 0, "same array");
  node_cache_check(ctx, m, p, y, VM_RULE_CORNER, 0, "another array, the same positions");
  x[3 * (m->nv - 1)] += 0.05; /* a free vertex (z = 4) */
  node_cache_check(ctx, m, p, x, VM_RULE_CORNER, 0, "a vertex moved");
  CHECK(vm_problem_set_target_ideal(p, 0.8) == 0, "targets");
  node_cache_check(ctx, m, p, x, VM_RULE_CORNER, 0.8, "new targets");
  CHECK(vm_problem_set_rule(p, VM_RULE_GEOMETRIC) == 0, "rule");
  node_cache_check(ctx, m, p, x, VM_RULE_GEOMETRIC, 0.8, "a new rule");
  vm_measure_params q = vm_measure_params_default();
  q.eps = 0.2;
  CHECK(vm_problem_set_measure(p, VM_MEASURE_PENALTY, &q) == 0, "measure");
  node_cache_check(ctx, m, p, x, VM_RULE_GEOMETRIC, 0.8, "a new eps");
  free(x);
  free(y);
  vm_problem_destroy(&p);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  test_fd(ctx);
  test_fd_special(ctx);
  test_invariance(ctx);
  test_known_values(ctx);
  test_threads(ctx);
  test_target_store(ctx);
  test_node_stats(ctx);
  test_subsets(ctx);
  test_node_weights(ctx);
  test_bernstein(ctx);
  test_fixed_cache(ctx);
  test_node_cache(ctx);
  test_errors(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("assembly");
}
