/* test/volume/test_slip.c: slip boundary conditions of the volume stage
 * (vm_volume_slip_*): on a rotated cube whose boundary vertices are
 * crowded towards two faces' middles, the boundary vertices slide on the
 * cube's faces, along its edges, corners and the inner cube stay
 * bit-identical, the result is valid and the boundary spacing evens out;
 * with the boundary fixed instead, the crowding stays. Hex and tet meshes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/rotcube.h"
#include "varmesh/io.h"
#include "varmesh/quality.h"
#include "varmesh/slip.h"
#include "varmesh/topology.h"
#include "varmesh/volume.h"
#include "vmtest.h"

static const double PI = 3.14159265358979323846;

/* Crowding of a boundary coordinate in [-1/2, 1/2]: monotone (a < 1/(2 pi)),
 * ends kept, so faces stay planar, edges on edges, corners put. */
static double crowd(double c) { return c + 0.12 * sin(2 * PI * (c + 0.5)); }

static int on_face(double c) { return fabs(fabs(c) - 0.5) < 1e-12; }

/* Ratio of the longest to the shortest boundary edge. */
static double boundary_edge_ratio(vm_ctx *ctx, const vm_mesh *m) {
  int64_t nf = 0;
  int32_t *fv = NULL;
  uint8_t *fnv = NULL;
  vm_mesh_boundary(m, &nf, &fv, &fnv, NULL, NULL);
  double lo = INFINITY, hi = 0;
  for (int64_t f = 0; f < nf; f++)
    for (int k = 0; k < fnv[f]; k++) {
      const double *a = m->xyz + 3 * (int64_t)fv[4 * f + k];
      const double *b = m->xyz + 3 * (int64_t)fv[4 * f + (k + 1) % fnv[f]];
      double l = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                      (a[2] - b[2]) * (a[2] - b[2]));
      lo = fmin(lo, l);
      hi = fmax(hi, l);
    }
  vm_free(ctx, fv);
  vm_free(ctx, fnv);
  return hi / lo;
}

static double slip_case(vm_ctx *ctx, const char *name, double alpha, int cells, int slip) {
  const int n = 8;
  double phi = -1;
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = n;
  ro.alpha = alpha;
  ro.cells = cells;
  vm_mesh *m;
  double *ref;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m, &ref) == VM_OK, "%s: generate", name);
  /* free the boundary (the generator fixes it) and crowd it */
  int64_t nbv = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    double *p = m->xyz + 3 * v;
    if (!on_face(p[0]) && !on_face(p[1]) && !on_face(p[2])) continue;
    nbv++;
    for (int c = 0; c < 3; c++)
      if (!on_face(p[c])) p[c] = crowd(p[c]);
    m->vflag[v] = VM_VERTEX_FIXED;
  }
  CHECK(nbv == 6 * (n - 1) * (n - 1) + 12 * (n - 1) + 8, "%s: %lld boundary vertices", name,
        (long long)nbv);
  double ratio0 = boundary_edge_ratio(ctx, m);
  vm_volume_slip *s = NULL;
  vm_volume_slip_info si;
  memset(&si, 0, sizeof si);
  vm_surface_ops ops;
  if (slip) {
    for (int64_t v = 0; v < m->nv; v++) {
      const double *p = m->xyz + 3 * v;
      if (on_face(p[0]) || on_face(p[1]) || on_face(p[2])) m->vflag[v] = VM_VERTEX_FREE;
    }
    int st = vm_volume_slip_create(ctx, m, 40, 60, &s, &si);
    CHECK(st == VM_OK, "%s: slip create: %s", name, vm_ctx_error(ctx));
    if (st != VM_OK) goto out;
    ops = vm_volume_slip_ops(s);
    CHECK(si.nboundary == nbv && si.nsurface == 6 * (n - 1) * (n - 1) && si.nline == 12 * (n - 1) &&
              si.ncorner == 8 && si.lines == 12 && si.nkept_fixed == 0 && si.patches == 6,
          "%s: classes: %lld boundary, %lld surface, %lld line (%d lines), %lld corners, %lld "
          "kept fixed",
          name, (long long)si.nboundary, (long long)si.nsurface, (long long)si.nline, si.lines,
          (long long)si.ncorner, (long long)si.nkept_fixed);
  }
  vm_mesh *before;
  vm_mesh_clone(m, &before);
  vm_volume_opts o = vm_volume_opts_default();
  o.target_size = 1.0 / n;
  o.opt_iter = 200;
  o.time_limit = 600; /* a hang guard only */
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, slip ? &ops : NULL, &o, &r);
  CHECK(st == VM_OK && r.valid, "%s: status %d, M %lld -> %lld", name, st, (long long)r.M_init,
        (long long)r.M_final);
  vm_quality q;
  vm_quality_opts qo = {VM_RULE_CORNER, 1.0 / n};
  vm_mesh_quality(m, &qo, &q);
  if (getenv("SLIP_DUMP")) {
    char path[256];
    snprintf(path, sizeof path, "%s-%d-%d.vtu", getenv("SLIP_DUMP"), cells, slip);
    vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL);
  }
  CHECK(q.all.inverted_nodes == 0, "%s: independent check: M %lld", name,
        (long long)q.all.inverted_nodes);
  int64_t moved_fixed = 0, moved_bnd = 0, off = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v, *p0 = before->xyz + 3 * v;
    int same = !memcmp(p, p0, 3 * sizeof(double));
    if (m->vflag[v] == VM_VERTEX_FIXED) moved_fixed += !same;
    int nface = on_face(p0[0]) + on_face(p0[1]) + on_face(p0[2]);
    if (!nface) continue;
    moved_bnd += !same;
    /* the coordinates that put the vertex on its faces are kept (to
     * rounding: projections are computed in floating point) */
    for (int c = 0; c < 3; c++)
      if (on_face(p0[c]) && fabs(p[c] - p0[c]) > 1e-12) off++;
    /* and it stays inside the cube */
    for (int c = 0; c < 3; c++)
      if (fabs(p[c]) > 0.5 + 1e-12) off++;
  }
  CHECK(moved_fixed == 0, "%s: %lld fixed vertices moved", name, (long long)moved_fixed);
  CHECK(off == 0, "%s: %lld boundary coordinates left their face", name, (long long)off);
  double ratio1 = boundary_edge_ratio(ctx, m);
  if (slip) {
    CHECK(moved_bnd > 0, "%s: boundary vertices slid", name);
    /* crowding by 0.12 sin: edge ratio about 5 on the input; without a
     * twist the optimum is the uniform grid, and sliding gets close */
    if (alpha == 0)
      CHECK(ratio1 < 1.25, "%s: boundary edge ratio %.3f -> %.3f", name, ratio0, ratio1);
    double dist = 1;
    CHECK(vm_volume_slip_distance(s, m, &dist) == VM_OK && dist < 1e-12,
          "%s: distance to the boundary surface %g", name, dist);
  } else {
    CHECK(moved_bnd == 0 && ratio1 == ratio0, "%s: fixed boundary kept", name);
  }
  fprintf(stderr,
          "%-22s M %4lld -> %lld, boundary edge ratio %.3f -> %.3f, phi_min %.3e, "
          "psi_min %.3e, %d+%d+%d iterations\n",
          name, (long long)r.M_init, (long long)r.M_final, ratio0, ratio1, r.phi_min, r.psi_min,
          r.iter_untangle, r.iter_local, r.iter_opt);
  phi = r.phi_min;
  vm_mesh_destroy(&before);
out:
  vm_volume_slip_destroy(&s);
  vm_free(ctx, ref);
  vm_mesh_destroy(&m);
  return phi;
}

/* Bad input: a surface mesh has no volume elements; angles out of range. */
static void bad_input(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  vm_mesh_add_vertex(m, 0, 0, 0, NULL);
  vm_mesh_add_vertex(m, 1, 0, 0, NULL);
  vm_mesh_add_vertex(m, 0, 1, 0, NULL);
  int32_t t[3] = {0, 1, 2};
  vm_mesh_add_element(m, VM_TRI, t);
  vm_volume_slip *s = NULL;
  CHECK(vm_volume_slip_create(ctx, m, 40, 60, &s, NULL) == VM_ERR_ARG && !s &&
            strstr(vm_ctx_error(ctx), "no volume elements"),
        "surface mesh refused: %s", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = 2;
  vm_gen_rotated_cube(ctx, &ro, &m, NULL);
  CHECK(vm_volume_slip_create(ctx, m, 0, 60, &s, NULL) == VM_ERR_ARG && !s, "angle 0 refused");
  CHECK(vm_volume_slip_create(ctx, m, 40, 200, &s, NULL) == VM_ERR_ARG && !s,
        "corner angle 200 refused");
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  slip_case(ctx, "hex, no twist, slip", 0, VM_GEN_HEX, 1);
  double ps = slip_case(ctx, "hex, pi/2, slip", PI / 2, VM_GEN_HEX, 1);
  double pf = slip_case(ctx, "hex, pi/2, fixed", PI / 2, VM_GEN_HEX, 0);
  /* the crowded boundary, once free to slide, no longer pins the worst
   * element (measured: phi_min 8.4e-2 against 2.4e-2 fixed; 5.2e-3 fixed
   * before the optimization after the certifying repair) */
  CHECK(ps > 2 * pf, "slip improves phi_min: %.3e vs %.3e fixed", ps, pf);
  double ts = slip_case(ctx, "tets, pi/2, slip", PI / 2, VM_GEN_TETS, 1);
  CHECK(ts > 1e-2, "tets: phi_min %.3e with slip", ts);
  bad_input(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "leaked %ld allocations", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("slip");
}
