/* test/surface/test_unfold.c: the surface stage's exact check of a moved
 * surface and its local back-off (vm_surface_unfold). An icosphere
 * (level 3, radius 1) whose vertices all moved a little (a smooth,
 * valid motion) and one of which was pushed through the sphere to the
 * other side (its triangles cross the far side's and reverse): the
 * back-off leaves no intersecting pair and no reversed triangle, puts
 * back that vertex and a few rings around it, and leaves every other
 * vertex where the motion took it, bit for bit. A motion with no fold is
 * left alone, and the summary then says no element is reversed whatever
 * it said before; a start that intersects itself is not the back-off's to
 * fix; quads are not checked. A fold that no round of the back-off (up
 * to 63 rings) can take back undoes the whole motion. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/repair.h"
#include "varmesh/shapes.h"
#include "varmesh/surface.h"
#include "vmtest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static vm_mesh *sphere(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  double c[3] = {0, 0, 0};
  CHECK(vm_mesh_create(ctx, &m) == 0, "mesh");
  CHECK(m && vm_gen_icosphere(m, c, 1.0, 3, 0, NULL) == 0, "icosphere: %s", vm_ctx_error(ctx));
  return m;
}

/* A smooth motion that folds nothing: every vertex turned by 0.02 rad
 * about z, scaled by 1 + 0.01 z. */
static void twist(vm_mesh *m) {
  for (int64_t v = 0; v < m->nv; v++) {
    double *p = m->xyz + 3 * v, c = cos(0.02), s = sin(0.02);
    double x = c * p[0] - s * p[1], y = s * p[0] + c * p[1], f = 1 + 0.01 * p[2];
    p[0] = f * x;
    p[1] = f * y;
    p[2] = f * p[2];
  }
}

int main(void) {
  vm_ctx *ctx = NULL;
  CHECK(vm_ctx_create(&ctx) == 0, "context");
  vm_mesh *m = sphere(ctx);
  if (!m) return vmtest_end("unfold");
  int64_t nv = m->nv;
  size_t sz = 3 * (size_t)nv * sizeof(double);
  double *x0 = malloc(sz), *moved = malloc(sz);
  memcpy(x0, m->xyz, sz);

  /* no fold: nothing changes */
  twist(m);
  memcpy(moved, m->xyz, sz);
  vm_surface_summary s;
  memset(&s, 0, sizeof s);
  /* the adaptation's own count of flipped elements, which the angle floor
   * may have taken back before this check: what is left replaces it (a
   * stale count made vm-surface exit 3 on a Gmsh-meshed wing whose
   * result had no reversed element) */
  s.adapt.flipped = 92;
  CHECK(vm_surface_unfold(m, x0, &s) == 0, "unfold (no fold): %s", vm_ctx_error(ctx));
  CHECK(s.self_intersections == 0 && s.adapt.flipped == 0 && s.adapt_backed_off == 0,
        "no fold: %lld pairs, %lld flipped, %lld put back", (long long)s.self_intersections,
        (long long)s.adapt.flipped, (long long)s.adapt_backed_off);
  CHECK(!memcmp(m->xyz, moved, sz), "a motion without a fold was changed");

  /* vertex 0 pushed through the sphere to the far side */
  double *p = m->xyz;
  for (int r = 0; r < 3; r++) p[r] = -1.3 * x0[r];
  memcpy(moved, m->xyz, sz);
  int64_t pairs0 = 0;
  CHECK(vm_surface_self_intersections(m, &pairs0, NULL) == 0 && pairs0 > 0,
        "the pushed vertex makes %lld pairs", (long long)pairs0);
  memset(&s, 0, sizeof s);
  CHECK(vm_surface_unfold(m, x0, &s) == 0, "unfold: %s", vm_ctx_error(ctx));
  int64_t left = -1;
  CHECK(vm_surface_self_intersections(m, &left, NULL) == 0 && left == 0, "%lld pairs left",
        (long long)left);
  CHECK(s.self_intersections == 0 && s.adapt.flipped == 0, "summary: %lld pairs, %lld flipped",
        (long long)s.self_intersections, (long long)s.adapt.flipped);
  CHECK(s.folds_found == pairs0, "folds found %lld, pairs %lld", (long long)s.folds_found,
        (long long)pairs0);
  CHECK(!memcmp(m->xyz, x0, 3 * sizeof(double)), "the pushed vertex is not back");
  /* put back: the vertex, its fold's far-side triangles' vertices and a
   * ring around each; everything else where the motion left it */
  int64_t back = 0, kept = 0;
  for (int64_t v = 0; v < nv; v++) {
    if (!memcmp(m->xyz + 3 * v, x0 + 3 * v, 3 * sizeof(double)))
      back++;
    else if (!memcmp(m->xyz + 3 * v, moved + 3 * v, 3 * sizeof(double)))
      kept++;
  }
  CHECK(back + kept == nv, "%lld vertices neither back nor where they moved",
        (long long)(nv - back - kept));
  CHECK(back == s.adapt_backed_off, "%lld back, summary says %lld", (long long)back,
        (long long)s.adapt_backed_off);
  CHECK(back >= 7 && back <= nv / 4, "%lld of %lld vertices put back", (long long)back,
        (long long)nv);

  /* a start that intersects itself: not the back-off's to fix */
  double *bad0 = malloc(sz);
  memcpy(bad0, moved, sz);
  memcpy(m->xyz, moved, sz);
  memset(&s, 0, sizeof s);
  CHECK(vm_surface_unfold(m, bad0, &s) == 0, "unfold (folded start)");
  CHECK(s.self_intersections == pairs0 && s.adapt_backed_off == 0 && !memcmp(m->xyz, moved, sz),
        "folded start: %lld pairs, %lld put back", (long long)s.self_intersections,
        (long long)s.adapt_backed_off);
  CHECK(vm_surface_unfold(NULL, x0, &s) == VM_ERR_ARG, "NULL mesh");

  /* a fold no local back-off can take back: on a finer sphere (about 160 rings
   * from the equator to a pole) the northern half turned by half a turn
   * about z, the turn growing from 0 at the equator to pi at z = 0.1; the
   * seam the back-off leaves between restored and turned vertices folds
   * again wherever it is: the whole motion is undone, the surface before
   * it (free of pairs) comes back bit for bit */
  vm_mesh *f = NULL;
  double c0[3] = {0, 0, 0};
  CHECK(vm_mesh_create(ctx, &f) == 0 && vm_gen_icosphere(f, c0, 1.0, 7, 0, NULL) == 0,
        "fine icosphere");
  if (f) {
    int64_t fn = f->nv;
    size_t fsz = 3 * (size_t)fn * sizeof(double);
    double *f0 = malloc(fsz);
    memcpy(f0, f->xyz, fsz);
    for (int64_t v = 0; v < fn; v++) {
      double *q = f->xyz + 3 * v;
      double a = q[2] <= 0 ? 0 : q[2] >= 0.1 ? M_PI : M_PI * q[2] / 0.1;
      double x = cos(a) * q[0] - sin(a) * q[1], y = sin(a) * q[0] + cos(a) * q[1];
      q[0] = x;
      q[1] = y;
    }
    int64_t fp = 0;
    CHECK(vm_surface_self_intersections(f, &fp, NULL) == 0 && fp > 0, "the turn makes %lld pairs",
          (long long)fp);
    memset(&s, 0, sizeof s);
    CHECK(vm_surface_unfold(f, f0, &s) == 0, "unfold (turn): %s", vm_ctx_error(ctx));
    int64_t fl = -1;
    CHECK(vm_surface_self_intersections(f, &fl, NULL) == 0 && fl == 0 &&
              s.self_intersections == 0 && s.adapt.flipped == 0,
          "turn: %lld pairs left (summary %lld, flipped %lld)", (long long)fl,
          (long long)s.self_intersections, (long long)s.adapt.flipped);
    CHECK(!memcmp(f->xyz, f0, fsz) && s.adapt_backed_off == fn,
          "turn: the motion is undone, every vertex back bit for bit (%lld of %lld put back)",
          (long long)s.adapt_backed_off, (long long)fn);
    free(f0);
  }
  vm_mesh_destroy(&f);

  free(bad0);
  free(x0);
  free(moved);
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("unfold");
}
