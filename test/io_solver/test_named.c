/* test/io_solver/test_named.c: named boundaries through every format. A
 * mixed mesh whose boundary faces are tagged "wall", "farfield",
 * "symmetry" and "outer" is written and read back: SU2, CGNS and Gmsh
 * (4.1 ASCII and binary, 2.2) give every face back with its name; VTK,
 * VTU and MEDIT give it back with its tag (they cannot hold the names:
 * VM_WARN_LOSSY, and the warning names each one); the CGNS families carry
 * the boundary-condition type each name says (wall BCWall, farfield
 * BCFarfield, symmetry BCSymmetryPlane, outer BCTypeUserDefined). */
#include "solver_testlib.h"

#if __has_include(<cgnslib.h>)
#include <cgnslib.h>
#define HAVE_CGNSLIB_H 1
#endif

static vm_ctx *ctx;
static char dir[] = "/tmp/vm_named_XXXXXX";

static const char *const names[4] = {"wall", "farfield", "symmetry", "outer"};

/* layered_mesh with its tags renamed: 1 wall, 2 farfield, 7 symmetry, and
 * the last two faces (above the pyramid) moved to tag 3, outer. */
static vm_mesh *named_mesh(void) {
  vm_mesh *m = layered_mesh(ctx, 3);
  int32_t *t = (int32_t *)vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT)->data;
  t[m->ne - 1] = t[m->ne - 2] = 3;
  vm_mesh_set_attr(m, "gmsh:physical_name:2:1", "wall");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:2", "farfield");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:7", "symmetry");
  vm_mesh_set_attr(m, "gmsh:physical_name:2:3", "outer");
  /* the fields the formats differ on are not what this test is about */
  vm_mesh_remove_field(m, "layer", VM_FIELD_ELEMENT);
  vm_mesh_remove_field(m, "thickness", VM_FIELD_ELEMENT);
  return m;
}

typedef struct {
  int32_t v[4];
  int32_t tag;
  const char *name;
} face;

static int cmp_face(const void *a, const void *b) {
  const face *x = a, *y = b;
  for (int i = 0; i < 4; i++)
    if (x->v[i] != y->v[i]) return x->v[i] < y->v[i] ? -1 : 1;
  return 0;
}

/* The faces of m, each as its sorted vertices with its tag and name. */
static face *faces_of(const vm_mesh *m, int64_t *n) {
  const int32_t *t = i32_field(m, "gmsh:physical");
  face *f = calloc((size_t)m->ne + 1, sizeof *f);
  *n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    face *q = &f[(*n)++];
    int k = vm_elem_nverts(m->etype[e]);
    for (int i = 0; i < 4; i++) q->v[i] = i < k ? m->conn[m->eoff[e] + i] : INT32_MAX;
    for (int i = 1; i < 4; i++)
      for (int j = i; j > 0 && q->v[j - 1] > q->v[j]; j--) {
        int32_t s = q->v[j];
        q->v[j] = q->v[j - 1];
        q->v[j - 1] = s;
      }
    q->tag = t ? t[e] : 0;
    char key[64];
    snprintf(key, sizeof key, "gmsh:physical_name:2:%d", (int)q->tag);
    q->name = vm_mesh_get_attr(m, key);
  }
  qsort(f, (size_t)*n, sizeof *f, cmp_face);
  return f;
}

static void warn_fn(void *user, int level, const char *msg) {
  char *all = user;
  size_t k = strlen(all);
  if (level == VM_LOG_WARN && k + strlen(msg) + 2 < 8192) {
    strcat(all, msg);
    strcat(all, "\n");
  }
}

/* Write m as `file` and read it back; names: 1 compare names, 0 tags. */
static void round_trip(const vm_mesh *m, const char *file, int binary, int msh_version,
                       int by_name) {
  char path[256], all[8192] = "";
  snprintf(path, sizeof path, "%s/%s", dir, file);
  vm_write_opts o = vm_write_opts_default();
  o.binary = binary;
  if (msh_version) o.msh_version = msh_version;
  vm_ctx_set_log(ctx, warn_fn, all);
  int st = vm_mesh_write(ctx, m, path, VM_FMT_AUTO, &o);
  vm_ctx_set_log(ctx, NULL, NULL);
  char what[80];
  snprintf(what, sizeof what, "%s%s%s", file, binary ? " binary" : "",
           msh_version == 22 ? " 2.2" : "");
  if (by_name) {
    CHECK(st == VM_OK, "%s: write status %d (%s) warnings: %s", what, st, vm_ctx_error(ctx), all);
  } else {
    /* the names are lost, and said to be: each one in a warning */
    CHECK(st == VM_WARN_LOSSY, "%s: write status %d (%s)", what, st, vm_ctx_error(ctx));
    for (int i = 0; i < 4; i++)
      CHECK(strstr(all, names[i]), "%s: no warning names the lost '%s': %s", what, names[i], all);
  }
  vm_mesh *r = NULL;
  st = vm_mesh_read(ctx, path, VM_FMT_AUTO, &r);
  CHECK(st == VM_OK && r, "%s: read: %s", what, vm_ctx_error(ctx));
  if (!r) return;
  int64_t na, nb;
  face *a = faces_of(m, &na), *b = faces_of(r, &nb);
  CHECK(na == nb, "%s: %lld faces back, want %lld", what, (long long)nb, (long long)na);
  int64_t bad = 0;
  for (int64_t i = 0; i < na && na == nb; i++) {
    int same = !cmp_face(&a[i], &b[i]);
    if (by_name)
      same = same && a[i].name && b[i].name && !strcmp(a[i].name, b[i].name);
    else
      same = same && a[i].tag == b[i].tag;
    bad += !same;
  }
  CHECK(!bad, "%s: %lld faces came back with another %s", what, (long long)bad,
        by_name ? "name" : "tag");
  free(a);
  free(b);
  vm_mesh_destroy(&r);
}

#ifdef HAVE_CGNSLIB_H
/* The boundary-condition type of every family in the file. */
static void check_cgns_bc(const char *file) {
  char path[256];
  snprintf(path, sizeof path, "%s/%s", dir, file);
  int fn, nfam = 0;
  if (cg_open(path, CG_MODE_READ, &fn)) {
    CHECK(0, "%s: cg_open: %s", file, cg_get_error());
    return;
  }
  cg_nfamilies(fn, 1, &nfam);
  static const struct {
    const char *name;
    CGNS_ENUMT(BCType_t) bc;
  } want[4] = {{"wall", CGNS_ENUMV(BCWall)},
               {"farfield", CGNS_ENUMV(BCFarfield)},
               {"symmetry", CGNS_ENUMV(BCSymmetryPlane)},
               {"outer", CGNS_ENUMV(BCTypeUserDefined)}};
  int seen = 0;
  for (int f = 1; f <= nfam; f++) {
    char name[40], bcname[40];
    int nbc, ngeo;
    CGNS_ENUMT(BCType_t) bc;
    if (cg_family_read(fn, 1, f, name, &nbc, &ngeo) || nbc != 1 ||
        cg_fambc_read(fn, 1, f, 1, bcname, &bc)) {
      CHECK(0, "%s: family %d: %s", file, f, cg_get_error());
      continue;
    }
    for (int i = 0; i < 4; i++)
      if (!strcmp(name, want[i].name)) {
        seen++;
        CHECK(bc == want[i].bc, "%s: family %s is %s, want %s", file, name, BCTypeName[bc],
              BCTypeName[want[i].bc]);
      }
  }
  CHECK(seen == 4, "%s: %d of the 4 families found (of %d)", file, seen, nfam);
  cg_close(fn);
}
#endif

int main(void) {
  vm_ctx_create(&ctx);
  if (!mkdtemp(dir)) return 1;
  vm_mesh *m = named_mesh();
  round_trip(m, "n.su2", 0, 0, 1);
  if (vm_have_cgns()) {
    round_trip(m, "n.cgns", 0, 0, 1);
#ifdef HAVE_CGNSLIB_H
    check_cgns_bc("n.cgns");
#endif
  } else {
    fprintf(stderr, "test_named: built without libcgns: no .cgns\n");
  }
  round_trip(m, "n.msh", 0, 0, 1);
  round_trip(m, "nb.msh", 1, 0, 1);
  round_trip(m, "n22.msh", 0, 22, 1);
  round_trip(m, "n.vmsh", 0, 0, 1);
  round_trip(m, "n.vtk", 0, 0, 0);
  round_trip(m, "n.vtu", 0, 0, 0);
  round_trip(m, "n.mesh", 0, 0, 0);
  vm_mesh_destroy(&m);
  static const char *const files[] = {"n.su2",  "n.cgns", "n.msh", "nb.msh", "n22.msh",
                                      "n.vmsh", "n.vtk",  "n.vtu", "n.mesh"};
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
    char p[256];
    snprintf(p, sizeof p, "%s/%s", dir, files[i]);
    remove(p);
  }
  rmdir(dir);
  vm_ctx_destroy(&ctx);
  return vmtest_end("test_named");
}
