/* test/io_solver/test_su2.c: the SU2 reader reads back exactly what the
 * writer writes (a mixed prism-layer mesh with named families; a second
 * write is the same file but for the header line, also through .vmsh),
 * reads the general format (2D, any section order, optional indices,
 * comments, line markers), and refuses malformed input with one line
 * naming the line. */
#include "solver_testlib.h"

static vm_ctx *ctx;
static char dir[] = "/tmp/vm_su2_XXXXXX";

static void path_in(char *buf, size_t n, const char *name) { snprintf(buf, n, "%s/%s", dir, name); }

/* Files equal apart from their first line (the header comment). */
static int same_but_header(const char *p1, const char *p2) {
  char *a = slurp(p1, NULL), *b = slurp(p2, NULL);
  int same = a && b && !strcmp(strchr(a, '\n'), strchr(b, '\n'));
  free(a);
  free(b);
  return same;
}

static void test_round_trip(void) {
  char a[256], b[256], c[256], d[256];
  path_in(a, sizeof a, "a.su2");
  path_in(b, sizeof b, "b.su2");
  path_in(c, sizeof c, "c.vmsh");
  path_in(d, sizeof d, "d.su2");
  vm_mesh *m = layered_mesh(ctx, 5), *r = NULL, *r2 = NULL;
  int st = vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  CHECK(st == VM_WARN_LOSSY, "write: status %d: %s", st, vm_ctx_error(ctx));
  st = vm_mesh_read(ctx, a, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK, "read: %s", vm_ctx_error(ctx));
  if (!r) {
    vm_mesh_destroy(&m);
    return;
  }
  CHECK(r->dim == 3, "dim %d", r->dim);
  compare_read_back("su2", m, r, 0, NULL);
  CHECK(!strcmp(vm_mesh_get_attr(r, "gmsh:physical_name:2:3")
                    ? vm_mesh_get_attr(r, "gmsh:physical_name:2:3")
                    : "",
                "boundary_7"),
        "third marker's name");
  /* written again: the same file but for the header; and through .vmsh */
  /* the families are all it has: written again without loss */
  CHECK(vm_mesh_write(ctx, r, b, VM_FMT_AUTO, NULL) == VM_OK, "rewrite: %s", vm_ctx_error(ctx));
  CHECK(same_but_header(a, b), "su2 -> su2 differs");
  CHECK(vm_mesh_write(ctx, r, c, VM_FMT_AUTO, NULL) == VM_OK, "vmsh: %s", vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, c, VM_FMT_AUTO, &r2) == VM_OK, "vmsh read: %s", vm_ctx_error(ctx));
  if (r2) {
    CHECK(vm_mesh_write(ctx, r2, d, VM_FMT_AUTO, NULL) >= 0, "vmsh -> su2: %s", vm_ctx_error(ctx));
    CHECK(same_but_header(a, d), "su2 -> vmsh -> su2 differs");
  }
  /* from memory, the same mesh */
  size_t len;
  char *text = slurp(a, &len);
  vm_mesh *r3 = NULL;
  CHECK(vm_mesh_read_memory(ctx, "mem.su2", (const uint8_t *)text, len, VM_FMT_SU2, &r3) == VM_OK,
        "memory: %s", vm_ctx_error(ctx));
  if (r3) {
    const char *diff = mesh_diff(r, r3);
    CHECK(!diff, "memory read differs: %s", diff);
  }
  free(text);
  vm_mesh_destroy(&r3);
  vm_mesh_destroy(&r2);
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);
  remove(a);
  remove(b);
  remove(c);
  remove(d);
}

/* A surface mesh (triangles and quads in any order) is written as NDIME= 3
 * with its faces as NELEM and NMARK= 0, one warning that SU2's solvers
 * need volume cells, and read back bit for bit in the same order; tags are
 * lost (warned); a 2D mesh and a mesh without elements are refused. */
static void test_surface(void) {
  char a[256], b[256];
  path_in(a, sizeof a, "surface.su2");
  path_in(b, sizeof b, "tagged.su2");
  vm_mesh *m = surface_mesh(ctx, 1), *r = NULL;
  tlog lg = {0};
  vm_ctx_set_log(ctx, tlog_fn, &lg);
  int st = vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  vm_ctx_set_log(ctx, NULL, NULL);
  CHECK(st == VM_OK, "surface write: status %d: %s", st, vm_ctx_error(ctx));
  CHECK(lg.warnings == 1 && strstr(lg.last, "SU2's solvers need volume cells"),
        "surface write: %d warnings, last '%s'", lg.warnings, lg.last);
  char *text = slurp(a, NULL);
  CHECK(text && strstr(text, "\nNDIME= 3\n") && strstr(text, "\nNMARK= 0\n"),
        "surface file header");
  free(text);
  st = vm_mesh_read(ctx, a, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r, "surface read: %s", vm_ctx_error(ctx));
  const char *diff = r ? mesh_diff(m, r) : "not read";
  CHECK(!diff, "surface round trip: %s", diff);
  vm_mesh_destroy(&r);
  /* with tags: written all the same, the tags reported lost */
  vm_field *f;
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = 1 + (m->etype[e] == VM_QUAD);
  vm_mesh_set_attr(m, "gmsh:physical_name:2:1", "sphere");
  st = vm_mesh_write(ctx, m, b, VM_FMT_AUTO, NULL);
  CHECK(st == VM_WARN_LOSSY, "tagged surface: status %d: %s", st, vm_ctx_error(ctx));
  st = vm_mesh_read(ctx, b, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r && r->nfield == 0 && r->ne == m->ne, "tagged surface read: %s",
        vm_ctx_error(ctx));
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);
  remove(a);
  remove(b);
  /* refused, nothing written: 2D, and no elements */
  vm_mesh_create(ctx, &m);
  static const int32_t t[3] = {0, 1, 2};
  for (int i = 0; i < 3; i++) vm_mesh_add_vertex(m, i == 1, i == 2, 0, NULL);
  st = vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  CHECK(st == VM_ERR_ARG && strstr(vm_ctx_error(ctx), "surface.su2: SU2 needs cells") &&
            access(a, F_OK) != 0,
        "no elements: status %d, '%s'", st, vm_ctx_error(ctx));
  vm_mesh_add_element(m, VM_TRI, t);
  m->dim = 2;
  st = vm_mesh_write(ctx, m, a, VM_FMT_AUTO, NULL);
  CHECK(st == VM_ERR_UNSUPPORTED && strstr(vm_ctx_error(ctx), "needs a 3D mesh") &&
            access(a, F_OK) != 0,
        "2D: status %d, '%s'", st, vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
}

/* A mesh without faces: its extracted boundary is one marker "boundary". */
static void test_no_faces(void) {
  char a[256], b[256];
  path_in(a, sizeof a, "nf.su2");
  path_in(b, sizeof b, "nf2.su2");
  vm_mesh *m = layered_mesh(ctx, 2), *r = NULL;
  vm_mesh *cells;
  vm_mesh_create(ctx, &cells);
  vm_mesh_set_vertices(cells, m->nv);
  memcpy(cells->xyz, m->xyz, sizeof(double) * 3 * (size_t)m->nv);
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 3)
      vm_mesh_add_element(cells, m->etype[e], m->conn + m->eoff[e]);
  CHECK(vm_mesh_write(ctx, cells, a, VM_FMT_AUTO, NULL) == VM_OK, "write: %s", vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, a, VM_FMT_AUTO, &r) == VM_OK, "read: %s", vm_ctx_error(ctx));
  if (r) {
    const char *nm = vm_mesh_get_attr(r, "gmsh:physical_name:2:1");
    CHECK(nm && !strcmp(nm, "boundary"), "marker name %s", nm ? nm : "(none)");
    CHECK(vm_mesh_write(ctx, r, b, VM_FMT_AUTO, NULL) >= 0, "rewrite: %s", vm_ctx_error(ctx));
    CHECK(same_but_header(a, b), "rewrite differs");
  }
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&cells);
  vm_mesh_destroy(&m);
  remove(a);
  remove(b);
}

/* The general format: comments, points before elements, elements with and
 * without their index, "KEY=value" without a blank, a line marker (dropped
 * with a warning), CRLF line ends. */
static void test_general(void) {
  static const char text[] = "% a hand-written SU2 file\r\n"
                             "NDIME=3\r\n"
                             "NPOIN= 7 7\r\n"
                             "0 0 0 0\r\n1 0 0 1\r\n0 1 0 2\r\n0 0 1\r\n1 0 1\r\n0 1 1 5\r\n"
                             "0.25 0.25 2 6\r\n"
                             "\r\n"
                             "% cells\r\n"
                             "NELEM= 2\r\n"
                             "13 0 2 1 3 5 4 0\r\n"
                             "10 3 4 5 6\r\n"
                             "NMARK= 2\r\n"
                             "MARKER_TAG= bottom wall\r\n"
                             "MARKER_ELEMS= 2\r\n"
                             "5 0 2 1\r\n"
                             "3 0 1 1\r\n"
                             "MARKER_TAG=top\r\n"
                             "MARKER_ELEMS=1\r\n"
                             "5 3 4 6\r\n";
  tlog lg = {0};
  vm_ctx_set_log(ctx, tlog_fn, &lg);
  vm_mesh *m = NULL;
  int st = vm_mesh_read_memory(ctx, "general.su2", (const uint8_t *)text, sizeof text - 1,
                               VM_FMT_AUTO, &m);
  vm_ctx_set_log(ctx, NULL, NULL);
  CHECK(st == VM_OK && m, "general: %s", vm_ctx_error(ctx));
  if (!m) return;
  CHECK(m->nv == 7 && m->ne == 4, "general: %lld vertices, %lld elements", (long long)m->nv,
        (long long)m->ne);
  CHECK(m->etype[0] == VM_PRISM && m->etype[1] == VM_TET && m->etype[2] == VM_TRI &&
            m->etype[3] == VM_TRI,
        "general: element types");
  /* VTK's wedge 0 2 1 3 5 4 is varmesh's prism 0 1 2 3 4 5 */
  static const int32_t prism[6] = {0, 1, 2, 3, 4, 5};
  CHECK(!memcmp(m->conn, prism, sizeof prism), "general: prism vertex order %d %d %d", m->conn[0],
        m->conn[1], m->conn[2]);
  CHECK(m->xyz[3 * 6 + 2] == 2.0 && m->xyz[3 * 6] == 0.25, "general: coordinates");
  const int32_t *t = i32_field(m, "gmsh:physical");
  CHECK(t && t[0] == 0 && t[2] == 1 && t[3] == 2, "general: tags");
  const char *n1 = vm_mesh_get_attr(m, "gmsh:physical_name:2:1");
  CHECK(n1 && !strcmp(n1, "bottom wall"), "general: marker name '%s'", n1 ? n1 : "");
  CHECK(lg.warnings == 1 && strstr(lg.last, "line"), "general: %d warnings, '%s'", lg.warnings,
        lg.last);
  vm_mesh_destroy(&m);

  static const char text2d[] = "NDIME= 2\nNELEM= 2\n5 0 1 2 0\n9 1 3 4 2 1\nNPOIN= 5\n"
                               "0 0\n1 0\n0 1\n2 0 3\n2 1 4\nNMARK= 1\nMARKER_TAG= far\n"
                               "MARKER_ELEMS= 2\n3 0 1\n3 1 3\n";
  st = vm_mesh_read_memory(ctx, "plane.su2", (const uint8_t *)text2d, sizeof text2d - 1,
                           VM_FMT_AUTO, &m);
  CHECK(st == VM_OK && m && m->dim == 2 && m->ne == 2 && m->nv == 5, "2D: %s", vm_ctx_error(ctx));
  if (m)
    CHECK(m->etype[1] == VM_QUAD && m->xyz[3 * 4 + 1] == 1.0 && m->xyz[3 * 4 + 2] == 0.0,
          "2D: quad and coordinates");
  vm_mesh_destroy(&m);
}

/* Bad input: negative status, one line "name: line N: ...", no mesh, no leak. */
static void expect_fail_len(const char *name, const char *text, size_t len, int want_st,
                            const char *want) {
  long live0 = vm_ctx_alloc_live(ctx);
  char *copy = malloc(len ? len : 1); /* exact size: the sanitizers see over-reads */
  memcpy(copy, text, len);
  vm_mesh *m = NULL;
  int st = vm_mesh_read_memory(ctx, name, (const uint8_t *)copy, len, VM_FMT_SU2, &m);
  free(copy);
  const char *e = vm_ctx_error(ctx);
  CHECK(st == want_st && !m, "%s: status %d, want %d (%s)", name, st, want_st, e);
  CHECK(!strncmp(e, name, strlen(name)) && !strchr(e, '\n'), "%s: message '%s'", name, e);
  CHECK(strstr(e, want), "%s: message '%s' lacks '%s'", name, e, want);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leak", name);
  vm_mesh_destroy(&m);
  fprintf(stderr, "  refused: %s\n", e);
}

static void expect_fail(const char *name, const char *text, int want_st, const char *want) {
  expect_fail_len(name, text, strlen(text), want_st, want);
}

#define HEAD "NDIME= 3\nNELEM= 1\n10 0 1 2 3 0\nNPOIN= 4\n0 0 0 0\n1 0 0 1\n0 1 0 2\n0 0 1 3\n"

static void test_bad(void) {
  const int F = VM_ERR_FORMAT;
  expect_fail("empty.su2", "", F, "no NDIME=");
  expect_fail("comment.su2", "% nothing\n", F, "no NDIME=");
  /* cut short: a count whose records cannot fit is refused at once; one
   * that fits, at the cut */
  expect_fail("truncated-count.su2",
              "NDIME= 3\nNELEM= 1\n10 0 1 2 3 0\nNPOIN= 4\n0 0 0 0\n1 0 0 1\n", F,
              "line 4: NPOIN= 4: that many records cannot fit");
  expect_fail("truncated-point.su2", "NDIME= 3\nNPOIN= 2\n0.5 0.5 0.5 0\n1 0", F,
              "line 4: point 1: expected 3 coordinates");
  expect_fail("truncated-marker.su2",
              HEAD "NMARK= 2\nMARKER_TAG= a\nMARKER_ELEMS= 1\n5 0 1 2\n"
                   "MARKER_TAG= b\n",
              F, "line 14: unexpected end of file, expected MARKER_ELEMS= of marker 'b'");
  expect_fail("truncated-elem.su2", "NDIME= 3\nNELEM= 2\n10 0 1 2 3 0\n10 0 1", F,
              "line 4: element of type 10: expected 4 vertex indices");
  expect_fail("lying-nelem.su2", "NDIME= 3\nNELEM= 1000000000\n10 0 1 2 3 0\n", F,
              "line 2: NELEM= 1000000000: that many records cannot fit");
  expect_fail("lying-npoin.su2", "NDIME= 3\nNPOIN= 99999999999\n0 0 0\n", F,
              "line 2: NPOIN= 99999999999");
  expect_fail("lying-nmark.su2", HEAD "NMARK= 100000\nMARKER_TAG= a\nMARKER_ELEMS= 0\n", F,
              "line 9: NMARK= 100000");
  expect_fail("lying-small.su2", "NDIME= 3\nNELEM= 1\n10 0 1 2 3 0\n10 0 1 2 3 1\nNPOIN= 4\n", F,
              "line 4: expected a KEY= line, found '10'");
  expect_fail("bad-index.su2",
              "NDIME= 3\nNELEM= 1\n10 0 1 2 4 0\nNPOIN= 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n", F,
              "line 3: vertex index 4 is not in 0..3");
  expect_fail("negative-index.su2", HEAD "NMARK= 1\nMARKER_TAG= w\nMARKER_ELEMS= 1\n5 0 -1 2\n", F,
              "line 12: marker element: vertex index -1 is not in 0..3");
  expect_fail("nan.su2",
              "NDIME= 3\nNELEM= 1\n10 0 1 2 3 0\nNPOIN= 4\n0 0 0 0\n1 nan 0 1\n0 1 0 2\n0 0 1 3\n",
              F, "line 6: point 1: coordinate is not finite");
  expect_fail("inf.su2", "NDIME= 3\nNPOIN= 1\n1e999 0 0\n", F,
              "line 3: point 0: coordinate is not finite");
  expect_fail("unknown-type.su2", "NDIME= 3\nNELEM= 1\n11 0 1 2 3 0\n", F,
              "line 3: element type 11 is not a 3D cell");
  expect_fail("surface-after-cells.su2", "NDIME= 3\nNELEM= 2\n10 0 1 2 3 0\n5 0 1 2 1\n", F,
              "line 4: element type 5: a surface element among volume cells");
  expect_fail("cell-after-surface.su2", "NDIME= 3\nNELEM= 2\n5 0 1 2 0\n10 0 1 2 3 1\n", F,
              "line 4: element type 10: a volume cell among surface elements");
  expect_fail("line-cell.su2", "NDIME= 3\nNELEM= 1\n3 0 1 0\n", F,
              "line 3: element type 3 is not a 3D cell or surface element");
  expect_fail("surface-marker.su2",
              "NDIME= 3\nNMARK= 1\nMARKER_TAG= w\nMARKER_ELEMS= 2\n3 0 1\n5 0 1 2\n"
              "NELEM= 1\n5 0 1 2\nNPOIN= 3\n0 0 0\n1 0 0\n0 1 0\n",
              F, "line 6: a marker of triangles or quadrilaterals in a surface mesh");
  expect_fail("marker-tet.su2", HEAD "NMARK= 1\nMARKER_TAG= w\nMARKER_ELEMS= 1\n10 0 1 2 3\n", F,
              "line 12: marker 'w': element type 10 is not a boundary element");
  expect_fail("garbage-number.su2", "NDIME= 3\nNPOIN= 1\n0 0x 0\n", F,
              "line 3: coordinate: '0x' is not a number");
  expect_fail(
      "extra-numbers.su2", "NDIME= 3\nNELEM= 1\n10 0 1 2 3 0 7\n", F,
      "line 3: element of type 10: expected 4 vertex indices and an optional index, found 6");
  expect_fail("ndime.su2", "NDIME= 4\n", F, "line 1: NDIME= 4 is not 2 or 3");
  expect_fail("no-ndime.su2", "NELEM= 0\n", F, "line 1: NELEM= before NDIME=");
  expect_fail("twice.su2", HEAD "NPOIN= 0\n", F, "line 9: a second NPOIN=");
  expect_fail("unknown-key.su2", "NDIME= 3\nNFOO= 3\n", F, "line 2: unknown keyword 'NFOO='");
  expect_fail("not-su2.su2", "solid cube\nfacet normal 0 0 1\n", F,
              "line 1: expected a KEY= line, found 'solid'");
  expect_fail("no-tag.su2", HEAD "NMARK= 1\nMARKER_ELEMS= 0\n", F,
              "line 10: expected MARKER_TAG= of marker 1");
  expect_fail("empty-tag.su2", HEAD "NMARK= 1\nMARKER_TAG=\nMARKER_ELEMS= 0\n", F,
              "line 10: MARKER_TAG= needs a name");
  expect_fail("no-points.su2", "NDIME= 3\nNELEM= 0\n", F, "no NPOIN= section");
  expect_fail("multizone.su2", "NZONE= 2\nIZONE= 1\nNDIME= 3\n", VM_ERR_UNSUPPORTED,
              "line 1: NZONE= 2: multi-zone SU2 files are not supported");
  /* a NUL byte separates tokens, as in the other text readers */
  static const char nul[] = "NDIME= 3\nNPOIN= 1\n0 0 0\0zz\n";
  expect_fail_len("nul.su2", nul, sizeof nul - 1, F, "line 3: point index: 'zz' is not an integer");
}

int main(void) {
  vm_ctx_create(&ctx);
  if (!mkdtemp(dir)) return 1;
  test_round_trip();
  test_no_faces();
  test_surface();
  test_general();
  test_bad();
  rmdir(dir);
  long live = vm_ctx_alloc_live(ctx);
  CHECK(live == 0, "%ld blocks live at the end", live);
  vm_ctx_destroy(&ctx);
  return vmtest_end("su2");
}
