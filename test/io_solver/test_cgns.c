/* test/io_solver/test_cgns.c: the CGNS reader reads back exactly what the
 * writer writes (coordinates bit for bit, cells grouped by type as the
 * writer stores them, families, cell fields), again after a second write
 * and through .vmsh; reads a file written directly with libcgns (a MIXED
 * section, a BC by point list, faces without a BC, vertex and cell
 * solutions); refuses garbage with one line; leaves no temporary file.
 * Skipped (77) in a build without libcgns. */
#include <dirent.h>

#include "solver_testlib.h"

#if __has_include(<cgnslib.h>)
#include <cgnslib.h>
#define HAVE_CGNSLIB_H 1
#endif

static vm_ctx *ctx;
static char dir[] = "/tmp/vm_cgns_XXXXXX";
static char tmpdir[] = "/tmp/vm_cgns_tmp_XXXXXX";

static void path_in(char *buf, size_t n, const char *name) { snprintf(buf, n, "%s/%s", dir, name); }

static int files_in(const char *d) {
  DIR *h = opendir(d);
  int n = 0;
  struct dirent *e;
  while (h && (e = readdir(h))) n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
  if (h) closedir(h);
  return n;
}

static void test_round_trip(void) {
  char a[256], b[256], c[256], d[256];
  path_in(a, sizeof a, "a.cgns");
  path_in(b, sizeof b, "b.cgns");
  path_in(c, sizeof c, "c.vmsh");
  path_in(d, sizeof d, "d.cgns");
  vm_mesh *m = layered_mesh(ctx, 5), *r = NULL, *r2 = NULL, *r3 = NULL, *r4 = NULL;
  /* families, int and f64 cell fields: nothing lost */
  int st = vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  CHECK(st == VM_OK, "write: status %d: %s", st, vm_ctx_error(ctx));
  st = vm_mesh_read(ctx, a, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r, "read: %s", vm_ctx_error(ctx));
  if (!r) {
    vm_mesh_destroy(&m);
    return;
  }
  static const char *const fields[] = {"layer", "thickness", NULL};
  compare_read_back("cgns", m, r, 1, fields);
  /* written again and read: the same mesh; also through .vmsh */
  CHECK(vm_mesh_write(ctx, r, b, VM_FMT_AUTO, NULL) == VM_OK, "rewrite: %s", vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, b, VM_FMT_AUTO, &r2) == VM_OK, "reread: %s", vm_ctx_error(ctx));
  const char *diff = r2 ? mesh_diff(r, r2) : "not read";
  CHECK(!diff, "cgns -> cgns: %s", diff);
  CHECK(vm_mesh_write(ctx, r, c, VM_FMT_AUTO, NULL) == VM_OK, "vmsh: %s", vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, c, VM_FMT_AUTO, &r3) == VM_OK, "vmsh read: %s", vm_ctx_error(ctx));
  if (r3)
    CHECK(vm_mesh_write(ctx, r3, d, VM_FMT_AUTO, NULL) >= 0, "to cgns: %s", vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, d, VM_FMT_AUTO, &r4) == VM_OK, "read d: %s", vm_ctx_error(ctx));
  diff = r4 ? mesh_diff(r, r4) : "not read";
  CHECK(!diff, "cgns -> vmsh -> cgns: %s", diff);
  /* from memory */
  size_t len;
  char *bytes = slurp(a, &len);
  vm_mesh *r5 = NULL;
  CHECK(vm_mesh_read_memory(ctx, "mem.cgns", (const uint8_t *)bytes, len, VM_FMT_AUTO, &r5) ==
            VM_OK,
        "memory: %s", vm_ctx_error(ctx));
  diff = r5 ? mesh_diff(r, r5) : "not read";
  CHECK(!diff, "memory read: %s", diff);
  /* an allocation failing at every allocation of the read: a clean error
   * each time, nothing leaked */
  long before = vm_ctx_alloc_count(ctx);
  vm_mesh *r6 = NULL;
  vm_mesh_read_memory(ctx, "mem.cgns", (const uint8_t *)bytes, len, VM_FMT_AUTO, &r6);
  vm_mesh_destroy(&r6);
  long nalloc = vm_ctx_alloc_count(ctx) - before, leaks = 0, silent = 0;
  for (long k = 1; k <= nalloc; k++) {
    long live = vm_ctx_alloc_live(ctx);
    vm_ctx_set_alloc_fail(ctx, k);
    int s2 = vm_mesh_read_memory(ctx, "mem.cgns", (const uint8_t *)bytes, len, VM_FMT_AUTO, &r6);
    vm_ctx_set_alloc_fail(ctx, 0);
    silent += s2 >= 0;
    vm_mesh_destroy(&r6);
    leaks += vm_ctx_alloc_live(ctx) != live;
  }
  CHECK(nalloc > 5 && !leaks && !silent,
        "alloc-failure sweep over %ld allocations: %ld leaks, "
        "%ld failures not reported",
        nalloc, leaks, silent);
  free(bytes);
  vm_mesh *mm[] = {r, r2, r3, r4, r5, m};
  for (int i = 0; i < 6; i++) vm_mesh_destroy(&mm[i]);
  remove(a);
  remove(b);
  remove(c);
  remove(d);
}

/* A surface mesh: a base of cell dimension 2 with a TRI_3 and a QUAD_4
 * section, read back bit for bit with its cell fields; triangles and quads
 * interleaved come back grouped by type, each in mesh order. */
static void test_surface(void) {
  char a[256], b[256];
  path_in(a, sizeof a, "surface.cgns");
  path_in(b, sizeof b, "interleaved.cgns");
  vm_mesh *m = surface_mesh(ctx, 0), *mi = surface_mesh(ctx, 1), *r = NULL, *ri = NULL;
  vm_field *fi, *fd;
  /* each field is found again after the last one is added: adding a field
   * may move the array that holds the others */
  vm_mesh_add_field(m, "patch", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &fi);
  vm_mesh_add_field(m, "size", VM_FIELD_ELEMENT, VM_FIELD_F64, 1, &fd);
  fi = vm_mesh_find_field(m, "patch", VM_FIELD_ELEMENT);
  fd = vm_mesh_find_field(m, "size", VM_FIELD_ELEMENT);
  for (int64_t e = 0; e < m->ne; e++) {
    ((int32_t *)fi->data)[e] = 1 + (m->etype[e] == VM_QUAD);
    ((double *)fd->data)[e] = 1.0 / (double)(e + 3);
  }
  int st = vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  CHECK(st == VM_OK, "surface write: status %d: %s", st, vm_ctx_error(ctx));
  st = vm_mesh_read(ctx, a, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r, "surface read: %s", vm_ctx_error(ctx));
  const char *diff = r ? mesh_diff(m, r) : "not read";
  CHECK(!diff, "surface round trip: %s", diff);
  st = vm_mesh_write(ctx, mi, b, VM_FMT_AUTO, NULL);
  CHECK(st == VM_OK, "interleaved write: status %d: %s", st, vm_ctx_error(ctx));
  st = vm_mesh_read(ctx, b, VM_FMT_AUTO, &ri);
  CHECK(st == VM_OK && ri, "interleaved read: %s", vm_ctx_error(ctx));
  vm_mesh *plain = surface_mesh(ctx, 0);
  diff = ri ? mesh_diff(plain, ri) : "not read";
  CHECK(!diff, "interleaved round trip: %s", diff);
  vm_mesh *mm[] = {m, mi, r, ri, plain};
  for (int i = 0; i < 5; i++) vm_mesh_destroy(&mm[i]);
  remove(a);
  remove(b);
}

#ifdef HAVE_CGNSLIB_H
/* A file written with libcgns directly, in ways the writer does not. */
static void test_foreign(void) {
  char p[256];
  path_in(p, sizeof p, "foreign.cgns");
  int fn, B, Z, C, S, BC, F;
  cgsize_t size[3] = {6, 3, 0};
  double x[6] = {0, 1, 0, 0, 1, 0.5}, y[6] = {0, 0, 1, 0, 1, 0.5}, z[6] = {0, 0, 0, 1, 0, -1};
  /* MIXED: tet, tet, pyramid (elements 1..3); TRI_3 4..5 (no BC); QUAD_4 6 (BC "inlet") */
  cgsize_t mixed[] = {CGNS_ENUMV(TETRA_4),
                      1,
                      2,
                      3,
                      4,
                      CGNS_ENUMV(TETRA_4),
                      2,
                      5,
                      3,
                      4,
                      CGNS_ENUMV(PYRA_5),
                      1,
                      2,
                      5,
                      3,
                      6};
  cgsize_t moff[4] = {0, 5, 10, 16};
  cgsize_t tris[] = {1, 3, 4, 2, 5, 4}, quad[] = {1, 3, 5, 2};
  cgsize_t list[1] = {6};
  double pv[6] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  int idv[3] = {7, 8, 9};
  int ok = !cg_open(p, CG_MODE_WRITE, &fn) && !cg_base_write(fn, "b", 3, 3, &B) &&
           !cg_zone_write(fn, B, "z", size, CGNS_ENUMV(Unstructured), &Z) &&
           !cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), "CoordinateX", x, &C) &&
           !cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), "CoordinateY", y, &C) &&
           !cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), "CoordinateZ", z, &C) &&
           !cg_poly_section_write(fn, B, Z, "cells", CGNS_ENUMV(MIXED), 1, 3, 0, mixed, moff, &S) &&
           !cg_section_write(fn, B, Z, "quads", CGNS_ENUMV(QUAD_4), 6, 6, 0, quad, &S) &&
           !cg_section_write(fn, B, Z, "sym", CGNS_ENUMV(TRI_3), 4, 5, 0, tris, &S) &&
           !cg_boco_write(fn, B, Z, "inlet", CGNS_ENUMV(BCInflow), CGNS_ENUMV(PointList), 1, list,
                          &BC) &&
           !cg_boco_gridlocation_write(fn, B, Z, BC, CGNS_ENUMV(FaceCenter)) &&
           !cg_sol_write(fn, B, Z, "nodes", CGNS_ENUMV(Vertex), &S) &&
           !cg_field_write(fn, B, Z, S, CGNS_ENUMV(RealDouble), "p", pv, &F) &&
           !cg_sol_write(fn, B, Z, "cellsol", CGNS_ENUMV(CellCenter), &S) &&
           !cg_field_write(fn, B, Z, S, CGNS_ENUMV(Integer), "id", idv, &F);
  ok = !cg_close(fn) && ok;
  CHECK(ok, "libcgns: %s", cg_get_error());
  vm_mesh *m = NULL;
  CHECK(vm_mesh_read(ctx, p, VM_FMT_AUTO, &m) == VM_OK && m, "foreign: %s", vm_ctx_error(ctx));
  if (m) {
    CHECK(m->nv == 6 && m->ne == 6, "foreign: %lld vertices, %lld elements", (long long)m->nv,
          (long long)m->ne);
    static const int types[6] = {VM_TET, VM_TET, VM_PYRAMID, VM_TRI, VM_TRI, VM_QUAD};
    for (int e = 0; e < 6 && e < m->ne; e++)
      CHECK(m->etype[e] == types[e], "foreign: element %d type %d", e, m->etype[e]);
    CHECK(m->ne == 6 && m->conn[m->eoff[2] + 4] == 5, "foreign: pyramid apex");
    const int32_t *t = i32_field(m, "gmsh:physical");
    char b1[32];
    CHECK(t && !strcmp(family_of(m, 5, b1, sizeof b1), "inlet") &&
              !strcmp(family_of(m, 3, b1, sizeof b1), "sym") && t[0] == 0,
          "foreign: families");
    const int32_t *id = i32_field(m, "id");
    CHECK(id && id[0] == 7 && id[2] == 9 && id[3] == 0, "foreign: cell field");
    const vm_field *pf = vm_mesh_find_field(m, "p", VM_FIELD_VERTEX);
    CHECK(pf && ((double *)pf->data)[5] == 0.6, "foreign: vertex field");
  }
  vm_mesh_destroy(&m);
  remove(p);
}
#endif

#ifdef HAVE_CGNSLIB_H
/* A base of cell dimension 2 holding a tetrahedron: refused, one line. */
static void test_surface_with_cells(void) {
  char p[256];
  path_in(p, sizeof p, "surface-tet.cgns");
  int fn, B, Z, C, S;
  cgsize_t size[3] = {4, 1, 0};
  double x[4] = {0, 1, 0, 0}, y[4] = {0, 0, 1, 0}, z[4] = {0, 0, 0, 1};
  cgsize_t tet[4] = {1, 2, 3, 4};
  int ok = !cg_open(p, CG_MODE_WRITE, &fn) && !cg_base_write(fn, "b", 2, 3, &B) &&
           !cg_zone_write(fn, B, "z", size, CGNS_ENUMV(Unstructured), &Z) &&
           !cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), "CoordinateX", x, &C) &&
           !cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), "CoordinateY", y, &C) &&
           !cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), "CoordinateZ", z, &C) &&
           !cg_section_write(fn, B, Z, "tets", CGNS_ENUMV(TETRA_4), 1, 1, 0, tet, &S);
  ok = !cg_close(fn) && ok;
  CHECK(ok, "libcgns: %s", cg_get_error());
  vm_mesh *m = NULL;
  int st = vm_mesh_read(ctx, p, VM_FMT_AUTO, &m);
  CHECK(st == VM_ERR_FORMAT && !m &&
            strstr(vm_ctx_error(ctx), "a TETRA_4 in a base of cell dimension 2") &&
            !strchr(vm_ctx_error(ctx), '\n'),
        "tet in a surface base: status %d, '%s'", st, vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
  remove(p);
}
#endif

static void expect_fail(const char *name, const void *buf, size_t len, const char *want) {
  long live0 = vm_ctx_alloc_live(ctx);
  vm_mesh *m = NULL;
  int st = vm_mesh_read_memory(ctx, name, buf, len, VM_FMT_CGNS, &m);
  const char *e = vm_ctx_error(ctx);
  CHECK(st < 0 && !m, "%s: status %d", name, st);
  CHECK(!strncmp(e, name, strlen(name)) && !strchr(e, '\n'), "%s: message '%s'", name, e);
  CHECK(!want || strstr(e, want), "%s: message '%s' lacks '%s'", name, e, want);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leak", name);
  vm_mesh_destroy(&m);
  fprintf(stderr, "  refused: %s\n", e);
}

static void test_bad(void) {
  expect_fail("empty.cgns", "", 0, "not a readable CGNS file");
  static const char text[] = "NDIME= 3\nNELEM= 0\nNPOIN= 0\n";
  expect_fail("su2-text.cgns", text, sizeof text - 1, "not a readable CGNS file");
  uint8_t junk[4096];
  for (size_t i = 0; i < sizeof junk; i++) junk[i] = (uint8_t)(i * 2654435761u >> 13);
  expect_fail("junk.cgns", junk, sizeof junk, NULL);
  /* a real file cut short, at a few lengths */
  char a[256];
  path_in(a, sizeof a, "cut.cgns");
  vm_mesh *m = layered_mesh(ctx, 3);
  vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  vm_mesh_destroy(&m);
  size_t len;
  char *bytes = slurp(a, &len);
  int nread = 0;
  for (int k = 1; k < 8; k++) {
    size_t n = len * (size_t)k / 8;
    vm_mesh *r = NULL;
    long live0 = vm_ctx_alloc_live(ctx);
    int st = vm_mesh_read_memory(ctx, "cut.cgns", (const uint8_t *)bytes, n, VM_FMT_CGNS, &r);
    const char *e = vm_ctx_error(ctx);
    if (st >= 0)
      nread++;
    else
      CHECK(!strncmp(e, "cut.cgns: ", 10) && !strchr(e, '\n'), "cut at %zu: message '%s'", n, e);
    vm_mesh_destroy(&r);
    CHECK(vm_ctx_alloc_live(ctx) == live0, "cut at %zu: leak", n);
  }
  fprintf(stderr, "  truncated files: %d of 7 read (HDF5 may not need the tail)\n", nread);
  free(bytes);
  remove(a);
}

int main(void) {
  if (!vm_have_cgns()) {
    fprintf(stderr, "cgns: built without libcgns, skipped\n");
    return 77;
  }
  vm_ctx_create(&ctx);
  if (!mkdtemp(dir) || !mkdtemp(tmpdir)) return 1;
  setenv("TMPDIR", tmpdir, 1); /* where the reader's temporary files go */
  test_round_trip();
  test_surface();
#ifdef HAVE_CGNSLIB_H
  test_foreign();
  test_surface_with_cells();
#endif
  test_bad();
  CHECK(files_in(tmpdir) == 0, "%d temporary files left in %s", files_in(tmpdir), tmpdir);
  rmdir(tmpdir);
  rmdir(dir);
  long live = vm_ctx_alloc_live(ctx);
  CHECK(live == 0, "%ld blocks live at the end", live);
  vm_ctx_destroy(&ctx);
  return vmtest_end("cgns");
}
