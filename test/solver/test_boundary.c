/* test/solver/test_boundary.c: analytic surfaces and the tangent-cone
 * projectors L_k: ranks 0..3 on a box, sphere and plane projections,
 * L^2 = L, fixed vertices never written, error paths. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "varmesh/boundary.h"
#include "vmtest.h"

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void test_box(vm_ctx *ctx) {
  vm_analytic_surfaces *s = NULL;
  CHECK(vm_analytic_surfaces_create(ctx, &s) == VM_OK, "create");
  double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
  CHECK(vm_analytic_add_box(s, 5, lo, hi) == VM_OK, "box");
  double bad[3] = {1, 0, 0};
  CHECK(vm_analytic_add_box(s, 6, lo, bad) == VM_ERR_ARG, "degenerate box accepted");
  vm_surface_ops ops = vm_analytic_surfaces_ops(s);
  double q[3], n[9];
  /* inside, nearest face x = 0 */
  double p1[3] = {0.1, 1.0, 1.5};
  CHECK(ops.project(ops.user, 5, p1, q, n) == 1, "face: 1 normal");
  CHECK(q[0] == 0 && q[1] == 1.0 && q[2] == 1.5, "face point (%g %g %g)", q[0], q[1], q[2]);
  CHECK(n[0] == -1 && n[1] == 0 && n[2] == 0, "face normal");
  /* outside beyond an edge: clamped onto the edge x = 1, y = 2 */
  double p2[3] = {1.5, 2.5, 1.0};
  CHECK(ops.project(ops.user, 5, p2, q, n) == 2, "edge: 2 normals");
  CHECK(q[0] == 1 && q[1] == 2 && q[2] == 1, "edge point");
  /* beyond a corner */
  double p3[3] = {-1, -1, 4};
  CHECK(ops.project(ops.user, 5, p3, q, n) == 3, "corner: 3 normals");
  CHECK(q[0] == 0 && q[1] == 0 && q[2] == 3, "corner point");
  CHECK(ops.project(ops.user, 99, p3, q, n) < 0, "unknown surface id");
  vm_analytic_surfaces_destroy(&s);
  CHECK(s == NULL, "destroy sets NULL");
}

static void test_sphere_plane(vm_ctx *ctx) {
  vm_analytic_surfaces *s = NULL;
  vm_analytic_surfaces_create(ctx, &s);
  double c[3] = {1, 2, 3}, nz[3] = {0, 0, 2}, zero[3] = {0, 0, 0};
  CHECK(vm_analytic_add_sphere(s, 0, c, 2.0) == VM_OK, "sphere");
  CHECK(vm_analytic_add_sphere(s, 9, c, -1.0) == VM_ERR_ARG, "negative radius");
  CHECK(vm_analytic_add_plane(s, 1, c, nz) == VM_OK, "plane");
  CHECK(vm_analytic_add_plane(s, 9, c, zero) == VM_ERR_ARG, "zero normal");
  vm_surface_ops ops = vm_analytic_surfaces_ops(s);
  double p[3] = {2.3, 0.4, 5.1}, q[3], n[9];
  CHECK(ops.project(ops.user, 0, p, q, n) == 1, "sphere 1 normal");
  double d[3] = {q[0] - c[0], q[1] - c[1], q[2] - c[2]};
  CHECK_NEAR(sqrt(dot3(d, d)), 2.0, 1e-14, "on sphere");
  CHECK_NEAR(dot3(n, d), 2.0, 1e-14, "radial unit normal");
  CHECK(ops.project(ops.user, 0, c, q, n) < 0, "projection from the centre fails");
  CHECK(ops.project(ops.user, 1, p, q, n) == 1, "plane");
  CHECK(q[2] == 3 && q[0] == p[0] && q[1] == p[1], "plane point");
  /* replacing an id */
  CHECK(vm_analytic_add_sphere(s, 1, c, 1.0) == VM_OK, "replace");
  ops.project(ops.user, 1, p, q, n);
  for (int k = 0; k < 3; k++) d[k] = q[k] - c[k];
  CHECK_NEAR(sqrt(dot3(d, d)), 1.0, 1e-14, "replaced surface is the sphere");
  vm_analytic_surfaces_destroy(&s);
}

/* A surface that counts its projections. */
typedef struct {
  vm_surface_ops inner;
  int calls;
} counting;

static int count_project(void *user, int id, const double p[3], double out[3], double n[9]) {
  counting *c = user;
  c->calls++;
  return c->inner.project(c->inner.user, id, p, out, n);
}

/* A mesh of loose vertices (no elements needed by vm_bc). */
static vm_mesh *points(vm_ctx *ctx, int dim, const double *xyz, const uint8_t *flag,
                       const int32_t *surf, int nv) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  m->dim = dim;
  vm_mesh_set_vertices(m, nv);
  memcpy(m->xyz, xyz, (size_t)nv * 3 * sizeof(double));
  memcpy(m->vflag, flag, (size_t)nv);
  memcpy(m->vsurf, surf, (size_t)nv * sizeof(int32_t));
  return m;
}

static void test_bc(vm_ctx *ctx) {
  vm_analytic_surfaces *s = NULL;
  vm_analytic_surfaces_create(ctx, &s);
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, c[3] = {0, 0, 0};
  vm_analytic_add_box(s, 0, lo, hi);
  vm_analytic_add_sphere(s, 1, c, 3.0);
  vm_surface_ops ops = vm_analytic_surfaces_ops(s);
  /* free, fixed, box face, box edge, box corner, sphere */
  double xyz[] = {0.5, 0.5, 0.5, 0.2, 0.3, 0.4, 0.5, 0.5, 0.0,
                  0.0, 0.5, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0};
  uint8_t fl[] = {VM_VERTEX_FREE, VM_VERTEX_FIXED, VM_VERTEX_SLIP,
                  VM_VERTEX_SLIP, VM_VERTEX_SLIP,  VM_VERTEX_SLIP};
  int32_t sf[] = {-1, -1, 0, 0, 0, 1};
  vm_mesh *m = points(ctx, 3, xyz, fl, sf, 6);
  vm_bc *bc = NULL;
  CHECK(vm_bc_create(ctx, m, NULL, &bc) == VM_ERR_ARG, "slip without surfaces");
  CHECK(vm_bc_create(ctx, m, &ops, &bc) == VM_OK, "bc");
  CHECK(vm_bc_count(bc, VM_VERTEX_SLIP) == 4 && vm_bc_count(bc, VM_VERTEX_FIXED) == 1, "counts");
  double x[18];
  memcpy(x, xyz, sizeof x);
  CHECK(vm_bc_project(bc, x) == VM_OK, "project");
  double r6 = sqrt(dot3(x + 15, x + 15));
  CHECK_NEAR(r6, 3.0, 1e-14, "sphere vertex projected");
  CHECK(memcmp(x, xyz, 15 * sizeof(double)) == 0, "box/free/fixed points unchanged");
  int expect[6] = {3, 0, 2, 1, 0, 2};
  for (int v = 0; v < 6; v++) {
    double Q[9];
    int k = vm_bc_basis(bc, v, Q);
    CHECK(k == expect[v], "vertex %d rank %d, expected %d", v, k, expect[v]);
    for (int i = 0; i < k; i++)
      for (int j = 0; j < k; j++)
        CHECK_NEAR(dot3(Q + 3 * i, Q + 3 * j), i == j ? 1.0 : 0.0, 1e-14, "orthonormal");
  }
  /* edge vertex (x = 0, z = 1) moves along y only */
  double Q[9];
  vm_bc_basis(bc, 3, Q);
  CHECK(fabs(Q[1]) == 1 && Q[0] == 0 && Q[2] == 0, "edge direction y");
  /* L r: idempotent, fixed -> 0, tangent at the sphere */
  double r[18], r2[18];
  for (int i = 0; i < 18; i++) r[i] = sin(1.0 + i);
  vm_bc_apply(bc, r);
  memcpy(r2, r, sizeof r);
  vm_bc_apply(bc, r2);
  for (int i = 0; i < 18; i++) CHECK_NEAR(r2[i], r[i], 1e-15, "L^2 = L");
  CHECK(r[3] == 0 && r[4] == 0 && r[5] == 0, "fixed row zero");
  CHECK(r[8] == 0, "face z = 0 normal component removed");
  CHECK(r[9] == 0 && r[11] == 0, "edge keeps only y");
  CHECK(r[12] == 0 && r[13] == 0 && r[14] == 0, "corner: rank 0");
  CHECK_NEAR(dot3(r + 15, x + 15), 0.0, 1e-14, "sphere tangent");
  /* a step: fixed entries of xout are not written, slip stays on surfaces */
  double xo[18];
  for (int i = 0; i < 18; i++) xo[i] = -777.0;
  double dz[18];
  for (int i = 0; i < 18; i++) dz[i] = 0.3 * cos(2.0 + i);
  CHECK(vm_bc_step(bc, x, dz, 1.0, xo) == VM_OK, "step");
  CHECK(xo[3] == -777.0 && xo[4] == -777.0 && xo[5] == -777.0, "fixed vertex written");
  CHECK(xo[8] == 0.0, "face vertex left its face");
  CHECK(xo[9] == 0.0 && xo[11] == 1.0, "edge vertex left its edge");
  CHECK(memcmp(xo + 12, x + 12, 24) == 0, "corner moved");
  CHECK_NEAR(sqrt(dot3(xo + 15, xo + 15)), 3.0, 1e-14, "sphere vertex off the sphere");
  /* the bases at an accepted trial point come from the step's own
   * projections (no second one): the same as a fresh bc's projection
   * there (to rounding: on the sphere the normal is taken at the point
   * projected, not at the point on it), for the later and the earlier of
   * two trials */
  {
    double xa[18], xb[18];
    memcpy(xa, x, sizeof xa);
    memcpy(xb, x, sizeof xb);
    CHECK(vm_bc_step(bc, x, dz, 0.5, xa) == VM_OK && vm_bc_step(bc, x, dz, 0.25, xb) == VM_OK,
          "two trials");
    const double *at[2] = {xb, xa};
    for (int t = 0; t < 2; t++) {
      vm_bc *fresh = NULL;
      CHECK(vm_bc_create(ctx, m, &ops, &fresh) == VM_OK && vm_bc_refresh(fresh, at[t]) == VM_OK,
            "fresh bc");
      CHECK(vm_bc_refresh(bc, at[t]) == VM_OK, "refresh at trial %d", t);
      for (int v = 0; v < 6; v++) {
        double Qa[9], Qb[9];
        int ka = vm_bc_basis(bc, v, Qa), kb = vm_bc_basis(fresh, v, Qb);
        double dq = 0;
        for (int i = 0; i < 3 * ka && ka == kb; i++) dq = fmax(dq, fabs(Qa[i] - Qb[i]));
        CHECK(ka == kb && dq <= 1e-14,
              "trial %d vertex %d: basis from the step (rank %d) differs from a projection "
              "(rank %d) by %g",
              t, v, ka, kb, dq);
      }
      vm_bc_destroy(&fresh);
    }
    /* and they are taken from the step: no projection at a trial point,
     * one per slip vertex elsewhere (but the corner, which the step left
     * where it was) */
    counting cnt = {ops, 0};
    vm_surface_ops cops = {count_project, &cnt, NULL, 0};
    vm_bc *cb = NULL;
    CHECK(vm_bc_create(ctx, m, &cops, &cb) == VM_OK && vm_bc_refresh(cb, x) == VM_OK, "bc");
    CHECK(vm_bc_step(cb, x, dz, 0.5, xa) == VM_OK, "step");
    cnt.calls = 0;
    CHECK(vm_bc_refresh(cb, xa) == VM_OK && cnt.calls == 0,
          "refresh at the trial point projected %d times", cnt.calls);
    CHECK(vm_bc_refresh(cb, x) == VM_OK && cnt.calls == 3,
          "refresh elsewhere: %d projections, expected 3", cnt.calls);
    vm_bc_destroy(&cb);
  }
  vm_bc_destroy(&bc);
  CHECK(bc == NULL, "destroy sets NULL");
  vm_mesh_destroy(&m);

  /* 2D: free vertices move in xy only; a slip vertex on a circle (the
   * sphere's trace) has rank 1 */
  double xy[] = {0.5, 0.5, 0.0, 3.0, 0.0, 0.0};
  uint8_t f2[] = {VM_VERTEX_FREE, VM_VERTEX_SLIP};
  int32_t s2[] = {-1, 1};
  m = points(ctx, 2, xy, f2, s2, 2);
  CHECK(vm_bc_create(ctx, m, &ops, &bc) == VM_OK, "bc 2D");
  vm_bc_refresh(bc, xy);
  CHECK(vm_bc_dim(bc) == 2, "dim 2");
  CHECK(vm_bc_basis(bc, 0, Q) == 2, "free 2D rank 2");
  CHECK(vm_bc_basis(bc, 1, Q) == 1, "circle rank 1");
  CHECK(fabs(Q[1]) == 1, "circle tangent at (3,0) is y");
  double r3[6] = {1, 2, 3, 4, 5, 6};
  vm_bc_apply(bc, r3);
  CHECK(r3[2] == 0 && r3[3] == 0 && r3[5] == 0 && r3[4] == 5, "2D projection");
  vm_bc_destroy(&bc);
  vm_mesh_destroy(&m);
  vm_analytic_surfaces_destroy(&s);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  test_box(ctx);
  test_sphere_plane(ctx);
  test_bc(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leak: %ld live allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_boundary");
}
