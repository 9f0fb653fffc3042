/* apps/cli_verify.c: vm-quality --verify's exact checks, also run by
 * vm-volume before it reports success. */
#include "cli_verify.h"

#include "varmesh/jacobian.h"
#include "varmesh/quadrature.h"
#include "varmesh/verify.h"

int vm_cli_verify(const vm_cli *cli, const char *path, const vm_mesh *m, int rule, int text,
                  FILE *out) {
  int64_t bn, be, first, ip, wc, fp[2], counts[VM_NTYPES];
  const char *rname = rule == VM_RULE_GEOMETRIC ? "geometric" : "corner";
  if (vm_verify_orientation(m, rule, &bn, &be, &first) < 0) {
    vm_cli_error(cli, "%s", vm_ctx_error(cli->ctx));
    return VM_EXIT_INPUT;
  }
  if (bn > 0) {
    vm_cli_error(cli,
                 "%s: verify: element %lld (%s) has a quadrature simplex (%s rule) that is not "
                 "positively oriented; %lld such simplices in %lld elements (exact test)",
                 path, (long long)first, vm_elem_name(m->etype[first]), rname, (long long)bn,
                 (long long)be);
    return VM_EXIT_CHECK;
  }
  /* valid to a solver: det J > 0 everywhere in every cell, certified from
   * its Bernstein coefficients (the corner simplices do not imply it) */
  vm_jac_report jr;
  if (vm_mesh_jacobian_certify(m, &jr, NULL) < 0) {
    vm_cli_error(cli, "%s", vm_ctx_error(cli->ctx));
    return VM_EXIT_INPUT;
  }
  if (jr.invalid + jr.undecided > 0) {
    vm_cli_error(cli,
                 "%s: verify: element %lld (%s) is not certified valid (det J > 0 everywhere "
                 "in the cell); %lld cells certified invalid, %lld undecided, of %lld",
                 path, (long long)jr.first_bad, vm_elem_name(m->etype[jr.first_bad]),
                 (long long)jr.invalid, (long long)jr.undecided, (long long)jr.cells);
    return VM_EXIT_CHECK;
  }
  vm_mesh_count_types(m, counts);
  if (counts[VM_PRISM]) {
    if (vm_verify_prism_layer(m, &ip, &wc, fp) < 0) {
      vm_cli_error(cli, "%s", vm_ctx_error(cli->ctx));
      return VM_EXIT_INPUT;
    }
    if (ip > 0 || wc > 0) {
      vm_cli_error(cli,
                   "%s: verify: prisms %lld and %lld: %s; %lld intersecting pairs of outer "
                   "faces, %lld outer faces crossing the wall (exact test)",
                   path, (long long)fp[0], (long long)fp[1],
                   ip > 0 ? "outer faces intersect" : "an outer face crosses the wall",
                   (long long)ip, (long long)wc);
      return VM_EXIT_CHECK;
    }
  }
  if (text)
    fprintf(out,
            "verify: every quadrature simplex (%s rule) positively oriented (exact), every cell "
            "certified det J > 0%s\n",
            rname,
            counts[VM_PRISM]
                ? "; prism layer: outer faces intersect neither each other nor the wall"
                : "");
  return VM_EXIT_OK;
}
