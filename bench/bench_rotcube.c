/* bench/bench_rotcube.c: the paper's Table 1: untangling the rotated cube
 * (Section 6.1) at five angles, printed beside the paper's figures. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "varmesh/rotcube.h"
#include "varmesh/problem.h"
#include "varmesh/jacobian.h"
#include "varmesh/quality.h"
#include "varmesh/volume.h"

static const char *angle_names[] = {"pi/8", "3pi/8", "pi/2", "7pi/8", "pi"};
static const double angle_frac[] = {1.0 / 8, 3.0 / 8, 0.5, 7.0 / 8, 1.0};
/* Table 1 of the paper (n = 32, implicit penalty untangling, corner rule
 * not stated; 64-node rule implied by "M_init ... tetrahedra ... (24)") */
static const double paper[6][5] = {{19264, 22400, 31192, 32032, 34157},           /* M_init */
                                   {19264, 36029, 82330, 213554, 126644},         /* M_max */
                                   {140, 8160, 2120, 63600, 56000},               /* niter */
                                   {164, 8243, 2983, 84562, 67928},               /* t_u, s */
                                   {4.34e-2, 1.72e-3, 1.97e-3, 1.02e-4, 2.65e-4}, /* phi_min */
                                   {1.06e-1, 7.0e-3, 1.48e-2, 3.05e-4, 1.87e-3}}; /* psi_min */

static void usage(void) {
  fprintf(stderr,
          "usage: bench_rotcube [--n N] [--angles i,j,..] [--geometric] [--tets] [--mixed]\n"
          "                     [--time-limit S] [--max-iter N] [--opt-iter N] [--method "
          "penalty|oneway|barrier|adaptive|foldover]\n"
          "                     [--eps-inner N] [--eps-cap R] [--local-threshold N] [--theta T]\n"
          "                     [--theta-untangle T]\n"
          "                     [--explicit | --newton] [--staged | --direct] [--qi-steps N] "
          "[--threads N] "
          "[--verbose] [--where]\n"
          "angles are indices 0..4 of pi/8 3pi/8 pi/2 7pi/8 pi (default all); the schedule is\n"
          "vm-volume's default: staged with hexahedra, direct (--direct) with tets\n");
}

/* The least scaled Jacobian det J/(|J1||J2||J3|) of a hex's trilinear map
 * sampled on a 5^3 grid of its reference cube (corners included). */
static double hex_sj_sampled(const vm_mesh *m, int64_t e) {
  static const int c[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                              {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  double lo = INFINITY;
  for (int g = 0; g < 125; g++) {
    double u[3] = {g % 5 / 4.0, g / 5 % 5 / 4.0, g / 25 / 4.0}, J[3][3] = {{0}};
    for (int i = 0; i < 8; i++) {
      const double *x = m->xyz + 3 * m->conn[m->eoff[e] + i];
      for (int d = 0; d < 3; d++) {
        /* d/du_d of the corner's shape function */
        double w = c[i][d] ? 1 : -1;
        for (int k = 0; k < 3; k++)
          if (k != d) w *= c[i][k] ? u[k] : 1 - u[k];
        for (int r = 0; r < 3; r++) J[d][r] += w * x[r];
      }
    }
    double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                 J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                 J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    double l = 1;
    for (int d = 0; d < 3; d++)
      l *= sqrt(J[d][0] * J[d][0] + J[d][1] * J[d][1] + J[d][2] * J[d][2]);
    double sj = l > 0 ? det / l : -1;
    if (sj < lo) lo = sj;
  }
  return lo;
}

typedef struct {
  int verbose;
  int every;
} prog;

static void progress(void *user, const vm_volume_progress *p) {
  const prog *g = user;
  if (!g->verbose || p->iter % g->every) return;
  fprintf(stderr, "  %-9s it %6d F %.4e M %7lld min det %+.2e eps %.1e tau %.1e cg %4d %6.1fs\n",
          p->phase, p->iter, p->F, (long long)p->inverted, p->min_det, p->eps, p->tau, p->pcg_iters,
          p->elapsed);
}

int main(int argc, char **argv) {
  int n = 32, use[5] = {1, 1, 1, 1, 1}, cells = VM_GEN_HEX, threads = 0, where = 0;
  /* vm-volume's default schedule: staged where there are hexahedra (its
   * fallback to the direct schedule on a stall is not run here) */
  int direct = 0;
  for (int i = 1; i < argc; i++)
    direct |= !strcmp(argv[i], "--direct") || !strcmp(argv[i], "--tets");
  vm_volume_opts o = direct ? vm_volume_opts_direct() : vm_volume_opts_staged();
  o.time_limit = 60;
  prog g = {0, getenv("VM_EVERY") ? atoi(getenv("VM_EVERY")) : 50};
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : "";
    if (!strcmp(a, "--n")) {
      n = atoi(v);
      i++;
    } else if (!strcmp(a, "--angles")) {
      memset(use, 0, sizeof use);
      for (const char *p = v; *p; p++)
        if (*p >= '0' && *p <= '4') use[*p - '0'] = 1;
      i++;
    } else if (!strcmp(a, "--geometric")) {
      o.rule = VM_RULE_GEOMETRIC;
    } else if (!strcmp(a, "--tets")) {
      cells = VM_GEN_TETS;
    } else if (!strcmp(a, "--mixed")) {
      cells = VM_GEN_MIXED;
    } else if (!strcmp(a, "--explicit")) {
      o.solver = VM_MINIMIZER_EXPLICIT;
    } else if (!strcmp(a, "--newton")) {
      o.solver = VM_MINIMIZER_NEWTON;
    } else if (!strcmp(a, "--time-limit")) {
      o.time_limit = atof(v);
      i++;
    } else if (!strcmp(a, "--max-iter")) {
      o.max_iter = atoi(v);
      i++;
    } else if (!strcmp(a, "--opt-iter")) {
      o.opt_iter = atoi(v);
      i++;
    } else if (!strcmp(a, "--eps-inner")) {
      o.eps_inner = atoi(v);
      i++;
    } else if (!strcmp(a, "--eps-cap")) {
      o.eps_cap = atof(v);
      i++;
    } else if (!strcmp(a, "--local-threshold")) {
      o.local_threshold = atoi(v);
      i++;
    } else if (!strcmp(a, "--theta-untangle")) {
      o.theta_untangle = atof(v);
      i++;
    } else if (!strcmp(a, "--theta")) {
      o.theta = atof(v);
      i++;
    } else if (!strcmp(a, "--threads")) {
      threads = atoi(v);
      i++;
    } else if (!strcmp(a, "--method")) {
      o.method = !strcmp(v, "barrier")    ? VM_UNTANGLE_BARRIER
                 : !strcmp(v, "oneway")   ? VM_UNTANGLE_PENALTY_ONEWAY
                 : !strcmp(v, "adaptive") ? VM_UNTANGLE_ADAPTIVE
                 : !strcmp(v, "foldover") ? VM_UNTANGLE_FOLDOVER
                                          : VM_UNTANGLE_PENALTY;
      i++;
    } else if (!strcmp(a, "--where")) {
      where = 1;
    } else if (!strcmp(a, "--staged")) {
      o.staged = 1;
    } else if (!strcmp(a, "--direct")) {
      /* read above */
    } else if (!strcmp(a, "--qi-steps")) {
      o.qi_steps = atoi(v);
      i++;
    } else if (!strcmp(a, "--verbose")) {
      g.verbose = 1;
    } else {
      usage();
      return 2;
    }
  }
  o.progress = progress;
  o.user = &g;
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  vm_ctx_set_threads(ctx, threads);
  printf("rotated cube n = %d, %s, %s rule, %s untangling, %s solver, time limit %.0f s\n", n,
         cells == VM_GEN_HEX    ? "hexahedra"
         : cells == VM_GEN_TETS ? "6 tets per hex"
                                : "mixed",
         o.rule == VM_RULE_GEOMETRIC ? "geometric (64-node)" : "corner (8 tets)",
         vm_untangle_method_name(o.method),
         o.solver == VM_MINIMIZER_IMPLICIT ? "implicit"
         : o.solver == VM_MINIMIZER_NEWTON ? "newton"
                                           : "explicit",
         o.time_limit);
  printf(
      "%-6s %9s %9s %9s %7s %7s %7s %9s %10s %10s %8s %8s %8s   | paper: %7s %7s %6s %6s %9s %9s\n",
      "angle", "M_init", "M_max", "M_final", "niter", "local", "opt", "t_untgl", "phi_min",
      "psi_min", "inv.hex", "t_total", "cpu", "M_init", "M_max", "niter", "t_u", "phi_min",
      "psi_min");
  int all_ok = 1;
  for (int a = 0; a < 5; a++) {
    if (!use[a]) continue;
    vm_rotcube_opts ro = vm_rotcube_opts_default();
    ro.n = n;
    ro.alpha = angle_frac[a] * 3.14159265358979323846;
    ro.cells = cells;
    vm_mesh *m;
    double *ref;
    if (vm_gen_rotated_cube(ctx, &ro, &m, &ref)) {
      fprintf(stderr, "%s\n", vm_ctx_error(ctx));
      return 1;
    }
    o.target_xyz = ref;
    vm_volume_report r;
    clock_t c0 = clock();
    int st = vm_volume_run(ctx, m, NULL, &o, &r);
    double cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
    if (st < 0) fprintf(stderr, "%s: %s\n", angle_names[a], vm_ctx_error(ctx));
    /* independent check: every corner simplex of every element */
    vm_quality q;
    vm_quality_opts qo = {VM_RULE_CORNER, 1.0 / n};
    vm_mesh_quality(m, &qo, &q);
    /* a run that ended in an error filled no final figures: M from the
     * independent check */
    if (st < 0) r.M_final = q.all.inverted_nodes;
    if (r.M_final || q.all.inverted_nodes) all_ok = 0;
    printf(
        "%-6s %9lld %9lld %9lld %7d %7d %7d %9.2f %10.3e %10.3e %8lld %8.2f %8.2f   | paper: %7.0f "
        "%7.0f %6.0f %6.0f %9.2e %9.2e\n"
        "       certified: %lld invalid, %lld undecided of %lld cells; repair: %lld cells, %d "
        "iterations (geometric phase: %lld cells left, %.2f s), %d rounds; certified valid "
        "after %.2f s\n",
        angle_names[a], (long long)r.M_init, (long long)r.M_max, (long long)r.M_final,
        r.iter_untangle, r.iter_local, r.iter_opt, r.time_untangle, r.phi_min, r.psi_min,
        (long long)q.all.inverted_elems, r.time_total, cpu, paper[0][a], paper[1][a], paper[2][a],
        paper[3][a], paper[4][a], paper[5][a], (long long)r.cert_invalid,
        (long long)r.cert_undecided, (long long)r.cert_cells, (long long)r.cert_bad_init,
        r.iter_repair, (long long)r.geometric_left, r.time_geometric, r.repair_rounds,
        r.valid ? r.time_certified : -1.0);
    /* what a solver sees: the scaled Jacobian sampled inside the hexes,
     * OpenFOAM's negative volumes and face pyramids (as checkMesh counts) */
    double sj5 = INFINITY;
    for (int64_t e = 0; e < m->ne; e++)
      if (m->etype[e] == VM_HEX) {
        double v = hex_sj_sampled(m, e);
        if (v < sj5) sj5 = v;
      }
    /* phi and psi over the geometric rule's 64 nodes (24): all positive
     * imply a valid cell (Theorem 3.1), but a certified cell may have some
     * negative (its Bernstein coefficients are their means) */
    vm_quality qg;
    vm_quality_opts qgo = {VM_RULE_GEOMETRIC, 1.0 / n};
    vm_mesh_quality(m, &qgo, &qg);
    printf("       over the geometric rule's nodes (24): phi_min %.3e, psi_min %.3e, M %lld; min "
           "scaled Jacobian on a 5^3 grid per hex %.4f; OpenFOAM: %lld negative volumes, %lld "
           "face pyramid errors\n",
           qg.all.phi_min, qg.all.psi_min, (long long)qg.all.inverted_nodes, sj5,
           (long long)q.foam_neg_volumes, (long long)q.foam_pyramid_errors);
    /* phi and psi over the whole of every hex, certified (the rules' nodes
     * sample the cell; the certificate is the Bernstein coefficients') */
    vm_hex_bounds hb;
    if (vm_mesh_hex_bounds(m, 1.0 / n, 0.01, 0, &hb) == VM_OK)
      printf("       over the whole cell (certified bracket): phi_min in [%.3e, %.3e], psi_min in "
             "[%.3e, %.3e] (%lld of %lld hexes subdivided, %lld parts)\n",
             hb.phi_lo, hb.phi_hi, hb.psi_lo, hb.psi_hi, (long long)hb.refined, (long long)hb.hexes,
             (long long)hb.parts);
    if (!r.valid || q.foam_neg_volumes || q.foam_pyramid_errors) all_ok = 0;
    fflush(stdout);
    if (where && cells != VM_GEN_MIXED) {
      /* where the inverted nodes are: per cell, its layer outside the inner
       * cube along x, y, z (0: within the inner cube's slab, 3: 3 or more) */
      vm_problem *P = NULL;
      int64_t nn = 0;
      if (vm_problem_create(ctx, m, &P) == VM_OK && vm_problem_set_rule(P, o.rule) == VM_OK &&
          vm_problem_set_target_reference(P, ref) == VM_OK)
        nn = vm_problem_num_nodes(P);
      double *d = malloc(sizeof *d * (size_t)(nn > 0 ? nn : 1));
      if (!d || vm_problem_node_dets(P, m->xyz, d) < 0) nn = 0;
      const int32_t *nel = nn ? vm_problem_node_elements(P) : NULL;
      int cnt[64] = {0};
      for (int64_t q = 0; q < nn; q++) {
        if (d[q] > 0) continue;
        int32_t e = nel[q];
        int per = cells == VM_GEN_TETS ? 6 : 1;
        int64_t h = e / per;
        int i = (int)(h % n), j = (int)(h / n % n), k = (int)(h / n / n);
        /* cell centre distance outside the inner cube, in cells, per axis */
        double c[3] = {-0.5 + (i + 0.5) / n, -0.5 + (j + 0.5) / n, -0.5 + (k + 0.5) / n};
        int cls = 0;
        for (int a = 0; a < 3; a++) {
          double out = fabs(c[a]) - ro.inner;
          int l = out <= 0 ? 0 : (int)(out * n) + 1;
          cls = cls * 4 + (l > 3 ? 3 : l);
        }
        cnt[cls]++;
      }
      printf("  inverted nodes by cell layer outside the inner cube (x y z):");
      for (int c2 = 0; c2 < 64; c2++)
        if (cnt[c2]) printf(" %d%d%d:%d", c2 / 16, c2 / 4 % 4, c2 % 4, cnt[c2]);
      printf("\n");
      free(d);
      vm_problem_destroy(&P);
    }
    vm_free(ctx, ref);
    vm_mesh_destroy(&m);
  }
  vm_ctx_destroy(&ctx);
  return all_ok ? 0 : 1;
}
