/* lib/io/src/medit.c: MEDIT .mesh (ASCII; mmg, TetGen, Gmsh) reader and writer. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "formats_private.h"
#include "lex_private.h"

/* Vertex references travel as the vertex field "medit:ref"; element
 * references are the element field "gmsh:physical", the tags every format
 * groups boundaries by (an element field "medit:ref", as older readers
 * made, is written when "gmsh:physical" is absent). */
#define MEDIT_REF "medit:ref"
#define MEDIT_PHYS "gmsh:physical"

/* Cell keywords, in the order the writer emits them (vm type order).
 * MEDIT (libMeshb's GMF) lists the vertices of its linear cells in the
 * order vm_mesh uses: tetrahedra with det(p1-p0, p2-p0, p3-p0) > 0 (mmg
 * reorients the others), hexahedra 0-1-2-3 bottom and 4-5-6-7 top, prisms
 * 0-1-2 / 3-4-5 with (p1-p0)x(p2-p0) toward the top, pyramids with the base
 * normal toward the apex (SALOME's MED->GMF writer mirrors MED's cells into
 * exactly these). perm[t][k] is the vm position of file vertex k; it is the
 * identity, spelled out so the convention has one place to change. */
static const struct {
  const char *kw;
  int type;
} cell_kw[] = {{"Triangles", VM_TRI},    {"Quadrilaterals", VM_QUAD}, {"Tetrahedra", VM_TET},
               {"Pyramids", VM_PYRAMID}, {"Prisms", VM_PRISM},        {"Hexahedra", VM_HEX}};

static const int perm[VM_NTYPES][VM_MAX_ELEM_VERTS] = {
    {0, 1, 2},       {0, 1, 2, 3},       {0, 1, 2, 3},
    {0, 1, 2, 3, 4}, {0, 1, 2, 3, 4, 5}, {0, 1, 2, 3, 4, 5, 6, 7}};

/* Keywords parsed and dropped: integers and reals per entry (-1 reals: one
 * per coordinate). */
static const struct {
  const char *kw;
  int nint, nreal;
} skip_kw[] = {{"Edges", 3, 0},
               {"Corners", 1, 0},
               {"Ridges", 1, 0},
               {"RequiredEdges", 1, 0},
               {"RequiredTriangles", 1, 0},
               {"RequiredQuadrilaterals", 1, 0},
               {"RequiredTetrahedra", 1, 0},
               {"RequiredHexahedra", 1, 0},
               {"Normals", 0, -1},
               {"Tangents", 0, -1},
               {"NormalAtVertices", 2, 0},
               {"TangentAtVertices", 2, 0},
               {"NormalAtTriangleVertices", 3, 0},
               {"TangentAtEdgeVertices", 3, 0},
               {"SubDomainFromMesh", 4, 0},
               {"VertexOnGeometricVertex", 2, 0},
               {"VertexOnGeometricEdge", 2, 1},
               {"EdgeOnGeometricEdge", 2, 0}};

typedef struct {
  vm_ctx *ctx;
  const char *name;
  vm_lex lx;
  vm_mesh *m;
  int dim, have_verts;
  int32_t *eref;
  int64_t ecap;
  /* entries of the ignored keywords, said once each at the end (a file of
   * many small sections would otherwise print a line per section) */
  int64_t skipped[sizeof skip_kw / sizeof skip_kw[0]];
  int64_t ignored_lines; /* Identifier, Geometry */
} medit_rd;

/* Nonzero if only blanks (or a comment) remain on the current line. */
static int line_done(const vm_lex *lx) {
  const char *p = lx->p;
  while (p < lx->end && (*p == ' ' || *p == '\t' || *p == '\r')) p++;
  return p >= lx->end || *p == '\n' || *p == '#';
}

static int check_line(medit_rd *r, int64_t line, const char *kw, int64_t i, int ntok) {
  if (r->lx.line != line || !line_done(&r->lx))
    return vm_lex_fail(&r->lx, "%s %lld: expected %d numbers on its line", kw, (long long)(i + 1),
                       ntok);
  return VM_OK;
}

/* Entry count of a keyword, refused if the bytes left cannot hold it. */
static int read_count(medit_rd *r, int64_t *n, int ntok, const char *kw) {
  int st = vm_lex_int(&r->lx, n, kw);
  if (st) return st;
  int64_t left = (int64_t)(r->lx.end - r->lx.p);
  if (*n < 0 || *n > left / (2 * ntok))
    return vm_lex_fail(&r->lx, "%s: %lld entries cannot fit in the %lld bytes left", kw,
                       (long long)*n, (long long)left);
  return VM_OK;
}

static int read_ref(medit_rd *r, int32_t *ref) {
  int64_t x;
  int st = vm_lex_int(&r->lx, &x, "reference");
  if (st) return st;
  if (x < INT32_MIN || x > INT32_MAX)
    return vm_lex_fail(&r->lx, "reference %lld is out of range", (long long)x);
  *ref = (int32_t)x;
  return VM_OK;
}

static int read_vertices(medit_rd *r) {
  if (r->have_verts) return vm_lex_fail(&r->lx, "a second Vertices section");
  if (!r->dim) return vm_lex_fail(&r->lx, "Vertices before Dimension");
  int64_t n;
  int st = read_count(r, &n, r->dim + 1, "Vertices");
  if (st) return st;
  if (n > INT32_MAX) return vm_lex_fail(&r->lx, "%lld vertices are too many", (long long)n);
  vm_field *f;
  if ((st = vm_mesh_set_vertices(r->m, n)) ||
      (st = vm_mesh_add_field(r->m, MEDIT_REF, VM_FIELD_VERTEX, VM_FIELD_I32, 1, &f)))
    return st;
  int32_t *ref = f->data;
  for (int64_t i = 0; i < n; i++) {
    double *x = r->m->xyz + 3 * i;
    int64_t line = 0;
    for (int c = 0; c < r->dim; c++) {
      if ((st = vm_lex_double(&r->lx, &x[c], "vertex coordinate"))) return st;
      if (!c) line = r->lx.line;
    }
    if ((st = read_ref(r, &ref[i])) || (st = check_line(r, line, "vertex", i, r->dim + 1)))
      return st;
    if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2]))
      return vm_lex_fail(&r->lx, "vertex %lld: coordinate is not finite", (long long)(i + 1));
  }
  r->have_verts = 1;
  return VM_OK;
}

static int read_vertex_index(medit_rd *r, const char *kw, int32_t *v) {
  int64_t x;
  int st = vm_lex_int(&r->lx, &x, "vertex index");
  if (st) return st;
  if (x < 1 || x > r->m->nv)
    return vm_lex_fail(&r->lx, "%s: vertex %lld is not in 1..%lld", kw, (long long)x,
                       (long long)r->m->nv);
  *v = (int32_t)(x - 1);
  return VM_OK;
}

static int read_cells(medit_rd *r, const char *kw, int type) {
  int k = vm_elem_nverts(type);
  if (!r->have_verts) return vm_lex_fail(&r->lx, "%s before Vertices", kw);
  if (vm_elem_dim(type) > r->dim)
    return vm_lex_fail(&r->lx, "%s in a %d-dimensional mesh", kw, r->dim);
  int64_t n;
  int st = read_count(r, &n, k + 1, kw);
  if (st) return st;
  int64_t need = r->m->ne + n;
  if (need > r->ecap) {
    int64_t cap = need > 2 * r->ecap ? need : 2 * r->ecap;
    int32_t *e = vm_realloc(r->ctx, r->eref, (size_t)cap * sizeof *e);
    if (!e) return VM_ERR_NOMEM;
    r->eref = e;
    r->ecap = cap;
  }
  for (int64_t i = 0; i < n; i++) {
    int32_t v[VM_MAX_ELEM_VERTS];
    int64_t line = 0;
    for (int j = 0; j < k; j++) {
      if ((st = read_vertex_index(r, kw, &v[perm[type][j]]))) return st;
      if (!j) line = r->lx.line;
    }
    int64_t e = r->m->ne;
    if ((st = read_ref(r, &r->eref[e])) || (st = check_line(r, line, kw, i, k + 1)) ||
        (st = vm_mesh_add_element(r->m, type, v)))
      return st;
  }
  return VM_OK;
}

static int read_required(medit_rd *r) {
  if (!r->have_verts) return vm_lex_fail(&r->lx, "RequiredVertices before Vertices");
  int64_t n;
  int st = read_count(r, &n, 1, "RequiredVertices");
  for (int64_t i = 0; !st && i < n; i++) {
    int32_t v = 0;
    if (!(st = read_vertex_index(r, "RequiredVertices", &v))) r->m->vflag[v] = VM_VERTEX_FIXED;
  }
  return st;
}

static int read_skipped(medit_rd *r, size_t which) {
  const char *kw = skip_kw[which].kw;
  int nint = skip_kw[which].nint, nreal = skip_kw[which].nreal;
  if (nreal < 0) nreal = r->dim ? r->dim : 3;
  int64_t n;
  int st = read_count(r, &n, nint + nreal, kw);
  for (int64_t i = 0; !st && i < n; i++) {
    for (int j = 0; !st && j < nint; j++) {
      int64_t x;
      st = vm_lex_int(&r->lx, &x, kw);
    }
    for (int j = 0; !st && j < nreal; j++) {
      double x;
      st = vm_lex_double(&r->lx, &x, kw);
    }
  }
  if (!st) r->skipped[which] += n;
  return st;
}

static int read_keywords(medit_rd *r) {
  vm_lex *lx = &r->lx;
  int64_t x;
  int st = vm_lex_expect(lx, "MeshVersionFormatted");
  if (st) return st;
  if ((st = vm_lex_int(lx, &x, "MeshVersionFormatted"))) return st;
  if (x < 1 || x > 4)
    return vm_lex_fail(lx, "MeshVersionFormatted %lld is not 1 to 4", (long long)x);
  for (;;) {
    const char *s;
    size_t n;
    if (vm_lex_eof(lx)) return vm_lex_fail(lx, "no End keyword (truncated file?)");
    vm_lex_word(lx, &s, &n, "keyword");
    if (vm_tok_is(s, n, "End")) {
      for (size_t i = 0; i < sizeof skip_kw / sizeof skip_kw[0]; i++)
        if (r->skipped[i])
          vm_log(r->ctx, VM_LOG_WARN, "%s: ignored %lld %s", r->name, (long long)r->skipped[i],
                 skip_kw[i].kw);
      if (r->ignored_lines)
        vm_log(r->ctx, VM_LOG_WARN, "%s: ignored Identifier / Geometry (%lld lines)", r->name,
               (long long)r->ignored_lines);
      return VM_OK;
    }
    if (vm_tok_is(s, n, "Dimension")) {
      if ((st = vm_lex_int(lx, &x, "Dimension"))) return st;
      if (x != 2 && x != 3) return vm_lex_fail(lx, "Dimension %lld is not 2 or 3", (long long)x);
      if (r->have_verts && x != r->dim) return vm_lex_fail(lx, "Dimension changes after Vertices");
      r->dim = (int)x;
      continue;
    }
    if (vm_tok_is(s, n, "Vertices")) {
      if ((st = read_vertices(r))) return st;
      continue;
    }
    if (vm_tok_is(s, n, "RequiredVertices")) {
      if ((st = read_required(r))) return st;
      continue;
    }
    if (vm_tok_is(s, n, "Identifier") || vm_tok_is(s, n, "Geometry")) {
      const char *rest;
      size_t rn;
      if (vm_lex_eof(lx)) return vm_lex_fail(lx, "%.*s without a value", (int)n, s);
      vm_lex_line(lx, &rest, &rn);
      r->ignored_lines++;
      continue;
    }
    int done = 0;
    for (size_t i = 0; i < sizeof cell_kw / sizeof cell_kw[0] && !done; i++)
      if (vm_tok_is(s, n, cell_kw[i].kw)) {
        if ((st = read_cells(r, cell_kw[i].kw, cell_kw[i].type))) return st;
        done = 1;
      }
    if (!done && vm_tok_is(s, n, "Hexaedra")) {
      if ((st = read_cells(r, "Hexaedra", VM_HEX))) return st;
      done = 1;
    }
    for (size_t i = 0; i < sizeof skip_kw / sizeof skip_kw[0] && !done; i++)
      if (vm_tok_is(s, n, skip_kw[i].kw)) {
        if ((st = read_skipped(r, i))) return st;
        done = 1;
      }
    if (!done) return vm_lex_fail(lx, "unknown keyword '%.*s'", (int)(n > 40 ? 40 : n), s);
  }
}

int vm_read_medit(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  medit_rd r;
  memset(&r, 0, sizeof r);
  r.ctx = ctx;
  r.name = name;
  vm_lex_init(&r.lx, ctx, name, buf, len);
  r.lx.comment = '#';
  int st = vm_mesh_create(ctx, &r.m);
  if (!st) st = read_keywords(&r);
  if (!st) {
    vm_field *f;
    r.m->dim = r.dim ? r.dim : 3;
    if (!vm_mesh_find_field(r.m, MEDIT_REF, VM_FIELD_VERTEX))
      st = vm_mesh_add_field(r.m, MEDIT_REF, VM_FIELD_VERTEX, VM_FIELD_I32, 1, NULL);
    if (!st) st = vm_mesh_add_field(r.m, MEDIT_PHYS, VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f);
    if (!st && r.m->ne) memcpy(f->data, r.eref, (size_t)r.m->ne * sizeof *r.eref);
  }
  vm_free(ctx, r.eref);
  if (st < 0) {
    vm_mesh_destroy(&r.m);
    return vm_error_name_prefix(ctx, st, name);
  }
  *out = r.m;
  return VM_OK;
}

/* A reference field we can write: 1-component int. */
static const int32_t *ref_field(const vm_mesh *m, const char *name, int loc) {
  const vm_field *f = vm_mesh_find_field(m, name, loc);
  return f && f->type == VM_FIELD_I32 && f->ncomp == 1 ? f->data : NULL;
}

/* The references written: vertices' "medit:ref"; elements' "gmsh:physical",
 * else "medit:ref". */
static const int32_t *ref_data(const vm_mesh *m, int loc) {
  if (loc == VM_FIELD_VERTEX) return ref_field(m, MEDIT_REF, loc);
  const int32_t *r = ref_field(m, MEDIT_PHYS, loc);
  return r ? r : ref_field(m, MEDIT_REF, loc);
}

/* Logs each thing MEDIT cannot carry; returns nonzero if anything is lost. */
static int medit_losses(vm_ctx *ctx, const vm_mesh *m, const char *path, int *wdim) {
  int lossy = 0;
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *f = &m->fields[i];
    if (ref_data(m, f->location) == f->data) continue;
    vm_log(ctx, VM_LOG_WARN, "%s: %s field '%s' cannot be stored in MEDIT .mesh; dropped", path,
           f->location == VM_FIELD_VERTEX ? "vertex" : "element", f->name);
    lossy = 1;
  }
  for (int i = 0; i < m->nattr; i++) {
    const char *k = m->attrs[i].key, *tag = NULL;
    if (!strncmp(k, "gmsh:physical_name:", 19) && (tag = strchr(k + 19, ':')))
      vm_log(ctx, VM_LOG_WARN,
             "%s: the name '%s' of reference %s cannot be stored in MEDIT .mesh (the reference "
             "is kept); dropped",
             path, m->attrs[i].value, tag + 1);
    else
      vm_log(ctx, VM_LOG_WARN, "%s: attribute '%s' cannot be stored in MEDIT .mesh; dropped", path,
             k);
    lossy = 1;
  }
  int64_t nslip = 0;
  for (int64_t v = 0; v < m->nv; v++) nslip += m->vflag[v] == VM_VERTEX_SLIP || m->vsurf[v] != -1;
  if (nslip) {
    vm_log(ctx, VM_LOG_WARN, "%s: %lld slip vertices (flag and surface id) written as free", path,
           (long long)nslip);
    lossy = 1;
  }
  int grouped = 1, has3d = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (e && m->etype[e] < m->etype[e - 1]) grouped = 0;
    has3d |= vm_elem_dim(m->etype[e]) == 3;
  }
  if (!grouped) {
    vm_log(ctx, VM_LOG_WARN, "%s: element order changes: MEDIT groups elements by type", path);
    lossy = 1;
  }
  *wdim = m->dim;
  if (m->dim == 2 && has3d) {
    vm_log(ctx, VM_LOG_WARN, "%s: 2D mesh with volume elements written as Dimension 3", path);
    *wdim = 3;
    lossy = 1;
  }
  return lossy;
}

int vm_write_medit(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o; /* ASCII only: .meshb is not written */
  int wdim, lossy = medit_losses(ctx, m, path, &wdim);
  vm_outfile *of;
  int st = vm_outfile_open(ctx, path, &of);
  if (st) {
    if (st == VM_ERR_NOMEM) vm_error(ctx, st, "%s: out of memory", path);
    return st;
  }
  FILE *fp = vm_outfile_fp(of);
  const int32_t *vref = ref_data(m, VM_FIELD_VERTEX), *eref = ref_data(m, VM_FIELD_ELEMENT);
  fprintf(fp, "MeshVersionFormatted 2\n\nDimension %d\n\nVertices\n%lld\n", wdim, (long long)m->nv);
  for (int64_t v = 0; v < m->nv; v++) {
    const double *x = m->xyz + 3 * v;
    if (wdim == 2)
      fprintf(fp, "%.17g %.17g %d\n", x[0], x[1], vref ? (int)vref[v] : 0);
    else
      fprintf(fp, "%.17g %.17g %.17g %d\n", x[0], x[1], x[2], vref ? (int)vref[v] : 0);
  }
  for (size_t i = 0; i < sizeof cell_kw / sizeof cell_kw[0]; i++) {
    int t = cell_kw[i].type, k = vm_elem_nverts(t);
    int64_t n = 0;
    for (int64_t e = 0; e < m->ne; e++) n += m->etype[e] == t;
    if (!n) continue;
    fprintf(fp, "\n%s\n%lld\n", cell_kw[i].kw, (long long)n);
    for (int64_t e = 0; e < m->ne; e++) {
      if (m->etype[e] != t) continue;
      const int32_t *c = m->conn + m->eoff[e];
      for (int j = 0; j < k; j++) fprintf(fp, "%d ", c[perm[t][j]] + 1);
      fprintf(fp, "%d\n", eref ? (int)eref[e] : 0);
    }
  }
  int64_t nfix = 0;
  for (int64_t v = 0; v < m->nv; v++) nfix += m->vflag[v] == VM_VERTEX_FIXED;
  if (nfix) {
    fprintf(fp, "\nRequiredVertices\n%lld\n", (long long)nfix);
    for (int64_t v = 0; v < m->nv; v++)
      if (m->vflag[v] == VM_VERTEX_FIXED) fprintf(fp, "%lld\n", (long long)(v + 1));
  }
  fputs("\nEnd\n", fp);
  if ((st = vm_outfile_commit(&of))) return st;
  return lossy ? VM_WARN_LOSSY : VM_OK;
}
