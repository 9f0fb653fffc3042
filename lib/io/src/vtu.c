/* lib/io/src/vtu.c: VTK XML unstructured grid (.vtu) reader and writer, with
 * its own small XML scanner, base64 coder and zlib inflater. */
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats_private.h"
#include "lex_private.h"
#include "vtk_private.h"

/* Zlib inflate (RFC 1950 / 1951), for vtkZLibDataCompressor blocks. */

typedef struct {
  const uint8_t *in;
  size_t inlen, inpos;
  uint32_t bits;
  int nbits;
  uint8_t *out;
  size_t outlen, outpos;
  int bad; /* ran out of input */
} inflater;

/* Canonical Huffman code: counts of codes per length, symbols by code. */
typedef struct {
  uint16_t count[16];
  uint16_t symbol[288];
} huffman;

static uint32_t inf_bits(inflater *s, int n) {
  while (s->nbits < n) {
    if (s->inpos >= s->inlen) {
      s->bad = 1;
      return 0;
    }
    s->bits |= (uint32_t)s->in[s->inpos++] << s->nbits;
    s->nbits += 8;
  }
  uint32_t v = s->bits & ((1u << n) - 1u);
  s->bits >>= n;
  s->nbits -= n;
  return v;
}

/* Returns 0, or -1 if the lengths over-subscribe the code space. */
static int huff_build(huffman *h, const uint8_t *len, int n) {
  uint16_t offs[16];
  memset(h->count, 0, sizeof h->count);
  for (int i = 0; i < n; i++) h->count[len[i]]++;
  h->count[0] = 0;
  int left = 1;
  for (int l = 1; l < 16; l++) {
    left = 2 * left - h->count[l];
    if (left < 0) return -1;
  }
  offs[1] = 0;
  for (int l = 1; l < 15; l++) offs[l + 1] = (uint16_t)(offs[l] + h->count[l]);
  for (int i = 0; i < n; i++)
    if (len[i]) h->symbol[offs[len[i]]++] = (uint16_t)i;
  return 0;
}

/* Decode one symbol: codes of each length are consecutive integers. */
static int huff_decode(inflater *s, const huffman *h) {
  int code = 0, first = 0, index = 0;
  for (int l = 1; l < 16; l++) {
    code |= (int)inf_bits(s, 1);
    if (s->bad) return -1;
    int cnt = h->count[l];
    if (code - first < cnt) return h->symbol[index + code - first];
    index += cnt;
    first = (first + cnt) << 1;
    code <<= 1;
  }
  return -1;
}

static const uint16_t len_base[29] = {3,  4,  5,  6,   7,   8,   9,   10,  11, 13,
                                      15, 17, 19, 23,  27,  31,  35,  43,  51, 59,
                                      67, 83, 99, 115, 131, 163, 195, 227, 258};
static const uint8_t len_extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                      2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const uint16_t dist_base[30] = {
    1,   2,   3,   4,   5,   7,    9,    13,   17,   25,   33,   49,   65,    97,    129,
    193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
static const uint8_t dist_extra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                       6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

/* One compressed block's literals and matches. */
static int inf_codes(inflater *s, const huffman *lit, const huffman *dist) {
  for (;;) {
    int sym = huff_decode(s, lit);
    if (sym < 0) return -1;
    if (sym < 256) {
      if (s->outpos >= s->outlen) return -1;
      s->out[s->outpos++] = (uint8_t)sym;
    } else if (sym == 256) {
      return 0;
    } else {
      sym -= 257;
      if (sym >= 29) return -1;
      size_t len = len_base[sym] + inf_bits(s, len_extra[sym]);
      int ds = huff_decode(s, dist);
      if (ds < 0 || ds >= 30) return -1;
      size_t d = dist_base[ds] + inf_bits(s, dist_extra[ds]);
      if (s->bad || d > s->outpos || len > s->outlen - s->outpos) return -1;
      for (size_t i = 0; i < len; i++, s->outpos++) s->out[s->outpos] = s->out[s->outpos - d];
    }
  }
}

static int inf_dynamic(inflater *s) {
  static const uint8_t order[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                    11, 4,  12, 3, 13, 2, 14, 1, 15};
  uint8_t len[320];
  huffman lit, dist;
  int nlen = (int)inf_bits(s, 5) + 257, ndist = (int)inf_bits(s, 5) + 1;
  int ncode = (int)inf_bits(s, 4) + 4;
  if (s->bad || nlen > 286 || ndist > 30) return -1;
  memset(len, 0, sizeof len);
  for (int i = 0; i < ncode; i++) len[order[i]] = (uint8_t)inf_bits(s, 3);
  if (s->bad || huff_build(&lit, len, 19)) return -1;
  int i = 0;
  while (i < nlen + ndist) {
    int sym = huff_decode(s, &lit);
    if (sym < 0) return -1;
    if (sym < 16) {
      len[i++] = (uint8_t)sym;
      continue;
    }
    int rep;
    uint8_t v = 0;
    if (sym == 16) {
      if (i == 0) return -1;
      v = len[i - 1];
      rep = 3 + (int)inf_bits(s, 2);
    } else if (sym == 17) {
      rep = 3 + (int)inf_bits(s, 3);
    } else {
      rep = 11 + (int)inf_bits(s, 7);
    }
    if (s->bad || i + rep > nlen + ndist) return -1;
    while (rep--) len[i++] = v;
  }
  if (len[256] == 0) return -1;
  if (huff_build(&lit, len, nlen) || huff_build(&dist, len + nlen, ndist)) return -1;
  return inf_codes(s, &lit, &dist);
}

static int inf_fixed(inflater *s) {
  uint8_t len[288];
  huffman lit, dist;
  for (int i = 0; i < 288; i++) len[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
  huff_build(&lit, len, 288);
  for (int i = 0; i < 30; i++) len[i] = 5;
  huff_build(&dist, len, 30);
  return inf_codes(s, &lit, &dist);
}

static int inf_stored(inflater *s) {
  s->bits = 0;
  s->nbits = 0;
  if (s->inlen - s->inpos < 4) return -1;
  const uint8_t *p = s->in + s->inpos;
  unsigned len = p[0] | (unsigned)p[1] << 8, nlen = p[2] | (unsigned)p[3] << 8;
  s->inpos += 4;
  if ((len ^ 0xffffu) != nlen || s->inlen - s->inpos < len || s->outlen - s->outpos < len)
    return -1;
  memcpy(s->out + s->outpos, s->in + s->inpos, len);
  s->inpos += len;
  s->outpos += len;
  return 0;
}

/* Inflate a zlib stream into exactly outlen bytes; 0 or -1. */
static int zlib_inflate(const uint8_t *in, size_t inlen, uint8_t *out, size_t outlen) {
  if (inlen < 6) return -1;
  unsigned cmf = in[0], flg = in[1];
  if ((cmf & 15) != 8 || (cmf >> 4) > 7 || (cmf * 256 + flg) % 31 || (flg & 32)) return -1;
  inflater s = {in, inlen - 4, 2, 0, 0, out, outlen, 0, 0};
  int last;
  do {
    last = (int)inf_bits(&s, 1);
    int type = (int)inf_bits(&s, 2);
    int st = s.bad       ? -1
             : type == 0 ? inf_stored(&s)
             : type == 1 ? inf_fixed(&s)
             : type == 2 ? inf_dynamic(&s)
                         : -1;
    if (st || s.bad) return -1;
  } while (!last);
  if (s.outpos != outlen) return -1;
  const uint8_t *a = in + inlen - 4;
  uint32_t want = (uint32_t)a[0] << 24 | (uint32_t)a[1] << 16 | (uint32_t)a[2] << 8 | a[3];
  uint32_t s1 = 1, s2 = 0;
  for (size_t i = 0; i < outlen; i++) {
    s1 = (s1 + out[i]) % 65521u;
    s2 = (s2 + s1) % 65521u;
  }
  return (s2 << 16 | s1) == want ? 0 : -1;
}

/* Base64. */

static int b64_val(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

/* Decode quad by quad (so separately padded pieces decode as one stream)
 * until `need` bytes are out or the text ends. out holds need + 2 bytes.
 * Returns 0, -1 with *bad at an offending character, or -2 if the text
 * ends inside a group. */
static int b64_decode(const char *s, const char *end, uint8_t *out, size_t need, size_t *got,
                      const char **bad) {
  size_t n = 0;
  int q[4], k = 0, pad = 0;
  const char *p = s;
  while (n < need && p < end) {
    unsigned char c = (unsigned char)*p;
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      p++;
      continue;
    }
    if (c == '=') {
      if (k < 2) break;
      pad++;
      q[k++] = 0;
    } else {
      int v = b64_val(c);
      if (v < 0 || pad) break;
      q[k++] = v;
    }
    p++;
    if (k == 4) {
      uint32_t w =
          (uint32_t)q[0] << 18 | (uint32_t)q[1] << 12 | (uint32_t)q[2] << 6 | (uint32_t)q[3];
      out[n++] = (uint8_t)(w >> 16);
      if (pad < 2) out[n++] = (uint8_t)(w >> 8);
      if (pad < 1) out[n++] = (uint8_t)w;
      k = 0;
      pad = 0;
    }
  }
  if (n < need && p < end) {
    *bad = p;
    return -1;
  }
  if (k == 1 || pad) return -2;
  if (k >= 2) {
    uint32_t w = (uint32_t)q[0] << 18 | (uint32_t)q[1] << 12 | (k == 3 ? (uint32_t)q[2] << 6 : 0);
    out[n++] = (uint8_t)(w >> 16);
    if (k == 3) out[n++] = (uint8_t)(w >> 8);
  }
  *got = n;
  return 0;
}

/* XML scanning. */

enum { K_FILE, K_GRID, K_PIECE, K_POINTS, K_CELLS, K_PDATA, K_CDATA, K_ARRAY, K_OTHER };

typedef struct {
  int parent;        /* K_POINTS, K_CELLS, K_PDATA, K_CDATA */
  const char *attrs; /* attribute text of the start tag */
  size_t alen;
  const char *body, *bend; /* inline content, NULL if self-closing */
  const char *at;          /* the '<' of the tag */
} darr;

typedef struct {
  vm_ctx *ctx;
  const char *name;
  const char *base, *end;
  /* VTKFile */
  int big;   /* byte_order BigEndian */
  int hsize; /* header_type size: 4 or 8 */
  int zlib;  /* vtkZLibDataCompressor */
  int npieces;
  const char *piece_attrs;
  size_t piece_alen;
  const char *piece_at, *cells_at;
  const char *appended; /* first byte after '_', NULL if none */
  int app_b64;
  darr *arr;
  int narr, carr;
  uint64_t inflated; /* bytes the compressed arrays have inflated to so far */
  int nstored;       /* DataArrays stored as fields so far (at most VM_IO_MAX_ARRAYS) */
} vturd;

/* What compressed arrays may inflate to in all: this many times the file's
 * size, at least 256 MiB (VTK's own files compress 2 to 10 times; a 3.6 MB
 * file claiming 150 M points took 7.8 GB). VM_MAX_INFLATE=R in the
 * environment sets the ratio. */
static uint64_t inflate_limit(const vturd *r) {
  double ratio = 64;
  const char *e = getenv("VM_MAX_INFLATE");
  if (e && *e) {
    char *end;
    double v = strtod(e, &end);
    if (!*end && v > 0 && v < 1e12) ratio = v;
  }
  double lim = ratio * (double)(r->end - r->base);
  if (lim < 256.0 * 1048576) lim = 256.0 * 1048576;
  return lim > 1.8e19 ? UINT64_MAX : (uint64_t)lim;
}

static int64_t line_at(const vturd *r, const char *p) {
  int64_t line = 1;
  for (const char *q = r->base; q < p && (q = memchr(q, '\n', (size_t)(p - q))) != NULL; q++)
    line++;
  return line;
}

static int vfail(const vturd *r, const char *at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int vfail(const vturd *r, const char *at, const char *fmt, ...) {
  char msg[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vm_error(r->ctx, VM_ERR_FORMAT, "%s: line %lld: %s", r->name, (long long)line_at(r, at),
                  msg);
}

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

static const char *find_str(const char *p, const char *end, const char *s) {
  size_t n = strlen(s);
  for (; (size_t)(end - p) >= n; p++)
    if (*p == *s && !memcmp(p, s, n)) return p;
  return NULL;
}

/* Look up attribute `key` in a start tag's attribute text (already checked
 * to be well formed). Returns 1 and the raw value if present. */
static int attr_raw(const char *a, size_t alen, const char *key, const char **v, size_t *vn) {
  if (!alen) /* a tag without attributes may pass a = NULL: no arithmetic on it */
    return 0;
  const char *p = a, *end = a + alen;
  size_t kn = strlen(key);
  while (p < end) {
    while (p < end && is_space(*p)) p++;
    const char *k = p;
    while (p < end && *p != '=' && !is_space(*p)) p++;
    size_t klen = (size_t)(p - k);
    while (p < end && *p != '"' && *p != '\'') p++;
    if (p >= end) return 0;
    char qc = *p++;
    const char *vs = p;
    while (p < end && *p != qc) p++;
    if (klen == kn && !memcmp(k, key, kn)) {
      *v = vs;
      *vn = (size_t)(p - vs);
      return 1;
    }
    p++;
  }
  return 0;
}

static int attr_is(const char *a, size_t alen, const char *key, const char *val) {
  const char *v;
  size_t n;
  return attr_raw(a, alen, key, &v, &n) && n == strlen(val) && !memcmp(v, val, n);
}

/* Attribute value with the XML entities replaced, in buf (truncated to cap). */
static int attr_text(const char *a, size_t alen, const char *key, char *buf, size_t cap) {
  const char *v;
  size_t n, k = 0;
  buf[0] = 0;
  if (!attr_raw(a, alen, key, &v, &n)) return 0;
  for (size_t i = 0; i < n && k + 5 < cap; i++) {
    static const struct {
      const char *ent;
      char c;
    } ents[] = {{"&lt;", '<'}, {"&gt;", '>'}, {"&amp;", '&'}, {"&quot;", '"'}, {"&apos;", '\''}};
    int done = 0;
    for (size_t e = 0; e < 5 && v[i] == '&'; e++) {
      size_t el = strlen(ents[e].ent);
      if (n - i >= el && !memcmp(v + i, ents[e].ent, el)) {
        buf[k++] = ents[e].c;
        i += el - 1;
        done = 1;
        break;
      }
    }
    if (!done && v[i] == '&' && i + 2 < n && v[i + 1] == '#') {
      size_t j = i + 2;
      int hex = j < n && v[j] == 'x';
      unsigned long cp = 0;
      j += (size_t)hex;
      while (j < n && j - i < 12 && v[j] != ';') {
        int d = v[j] >= '0' && v[j] <= '9'          ? v[j] - '0'
                : hex && v[j] >= 'a' && v[j] <= 'f' ? v[j] - 'a' + 10
                : hex && v[j] >= 'A' && v[j] <= 'F' ? v[j] - 'A' + 10
                                                    : -1;
        if (d < 0) break;
        cp = cp * (hex ? 16u : 10u) + (unsigned long)d;
        j++;
      }
      if (j < n && v[j] == ';' && cp > 0 && cp < 0x110000) {
        if (cp < 0x80) {
          buf[k++] = (char)cp;
        } else if (cp < 0x800) {
          buf[k++] = (char)(0xc0 | (cp >> 6));
          buf[k++] = (char)(0x80 | (cp & 63));
        } else if (cp < 0x10000) {
          buf[k++] = (char)(0xe0 | (cp >> 12));
          buf[k++] = (char)(0x80 | ((cp >> 6) & 63));
          buf[k++] = (char)(0x80 | (cp & 63));
        } else {
          buf[k++] = (char)(0xf0 | (cp >> 18));
          buf[k++] = (char)(0x80 | ((cp >> 12) & 63));
          buf[k++] = (char)(0x80 | ((cp >> 6) & 63));
          buf[k++] = (char)(0x80 | (cp & 63));
        }
        i = j;
        done = 1;
      }
    }
    if (!done) buf[k++] = v[i];
  }
  buf[k] = 0;
  return 1;
}

/* A non-negative integer attribute; -1 if absent, -2 if malformed. */
static int64_t attr_int(const char *a, size_t alen, const char *key) {
  char buf[32];
  if (!attr_text(a, alen, key, buf, sizeof buf)) return -1;
  char *e;
  long long v = strtoll(buf, &e, 10);
  if (e == buf || *e || v < 0) return -2;
  return v;
}

static int push_array(vturd *r, int parent, const char *at, const char *a, size_t alen,
                      const char *body, const char *bend) {
  if (r->narr == r->carr) {
    int c = r->carr ? 2 * r->carr : 16;
    darr *n = vm_realloc(r->ctx, r->arr, (size_t)c * sizeof *n);
    if (!n) return VM_ERR_NOMEM;
    r->arr = n;
    r->carr = c;
  }
  darr *d = &r->arr[r->narr++];
  d->parent = parent;
  d->at = at;
  d->attrs = a;
  d->alen = alen;
  d->body = body;
  d->bend = bend;
  return VM_OK;
}

static int vtkfile_attrs(vturd *r, const char *at, const char *a, size_t alen) {
  char buf[64];
  attr_text(a, alen, "type", buf, sizeof buf);
  if (strcmp(buf, "UnstructuredGrid"))
    return vfail(r, at, "VTKFile type '%s' is not supported (only UnstructuredGrid)", buf);
  r->big = 0;
  if (attr_text(a, alen, "byte_order", buf, sizeof buf)) {
    r->big = !strcmp(buf, "BigEndian");
    if (!r->big && strcmp(buf, "LittleEndian"))
      return vfail(r, at, "byte_order '%s' is not supported", buf);
  }
  r->hsize = 4;
  if (attr_text(a, alen, "header_type", buf, sizeof buf)) {
    if (!strcmp(buf, "UInt64"))
      r->hsize = 8;
    else if (strcmp(buf, "UInt32"))
      return vfail(r, at, "header_type '%s' is not supported (UInt32 or UInt64)", buf);
  }
  if (attr_text(a, alen, "compressor", buf, sizeof buf) && buf[0]) {
    if (strcmp(buf, "vtkZLibDataCompressor"))
      return vfail(r, at, "compressed VTU not supported (compressor '%s'; zlib is)", buf);
    r->zlib = 1;
  }
  return VM_OK;
}

/* One pass over the markup up to AppendedData: checks nesting, records the
 * Piece and every DataArray under Points, Cells, PointData and CellData. */
static int xml_scan(vturd *r) {
  enum { MAXDEPTH = 64 };
  int kind[MAXDEPTH];
  const char *tname[MAXDEPTH];
  size_t tlen[MAXDEPTH];
  int depth = 0, seen_root = 0, cur_arr = -1;
  const char *text_from = NULL;
  const char *p = r->base, *end = r->end;
  for (;;) {
    const char *lt = memchr(p, '<', (size_t)(end - p));
    if (!lt) break;
    p = lt;
    const char *close = NULL;
    if (end - p >= 4 && !memcmp(p, "<!--", 4))
      close = find_str(p + 4, end, "-->");
    else if (end - p >= 2 && !memcmp(p, "<?", 2))
      close = find_str(p + 2, end, "?>");
    else if (end - p >= 9 && !memcmp(p, "<![CDATA[", 9))
      close = find_str(p + 9, end, "]]>");
    else if (end - p >= 2 && p[1] == '!')
      close = memchr(p, '>', (size_t)(end - p));
    else
      goto tag;
    if (!close) return vfail(r, p, "unterminated comment or declaration");
    p = close + 1;
    continue;
  tag:;
    int is_end = end - p >= 2 && p[1] == '/';
    const char *n0 = p + 1 + is_end, *q = n0;
    while (q < end && !is_space(*q) && *q != '>' && *q != '/') q++;
    size_t nlen = (size_t)(q - n0);
    if (nlen == 0) return vfail(r, p, "malformed tag");
    /* attributes: name="value" pairs, up to '>' or '/>' */
    const char *a0 = q;
    int selfclose = 0;
    for (;;) {
      while (q < end && is_space(*q)) q++;
      if (q >= end) return vfail(r, p, "unterminated tag <%.*s", (int)(nlen > 40 ? 40 : nlen), n0);
      if (*q == '>') break;
      if (*q == '/' && !is_end) {
        if (q + 1 >= end || q[1] != '>') return vfail(r, p, "malformed tag");
        selfclose = 1;
        break;
      }
      if (is_end) return vfail(r, p, "malformed end tag");
      const char *k = q;
      while (q < end && *q != '=' && !is_space(*q) && *q != '>' && *q != '/') q++;
      if (q == k) return vfail(r, p, "malformed attribute");
      while (q < end && is_space(*q)) q++;
      if (q >= end || *q != '=') return vfail(r, p, "attribute without a value");
      q++;
      while (q < end && is_space(*q)) q++;
      if (q >= end || (*q != '"' && *q != '\'')) return vfail(r, p, "attribute value not quoted");
      const char *e = memchr(q + 1, *q, (size_t)(end - q - 1));
      if (!e) return vfail(r, p, "unterminated attribute value");
      q = e + 1;
    }
    size_t alen = (size_t)(q - a0);
    const char *after = q + 1 + selfclose;
    if (is_end) {
      if (depth == 0) return vfail(r, p, "unexpected </%.*s>", (int)(nlen > 40 ? 40 : nlen), n0);
      depth--;
      if (tlen[depth] != nlen || memcmp(tname[depth], n0, nlen))
        return vfail(r, p, "</%.*s> closes <%.*s>", (int)(nlen > 40 ? 40 : nlen), n0,
                     (int)(tlen[depth] > 40 ? 40 : tlen[depth]), tname[depth]);
      /* a DataArray's data is its text after any child elements: VTK
       * writes <InformationKey> children before inline data */
      if (kind[depth] == K_ARRAY) {
        r->arr[cur_arr].body = text_from;
        r->arr[cur_arr].bend = p;
      } else if (depth && kind[depth - 1] == K_ARRAY) {
        text_from = after;
      }
      p = after;
      if (depth == 0) break;
      continue;
    }
#define TAG_IS(s) (nlen == strlen(s) && !memcmp(n0, s, nlen))
    int parent = depth ? kind[depth - 1] : -1, k = K_OTHER;
    if (depth == 0) {
      if (seen_root) return vfail(r, p, "content after </VTKFile>");
      if (!TAG_IS("VTKFile")) return vfail(r, p, "not a VTK XML file (no <VTKFile>)");
      int st = vtkfile_attrs(r, p, a0, alen);
      if (st) return st;
      seen_root = 1;
      k = K_FILE;
    } else if (parent == K_FILE && TAG_IS("UnstructuredGrid")) {
      k = K_GRID;
    } else if (parent == K_FILE && TAG_IS("AppendedData")) {
      char enc[16];
      attr_text(a0, alen, "encoding", enc, sizeof enc);
      if (strcmp(enc, "raw") && strcmp(enc, "base64"))
        return vfail(r, p, "AppendedData encoding '%s' is not supported (raw or base64)", enc);
      r->app_b64 = !strcmp(enc, "base64");
      const char *u = after;
      while (u < end && is_space(*u)) u++;
      if (selfclose || u >= end || *u != '_')
        return vfail(r, p, "AppendedData does not start with '_'");
      r->appended = u + 1;
      /* the data are not scanned, but a truncated file must not pass */
      const char *t = end;
      while (t > r->appended && is_space(t[-1])) t--;
      static const char tail[] = "</VTKFile>";
      size_t tl = sizeof tail - 1;
      if ((size_t)(t - r->appended) < tl || memcmp(t - tl, tail, tl))
        return vfail(r, end, "file truncated: no </VTKFile> after the appended data");
      return VM_OK;
    } else if (parent == K_GRID && TAG_IS("Piece")) {
      if (++r->npieces > 1) return vfail(r, p, "more than one Piece is not supported");
      r->piece_attrs = a0;
      r->piece_alen = alen;
      r->piece_at = p;
      k = K_PIECE;
    } else if (parent == K_PIECE && TAG_IS("Points")) {
      k = K_POINTS;
    } else if (parent == K_PIECE && TAG_IS("Cells")) {
      r->cells_at = p;
      k = K_CELLS;
    } else if (parent == K_PIECE && TAG_IS("PointData")) {
      k = K_PDATA;
    } else if (parent == K_PIECE && TAG_IS("CellData")) {
      k = K_CDATA;
    } else if ((parent == K_POINTS || parent == K_CELLS || parent == K_PDATA ||
                parent == K_CDATA) &&
               TAG_IS("DataArray")) {
      k = K_ARRAY;
      int st = push_array(r, parent, p, a0, alen, NULL, NULL);
      if (st) return st;
      cur_arr = r->narr - 1;
      text_from = after;
    }
#undef TAG_IS
    if (!selfclose) {
      if (depth == MAXDEPTH) return vfail(r, p, "XML nested too deeply");
      kind[depth] = k;
      tname[depth] = n0;
      tlen[depth] = nlen;
      depth++;
    }
    p = after;
  }
  if (!seen_root)
    return vm_error(r->ctx, VM_ERR_FORMAT, "%s: not a VTK XML file (no <VTKFile>)", r->name);
  if (depth)
    return vfail(r, end, "unexpected end of file inside <%.*s>",
                 (int)(tlen[depth - 1] > 40 ? 40 : tlen[depth - 1]), tname[depth - 1]);
  if (!r->npieces)
    return vm_error(r->ctx, VM_ERR_FORMAT, "%s: no <Piece> in the UnstructuredGrid", r->name);
  return VM_OK;
}

/* DataArray decoding. */

typedef struct {
  const char *name;
  int size;
  char kind;
} xtype;

static const xtype xtypes[] = {{"Int8", 1, 'i'},   {"UInt8", 1, 'u'},  {"Int16", 2, 'i'},
                               {"UInt16", 2, 'u'}, {"Int32", 4, 'i'},  {"UInt32", 4, 'u'},
                               {"Int64", 8, 'i'},  {"UInt64", 8, 'u'}, {"Float32", 4, 'f'},
                               {"Float64", 8, 'f'}};

static const xtype *array_type(const darr *a) {
  char buf[16];
  attr_text(a->attrs, a->alen, "type", buf, sizeof buf);
  for (size_t i = 0; i < sizeof xtypes / sizeof xtypes[0]; i++)
    if (!strcmp(buf, xtypes[i].name)) return &xtypes[i];
  return NULL;
}

static uint64_t load_u(const uint8_t *p, int size, int big) {
  uint64_t v = 0;
  for (int i = 0; i < size; i++) v |= (uint64_t)p[big ? i : size - 1 - i] << (8 * (size - 1 - i));
  return v;
}

/* A DataArray being read: its label for messages and where it starts. */
typedef struct {
  vturd *r;
  const darr *a;
  char label[96];
} actx;

static int afail(const actx *c, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static int afail(const actx *c, const char *fmt, ...) {
  char msg[600];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vfail(c->r, c->a->at, "DataArray '%s': %s", c->label, msg);
}

static uint64_t hdr_word(const actx *c, const uint8_t *p, int i) {
  return load_u(p + (size_t)i * (size_t)c->r->hsize, c->r->hsize, c->r->big);
}

/* Length of the header plus data of a binary block starting at src (len
 * bytes known so far), given at least the header words it needs.
 * Returns 0 with *need (bytes needed in all) or an error. */
static int block_need(const actx *c, const uint8_t *src, size_t len, size_t *need) {
  size_t hs = (size_t)c->r->hsize;
  if (!c->r->zlib) {
    if (len < hs) {
      *need = hs;
      return VM_OK;
    }
    uint64_t n = hdr_word(c, src, 0);
    if (n > SIZE_MAX - hs) return afail(c, "block size %" PRIu64 " is impossible", n);
    *need = hs + (size_t)n;
    return VM_OK;
  }
  if (len < 3 * hs) {
    *need = 3 * hs;
    return VM_OK;
  }
  uint64_t nb = hdr_word(c, src, 0);
  if (nb > SIZE_MAX / hs - 3)
    return afail(c, "compressed block count %" PRIu64 " is impossible", nb);
  size_t h = (3 + (size_t)nb) * hs;
  if (len < h) {
    *need = h;
    return VM_OK;
  }
  size_t total = h;
  for (uint64_t b = 0; b < nb; b++) {
    uint64_t cs = hdr_word(c, src, 3 + (int)b);
    if (cs > SIZE_MAX - total)
      return afail(c, "compressed block size %" PRIu64 " is impossible", cs);
    total += (size_t)cs;
  }
  *need = total;
  return VM_OK;
}

/* Turn a complete block (header and data, len bytes) into the array's raw
 * bytes: *data points into src or into *owned (allocated, inflated). */
static int block_payload(const actx *c, const uint8_t *src, size_t len, const uint8_t **data,
                         size_t *nbytes, uint8_t **owned) {
  vm_ctx *ctx = c->r->ctx;
  size_t need, hs = (size_t)c->r->hsize;
  *owned = NULL;
  int st = block_need(c, src, len, &need);
  if (st) return st;
  if (need > len) return afail(c, "data truncated: needs %zu bytes, has %zu", need, len);
  if (!c->r->zlib) {
    *data = src + hs;
    *nbytes = need - hs;
    return VM_OK;
  }
  uint64_t nb = hdr_word(c, src, 0), bs = hdr_word(c, src, 1), last = hdr_word(c, src, 2);
  if (nb == 0) {
    *data = src;
    *nbytes = 0;
    return VM_OK;
  }
  if (last == 0) last = bs;
  if (bs == 0 || last > bs) return afail(c, "bad compression header");
  /* deflate cannot expand data more than about 1032 times */
  size_t h = (3 + (size_t)nb) * hs;
  uint64_t limit = 1032 * ((uint64_t)(len - h) + nb), full = 0;
  if (nb > 1 && bs > limit / (nb - 1)) limit = 0;
  if (nb > 1 && limit) full = (nb - 1) * bs;
  if (!limit || last > limit - full || limit > SIZE_MAX)
    return afail(c, "compression header claims more data than %zu bytes can hold", len - h);
  uint64_t total = full + last, lim = inflate_limit(c->r);
  if (total > lim || c->r->inflated + total > lim)
    return afail(c,
                 "the compressed arrays would inflate to more than %" PRIu64
                 " bytes (%s times the file's %zu bytes, at least 256 MiB): refused "
                 "(VM_MAX_INFLATE=R in the environment sets the ratio)",
                 lim, getenv("VM_MAX_INFLATE") ? getenv("VM_MAX_INFLATE") : "64",
                 (size_t)(c->r->end - c->r->base));
  c->r->inflated += total;
  uint8_t *out = vm_malloc(ctx, total ? (size_t)total : 1);
  if (!out) return VM_ERR_NOMEM;
  size_t in = h, o = 0;
  for (uint64_t b = 0; b < nb; b++) {
    size_t cs = (size_t)hdr_word(c, src, 3 + (int)b);
    size_t us = (size_t)(b + 1 == nb ? last : bs);
    if (zlib_inflate(src + in, cs, out + o, us)) {
      vm_free(ctx, out);
      return afail(c, "corrupt zlib data in block %" PRIu64, b);
    }
    in += cs;
    o += us;
  }
  *owned = out;
  *data = out;
  *nbytes = (size_t)total;
  return VM_OK;
}

/* Decode base64 text s..end holding one block; *buf is allocated. The
 * header is decoded first to learn how much follows. */
static int b64_block(const actx *c, const char *s, const char *end, uint8_t **buf, size_t *len) {
  vm_ctx *ctx = c->r->ctx;
  uint64_t chars = (uint64_t)(end - s);
  size_t need = (size_t)c->r->hsize, got = 0;
  uint8_t *b = NULL;
  const char *bad;
  *buf = NULL;
  for (;;) {
    if (need > chars / 4 * 3 + 3) {
      vm_free(ctx, b);
      return afail(c, "needs %zu bytes but only %" PRIu64 " base64 characters follow", need, chars);
    }
    vm_free(ctx, b);
    b = vm_malloc(ctx, need + 3);
    if (!b) return VM_ERR_NOMEM;
    int bst = b64_decode(s, end, b, need, &got, &bad);
    if (bst) {
      vm_free(ctx, b);
      if (bst == -2) return afail(c, "bad base64: the text ends inside a group of 4 characters");
      return afail(c, "bad base64 character '%c' at line %lld",
                   (*bad >= 32 && *bad < 127) ? *bad : '?', (long long)line_at(c->r, bad));
    }
    size_t more;
    int st = got < need ? afail(c, "base64 data truncated") : block_need(c, b, got, &more);
    if (st) {
      vm_free(ctx, b);
      return st;
    }
    if (more <= got) break;
    need = more;
  }
  *buf = b;
  *len = got;
  return VM_OK;
}

/* Read exactly `count` values of the array into a new array *alloc of
 * int64 (want_int, each in [lo, hi]) or double, after checking that the
 * file holds them. */
static int array_values(const actx *c, int64_t count, int want_int, int64_t lo, int64_t hi,
                        void **alloc) {
  vturd *r = c->r;
  const darr *a = c->a;
  vm_ctx *ctx = r->ctx;
  *alloc = NULL;
  const xtype *t = array_type(a);
  char fmt[16];
  if (!t) {
    attr_text(a->attrs, a->alen, "type", fmt, sizeof fmt);
    return afail(c, "type '%s' is not supported", fmt);
  }
  if (want_int && t->kind == 'f') return afail(c, "needs an integer type, has %s", t->name);
  attr_text(a->attrs, a->alen, "format", fmt, sizeof fmt);
  int ascii = !strcmp(fmt, "ascii"), app = !strcmp(fmt, "appended");
  if (!ascii && !app && strcmp(fmt, "binary"))
    return afail(c, "format '%s' is not supported (ascii, binary or appended)", fmt);
  /* <DataArray .../> without content holds no values */
  const char *body = a->body ? a->body : "", *bend = a->body ? a->bend : body;
  size_t outsz = want_int ? sizeof(int64_t) : sizeof(double);
  if (ascii) {
    size_t blen = (size_t)(bend - body);
    if ((uint64_t)count > (blen + 1) / 2)
      return afail(c, "%lld values cannot fit in %zu characters", (long long)count, blen);
    void *out = vm_alloc_array(ctx, count ? (size_t)count : 1, outsz);
    if (!out) return VM_ERR_NOMEM;
    vm_lex lx;
    vm_lex_init(&lx, ctx, r->name, body, blen);
    lx.line = a->body ? line_at(r, a->body) : line_at(r, a->at);
    int st = VM_OK;
    for (int64_t i = 0; !st && i < count; i++) {
      if (want_int) {
        int64_t v;
        st = vm_lex_int(&lx, &v, c->label);
        if (!st && (v < lo || v > hi))
          st = vm_lex_fail(&lx, "DataArray '%s': value %lld out of range [%lld, %lld]", c->label,
                           (long long)v, (long long)lo, (long long)hi);
        if (!st) ((int64_t *)out)[i] = v;
      } else {
        st = vm_lex_double(&lx, &((double *)out)[i], c->label);
      }
    }
    if (!st && !vm_lex_eof(&lx))
      st = vm_lex_fail(&lx, "DataArray '%s': more than the %lld values expected", c->label,
                       (long long)count);
    if (st) {
      vm_free(ctx, out);
      return st;
    }
    *alloc = out;
    return VM_OK;
  }
  /* binary: one block inline (base64) or in the appended section */
  const uint8_t *data;
  size_t nbytes;
  uint8_t *dec = NULL, *owned = NULL;
  int st;
  if (!app) {
    size_t len;
    if ((st = b64_block(c, body, bend, &dec, &len))) return st;
    st = block_payload(c, dec, len, &data, &nbytes, &owned);
  } else {
    int64_t off = attr_int(a->attrs, a->alen, "offset");
    if (!r->appended) return afail(c, "format 'appended' but no AppendedData");
    if (off < 0 || (uint64_t)off > (uint64_t)(r->end - r->appended))
      return afail(c, "bad appended data offset");
    const char *src = r->appended + off;
    if (r->app_b64) {
      size_t len;
      if ((st = b64_block(c, src, r->end, &dec, &len))) return st;
      st = block_payload(c, dec, len, &data, &nbytes, &owned);
    } else {
      st = block_payload(c, (const uint8_t *)src, (size_t)(r->end - src), &data, &nbytes, &owned);
    }
  }
  if (!st && ((uint64_t)count > nbytes / (uint64_t)t->size ||
              (uint64_t)count * (uint64_t)t->size != nbytes))
    st = afail(c, "has %zu bytes of data, expected %lld values of %d bytes", nbytes,
               (long long)count, t->size);
  void *out = NULL;
  if (!st) {
    out = vm_alloc_array(ctx, count ? (size_t)count : 1, outsz);
    if (!out) st = VM_ERR_NOMEM;
  }
  for (int64_t i = 0; !st && i < count; i++) {
    uint64_t u = load_u(data + (size_t)i * (size_t)t->size, t->size, r->big);
    int64_t v = 0;
    double x;
    if (t->kind == 'f') {
      if (t->size == 4) {
        uint32_t u32 = (uint32_t)u;
        float f;
        memcpy(&f, &u32, sizeof f);
        x = f;
      } else {
        memcpy(&x, &u, sizeof x);
      }
    } else {
      if (t->kind == 'u' && u > INT64_MAX) {
        st = afail(c, "value %lld too large", (long long)i);
        break;
      }
      if (t->kind == 'u' || t->size == 8) {
        memcpy(&v, &u, sizeof v);
      } else {
        v = (int64_t)u;
        if (u >> (8 * t->size - 1)) v -= (int64_t)1 << (8 * t->size);
      }
      x = (double)v;
      if (want_int && (v < lo || v > hi)) {
        st = afail(c, "value %lld at index %lld out of range [%lld, %lld]", (long long)v,
                   (long long)i, (long long)lo, (long long)hi);
        break;
      }
    }
    if (want_int)
      ((int64_t *)out)[i] = v;
    else
      ((double *)out)[i] = x;
  }
  vm_free(ctx, dec);
  vm_free(ctx, owned);
  if (st) {
    vm_free(ctx, out);
    return st;
  }
  *alloc = out;
  return VM_OK;
}

static void actx_init(actx *c, vturd *r, const darr *a, const char *fallback) {
  c->r = r;
  c->a = a;
  if (!attr_text(a->attrs, a->alen, "Name", c->label, sizeof c->label) || !c->label[0])
    snprintf(c->label, sizeof c->label, "%s", fallback);
}

static const darr *find_cells_array(const vturd *r, const char *aname) {
  for (int i = 0; i < r->narr; i++)
    if (r->arr[i].parent == K_CELLS && attr_is(r->arr[i].attrs, r->arr[i].alen, "Name", aname))
      return &r->arr[i];
  return NULL;
}

static int read_points(vturd *r, vm_mesh *m, int64_t np) {
  const darr *a = NULL;
  for (int i = 0; i < r->narr && !a; i++)
    if (r->arr[i].parent == K_POINTS) a = &r->arr[i];
  if (!a) {
    if (np) return vfail(r, r->piece_at, "no Points DataArray");
    return vm_mesh_set_vertices(m, 0);
  }
  actx c;
  actx_init(&c, r, a, "Points");
  int64_t nc = attr_int(a->attrs, a->alen, "NumberOfComponents");
  if (nc != 3) return afail(&c, "points need NumberOfComponents=\"3\"");
  void *v;
  int st = array_values(&c, 3 * np, 0, 0, 0, &v);
  if (st) return st;
  double *x = v;
  for (int64_t i = 0; i < 3 * np; i++)
    if (!isfinite(x[i])) {
      vm_free(r->ctx, v);
      return afail(&c, "point %lld is not finite", (long long)(i / 3));
    }
  st = vm_mesh_set_vertices(m, np);
  if (!st) memcpy(m->xyz, x, (size_t)np * 3 * sizeof *x);
  vm_free(r->ctx, v);
  return st;
}

static int read_cells(vturd *r, vm_mesh *m, int64_t nc, int64_t **map) {
  const darr *ac = find_cells_array(r, "connectivity"), *ao = find_cells_array(r, "offsets"),
             *at = find_cells_array(r, "types");
  vm_ctx *ctx = r->ctx;
  if (nc && (!ac || !ao || !at))
    return vfail(r, r->cells_at ? r->cells_at : r->piece_at,
                 "Cells needs connectivity, offsets and types DataArrays");
  int64_t *off = NULL;
  void *vo = NULL, *vt = NULL, *vc = NULL;
  int32_t *types = NULL;
  int st = VM_OK;
  actx c;
  /* the arrays are read (and their sizes checked) before anything sized by
   * NumberOfCells is allocated */
  if (nc) {
    actx_init(&c, r, ao, "offsets");
    st = array_values(&c, nc, 1, 0, INT64_MAX, &vo);
  }
  if (!st) {
    off = vm_alloc_array(ctx, (size_t)nc + 1, sizeof *off);
    if (!off) st = VM_ERR_NOMEM;
  }
  for (int64_t i = 0; !st && i <= nc; i++) {
    off[i] = i ? ((const int64_t *)vo)[i - 1] : 0;
    if (i && off[i] < off[i - 1]) st = afail(&c, "offsets decrease at cell %lld", (long long)i - 1);
  }
  if (!st && nc) {
    actx_init(&c, r, at, "types");
    st = array_values(&c, nc, 1, 0, 255, &vt);
  }
  if (!st) {
    types = vm_alloc_array(ctx, nc ? (size_t)nc : 1, sizeof *types);
    if (!types) st = VM_ERR_NOMEM;
  }
  for (int64_t i = 0; !st && i < nc; i++) types[i] = (int32_t)((const int64_t *)vt)[i];
  if (!st && nc) {
    actx_init(&c, r, ac, "connectivity");
    st = array_values(&c, off[nc], 1, INT64_MIN, INT64_MAX, &vc);
  }
  if (!st) {
    char where[64];
    snprintf(where, sizeof where, "line %lld",
             (long long)line_at(r, r->cells_at ? r->cells_at : r->piece_at));
    vm_vtk_cells cl = {nc, off, vc, types};
    st = vm_vtk_build_elements(ctx, m, r->name, where, &cl, map);
  }
  vm_free(ctx, off);
  vm_free(ctx, types);
  vm_free(ctx, vo);
  vm_free(ctx, vt);
  vm_free(ctx, vc);
  return st;
}

/* PointData / CellData arrays become fields; cell rows of skipped cells go. */
static int read_data(vturd *r, vm_mesh *m, int parent, int64_t n, const int64_t *map) {
  vm_ctx *ctx = r->ctx;
  int loc = parent == K_PDATA ? VM_FIELD_VERTEX : VM_FIELD_ELEMENT;
  for (int i = 0; i < r->narr; i++) {
    const darr *a = &r->arr[i];
    if (a->parent != parent) continue;
    actx c;
    actx_init(&c, r, a, "");
    const xtype *t = array_type(a);
    if (!c.label[0] || !t) {
      char ty[16];
      attr_text(a->attrs, a->alen, "type", ty, sizeof ty);
      vm_log(ctx, VM_LOG_WARN, "%s: line %lld: skipped DataArray '%s' of type '%s'%s", r->name,
             (long long)line_at(r, a->at), c.label, ty, c.label[0] ? "" : " (no Name)");
      continue;
    }
    int64_t ncomp = attr_int(a->attrs, a->alen, "NumberOfComponents");
    if (ncomp == -1) ncomp = 1;
    if (ncomp < 1 || ncomp > (1 << 20)) return afail(&c, "bad NumberOfComponents");
    if (n > INT64_MAX / ncomp) return afail(&c, "too many values");
    if (r->nstored == VM_IO_MAX_ARRAYS)
      return afail(&c, "more than %d data arrays (the reader's ceiling)", VM_IO_MAX_ARRAYS);
    r->nstored++;
    int isint = t->kind != 'f';
    void *v;
    int st = array_values(&c, n * ncomp, isint, INT32_MIN, INT32_MAX, &v);
    if (st) return st;
    vm_field *f;
    st = vm_mesh_add_field(m, c.label, loc, isint ? VM_FIELD_I32 : VM_FIELD_F64, (int)ncomp, &f);
    if (!st)
      for (int64_t k = 0; k < n; k++) {
        int64_t row = map ? map[k] : k;
        if (row < 0) continue;
        for (int64_t j = 0; j < ncomp; j++) {
          if (isint)
            ((int32_t *)f->data)[row * ncomp + j] = (int32_t)((int64_t *)v)[k * ncomp + j];
          else
            ((double *)f->data)[row * ncomp + j] = ((double *)v)[k * ncomp + j];
        }
      }
    vm_free(ctx, v);
    if (st) return st;
  }
  return VM_OK;
}

int vm_read_vtu(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  vturd r;
  memset(&r, 0, sizeof r);
  r.ctx = ctx;
  r.name = name;
  r.base = (const char *)buf;
  r.end = r.base + len;
  vm_mesh *m = NULL;
  int64_t *map = NULL;
  int st = xml_scan(&r);
  int64_t np = 0, nc = 0;
  if (!st) {
    np = attr_int(r.piece_attrs, r.piece_alen, "NumberOfPoints");
    nc = attr_int(r.piece_attrs, r.piece_alen, "NumberOfCells");
    if (np < 0 || nc < 0)
      st = vfail(&r, r.piece_at, "Piece needs NumberOfPoints and NumberOfCells");
    else if (np > INT32_MAX || nc > INT32_MAX)
      st = vfail(&r, r.piece_at, "too many points or cells");
  }
  if (!st) st = vm_mesh_create(ctx, &m);
  if (!st) st = read_points(&r, m, np);
  if (!st) st = read_cells(&r, m, nc, &map);
  if (!st) st = read_data(&r, m, K_PDATA, np, NULL);
  if (!st) st = read_data(&r, m, K_CDATA, nc, map);
  if (!st) st = vm_vtk_finish_mesh(ctx, m, name);
  vm_free(ctx, map);
  vm_free(ctx, r.arr);
  if (st) {
    vm_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return VM_OK;
}

/* Writer. */

typedef struct {
  FILE *fp;
  uint8_t in[3];
  int n;
  char line[80];
  int col;
} b64out;

static void b64_flush_line(b64out *b) {
  if (b->col) fwrite(b->line, 1, (size_t)b->col, b->fp);
  b->col = 0;
}

static void b64_quad(b64out *b, int nbytes) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  uint32_t w = (uint32_t)b->in[0] << 16 | (uint32_t)(nbytes > 1 ? b->in[1] : 0) << 8 |
               (uint32_t)(nbytes > 2 ? b->in[2] : 0);
  if (b->col + 4 > (int)sizeof b->line) b64_flush_line(b);
  b->line[b->col++] = tab[(w >> 18) & 63];
  b->line[b->col++] = tab[(w >> 12) & 63];
  b->line[b->col++] = nbytes > 1 ? tab[(w >> 6) & 63] : '=';
  b->line[b->col++] = nbytes > 2 ? tab[w & 63] : '=';
}

static void b64_put(b64out *b, uint64_t v, int size) {
  for (int i = 0; i < size; i++, v >>= 8) { /* little-endian */
    b->in[b->n++] = (uint8_t)v;
    if (b->n == 3) {
      b64_quad(b, 3);
      b->n = 0;
    }
  }
}

static void b64_end(b64out *b) {
  if (b->n) b64_quad(b, b->n);
  b->n = 0;
  b64_flush_line(b);
}

static void xml_name(FILE *fp, const char *s) {
  for (; *s; s++) {
    switch (*s) {
    case '<': fputs("&lt;", fp); break;
    case '>': fputs("&gt;", fp); break;
    case '&': fputs("&amp;", fp); break;
    case '"': fputs("&quot;", fp); break;
    case '\'': fputs("&apos;", fp); break;
    default:
      if ((unsigned char)*s < 32)
        fprintf(fp, "&#%d;", *s);
      else
        fputc(*s, fp);
    }
  }
}

/* One inline base64 DataArray: UInt64 byte count, then the values. */
static void write_array(FILE *fp, const char *indent, const char *type, const char *aname,
                        int ncomp, int64_t nval, int size, const void *data,
                        uint64_t (*get)(const void *, int64_t)) {
  fprintf(fp, "%s<DataArray type=\"%s\"", indent, type);
  if (aname) {
    fputs(" Name=\"", fp);
    xml_name(fp, aname);
    fputc('"', fp);
  }
  if (ncomp) fprintf(fp, " NumberOfComponents=\"%d\"", ncomp);
  fprintf(fp, " format=\"binary\">\n%s  ", indent);
  b64out b = {fp, {0, 0, 0}, 0, {0}, 0};
  b64_put(&b, (uint64_t)nval * (uint64_t)size, 8);
  for (int64_t i = 0; i < nval; i++) b64_put(&b, get(data, i), size);
  b64_end(&b);
  fprintf(fp, "\n%s</DataArray>\n", indent);
}

static uint64_t get_f64(const void *d, int64_t i) {
  uint64_t u;
  memcpy(&u, (const double *)d + i, sizeof u);
  return u;
}
static uint64_t get_i32(const void *d, int64_t i) { return (uint32_t)((const int32_t *)d)[i]; }
static uint64_t get_u8(const void *d, int64_t i) { return ((const uint8_t *)d)[i]; }
static uint64_t get_conn(const void *d, int64_t i) {
  return (uint64_t)(int64_t)((const int32_t *)d)[i];
}
static uint64_t get_offset(const void *d, int64_t i) {
  return (uint64_t)((const int64_t *)d)[i + 1];
}
static uint64_t get_vtktype(const void *d, int64_t i) {
  return (uint64_t)vm_elem_to_vtk(((const uint8_t *)d)[i]);
}

static void write_fields(FILE *fp, const vm_mesh *m, int loc, int flags) {
  int64_t n = loc == VM_FIELD_VERTEX ? m->nv : m->ne;
  int any = loc == VM_FIELD_VERTEX && flags;
  for (int i = 0; i < m->nfield; i++)
    any |= m->fields[i].location == loc && vm_vtk_field_written(&m->fields[i], flags);
  if (!any) return;
  const char *tag = loc == VM_FIELD_VERTEX ? "PointData" : "CellData";
  fprintf(fp, "      <%s>\n", tag);
  const char *ind = "        ";
  if (loc == VM_FIELD_VERTEX && flags) {
    write_array(fp, ind, "UInt8", VM_VTK_FLAG_NAME, 1, n, 1, m->vflag, get_u8);
    write_array(fp, ind, "Int32", VM_VTK_SURF_NAME, 1, n, 4, m->vsurf, get_i32);
  }
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (f->location != loc || !vm_vtk_field_written(f, flags)) continue;
    if (f->type == VM_FIELD_F64)
      write_array(fp, ind, "Float64", f->name, f->ncomp, n * f->ncomp, 8, f->data, get_f64);
    else
      write_array(fp, ind, "Int32", f->name, f->ncomp, n * f->ncomp, 4, f->data, get_i32);
  }
  fprintf(fp, "      </%s>\n", tag);
}

int vm_write_vtu(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  int flags = vm_vtk_need_flags(m);
  /* connectivity in VTK's vertex order (prisms differ) */
  int64_t nconn = m->eoff[m->ne];
  int32_t *conn = vm_alloc_array(ctx, (size_t)(nconn ? nconn : 1), sizeof *conn);
  if (!conn) return VM_ERR_NOMEM;
  for (int64_t e = 0; e < m->ne; e++)
    for (int64_t j = 0; j < m->eoff[e + 1] - m->eoff[e]; j++)
      conn[m->eoff[e] + j] = m->conn[m->eoff[e] + vm_elem_vtk_node(m->etype[e], (int)j)];
  vm_outfile *of;
  int st = vm_outfile_open(ctx, path, &of);
  if (st) {
    vm_free(ctx, conn);
    return st;
  }
  FILE *fp = vm_outfile_fp(of);
  fprintf(fp,
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
          "header_type=\"UInt64\">\n"
          "  <UnstructuredGrid>\n"
          "    <Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n",
          (long long)m->nv, (long long)m->ne);
  write_fields(fp, m, VM_FIELD_VERTEX, flags);
  write_fields(fp, m, VM_FIELD_ELEMENT, flags);
  fputs("      <Points>\n", fp);
  write_array(fp, "        ", "Float64", "Points", 3, 3 * m->nv, 8, m->xyz, get_f64);
  fputs("      </Points>\n      <Cells>\n", fp);
  write_array(fp, "        ", "Int64", "connectivity", 0, nconn, 8, conn, get_conn);
  vm_free(ctx, conn);
  write_array(fp, "        ", "Int64", "offsets", 0, m->ne, 8, m->eoff, get_offset);
  write_array(fp, "        ", "UInt8", "types", 0, m->ne, 1, m->etype, get_vtktype);
  fputs("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n", fp);
  st = vm_outfile_commit(&of);
  if (st) return st;
  return vm_vtk_report_lost(ctx, m, path, flags) ? VM_WARN_LOSSY : VM_OK;
}
