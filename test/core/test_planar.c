/* test/core/test_planar.c: planar 2D meshes (varmesh/planar.h): the plane
 * found (axis-aligned exactly, tilted within the tolerance, a bump refused
 * naming its vertex), the orientation taken from the total signed area, the
 * way back bit for bit for what did not move, and elements not oriented
 * alike found. */
#include <math.h>
#include <string.h>

#include "varmesh/mesh.h"
#include "varmesh/planar.h"
#include "vmtest.h"

#define N 4 /* N x N quads */

/* An N x N grid of quads on [0,1]^2 mapped by emb(); `cw` orders every
 * element clockwise in (s, t). */
static vm_mesh *grid(vm_ctx *ctx, void (*emb)(double, double, double *), int cw) {
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m) < 0 || vm_mesh_set_vertices(m, (N + 1) * (N + 1)) < 0) return NULL;
  for (int j = 0; j <= N; j++)
    for (int i = 0; i <= N; i++) emb((double)i / N, (double)j / N, m->xyz + 3 * (j * (N + 1) + i));
  for (int j = 0; j < N; j++)
    for (int i = 0; i < N; i++) {
      int32_t a = j * (N + 1) + i, q[4] = {a, a + 1, a + N + 2, a + N + 1};
      if (cw) {
        int32_t t = q[1];
        q[1] = q[3];
        q[3] = t;
      }
      vm_mesh_add_element(m, VM_QUAD, q);
    }
  return m;
}

static void emb_z0(double s, double t, double *p) { p[0] = s, p[1] = t, p[2] = 0; }
static void emb_z5(double s, double t, double *p) { p[0] = s, p[1] = t, p[2] = 5; }
/* the plane x = -2 with (s, t) along (z, y): seen from +x, clockwise */
static void emb_x(double s, double t, double *p) { p[0] = -2, p[1] = t, p[2] = s; }
static void emb_tilt(double s, double t, double *p) {
  double c = cos(0.7), d = sin(0.7);
  p[0] = 10 + s * c;
  p[1] = -3 + t;
  p[2] = 7 + s * d;
}
static void emb_bump(double s, double t, double *p) {
  emb_z0(s, t, p);
  if (s == 0.5 && t == 0.5) p[2] = 0.02;
}

/* to the plane, move vertex `mv` (if >= 0) by (0.01, 0.02) in it, and back:
 * every other vertex bit for bit as given; the moved one in the plane */
static void round_trip(vm_ctx *ctx, void (*emb)(double, double, double *), int cw, int axis,
                       int flip, const char *name) {
  vm_mesh *m = grid(ctx, emb, cw);
  CHECK(m != NULL, "%s: mesh", name);
  if (!m) return;
  vm_plane_frame f;
  CHECK(vm_mesh_plane_frame(m, VM_PLANE_TOL, &f) == VM_OK, "%s: planar", name);
  CHECK(f.axis == axis, "%s: axis %d, expected %d", name, f.axis, axis);
  size_t n = (size_t)m->nv * 3;
  double xyz0[3 * (N + 1) * (N + 1)], x2d0[3 * (N + 1) * (N + 1)];
  memcpy(xyz0, m->xyz, n * sizeof *xyz0);
  vm_mesh_to_plane(m, &f);
  CHECK(m->dim == 2, "%s: dimension 2 in the plane", name);
  CHECK(f.flip == flip, "%s: flip %d, expected %d", name, f.flip, flip);
  CHECK(vm_mesh_signed_area_2d(m) > 0.999 && vm_mesh_signed_area_2d(m) < 1.001,
        "%s: signed area %g, expected 1", name, vm_mesh_signed_area_2d(m));
  memcpy(x2d0, m->xyz, n * sizeof *x2d0);
  int mv = (N / 2) * (N + 1) + N / 2; /* the middle vertex */
  m->xyz[3 * mv] += 0.01;
  m->xyz[3 * mv + 1] += 0.02;
  vm_mesh_from_plane(m, &f, x2d0, xyz0);
  int same = 1;
  for (int v = 0; v < m->nv; v++)
    if (v != mv) same &= memcmp(m->xyz + 3 * v, xyz0 + 3 * v, 3 * sizeof(double)) == 0;
  CHECK(same, "%s: the vertices that did not move are bit for bit the input's", name);
  CHECK(m->dim == f.dim0, "%s: the dimension back", name);
  double d[3] = {m->xyz[3 * mv] - xyz0[3 * mv], m->xyz[3 * mv + 1] - xyz0[3 * mv + 1],
                 m->xyz[3 * mv + 2] - xyz0[3 * mv + 2]};
  double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  CHECK(fabs(len - sqrt(0.0005)) < 1e-12, "%s: the moved vertex moved by %g in space", name, len);
  if (axis >= 0)
    CHECK(m->xyz[3 * mv + axis] == xyz0[3 * mv + axis], "%s: its constant coordinate exact", name);
  else
    CHECK(fabs(d[0] * f.n[0] + d[1] * f.n[1] + d[2] * f.n[2]) < 1e-12,
          "%s: it stays in the tilted plane", name);
  vm_mesh_destroy(&m);
}

int main(void) {
  vm_ctx *ctx = NULL;
  vm_ctx_create(&ctx);
  round_trip(ctx, emb_z0, 0, 2, 0, "z = 0");
  round_trip(ctx, emb_z0, 1, 2, 1, "z = 0, clockwise");
  round_trip(ctx, emb_z5, 0, 2, 0, "z = 5");
  round_trip(ctx, emb_x, 0, 0, 1, "x = -2");
  round_trip(ctx, emb_tilt, 0, -1, 0, "tilted");
  round_trip(ctx, emb_tilt, 1, -1, 0, "tilted, clockwise (the normal turns with it)");

  /* a bump: refused, naming the vertex off the plane */
  vm_mesh *m = grid(ctx, emb_bump, 0);
  vm_plane_frame f;
  CHECK(vm_mesh_plane_frame(m, VM_PLANE_TOL, &f) == VM_ERR_ARG, "bump: not planar");
  CHECK(f.worst == (N / 2) * (N + 1) + N / 2, "bump: the lifted vertex named (%lld)",
        (long long)f.worst);
  CHECK(fabs(f.offset - 0.02) < 1e-12, "bump: its distance %g", f.offset);
  vm_mesh_destroy(&m);

  /* one element numbered the other way round: its four edges conflict */
  m = grid(ctx, emb_z0, 0);
  int64_t pair[2];
  int32_t edge[2];
  CHECK(vm_mesh_orientation_conflicts_2d(m, pair, edge) == 0, "grid: oriented alike");
  int32_t *c = m->conn + m->eoff[5];
  int32_t t = c[1];
  c[1] = c[3];
  c[3] = t;
  int64_t nc = vm_mesh_orientation_conflicts_2d(m, pair, edge);
  CHECK(nc == 4, "one element reversed: %lld conflicting edges, expected 4", (long long)nc);
  CHECK(pair[0] == 5 || pair[1] == 5, "the reversed element named (%lld, %lld)", (long long)pair[0],
        (long long)pair[1]);
  vm_mesh_destroy(&m);

  /* a volume mesh is not a planar 2D mesh */
  vm_mesh_create(ctx, &m);
  vm_mesh_set_vertices(m, 4);
  double tet[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  memcpy(m->xyz, tet, sizeof tet);
  int32_t tv[4] = {0, 1, 2, 3};
  vm_mesh_add_element(m, VM_TET, tv);
  CHECK(vm_mesh_plane_frame(m, VM_PLANE_TOL, &f) == VM_ERR_ARG, "a tet: not a 2D mesh");
  CHECK_NEAR(vm_mesh_signed_volume(m), 1.0 / 6, 1e-15, "the unit tet's signed volume");
  m->xyz[0 + 3] = -1; /* (1,0,0) -> (-1,0,0): the tet numbered the other way round */
  CHECK_NEAR(vm_mesh_signed_volume(m), -1.0 / 6, 1e-15, "mirrored, the signed volume's sign");
  vm_mesh_destroy(&m);
  vm_ctx_destroy(&ctx);
  return vmtest_end("planar");
}
