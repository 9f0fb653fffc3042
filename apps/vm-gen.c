/* apps/vm-gen.c: write generated meshes: the rotated-cube untangling
 * problem of the paper's Section 6.1 (hexahedra or tetrahedra), and the
 * bundled aircraft surface model. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "varmesh/aircraft.h"
#include "varmesh/shapes.h"
#include "varmesh/rotcube.h"
#include "varmesh/io.h"
#include "varmesh/symmetry.h"

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

typedef struct {
  const char *what, *out;
  vm_rotcube_opts o;
  vm_aircraft_opts ao;
  int level;
  double radius;
  int chordwise, spanwise; /* wing */
  double thickness_ratio;
  int half;
  vm_write_opts wo;
} args;

static int opt_angle(vm_cli *cli, const vm_opt *opt, const char *val, void *a) {
  if (!val || parse_angle(val, &((args *)a)->o.alpha) || !isfinite(((args *)a)->o.alpha))
    return vm_cli_usage_error(cli, "%s expects radians or a multiple of pi", opt->name);
  return VM_EXIT_OK;
}

static int opt_axis(vm_cli *cli, const vm_opt *opt, const char *val, void *a) {
  double *x = ((args *)a)->o.axis;
  if (!val || sscanf(val, "%lf,%lf,%lf", &x[0], &x[1], &x[2]) != 3)
    return vm_cli_usage_error(cli, "%s expects X,Y,Z", opt->name);
  return VM_EXIT_OK;
}

#define A(f) offsetof(args, f)
static const vm_opt opts[] = {
    {"--n", NULL, VM_OPT_INT, A(o.n), "N", "cells per direction (default 8)", .lo = 2, .hi = 1000},
    {"--angle", NULL, VM_OPT_CALL, 0, "A",
     "rotation angle in radians, or a multiple of pi: 'pi/2', '7pi/8'", .fn = opt_angle},
    {"--axis", NULL, VM_OPT_CALL, 0, "X,Y,Z", "rotation axis (default 0,0,1)", .fn = opt_axis},
    {"--inner", NULL, VM_OPT_DOUBLE, A(o.inner), "S", "inner cube half-size (default 1/(2 sqrt 2))",
     .lo = 1e-6, .hi = 0.4999},
    {"--tets", NULL, VM_OPT_FLAG, A(o.cells), NULL, "split every hex into 6 tets",
     .ival = VM_GEN_TETS},
    {"--free-boundary", NULL, VM_OPT_FLAG, A(o.free_boundary), NULL,
     "leave the outer boundary free (for vm-volume --slip-boundary)", .ival = 1},
    {"--mixed", NULL, VM_OPT_FLAG, A(o.cells), NULL,
     "hexes, prisms, pyramids and tets by (i+j+k) mod 4", .ival = VM_GEN_MIXED},
    {"--binary", NULL, VM_OPT_FLAG, A(wo.binary), NULL, "binary output where the format has both",
     .ival = 1},
    {.kind = VM_OPT_HEADING,
     .help =
         "\n"
         "usage: vm-gen aircraft [options] OUT\n"
         "A closed, outward-oriented triangulated aircraft (fuselage, swept wings with\n"
         "NACA sections and sharp trailing edges, stabilizers, fin), nose at x = 0, z up;\n"
         "the project's example model. OUT in any surface or mesh format (.stl, .vmsh, .vtu).\n"},
    {"--resolution", NULL, VM_OPT_INT, A(ao.resolution), "R",
     "1..32, scales every direction (default 4: about 15k triangles)", .lo = 1, .hi = 32},
    {"--length", NULL, VM_OPT_DOUBLE, A(ao.length), "L", "nose to tail (default 15)", .lo = 1e-6,
     .hi = 1e6},
    {"--span", NULL, VM_OPT_DOUBLE, A(ao.span), "S",
     "wing span, 0.35..2.5 times the length (default 0.9 L)", .lo = 1e-6, .hi = 1e6},
    {"--sweep", NULL, VM_OPT_DOUBLE, A(ao.sweep_deg), "D",
     "wing leading-edge sweep in degrees, 0..50 (default 28)", .lo = 0, .hi = 50},
    {"--half", NULL, VM_OPT_FLAG, A(half), NULL,
     "a half model instead: the aircraft cut by its symmetry plane y = 0 (vm_mesh_cut_plane, "
     "the side y >= 0 kept), its open border exactly in the plane, which the mesh names "
     "(attribute symmetry_plane)",
     .ival = 1},
    {"--components", NULL, VM_OPT_FLAG, A(ao.tag_components), NULL,
     "add the int cell field 'component' (0 fuselage, 1-2 wings, 3-4 stabilizers, 5 fin)",
     .ival = 1},
    {.kind = VM_OPT_HEADING,
     .help = "\n"
             "usage: vm-gen sphere [options] OUT\n"
             "A closed, outward-oriented icosphere about the origin (the smooth body of the\n"
             "solver tests: potential flow around it has a known surface pressure).\n"},
    {"--level", NULL, VM_OPT_INT, A(level), "N",
     "subdivisions of the icosahedron, 0..8 (default 3: 1280 triangles)", .lo = 0, .hi = 8},
    {"--radius", NULL, VM_OPT_DOUBLE, A(radius), "R", "radius (default 1)", .lo = 1e-6, .hi = 1e6},
    {"--half", NULL, VM_OPT_FLAG, A(half), NULL,
     "a half model instead: the upper half (z >= 0) of a cube-sphere with 2^(level+1) intervals "
     "along each cube edge (level 3: 1,536 triangles), its open border exactly in the symmetry "
     "plane z = 0",
     .ival = 1},
    {.kind = VM_OPT_HEADING,
     .help = "\n"
             "usage: vm-gen wing [options] OUT\n"
             "An isolated, closed swept wing (ONERA M6 planform: chords 0.806 and 0.455,\n"
             "semispan 1.196 along y, z up) with NACA 00xx sections, a sharp trailing edge and\n"
             "flat root and tip caps, graded chordwise as a CAD mesher grades (cosine\n"
             "spacing): the needles at its trailing edge are what real wing surfaces have.\n"
             "--sweep (default 28) is the leading edge's.\n"},
    {"--chordwise", NULL, VM_OPT_INT, A(chordwise), "N",
     "chordwise intervals per side, cosine-spaced (default 160)", .lo = 4, .hi = 100000},
    {"--spanwise", NULL, VM_OPT_INT, A(spanwise), "N", "spanwise intervals (default 8)", .lo = 1,
     .hi = 100000},
    {"--thickness-ratio", NULL, VM_OPT_DOUBLE, A(thickness_ratio), "T",
     "section thickness / chord (default 0.10)", .lo = 1e-3, .hi = 0.5},
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-gen rotcube [options] OUT\n"
    "The unit cube with n^3 cells whose inner cube is rotated by --angle and fixed\n"
    "with the outer boundary (Section 6.1); every other vertex is left Cartesian,\n"
    "so the mesh is tangled for large angles. Fixed vertices carry the int point\n"
    "field 'fixed' = 1.\n",
    opts,
    "exit: 0 ok, 1 I/O failure, 2 usage\n",
    {A(what), A(out)},
    2,
    NULL};

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-gen");
  args a = {.o = vm_rotcube_opts_default(),
            .ao = vm_aircraft_opts_default(),
            .level = 3,
            .radius = 1,
            .chordwise = 160,
            .spanwise = 8,
            .thickness_ratio = 0.10,
            .wo = vm_write_opts_default()};
  a.ao.span = NAN; /* not given: the default proportions, below */
  vm_mesh *m = NULL;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  int plane = a.what && !strcmp(a.what, "aircraft");
  int sphere = a.what && !strcmp(a.what, "sphere");
  int wing = a.what && !strcmp(a.what, "wing");
  if (!a.what || (strcmp(a.what, "rotcube") && !plane && !sphere && !wing) || !a.out) {
    rc = vm_cli_usage_error(&cli, "expected: vm-gen rotcube|aircraft|sphere|wing [options] OUT");
    goto done;
  }
  if (isnan(a.ao.span)) a.ao.span = 0.9 * a.ao.length;
  if (plane && !(a.ao.span >= 0.35 * a.ao.length && a.ao.span <= 2.5 * a.ao.length)) {
    rc = vm_cli_usage_error(&cli, "--span must be 0.35 to 2.5 times the length");
    goto done;
  }
  int grc;
  if (a.half && !sphere && !plane) {
    rc = vm_cli_usage_error(&cli, "--half is for vm-gen sphere and vm-gen aircraft");
    goto done;
  }
  if (sphere && a.half) {
    grc = vm_mesh_create(cli.ctx, &m);
    if (grc == VM_OK) grc = vm_gen_hemisphere(m, a.radius, 2 << a.level);
    if (grc == VM_OK) grc = vm_mesh_set_symmetry_plane(m, 2, 0);
  } else if (sphere) {
    grc = vm_mesh_create(cli.ctx, &m);
    if (grc == VM_OK) grc = vm_gen_icosphere(m, NULL, a.radius, a.level, 0, NULL);
  } else if (wing) {
    grc = vm_mesh_create(cli.ctx, &m);
    if (grc == VM_OK)
      grc = vm_gen_wing(m, a.chordwise, a.spanwise, a.thickness_ratio, a.ao.sweep_deg);
  } else {
    grc =
        plane ? vm_gen_aircraft(cli.ctx, &a.ao, &m) : vm_gen_rotated_cube(cli.ctx, &a.o, &m, NULL);
    if (grc == VM_OK && plane && a.half && (grc = vm_mesh_cut_plane(m, 1, 0, 1, 0, NULL)) == VM_OK)
      grc = vm_mesh_set_symmetry_plane(m, 1, 0);
  }
  if (grc < 0 || vm_mesh_write(cli.ctx, m, a.out, VM_FMT_AUTO, &a.wo) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
  }
done:
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
