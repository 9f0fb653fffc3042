/* test/prism/test_prism_shapes.c: the prism stage on walls that exercise
 * each part of the method: a cube (sharp convex edges and corners), the
 * hole of a torus (concave, the layer closes the hole), two spheres closer
 * than 2T (cutting must end in a contact without intersection), and a
 * plate thinner than T. Checked independently of the library: corner tets
 * and an all-pairs separating-axis test of the boundary faces. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "support/check_prism.h"
#include "varmesh/prism.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

/* Outer faces against each other and against the wall (the triangles of
 * the result: wall tag 1, outer tag 2), all pairs. */
static int64_t boundary_intersections(const vm_mesh *res) {
  const vm_field *ph = vm_mesh_find_field(res, VM_PRISM_FIELD_PHYS, VM_FIELD_ELEMENT);
  int64_t n = 0;
  for (int64_t e = 0; e < res->ne; e++) n += res->etype[e] == VM_TRI;
  int32_t *tri = malloc(sizeof(int32_t) * 3 * (size_t)n);
  int32_t *grp = malloc(sizeof(int32_t) * (size_t)n);
  int64_t k = 0;
  for (int64_t e = 0; e < res->ne; e++) {
    if (res->etype[e] != VM_TRI) continue;
    memcpy(tri + 3 * k, res->conn + res->eoff[e], 3 * sizeof(int32_t));
    grp[k++] = ((const int32_t *)ph->data)[e] == VM_PRISM_TAG_WALL ? 0 : 1;
  }
  int64_t c = chk_count_intersections(res->xyz, n, tri, grp, 1e-6);
  free(tri);
  free(grp);
  return c;
}

typedef struct {
  vm_mesh *res;
  vm_prism_report r;
  int64_t nw;
} run_out;

static int run(vm_ctx *ctx, const char *name, vm_mesh *w, double T, int layers, run_out *out) {
  double *w0 = malloc(sizeof(double) * 3 * (size_t)w->nv);
  memcpy(w0, w->xyz, sizeof(double) * 3 * (size_t)w->nv);
  vm_prism_opts o = vm_prism_opts_default();
  o.thickness = T;
  o.nlayers = layers;
  o.growth = 1.2;
  o.check_incremental = 1; /* every incremental intersection query checked */
  int st = vm_prism_run(ctx, w, &o, &out->res, &out->r);
  CHECK(st == 0, "%s: run: %d %s", name, st, vm_ctx_error(ctx));
  if (st < 0 && out->r.wall_triangles == 0) { /* the wall was refused */
    free(w0);
    return st;
  }
  out->nw = out->r.wall_vertices;
  const vm_prism_report *r = &out->r;
  fprintf(stderr,
          "%s: %lld prisms, %d layers, cut %d rounds (%lld pairs first), full %.3f, thick "
          "%.3f..%.3f, inverted %lld, sj %.3f, normal dev %.2f deg, growth %.3f, %.2f s\n",
          name, (long long)r->prisms, r->layers, r->cut_rounds, (long long)r->cut_pairs_first,
          r->full_fraction, r->thick_min, r->thick_mean, (long long)r->inverted, r->sj_min,
          r->normal_dev_max, r->growth_max, r->time_total);
  for (int k = 0; k < VM_PRISM_NPHASES; k++)
    fprintf(stderr, "  %s %.3f s\n", vm_prism_phase_name((vm_prism_phase)k), r->time[k]);
  CHECK(r->inverted == 0, "%s: %lld inverted corner tets", name, (long long)r->inverted);
  CHECK(r->intersections == 0, "%s: %lld intersections left", name, (long long)r->intersections);
  if (out->res) {
    CHECK(vm_mesh_check(out->res) == 0, "%s: result: %s", name, vm_ctx_error(ctx));
    CHECK(chk_corner_inverted(out->res) == 0, "%s: result has inverted corner tets", name);
    CHECK(!memcmp(out->res->xyz, w0, sizeof(double) * 3 * (size_t)w->nv), "%s: wall moved", name);
    int64_t ni = boundary_intersections(out->res);
    CHECK(ni == 0, "%s: %lld intersecting boundary face pairs (independent check)", name,
          (long long)ni);
    /* the room figures from the output's fields: thickness and radius */
    const vm_field *fr = vm_mesh_find_field(out->res, VM_PRISM_FIELD_MEDIAL, VM_FIELD_VERTEX);
    const vm_field *fl = vm_mesh_find_field(out->res, VM_PRISM_FIELD_FILL, VM_FIELD_VERTEX);
    const vm_field *ft = vm_mesh_find_field(out->res, VM_PRISM_FIELD_THICKNESS, VM_FIELD_VERTEX);
    CHECK(fr && fl && ft, "%s: no medial_radius / fill / thickness field", name);
    if (fr && fl && ft) {
      const double *rad = fr->data, *fill = fl->data, *th = ft->data;
      int64_t room = 0, reach = 0, bad = 0;
      double fsum = 0;
      for (int64_t v = 0; v < out->nw; v++) {
        double allowed = fmin(T, rad[v]);
        double f = allowed > 0 ? fmin(1, th[v] / allowed) : 1;
        bad += fabs(f - fill[v]) > 1e-12 || rad[v] < 0 || rad[v] > 4 * T;
        fsum += f;
        if (rad[v] >= 1.05 * T) {
          room++;
          reach += th[v] >= 0.99 * T;
        }
      }
      fprintf(stderr,
              "%s: room for T %.3f, of those at T %.4f (%lld short), fill %.4f (rest %.4f)\n", name,
              r->medial_room, r->medial_reach, (long long)r->medial_short, r->medial_fill,
              r->medial_fill_rest);
      CHECK(bad == 0, "%s: %lld columns with a wrong fill or radius", name, (long long)bad);
      CHECK_NEAR(r->medial_room, (double)room / (double)out->nw, 1e-12, "room share");
      CHECK_NEAR(r->medial_reach, room ? (double)reach / (double)room : 1, 1e-12, "reach share");
      CHECK(r->medial_short == room - reach, "%s: short %lld, fields %lld", name,
            (long long)r->medial_short, (long long)(room - reach));
      CHECK_NEAR(r->medial_fill, fsum / (double)out->nw, 1e-12, "fill");
    }
  }
  free(w0);
  return 0;
}

static const double *top_of(const run_out *o, int64_t v) {
  return o->res->xyz + 3 * (o->r.layers * o->nw + v);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);

  { /* cube: sharp convex edges and corners */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    const int n[3] = {6, 6, 6};
    CHECK(vm_gen_box(w, lo, hi, n) == 0, "box");
    run_out o = {0};
    run(ctx, "cube", w, 0.6, 4, &o);
    CHECK(o.r.full_fraction >= 0.95, "cube: full fraction %g", o.r.full_fraction);
    CHECK(o.r.normal_dev_max < 5, "cube: normal deviation %g", o.r.normal_dev_max);
    /* the outer surface stays outside the cube by about T */
    double dmin = INFINITY;
    for (int64_t v = 0; o.res && v < o.nw; v++) {
      const double *x = top_of(&o, v);
      double d = fmax(fmax(fabs(x[0]), fabs(x[1])), fabs(x[2])) - 1;
      dmin = fmin(dmin, d);
    }
    CHECK(dmin > 0.5 * 0.6, "cube: outer vertex only %g outside", dmin);
    vm_mesh_destroy(&o.res);
    vm_mesh_destroy(&w);
  }

  { /* torus: the hole (radius 0.5) is closed by a layer of T = 0.7 */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    CHECK(vm_gen_torus(w, NULL, 1.0, 0.5, 32, 16, VM_GEN_TORUS_TRI, NULL, NULL) == 0, "torus");
    run_out o = {0};
    run(ctx, "torus", w, 0.7, 3, &o);
    /* inner equator columns end near the axis, none crosses it */
    double rmin = INFINITY, rmax_inner = 0;
    for (int64_t v = 0; o.res && v < o.nw; v++) {
      const double *y = o.res->xyz + 3 * v;
      if (fabs(y[2]) > 1e-9 || hypot(y[0], y[1]) > 0.5 + 1e-9) continue;
      const double *x = top_of(&o, v);
      double r = hypot(x[0], x[1]);
      rmin = fmin(rmin, r);
      rmax_inner = fmax(rmax_inner, r);
    }
    fprintf(stderr, "torus: inner-equator tops at axis distance %.3f..%.3f\n", rmin, rmax_inner);
    CHECK(rmax_inner < 0.25, "torus: the hole stays open (%g)", rmax_inner);
    CHECK(o.r.normal_dev_over5 == 0, "torus: %lld first-layer side edges more than 5 deg off",
          (long long)o.r.normal_dev_over5);
    vm_mesh_destroy(&o.res);
    vm_mesh_destroy(&w);
  }

  { /* two spheres 0.6 apart, T = 0.5: contact in the middle */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    const double ca[3] = {-1.3, 0, 0}, cb[3] = {1.3, 0, 0};
    CHECK(vm_gen_icosphere(w, ca, 1.0, 3, 0, NULL) == 0, "sphere");
    int64_t na = w->nv;
    CHECK(vm_gen_icosphere(w, cb, 1.0, 3, 0, NULL) == 0, "sphere");
    run_out o = {0};
    run(ctx, "two spheres", w, 0.5, 3, &o);
    double gap = INFINITY, tmax = 0;
    for (int64_t a = 0; o.res && a < na; a++) {
      const double *xa = top_of(&o, a);
      for (int64_t b = na; b < o.nw; b++)
        gap = fmin(gap, sqrt(pow(xa[0] - top_of(&o, b)[0], 2) + pow(xa[1] - top_of(&o, b)[1], 2) +
                             pow(xa[2] - top_of(&o, b)[2], 2)));
      const double *y = o.res->xyz + 3 * a;
      if (y[0] > -0.35)
        tmax = fmax(tmax, sqrt(pow(xa[0] - y[0], 2) + pow(xa[1] - y[1], 2) + pow(xa[2] - y[2], 2)));
    }
    /* the outer surface's edges at the contact: the layers stop a slot
     * of about that width apart (open_slots), so the fill's tets across
     * it are not flat; cutting alone left 0.0065 */
    double hsum = 0;
    int64_t hn = 0;
    for (int64_t t = 0; o.res && t < o.r.wall_triangles; t++) {
      const int32_t *c = o.res->conn + o.res->eoff[t];
      if (c[0] >= na || o.res->xyz[3 * c[0]] < -0.35) continue;
      for (int i = 0; i < 3; i++) {
        const double *x = top_of(&o, c[i]), *y = top_of(&o, c[(i + 1) % 3]);
        hsum += sqrt(pow(x[0] - y[0], 2) + pow(x[1] - y[1], 2) + pow(x[2] - y[2], 2));
        hn++;
      }
    }
    double hout = hn ? hsum / (double)hn : 0;
    fprintf(stderr,
            "two spheres: gap between the layers %.4f, outer edges there %.4f, thickness at "
            "contact <= %.3f, %lld columns lowered to open the slot\n",
            gap, hout, tmax, (long long)o.r.slots_lowered);
    CHECK(o.r.slots_lowered > 0 && gap > 0.5 * hout && gap < 1.5 * hout,
          "two spheres: slot %g between the layers against outer edges of %g", gap, hout);
    CHECK(tmax < 0.4, "two spheres: column at the contact %g long", tmax);
    CHECK(o.r.full_fraction > 0.6, "two spheres: full fraction %g", o.r.full_fraction);
    CHECK(o.r.normal_dev_over5 == 0 && o.r.normal_dev_max < 5,
          "two spheres: first layer on the normal at the contact too (max %g deg, %lld above 5)",
          o.r.normal_dev_max, (long long)o.r.normal_dev_over5);
    vm_mesh_destroy(&o.res);
    vm_mesh_destroy(&w);
  }

  { /* two spheres 0.6 apart, T = 0.5, 8 layers: the columns shortened at
     * the contact keep the schedule's first height (the wall's cells one
     * height, as a solver's wall treatment assumes) and the growth law
     * with a smaller ratio; scaling the whole schedule put their first
     * level at len/T of it */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    const double ca[3] = {-1.3, 0, 0}, cb[3] = {1.3, 0, 0};
    CHECK(vm_gen_icosphere(w, ca, 1.0, 3, 0, NULL) == 0, "sphere");
    CHECK(vm_gen_icosphere(w, cb, 1.0, 3, 0, NULL) == 0, "sphere");
    run_out o = {0};
    run(ctx, "two spheres, 8 layers", w, 0.5, 8, &o);
    const double h1 = o.r.first_height;
    int64_t nshort = 0, nkept = 0, nmono = 0;
    double rmin = INFINITY, rmax = 0;
    for (int64_t v = 0; o.res && v < o.nw; v++) {
      double len = 0, h[64];
      int nl = o.r.layers;
      for (int k = 0; k < nl && k < 64; k++) {
        const double *a = o.res->xyz + 3 * (k * o.nw + v),
                     *b = o.res->xyz + 3 * ((k + 1) * o.nw + v);
        h[k] = sqrt(pow(b[0] - a[0], 2) + pow(b[1] - a[1], 2) + pow(b[2] - a[2], 2));
        len += h[k];
      }
      /* shortened, yet long enough for nl cells of h1 */
      if (!(len < 0.9 * 0.5 && len > 1.1 * nl * h1)) continue;
      nshort++;
      double r = h[0] / h1;
      rmin = fmin(rmin, r);
      rmax = fmax(rmax, r);
      if (fabs(r - 1) < 0.05) nkept++;
      int mono = 1; /* heights rise with a ratio in [1, 1.2] */
      for (int k = 1; k < nl; k++)
        mono &= h[k] >= h[k - 1] * (1 - 1e-6) && h[k] <= 1.2 * h[k - 1] * (1 + 1e-6);
      nmono += mono;
    }
    fprintf(stderr,
            "two spheres, 8 layers: h1 %.4f; %lld shortened columns, first height / h1 %.3f..%.3f, "
            "%lld within 5 %%, %lld with ratios in [1, 1.2]\n",
            h1, (long long)nshort, rmin, rmax, (long long)nkept, (long long)nmono);
    CHECK(nshort >= 20, "two spheres, 8 layers: only %lld shortened columns", (long long)nshort);
    CHECK(nkept >= 0.9 * nshort, "two spheres, 8 layers: %lld of %lld shortened columns keep h1",
          (long long)nkept, (long long)nshort);
    CHECK(nmono >= 0.9 * nshort, "two spheres, 8 layers: %lld of %lld on a growth law in [1, 1.2]",
          (long long)nmono, (long long)nshort);
    vm_mesh_destroy(&o.res);
    vm_mesh_destroy(&w);
  }

  { /* two spheres with cutting stopped after one round: pairs are left,
     * yet restoring still brings the columns away from the contact to
     * full thickness (it used to stop at its first pass) and adds no pair
     * of its own. The spheres are projected only at the end: on the
     * default (more uniform) icosphere one cut round already leaves no
     * pair, and the case would test nothing */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    const double ca[3] = {-1.3, 0, 0}, cb[3] = {1.3, 0, 0};
    CHECK(vm_gen_icosphere(w, ca, 1.0, 3, VM_GEN_PROJECT_AT_END, NULL) == 0, "sphere");
    CHECK(vm_gen_icosphere(w, cb, 1.0, 3, VM_GEN_PROJECT_AT_END, NULL) == 0, "sphere");
    vm_prism_opts po = vm_prism_opts_default();
    po.thickness = 0.5;
    po.nlayers = 3;
    po.max_cut_rounds = 1;
    po.springback_iter = 1; /* short of T: restoring has work to do */
    po.check_incremental = 1;
    vm_prism *p = NULL;
    int st = vm_prism_create(ctx, w, &po, &p);
    CHECK(st == 0, "two spheres, 1 cut round: create: %s", vm_ctx_error(ctx));
    int64_t after_cut = -1;
    vm_prism_report r;
    for (int ph = 0; p && ph < VM_PRISM_NPHASES; ph++) {
      static int (*const fn[])(vm_prism *) = {vm_prism_thin, vm_prism_springback, vm_prism_cut,
                                              vm_prism_restore, vm_prism_march};
      st = fn[ph](p);
      CHECK(st >= 0, "two spheres, 1 cut round: phase %d: %s", ph, vm_ctx_error(ctx));
      vm_prism_get_report(p, &r);
      if (ph == VM_PRISM_PHASE_CUT) after_cut = r.intersections;
      if (ph == VM_PRISM_PHASE_RESTORE) {
        fprintf(stderr,
                "two spheres, 1 cut round: %lld pairs after cutting, %lld after restoring\n",
                (long long)after_cut, (long long)r.intersections);
        CHECK(after_cut > 0, "two spheres, 1 cut round: no pair left to test with");
        CHECK(r.intersections <= after_cut, "two spheres, 1 cut round: restoring added pairs");
      }
    }
    vm_prism_get_report(p, &r);
    fprintf(stderr, "two spheres, 1 cut round: full %.3f, mean %.3f\n", r.full_fraction,
            r.thick_mean);
    CHECK(r.full_fraction > 0.6, "two spheres, 1 cut round: full fraction %g", r.full_fraction);
    CHECK(r.inverted == 0, "two spheres, 1 cut round: %lld inverted", (long long)r.inverted);
    vm_prism_destroy(&p);
    vm_mesh_destroy(&w);
  }

  { /* a plate 0.1 thick, T = 0.3 */
    vm_mesh *w = NULL;
    vm_mesh_create(ctx, &w);
    const double lo[3] = {-1, -1, -0.05}, hi[3] = {1, 1, 0.05};
    const int n[3] = {10, 10, 1};
    CHECK(vm_gen_box(w, lo, hi, n) == 0, "box");
    run_out o = {0};
    run(ctx, "plate", w, 0.3, 4, &o);
    CHECK(o.r.full_fraction >= 0.9, "plate: full fraction %g", o.r.full_fraction);
    vm_mesh_destroy(&o.res);
    vm_mesh_destroy(&w);
  }

  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("prism_shapes");
}
