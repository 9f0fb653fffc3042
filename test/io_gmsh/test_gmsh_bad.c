/* test/io_gmsh/test_gmsh_bad.c: the .msh and MEDIT readers fed empty, truncated,
 * lying, non-finite, inconsistent, garbage and mutated input, and the readers and
 * writers run with an allocator that fails on the n-th call. */
#include "gmsh_testlib.h"

static vm_ctx *ctx;
static tlog lg;
static long alloc_limit = 40; /* allocations a refused input may make */

/* Reads from an exact-size heap copy, so that any read past the end is an
 * out-of-bounds access the sanitizers catch. */
static int read_copy(const char *name, const void *buf, size_t len, int fmt, vm_mesh **m) {
  void *c = malloc(len ? len : 1);
  memcpy(c, buf, len);
  int st = vm_mesh_read_memory(ctx, name, c, len, fmt, m);
  free(c);
  return st;
}

static int starts_with_name(const char *name) {
  const char *e = vm_ctx_error(ctx);
  size_t n = strlen(name);
  return !strncmp(e, name, n) && e[n] == ':';
}

/* Bad input: negative status, the file name first in the one-line message,
 * the expected words in it, no mesh, no leak, only a few allocations. */
static void expect_fail(const char *name, const void *buf, size_t len, int fmt, const char *want) {
  long live0 = vm_ctx_alloc_live(ctx), count0 = vm_ctx_alloc_count(ctx);
  vm_mesh *m = NULL;
  int st = read_copy(name, buf, len, fmt, &m);
  CHECK(st < 0 && !m, "%s: status %d for bad input", name, st);
  CHECK(starts_with_name(name), "%s: message '%s'", name, vm_ctx_error(ctx));
  CHECK(!strchr(vm_ctx_error(ctx), '\n'), "%s: message has a newline", name);
  if (want)
    CHECK(strstr(vm_ctx_error(ctx), want), "%s: message '%s' lacks '%s'", name, vm_ctx_error(ctx),
          want);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leaks %ld blocks", name,
        vm_ctx_alloc_live(ctx) - live0);
  CHECK(vm_ctx_alloc_count(ctx) - count0 < alloc_limit, "%s: %ld allocations for bad input", name,
        vm_ctx_alloc_count(ctx) - count0);
  if (m) vm_mesh_destroy(&m);
}

static void expect_fail_str(const char *name, const char *text, int fmt, const char *want) {
  expect_fail(name, text, strlen(text), fmt, want);
}

static vm_mesh *build_small(void) {
  vm_mesh *m;
  vm_mesh_create(ctx, &m);
  for (int t = 0; t < VM_NTYPES; t++) add_ref_cell(m, t, 2.0 * t);
  vm_field *f;
  vm_mesh_add_field(m, "t", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  for (int64_t v = 0; v < m->nv; v++) ((double *)f->data)[v] = 0.5 * (double)v;
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  for (int64_t e = 0; e < m->ne; e++) ((int32_t *)f->data)[e] = (int32_t)(e % 2 + 1);
  vm_mesh_add_field(m, "medit:ref", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
  vm_mesh_set_attr(m, "gmsh:physical_name:3:1", "one");
  m->vflag[2] = VM_VERTEX_FIXED;
  return m;
}

typedef struct {
  const char *name, *end; /* every prefix shorter than the end of `end` must fail */
  int fmt;
  uint8_t *buf;
  size_t len;
} input;

enum { NIN = 9 };
static input in[NIN];

static const char small41[] =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n1\n3 2 \"v\"\n$EndPhysicalNames\n"
    "$Entities\n0 0 0 1\n2 0 0 0 1 1 1 1 2 0\n$EndEntities\n"
    "$Nodes\n1 5 1 5\n3 2 0 5\n1\n2\n3\n4\n5\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n$EndNodes\n"
    "$Elements\n2 2 1 2\n3 2 7 1\n1 1 2 3 4 5\n3 2 4 1\n2 1 2 4 5\n$EndElements\n";

static const char small_medit[] =
    "MeshVersionFormatted 2\nDimension 3\nVertices\n5\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n"
    "0.5 0.5 1 2\nTriangles\n1\n1 2 3 4\nPyramids\n1\n1 2 3 4 5 6\nCorners\n1\n1\n"
    "RequiredVertices\n1\n5\nEnd\n";

static void make_inputs(void) {
  vm_mesh *m = build_small();
  static const struct {
    const char *file;
    int ver, bin, fmt;
  } w[5] = {{"w41a.msh", 41, 0, VM_FMT_MSH},
            {"w41b.msh", 41, 1, VM_FMT_MSH},
            {"w22a.msh", 22, 0, VM_FMT_MSH},
            {"w22b.msh", 22, 1, VM_FMT_MSH},
            {"w.mesh", 0, 0, VM_FMT_MEDIT}};
  for (int i = 0; i < 5; i++) {
    char path[256];
    tdir_path(path, sizeof path, w[i].file);
    vm_write_opts o = {w[i].bin, w[i].ver};
    int st = vm_mesh_write(ctx, m, path, w[i].fmt, &o);
    CHECK(st >= 0, "%s: %s", path, vm_ctx_error(ctx));
    in[i].name = w[i].file;
    in[i].fmt = w[i].fmt;
    in[i].end = w[i].fmt == VM_FMT_MSH ? "$EndElements" : "End\n";
    in[i].buf = slurp(path, &in[i].len);
  }
  in[5] = (input){"small41.msh", "$EndElements", VM_FMT_MSH, NULL, sizeof small41 - 1};
  in[6] = (input){"small.mesh", "End\n", VM_FMT_MEDIT, NULL, sizeof small_medit - 1};
  in[5].buf = malloc(in[5].len);
  memcpy(in[5].buf, small41, in[5].len);
  in[6].buf = malloc(in[6].len);
  memcpy(in[6].buf, small_medit, in[6].len);
  /* binary files written by Gmsh itself (test/io_gmsh/data) */
  static const char *gmsh_files[2] = {"gmsh41b.msh", "gmsh22b.msh"};
  const char *root = getenv("VM_SOURCE_ROOT");
  for (int i = 0; i < 2; i++) {
    char path[1024];
    snprintf(path, sizeof path, "%s/test/io_gmsh/data/%s", root ? root : ".", gmsh_files[i]);
    in[7 + i] = (input){gmsh_files[i], "$EndElements", VM_FMT_MSH, NULL, 0};
    in[7 + i].buf = slurp(path, &in[7 + i].len);
    CHECK(in[7 + i].buf != NULL, "cannot read %s", path);
    if (!in[7 + i].buf) exit(vmtest_end("test_gmsh_bad"));
  }
  vm_mesh_destroy(&m);
}

static void test_inputs_valid(void) {
  for (int i = 0; i < NIN; i++) {
    vm_mesh *m = read_ok(ctx, in[i].name, in[i].buf, in[i].len, in[i].fmt);
    if (m) {
      CHECK(m->ne == (i < 5   ? VM_NTYPES
                      : i < 7 ? 2
                              : 57),
            "%s: %lld elements", in[i].name, (long long)m->ne);
      /* Gmsh orients its boundary faces outward: only cells are checked there */
      for (int64_t e = 0; e < m->ne; e++)
        if (i < 7 || vm_elem_dim(m->etype[e]) == 3)
          CHECK(elem_measure(m, e) > 0, "%s: element %lld not positive", in[i].name, (long long)e);
      vm_mesh_destroy(&m);
    }
  }
}

/* Every prefix of every input: prefixes that end before the last required
 * section must fail; none may crash or leak. */
static void test_truncations(void) {
  for (int i = 0; i < NIN; i++) {
    const uint8_t *b = in[i].buf;
    size_t must = 0, el = strlen(in[i].end);
    for (size_t p = 0; p + el <= in[i].len; p++)
      if (!memcmp(b + p, in[i].end, el)) must = p + el - (in[i].end[el - 1] == '\n');
    CHECK(must > 0, "%s: marker not found", in[i].name);
    long live0 = vm_ctx_alloc_live(ctx);
    int bad_ok = 0, bad_msg = 0;
    size_t first = 0;
    /* every length of the small files; a stride through the larger ones */
    size_t step = in[i].len < 4096 ? 1 : 7;
    for (size_t len = 0; len < in[i].len; len += step) {
      vm_mesh *m = NULL;
      int st = read_copy(in[i].name, b, len, in[i].fmt, &m);
      if (st >= 0) {
        if (len < must && !bad_ok++) first = len;
        vm_mesh_destroy(&m);
      } else if (!starts_with_name(in[i].name)) {
        bad_msg++;
      }
    }
    CHECK(!bad_ok, "%s: %d truncated files accepted (first at %zu of %zu)", in[i].name, bad_ok,
          first, in[i].len);
    CHECK(!bad_msg, "%s: %d messages without the file name", in[i].name, bad_msg);
    CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: truncations leak", in[i].name);
  }
  expect_fail("empty.msh", "", 0, VM_FMT_MSH, "$MeshFormat");
  expect_fail("empty.mesh", "", 0, VM_FMT_MEDIT, "MeshVersionFormatted");
}

#define HDR41 "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
#define HDR22 "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
#define NODES41 "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
#define NODES22 "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
#define MEDIT_HDR "MeshVersionFormatted 2\nDimension 3\n"
#define MEDIT_V "Vertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"

static void test_lying_counts(void) {
  expect_fail_str("n41.msh",
                  HDR41 "$Nodes\n1 1099511627776 1 1099511627776\n3 1 0 1\n1\n0 0 0\n$EndNodes\n",
                  VM_FMT_MSH, "1099511627776 nodes cannot fit");
  expect_fail_str("b41.msh", HDR41 "$Nodes\n1099511627776 1 1 1\n3 1 0 1\n1\n0 0 0\n$EndNodes\n",
                  VM_FMT_MSH, "node blocks cannot fit");
  expect_fail_str(
      "e41.msh", HDR41 NODES41 "$Elements\n1 1099511627776 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n",
      VM_FMT_MSH, "elements cannot fit");
  expect_fail_str("blk41.msh",
                  HDR41 NODES41
                  "$Elements\n1 1 1 1\n3 1 4 1099511627776\n1 1 2 3 4\n$EndElements\n",
                  VM_FMT_MSH, "more elements than");
  expect_fail_str("ent41.msh", HDR41 "$Entities\n0 0 0 1099511627776\n$EndEntities\n", VM_FMT_MSH,
                  "entities cannot fit");
  expect_fail_str("phys.msh", HDR41 "$PhysicalNames\n1099511627776\n3 1 \"a\"\n$EndPhysicalNames\n",
                  VM_FMT_MSH, "cannot fit");
  expect_fail_str(
      "nd.msh", HDR41 NODES41 "$NodeData\n1\n\"a\"\n0\n3\n0\n1\n1099511627776\n1 0\n$EndNodeData\n",
      VM_FMT_MSH, "data values cannot fit");
  expect_fail_str("ncomp.msh",
                  HDR41 NODES41 "$NodeData\n0\n0\n3\n0\n1099511627776\n1\n1 0\n$EndNodeData\n",
                  VM_FMT_MSH, "components");
  expect_fail_str("budget.msh", HDR41 NODES41 "$NodeData\n0\n0\n3\n0\n1048576\n0\n$EndNodeData\n",
                  VM_FMT_MSH, "4 x 1048576 values are more than this file can hold");
  tbuf many = {0};
  tb_str(&many, HDR41 NODES41);
  for (int i = 0; i <= 1024; i++) {
    char sec[96];
    snprintf(sec, sizeof sec, "$NodeData\n1\n\"d%d\"\n0\n3\n0\n1\n0\n$EndNodeData\n", i);
    tb_str(&many, sec);
  }
  alloc_limit = 5000; /* the 1024 datasets before the refused one are real */
  expect_fail("datasets.msh", many.p, many.n, VM_FMT_MSH, "more than 1024 datasets");
  alloc_limit = 40;
  tb_free(&many);
  expect_fail_str("n22.msh", HDR22 "$Nodes\n1099511627776\n1 0 0 0\n$EndNodes\n", VM_FMT_MSH,
                  "cannot fit");
  expect_fail_str("e22.msh",
                  HDR22 NODES22 "$Elements\n1099511627776\n1 4 0 1 2 3 4\n$EndElements\n",
                  VM_FMT_MSH, "cannot fit");
  /* binary: 2^40 nodes, then a size_t beyond INT64_MAX, then a lying 2.2 element header */
  tbuf b = {0};
  tb_str(&b, "$MeshFormat\n4.1 1 8\n");
  tb_i32(&b, 1);
  tb_str(&b, "\n$EndMeshFormat\n$Nodes\n");
  size_t at = b.n;
  tb_u64(&b, 1);
  tb_u64(&b, 1ull << 40);
  tb_u64(&b, 1);
  tb_u64(&b, 1ull << 40);
  tb_str(&b, "\n$EndNodes\n");
  expect_fail("nbin.msh", b.p, b.n, VM_FMT_MSH, "nodes cannot fit");
  uint64_t huge = ~0ull;
  memcpy(b.p + at, &huge, 8);
  expect_fail("hbin.msh", b.p, b.n, VM_FMT_MSH, "too large");
  tb_free(&b);
  tb_str(&b, "$MeshFormat\n2.2 1 8\n");
  tb_i32(&b, 1);
  tb_str(&b, "\n$EndMeshFormat\n$Nodes\n1\n");
  tb_i32(&b, 1);
  for (int c = 0; c < 3; c++) tb_f64(&b, 0);
  tb_str(&b, "\n$EndNodes\n$Elements\n1\n");
  tb_i32(&b, 15);
  tb_i32(&b, 1 << 30);
  tb_i32(&b, 0);
  tb_i32(&b, 1);
  tb_i32(&b, 1);
  tb_str(&b, "\n$EndElements\n");
  expect_fail("ebin22.msh", b.p, b.n, VM_FMT_MSH, "element header announces");
  tb_free(&b);
  expect_fail_str("v.mesh", MEDIT_HDR "Vertices\n1099511627776\n0 0 0 0\nEnd\n", VM_FMT_MEDIT,
                  "cannot fit");
  expect_fail_str("t.mesh", MEDIT_HDR MEDIT_V "Triangles\n1099511627776\n1 2 3 0\nEnd\n",
                  VM_FMT_MEDIT, "cannot fit");
  expect_fail_str("c.mesh", MEDIT_HDR MEDIT_V "Corners\n1099511627776\n1\nEnd\n", VM_FMT_MEDIT,
                  "cannot fit");
  expect_fail_str("neg.mesh", MEDIT_HDR "Vertices\n-1\nEnd\n", VM_FMT_MEDIT, "cannot fit");
}

static void test_non_finite(void) {
  expect_fail_str(
      "nan.msh",
      HDR41 "$Nodes\n1 1 1 1\n3 1 0 1\n1\nnan 0 0\n$EndNodes\n$Elements\n0 0 0 0\n$EndElements\n",
      VM_FMT_MSH, "not finite");
  expect_fail_str("inf.msh", HDR22 "$Nodes\n1\n1 0 -inf 0\n$EndNodes\n$Elements\n0\n$EndElements\n",
                  VM_FMT_MSH, "not finite");
  expect_fail_str("flagnan.msh",
                  HDR41 NODES41 "$Elements\n0 0 0 0\n$EndElements\n"
                                "$NodeData\n1\n\"vm_flag\"\n0\n3\n0\n1\n1\n2 NaN\n$EndNodeData\n",
                  VM_FMT_MSH, "vm_flag of node 2 is nan");
  tbuf b = {0};
  tb_str(&b, "$MeshFormat\n2.2 1 8\n");
  tb_i32(&b, 1);
  tb_str(&b, "\n$EndMeshFormat\n$Nodes\n1\n");
  tb_i32(&b, 1);
  tb_f64(&b, 0);
  tb_f64(&b, NAN);
  tb_f64(&b, 0);
  tb_str(&b, "\n$EndNodes\n$Elements\n0\n\n$EndElements\n");
  expect_fail("nanbin.msh", b.p, b.n, VM_FMT_MSH, "not finite");
  tb_free(&b);
  expect_fail_str("nan.mesh", MEDIT_HDR "Vertices\n1\n0 nan 0 0\nEnd\n", VM_FMT_MEDIT,
                  "not finite");
  expect_fail_str("inf.mesh", MEDIT_HDR "Vertices\n1\n0 0 INF 0\nEnd\n", VM_FMT_MEDIT,
                  "not finite");
}

static void test_inconsistent(void) {
  /* nodes that do not exist, wrong node counts, unknown and higher-order types */
  expect_fail_str("node99.msh",
                  HDR41 NODES41 "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 99\n$EndElements\n",
                  VM_FMT_MSH, "element 1: node 99 does not exist");
  expect_fail_str("node99_22.msh", HDR22 NODES22 "$Elements\n1\n5 4 0 1 2 3 99\n$EndElements\n",
                  VM_FMT_MSH, "element 5: node 99 does not exist");
  expect_fail_str("few.msh",
                  HDR41 NODES41 "$Elements\n1 2 1 2\n3 1 4 2\n1 1 2 3\n2 1 2 3 4\n$EndElements\n",
                  VM_FMT_MSH, "element 1: expected 4 node tags");
  expect_fail_str("many.msh",
                  HDR41 NODES41 "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4 1\n$EndElements\n",
                  VM_FMT_MSH, "element 1: expected 4 node tags");
  expect_fail_str("few22.msh",
                  HDR22 NODES22 "$Elements\n2\n1 4 0 1 2 3\n2 4 0 1 2 3 4\n$EndElements\n",
                  VM_FMT_MSH, "element 1: expected 4 node tags");
  expect_fail_str("type999.msh",
                  HDR41 NODES41 "$Elements\n1 1 1 1\n3 1 999 1\n1 1 2 3 4\n$EndElements\n",
                  VM_FMT_MSH, "element 1: Gmsh element type 999 is not a Gmsh element type");
  expect_fail_str("type0.msh", HDR41 NODES41 "$Elements\n1 0 1 1\n3 1 0 0\n$EndElements\n",
                  VM_FMT_MSH, "element block 0: Gmsh element type 0 is not a Gmsh element type");
  expect_fail_str("tet10.msh",
                  HDR41 NODES41
                  "$Elements\n1 1 7 7\n3 1 11 1\n7 1 2 3 4 1 2 3 4 1 2\n$EndElements\n",
                  VM_FMT_MSH, "element 7: Gmsh element type 11 is not a linear element");
  expect_fail_str("tet10_22.msh",
                  HDR22 NODES22 "$Elements\n1\n3 11 0 1 2 3 4 1 2 3 4 1 2\n$EndElements\n",
                  VM_FMT_MSH, "element 3: Gmsh element type 11");
  /* duplicates, zero tags, order of sections, versions */
  expect_fail_str("dupnode.msh",
                  HDR22 "$Nodes\n2\n1 0 0 0\n1 1 0 0\n$EndNodes\n$Elements\n0\n$EndElements\n",
                  VM_FMT_MSH, "node tag 1 appears twice");
  expect_fail_str("dupnode2.msh",
                  HDR22
                  "$Nodes\n3\n2 0 0 0\n1 1 0 0\n2 0 1 0\n$EndNodes\n$Elements\n0\n$EndElements\n",
                  VM_FMT_MSH, "node tag 2 appears twice");
  expect_fail_str("dupelem.msh",
                  HDR22 NODES22 "$Elements\n2\n1 4 0 1 2 3 4\n1 4 0 1 2 3 4\n$EndElements\n",
                  VM_FMT_MSH, "element tag 1 appears twice");
  expect_fail_str("zero.msh", HDR22 "$Nodes\n1\n0 0 0 0\n$EndNodes\n$Elements\n0\n$EndElements\n",
                  VM_FMT_MSH, "not positive");
  expect_fail_str("order.msh", HDR22 "$Elements\n0\n$EndElements\n" NODES22, VM_FMT_MSH,
                  "$Elements before $Nodes");
  expect_fail_str("twice.msh", HDR22 NODES22 NODES22 "$Elements\n0\n$EndElements\n", VM_FMT_MSH,
                  "second $Nodes");
  expect_fail_str("noelem.msh", HDR22 NODES22, VM_FMT_MSH, "no $Elements");
  expect_fail_str("nonodes.msh", HDR41, VM_FMT_MSH, "no $Nodes");
  expect_fail_str("v40.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n", VM_FMT_MSH,
                  "version 4 is not supported");
  expect_fail_str("v30.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", VM_FMT_MSH, "not supported");
  expect_fail_str("ds4.msh", "$MeshFormat\n4.1 0 4\n$EndMeshFormat\n", VM_FMT_MSH, "data size 4");
  expect_fail_str("ft2.msh", "$MeshFormat\n4.1 2 8\n$EndMeshFormat\n", VM_FMT_MSH, "file type 2");
  static const char endian[] = "$MeshFormat\n4.1 1 8\n\x02\x00\x00\x00\n$EndMeshFormat\n";
  expect_fail("endian.msh", endian, sizeof endian - 1, VM_FMT_MSH, "endianness check reads 2");
  expect_fail_str("nofmt.msh", NODES22, VM_FMT_MSH, "does not start with $MeshFormat");
  expect_fail_str("word.msh", HDR41 "hello\n", VM_FMT_MSH, "expected a section");
  expect_fail_str("endnode.msh", HDR22 "$Nodes\n0\n$EndNode\n", VM_FMT_MSH, "expected $EndNodes");
  expect_fail_str("unterm.msh", HDR41 "$Foo\nbar\n$EndFo\n", VM_FMT_MSH, "no $EndFoo");
  expect_fail_str("announce.msh", HDR41 "$Nodes\n1 3 1 2\n3 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n",
                  VM_FMT_MSH, "3 nodes announced, the blocks hold 2");
  expect_fail_str("param.msh", HDR41 "$Nodes\n1 1 1 1\n3 1 2 1\n1\n0 0 0\n$EndNodes\n", VM_FMT_MSH,
                  "parametric flag 2");
  expect_fail_str("entdup.msh",
                  HDR41 "$Entities\n0 0 0 2\n1 0 0 0 1 1 1 0 0\n1 0 0 0 1 1 1 0 0\n$EndEntities\n",
                  VM_FMT_MSH, "defined twice");
  expect_fail_str("quote.msh", HDR41 "$PhysicalNames\n1\n3 1 \"abc\n$EndPhysicalNames\n",
                  VM_FMT_MSH, "unterminated");
  expect_fail_str("flag.msh",
                  HDR41 NODES41 "$Elements\n0 0 0 0\n$EndElements\n"
                                "$NodeData\n1\n\"vm_flag\"\n0\n3\n0\n1\n1\n1 7\n$EndNodeData\n",
                  VM_FMT_MSH, "not a vertex flag");
  expect_fail_str("ndnode.msh",
                  HDR41 NODES41 "$NodeData\n1\n\"a\"\n0\n3\n0\n1\n1\n9 1\n$EndNodeData\n",
                  VM_FMT_MSH, "node 9 does not exist");
  expect_fail_str("ndfirst.msh", HDR41 "$NodeData\n1\n\"a\"\n0\n3\n0\n1\n0\n$EndNodeData\n",
                  VM_FMT_MSH, "data before the nodes");
  expect_fail_str("int.msh", HDR41 "$Nodes\n1 1 1 x\n", VM_FMT_MSH, "'x' is not an integer");
  expect_fail_str("bintext.msh", "$MeshFormat\n4.1 1 8 junk\n", VM_FMT_MSH,
                  "unexpected text 'junk'");
  /* MEDIT */
  expect_fail_str("noend.mesh", MEDIT_HDR MEDIT_V, VM_FMT_MEDIT, "no End");
  expect_fail_str("nover.mesh", "Dimension 3\nEnd\n", VM_FMT_MEDIT, "MeshVersionFormatted");
  expect_fail_str("ver7.mesh", "MeshVersionFormatted 7\nEnd\n", VM_FMT_MEDIT, "not 1 to 4");
  expect_fail_str("dim4.mesh", "MeshVersionFormatted 1\nDimension 4\nEnd\n", VM_FMT_MEDIT,
                  "Dimension 4");
  expect_fail_str("nodim.mesh", "MeshVersionFormatted 1\n" MEDIT_V "End\n", VM_FMT_MEDIT,
                  "Vertices before Dimension");
  expect_fail_str("tet2d.mesh",
                  "MeshVersionFormatted 1\nDimension 2\nVertices\n4\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n"
                  "Tetrahedra\n1\n1 2 3 4 0\nEnd\n",
                  VM_FMT_MEDIT, "Tetrahedra in a 2-dimensional mesh");
  expect_fail_str("kw.mesh", MEDIT_HDR MEDIT_V "Polyhedra\n0\nEnd\n", VM_FMT_MEDIT,
                  "unknown keyword 'Polyhedra'");
  expect_fail_str("idx0.mesh", MEDIT_HDR MEDIT_V "Triangles\n1\n0 2 3 0\nEnd\n", VM_FMT_MEDIT,
                  "vertex 0 is not in 1..4");
  expect_fail_str("idx99.mesh", MEDIT_HDR MEDIT_V "Tetrahedra\n1\n1 2 3 99 0\nEnd\n", VM_FMT_MEDIT,
                  "vertex 99 is not in 1..4");
  expect_fail_str("ref.mesh", MEDIT_HDR MEDIT_V "Triangles\n1\n1 2 3 1099511627776\nEnd\n",
                  VM_FMT_MEDIT, "out of range");
  expect_fail_str("noref.mesh", MEDIT_HDR MEDIT_V "Triangles\n2\n1 2 3\n1 2 4 0\nEnd\n",
                  VM_FMT_MEDIT, "Triangles 1: expected 4 numbers");
  expect_fail_str("extra.mesh", MEDIT_HDR MEDIT_V "Triangles\n1\n1 2 3 4 0\nEnd\n", VM_FMT_MEDIT,
                  "Triangles 1: expected 4 numbers");
  expect_fail_str("vline.mesh", MEDIT_HDR "Vertices\n2\n0 0 0\n0 1 0 0 0\nEnd\n", VM_FMT_MEDIT,
                  "vertex 1: expected 4 numbers");
  expect_fail_str("req.mesh", MEDIT_HDR "RequiredVertices\n1\n1\nEnd\n", VM_FMT_MEDIT,
                  "RequiredVertices before");
  expect_fail_str("req99.mesh", MEDIT_HDR MEDIT_V "RequiredVertices\n1\n99\nEnd\n", VM_FMT_MEDIT,
                  "vertex 99");
  expect_fail_str("vv.mesh", MEDIT_HDR MEDIT_V MEDIT_V "End\n", VM_FMT_MEDIT, "second Vertices");
  expect_fail_str("tfirst.mesh", MEDIT_HDR "Triangles\n0\nEnd\n", VM_FMT_MEDIT,
                  "Triangles before Vertices");
  expect_fail_str("num.mesh", MEDIT_HDR "Vertices\n1\n0 zero 0 0\nEnd\n", VM_FMT_MEDIT,
                  "not a number");
}

/* Deterministic garbage: raw random bytes, and random bytes after valid headers. */
static void test_garbage(void) {
  vm_ctx_seed(ctx, 12345);
  long live0 = vm_ctx_alloc_live(ctx);
  int accepted = 0, bad_msg = 0;
#define P(s)                                                                                       \
  { s, sizeof s - 1 }
  static const struct {
    const char *p;
    size_t n;
  } prefix[5] = {P(""), P("$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n$Nodes\n"),
                 P("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"),
                 P("MeshVersionFormatted 2\nDimension 3\n"),
                 P("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Elements\n")};
#undef P
  uint8_t buf[600];
  for (int k = 0; k < 1500; k++) {
    int pi = k % 5;
    size_t pl = prefix[pi].n;
    memcpy(buf, prefix[pi].p, pl);
    size_t n = pl + (size_t)(vm_ctx_rand_u64(ctx) % 500);
    int text = k % 2;
    for (size_t i = pl; i < n; i++) {
      uint64_t r = vm_ctx_rand_u64(ctx);
      buf[i] = text ? (uint8_t) " 0123456789.-e\n$\"#"[r % 18] : (uint8_t)r;
    }
    int fmt = pi == 3 || (pi == 0 && k % 4 == 0) ? VM_FMT_MEDIT : VM_FMT_MSH;
    vm_mesh *m = NULL;
    int st = read_copy("garbage", buf, n, fmt, &m);
    if (st >= 0) {
      accepted++;
      vm_mesh_destroy(&m);
    } else if (!starts_with_name("garbage")) {
      bad_msg++;
    }
  }
  CHECK(!accepted, "%d garbage buffers accepted", accepted);
  CHECK(!bad_msg, "%d garbage messages without the file name", bad_msg);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "garbage leaks");
}

/* Valid files with a few bytes changed: any status, but no crash, no leak,
 * a named message on failure and a valid mesh on success. */
static void test_mutations(void) {
  vm_ctx_seed(ctx, 777);
  long live0 = vm_ctx_alloc_live(ctx);
  int bad_msg = 0, ok = 0, fail = 0;
  static const char interesting[] = "0123456789 -.e\n$\"";
  for (int i = 0; i < NIN; i++) {
    uint8_t *b = malloc(in[i].len);
    for (int k = 0; k < 400; k++) {
      memcpy(b, in[i].buf, in[i].len);
      int nmut = 1 + (int)(vm_ctx_rand_u64(ctx) % 3);
      for (int j = 0; j < nmut; j++) {
        uint64_t r = vm_ctx_rand_u64(ctx);
        size_t at = (size_t)(r % in[i].len);
        b[at] = (r >> 32) % 2 ? (uint8_t)interesting[(r >> 40) % (sizeof interesting - 1)]
                              : (uint8_t)(r >> 48);
      }
      vm_mesh *m = NULL;
      int st = read_copy(in[i].name, b, in[i].len, in[i].fmt, &m);
      if (st >= 0) {
        ok++;
        CHECK(vm_mesh_check(m) == VM_OK, "%s: mutated mesh invalid", in[i].name);
        vm_mesh_destroy(&m);
      } else {
        fail++;
        bad_msg += !starts_with_name(in[i].name);
      }
    }
    free(b);
  }
  CHECK(!bad_msg, "%d mutation messages without the file name", bad_msg);
  CHECK(fail > 0 && ok > 0, "mutations: %d accepted, %d refused", ok, fail);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "mutations leak");
}

/* Every allocation of every reader and writer fails once. */
static void test_alloc_failures(void) {
  long live0 = vm_ctx_alloc_live(ctx);
  for (int i = 0; i < NIN; i++) {
    int n, done = 0, wrong = 0;
    for (n = 1; n < 2000 && !done; n++) {
      vm_mesh *m = NULL;
      void *c = malloc(in[i].len);
      memcpy(c, in[i].buf, in[i].len);
      vm_ctx_set_alloc_fail(ctx, n);
      int st = vm_mesh_read_memory(ctx, in[i].name, c, in[i].len, in[i].fmt, &m);
      vm_ctx_set_alloc_fail(ctx, 0);
      free(c);
      if (st == VM_OK) {
        done = 1;
        vm_mesh_destroy(&m);
      } else {
        wrong += st != VM_ERR_NOMEM || !starts_with_name(in[i].name);
      }
      CHECK(vm_ctx_alloc_live(ctx) == live0, "%s: leak when allocation %d fails", in[i].name, n);
    }
    CHECK(done && !wrong, "%s: %d wrong statuses over %d failing allocations", in[i].name, wrong,
          n);
  }
  vm_mesh *m = build_small();
  vm_mesh_set_attr(m, "note", "x"); /* lossy, so the warning paths run too */
  long live1 = vm_ctx_alloc_live(ctx);
  static const vm_write_opts opts[4] = {{0, 41}, {1, 41}, {0, 22}, {1, 22}};
  for (int w = 0; w < 5; w++) {
    char path[256];
    tdir_path(path, sizeof path, w < 4 ? "fail.msh" : "fail.mesh");
    int before = tdir_count(), done = 0, wrong = 0;
    for (int n = 1; n < 200 && !done; n++) {
      unlink(path);
      vm_ctx_set_alloc_fail(ctx, n);
      int st = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, w < 4 ? &opts[w] : NULL);
      vm_ctx_set_alloc_fail(ctx, 0);
      if (st >= 0) {
        done = 1;
        CHECK(st == VM_WARN_LOSSY && access(path, F_OK) == 0, "%s: status %d", path, st);
      } else {
        wrong += st != VM_ERR_NOMEM || strncmp(vm_ctx_error(ctx), path, strlen(path)) ||
                 access(path, F_OK) == 0 || tdir_count() != before;
      }
      CHECK(vm_ctx_alloc_live(ctx) == live1, "writer %d leaks when allocation %d fails", w, n);
    }
    CHECK(done && !wrong, "writer %d: %d wrong failures", w, wrong);
    unlink(path);
  }
  /* I/O errors and bad options */
  int st = vm_mesh_write(ctx, m, "/nonexistent-dir/x.msh", VM_FMT_MSH, NULL);
  CHECK(st == VM_ERR_IO && strstr(vm_ctx_error(ctx), "/nonexistent-dir/x.msh"), "msh I/O error %d",
        st);
  st = vm_mesh_write(ctx, m, "/nonexistent-dir/x.mesh", VM_FMT_MEDIT, NULL);
  CHECK(st == VM_ERR_IO && strstr(vm_ctx_error(ctx), "/nonexistent-dir/x.mesh"),
        "MEDIT I/O error %d", st);
  vm_write_opts bad = {0, 30};
  char path[256];
  tdir_path(path, sizeof path, "v30.msh");
  st = vm_mesh_write(ctx, m, path, VM_FMT_MSH, &bad);
  CHECK(st == VM_ERR_ARG && access(path, F_OK) != 0, "version 30 refused: %d", st);
  vm_mesh_destroy(&m);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "alloc failure tests leak");
}

int main(void) {
  vm_ctx_create(&ctx);
  vm_ctx_set_log(ctx, tlog_fn, &lg);
  tdir_make();
  long live0 = vm_ctx_alloc_live(ctx);
  make_inputs();
  test_inputs_valid();
  test_truncations();
  test_lying_counts();
  test_non_finite();
  test_inconsistent();
  test_garbage();
  test_mutations();
  test_alloc_failures();
  for (int i = 0; i < NIN; i++) free(in[i].buf);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leaked %ld blocks", vm_ctx_alloc_live(ctx) - live0);
  tdir_remove();
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_gmsh_bad");
}
