/* test/fuzz/gen_corpus.c: write the seed corpus of the reader fuzzers with
 * the library's own writers: a small mixed volume mesh with flags, fields and
 * attributes, a 2D mesh and a tri/quad surface, in every format and variant.
 * usage: gen_corpus OUTDIR   (writes OUTDIR/<reader>/gen-*) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "varmesh/ctx.h"
#include "varmesh/io.h"
#include "varmesh/mesh.h"

#define DIE(...)                                                                                   \
  do {                                                                                             \
    fprintf(stderr, __VA_ARGS__);                                                                  \
    fputc('\n', stderr);                                                                           \
    exit(1);                                                                                       \
  } while (0)

static void ok(vm_ctx *ctx, int st, const char *what) {
  if (st < 0) DIE("gen_corpus: %s: %s", what, vm_ctx_error(ctx));
}

/* hex + prism on top + pyramid and tet below, a boundary tri and quad */
static vm_mesh *volume_mesh(vm_ctx *ctx) {
  static const double x[][3] = {{0, 0, 0}, {1, 0, 0},    {1, 1, 0},   {0, 1, 0}, {0, 0, 1},
                                {1, 0, 1}, {1, 1, 1},    {0, 1, 1},   {0, 0, 2}, {1, 0, 2},
                                {1, 1, 2}, {.5, .5, -1}, {-1, .5, .5}};
  static const int32_t hex[] = {0, 1, 2, 3, 4, 5, 6, 7}, prism[] = {4, 5, 6, 8, 9, 10},
                       pyr[] = {0, 3, 2, 1, 11}, tet[] = {0, 4, 3, 12}, tri[] = {8, 9, 10},
                       quad[] = {0, 1, 5, 4};
  vm_mesh *m;
  ok(ctx, vm_mesh_create(ctx, &m), "create");
  for (int i = 0; i < 13; i++) ok(ctx, vm_mesh_add_vertex(m, x[i][0], x[i][1], x[i][2], NULL), "v");
  ok(ctx, vm_mesh_add_element(m, VM_HEX, hex), "hex");
  ok(ctx, vm_mesh_add_element(m, VM_PRISM, prism), "prism");
  ok(ctx, vm_mesh_add_element(m, VM_PYRAMID, pyr), "pyramid");
  ok(ctx, vm_mesh_add_element(m, VM_TET, tet), "tet");
  ok(ctx, vm_mesh_add_element(m, VM_TRI, tri), "tri");
  ok(ctx, vm_mesh_add_element(m, VM_QUAD, quad), "quad");
  for (int v = 0; v < 4; v++) m->vflag[v] = VM_VERTEX_FIXED;
  for (int v = 8; v < 11; v++) {
    m->vflag[v] = VM_VERTEX_SLIP;
    m->vsurf[v] = 3;
  }
  vm_field *f;
  ok(ctx, vm_mesh_add_field(m, "curvature", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f), "field");
  for (int64_t v = 0; v < m->nv; v++) ((double *)f->data)[v] = 0.25 * (double)v - 1;
  ok(ctx, vm_mesh_add_field(m, "layer", VM_FIELD_ELEMENT, VM_FIELD_I32, 2, &f), "field");
  for (int64_t e = 0; e < 2 * m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(e % 3);
  ok(ctx, vm_mesh_set_attr(m, "gmsh:physical_name:2:7", "wall"), "attr");
  ok(ctx, vm_mesh_set_attr(m, "note", "seed"), "attr");
  return m;
}

/* two triangles and a quad in the plane, dim 2 */
static vm_mesh *planar_mesh(vm_ctx *ctx) {
  static const int32_t t0[] = {0, 1, 2}, t1[] = {0, 2, 3}, q[] = {1, 4, 5, 2};
  vm_mesh *m;
  ok(ctx, vm_mesh_create(ctx, &m), "create");
  double x[][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0}, {2, 1}};
  for (int i = 0; i < 6; i++) ok(ctx, vm_mesh_add_vertex(m, x[i][0], x[i][1], 0, NULL), "v");
  m->dim = 2;
  ok(ctx, vm_mesh_add_element(m, VM_TRI, t0), "tri");
  ok(ctx, vm_mesh_add_element(m, VM_TRI, t1), "tri");
  ok(ctx, vm_mesh_add_element(m, VM_QUAD, q), "quad");
  return m;
}

/* a closed tetrahedron surface plus a quad fin, in 3D, awkward coordinates */
static vm_mesh *surface_mesh(vm_ctx *ctx) {
  static const int32_t f[][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  static const int32_t q[] = {1, 4, 5, 2};
  vm_mesh *m;
  ok(ctx, vm_mesh_create(ctx, &m), "create");
  double x[][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1e-300, 2, 3e10}, {-0.1, 1.5, 1}};
  for (int i = 0; i < 6; i++) ok(ctx, vm_mesh_add_vertex(m, x[i][0], x[i][1], x[i][2], NULL), "v");
  for (int i = 0; i < 4; i++) ok(ctx, vm_mesh_add_element(m, VM_TRI, f[i]), "tri");
  ok(ctx, vm_mesh_add_element(m, VM_QUAD, q), "quad");
  return m;
}

static void put(vm_ctx *ctx, const char *out, const char *dir, const char *file, const vm_mesh *m,
                int fmt, int binary, int mshver) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", out, dir);
  mkdir(path, 0777);
  snprintf(path, sizeof path, "%s/%s/%s", out, dir, file);
  vm_write_opts o = vm_write_opts_default();
  o.binary = binary;
  if (mshver) o.msh_version = mshver;
  ok(ctx, vm_mesh_write(ctx, m, path, fmt, &o), path);
}

int main(int argc, char **argv) {
  if (argc != 2) DIE("usage: gen_corpus OUTDIR");
  const char *out = argv[1];
  mkdir(out, 0777);
  vm_ctx *ctx;
  if (vm_ctx_create(&ctx)) DIE("no context");
  vm_mesh *vol = volume_mesh(ctx), *pl = planar_mesh(ctx), *sf = surface_mesh(ctx);
  const vm_mesh *ms[3] = {vol, pl, sf};
  const char *mn[3] = {"volume", "planar", "surface"};
  for (int i = 0; i < 3; i++) {
    char f[64];
    const vm_mesh *m = ms[i];
    snprintf(f, sizeof f, "gen-%s", mn[i]);
    put(ctx, out, "vmsh", f, m, VM_FMT_VMSH, 0, 0);
    put(ctx, out, "vmsht", f, m, VM_FMT_VMSH_TEXT, 0, 0);
    put(ctx, out, "vtu", f, m, VM_FMT_VTU, 1, 0);
    put(ctx, out, "medit", f, m, VM_FMT_MEDIT, 0, 0);
    snprintf(f, sizeof f, "gen-%s-ascii", mn[i]);
    put(ctx, out, "vtk", f, m, VM_FMT_VTK, 0, 0);
    put(ctx, out, "msh", f, m, VM_FMT_MSH, 0, 41);
    snprintf(f, sizeof f, "gen-%s-binary", mn[i]);
    put(ctx, out, "vtk", f, m, VM_FMT_VTK, 1, 0);
    put(ctx, out, "msh", f, m, VM_FMT_MSH, 1, 41);
    snprintf(f, sizeof f, "gen-%s-v22", mn[i]);
    put(ctx, out, "msh", f, m, VM_FMT_MSH, 0, 22);
    snprintf(f, sizeof f, "gen-%s-v22-binary", mn[i]);
    put(ctx, out, "msh", f, m, VM_FMT_MSH, 1, 22);
  }
  put(ctx, out, "stl", "gen-surface-ascii", sf, VM_FMT_STL, 0, 0);
  put(ctx, out, "stl", "gen-surface-binary", sf, VM_FMT_STL, 1, 0);
  put(ctx, out, "obj", "gen-surface", sf, VM_FMT_OBJ, 0, 0);
  put(ctx, out, "off", "gen-surface", sf, VM_FMT_OFF, 0, 0);
  put(ctx, out, "ply", "gen-surface-ascii", sf, VM_FMT_PLY, 0, 0);
  put(ctx, out, "ply", "gen-surface-binary", sf, VM_FMT_PLY, 1, 0);
  put(ctx, out, "obj", "gen-planar", pl, VM_FMT_OBJ, 0, 0);
  put(ctx, out, "off", "gen-planar", pl, VM_FMT_OFF, 0, 0);
  put(ctx, out, "ply", "gen-planar-binary", pl, VM_FMT_PLY, 1, 0);
  put(ctx, out, "su2", "gen-volume", vol, VM_FMT_SU2, 0, 0);
  put(ctx, out, "su2", "gen-surface", sf, VM_FMT_SU2, 0, 0);
  vm_mesh_destroy(&vol);
  vm_mesh_destroy(&pl);
  vm_mesh_destroy(&sf);
  vm_ctx_destroy(&ctx);
  return 0;
}
