/* test/prism/test_prism_short.c: short columns given the layers that fit
 * them (vm_prism_opts.end_short) on two unit spheres 0.06 apart (length
 * 4.06, T = 5 % = 0.203, 20 layers): in the gap each layer is stopped at
 * about 0.03, and with every layer kept there its cells are some 80 times
 * wider than high, below OpenFOAM's cell determinant limit (checkMesh
 * -allGeometry). Run with and without it:
 * - with it, layers end on short columns (the report's short_ended,
 *   pyramids and tets), and the layer's cells below the determinant limit,
 *   counted here over every cell (prisms, pyramids, tets; every face
 *   inside but the wall's, as in the hybrid mesh), are at most half of
 *   those without it (the stage keeps a patch only then);
 * - both layers are valid as a solver checks them: no inverted corner
 *   tet, every prism positive in every 3-tet split, every cell of
 *   positive OpenFOAM volume with no wrong face pyramid;
 * - the wall is the input's and the outer surface (the column tops) is
 *   the same in both runs, bit for bit: only interior levels change;
 * - the ended columns follow the growth law (every column in the growth
 *   band, as the report counts it);
 * - on one sphere alone, where no cell is below the limit, the result is
 *   the same bit for bit with and without the option. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/check_prism.h"
#include "varmesh/prism.h"
#include "varmesh/quality.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

static vm_mesh *run(vm_ctx *ctx, const vm_mesh *w, double T, int end_short, vm_prism_report *r) {
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = T;
  o.end_short = end_short;
  o.check_incremental = 1;
  vm_mesh *res = NULL;
  int st = vm_prism_run(ctx, w, &o, &res, r);
  CHECK(st == 0 && res, "end_short %d: run %d %s", end_short, st, vm_ctx_error(ctx));
  return res;
}

/* Cells of the layer m (wall vertices 0..nw-1) below OpenFOAM's cell
 * determinant limit, every face counted as inside but those on the wall;
 * *bad: cells not valid as a solver checks them. */
static int64_t flat_cells(const vm_mesh *m, int64_t nw, int64_t *bad) {
  int64_t n = 0;
  *bad = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int type = m->etype[e];
    if (type != VM_PRISM && type != VM_PYRAMID && type != VM_TET) continue;
    const int32_t *cv = m->conn + m->eoff[e];
    int nv = vm_elem_nverts(type), fv[6][4], nfv[6], nf = vm_elem_faces(type, fv, nfv), ns = 0;
    double x[18], s[6][3], vol = 0;
    for (int i = 0; i < nv; i++) memcpy(x + 3 * i, m->xyz + 3 * (int64_t)cv[i], 3 * sizeof *x);
    for (int f = 0; f < nf; f++) {
      int wall = 1;
      double y[12], c[3];
      for (int i = 0; i < nfv[f]; i++) {
        wall &= cv[fv[f][i]] < nw;
        memcpy(y + 3 * i, x + 3 * fv[f][i], 3 * sizeof *y);
      }
      if (wall) continue;
      vm_foam_face(y, nfv[f], c, s[ns++]);
    }
    n += vm_foam_cell_determinant(ns, (const double(*)[3])s) < 1e-3;
    if (vm_cell_foam(type, x, &vol) != 0 || !(vol > 0)) (*bad)++;
    if (type == VM_PRISM && vm_prism_split_check(x, NULL) > 0) (*bad)++;
  }
  return n;
}

/* Are the last 2 nt elements (the wall's and the outer surface's
 * triangles) of a and b at the same coordinates, bit for bit? */
static int same_surfaces(const vm_mesh *a, const vm_mesh *b, int64_t nt) {
  for (int64_t j = 0; j < 2 * nt; j++) {
    int64_t ea = a->ne - 2 * nt + j, eb = b->ne - 2 * nt + j;
    for (int i = 0; i < 3; i++) {
      const double *xa = a->xyz + 3 * (int64_t)a->conn[a->eoff[ea] + i];
      const double *xb = b->xyz + 3 * (int64_t)b->conn[b->eoff[eb] + i];
      if (memcmp(xa, xb, 3 * sizeof *xa)) return 0;
    }
  }
  return 1;
}

static int same_mesh(const vm_mesh *a, const vm_mesh *b) {
  return a->nv == b->nv && a->ne == b->ne &&
         !memcmp(a->xyz, b->xyz, 3 * sizeof *a->xyz * (size_t)a->nv) &&
         !memcmp(a->etype, b->etype, (size_t)a->ne) &&
         !memcmp(a->conn, b->conn, sizeof *a->conn * (size_t)a->eoff[a->ne]);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  vm_mesh *w = NULL;
  vm_mesh_create(ctx, &w);
  const double ca[3] = {-1.03, 0, 0}, cb[3] = {1.03, 0, 0};
  CHECK(vm_gen_icosphere(w, ca, 1.0, 3, 0, NULL) == 0 &&
            vm_gen_icosphere(w, cb, 1.0, 3, 0, NULL) == 0,
        "two spheres");
  double T = 0.05 * 4.06;
  int64_t nw = w->nv, nt = w->ne;
  vm_prism_report ra, rb;
  vm_mesh *a = run(ctx, w, T, 1, &ra), *b = run(ctx, w, T, 0, &rb);
  if (a && b) {
    int64_t bad_a, bad_b, fa = flat_cells(a, nw, &bad_a), fb = flat_cells(b, nw, &bad_b);
    fprintf(stderr,
            "two spheres: cells below the determinant limit %lld with, %lld without; %lld "
            "columns short, %lld pyramids, %lld tets\n",
            (long long)fa, (long long)fb, (long long)ra.short_ended, (long long)ra.pyramids,
            (long long)ra.tets);
    CHECK(fb > 100, "the squeeze is not one: %lld cells below the limit without", (long long)fb);
    CHECK(ra.short_ended > 0 && ra.ended_columns >= ra.short_ended && ra.pyramids + ra.tets > 0,
          "no layer ended: %lld short, %lld ended, %lld pyramids, %lld tets",
          (long long)ra.short_ended, (long long)ra.ended_columns, (long long)ra.pyramids,
          (long long)ra.tets);
    CHECK(rb.short_ended == 0 && rb.ended_columns == 0 && rb.pyramids == 0 && rb.tets == 0,
          "layers ended without the option");
    CHECK(2 * fa <= fb, "cells below the determinant limit %lld with, %lld without", (long long)fa,
          (long long)fb);
    CHECK(ra.det_small == fa && rb.det_small == fb,
          "the reports count %lld and %lld cells below the determinant limit, this test %lld "
          "and %lld",
          (long long)ra.det_small, (long long)rb.det_small, (long long)fa, (long long)fb);
    CHECK(bad_a == 0 && bad_b == 0, "cells a solver refuses: %lld with, %lld without",
          (long long)bad_a, (long long)bad_b);
    CHECK(chk_corner_inverted(a) == 0 && chk_corner_inverted(b) == 0, "inverted corner tets");
    CHECK(ra.inverted == 0 && ra.split_negative == 0,
          "the report: %lld inverted, "
          "%lld split negative",
          (long long)ra.inverted, (long long)ra.split_negative);
    CHECK(!memcmp(a->xyz, w->xyz, 3 * sizeof *a->xyz * (size_t)nw) &&
              !memcmp(b->xyz, w->xyz, 3 * sizeof *b->xyz * (size_t)nw),
          "the wall moved");
    CHECK(same_surfaces(a, b, nt), "the wall's or the outer surface's triangles differ");
    CHECK(ra.growth_band_share == 1, "columns in the growth band: %.4f", ra.growth_band_share);
  }
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);
  /* one sphere: nothing to end */
  vm_mesh *s = NULL;
  vm_mesh_create(ctx, &s);
  CHECK(vm_gen_icosphere(s, ca, 1.0, 3, 0, NULL) == 0, "one sphere");
  a = run(ctx, s, 0.1, 1, &ra);
  b = run(ctx, s, 0.1, 0, &rb);
  if (a && b) {
    CHECK(ra.short_ended == 0 && ra.ended_columns == 0, "one sphere: layers ended");
    CHECK(same_mesh(a, b), "one sphere: the option changed the layer");
  }
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);
  vm_mesh_destroy(&s);
  vm_mesh_destroy(&w);
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_short");
}
