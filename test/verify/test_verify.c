/* test/verify/test_verify.c: the exact verification of varmesh/verify.h:
 * valid rotated and jittered meshes pass, a single inverted corner tet and
 * a flipped tet are caught, near-degenerate orientations are decided exactly
 * where double arithmetic is wrong (checked against 128-bit integer
 * determinants), the geometric rule's compound nodes agree with an exact
 * count, and crossing prism tops or a top through the wall are caught. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "varmesh/ctx.h"
#include "varmesh/rotcube.h"
#include "varmesh/mesh.h"
#include "varmesh/quadrature.h"
#include "varmesh/verify.h"
#include "vmtest.h"

__extension__ typedef __int128 i128;

static int sign128(i128 x) { return (x > 0) - (x < 0); }

/* det[b-a, c-a, d-a] exactly, integer coordinates below 2^41 in size */
static i128 det_int(const int64_t a[3], const int64_t b[3], const int64_t c[3],
                    const int64_t d[3]) {
  i128 u[3], v[3], w[3];
  for (int k = 0; k < 3; k++) {
    u[k] = (i128)b[k] - a[k];
    v[k] = (i128)c[k] - a[k];
    w[k] = (i128)d[k] - a[k];
  }
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* The same in doubles, as a solver computes det E: the naive expansion. */
static double det_naive(const double a[3], const double b[3], const double c[3],
                        const double d[3]) {
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; k++) {
    u[k] = b[k] - a[k];
    v[k] = c[k] - a[k];
    w[k] = d[k] - a[k];
  }
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static int sgn(double x) { return (x > 0) - (x < 0); }

static void orient(const vm_mesh *m, int rule, int64_t *bn, int64_t *be, int64_t *first) {
  int st = vm_verify_orientation(m, rule, bn, be, first);
  CHECK(st == VM_OK, "vm_verify_orientation: %d %s", st, vm_ctx_error(m->ctx));
}

/* a mesh with one tet on the given points */
static vm_mesh *one_tet(vm_ctx *ctx, double p[4][3]) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, p[i][0], p[i][1], p[i][2], NULL);
  static const int32_t t[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_TET, t);
  return m;
}

/* Rotate the whole mesh about a skew axis and jitter every vertex by up to
 * `jit` times the cell size; the result is valid. */
static void rotate_jitter(vm_ctx *ctx, vm_mesh *m, double jit, double h) {
  double ax[3] = {1 / sqrt(3.0), 1 / sqrt(3.0), 1 / sqrt(3.0)}, a = 0.7;
  double c = cos(a), s = sin(a);
  for (int64_t v = 0; v < m->nv; v++) {
    double *x = m->xyz + 3 * v, y[3];
    double d = ax[0] * x[0] + ax[1] * x[1] + ax[2] * x[2];
    double cr[3] = {ax[1] * x[2] - ax[2] * x[1], ax[2] * x[0] - ax[0] * x[2],
                    ax[0] * x[1] - ax[1] * x[0]};
    for (int k = 0; k < 3; k++) y[k] = x[k] * c + cr[k] * s + ax[k] * d * (1 - c);
    for (int k = 0; k < 3; k++) x[k] = y[k] + jit * h * (2 * vm_ctx_rand_unit(ctx) - 1);
  }
}

static void test_valid_meshes(vm_ctx *ctx) {
  for (int cells = 0; cells < 3; cells++) {
    vm_rotcube_opts o = vm_rotcube_opts_default();
    o.n = 4;
    o.cells = cells;
    vm_mesh *m = NULL;
    CHECK(vm_gen_rotated_cube(ctx, &o, &m, NULL) == VM_OK, "generate");
    if (!m) continue;
    rotate_jitter(ctx, m, 0.1, 1.0 / o.n);
    int64_t bn = -1, be = -1, first = -2;
    orient(m, VM_RULE_CORNER, &bn, &be, &first);
    CHECK(bn == 0 && be == 0 && first == -1, "cells %d corner: %lld bad nodes in %lld elements",
          cells, (long long)bn, (long long)be);
    orient(m, VM_RULE_GEOMETRIC, &bn, &be, &first);
    CHECK(bn == 0 && be == 0 && first == -1, "cells %d geometric: %lld bad nodes in %lld elements",
          cells, (long long)bn, (long long)be);
    int64_t ip = -1, wc = -1, fp[2] = {-2, -2};
    CHECK(vm_verify_prism_layer(m, &ip, &wc, fp) == VM_OK, "prism layer");
    CHECK(ip == 0 && wc == 0 && fp[0] == -1, "cells %d: %lld intersecting, %lld crossings", cells,
          (long long)ip, (long long)wc);
    vm_mesh_destroy(&m);
  }
}

static void test_inverted(vm_ctx *ctx) {
  /* 2x2x2 hexes; the cube corner (-1/2,-1/2,-1/2) belongs to one hex only:
   * pushed inside past the plane of its 3 neighbours, it inverts exactly
   * that hex's corner tet at the vertex */
  vm_rotcube_opts o = vm_rotcube_opts_default();
  o.n = 2;
  vm_mesh *m = NULL;
  CHECK(vm_gen_rotated_cube(ctx, &o, &m, NULL) == VM_OK, "generate");
  int64_t corner = -1, owner = -1;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->xyz[3 * v] == -0.5 && m->xyz[3 * v + 1] == -0.5 && m->xyz[3 * v + 2] == -0.5) corner = v;
  for (int64_t e = 0; e < m->ne; e++)
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++)
      if (m->conn[k] == corner) owner = e;
  CHECK(corner >= 0 && owner >= 0, "corner vertex %lld in hex %lld", (long long)corner,
        (long long)owner);
  for (int k = 0; k < 3; k++) m->xyz[3 * corner + k] = -0.3;
  int64_t bn, be, first;
  orient(m, VM_RULE_CORNER, &bn, &be, &first);
  CHECK(bn == 1 && be == 1 && first == owner, "inverted corner: %lld nodes, %lld elems, first %lld",
        (long long)bn, (long long)be, (long long)first);
  orient(m, VM_RULE_GEOMETRIC, &bn, &be, &first);
  CHECK(bn >= 1 && be == 1 && first == owner, "geometric: %lld nodes, %lld elems, first %lld",
        (long long)bn, (long long)be, (long long)first);
  vm_mesh_destroy(&m);

  /* tets: swap two vertices of one tet */
  o.cells = VM_GEN_TETS;
  CHECK(vm_gen_rotated_cube(ctx, &o, &m, NULL) == VM_OK, "generate tets");
  int32_t *c = m->conn + m->eoff[17];
  int32_t t = c[1];
  c[1] = c[2];
  c[2] = t;
  orient(m, VM_RULE_CORNER, &bn, &be, &first);
  CHECK(bn == 1 && be == 1 && first == 17, "flipped tet: %lld nodes, %lld elems, first %lld",
        (long long)bn, (long long)be, (long long)first);
  vm_mesh_destroy(&m);

  /* 2D: a quad with a reflex corner (dart) has one bad corner triangle */
  vm_mesh_create(ctx, &m);
  m->dim = 2;
  double q[4][2] = {{0, 0}, {1, 0}, {0.2, 0.2}, {0, 1}};
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, q[i][0], q[i][1], 0, NULL);
  static const int32_t quad[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_QUAD, quad);
  orient(m, VM_RULE_CORNER, &bn, &be, &first);
  CHECK(bn == 1 && be == 1 && first == 0, "dart quad: %lld nodes", (long long)bn);
  vm_mesh_destroy(&m);
}

/* Tiny scale: a unit tet scaled by 2^-370 has det ~ 1e-335, which
 * underflows to 0 in double; the exact orientation is still positive. */
static void test_tiny(vm_ctx *ctx) {
  double s = ldexp(1.0, -370);
  double p[4][3] = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}};
  CHECK(det_naive(p[0], p[1], p[2], p[3]) == 0, "naive det should underflow to 0");
  vm_mesh *m = one_tet(ctx, p);
  int64_t bn, be, first;
  orient(m, VM_RULE_CORNER, &bn, &be, &first);
  CHECK(bn == 0, "tiny positive tet judged bad");
  vm_mesh_destroy(&m);
  double r[4][3] = {{0, 0, 0}, {0, s, 0}, {s, 0, 0}, {0, 0, s}};
  m = one_tet(ctx, r);
  orient(m, VM_RULE_CORNER, &bn, &be, &first);
  CHECK(bn == 1, "tiny inverted tet not caught");
  vm_mesh_destroy(&m);
}

static uint64_t lcg(uint64_t *s) {
  *s = *s * 6364136223846793005ull + 1442695040888963407ull;
  return *s >> 33;
}

/* Almost coplanar points with integer coordinates near 2^40: the exact
 * determinant (128-bit integers) is small, the naive one is ruled by
 * rounding. Find cases where the naive sign is wrong, and check that the
 * verification always agrees with the exact sign. */
static void test_near_coplanar(vm_ctx *ctx) {
  uint64_t seed = 12345;
  int wrong_pos = 0, wrong_neg = 0, wrong_zero = 0, tried = 0;
  const int64_t B = (int64_t)1 << 40;
  while (tried < 200000 && (wrong_pos < 3 || wrong_neg < 3 || wrong_zero < 3)) {
    tried++;
    int64_t a[3] = {0, 0, 0}, b[3], c[3], d[3];
    for (int k = 0; k < 3; k++) b[k] = B + (int64_t)(lcg(&seed) % 64);
    for (int k = 0; k < 3; k++) c[k] = b[k] + 1 + (int64_t)(lcg(&seed) % 3);
    int mode = (int)(lcg(&seed) % 2);
    for (int k = 0; k < 3; k++) {
      /* on the plane (a, b, c) exactly, or next to it */
      d[k] = 3 * b[k] - 2 * c[k];
      if (mode) d[k] += (int64_t)(lcg(&seed) % 5) - 2;
    }
    int ex = sign128(det_int(a, b, c, d));
    double pd[4][3];
    for (int k = 0; k < 3; k++) {
      pd[0][k] = (double)a[k];
      pd[1][k] = (double)b[k];
      pd[2][k] = (double)c[k];
      pd[3][k] = (double)d[k];
    }
    int nv = sgn(det_naive(pd[0], pd[1], pd[2], pd[3]));
    if (nv == ex) continue;
    if (ex > 0 && wrong_pos >= 3) continue;
    if (ex < 0 && wrong_neg >= 3) continue;
    if (ex == 0 && wrong_zero >= 3) continue;
    if (ex > 0)
      wrong_pos++;
    else if (ex < 0)
      wrong_neg++;
    else
      wrong_zero++;
    vm_mesh *m = one_tet(ctx, pd);
    int64_t bn, be, first;
    orient(m, VM_RULE_CORNER, &bn, &be, &first);
    CHECK(bn == (ex > 0 ? 0 : 1), "exact sign %d, naive %d: verify says %lld bad", ex, nv,
          (long long)bn);
    vm_mesh_destroy(&m);
  }
  fprintf(stderr,
          "near-coplanar: %d tries; naive sign wrong: %d exact-positive, "
          "%d exact-negative, %d exact-zero cases checked\n",
          tried, wrong_pos, wrong_neg, wrong_zero);
  CHECK(wrong_pos >= 1 && wrong_neg >= 1 && wrong_zero >= 1,
        "no case where the naive determinant is wrong was found");
}

/* Compound nodes of the geometric rule on distorted hexes and prisms with
 * integer coordinates: the count of bad nodes equals the exact one. Flat
 * elements (every det exactly 0) need the exact fallback. */
static void test_compound(vm_ctx *ctx) {
  uint64_t seed = 777;
  static const int types[2] = {VM_HEX, VM_PRISM};
  int64_t total_bad = 0, total_nodes = 0;
  for (int trial = 0; trial < 400; trial++) {
    int type = types[trial % 2], nvt = vm_elem_nverts(type);
    double ref[VM_MAX_ELEM_VERTS * 3];
    vm_elem_ideal(type, ref);
    int flat = trial % 10 == 9;
    int64_t xi[VM_MAX_ELEM_VERTS][3];
    vm_mesh *m = NULL;
    vm_mesh_create(ctx, &m);
    for (int i = 0; i < nvt; i++) {
      for (int k = 0; k < 3; k++) {
        int64_t base = (int64_t)llround(ref[3 * i + k] * 1000) + ((int64_t)1 << 45);
        xi[i][k] = base + (int64_t)(lcg(&seed) % 1201) - 600;
      }
      double x = (double)xi[i][0], y = (double)xi[i][1], z = (double)xi[i][2];
      if (flat) {
        /* on the plane x = y, magnitudes 2^52 and 2^-3 mixed: the edge
         * differences are not doubles, every det is exactly 0, and interval
         * arithmetic cannot tell (the exact fallback decides) */
        x = y = (i % 2 ? ldexp(1.0, 52) + (double)(lcg(&seed) % 1000) : 0.125 * (double)(i + 1));
        z = (double)(lcg(&seed) % 1000) - 500;
      }
      vm_mesh_add_vertex(m, x, y, z, NULL);
    }
    int32_t conn[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    vm_mesh_add_element(m, type, conn);
    const vm_qrule *qr = vm_qrule_get(type, VM_RULE_GEOMETRIC);
    int64_t want = flat ? qr->nnodes : 0;
    for (int q = 0; q < qr->nnodes && !flat; q++) {
      const vm_qnode *n = &qr->nodes[q];
      i128 col[3][3];
      for (int k = 0; k < 3; k++)
        for (int r = 0; r < 3; r++)
          col[k][r] = (i128)xi[(int)n->head[k]][r] - xi[(int)n->tail[k]][r];
      i128 det = col[0][0] * (col[1][1] * col[2][2] - col[1][2] * col[2][1]) -
                 col[1][0] * (col[0][1] * col[2][2] - col[0][2] * col[2][1]) +
                 col[2][0] * (col[0][1] * col[1][2] - col[0][2] * col[1][1]);
      want += det <= 0;
    }
    int64_t bn, be, first;
    orient(m, VM_RULE_GEOMETRIC, &bn, &be, &first);
    CHECK(bn == want, "trial %d (%s%s): verify %lld bad nodes, exact %lld", trial,
          vm_elem_name(type), flat ? ", flat" : "", (long long)bn, (long long)want);
    total_bad += want;
    total_nodes += qr->nnodes;
    vm_mesh_destroy(&m);
  }
  fprintf(stderr, "compound nodes: %lld of %lld bad, all agree with the exact count\n",
          (long long)total_bad, (long long)total_nodes);
  CHECK(total_bad > 0 && total_bad < total_nodes, "the distortions should invert some nodes");
}

/* prisms on the plate z = 0: n x n squares, two triangles each, extruded
 * by `layers` layers of height 1 */
static vm_mesh *plate_layer(vm_ctx *ctx, int n, int layers) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  int per = (n + 1) * (n + 1);
  for (int l = 0; l <= layers; l++)
    for (int j = 0; j <= n; j++)
      for (int i = 0; i <= n; i++) vm_mesh_add_vertex(m, i, j, l, NULL);
  for (int l = 0; l < layers; l++)
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        int32_t v00 = l * per + j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
        int32_t p1[6] = {v00, v10, v11, v00 + per, v10 + per, v11 + per};
        int32_t p2[6] = {v00, v11, v01, v00 + per, v11 + per, v01 + per};
        vm_mesh_add_element(m, VM_PRISM, p1);
        vm_mesh_add_element(m, VM_PRISM, p2);
      }
  return m;
}

/* two separate prisms on the plate; their tops are given */
static vm_mesh *two_prisms(vm_ctx *ctx, const double top[6][3]) {
  static const double bottom[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                      {2, 0, 0}, {3, 0, 0}, {2, 1, 0}};
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 6; i++) vm_mesh_add_vertex(m, bottom[i][0], bottom[i][1], bottom[i][2], NULL);
  for (int i = 0; i < 6; i++) vm_mesh_add_vertex(m, top[i][0], top[i][1], top[i][2], NULL);
  int32_t a[6] = {0, 1, 2, 6, 7, 8}, b[6] = {3, 4, 5, 9, 10, 11};
  vm_mesh_add_element(m, VM_PRISM, a);
  vm_mesh_add_element(m, VM_PRISM, b);
  return m;
}

static void layer(const vm_mesh *m, int64_t *ip, int64_t *wc, int64_t fp[2]) {
  int st = vm_verify_prism_layer(m, ip, wc, fp);
  CHECK(st == VM_OK, "vm_verify_prism_layer: %d %s", st, vm_ctx_error(m->ctx));
}

static void test_prism_layer(vm_ctx *ctx) {
  int64_t ip, wc, fp[2];
  for (int layers = 1; layers <= 3; layers++) {
    vm_mesh *m = plate_layer(ctx, 4, layers);
    rotate_jitter(ctx, m, 0.05, 1.0);
    layer(m, &ip, &wc, fp);
    CHECK(ip == 0 && wc == 0 && fp[0] == -1, "valid %d-layer plate: %lld pairs, %lld crossings",
          layers, (long long)ip, (long long)wc);
    int64_t bn, be, first;
    orient(m, VM_RULE_CORNER, &bn, &be, &first);
    CHECK(bn == 0, "valid plate: %lld inverted", (long long)bn);
    vm_mesh_destroy(&m);
  }
  /* a fold: one top vertex of the plate pulled over its neighbours' tops, so
   * outer faces on a shared edge overlap in their plane */
  {
    vm_mesh *m = plate_layer(ctx, 3, 1);
    int per = 16;
    int64_t v = per + 1 * 4 + 1; /* top vertex above (1,1) */
    m->xyz[3 * v] = 2.6;
    m->xyz[3 * v + 1] = 2.4;
    layer(m, &ip, &wc, fp);
    CHECK(ip > 0 && wc == 0, "fold in the outer surface: %lld pairs, %lld crossings", (long long)ip,
          (long long)wc);
    vm_mesh_destroy(&m);
  }
  /* two prisms whose tilted tops cross each other */
  {
    const double top[6][3] = {{1.5, 0, 1.0}, {2.5, 0, 1.6}, {1.5, 1, 1.0},
                              {1.2, 0, 1.4}, {2.2, 0, 1.0}, {1.2, 1, 1.4}};
    vm_mesh *m = two_prisms(ctx, top);
    layer(m, &ip, &wc, fp);
    CHECK(ip == 1 && wc == 0 && fp[0] == 0 && fp[1] == 1,
          "crossing tops: %lld pairs, %lld crossings, first %lld %lld", (long long)ip,
          (long long)wc, (long long)fp[0], (long long)fp[1]);
    vm_mesh_destroy(&m);
  }
  /* the same tops lifted apart: no intersection */
  {
    const double top[6][3] = {{1.5, 0, 1.0}, {2.5, 0, 1.6}, {1.5, 1, 1.0},
                              {1.2, 0, 2.4}, {2.2, 0, 2.0}, {1.2, 1, 2.4}};
    vm_mesh *m = two_prisms(ctx, top);
    layer(m, &ip, &wc, fp);
    CHECK(ip == 0 && wc == 0 && fp[0] == -1, "separated tops: %lld pairs", (long long)ip);
    vm_mesh_destroy(&m);
  }
  /* the first prism's top dips through the second prism's wall triangle */
  {
    const double top[6][3] = {{0, 0, 1}, {5, 0.2, -1}, {0, 1, 1}, {2, 0, 1}, {3, 0, 1}, {2, 1, 1}};
    vm_mesh *m = two_prisms(ctx, top);
    layer(m, &ip, &wc, fp);
    CHECK(ip == 0 && wc == 1 && fp[0] == 0 && fp[1] == 1,
          "top through the wall: %lld pairs, %lld crossings, first %lld %lld", (long long)ip,
          (long long)wc, (long long)fp[0], (long long)fp[1]);
    vm_mesh_destroy(&m);
  }
  /* touching at one point only counts too (closed triangles) */
  {
    const double top[6][3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1},
                              {2, 0, 1}, {3, 0, 1}, {0.5, 0.25, 1}};
    vm_mesh *m = two_prisms(ctx, top);
    layer(m, &ip, &wc, fp);
    CHECK(ip == 1, "touching tops: %lld pairs", (long long)ip);
    vm_mesh_destroy(&m);
  }
}

static void test_args(vm_ctx *ctx) {
  CHECK(vm_verify_orientation(NULL, VM_RULE_CORNER, NULL, NULL, NULL) == VM_ERR_ARG, "NULL mesh");
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_verify_orientation(m, 7, NULL, NULL, NULL) == VM_ERR_ARG, "bad rule");
  int64_t bn = -1, ip = -1, wc = -1, fp[2];
  CHECK(vm_verify_orientation(m, VM_RULE_CORNER, &bn, NULL, NULL) == VM_OK && bn == 0, "empty");
  CHECK(vm_verify_prism_layer(m, &ip, &wc, fp) == VM_OK && ip == 0 && wc == 0, "empty layer");
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_seed(ctx, 42);
  test_valid_meshes(ctx);
  test_inverted(ctx);
  test_tiny(ctx);
  test_near_coplanar(ctx);
  test_compound(ctx);
  test_prism_layer(ctx);
  test_args(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld blocks", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_verify");
}
