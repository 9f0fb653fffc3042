/* test/volume/test_certified.c: the volume stage's result is valid to a
 * solver: the rotated cube at pi (n = 12, inner half-size 0.3), untangled by the staged
 * schedule and the certifying repair, has every hex certified det J > 0
 * everywhere (varmesh/jacobian.h), not only its corner tets positive. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "varmesh/jacobian.h"
#include "varmesh/quadrature.h"
#include "varmesh/quality.h"
#include "varmesh/rotcube.h"
#include "varmesh/topology.h"
#include "varmesh/volume.h"
#include "twisted_hex.h"
#include "vmtest.h"

static const double PI = 3.14159265358979323846;

/* The schedule vm-volume chooses for hexahedra by default. */
static vm_volume_opts staged_opts(void) {
  vm_volume_opts o = vm_volume_opts_staged();
  CHECK(o.staged && o.method == VM_UNTANGLE_FOLDOVER && o.eps_inner == 3 &&
            o.theta_untangle == 0.999 && o.eps_cap == 1 && o.qi_steps == 1,
        "the staged schedule's options");
  /* a guard against hangs, not a speed test (sanitizer builds on a busy
   * machine are many times slower) */
  o.time_limit = 900;
  return o;
}

static void pi_cube(vm_ctx *ctx, int n) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = n;
  ro.alpha = PI;
  ro.inner = 0.3; /* two free layers around it, as n = 16 has (golden volume-staged) */
  vm_mesh *m = NULL;
  double *ref = NULL;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m, &ref) == VM_OK, "generate");
  vm_mesh *before = NULL;
  vm_mesh_clone(m, &before);
  vm_jac_report jr0;
  vm_mesh_jacobian_certify(m, &jr0, NULL);
  CHECK(jr0.invalid > 0, "the input is tangled (%lld cells certified invalid)",
        (long long)jr0.invalid);
  vm_volume_opts o = staged_opts();
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  CHECK(st == VM_OK && r.valid,
        "n = %d pi: status %d, M %lld, certified invalid %lld, undecided %lld", n, st,
        (long long)r.M_final, (long long)r.cert_invalid, (long long)r.cert_undecided);
  /* independently of the report */
  vm_jac_report jr;
  vm_mesh_jacobian_certify(m, &jr, NULL);
  CHECK(jr.cells == m->ne && jr.invalid == 0 && jr.undecided == 0,
        "certified: %lld invalid, %lld undecided of %lld", (long long)jr.invalid,
        (long long)jr.undecided, (long long)jr.cells);
  CHECK(r.cert_cells == jr.cells && r.cert_invalid == 0 && r.cert_undecided == 0,
        "the report's counts");
  vm_quality q;
  vm_quality_opts qo = {VM_RULE_CORNER, 0};
  vm_mesh_quality(m, &qo, &q);
  CHECK(q.all.inverted_nodes == 0 && q.all.phi_min > 0, "corner tets: M %lld, phi_min %g",
        (long long)q.all.inverted_nodes, q.all.phi_min);
  int64_t moved_fixed = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_FIXED)
      moved_fixed += memcmp(m->xyz + 3 * v, before->xyz + 3 * v, 3 * sizeof(double)) != 0;
  CHECK(moved_fixed == 0, "%lld fixed vertices moved", (long long)moved_fixed);
  CHECK(r.time_certified > 0 && r.time_certified <= r.time_total, "time to certified %.2f of %.2f",
        r.time_certified, r.time_total);
  CHECK(r.cert_bad_init <= 0 || (r.geometric_left >= 0 && r.geometric_left <= r.cert_bad_init),
        "the geometric phase ran: %lld cells at the start, %lld after it",
        (long long)r.cert_bad_init, (long long)r.geometric_left);
  fprintf(stderr,
          "hex n=%d pi: M %lld -> 0, %d + %d local + %d opt + %d repair iterations (%d rounds, "
          "%lld cells not certified when the repair began), phi_min %.3e, certified after "
          "%.2f s, %.2f s in all\n",
          n, (long long)r.M_init, r.iter_untangle, r.iter_local, r.iter_opt, r.iter_repair,
          r.repair_rounds, (long long)r.cert_bad_init, r.phi_min, r.time_certified, r.time_total);
  vm_free(ctx, ref);
  vm_mesh_destroy(&before);
  vm_mesh_destroy(&m);
}

/* The quasi-isometric step of the staged schedule comes after the repair
 * (the path to a certified mesh is the same without it: the same
 * iterations) and keeps every cell certified while it lifts the worst:
 * phi_min at the corners and over the whole of every hex rise. */
static void qi_last(vm_ctx *ctx) {
  vm_volume_report r[2];
  vm_hex_bounds hb[2];
  for (int k = 0; k < 2; k++) {
    vm_rotcube_opts ro = vm_rotcube_opts_default();
    ro.n = 12;
    ro.alpha = PI;
    ro.inner = 0.3;
    vm_mesh *m = NULL;
    CHECK(vm_gen_rotated_cube(ctx, &ro, &m, NULL) == VM_OK, "generate");
    vm_volume_opts o = staged_opts();
    o.qi_steps = k;
    int st = vm_volume_run(ctx, m, NULL, &o, &r[k]);
    vm_jac_report jr;
    vm_mesh_jacobian_certify(m, &jr, NULL);
    CHECK(st == VM_OK && r[k].valid && jr.invalid + jr.undecided == 0,
          "qi %d: status %d, %lld cells not certified", k, st,
          (long long)(jr.invalid + jr.undecided));
    vm_mesh_hex_bounds(m, 1.0 / 12, 0, 0, &hb[k]);
    fprintf(stderr,
            "qi steps %d: %d + %d + %d repair + %d opt iterations, t %.3g; phi_min %.3e at the "
            "corners, [%.3e, %.3e] over the cells\n",
            k, r[k].iter_untangle, r[k].iter_local, r[k].iter_repair, r[k].iter_opt, r[k].t_reached,
            r[k].phi_min, hb[k].phi_lo, hb[k].phi_hi);
    vm_mesh_destroy(&m);
  }
  CHECK(r[0].cert_bad_init > 0, "the repair had cells to certify (%lld)",
        (long long)r[0].cert_bad_init);
  CHECK(r[0].iter_untangle == r[1].iter_untangle && r[0].iter_local == r[1].iter_local &&
            r[0].iter_repair == r[1].iter_repair && r[1].iter_opt > r[0].iter_opt,
        "the same path to certified, then the step");
  CHECK(r[1].t_reached > 0 && r[1].phi_min > 1.2 * r[0].phi_min && hb[1].phi_lo > hb[0].phi_lo,
        "the step lifts phi_min: %.3e -> %.3e (cells %.3e -> %.3e)", r[0].phi_min, r[1].phi_min,
        hb[0].phi_lo, hb[1].phi_lo);
}

/* The repair works on the cells within repair_rings of those not certified
 * only, as a mesh of its own: one round (2 rings, so that the region is not
 * the whole of this small mesh) from m, whose corner tets are all positive
 * but some cells not certified, moves no vertex that has a cell outside
 * that region (bit for bit), and certifies cells (all 143: one round of
 * the Bernstein repair). */
static void repair_region(vm_ctx *ctx, const vm_mesh *m0) {
  vm_mesh *m = NULL;
  CHECK(vm_mesh_clone(m0, &m) == VM_OK, "clone");
  uint8_t *verdict = vm_malloc(ctx, (size_t)m->ne);
  uint8_t *emask = vm_malloc(ctx, (size_t)m->ne);
  uint8_t *vin = vm_malloc(ctx, (size_t)m->nv);
  int64_t *vrp = NULL;
  int32_t *vel = NULL;
  vm_jac_report jr0;
  vm_mesh_jacobian_certify(m, &jr0, verdict);
  CHECK(vm_mesh_vertex_elements(m, &vrp, &vel) == VM_OK, "vertex elements");
  for (int64_t e = 0; e < m->ne; e++) emask[e] = verdict[e] != VM_JAC_VALID;
  const int rings = 2;
  for (int r = 0; r < rings; r++) {
    memset(vin, 0, (size_t)m->nv);
    for (int64_t e = 0; e < m->ne; e++)
      if (emask[e])
        for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++) vin[m->conn[k]] = 1;
    for (int64_t v = 0; v < m->nv; v++)
      if (vin[v])
        for (int64_t k = vrp[v]; k < vrp[v + 1]; k++) emask[vel[k]] = 1;
  }
  int64_t region = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    vin[v] = 1;
    for (int64_t k = vrp[v]; k < vrp[v + 1]; k++) vin[v] &= emask[vel[k]];
  }
  for (int64_t e = 0; e < m->ne; e++) region += emask[e];
  vm_volume_opts o = staged_opts();
  o.opt_iter = 0;
  o.repair_rounds = 1;
  o.repair_rings = rings;
  o.repair_geometric = 0; /* the rounds' region: the geometric phase is the whole mesh's */
  vm_volume_report r;
  vm_volume_run(ctx, m, NULL, &o, &r);
  int64_t moved_out = 0, moved_in = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    int moved = memcmp(m->xyz + 3 * v, m0->xyz + 3 * v, 3 * sizeof(double)) != 0;
    moved_out += moved && !vin[v];
    moved_in += moved && vin[v];
  }
  vm_jac_report jr;
  vm_mesh_jacobian_certify(m, &jr, NULL);
  CHECK(r.repair_rounds == 1 && r.cert_bad_init == jr0.invalid + jr0.undecided,
        "repair region: %d rounds, %lld cells not certified at its start (%lld)", r.repair_rounds,
        (long long)r.cert_bad_init, (long long)(jr0.invalid + jr0.undecided));
  CHECK(moved_out == 0, "repair region: %lld vertices outside the region moved",
        (long long)moved_out);
  CHECK(region < m->ne, "repair region: %lld of %lld cells, not a proper region", (long long)region,
        (long long)m->ne);
  int64_t left = jr.invalid + jr.undecided;
  CHECK(moved_in > 0 && left < r.cert_bad_init,
        "repair region: %lld vertices moved, %lld -> %lld cells not certified", (long long)moved_in,
        (long long)r.cert_bad_init, (long long)left);
  CHECK(r.cert_invalid + r.cert_undecided == left, "repair region: the report's counts");
  fprintf(stderr,
          "repair region: %lld of %lld cells, %lld vertices moved, %lld -> %lld not certified\n",
          (long long)region, (long long)m->ne, (long long)moved_in, (long long)r.cert_bad_init,
          (long long)(jr.invalid + jr.undecided));
  vm_free(ctx, verdict);
  vm_free(ctx, emask);
  vm_free(ctx, vin);
  vm_free(ctx, vrp);
  vm_free(ctx, vel);
  vm_mesh_destroy(&m);
}

/* The repair's geometric phase alone (no rounds after it) certifies every
 * cell of m (corner tets all positive, some cells not certified): the whole
 * mesh untangled under the rule of (24), stopping once every cell is
 * certified; the fixed vertices do not move. */
static void geometric_alone(vm_ctx *ctx, const vm_mesh *m0) {
  vm_mesh *m = NULL;
  CHECK(vm_mesh_clone(m0, &m) == VM_OK, "clone");
  vm_jac_report jr0;
  vm_mesh_jacobian_certify(m, &jr0, NULL);
  vm_volume_opts o = staged_opts();
  o.opt_iter = 0;
  o.repair_rounds = 0;
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  vm_jac_report jr;
  vm_mesh_jacobian_certify(m, &jr, NULL);
  CHECK(st == VM_OK && r.valid && jr.invalid + jr.undecided == 0,
        "geometric phase: status %d, %lld -> %lld cells not certified", st,
        (long long)(jr0.invalid + jr0.undecided), (long long)(jr.invalid + jr.undecided));
  CHECK(r.cert_bad_init == jr0.invalid + jr0.undecided && r.geometric_left == 0 &&
            r.repair_rounds == 0 && r.iter_repair > 0,
        "geometric phase: the report (%lld at the start, %lld left, %d rounds, %d iterations)",
        (long long)r.cert_bad_init, (long long)r.geometric_left, r.repair_rounds, r.iter_repair);
  int64_t moved_fixed = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (m->vflag[v] == VM_VERTEX_FIXED)
      moved_fixed += memcmp(m->xyz + 3 * v, m0->xyz + 3 * v, 3 * sizeof(double)) != 0;
  CHECK(moved_fixed == 0, "geometric phase: %lld fixed vertices moved", (long long)moved_fixed);
  fprintf(stderr, "geometric phase: %lld -> 0 cells not certified in %d iterations, %.2f s\n",
          (long long)r.cert_bad_init, r.iter_repair, r.time_geometric);
  /* without the cap on eps (opts eps_cap), the phase's eps at its own
   * pace (geometric_decay 0.7 per block) and at the other phases' (0.9):
   * certified too, the second in more iterations (with the cap, eps
   * follows |min det| and the decay hardly matters) */
  vm_volume_report rd[2];
  for (int k = 0; k < 2; k++) {
    vm_mesh *m9 = NULL;
    CHECK(vm_mesh_clone(m0, &m9) == VM_OK, "clone");
    o.eps_cap = 0;
    o.geometric_decay = k ? 0.9 : 0.7;
    st = vm_volume_run(ctx, m9, NULL, &o, &rd[k]);
    CHECK(st == VM_OK && rd[k].valid && rd[k].geometric_left == 0,
          "geometric phase, no cap, decay %g: status %d, %lld cells left", o.geometric_decay, st,
          (long long)rd[k].geometric_left);
    fprintf(stderr, "geometric phase, no cap, decay %g: %d iterations, %.2f s\n", o.geometric_decay,
            rd[k].iter_repair, rd[k].time_geometric);
    vm_mesh_destroy(&m9);
  }
  CHECK(rd[1].iter_repair > rd[0].iter_repair,
        "geometric phase without the cap: decay 0.9 took %d iterations, 0.7 %d", rd[1].iter_repair,
        rd[0].iter_repair);
  vm_mesh_destroy(&m);
}

/* repair off: the corner rule's M = 0 is all the stage promises, and the
 * report says whether the cells certify */
static void no_repair(vm_ctx *ctx) {
  vm_rotcube_opts ro = vm_rotcube_opts_default();
  ro.n = 12;
  ro.alpha = PI;
  ro.inner = 0.3; /* two free layers around it, as n = 16 has (golden volume-staged) */
  vm_mesh *m = NULL;
  double *ref = NULL;
  CHECK(vm_gen_rotated_cube(ctx, &ro, &m, &ref) == VM_OK, "generate");
  vm_volume_opts o = staged_opts();
  o.repair = 0;
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  vm_jac_report jr;
  vm_mesh_jacobian_certify(m, &jr, NULL);
  int64_t bad = jr.invalid + jr.undecided;
  CHECK(r.M_final == 0 && r.cert_bad_init == -1, "no repair: M %lld, repair ran (%lld)",
        (long long)r.M_final, (long long)r.cert_bad_init);
  CHECK(r.cert_invalid == jr.invalid && r.cert_undecided == jr.undecided,
        "no repair: the report's counts");
  CHECK(r.valid == (bad == 0) && (st == VM_OK) == (bad == 0),
        "no repair: valid %d, status %d, %lld cells not certified", r.valid, st, (long long)bad);
  fprintf(stderr, "hex n=12 pi without repair: M 0, %lld cells not certified\n", (long long)bad);
  CHECK(bad > 0, "no repair: every cell certified, nothing for the repair to do");
  repair_region(ctx, m);
  geometric_alone(ctx, m);
  vm_free(ctx, ref);
  vm_mesh_destroy(&m);
}

/* The repair's map from the nodes of (24) to the Bernstein coefficients of
 * det J (volume.c, hex_node_coef): with the node order of the rule table,
 * the mean of each coefficient's nodes, as triquadratic Bernstein
 * coefficients, gives det J of the trilinear map of a perturbed cube. */
static int node_coef(int n) {
  int j3 = n & 1, i3 = n >> 1 & 1, k2 = n >> 2 & 1, i2 = n >> 3 & 1, k = n >> 4 & 1, j = n >> 5 & 1;
  return 9 * (i2 + i3) + 3 * (j + j3) + (k + k2);
}

static double det3(const double *E) {
  return E[0] * (E[4] * E[8] - E[5] * E[7]) - E[1] * (E[3] * E[8] - E[5] * E[6]) +
         E[2] * (E[3] * E[7] - E[4] * E[6]);
}

static void bernstein_map(void) {
  /* VTK hex vertex -> unit cube corner */
  static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  double x[24];
  for (int v = 0; v < 8; v++)
    for (int d = 0; d < 3; d++) x[3 * v + d] = corner[v][d] + 0.3 * sin(7.0 * v + 3.0 * d + 1);
  const vm_qrule *R = vm_qrule_get(VM_HEX, VM_RULE_GEOMETRIC);
  double b[27] = {0};
  int cnt[27] = {0};
  for (int n = 0; n < R->nnodes; n++) {
    double E[9];
    vm_qnode_edges(&R->nodes[n], 3, x, E);
    b[node_coef(n)] += det3(E);
    cnt[node_coef(n)]++;
  }
  double err = 0;
  for (int c = 0; c < 27; c++) b[c] /= cnt[c];
  for (int t = 0; t < 27; t++) {
    double p[3] = {0.1 + 0.35 * (t % 3), 0.15 + 0.3 * (t / 3 % 3), 0.05 + 0.4 * (t / 9)};
    /* J of the trilinear map: column d = sum over vertices of x_v dN_v/dp_d */
    double J[9] = {0};
    for (int v = 0; v < 8; v++)
      for (int d = 0; d < 3; d++) {
        double g = 1;
        for (int e = 0; e < 3; e++) {
          double f = corner[v][e] ? p[e] : 1 - p[e];
          if (e == d) f = corner[v][e] ? 1 : -1;
          g *= f;
        }
        for (int r = 0; r < 3; r++) J[3 * r + d] += g * x[3 * v + r];
      }
    double val = 0;
    for (int a = 0; a < 3; a++)
      for (int bb = 0; bb < 3; bb++)
        for (int cc = 0; cc < 3; cc++) {
          double B[3][3];
          for (int e = 0; e < 3; e++) {
            double u = p[e];
            B[e][0] = (1 - u) * (1 - u);
            B[e][1] = 2 * u * (1 - u);
            B[e][2] = u * u;
          }
          val += b[9 * a + 3 * bb + cc] * B[0][a] * B[1][bb] * B[2][cc];
        }
    err = fmax(err, fabs(val - det3(J)));
  }
  CHECK(err < 1e-12, "Bernstein coefficients from the nodes of (24): det J off by %g", err);
}

/* The face-pyramid relief after the optimization: the certified hex of an
 * untangled n = 32 7pi/8 cube whose OpenFOAM centre falls beyond a warped
 * face (test/twisted_hex.h), alone, its vertex 6 free and the
 * others fixed, no optimization iterations: the relief moves vertex 6 so
 * that no face pyramid is wrong, the cell stays certified, the fixed
 * vertices stay bit-identical. */
static void foam_relief(vm_ctx *ctx) {
  vm_mesh *m = NULL;
  CHECK(vm_mesh_create(ctx, &m) == VM_OK && vm_mesh_set_vertices(m, 8) == VM_OK, "mesh");
  memcpy(m->xyz, twisted_hex, sizeof twisted_hex);
  for (int v = 0; v < 8; v++) m->vflag[v] = v == 6 ? VM_VERTEX_FREE : VM_VERTEX_FIXED;
  const int32_t h[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  CHECK(vm_mesh_add_element(m, VM_HEX, h) == VM_OK, "hex");
  CHECK(vm_cell_foam(VM_HEX, m->xyz, NULL) == 1, "before: 1 face pyramid wrong");
  vm_volume_opts o = staged_opts();
  o.opt_iter = 0;
  vm_volume_report r;
  int st = vm_volume_run(ctx, m, NULL, &o, &r);
  int bad = vm_cell_foam(VM_HEX, m->xyz, NULL), same = 1;
  for (int v = 0; v < 8; v++)
    if (v != 6) same &= !memcmp(m->xyz + 3 * v, twisted_hex[v], sizeof twisted_hex[v]);
  CHECK(st == VM_OK && r.valid, "relief: valid (status %d)", st);
  CHECK(bad == 0, "relief: %d face pyramids wrong after it", bad);
  CHECK(vm_jacobian_certify(VM_HEX, m->xyz, 0, NULL) == VM_JAC_VALID, "relief: still certified");
  CHECK(same, "relief: the fixed vertices bit-identical");
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  bernstein_map();
  pi_cube(ctx, 12);
  qi_last(ctx);
  no_repair(ctx);
  foam_relief(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("certified");
}
