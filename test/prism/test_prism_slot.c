/* test/prism/test_prism_slot.c: a slot between two parts' layers, opened.
 *
 * Two unit spheres 0.6 apart under a layer of T = 0.5: cutting stops the
 * two layers where they meet, a few thousandths apart, and the fill's
 * tets across that slot are flat (OpenFOAM's cell determinant far below
 * its 0.001). With the default slot clearance the columns there are
 * lowered until the outer surfaces are about an outer edge apart, and
 * the fill's tets in the slot are not flat. The same run with
 * slot_clearance = 0 is the control: it must show the flat tets, or the
 * test would prove nothing.
 *
 * A gap the wall's triangles do not resolve is said before the run: two
 * such spheres 0.02 apart (edges about 0.15) have wall vertices whose
 * exterior medial ball is stopped by the other sphere within a quarter of
 * their edges; the narrowest gap the report gives is at least the true
 * 0.02 and at the slot. At 0.6 apart there is none. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/fill.h"
#include "varmesh/shapes.h"
#include "varmesh/mesh.h"
#include "varmesh/prism.h"
#include "varmesh/quality.h"
#include "vmtest.h"

typedef struct {
  int64_t tets; /* the fill's tets in the slot (centroid |x| < 0.3) */
  int64_t flat; /* of those, OpenFOAM's determinant below 0.001 */
  double det;   /* the least determinant there */
  double gap;   /* the least distance between the two layers' tops */
  int64_t lowered;
  double fill_rest;
} slot_figures;

static double dist(const double *a, const double *b) {
  return sqrt(pow(a[0] - b[0], 2) + pow(a[1] - b[1], 2) + pow(a[2] - b[2], 2));
}

static void run(vm_ctx *ctx, const vm_mesh *w, int64_t na, double clearance, slot_figures *f) {
  memset(f, 0, sizeof *f);
  f->det = INFINITY;
  f->gap = INFINITY;
  vm_prism_opts po = vm_prism_opts_default();
  po.thickness = 0.5;
  po.nlayers = 3;
  po.slot_clearance = clearance;
  vm_mesh *layer = NULL, *out = NULL;
  vm_prism_report pr;
  int st = vm_prism_run(ctx, w, &po, &layer, &pr);
  CHECK(st == VM_OK, "clearance %g: prism: %s", clearance, vm_ctx_error(ctx));
  if (st != VM_OK) return;
  CHECK(pr.inverted == 0 && pr.intersections == 0, "clearance %g: %lld inverted, %lld pairs",
        clearance, (long long)pr.inverted, (long long)pr.intersections);
  f->lowered = pr.slots_lowered;
  f->fill_rest = pr.medial_fill_rest;
  int64_t nw = pr.wall_vertices;
  const double *top = layer->xyz + 3 * (pr.layers * nw);
  for (int64_t a = 0; a < na; a++)
    for (int64_t b = na; b < nw; b++) f->gap = fmin(f->gap, dist(top + 3 * a, top + 3 * b));
  vm_fill_opts fo = vm_fill_opts_default();
  fo.farfield = 3;
  vm_fill_report fr;
  st = vm_fill_run(ctx, layer, &fo, &out, &fr);
  CHECK(st == VM_OK, "clearance %g: fill: %s", clearance, vm_ctx_error(ctx));
  if (st == VM_OK) {
    static const int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    for (int64_t e = 0; e < out->ne; e++) {
      if (out->etype[e] != VM_TET) continue;
      const int32_t *c = out->conn + out->eoff[e];
      double g[3] = {0, 0, 0}, s[4][3];
      for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++) g[k] += out->xyz[3 * (int64_t)c[i] + k] / 4;
      if (!(fabs(g[0]) < 0.3)) continue;
      for (int j = 0; j < 4; j++) {
        const double *p0 = out->xyz + 3 * (int64_t)c[fv[j][0]],
                     *p1 = out->xyz + 3 * (int64_t)c[fv[j][1]],
                     *p2 = out->xyz + 3 * (int64_t)c[fv[j][2]];
        double u[3], v[3];
        for (int k = 0; k < 3; k++) u[k] = p1[k] - p0[k], v[k] = p2[k] - p0[k];
        s[j][0] = 0.5 * (u[1] * v[2] - u[2] * v[1]);
        s[j][1] = 0.5 * (u[2] * v[0] - u[0] * v[2]);
        s[j][2] = 0.5 * (u[0] * v[1] - u[1] * v[0]);
      }
      double d = vm_foam_cell_determinant(4, (const double(*)[3])s);
      f->tets++;
      f->flat += d < 1e-3;
      f->det = fmin(f->det, d);
    }
  }
  fprintf(stderr,
          "clearance %g: %lld columns lowered, gap between the layers %.4f, fill where there is "
          "no room %.3f; %lld tets in the slot, %lld with a determinant below 0.001 (least "
          "%.3g), %.2f s + %.2f s\n",
          clearance, (long long)f->lowered, f->gap, f->fill_rest, (long long)f->tets,
          (long long)f->flat, f->det, pr.time_total, fr.time_mesh);
  vm_mesh_destroy(&out);
  vm_mesh_destroy(&layer);
}

/* Two unit spheres of the given level `gap` apart along x, as one wall;
 * *na: the first sphere's vertex count. */
static vm_mesh *two_spheres(vm_ctx *ctx, double gap, int level, int64_t *na) {
  vm_mesh *w = NULL;
  vm_mesh_create(ctx, &w);
  const double ca[3] = {-1 - gap / 2, 0, 0}, cb[3] = {1 + gap / 2, 0, 0};
  CHECK(vm_gen_icosphere(w, ca, 1.0, level, 0, NULL) == 0, "sphere");
  *na = w->nv;
  CHECK(vm_gen_icosphere(w, cb, 1.0, level, 0, NULL) == 0, "sphere");
  return w;
}

/* The narrow-gap figures of the wall w before any phase runs. */
static vm_prism_report gaps(vm_ctx *ctx, const vm_mesh *w) {
  vm_prism_report r;
  memset(&r, 0, sizeof r);
  vm_prism_opts po = vm_prism_opts_default();
  po.thickness = 0.5;
  vm_prism *p = NULL;
  const double *radius = NULL;
  int st = vm_prism_create(ctx, w, &po, &p);
  if (st >= 0) st = vm_prism_medial_radius(p, &radius);
  if (st >= 0) st = vm_prism_get_report(p, &r);
  CHECK(st >= 0, "narrow gaps: %s", vm_ctx_error(ctx));
  vm_prism_destroy(&p);
  return r;
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  vm_ctx_set_threads(ctx, 1);
  int64_t na = 0;
  vm_mesh *w = two_spheres(ctx, 0.6, 3, &na);
  vm_prism_report g = gaps(ctx, w);
  CHECK(g.narrow_gap == 0 && g.narrow_gap_min == 0,
        "0.6 apart: %lld vertices in a narrow gap (narrowest %g)", (long long)g.narrow_gap,
        g.narrow_gap_min);
  {
    int64_t nn = 0;
    vm_mesh *n = two_spheres(ctx, 0.02, 3, &nn);
    vm_prism_report h = gaps(ctx, n);
    fprintf(stderr,
            "0.02 apart: %lld wall vertices in a narrow gap, narrowest %.4f at (%.3f, %.3f, "
            "%.3f)\n",
            (long long)h.narrow_gap, h.narrow_gap_min, h.narrow_gap_at[0], h.narrow_gap_at[1],
            h.narrow_gap_at[2]);
    CHECK(h.narrow_gap > 0 && h.narrow_gap <= 40,
          "0.02 apart: %lld vertices in a narrow gap (a few, at the slot)",
          (long long)h.narrow_gap);
    CHECK(h.narrow_gap_min >= 0.02 * (1 - 1e-9) && h.narrow_gap_min < 0.05 &&
              fabs(h.narrow_gap_at[0]) < 0.1,
          "0.02 apart: narrowest %g at x = %g", h.narrow_gap_min, h.narrow_gap_at[0]);
    vm_mesh_destroy(&n);
  }
  slot_figures off, on;
  run(ctx, w, na, 0, &off);
  run(ctx, w, na, 0.5, &on);
  /* the control: cutting alone leaves the layers touching, tets flat */
  CHECK(off.lowered == 0 && off.gap < 0.02 && off.flat > 0,
        "control: %lld lowered, gap %g, %lld flat tets", (long long)off.lowered, off.gap,
        (long long)off.flat);
  /* opened: about an outer edge (0.2 here) apart, no flat tet in the slot */
  CHECK(on.lowered > 0 && on.gap > 0.1, "opened: %lld lowered, gap %g", (long long)on.lowered,
        on.gap);
  CHECK(on.tets > 0 && on.flat == 0 && on.det > 10 * off.det,
        "opened: %lld of %lld tets in the slot flat (least determinant %g, control %g)",
        (long long)on.flat, (long long)on.tets, on.det, off.det);
  vm_mesh_destroy(&w);
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_slot");
}
