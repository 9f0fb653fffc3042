/* apps/vm-fill.c: the fill stage: tetrahedra from a prism layer's outer
 * surface (or a closed surface) out to a far-field boundary, by Gmsh in
 * memory, the envelope kept exactly; the tets next to the layer optimized. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "varmesh/fill.h"
#include "varmesh/io.h"

typedef struct {
  const char *in, *out, *refine;
  int fout, json, algorithm;
  vm_fill_opts o;
  vm_write_opts wo;
} args;

static int opt_refine(vm_cli *cli, const vm_opt *opt, const char *val, void *p) {
  args *a = p;
  double v[7];
  int n = 0;
  const char *s = val;
  char *end;
  while (s && n < 7) {
    v[n] = strtod(s, &end);
    if (end == s || !isfinite(v[n])) break;
    n++;
    s = *end == ',' && n < 7 ? end + 1 : end;
    if (n == 7 && *s) n = 0;
  }
  if (n != 7 || !(v[6] > 0) || v[0] >= v[3] || v[1] >= v[4] || v[2] >= v[5])
    return vm_cli_usage_error(cli,
                              "%s expects X0,Y0,Z0,X1,Y1,Z1,H: a box with X0 < X1, Y0 < Y1, "
                              "Z0 < Z1 and a size H > 0",
                              opt->name);
  for (int k = 0; k < 3; k++) a->o.refine_lo[k] = v[k], a->o.refine_hi[k] = v[k + 3];
  a->o.refine_size = v[6];
  return VM_EXIT_OK;
}

#define A(f) offsetof(args, f)
static const char *const shapes[] = {"box", "sphere", NULL};
static const char *const algos[] = {"delaunay", "hxt", NULL};
static const vm_opt opts[] = {
    {"--farfield", NULL, VM_OPT_DOUBLE, A(o.farfield), "D",
     "far-field distance from the model's centre in model lengths (its largest extent); "
     "default 20",
     .lo = 0.5, .hi = 1e6},
    {"--shape", NULL, VM_OPT_CHOICE, A(o.shape), NULL, "far-field boundary (default box)",
     .choices = shapes},
    {"--growth", NULL, VM_OPT_DOUBLE, A(o.growth), "G",
     "size growth bound: the size at x is at most h_v + (G - 1)|x - v| for every envelope "
     "vertex v of size h_v (default 1.2)",
     .lo = 1.001, .hi = 10},
    {"--far-size", NULL, VM_OPT_DOUBLE, A(o.far_size), "H",
     "largest tet size (default: what the growth bound gives at the far field)", .lo = 1e-300,
     .hi = 1e300},
    {"--refine", NULL, VM_OPT_CALL, 0, "X0,Y0,Z0,X1,Y1,Z1,H",
     "a refinement box (a wake, a region of interest): size at most H inside it", .fn = opt_refine},
    {"--opt-iter", NULL, VM_OPT_INT, A(o.opt_iter), "N",
     "optimization iterations of the tets next to the layer (default 30; 0: off)", .lo = 0,
     .hi = 1e6},
    {"--opt-rings", NULL, VM_OPT_INT, A(o.opt_rings), "N",
     "vertex rings from the envelope that the optimization moves (default 3)", .lo = 0, .hi = 1000},
    {"--fv-sweeps", NULL, VM_OPT_INT, A(o.fv_sweeps), "N",
     "sweeps of the finite-volume relief: the tets' vertices moved where OpenFOAM's "
     "non-orthogonality, skewness, weights, volume ratios or determinants near their limits "
     "(default 8; 0: off)",
     .lo = 0, .hi = 100},
    {"--mesher", NULL, VM_OPT_CHOICE, A(algorithm), NULL, "Gmsh's 3D algorithm (default delaunay)",
     .choices = algos},
    VM_CLI_OPT_THREADS,
    {"--format", NULL, VM_OPT_CALL, A(fout), "F", "output format", .fn = vm_cli_opt_format},
    {"--binary", NULL, VM_OPT_FLAG, A(wo.binary), NULL, "binary output where the format has both",
     .ival = 1},
    {"--json", NULL, VM_OPT_FLAG, A(json), NULL, "JSON summary on stdout", .ival = 1},
    VM_CLI_OPT_QUIET("no progress"),
    VM_CLI_OPT_VERBOSE("debug messages too (Gmsh's own)"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-fill [options] LAYERS OUT\n"
    "Fill the region between a prism layer's outer surface (its faces named 'outer',\n"
    "else its outermost boundary) and a far-field box or sphere with tetrahedra, by\n"
    "Gmsh's Delaunay mesher in memory; the envelope's triangles are kept exactly (same\n"
    "vertices, bit-identical coordinates), so the merged mesh is conformal. LAYERS may\n"
    "also be a closed triangulated surface (it becomes the wall). The far field is\n"
    "named 'farfield'. Then the tets next to the layer are optimized by the\n"
    "variational method (shape measure; the layer and the far field fixed), and\n"
    "where a face or tet is near the limits of OpenFOAM's checkMesh, its vertices\n"
    "move (the finite-volume relief). A half model's layer (its outer surface open,\n"
    "its border in a plane x, y or z = const: vm-prism's output on a cut wall) is\n"
    "filled in its half: a half far field and the symmetry plane between it and the\n"
    "layer, named 'symmetry' with the layer's faces there.\n",
    opts,
    "exit: 0 ok; 1 bad input (no envelope, quadrilaterals on it, a far field cutting the\n"
    "layer), Gmsh failing or not keeping the envelope, or I/O; 2 usage; 4 interrupted\n"
    "(nothing written)\n",
    {A(in), A(out)},
    2,
    "need LAYERS and OUT"};

static void print_json(const args *a, const vm_fill_report *r) {
  printf("{\"input\": ");
  vm_json_string(stdout, a->in);
  printf(", \"output\": ");
  vm_json_string(stdout, a->out);
  printf(
      ", \"layer_cells\": %lld, \"envelope_faces\": %lld, \"farfield_faces\": %lld, "
      "\"tets\": %lld, \"new_vertices\": %lld, \"optimized_vertices\": %lld, "
      "\"flat_envelope_tets\": %lld, \"time_mesh\": %.3f, \"time_opt\": %.3f, \"time_total\": %.3f",
      (long long)r->layer_cells, (long long)r->env_faces, (long long)r->far_faces,
      (long long)r->tets, (long long)r->new_vertices, (long long)r->opt_free,
      (long long)r->flat_env_tets, r->time_mesh, r->time_opt, r->time_total);
  if (r->sym_axis >= 0)
    printf(", \"symmetry_plane\": \"%c=%.17g\", \"symmetry_faces\": %lld", "xyz"[r->sym_axis],
           r -> sym_value, (long long)r -> sym_faces);
  else
    printf(", \"symmetry_plane\": null");
  printf(", \"model_length\": ");
  vm_json_double(stdout, r->model_length);
  printf(", \"farfield_distance\": ");
  vm_json_double(stdout, r->far_distance);
  printf(", \"farfield_size\": ");
  vm_json_double(stdout, r->far_size);
  const vm_fill_tet_quality *q[2] = {&r->before, &r->after};
  const char *nm[2] = {"before", "after"};
  for (int i = 0; i < 2; i++) {
    printf(", \"%s\": {\"min_dihedral\": ", nm[i]);
    vm_json_double(stdout, q[i]->min_dihedral);
    printf(", \"max_dihedral\": ");
    vm_json_double(stdout, q[i]->max_dihedral);
    printf(", \"sj_min\": ");
    vm_json_double(stdout, q[i]->sj_min);
    printf(", \"vol_ratio_envelope\": ");
    vm_json_double(stdout, q[i]->vol_ratio_env);
    printf(", \"vol_ratio_tets\": ");
    vm_json_double(stdout, q[i]->vol_ratio_tets);
    printf(", \"inverted\": %lld}", (long long)q[i]->inverted);
  }
  const vm_fill_fv_figures *f[2] = {&r->fv_before, &r->fv_after};
  printf(", \"fv_moved\": %lld, \"fv_flips\": %lld, \"time_fv\": %.3f", (long long)r->fv_moved,
         (long long)r->fv_flips, r->time_fv);
  for (int i = 0; i < 2; i++) {
    printf(", \"fv_%s\": {\"faces\": %lld, \"tets\": %lld, \"nonortho_over70\": %lld, "
           "\"skew_over4\": %lld, \"weight_under005\": %lld, \"volratio_under001\": %lld, "
           "\"det_under0001\": %lld, \"nonortho_max\": ",
           nm[i], (long long)f[i]->faces, (long long)f[i]->tets, (long long)f[i]->nonortho_over70,
           (long long)f[i]->skew_over4, (long long)f[i]->weight_under,
           (long long)f[i]->volratio_under, (long long)f[i]->det_under);
    vm_json_double(stdout, f[i]->nonortho_max);
    printf(", \"skew_max\": ");
    vm_json_double(stdout, f[i]->skew_max);
    printf(", \"weight_min\": ");
    vm_json_double(stdout, f[i]->weight_min);
    printf(", \"volratio_min\": ");
    vm_json_double(stdout, f[i]->volratio_min);
    printf(", \"det_min\": ");
    vm_json_double(stdout, f[i]->det_min);
    printf("}");
  }
  printf("}\n");
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-fill");
  args a = {.o = vm_fill_opts_default(), .wo = vm_write_opts_default(), .fout = VM_FMT_AUTO};
  vm_mesh *m = NULL, *res = NULL;
  vm_fill_report rep;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  a.o.algorithm = a.algorithm == 1 ? 10 : 1;
  if (a.fout == VM_FMT_AUTO && vm_format_from_path(a.out) == VM_FMT_AUTO)
    a.fout = vm_format_from_path(a.in);
  if ((rc = vm_cli_volume_output(
           &cli, a.out, a.fout != VM_FMT_AUTO ? a.fout : vm_format_from_path(a.out))) != VM_EXIT_OK)
    goto done;
  if (vm_mesh_read(cli.ctx, a.in, VM_FMT_AUTO, &m) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  vm_cli_catch_interrupts(&cli);
  int st = vm_fill_run(cli.ctx, m, &a.o, &res, &rep);
  if (st == VM_ERR_INTERRUPTED) {
    vm_cli_error(&cli, "%s: interrupted; nothing written", a.out);
    rc = VM_EXIT_INTERRUPTED;
    goto done;
  }
  if (st < 0) {
    rc = vm_cli_input_error(&cli, a.in);
    goto done;
  }
  if (vm_mesh_write(cli.ctx, res, a.out, a.fout, &a.wo) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  char half[96] = "";
  if (rep.sym_axis >= 0)
    snprintf(half, sizeof half, "; a half model: the symmetry plane %c = %g, %lld triangles",
             "xyz"[rep.sym_axis], rep.sym_value, (long long)rep.sym_faces);
  if (!cli.quiet)
    fprintf(stderr,
            "vm-fill: %s: %lld layer cells + %lld tets (%lld new vertices), envelope %lld "
            "triangles kept exactly; far field %lld triangles at %g%s; Gmsh %.2f s, "
            "optimization %.2f s, finite-volume relief %.2f s\n",
            a.out, (long long)rep.layer_cells, (long long)rep.tets, (long long)rep.new_vertices,
            (long long)rep.env_faces, (long long)rep.far_faces, rep.far_distance, half,
            rep.time_mesh, rep.time_opt, rep.time_fv);
  if (a.json) print_json(&a, &rep);
done:
  vm_mesh_destroy(&res);
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
