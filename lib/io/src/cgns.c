/* lib/io/src/cgns.c: CGNS unstructured meshes through libcgns. Export:
 * one base, one zone, a section per cell type and per boundary family,
 * Family_t + BC_t per family, cell fields as a cell-centred FlowSolution_t
 * (a surface mesh: a base of cell dimension 2, sections TRI_3 / QUAD_4, no
 * families); import: the same and what varmesh/io.h lists. */
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "families_private.h"
#include "formats_private.h"

#ifdef VM_HAVE_CGNS
#include <cgnslib.h>

int vm_have_cgns(void) { return 1; }

/* A failed write: libcgns's message, and the system's reason when the
 * failure came from the disk (errno is cleared before each write step, so
 * a reason left by an earlier, harmless probe is not reported). */
static int cg_fail(vm_ctx *ctx, const char *path, const char *what) {
  int e = errno;
  int disk = e == ENOSPC || e == EFBIG || e == EDQUOT || e == EIO || e == EACCES || e == EROFS ||
             e == EPERM;
  return vm_error(ctx, VM_ERR_BACKEND, "%s: libcgns: %s: %s%s%s", path, what, cg_get_error(),
                  disk ? ": write failed: " : "", disk ? strerror(e) : "");
}

/* HDF5 closes every file it still has open in an atexit handler, and that
 * handler crashes (SIGSEGV in H5F__close_cb) on a file whose close failed,
 * e.g. on a full disk. varmesh closes its files itself, so the handler is
 * turned off before HDF5's first use: H5dont_atexit, looked up at run time
 * in the HDF5 that libcgns loaded (its headers are not needed). */
static void hdf5_no_atexit(void) {
  static int done;
  if (done) return;
  done = 1;
  void *self = dlopen(NULL, RTLD_NOW);
  if (!self) return;
  int (*dont)(void);
  *(void **)&dont = dlsym(self, "H5dont_atexit"); /* POSIX's idiom for a function */
  if (dont) dont();
  dlclose(self);
}

/* CGNS type and VTK-order -> CGNS-order (identical for linear cells). */
static CGNS_ENUMT(ElementType_t) cg_type(int t) {
  switch (t) {
  case VM_TRI: return CGNS_ENUMV(TRI_3);
  case VM_QUAD: return CGNS_ENUMV(QUAD_4);
  case VM_TET: return CGNS_ENUMV(TETRA_4);
  case VM_PYRAMID: return CGNS_ENUMV(PYRA_5);
  case VM_PRISM: return CGNS_ENUMV(PENTA_6);
  case VM_HEX: return CGNS_ENUMV(HEXA_8);
  default: return CGNS_ENUMV(ElementTypeNull);
  }
}

static int write_file(vm_ctx *ctx, const vm_mesh *m, const ex_groups *g, const char *tmp,
                      const char *path) {
  int fn, B, Z, st = VM_OK;
  hdf5_no_atexit();
  errno = 0;
  if (cg_open(tmp, CG_MODE_WRITE, &fn)) return cg_fail(ctx, path, "open");
  errno = 0;
  cgsize_t size[3] = {(cgsize_t)m->nv, (cgsize_t)g->ncell, 0};
  double *c = vm_alloc_array(ctx, (size_t)(m->nv ? m->nv : 1), sizeof *c);
  int32_t *order = vm_alloc_array(ctx, (size_t)(g->ncell ? g->ncell : 1), sizeof *order);
  cgsize_t *conn = vm_alloc_array(
      ctx, (size_t)(8 * (g->ncell > g->nface ? g->ncell : g->nface) + 1), sizeof *conn);
  double *cellval = vm_alloc_array(ctx, (size_t)(g->ncell ? g->ncell : 1), sizeof *cellval);
  if (!c || !order || !conn || !cellval) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int surface = ex_groups_surface(m);
  if (cg_base_write(fn, "varmesh", surface ? 2 : 3, 3, &B) ||
      cg_zone_write(fn, B, surface ? "surface" : "layers", size, CGNS_ENUMV(Unstructured), &Z)) {
    st = cg_fail(ctx, path, "zone");
    goto done;
  }
  static const char *const cname[3] = {"CoordinateX", "CoordinateY", "CoordinateZ"};
  for (int k = 0; k < 3; k++) {
    int C;
    for (int64_t v = 0; v < m->nv; v++) c[v] = m->xyz[3 * v + k];
    errno = 0;
    if (cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), cname[k], c, &C)) {
      st = cg_fail(ctx, path, "coordinates");
      goto done;
    }
  }
  /* cells grouped by type: elements 1..ncell in that order */
  cgsize_t next = 1;
  int64_t nord = 0;
  /* the cells are volume elements, or the triangles and quads of a surface */
  static const int vol_types[6] = {VM_TRI, VM_QUAD, VM_TET, VM_PYRAMID, VM_PRISM, VM_HEX};
  static const char *const vol_names[6] = {"Triangles", "Quadrilaterals", "Tetrahedra",
                                           "Pyramids",  "Prisms",         "Hexahedra"};
  for (int ti = 0; ti < 6; ti++) {
    int64_t n = 0, k = 0;
    for (int64_t i = 0; i < g->ncell; i++) {
      int32_t e = g->cell[i];
      if (m->etype[e] != vol_types[ti]) continue;
      order[nord++] = e;
      for (int64_t j = m->eoff[e]; j < m->eoff[e + 1]; j++) conn[k++] = (cgsize_t)m->conn[j] + 1;
      n++;
    }
    if (!n) continue;
    int S;
    errno = 0;
    if (cg_section_write(fn, B, Z, vol_names[ti], cg_type(vol_types[ti]), next, next + n - 1, 0,
                         conn, &S)) {
      st = cg_fail(ctx, path, "cell section");
      goto done;
    }
    next += n;
  }
  for (int f = 0; f < g->nfam; f++) {
    int64_t a = g->fbeg[f], b = g->fbeg[f + 1];
    if (a == b) continue;
    /* one section per face type within the family (TRI_3 first) */
    cgsize_t first = next;
    for (int nv = 3; nv <= 4; nv++) {
      int64_t n = 0, k = 0;
      for (int64_t i = a; i < b; i++) {
        if (g->fnv[i] != nv) continue;
        for (int j = 0; j < nv; j++) conn[k++] = (cgsize_t)g->fv[4 * i + j] + 1;
        n++;
      }
      if (!n) continue;
      char sname[64];
      snprintf(sname, sizeof sname, "%.40s_%s", g->name[f], nv == 3 ? "tri" : "quad");
      int S;
      errno = 0;
      if (cg_section_write(fn, B, Z, sname, nv == 3 ? CGNS_ENUMV(TRI_3) : CGNS_ENUMV(QUAD_4), next,
                           next + n - 1, 0, conn, &S)) {
        st = cg_fail(ctx, path, "face section");
        goto done;
      }
      next += n;
    }
    int F, FB, BC;
    /* "outer" (the top of a prism layer) is no far field: user defined */
    int kind = ex_family_kind(g->name[f]);
    CGNS_ENUMT(BCType_t)
    bt = kind == EX_FAM_WALL       ? CGNS_ENUMV(BCWall)
         : kind == EX_FAM_FARFIELD ? CGNS_ENUMV(BCFarfield)
         : kind == EX_FAM_SYMMETRY ? CGNS_ENUMV(BCSymmetryPlane)
                                   : CGNS_ENUMV(BCTypeUserDefined);
    cgsize_t range[2] = {first, next - 1};
    errno = 0;
    if (cg_family_write(fn, B, g->name[f], &F) || cg_fambc_write(fn, B, F, "FamBC", bt, &FB) ||
        cg_boco_write(fn, B, Z, g->name[f], CGNS_ENUMV(FamilySpecified), CGNS_ENUMV(PointRange), 2,
                      range, &BC) ||
        cg_boco_gridlocation_write(fn, B, Z, BC, CGNS_ENUMV(FaceCenter)) ||
        cg_goto(fn, B, "Zone_t", Z, "ZoneBC_t", 1, "BC_t", BC, "end") ||
        cg_famname_write(g->name[f])) {
      st = cg_fail(ctx, path, "boundary family");
      goto done;
    }
  }
  /* cell fields */
  int S = 0;
  for (int i = 0; i < m->nfield; i++) {
    const vm_field *fl = &m->fields[i];
    if (fl->location != VM_FIELD_ELEMENT || fl->ncomp != 1 || !strncmp(fl->name, "gmsh:", 5))
      continue; /* reported by ex_groups_lossy */
    if (!S && cg_sol_write(fn, B, Z, "CellData", CGNS_ENUMV(CellCenter), &S)) {
      st = cg_fail(ctx, path, "solution");
      goto done;
    }
    int F, r;
    errno = 0;
    if (fl->type == VM_FIELD_F64) {
      double *v = cellval;
      for (int64_t k = 0; k < g->ncell; k++) v[k] = ((const double *)fl->data)[order[k]];
      r = cg_field_write(fn, B, Z, S, CGNS_ENUMV(RealDouble), fl->name, v, &F);
    } else {
      int *v = (int *)conn;
      for (int64_t k = 0; k < g->ncell; k++) v[k] = ((const int32_t *)fl->data)[order[k]];
      r = cg_field_write(fn, B, Z, S, CGNS_ENUMV(Integer), fl->name, v, &F);
    }
    if (r) {
      st = cg_fail(ctx, path, "field");
      goto done;
    }
  }
done:
  vm_free(ctx, c);
  vm_free(ctx, cellval);
  vm_free(ctx, order);
  vm_free(ctx, conn);
  errno = 0;
  if (cg_close(fn) && st == VM_OK) st = cg_fail(ctx, path, "close");
  return st;
}

int vm_write_cgns(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  if (!m || !path) return vm_error(ctx, VM_ERR_ARG, "vm_write_cgns: NULL argument");
  int st = ex_groups_check(ctx, m, path, "CGNS");
  if (st) return st;
  if (m->nv > 2147483647 / 8) return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: mesh too large", path);
  ex_groups g;
  st = ex_groups_build(ctx, m, &g);
  if (st) {
    ex_groups_free(ctx, &g);
    return st < 0 ? st : VM_ERR_ARG;
  }
  char tmp[4096];
  char *tn = vm_io_temp_name(ctx, path, "", ".tmp.");
  if (!tn || strlen(tn) >= sizeof tmp) {
    vm_free(ctx, tn);
    ex_groups_free(ctx, &g);
    return tn ? vm_error(ctx, VM_ERR_ARG, "%s: path too long", path) : VM_ERR_NOMEM;
  }
  memcpy(tmp, tn, strlen(tn) + 1);
  vm_free(ctx, tn);
  vm_io_tmp_register(tmp);
  st = write_file(ctx, m, &g, tmp, path);
  ex_groups_free(ctx, &g);
  if (st) {
    vm_io_tmp_unregister(tmp);
    remove(tmp);
    return st;
  }
  if (rename(tmp, path)) {
    int e = errno;
    vm_io_tmp_unregister(tmp);
    remove(tmp);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot rename the temporary file: %s", path, strerror(e));
  }
  vm_io_tmp_unregister(tmp);
  return ex_groups_lossy(ctx, m, path, "CGNS", 1) ? VM_WARN_LOSSY : VM_OK;
}

/* Reading. libcgns opens files by path only: the buffer goes to a private
 * temporary file (mkstemp in $TMPDIR or /tmp), which is unlinked as soon as
 * cg_open has it open, so nothing is left behind on any path. */

/* libcgns prints warnings to stdout unless a handler is set; the library
 * never prints, so they are discarded (errors stay in cg_get_error). */
static void cg_quiet(int is_error, char *msg) {
  (void)is_error;
  (void)msg;
}

typedef struct {
  vm_ctx *ctx;
  const char *name;
  size_t len;
  int fn;
  int cdim; /* the base's cell dimension: 3, or 2 for a surface mesh */
  vm_mesh *m;
  int nsec;
  struct csec {
    int S;
    CGNS_ENUMT(ElementType_t) type;
    cgsize_t start, end;
    int64_t moff; /* offset of its first element in emap */
    char name[33];
  } * sec;
  int64_t nid;   /* element ids covered by sections */
  int32_t *emap; /* section element -> vm element, -1 if dropped */
  int32_t *tag;  /* per vm element: family tag (0 none) */
  int ntag;
  char (*tname)[33];
  int64_t nskip; /* NODE / BAR_2 elements dropped */
} cg_rd;

/* A libcgns failure on this input: one line, "name: what: libcgns message". */
static int cg_rfail(cg_rd *r, const char *what) {
  char msg[256];
  snprintf(msg, sizeof msg, "%s", cg_get_error());
  for (char *p = msg; *p; p++)
    if (*p == '\n' || *p == '\r') *p = ' ';
  return vm_error(r->ctx, VM_ERR_FORMAT, "%s: %s: libcgns: %s", r->name, what, msg);
}

/* Refuse arrays claiming more entries than the file has bytes (an input
 * that cannot hold them: bounded memory for any file). */
static int cg_bound(cg_rd *r, int64_t n, const char *what) {
  if (n < 0 || (uint64_t)n > (uint64_t)r->len)
    return vm_error(r->ctx, VM_ERR_FORMAT, "%s: %s: %lld entries cannot fit in a %zu-byte file",
                    r->name, what, (long long)n, r->len);
  return VM_OK;
}

static int vm_type_of(CGNS_ENUMT(ElementType_t) t) {
  switch (t) {
  case CGNS_ENUMV(TRI_3): return VM_TRI;
  case CGNS_ENUMV(QUAD_4): return VM_QUAD;
  case CGNS_ENUMV(TETRA_4): return VM_TET;
  case CGNS_ENUMV(PYRA_5): return VM_PYRAMID;
  case CGNS_ENUMV(PENTA_6): return VM_PRISM;
  case CGNS_ENUMV(HEXA_8): return VM_HEX;
  case CGNS_ENUMV(NODE): return -2;
  case CGNS_ENUMV(BAR_2): return -3;
  default: return -1;
  }
}

static const char *type_name(CGNS_ENUMT(ElementType_t) t) {
  return t >= 0 && t < NofValidElementTypes ? ElementTypeName[t] : "?";
}

static int cmp_sec(const void *a, const void *b) {
  const struct csec *x = a, *y = b;
  return (x->start > y->start) - (x->start < y->start);
}

/* vm element of a CGNS element id, -1 if none (dropped or not in a section). */
static int32_t cg_elem(const cg_rd *r, int64_t id) {
  int lo = 0, hi = r->nsec - 1;
  while (lo <= hi) {
    int mid = (lo + hi) / 2;
    if (id < r->sec[mid].start)
      hi = mid - 1;
    else if (id > r->sec[mid].end)
      lo = mid + 1;
    else
      return r->emap[r->sec[mid].moff + (id - r->sec[mid].start)];
  }
  return -1;
}

static int cg_coords(cg_rd *r, int64_t nv) {
  int st;
  if ((st = cg_bound(r, 3 * nv, "coordinates")) || (st = vm_mesh_set_vertices(r->m, nv))) return st;
  if (!nv) return VM_OK;
  double *c = vm_alloc_array(r->ctx, (size_t)nv, sizeof *c);
  if (!c) return VM_ERR_NOMEM;
  static const char *const cname[3] = {"CoordinateX", "CoordinateY", "CoordinateZ"};
  cgsize_t lo = 1, hi = (cgsize_t)nv;
  for (int k = 0; k < 3 && !st; k++) {
    if (cg_coord_read(r->fn, 1, 1, cname[k], CGNS_ENUMV(RealDouble), &lo, &hi, c)) {
      st = cg_rfail(r, cname[k]);
      break;
    }
    for (int64_t v = 0; v < nv; v++) {
      if (!isfinite(c[v])) {
        st = vm_error(r->ctx, VM_ERR_FORMAT, "%s: %s of vertex %lld is not finite", r->name,
                      cname[k], (long long)v + 1);
        break;
      }
      r->m->xyz[3 * v + k] = c[v];
    }
  }
  vm_free(r->ctx, c);
  return st;
}

/* Every section: cells and faces become vm elements in element-id order. */
static int cg_sections(cg_rd *r) {
  int n, st = VM_OK;
  if (cg_nsections(r->fn, 1, 1, &n)) return cg_rfail(r, "sections");
  if ((st = cg_bound(r, n, "sections"))) return st;
  r->sec = vm_calloc(r->ctx, (size_t)(n ? n : 1), sizeof *r->sec);
  if (!r->sec) return VM_ERR_NOMEM;
  r->nsec = n;
  for (int i = 0; i < n; i++) {
    struct csec *s = &r->sec[i];
    int nb, pf;
    s->S = i + 1;
    if (cg_section_read(r->fn, 1, 1, s->S, s->name, &s->type, &s->start, &s->end, &nb, &pf))
      return cg_rfail(r, "section");
    s->name[32] = 0;
    if (s->start < 1 || s->end < s->start)
      return vm_error(r->ctx, VM_ERR_FORMAT, "%s: section '%s': element range %lld..%lld", r->name,
                      s->name, (long long)s->start, (long long)s->end);
    if (s->type != CGNS_ENUMV(MIXED) && vm_type_of(s->type) == -1)
      return vm_error(r->ctx, VM_ERR_UNSUPPORTED,
                      "%s: section '%s': element type %s is not "
                      "supported (linear TRI_3, QUAD_4, TETRA_4, PYRA_5, PENTA_6, HEXA_8, MIXED)",
                      r->name, s->name, type_name(s->type));
    if ((st = cg_bound(r, (int64_t)s->end - s->start + 1, "section elements"))) return st;
    s->moff = r->nid;
    r->nid += (int64_t)s->end - s->start + 1;
    if ((st = cg_bound(r, r->nid, "elements"))) return st;
  }
  qsort(r->sec, (size_t)n, sizeof *r->sec, cmp_sec);
  for (int i = 1; i < n; i++)
    if (r->sec[i].start <= r->sec[i - 1].end)
      return vm_error(r->ctx, VM_ERR_FORMAT, "%s: sections '%s' and '%s' overlap", r->name,
                      r->sec[i - 1].name, r->sec[i].name);
  r->emap = vm_alloc_array(r->ctx, (size_t)(r->nid ? r->nid : 1), sizeof *r->emap);
  if (!r->emap) return VM_ERR_NOMEM;
  for (int i = 0; i < n && !st; i++) {
    struct csec *s = &r->sec[i];
    int nb, pf;
    char nm[33];
    CGNS_ENUMT(ElementType_t) t;
    cgsize_t a, b, size;
    /* sorted: re-read the flag of this section */
    if (cg_section_read(r->fn, 1, 1, s->S, nm, &t, &a, &b, &nb, &pf)) return cg_rfail(r, "section");
    if (cg_ElementDataSize(r->fn, 1, 1, s->S, &size)) return cg_rfail(r, "section size");
    int64_t ne = (int64_t)s->end - s->start + 1;
    int npe = 0;
    if (s->type != CGNS_ENUMV(MIXED)) cg_npe(s->type, &npe);
    if ((st = cg_bound(r, size, "connectivity"))) return st;
    if (s->type == CGNS_ENUMV(MIXED) ? size < 2 * ne : size != ne * npe)
      return vm_error(r->ctx, VM_ERR_FORMAT,
                      "%s: section '%s': %lld connectivity entries for "
                      "%lld elements",
                      r->name, s->name, (long long)size, (long long)ne);
    int mixed = s->type == CGNS_ENUMV(MIXED);
    cgsize_t *conn = vm_alloc_array(r->ctx, (size_t)(size ? size : 1), sizeof *conn);
    cgsize_t *par = pf ? vm_alloc_array(r->ctx, (size_t)(4 * ne), sizeof *par) : NULL;
    cgsize_t *off = mixed ? vm_alloc_array(r->ctx, (size_t)ne + 1, sizeof *off) : NULL;
    if (!conn || (pf && !par) || (mixed && !off)) {
      vm_free(r->ctx, conn);
      vm_free(r->ctx, par);
      vm_free(r->ctx, off);
      return VM_ERR_NOMEM;
    }
    /* MIXED sections carry offsets (ElementStartOffset) since CGNS 3.4 */
    if (mixed ? cg_poly_elements_read(r->fn, 1, 1, s->S, conn, off, par)
              : cg_elements_read(r->fn, 1, 1, s->S, conn, par))
      st = cg_rfail(r, "elements");
    int64_t k = 0;
    for (int64_t e = 0; e < ne && !st; e++) {
      CGNS_ENUMT(ElementType_t) et = s->type;
      if (mixed) {
        npe = 0;
        int typed = k < size && off[e] == k;
        et = typed ? (CGNS_ENUMT(ElementType_t))conn[k++] : CGNS_ENUMV(ElementTypeNull);
        if (!typed || vm_type_of(et) == -1 || cg_npe(et, &npe) || npe < 1 || k + npe > size ||
            off[e + 1] != k + npe) {
          st = vm_error(r->ctx, VM_ERR_FORMAT,
                        "%s: section '%s': element %lld: type %d is "
                        "not supported or its nodes disagree with the offsets",
                        r->name, s->name, (long long)(s->start + e), (int)et);
          break;
        }
      }
      int t = vm_type_of(et);
      if (t >= 0 && vm_elem_dim(t) > r->cdim) {
        st = vm_error(r->ctx, VM_ERR_FORMAT,
                      "%s: section '%s': element %lld: a %s in a base of cell dimension %d",
                      r->name, s->name, (long long)(s->start + e), type_name(et), r->cdim);
        break;
      }
      int32_t v[VM_MAX_ELEM_VERTS];
      for (int j = 0; j < npe; j++) {
        cgsize_t x = conn[k++];
        if (x < 1 || x > r->m->nv) {
          st = vm_error(r->ctx, VM_ERR_FORMAT,
                        "%s: section '%s': element %lld: node %lld is "
                        "not in 1..%lld",
                        r->name, s->name, (long long)(s->start + e), (long long)x,
                        (long long)r->m->nv);
          break;
        }
        if (j < VM_MAX_ELEM_VERTS) v[j] = (int32_t)(x - 1);
      }
      if (st) break;
      if (t < 0) {
        r->emap[s->moff + e] = -1;
        r->nskip++;
        continue;
      }
      r->emap[s->moff + e] = (int32_t)r->m->ne;
      st = vm_mesh_add_element(r->m, t, v);
    }
    vm_free(r->ctx, conn);
    vm_free(r->ctx, par);
    vm_free(r->ctx, off);
  }
  return st;
}

static int find_tag(cg_rd *r, const char *nm) {
  for (int i = 0; i < r->ntag; i++)
    if (!strcmp(r->tname[i], nm)) return i + 1;
  snprintf(r->tname[r->ntag], sizeof r->tname[0], "%s", nm);
  return ++r->ntag;
}

/* Boundary conditions on faces: their family (FamilyName, else the BC's
 * name) becomes a tag, in order of first appearance. */
static int cg_bcs(cg_rd *r) {
  int nbc, st = VM_OK;
  if (cg_nbocos(r->fn, 1, 1, &nbc)) return cg_rfail(r, "boundary conditions");
  if ((st = cg_bound(r, nbc, "boundary conditions"))) return st;
  r->tag = vm_calloc(r->ctx, (size_t)(r->m->ne ? r->m->ne : 1), sizeof *r->tag);
  r->tname = vm_calloc(r->ctx, (size_t)(nbc + r->nsec + 1), sizeof *r->tname);
  if (!r->tag || !r->tname) return VM_ERR_NOMEM;
  int64_t nvert_bc = 0, nbad = 0, nclash = 0;
  for (int bc = 1; bc <= nbc && !st; bc++) {
    char bname[33], fam[33];
    CGNS_ENUMT(BCType_t) bt;
    CGNS_ENUMT(PointSetType_t) pt;
    CGNS_ENUMT(GridLocation_t) loc;
    CGNS_ENUMT(DataType_t) ndt;
    cgsize_t np, nls;
    int nidx[3], nds;
    if (cg_boco_info(r->fn, 1, 1, bc, bname, &bt, &pt, &np, nidx, &nls, &ndt, &nds) ||
        cg_boco_gridlocation_read(r->fn, 1, 1, bc, &loc))
      return cg_rfail(r, "boundary condition");
    bname[32] = 0;
    int range = pt == CGNS_ENUMV(PointRange) || pt == CGNS_ENUMV(ElementRange);
    int list = pt == CGNS_ENUMV(PointList) || pt == CGNS_ENUMV(ElementList);
    int elems = pt == CGNS_ENUMV(ElementRange) || pt == CGNS_ENUMV(ElementList) ||
                ((range || list) && loc != CGNS_ENUMV(Vertex));
    if (!elems) {
      nvert_bc++;
      continue;
    }
    if ((st = cg_bound(r, np, "boundary condition points"))) return st;
    if (range && np != 2)
      return vm_error(r->ctx, VM_ERR_FORMAT,
                      "%s: boundary condition '%s': a range of %lld "
                      "values",
                      r->name, bname, (long long)np);
    cgsize_t *p = vm_alloc_array(r->ctx, (size_t)(np ? np : 1), sizeof *p);
    if (!p) return VM_ERR_NOMEM;
    if (np && cg_boco_read(r->fn, 1, 1, bc, p, NULL)) {
      vm_free(r->ctx, p);
      return cg_rfail(r, "boundary condition points");
    }
    int have_fam = !cg_goto(r->fn, 1, "Zone_t", 1, "ZoneBC_t", 1, "BC_t", bc, "end") &&
                   cg_famname_read(fam) == CG_OK;
    if (have_fam) fam[32] = 0;
    int tag = find_tag(r, have_fam && fam[0] ? fam : bname);
    int64_t a = range ? p[0] : 0, b = range ? p[1] : np - 1;
    if (range && (b < a || b - a >= r->nid)) {
      st = vm_error(r->ctx, VM_ERR_FORMAT,
                    "%s: boundary condition '%s': element range "
                    "%lld..%lld is not inside the %lld elements",
                    r->name, bname, (long long)a, (long long)b, (long long)r->nid);
      vm_free(r->ctx, p);
      return st;
    }
    for (int64_t i = a; i <= b; i++) {
      int32_t e = cg_elem(r, range ? i : p[i]);
      if (e < 0 || vm_elem_dim(r->m->etype[e]) != 2) {
        nbad++;
        continue;
      }
      if (r->tag[e])
        nclash += r->tag[e] != tag;
      else
        r->tag[e] = tag;
    }
    vm_free(r->ctx, p);
  }
  if (nvert_bc)
    vm_log(r->ctx, VM_LOG_WARN, "%s: %lld boundary conditions given on vertices ignored", r->name,
           (long long)nvert_bc);
  if (nbad)
    vm_log(r->ctx, VM_LOG_WARN, "%s: %lld boundary-condition elements are not faces; ignored",
           r->name, (long long)nbad);
  if (nclash)
    vm_log(r->ctx, VM_LOG_WARN, "%s: %lld faces in two boundary conditions keep the first", r->name,
           (long long)nclash);
  /* faces in no boundary condition: one family per section, named after it */
  for (int i = 0; i < r->nsec; i++) {
    const struct csec *s = &r->sec[i];
    int tag = 0;
    for (int64_t e = 0; e <= (int64_t)s->end - s->start; e++) {
      int32_t v = r->emap[s->moff + e];
      if (v < 0 || vm_elem_dim(r->m->etype[v]) != 2 || r->tag[v]) continue;
      if (!tag) tag = find_tag(r, s->name);
      r->tag[v] = tag;
    }
  }
  return st;
}

/* Vertex and cell-centred solutions as vertex and element fields. */
static int cg_fields(cg_rd *r, int64_t ncell) {
  int nsol, st = VM_OK;
  if (cg_nsols(r->fn, 1, 1, &nsol)) return cg_rfail(r, "solutions");
  int64_t ncell_read = 0, nskipped = 0;
  for (int64_t e = 0; e < r->m->ne; e++) ncell_read += vm_elem_dim(r->m->etype[e]) == r->cdim;
  for (int S = 1; S <= nsol && !st; S++) {
    char sname[33];
    CGNS_ENUMT(GridLocation_t) loc;
    int nf, ddim;
    cgsize_t dims[3];
    if (cg_sol_info(r->fn, 1, 1, S, sname, &loc) || cg_nfields(r->fn, 1, 1, S, &nf) ||
        cg_sol_size(r->fn, 1, 1, S, &ddim, dims))
      return cg_rfail(r, "solution");
    /* libcgns finds each field by name among all of its solution's
     * (cg_field_read): many fields would cost their square */
    if ((int64_t)r->m->nfield + nf > VM_IO_MAX_ARRAYS)
      return vm_error(r->ctx, VM_ERR_FORMAT,
                      "%s: solution '%.32s': more than %d fields (the reader's ceiling)", r->name,
                      sname, VM_IO_MAX_ARRAYS);
    int at_cells = loc == CGNS_ENUMV(CellCenter);
    int64_t n = at_cells ? ncell : r->m->nv;
    if ((loc != CGNS_ENUMV(Vertex) && !at_cells) || ddim != 1 || dims[0] != n ||
        (at_cells && ncell != ncell_read)) {
      nskipped += nf;
      continue;
    }
    for (int F = 1; F <= nf && !st; F++) {
      CGNS_ENUMT(DataType_t) dt;
      char fname[33];
      if (cg_field_info(r->fn, 1, 1, S, F, &dt, fname)) return cg_rfail(r, "field");
      fname[32] = 0;
      int isint = dt == CGNS_ENUMV(Integer);
      if ((!isint && dt != CGNS_ENUMV(RealSingle) && dt != CGNS_ENUMV(RealDouble)) ||
          !strncmp(fname, "gmsh:", 5) || !n) {
        nskipped++;
        continue;
      }
      void *buf = vm_alloc_array(r->ctx, (size_t)n, isint ? sizeof(int) : sizeof(double));
      if (!buf) return VM_ERR_NOMEM;
      cgsize_t lo = 1, hi = (cgsize_t)n;
      vm_field *f;
      if (cg_field_read(r->fn, 1, 1, S, fname, isint ? CGNS_ENUMV(Integer) : CGNS_ENUMV(RealDouble),
                        &lo, &hi, buf))
        st = cg_rfail(r, "field");
      else
        st = vm_mesh_add_field(r->m, fname, at_cells ? VM_FIELD_ELEMENT : VM_FIELD_VERTEX,
                               isint ? VM_FIELD_I32 : VM_FIELD_F64, 1, &f);
      /* cell value k belongs to the k-th cell in element-id order */
      for (int64_t e = 0, k = 0; !st && k < n; e++) {
        if (at_cells && vm_elem_dim(r->m->etype[e]) != r->cdim) continue;
        if (isint)
          ((int32_t *)f->data)[e] = ((const int *)buf)[k];
        else
          ((double *)f->data)[e] = ((const double *)buf)[k];
        k++;
      }
      vm_free(r->ctx, buf);
    }
  }
  if (!st && nskipped)
    vm_log(r->ctx, VM_LOG_WARN, "%s: %lld solution fields ignored (location, size or type)",
           r->name, (long long)nskipped);
  return st;
}

static int cg_parse(cg_rd *r) {
  int nb, nz, cdim, pdim, st;
  char nm[33];
  CGNS_ENUMT(ZoneType_t) zt;
  cgsize_t size[3];
  if (cg_nbases(r->fn, &nb)) return cg_rfail(r, "bases");
  if (nb != 1)
    return vm_error(r->ctx, nb ? VM_ERR_UNSUPPORTED : VM_ERR_FORMAT,
                    "%s: %d bases (one base with one zone can be read)", r->name, nb);
  if (cg_base_read(r->fn, 1, nm, &cdim, &pdim)) return cg_rfail(r, "base");
  if ((cdim != 3 && cdim != 2) || pdim != 3)
    return vm_error(r->ctx, VM_ERR_UNSUPPORTED,
                    "%s: base of cell dimension %d in %d "
                    "dimensions (3 or 2 in 3 can be read)",
                    r->name, cdim, pdim);
  r->cdim = cdim;
  if (cg_nzones(r->fn, 1, &nz)) return cg_rfail(r, "zones");
  if (nz != 1)
    return vm_error(r->ctx, nz ? VM_ERR_UNSUPPORTED : VM_ERR_FORMAT,
                    "%s: %d zones (multi-zone CGNS files are not supported)", r->name, nz);
  if (cg_zone_type(r->fn, 1, 1, &zt) || cg_zone_read(r->fn, 1, 1, nm, size))
    return cg_rfail(r, "zone");
  if (zt != CGNS_ENUMV(Unstructured))
    return vm_error(r->ctx, VM_ERR_UNSUPPORTED, "%s: zone '%s' is not unstructured", r->name, nm);
  if ((st = cg_coords(r, size[0])) || (st = cg_sections(r))) return st;
  if (cdim == 2) {
    /* a surface mesh: its boundary conditions are on edges, which are not kept */
    int nbc;
    if (cg_nbocos(r->fn, 1, 1, &nbc)) return cg_rfail(r, "boundary conditions");
    if (nbc)
      vm_log(r->ctx, VM_LOG_WARN, "%s: %d boundary conditions of a surface mesh ignored", r->name,
             nbc);
    if (r->nskip)
      vm_log(r->ctx, VM_LOG_WARN, "%s: %lld NODE and BAR_2 elements dropped", r->name,
             (long long)r->nskip);
    return cg_fields(r, size[1]);
  }
  if ((st = cg_bcs(r))) return st;
  vm_field *f;
  if ((st = vm_mesh_add_field(r->m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &f)))
    return st;
  if (r->m->ne) memcpy(f->data, r->tag, (size_t)r->m->ne * sizeof *r->tag);
  for (int i = 0; i < r->ntag; i++) {
    char key[64];
    snprintf(key, sizeof key, "gmsh:physical_name:2:%d", i + 1);
    if ((st = vm_mesh_set_attr(r->m, key, r->tname[i]))) return st;
  }
  if (r->nskip)
    vm_log(r->ctx, VM_LOG_WARN, "%s: %lld NODE and BAR_2 elements dropped", r->name,
           (long long)r->nskip);
  return cg_fields(r, size[1]);
}

int vm_read_cgns(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  *out = NULL;
  const char *dir = getenv("TMPDIR");
  char tmp[4096];
  if (!dir || !*dir) dir = "/tmp";
  if ((size_t)snprintf(tmp, sizeof tmp, "%s/varmesh-cgns-XXXXXX", dir) >= sizeof tmp)
    return vm_error(ctx, VM_ERR_IO, "%s: TMPDIR is too long", name);
  int fd = mkstemp(tmp);
  if (fd < 0)
    return vm_error(ctx, VM_ERR_IO, "%s: cannot create a temporary file in %s: %s", name, dir,
                    strerror(errno));
  size_t done = 0;
  while (done < len) {
    ssize_t w = write(fd, buf + done, len - done);
    if (w <= 0) break;
    done += (size_t)w;
  }
  int e = done != len ? (errno ? errno : EIO) : 0;
  if (close(fd) != 0 && !e) e = errno ? errno : EIO;
  if (e) {
    remove(tmp);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot write the temporary file %s: %s", name, tmp,
                    strerror(e));
  }
  cg_rd r;
  memset(&r, 0, sizeof r);
  r.ctx = ctx;
  r.name = name;
  r.len = len;
  /* cg_configure takes the handler as a void * (POSIX: same size and representation) */
  void (*handler)(int, char *) = cg_quiet;
  void *hp;
  memcpy(&hp, &handler, sizeof hp);
  cg_configure(CG_CONFIG_ERROR, hp);
  hdf5_no_atexit();
  r.fn = -1;
  int st = cg_open(tmp, CG_MODE_READ, &r.fn);
  remove(tmp); /* the open file stays readable */
  if (st) {
    /* libcgns keeps the file open when cg_open fails while reading its
     * tree (e.g. Elements_t in a structured zone): one descriptor lost per
     * bad file, and after a few hundred "Too many files opened" for every
     * file (found by test/fuzz/fuzz_cgns.c). It has given the number. */
    st = cg_rfail(&r, "not a readable CGNS file");
    if (r.fn >= 0) cg_close(r.fn);
    return st;
  }
  st = vm_mesh_create(ctx, &r.m);
  if (!st) st = cg_parse(&r);
  cg_close(r.fn);
  vm_free(ctx, r.sec);
  vm_free(ctx, r.emap);
  vm_free(ctx, r.tag);
  vm_free(ctx, r.tname);
  if (st < 0) {
    vm_mesh_destroy(&r.m);
    return vm_error_name_prefix(ctx, st, name);
  }
  *out = r.m;
  return VM_OK;
}

#else

int vm_have_cgns(void) { return 0; }

int vm_write_cgns(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  (void)m;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: this build has no CGNS support (libcgns)",
                  path ? path : "(null)");
}

int vm_read_cgns(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, vm_mesh **out) {
  (void)buf;
  (void)len;
  *out = NULL;
  return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: this build has no CGNS support (libcgns)", name);
}

#endif
