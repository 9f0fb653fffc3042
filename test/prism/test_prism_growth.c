/* test/prism/test_prism_growth.c: the growth relief (vm_prism_opts.
 * growth_relief, issue 24's growth band), on vm-gen's coarse aircraft
 * (resolution 1, T = 5 %, 20 layers), run with and without it:
 * - it re-spaces some columns, and the share of columns whose ratios of
 *   successive heights lie in [r / 1.5, 1.5 r], counted here from the
 *   result's levels and equal to the report's, rises;
 * - it moves nothing but interior levels along their own column: the wall
 *   and the outer surface are bit-identical to the run without it, every
 *   moved level lies on its column's polyline before (within 1e-9 of the
 *   column's length), and every level stays above the one below it along
 *   that polyline;
 * - none of the checks it guards gets worse anywhere: cells below
 *   checkMesh's determinant limit, faces beyond 70 degrees, the largest
 *   non-orthogonality, prisms failing a 3-tet split, inverted corner tets,
 *   the largest skewness, and the least scaled Jacobian only where it
 *   stays above 0.05. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/check_prism.h"
#include "varmesh/aircraft.h"
#include "varmesh/prism.h"
#include "vmtest.h"

static vm_mesh *run(vm_ctx *ctx, const vm_mesh *w, double length, int relief, vm_prism_report *r) {
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = 0.05 * length;
  o.growth_relief = relief;
  vm_mesh *res = NULL;
  int st = vm_prism_run(ctx, w, &o, &res, r);
  CHECK(st == 0 && res, "relief %d: run %d %s", relief, st, vm_ctx_error(ctx));
  return res;
}

/* Columns of the result (levels of nw vertices, level k of column v at
 * k nw + v) whose every ratio of successive heights lies in [lo, hi]. */
static int64_t in_band(const vm_mesh *m, int64_t nw, int nl, double lo, double hi) {
  int64_t n = 0;
  for (int64_t v = 0; v < nw; v++) {
    int ok = 1;
    for (int k = 0; k + 2 <= nl; k++) {
      const double *a = m->xyz + 3 * (k * nw + v), *b = a + 3 * nw, *c = b + 3 * nw;
      double h0 = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                       (b[2] - a[2]) * (b[2] - a[2]));
      double h1 = sqrt((c[0] - b[0]) * (c[0] - b[0]) + (c[1] - b[1]) * (c[1] - b[1]) +
                       (c[2] - b[2]) * (c[2] - b[2]));
      ok &= h0 > 0 && h1 / h0 >= lo && h1 / h0 <= hi;
    }
    n += ok;
  }
  return n;
}

/* Distance from x to segment ab, and the arc length along it of the
 * nearest point (0 at a). */
static double seg_dist(const double *x, const double *a, const double *b, double *s) {
  double ab[3], ax[3];
  chk_sub(b, a, ab);
  chk_sub(x, a, ax);
  double l2 = chk_dot(ab, ab), u = l2 > 0 ? chk_dot(ax, ab) / l2 : 0;
  u = u < 0 ? 0 : u > 1 ? 1 : u;
  double d[3];
  for (int c = 0; c < 3; c++) d[c] = ax[c] - u * ab[c];
  *s = u * sqrt(l2);
  return sqrt(chk_dot(d, d));
}

int main(void) {
  vm_ctx *ctx = NULL;
  CHECK(vm_ctx_create(&ctx) == 0, "context");
  vm_aircraft_opts ao = vm_aircraft_opts_default();
  ao.resolution = 1;
  vm_mesh *w = NULL;
  CHECK(vm_gen_aircraft(ctx, &ao, &w) == 0, "aircraft: %s", vm_ctx_error(ctx));
  if (!w) return vmtest_end("prism_growth");
  vm_prism_report ra, rb;
  vm_mesh *a = run(ctx, w, ao.length, 1, &ra), *b = run(ctx, w, ao.length, 0, &rb);
  if (a && b) {
    int64_t nw = ra.wall_vertices;
    int nl = ra.layers;
    fprintf(stderr,
            "growth relief on / off: %lld columns re-spaced; band %.4f / %.4f; det < 0.001 %lld / "
            "%lld; faces > 70 deg %lld / %lld (max %.2f / %.2f); split negative %lld / %lld; "
            "min SJ %.4g / %.4g; max skewness %.3f / %.3f\n",
            (long long)ra.growth_respaced, ra.growth_band_share, rb.growth_band_share,
            (long long)ra.det_small, (long long)rb.det_small, (long long)ra.nonortho_over70,
            (long long)rb.nonortho_over70, ra.nonortho_max, rb.nonortho_max,
            (long long)ra.split_negative, (long long)rb.split_negative, ra.sj_min, rb.sj_min,
            ra.skew_max, rb.skew_max);
    CHECK(rb.growth_respaced == 0 && ra.growth_respaced > 0, "re-spaced: %lld with, %lld without",
          (long long)ra.growth_respaced, (long long)rb.growth_respaced);
    CHECK(a->nv == b->nv && a->nv == (int64_t)(nl + 1) * nw && rb.layers == nl,
          "%lld / %lld vertices", (long long)a->nv, (long long)b->nv);
    if (a->nv == b->nv && a->nv == (int64_t)(nl + 1) * nw) {
      double lo = ra.growth / 1.5, hi = ra.growth * 1.5;
      int64_t ia = in_band(a, nw, nl, lo, hi), ib = in_band(b, nw, nl, lo, hi);
      CHECK(ia == llround(ra.growth_band_share * (double)nw) &&
                ib == llround(rb.growth_band_share * (double)nw),
            "in band here %lld / %lld, reported %.6f / %.6f of %lld", (long long)ia, (long long)ib,
            ra.growth_band_share, rb.growth_band_share, (long long)nw);
      CHECK(ia > ib, "columns in the band: %lld with the relief, %lld without", (long long)ia,
            (long long)ib);
      /* the wall and the outer surface untouched */
      CHECK(
          !memcmp(a->xyz, b->xyz, sizeof(double) * 3 * (size_t)nw) &&
              !memcmp(a->xyz + 3 * nl * nw, b->xyz + 3 * nl * nw, sizeof(double) * 3 * (size_t)nw),
          "the wall or the outer surface moved");
      /* every level on its column's course before, in order along it */
      int64_t moved = 0, off = 0, order = 0;
      double worst = 0;
      for (int64_t v = 0; v < nw; v++) {
        double len = 0, prev = -1;
        for (int k = 0; k < nl; k++) {
          const double *p0 = b->xyz + 3 * (k * nw + v);
          double d[3];
          chk_sub(p0 + 3 * nw, p0, d);
          len += sqrt(chk_dot(d, d));
        }
        int col = 0;
        for (int k = 1; k < nl; k++) {
          const double *x = a->xyz + 3 * (k * nw + v);
          col |= memcmp(x, b->xyz + 3 * (k * nw + v), 3 * sizeof *x) != 0;
          double best = INFINITY, arc = 0, at = 0;
          for (int j = 0; j < nl; j++) {
            const double *p0 = b->xyz + 3 * (j * nw + v), *p1 = p0 + 3 * nw;
            double s, dd = seg_dist(x, p0, p1, &s), e[3];
            if (dd < best) {
              best = dd;
              at = arc + s;
            }
            chk_sub(p1, p0, e);
            arc += sqrt(chk_dot(e, e));
          }
          worst = best / len > worst ? best / len : worst;
          off += best > 1e-9 * len;
          order += !(at > prev);
          prev = at;
        }
        moved += col;
      }
      CHECK(moved == ra.growth_respaced, "%lld columns differ, %lld re-spaced", (long long)moved,
            (long long)ra.growth_respaced);
      CHECK(off == 0 && order == 0,
            "%lld levels off their column's course (worst %.3g of its length), %lld out of order",
            (long long)off, worst, (long long)order);
    }
    CHECK(ra.det_small <= rb.det_small, "determinants below 0.001: %lld with, %lld without",
          (long long)ra.det_small, (long long)rb.det_small);
    CHECK(ra.nonortho_over70 <= rb.nonortho_over70 && ra.nonortho_max <= rb.nonortho_max + 1e-9,
          "faces beyond 70 degrees %lld (max %.3f) with, %lld (max %.3f) without",
          (long long)ra.nonortho_over70, ra.nonortho_max, (long long)rb.nonortho_over70,
          rb.nonortho_max);
    CHECK(ra.split_negative <= rb.split_negative && ra.inverted == 0 && rb.inverted == 0,
          "split negative %lld / %lld, inverted %lld / %lld", (long long)ra.split_negative,
          (long long)rb.split_negative, (long long)ra.inverted, (long long)rb.inverted);
    CHECK(ra.sj_min >= (rb.sj_min < 0.05 ? rb.sj_min : 0.05), "min scaled Jacobian %.4g / %.4g",
          ra.sj_min, rb.sj_min);
    CHECK(chk_corner_inverted(a) == 0, "the result has inverted corner tets");
  }
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);
  vm_mesh_destroy(&w);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_growth");
}
