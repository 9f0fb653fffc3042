/* lib/io/src/cgns.c: CGNS unstructured export through libcgns: one
 * base, one zone, a section per cell type and per boundary family, Family_t
 * + BC_t per family, cell fields as a cell-centred FlowSolution_t. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "families_private.h"
#include "formats_private.h"

#ifdef VM_HAVE_CGNS
#include <cgnslib.h>

int vm_have_cgns(void) { return 1; }

static int cg_fail(vm_ctx *ctx, const char *path, const char *what) {
  return vm_error(ctx, VM_ERR_BACKEND, "%s: libcgns: %s: %s", path, what, cg_get_error());
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
                      const char *path, int *lossy) {
  int fn, B, Z, st = VM_OK;
  if (cg_open(tmp, CG_MODE_WRITE, &fn)) return cg_fail(ctx, path, "open");
  cgsize_t size[3] = {(cgsize_t)m->nv, (cgsize_t)g->ncell, 0};
  double *c = vm_alloc_array(ctx, (size_t)(m->nv ? m->nv : 1), sizeof *c);
  int32_t *order = vm_alloc_array(ctx, (size_t)(g->ncell ? g->ncell : 1), sizeof *order);
  cgsize_t *conn = vm_alloc_array(ctx, (size_t)(8 * (g->ncell > g->nface ? g->ncell : g->nface) + 1),
                                  sizeof *conn);
  if (!c || !order || !conn) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  if (cg_base_write(fn, "varmesh", 3, 3, &B) ||
      cg_zone_write(fn, B, "layers", size, CGNS_ENUMV(Unstructured), &Z)) {
    st = cg_fail(ctx, path, "zone");
    goto done;
  }
  static const char *const cname[3] = {"CoordinateX", "CoordinateY", "CoordinateZ"};
  for (int k = 0; k < 3; k++) {
    int C;
    for (int64_t v = 0; v < m->nv; v++) c[v] = m->xyz[3 * v + k];
    if (cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), cname[k], c, &C)) {
      st = cg_fail(ctx, path, "coordinates");
      goto done;
    }
  }
  /* cells grouped by type: elements 1..ncell in that order */
  cgsize_t next = 1;
  int64_t nord = 0;
  static const int vol_types[4] = {VM_TET, VM_PYRAMID, VM_PRISM, VM_HEX};
  static const char *const vol_names[4] = {"Tetrahedra", "Pyramids", "Prisms", "Hexahedra"};
  for (int ti = 0; ti < 4; ti++) {
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
      if (cg_section_write(fn, B, Z, sname, nv == 3 ? CGNS_ENUMV(TRI_3) : CGNS_ENUMV(QUAD_4),
                           next, next + n - 1, 0, conn, &S)) {
        st = cg_fail(ctx, path, "face section");
        goto done;
      }
      next += n;
    }
    int F, FB, BC;
    CGNS_ENUMT(BCType_t) bt = !strcmp(g->name[f], "wall")    ? CGNS_ENUMV(BCWall)
                              : !strcmp(g->name[f], "outer") ? CGNS_ENUMV(BCFarfield)
                                                             : CGNS_ENUMV(BCTypeUserDefined);
    cgsize_t range[2] = {first, next - 1};
    if (cg_family_write(fn, B, g->name[f], &F) || cg_fambc_write(fn, B, F, "FamBC", bt, &FB) ||
        cg_boco_write(fn, B, Z, g->name[f], CGNS_ENUMV(FamilySpecified), CGNS_ENUMV(PointRange),
                      2, range, &BC) ||
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
    if (fl->location != VM_FIELD_ELEMENT) {
      *lossy = 1;
      continue;
    }
    if (fl->ncomp != 1 || !strncmp(fl->name, "gmsh:", 5)) continue;
    if (!S && cg_sol_write(fn, B, Z, "CellData", CGNS_ENUMV(CellCenter), &S)) {
      st = cg_fail(ctx, path, "solution");
      goto done;
    }
    int F, r;
    if (fl->type == VM_FIELD_F64) {
      double *v = (double *)c;
      if (g->ncell > m->nv) {
        *lossy = 1;
        continue;
      }
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
  vm_free(ctx, order);
  vm_free(ctx, conn);
  if (cg_close(fn) && st == VM_OK) st = cg_fail(ctx, path, "close");
  return st;
}

int vm_write_cgns(vm_ctx *ctx, const vm_mesh *m, const char *path, const vm_write_opts *o) {
  (void)o;
  if (!m || !path) return vm_error(ctx, VM_ERR_ARG, "vm_write_cgns: NULL argument");
  if (m->dim != 3) return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: CGNS export needs a 3D mesh", path);
  if (m->nv > 2147483647 / 8) return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: mesh too large", path);
  ex_groups g;
  int st = ex_groups_build(ctx, m, &g);
  if (st) {
    ex_groups_free(ctx, &g);
    return st < 0 ? st : VM_ERR_ARG;
  }
  char tmp[4096];
  if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid()) >= sizeof tmp) {
    ex_groups_free(ctx, &g);
    return vm_error(ctx, VM_ERR_ARG, "%s: path too long", path);
  }
  int lossy = m->nattr > 0;
  st = write_file(ctx, m, &g, tmp, path, &lossy);
  ex_groups_free(ctx, &g);
  if (st) {
    remove(tmp);
    return st;
  }
  if (rename(tmp, path)) {
    remove(tmp);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot rename the temporary file", path);
  }
  if (lossy) {
    vm_log(ctx, VM_LOG_WARN, "%s: vertex fields and attributes are not stored in CGNS", path);
    return VM_WARN_LOSSY;
  }
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

#endif
