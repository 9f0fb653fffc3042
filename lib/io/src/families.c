/* lib/io/src/families.c: cells and boundary-face families for the
 * solver formats (SU2, CGNS, OpenFOAM). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "families_private.h"
#include "formats_private.h"
#include "varmesh/topology.h"

int ex_groups_lossy(vm_ctx *ctx, const vm_mesh *m, const char *path, const char *fmt,
                    int cell_fields) {
  vm_lost_list l;
  vm_lost_init(&l);
  /* a surface mesh has no boundary faces: its tags and their names are lost */
  int surface = ex_groups_surface(m);
  for (int loc = 0; loc < 2; loc++)
    for (int i = 0; i < m->nfield; i++) {
      const vm_field *f = &m->fields[i];
      if ((f->location == VM_FIELD_ELEMENT) != (loc == 0)) continue;
      if (!surface && f->location == VM_FIELD_ELEMENT && !strcmp(f->name, "gmsh:physical") &&
          f->type == VM_FIELD_I32 && f->ncomp == 1)
        continue;
      if (cell_fields && f->location == VM_FIELD_ELEMENT && f->ncomp == 1 &&
          strncmp(f->name, "gmsh:", 5))
        continue;
      char item[320];
      snprintf(item, sizeof item, "'%s'", f->name);
      vm_lost_add(&l, loc, loc == 0 ? "element fields" : "vertex fields", item);
    }
  for (int i = 0; i < m->nattr; i++) {
    const char *k = m->attrs[i].key;
    if (!surface && !strncmp(k, "gmsh:physical_name:2:", 21)) continue;
    char item[320];
    if (!strncmp(k, "gmsh:physical_name:", 19))
      snprintf(item, sizeof item, "'%s' ('%s')", k, m->attrs[i].value);
    else
      snprintf(item, sizeof item, "'%s'", k);
    vm_lost_add(&l, 2, "attributes", item);
  }
  int64_t nflag = 0;
  for (int64_t v = 0; v < m->nv; v++) nflag += m->vflag[v] != VM_VERTEX_FREE;
  if (!l.items && !l.more && !nflag) return 0;
  char flags[64] = "";
  if (nflag)
    snprintf(flags, sizeof flags, "%svertex flags (%lld fixed or slip)",
             l.items || l.more ? "; " : "", (long long)nflag);
  vm_log(ctx, VM_LOG_WARN, "%s: %s cannot store %s%s; dropped", path, fmt, vm_lost_text(&l), flags);
  return 1;
}

int ex_groups_surface(const vm_mesh *m) {
  int64_t counts[VM_NTYPES];
  return m->dim == 3 && vm_mesh_count_types(m, counts) == 2;
}

int ex_groups_check(vm_ctx *ctx, const vm_mesh *m, const char *path, const char *fmt) {
  int64_t counts[VM_NTYPES];
  int top = vm_mesh_count_types(m, counts);
  if (m->dim != 3)
    return vm_error(ctx, VM_ERR_UNSUPPORTED, "%s: %s export needs a 3D mesh", path, fmt);
  if (top != 3 && top != 2)
    return vm_error(ctx, VM_ERR_ARG,
                    "%s: %s needs cells (tetrahedra, pyramids, prisms, hexahedra, or triangles "
                    "and quadrilaterals of a surface); the mesh has no elements",
                    path, fmt);
  return VM_OK;
}

void ex_groups_free(vm_ctx *ctx, ex_groups *g) {
  for (int f = 0; f < g->nfam; f++) vm_free(ctx, g->name[f]);
  vm_free(ctx, g->name);
  vm_free(ctx, g->cell);
  vm_free(ctx, g->fbeg);
  vm_free(ctx, g->fv);
  vm_free(ctx, g->fnv);
  vm_free(ctx, g->felem);
  memset(g, 0, sizeof *g);
}

typedef struct {
  int32_t tag;
  int64_t e;
} tagged;

static int cmp_tagged(const void *a, const void *b) {
  const tagged *x = a, *y = b;
  if (x->tag != y->tag) return x->tag < y->tag ? -1 : 1;
  return (x->e > y->e) - (x->e < y->e);
}

int ex_groups_build(vm_ctx *ctx, const vm_mesh *m, ex_groups *g) {
  memset(g, 0, sizeof *g);
  int64_t counts[VM_NTYPES];
  int top = vm_mesh_count_types(m, counts);
  if (top != 3 && top != 2) return vm_error(ctx, VM_ERR_ARG, "export: the mesh has no cells");
  if (top == 2) {
    /* a surface: its triangles and quads are the cells, in mesh order; no faces */
    g->ncell = counts[VM_TRI] + counts[VM_QUAD];
    g->cell = vm_alloc_array(ctx, (size_t)(g->ncell ? g->ncell : 1), sizeof *g->cell);
    g->fbeg = vm_alloc_array(ctx, 1, sizeof *g->fbeg);
    if (!g->cell || !g->fbeg) return VM_ERR_NOMEM;
    int64_t k = 0;
    for (int64_t e = 0; e < m->ne; e++)
      if (vm_elem_dim(m->etype[e]) == 2) g->cell[k++] = (int32_t)e;
    g->fbeg[0] = 0;
    return VM_OK;
  }
  int64_t nf = counts[VM_TRI] + counts[VM_QUAD];
  g->ncell = counts[VM_TET] + counts[VM_PYRAMID] + counts[VM_PRISM] + counts[VM_HEX];
  g->cell = vm_alloc_array(ctx, (size_t)g->ncell, sizeof *g->cell);
  if (!g->cell) return VM_ERR_NOMEM;
  int64_t k = 0;
  for (int64_t e = 0; e < m->ne; e++)
    if (vm_elem_dim(m->etype[e]) == 3) g->cell[k++] = (int32_t)e;
  int st = VM_OK;
  if (nf == 0) {
    /* no faces in the mesh: its boundary is one family */
    int32_t *fv = NULL;
    uint8_t *fnv = NULL;
    if ((st = vm_mesh_boundary(m, &g->nface, &fv, &fnv, NULL, NULL))) return st;
    g->fv = fv;
    g->fnv = fnv;
    g->felem = vm_alloc_array(ctx, (size_t)(g->nface ? g->nface : 1), sizeof *g->felem);
    g->name = vm_alloc_array(ctx, 1, sizeof *g->name);
    g->fbeg = vm_alloc_array(ctx, 2, sizeof *g->fbeg);
    if (!g->felem || !g->name || !g->fbeg) return VM_ERR_NOMEM;
    for (int64_t f = 0; f < g->nface; f++) g->felem[f] = -1;
    g->nfam = 1;
    g->name[0] = vm_strdup(ctx, "boundary");
    if (!g->name[0]) return VM_ERR_NOMEM;
    g->fbeg[0] = 0;
    g->fbeg[1] = g->nface;
    return VM_OK;
  }
  const vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  if (ph && (ph->type != VM_FIELD_I32 || ph->ncomp != 1)) ph = NULL;
  tagged *tg = vm_alloc_array(ctx, (size_t)nf, sizeof *tg);
  g->fv = vm_alloc_array(ctx, (size_t)(4 * nf), sizeof *g->fv);
  g->fnv = vm_alloc_array(ctx, (size_t)nf, sizeof *g->fnv);
  g->felem = vm_alloc_array(ctx, (size_t)nf, sizeof *g->felem);
  g->fbeg = vm_alloc_array(ctx, (size_t)nf + 1, sizeof *g->fbeg);
  g->name = vm_calloc(ctx, (size_t)nf, sizeof *g->name);
  if (!tg || !g->fv || !g->fnv || !g->felem || !g->fbeg || !g->name) {
    vm_free(ctx, tg);
    return VM_ERR_NOMEM;
  }
  k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI && m->etype[e] != VM_QUAD) continue;
    tg[k].tag = ph ? ((const int32_t *)ph->data)[e] : 0;
    tg[k++].e = e;
  }
  qsort(tg, (size_t)nf, sizeof *tg, cmp_tagged);
  g->nface = nf;
  for (int64_t f = 0; f < nf; f++) {
    int64_t e = tg[f].e;
    int n = vm_elem_nverts(m->etype[e]);
    g->fnv[f] = (uint8_t)n;
    g->felem[f] = (int32_t)e;
    for (int i = 0; i < 4; i++) g->fv[4 * f + i] = i < n ? m->conn[m->eoff[e] + i] : -1;
    if (f == 0 || tg[f].tag != tg[f - 1].tag) {
      char key[64], buf[64];
      snprintf(key, sizeof key, "gmsh:physical_name:2:%d", (int)tg[f].tag);
      const char *nm = vm_mesh_get_attr(m, key);
      if (!nm) {
        snprintf(buf, sizeof buf, "boundary_%d", (int)tg[f].tag);
        nm = buf;
      }
      g->fbeg[g->nfam] = f;
      g->name[g->nfam] = vm_strdup(ctx, nm);
      if (!g->name[g->nfam++]) st = VM_ERR_NOMEM;
    }
  }
  g->fbeg[g->nfam] = nf;
  vm_free(ctx, tg);
  return st;
}

int ex_family_kind(const char *name) {
  if (!strncasecmp(name, "wall", 4)) return EX_FAM_WALL;
  if (!strcasecmp(name, "farfield")) return EX_FAM_FARFIELD;
  if (!strcasecmp(name, "symmetry")) return EX_FAM_SYMMETRY;
  return EX_FAM_OTHER;
}
