/* test/io_robust/test_complexity.c: hostile input gets linear time. Each
 * reader's worst case as far as we know it, crafted at about 1 MB and 10 MB:
 *  - OBJ and PLY: star polygons of 1,024 vertices where ear clipping found
 *    no ear and searched k^3 steps (a 1.2 MB file took 86-93 s);
 *  - OBJ: convex 1,024-gons;
 *  - STL: points whose coordinates put them all in one slot of the fixed
 *    hash the vertex merge used (8.9 MB took 39 s);
 *  - VTK and VTU: many small data arrays, each one a field whose addition
 *    searched all the others (a FIELD block of 40,000 arrays, 0.9 MB, took
 *    11 s); refused now past the readers' ceiling of arrays;
 *  - MSH 4.1: one element block per element, each on its own entity with
 *    its own physical name (searches per block, one attribute per name);
 *  - MEDIT: one Triangles and one Corners section per triangle (a growing
 *    element array per section);
 *  - OFF: the star polygons;
 *  - SU2: one marker per boundary triangle, each with its own name (an
 *    attribute each, once searched among all the others);
 *  - .vmsht and .vmsh: many one-value fields (vm_mesh_check compared every
 *    pair of names: a 6 MB .vmsht took 67 s);
 *  - CGNS (where libcgns is): many fields, refused past the reader's
 *    ceiling of fields (libcgns finds each by name among all); libcgns still
 *    reads the whole tree first, its own cost. At 0.25 and 2.5 MB: libcgns's
 *    writer, which makes the files, is quadratic in the fields.
 * The CPU time of the 10 MB file must stay within 30 times the 1 MB file's
 * (linear: 10; n log n: about 12) and below 10 s (1 MB/s: the readers take
 * 0.2-0.3 s; before, the stars took 54 s), and every file must read (a mesh with
 * the right number of triangles). CPU time, not wall time: another process
 * on the machine does not make it flaky. */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "varmesh/io.h"
#include "vmtest.h"

typedef struct {
  char *p;
  size_t n, cap;
} buf;

static void put(buf *b, const char *fmt, ...) {
  va_list ap;
  for (;;) {
    va_start(ap, fmt);
    int k = vsnprintf(b->p + b->n, b->cap - b->n, fmt, ap);
    va_end(ap);
    if (k >= 0 && (size_t)k < b->cap - b->n) {
      b->n += (size_t)k;
      return;
    }
    b->cap = 2 * b->cap + 1024;
    b->p = realloc(b->p, b->cap);
  }
}

enum { K = 1024 };

/* A star polygon {K/3} (self-intersecting) whose points alternate between
 * two radii: every corner turns left, yet every candidate ear holds points
 * of the inner circle, so the ear clipper scanned all K corners, each
 * against all K others, for every one of the K triangles. */
static void star(double *x, double *y) {
  for (int i = 0; i < K; i++) {
    int j = (3 * i) % K;
    double r = j % 2 ? 0.3 : 1.0, a = 2 * 3.14159265358979 * j / K;
    x[i] = r * cos(a), y[i] = r * sin(a);
  }
}

static void make_poly(buf *b, const char *fmt, size_t target, int convex, int64_t *ntri) {
  double x[K], y[K];
  if (convex)
    for (int i = 0; i < K; i++)
      x[i] = cos(2 * 3.14159265358979 * i / K), y[i] = sin(2 * 3.14159265358979 * i / K);
  else
    star(x, y);
  /* polygons sharing nothing, each its own K vertices */
  int np = 0;
  buf body = {0};
  size_t per = 0;
  /* estimate the bytes per polygon with one */
  for (int i = 0; i < K; i++) put(&body, "%.6g %.6g %d\n", x[i], y[i], 0);
  per = body.n + 8 * K;
  body.n = 0;
  np = (int)(target / per) + 1;
  b->n = 0;
  if (!strcmp(fmt, "obj")) {
    for (int p = 0; p < np; p++)
      for (int i = 0; i < K; i++) put(b, "v %.6g %.6g %d\n", x[i], y[i], p);
    for (int p = 0; p < np; p++) {
      put(b, "f");
      for (int i = 0; i < K; i++) put(b, " %d", p * K + i + 1);
      put(b, "\n");
    }
  } else {
    /* OFF and PLY: a header, then the same vertex and face lines */
    if (!strcmp(fmt, "off"))
      put(b, "OFF\n%d %d 0\n", np * K, np);
    else
      put(b,
          "ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
          "property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
          "end_header\n",
          np * K, np);
    for (int p = 0; p < np; p++)
      for (int i = 0; i < K; i++) put(b, "%.6g %.6g %d\n", x[i], y[i], p);
    for (int p = 0; p < np; p++) {
      put(b, "%d", K);
      for (int i = 0; i < K; i++) put(b, " %d", p * K + i);
      put(b, "\n");
    }
  }
  free(body.p);
  *ntri = (int64_t)np * (K - 2);
}

/* The vertex merge once hashed each point with a fixed, invertible mix
 * (splitmix64's finalizer over the coordinates' bits): a file could choose
 * its z coordinates so every point landed in one slot of the table. These
 * are those points (each distinct; x = the point's number, y = 0.5, z the
 * double whose bits make the hash's low 32 bits 0). */
static uint64_t mix64(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

static uint64_t inv_mul(uint64_t a) { /* a odd: a^-1 mod 2^64 by Newton */
  uint64_t x = a;
  for (int i = 0; i < 6; i++) x *= 2 - a * x;
  return x;
}

static uint64_t unmix64(uint64_t x) {
  x ^= x >> 31 ^ x >> 62;
  x *= inv_mul(0x94d049bb133111ebULL);
  x ^= x >> 27 ^ x >> 54;
  x *= inv_mul(0xbf58476d1ce4e5b9ULL);
  x ^= x >> 30 ^ x >> 60;
  return x;
}

static double colliding_z(double x, double y, uint64_t salt) {
  uint64_t h = 0x9e3779b97f4a7c15ULL, b;
  memcpy(&b, &x, sizeof b);
  h = mix64(h ^ b);
  memcpy(&b, &y, sizeof b);
  h = mix64(h ^ b);
  for (uint64_t k = 0;; k++) {
    uint64_t bz = unmix64((salt * 0x9e3779b97f4a7c15ULL + k) << 32) ^ h;
    double z;
    memcpy(&z, &bz, sizeof z);
    if (isfinite(z) && z != 0 && fabs(z) < 1e300 && fabs(z) > 1e-300) return z;
  }
}

static void make_stl(buf *b, size_t target, int64_t *ntri) {
  b->n = 0;
  put(b, "solid s\n");
  int64_t t = 0;
  while (b->n < target) {
    put(b, "facet normal 0 0 1\n outer loop\n");
    for (int i = 0; i < 3; i++) {
      int64_t c = 3 * t + i;
      double x = (double)c, y = 0.5;
      put(b, "  vertex %.17g %.17g %.17g\n", x, y, colliding_z(x, y, (uint64_t)c + 1));
    }
    put(b, " endloop\nendfacet\n");
    t++;
  }
  put(b, "endsolid s\n");
  *ntri = t;
}

/* Legacy VTK (vtu = 0) or VTU: one triangle, then tiny point data arrays
 * until the file has `target` bytes. */
static void make_arrays(buf *b, size_t target, int vtu) {
  b->n = 0;
  int64_t n = (int64_t)(target / 24) + 1;
  if (!vtu) {
    put(b,
        "# vtk DataFile Version 3.0\nmany arrays\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n"
        "POINT_DATA 3\nFIELD f %lld\n",
        (long long)n);
    for (int64_t i = 0; i < n; i++) put(b, "a%lld 1 3 float\n0 0 0\n", (long long)i);
    return;
  }
  put(b, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n"
         "<UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"1\">\n<Points>"
         "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 "
         "1 0</DataArray></Points>\n<Cells><DataArray type=\"Int64\" Name=\"connectivity\" "
         "format=\"ascii\">0 1 2</DataArray><DataArray type=\"Int64\" Name=\"offsets\" "
         "format=\"ascii\">3</DataArray><DataArray type=\"UInt8\" Name=\"types\" "
         "format=\"ascii\">5</DataArray></Cells>\n<PointData>\n");
  while (b->n < target)
    put(b, "<DataArray type=\"Float64\" Name=\"a%zu\" format=\"ascii\">0 0 0</DataArray>\n", b->n);
  put(b, "</PointData></Piece></UnstructuredGrid></VTKFile>\n");
}

/* MSH 4.1: a triangle per element block, each block on its own surface
 * entity with its own physical group and name. */
static void make_msh_blocks(buf *b, size_t target, int64_t *ntri) {
  int64_t n = (int64_t)(target / 80) + 1;
  b->n = 0;
  put(b, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n%lld\n", (long long)n);
  for (int64_t s = 1; s <= n; s++) put(b, "2 %lld \"g%lld\"\n", (long long)s, (long long)s);
  put(b, "$EndPhysicalNames\n$Entities\n0 0 %lld 0\n", (long long)n);
  for (int64_t s = 1; s <= n; s++)
    put(b, "%lld 0 0 0 1 1 0 1 %lld 0\n", (long long)s, (long long)s);
  put(b,
      "$EndEntities\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n"
      "$EndNodes\n$Elements\n%lld %lld 1 %lld\n",
      (long long)n, (long long)n, (long long)n);
  for (int64_t s = 1; s <= n; s++) put(b, "2 %lld 2 1\n%lld 1 2 3\n", (long long)s, (long long)s);
  put(b, "$EndElements\n");
  *ntri = n;
}

/* MEDIT: three vertices, then a Triangles and a Corners section of one
 * entry each, over and over. */
static void make_medit_sections(buf *b, size_t target, int64_t *ntri) {
  b->n = 0;
  put(b, "MeshVersionFormatted 2\nDimension 3\nVertices\n3\n0 0 0 0\n1 0 0 0\n0 1 0 0\n");
  int64_t n = 0;
  while (b->n < target) {
    put(b, "Triangles\n1\n1 2 3 %lld\nCorners\n1\n1\n", (long long)(n % 1000));
    n++;
  }
  put(b, "End\n");
  *ntri = n;
}

/* SU2: a tetrahedron, then one marker per boundary triangle, each with its
 * own name (one attribute per marker, once searched among all the others). */
static void make_su2_markers(buf *b, size_t target, int64_t *ne) {
  int64_t n = (int64_t)(target / 40) + 1;
  b->n = 0;
  put(b, "NDIME= 3\nNELEM= 1\n10 0 1 2 3\nNPOIN= 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nNMARK= %lld\n",
      (long long)n);
  for (int64_t k = 0; k < n; k++)
    put(b, "MARKER_TAG= m%lld\nMARKER_ELEMS= 1\n5 0 2 1\n", (long long)k);
  *ne = 1 + n;
}

/* .vmsht: one triangle and many one-value element fields (vm_mesh_check
 * compared every pair of names: 6 MB took 67 s). */
static void make_vmsht_fields(buf *b, size_t target, int64_t *ne) {
  int64_t n = (int64_t)(target / 40) + 1;
  b->n = 0;
  put(b,
      "vmsht 1 0\ndim 3\nvertices 3\n0 0 0 free -1\n1 0 0 free -1\n0 1 0 free -1\n"
      "elements 1\ntri 0 1 2\nfields %lld\n",
      (long long)n);
  for (int64_t k = 0; k < n; k++) put(b, "field element f64 1 \"f%lld\"\n0\n", (long long)k);
  put(b, "attributes 0\nend\n");
  *ne = 1;
}

/* The same mesh in another format (binary .vmsh, CGNS), through the
 * library's writer: b holds the file's bytes after. */
static int convert_buf(vm_ctx *ctx, buf *b, const char *dir, const char *ext, int fmt) {
  vm_mesh *m = NULL;
  char path[300];
  snprintf(path, sizeof path, "%s/conv.%s", dir, ext);
  int st = vm_mesh_read_memory(ctx, "x.vmsht", (const uint8_t *)b->p, b->n, VM_FMT_VMSH_TEXT, &m);
  if (st >= 0) st = vm_mesh_write(ctx, m, path, fmt, NULL);
  vm_mesh_destroy(&m);
  if (st < 0) return st;
  FILE *f = fopen(path, "rb");
  if (!f) return VM_ERR_IO;
  fseek(f, 0, SEEK_END);
  long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  if (len < 0 || (size_t)len > b->cap) {
    b->cap = (size_t)(len < 0 ? 0 : len) + 1;
    b->p = realloc(b->p, b->cap);
  }
  b->n = len > 0 ? fread(b->p, 1, (size_t)len, f) : 0;
  fclose(f);
  remove(path);
  return VM_OK;
}

/* The CPU seconds of reading b as `path`: it must give a mesh of
 * want_tri elements, or (want_tri < 0) be refused with a message
 * holding `refusal`. */
static double cpu_read(vm_ctx *ctx, const char *path, const buf *b, int64_t want_tri,
                       const char *what, const char *refusal) {
  FILE *f = fopen(path, "wb");
  fwrite(b->p, 1, b->n, f);
  fclose(f);
  clock_t t0 = clock();
  vm_mesh *m = NULL;
  int st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &m);
  double dt = (double)(clock() - t0) / CLOCKS_PER_SEC;
  if (want_tri < 0)
    CHECK(st < 0 && !m && strstr(vm_ctx_error(ctx), refusal),
          "%s (%zu bytes): read %d, not refused with '%s': %s", what, b->n, st, refusal,
          vm_ctx_error(ctx));
  else
    CHECK(st >= 0 && m && m->ne == want_tri, "%s (%zu bytes): read %d, %lld triangles of %lld: %s",
          what, b->n, st, m ? (long long)m->ne : -1LL, (long long)want_tri, vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
  remove(path);
  return dt;
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  vm_ctx_set_log(ctx, NULL, NULL);
  char dir[] = "/tmp/vm_complexity_XXXXXX";
  if (!mkdtemp(dir)) return 1;
  char path[256];
  buf b = {0};
  struct {
    const char *name, *ext;
    int kind; /* 0 poly comb, 1 poly convex, 2 stl, 3 vtk arrays, 4 vtu arrays, 5 msh
                 blocks, 6 medit sections, 7 su2 markers, 8 vmsht fields, 9 vmsh fields,
                 10 cgns fields */
  } cases[] = {
      {"OBJ stars", "obj", 0},    {"OBJ convex", "obj", 1},     {"PLY stars", "ply", 0},
      {"OFF stars", "off", 0},    {"STL one slot", "stl", 2},   {"VTK arrays", "vtk", 3},
      {"VTU arrays", "vtu", 4},   {"MSH blocks", "msh", 5},     {"MEDIT sections", "mesh", 6},
      {"SU2 markers", "su2", 7},  {"VMSHT fields", "vmsht", 8}, {"VMSH fields", "vmsh", 9},
      {"CGNS fields", "cgns", 10}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    /* CGNS where the library has it: many fields are refused past the
     * reader's ceiling, after libcgns has read the file's tree */
    if (cases[c].kind == 10 && !vm_have_cgns()) continue;
    double t[2];
    size_t bytes[2];
    for (int s = 0; s < 2; s++) {
      size_t target = s ? 10u << 20 : 1u << 20;
      int64_t ntri = 0;
      int kind = cases[c].kind;
      if (kind == 2)
        make_stl(&b, target, &ntri);
      else if (kind == 3 || kind == 4)
        make_arrays(&b, target, kind == 4), ntri = -1; /* past the ceiling of arrays */
      else if (kind == 5)
        make_msh_blocks(&b, target, &ntri);
      else if (kind == 6)
        make_medit_sections(&b, target, &ntri);
      else if (kind == 7)
        make_su2_markers(&b, target, &ntri);
      else if (kind == 8)
        make_vmsht_fields(&b, target, &ntri);
      else if (kind == 9) {
        /* the binary chunks are bigger than the text's lines */
        make_vmsht_fields(&b, target / 2, &ntri);
        CHECK(convert_buf(ctx, &b, dir, "vmsh", VM_FMT_VMSH) == VM_OK, "VMSH fields: written");
      } else if (kind == 10) {
        /* HDF5 spends about 700 bytes on a field; a quarter of the sizes
         * (0.25 and 2.5 MB): libcgns's writer takes the square of the
         * fields' count (10 MB, 15,000 fields: a minute) */
        make_vmsht_fields(&b, target / 68, &ntri);
        CHECK(convert_buf(ctx, &b, dir, "cgns", VM_FMT_CGNS) >= 0, "CGNS fields: written");
        /* read (386 fields), or refused past the ceiling (3,856) */
        if ((int64_t)(target / 68 / 40) + 1 > 1024) ntri = -1;
      } else
        make_poly(&b, cases[c].ext, target, kind == 1, &ntri);
      snprintf(path, sizeof path, "%s/x.%s", dir, cases[c].ext);
      bytes[s] = b.n;
      t[s] = cpu_read(ctx, path, &b, ntri, cases[c].name, "ceiling");
    }
    double ratio = t[1] / fmax(t[0], 1e-3);
    fprintf(stderr, "%-14s %8.2f MB %7.3f s  %8.2f MB %7.3f s  ratio %.1f\n", cases[c].name,
            bytes[0] / 1048576.0, t[0], bytes[1] / 1048576.0, t[1], ratio);
    CHECK(ratio < 30 && t[1] < 10, "%s: 10 MB in %.2f s, 1 MB in %.2f s: not linear", cases[c].name,
          t[1], t[0]);
  }
  free(b.p);
  rmdir(dir);
  vm_ctx_destroy(&ctx);
  return vmtest_end("complexity");
}
