/* test/prism/test_prism_medial.c: the exterior medial radius of the wall
 * vertices (vm_prism_medial_radius), the room the geometry leaves a
 * column, against known answers: two spheres (the largest ball along a
 * vertex's normal that misses the other sphere, in closed form), the hole
 * of a torus (a faceted concave ring: its radius, not 0), a cube (convex:
 * no ball ever shrinks); the same radii on one thread and two. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/prism.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

/* The radii of wall w at thickness T on `threads` threads (malloc'd copy). */
static double *radii(vm_ctx *ctx, const vm_mesh *w, double T, int threads) {
  omp_set_num_threads(threads);
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = T;
  vm_prism *p = NULL;
  CHECK(vm_prism_create(ctx, w, &o, &p) == VM_OK, "create: %s", vm_ctx_error(ctx));
  const double *r = NULL;
  CHECK(p && vm_prism_medial_radius(p, &r) == VM_OK && r, "medial radius: %s", vm_ctx_error(ctx));
  double *c = malloc((size_t)w->nv * sizeof *c);
  if (c && r) memcpy(c, r, (size_t)w->nv * sizeof *c);
  vm_prism_destroy(&p);
  omp_set_num_threads(2);
  return c;
}

static double dist(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);

  { /* two unit spheres 0.6 apart (level 4: edges about 0.08). At a vertex
     * p of sphere A with outward radial normal n the largest ball centred
     * at p + r n that misses sphere B (centre O) has |p + r n - O| = r + 1:
     * r = (|p - O|^2 - 1) / (2 (1 - n.(p - O))) */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    const double ca[3] = {-1.3, 0, 0}, cb[3] = {1.3, 0, 0};
    CHECK(vm_gen_icosphere(w, ca, 1.0, 4, 0, NULL) == 0, "sphere");
    int64_t na = w->nv;
    CHECK(vm_gen_icosphere(w, cb, 1.0, 4, 0, NULL) == 0, "sphere");
    const double T = 0.5, cap = 4 * T;
    double *r = radii(ctx, w, T, 2);
    double *r1 = radii(ctx, w, T, 1);
    CHECK(r && r1 && memcmp(r, r1, (size_t)w->nv * sizeof *r) == 0,
          "two spheres: the radii depend on the thread count");
    double worst = 0, at_axis = NAN;
    int64_t ncap = 0, nexp_cap = 0, nnear = 0;
    for (int64_t v = 0; r && v < w->nv; v++) {
      const double *p = w->xyz + 3 * v, *c = v < na ? ca : cb, *O = v < na ? cb : ca;
      double n[3], d[3];
      double len = dist(p, c);
      for (int k = 0; k < 3; k++) {
        n[k] = (p[k] - c[k]) / len;
        d[k] = p[k] - O[k];
      }
      double re = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1) /
                  (2 * (1 - (n[0] * d[0] + n[1] * d[1] + n[2] * d[2])));
      if (fabs(p[1]) < 1e-12 && fabs(p[2]) < 1e-12 && fabs(fabs(p[0]) - 0.3) < 1e-12)
        at_axis = r[v];
      CHECK(r[v] >= 0 && r[v] <= cap, "two spheres: radius %g outside [0, %g]", r[v], cap);
      if (re > 1.1 * cap) {
        nexp_cap++;
        ncap += r[v] == cap;
        continue;
      }
      if (re < cap / 1.1) {
        nnear++;
        worst = fmax(worst, fabs(r[v] - re) / re);
      }
    }
    fprintf(stderr,
            "two spheres: %lld vertices facing the other sphere, radius vs closed form within "
            "%.2e (relative); at the axis %.17g; %lld of %lld far vertices at the cap\n",
            (long long)nnear, worst, at_axis, (long long)ncap, (long long)nexp_cap);
    CHECK(nnear > 100, "two spheres: only %lld vertices facing", (long long)nnear);
    /* the facets lie inside the true sphere by at most its sagitta (1e-3) */
    CHECK(worst < 0.02, "two spheres: radius off the closed form by %g", worst);
    /* the nearest vertices see each other along the axis: exactly half the gap */
    CHECK_NEAR(at_axis, 0.3, 1e-12, "two spheres: radius at the axis");
    CHECK(ncap == nexp_cap && nexp_cap > 0, "two spheres: %lld of %lld far vertices at the cap",
          (long long)ncap, (long long)nexp_cap);
    free(r);
    free(r1);
    vm_mesh_destroy(&w);
  }

  { /* torus R = 1, a = 0.5: the hole is a concave ring of radius 0.5,
     * faceted by 64 segments (5.6 degrees each) around the axis and 32
     * around the tube. A ball at an inner equator vertex fits the hole:
     * radius 0.5, less the facets' sagittas (0.0006 around the axis, 0.0024
     * around the tube) magnified by the ball's slant, 0.49 at the least;
     * counting the incident facets as obstacles would shrink it to
     * nothing. Outer equator: convex, the ball never shrinks. */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    CHECK(vm_gen_torus(w, NULL, 1.0, 0.5, 64, 32, VM_GEN_TORUS_TRI, NULL, NULL) == 0, "torus");
    const double T = 0.7, cap = 4 * T;
    double *r = radii(ctx, w, T, 2);
    double imin = INFINITY, imax = 0;
    int64_t ninner = 0, nouter = 0, ncap = 0;
    for (int64_t v = 0; r && v < w->nv; v++) {
      const double *y = w->xyz + 3 * v;
      if (fabs(y[2]) > 1e-9) continue;
      double rho = hypot(y[0], y[1]);
      if (rho < 0.5 + 1e-9) {
        ninner++;
        imin = fmin(imin, r[v]);
        imax = fmax(imax, r[v]);
      } else if (rho > 1.5 - 1e-9) {
        nouter++;
        ncap += r[v] == cap;
      }
    }
    fprintf(stderr, "torus: %lld inner equator radii %.4f..%.4f; %lld of %lld outer at the cap\n",
            (long long)ninner, imin, imax, (long long)ncap, (long long)nouter);
    CHECK(ninner == 64 && nouter == 64, "torus: %lld inner, %lld outer equator vertices",
          (long long)ninner, (long long)nouter);
    CHECK(imin > 0.49 && imax <= 0.5 + 1e-9, "torus: hole radius %g..%g, not 0.5", imin, imax);
    CHECK(ncap == nouter, "torus: outer equator below the cap");
    free(r);
    vm_mesh_destroy(&w);
  }

  { /* a cube: convex, sharp edges and corners (normals bisect them): every
     * ball stays at the cap */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    CHECK(vm_gen_cube(w, 4) == 0, "cube");
    const double T = 0.3;
    double *r = radii(ctx, w, T, 2);
    int64_t ncap = 0;
    for (int64_t v = 0; r && v < w->nv; v++) ncap += r[v] == 4 * T;
    CHECK(ncap == w->nv, "cube: %lld of %lld vertices below the cap", (long long)(w->nv - ncap),
          (long long)w->nv);
    free(r);
    vm_mesh_destroy(&w);
  }

  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_medial");
}
