/* apps/vm-quality.c: judge a mesh: per element type and overall counts, M
 * (inverted quadrature simplices), phi_min, psi_min, scaled Jacobians. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_report.h"
#include "cli_verify.h"
#include "varmesh/io.h"
#include "varmesh/quality.h"

static const char usage[] =
    "usage: vm-quality [options] MESH\n"
    "Quality of every element of the mesh's top dimension (docs/cli.md):\n"
    "M = inverted quadrature simplices, phi = det C/(tr C^T C/d)^(d/2),\n"
    "psi = 2 det C/(1 + det C^2) (needs a target size), scaled Jacobian.\n"
    "  --rule corner|geometric   quadrature simplices to measure (default corner)\n"
    "  --target-size H           ideal element edge length for psi\n"
    "  --format F                input format (default: from the extension)\n"
    "  --json                    machine-readable summary on stdout\n"
    "  --require-valid           exit 3 if any quadrature simplex is inverted (M > 0)\n"
    "  --min-sj X                exit 3 if the minimum scaled Jacobian is below X\n"
    "  --verify                  exact checks (CGAL predicates), exit 3 on failure: every\n"
    "                            quadrature simplex of --rule positively oriented; if there\n"
    "                            are prisms, their outer (top) faces neither intersect\n"
    "                            each other nor cross the wall (bottom faces)\n"
    "  --report DIR              write DIR/index.html with pictures: quality histograms, a\n"
    "                            slice if 3D, a rendered surface if triangles/quads in 3D\n"
    "  --report-field NAME       field colouring the surface picture (default\n"
    "                            mean_curvature if present, else the scaled Jacobian)\n"
    "  -q, --quiet               no warnings\n"
    "  --help, --version\n"
    "exit: 0 ok, 1 bad input, 2 usage, 3 a requested check failed\n";

static void print_text(const char *path, const vm_mesh *m, const vm_quality *q) {
  printf("mesh %s: %lld vertices, %lld elements measured (dimension %d)", path,
         (long long)m->nv, (long long)q->measured, q->top_dim);
  if (q->skipped) printf(", %lld lower-dimensional elements not measured", (long long)q->skipped);
  printf("\n%-8s %10s %10s %10s %10s %12s %12s %10s\n", "type", "elements", "simplices", "M",
         "inv.elems", "phi_min", "psi_min", "sj_min");
  for (int t = 0; t <= VM_NTYPES; t++) {
    const vm_type_quality *tq = t < VM_NTYPES ? &q->type[t] : &q->all;
    if (t < VM_NTYPES && !tq->count) continue;
    printf("%-8s %10lld %10lld %10lld %10lld %12.4e %12.4e %10.4f\n",
           t < VM_NTYPES ? vm_elem_name(t) : "all", (long long)tq->count, (long long)tq->nodes,
           (long long)tq->inverted_nodes, (long long)tq->inverted_elems, tq->phi_min,
           tq->psi_min, tq->sj_min);
  }
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

static void print_json(const char *path, const vm_mesh *m, const vm_quality *q) {
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
  printf("}, \"sj_histogram\": [");
  for (int b = 0; b < VM_QUALITY_NBINS; b++)
    printf("%s%lld", b ? ", " : "", (long long)q->sj_hist[b]);
  printf("]}\n");
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-quality");
  const char *path = NULL, *report = NULL, *report_field = NULL;
  int json = 0, require_valid = 0, verify = 0, fin = VM_FMT_AUTO;
  double min_sj = -INFINITY;
  vm_quality_opts qo = {VM_RULE_CORNER, 0};
  int rc = VM_EXIT_OK;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    const char *val = i + 1 < argc ? argv[i + 1] : NULL;
    if (vm_cli_info_option(&cli, a, usage)) {
      goto done;
    } else if (!strcmp(a, "--json")) {
      json = 1;
    } else if (!strcmp(a, "--require-valid")) {
      require_valid = 1;
    } else if (!strcmp(a, "--verify")) {
      verify = 1;
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      cli.quiet = 1;
    } else if (!strcmp(a, "--rule")) {
      i++;
      if (val && !strcmp(val, "corner"))
        qo.rule = VM_RULE_CORNER;
      else if (val && !strcmp(val, "geometric"))
        qo.rule = VM_RULE_GEOMETRIC;
      else {
        rc = vm_cli_usage_error(&cli, "--rule expects corner or geometric");
        goto done;
      }
    } else if (!strcmp(a, "--target-size")) {
      i++;
      if (vm_cli_double(&cli, a, val, 1e-300, 1e300, &qo.target_size)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
    } else if (!strcmp(a, "--min-sj")) {
      i++;
      if (vm_cli_double(&cli, a, val, -1, 1, &min_sj)) {
        rc = VM_EXIT_USAGE;
        goto done;
      }
    } else if (!strcmp(a, "--report") || !strcmp(a, "--report-field")) {
      i++;
      if (!val) {
        rc = vm_cli_usage_error(&cli, "%s expects a value", a);
        goto done;
      }
      *(!strcmp(a, "--report") ? &report : &report_field) = val;
    } else if (!strcmp(a, "--format")) {
      i++;
      if ((rc = vm_cli_format(&cli, val, &fin)) != VM_EXIT_OK) goto done;
    } else if ((rc = vm_cli_operand(&cli, a, (const char **const[]){&path}, 1)) != VM_EXIT_OK) {
      goto done;
    }
  }
  if (!path) {
    rc = vm_cli_usage_error(&cli, "need a MESH file");
    goto done;
  }
  vm_mesh *m = NULL;
  if (vm_mesh_read(cli.ctx, path, fin, &m) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
    goto done;
  }
  vm_quality q;
  if (vm_mesh_quality(m, &qo, &q) < 0) {
    vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    rc = VM_EXIT_INPUT;
  } else {
    if (json)
      print_json(path, m, &q);
    else
      print_text(path, m, &q);
    if (require_valid && q.all.inverted_nodes > 0) {
      vm_cli_error(&cli, "%s: %lld inverted quadrature simplices in %lld elements", path,
                   (long long)q.all.inverted_nodes, (long long)q.all.inverted_elems);
      rc = VM_EXIT_CHECK;
    }
    if (q.measured && q.all.sj_min < min_sj) {
      vm_cli_error(&cli, "%s: minimum scaled Jacobian %.4f is below %.4f", path, q.all.sj_min,
                   min_sj);
      rc = VM_EXIT_CHECK;
    }
    if (verify) {
      int vrc = vm_cli_verify(&cli, path, m, qo.rule, !json, stdout);
      if (vrc != VM_EXIT_OK) rc = vrc;
    }
    if (report) {
      int rrc = vm_cli_report_quality(&cli, report, path, m, &qo, report_field);
      if (rrc != VM_EXIT_OK) rc = rrc;
    }
  }
  vm_mesh_destroy(&m);
done:
  vm_cli_finish(&cli);
  return rc;
}
