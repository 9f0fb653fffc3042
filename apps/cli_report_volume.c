/* apps/cli_report_volume.c: vm-volume's --report page (the run's numbers,
 * convergence, quality before and after). */
#include "cli_report.h"
#include "varmesh/volume.h"

int vm_cli_report_volume(const vm_cli *cli, vm_report **r, const char *dir, const char *in,
                         const char *out, const vm_mesh *before, const vm_mesh *after,
                         const vm_report_history *hist, const struct vm_volume_opts *o,
                         const struct vm_volume_report *rep) {
  vm_report *rp = *r;
  int st = vm_report_heading(rp, "run");
  if (st >= 0) st = vm_report_row(rp, "input, output", "%s, %s", in, out);
  if (st >= 0)
    st = vm_report_row(rp, "vertices, elements, quadrature simplices", "%lld, %lld, %lld",
                       (long long)after->nv, (long long)after->ne, (long long)rep->nodes);
  if (st >= 0)
    st = vm_report_row(rp, "untangling method, rule", "%s, %s", vm_untangle_method_name(o->method),
                       o->rule == VM_RULE_GEOMETRIC ? "geometric" : "corner");
  if (st >= 0)
    st = vm_report_row(rp, "M: start, max, end", "%lld, %lld, %lld", (long long)rep->M_init,
                       (long long)rep->M_max, (long long)rep->M_final);
  if (st >= 0)
    st = vm_report_row(rp, "iterations: untangling, local, optimization", "%d, %d, %d",
                       rep->iter_untangle, rep->iter_local, rep->iter_opt);
  if (st >= 0)
    st = vm_report_row(rp, "time: untangled after, total", "%.2f s, %.2f s", rep->time_untangle,
                       rep->time_total);
  if (st >= 0) st = vm_report_row(rp, "valid (M = 0)", "%s", rep->valid ? "yes" : "no");
  if (st >= 0)
    st = vm_report_convergence(rp, "convergence",
                               "Convergence of the run: M (inverted quadrature simplices, log "
                               "scale, 0 on the bottom edge), the functional F and epsilon per "
                               "iteration; dashed lines separate the phases.",
                               hist);
  vm_quality_opts qo = {o->rule == VM_RULE_GEOMETRIC ? VM_RULE_GEOMETRIC : VM_RULE_CORNER,
                        o->target_size};
  if (st >= 0) st = vm_report_mesh(rp, "before-", "before", before, &qo, NULL);
  if (st >= 0) st = vm_report_mesh(rp, "after-", "after", after, &qo, NULL);
  return vm_cli_report_finish(cli, r, dir, st);
}
