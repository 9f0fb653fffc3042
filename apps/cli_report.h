/* apps/cli_report.h: the --report DIR option of the command-line programs:
 * a report page with pictures (varmesh/report.h), errors on stderr, exit
 * codes. */
#ifndef VARMESH_APPS_CLI_REPORT_H
#define VARMESH_APPS_CLI_REPORT_H

#include "cli.h"
#include "varmesh/quality.h"
#include "varmesh/report.h"

/* Create the report directory and object, and (hist not NULL) an empty
 * convergence history for the run. Returns VM_EXIT_OK, or after an error
 * message VM_EXIT_USAGE (this build has no cairo) or VM_EXIT_INPUT. */
int vm_cli_report_open(const vm_cli *cli, const char *dir, const char *title, vm_report **out,
                       vm_report_history **hist);

/* vm-quality --report: the quality table and pictures of one mesh
 * (vm_report_mesh) and DIR/index.html. field: colours a surface picture
 * (NULL: default). Returns an exit code; "wrote DIR/index.html" on stderr
 * unless quiet. */
int vm_cli_report_quality(const vm_cli *cli, const char *dir, const char *path, const vm_mesh *m,
                          const vm_quality_opts *qo, const char *field);

/* vm-volume --report, after the run: the run's numbers, the convergence
 * plot of `hist`, quality pictures of the mesh before and after, and
 * DIR/index.html (dir as given to vm_cli_report_open). Destroys *r.
 * Returns an exit code. */
struct vm_volume_opts;
struct vm_volume_report;
int vm_cli_report_volume(const vm_cli *cli, vm_report **r, const char *dir, const char *in,
                         const char *out, const vm_mesh *before, const vm_mesh *after,
                         const vm_report_history *hist, const struct vm_volume_opts *o,
                         const struct vm_volume_report *rep);

/* Write DIR/index.html of report *r unless st < 0 (then report the error),
 * destroy *r, and return an exit code. */
int vm_cli_report_finish(const vm_cli *cli, vm_report **r, const char *dir, int st);

/* The stages' --report (vm-surface, vm-prism), after the run: the rows the
 * caller has added (st: their status; < 0 reports that error), then the
 * convergence plot of `hist` (with `caption`) if it has samples, the
 * standard pictures of the result `m` under `label` (vm_report_mesh,
 * corner rule: histograms, slices of volume elements, the surface coloured
 * by `field`, NULL for the default) and DIR/index.html. Destroys *r.
 * Returns an exit code. */
int vm_cli_report_result(const vm_cli *cli, vm_report **r, const char *dir, int st,
                         const char *label, const vm_mesh *m, const char *field,
                         const vm_report_history *hist, const char *caption);

#endif
