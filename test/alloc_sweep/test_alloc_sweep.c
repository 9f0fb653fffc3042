/* test/alloc_sweep/test_alloc_sweep.c: allocation failure across a whole
 * run. A small tangled cube is read from a file, untangled and optimized by
 * vm_volume_run (few iterations) and written; for every n from 1 to the
 * number of allocations of that run, the run is repeated with the n-th
 * allocation failing. Each must end in VM_ERR_NOMEM (or succeed, if that
 * allocation was optional), free everything it allocated, and leave no
 * output and no temporary file behind when it failed.
 * usage: test_alloc_sweep [--stride K]  (test every K-th n; default 1) */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/ctx.h"
#include "varmesh/rotcube.h"
#include "varmesh/io.h"
#include "varmesh/mesh.h"
#include "varmesh/topology.h"
#include "varmesh/volume.h"
#include "vmtest.h"

typedef struct run_result {
  int st;         /* first negative status, or vm_volume_run's status */
  const char *at; /* stage that failed */
  long allocs;    /* allocations made */
  int64_t M_final;
  int iters[3]; /* untangling, local, optimization iterations */
} run_result;

/* read -> mark fixed and boundary -> vm_volume_run -> write */
static run_result one_run(vm_ctx *ctx, const char *in, const char *out, int method,
                          int local_threshold, long fail_at) {
  run_result r = {0, "", 0, -1, {0, 0, 0}};
  long count0 = vm_ctx_alloc_count(ctx);
  vm_ctx_set_alloc_fail(ctx, fail_at);
  vm_mesh *m = NULL;
  r.st = vm_mesh_read(ctx, in, VM_FMT_AUTO, &m);
  r.at = "read";
  if (r.st >= 0) {
    vm_mesh_apply_fixed_field(m);
    r.st = vm_mesh_mark_boundary(m, VM_VERTEX_FIXED, NULL);
    r.at = "mark boundary";
  }
  if (r.st >= 0) {
    vm_volume_opts o = vm_volume_opts_default();
    o.method = (vm_untangle_method)method;
    o.max_iter = 40;
    o.opt_iter = 3;
    o.local_threshold = local_threshold;
    vm_volume_report rep;
    r.st = vm_volume_run(ctx, m, NULL, &o, &rep);
    r.at = "vm_volume_run";
    if (r.st >= 0) {
      r.M_final = rep.M_final;
      r.iters[0] = rep.iter_untangle;
      r.iters[1] = rep.iter_local;
      r.iters[2] = rep.iter_opt;
    }
  }
  if (r.st >= 0) {
    int w = vm_mesh_write(ctx, m, out, VM_FMT_AUTO, NULL);
    if (w < 0) {
      r.st = w;
      r.at = "write";
    }
  }
  vm_mesh_destroy(&m);
  vm_ctx_set_alloc_fail(ctx, 0);
  r.allocs = vm_ctx_alloc_count(ctx) - count0;
  return r;
}

/* files in dir other than `keep` */
static int stray_files(const char *dir, const char *keep) {
  DIR *d = opendir(dir);
  int n = 0;
  struct dirent *e;
  while (d && (e = readdir(d)))
    if (e->d_name[0] != '.' && strcmp(e->d_name, keep)) {
      fprintf(stderr, "  stray file %s/%s\n", dir, e->d_name);
      n++;
    }
  if (d) closedir(d);
  return n;
}

int main(int argc, char **argv) {
  long stride = 1;
  if (argc == 3 && !strcmp(argv[1], "--stride")) stride = atol(argv[2]);
  if (stride < 1) stride = 1;
  const char *tmpdir = getenv("TMPDIR");
  char dir[512], in[600], out[600];
  snprintf(dir, sizeof dir, "%s/vm-alloc-sweep-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  snprintf(in, sizeof in, "%s/tangled.vmsh", dir);

  /* the input: a 5^3 cube whose 8 inner vertices are turned by pi/2 */
  {
    vm_ctx *g = NULL;
    vm_mesh *m = NULL;
    if (vm_ctx_create(&g)) return 1;
    vm_rotcube_opts o = vm_rotcube_opts_default();
    o.n = 5;
    o.inner = 0.2;
    o.alpha = 1.5707963267948966;
    CHECK(vm_gen_rotated_cube(g, &o, &m, NULL) == VM_OK, "generate: %s", vm_ctx_error(g));
    CHECK(vm_mesh_write(g, m, in, VM_FMT_VMSH, NULL) >= 0, "write input: %s", vm_ctx_error(g));
    vm_mesh_destroy(&m);
    vm_ctx_destroy(&g);
  }

  /* output format, method (-1: the default), local_threshold (0: global only) */
  static const struct {
    const char *ext;
    int method, local;
  } runs[] = {{"vmsh", VM_UNTANGLE_PENALTY, 0},
              {"vtu", VM_UNTANGLE_BARRIER, 0},
              {"msh", -1, 100},
              {"vmsht", VM_UNTANGLE_PENALTY_ONEWAY, 100}};
  long tried = 0;
  for (size_t k = 0; k < sizeof runs / sizeof runs[0]; k++) {
    int method = runs[k].method < 0 ? (int)vm_volume_opts_default().method : runs[k].method;
    snprintf(out, sizeof out, "%s/out.%s", dir, runs[k].ext);
    vm_ctx *ctx = NULL;
    if (vm_ctx_create(&ctx)) return 1;
    vm_ctx_set_threads(ctx, 1); /* the allocation order must be the same every run */
    long live0 = vm_ctx_alloc_live(ctx);
    run_result ref = one_run(ctx, in, out, method, runs[k].local, 0);
    CHECK(ref.st >= 0, "reference run (%s, %s): %s failed: %d %s", runs[k].ext,
          vm_untangle_method_name((vm_untangle_method)method), ref.at, ref.st, vm_ctx_error(ctx));
    CHECK(vm_ctx_alloc_live(ctx) == live0, "reference run leaked %ld blocks",
          vm_ctx_alloc_live(ctx) - live0);
    fprintf(stderr,
            "%s, %s: reference run: status %d, M_final %lld, %d untangling + %d local + %d "
            "optimization iterations, %ld allocations\n",
            runs[k].ext, vm_untangle_method_name((vm_untangle_method)method), ref.st,
            (long long)ref.M_final, ref.iters[0], ref.iters[1], ref.iters[2], ref.allocs);
    long nomem = 0, ok = 0;
    for (long n = 1; n <= ref.allocs; n += stride) {
      remove(out);
      run_result r = one_run(ctx, in, out, method, runs[k].local, n);
      tried++;
      long leak = vm_ctx_alloc_live(ctx) - live0;
      CHECK(leak == 0, "%s: failing allocation %ld (%s: status %d): %ld blocks leaked", runs[k].ext,
            n, r.at, r.st, leak);
      CHECK(r.st == VM_ERR_NOMEM || r.st >= 0,
            "%s: failing allocation %ld: %s returned %d, not VM_ERR_NOMEM: %s", runs[k].ext, n,
            r.at, r.st, vm_ctx_error(ctx));
      if (r.st < 0) {
        nomem++;
        CHECK(access(out, F_OK) != 0, "%s: failing allocation %ld: output written anyway",
              runs[k].ext, n);
        CHECK(vm_ctx_error(ctx)[0] != 0, "%s: failing allocation %ld: no message", runs[k].ext, n);
      } else {
        ok++;
        CHECK(r.st == ref.st && r.M_final == ref.M_final,
              "%s: allocation %ld failed but the run went on to a different result (%d, M %lld)",
              runs[k].ext, n, r.st, (long long)r.M_final);
      }
      CHECK(stray_files(dir, "tangled.vmsh") <= (r.st >= 0),
            "%s: failing allocation %ld: "
            "files left behind",
            runs[k].ext, n);
      if (vmtest_failures > 20) break;
    }
    fprintf(stderr, "%s: %ld failing allocations tried: %ld clean VM_ERR_NOMEM, %ld tolerated\n",
            runs[k].ext, (ref.allocs + stride - 1) / stride, nomem, ok);
    remove(out);
    vm_ctx_destroy(&ctx);
  }
  fprintf(stderr, "alloc sweep: %ld runs with a failing allocation\n", tried);
  remove(in);
  rmdir(dir);
  return vmtest_end("test_alloc_sweep");
}
