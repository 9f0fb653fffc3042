/* lib/io/src/su2.c: SU2's native mesh format (ASCII), cells plus
 * one marker per boundary-face family. */
#include <stdio.h>

#include "families_private.h"
#include "varmesh/io.h"
#include "formats_private.h"

int vm_write_su2(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  if (!m || !path) return vm_error(ctx, VM_ERR_ARG, "vm_write_su2: NULL argument");
  if (m->dim != 3) return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: SU2 export needs a 3D mesh", path);
  ex_groups g;
  int st = ex_groups_build(ctx, m, &g);
  if (st) {
    ex_groups_free(ctx, &g);
    return st < 0 ? st : VM_ERR_ARG;
  }
  vm_outfile *of = NULL;
  if ((st = vm_outfile_open(ctx, path, &of))) {
    ex_groups_free(ctx, &g);
    return st;
  }
  FILE *f = vm_outfile_fp(of);
  fprintf(f, "%% SU2 mesh written by varmesh %s\nNDIME= 3\nNELEM= %lld\n", vm_version(),
          (long long)g.ncell);
  for (int64_t c = 0; c < g.ncell; c++) {
    int32_t e = g.cell[c];
    fprintf(f, "%d", vm_elem_to_vtk(m->etype[e]));
    for (int64_t k = 0; k < m->eoff[e + 1] - m->eoff[e]; k++)
      fprintf(f, " %d", (int)m->conn[m->eoff[e] + vm_elem_vtk_node(m->etype[e], (int)k)]);
    fprintf(f, " %lld\n", (long long)c);
  }
  fprintf(f, "NPOIN= %lld\n", (long long)m->nv);
  for (int64_t v = 0; v < m->nv; v++)
    fprintf(f, "%.17g %.17g %.17g %lld\n", m->xyz[3 * v], m->xyz[3 * v + 1], m->xyz[3 * v + 2],
            (long long)v);
  fprintf(f, "NMARK= %d\n", g.nfam);
  for (int fam = 0; fam < g.nfam; fam++) {
    fprintf(f, "MARKER_TAG= %s\nMARKER_ELEMS= %lld\n", g.name[fam],
            (long long)(g.fbeg[fam + 1] - g.fbeg[fam]));
    for (int64_t k = g.fbeg[fam]; k < g.fbeg[fam + 1]; k++) {
      fprintf(f, "%d", g.fnv[k] == 3 ? 5 : 9);
      for (int i = 0; i < g.fnv[k]; i++) fprintf(f, " %d", (int)g.fv[4 * k + i]);
      fputc('\n', f);
    }
  }
  ex_groups_free(ctx, &g);
  if (ferror(f)) {
    vm_outfile_abort(&of);
    return vm_error(ctx, VM_ERR_IO, "%s: write failed", path);
  }
  if ((st = vm_outfile_commit(&of))) return st;
  if (m->nfield || m->nattr) {
    vm_log(ctx, VM_LOG_WARN, "%s: SU2 cannot store fields or attributes; dropped", path);
    return VM_WARN_LOSSY;
  }
  return VM_OK;
}
