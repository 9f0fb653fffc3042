/* test/surface/test_ortho2d.c: the wall's finite-volume orthogonality
 * relief (vm_surface_ortho_relief) and its measure.
 *  - Known answers of vm_surface_edge_nonortho: a rectangle L x h split
 *    along its diagonal has acos(2 L h / (L^2 + h^2)) there (a square 0,
 *    3 x 1 53.13 degrees, 6 x 1 71.08), degenerate triangles 90.
 *  - A unit cube whose faces are 12 x 12 grids squeezed towards one side
 *    (face coordinate u -> u^2: the first columns 1/144 wide and 1/12
 *    long), so dozens of edges are beyond 70 degrees: after the relief
 *    far fewer, the largest angle no larger, every vertex still on the
 *    cube (face vertices in their face's plane, edge vertices on their
 *    edge, the 8 corners bit for bit), no triangle turned, the smallest
 *    angle not below min(20, before); the same result on a second run, bit
 *    for bit; with 0 sweeps the figures only, nothing moved.
 *  - Bad options are refused; a quad mesh is left as it is. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/check_surface.h"
#include "varmesh/ortho2d.h"
#include "varmesh/surface.h"
#include "vmtest.h"

#define N 12

static const double PI = 3.14159265358979323846;

static void known_answers(void) {
  double a[3] = {0, 0, 0}, b[3], p[3], q[3];
  const double L[4] = {1, 3, 6, 0.25};
  for (int i = 0; i < 4; i++) {
    double l = L[i], h = 1;
    /* (a, b) the diagonal from (0, 0) to (l, h); p = (l, 0) on one side,
     * q = (0, h) on the other: (a, b, p) and (b, a, q) both clockwise */
    b[0] = l, b[1] = h, b[2] = 0;
    p[0] = l, p[1] = 0, p[2] = 0;
    q[0] = 0, q[1] = h, q[2] = 0;
    double want = acos(2 * l * h / (l * l + h * h)) * 180 / PI;
    double got = vm_surface_edge_nonortho(a, b, p, q);
    CHECK(fabs(got - want) < 1e-5, "rectangle %g x 1: %.12f degrees, expected %.12f", l, got, want);
  }
  /* a fold: the same rectangle bent by 90 degrees along the diagonal
   * keeps the angle measured with the mean normal finite */
  double flat[3] = {1, 0, 0}, up[3] = {0, 0, 1};
  b[0] = 0, b[1] = 1, b[2] = 0;
  double got = vm_surface_edge_nonortho(a, b, flat, up);
  CHECK(got >= 0 && got <= 90, "bent pair: %g", got);
  /* degenerate: p on the edge's line */
  double on[3] = {0, 2, 0};
  CHECK(vm_surface_edge_nonortho(a, b, on, flat) == 90, "degenerate triangle: 90 degrees");
}

/* The squeezed cube: vertex (i, j, k) of the 13^3 lattice on the surface,
 * coordinates (i/N)^2 along each axis (so every face is squeezed towards
 * the cube's corner at the origin in both its directions). */
static vm_mesh *squeezed_cube(vm_ctx *ctx) {
  static int32_t vid[(N + 1) * (N + 1) * (N + 1)];
  vm_mesh *m = chk_grid_cube(ctx, N, 2, vid);
  CHECK(m != NULL, "mesh");
  return m;
}

/* How many of p's coordinates are 0 or 1 (within tol). */
static int on_planes(const double *p, double tol) {
  int n = 0;
  for (int r = 0; r < 3; r++) n += fabs(p[r]) <= tol || fabs(p[r] - 1) <= tol;
  return n;
}

static void tri_n(const vm_mesh *m, const double *x, int64_t e, double n[3]) {
  const int32_t *c = m->conn + m->eoff[e];
  const double *a = x + 3 * (int64_t)c[0], *b = x + 3 * (int64_t)c[1], *d = x + 3 * (int64_t)c[2];
  double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
         w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  n[0] = u[1] * w[2] - u[2] * w[1];
  n[1] = u[2] * w[0] - u[0] * w[2];
  n[2] = u[0] * w[1] - u[1] * w[0];
}

static void test_cube(vm_ctx *ctx) {
  vm_mesh *m = squeezed_cube(ctx);
  if (!m) return;
  int64_t nv = m->nv;
  double *x0 = malloc(3 * (size_t)nv * sizeof *x0);
  memcpy(x0, m->xyz, 3 * (size_t)nv * sizeof *x0);
  double amin0 = vm_surface_min_angle(m);

  /* 0 sweeps: the figures, nothing moved */
  vm_ortho2d_opts o = vm_ortho2d_opts_default();
  o.sweeps = 0;
  vm_ortho2d_result r0;
  CHECK(vm_surface_ortho_relief(m, NULL, &o, &r0) == 0, "0 sweeps: %s", vm_ctx_error(ctx));
  CHECK(!memcmp(m->xyz, x0, 3 * (size_t)nv * sizeof *x0) && r0.moved == 0,
        "0 sweeps: nothing moves");
  CHECK(r0.over70_before == r0.over70_after && r0.max_before == r0.max_after,
        "0 sweeps: before = after");
  CHECK(r0.edges == 3 * m->ne / 2, "interior edges %lld of %lld triangles", (long long)r0.edges,
        (long long)m->ne);
  fprintf(
      stderr, "squeezed cube: %lld edges, %lld beyond 70 degrees, %lld beyond 60, largest %.1f\n",
      (long long)r0.edges, (long long)r0.over70_before, (long long)r0.over60_before, r0.max_before);
  CHECK(r0.over70_before >= 50, "the squeezed cube has %lld edges beyond 70 degrees",
        (long long)r0.over70_before);

  vm_ortho2d_result r;
  CHECK(vm_surface_ortho_relief(m, NULL, NULL, &r) == 0, "relief: %s", vm_ctx_error(ctx));
  fprintf(stderr,
          "relief: beyond 70 %lld -> %lld, beyond 60 %lld -> %lld, largest %.1f -> %.1f; "
          "%lld steps in %d sweeps, %lld vertices moved (at most %.4f)\n",
          (long long)r.over70_before, (long long)r.over70_after, (long long)r.over60_before,
          (long long)r.over60_after, r.max_before, r.max_after, (long long)r.moves, r.sweeps,
          (long long)r.moved, r.max_shift);
  CHECK(r.over70_before == r0.over70_before, "the same figures before");
  CHECK(r.over70_after * 4 <= r.over70_before, "edges beyond 70 degrees %lld -> %lld",
        (long long)r.over70_before, (long long)r.over70_after);
  CHECK(r.max_after <= r.max_before, "largest angle %.2f -> %.2f", r.max_before, r.max_after);
  /* every vertex on the cube, on its own face, edge or corner */
  int64_t off = 0, corner_moved = 0, edge_off = 0;
  for (int64_t v = 0; v < nv; v++) {
    const double *p = m->xyz + 3 * v, *q = x0 + 3 * v;
    int k0 = on_planes(q, 0), k1 = on_planes(p, 1e-12);
    off += k1 < 1;
    if (k0 == 3) corner_moved += memcmp(p, q, 3 * sizeof *p) != 0;
    if (k0 == 2) edge_off += k1 < 2;
    for (int c = 0; c < 3; c++)
      if (fabs(q[c]) == 0 || q[c] == 1) off += fabs(p[c] - q[c]) > 1e-12;
  }
  CHECK(off == 0, "%lld vertices off their face", (long long)off);
  CHECK(corner_moved == 0, "%lld corners moved", (long long)corner_moved);
  CHECK(edge_off == 0, "%lld edge vertices off their edge", (long long)edge_off);
  int64_t turned = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    double a[3], b[3];
    tri_n(m, m->xyz, e, a);
    tri_n(m, x0, e, b);
    turned += a[0] * b[0] + a[1] * b[1] + a[2] * b[2] <= 0;
  }
  CHECK(turned == 0, "%lld triangles turned", (long long)turned);
  double amin = vm_surface_min_angle(m);
  CHECK(amin >= (amin0 < 20 ? amin0 : 20) - 1e-9, "smallest angle %.3f -> %.3f", amin0, amin);

  /* the same again, bit for bit */
  vm_mesh *m2 = squeezed_cube(ctx);
  vm_ortho2d_result r2;
  CHECK(m2 && vm_surface_ortho_relief(m2, NULL, NULL, &r2) == 0, "second run");
  CHECK(m2 && !memcmp(m2->xyz, m->xyz, 3 * (size_t)nv * sizeof *x0) && r2.moves == r.moves,
        "a second run gives the same surface, bit for bit");
  vm_mesh_destroy(&m2);

  /* bad options */
  o = vm_ortho2d_opts_default();
  o.relief_deg = 95;
  CHECK(vm_surface_ortho_relief(m, NULL, &o, NULL) == VM_ERR_ARG, "relief angle 95 refused");
  o = vm_ortho2d_opts_default();
  o.sweeps = -1;
  CHECK(vm_surface_ortho_relief(m, NULL, &o, NULL) == VM_ERR_ARG, "negative sweeps refused");
  free(x0);
  vm_mesh_destroy(&m);
}

static void test_quads(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  CHECK(vm_mesh_create(ctx, &m) == 0, "mesh");
  if (!m) return;
  vm_mesh_set_vertices(m, 4);
  const double p[12] = {0, 0, 0, 5, 0, 0, 5, 1, 0, 0, 1, 0};
  memcpy(m->xyz, p, sizeof p);
  int32_t q[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_QUAD, q);
  vm_ortho2d_result r;
  CHECK(vm_surface_ortho_relief(m, NULL, NULL, &r) == 0 && r.edges == 0 && r.moved == 0,
        "a quad mesh is left as it is");
  CHECK(!memcmp(m->xyz, p, sizeof p), "its vertices unchanged");
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  CHECK(vm_ctx_create(&ctx) == 0, "context");
  known_answers();
  test_cube(ctx);
  test_quads(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("ortho2d");
}
