/* apps/vm-gen.c: write generated meshes: the rotated-cube untangling
 * problem of the paper's Section 6.1 (hexahedra or tetrahedra), and the
 * bundled aircraft surface model. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "varmesh/aircraft.h"
#include "varmesh/rotcube.h"
#include "varmesh/io.h"

static const char usage[] =
    "usage: vm-gen rotcube [options] OUT\n"
    "The unit cube with n^3 cells whose inner cube is rotated by --angle and fixed\n"
    "with the outer boundary (Section 6.1); every other vertex is left Cartesian,\n"
    "so the mesh is tangled for large angles. Fixed vertices carry the int point\n"
    "field 'fixed' = 1.\n"
    "  --n N           cells per direction (default 8)\n"
    "  --angle A       rotation angle in radians, or a multiple of pi: 'pi/2', '7pi/8'\n"
    "  --axis X,Y,Z    rotation axis (default 0,0,1)\n"
    "  --inner S       inner cube half-size (default 1/(2 sqrt 2))\n"
    "  --tets          split every hex into 6 tets\n"
    "  --free-boundary leave the outer boundary free (for vm-volume --slip-boundary)\n"
    "  --mixed         hexes, prisms, pyramids and tets by (i+j+k) mod 4\n"
    "  --binary        binary output where the format has both\n"
    "  --help, --version\n"
    "\n"
    "usage: vm-gen aircraft [options] OUT\n"
    "A closed, outward-oriented triangulated aircraft (fuselage, swept wings with\n"
    "NACA sections and sharp trailing edges, stabilizers, fin), nose at x = 0, z up;\n"
    "the project's example model. OUT in any surface or mesh format (.stl, .vmsh, .vtu).\n"
    "  --resolution R  1..32, scales every direction (default 4: about 15k triangles)\n"
    "  --length L      nose to tail (default 15)\n"
    "  --span S        wing span, 0.35..2.5 times the length (default 0.9 L)\n"
    "  --sweep D       wing leading-edge sweep in degrees, 0..50 (default 28)\n"
    "  --components    add the int cell field 'component' (0 fuselage, 1-2 wings,\n"
    "                  3-4 stabilizers, 5 fin)\n"
    "exit: 0 ok, 1 I/O failure, 2 usage\n";

/* "pi", "pi/2", "7pi/8", "3*pi/8", or a plain number. */
static int parse_angle(const char *s, double *out) {
  double num = 1, den = 1;
  char *e;
  const char *p = strstr(s, "pi");
  if (!p) {
    *out = strtod(s, &e);
    return !*s || *e;
  }
  if (p != s) {
    num = strtod(s, &e);
    if (e == s || (e != p && !(*e == '*' && e + 1 == p))) return 1;
  }
  p += 2;
  if (*p == '/') {
    den = strtod(p + 1, &e);
    if (*e || den == 0) return 1;
  } else if (*p) {
    return 1;
  }
  *out = num * 3.14159265358979323846 / den;
  return 0;
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-gen");
  vm_rotcube_opts o = vm_rotcube_opts_default();
  vm_aircraft_opts ao = vm_aircraft_opts_default();
  int span_given = 0;
  vm_write_opts wo = vm_write_opts_default();
  const char *what = NULL, *out = NULL;
  int rc = VM_EXIT_OK;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
    long n;
    if (vm_cli_info_option(&cli, a, usage)) {
      goto done;
    } else if (!strcmp(a, "--n")) {
      i++;
      if (vm_cli_int(&cli, a, val, 2, 1000, &n)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      o.n = (int)n;
    } else if (!strcmp(a, "--angle")) {
      i++;
      if (!val || parse_angle(val, &o.alpha)) {
        rc = vm_cli_usage_error(&cli, "--angle expects radians or a multiple of pi");
        goto done;
      }
    } else if (!strcmp(a, "--axis")) {
      i++;
      if (!val || sscanf(val, "%lf,%lf,%lf", &o.axis[0], &o.axis[1], &o.axis[2]) != 3) {
        rc = vm_cli_usage_error(&cli, "--axis expects X,Y,Z");
        goto done;
      }
    } else if (!strcmp(a, "--inner")) {
      i++;
      if (vm_cli_double(&cli, a, val, 1e-6, 0.4999, &o.inner)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
    } else if (!strcmp(a, "--tets")) {
      o.cells = VM_GEN_TETS;
    } else if (!strcmp(a, "--free-boundary")) {
      o.free_boundary = 1;
    } else if (!strcmp(a, "--mixed")) {
      o.cells = VM_GEN_MIXED;
    } else if (!strcmp(a, "--binary")) {
      wo.binary = 1;
    } else if (!strcmp(a, "--resolution")) {
      i++;
      if (vm_cli_int(&cli, a, val, 1, 32, &n)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
      ao.resolution = (int)n;
    } else if (!strcmp(a, "--length") || !strcmp(a, "--span") || !strcmp(a, "--sweep")) {
      int sweep = !strcmp(a, "--sweep");
      double *dst = sweep ? &ao.sweep_deg : !strcmp(a, "--span") ? &ao.span : &ao.length;
      span_given |= dst == &ao.span;
      i++;
      if (vm_cli_double(&cli, a, val, sweep ? 0 : 1e-6, sweep ? 50 : 1e6, dst)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
    } else if (!strcmp(a, "--components")) {
      ao.tag_components = 1;
    } else if ((rc = vm_cli_operand(&cli, a, (const char **const[]){&what, &out}, 2)) != VM_EXIT_OK) {
      goto done;
    }
  }
  int plane = what && !strcmp(what, "aircraft");
  if (!what || (strcmp(what, "rotcube") && !plane) || !out) {
    rc = vm_cli_usage_error(&cli, "expected: vm-gen rotcube|aircraft [options] OUT");
    goto done;
  }
  if (plane && !span_given) ao.span = 0.9 * ao.length; /* the default proportions */
  if (plane && !(ao.span >= 0.35 * ao.length && ao.span <= 2.5 * ao.length)) {
    rc = vm_cli_usage_error(&cli, "--span must be 0.35 to 2.5 times the length");
    goto done;
  }
  vm_mesh *m = NULL;
  int grc = plane ? vm_gen_aircraft(cli.ctx, &ao, &m) : vm_gen_rotated_cube(cli.ctx, &o, &m, NULL);
  if (grc < 0 || vm_mesh_write(cli.ctx, m, out, VM_FMT_AUTO, &wo) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
  }
  vm_mesh_destroy(&m);
done:
  vm_cli_finish(&cli);
  return rc;
}
