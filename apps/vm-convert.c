/* apps/vm-convert.c: convert a mesh between the formats varmesh reads and
 * writes, saying what the target format cannot carry. */
#define _XOPEN_SOURCE 700 /* nftw */
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "varmesh/io.h"
#include "varmesh/symmetry.h"

typedef struct {
  const char *in, *out, *cut;
  double cut_snap;
  int fin, fout, strict, mirror;
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
    {"--mirror", NULL, VM_OPT_FLAG, A(mirror), NULL,
     "a half model (its symmetry plane named in the mesh, as the stages write it): write the "
     "whole, the half and its mirror image, the faces in the plane left out",
     .ival = 1},
    {"--strict", NULL, VM_OPT_FLAG, A(strict), NULL,
     "exit 3, writing nothing, if the output format cannot carry everything", .ival = 1},
    {"--cut", NULL, VM_OPT_STRING, A(cut), "AXIS=C[:+|:-]",
     "cut a closed triangle surface by the plane x, y or z = C and keep one side (:+ the side "
     "where the coordinate is above C, :- below; default the side the model reaches farther "
     "into): a half model, its open border exactly in the plane",
     .error = "expects a plane, e.g. y=0 or y=0:-"},
    {"--cut-snap", NULL, VM_OPT_DOUBLE, A(cut_snap), "F",
     "with --cut: where the plane would cut an edge within F of its length from an end, that "
     "vertex is moved onto the plane instead (no needle beside the cut; the surface moves by "
     "at most F of the edge there); default 0: only vertices within 1e-9 of the diagonal",
     .lo = 0, .hi = 0.49},
    VM_CLI_OPT_QUIET("no warnings"),
    VM_CLI_OPT_VERBOSE("debug messages too"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-convert [options] IN OUT\n"
    "Convert a mesh; formats from the extensions (.vmsh .vmsht .vtk .vtu .msh .mesh\n"
    ".stl .obj .off .ply .su2 .cgns .foam) unless forced. SU2 and CGNS take volume\n"
    "meshes and surface meshes (triangles and quadrilaterals in 3D). OpenFOAM (.foam\n"
    "or --format foam, write only): OUT is a case directory; OUT/constant/polyMesh\n"
    "is written (replaced in an existing case, whose other files stay).\n",
    opts,
    "exit: 0 ok, 1 bad input or I/O failure, 2 usage, 3 --strict and information would be\n"
    "lost (nothing written)\n",
    {A(in), A(out)},
    2,
    "need IN and OUT"};

/* --strict: a trial write into a private temporary directory first, its
 * messages held back and naming OUT; only a lossless trial lets the real
 * write happen (a lossy file was written before the exit 3, and with
 * OUT == IN the input was gone). */
typedef struct {
  vm_cli *cli;
  const char *trial, *out;
  char *held;
  size_t len;
} trial_log;

static void hold(void *user, int level, const char *msg) {
  trial_log *t = user;
  if (level != VM_LOG_WARN) return;
  char line[1400];
  const char *hit = strstr(msg, t->trial);
  if (hit)
    snprintf(line, sizeof line, "%.*s%s%s", (int)(hit - msg), msg, t->out, hit + strlen(t->trial));
  else
    snprintf(line, sizeof line, "%s", msg);
  size_t n = strlen(line) + 1;
  char *p = realloc(t->held, t->len + n);
  if (!p) return;
  memcpy(p + t->len, line, n);
  t->held = p;
  t->len += n;
}

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw) {
  (void)sb, (void)flag, (void)ftw;
  return remove(path);
}

/* VM_WARN_LOSSY if writing m as OUT would lose something (the warnings
 * printed, naming OUT), VM_OK if not, < 0 on a failure of the trial. */
static int strict_trial(vm_cli *cli, const vm_mesh *m, const char *out, int fmt,
                        const vm_write_opts *wo) {
  const char *tmpdir = getenv("TMPDIR");
  char dir[4096], trial[8192];
  snprintf(dir, sizeof dir, "%s/vm-convert-strict.XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
  if (!mkdtemp(dir))
    return vm_error(cli->ctx, VM_ERR_IO, "%s: cannot make a temporary directory", dir);
  const char *base = strrchr(out, '/');
  base = base ? base + 1 : out;
  snprintf(trial, sizeof trial, "%s/%s", dir, *base ? base : "out");
  trial_log t = {cli, trial, out, NULL, 0};
  vm_ctx_set_log(cli->ctx, hold, &t);
  int st = vm_mesh_write(cli->ctx, m, trial, fmt, wo);
  vm_ctx_set_log(cli->ctx, vm_cli_log, cli);
  nftw(dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
  if (st < 0) { /* the trial's error names OUT */
    char msg[1400];
    const char *e = vm_ctx_error(cli->ctx), *hit = strstr(e, trial);
    if (hit) {
      snprintf(msg, sizeof msg, "%.*s%s%s", (int)(hit - e), e, out, hit + strlen(trial));
      vm_error(cli->ctx, st, "%s", msg);
    }
  }
  if (st == VM_WARN_LOSSY)
    for (size_t i = 0; i < t.len; i += strlen(t.held + i) + 1)
      vm_cli_log(cli, VM_LOG_WARN, t.held + i);
  free(t.held);
  return st;
}

/* --cut: m cut by the plane, one side kept (varmesh/symmetry.h), said on
 * stderr. */
static int cut(vm_cli *cli, vm_mesh *m, int axis, double level, int side, double snap) {
  vm_cut_report r;
  int st = vm_mesh_cut_plane(m, axis, level, side, snap, &r);
  if (st < 0) return st;
  char pl[64];
  vm_axis_plane_format(axis, level, pl, sizeof pl);
  vm_log(cli->ctx, VM_LOG_INFO,
         "cut at %s, the %s side kept: %lld -> %lld triangles, %lld -> %lld vertices; %lld "
         "triangles clipped, %lld edges split, %lld vertices within %.3g and %lld near a cut "
         "snapped onto the plane, "
         "%lld zero-area triangles left out; %lld border edges",
         pl, r.side > 0 ? "+" : "-", (long long)r.nf_in, (long long)r.nf, (long long)r.nv_in,
         (long long)r.nv, (long long)r.clipped, (long long)r.split_edges, (long long)r.snapped,
         r.tol, (long long)r.snapped_near, (long long)r.degenerate, (long long)r.border_edges);
  if (r.border_off)
    vm_log(cli->ctx, VM_LOG_WARN,
           "cut: %lld border edges are not in the plane %s (the input was not closed)",
           (long long)r.border_off, pl);
  return VM_OK;
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-convert");
  args a = {.fin = VM_FMT_AUTO, .fout = VM_FMT_AUTO, .wo = vm_write_opts_default()};
  vm_mesh *m = NULL;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  int axis = 0, side = 0;
  double level = 0;
  if (a.cut && vm_axis_plane_parse(cli.ctx, a.cut, &axis, &level, &side)) {
    rc = vm_cli_usage_error(&cli, "--cut %s", vm_ctx_error(cli.ctx));
    goto done;
  }
  if (a.cut_snap > 0 && !a.cut) {
    rc = vm_cli_usage_error(&cli, "--cut-snap needs --cut");
    goto done;
  }
  if (a.fout == VM_FMT_AUTO && vm_format_from_path(a.out) == VM_FMT_AUTO) {
    rc = vm_cli_usage_error(&cli, "%s: cannot tell the output format; use --format", a.out);
    goto done;
  }
  int st = vm_mesh_read(cli.ctx, a.in, a.fin, &m);
  if (st >= 0 && a.cut) st = cut(&cli, m, axis, level, side, a.cut_snap);
  if (st >= 0 && a.mirror) {
    vm_mesh *whole = NULL;
    if ((st = vm_mesh_mirror(cli.ctx, m, &whole)) >= 0) {
      vm_mesh_destroy(&m);
      m = whole;
    }
  }
  if (st >= 0 && a.strict) {
    st = strict_trial(&cli, m, a.out, a.fout, &a.wo);
    if (st == VM_WARN_LOSSY) {
      vm_cli_error(&cli,
                   "%s: the output format cannot carry everything (see warnings); nothing written",
                   a.out);
      rc = VM_EXIT_CHECK;
      goto done;
    }
  }
  if (st >= 0) st = vm_mesh_write(cli.ctx, m, a.out, a.fout, &a.wo);
  if (st < 0) rc = vm_cli_input_error(&cli, NULL);
done:
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
