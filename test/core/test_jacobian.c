/* test/core/test_jacobian.c: certified validity (varmesh/jacobian.h)
 * against brute-force sampling of det J on fine grids, on ideal cells,
 * mirrored cells, perturbed cubes, twisted prisms and pyramids, and a
 * hexahedron whose 8 corner tets are positive while det J is negative
 * inside. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "varmesh/jacobian.h"
#include "varmesh/rotcube.h"
#include "vmtest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double rnd(uint64_t *s) { /* splitmix64 in [0, 1) */
  uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}

static double det3(const double *a, const double *b, const double *c) {
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

static const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* The columns of J of the trilinear map at (u, v, w): d[l] = dx/du_l. */
static void hex_jac(const double *x, double u, double v, double w, double d[3][3]) {
  memset(d, 0, 9 * sizeof(double));
  for (int n = 0; n < 8; n++) {
    double a = cube[n][0], b = cube[n][1], c = cube[n][2];
    double fu = a ? u : 1 - u, fv = b ? v : 1 - v, fw = c ? w : 1 - w;
    double su = a ? 1 : -1, sv = b ? 1 : -1, sw = c ? 1 : -1;
    for (int r = 0; r < 3; r++) {
      d[0][r] += su * fv * fw * x[3 * n + r];
      d[1][r] += fu * sv * fw * x[3 * n + r];
      d[2][r] += fu * fv * sw * x[3 * n + r];
    }
  }
}

/* det J of the trilinear map at (u, v, w), computed directly. */
static double hex_det(const double *x, double u, double v, double w) {
  double d[3][3];
  hex_jac(x, u, v, w, d);
  return det3(d[0], d[1], d[2]);
}

static double hex_grid_min(const double *x, int g) {
  double lo = INFINITY;
  for (int i = 0; i <= g; i++)
    for (int j = 0; j <= g; j++)
      for (int k = 0; k <= g; k++) {
        double d = hex_det(x, (double)i / g, (double)j / g, (double)k / g);
        if (d < lo) lo = d;
      }
  return lo;
}

/* det J of the prism map at barycentric (u, v) and height w. */
static double prism_det(const double *x, double u, double v, double w) {
  double xu[3], xv[3], xw[3];
  for (int r = 0; r < 3; r++) {
    xu[r] = (1 - w) * (x[3 + r] - x[r]) + w * (x[12 + r] - x[9 + r]);
    xv[r] = (1 - w) * (x[6 + r] - x[r]) + w * (x[15 + r] - x[9 + r]);
    xw[r] =
        (1 - u - v) * (x[9 + r] - x[r]) + u * (x[12 + r] - x[3 + r]) + v * (x[15 + r] - x[6 + r]);
  }
  return det3(xu, xv, xw);
}

static double prism_grid_min(const double *x, int g) {
  double lo = INFINITY;
  for (int i = 0; i <= g; i++)
    for (int j = 0; i + j <= g; j++)
      for (int k = 0; k <= g; k++) {
        double d = prism_det(x, (double)i / g, (double)j / g, (double)k / g);
        if (d < lo) lo = d;
      }
  return lo;
}

/* q(u, v) = (Q_u x Q_v) . (A - Q) of the pyramid (det J / (1-w)^2). */
static double pyramid_q(const double *x, double u, double v) {
  double Qu[3], Qv[3], R[3];
  for (int r = 0; r < 3; r++) {
    Qu[r] = (1 - v) * (x[3 + r] - x[r]) + v * (x[6 + r] - x[9 + r]);
    Qv[r] = (1 - u) * (x[9 + r] - x[r]) + u * (x[6 + r] - x[3 + r]);
    double Q = (1 - u) * (1 - v) * x[r] + u * (1 - v) * x[3 + r] + u * v * x[6 + r] +
               (1 - u) * v * x[9 + r];
    R[r] = x[12 + r] - Q;
  }
  return det3(Qu, Qv, R);
}

static double pyramid_grid_min(const double *x, int g) {
  double lo = INFINITY;
  for (int i = 0; i <= g; i++)
    for (int j = 0; j <= g; j++) {
      double d = pyramid_q(x, (double)i / g, (double)j / g);
      if (d < lo) lo = d;
    }
  return lo;
}

static void ideal_cells(void) {
  double x[24];
  memcpy(x, cube, sizeof cube);
  double b;
  CHECK(vm_jacobian_certify(VM_HEX, x, 0, &b) == VM_JAC_VALID, "unit cube");
  CHECK_NEAR(b, 1 / (3 * sqrt(3.0)), 1e-14, "unit cube bound (det 1 / diagonal^3)");
  for (int n = 0; n < 8; n++) x[3 * n] = -x[3 * n];
  CHECK(vm_jacobian_certify(VM_HEX, x, 0, &b) == VM_JAC_INVALID, "mirrored cube");
  /* flat hex: top face on the bottom one */
  memcpy(x, cube, sizeof cube);
  for (int n = 4; n < 8; n++) x[3 * n + 2] = 0;
  CHECK(vm_jacobian_certify(VM_HEX, x, 0, NULL) != VM_JAC_VALID, "flat hex is not valid");
  const double pr[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  CHECK(vm_jacobian_certify(VM_PRISM, pr, 0, NULL) == VM_JAC_VALID, "right prism");
  const double py[15] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0.7};
  CHECK(vm_jacobian_certify(VM_PYRAMID, py, 0, NULL) == VM_JAC_VALID, "pyramid");
  const double py_flip[15] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, -0.7};
  CHECK(vm_jacobian_certify(VM_PYRAMID, py_flip, 0, NULL) == VM_JAC_INVALID, "apex below");
  const double tet[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  CHECK(vm_jacobian_certify(VM_TET, tet, 0, NULL) == VM_JAC_VALID, "tet");
  const double tet_flip[12] = {0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1};
  CHECK(vm_jacobian_certify(VM_TET, tet_flip, 0, NULL) == VM_JAC_INVALID, "tet flipped");
  const double quad_ok[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const double quad_bad[12] = {0, 0, 0, 1, 0, 0, 0.2, 0.2, 0, 0, 1, 0}; /* dart, reflex 2 */
  CHECK(vm_jacobian_certify(VM_QUAD, quad_ok, 0, NULL) == VM_JAC_VALID, "square");
  CHECK(vm_jacobian_certify(VM_QUAD, quad_bad, 0, NULL) == VM_JAC_INVALID, "dart quad");
}

/* Perturbed cubes: a certified verdict never contradicts a 24^3 sample. */
static void perturbed_hexes(void) {
  uint64_t s = 12345;
  int nvalid = 0, ninvalid = 0, nund = 0, inside_only = 0;
  for (int trial = 0; trial < 3000; trial++) {
    double x[24], amp = 0.15 + 0.5 * (trial % 10) / 10.0;
    for (int n = 0; n < 8; n++)
      for (int r = 0; r < 3; r++) x[3 * n + r] = cube[n][r] + amp * (2 * rnd(&s) - 1);
    vm_jac_verdict v = vm_jacobian_certify(VM_HEX, x, 0, NULL);
    double g = hex_grid_min(x, 24);
    if (v == VM_JAC_VALID) {
      nvalid++;
      CHECK(g > 0, "trial %d: certified valid but det J = %g on the grid", trial, g);
    } else if (v == VM_JAC_INVALID) {
      ninvalid++;
    } else {
      nund++;
    }
    if (g < -1e-9)
      CHECK(v == VM_JAC_INVALID, "trial %d: det J %g on the grid, verdict %d", trial, g, v);
    /* corner dets positive, negative inside: the case the corner rule misses */
    int corners_ok = 1;
    for (int c = 0; c < 8; c++)
      if (hex_det(x, cube[c][0], cube[c][1], cube[c][2]) <= 0) corners_ok = 0;
    if (corners_ok && g < -1e-9) inside_only++;
  }
  fprintf(stderr, "perturbed hexes: %d valid, %d invalid, %d undecided; %d negative inside only\n",
          nvalid, ninvalid, nund, inside_only);
  CHECK(nvalid > 300 && ninvalid > 300, "both verdicts occur (%d, %d)", nvalid, ninvalid);
  CHECK(nund <= 30, "at most 1 %% undecided (%d)", nund);
  CHECK(inside_only > 0, "some hex is negative only inside (%d)", inside_only);
}

/* A hexahedron whose 8 corner Jacobians are positive but whose det J is
 * negative at the centre of its top face: the top face is a strongly
 * twisted quad (its corners turned by +-t about the vertical axis). */
static void twisted_hex(void) {
  for (int deg = 10; deg <= 170; deg += 20) {
    double t = deg * M_PI / 180, x[24];
    memcpy(x, cube, sizeof cube);
    for (int n = 4; n < 8; n++) {
      double px = cube[n][0] - 0.5, py = cube[n][1] - 0.5;
      x[3 * n] = 0.5 + cos(t) * px - sin(t) * py;
      x[3 * n + 1] = 0.5 + sin(t) * px + cos(t) * py;
    }
    vm_jac_verdict v = vm_jacobian_certify(VM_HEX, x, 0, NULL);
    double g = hex_grid_min(x, 40);
    CHECK((v == VM_JAC_VALID) == (g > 0), "twist %d deg: verdict %d, grid min %g", deg, v, g);
  }
}

static void prisms_and_pyramids(void) {
  uint64_t s = 777;
  int nv = 0, ni = 0, nu = 0;
  for (int trial = 0; trial < 2000; trial++) {
    double x[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
    double amp = 0.1 + 0.6 * (trial % 10) / 10.0;
    for (int k = 0; k < 18; k++) x[k] += amp * (2 * rnd(&s) - 1);
    vm_jac_verdict v = vm_jacobian_certify(VM_PRISM, x, 0, NULL);
    double g = prism_grid_min(x, 30);
    if (v == VM_JAC_VALID) {
      nv++;
      CHECK(g > 0, "prism %d: valid but %g", trial, g);
    }
    if (v == VM_JAC_INVALID) ni++;
    if (v == VM_JAC_UNDECIDED) nu++;
    if (g < -1e-9) CHECK(v == VM_JAC_INVALID, "prism %d: grid %g, verdict %d", trial, g, v);
  }
  fprintf(stderr, "perturbed prisms: %d valid, %d invalid, %d undecided\n", nv, ni, nu);
  CHECK(nv > 200 && ni > 200 && nu <= 20, "prism verdicts %d %d %d", nv, ni, nu);
  nv = ni = nu = 0;
  for (int trial = 0; trial < 2000; trial++) {
    double x[15] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0.7};
    double amp = 0.1 + 0.6 * (trial % 10) / 10.0;
    for (int k = 0; k < 15; k++) x[k] += amp * (2 * rnd(&s) - 1);
    vm_jac_verdict v = vm_jacobian_certify(VM_PYRAMID, x, 0, NULL);
    double g = pyramid_grid_min(x, 60);
    if (v == VM_JAC_VALID) {
      nv++;
      CHECK(g > 0, "pyramid %d: valid but %g", trial, g);
    }
    if (v == VM_JAC_INVALID) ni++;
    if (v == VM_JAC_UNDECIDED) nu++;
    if (g < -1e-9) CHECK(v == VM_JAC_INVALID, "pyramid %d: grid %g, verdict %d", trial, g, v);
  }
  fprintf(stderr, "perturbed pyramids: %d valid, %d invalid, %d undecided\n", nv, ni, nu);
  CHECK(nv > 200 && ni > 200 && nu <= 20, "pyramid verdicts %d %d %d", nv, ni, nu);
}

/* phi = det J / (|J|_F^2 / 3)^{3/2} of the trilinear map at (u, v, w). */
static double hex_phi(const double *x, double u, double v, double w) {
  double d[3][3], f = 0;
  hex_jac(x, u, v, w, d);
  for (int l = 0; l < 3; l++)
    for (int r = 0; r < 3; r++) f += d[l][r] * d[l][r];
  return det3(d[0], d[1], d[2]) / pow(f / 3, 1.5);
}

/* One hexahedron as a mesh, its bounds at target edge h. */
static vm_hex_bounds one_hex_bounds(vm_ctx *ctx, const double *x, double h) {
  vm_mesh *m = NULL;
  vm_hex_bounds b = {0};
  int32_t v[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  CHECK(vm_mesh_create(ctx, &m) == VM_OK, "mesh");
  for (int n = 0; n < 8; n++) vm_mesh_add_vertex(m, x[3 * n], x[3 * n + 1], x[3 * n + 2], NULL);
  vm_mesh_add_element(m, VM_HEX, v);
  CHECK(vm_mesh_hex_bounds(m, h, 0.01, 0, &b) == VM_OK, "bounds");
  vm_mesh_destroy(&m);
  return b;
}

/* phi and psi over the whole cell: exact on affine cells; on non-affine
 * ones the bracket holds the least value of a 40^3 grid's and is within
 * about 1 % of it; a parallelepiped scaled by 2 has det C = 8 at h = 1. */
static void hex_bounds(vm_ctx *ctx) {
  vm_hex_bounds b = one_hex_bounds(ctx, &cube[0][0], 1);
  CHECK(b.hexes == 1 && b.refined == 0, "one hex, not subdivided");
  CHECK(fabs(b.phi_lo - 1) < 1e-14 && fabs(b.phi_hi - 1) < 1e-14, "cube: phi [%g, %g]", b.phi_lo,
        b.phi_hi);
  CHECK(fabs(b.psi_lo - 1) < 1e-14 && fabs(b.psi_hi - 1) < 1e-14, "cube: psi [%g, %g]", b.psi_lo,
        b.psi_hi);
  /* a sheared, stretched parallelepiped: phi of the constant matrix */
  double x[24], A[3][3] = {{2, 0.6, 0.2}, {0, 2, -0.4}, {0, 0, 2}};
  for (int n = 0; n < 8; n++)
    for (int r = 0; r < 3; r++)
      x[3 * n + r] = A[r][0] * cube[n][0] + A[r][1] * cube[n][1] + A[r][2] * cube[n][2];
  double want = hex_phi(x, 0.3, 0.6, 0.1);
  b = one_hex_bounds(ctx, x, 1);
  CHECK(fabs(b.phi_lo - want) < 1e-13 && fabs(b.phi_hi - want) < 1e-13,
        "parallelepiped: phi [%g, %g], want %g", b.phi_lo, b.phi_hi, want);
  CHECK(fabs(b.psi_hi - 2 * 8.0 / 65) < 1e-13 && fabs(b.psi_lo - b.psi_hi) < 1e-13,
        "parallelepiped: psi [%g, %g], want %g", b.psi_lo, b.psi_hi, 16.0 / 65);
  /* perturbed cubes that are valid: lo <= grid min, hi attained, close */
  uint64_t s = 777;
  int tried = 0, refined = 0;
  double lo_all = INFINITY, hi_all = INFINITY;
  vm_mesh *all = NULL;
  CHECK(vm_mesh_create(ctx, &all) == VM_OK, "mesh");
  for (int trial = 0; trial < 400 && tried < 40; trial++) {
    for (int n = 0; n < 8; n++)
      for (int r = 0; r < 3; r++) x[3 * n + r] = cube[n][r] + 0.3 * (2 * rnd(&s) - 1);
    if (vm_jacobian_certify(VM_HEX, x, 0, NULL) != VM_JAC_VALID) continue;
    int32_t v[8];
    for (int n = 0; n < 8; n++) {
      v[n] = (int32_t)(8 * tried + n);
      vm_mesh_add_vertex(all, x[3 * n], x[3 * n + 1], x[3 * n + 2], NULL);
    }
    vm_mesh_add_element(all, VM_HEX, v);
    tried++;
    double g = INFINITY;
    for (int i = 0; i <= 40; i++)
      for (int j = 0; j <= 40; j++)
        for (int k = 0; k <= 40; k++) g = fmin(g, hex_phi(x, i / 40.0, j / 40.0, k / 40.0));
    b = one_hex_bounds(ctx, x, 0);
    refined += b.refined > 0;
    CHECK(b.phi_lo <= g + 1e-14 && b.phi_hi >= b.phi_lo, "trial %d: phi [%g, %g], grid %g", trial,
          b.phi_lo, b.phi_hi, g);
    CHECK(b.phi_hi - b.phi_lo <= 0.011 * fabs(b.phi_hi) + 1e-14, "trial %d: bracket [%g, %g]",
          trial, b.phi_lo, b.phi_hi);
    CHECK(g >= b.phi_lo && g - b.phi_lo <= 0.02 * fabs(g), "trial %d: grid %g beyond [%g, %g]",
          trial, g, b.phi_lo, b.phi_hi);
    CHECK(isnan(b.psi_lo) && isnan(b.psi_hi), "no target size: no psi");
    lo_all = fmin(lo_all, b.phi_lo);
    hi_all = fmin(hi_all, b.phi_hi);
  }
  CHECK(tried == 40 && refined > 10, "40 valid perturbed cubes (%d), most subdivided (%d)", tried,
        refined);
  /* the 40 as one mesh: the least value's bracket, the same with 1 and 2
   * threads (each cell is refined against the mesh's least value, so a
   * cell alone may be bracketed tighter than within the mesh) */
  vm_hex_bounds b1, b2;
  vm_ctx_set_threads(ctx, 1);
  CHECK(vm_mesh_hex_bounds(all, 0.9, 0, 0, &b1) == VM_OK, "bounds");
  vm_ctx_set_threads(ctx, 2);
  CHECK(vm_mesh_hex_bounds(all, 0.9, 0, 0, &b2) == VM_OK, "bounds");
  CHECK(b1.hexes == 40 && !memcmp(&b1, &b2, sizeof b1), "thread-independent bounds");
  CHECK(b1.phi_hi == hi_all && b1.phi_lo <= hi_all && b1.phi_lo >= lo_all - 0.011 * fabs(hi_all),
        "mesh: phi [%g, %g], cells [%g, %g]", b1.phi_lo, b1.phi_hi, lo_all, hi_all);
  CHECK(b1.psi_lo <= b1.psi_hi && b1.psi_hi - b1.psi_lo <= 0.011 * fabs(b1.psi_hi),
        "mesh: psi [%g, %g]", b1.psi_lo, b1.psi_hi);
  vm_mesh_destroy(&all);
  /* valid, with negative Bernstein coefficients (a top face turned by
   * 170 degrees): far below its corners' phi inside */
  memcpy(x, cube, sizeof cube);
  for (int n = 4; n < 8; n++) {
    double px = cube[n][0] - 0.5, py = cube[n][1] - 0.5, t = 170 * M_PI / 180;
    x[3 * n] = 0.5 + cos(t) * px - sin(t) * py;
    x[3 * n + 1] = 0.5 + sin(t) * px + cos(t) * py;
  }
  double g = INFINITY, gc = INFINITY;
  for (int i = 0; i <= 40; i++)
    for (int j = 0; j <= 40; j++)
      for (int k = 0; k <= 40; k++) g = fmin(g, hex_phi(x, i / 40.0, j / 40.0, k / 40.0));
  for (int n = 0; n < 8; n++) gc = fmin(gc, hex_phi(x, cube[n][0], cube[n][1], cube[n][2]));
  b = one_hex_bounds(ctx, x, 0);
  CHECK(b.phi_lo > 0 && b.phi_lo <= g && g - b.phi_lo <= 0.02 * g && gc > 10 * g,
        "twisted 170 deg: phi [%g, %g], grid %g, corners %g", b.phi_lo, b.phi_hi, g, gc);
  /* a cell turned over at a corner: lo -1 (no bound), hi negative */
  memcpy(x, cube, sizeof cube);
  x[18] = x[19] = x[20] = 0.1;
  CHECK(hex_grid_min(x, 40) < 0, "the hex is negative somewhere");
  b = one_hex_bounds(ctx, x, 1);
  CHECK(b.phi_lo == -1 && b.phi_hi < 0 && b.psi_lo <= b.psi_hi && b.psi_hi < 0,
        "turned over: phi [%g, %g], psi [%g, %g]", b.phi_lo, b.phi_hi, b.psi_lo, b.psi_hi);
}

/* The mesh-level counts agree with per-element verdicts and do not depend
 * on the thread count; the untangled-looking input of the rotated cube is
 * tangled. */
static void mesh_counts(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_rotcube_opts o = vm_rotcube_opts_default();
  o.n = 8;
  o.alpha = M_PI / 2;
  CHECK(vm_gen_rotated_cube(ctx, &o, &m, NULL) == VM_OK, "rotcube");
  if (!m) return;
  vm_jac_report r1, r2;
  uint8_t *ver = vm_malloc(ctx, (size_t)m->ne);
  vm_ctx_set_threads(m->ctx, 1);
  CHECK(vm_mesh_jacobian_certify(m, &r1, ver) == VM_OK, "certify");
  vm_ctx_set_threads(m->ctx, 2);
  CHECK(vm_mesh_jacobian_certify(m, &r2, NULL) == VM_OK, "certify");
  CHECK(r1.cells == m->ne && r1.invalid == r2.invalid && r1.undecided == r2.undecided &&
            r1.first_bad == r2.first_bad,
        "thread-independent counts");
  int64_t bad = 0, first = -1;
  for (int64_t e = 0; e < m->ne; e++)
    if (ver[e] != VM_JAC_VALID) {
      bad++;
      if (first < 0) first = e;
    }
  CHECK(bad == r1.invalid + r1.undecided && first == r1.first_bad, "counts match verdicts");
  CHECK(r1.invalid > 0, "the rotated cube is tangled (%lld invalid)", (long long)r1.invalid);
  vm_free(ctx, ver);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  ideal_cells();
  perturbed_hexes();
  twisted_hex();
  prisms_and_pyramids();
  mesh_counts(ctx);
  hex_bounds(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("jacobian");
}
