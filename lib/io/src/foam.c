/* lib/io/src/foam.c: OpenFOAM polyMesh writer: a case directory with
 * constant/polyMesh/{points,faces,owner,neighbour,boundary}, ASCII or binary,
 * the mesh's named boundaries as patches. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "families_private.h"
#include "formats_private.h"

/* Where the faces of cells that no boundary element covers go (the name
 * blockMesh gives them). */
#define FOAM_DEFAULT_PATCH "defaultFaces"

/* A face of a cell, its vertices sorted (v[3] = INT32_MAX for a triangle):
 * equal keys are the same face seen from two cells. */
typedef struct {
  int32_t v[4];
  int32_t cell, lf;
} fkey;

/* A face as written: its owner cell and the owner's local face (whose
 * vertex order, outward from the owner, is the face's), the neighbour cell
 * (-1 on the boundary), and for boundary faces the patch and the rank
 * within it. */
typedef struct {
  int32_t own, nbr, lf, patch;
  int64_t seq;
} oface;

typedef struct {
  char *name;
  int kind;         /* EX_FAM_* of the name */
  const char *type; /* polyPatch type */
  int64_t start, n;
} fpatch;

typedef struct {
  vm_ctx *ctx;
  const vm_mesh *m;
  const char *path;
  int64_t ncell, npoint, nface, nint;
  int32_t *cell; /* element of each cell, in mesh order */
  int32_t *pnum; /* vertex -> point number, -1 if no cell uses it */
  oface *face;   /* internal faces (upper-triangular order), then boundary faces by patch */
  int npatch;
  fpatch *patch;
  int lossy;
  int ftab[VM_NTYPES][6][4], fnv[VM_NTYPES][6], nfc[VM_NTYPES];
} foam_mesh;

static int cmp_verts(const int32_t *a, const int32_t *b) {
  for (int i = 0; i < 4; i++)
    if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
  return 0;
}

static int cmp_fkey(const void *a, const void *b) {
  const fkey *x = a, *y = b;
  int c = cmp_verts(x->v, y->v);
  if (c) return c;
  if (x->cell != y->cell) return x->cell < y->cell ? -1 : 1;
  return (x->lf > y->lf) - (x->lf < y->lf);
}

/* OpenFOAM's order: internal faces by owner, then neighbour; boundary
 * faces by patch, then rank. */
static int cmp_oface(const void *a, const void *b) {
  const oface *x = a, *y = b;
  if (x->nbr < 0 || y->nbr < 0) {
    if ((x->nbr < 0) != (y->nbr < 0)) return x->nbr < 0 ? 1 : -1;
    if (x->patch != y->patch) return x->patch < y->patch ? -1 : 1;
    return (x->seq > y->seq) - (x->seq < y->seq);
  }
  if (x->own != y->own) return x->own < y->own ? -1 : 1;
  if (x->nbr != y->nbr) return x->nbr < y->nbr ? -1 : 1;
  return (x->lf > y->lf) - (x->lf < y->lf);
}

/* v[0..n) sorted ascending, the rest INT32_MAX; 0 if a vertex repeats. */
static int make_key(int32_t v[4], int n) {
  for (int i = n; i < 4; i++) v[i] = INT32_MAX;
  for (int i = 1; i < n; i++)
    for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
      int32_t t = v[j];
      v[j] = v[j - 1];
      v[j - 1] = t;
    }
  for (int i = 1; i < n; i++)
    if (v[i] == v[i - 1]) return 0;
  return 1;
}

/* First key with these vertices, or -1. */
static int64_t find_key(const fkey *k, int64_t n, const int32_t v[4]) {
  int64_t lo = 0, hi = n;
  while (lo < hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (cmp_verts(k[mid].v, v) < 0)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < n && !cmp_verts(k[lo].v, v) ? lo : -1;
}

/* Point k of written face f. */
static int32_t face_point(const foam_mesh *fm, const oface *f, int k) {
  const vm_mesh *m = fm->m;
  int32_t e = fm->cell[f->own];
  int t = m->etype[e];
  return fm->pnum[m->conn[m->eoff[e] + fm->ftab[t][f->lf][k]]];
}

static int face_nv(const foam_mesh *fm, const oface *f) {
  return fm->fnv[fm->m->etype[fm->cell[f->own]]][f->lf];
}

/* A family name as an OpenFOAM word: letters, digits, '_', '-' and '.'
 * kept, anything else '_', and "patch_" before a name that does not start
 * with a letter or '_'. *changed is set if the name had to change. */
static char *foam_word(vm_ctx *ctx, const char *name, int *changed) {
  size_t n = strlen(name);
  int pre =
      !((name[0] >= 'a' && name[0] <= 'z') || (name[0] >= 'A' && name[0] <= 'Z') || name[0] == '_');
  char *w = vm_malloc(ctx, n + 7);
  if (!w) return NULL;
  char *p = w;
  if (pre) p += sprintf(p, "patch_");
  *changed = pre;
  for (size_t i = 0; i < n; i++) {
    unsigned char c = (unsigned char)name[i];
    int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
             c == '_' || c == '-' || c == '.';
    *p++ = ok ? (char)c : '_';
    *changed |= !ok;
  }
  *p = 0;
  return w;
}

static int add_patch(foam_mesh *fm, const char *word, int *index) {
  for (int p = 0; p < fm->npatch; p++)
    if (!strcmp(fm->patch[p].name, word)) {
      *index = p;
      return VM_OK;
    }
  fpatch *np = vm_realloc(fm->ctx, fm->patch, sizeof *np * (size_t)(fm->npatch + 1));
  if (!np) return VM_ERR_NOMEM;
  fm->patch = np;
  fpatch *q = &np[fm->npatch];
  memset(q, 0, sizeof *q);
  if (!(q->name = vm_strdup(fm->ctx, word))) return VM_ERR_NOMEM;
  q->kind = ex_family_kind(word);
  *index = fm->npatch++;
  return VM_OK;
}

/* Patch ranks of family faces come first; faces in no family follow in
 * cell order. */
#define FOAM_UNNAMED_RANK ((int64_t)1 << 40)

/* The boundary elements of the mesh, family by family, onto the cell faces
 * they cover (same vertex set). bpatch/bseq are per key (singletons only). */
static int assign_families(foam_mesh *fm, const fkey *key, int64_t nkey, const uint8_t *single,
                           int32_t *bpatch, int64_t *bseq) {
  vm_ctx *ctx = fm->ctx;
  const char *path = fm->path;
  ex_groups g;
  int st = ex_groups_build(ctx, fm->m, &g);
  if (st) {
    ex_groups_free(ctx, &g);
    return st;
  }
  int64_t ndup = 0, ninner = 0, norphan = 0, seq = 0;
  for (int f = 0; f < g.nfam && !st; f++) {
    if (g.fbeg[f] < g.fbeg[f + 1] && g.felem[g.fbeg[f]] < 0) continue; /* extracted, not named */
    int changed, p;
    char *w = foam_word(ctx, g.name[f], &changed);
    if (!w) {
      st = VM_ERR_NOMEM;
      break;
    }
    if (changed) {
      vm_log(ctx, VM_LOG_WARN, "%s: boundary '%s' written as the patch '%s' (not an OpenFOAM word)",
             path, g.name[f], w);
      fm->lossy = 1;
    }
    st = add_patch(fm, w, &p);
    vm_free(ctx, w);
    for (int64_t i = g.fbeg[f]; i < g.fbeg[f + 1] && !st; i++) {
      int32_t v[4];
      for (int j = 0; j < 4; j++) v[j] = g.fv[4 * i + j];
      int64_t k = make_key(v, g.fnv[i]) ? find_key(key, nkey, v) : -1;
      if (k < 0)
        norphan++;
      else if (!single[k])
        ninner++;
      else if (bpatch[k] >= 0)
        ndup++;
      else {
        bpatch[k] = p;
        bseq[k] = seq++;
      }
    }
  }
  ex_groups_free(ctx, &g);
  if (st) return st;
  if (ninner)
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld boundary elements lie between two cells; OpenFOAM patches hold only boundary "
           "faces: dropped",
           path, (long long)ninner);
  if (norphan)
    vm_log(ctx, VM_LOG_WARN, "%s: %lld boundary elements are no face of any cell; dropped", path,
           (long long)norphan);
  if (ndup)
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld boundary elements repeat a face already in a patch; the first one kept", path,
           (long long)ndup);
  fm->lossy |= ninner || norphan || ndup;
  return VM_OK;
}

/* symmetryPlane if the patch is flat to the tolerance OpenFOAM checks
 * (|n_f - mean n|^2 <= 1e-15 for every unit face normal n_f; we ask 1e-16
 * so that rounding cannot tip it), else symmetry, which takes any shape. */
static int patch_planar(const foam_mesh *fm, const fpatch *pt) {
  const double *X = fm->m->xyz;
  double mean[3] = {0, 0, 0};
  double *nrm = vm_alloc_array(fm->ctx, (size_t)(pt->n ? pt->n : 1), 3 * sizeof(double));
  if (!nrm) return -1;
  /* Newell's normal of each face, from the owner cell's vertices */
  for (int64_t i = 0; i < pt->n; i++) {
    const oface *f = &fm->face[pt->start + i];
    int32_t e = fm->cell[f->own];
    int t = fm->m->etype[e], nv = face_nv(fm, f);
    const int32_t *c = fm->m->conn + fm->m->eoff[e];
    double n[3] = {0, 0, 0};
    for (int k = 0; k < nv; k++) {
      const double *a = X + 3 * (int64_t)c[fm->ftab[t][f->lf][k]];
      const double *b = X + 3 * (int64_t)c[fm->ftab[t][f->lf][(k + 1) % nv]];
      n[0] += (a[1] - b[1]) * (a[2] + b[2]);
      n[1] += (a[2] - b[2]) * (a[0] + b[0]);
      n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int d = 0; d < 3; d++) {
      nrm[3 * i + d] = l > 0 ? n[d] / l : 0;
      mean[d] += nrm[3 * i + d];
    }
  }
  int flat = 1;
  for (int64_t i = 0; i < pt->n && flat; i++) {
    double s = 0;
    for (int d = 0; d < 3; d++) {
      double x = nrm[3 * i + d] - mean[d] / (double)pt->n;
      s += x * x;
    }
    flat = s <= 1e-16;
  }
  vm_free(fm->ctx, nrm);
  return flat;
}

static void foam_free(foam_mesh *fm) {
  vm_ctx *ctx = fm->ctx;
  for (int p = 0; p < fm->npatch; p++) vm_free(ctx, fm->patch[p].name);
  vm_free(ctx, fm->patch);
  vm_free(ctx, fm->cell);
  vm_free(ctx, fm->pnum);
  vm_free(ctx, fm->face);
}

/* Cells, points, faces and patches of the mesh as OpenFOAM wants them. */
static int foam_build(foam_mesh *fm) {
  vm_ctx *ctx = fm->ctx;
  const vm_mesh *m = fm->m;
  const char *path = fm->path;
  for (int t = 0; t < VM_NTYPES; t++) fm->nfc[t] = vm_elem_faces(t, fm->ftab[t], fm->fnv[t]);
  int64_t nkey = 0;
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 3) {
      fm->ncell++;
      nkey += fm->nfc[m->etype[e]];
    }
  if (nkey > INT32_MAX)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: %lld cell faces are too many for 32-bit labels",
                    path, (long long)nkey);
  fm->cell = vm_alloc_array(ctx, (size_t)fm->ncell, sizeof *fm->cell);
  fm->pnum = vm_alloc_array(ctx, (size_t)(m->nv ? m->nv : 1), sizeof *fm->pnum);
  fkey *key = vm_alloc_array(ctx, (size_t)nkey, sizeof *key);
  uint8_t *single = vm_calloc(ctx, (size_t)nkey, 1);
  int32_t *bpatch = vm_alloc_array(ctx, (size_t)nkey, sizeof *bpatch);
  int64_t *bseq = vm_alloc_array(ctx, (size_t)nkey, sizeof *bseq);
  int st = VM_OK;
  if (!fm->cell || !fm->pnum || !key || !single || !bpatch || !bseq) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  /* points: the vertices of cells, in vertex order */
  for (int64_t v = 0; v < m->nv; v++) fm->pnum[v] = -1;
  int64_t c = 0, k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 3) continue;
    const int32_t *cv = m->conn + m->eoff[e];
    for (int j = 0; j < vm_elem_nverts(t); j++) fm->pnum[cv[j]] = 0;
    for (int lf = 0; lf < fm->nfc[t]; lf++, k++) {
      for (int j = 0; j < fm->fnv[t][lf]; j++) key[k].v[j] = cv[fm->ftab[t][lf][j]];
      if (!make_key(key[k].v, fm->fnv[t][lf])) {
        st = vm_error(ctx, VM_ERR_ARG,
                      "%s: element %lld (%s) has a face with a repeated vertex; OpenFOAM needs "
                      "proper cells",
                      path, (long long)e, vm_elem_name(t));
        goto done;
      }
      key[k].cell = (int32_t)c;
      key[k].lf = lf;
    }
    fm->cell[c++] = (int32_t)e;
  }
  for (int64_t v = 0; v < m->nv; v++)
    if (!fm->pnum[v]) fm->pnum[v] = (int32_t)fm->npoint++;
  if (fm->npoint < m->nv) {
    vm_log(ctx, VM_LOG_WARN, "%s: %lld vertices used by no cell are not written", path,
           (long long)(m->nv - fm->npoint));
    fm->lossy = 1;
  }
  /* faces: equal keys pair up into internal faces */
  qsort(key, (size_t)nkey, sizeof *key, cmp_fkey);
  int64_t nb = 0;
  for (int64_t i = 0, j; i < nkey; i = j) {
    for (j = i + 1; j < nkey && !cmp_verts(key[j].v, key[i].v);) j++;
    if (j - i > 2 || (j - i == 2 && key[i].cell == key[i + 1].cell)) {
      const int32_t *v = key[i].v;
      if (j - i > 2)
        st = vm_error(ctx, VM_ERR_ARG,
                      "%s: the face of vertices %d %d %d%s is shared by %lld cells; OpenFOAM needs "
                      "each face between at most two",
                      path, v[0], v[1], v[2], v[3] == INT32_MAX ? "" : " ...", (long long)(j - i));
      else
        st = vm_error(ctx, VM_ERR_ARG, "%s: element %lld (%s) has two faces on the same vertices",
                      path, (long long)fm->cell[key[i].cell],
                      vm_elem_name(m->etype[fm->cell[key[i].cell]]));
      goto done;
    }
    single[i] = j - i == 1;
    nb += j - i == 1;
    bpatch[i] = -1;
    if (j - i == 2) bpatch[i + 1] = -1;
  }
  fm->nint = (nkey - nb) / 2;
  fm->nface = fm->nint + nb;
  if ((st = assign_families(fm, key, nkey, single, bpatch, bseq))) goto done;
  int64_t nunnamed = 0;
  int pdef = -1;
  for (int64_t i = 0; i < nkey; i++) nunnamed += single[i] && bpatch[i] < 0;
  if (nunnamed) {
    if ((st = add_patch(fm, FOAM_DEFAULT_PATCH, &pdef))) goto done;
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld boundary faces are in no named boundary; written to the patch '%s'", path,
           (long long)nunnamed, FOAM_DEFAULT_PATCH);
  }
  fm->face = vm_alloc_array(ctx, (size_t)(fm->nface ? fm->nface : 1), sizeof *fm->face);
  if (!fm->face) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t f = 0;
  for (int64_t i = 0; i < nkey; i++) {
    oface *o = &fm->face[f];
    if (single[i]) {
      o->own = key[i].cell;
      o->lf = key[i].lf;
      o->nbr = -1;
      o->patch = bpatch[i] >= 0 ? bpatch[i] : pdef;
      o->seq = bpatch[i] >= 0 ? bseq[i] : FOAM_UNNAMED_RANK + 8 * (int64_t)key[i].cell + key[i].lf;
      f++;
    } else if (i + 1 < nkey && !single[i + 1] && !cmp_verts(key[i].v, key[i + 1].v)) {
      /* keys sort by cell within a face: the first is the lower cell, the owner */
      o->own = key[i].cell;
      o->lf = key[i].lf;
      o->nbr = key[i + 1].cell;
      o->patch = -1;
      o->seq = 0;
      f++;
      i++;
    }
  }
  qsort(fm->face, (size_t)fm->nface, sizeof *fm->face, cmp_oface);
  for (int64_t i = fm->nint; i < fm->nface; i++) fm->patch[fm->face[i].patch].n++;
  int64_t start = fm->nint;
  for (int p = 0; p < fm->npatch; p++) {
    fpatch *pt = &fm->patch[p];
    pt->start = start;
    start += pt->n;
    pt->type = pt->kind == EX_FAM_WALL ? "wall" : "patch";
    if (pt->kind == EX_FAM_SYMMETRY) {
      int flat = patch_planar(fm, pt);
      if (flat < 0) {
        st = VM_ERR_NOMEM;
        goto done;
      }
      pt->type = flat ? "symmetryPlane" : "symmetry";
      if (!flat)
        vm_log(ctx, VM_LOG_WARN,
               "%s: the patch '%s' is not planar: written as type symmetry, not symmetryPlane",
               path, pt->name);
    }
  }
done:
  vm_free(ctx, key);
  vm_free(ctx, single);
  vm_free(ctx, bpatch);
  vm_free(ctx, bseq);
  return st;
}

/* Writing. */

static void put_header(FILE *fp, int bin, const char *cls, const char *loc, const char *obj,
                       const char *note) {
  static const union {
    uint16_t u;
    uint8_t b[2];
  } endian = {1};
  fputs("/*--------------------------------*- C++ -*----------------------------------*\\\n"
        "  OpenFOAM polyMesh written by varmesh\n"
        "\\*---------------------------------------------------------------------------*/\n",
        fp);
  fprintf(fp, "FoamFile\n{\n    version     2.0;\n    format      %s;\n    class       %s;\n",
          bin ? "binary" : "ascii", cls);
  if (bin) fprintf(fp, "    arch        \"%s;label=32;scalar=64\";\n", endian.b[0] ? "LSB" : "MSB");
  if (note) fprintf(fp, "    note        \"%s\";\n", note);
  fprintf(fp, "    location    \"%s\";\n    object      %s;\n}\n", loc, obj);
  fputs("// * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //\n\n", fp);
}

static void put_footer(FILE *fp) {
  fputs("\n\n// ************************************************************************* //\n",
        fp);
}

/* A binary list: "n\n(" raw bytes ")"; OpenFOAM writes an empty one as
 * its size alone. */
static void put_raw(FILE *fp, int64_t n, const void *data, size_t bytes) {
  fprintf(fp, "%lld\n", (long long)n);
  if (!n) return;
  fputc('(', fp);
  fwrite(data, 1, bytes, fp);
  fputc(')', fp);
}

/* Labels of a list, from a callback, in chunks (binary) or one a line. */
typedef int32_t (*label_fn)(const foam_mesh *fm, int64_t i);

static void put_labels(FILE *fp, int bin, const foam_mesh *fm, int64_t n, label_fn get) {
  if (!bin) {
    fprintf(fp, "%lld\n(\n", (long long)n);
    for (int64_t i = 0; i < n; i++) fprintf(fp, "%d\n", (int)get(fm, i));
    fputs(")\n", fp);
    return;
  }
  fprintf(fp, "%lld\n", (long long)n);
  if (!n) return;
  fputc('(', fp);
  int32_t buf[1024];
  for (int64_t i = 0; i < n;) {
    int k = 0;
    while (k < 1024 && i < n) buf[k++] = get(fm, i++);
    fwrite(buf, sizeof *buf, (size_t)k, fp);
  }
  fputc(')', fp);
}

static int32_t owner_of(const foam_mesh *fm, int64_t i) { return fm->face[i].own; }
static int32_t neighbour_of(const foam_mesh *fm, int64_t i) { return fm->face[i].nbr; }

/* ASCII: a faceList; binary: a faceCompactList (the offsets of every face
 * in the second list, then the points of every face), as OpenFOAM writes. */
static void put_faces(FILE *fp, int bin, const foam_mesh *fm) {
  if (!bin) {
    fprintf(fp, "%lld\n(\n", (long long)fm->nface);
    for (int64_t i = 0; i < fm->nface; i++) {
      const oface *f = &fm->face[i];
      int nv = face_nv(fm, f);
      fprintf(fp, "%d(", nv);
      for (int k = 0; k < nv; k++) fprintf(fp, k ? " %d" : "%d", (int)face_point(fm, f, k));
      fputs(")\n", fp);
    }
    fputs(")\n", fp);
    return;
  }
  int32_t buf[1024];
  int64_t total = 0;
  fprintf(fp, "%lld\n(", (long long)(fm->nface + 1));
  int k = 0;
  buf[k++] = 0;
  for (int64_t i = 0; i < fm->nface; i++) {
    total += face_nv(fm, &fm->face[i]);
    buf[k++] = (int32_t)total;
    if (k == 1024) {
      fwrite(buf, sizeof *buf, (size_t)k, fp);
      k = 0;
    }
  }
  fwrite(buf, sizeof *buf, (size_t)k, fp);
  fprintf(fp, ")\n\n%lld\n", (long long)total);
  if (!total) return;
  fputc('(', fp);
  k = 0;
  for (int64_t i = 0; i < fm->nface; i++) {
    const oface *f = &fm->face[i];
    int nv = face_nv(fm, f);
    if (k + nv > 1024) {
      fwrite(buf, sizeof *buf, (size_t)k, fp);
      k = 0;
    }
    for (int j = 0; j < nv; j++) buf[k++] = face_point(fm, f, j);
  }
  fwrite(buf, sizeof *buf, (size_t)k, fp);
  fputc(')', fp);
}

static void put_points(FILE *fp, int bin, const foam_mesh *fm) {
  const vm_mesh *m = fm->m;
  if (!bin) {
    fprintf(fp, "%lld\n(\n", (long long)fm->npoint);
    for (int64_t v = 0; v < m->nv; v++)
      if (fm->pnum[v] >= 0) {
        const double *x = m->xyz + 3 * v;
        fprintf(fp, "(%.17g %.17g %.17g)\n", x[0], x[1], x[2]);
      }
    fputs(")\n", fp);
    return;
  }
  if (fm->npoint == m->nv) {
    put_raw(fp, m->nv, m->xyz, sizeof(double) * 3 * (size_t)m->nv);
    return;
  }
  fprintf(fp, "%lld\n", (long long)fm->npoint);
  if (!fm->npoint) return;
  fputc('(', fp);
  for (int64_t v = 0; v < m->nv; v++)
    if (fm->pnum[v] >= 0) fwrite(m->xyz + 3 * v, sizeof(double), 3, fp);
  fputc(')', fp);
}

static void put_boundary(FILE *fp, const foam_mesh *fm) {
  fprintf(fp, "%d\n(\n", fm->npatch);
  for (int p = 0; p < fm->npatch; p++) {
    const fpatch *pt = &fm->patch[p];
    fprintf(fp, "    %s\n    {\n        type            %s;\n", pt->name, pt->type);
    if (strcmp(pt->type, "patch"))
      fprintf(fp, "        inGroups        List<word> 1(%s);\n", pt->type);
    fprintf(fp, "        nFaces          %lld;\n        startFace       %lld;\n    }\n",
            (long long)pt->n, (long long)pt->start);
  }
  fputs(")\n", fp);
}

/* One file of the polyMesh in dir. */
static int write_one(const foam_mesh *fm, const char *dir, const char *obj, int bin) {
  vm_ctx *ctx = fm->ctx;
  size_t n = strlen(dir) + strlen(obj) + 2;
  char *p = vm_malloc(ctx, n);
  if (!p) return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", fm->path);
  snprintf(p, n, "%s/%s", dir, obj);
  FILE *fp = fopen(p, "wb");
  vm_free(ctx, p);
  if (!fp)
    return vm_error(ctx, VM_ERR_IO, "%s: cannot create %s: %s", fm->path, obj, strerror(errno));
  static const char loc[] = "constant/polyMesh";
  char note[200];
  snprintf(note, sizeof note, "nPoints:%lld  nCells:%lld  nFaces:%lld  nInternalFaces:%lld",
           (long long)fm->npoint, (long long)fm->ncell, (long long)fm->nface, (long long)fm->nint);
  if (!strcmp(obj, "points")) {
    put_header(fp, bin, "vectorField", loc, obj, NULL);
    put_points(fp, bin, fm);
  } else if (!strcmp(obj, "faces")) {
    put_header(fp, bin, bin ? "faceCompactList" : "faceList", loc, obj, NULL);
    put_faces(fp, bin, fm);
  } else if (!strcmp(obj, "owner")) {
    put_header(fp, bin, "labelList", loc, obj, note);
    put_labels(fp, bin, fm, fm->nface, owner_of);
  } else if (!strcmp(obj, "neighbour")) {
    put_header(fp, bin, "labelList", loc, obj, note);
    put_labels(fp, bin, fm, fm->nint, neighbour_of);
  } else {
    /* a dictionary: text in either format */
    put_header(fp, 0, "polyBoundaryMesh", loc, obj, NULL);
    put_boundary(fp, fm);
  }
  put_footer(fp);
  int bad = fflush(fp) != 0 || ferror(fp);
  int e = errno;
  bad |= fclose(fp) != 0;
  if (bad)
    return vm_error(ctx, VM_ERR_IO, "%s: writing %s failed: %s", fm->path, obj,
                    strerror(e ? e : errno));
  return VM_OK;
}

static int write_polymesh(const foam_mesh *fm, const char *dir, int bin) {
  static const char *const obj[] = {"points", "faces", "owner", "neighbour", "boundary"};
  int st = VM_OK;
  for (int i = 0; i < 5 && !st; i++) st = write_one(fm, dir, obj[i], bin);
  return st;
}

/* system/controlDict, fvSchemes and fvSolution, so that OpenFOAM's
 * programs (checkMesh, foamToVTK, ...) run on the case as it is; a
 * solver run needs its own. */
static void put_sys_header(FILE *fp, const char *obj) {
  fprintf(fp,
          "/*--------------------------------*- C++ -*----------------------------------*\\\n"
          "  written by varmesh with the mesh, where the case had none: edit for a run\n"
          "\\*---------------------------------------------------------------------------*/\n"
          "FoamFile\n{\n    version     2.0;\n    format      ascii;\n"
          "    class       dictionary;\n    location    \"system\";\n    object      %s;\n}\n\n",
          obj);
}

static void put_control_dict(FILE *fp, int bin) {
  put_sys_header(fp, "controlDict");
  fputs("startFrom       startTime;\nstartTime       0;\nstopAt          endTime;\n"
        "endTime         1000;\ndeltaT          1;\nwriteControl    timeStep;\n"
        "writeInterval   100;\npurgeWrite      0;\n",
        fp);
  fprintf(fp, "writeFormat     %s;\n", bin ? "binary" : "ascii");
  fputs("writePrecision  8;\nwriteCompression off;\ntimeFormat      general;\n"
        "timePrecision   6;\nrunTimeModifiable true;\n",
        fp);
}

static void put_fv_schemes(FILE *fp, int bin) {
  (void)bin;
  put_sys_header(fp, "fvSchemes");
  fputs("ddtSchemes\n{\n    default         steadyState;\n}\n\n"
        "gradSchemes\n{\n    default         Gauss linear;\n}\n\n"
        "divSchemes\n{\n    default         none;\n}\n\n"
        "laplacianSchemes\n{\n    default         Gauss linear corrected;\n}\n\n"
        "interpolationSchemes\n{\n    default         linear;\n}\n\n"
        "snGradSchemes\n{\n    default         corrected;\n}\n",
        fp);
}

static void put_fv_solution(FILE *fp, int bin) {
  (void)bin;
  put_sys_header(fp, "fvSolution");
  fputs("solvers\n{\n}\n", fp);
}

static const struct {
  const char *name;
  void (*put)(FILE *fp, int bin);
} sys_files[] = {
    {"controlDict", put_control_dict},
    {"fvSchemes", put_fv_schemes},
    {"fvSolution", put_fv_solution},
};
#define NSYS (sizeof sys_files / sizeof sys_files[0])

static char *join(vm_ctx *ctx, const char *a, const char *b) {
  size_t n = strlen(a) + strlen(b) + 2;
  char *s = vm_malloc(ctx, n);
  if (s) snprintf(s, n, "%s/%s", a, b);
  return s;
}

/* mkdir that records whether it made the directory (made may be NULL). */
static int make_dir(const char *p, int *made) {
  if (made) *made = 0;
  if (mkdir(p, 0777) == 0) {
    if (made) *made = 1;
    return 0;
  }
  struct stat st;
  return errno == EEXIST && stat(p, &st) == 0 && S_ISDIR(st.st_mode) ? 0 : -1;
}

/* A new case: built whole in a temporary directory, renamed into place. */
static int write_new_case(const foam_mesh *fm, const char *out, int bin) {
  vm_ctx *ctx = fm->ctx;
  vm_outdir *d;
  int st = vm_outdir_open(ctx, out, &d);
  if (st) return st;
  const char *t = vm_outdir_tmp(d);
  char *con = join(ctx, t, "constant"), *pm = con ? join(ctx, con, "polyMesh") : NULL;
  char *sys = join(ctx, t, "system");
  if (!pm || !sys) {
    st = vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", out);
  } else if (make_dir(con, NULL) || make_dir(pm, NULL) || make_dir(sys, NULL)) {
    st = vm_error(ctx, VM_ERR_IO, "%s: cannot create a directory: %s", out, strerror(errno));
  } else {
    st = write_polymesh(fm, pm, bin);
    for (size_t i = 0; i < NSYS && !st; i++) {
      char *f = join(ctx, sys, sys_files[i].name);
      if (!f) {
        st = vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", out);
        break;
      }
      FILE *fp = fopen(f, "wb");
      vm_free(ctx, f);
      if (fp) sys_files[i].put(fp, bin);
      int bad = !fp || fflush(fp) != 0 || ferror(fp);
      int e = bad ? (errno ? errno : EIO) : 0;
      if (fp && fclose(fp) != 0 && !bad) bad = 1, e = errno;
      if (bad)
        st = vm_error(ctx, VM_ERR_IO, "%s: cannot write system/%s: %s", out, sys_files[i].name,
                      strerror(e));
    }
  }
  vm_free(ctx, con);
  vm_free(ctx, pm);
  vm_free(ctx, sys);
  if (st) {
    vm_outdir_abort(&d);
    return st;
  }
  return vm_outdir_commit(&d);
}

/* An existing case: only constant/polyMesh is replaced (0/, system/ and
 * the rest of constant/ stay); the files of system/ that are missing are
 * added. */
static int write_into_case(const foam_mesh *fm, const char *out, int bin) {
  vm_ctx *ctx = fm->ctx;
  char *con = join(ctx, out, "constant"), *pm = con ? join(ctx, con, "polyMesh") : NULL;
  char *sys = join(ctx, out, "system");
  vm_outdir *d = NULL;
  vm_outfile *of[NSYS] = {NULL};
  int made_con = 0, made_sys = 0, st = VM_OK;
  if (!pm || !sys) {
    st = vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", out);
    goto done;
  }
  if (make_dir(con, &made_con)) {
    st = vm_error(ctx, VM_ERR_IO, "%s: cannot create constant/: %s", out, strerror(errno));
    goto done;
  }
  if ((st = vm_outdir_open(ctx, pm, &d))) goto done;
  if ((st = write_polymesh(fm, vm_outdir_tmp(d), bin))) goto done;
  for (size_t i = 0; i < NSYS; i++) {
    char *f = join(ctx, sys, sys_files[i].name);
    struct stat sb;
    if (!f) {
      st = vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", out);
      goto done;
    }
    if (stat(f, &sb) == 0) {
      vm_free(ctx, f);
      continue;
    }
    if (!made_sys && make_dir(sys, &made_sys)) {
      vm_free(ctx, f);
      st = vm_error(ctx, VM_ERR_IO, "%s: cannot create system/: %s", out, strerror(errno));
      goto done;
    }
    st = vm_outfile_open(ctx, f, &of[i]);
    vm_free(ctx, f);
    if (st) goto done;
    sys_files[i].put(vm_outfile_fp(of[i]), bin);
  }
  if ((st = vm_outdir_commit(&d))) goto done;
  for (size_t i = 0; i < NSYS && !st; i++)
    if (of[i]) st = vm_outfile_commit(&of[i]);
done:
  vm_outdir_abort(&d);
  for (size_t i = 0; i < NSYS; i++) vm_outfile_abort(&of[i]);
  if (st) {
    if (made_sys) rmdir(sys);
    if (made_con) rmdir(con);
  }
  vm_free(ctx, con);
  vm_free(ctx, pm);
  vm_free(ctx, sys);
  return st;
}

int vm_write_foam(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  int bin = o && o->binary;
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 3 || m->dim != 3)
    return vm_error(ctx, VM_ERR_UNSUPPORTED,
                    "%s: OpenFOAM needs 3D cells (tetrahedra, pyramids, prisms, hexahedra); the "
                    "mesh has none",
                    path);
  /* the case directory's name without trailing slashes */
  size_t len = strlen(path);
  while (len > 1 && path[len - 1] == '/') len--;
  char *out = vm_malloc(ctx, len + 1);
  if (!out) return vm_error(ctx, VM_ERR_NOMEM, "%s: out of memory", path);
  memcpy(out, path, len);
  out[len] = 0;
  foam_mesh fm;
  memset(&fm, 0, sizeof fm);
  fm.ctx = ctx;
  fm.m = m;
  fm.path = out;
  int lossy = ex_groups_lossy(ctx, m, out, "OpenFOAM", 0);
  int st = foam_build(&fm);
  if (st == VM_ERR_NOMEM) vm_error(ctx, st, "%s: out of memory", out);
  struct stat sb;
  if (!st) {
    if (stat(out, &sb) != 0)
      st = write_new_case(&fm, out, bin);
    else if (!S_ISDIR(sb.st_mode))
      st = vm_error(ctx, VM_ERR_IO,
                    "%s: exists and is not a directory (an OpenFOAM case is a directory)", out);
    else
      st = write_into_case(&fm, out, bin);
  }
  lossy |= fm.lossy;
  foam_free(&fm);
  vm_free(ctx, out);
  if (st) return st;
  return lossy ? VM_WARN_LOSSY : VM_OK;
}
