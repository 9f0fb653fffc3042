/* apps/cli_report.c: --report DIR for vm-quality, vm-volume, vm-surface and
 * vm-prism. */
#include "cli_report.h"

#include <stdio.h>

#include "varmesh/ctx.h"

int vm_cli_report_open(const vm_cli *cli, const char *dir, const char *title, vm_report **out,
                       vm_report_history **hist) {
  int st = vm_report_create(cli->ctx, dir, title, out);
  if (st >= 0 && hist) st = vm_report_history_create(cli->ctx, hist);
  if (st >= 0) return VM_EXIT_OK;
  vm_cli_error(cli, "%s", vm_ctx_error(cli->ctx));
  return st == VM_ERR_UNSUPPORTED ? VM_EXIT_USAGE : VM_EXIT_INPUT;
}

int vm_cli_report_finish(const vm_cli *cli, vm_report **r, const char *dir, int st) {
  if (st >= 0) st = vm_report_write(*r);
  vm_report_destroy(r);
  if (st < 0) {
    vm_cli_error(cli, "%s", vm_ctx_error(cli->ctx));
    return st == VM_ERR_ARG ? VM_EXIT_USAGE : VM_EXIT_INPUT; /* e.g. no such field */
  }
  if (!cli->quiet) fprintf(stderr, "%s: report in %s/index.html\n", cli->prog, dir);
  return VM_EXIT_OK;
}

int vm_cli_report_quality(const vm_cli *cli, const char *dir, const char *path, const vm_mesh *m,
                          const vm_quality_opts *qo, const char *field) {
  vm_report *r;
  char title[512];
  snprintf(title, sizeof title, "vm-quality: %s", path);
  int rc = vm_cli_report_open(cli, dir, title, &r, NULL);
  if (rc != VM_EXIT_OK) return rc;
  int st = vm_report_heading(r, "input");
  if (st >= 0) st = vm_report_row(r, "file", "%s", path);
  if (st >= 0)
    st = vm_report_row(r, "vertices, elements", "%lld, %lld", (long long)m->nv, (long long)m->ne);
  if (st >= 0) st = vm_report_mesh(r, "", "quality", m, qo, field);
  return vm_cli_report_finish(cli, &r, dir, st);
}

int vm_cli_report_result(const vm_cli *cli, vm_report **r, const char *dir, int st,
                         const char *label, const vm_mesh *m, const char *field,
                         const vm_report_history *hist, const char *caption) {
  vm_quality_opts qo = {VM_RULE_CORNER, 0};
  if (st >= 0 && hist && vm_report_history_count(hist) > 0)
    st = vm_report_convergence(*r, "convergence", caption, hist);
  if (st >= 0) st = vm_report_mesh(*r, "", label, m, &qo, field);
  return vm_cli_report_finish(cli, r, dir, st);
}
