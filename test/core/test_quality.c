/* test/core/test_quality.c: quality figures, boundary extraction and the
 * rotated-cube generator on shapes with known answers. */
#include <math.h>
#include <string.h>

#include "varmesh/jacobian.h"
#include "varmesh/rotcube.h"
#include "varmesh/quality.h"
#include "varmesh/quadrature.h"
#include "varmesh/topology.h"
#include "twisted_hex.h"
#include "vmtest.h"

/* One ideal element of each type, scaled by h: phi = psi = sj = 1, M = 0. */
static void ideal_elements(vm_ctx *ctx) {
  for (int t = 0; t < VM_NTYPES; t++) {
    vm_mesh *m;
    vm_mesh_create(ctx, &m);
    int k = vm_elem_nverts(t);
    double ref[VM_MAX_ELEM_VERTS * 3];
    vm_elem_ideal(t, ref);
    vm_mesh_set_vertices(m, k);
    const double h = 0.3;
    for (int i = 0; i < 3 * k; i++) m->xyz[i] = h * ref[i] + 1.0;
    if (vm_elem_dim(t) == 2) {
      m->dim = 2;
      for (int i = 0; i < k; i++) m->xyz[3 * i + 2] = 0;
    }
    int32_t c[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    vm_mesh_add_element(m, t, c);
    vm_quality q;
    vm_quality_opts o = {VM_RULE_GEOMETRIC, h};
    CHECK(vm_mesh_quality(m, &o, &q) == VM_OK, "quality %s", vm_elem_name(t));
    CHECK(q.all.inverted_nodes == 0, "%s: M = %lld", vm_elem_name(t),
          (long long)q.all.inverted_nodes);
    CHECK_NEAR(q.all.phi_min, 1.0, 1e-12, vm_elem_name(t));
    CHECK_NEAR(q.all.psi_min, 1.0, 1e-12, vm_elem_name(t));
    CHECK_NEAR(q.all.sj_min, 1.0, 1e-12, vm_elem_name(t));
    /* mirror the element: every node inverted, sj = -1 */
    for (int i = 0; i < k; i++) m->xyz[3 * i] = -m->xyz[3 * i];
    CHECK(vm_mesh_quality(m, &o, &q) == VM_OK, "quality");
    CHECK(q.all.inverted_nodes == q.all.nodes && q.all.inverted_elems == 1,
          "%s mirrored: M = %lld of %lld", vm_elem_name(t), (long long)q.all.inverted_nodes,
          (long long)q.all.nodes);
    CHECK_NEAR(q.all.sj_min, -1.0, 1e-12, vm_elem_name(t));
    vm_mesh_destroy(&m);
  }
}

static void rotated_cube(vm_ctx *ctx) {
  vm_rotcube_opts o = vm_rotcube_opts_default();
  o.n = 8;
  for (int tets = 0; tets < 2; tets++) {
    o.cells = tets ? VM_GEN_TETS : VM_GEN_HEX;
    o.alpha = 0;
    vm_mesh *m;
    double *ref;
    CHECK(vm_gen_rotated_cube(ctx, &o, &m, &ref) == VM_OK, "generate");
    CHECK(m->nv == 729 && m->ne == (tets ? 6 * 512 : 512), "sizes %lld %lld", (long long)m->nv,
          (long long)m->ne);
    CHECK(memcmp(m->xyz, ref, sizeof(double) * 3 * 729) == 0, "alpha 0 is Cartesian");
    /* fixed: 9^3 - 7^3 boundary + inner vertices with |x| < 0.3536: i in 2..6 => 3^3? */
    int64_t nfix = 0;
    for (int64_t v = 0; v < m->nv; v++) nfix += m->vflag[v] == VM_VERTEX_FIXED;
    /* coordinates -0.5 + i/8 strictly inside 0.35355: |x| in {0, .125, .25} => 5 per axis */
    CHECK(nfix == 729 - 343 + 125, "fixed %lld", (long long)nfix);
    vm_quality q;
    vm_quality_opts qo = {VM_RULE_CORNER, 1.0 / 8};
    vm_mesh_quality(m, &qo, &q);
    CHECK(q.all.inverted_nodes == 0, "untangled at alpha 0");
    CHECK(q.foam_neg_volumes == 0 && q.foam_pyramid_errors == 0,
          "OpenFOAM at alpha 0: %lld negative volumes, %lld face pyramids",
          (long long)q.foam_neg_volumes, (long long)q.foam_pyramid_errors);
    if (!tets) {
      CHECK_NEAR(q.all.phi_min, 1.0, 1e-12, "phi at alpha 0");
      CHECK_NEAR(q.all.psi_min, 1.0, 1e-12, "psi at alpha 0");
    }
    int64_t nb, nbv;
    vm_mesh_boundary(m, &nb, NULL, NULL, NULL, NULL);
    CHECK(nb == (tets ? 2 : 1) * 6 * 64, "boundary faces %lld", (long long)nb);
    vm_mesh *c;
    vm_mesh_clone(m, &c);
    memset(c->vflag, 0, (size_t)c->nv);
    vm_mesh_mark_boundary(c, VM_VERTEX_FIXED, &nbv);
    CHECK(nbv == 729 - 343, "boundary vertices %lld", (long long)nbv);
    vm_mesh_destroy(&c);
    vm_free(ctx, ref);
    vm_mesh_destroy(&m);
    /* pi/2: the generator's whole point is a tangled mesh */
    o.alpha = 3.14159265358979323846 / 2;
    vm_gen_rotated_cube(ctx, &o, &m, NULL);
    vm_mesh_quality(m, &qo, &q);
    CHECK(q.all.inverted_nodes > 0 && q.all.inverted_elems > 0, "tangled at pi/2: M = %lld",
          (long long)q.all.inverted_nodes);
    CHECK(q.foam_pyramid_errors > 0, "OpenFOAM at pi/2: face pyramids wrong");
    fprintf(stderr, "rotcube n=8 pi/2 %s: M = %lld, inverted elements %lld\n",
            tets ? "tets" : "hexes", (long long)q.all.inverted_nodes,
            (long long)q.all.inverted_elems);
    vm_mesh_destroy(&m);
  }
}

/* The mixed cube: all four 3D types, valid at alpha 0, tangled at pi. */
static void mixed_cube(vm_ctx *ctx) {
  vm_rotcube_opts o = vm_rotcube_opts_default();
  o.n = 8;
  o.cells = VM_GEN_MIXED;
  for (int tangled = 0; tangled < 2; tangled++) {
    o.alpha = tangled ? 3.14159265358979323846 : 0;
    vm_mesh *m;
    double *ref;
    CHECK(vm_gen_rotated_cube(ctx, &o, &m, &ref) == VM_OK, "mixed");
    int64_t cnt[VM_NTYPES];
    vm_mesh_count_types(m, cnt);
    CHECK(cnt[VM_HEX] == 128 && cnt[VM_PRISM] == 256 && cnt[VM_PYRAMID] == 6 * 128 &&
              cnt[VM_TET] == 6 * 128,
          "mixed counts %lld %lld %lld %lld", (long long)cnt[VM_HEX], (long long)cnt[VM_PRISM],
          (long long)cnt[VM_PYRAMID], (long long)cnt[VM_TET]);
    CHECK(m->nv == 729 + 128, "mixed vertices %lld", (long long)m->nv);
    CHECK(vm_mesh_check(m) == VM_OK, "mixed invariants");
    vm_quality q;
    vm_quality_opts qo = {VM_RULE_CORNER, 1.0 / 8};
    vm_mesh_quality(m, &qo, &q);
    if (tangled)
      CHECK(q.all.inverted_nodes > 0, "mixed tangled at pi");
    else
      CHECK(q.all.inverted_nodes == 0 && q.all.sj_min > 0.4, "mixed valid at 0: M %lld sj %g",
            (long long)q.all.inverted_nodes, q.all.sj_min);
    vm_free(ctx, ref);
    vm_mesh_destroy(&m);
  }
}

static void adjacency(vm_ctx *ctx) {
  vm_rotcube_opts o = vm_rotcube_opts_default();
  o.n = 3;
  vm_mesh *m;
  vm_gen_rotated_cube(ctx, &o, &m, NULL);
  int64_t *rp;
  int32_t *el;
  CHECK(vm_mesh_vertex_elements(m, &rp, &el) == VM_OK, "adjacency");
  /* corner vertex: 1 hex; centre-ish vertex (1,1,1): 8 hexes */
  CHECK(rp[1] - rp[0] == 1, "corner valence %lld", (long long)(rp[1] - rp[0]));
  int64_t v = (1 * 4 + 1) * 4 + 1;
  CHECK(rp[v + 1] - rp[v] == 8, "inner valence %lld", (long long)(rp[v + 1] - rp[v]));
  for (int64_t k = rp[v]; k + 1 < rp[v + 1]; k++) CHECK(el[k] < el[k + 1], "sorted");
  vm_free(ctx, rp);
  vm_free(ctx, el);
  vm_mesh_destroy(&m);
}

/* The figures do not depend on units: a valid mesh scaled by 1e-120 or
 * 1e120 stays valid with the same phi_min (every det underflowed to 0 at
 * 1e-120: "inverted"); a target_size field with a value that is not a
 * positive finite size is refused, not measured (-1, NaN and 1e200 made a
 * valid mesh "inverted"). */
static void units(vm_ctx *ctx) {
  vm_rotcube_opts o = vm_rotcube_opts_default();
  o.n = 4;
  o.alpha = 0.3;
  o.cells = VM_GEN_MIXED;
  vm_mesh *m = NULL;
  vm_gen_rotated_cube(ctx, &o, &m, NULL);
  vm_quality q0, q;
  vm_mesh_quality(m, NULL, &q0);
  CHECK(q0.all.inverted_nodes == 0, "units: the mixed cube at 0.3 is valid (%lld)",
        (long long)q0.all.inverted_nodes);
  double scales[2] = {1e-120, 1e120};
  for (int k = 0; k < 2; k++) {
    vm_mesh *c = NULL;
    vm_mesh_clone(m, &c);
    for (int64_t i = 0; i < 3 * c->nv; i++) c->xyz[i] *= scales[k];
    int st = vm_mesh_quality(c, NULL, &q);
    CHECK(st == VM_OK && q.all.inverted_nodes == 0, "units: scaled by %g: %lld inverted nodes",
          scales[k], (long long)q.all.inverted_nodes);
    CHECK(fabs(q.all.phi_min - q0.all.phi_min) <= 1e-12 * fabs(q0.all.phi_min) &&
              fabs(q.all.sj_min - q0.all.sj_min) <= 1e-12,
          "units: scaled by %g: phi_min %.17g (%.17g), sj_min %.17g (%.17g)", scales[k],
          q.all.phi_min, q0.all.phi_min, q.all.sj_min, q0.all.sj_min);
    vm_mesh_destroy(&c);
  }
  double bad[3] = {-1, NAN, 1e300 * 10};
  for (int k = 0; k < 3; k++) {
    vm_field *f;
    vm_mesh_add_field(m, "target_size", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
    for (int64_t e = 0; e < m->ne; e++) ((double *)f->data)[e] = e == 5 ? bad[k] : 0.2;
    int st = vm_mesh_quality(m, NULL, &q);
    CHECK(st == VM_ERR_FORMAT && strstr(vm_ctx_error(ctx), "element 5: target_size"),
          "units: target_size %g refused: %d %s", bad[k], st, vm_ctx_error(ctx));
  }
  vm_mesh_destroy(&m);
}

/* OpenFOAM's cell geometry (vm_cell_foam): the ideal cells' volumes, every
 * face pyramid wrong on a mirrored cell, and a certified-valid hex that
 * checkMesh still fails (a thin twisted cell of an untangled rotated cube
 * whose centre falls outside one face's plane). */
static void foam_cells(void) {
  const double vol[VM_NTYPES] = {[VM_TET] = 1 / (6 * sqrt(2.0)),
                                 [VM_PYRAMID] = sqrt(2.0) / 6,
                                 [VM_PRISM] = sqrt(3.0) / 4,
                                 [VM_HEX] = 1};
  const double h = 0.3, shift[3] = {5, -2, 7};
  for (int t = VM_TET; t < VM_NTYPES; t++) {
    double x[VM_MAX_ELEM_VERTS * 3], v;
    int k = vm_elem_nverts(t), fv[6][4], nfv[6], nf = vm_elem_faces(t, fv, nfv);
    vm_elem_ideal(t, x);
    for (int i = 0; i < 3 * k; i++) x[i] = h * x[i] + shift[i % 3];
    int bad = vm_cell_foam(t, x, &v);
    CHECK(bad == 0, "%s: %d face pyramids wrong on the ideal cell", vm_elem_name(t), bad);
    CHECK_NEAR(v, vol[t] * h * h * h, 1e-12, vm_elem_name(t));
    for (int i = 0; i < k; i++) x[3 * i] = -x[3 * i];
    bad = vm_cell_foam(t, x, &v);
    CHECK(bad == nf && v < 0, "%s mirrored: %d of %d face pyramids wrong, volume %g",
          vm_elem_name(t), bad, nf, v);
  }
  CHECK(vm_cell_foam(VM_QUAD, NULL, NULL) == -1, "a quad is not a 3D cell");
  double v;
  CHECK(vm_jacobian_certify(VM_HEX, twisted_hex[0], 6, NULL) == VM_JAC_VALID,
        "the twisted hex is certified valid");
  CHECK(vm_cell_foam(VM_HEX, twisted_hex[0], &v) == 1 && v > 0,
        "the twisted hex: 1 face pyramid wrong, volume %g > 0", v);
}

/* OpenFOAM's face measures and cell determinant (vm_foam_*), known
 * answers: the face x = 1 of the unit square [1] x [0,1]^2 between centres
 * (0.5, 0.5, 0.5) and (1.5, 0.5, 0.5) is orthogonal, unskewed, weight 0.5;
 * with the neighbour's centre at (1.5, 1.5, 0.5) the angle is 45 degrees
 * and the line meets the face 0.5 off its centre, its extent that way 0.5:
 * skewness 1; a neighbour three times as far from the face: weight 1/4.
 * A box a x b x c with every face internal: determinant (abc)^4 / ((bc +
 * ca + ab)/3)^6, 1 for the cube. */
static void foam_faces(void) {
  const double y[12] = {1, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1};
  const double cp[3] = {0.5, 0.5, 0.5}, cn[3] = {1.5, 0.5, 0.5}, cs[3] = {1.5, 1.5, 0.5},
               cf[3] = {2.5, 0.5, 0.5};
  double c[3], s[3];
  vm_foam_face(y, 4, c, s);
  CHECK_NEAR(vm_foam_ortho_cos(c, s, cp, cn), 1, 1e-14, "orthogonal face: cos 1");
  CHECK_NEAR(vm_foam_ortho_cos(c, s, cn, cp), 1, 1e-14, "from the other side: cos 1");
  CHECK_NEAR(vm_foam_skew(y, 4, c, s, cp, cn), 0, 1e-14, "orthogonal face: skewness 0");
  CHECK_NEAR(vm_foam_weight(c, s, cp, cn), 0.5, 1e-14, "centred: weight 0.5");
  CHECK_NEAR(vm_foam_ortho_cos(c, s, cp, cs), sqrt(0.5), 1e-14, "45 degrees");
  CHECK_NEAR(vm_foam_skew(y, 4, c, s, cp, cs), 1, 1e-14, "skewness 1");
  CHECK_NEAR(vm_foam_weight(c, s, cp, cf), 0.25, 1e-14, "weight 1/4");
  const double dims[3][3] = {{1, 1, 1}, {1, 1, 0.1}, {2, 0.5, 0.01}};
  for (int k = 0; k < 3; k++) {
    double a = dims[k][0], b = dims[k][1], h = dims[k][2];
    double S[6][3] = {{b * h, 0, 0},  {-b * h, 0, 0}, {0, a * h, 0},
                      {0, -a * h, 0}, {0, 0, a * b},  {0, 0, -a * b}};
    double avg = (b * h + a * h + a * b) / 3;
    double want = pow(a * b * h, 4) / pow(avg, 6);
    CHECK_NEAR(vm_foam_cell_determinant(6, (const double(*)[3])S) / want, 1, 1e-12,
               "box determinant");
  }
  CHECK(vm_foam_cell_determinant(0, NULL) == 0, "no internal face: determinant 0");
}

/* A prism on an equilateral triangle whose top is the bottom turned by
 * theta about the axis and lifted by h: every corner tet has det 2 A h > 0
 * whatever theta (the top vertex adds only its height), but a tet of two
 * bottom and two top vertices has det proportional to h sin(60 deg -
 * theta) (three of them) or h sin(60 deg + theta) (the other three): its
 * two horizontal edges' cross product is vertical. Three reach 0 at a
 * twist of exactly 60 degrees either way, for any h. So the twist
 * 59 degrees: positive in all six 3-tet splits; 61: 3 tets negative,
 * while the corner rule (and a check of the corner tets) sees nothing. */
static void prism_twist(vm_ctx *ctx, double theta_deg, double h, int want) {
  double x[18], th = theta_deg * 3.14159265358979323846 / 180;
  for (int i = 0; i < 3; i++) {
    double a = 2 * 3.14159265358979323846 * i / 3;
    x[3 * i] = cos(a), x[3 * i + 1] = sin(a), x[3 * i + 2] = 0;
    x[9 + 3 * i] = cos(a + th), x[9 + 3 * i + 1] = sin(a + th), x[9 + 3 * i + 2] = h;
  }
  double q[6];
  int bad = vm_prism_split_check(x, q);
  CHECK(bad == want, "twist %g deg, h %g: %d split tets not positive, want %d", theta_deg, h, bad,
        want);
  /* the mesh figure: the corner rule sees no inverted node, the split
   * count sees the prism */
  vm_mesh *m = NULL;
  vm_mesh_create(ctx, &m);
  vm_mesh_set_vertices(m, 6);
  memcpy(m->xyz, x, sizeof x);
  vm_mesh_set_elements(m, 1, 6);
  m->etype[0] = VM_PRISM;
  for (int i = 0; i < 6; i++) m->conn[i] = i;
  m->eoff[1] = 6;
  vm_quality Q;
  CHECK(vm_mesh_quality(m, NULL, &Q) == 0, "quality");
  CHECK(Q.all.inverted_nodes == 0, "twist %g: %lld corner nodes inverted", theta_deg,
        (long long)Q.all.inverted_nodes);
  CHECK(Q.prism_split_negative == (want > 0), "twist %g: split negative %lld", theta_deg,
        (long long)Q.prism_split_negative);
  vm_mesh_destroy(&m);
}

static void prism_splits(vm_ctx *ctx) {
  /* the right prism on the unit right triangle: tet (0, 1, 5, 4) has edges
   * (1,0,0), (0,1,1), (1,0,1): det 1, lengths 1, sqrt 2, sqrt 2 */
  const double right[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  double q[6];
  CHECK(vm_prism_split_check(right, q) == 0, "the right prism");
  CHECK_NEAR(q[0], 0.5, 1e-15, "right prism: tet (0, 1, 5, 4)");
  for (int j = 0; j < 6; j++) CHECK(q[j] > 0.25, "right prism: split tet %d q %g", j, q[j]);
  const double hs[3] = {1e-4, 0.1, 10};
  for (int i = 0; i < 3; i++) {
    prism_twist(ctx, 0, hs[i], 0);
    prism_twist(ctx, 59, hs[i], 0);
    prism_twist(ctx, -59, hs[i], 0);
    prism_twist(ctx, 61, hs[i], 3);
    prism_twist(ctx, -61, hs[i], 3);
    prism_twist(ctx, 110, hs[i], 3);
  }
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  long live0 = vm_ctx_alloc_live(ctx);
  ideal_elements(ctx);
  rotated_cube(ctx);
  mixed_cube(ctx);
  adjacency(ctx);
  units(ctx);
  foam_cells();
  foam_faces();
  prism_splits(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leak: %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  vm_ctx_destroy(&ctx);
  return vmtest_end("quality");
}
