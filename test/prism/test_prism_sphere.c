/* test/prism/test_prism_sphere.c: the prism stage on a sphere, where the
 * exact answer is known: concentric shells at the schedule's radii, side
 * edges radial, every column at full thickness. Each phase is checked for
 * validity, and the wall must stay bit-identical. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "support/check_prism.h"
#include "varmesh/prism.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

static int64_t layer_faces_intersections(const vm_mesh *L, int64_t nw) {
  /* tops and the wall of a single layer (vertices nw.. are the top) */
  int64_t nt = L->ne;
  int32_t *tri = malloc(sizeof(int32_t) * 6 * (size_t)nt);
  int32_t *grp = malloc(sizeof(int32_t) * 2 * (size_t)nt);
  for (int64_t t = 0; t < nt; t++) {
    for (int i = 0; i < 3; i++) {
      tri[3 * t + i] = L->conn[6 * t + 3 + i];
      tri[3 * (nt + t) + i] = L->conn[6 * t + i];
    }
    grp[t] = 1;
    grp[nt + t] = 0;
  }
  (void)nw;
  int64_t n = chk_count_intersections(L->xyz, 2 * nt, tri, grp, 1e-6);
  free(tri);
  free(grp);
  return n;
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  vm_mesh *w = NULL;
  vm_mesh_create(ctx, &w);
  const double c0[3] = {0, 0, 0};
  CHECK(vm_gen_icosphere(w, c0, 1.0, 3, 0, NULL) == 0, "icosphere");
  double *w0 = malloc(sizeof(double) * 3 * (size_t)w->nv);
  memcpy(w0, w->xyz, sizeof(double) * 3 * (size_t)w->nv);

  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = 0.5;
  o.nlayers = 5;
  o.growth = 1.3;
  o.check_incremental = 1; /* every incremental intersection query checked */
  vm_prism *p = NULL;
  int st = vm_prism_create(ctx, w, &o, &p);
  CHECK(st == 0, "create: %d %s", st, vm_ctx_error(ctx));
  if (st) return vmtest_end("prism_sphere");

  st = vm_prism_thin(p);
  CHECK(st == 0, "thin: %d %s", st, vm_ctx_error(ctx));
  const vm_mesh *L = vm_prism_layer(p);
  CHECK(chk_corner_inverted(L) == 0, "thin layer inverted");
  int64_t nw = L->nv / 2;
  CHECK(nw == w->nv, "wall vertices %lld", (long long)nw);

  st = vm_prism_springback(p);
  CHECK(st == 0, "springback: %d %s", st, vm_ctx_error(ctx));
  L = vm_prism_layer(p);
  CHECK(chk_corner_inverted(L) == 0, "springback inverted");
  double dev = 0, ang = 0;
  for (int64_t v = 0; v < nw; v++) {
    const double *a = L->xyz + 3 * v, *b = L->xyz + 3 * (v + nw);
    double e[3];
    chk_sub(b, a, e);
    double l = sqrt(chk_dot(e, e));
    dev = fmax(dev, fabs(l / o.thickness - 1));
    double cs = chk_dot(e, a) / (l * sqrt(chk_dot(a, a)));
    ang = fmax(ang, acos(fmin(1, cs)) * 180 / 3.14159265358979323846);
  }
  fprintf(stderr, "springback: max |len/T - 1| = %.3g, max angle %.3g deg\n", dev, ang);
  CHECK(dev < 0.03, "springback thickness deviation %g", dev);
  CHECK(ang < 1.0, "springback columns not radial: %g deg", ang);

  st = vm_prism_cut(p);
  CHECK(st == 0, "cut: %d %s", st, vm_ctx_error(ctx));
  vm_prism_report r;
  vm_prism_get_report(p, &r);
  CHECK(r.cut_rounds == 0 && r.cut_pairs_first == 0, "sphere needs no cutting: %d rounds, %lld",
        r.cut_rounds, (long long)r.cut_pairs_first);
  CHECK(layer_faces_intersections(vm_prism_layer(p), nw) == 0, "layer self-intersects");

  st = vm_prism_restore(p);
  CHECK(st == 0, "restore: %d %s", st, vm_ctx_error(ctx));
  CHECK(chk_corner_inverted(vm_prism_layer(p)) == 0, "restore inverted");

  st = vm_prism_march(p);
  CHECK(st == 0, "march: %d %s", st, vm_ctx_error(ctx));
  vm_prism_get_report(p, &r);
  fprintf(stderr,
          "report: layers %d prisms %lld full %.3f thick %.4f..%.4f inverted %lld sj %.3f "
          "normal dev %.3f/%.3f deg growth %.3f (r %.3f h1 %.4g) time %.2f s\n",
          r.layers, (long long)r.prisms, r.full_fraction, r.thick_min, r.thick_mean,
          (long long)r.inverted, r.sj_min, r.normal_dev_max, r.normal_dev_mean, r.growth_max,
          r.growth, r.first_height, r.time_total);
  for (int k = 0; k < VM_PRISM_NPHASES; k++)
    fprintf(stderr, "  %s %.3f s\n", vm_prism_phase_name((vm_prism_phase)k), r.time[k]);
  CHECK(r.layers == 5, "layers %d", r.layers);
  CHECK(r.inverted == 0, "inverted %lld", (long long)r.inverted);
  CHECK(r.full_fraction == 1.0, "full fraction %g", r.full_fraction);
  CHECK(r.normal_dev_max < 1.0, "normal deviation %g", r.normal_dev_max);
  CHECK(fabs(r.growth_max - 1.3) < 0.05, "growth %g", r.growth_max);
  /* every column is smooth and on the schedule: the figures over all
   * columns are those over the smooth ones, the percentiles below the
   * largest, every column's ratios within the growth band */
  CHECK(r.smooth_vertices == nw && r.normal_dev_all_max == r.normal_dev_max &&
            r.normal_dev_p99 <= r.normal_dev_max && r.normal_dev_all_p99 == r.normal_dev_p99,
        "normal deviation: all %g / p99 %g, smooth %g / p99 %g", r.normal_dev_all_max,
        r.normal_dev_all_p99, r.normal_dev_max, r.normal_dev_p99);
  CHECK(r.growth_p99 <= r.growth_max && fabs(r.growth_p99 - 1.3) < 0.05 && r.growth_band_share == 1,
        "growth p99 %g, band share %g", r.growth_p99, r.growth_band_share);

  vm_mesh *res = NULL;
  st = vm_prism_result(p, &res);
  CHECK(st == 0 && res, "result: %d", st);
  if (res) {
    CHECK(vm_mesh_check(res) == 0, "result check: %s", vm_ctx_error(ctx));
    CHECK(chk_corner_inverted(res) == 0, "result inverted");
    CHECK(!memcmp(res->xyz, w0, sizeof(double) * 3 * (size_t)nw), "wall moved");
    /* concentric shells: level k at radius 1 + sum of the first k heights */
    double rad = 1, werr = 0, aerr = 0, h = r.first_height;
    for (int k = 1; k <= 5; k++) {
      rad += h;
      h *= 1.3;
      for (int64_t v = 0; v < nw; v++) {
        const double *x = res->xyz + 3 * (k * nw + v), *y = res->xyz + 3 * ((k - 1) * nw + v);
        werr = fmax(werr, fabs(sqrt(chk_dot(x, x)) - rad) / o.thickness);
        double e[3];
        chk_sub(x, y, e);
        double cs = chk_dot(e, x) / sqrt(chk_dot(e, e) * chk_dot(x, x));
        aerr = fmax(aerr, acos(fmin(1, cs)) * 180 / 3.14159265358979323846);
      }
    }
    fprintf(stderr, "shells: max radius error %.3g T, max side-edge angle %.3g deg\n", werr, aerr);
    CHECK(werr < 0.01, "shell radius error %g T", werr);
    CHECK(aerr < 1.0, "side edges not radial: %g deg", aerr);
    int64_t np = -1;
    uint8_t *wall = calloc((size_t)res->nv, 1);
    for (int64_t v = 0; v < nw; v++) wall[v] = 1;
    st = vm_prism_mesh_intersections(ctx, res, wall, &np);
    CHECK(st == 0 && np == 0, "boundary intersections %lld", (long long)np);
    free(wall);
    vm_mesh_destroy(&res);
  }
  vm_prism_destroy(&p);
  vm_mesh_destroy(&w);
  free(w0);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_sphere");
}
