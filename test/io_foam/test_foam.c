/* test/io_foam/test_foam.c: the OpenFOAM polyMesh writer, read back by the
 * test's own reader (foam_testlib.h): for meshes of hexahedra, prisms,
 * pyramids, tetrahedra and all four, ASCII and binary, the counts, points
 * bit for bit, upper-triangular face order, every face's normal from owner
 * to neighbour (out of the domain on the boundary), closed cells, patches
 * named, typed and filled from the boundary elements (defaultFaces for the
 * rest); an existing case keeps everything but constant/polyMesh; what
 * cannot be written is refused with one line and leaves nothing behind,
 * also when any allocation fails. */
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "foam_testlib.h"
#include "varmesh/io.h"
#include "varmesh/shapes.h"
#include "vmtest.h"

static vm_ctx *ctx;
static char dir[] = "/tmp/vm_foam_XXXXXX";

typedef struct {
  int n;
  char all[8192];
} wlog;

static void wlog_fn(void *user, int level, const char *msg) {
  wlog *l = user;
  if (level != VM_LOG_WARN) return;
  l->n++;
  size_t k = strlen(l->all);
  if (k + strlen(msg) + 2 < sizeof l->all) {
    strcat(l->all, msg);
    strcat(l->all, "\n");
  }
}

static void path_in(char *buf, size_t n, const char *name) { snprintf(buf, n, "%s/%s", dir, name); }

/* Write with the warnings captured. */
static int write_logged(const vm_mesh *m, const char *path, int binary, wlog *lg) {
  memset(lg, 0, sizeof *lg);
  vm_write_opts o = vm_write_opts_default();
  o.binary = binary;
  vm_ctx_set_log(ctx, wlog_fn, lg);
  /* by extension if there is one ("x.foam", "x.foam/"), else by name */
  int fmt = vm_format_from_path(path) ? VM_FMT_AUTO : VM_FMT_FOAM;
  int st = vm_mesh_write(ctx, m, path, fmt, &o);
  vm_ctx_set_log(ctx, NULL, NULL);
  return st;
}

/* Entries of a directory whose name starts with '.' (temporary trees). */
static int hidden_entries(const char *d) {
  DIR *dp = opendir(d);
  int n = 0;
  struct dirent *e;
  while (dp && (e = readdir(dp)))
    if (e->d_name[0] == '.' && strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
      fprintf(stderr, "  left behind: %s/%s\n", d, e->d_name);
      n++;
    }
  if (dp) closedir(dp);
  return n;
}

static int exists(const char *p) {
  struct stat st;
  return stat(p, &st) == 0;
}

static char *read_text(const char *p) {
  size_t n;
  return ft_slurp(p, &n);
}

static void put_text(const char *p, const char *text) {
  FILE *f = fopen(p, "w");
  if (!f) return;
  fputs(text, f);
  fclose(f);
}

typedef struct {
  const char *name, *type, *groups;
  int tag; /* side tag of its faces (0: the untagged sides) */
} want_patch;

/* Area vector (Newell) and centroid of face f. */
static void face_geom(const ft_case *c, long long f, double A[3], double x[3]) {
  long long a = c->fofs[f], b = c->fofs[f + 1];
  for (int d = 0; d < 3; d++) A[d] = x[d] = 0;
  for (long long i = a; i < b; i++) {
    const double *p = c->pts + 3 * c->fpts[i];
    const double *q = c->pts + 3 * c->fpts[i + 1 < b ? i + 1 : a];
    A[0] += 0.5 * (p[1] - q[1]) * (p[2] + q[2]);
    A[1] += 0.5 * (p[2] - q[2]) * (p[0] + q[0]);
    A[2] += 0.5 * (p[0] - q[0]) * (p[1] + q[1]);
    for (int d = 0; d < 3; d++) x[d] += p[d] / (double)(b - a);
  }
}

/* The written case against the mesh it came from. Every vertex of m is
 * used by a cell, so point k is vertex k. */
static void check_case(const char *what, const vm_mesh *m, const ft_case *c, const want_patch *wp,
                       int nwp) {
  int64_t ncell = 0, nkey = 0;
  int fc[6][4], fnv[6];
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 3) {
      ncell++;
      nkey += vm_elem_faces(m->etype[e], fc, fnv);
    }
  int64_t nb = 0;
  vm_mesh_boundary(m, &nb, NULL, NULL, NULL, NULL);
  long long nint = (nkey - nb) / 2;
  CHECK(c->npoint == m->nv && !memcmp(c->pts, m->xyz, sizeof(double) * 3 * (size_t)m->nv),
        "%s: %lld points, want the %lld vertices bit for bit", what, c->npoint, (long long)m->nv);
  CHECK(c->nface == nint + nb && c->nown == c->nface && c->nnbr == nint,
        "%s: %lld faces, %lld owners, %lld neighbours; want %lld internal + %lld boundary", what,
        c->nface, c->nown, c->nnbr, nint, (long long)nb);
  char note[200];
  snprintf(note, sizeof note, "nPoints:%lld  nCells:%lld  nFaces:%lld  nInternalFaces:%lld",
           (long long)m->nv, (long long)ncell, nint + nb, nint);
  CHECK(!strcmp(c->note, note), "%s: owner's note '%s', want '%s'", what, c->note, note);
  if (c->nface != nint + nb || c->nown != c->nface || c->nnbr != nint) return;
  /* cell centroids, in mesh order of the volume elements */
  double *cc = calloc((size_t)ncell * 3, sizeof *cc);
  double *sum = calloc((size_t)ncell * 3, sizeof *sum);
  int *nfc = calloc((size_t)ncell, sizeof *nfc), *want_nf = calloc((size_t)ncell, sizeof *want_nf);
  double scale = 0;
  for (int64_t e = 0, k = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 3) continue;
    int nv = vm_elem_nverts(t);
    for (int j = 0; j < nv; j++)
      for (int d = 0; d < 3; d++) cc[3 * k + d] += m->xyz[3 * m->conn[m->eoff[e] + j] + d] / nv;
    want_nf[k++] = vm_elem_faces(t, fc, fnv);
  }
  long long bad_range = 0, bad_order = 0, bad_dir = 0, bad_out = 0, bad_closed = 0, bad_nf = 0;
  for (long long f = 0; f < c->nface; f++) {
    long long k = c->fofs[f + 1] - c->fofs[f];
    for (long long i = c->fofs[f]; i < c->fofs[f + 1]; i++)
      bad_range += c->fpts[i] < 0 || c->fpts[i] >= c->npoint;
    long long o = c->own[f], nb2 = f < nint ? c->nbr[f] : -1;
    if (k < 3 || k > 4 || o < 0 || o >= ncell || (f < nint && (nb2 <= o || nb2 >= ncell))) {
      bad_range++;
      continue;
    }
    if (f && f < nint)
      bad_order +=
          c->own[f] < c->own[f - 1] || (c->own[f] == c->own[f - 1] && nb2 <= c->nbr[f - 1]);
    double A[3], x[3];
    face_geom(c, f, A, x);
    double a = sqrt(A[0] * A[0] + A[1] * A[1] + A[2] * A[2]);
    scale = a > scale ? a : scale;
    double dv[3];
    for (int d = 0; d < 3; d++) {
      dv[d] = (f < nint ? cc[3 * nb2 + d] : x[d]) - cc[3 * o + d];
      sum[3 * o + d] += A[d];
      if (f < nint) sum[3 * nb2 + d] -= A[d];
    }
    double dot = A[0] * dv[0] + A[1] * dv[1] + A[2] * dv[2];
    if (f < nint)
      bad_dir += !(dot > 0);
    else
      bad_out += !(dot > 0);
    nfc[o]++;
    if (f < nint) nfc[nb2]++;
  }
  for (int64_t k = 0; k < ncell; k++) {
    bad_nf += nfc[k] != want_nf[k];
    double s = fabs(sum[3 * k]) + fabs(sum[3 * k + 1]) + fabs(sum[3 * k + 2]);
    bad_closed += !(s <= 1e-12 * scale);
  }
  CHECK(!bad_range, "%s: %lld faces with points, owner or neighbour out of range", what, bad_range);
  CHECK(!bad_order, "%s: %lld internal faces out of upper-triangular order", what, bad_order);
  CHECK(!bad_dir, "%s: %lld internal faces point from the neighbour to the owner", what, bad_dir);
  CHECK(!bad_out, "%s: %lld boundary faces point into the domain", what, bad_out);
  CHECK(!bad_nf, "%s: %lld cells with the wrong number of faces", what, bad_nf);
  CHECK(!bad_closed, "%s: %lld cells not closed (faces oriented inconsistently)", what, bad_closed);
  free(cc);
  free(sum);
  free(nfc);
  free(want_nf);
  /* patches: as wanted, contiguous after the internal faces, each face on
   * its side of the cube and as many as there are tagged elements */
  CHECK(c->npatch == nwp, "%s: %d patches, want %d", what, c->npatch, nwp);
  const vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  long long start = nint;
  for (int p = 0; p < c->npatch && p < nwp; p++) {
    const ft_patch *q = &c->patch[p];
    CHECK(!strcmp(q->name, wp[p].name) && !strcmp(q->type, wp[p].type) &&
              !strcmp(q->groups, wp[p].groups),
          "%s: patch %d is '%s' type '%s' inGroups '%s'; want '%s' '%s' '%s'", what, p, q->name,
          q->type, q->groups, wp[p].name, wp[p].type, wp[p].groups);
    CHECK(q->start == start, "%s: patch %s starts at %lld, want %lld", what, q->name, q->start,
          start);
    long long want = 0, off = 0;
    for (int64_t e = 0; e < m->ne; e++)
      if (vm_elem_dim(m->etype[e]) == 2 && ph) want += ((int32_t *)ph->data)[e] == wp[p].tag;
    if (!wp[p].tag) want = nb - (ph ? (long long)(m->ne - ncell) : 0);
    for (long long f = q->start; f >= 0 && f < q->start + q->nfaces && f < c->nface; f++) {
      int32_t v[4];
      long long k = c->fofs[f + 1] - c->fofs[f];
      for (long long i = 0; i < k; i++) v[i] = (int32_t)c->fpts[c->fofs[f] + i];
      off += ph && ft_side_tag(m, v, (int)k) != wp[p].tag; /* untagged: all sides */
    }
    CHECK(q->nfaces == want && !off, "%s: patch %s: %lld faces (%lld off its side), want %lld",
          what, q->name, q->nfaces, off, want);
    start += q->nfaces;
  }
  CHECK(start == c->nface, "%s: the patches end at %lld of %lld faces", what, start, c->nface);
}

static const want_patch named[5] = {
    {"wall", "wall", "List<word> 1(wall)", FT_WALL},
    {"farfield", "patch", "", FT_FARFIELD},
    {"symmetry", "symmetryPlane", "List<word> 1(symmetryPlane)", FT_SYMMETRY},
    {"outer", "patch", "", FT_OUTER},
    {"defaultFaces", "patch", "", 0},
};

static int same_case(const ft_case *a, const ft_case *b) {
  if (a->npoint != b->npoint || a->nface != b->nface || a->nnbr != b->nnbr) return 0;
  long long np = a->fofs[a->nface];
  return !memcmp(a->pts, b->pts, 24 * (size_t)a->npoint) &&
         !memcmp(a->fofs, b->fofs, 8 * (size_t)(a->nface + 1)) &&
         !memcmp(a->fpts, b->fpts, 8 * (size_t)np) &&
         !memcmp(a->own, b->own, 8 * (size_t)a->nface) &&
         !memcmp(a->nbr, b->nbr, 8 * (size_t)a->nnbr);
}

/* Every kind of cell, with named boundaries, ASCII and binary. */
static void test_kinds(void) {
  for (int kind = 0; kind < FT_NKIND; kind++) {
    vm_mesh *m = ft_cube(ctx, 4, kind, 0.15);
    int64_t nt = ft_tag_boundary(m);
    CHECK(nt > 0, "%s: tagged %lld faces", ft_name[kind], (long long)nt);
    ft_case ca, cb;
    for (int bin = 0; bin < 2; bin++) {
      char path[256], what[64];
      snprintf(what, sizeof what, "%s%s", ft_name[kind], bin ? " binary" : "");
      snprintf(path, sizeof path, "%s/%s%s.foam", dir, ft_name[kind], bin ? "_bin" : "");
      wlog lg;
      int st = write_logged(m, path, bin, &lg);
      CHECK(st == VM_OK, "%s: write status %d: %s", what, st, vm_ctx_error(ctx));
      CHECK(lg.n == 1 &&
                strstr(lg.all, "in no named boundary; written to the patch 'defaultFaces'"),
            "%s: warnings: %s", what, lg.all);
      ft_case *c = bin ? &cb : &ca;
      int ok = ft_read(path, c);
      CHECK(ok, "%s: %s", what, c->err);
      if (ok) check_case(what, m, c, named, 5);
      for (int o = 0; o < 4; o++)
        CHECK(c->binary[o] == bin, "%s: file %d format binary=%d", what, o, c->binary[o]);
      CHECK(!c->binary[4], "%s: boundary is text", what);
      CHECK(hidden_entries(dir) == 0, "%s: temporary trees left", what);
    }
    CHECK(same_case(&ca, &cb), "%s: binary and ASCII differ", ft_name[kind]);
    /* counts of cell types, as checkMesh would count them */
    int64_t cnt[VM_NTYPES];
    vm_mesh_count_types(m, cnt);
    CHECK(kind != FT_MIXED || (cnt[VM_HEX] && cnt[VM_PRISM] && cnt[VM_PYRAMID] && cnt[VM_TET]),
          "mixed: hex %lld prism %lld pyramid %lld tet %lld", (long long)cnt[VM_HEX],
          (long long)cnt[VM_PRISM], (long long)cnt[VM_PYRAMID], (long long)cnt[VM_TET]);
    ft_case_free(&ca);
    ft_case_free(&cb);
    vm_mesh_destroy(&m);
  }
}

/* Without boundary elements every boundary face is in defaultFaces; a
 * trailing slash names the same directory. */
static void test_no_faces(void) {
  vm_mesh *m = ft_cube(ctx, 2, FT_MIXED, 0.1);
  char path[256];
  path_in(path, sizeof path, "plain.foam/");
  wlog lg;
  int st = write_logged(m, path, 0, &lg);
  CHECK(st == VM_OK && lg.n == 1, "no faces: status %d, warnings %s", st, lg.all);
  ft_case c;
  path_in(path, sizeof path, "plain.foam");
  int ok = ft_read(path, &c);
  CHECK(ok, "no faces: %s", c.err);
  static const want_patch def[1] = {{"defaultFaces", "patch", "", 0}};
  if (ok) check_case("no faces", m, &c, def, 1);
  ft_case_free(&c);
  vm_mesh_destroy(&m);
}

/* Refused, with one line and nothing written. */
static void expect_refused(vm_mesh *m, const char *name, int want_st, const char *want_msg) {
  char path[256];
  path_in(path, sizeof path, name);
  int st = vm_mesh_write(ctx, m, path, VM_FMT_FOAM, NULL);
  const char *e = vm_ctx_error(ctx);
  CHECK(st == want_st && strstr(e, want_msg) && !strchr(e, '\n') && !exists(path),
        "%s: status %d, '%s'", name, st, e);
  CHECK(hidden_entries(dir) == 0, "%s: temporary trees left", name);
}

static void test_refused(void) {
  vm_mesh *m;
  /* a 2D mesh, a surface in 3D */
  vm_mesh_create(ctx, &m);
  static const int32_t tri[3] = {0, 1, 2};
  for (int i = 0; i < 3; i++) vm_mesh_add_vertex(m, i == 1, i == 2, 0, NULL);
  vm_mesh_add_element(m, VM_TRI, tri);
  m->dim = 2;
  expect_refused(m, "flat.foam", VM_ERR_UNSUPPORTED, "flat.foam: OpenFOAM needs 3D cells");
  vm_mesh_destroy(&m);
  vm_mesh_create(ctx, &m);
  vm_gen_cube(m, 2);
  expect_refused(m, "surface.foam", VM_ERR_UNSUPPORTED, "OpenFOAM needs 3D cells");
  vm_mesh_destroy(&m);
  /* three tetrahedra on one triangle; a tetrahedron with a repeated vertex */
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 6; i++) vm_mesh_add_vertex(m, i == 1, i == 2, i >= 3 ? i - 2.0 : 0, NULL);
  for (int32_t a = 3; a < 6; a++) {
    int32_t t[4] = {0, 1, 2, a};
    vm_mesh_add_element(m, VM_TET, t);
  }
  expect_refused(m, "nonmanifold.foam", VM_ERR_ARG, "is shared by 3 cells");
  vm_mesh_destroy(&m);
  vm_mesh_create(ctx, &m);
  for (int i = 0; i < 4; i++) vm_mesh_add_vertex(m, i == 1, i == 2, i == 3, NULL);
  static const int32_t degen[4] = {0, 1, 1, 3};
  vm_mesh_add_element(m, VM_TET, degen);
  expect_refused(m, "degenerate.foam", VM_ERR_ARG, "element 0 (tet) has a face with a repeated");
  vm_mesh_destroy(&m);
  /* the target is a file: left alone */
  char path[256];
  path_in(path, sizeof path, "file.foam");
  put_text(path, "not a case\n");
  m = ft_cube(ctx, 2, FT_HEX, 0);
  int st = vm_mesh_write(ctx, m, path, VM_FMT_FOAM, NULL);
  char *t = read_text(path);
  CHECK(st == VM_ERR_IO && strstr(vm_ctx_error(ctx), "is not a directory") && t &&
            !strcmp(t, "not a case\n"),
        "file target: status %d, '%s'", st, vm_ctx_error(ctx));
  free(t);
  remove(path);
  vm_mesh_destroy(&m);
  /* write only */
  vm_mesh *r = NULL;
  path_in(path, sizeof path, "hex.foam");
  st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &r);
  CHECK(st == VM_ERR_UNSUPPORTED && strstr(vm_ctx_error(ctx), "cannot be read"),
        "read: status %d, '%s'", st, vm_ctx_error(ctx));
  CHECK(vm_format_from_path("a/b.FOAM") == VM_FMT_FOAM &&
            vm_format_from_name("openfoam") == VM_FMT_FOAM &&
            !strcmp(vm_format_name(VM_FMT_FOAM), "foam"),
        "format names");
}

/* An existing case: 0/, system/ and constant/ but polyMesh are kept; the
 * old polyMesh goes whole; missing system files are added. */
static void test_existing_case(void) {
  char c[256], p[512];
  path_in(c, sizeof c, "case");
  static const char *const dirs[] = {"", "/0", "/system", "/constant", "/constant/polyMesh"};
  for (int i = 0; i < 5; i++) {
    snprintf(p, sizeof p, "%s%s", c, dirs[i]);
    mkdir(p, 0777);
  }
  static const char *const keep[][2] = {{"0/U", "U: the user's\n"},
                                        {"system/controlDict", "the user's controlDict\n"},
                                        {"constant/transportProperties", "nu 1e-5;\n"}};
  for (int i = 0; i < 3; i++) {
    snprintf(p, sizeof p, "%s/%s", c, keep[i][0]);
    put_text(p, keep[i][1]);
  }
  snprintf(p, sizeof p, "%s/constant/polyMesh/cellZones", c);
  put_text(p, "old\n");
  vm_mesh *m = ft_cube(ctx, 2, FT_PRISM, 0.1);
  ft_tag_boundary(m);
  wlog lg;
  int st = write_logged(m, c, 0, &lg);
  CHECK(st == VM_OK, "existing case: status %d: %s", st, vm_ctx_error(ctx));
  for (int i = 0; i < 3; i++) {
    snprintf(p, sizeof p, "%s/%s", c, keep[i][0]);
    char *t = read_text(p);
    CHECK(t && !strcmp(t, keep[i][1]), "existing case: %s changed", keep[i][0]);
    free(t);
  }
  snprintf(p, sizeof p, "%s/constant/polyMesh/cellZones", c);
  CHECK(!exists(p), "existing case: the old polyMesh's cellZones is still there");
  snprintf(p, sizeof p, "%s/system/fvSchemes", c);
  CHECK(exists(p), "existing case: system/fvSchemes added");
  ft_case fc;
  int ok = ft_read(c, &fc);
  CHECK(ok, "existing case: %s", fc.err);
  if (ok) check_case("existing case", m, &fc, named, 5);
  ft_case_free(&fc);
  snprintf(p, sizeof p, "%s/constant", c);
  CHECK(hidden_entries(p) == 0 && hidden_entries(dir) == 0, "existing case: temporary trees left");
  vm_mesh_destroy(&m);
}

/* What the writer cannot carry: boundary elements that are no boundary
 * face, repeated ones, names that are no OpenFOAM word, unused vertices;
 * a symmetry patch that is not flat becomes type symmetry. */
static void test_lossy(void) {
  vm_mesh *m = ft_cube(ctx, 2, FT_HEX, 0);
  ft_tag_boundary(m);
  vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  int32_t *tag = malloc(sizeof *tag * (size_t)(m->ne + 8));
  memcpy(tag, ph->data, sizeof *tag * (size_t)m->ne);
  /* the quad between the first two hexes, a repeated wall face, a quad
   * of no cell (an unused vertex in it) */
  int64_t nv;
  vm_mesh_add_vertex(m, 5, 5, 5, &nv);
  const int32_t *h0 = m->conn + m->eoff[0];
  int32_t inner[4] = {h0[1], h0[2], h0[6], h0[5]};
  int32_t orphan[4] = {h0[0], h0[1], h0[2], (int32_t)nv};
  int64_t e_wall = -1;
  for (int64_t e = 0; e < m->ne; e++)
    if (tag[e] == FT_WALL) e_wall = e;
  int32_t again[4];
  memcpy(again, m->conn + m->eoff[e_wall], sizeof again);
  int64_t ne0 = m->ne;
  vm_mesh_add_element(m, VM_QUAD, inner);
  vm_mesh_add_element(m, VM_QUAD, again);
  vm_mesh_add_element(m, VM_QUAD, orphan);
  tag[ne0] = 5;
  tag[ne0 + 1] = FT_WALL;
  tag[ne0 + 2] = 5;
  vm_mesh_remove_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &ph);
  memcpy(ph->data, tag, sizeof *tag * (size_t)m->ne);
  vm_mesh_set_attr(m, "gmsh:physical_name:2:5", "wall 2");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:2", "7 inlet");
  /* the symmetry side bulges: one vertex off the plane y = 0 (lattice
   * vertex (1, 0, 1) of the 3 x 3 x 3) */
  m->xyz[3 * (9 * 1 + 3 * 0 + 1) + 1] = -0.01;
  char path[256];
  path_in(path, sizeof path, "lossy.foam");
  wlog lg;
  int st = write_logged(m, path, 0, &lg);
  CHECK(st == VM_WARN_LOSSY, "lossy: status %d: %s", st, vm_ctx_error(ctx));
  static const char *const want[] = {"1 boundary elements lie between two cells",
                                     "1 boundary elements are no face of any cell",
                                     "1 boundary elements repeat a face already in a patch",
                                     "boundary 'wall 2' written as the patch 'wall_2'",
                                     "boundary '7 inlet' written as the patch 'patch_7_inlet'",
                                     "1 vertices used by no cell are not written",
                                     "the patch 'symmetry' is not planar: written as type symmetry",
                                     "in no named boundary"};
  for (size_t i = 0; i < sizeof want / sizeof want[0]; i++)
    CHECK(strstr(lg.all, want[i]), "lossy: no warning '%s' in:\n%s", want[i], lg.all);
  CHECK(lg.n == (int)(sizeof want / sizeof want[0]), "lossy: %d warnings:\n%s", lg.n, lg.all);
  ft_case c;
  int ok = ft_read(path, &c);
  CHECK(ok, "lossy: %s", c.err);
  if (ok) {
    CHECK(c.npoint == m->nv - 1, "lossy: %lld points", c.npoint);
    CHECK(c.npatch == 6 && !strcmp(c.patch[1].name, "patch_7_inlet") &&
              !strcmp(c.patch[2].type, "symmetry") &&
              !strcmp(c.patch[2].groups, "List<word> 1(symmetry)") &&
              !strcmp(c.patch[4].name, "wall_2") && !strcmp(c.patch[4].type, "wall") &&
              c.patch[4].nfaces == 0 && c.patch[0].nfaces == 4,
          "lossy: patches");
  }
  ft_case_free(&c);
  free(tag);
  vm_mesh_destroy(&m);
}

/* Every allocation of a write, failing in turn: VM_ERR_NOMEM, nothing
 * leaked, nothing left: no new case; an existing case unchanged. */
static void test_alloc_failures(void) {
  vm_mesh *m = ft_cube(ctx, 2, FT_MIXED, 0.1);
  ft_tag_boundary(m);
  char path[256], owner[512], con[300];
  path_in(path, sizeof path, "sweep.foam");
  long live0 = vm_ctx_alloc_live(ctx), n, fails = 0;
  for (n = 1; n < 10000; n++) {
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_mesh_write(ctx, m, path, VM_FMT_FOAM, NULL);
    vm_ctx_set_alloc_fail(ctx, 0);
    CHECK(vm_ctx_alloc_live(ctx) == live0, "new case, allocation %ld: leaked %ld", n,
          vm_ctx_alloc_live(ctx) - live0);
    if (st >= 0) break;
    fails++;
    CHECK(st == VM_ERR_NOMEM && !exists(path) && !hidden_entries(dir),
          "new case, allocation %ld: status %d (%s), left %s", n, st, vm_ctx_error(ctx),
          exists(path) ? "the case" : "");
  }
  CHECK(fails > 10, "new case: %ld allocations failed in turn", fails);
  /* again over the case just written, from a different mesh */
  vm_mesh *h = ft_cube(ctx, 2, FT_HEX, 0);
  snprintf(owner, sizeof owner, "%s/constant/polyMesh/owner", path);
  snprintf(con, sizeof con, "%s/constant", path);
  char *before = read_text(owner);
  for (n = 1; n < 10000; n++) {
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_mesh_write(ctx, h, path, VM_FMT_FOAM, NULL);
    vm_ctx_set_alloc_fail(ctx, 0);
    if (st >= 0) break;
    char *now = read_text(owner);
    CHECK(st == VM_ERR_NOMEM && now && before && !strcmp(now, before) && !hidden_entries(con),
          "existing case, allocation %ld: status %d, owner %s", n, st,
          now && before && !strcmp(now, before) ? "kept" : "changed");
    free(now);
  }
  char *after = read_text(owner);
  CHECK(after && before && strcmp(after, before), "existing case: replaced in the end");
  free(before);
  free(after);
  vm_mesh_destroy(&h);
  vm_mesh_destroy(&m);
}

int main(void) {
  if (vm_ctx_create(&ctx) || !mkdtemp(dir)) return 1;
  test_kinds();
  test_no_faces();
  test_refused();
  test_existing_case();
  test_lossy();
  test_alloc_failures();
  vm_ctx_destroy(&ctx);
  if (!vmtest_failures) ft_rmtree(dir);
  return vmtest_end("test_foam");
}
