/* lib/io/src/vmsh.c: the .vmsh binary and .vmsht text mesh formats (specification: docs/vmsh.md).
 */
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <errno.h>
#include <string.h>

#include "formats_private.h"
#include "mesh_names.h"
#include "lex_private.h"

#define VMSH_MAJOR 1
#define VMSH_MINOR 0
#define VMSH_HEADER_SIZE 24
#define VMSH_CHUNK_HEADER_SIZE 16
#define VMSH_TRAILER_SIZE 4
#define VMSH_MESH_BODY 32
#define VMSH_FIELD_HEADER 16
#define VMSH_ATTR_HEADER 8
#define VMSH_CRITICAL 1u
#define VMSH_MAX_NCOMP (1 << 20)

static const uint8_t vmsh_magic[8] = {0x89, 'V', 'M', 'S', 'H', 0x0D, 0x0A, 0x1A};
static const char vmsht_magic[] = "vmsht";

enum { K_MESH, K_VERT, K_VFLG, K_ELEM, K_FILD, K_ATTR, K_UNKNOWN };
static const char *const chunk_tags[K_UNKNOWN] = {"MESH", "VERT", "VFLG", "ELEM", "FILD", "ATTR"};

static const char *const flag_names[3] = {"free", "fixed", "slip"};
static const char *const loc_names[2] = {"vertex", "element"};
static const char *const ftype_names[2] = {"f64", "i32"};

/* CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320, init and xorout
 * 0xFFFFFFFF). The table lives in the state, so there is no global. */
typedef struct {
  uint32_t tab[256];
  uint32_t crc;
} crc32_state;

static void crc_init(crc32_state *s) {
  for (uint32_t i = 0; i < 256; i++) {
    uint32_t c = i;
    for (int k = 0; k < 8; k++) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    s->tab[i] = c;
  }
  s->crc = 0xFFFFFFFFu;
}

static void crc_update(crc32_state *s, const uint8_t *p, size_t n) {
  uint32_t c = s->crc;
  for (size_t i = 0; i < n; i++) c = s->tab[(c ^ p[i]) & 0xFF] ^ (c >> 8);
  s->crc = c;
}

static uint32_t crc_final(const crc32_state *s) { return s->crc ^ 0xFFFFFFFFu; }

/* Little-endian decoding, independent of the host's byte order. */
static uint16_t get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (unsigned)p[1] << 8); }
static uint32_t get_u32(const uint8_t *p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint64_t get_u64(const uint8_t *p) {
  return (uint64_t)get_u32(p) | (uint64_t)get_u32(p + 4) << 32;
}
static int32_t get_i32(const uint8_t *p) {
  uint32_t u = get_u32(p);
  int32_t v;
  memcpy(&v, &u, sizeof v);
  return v;
}
static double get_f64(const uint8_t *p) {
  uint64_t u = get_u64(p);
  double d;
  memcpy(&d, &u, sizeof d);
  return d;
}

static uint64_t pad4(uint64_t n) { return (n + 3) & ~(uint64_t)3; }
static uint64_t pad8(uint64_t n) { return (n + 7) & ~(uint64_t)7; }

static int has_nul(const uint8_t *p, uint64_t n) { return n && memchr(p, 0, (size_t)n) != NULL; }

/* A copy of n bytes as a NUL-terminated string. */
static char *dup_bytes(vm_ctx *ctx, const void *p, size_t n) {
  char *s = vm_malloc(ctx, n + 1);
  if (!s) return NULL;
  if (n) memcpy(s, p, n);
  s[n] = 0;
  return s;
}

/* Binary reader. */

typedef struct {
  vm_ctx *ctx;
  const char *name;
  const uint8_t *buf;
  uint64_t end; /* offset of the trailer: chunks live in [24, end) */
} bin_reader;

typedef struct {
  uint64_t off; /* offset of the chunk header in the file */
  int kind;
  char tag[16]; /* printable form of the tag */
  uint32_t flags;
  uint64_t len;
  const uint8_t *body;
} bin_chunk;

typedef struct {
  int dim;
  uint64_t nv, ne, nconn;
  int nfield, nattr;
  int seen[K_UNKNOWN];
} bin_counts;

static void tag_text(const uint8_t *t, char out[16]) {
  int printable = 1;
  for (int i = 0; i < 4; i++)
    if (t[i] < 0x20 || t[i] > 0x7E) printable = 0;
  if (printable)
    snprintf(out, 16, "%c%c%c%c", t[0], t[1], t[2], t[3]);
  else
    snprintf(out, 16, "0x%02X%02X%02X%02X", t[0], t[1], t[2], t[3]);
}

static int bin_fail(const bin_reader *r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static int bin_fail(const bin_reader *r, const char *fmt, ...) {
  char msg[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vm_error(r->ctx, VM_ERR_FORMAT, "%s: %s", r->name, msg);
}

static int chunk_fail(const bin_reader *r, const bin_chunk *c, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int chunk_fail(const bin_reader *r, const bin_chunk *c, const char *fmt, ...) {
  char msg[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vm_error(r->ctx, VM_ERR_FORMAT, "%s: %s chunk at offset %llu: %s", r->name, c->tag,
                  (unsigned long long)c->off, msg);
}

/* Decode the chunk at *pos and advance *pos past it and its padding.
 * Checks only the framing: header, length and zero padding fit the file. */
static int next_chunk(const bin_reader *r, uint64_t *pos, bin_chunk *c) {
  uint64_t p = *pos, left = r->end - p;
  if (left < VMSH_CHUNK_HEADER_SIZE)
    return bin_fail(r, "offset %llu: chunk header needs %d bytes, only %llu left",
                    (unsigned long long)p, VMSH_CHUNK_HEADER_SIZE, (unsigned long long)left);
  const uint8_t *h = r->buf + p;
  c->off = p;
  tag_text(h, c->tag);
  c->kind = K_UNKNOWN;
  for (int k = 0; k < K_UNKNOWN; k++)
    if (!memcmp(h, chunk_tags[k], 4)) c->kind = k;
  c->flags = get_u32(h + 4);
  c->len = get_u64(h + 8);
  c->body = h + VMSH_CHUNK_HEADER_SIZE;
  left -= VMSH_CHUNK_HEADER_SIZE;
  if (c->len > left)
    return chunk_fail(r, c, "length %llu exceeds the %llu bytes left before the trailer",
                      (unsigned long long)c->len, (unsigned long long)left);
  uint64_t padded = pad8(c->len);
  if (padded > left) return chunk_fail(r, c, "padding to 8 bytes runs past the trailer");
  for (uint64_t i = c->len; i < padded; i++)
    if (c->body[i])
      return chunk_fail(r, c, "padding byte at offset %llu is not zero",
                        (unsigned long long)(p + VMSH_CHUNK_HEADER_SIZE + i));
  *pos = p + VMSH_CHUNK_HEADER_SIZE + padded;
  return VM_OK;
}

static uint64_t field_item_count(const bin_counts *k, int location) {
  return location == VM_FIELD_VERTEX ? k->nv : k->ne;
}

/* Pass 1 for one chunk: counts and lengths, before anything is allocated. */
static int check_chunk(const bin_reader *r, const bin_chunk *c, int index, bin_counts *k) {
  if (index == 0 && c->kind != K_MESH) return chunk_fail(r, c, "the first chunk must be MESH");
  if (c->kind == K_UNKNOWN) {
    if (c->flags & VMSH_CRITICAL)
      return chunk_fail(r, c,
                        "unknown chunk marked critical (written by a newer version?); "
                        "cannot read this file");
    return VM_OK;
  }
  if (c->kind != K_FILD && c->kind != K_ATTR && k->seen[c->kind])
    return chunk_fail(r, c, "chunk appears more than once");
  k->seen[c->kind]++;
  const uint8_t *b = c->body;
  switch (c->kind) {
  case K_MESH: {
    if (c->len != VMSH_MESH_BODY)
      return chunk_fail(r, c, "length %llu, expected %d", (unsigned long long)c->len,
                        VMSH_MESH_BODY);
    uint32_t dim = get_u32(b);
    if (dim != 2 && dim != 3) return chunk_fail(r, c, "dimension %u is not 2 or 3", dim);
    if (get_u32(b + 4)) return chunk_fail(r, c, "reserved word is not zero");
    k->dim = (int)dim;
    k->nv = get_u64(b + 8);
    k->ne = get_u64(b + 16);
    k->nconn = get_u64(b + 24);
    if (k->nv > INT32_MAX)
      return chunk_fail(r, c, "vertex count %llu exceeds the limit %d", (unsigned long long)k->nv,
                        INT32_MAX);
    if (k->ne > INT32_MAX)
      return chunk_fail(r, c, "element count %llu exceeds the limit %d", (unsigned long long)k->ne,
                        INT32_MAX);
    if (k->nconn < 3 * k->ne || k->nconn > (uint64_t)VM_MAX_ELEM_VERTS * k->ne)
      return chunk_fail(r, c, "connectivity length %llu impossible for %llu elements",
                        (unsigned long long)k->nconn, (unsigned long long)k->ne);
    return VM_OK;
  }
  case K_VERT:
    if (c->len != 24 * k->nv)
      return chunk_fail(r, c, "length %llu, expected %llu for %llu vertices",
                        (unsigned long long)c->len, (unsigned long long)(24 * k->nv),
                        (unsigned long long)k->nv);
    return VM_OK;
  case K_VFLG:
    if (c->len != 5 * k->nv)
      return chunk_fail(r, c, "length %llu, expected %llu for %llu vertices",
                        (unsigned long long)c->len, (unsigned long long)(5 * k->nv),
                        (unsigned long long)k->nv);
    return VM_OK;
  case K_ELEM: {
    uint64_t want = pad4(k->ne) + 4 * k->nconn;
    if (c->len != want)
      return chunk_fail(r, c, "length %llu, expected %llu for %llu elements and %llu indices",
                        (unsigned long long)c->len, (unsigned long long)want,
                        (unsigned long long)k->ne, (unsigned long long)k->nconn);
    return VM_OK;
  }
  case K_FILD: {
    if (c->len < VMSH_FIELD_HEADER)
      return chunk_fail(r, c, "length %llu is shorter than the %d-byte field header",
                        (unsigned long long)c->len, VMSH_FIELD_HEADER);
    int loc = b[0], type = b[1];
    uint32_t ncomp = get_u32(b + 4), nlen = get_u32(b + 8);
    if (loc != VM_FIELD_VERTEX && loc != VM_FIELD_ELEMENT)
      return chunk_fail(r, c, "field location %d is not 0 (vertex) or 1 (element)", loc);
    if (type != VM_FIELD_F64 && type != VM_FIELD_I32)
      return chunk_fail(r, c, "field type %d is not 0 (f64) or 1 (i32)", type);
    if (get_u16(b + 2) || get_u32(b + 12))
      return chunk_fail(r, c, "reserved field header bytes are not zero");
    if (ncomp < 1 || ncomp > VMSH_MAX_NCOMP)
      return chunk_fail(r, c, "component count %u is not in [1, %d]", ncomp, VMSH_MAX_NCOMP);
    if (nlen == 0) return chunk_fail(r, c, "field name is empty");
    if (nlen > c->len - VMSH_FIELD_HEADER)
      return chunk_fail(r, c, "field name length %u runs past the chunk", nlen);
    for (uint64_t i = nlen; i < pad8(nlen) && i < c->len - VMSH_FIELD_HEADER; i++)
      if (b[VMSH_FIELD_HEADER + i])
        return chunk_fail(r, c, "padding after the field name is not zero");
    uint64_t esz = type == VM_FIELD_F64 ? 8 : 4;
    uint64_t items = field_item_count(k, loc);
    uint64_t want = VMSH_FIELD_HEADER + pad8(nlen) + items * ncomp * esz;
    if (c->len != want)
      return chunk_fail(r, c, "length %llu, expected %llu for %llu %ss x %u %s values",
                        (unsigned long long)c->len, (unsigned long long)want,
                        (unsigned long long)items, loc_names[loc], ncomp, ftype_names[type]);
    if (k->nfield == INT_MAX) return chunk_fail(r, c, "too many fields");
    k->nfield++;
    return VM_OK;
  }
  case K_ATTR: {
    if (c->len < VMSH_ATTR_HEADER)
      return chunk_fail(r, c, "length %llu is shorter than the %d-byte attribute header",
                        (unsigned long long)c->len, VMSH_ATTR_HEADER);
    uint64_t klen = get_u32(b), vlen = get_u32(b + 4);
    if (klen == 0) return chunk_fail(r, c, "attribute key is empty");
    if (c->len != VMSH_ATTR_HEADER + klen + vlen)
      return chunk_fail(r, c, "length %llu, expected %llu for a %llu-byte key and %llu-byte value",
                        (unsigned long long)c->len,
                        (unsigned long long)(VMSH_ATTR_HEADER + klen + vlen),
                        (unsigned long long)klen, (unsigned long long)vlen);
    if (k->nattr == INT_MAX) return chunk_fail(r, c, "too many attributes");
    k->nattr++;
    return VM_OK;
  }
  default: return VM_OK;
  }
}

/* Pass 2 for one chunk: decode and validate the values into m. */
static int load_chunk(const bin_reader *r, const bin_chunk *c, const bin_counts *k, vm_mesh *m,
                      uint64_t *field_at, uint64_t *attr_at) {
  vm_ctx *ctx = r->ctx;
  const uint8_t *b = c->body;
  switch (c->kind) {
  case K_VERT:
    for (uint64_t i = 0; i < 3 * k->nv; i++) {
      double x = get_f64(b + 8 * i);
      if (!isfinite(x))
        return chunk_fail(r, c, "vertex %llu: coordinate %c is %s", (unsigned long long)(i / 3),
                          "xyz"[i % 3], isnan(x) ? "NaN" : "infinite");
      m->xyz[i] = x;
    }
    return VM_OK;
  case K_VFLG: {
    const uint8_t *fl = b + 4 * k->nv;
    for (uint64_t v = 0; v < k->nv; v++) {
      if (fl[v] > VM_VERTEX_SLIP)
        return chunk_fail(r, c, "vertex %llu: flag %d is not 0 (free), 1 (fixed) or 2 (slip)",
                          (unsigned long long)v, fl[v]);
      m->vflag[v] = fl[v];
      m->vsurf[v] = get_i32(b + 4 * v);
    }
    return VM_OK;
  }
  case K_ELEM: {
    m->eoff[0] = 0;
    for (uint64_t e = 0; e < k->ne; e++) {
      int k_e = vm_elem_nverts(b[e]);
      if (!k_e)
        return chunk_fail(r, c, "element %llu: type %d is not a known element type",
                          (unsigned long long)e, b[e]);
      if ((uint64_t)m->eoff[e] + (uint64_t)k_e > k->nconn)
        return chunk_fail(r, c, "element %llu: connectivity runs past the %llu indices",
                          (unsigned long long)e, (unsigned long long)k->nconn);
      m->etype[e] = b[e];
      m->eoff[e + 1] = m->eoff[e] + k_e;
    }
    if ((uint64_t)m->eoff[k->ne] != k->nconn)
      return chunk_fail(r, c, "element types need %lld indices, MESH says %llu",
                        (long long)m->eoff[k->ne], (unsigned long long)k->nconn);
    for (uint64_t i = k->ne; i < pad4(k->ne); i++)
      if (b[i]) return chunk_fail(r, c, "padding after the element types is not zero");
    const uint8_t *cn = b + pad4(k->ne);
    uint64_t e = 0;
    for (uint64_t i = 0; i < k->nconn; i++) {
      while ((uint64_t)m->eoff[e + 1] <= i) e++;
      int32_t v = get_i32(cn + 4 * i);
      if (v < 0 || (uint64_t)v >= k->nv)
        return chunk_fail(r, c, "element %llu: vertex index %d out of range [0, %llu)",
                          (unsigned long long)e, v, (unsigned long long)k->nv);
      m->conn[i] = v;
    }
    return VM_OK;
  }
  case K_FILD: {
    int loc = b[0], type = b[1];
    uint32_t ncomp = get_u32(b + 4), nlen = get_u32(b + 8);
    const uint8_t *nm = b + VMSH_FIELD_HEADER;
    if (has_nul(nm, nlen)) return chunk_fail(r, c, "field name contains a NUL byte");
    uint64_t nval = field_item_count(k, loc) * ncomp;
    size_t esz = type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t);
    char *name = dup_bytes(ctx, nm, nlen);
    void *data = vm_alloc_array(ctx, (size_t)nval, esz);
    if (!name || !data) {
      vm_free(ctx, name);
      vm_free(ctx, data);
      return vm_error(ctx, VM_ERR_NOMEM, "%s: %s chunk at offset %llu: out of memory", r->name,
                      c->tag, (unsigned long long)c->off);
    }
    const uint8_t *d = nm + pad8(nlen);
    for (uint64_t i = 0; i < nval; i++) {
      if (type == VM_FIELD_F64)
        ((double *)data)[i] = get_f64(d + 8 * i);
      else
        ((int32_t *)data)[i] = get_i32(d + 4 * i);
    }
    vm_field *f = &m->fields[m->nfield];
    f->name = name;
    f->location = loc;
    f->type = type;
    f->ncomp = (int)ncomp;
    f->data = data;
    field_at[m->nfield++] = c->off;
    return VM_OK;
  }
  case K_ATTR: {
    uint32_t klen = get_u32(b), vlen = get_u32(b + 4);
    const uint8_t *ks = b + VMSH_ATTR_HEADER, *vs = ks + klen;
    if (has_nul(ks, klen)) return chunk_fail(r, c, "attribute key contains a NUL byte");
    if (has_nul(vs, vlen)) return chunk_fail(r, c, "attribute value contains a NUL byte");
    char *key = dup_bytes(ctx, ks, klen);
    char *val = dup_bytes(ctx, vs, vlen);
    if (!key || !val) {
      vm_free(ctx, key);
      vm_free(ctx, val);
      return vm_error(ctx, VM_ERR_NOMEM, "%s: %s chunk at offset %llu: out of memory", r->name,
                      c->tag, (unsigned long long)c->off);
    }
    m->attrs[m->nattr].key = key;
    m->attrs[m->nattr].value = val;
    attr_at[m->nattr++] = c->off;
    return VM_OK;
  }
  default: return VM_OK;
  }
}

/* Allocate the mesh for the validated counts; fields and attributes get
 * their exact array sizes so loading never reallocates. */
static int alloc_mesh(vm_ctx *ctx, const char *name, int dim, int64_t nv, int64_t ne, int64_t nconn,
                      int nfield, int nattr, vm_mesh **out, uint64_t **field_at,
                      uint64_t **attr_at) {
  vm_mesh *m = NULL;
  int st = vm_mesh_create(ctx, &m);
  if (!st) st = vm_mesh_set_vertices(m, nv);
  if (!st && ne >= 0) st = vm_mesh_set_elements(m, ne, nconn);
  if (!st) {
    m->dim = dim;
    m->fields = nfield ? vm_calloc(ctx, (size_t)nfield, sizeof *m->fields) : NULL;
    m->attrs = nattr ? vm_calloc(ctx, (size_t)nattr, sizeof *m->attrs) : NULL;
    *field_at = nfield ? vm_alloc_array(ctx, (size_t)nfield, sizeof **field_at) : NULL;
    *attr_at = nattr ? vm_alloc_array(ctx, (size_t)nattr, sizeof **attr_at) : NULL;
    if ((nfield && (!m->fields || !*field_at)) || (nattr && (!m->attrs || !*attr_at)))
      st = VM_ERR_NOMEM;
  }
  if (st) {
    vm_free(ctx, *field_at);
    vm_free(ctx, *attr_at);
    *field_at = *attr_at = NULL;
    vm_mesh_destroy(&m);
    return vm_error(ctx, st, "%s: out of memory for the mesh", name);
  }
  *out = m;
  return VM_OK;
}

/* Reject repeated field names (per location) and attribute keys; `text`
 * selects "line N" instead of "FILD chunk at offset N" in the message. */
static int check_duplicates(vm_ctx *ctx, const char *name, const vm_mesh *m,
                            const uint64_t *field_at, const uint64_t *attr_at, int text) {
  int d;
  if (vm_mesh_first_duplicate(ctx, m, 1, &d))
    return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", name);
  if (d >= 0) {
    const vm_field *f = &m->fields[d];
    if (text)
      return vm_error(ctx, VM_ERR_FORMAT, "%s: line %llu: %s field '%.80s' appears twice", name,
                      (unsigned long long)field_at[d], loc_names[f->location], f->name);
    return vm_error(ctx, VM_ERR_FORMAT,
                    "%s: FILD chunk at offset %llu: %s field '%.80s' appears twice", name,
                    (unsigned long long)field_at[d], loc_names[f->location], f->name);
  }
  if (vm_mesh_first_duplicate(ctx, m, 0, &d))
    return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", name);
  if (d >= 0) {
    if (text)
      return vm_error(ctx, VM_ERR_FORMAT, "%s: line %llu: attribute '%.80s' appears twice", name,
                      (unsigned long long)attr_at[d], m->attrs[d].key);
    return vm_error(ctx, VM_ERR_FORMAT,
                    "%s: ATTR chunk at offset %llu: attribute '%.80s' appears twice", name,
                    (unsigned long long)attr_at[d], m->attrs[d].key);
  }
  return VM_OK;
}

static int read_binary(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                       vm_mesh **out) {
  bin_reader r = {ctx, name, buf, 0};
  if (len < VMSH_HEADER_SIZE) {
    if (len >= 12 && get_u16(buf + 8) > VMSH_MAJOR)
      return bin_fail(&r, "header: format version %u.%u is newer than this reader (%d.x)",
                      get_u16(buf + 8), get_u16(buf + 10), VMSH_MAJOR);
    return bin_fail(&r, "header: file is truncated (%zu bytes, the header alone needs %d)", len,
                    VMSH_HEADER_SIZE);
  }
  unsigned major = get_u16(buf + 8), minor = get_u16(buf + 10);
  if (major > VMSH_MAJOR)
    return bin_fail(&r, "header: format version %u.%u is newer than this reader (%d.x)", major,
                    minor, VMSH_MAJOR);
  if (major < 1) return bin_fail(&r, "header: format version %u.%u is not valid", major, minor);
  if (get_u32(buf + 12)) return bin_fail(&r, "header: reserved word is not zero");
  uint64_t fsize = get_u64(buf + 16);
  if (fsize != len)
    return bin_fail(&r, "header: file size field says %llu bytes but the file has %zu%s",
                    (unsigned long long)fsize, len, fsize > len ? " (truncated?)" : "");
  if (len < VMSH_HEADER_SIZE + VMSH_TRAILER_SIZE)
    return bin_fail(&r, "header: file of %zu bytes has no room for the checksum", len);
  if ((len - VMSH_HEADER_SIZE - VMSH_TRAILER_SIZE) % 8)
    return bin_fail(&r, "header: file size %zu is not 28 plus a multiple of 8", len);
  r.end = len - VMSH_TRAILER_SIZE;
  crc32_state crc;
  crc_init(&crc);
  crc_update(&crc, buf, (size_t)r.end);
  uint32_t want = get_u32(buf + r.end), got = crc_final(&crc);
  if (want != got)
    return bin_fail(&r,
                    "trailer at offset %llu: checksum mismatch (stored 0x%08X, computed 0x%08X)",
                    (unsigned long long)r.end, want, got);

  /* pass 1: framing, counts and every length, before any allocation */
  bin_counts k;
  memset(&k, 0, sizeof k);
  bin_chunk c;
  int nchunk = 0, st;
  for (uint64_t pos = VMSH_HEADER_SIZE; pos < r.end; nchunk++) {
    if ((st = next_chunk(&r, &pos, &c))) return st;
    if ((st = check_chunk(&r, &c, nchunk, &k))) return st;
  }
  if (!k.seen[K_MESH]) return bin_fail(&r, "offset %d: missing the MESH chunk", VMSH_HEADER_SIZE);
  if (!k.seen[K_VERT]) return bin_fail(&r, "missing the required VERT chunk");
  if (!k.seen[K_ELEM]) return bin_fail(&r, "missing the required ELEM chunk");

  /* pass 2: values */
  vm_mesh *m = NULL;
  uint64_t *field_at = NULL, *attr_at = NULL;
  st = alloc_mesh(ctx, name, k.dim, (int64_t)k.nv, (int64_t)k.ne, (int64_t)k.nconn, k.nfield,
                  k.nattr, &m, &field_at, &attr_at);
  if (st) return st;
  for (uint64_t pos = VMSH_HEADER_SIZE; pos < r.end && !st;) {
    st = next_chunk(&r, &pos, &c);
    if (!st) st = load_chunk(&r, &c, &k, m, field_at, attr_at);
  }
  if (!st) st = check_duplicates(ctx, name, m, field_at, attr_at, 0);
  vm_free(ctx, field_at);
  vm_free(ctx, attr_at);
  if (st) {
    vm_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return VM_OK;
}

/* Text reader. */

/* Reject a count whose records cannot fit in what is left: each record has
 * at least `tokens` tokens and each token takes at least 2 bytes. */
static int check_room(vm_lex *lx, int64_t n, int64_t limit, int tokens, const char *what) {
  if (n < 0 || n > limit) return vm_lex_fail(lx, "%s count %lld out of range", what, (long long)n);
  uint64_t left = (uint64_t)(lx->end - lx->p);
  if ((uint64_t)n > left / (2 * (uint64_t)tokens))
    return vm_lex_fail(lx, "%s count %lld cannot fit in the %llu bytes left", what, (long long)n,
                       (unsigned long long)left);
  return VM_OK;
}

static int lex_nomem(vm_lex *lx, const char *what) {
  return vm_error(lx->ctx, VM_ERR_NOMEM, "%s: line %lld: out of memory for %s", lx->name,
                  (long long)lx->line, what);
}

static int hexval(char ch) {
  if (ch >= '0' && ch <= '9') return ch - '0';
  if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
  if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
  return -1;
}

/* A quoted, percent-encoded string token: "abc%20def". */
static int lex_string(vm_lex *lx, char **out, const char *what) {
  const char *s;
  size_t n;
  *out = NULL;
  int st = vm_lex_word(lx, &s, &n, what);
  if (st) return st;
  if (n < 2 || s[0] != '"' || s[n - 1] != '"')
    return vm_lex_fail(lx, "%s: expected a quoted string, found '%.*s'", what,
                       (int)(n > 40 ? 40 : n), s);
  char *r = vm_malloc(lx->ctx, n - 1);
  if (!r) return lex_nomem(lx, what);
  size_t k = 0;
  for (size_t i = 1; i + 1 < n; i++) {
    char ch = s[i];
    if (ch == '"') {
      vm_free(lx->ctx, r);
      return vm_lex_fail(lx, "%s: unescaped '\"' inside a string", what);
    }
    if (ch == '%') {
      int hi = i + 3 < n ? hexval(s[i + 1]) : -1, lo = i + 3 < n ? hexval(s[i + 2]) : -1;
      if (hi < 0 || lo < 0) {
        vm_free(lx->ctx, r);
        return vm_lex_fail(lx, "%s: '%%' must be followed by two hex digits", what);
      }
      ch = (char)(hi * 16 + lo);
      if (!ch) {
        vm_free(lx->ctx, r);
        return vm_lex_fail(lx, "%s: string contains a NUL byte (%%00)", what);
      }
      i += 2;
    }
    r[k++] = ch;
  }
  r[k] = 0;
  *out = r;
  return VM_OK;
}

static int lex_keyword(vm_lex *lx, const char *const *names, int count, const char *what,
                       int *out) {
  const char *s;
  size_t n;
  int st = vm_lex_word(lx, &s, &n, what);
  if (st) return st;
  for (int i = 0; i < count; i++)
    if (vm_tok_is(s, n, names[i])) {
      *out = i;
      return VM_OK;
    }
  return vm_lex_fail(lx, "%s: unknown '%.*s'", what, (int)(n > 40 ? 40 : n), s);
}

static int text_vertices(vm_lex *lx, vm_mesh *m) {
  for (int64_t v = 0; v < m->nv; v++) {
    int st, flag = 0;
    int64_t surf;
    for (int i = 0; i < 3; i++) {
      double x;
      if ((st = vm_lex_double(lx, &x, "vertex coordinate"))) return st;
      if (!isfinite(x))
        return vm_lex_fail(lx, "vertex %lld: coordinate %c is %s", (long long)v, "xyz"[i],
                           isnan(x) ? "NaN" : "infinite");
      m->xyz[3 * v + i] = x;
    }
    if ((st = lex_keyword(lx, flag_names, 3, "vertex flag", &flag))) return st;
    if ((st = vm_lex_int(lx, &surf, "slip surface id"))) return st;
    if (surf < INT32_MIN || surf > INT32_MAX)
      return vm_lex_fail(lx, "vertex %lld: surface id %lld out of range", (long long)v,
                         (long long)surf);
    m->vflag[v] = (uint8_t)flag;
    m->vsurf[v] = (int32_t)surf;
  }
  return VM_OK;
}

static int text_elements(vm_lex *lx, vm_mesh *m, int64_t ne) {
  static const char *const type_names[VM_NTYPES] = {"tri",     "quad",  "tet",
                                                    "pyramid", "prism", "hex"};
  for (int64_t e = 0; e < ne; e++) {
    int type = 0, st;
    int32_t verts[VM_MAX_ELEM_VERTS];
    if ((st = lex_keyword(lx, type_names, VM_NTYPES, "element type", &type))) return st;
    for (int i = 0; i < vm_elem_nverts(type); i++) {
      int64_t v;
      if ((st = vm_lex_int(lx, &v, "vertex index"))) return st;
      if (v < 0 || v >= m->nv)
        return vm_lex_fail(lx, "element %lld: vertex index %lld out of range [0, %lld)",
                           (long long)e, (long long)v, (long long)m->nv);
      verts[i] = (int32_t)v;
    }
    if (vm_mesh_add_element(m, type, verts)) return lex_nomem(lx, "elements");
  }
  return VM_OK;
}

static int text_field(vm_lex *lx, vm_mesh *m, uint64_t *field_at) {
  int loc = 0, type = 0, st;
  int64_t ncomp;
  char *name = NULL;
  if ((st = vm_lex_expect(lx, "field"))) return st;
  uint64_t line = (uint64_t)lx->line;
  if ((st = lex_keyword(lx, loc_names, 2, "field location", &loc))) return st;
  if ((st = lex_keyword(lx, ftype_names, 2, "field type", &type))) return st;
  if ((st = vm_lex_int(lx, &ncomp, "field component count"))) return st;
  if (ncomp < 1 || ncomp > VMSH_MAX_NCOMP)
    return vm_lex_fail(lx, "field component count %lld is not in [1, %d]", (long long)ncomp,
                       VMSH_MAX_NCOMP);
  if ((st = lex_string(lx, &name, "field name"))) return st;
  if (!*name) {
    vm_free(m->ctx, name);
    return vm_lex_fail(lx, "field name is empty");
  }
  int64_t items = loc == VM_FIELD_VERTEX ? m->nv : m->ne;
  int64_t nval = items * ncomp;
  if ((st = check_room(lx, nval, INT64_MAX, 1, "field value"))) {
    vm_free(m->ctx, name);
    return st;
  }
  size_t esz = type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t);
  void *data = vm_alloc_array(m->ctx, (size_t)nval, esz);
  if (!data) {
    vm_free(m->ctx, name);
    return lex_nomem(lx, "field values");
  }
  for (int64_t i = 0; i < nval && !st; i++) {
    if (type == VM_FIELD_F64) {
      st = vm_lex_double(lx, (double *)data + i, "field value");
    } else {
      int64_t v;
      st = vm_lex_int(lx, &v, "field value");
      if (!st && (v < INT32_MIN || v > INT32_MAX))
        st = vm_lex_fail(lx, "field '%.80s': value %lld does not fit in i32", name, (long long)v);
      if (!st) ((int32_t *)data)[i] = (int32_t)v;
    }
  }
  if (st) {
    vm_free(m->ctx, name);
    vm_free(m->ctx, data);
    return st;
  }
  vm_field *f = &m->fields[m->nfield];
  f->name = name;
  f->location = loc;
  f->type = type;
  f->ncomp = (int)ncomp;
  f->data = data;
  field_at[m->nfield++] = line;
  return VM_OK;
}

static int text_attr(vm_lex *lx, vm_mesh *m, uint64_t *attr_at) {
  char *key = NULL, *val = NULL;
  vm_lex_eof(lx);
  uint64_t line = (uint64_t)lx->line;
  int st = lex_string(lx, &key, "attribute key");
  if (!st && !*key) st = vm_lex_fail(lx, "attribute key is empty");
  if (!st) st = lex_string(lx, &val, "attribute value");
  if (st) {
    vm_free(m->ctx, key);
    vm_free(m->ctx, val);
    return st;
  }
  m->attrs[m->nattr].key = key;
  m->attrs[m->nattr].value = val;
  attr_at[m->nattr++] = line;
  return VM_OK;
}

static int read_text(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  vm_lex lx;
  vm_lex_init(&lx, ctx, name, buf, len);
  lx.comment = '#';
  int64_t major, minor, dim, nv, ne, nf, na;
  int st;
  if ((st = vm_lex_expect(&lx, vmsht_magic))) return st;
  if ((st = vm_lex_int(&lx, &major, "major version"))) return st;
  if ((st = vm_lex_int(&lx, &minor, "minor version"))) return st;
  if (major > VMSH_MAJOR)
    return vm_lex_fail(&lx, "format version %lld.%lld is newer than this reader (%d.x)",
                       (long long)major, (long long)minor, VMSH_MAJOR);
  if (major < 1 || minor < 0)
    return vm_lex_fail(&lx, "format version %lld.%lld is not valid", (long long)major,
                       (long long)minor);
  if ((st = vm_lex_expect(&lx, "dim"))) return st;
  if ((st = vm_lex_int(&lx, &dim, "dimension"))) return st;
  if (dim != 2 && dim != 3) return vm_lex_fail(&lx, "dimension %lld is not 2 or 3", (long long)dim);
  if ((st = vm_lex_expect(&lx, "vertices"))) return st;
  if ((st = vm_lex_int(&lx, &nv, "vertex count"))) return st;
  if ((st = check_room(&lx, nv, INT32_MAX, 5, "vertex"))) return st;

  vm_mesh *m = NULL;
  uint64_t *field_at = NULL, *attr_at = NULL;
  if ((st = alloc_mesh(ctx, name, (int)dim, nv, -1, 0, 0, 0, &m, &field_at, &attr_at))) return st;
  if ((st = text_vertices(&lx, m))) goto done;
  if ((st = vm_lex_expect(&lx, "elements"))) goto done;
  if ((st = vm_lex_int(&lx, &ne, "element count"))) goto done;
  if ((st = check_room(&lx, ne, INT32_MAX, 4, "element"))) goto done;
  if ((st = text_elements(&lx, m, ne))) goto done;

  if ((st = vm_lex_expect(&lx, "fields"))) goto done;
  if ((st = vm_lex_int(&lx, &nf, "field count"))) goto done;
  if ((st = check_room(&lx, nf, INT_MAX, 5, "field"))) goto done;
  if (nf) {
    m->fields = vm_calloc(ctx, (size_t)nf, sizeof *m->fields);
    field_at = vm_alloc_array(ctx, (size_t)nf, sizeof *field_at);
    if (!m->fields || !field_at) {
      st = lex_nomem(&lx, "fields");
      goto done;
    }
  }
  for (int64_t i = 0; i < nf; i++)
    if ((st = text_field(&lx, m, field_at))) goto done;

  if ((st = vm_lex_expect(&lx, "attributes"))) goto done;
  if ((st = vm_lex_int(&lx, &na, "attribute count"))) goto done;
  if ((st = check_room(&lx, na, INT_MAX, 2, "attribute"))) goto done;
  if (na) {
    m->attrs = vm_calloc(ctx, (size_t)na, sizeof *m->attrs);
    attr_at = vm_alloc_array(ctx, (size_t)na, sizeof *attr_at);
    if (!m->attrs || !attr_at) {
      st = lex_nomem(&lx, "attributes");
      goto done;
    }
  }
  for (int64_t i = 0; i < na; i++)
    if ((st = text_attr(&lx, m, attr_at))) goto done;

  if ((st = vm_lex_expect(&lx, "end"))) goto done;
  if (!vm_lex_eof(&lx)) {
    const char *s;
    size_t n;
    vm_lex_word(&lx, &s, &n, "end of file");
    st = vm_lex_fail(&lx, "unexpected '%.*s' after 'end'", (int)(n > 40 ? 40 : n), s);
    goto done;
  }
  st = check_duplicates(ctx, name, m, field_at, attr_at, 1);
done:
  vm_free(ctx, field_at);
  vm_free(ctx, attr_at);
  if (st) {
    vm_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return VM_OK;
}

int vm_read_vmsh(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  if (!buf || len == 0) return vm_error(ctx, VM_ERR_FORMAT, "%s: header: file is empty", name);
  size_t nm = len < sizeof vmsh_magic ? len : sizeof vmsh_magic;
  if (!memcmp(buf, vmsh_magic, nm)) return read_binary(ctx, name, buf, len, out);
  size_t nt = sizeof vmsht_magic - 1;
  if (len > nt && !memcmp(buf, vmsht_magic, nt) &&
      (buf[nt] == ' ' || buf[nt] == '\t' || buf[nt] == '\n' || buf[nt] == '\r'))
    return read_text(ctx, name, buf, len, out);
  return vm_error(ctx, VM_ERR_FORMAT,
                  "%s: header: not a .vmsh file (magic is neither \\x89VMSH\\r\\n\\x1a nor "
                  "'vmsht')",
                  name);
}

/* Writers. */

/* What the writers need beyond vm_mesh_check, so that they never produce a
 * file their reader refuses. */
static int check_writable(vm_ctx *ctx, const vm_mesh *m, const char *path) {
  int st = vm_mesh_check(m);
  if (st) {
    char msg[900];
    snprintf(msg, sizeof msg, "%s", vm_ctx_error(ctx));
    return vm_error(ctx, st, "%s: %s", path, msg);
  }
  if (m->nv > INT32_MAX || m->ne > INT32_MAX)
    return vm_error(ctx, VM_ERR_ARG, "%s: too many vertices or elements for .vmsh", path);
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (!f->name || !*f->name || strlen(f->name) > UINT32_MAX)
      return vm_error(ctx, VM_ERR_ARG, "%s: field %d: name is empty or too long", path, i);
    if (f->ncomp > VMSH_MAX_NCOMP)
      return vm_error(ctx, VM_ERR_ARG, "%s: field '%.80s': %d components exceed the limit %d", path,
                      f->name, f->ncomp, VMSH_MAX_NCOMP);
  }
  for (int i = 0; i < m->nattr; i++) {
    const vm_attr *a = &m->attrs[i];
    if (!a->key || !*a->key || !a->value || strlen(a->key) > UINT32_MAX ||
        strlen(a->value) > UINT32_MAX)
      return vm_error(ctx, VM_ERR_ARG, "%s: attribute %d: key is empty or too long", path, i);
  }
  int d;
  if (vm_mesh_first_duplicate(ctx, m, 0, &d))
    return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", path);
  if (d >= 0)
    return vm_error(ctx, VM_ERR_ARG, "%s: attribute '%.80s' appears twice", path, m->attrs[d].key);
  return VM_OK;
}

typedef struct {
  FILE *fp;
  crc32_state crc;
  uint64_t count;
  size_t n;
  int failed;
  uint8_t buf[1 << 14];
} bin_writer;

static void bw_flush(bin_writer *w) {
  crc_update(&w->crc, w->buf, w->n);
  if (w->n && fwrite(w->buf, 1, w->n, w->fp) != w->n && !w->failed) w->failed = errno ? errno : EIO;
  w->count += w->n;
  w->n = 0;
}

static void bw_byte(bin_writer *w, uint8_t b) {
  if (w->n == sizeof w->buf) bw_flush(w);
  w->buf[w->n++] = b;
}

static void bw_bytes(bin_writer *w, const void *p, size_t n) {
  const uint8_t *s = p;
  for (size_t i = 0; i < n; i++) bw_byte(w, s[i]);
}

static void bw_u16(bin_writer *w, uint16_t v) {
  bw_byte(w, (uint8_t)v);
  bw_byte(w, (uint8_t)(v >> 8));
}

static void bw_u32(bin_writer *w, uint32_t v) {
  for (int i = 0; i < 4; i++) bw_byte(w, (uint8_t)(v >> (8 * i)));
}

static void bw_u64(bin_writer *w, uint64_t v) {
  for (int i = 0; i < 8; i++) bw_byte(w, (uint8_t)(v >> (8 * i)));
}

static void bw_i32(bin_writer *w, int32_t v) {
  uint32_t u;
  memcpy(&u, &v, sizeof u);
  bw_u32(w, u);
}

static void bw_f64(bin_writer *w, double v) {
  uint64_t u;
  memcpy(&u, &v, sizeof u);
  bw_u64(w, u);
}

static void bw_zeros(bin_writer *w, uint64_t n) {
  for (uint64_t i = 0; i < n; i++) bw_byte(w, 0);
}

static void bw_chunk(bin_writer *w, const char *tag, uint64_t len) {
  bw_bytes(w, tag, 4);
  bw_u32(w, VMSH_CRITICAL);
  bw_u64(w, len);
}

static uint64_t field_body_len(const vm_mesh *m, const vm_field *f) {
  uint64_t esz = f->type == VM_FIELD_F64 ? 8 : 4;
  return VMSH_FIELD_HEADER + pad8(strlen(f->name)) +
         (uint64_t)vm_field_count(m, f) * (uint64_t)f->ncomp * esz;
}

static uint64_t attr_body_len(const vm_attr *a) {
  return VMSH_ATTR_HEADER + strlen(a->key) + strlen(a->value);
}

static uint64_t chunk_size(uint64_t body) { return VMSH_CHUNK_HEADER_SIZE + pad8(body); }

int vm_write_vmsh(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  int st = check_writable(ctx, m, path);
  if (st) return st;
  uint64_t nv = (uint64_t)m->nv, ne = (uint64_t)m->ne, nconn = (uint64_t)m->eoff[m->ne];
  uint64_t vert_len = 24 * nv, vflg_len = 5 * nv, elem_len = pad4(ne) + 4 * nconn;
  uint64_t size = VMSH_HEADER_SIZE + chunk_size(VMSH_MESH_BODY) + chunk_size(vert_len) +
                  chunk_size(vflg_len) + chunk_size(elem_len) + VMSH_TRAILER_SIZE;
  for (int i = 0; i < m->nfield; i++) size += chunk_size(field_body_len(m, &m->fields[i]));
  for (int i = 0; i < m->nattr; i++) size += chunk_size(attr_body_len(&m->attrs[i]));

  bin_writer *w = vm_malloc(ctx, sizeof *w);
  if (!w) return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", path);
  vm_outfile *of = NULL;
  if ((st = vm_outfile_open(ctx, path, &of))) {
    vm_free(ctx, w);
    return st;
  }
  w->fp = vm_outfile_fp(of);
  crc_init(&w->crc);
  w->count = 0;
  w->n = 0;
  w->failed = 0;

  bw_bytes(w, vmsh_magic, sizeof vmsh_magic);
  bw_u16(w, VMSH_MAJOR);
  bw_u16(w, VMSH_MINOR);
  bw_u32(w, 0);
  bw_u64(w, size);

  bw_chunk(w, "MESH", VMSH_MESH_BODY);
  bw_u32(w, (uint32_t)m->dim);
  bw_u32(w, 0);
  bw_u64(w, nv);
  bw_u64(w, ne);
  bw_u64(w, nconn);

  bw_chunk(w, "VERT", vert_len);
  for (uint64_t i = 0; i < 3 * nv; i++) bw_f64(w, m->xyz[i]);

  bw_chunk(w, "VFLG", vflg_len);
  for (uint64_t v = 0; v < nv; v++) bw_i32(w, m->vsurf[v]);
  bw_bytes(w, m->vflag, (size_t)nv);
  bw_zeros(w, pad8(vflg_len) - vflg_len);

  bw_chunk(w, "ELEM", elem_len);
  bw_bytes(w, m->etype, (size_t)ne);
  bw_zeros(w, pad4(ne) - ne);
  for (uint64_t i = 0; i < nconn; i++) bw_i32(w, m->conn[i]);
  bw_zeros(w, pad8(elem_len) - elem_len);

  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    uint64_t len = field_body_len(m, f), nlen = strlen(f->name);
    uint64_t nval = (uint64_t)vm_field_count(m, f) * (uint64_t)f->ncomp;
    bw_chunk(w, "FILD", len);
    bw_byte(w, (uint8_t)f->location);
    bw_byte(w, (uint8_t)f->type);
    bw_u16(w, 0);
    bw_u32(w, (uint32_t)f->ncomp);
    bw_u32(w, (uint32_t)nlen);
    bw_u32(w, 0);
    bw_bytes(w, f->name, (size_t)nlen);
    bw_zeros(w, pad8(nlen) - nlen);
    for (uint64_t j = 0; j < nval; j++) {
      if (f->type == VM_FIELD_F64)
        bw_f64(w, ((const double *)f->data)[j]);
      else
        bw_i32(w, ((const int32_t *)f->data)[j]);
    }
    bw_zeros(w, pad8(len) - len);
  }
  for (int i = 0; i < m->nattr; i++) {
    const vm_attr *a = &m->attrs[i];
    uint64_t len = attr_body_len(a), klen = strlen(a->key), vlen = strlen(a->value);
    bw_chunk(w, "ATTR", len);
    bw_u32(w, (uint32_t)klen);
    bw_u32(w, (uint32_t)vlen);
    bw_bytes(w, a->key, (size_t)klen);
    bw_bytes(w, a->value, (size_t)vlen);
    bw_zeros(w, pad8(len) - len);
  }
  bw_flush(w);
  uint32_t crc = crc_final(&w->crc);
  bw_u32(w, crc);
  bw_flush(w);
  int failed = w->failed ? w->failed : w->count != size ? EIO : 0;
  vm_free(ctx, w);
  if (failed) {
    vm_outfile_abort(&of);
    return vm_error(ctx, VM_ERR_IO, "%s: write failed: %s", path, strerror(failed));
  }
  return vm_outfile_commit(&of);
}

/* Quoted, percent-encoded string for the text variant. */
static void put_string(FILE *fp, const char *s) {
  fputc('"', fp);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p <= 0x20 || *p == 0x7F || *p == '"' || *p == '%')
      fprintf(fp, "%%%02X", *p);
    else
      fputc(*p, fp);
  }
  fputc('"', fp);
}

int vm_write_vmsh_text(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  static const char *const type_names[VM_NTYPES] = {"tri",     "quad",  "tet",
                                                    "pyramid", "prism", "hex"};
  int st = check_writable(ctx, m, path);
  if (st) return st;
  vm_outfile *of = NULL;
  if ((st = vm_outfile_open(ctx, path, &of))) return st;
  FILE *fp = vm_outfile_fp(of);
  fprintf(fp, "%s %d %d\ndim %d\nvertices %lld\n", vmsht_magic, VMSH_MAJOR, VMSH_MINOR, m->dim,
          (long long)m->nv);
  for (int64_t v = 0; v < m->nv; v++) {
    const double *p = m->xyz + 3 * v;
    fprintf(fp, "%.17g %.17g %.17g %s %d\n", p[0], p[1], p[2], flag_names[m->vflag[v]],
            (int)m->vsurf[v]);
  }
  fprintf(fp, "elements %lld\n", (long long)m->ne);
  for (int64_t e = 0; e < m->ne; e++) {
    fputs(type_names[m->etype[e]], fp);
    for (int64_t i = m->eoff[e]; i < m->eoff[e + 1]; i++) fprintf(fp, " %d", (int)m->conn[i]);
    fputc('\n', fp);
  }
  fprintf(fp, "fields %d\n", m->nfield);
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    fprintf(fp, "field %s %s %d ", loc_names[f->location], ftype_names[f->type], f->ncomp);
    put_string(fp, f->name);
    fputc('\n', fp);
    int64_t items = vm_field_count(m, f);
    for (int64_t j = 0; j < items; j++) {
      for (int c = 0; c < f->ncomp; c++) {
        int64_t k = j * f->ncomp + c;
        if (c) fputc(' ', fp);
        if (f->type == VM_FIELD_F64)
          fprintf(fp, "%.17g", ((const double *)f->data)[k]);
        else
          fprintf(fp, "%d", (int)((const int32_t *)f->data)[k]);
      }
      fputc('\n', fp);
    }
  }
  fprintf(fp, "attributes %d\n", m->nattr);
  for (int i = 0; i < m->nattr; i++) {
    put_string(fp, m->attrs[i].key);
    fputc(' ', fp);
    put_string(fp, m->attrs[i].value);
    fputc('\n', fp);
  }
  fputs("end\n", fp);
  return vm_outfile_commit(&of);
}
