/* apps/vm-convert.c: convert a mesh between the formats varmesh reads and
 * writes, saying what the target format cannot carry. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "varmesh/io.h"

typedef struct {
  const char *in, *out;
  int fin, fout, strict;
  vm_write_opts wo;
} args;

#define A(f) offsetof(args, f)
static const vm_opt opts[] = {
    {"--format", NULL, VM_OPT_CALL, A(fout), "F",
     "output format (vmsh, vmsht, vtk, vtu, msh, mesh, stl, obj, off, ply, su2, cgns, foam)",
     .fn = vm_cli_opt_format, .error = "needs a value"},
    {"--in-format", NULL, VM_OPT_CALL, A(fin), "F", "input format", .fn = vm_cli_opt_format,
     .error = "needs a value"},
    {"--binary", NULL, VM_OPT_FLAG, A(wo.binary), NULL,
     "binary output where the format has both (vtk, msh, stl, ply, foam)", .ival = 1},
    {"--msh22", NULL, VM_OPT_FLAG, A(wo.msh_version), NULL, "write Gmsh 2.2 instead of 4.1",
     .ival = 22},
    {"--strict", NULL, VM_OPT_FLAG, A(strict), NULL,
     "exit 3 if the output format cannot carry everything", .ival = 1},
    VM_CLI_OPT_QUIET("no warnings"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-convert [options] IN OUT\n"
    "Convert a mesh; formats from the extensions (.vmsh .vmsht .vtk .vtu .msh .mesh\n"
    ".stl .obj .off .ply .su2 .cgns .foam) unless forced. SU2 and CGNS take volume\n"
    "meshes and surface meshes (triangles and quadrilaterals in 3D). OpenFOAM (.foam\n"
    "or --format foam, write only): OUT is a case directory; OUT/constant/polyMesh\n"
    "is written (replaced in an existing case, whose other files stay).\n",
    opts,
    "exit: 0 ok, 1 bad input or I/O failure, 2 usage, 3 --strict and information lost\n",
    {A(in), A(out)},
    2,
    "need IN and OUT"};

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-convert");
  args a = {.fin = VM_FMT_AUTO, .fout = VM_FMT_AUTO, .wo = vm_write_opts_default()};
  vm_mesh *m = NULL;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  if (a.fout == VM_FMT_AUTO && vm_format_from_path(a.out) == VM_FMT_AUTO) {
    rc = vm_cli_usage_error(&cli, "%s: cannot tell the output format; use --format", a.out);
    goto done;
  }
  int st = vm_mesh_read(cli.ctx, a.in, a.fin, &m);
  if (st >= 0) st = vm_mesh_write(cli.ctx, m, a.out, a.fout, &a.wo);
  if (st < 0) {
    rc = vm_cli_input_error(&cli, NULL);
  } else if (st == VM_WARN_LOSSY && a.strict) {
    vm_cli_error(&cli, "%s: the output format could not carry everything (see warnings)", a.out);
    rc = VM_EXIT_CHECK;
  }
done:
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
