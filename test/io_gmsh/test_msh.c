/* test/io_gmsh/test_msh.c: Gmsh .msh round trips (4.1/2.2, ASCII/binary), element
 * orientation, hand-written 4.1 and 2.2 files, groups, data and flags. */
#include "gmsh_testlib.h"

static tlog lg;

/* Mixed mesh with awkward doubles, groups, fields of both types and flags.
 * Element types and entities interleave: the 4.1 writer's blocks are runs
 * of one entity and type in mesh order, the elements numbered 1..N in the
 * order written (so readers that go by file position, like meshio, put
 * element data on the right cells). */
static vm_mesh *build_mixed(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  static const int types[8] = {VM_TET,   VM_TRI,     VM_HEX, VM_QUAD,
                               VM_PRISM, VM_PYRAMID, VM_TET, VM_HEX};
  static const int32_t phys[8] = {1, 5, 1, 5, 1, 2, 2, 0};
  static const int32_t ent[8] = {1, 2, 1, 2, 3, 4, 4, 6};
  for (int i = 0; i < 8; i++) add_ref_cell(m, types[i], 2.0 * i);
  m->xyz[0] = -0.0;
  m->xyz[1] = 0.1;
  m->xyz[2] = 1.0 / 3.0;
  m->xyz[4] = 4.9406564584124654e-324;
  m->xyz[5] = -1e300;
  m->xyz[3 * 7 + 1] = 0.30000000000000004;
  vm_field *f;
  vm_mesh_add_field(m, "temperature", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  for (int64_t v = 0; v < m->nv; v++) ((double *)f->data)[v] = 0.1 * (double)v + 1.0 / 7.0;
  vm_mesh_add_field(m, "velocity", VM_FIELD_VERTEX, VM_FIELD_F64, 3, &f);
  for (int64_t v = 0; v < 3 * m->nv; v++)
    ((double *)f->data)[v] = v % 5 ? 1e-310 * (double)v : -0.0;
  vm_mesh_add_field(m, "fixed", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f);
  for (int64_t v = 0; v < m->nv; v++) ((int32_t *)f->data)[v] = v % 3 == 0;
  vm_mesh_add_field(m, "weight", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((double *)f->data)[e] = 1.0 / (double)(e + 3);
  ((double *)f->data)[2] = HUGE_VAL; /* data fields may hold non-finite values */
  ((double *)f->data)[3] = -HUGE_VAL;
  vm_mesh_add_field(m, "layer", VM_FIELD_ELEMENT, VM_FIELD_I32, 2, &f);
  for (int64_t e = 0; e < 2 * m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(e * 7 - 20);
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  memcpy(f->data, phys, sizeof phys);
  vm_mesh_add_field(m, "gmsh:entity", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  memcpy(f->data, ent, sizeof ent);
  vm_mesh_set_attr(m, "gmsh:physical_name:3:1", "fluid region");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:5", "wall");
  vm_mesh_set_attr(m, "gmsh:physical_name:3:2", "inlet's block");
  m->vflag[0] = VM_VERTEX_FIXED;
  m->vflag[1] = VM_VERTEX_SLIP;
  m->vsurf[1] = 3;
  m->vflag[5] = VM_VERTEX_SLIP;
  m->vsurf[5] = 0;
  return m;
}

static const struct {
  int version, binary;
  const char *file;
} variants[4] = {{41, 0, "a41.msh"}, {41, 1, "b41.msh"}, {22, 0, "a22.msh"}, {22, 1, "b22.msh"}};

static vm_mesh *round_trip(vm_ctx *ctx, const vm_mesh *m, int variant, int *wst) {
  char path[256];
  tdir_path(path, sizeof path, variants[variant].file);
  vm_write_opts o = vm_write_opts_default();
  o.msh_version = variants[variant].version;
  o.binary = variants[variant].binary;
  *wst = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, &o);
  CHECK(*wst >= 0, "%s: write failed: %s", path, vm_ctx_error(ctx));
  vm_mesh *b = NULL;
  int st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &b);
  CHECK(st == VM_OK, "%s: read back failed: %s", path, vm_ctx_error(ctx));
  return b;
}

static void test_round_trips(vm_ctx *ctx) {
  long live0 = vm_ctx_alloc_live(ctx);
  vm_mesh *m = build_mixed(ctx);
  CHECK(vm_mesh_check(m) == VM_OK, "mixed mesh invalid: %s", vm_ctx_error(ctx));
  for (int i = 0; i < 4; i++) {
    tlog_reset(&lg);
    int wst;
    vm_mesh *b = round_trip(ctx, m, i, &wst);
    CHECK(wst == VM_OK && lg.nwarn == 0, "%s: write status %d, warnings: %s", variants[i].file, wst,
          lg.all);
    if (!b) continue;
    check_same_mesh(m, b, variants[i].file);
    CHECK(b->nfield == m->nfield, "%s: %d fields, expected %d", variants[i].file, b->nfield,
          m->nfield);
    CHECK(b->nattr == m->nattr, "%s: %d attributes", variants[i].file, b->nattr);
    CHECK(lg.nwarn == 0, "%s: warnings on read: %s", variants[i].file, lg.all);
    vm_mesh_destroy(&b);
  }
  /* the ASCII file is what Gmsh users see: spot-check its layout */
  char path[256];
  size_t len;
  tdir_path(path, sizeof path, "a41.msh");
  char *txt = (char *)slurp(path, &len);
  if (txt) {
    txt[len] = 0;
    CHECK(strstr(txt, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n") == txt, "4.1 header");
    CHECK(strstr(txt, "3 1 \"fluid region\"") != NULL, "physical name written");
    CHECK(strstr(txt, "$Entities\n0 0 1 4\n") != NULL, "1 surface and 4 volume entities");
    CHECK(strstr(txt, "\"vm_flag\"") != NULL, "vertex flags as NodeData");
    /* 8 blocks of one element each (no two neighbours share entity and
     * type), tags 1..8 in file order */
    const char *el = strstr(txt, "$Elements\n8 8 1 8\n");
    CHECK(el != NULL, "8 blocks, 8 elements, tags 1 to 8");
    int ntag = 0, inorder = 1;
    for (const char *p = el ? strchr(el + 10, '\n') + 1 : NULL; p && ntag < 8; ntag++) {
      p = strchr(p, '\n') + 1; /* block header: dim, entity, type, 1 */
      inorder &= atoi(p) == ntag + 1;
      p = strchr(p, '\n') + 1;
    }
    CHECK(ntag == 8 && inorder, "4.1 element tags in file order (%d read)", ntag);
    free(txt);
  }
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "round trips leak %ld blocks",
        vm_ctx_alloc_live(ctx) - live0);
}

/* Each reference cell has a positive measure; so does its copy read back. */
static void test_orientation(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  for (int t = 0; t < VM_NTYPES; t++) add_ref_cell(m, t, 3.0 * t);
  for (int64_t e = 0; e < m->ne; e++)
    CHECK_NEAR(elem_measure(m, e), ref_area_or_volume[m->etype[e]], 1e-14,
               vm_elem_name(m->etype[e]));
  for (int i = 0; i < 4; i++) {
    int wst;
    vm_mesh *b = round_trip(ctx, m, i, &wst);
    if (!b) continue;
    CHECK(b->ne == VM_NTYPES, "%s: %lld elements", variants[i].file, (long long)b->ne);
    for (int64_t e = 0; e < b->ne && e < VM_NTYPES; e++) {
      double v = elem_measure(b, e);
      CHECK(b->etype[e] == e && v > 0 && v == elem_measure(m, e), "%s: %s measure %g",
            variants[i].file, vm_elem_name(b->etype[e]), v);
    }
    vm_mesh_destroy(&b);
  }
  vm_mesh_destroy(&m);
}

/* Gmsh 4.1 as Gmsh writes it: entities, sparse and unsorted node tags, a
 * parametric node block, point and line elements, unsorted element tags,
 * two time steps, data for a skipped element, sections we do not know. */
static const char gmsh41[] =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    "$Comments\nwritten by hand\n$EndComments\n"
    "$PhysicalNames\n2\n2 20 \"wall\"\n3 10 \"solid body\"\n$EndPhysicalNames\n"
    "$Entities\n1 0 1 1\n"
    "7 5 5 5 0\n"
    "1 0 0 0 1 1 1 1 20 0\n"
    "1 0 0 0 1 1 1.5 1 10 1 1\n"
    "$EndEntities\n"
    "$Nodes\n4 12 10 1000000000\n"
    "0 7 0 1\n1000000000\n5 5 5\n"
    "3 1 0 8\n10\n20\n30\n40\n50\n60\n70\n80\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    "3 1 0 1\n90\n0.5 0.5 1.5\n"
    "2 1 1 2\n92\n91\n0 1 1 0.25 0.75\n1 1 1 0.5 0.5\n"
    "$EndNodes\n"
    "$Elements\n7 8 1 100\n"
    "0 7 15 1\n100 1000000000\n"
    "3 1 5 1\n5 10 20 30 40 50 60 70 80\n"
    "2 1 3 2\n4 50 60 91 92\n3 10 20 30 40\n"
    "3 1 4 1\n1 10 20 40 50\n"
    "1 5 1 1\n50 10 20\n"
    "3 1 6 1\n2 10 20 40 50 60 80\n"
    "3 1 7 1\n6 10 20 30 40 90\n"
    "$EndElements\n"
    "$Foo\n$Bar \x01\x02 $EndFo\n$EndFoo\n"
    "$NodeData\n1\n\"temperature\"\n1\n0.0\n3\n0\n1\n12\n"
    "10 1\n20 2\n30 3\n40 4\n50 5\n60 6\n70 7\n80 8\n90 9\n91 10\n92 11\n1000000000 12\n"
    "$EndNodeData\n"
    "$NodeData\n1\n\"temperature\"\n1\n1.0\n3\n1\n1\n1\n10 100\n$EndNodeData\n"
    "$ElementData\n1\n\"quality\"\n1\n0.0\n3\n0\n1\n4\n1 0.5\n2 0.25\n5 1\n100 "
    "7\n$EndElementData\n";

static void test_gmsh41_file(vm_ctx *ctx) {
  long live0 = vm_ctx_alloc_live(ctx);
  tlog_reset(&lg);
  vm_mesh *m = read_ok(ctx, "hand41.msh", gmsh41, sizeof gmsh41 - 1, VM_FMT_MSH);
  if (!m) return;
  CHECK(m->nv == 12 && m->ne == 6, "nv %lld ne %lld", (long long)m->nv, (long long)m->ne);
  CHECK(m->dim == 3, "dim %d", m->dim);
  /* elements come back in tag order: tet 1, prism 2, quad 3, quad 4, hex 5, pyramid 6 */
  static const int want[6] = {VM_TET, VM_PRISM, VM_QUAD, VM_QUAD, VM_HEX, VM_PYRAMID};
  static const int32_t wphys[6] = {10, 10, 20, 20, 10, 10};
  for (int64_t e = 0; e < m->ne && e < 6; e++) {
    CHECK(m->etype[e] == want[e], "element %lld is a %s", (long long)e, vm_elem_name(m->etype[e]));
    CHECK(ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, e) == wphys[e], "element %lld physical %d",
          (long long)e, ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, e));
    CHECK(ifield(m, "gmsh:entity", VM_FIELD_ELEMENT, e) == 1, "element %lld entity", (long long)e);
    if (vm_elem_dim(m->etype[e]) == 3)
      CHECK(elem_measure(m, e) > 0, "element %lld (%s) has measure %g", (long long)e,
            vm_elem_name(m->etype[e]), elem_measure(m, e));
  }
  CHECK_NEAR(elem_measure(m, 4), 1.0, 1e-15, "hex volume");
  CHECK_NEAR(elem_measure(m, 1), 0.5, 1e-15, "prism volume");
  CHECK_NEAR(elem_measure(m, 5), 0.5, 1e-15, "pyramid volume");
  CHECK_NEAR(elem_measure(m, 0), 1.0 / 6.0, 1e-15, "tet volume");
  /* vertices in tag order: 10..80 -> 0..7, 90 -> 8, 91 -> 9, 92 -> 10, 1e9 -> 11 */
  CHECK(m->xyz[3 * 9] == 1 && m->xyz[3 * 10] == 0 && m->xyz[3 * 11] == 5, "sorted by tag");
  CHECK(m->conn[m->eoff[3] + 2] == 9 && m->conn[m->eoff[3] + 3] == 10, "quad 4 uses 91, 92");
  const char *a = vm_mesh_get_attr(m, "gmsh:physical_name:3:10");
  CHECK(a && !strcmp(a, "solid body"), "physical name with a space: %s", a ? a : "(none)");
  a = vm_mesh_get_attr(m, "gmsh:physical_name:2:20");
  CHECK(a && !strcmp(a, "wall"), "physical name wall");
  CHECK(dfield(m, "temperature", VM_FIELD_VERTEX, 11, 0) == 12.0 &&
            dfield(m, "temperature", VM_FIELD_VERTEX, 0, 0) == 1.0,
        "first time step kept");
  CHECK(dfield(m, "quality", VM_FIELD_ELEMENT, 4, 0) == 1.0 &&
            dfield(m, "quality", VM_FIELD_ELEMENT, 2, 0) == 0.0,
        "element data by tag");
  CHECK(tlog_has(&lg, "skipped 1 point and 1 line"), "point/line warning: %s", lg.all);
  CHECK(tlog_has(&lg, "skipped 1 more"), "time step warning: %s", lg.all);
  CHECK(tlog_has(&lg, "$Foo") && !tlog_has(&lg, "$Comments"), "unknown section warning: %s",
        lg.all);
  CHECK(tlog_has(&lg, "ignored 1 element data"), "orphan data warning: %s", lg.all);
  CHECK(tlog_has(&lg, "'quality' has values for 3 of 6"), "partial data warning: %s", lg.all);
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "hand41 leaks");
}

static const char gmsh22[] =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n2\n3 1 \"volume\"\n2 2 \"boundary\"\n$EndPhysicalNames\n"
    "$Nodes\n9\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n"
    "9 0.5 0.5 -1\n$EndNodes\n"
    "$Elements\n7\n"
    "1 15 2 0 1 1\n"
    "2 4 2 1 11 1 2 4 5\n"
    "3 6 2 1 11 1 2 4 5 6 8\n"
    "4 7 2 1 12 1 4 3 2 9\n"
    "5 5 3 1 13 0 1 2 3 4 5 6 7 8\n"
    "7 2 2 2 21 1 2 4\n"
    "6 3 0 5 6 7 8\n"
    "$EndElements\n";

static void test_gmsh22_file(vm_ctx *ctx) {
  tlog_reset(&lg);
  vm_mesh *m = read_ok(ctx, "hand22.msh", gmsh22, sizeof gmsh22 - 1, VM_FMT_MSH);
  if (!m) return;
  CHECK(m->nv == 9 && m->ne == 6, "nv %lld ne %lld", (long long)m->nv, (long long)m->ne);
  static const int want[6] = {VM_TET, VM_PRISM, VM_PYRAMID, VM_HEX, VM_QUAD, VM_TRI};
  static const int32_t wphys[6] = {1, 1, 1, 1, 0, 2}, went[6] = {11, 11, 12, 13, 0, 21};
  for (int64_t e = 0; e < m->ne && e < 6; e++) {
    CHECK(m->etype[e] == want[e], "2.2 element %lld is a %s", (long long)e,
          vm_elem_name(m->etype[e]));
    CHECK(ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, e) == wphys[e] &&
              ifield(m, "gmsh:entity", VM_FIELD_ELEMENT, e) == went[e],
          "2.2 element %lld tags", (long long)e);
    if (vm_elem_dim(m->etype[e]) == 3)
      CHECK(elem_measure(m, e) > 0, "2.2 %s measure %g", vm_elem_name(m->etype[e]),
            elem_measure(m, e));
  }
  CHECK(elem_measure(m, 5) > 0, "2.2 triangle counter-clockwise");
  CHECK(tlog_has(&lg, "skipped 1 point and 0 line"), "2.2 point warning: %s", lg.all);
  const char *a = vm_mesh_get_attr(m, "gmsh:physical_name:2:2");
  CHECK(a && !strcmp(a, "boundary"), "2.2 physical name");
  vm_mesh_destroy(&m);
}

/* 2.2 binary assembled byte by byte: two element headers, tags, NodeData. */
static void build_bin22(tbuf *b) {
  static const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  tb_str(b, "$MeshFormat\n2.2 1 8\n");
  tb_i32(b, 1);
  tb_str(b, "\n$EndMeshFormat\n$Nodes\n5\n");
  for (int i = 0; i < 5; i++) {
    tb_i32(b, 5 - i); /* numbered backwards */
    for (int c = 0; c < 3; c++) tb_f64(b, xyz[4 - i][c]);
  }
  tb_str(b, "\n$EndNodes\n$Elements\n3\n");
  tb_i32(b, 4); /* header: tets, 1 element, 2 tags */
  tb_i32(b, 1);
  tb_i32(b, 2);
  int32_t tet[7] = {9, 7, 3, 1, 2, 3, 4};
  for (int i = 0; i < 7; i++) tb_i32(b, tet[i]);
  tb_i32(b, 2); /* header: triangles, 2 elements, 3 tags */
  tb_i32(b, 2);
  tb_i32(b, 3);
  int32_t tri[2][7] = {{4, 8, 5, 0, 1, 2, 3}, {2, 8, 5, 0, 2, 5, 3}};
  for (int j = 0; j < 2; j++)
    for (int i = 0; i < 7; i++) tb_i32(b, tri[j][i]);
  tb_str(b, "\n$EndElements\n$NodeData\n1\n\"h\"\n0\n3\n0\n1\n2\n");
  tb_i32(b, 5);
  tb_f64(b, 0.5);
  tb_i32(b, 1);
  tb_f64(b, 0.25);
  tb_str(b, "\n$EndNodeData\n");
}

static void test_gmsh22_binary(vm_ctx *ctx) {
  tbuf b = {0};
  build_bin22(&b);
  tlog_reset(&lg);
  vm_mesh *m = read_ok(ctx, "bin22.msh", b.p, b.n, VM_FMT_MSH);
  if (m) {
    CHECK(m->nv == 5 && m->ne == 3, "bin22 nv %lld ne %lld", (long long)m->nv, (long long)m->ne);
    /* element numbers 2, 4, 9 -> triangle, triangle, tet */
    CHECK(m->etype[0] == VM_TRI && m->etype[1] == VM_TRI && m->etype[2] == VM_TET, "bin22 types");
    CHECK(elem_measure(m, 2) > 0, "bin22 tet positive: %g", elem_measure(m, 2));
    CHECK(ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, 2) == 7 &&
              ifield(m, "gmsh:entity", VM_FIELD_ELEMENT, 2) == 3 &&
              ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, 0) == 8,
          "bin22 tags");
    CHECK(m->conn[m->eoff[0] + 1] == 4, "bin22 triangle 2 uses node 5 (the last)");
    CHECK(dfield(m, "h", VM_FIELD_VERTEX, 4, 0) == 0.5 &&
              dfield(m, "h", VM_FIELD_VERTEX, 0, 0) == 0.25,
          "bin22 node data");
    CHECK(m->xyz[3 * 4] == 1 && m->xyz[3 * 4 + 2] == 1, "bin22 node 5 coordinates");
    vm_mesh_destroy(&m);
  }
  tb_free(&b);
}

/* A 4.1 binary file by hand, in this machine's byte order and swapped. */
static void build_bin41(tbuf *b, int swap) {
  b->swap = swap;
  tb_str(b, "$MeshFormat\n4.1 1 8\n");
  tb_i32(b, 1);
  tb_str(b, "\n$EndMeshFormat\n$PhysicalNames\n1\n3 4 \"v\"\n$EndPhysicalNames\n$Entities\n");
  tb_u64(b, 0);
  tb_u64(b, 0);
  tb_u64(b, 0);
  tb_u64(b, 1);
  tb_i32(b, 2); /* volume 2, physical 4, no bounding surfaces */
  for (int i = 0; i < 6; i++) tb_f64(b, i < 3 ? 0 : 1);
  tb_u64(b, 1);
  tb_i32(b, 4);
  tb_u64(b, 0);
  tb_str(b, "\n$EndEntities\n$Nodes\n");
  tb_u64(b, 1);
  tb_u64(b, 6);
  tb_u64(b, 1);
  tb_u64(b, 6);
  tb_i32(b, 3);
  tb_i32(b, 2);
  tb_i32(b, 1); /* parametric: u v w follow each node */
  tb_u64(b, 6);
  for (int i = 1; i <= 6; i++) tb_u64(b, (uint64_t)i);
  static const double pri[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  for (int i = 0; i < 6; i++) {
    for (int c = 0; c < 3; c++) tb_f64(b, pri[i][c]);
    for (int c = 0; c < 3; c++) tb_f64(b, -7.0);
  }
  tb_str(b, "\n$EndNodes\n$Elements\n");
  tb_u64(b, 1);
  tb_u64(b, 1);
  tb_u64(b, 1);
  tb_u64(b, 1);
  tb_i32(b, 3);
  tb_i32(b, 2);
  tb_i32(b, 6);
  tb_u64(b, 1);
  tb_u64(b, 1);
  for (int i = 1; i <= 6; i++) tb_u64(b, (uint64_t)i);
  tb_str(b, "\n$EndElements\n$ElementData\n1\n\"q\"\n1\n0\n3\n0\n1\n1\n");
  tb_i32(b, 1);
  tb_f64(b, 2.5);
  tb_str(b, "\n$EndElementData\n");
}

static void test_gmsh41_binary(vm_ctx *ctx) {
  for (int swap = 0; swap < 2; swap++) {
    tbuf b = {0};
    build_bin41(&b, swap);
    vm_mesh *m = read_ok(ctx, swap ? "swapped41.msh" : "native41.msh", b.p, b.n, VM_FMT_MSH);
    if (m) {
      CHECK(m->nv == 6 && m->ne == 1 && m->etype[0] == VM_PRISM, "bin41 (swap %d) content", swap);
      CHECK_NEAR(elem_measure(m, 0), 0.5, 1e-15, "bin41 prism volume");
      CHECK(m->xyz[3 * 4] == 1 && m->xyz[3 * 4 + 2] == 1, "bin41 parametric coordinates skipped");
      CHECK(ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, 0) == 4 &&
                ifield(m, "gmsh:entity", VM_FIELD_ELEMENT, 0) == 2,
            "bin41 groups");
      CHECK(dfield(m, "q", VM_FIELD_ELEMENT, 0, 0) == 2.5, "bin41 element data");
      const char *a = vm_mesh_get_attr(m, "gmsh:physical_name:3:4");
      CHECK(a && !strcmp(a, "v"), "bin41 physical name");
      vm_mesh_destroy(&m);
    }
    tb_free(&b);
  }
}

/* Things .msh cannot hold are reported, once each, as VM_WARN_LOSSY. */
static void test_lossy(vm_ctx *ctx) {
  vm_mesh *m = build_mixed(ctx);
  vm_mesh_set_attr(m, "author", "someone");
  vm_mesh_add_field(m, "bad\"name", VM_FIELD_VERTEX, VM_FIELD_F64, 1, NULL);
  vm_field *f = vm_mesh_find_field(m, "gmsh:entity", VM_FIELD_ELEMENT);
  ((int32_t *)f->data)[3] = 2; /* quad: entity 2 ... */
  ((int32_t *)vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT)->data)[3] =
      7;                       /* ... group 7 */
  ((int32_t *)f->data)[7] = 0; /* hex: no entity */
  for (int i = 0; i < 4; i++) {
    tlog_reset(&lg);
    int wst;
    vm_mesh *b = round_trip(ctx, m, i, &wst);
    CHECK(wst == VM_WARN_LOSSY, "%s: status %d", variants[i].file, wst);
    CHECK(lg.nwarn == 3, "%s: %d warnings: %s", variants[i].file, lg.nwarn, lg.all);
    CHECK(tlog_has(&lg, "'author'") && tlog_has(&lg, "bad\"name") &&
              tlog_has(&lg, "new gmsh:entity"),
          "%s: warnings %s", variants[i].file, lg.all);
    if (!b) continue;
    CHECK(ifield(b, "gmsh:physical", VM_FIELD_ELEMENT, 3) == 7 &&
              ifield(b, "gmsh:physical", VM_FIELD_ELEMENT, 1) == 5,
          "%s: groups kept although entities were split", variants[i].file);
    int32_t e1 = ifield(b, "gmsh:entity", VM_FIELD_ELEMENT, 1),
            e3 = ifield(b, "gmsh:entity", VM_FIELD_ELEMENT, 3);
    CHECK(e1 == 2 && e3 > 2, "%s: entities %d %d", variants[i].file, e1, e3);
    CHECK(ifield(b, "gmsh:entity", VM_FIELD_ELEMENT, 7) > 4, "%s: fresh entity for the hex",
          variants[i].file);
    CHECK(!vm_mesh_get_attr(b, "author"), "attribute not invented");
    vm_mesh_destroy(&b);
  }
  vm_mesh_destroy(&m);
}

/* Meshes without groups, 2D meshes, planar 3D meshes, empty meshes. */
static void test_plain_meshes(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  add_ref_cell(m, VM_TRI, 0);
  add_ref_cell(m, VM_QUAD, 2);
  m->dim = 2;
  for (int i = 0; i < 4; i++) {
    int wst;
    vm_mesh *b = round_trip(ctx, m, i, &wst);
    CHECK(wst == VM_OK, "2D write %d", wst);
    if (!b) continue;
    check_same_mesh(m, b, "2D");
    CHECK(ifield(b, "gmsh:physical", VM_FIELD_ELEMENT, 1) == 0 &&
              ifield(b, "gmsh:entity", VM_FIELD_ELEMENT, 0) >= 1,
          "groups invented consistently");
    vm_mesh_destroy(&b);
  }
  m->dim = 3; /* a planar surface in 3D stays 3D */
  vm_field *f;
  vm_mesh_add_field(m, "missing", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  ((double *)f->data)[1] = NAN;
  int wst;
  for (int i = 0; i < 2; i++) {
    vm_mesh *b = round_trip(ctx, m, i, &wst);
    if (!b) continue;
    CHECK(b->dim == 3, "planar 3D surface kept dim 3");
    CHECK(isnan(dfield(b, "missing", VM_FIELD_VERTEX, 1, 0)) &&
              dfield(b, "missing", VM_FIELD_VERTEX, 2, 0) == 0,
          "NaN data value kept");
    vm_mesh_destroy(&b);
  }
  vm_mesh *b;
  vm_mesh_destroy(&m);
  static const char flat[] =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n"
      "0 0 0\n1 0 0\n0 1 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n"
      "$EndElements\n";
  m = read_ok(ctx, "flat.msh", flat, sizeof flat - 1, VM_FMT_MSH);
  if (m) {
    CHECK(m->dim == 2 && ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, 0) == 0,
          "Gmsh 2D file is 2D");
    vm_mesh_destroy(&m);
  }
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 4; i++) {
    b = round_trip(ctx, m, i, &wst);
    if (b) {
      CHECK(b->nv == 0 && b->ne == 0 && wst == VM_OK, "empty mesh");
      vm_mesh_destroy(&b);
    }
  }
  vm_mesh_destroy(&m);
}

/* Many physical names (sorted, appended once; the last of a key wins) and
 * $VarmeshInfo integer fields whose values are not integers. */
static void test_names_and_info(vm_ctx *ctx) {
  tbuf b = {0};
  tb_str(&b, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n60001\n");
  for (int i = 60000; i > 0; i--) {
    char line[64];
    snprintf(line, sizeof line, "%d %d \"g%d\"\n", i % 4, i, i);
    tb_str(&b, line);
  }
  tb_str(&b,
         "0 40000 \"last wins\"\n$EndPhysicalNames\n"
         "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n"
         "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n"
         "$VarmeshInfo\ni32 node \"a\"\ni32 element \"b\"\nfuture keyword 1 2\n$EndVarmeshInfo\n"
         "$NodeData\n1\n\"a\"\n0\n3\n0\n1\n3\n1 1\n2 2.5\n3 3\n$EndNodeData\n"
         "$ElementData\n1\n\"b\"\n0\n3\n0\n1\n1\n1 -7\n$EndElementData\n");
  tlog_reset(&lg);
  vm_mesh *m = read_ok(ctx, "names.msh", b.p, b.n, VM_FMT_MSH);
  if (m) {
    CHECK(m->nattr == 60000, "%d physical names", m->nattr);
    const char *a = vm_mesh_get_attr(m, "gmsh:physical_name:0:40000");
    CHECK(a && !strcmp(a, "last wins"), "duplicate key: %s", a ? a : "(none)");
    a = vm_mesh_get_attr(m, "gmsh:physical_name:1:12345");
    CHECK(a && !strcmp(a, "g12345"), "name 12345");
    const vm_field *f = vm_mesh_find_field(m, "a", VM_FIELD_VERTEX);
    CHECK(f && f->type == VM_FIELD_F64, "non-integral listed field stays f64");
    CHECK(tlog_has(&lg, "'a' is listed as integer"), "warning: %s", lg.all);
    CHECK(ifield(m, "b", VM_FIELD_ELEMENT, 0) == -7, "listed element field becomes i32");
    vm_mesh_destroy(&m);
  }
  tb_free(&b);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  vm_ctx_set_log(ctx, tlog_fn, &lg);
  tdir_make();
  long live0 = vm_ctx_alloc_live(ctx);
  test_round_trips(ctx);
  test_orientation(ctx);
  test_gmsh41_file(ctx);
  test_gmsh22_file(ctx);
  test_gmsh22_binary(ctx);
  test_gmsh41_binary(ctx);
  test_lossy(ctx);
  test_plain_meshes(ctx);
  test_names_and_info(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leaked %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  tdir_remove();
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_msh");
}
