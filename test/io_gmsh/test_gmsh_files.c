/* test/io_gmsh/test_gmsh_files.c: files written by Gmsh 4.8.4 itself (MSH 4.1 and 2.2,
 * ASCII and binary, MEDIT), see data/make_gmsh_data.py: counts, orientation, volume,
 * groups, datasets, and agreement between the four .msh encodings. */
#include "gmsh_testlib.h"

static tlog lg;

static vm_mesh *read_data_file(vm_ctx *ctx, const char *file) {
  const char *root = getenv("VM_SOURCE_ROOT");
  char path[1024];
  snprintf(path, sizeof path, "%s/test/io_gmsh/data/%s", root ? root : "..", file);
  vm_mesh *m = NULL;
  tlog_reset(&lg);
  int st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &m);
  CHECK(st == VM_OK, "%s: %s", path, vm_ctx_error(ctx));
  return st == VM_OK ? m : NULL;
}

/* mixed.geo: 4 triangles and 1 quadrangle on the floor (group 9), a hexahedron
 * (group 1), 24 tetrahedra and a pyramid (group 7), 26 prisms (group 8);
 * three unit boxes, so the volumes add up to 3. */
static void check_msh(const vm_mesh *m, const char *file) {
  static const int64_t want[VM_NTYPES] = {4, 1, 24, 1, 26, 1};
  static const int32_t group[VM_NTYPES] = {9, 9, 7, 7, 8, 1};
  int64_t c[VM_NTYPES];
  vm_mesh_count_types(m, c);
  CHECK(m->nv == 58 && m->dim == 3 && !memcmp(c, want, sizeof c), "%s: nv %lld, counts", file,
        (long long)m->nv);
  double vol = 0, idsum = 0;
  int bad = 0, badgroup = 0, badid = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    badgroup += ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, e) != group[t];
    double id = dfield(m, "cell id", VM_FIELD_ELEMENT, e, 0);
    double neg = dfield(m, "cell id", VM_FIELD_ELEMENT, e, 1);
    if (vm_elem_dim(t) == 2) {
      badid += id != 0 || neg != 0;
      continue;
    }
    double v = elem_measure(m, e);
    bad += !(v > 0);
    vol += v;
    /* the dataset holds each volume cell's model tag: 6 to 57, once each */
    badid += !(id >= 6 && id <= 57) || neg != -id;
    idsum += id;
  }
  CHECK(!bad, "%s: %d volume cells not positive", file, bad);
  CHECK_NEAR(vol, 3.0, 1e-12, file);
  CHECK(!badgroup, "%s: %d cells in the wrong physical group", file, badgroup);
  CHECK(!badid && idsum == (6 + 57) * 52 / 2, "%s: %d wrong 'cell id' values", file, badid);
  const char *a = vm_mesh_get_attr(m, "gmsh:physical_name:3:1");
  const char *b = vm_mesh_get_attr(m, "gmsh:physical_name:2:9");
  CHECK(a && !strcmp(a, "hex block") && b && !strcmp(b, "floor") && m->nattr == 3, "%s: names",
        file);
  int badnode = 0;
  for (int64_t v = 0; v < m->nv; v++) {
    const double *x = m->xyz + 3 * v;
    badnode +=
        fabs(dfield(m, "xyz sum", VM_FIELD_VERTEX, v, 0) - (x[0] + 2 * x[1] + 4 * x[2])) > 1e-12;
  }
  CHECK(!badnode, "%s: %d nodes with the wrong first time step value", file, badnode);
  CHECK(tlog_has(&lg, "skipped 1 more") && tlog_has(&lg, "'cell id' has values for 52 of 57"),
        "%s: warnings %s", file, lg.all);
}

/* The cell with a given 'cell id' has the same type and vertices in both
 * meshes (Gmsh numbers elements differently in 2.2 and 4.1 files). */
static int same_cells_by_id(const vm_mesh *a, const vm_mesh *b) {
  for (int64_t eb = 0; eb < b->ne; eb++) {
    double id = dfield(b, "cell id", VM_FIELD_ELEMENT, eb, 0);
    if (vm_elem_dim(b->etype[eb]) != 3) continue;
    int64_t ea = 0;
    while (ea < a->ne && dfield(a, "cell id", VM_FIELD_ELEMENT, ea, 0) != id) ea++;
    if (ea == a->ne || a->etype[ea] != b->etype[eb] ||
        memcmp(a->conn + a->eoff[ea], b->conn + b->eoff[eb],
               (size_t)vm_elem_nverts(a->etype[ea]) * sizeof(int32_t)))
      return 0;
  }
  return 1;
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  vm_ctx_set_log(ctx, tlog_fn, &lg);
  long live0 = vm_ctx_alloc_live(ctx);
  static const char *files[4] = {"gmsh41a.msh", "gmsh41b.msh", "gmsh22a.msh", "gmsh22b.msh"};
  vm_mesh *m[4];
  for (int i = 0; i < 4; i++) {
    m[i] = read_data_file(ctx, files[i]);
    if (m[i]) check_msh(m[i], files[i]);
  }
  /* the four encodings hold the same mesh: binary coordinates bit for bit,
   * ASCII ones to Gmsh's 16 printed digits; ASCII and binary of one version
   * element for element, the two versions cell for cell */
  for (int i = 1; i < 4; i++) {
    if (!m[0] || !m[i] || m[i]->nv != m[0]->nv || m[i]->ne != m[0]->ne) continue;
    const vm_mesh *twin = m[i == 3 ? 2 : 0];
    if (i != 2)
      CHECK(!memcmp(twin->etype, m[i]->etype, (size_t)m[i]->ne) &&
                !memcmp(twin->conn, m[i]->conn, (size_t)m[i]->eoff[m[i]->ne] * sizeof(int32_t)),
            "%s: connectivity differs from its ASCII twin", files[i]);
    CHECK(same_cells_by_id(m[0], m[i]), "%s: cells differ from %s", files[i], files[0]);
    double d = 0;
    for (int64_t k = 0; k < 3 * m[0]->nv; k++) d = fmax(d, fabs(m[0]->xyz[k] - m[i]->xyz[k]));
    CHECK(d <= 1e-15, "%s: coordinates differ by %g", files[i], d);
  }
  if (m[1] && m[3])
    CHECK(!memcmp(m[1]->xyz, m[3]->xyz, (size_t)m[1]->nv * 3 * sizeof(double)),
          "binary 4.1 and 2.2 coordinates bit for bit");
  /* Gmsh's MEDIT writer keeps tetrahedra, hexahedra, triangles, quadrangles */
  vm_mesh *md = read_data_file(ctx, "gmsh.mesh");
  if (md) {
    int64_t c[VM_NTYPES];
    vm_mesh_count_types(md, c);
    CHECK(md->nv == 58 && c[VM_TET] == 24 && c[VM_HEX] == 1 && c[VM_TRI] == 4 && c[VM_QUAD] == 1 &&
              c[VM_PRISM] == 0 && c[VM_PYRAMID] == 0,
          "gmsh.mesh counts");
    int bad = 0;
    for (int64_t e = 0; e < md->ne; e++)
      bad += vm_elem_dim(md->etype[e]) == 3 && !(elem_measure(md, e) > 0);
    CHECK(!bad, "gmsh.mesh: %d volume cells not positive", bad);
    CHECK(vm_mesh_find_field(md, "gmsh:physical", VM_FIELD_ELEMENT) != NULL, "gmsh.mesh refs");
    vm_mesh_destroy(&md);
  }
  for (int i = 0; i < 4; i++) vm_mesh_destroy(&m[i]);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leaked %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_gmsh_files");
}
