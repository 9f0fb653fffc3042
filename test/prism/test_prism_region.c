/* test/prism/test_prism_region.c: a thickness per wall face
 * (vm_prism_opts.elem_thickness, issue 24 item 5) on a sphere whose
 * northern faces ask for half the thickness of the southern ones. Known
 * answers: each column's aim is the least of its faces' graded at slope
 * 0.5 along the wall's edges (computed here independently, by relaxation
 * to the fixed point), every column reaches its aim, the first layer has
 * the schedule's height in both regions (the thin region grows more
 * slowly), the layers are valid, faces all at T give the run without the
 * option bit for bit, and out-of-range thicknesses are refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/check_prism.h"
#include "varmesh/prism.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

#define T_THICK 0.2
#define T_THIN 0.1
#define NL 10

static double dist(const double *a, const double *b) {
  double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  vm_mesh *w = NULL;
  vm_mesh_create(ctx, &w);
  const double c0[3] = {0, 0, 0};
  CHECK(vm_gen_icosphere(w, c0, 1.0, 3, 0, NULL) == 0, "icosphere");
  int64_t nw = w->nv, ne = w->ne;
  double *et = malloc(sizeof *et * (size_t)ne);
  for (int64_t e = 0; e < ne; e++) {
    const int32_t *c = w->conn + w->eoff[e];
    double z = (w->xyz[3 * c[0] + 2] + w->xyz[3 * c[1] + 2] + w->xyz[3 * c[2] + 2]) / 3;
    et[e] = z > 0 ? T_THIN : T_THICK;
  }
  /* the aims, independently: the least incident face's value, then
   * relaxation a_v = min(a_v, a_u + 0.5 |x_u - x_v|) over the edges until
   * nothing changes (the fixed point is unique) */
  double *aim = malloc(sizeof *aim * (size_t)nw);
  for (int64_t v = 0; v < nw; v++) aim[v] = INFINITY;
  for (int64_t e = 0; e < ne; e++)
    for (int i = 0; i < 3; i++) {
      int32_t v = w->conn[w->eoff[e] + i];
      aim[v] = fmin(aim[v], et[e]);
    }
  for (int changed = 1; changed;) {
    changed = 0;
    for (int64_t e = 0; e < ne; e++)
      for (int i = 0; i < 3; i++) {
        int32_t a = w->conn[w->eoff[e] + i], b = w->conn[w->eoff[e] + (i + 1) % 3];
        double l = 0.5 * dist(w->xyz + 3 * a, w->xyz + 3 * b);
        if (aim[a] + l < aim[b]) aim[b] = aim[a] + l, changed = 1;
        if (aim[b] + l < aim[a]) aim[a] = aim[b] + l, changed = 1;
      }
  }

  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = T_THICK;
  o.nlayers = NL;
  o.check_incremental = 1;
  o.elem_thickness = et;
  vm_mesh *out = NULL;
  vm_prism_report r;
  int st = vm_prism_run(ctx, w, &o, &out, &r);
  CHECK(st == 0 && out, "run: %d %s", st, vm_ctx_error(ctx));
  if (st || !out) return vmtest_end("prism_region");
  CHECK(r.inverted == 0 && chk_corner_inverted(out) == 0, "inverted corner tets: %lld",
        (long long)r.inverted);
  CHECK(r.layers == NL, "layers %d", r.layers);
  const vm_field *tf = vm_mesh_find_field(out, VM_PRISM_FIELD_TARGET, VM_FIELD_VERTEX);
  CHECK(tf != NULL, "no '%s' field", VM_PRISM_FIELD_TARGET);
  if (!tf) return vmtest_end("prism_region");
  const double *tg = tf->data;
  double aim_err = 0, slope = 0, len_err = 0;
  int64_t thin = 0, graded = 0;
  for (int64_t v = 0; v < nw; v++) {
    aim_err = fmax(aim_err, fabs(tg[v] - aim[v]));
    thin += tg[v] == T_THIN;
    graded += tg[v] > T_THIN && tg[v] < T_THICK;
    double len = dist(out->xyz + 3 * v, out->xyz + 3 * (NL * nw + v));
    len_err = fmax(len_err, fabs(len / tg[v] - 1));
  }
  for (int64_t e = 0; e < ne; e++)
    for (int i = 0; i < 3; i++) {
      int32_t a = w->conn[w->eoff[e] + i], b = w->conn[w->eoff[e] + (i + 1) % 3];
      slope = fmax(slope, fabs(tg[a] - tg[b]) / dist(w->xyz + 3 * a, w->xyz + 3 * b));
    }
  fprintf(stderr,
          "aims: %lld thin, %lld graded, %lld thick; max |aim - expected| %.3g, max slope %.4f; "
          "max |length / aim - 1| %.4f; full %.4f, thick_min %.4f, thick_max %.4f; first height "
          "%.5g, growth %.4f\n",
          (long long)thin, (long long)graded, (long long)(nw - thin - graded), aim_err, slope,
          len_err, r.full_fraction, r.thick_min, r.thick_max, r.first_height, r.growth);
  CHECK(aim_err <= 1e-12, "aims off the graded least by %g", aim_err);
  CHECK(slope <= 0.5 + 1e-12, "aims rise at slope %g > 0.5", slope);
  CHECK(thin > nw / 3 && graded > 0 && nw - thin - graded > nw / 3,
        "regions: %lld thin, %lld graded", (long long)thin, (long long)graded);
  CHECK(len_err < 0.02, "a column is %.3g off its aim", len_err);
  CHECK(r.full_fraction >= 0.99, "full thickness (against each column's aim) %g", r.full_fraction);
  /* the first layer: the schedule's height in both regions; the poles */
  double h1_dev = 0;
  for (int64_t v = 0; v < nw; v++) {
    double h1 = dist(out->xyz + 3 * v, out->xyz + 3 * (nw + v));
    h1_dev = fmax(h1_dev, fabs(h1 / r.first_height - 1));
  }
  fprintf(stderr, "first layer: max |h1 / schedule - 1| %.4f\n", h1_dev);
  CHECK(h1_dev < 0.05, "first layer %g off the schedule's height", h1_dev);
  CHECK(fabs(r.first_height - T_THICK * 0.2 / (pow(1.2, NL) - 1)) < 1e-12,
        "schedule's first height %g is not the thickest region's", r.first_height);
  /* the growth in the thin region is below 1.2: successive heights at the
   * north pole (z = 1, all its faces thin) */
  int64_t north = -1;
  for (int64_t v = 0; v < nw; v++)
    if (w->xyz[3 * v + 2] > 1 - 1e-9) north = v;
  CHECK(north >= 0, "no north pole");
  if (north >= 0) {
    double hs[NL], rmax = 0, rmin = INFINITY;
    for (int k = 0; k < NL; k++)
      hs[k] = dist(out->xyz + 3 * (k * nw + north), out->xyz + 3 * ((k + 1) * nw + north));
    for (int k = 0; k + 1 < NL; k++) {
      rmax = fmax(rmax, hs[k + 1] / hs[k]);
      rmin = fmin(rmin, hs[k + 1] / hs[k]);
    }
    fprintf(stderr, "north pole: heights %.4g .. %.4g, ratios %.4f .. %.4f\n", hs[0], hs[NL - 1],
            rmin, rmax);
    CHECK(rmin > 1 && rmax < 1.2, "north pole growth %g .. %g not in (1, 1.2)", rmin, rmax);
  }

  /* every face at T: the run without the option, bit for bit */
  double *all = malloc(sizeof *all * (size_t)ne);
  for (int64_t e = 0; e < ne; e++) all[e] = T_THICK;
  vm_mesh *a = NULL, *b = NULL;
  o.elem_thickness = all;
  st = vm_prism_run(ctx, w, &o, &a, NULL);
  o.elem_thickness = NULL;
  int st2 = vm_prism_run(ctx, w, &o, &b, NULL);
  CHECK(st == 0 && st2 == 0 && a && b, "runs: %d %d", st, st2);
  if (a && b)
    CHECK(a->nv == b->nv && !memcmp(a->xyz, b->xyz, sizeof(double) * 3 * (size_t)a->nv),
          "faces all at T differ from no thickness per face");
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);

  /* refused: a face above T, at 0, not a number; *out NULL */
  const double bad[] = {T_THICK * 1.01, 0, NAN, -1};
  for (int i = 0; i < 4; i++) {
    all[ne / 2] = bad[i];
    o.elem_thickness = all;
    st = vm_prism_run(ctx, w, &o, &a, NULL);
    CHECK(st == VM_ERR_ARG && !a, "face thickness %g: %d", bad[i], st);
    fprintf(stderr, "refused: %s\n", vm_ctx_error(ctx));
    vm_mesh_destroy(&a);
  }

  vm_mesh_destroy(&out);
  vm_mesh_destroy(&w);
  free(et);
  free(aim);
  free(all);
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_region");
}
