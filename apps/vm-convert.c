/* apps/vm-convert.c: convert a mesh between the formats varmesh reads and
 * writes, saying what the target format cannot carry. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "varmesh/io.h"

static const char usage[] =
    "usage: vm-convert [options] IN OUT\n"
    "Convert a mesh; formats from the extensions (.vmsh .vmsht .vtk .vtu .msh .mesh\n"
    ".stl .obj .off .ply .su2 .cgns) unless forced. SU2 and CGNS need volume cells.\n"
    "  --format F      output format (vmsh, vmsht, vtk, vtu, msh, mesh, stl, obj, off, ply,\n"
    "                  su2, cgns)\n"
    "  --in-format F   input format\n"
    "  --binary        binary output where the format has both (vtk, msh, stl)\n"
    "  --msh22         write Gmsh 2.2 instead of 4.1\n"
    "  --strict        exit 3 if the output format cannot carry everything\n"
    "  -q, --quiet     no warnings\n"
    "  --help, --version\n"
    "exit: 0 ok, 1 bad input or I/O failure, 2 usage, 3 --strict and information lost\n";

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-convert");
  const char *in = NULL, *out = NULL;
  int fin = VM_FMT_AUTO, fout = VM_FMT_AUTO, strict = 0;
  vm_write_opts wo = vm_write_opts_default();
  int rc = VM_EXIT_OK;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (vm_cli_info_option(&cli, a, usage)) {
      goto done;
    } else if (!strcmp(a, "--format") || !strcmp(a, "--in-format")) {
      if (i + 1 >= argc) {
        rc = vm_cli_usage_error(&cli, "%s needs a value", a);
        goto done;
      }
      int f = vm_format_from_name(argv[++i]);
      if (f == VM_FMT_AUTO) {
        rc = vm_cli_usage_error(&cli, "unknown format '%s'", argv[i]);
        goto done;
      }
      if (!strcmp(a, "--format"))
        fout = f;
      else
        fin = f;
    } else if (!strcmp(a, "--binary")) {
      wo.binary = 1;
    } else if (!strcmp(a, "--msh22")) {
      wo.msh_version = 22;
    } else if (!strcmp(a, "--strict")) {
      strict = 1;
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      cli.quiet = 1;
    } else if ((rc = vm_cli_operand(&cli, a, (const char **const[]){&in, &out}, 2)) != VM_EXIT_OK) {
      goto done;
    }
  }
  if (!in || !out) {
    rc = vm_cli_usage_error(&cli, "need IN and OUT");
    goto done;
  }
  if (fout == VM_FMT_AUTO && vm_format_from_path(out) == VM_FMT_AUTO) {
    rc = vm_cli_usage_error(&cli, "%s: cannot tell the output format; use --format", out);
    goto done;
  }
  vm_mesh *m = NULL;
  int st = vm_mesh_read(cli.ctx, in, fin, &m);
  if (st < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  st = vm_mesh_write(cli.ctx, m, out, fout, &wo);
  if (st < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
  } else if (st == VM_WARN_LOSSY && strict) {
    vm_cli_error(&cli, "%s: the output format could not carry everything (see warnings)", out);
    rc = VM_EXIT_CHECK;
  }
  vm_mesh_destroy(&m);
done:
  vm_cli_finish(&cli);
  return rc;
}
