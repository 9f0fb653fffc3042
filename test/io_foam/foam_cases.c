/* test/io_foam/foam_cases.c: writes the cases test_foam_checkmesh.sh hands
 * to OpenFOAM's checkMesh: the cube meshes of foam_testlib.h (hexahedra,
 * prisms, pyramids, tetrahedra, all four) with named boundaries, ASCII and
 * binary, one without boundary elements, and a closed sphere (sphere.stl)
 * for vm-prism.
 * usage: foam_cases DIR */
#include "foam_testlib.h"
#include "varmesh/io.h"
#include "varmesh/shapes.h"

static int put(vm_ctx *ctx, const vm_mesh *m, const char *dir, const char *name, int fmt,
               int binary) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  vm_write_opts o = vm_write_opts_default();
  o.binary = binary;
  int st = vm_mesh_write(ctx, m, path, fmt, &o);
  if (st < 0) fprintf(stderr, "foam_cases: %s\n", vm_ctx_error(ctx));
  return st < 0;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: foam_cases DIR\n");
    return 2;
  }
  vm_ctx *ctx;
  if (vm_ctx_create(&ctx)) return 1;
  vm_ctx_set_log(ctx, NULL, NULL);
  int bad = 0;
  for (int kind = 0; kind < FT_NKIND; kind++) {
    vm_mesh *m = ft_cube(ctx, 6, kind, 0.2);
    if (!m) return 1;
    ft_tag_boundary(m);
    char name[64];
    snprintf(name, sizeof name, "%s.foam", ft_name[kind]);
    bad |= put(ctx, m, argv[1], name, VM_FMT_FOAM, 0);
    snprintf(name, sizeof name, "%s_bin.foam", ft_name[kind]);
    bad |= put(ctx, m, argv[1], name, VM_FMT_FOAM, 1);
    vm_mesh_destroy(&m);
  }
  vm_mesh *m = ft_cube(ctx, 4, FT_MIXED, 0.2);
  bad |= !m || put(ctx, m, argv[1], "plain.foam", VM_FMT_FOAM, 0);
  vm_mesh_destroy(&m);
  if (vm_mesh_create(ctx, &m) || vm_gen_icosphere(m, NULL, 1.0, 2, 0, NULL)) return 1;
  bad |= put(ctx, m, argv[1], "sphere.stl", VM_FMT_STL, 0);
  vm_mesh_destroy(&m);
  vm_ctx_destroy(&ctx);
  return bad;
}
