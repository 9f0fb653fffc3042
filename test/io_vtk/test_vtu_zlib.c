/* test/io_vtk/test_vtu_zlib.c: the VTU reader's own inflater against data
 * compressed by the system zlib at every level and several block sizes. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "varmesh/io.h"
#include "vmtest.h"

typedef struct {
  char *b;
  size_t n, cap;
} text;

static void put(text *t, const void *p, size_t n) {
  if (t->n + n + 1 > t->cap) {
    t->cap = (t->n + n + 1) * 2;
    t->b = realloc(t->b, t->cap);
  }
  memcpy(t->b + t->n, p, n);
  t->n += n;
  t->b[t->n] = 0;
}
static void puts_(text *t, const char *s) { put(t, s, strlen(s)); }

static void b64(text *t, const uint8_t *p, size_t n) {
  static const char c[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t i = 0; i < n; i += 3) {
    uint32_t w = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0) |
                 (i + 2 < n ? p[i + 2] : 0);
    char q[4] = {c[w >> 18 & 63], c[w >> 12 & 63], i + 1 < n ? c[w >> 6 & 63] : '=',
                 i + 2 < n ? c[w & 63] : '='};
    put(t, q, 4);
  }
}

/* vtkZLibDataCompressor layout: [nblocks, blocksize, lastsize, csize...]
 * (UInt32, little-endian host assumed by the test), then the blocks. */
static void zarray(text *t, const char *decl, const void *data, size_t n, size_t bs, int level) {
  size_t nb = n ? (n + bs - 1) / bs : 0;
  uint32_t *hdr = calloc(3 + nb, 4);
  uint8_t *comp = malloc(nb * compressBound((uLong)bs) + 1);
  size_t clen = 0;
  hdr[0] = (uint32_t)nb;
  hdr[1] = (uint32_t)bs;
  hdr[2] = (uint32_t)(n % bs);
  for (size_t b = 0; b < nb; b++) {
    size_t len = b + 1 < nb || n % bs == 0 ? bs : n % bs;
    uLongf out = compressBound((uLong)bs);
    compress2(comp + clen, &out, (const Bytef *)data + b * bs, (uLong)len, level);
    hdr[3 + b] = (uint32_t)out;
    clen += out;
  }
  char buf[256];
  snprintf(buf, sizeof buf, "<DataArray %s format=\"binary\">", decl);
  puts_(t, buf);
  b64(t, (const uint8_t *)hdr, (3 + nb) * 4);
  b64(t, comp, clen);
  puts_(t, "</DataArray>\n");
  free(hdr);
  free(comp);
}

int main(void) {
  vm_ctx *ctx;
  vm_ctx_create(&ctx);
  long live0 = vm_ctx_alloc_live(ctx);
  enum { NP = 2000 };
  double *xyz = malloc(NP * 3 * sizeof *xyz);
  int32_t *ids = malloc(NP * sizeof *ids);
  uint32_t x = 1;
  for (int i = 0; i < NP; i++) {
    x = x * 1664525u + 1013904223u;
    xyz[3 * i] = i * 0.25;                   /* compressible */
    xyz[3 * i + 1] = (double)(x >> 8) / 7.0; /* noise */
    xyz[3 * i + 2] = (i % 17) - 8.0;
    ids[i] = (int32_t)(x >> (i % 20));
  }
  const int32_t conn[4] = {0, 1, 2, 3}, off[1] = {4};
  const uint8_t type[1] = {10};
  const size_t bsizes[3] = {1 << 15, 1000, 7};
  int runs = 0;
  const int levels[5] = {0, 1, 4, 6, 9}; /* stored, fixed and dynamic Huffman blocks */
  for (int l = 0; l < 5; l++)
    for (int k = 0; k < 3; k++) {
      int level = levels[l];
      size_t bs = bsizes[k];
      if (bs == 7 && level != 6) continue; /* tiny blocks: one level is enough */
      text t = {0};
      puts_(&t, "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" "
                "compressor=\"vtkZLibDataCompressor\"><UnstructuredGrid>");
      char buf[128];
      snprintf(buf, sizeof buf, "<Piece NumberOfPoints=\"%d\" NumberOfCells=\"1\">", NP);
      puts_(&t, buf);
      puts_(&t, "<PointData>");
      zarray(&t, "type=\"Int32\" Name=\"ids\"", ids, NP * 4, bs, level);
      puts_(&t, "</PointData><Points>");
      zarray(&t, "type=\"Float64\" NumberOfComponents=\"3\"", xyz, NP * 24, bs, level);
      puts_(&t, "</Points><Cells>");
      zarray(&t, "type=\"Int32\" Name=\"connectivity\"", conn, 16, bs, level);
      zarray(&t, "type=\"Int32\" Name=\"offsets\"", off, 4, bs, level);
      zarray(&t, "type=\"UInt8\" Name=\"types\"", type, 1, bs, level);
      puts_(&t, "</Cells></Piece></UnstructuredGrid></VTKFile>\n");
      vm_mesh *m = NULL;
      int st = vm_mesh_read_memory(ctx, "z.vtu", (const uint8_t *)t.b, t.n, VM_FMT_AUTO, &m);
      CHECK(st == VM_OK, "level %d block %zu: %s", level, bs, vm_ctx_error(ctx));
      if (m) {
        vm_field *f = vm_mesh_find_field(m, "ids", VM_FIELD_VERTEX);
        CHECK(m->nv == NP && !memcmp(m->xyz, xyz, NP * 24), "level %d block %zu: points", level,
              bs);
        CHECK(f && !memcmp(f->data, ids, NP * 4), "level %d block %zu: ids", level, bs);
        CHECK(m->ne == 1 && m->etype[0] == VM_TET, "level %d block %zu: cell", level, bs);
        vm_mesh_destroy(&m);
      }
      runs++;
      free(t.b);
    }
  CHECK(runs == 11, "ran %d cases", runs);
  free(xyz);
  free(ids);
  CHECK(vm_ctx_alloc_live(ctx) == live0, "leaked %ld", vm_ctx_alloc_live(ctx) - live0);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_vtu_zlib");
}
