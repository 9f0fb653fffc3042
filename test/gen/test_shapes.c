/* test/gen/test_shapes.c: the shape generators: sizes, closed and
 * consistently oriented surfaces (every directed edge once, its reverse
 * once), vertices on the shape, appending at a centre, exact torus H,
 * bad arguments, and every allocation failure leaving the mesh as it was. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/shapes.h"
#include "vmtest.h"

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

/* Directed edges of elements [e0, ne) with no partner running the other
 * way, or running the same way twice (0 for a closed, oriented surface). */
static int64_t unpaired_edges(const vm_mesh *m, int64_t e0) {
  int64_t n = m->eoff[m->ne] - m->eoff[e0], k = 0, bad = 0;
  int64_t *key = malloc(sizeof *key * (size_t)n);
  for (int64_t e = e0; e < m->ne; e++) {
    int64_t o = m->eoff[e], nv = m->eoff[e + 1] - o;
    for (int64_t i = 0; i < nv; i++)
      key[k++] = (int64_t)m->conn[o + i] * m->nv + m->conn[o + (i + 1) % nv];
  }
  qsort(key, (size_t)n, sizeof *key, cmp_i64);
  for (int64_t i = 0; i < n; i++) {
    int64_t rev = (key[i] % m->nv) * m->nv + key[i] / m->nv;
    if ((i + 1 < n && key[i + 1] == key[i]) || !bsearch(&rev, key, (size_t)n, sizeof *key, cmp_i64))
      bad++;
  }
  free(key);
  return bad;
}

/* Largest | |x - c| - r | over vertices [v0, nv). */
static double sphere_dev(const vm_mesh *m, int64_t v0, const double c[3], double r) {
  double d = 0;
  for (int64_t v = v0; v < m->nv; v++) {
    const double *x = m->xyz + 3 * v;
    d = fmax(d, fabs(sqrt(pow(x[0] - c[0], 2) + pow(x[1] - c[1], 2) + pow(x[2] - c[2], 2)) - r));
  }
  return d;
}

static void test_sizes_and_closure(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  const double c[3] = {3, -1, 0.5};
  CHECK(vm_gen_icosphere(m, NULL, 2.0, 3, 0, &(vm_gen_jitter){0.2, 5}) == 0, "icosphere");
  CHECK(m->nv == 642 && m->ne == 1280, "icosphere level 3: %lld %lld", (long long)m->nv,
        (long long)m->ne);
  CHECK(sphere_dev(m, 0, (double[3]){0, 0, 0}, 2.0) < 1e-14, "jittered sphere off the sphere");
  int64_t nv1 = m->nv, ne1 = m->ne;
  CHECK(vm_gen_icosphere(m, c, 0.5, 2, VM_GEN_PROJECT_AT_END, NULL) == 0, "second icosphere");
  CHECK(m->nv - nv1 == 162 && m->ne - ne1 == 320, "appended icosphere sizes");
  CHECK(sphere_dev(m, nv1, c, 0.5) < 1e-14, "appended sphere not about its centre");
  int64_t nv2 = m->nv;
  double *H = malloc(sizeof *H * 24 * 12);
  CHECK(vm_gen_torus(m, c, 1.0, 0.3, 24, 12, VM_GEN_TORUS_QUAD, NULL, H) == 0, "torus");
  CHECK(m->nv - nv2 == 288, "torus vertices");
  double herr = 0;
  for (int64_t v = 0; v < 288; v++) { /* H from the position: cos v = (rho - R) / r */
    const double *x = m->xyz + 3 * (nv2 + v);
    double rho = hypot(x[0] - c[0], x[1] - c[1]), cv = (rho - 1.0) / 0.3;
    herr = fmax(herr, fabs(H[v] - (1.0 + 2 * 0.3 * cv) / (2 * 0.3 * rho)));
  }
  CHECK(herr < 1e-12, "torus H off by %g", herr);
  free(H);
  CHECK(vm_gen_cube(m, 3) == 0 && vm_gen_lens(m, 1.0, 0.5, 0.2) == 0, "cube, lens");
  /* a box whose face coordinates do not round alike: still conforming */
  int64_t nv3 = m->nv;
  CHECK(vm_gen_box(m, (double[3]){0.1, -0.7, 2.3}, (double[3]){0.4, 0.33, 2.9},
                   (int[3]){3, 4, 5}) == 0,
        "box");
  CHECK(m->nv - nv3 == 4 * 5 * 6 - 2 * 3 * 4, "box vertices %lld", (long long)(m->nv - nv3));
  CHECK(vm_mesh_check(m) == 0, "check: %s", vm_ctx_error(ctx));
  CHECK(unpaired_edges(m, 0) == 0, "closed shapes: %lld unpaired edges",
        (long long)unpaired_edges(m, 0));
  int64_t ne4 = m->ne;
  CHECK(vm_gen_cylinder(m, 0.5, 1, 16, 4, &(vm_gen_jitter){0.3, 1}) == 0, "cylinder");
  CHECK(m->ne - ne4 == 2 * 16 * 3 && unpaired_edges(m, ne4) == 2 * 16, "cylinder: two open rims");
  vm_mesh_destroy(&m);
}

/* The wing: sizes, closed and consistently oriented, outward (positive
 * enclosed volume, close to the NACA section's area 0.6851 t c^2 integrated
 * over the span: the cosine-spaced polygon's area), its trailing edge sharp
 * (one vertex per station) and its planform M6's. */
static void test_wing(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  int nc = 40, ns = 6;
  CHECK(vm_gen_wing(m, nc, ns, 0.1, 30) == 0, "wing");
  CHECK(m->nv == 2 * nc * (ns + 1) && m->ne == 4 * nc * ns + 4 * (nc - 1), "wing sizes %lld %lld",
        (long long)m->nv, (long long)m->ne);
  CHECK(vm_mesh_check(m) == 0 && unpaired_edges(m, 0) == 0, "wing: closed, oriented");
  double vol = 0, lo[3], hi[3];
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *t = m->conn + m->eoff[e];
    const double *a = m->xyz + 3 * (int64_t)t[0], *b = m->xyz + 3 * (int64_t)t[1],
                 *c = m->xyz + 3 * (int64_t)t[2];
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) /
           6;
  }
  /* the chord is linear in y: the integral of c^2 over the semispan */
  double cr = 0.806, ct = 0.455, sp = 1.196;
  double expect = 0.6851 * 0.1 * sp * (cr * cr + cr * ct + ct * ct) / 3;
  CHECK(vol > 0 && fabs(vol - expect) < 0.01 * expect, "wing volume %g, expected about %g", vol,
        expect);
  vm_mesh_bounds(m, lo, hi);
  CHECK(fabs(hi[1] - 1.196) < 1e-12 && fabs(lo[1]) < 1e-12 && fabs(lo[0]) < 1e-12 &&
            fabs(hi[0] - (1.196 * tan(30 * 3.14159265358979323846 / 180) + 0.455)) < 1e-12,
        "wing planform %g..%g x %g..%g", lo[0], hi[0], lo[1], hi[1]);
  CHECK(m->xyz[2] == 0 && m->xyz[3 * (2 * nc * ns) + 2] == 0, "sharp trailing edge");
  CHECK(vm_gen_wing(m, 3, 6, 0.1, 30) == VM_ERR_ARG && vm_gen_wing(m, 40, 6, 0, 30) == VM_ERR_ARG,
        "wing: bad arguments");
  vm_mesh_destroy(&m);
}

static void test_bad_args(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  CHECK(vm_gen_icosphere(m, NULL, 0, 2, 0, NULL) == VM_ERR_ARG, "radius 0");
  CHECK(vm_gen_icosphere(m, NULL, 1, 13, 0, NULL) == VM_ERR_ARG, "level 13");
  CHECK(vm_gen_icosphere(m, NULL, 1, 1, 8, NULL) == VM_ERR_ARG, "unknown flag");
  CHECK(vm_gen_torus(m, NULL, 1, 1, 8, 8, 0, NULL, NULL) == VM_ERR_ARG, "r = R");
  CHECK(vm_gen_torus(m, NULL, 1, 0.5, 8, 8, 3, NULL, NULL) == VM_ERR_ARG, "cells 3");
  CHECK(vm_gen_cylinder(m, 1, 1, 8, 1, NULL) == VM_ERR_ARG, "one row");
  CHECK(vm_gen_cube(m, 0) == VM_ERR_ARG, "cube n 0");
  CHECK(vm_gen_box(m, (double[3]){0, 0, 0}, (double[3]){1, 0, 1}, (int[3]){1, 1, 1}) == VM_ERR_ARG,
        "flat box");
  CHECK(vm_gen_lens(m, 1, 1, 0.1) == VM_ERR_ARG, "lens d = R");
  CHECK(m->nv == 0 && m->ne == 0, "bad arguments changed the mesh");
  vm_mesh_destroy(&m);
}

static void test_alloc_failures(vm_ctx *ctx) {
  int points = 0, clean = 1;
  for (long n = 1; n < 200; n++) {
    vm_mesh *m = NULL;
    vm_mesh_create(ctx, &m);
    vm_gen_cube(m, 1);
    int64_t nv = m->nv, ne = m->ne;
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_gen_icosphere(m, NULL, 1, 2, 0, NULL);
    if (!st) st = vm_gen_torus(m, NULL, 1, 0.4, 16, 8, 0, NULL, NULL);
    if (!st) st = vm_gen_lens(m, 1, 0.5, 0.2);
    if (!st) st = vm_gen_box(m, (double[3]){0, 0, 0}, (double[3]){1, 1, 1}, (int[3]){2, 3, 4});
    if (!st) st = vm_gen_cube(m, 2);
    vm_ctx_set_alloc_fail(ctx, 0);
    if (st == VM_OK) {
      vm_mesh_destroy(&m);
      break;
    }
    points++;
    /* the failing call rolled back: the mesh is valid and no shorter */
    if (st != VM_ERR_NOMEM || vm_mesh_check(m) || m->nv < nv || m->ne < ne || unpaired_edges(m, 0))
      clean = 0;
    vm_mesh_destroy(&m);
  }
  CHECK(points > 5 && clean, "allocation failures: %d points, clean %d", points, clean);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  test_sizes_and_closure(ctx);
  test_bad_args(ctx);
  test_wing(ctx);
  test_alloc_failures(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("shapes");
}
