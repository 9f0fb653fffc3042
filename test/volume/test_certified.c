/* test/volume/test_certified.c: the volume stage's result is valid to a
 * solver: the rotated cube at pi (n = 12, inner half-size 0.3), untangled by the staged
 * schedule and the certifying repair, has every hex certified det J > 0
 * everywhere (varmesh/jacobian.h), not only its corner tets positive. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "varmesh/jacobian.h"
#include "varmesh/quality.h"
#include "varmesh/rotcube.h"
#include "varmesh/volume.h"
#include "vmtest.h"

static const double PI = 3.14159265358979323846;

/* The schedule vm-volume chooses for hexahedra by default. */
static vm_volume_opts staged_opts(void) {
  vm_volume_opts o = vm_volume_opts_default();
  o.staged = 1;
  o.method = VM_UNTANGLE_FOLDOVER;
  o.eps_inner = 3;
  o.theta_untangle = 0.999;
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
  vm_free(ctx, ref);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  pi_cube(ctx, 12);
  no_repair(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("certified");
}
