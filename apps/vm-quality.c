/* apps/vm-quality.c: judge a mesh: per element type and overall counts, M
 * (inverted quadrature simplices), phi_min, psi_min, scaled Jacobians. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_report.h"
#include "cli_verify.h"
#include "varmesh/planar.h"
#include "varmesh/io.h"
#include "varmesh/jacobian.h"
#include "varmesh/quality.h"

static void print_text(const char *path, const vm_mesh *m, const vm_quality *q,
                       const vm_jac_report *jr, const vm_hex_bounds *hb) {
  printf("mesh %s: %lld vertices, %lld elements measured (dimension %d)", path, (long long)m->nv,
         (long long)q->measured, q->top_dim);
  if (q->skipped) printf(", %lld lower-dimensional elements not measured", (long long)q->skipped);
  printf("\n%-8s %10s %10s %10s %10s %12s %12s %10s\n", "type", "elements", "simplices", "M",
         "inv.elems", "phi_min", "psi_min", "sj_min");
  for (int t = 0; t <= VM_NTYPES; t++) {
    const vm_type_quality *tq = t < VM_NTYPES ? &q->type[t] : &q->all;
    if (t < VM_NTYPES && !tq->count) continue;
    printf("%-8s %10lld %10lld %10lld %10lld %12.4e %12.4e %10.4f\n",
           t < VM_NTYPES ? vm_elem_name(t) : "all", (long long)tq->count, (long long)tq->nodes,
           (long long)tq->inverted_nodes, (long long)tq->inverted_elems, tq->phi_min, tq->psi_min,
           tq->sj_min);
  }
  if (jr->cells)
    printf("certified (det J > 0 everywhere in the cell): %lld of %lld cells; %lld invalid, "
           "%lld undecided\n",
           (long long)(jr->cells - jr->invalid - jr->undecided), (long long)jr->cells,
           (long long)jr->invalid, (long long)jr->undecided);
  if (hb->hexes) {
    printf("hexahedra over the whole cell (certified bracket): phi_min in [%.4e, %.4e]", hb->phi_lo,
           hb->phi_hi);
    if (!isnan(hb->psi_lo)) printf(", psi_min in [%.4e, %.4e]", hb->psi_lo, hb->psi_hi);
    printf("\n");
  }
  if (q->top_dim == 3 && q->measured)
    printf("OpenFOAM's checkMesh: %lld cells of volume <= 0, %lld face pyramids incorrectly "
           "oriented\n",
           (long long)q->foam_neg_volumes, (long long)q->foam_pyramid_errors);
  if (q->type[VM_PRISM].count)
    printf("prisms not positive in every 3-tet split: %lld of %lld\n",
           (long long)q->prism_split_negative, (long long)q->type[VM_PRISM].count);
  if (!q->measured) return;
  printf("scaled Jacobian: min %.4f  p1 %.4f  p5 %.4f  p25 %.4f  median %.4f\n", q->all.sj_min,
         q->sj_p01, q->sj_p05, q->sj_p25, q->sj_p50);
  int64_t mx = 1;
  for (int b = 0; b < VM_QUALITY_NBINS; b++)
    if (q->sj_hist[b] > mx) mx = q->sj_hist[b];
  for (int b = 0; b < VM_QUALITY_NBINS; b++) {
    double lo = -1 + 2.0 * b / VM_QUALITY_NBINS, hi = lo + 2.0 / VM_QUALITY_NBINS;
    int bar = (int)((q->sj_hist[b] * 50 + mx - 1) / mx);
    printf("  [%5.2f,%5.2f) %10lld |", lo, hi, (long long)q->sj_hist[b]);
    for (int i = 0; i < bar; i++) putchar('#');
    putchar('\n');
  }
}

static void json_tq(const vm_type_quality *tq) {
  printf("{\"elements\": %lld, \"simplices\": %lld, \"M\": %lld, \"inverted_elements\": %lld, "
         "\"phi_min\": ",
         (long long)tq->count, (long long)tq->nodes, (long long)tq->inverted_nodes,
         (long long)tq->inverted_elems);
  vm_json_double(stdout, tq->phi_min);
  printf(", \"psi_min\": ");
  vm_json_double(stdout, tq->psi_min);
  printf(", \"sj_min\": ");
  vm_json_double(stdout, tq->sj_min);
  printf("}");
}

static void print_json(const char *path, const vm_mesh *m, const vm_quality *q,
                       const vm_jac_report *jr, const vm_hex_bounds *hb) {
  printf("{\"file\": ");
  vm_json_string(stdout, path);
  printf(", \"vertices\": %lld, \"dimension\": %d, \"skipped\": %lld, \"types\": {",
         (long long)m->nv, q->top_dim, (long long)q->skipped);
  int first = 1;
  for (int t = 0; t < VM_NTYPES; t++) {
    if (!q->type[t].count) continue;
    printf("%s\"%s\": ", first ? "" : ", ", vm_elem_name(t));
    json_tq(&q->type[t]);
    first = 0;
  }
  printf("}, \"all\": ");
  json_tq(&q->all);
  printf(", \"sj_percentiles\": {\"p1\": ");
  vm_json_double(stdout, q->sj_p01);
  printf(", \"p5\": ");
  vm_json_double(stdout, q->sj_p05);
  printf(", \"p25\": ");
  vm_json_double(stdout, q->sj_p25);
  printf(", \"p50\": ");
  vm_json_double(stdout, q->sj_p50);
  printf("}, \"certified\": {\"cells\": %lld, \"invalid\": %lld, \"undecided\": %lld, "
         "\"first_bad\": %lld}",
         (long long)jr->cells, (long long)jr->invalid, (long long)jr->undecided,
         (long long)jr->first_bad);
  if (hb->hexes) {
    const double v[4] = {hb->phi_lo, hb->phi_hi, hb->psi_lo, hb->psi_hi};
    const char *k[4] = {"phi_min_lo", "phi_min_hi", "psi_min_lo", "psi_min_hi"};
    printf(", \"hex_whole_cell\": {");
    for (int i = 0; i < 4; i++) {
      printf("%s\"%s\": ", i ? ", " : "", k[i]);
      vm_json_double(stdout, v[i]);
    }
    printf("}");
  }
  if (q->top_dim == 3)
    printf(", \"foam\": {\"negative_volumes\": %lld, \"pyramid_errors\": %lld}",
           (long long)q->foam_neg_volumes, (long long)q->foam_pyramid_errors);
  printf(", \"prism_split_negative\": %lld", (long long)q->prism_split_negative);
  printf(", \"sj_histogram\": [");
  for (int b = 0; b < VM_QUALITY_NBINS; b++)
    printf("%s%lld", b ? ", " : "", (long long)q->sj_hist[b]);
  printf("]}\n");
}

typedef struct {
  const char *path, *report, *report_field;
  int json, require_valid, verify, fin;
  double min_sj;
  vm_quality_opts qo;
} args;

#define A(f) offsetof(args, f)
static const char *const rules[] = {"corner", "geometric", NULL};
static const vm_opt opts[] = {
    {"--rule", NULL, VM_OPT_CHOICE, A(qo.rule), NULL,
     "quadrature simplices to measure (default corner)", .choices = rules},
    {"--target-size", NULL, VM_OPT_DOUBLE, A(qo.target_size), "H",
     "ideal element edge length for psi", .lo = 1e-300, .hi = 1e300},
    {"--format", NULL, VM_OPT_CALL, A(fin), "F", "input format (default: from the extension)",
     .fn = vm_cli_opt_format},
    {"--json", NULL, VM_OPT_FLAG, A(json), NULL, "machine-readable summary on stdout", .ival = 1},
    {"--require-valid", NULL, VM_OPT_FLAG, A(require_valid), NULL,
     "exit 3 if any quadrature simplex is inverted (M > 0) or a cell is not certified valid "
     "(det J > 0 everywhere in it)",
     .ival = 1},
    {"--min-sj", NULL, VM_OPT_DOUBLE, A(min_sj), "X",
     "exit 3 if the minimum scaled Jacobian is below X", .lo = -1, .hi = 1},
    {"--verify", NULL, VM_OPT_FLAG, A(verify), NULL,
     "exact checks (CGAL predicates), exit 3 on failure: every quadrature simplex of --rule "
     "positively oriented; if there are prisms, their outer (top) faces neither intersect each "
     "other nor cross the wall (bottom faces)",
     .ival = 1},
    {"--report", NULL, VM_OPT_STRING, A(report), "DIR",
     "write DIR/index.html with pictures: quality histograms, a slice if 3D, a rendered "
     "surface if triangles/quads in 3D",
     .error = "expects a value"},
    {"--report-field", NULL, VM_OPT_STRING, A(report_field), "NAME",
     "field colouring the surface picture (default mean_curvature if present, else the scaled "
     "Jacobian)",
     .error = "expects a value"},
    VM_CLI_OPT_QUIET("no warnings"),
    VM_CLI_OPT_VERBOSE("debug messages too"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-quality [options] MESH\n"
    "Quality of every element of the mesh's top dimension (docs/cli.md):\n"
    "M = inverted quadrature simplices, phi = det C/(tr C^T C/d)^(d/2),\n"
    "psi = 2 det C/(1 + det C^2) (needs a target size), scaled Jacobian.\n",
    opts,
    "exit: 0 ok, 1 bad input, 2 usage, 3 a requested check failed\n",
    {A(path)},
    1,
    "need a MESH file"};

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-quality");
  args a = {.fin = VM_FMT_AUTO, .min_sj = -INFINITY, .qo = {VM_RULE_CORNER, 0}};
  vm_mesh *m = NULL;
  vm_quality q;
  vm_jac_report jr;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  if (vm_mesh_read(cli.ctx, a.path, a.fin, &m) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  /* an empty mesh passes no check and has nothing to report */
  if (m->ne == 0) {
    vm_cli_error(&cli, "%s: the mesh has no elements (%lld vertices)", a.path, (long long)m->nv);
    rc = VM_EXIT_INPUT;
    goto done;
  }
  {
    /* a 2D mesh in a plane is measured in the plane's coordinates, with the
     * orientation its boundary gives, as vm-volume optimizes it */
    int64_t counts[VM_NTYPES];
    vm_plane_frame f;
    if (vm_mesh_count_types(m, counts) == 2 && vm_mesh_plane_frame(m, VM_PLANE_TOL, &f) == VM_OK) {
      vm_mesh_to_plane(m, &f);
      if (f.flip && !cli.quiet)
        fprintf(stderr,
                "vm-quality: %s: a 2D mesh whose elements and boundary turn clockwise seen from "
                "its plane's normal: that orientation is taken as positive\n",
                a.path);
    }
    vm_ctx_clear_error(cli.ctx);
  }
  /* phi and psi over the whole of each hex, not only at the rule's nodes */
  vm_hex_bounds hb = {0};
  if (vm_mesh_quality(m, &a.qo, &q) < 0 || vm_mesh_jacobian_certify(m, &jr, NULL) < 0 ||
      vm_mesh_hex_bounds(m, a.qo.target_size, 0.01, 0, &hb) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  if (a.json)
    print_json(a.path, m, &q, &jr, &hb);
  else
    print_text(a.path, m, &q, &jr, &hb);
  if (a.require_valid && q.all.inverted_nodes > 0) {
    vm_cli_error(&cli, "%s: %lld inverted quadrature simplices in %lld elements", a.path,
                 (long long)q.all.inverted_nodes, (long long)q.all.inverted_elems);
    rc = VM_EXIT_CHECK;
  } else if (a.require_valid && jr.invalid + jr.undecided > 0) {
    vm_cli_error(&cli,
                 "%s: %lld cells not certified valid (det J > 0 everywhere): %lld invalid, %lld "
                 "undecided; the first is element %lld",
                 a.path, (long long)(jr.invalid + jr.undecided), (long long)jr.invalid,
                 (long long)jr.undecided, (long long)jr.first_bad);
    rc = VM_EXIT_CHECK;
  }
  if (q.measured && q.all.sj_min < a.min_sj) {
    vm_cli_error(&cli, "%s: minimum scaled Jacobian %.4f is below %.4f", a.path, q.all.sj_min,
                 a.min_sj);
    rc = VM_EXIT_CHECK;
  }
  if (a.verify) {
    int vrc = vm_cli_verify(&cli, a.path, m, a.qo.rule, !a.json, stdout);
    if (vrc != VM_EXIT_OK) rc = vrc;
  }
  if (a.report) {
    int rrc = vm_cli_report_quality(&cli, a.report, a.path, m, &a.qo, a.report_field);
    if (rrc != VM_EXIT_OK) rc = rrc;
  }
done:
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
