/* test/surface/test_curvature.c: discrete mean curvature against analytic
 * values (torus, icosphere, open cylinder, plane), sign convention, filter,
 * fields, bad input and allocation failures. Prints the accuracy table. */
#include <stdio.h>
#include <stdlib.h>

#include "varmesh/curvature.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

typedef struct {
  double rms, max;
} err_t;

static err_t rel_err(const double *H, const double *Hex, int64_t n) {
  err_t e = {0, 0};
  for (int64_t i = 0; i < n; i++) {
    double d = fabs(H[i] - Hex[i]) / fabs(Hex[i]);
    e.rms += d * d;
    if (d > e.max) e.max = d;
  }
  e.rms = sqrt(e.rms / (double)n);
  return e;
}

static err_t torus_err(vm_ctx *ctx, int nu, int kind, double jit, int smooth) {
  vm_mesh *m = NULL;
  double *Hex = malloc(sizeof *Hex * (size_t)nu * (size_t)(nu / 2));
  err_t e = {INFINITY, INFINITY};
  int st = vm_mesh_create(ctx, &m);
  if (!st) st = vm_gen_torus(m, NULL, 1.0, 0.4, nu, nu / 2, kind, &(vm_gen_jitter){jit, 7}, Hex);
  CHECK(st == 0, "torus: %d", st);
  if (st) {
    free(Hex);
    vm_mesh_destroy(&m);
    return e;
  }
  double *H = malloc(sizeof *H * (size_t)m->nv);
  st = vm_surface_mean_curvature(m, H, NULL, NULL, NULL);
  CHECK(st == 0, "curvature: %d", st);
  vm_curvature_filter f = vm_curvature_filter_default();
  f.smooth = smooth;
  CHECK(vm_curvature_filter_apply(m, &f, H) == 0, "filter");
  e = rel_err(H, Hex, m->nv);
  free(H);
  free(Hex);
  vm_mesh_destroy(&m);
  return e;
}

static err_t sphere_err(vm_ctx *ctx, int level, double jit, int smooth) {
  vm_mesh *m = NULL;
  err_t e = {INFINITY, INFINITY};
  if (vm_mesh_create(ctx, &m) ||
      vm_gen_icosphere(m, NULL, 1.0, level, 0, &(vm_gen_jitter){jit, 3})) {
    vm_mesh_destroy(&m);
    return e;
  }
  double *H = malloc(sizeof *H * (size_t)m->nv), *Hex = malloc(sizeof *H * (size_t)m->nv);
  for (int64_t i = 0; i < m->nv; i++) Hex[i] = 1.0;
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, NULL) == 0, "icosphere curvature");
  vm_curvature_filter f = vm_curvature_filter_default();
  f.smooth = smooth;
  vm_curvature_filter_apply(m, &f, H);
  e = rel_err(H, Hex, m->nv);
  free(H);
  free(Hex);
  vm_mesh_destroy(&m);
  return e;
}

/* The accuracy table: regular meshes converge at second order; jittered
 * ones (vertices moved along the surface by up to 10% or 20% of the grid
 * step) do not converge pointwise without smoothing, a known property of
 * the cotangent / dual-cell scheme on irregular meshes. */
static void accuracy_table(vm_ctx *ctx) {
  static const char *const kname[] = {"torus tri", "torus tri-alt", "torus quad"};
  printf("%-16s %6s %4s %-10s %10s %10s %6s\n", "mesh", "jitter", "pass", "size", "rms", "max",
         "order");
  for (int kind = 0; kind < 3; kind++) {
    for (int ij = 0; ij < 3; ij++) {
      double jit = 0.1 * ij;
      for (int smooth = 0; smooth <= (ij ? 2 : 0); smooth += 2) {
        err_t prev = {0, 0};
        for (int nu = 32; nu <= (ij ? 256 : 512); nu *= 2) {
          err_t e = torus_err(ctx, nu, kind, jit, smooth);
          double order = prev.rms > 0 ? log2(prev.rms / e.rms) : NAN;
          char size[32];
          snprintf(size, sizeof size, "%dx%d", nu, nu / 2);
          printf("%-16s %6.1f %4d %-10s %10.3e %10.3e %6.2f\n", kname[kind], jit, smooth, size,
                 e.rms, e.max, order);
          if (ij == 0 && kind != VM_GEN_TORUS_TRI_ALT) {
            if (nu == 128) {
              CHECK(e.rms <= 1e-3, "%s 128x64: rms %g > 1e-3", kname[kind], e.rms);
              CHECK(e.max <= 3e-3, "%s 128x64: max %g", kname[kind], e.max);
            }
            if (prev.rms > 0) CHECK(order >= 1.9, "%s %s: order %.2f", kname[kind], size, order);
          }
          if (ij == 0 && kind == VM_GEN_TORUS_TRI_ALT && prev.rms > 0)
            CHECK(order >= 0.9, "tri-alt %s: order %.2f", size, order);
          if (ij == 1 && smooth == 0)
            CHECK(e.rms <= 0.1, "jittered %s %s: rms %g", kname[kind], size, e.rms);
          prev = e;
        }
      }
    }
  }
  for (int ij = 0; ij < 3; ij++) {
    double jit = 0.1 * ij;
    err_t prev = {0, 0};
    for (int level = 2; level <= (ij ? 5 : 6); level++) {
      err_t e = sphere_err(ctx, level, jit, 0);
      double order = prev.rms > 0 ? log2(prev.rms / e.rms) : NAN;
      char size[32];
      snprintf(size, sizeof size, "level %d", level);
      printf("%-16s %6.1f %4d %-10s %10.3e %10.3e %6.2f\n", "icosphere", jit, 0, size, e.rms, e.max,
             order);
      if (ij == 0 && level == 5) {
        CHECK(e.rms <= 1e-5, "icosphere 5: rms %g > 1e-5", e.rms);
        CHECK(e.max <= 1e-5, "icosphere 5: max %g", e.max);
      }
      prev = e;
    }
  }
}

static void test_cylinder_plane_sign(vm_ctx *ctx) {
  /* open cylinder r = 0.5: H = 1/(2r) = 1 inside, boundary rows extrapolated */
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_cylinder(m, 0.5, 2.0, 64, 33, NULL) == 0, "cylinder");
  double *H = malloc(sizeof *H * (size_t)m->nv);
  vm_curvature_stats cs;
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, &cs) == 0, "cylinder H");
  double mx = 0;
  for (int64_t v = 0; v < m->nv; v++) mx = fmax(mx, fabs(H[v] - 1.0));
  CHECK(mx <= 1e-10, "cylinder: max |H - 1| = %g", mx);
  CHECK(cs.boundary == 128, "cylinder boundary vertices %lld", (long long)cs.boundary);
  CHECK(cs.degenerate == 0, "degenerate %lld", (long long)cs.degenerate);
  /* reversed orientation: the normal points in, H changes sign */
  for (int64_t e = 0; e < m->ne; e++) {
    int32_t *c = m->conn + m->eoff[e];
    int32_t s = c[1];
    c[1] = c[2];
    c[2] = s;
  }
  double *nrm = malloc(sizeof *nrm * 3 * (size_t)m->nv);
  CHECK(vm_surface_mean_curvature(m, H, nrm, NULL, NULL) == 0, "cylinder reversed");
  mx = 0;
  for (int64_t v = 0; v < m->nv; v++) mx = fmax(mx, fabs(H[v] + 1.0));
  CHECK(mx <= 1e-10, "reversed cylinder: max |H + 1| = %g", mx);
  /* normals point inward now: n . (x, y, 0) = -r */
  int64_t v = 5 * 64 + 3;
  double dot = nrm[3 * v] * m->xyz[3 * v] + nrm[3 * v + 1] * m->xyz[3 * v + 1];
  CHECK_NEAR(dot, -0.5, 1e-12, "inward normal");
  free(nrm);
  /* flatten: H = 0 */
  for (int64_t k = 0; k < m->nv; k++) m->xyz[3 * k] *= 0, m->xyz[3 * k + 1] = (double)(k % 64);
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, NULL) == 0, "plane");
  mx = 0;
  for (int64_t k = 0; k < m->nv; k++) mx = fmax(mx, fabs(H[k]));
  CHECK(mx <= 1e-12, "plane: max |H| = %g", mx);
  free(H);
  vm_mesh_destroy(&m);

  /* icosphere oriented inward: H = -1/R */
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_icosphere(m, NULL, 2.0, 4, 0, NULL) == 0, "icosphere");
  for (int64_t e = 0; e < m->ne; e++) {
    int32_t *c = m->conn + m->eoff[e];
    int32_t s = c[0];
    c[0] = c[1];
    c[1] = s;
  }
  H = malloc(sizeof *H * (size_t)m->nv);
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, &cs) == 0, "inward sphere");
  CHECK(fabs(cs.max + 0.5) < 1e-4 && fabs(cs.min + 0.5) < 1e-4, "inward sphere H in [%g, %g]",
        cs.min, cs.max);
  CHECK_NEAR(cs.mean_abs, 0.5, 1e-4, "mean |H|");
  free(H);
  vm_mesh_destroy(&m);
}

static void test_filter_fields(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_icosphere(m, NULL, 1.0, 2, 0, NULL) == 0, "icosphere");
  double H[4] = {0.05, -0.5, 3.0, -7.0};
  vm_mesh m4 = *m;
  m4.nv = 4; /* the filter without smoothing touches values only */
  vm_curvature_filter f = {0.1, 2.0, 0};
  CHECK(vm_curvature_filter_apply(&m4, &f, H) == 0, "filter");
  CHECK(H[0] == 0 && H[1] == -0.5 && H[2] == 2.0 && H[3] == -2.0, "filter: %g %g %g %g", H[0], H[1],
        H[2], H[3]);
  vm_curvature_filter bad = {-1, 0, 0};
  CHECK(vm_curvature_filter_apply(m, &bad, H) == VM_ERR_ARG, "negative threshold");
  bad.threshold = NAN;
  CHECK(vm_curvature_filter_apply(m, &bad, H) == VM_ERR_ARG, "NaN threshold");
  /* smoothing keeps a constant field and the fields land on the mesh */
  vm_curvature_filter sm = {0, 0, 3};
  vm_curvature_stats cs;
  CHECK(vm_surface_curvature(m, &sm, &cs) == 0, "curvature fields");
  vm_field *fr = vm_mesh_find_field(m, VM_FIELD_MEAN_CURVATURE, VM_FIELD_VERTEX);
  vm_field *ff = vm_mesh_find_field(m, VM_FIELD_MEAN_CURVATURE_FILTERED, VM_FIELD_VERTEX);
  CHECK(fr && ff && fr->ncomp == 1 && fr->type == VM_FIELD_F64, "fields present");
  if (fr && ff) {
    double mx = 0;
    for (int64_t v = 0; v < m->nv; v++)
      mx = fmax(mx, fabs(((double *)ff->data)[v] - ((double *)fr->data)[v]));
    CHECK(mx < 2e-3, "smoothing a near-constant field changed it by %g", mx);
  }
  /* recomputing replaces the fields */
  int nf = m->nfield;
  CHECK(vm_surface_curvature(m, NULL, NULL) == 0 && m->nfield == nf, "fields replaced");
  vm_mesh_destroy(&m);
}

static void test_bad_input(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  double H[8], nrm[24];
  vm_mesh_create(ctx, &m);
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, NULL) == VM_ERR_ARG, "empty mesh");
  CHECK(vm_surface_mean_curvature(NULL, H, NULL, NULL, NULL) == VM_ERR_ARG, "NULL mesh");
  CHECK(vm_surface_normals(m, nrm) == VM_ERR_ARG, "normals of empty mesh");
  /* one tet: no surface elements */
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, i == 1, i == 2, i == 3, NULL);
  int32_t tet[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_TET, tet);
  CHECK(vm_surface_mean_curvature(m, H, NULL, NULL, NULL) == VM_ERR_ARG, "volume mesh");
  /* zero-area triangles are skipped and counted, values stay finite */
  vm_mesh_add_vertex(m, 2, 0, 0, NULL);
  int32_t t1[3] = {0, 1, 2}, t2[3] = {0, 1, 4}, t3[3] = {1, 1, 2};
  vm_mesh_add_element(m, VM_TRI, t1);
  vm_mesh_add_element(m, VM_TRI, t2);
  vm_mesh_add_element(m, VM_TRI, t3);
  vm_curvature_stats cs;
  CHECK(vm_surface_mean_curvature(m, H, nrm, NULL, &cs) == 0, "degenerate input");
  CHECK(cs.degenerate == 2, "degenerate count %lld", (long long)cs.degenerate);
  int finite = 1;
  for (int v = 0; v < 5; v++) finite &= isfinite(H[v]) && isfinite(nrm[3 * v]);
  CHECK(finite, "finite output on degenerate input");
  vm_mesh_destroy(&m);
}

static void test_alloc_failures(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  vm_gen_icosphere(m, NULL, 1.0, 1, 0, NULL);
  int failures = 0;
  for (long n = 1; n < 200; n++) {
    long live = vm_ctx_alloc_live(ctx);
    vm_curvature_filter f = {0.1, 5, 2};
    vm_mesh *c = NULL;
    CHECK(vm_mesh_clone(m, &c) == 0, "clone");
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_surface_curvature(c, &f, NULL);
    vm_ctx_set_alloc_fail(ctx, 0);
    vm_mesh_destroy(&c);
    if (st == 0) break;
    failures++;
    CHECK(st == VM_ERR_NOMEM, "allocation %ld: status %d", n, st);
    CHECK(vm_ctx_alloc_live(ctx) == live, "allocation %ld: leak", n);
  }
  CHECK(failures >= 5, "only %d failure points", failures);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  if (vm_ctx_create(&ctx)) return 1;
  accuracy_table(ctx);
  test_cylinder_plane_sign(ctx);
  test_filter_fields(ctx);
  test_bad_input(ctx);
  test_alloc_failures(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("curvature");
}
