/* lib/gen/src/rotcube.c: generated benchmark meshes (uniform and rotated
 * cubes of Section 6.1, hexahedra or Kuhn tetrahedra). */
#include "varmesh/rotcube.h"

#include <math.h>
#include <string.h>

vm_rotcube_opts vm_rotcube_opts_default(void) {
  vm_rotcube_opts o;
  o.n = 8;
  o.alpha = 0;
  o.axis[0] = 0;
  o.axis[1] = 0;
  o.axis[2] = 1;
  o.inner = 0.5 / sqrt(2.0);
  o.cells = VM_GEN_HEX;
  o.free_boundary = 0;
  return o;
}

/* Rodrigues rotation of p about unit axis k by angle a. */
static void rotate(const double k[3], double a, const double p[3], double out[3]) {
  double c = cos(a), s = sin(a);
  double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
  double kx[3] = {k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]};
  for (int i = 0; i < 3; i++) out[i] = p[i] * c + kx[i] * s + k[i] * kp * (1 - c);
}

typedef struct {
  const vm_rotcube_opts *o;
  double axis[3];
  vm_mesh *m;
  double *ref; /* Cartesian positions (the target), or NULL */
} gen_state;

/* Add the vertex whose Cartesian position is p: rotated and fixed strictly
 * inside the inner cube, fixed on the outer boundary, free elsewhere. */
static int place_vertex(gen_state *g, const double p[3], int boundary, int64_t *index) {
  const double tol = 1e-12, a = g->o->inner;
  int in = fabs(p[0]) < a - tol && fabs(p[1]) < a - tol && fabs(p[2]) < a - tol;
  double x[3] = {p[0], p[1], p[2]};
  if (in) rotate(g->axis, g->o->alpha, p, x);
  int st = vm_mesh_add_vertex(g->m, x[0], x[1], x[2], index);
  if (st) return st;
  if (in || (boundary && !g->o->free_boundary)) g->m->vflag[*index] = VM_VERTEX_FIXED;
  if (g->ref) memcpy(g->ref + 3 * *index, p, 3 * sizeof *p);
  return VM_OK;
}

/* One cube with corners c (VTK hex order) as cells of `kind`: 0 hex, 1 two
 * prisms split by the 0-2 diagonal, 2 six pyramids around a new centre
 * vertex at Cartesian position `ctr`, 3 six Kuhn tets along the 0-6
 * diagonal. All positively oriented; faces shared with neighbours have the
 * same vertices (no hanging nodes). */
static int add_cell(gen_state *g, int kind, const int32_t c[8], const double ctr[3]) {
  static const int kuhn[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                 {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  static const int prisms[2][6] = {{0, 1, 2, 4, 5, 6}, {0, 2, 3, 4, 6, 7}};
  /* hex faces ordered so that the centre is on the apex side */
  static const int faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                                  {1, 5, 6, 2}, {2, 6, 7, 3}, {0, 3, 7, 4}};
  int st = VM_OK;
  int32_t v[8];
  switch (kind) {
  case 0: return vm_mesh_add_element(g->m, VM_HEX, c);
  case 1:
    for (int p = 0; p < 2 && !st; p++) {
      for (int q = 0; q < 6; q++) v[q] = c[prisms[p][q]];
      st = vm_mesh_add_element(g->m, VM_PRISM, v);
    }
    return st;
  case 2: {
    int64_t cv;
    if ((st = place_vertex(g, ctr, 0, &cv))) return st;
    for (int f = 0; f < 6 && !st; f++) {
      for (int q = 0; q < 4; q++) v[q] = c[faces[f][q]];
      v[4] = (int32_t)cv;
      st = vm_mesh_add_element(g->m, VM_PYRAMID, v);
    }
    return st;
  }
  default:
    for (int t = 0; t < 6 && !st; t++) {
      for (int q = 0; q < 4; q++) v[q] = c[kuhn[t][q]];
      st = vm_mesh_add_element(g->m, VM_TET, v);
    }
    return st;
  }
}

int vm_gen_rotated_cube(vm_ctx *ctx, const vm_rotcube_opts *o, vm_mesh **out, double **xyz_ref) {
  *out = NULL;
  if (xyz_ref) *xyz_ref = NULL;
  int n = o->n;
  if (n < 2 || n > 1000)
    return vm_error(ctx, VM_ERR_ARG, "rotated cube: n = %d out of [2, 1000]", n);
  double al = sqrt(o->axis[0] * o->axis[0] + o->axis[1] * o->axis[1] + o->axis[2] * o->axis[2]);
  if (!(al > 0)) return vm_error(ctx, VM_ERR_ARG, "rotated cube: zero rotation axis");
  if (!(o->inner > 0 && o->inner < 0.5))
    return vm_error(ctx, VM_ERR_ARG, "rotated cube: inner half-size %g not in (0, 1/2)", o->inner);
  if (o->cells < VM_GEN_HEX || o->cells > VM_GEN_MIXED)
    return vm_error(ctx, VM_ERR_ARG, "rotated cube: unknown cell kind %d", o->cells);
  gen_state g = {o, {o->axis[0] / al, o->axis[1] / al, o->axis[2] / al}, NULL, NULL};
  int st = vm_mesh_create(ctx, &g.m);
  if (st) return st;
  int64_t nv = (int64_t)(n + 1) * (n + 1) * (n + 1), ncell = (int64_t)n * n * n;
  /* room for the pyramid cells' centre vertices */
  int64_t nmax = nv + (o->cells == VM_GEN_MIXED ? ncell : 0);
  vm_field *fx = NULL;
  if (xyz_ref && !(g.ref = vm_alloc_array(ctx, (size_t)nmax * 3, sizeof *g.ref))) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  const double h = 1.0 / n;
  for (int kk = 0; kk <= n; kk++)
    for (int j = 0; j <= n; j++)
      for (int i = 0; i <= n; i++) {
        double p[3] = {-0.5 + i * h, -0.5 + j * h, -0.5 + kk * h};
        int bnd = i == 0 || j == 0 || kk == 0 || i == n || j == n || kk == n;
        int64_t v;
        if ((st = place_vertex(&g, p, bnd, &v))) goto fail;
      }
  for (int kk = 0; kk < n; kk++)
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        static const int di[8] = {0, 1, 1, 0, 0, 1, 1, 0}, dj[8] = {0, 0, 1, 1, 0, 0, 1, 1},
                         dk[8] = {0, 0, 0, 0, 1, 1, 1, 1};
        int32_t c[8];
        for (int q = 0; q < 8; q++)
          c[q] = (int32_t)(((int64_t)(kk + dk[q]) * (n + 1) + j + dj[q]) * (n + 1) + i + di[q]);
        double ctr[3] = {-0.5 + (i + 0.5) * h, -0.5 + (j + 0.5) * h, -0.5 + (kk + 0.5) * h};
        int kind = o->cells == VM_GEN_HEX ? 0 : o->cells == VM_GEN_TETS ? 3 : (i + j + kk) % 4;
        if ((st = add_cell(&g, kind, c, ctr))) goto fail;
      }
  /* the "fixed" convention of the readers, mirrored from the flags */
  if ((st = vm_mesh_add_field(g.m, "fixed", VM_FIELD_VERTEX, VM_FIELD_I32, 1, &fx))) goto fail;
  for (int64_t v = 0; v < g.m->nv; v++) ((int32_t *)fx->data)[v] = g.m->vflag[v] == VM_VERTEX_FIXED;
  *out = g.m;
  if (xyz_ref) *xyz_ref = g.ref;
  return VM_OK;
fail:
  vm_free(ctx, g.ref);
  vm_mesh_destroy(&g.m);
  return st;
}
