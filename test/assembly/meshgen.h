/* test/assembly/meshgen.h: small structured meshes of every element type
 * for the assembly tests and benchmark, with seeded jitter. */
#ifndef VM_TEST_MESHGEN_H
#define VM_TEST_MESHGEN_H

#include <math.h>
#include <stdlib.h>

#include "varmesh/mesh.h"

/* Grid vertex (i, j, k) of an (nx+1) x (ny+1) x (nz+1) lattice. */
static inline int32_t mg_vid(int i, int j, int k, int nx, int ny) {
  return (int32_t)(i + (nx + 1) * (j + (ny + 1) * k));
}

static inline double mg_tet_vol(const double *x, const int32_t *v) {
  const double *a = x + 3 * v[0], *b = x + 3 * v[1], *c = x + 3 * v[2], *d = x + 3 * v[3];
  double u[3], w[3], z[3];
  for (int r = 0; r < 3; r++) u[r] = b[r] - a[r], w[r] = c[r] - a[r], z[r] = d[r] - a[r];
  return u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) +
         u[2] * (w[0] * z[1] - w[1] * z[0]);
}

/* A lattice mesh of `type` elements over [0,nx h] x [0,ny h] x [0,nz h]
 * (nz ignored for 2D types). 2D types: plane mesh (dim 2) unless `surf`,
 * then a bumpy surface z = 0.3 h sin(x/h) cos(y/h) in 3D. Hexes and their
 * splits: tets (6 Kuhn tets per cube), pyramids (6 per cube around an added
 * centre vertex), prisms (2 per cube). Returns NULL on failure. */
static inline vm_mesh *mg_build(vm_ctx *ctx, int type, int surf, int nx, int ny, int nz, double h) {
  vm_mesh *m = NULL;
  if (vm_mesh_create(ctx, &m)) return NULL;
  int two = vm_elem_dim(type) == 2;
  if (two) nz = 0;
  m->dim = two && !surf ? 2 : 3;
  for (int k = 0; k <= nz; k++)
    for (int j = 0; j <= ny; j++)
      for (int i = 0; i <= nx; i++) {
        double z = k * h;
        if (two) z = surf ? 0.3 * h * sin(i) * cos(j) : 0;
        if (vm_mesh_add_vertex(m, i * h, j * h, z, NULL)) goto fail;
      }
  for (int k = 0; k < (two ? 1 : nz); k++)
    for (int j = 0; j < ny; j++)
      for (int i = 0; i < nx; i++) {
        int32_t c[8] = {mg_vid(i, j, k, nx, ny),
                        mg_vid(i + 1, j, k, nx, ny),
                        mg_vid(i + 1, j + 1, k, nx, ny),
                        mg_vid(i, j + 1, k, nx, ny),
                        mg_vid(i, j, k + 1, nx, ny),
                        mg_vid(i + 1, j, k + 1, nx, ny),
                        mg_vid(i + 1, j + 1, k + 1, nx, ny),
                        mg_vid(i, j + 1, k + 1, nx, ny)};
        int st = 0;
        switch (type) {
        case VM_QUAD:
        case VM_HEX: st = vm_mesh_add_element(m, type, c); break;
        case VM_TRI: {
          int32_t t0[3] = {c[0], c[1], c[2]}, t1[3] = {c[0], c[2], c[3]};
          st = vm_mesh_add_element(m, VM_TRI, t0) || vm_mesh_add_element(m, VM_TRI, t1);
          break;
        }
        case VM_PRISM: {
          int32_t p0[6] = {c[0], c[1], c[2], c[4], c[5], c[6]};
          int32_t p1[6] = {c[0], c[2], c[3], c[4], c[6], c[7]};
          st = vm_mesh_add_element(m, VM_PRISM, p0) || vm_mesh_add_element(m, VM_PRISM, p1);
          break;
        }
        case VM_TET: {
          /* Kuhn: paths 000 -> 111 along the axes in each order */
          static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                         {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
          for (int q = 0; q < 6 && !st; q++) {
            int ijk[3] = {0, 0, 0};
            int32_t t[4];
            t[0] = c[0];
            for (int s = 0; s < 3; s++) {
              ijk[perm[q][s]] = 1;
              t[s + 1] = mg_vid(i + ijk[0], j + ijk[1], k + ijk[2], nx, ny);
            }
            if (mg_tet_vol(m->xyz, t) < 0) {
              int32_t sw = t[1];
              t[1] = t[2];
              t[2] = sw;
            }
            st = vm_mesh_add_element(m, VM_TET, t);
          }
          break;
        }
        case VM_PYRAMID: {
          int64_t ctr;
          st = vm_mesh_add_vertex(m, (i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h, &ctr);
          int faces[6][4], nfv[6];
          int nf = vm_elem_faces(VM_HEX, faces, nfv);
          /* hex faces point out: reversed, the base normal points to the centre */
          for (int f = 0; f < nf && !st; f++) {
            int32_t py[5] = {c[faces[f][0]], c[faces[f][3]], c[faces[f][2]], c[faces[f][1]],
                             (int32_t)ctr};
            st = vm_mesh_add_element(m, VM_PYRAMID, py);
          }
          break;
        }
        default: st = 1;
        }
        if (st) goto fail;
      }
  return m;
fail:
  vm_mesh_destroy(&m);
  return NULL;
}

/* Move every vertex by amp*(uniform in [-1,1]) per coordinate (not z of
 * plane meshes), from the context's seeded generator. */
static inline void mg_jitter(vm_ctx *ctx, vm_mesh *m, double amp) {
  for (int64_t v = 0; v < m->nv; v++)
    for (int r = 0; r < m->dim; r++) m->xyz[3 * v + r] += amp * (2 * vm_ctx_rand_unit(ctx) - 1);
}

#endif
