/* apps/cli_verify.h: the exact verification of vm-quality --verify, shared by
 * the stages that must check their output before they report success. */
#ifndef VARMESH_APPS_CLI_VERIFY_H
#define VARMESH_APPS_CLI_VERIFY_H

#include "cli.h"
#include "varmesh/mesh.h"

/* Exact checks (volume/src/verify_cgal.cpp): every quadrature simplex of
 * `rule` (VM_RULE_CORNER or VM_RULE_GEOMETRIC) positively oriented, every
 * cell certified valid (varmesh/jacobian.h: det J > 0 everywhere) and, when
 * the mesh has prisms, their outer faces intersecting neither each other nor
 * the wall. `path` names the mesh in messages.
 * Returns VM_EXIT_OK (and, if `text`, prints one "verify: ..." line on
 * `out`), VM_EXIT_CHECK (one line on stderr naming the first bad element or
 * prism pair) or VM_EXIT_INPUT (the check could not run: out of memory,
 * backend error; message on stderr). */
int vm_cli_verify(const vm_cli *cli, const char *path, const vm_mesh *m, int rule, int text,
                  FILE *out);

#endif
