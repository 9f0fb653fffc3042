/* test/io_gmsh/test_medit.c: MEDIT .mesh round trips, element orientation, refs
 * (element refs are the tags "gmsh:physical"; names are lost, warned),
 * required vertices, a hand-written file with every cell type, 2D files. */
#include "gmsh_testlib.h"

static tlog lg;

static vm_mesh *write_read(vm_ctx *ctx, const vm_mesh *m, const char *file, int *wst) {
  char path[256];
  tdir_path(path, sizeof path, file);
  *wst = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL);
  CHECK(*wst >= 0, "%s: write failed: %s", file, vm_ctx_error(ctx));
  vm_mesh *b = NULL;
  int st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &b);
  CHECK(st == VM_OK, "%s: read back failed: %s", file, vm_ctx_error(ctx));
  return b;
}

/* Grouped by type (MEDIT's order), with refs, fixed vertices, awkward doubles. */
static vm_mesh *build_grouped(vm_ctx *ctx) {
  static const int types[9] = {VM_TRI,   VM_TRI,   VM_QUAD, VM_TET, VM_PYRAMID,
                               VM_PRISM, VM_PRISM, VM_HEX,  VM_HEX};
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 9; i++) add_ref_cell(m, types[i], 1.5 * i);
  m->xyz[0] = -0.0;
  m->xyz[1] = 0.1;
  m->xyz[2] = 4.9406564584124654e-324;
  m->xyz[3 * 9 + 2] = 1.0 / 3.0;
  vm_field *f;
  vm_mesh_add_field(m, "medit:ref", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f);
  for (int64_t v = 0; v < m->nv; v++) ((int32_t *)f->data)[v] = (int32_t)(v % 4) - 1;
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(100 + e);
  m->vflag[3] = VM_VERTEX_FIXED;
  m->vflag[m->nv - 1] = VM_VERTEX_FIXED;
  return m;
}

static void test_round_trip(vm_ctx *ctx) {
  long live0 = vm_ctx_alloc_live(ctx);
  vm_mesh *m = build_grouped(ctx);
  tlog_reset(&lg);
  int wst;
  vm_mesh *b = write_read(ctx, m, "grouped.mesh", &wst);
  CHECK(wst == VM_OK && lg.nwarn == 0, "grouped: status %d warnings %s", wst, lg.all);
  if (b) {
    check_same_mesh(m, b, "grouped.mesh");
    CHECK(b->nfield == 2 && b->nattr == 0, "grouped: %d fields", b->nfield);
    vm_mesh_destroy(&b);
  }
  /* 2D */
  vm_mesh *t;
  vm_mesh_create(ctx, &t);
  add_ref_cell(t, VM_TRI, 0);
  add_ref_cell(t, VM_QUAD, 1.25);
  t->dim = 2;
  t->vflag[2] = VM_VERTEX_FIXED;
  b = write_read(ctx, t, "flat.mesh", &wst);
  CHECK(wst == VM_OK, "2D write status %d", wst);
  if (b) {
    check_same_mesh(t, b, "flat.mesh");
    vm_mesh_destroy(&b);
  }
  vm_mesh_destroy(&t);
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "round trip leaks");
}

static void test_orientation(vm_ctx *ctx) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  for (int t = 0; t < VM_NTYPES; t++) add_ref_cell(m, t, 3.0 * t);
  int wst;
  vm_mesh *b = write_read(ctx, m, "cells.mesh", &wst);
  if (!b) goto out;
  CHECK(b->ne == VM_NTYPES, "%lld cells", (long long)b->ne);
  for (int64_t e = 0; e < b->ne && e < VM_NTYPES; e++) {
    double v = elem_measure(b, e);
    CHECK(b->etype[e] == e && v > 0 && v == ref_area_or_volume[e], "MEDIT %s measure %g",
          vm_elem_name(b->etype[e]), v);
  }
  vm_mesh_destroy(&b);
out:
  vm_mesh_destroy(&m);
}

static void test_lossy(vm_ctx *ctx) {
  vm_mesh *m = build_grouped(ctx);
  int32_t v[3] = {0, 1, 2};
  vm_mesh_add_element(m, VM_TRI, v); /* a triangle after the hexahedra */
  vm_mesh_remove_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, NULL);
  vm_mesh_add_field(m, "weight", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, NULL);
  vm_mesh_set_attr(m, "gmsh:physical_name:3:1", "fluid");
  m->vflag[0] = VM_VERTEX_SLIP;
  m->vsurf[0] = 2;
  tlog_reset(&lg);
  int wst;
  vm_mesh *b = write_read(ctx, m, "lossy.mesh", &wst);
  CHECK(wst == VM_WARN_LOSSY, "lossy status %d", wst);
  CHECK(lg.nwarn == 4 && tlog_has(&lg, "'weight'") &&
            tlog_has(&lg, "the name 'fluid' of reference 1 cannot be stored") &&
            tlog_has(&lg, "1 slip vertices") && tlog_has(&lg, "groups elements by type"),
        "lossy warnings (%d): %s", lg.nwarn, lg.all);
  if (b) {
    int64_t ca[VM_NTYPES], cb[VM_NTYPES];
    vm_mesh_count_types(m, ca);
    vm_mesh_count_types(b, cb);
    CHECK(!memcmp(ca, cb, sizeof ca), "same cells after regrouping");
    CHECK(b->etype[0] == VM_TRI && b->etype[1] == VM_TRI && b->etype[2] == VM_TRI,
          "triangles first");
    CHECK(b->vflag[0] == VM_VERTEX_FREE && b->vflag[3] == VM_VERTEX_FIXED, "slip lost, fixed kept");
    vm_mesh_destroy(&b);
  }
  vm_mesh_destroy(&m);
}

static const char medit_all[] =
    "# written by hand\n"
    "MeshVersionFormatted 2\n"
    "Dimension\n3\n"
    "Identifier\nmy mesh name\n"
    "vertices\n10\n"
    "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n0 0 1 2\n1 0 1 2\n1 1 1 2\n0 1 1 2\n"
    "0.5 0.5 1.5 3\n0.5 0.5 -1 4\n"
    "Edges\n2\n1 2 5\n2 3 5\n"
    "Triangles\n1\n1 2 4 10\n"
    "Quadrilaterals\n1\n1 2 3 4 11\n"
    "# volume cells\n"
    "TETRAHEDRA\n1\n1 2 4 5 20\n"
    "Pyramids\n2\n5 6 7 8 9 21\n1 4 3 2 10 22\n"
    "Prisms\n1\n1 2 4 5 6 8 23\n"
    "Hexaedra\n1\n1 2 3 4 5 6 7 8 24   # Dobrzynski's spelling\n"
    "Corners\n2\n1\n7\n"
    "Ridges\n1\n1\n"
    "RequiredVertices\n2\n1\n9\n"
    "Normals\n1\n0 0 1\n"
    "NormalAtVertices\n1\n1 1\n"
    "End\n";

static void test_hand_file(vm_ctx *ctx) {
  tlog_reset(&lg);
  vm_mesh *m = read_ok(ctx, "all.mesh", medit_all, sizeof medit_all - 1, VM_FMT_MEDIT);
  if (!m) return;
  static const int want[7] = {VM_TRI, VM_QUAD, VM_TET, VM_PYRAMID, VM_PYRAMID, VM_PRISM, VM_HEX};
  static const double vol[7] = {0.5, 1, 1.0 / 6.0, 1.0 / 6.0, 1.0 / 3.0, 0.5, 1};
  CHECK(m->nv == 10 && m->ne == 7 && m->dim == 3, "nv %lld ne %lld", (long long)m->nv,
        (long long)m->ne);
  for (int64_t e = 0; e < m->ne && e < 7; e++) {
    CHECK(m->etype[e] == want[e], "cell %lld is a %s", (long long)e, vm_elem_name(m->etype[e]));
    CHECK_NEAR(elem_measure(m, e), vol[e], 1e-15, vm_elem_name(m->etype[e]));
    CHECK(ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, e) == (e < 2 ? 10 : 18) + e,
          "cell %lld ref %d", (long long)e, ifield(m, "gmsh:physical", VM_FIELD_ELEMENT, e));
  }
  CHECK(ifield(m, "medit:ref", VM_FIELD_VERTEX, 9) == 4 &&
            ifield(m, "medit:ref", VM_FIELD_VERTEX, 4) == 2,
        "vertex refs");
  CHECK(m->vflag[0] == VM_VERTEX_FIXED && m->vflag[8] == VM_VERTEX_FIXED &&
            m->vflag[1] == VM_VERTEX_FREE,
        "required vertices are fixed");
  CHECK(lg.nwarn == 6 && tlog_has(&lg, "ignored 2 Edges") && tlog_has(&lg, "ignored 2 Corners") &&
            tlog_has(&lg, "ignored Identifier") && tlog_has(&lg, "ignored 1 Normals"),
        "warnings (%d): %s", lg.nwarn, lg.all);
  vm_mesh_destroy(&m);

  static const char flat[] =
      "MeshVersionFormatted 1\nDimension 2\nVertices\n4\n0 0 5\n1 0 5\n1 1 6\n"
      "0 1 6\nTriangles\n2\n1 2 3 1\n1 3 4 2\nend\n";
  m = read_ok(ctx, "flat.mesh", flat, sizeof flat - 1, VM_FMT_MEDIT);
  if (m) {
    CHECK(m->dim == 2 && m->ne == 2 && m->xyz[3 * 2 + 2] == 0.0, "2D file");
    CHECK(elem_measure(m, 0) > 0 && elem_measure(m, 1) > 0, "2D triangles counter-clockwise");
    vm_mesh_destroy(&m);
  }
}

/* Element refs: "gmsh:physical" is written and read back as such; an
 * element field "medit:ref" (what older readers made) is written when
 * there is no "gmsh:physical", and dropped with a warning when there is. */
static void test_ref_fields(vm_ctx *ctx) {
  vm_mesh *m = build_grouped(ctx);
  vm_field *f;
  vm_mesh_remove_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  vm_mesh_add_field(m, "medit:ref", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(7 * e - 3);
  tlog_reset(&lg);
  int wst;
  vm_mesh *b = write_read(ctx, m, "legacy.mesh", &wst);
  CHECK(wst == VM_OK && lg.nwarn == 0, "legacy refs: status %d, warnings %s", wst, lg.all);
  int64_t bad = 0;
  for (int64_t e = 0; b && e < b->ne; e++)
    bad += ifield(b, "gmsh:physical", VM_FIELD_ELEMENT, e) != 7 * e - 3;
  CHECK(b && !bad && !vm_mesh_find_field(b, "medit:ref", VM_FIELD_ELEMENT),
        "legacy refs read back as gmsh:physical (%lld differ)", (long long)bad);
  vm_mesh_destroy(&b);
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(e % 3);
  tlog_reset(&lg);
  b = write_read(ctx, m, "both.mesh", &wst);
  CHECK(wst == VM_WARN_LOSSY && lg.nwarn == 1 && tlog_has(&lg, "element field 'medit:ref'"),
        "both: status %d, warnings %s", wst, lg.all);
  bad = 0;
  for (int64_t e = 0; b && e < b->ne; e++)
    bad += ifield(b, "gmsh:physical", VM_FIELD_ELEMENT, e) != e % 3;
  CHECK(b && !bad, "both: gmsh:physical written (%lld differ)", (long long)bad);
  vm_mesh_destroy(&b);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  vm_ctx_set_log(ctx, tlog_fn, &lg);
  tdir_make();
  long live0 = vm_ctx_alloc_live(ctx);
  test_round_trip(ctx);
  test_orientation(ctx);
  test_lossy(ctx);
  test_ref_fields(ctx);
  test_hand_file(ctx);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leaked %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  tdir_remove();
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_medit");
}
