/* varmesh/boundary.h: per-vertex boundary conditions of the minimizers:
 * fixed vertices, free vertices, and slip vertices that slide on a
 * constraint surface through the tangent-cone projectors L_k of (30)-(33),
 * plus analytic constraint surfaces (plane, sphere, axis-aligned box). */
#ifndef VARMESH_BOUNDARY_H
#define VARMESH_BOUNDARY_H

#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Constraint surfaces, supplied by the caller. project() writes the point
 * `out` of surface `surf_id` closest to p and the unit normals of the
 * constraints active at `out` to normals[0..2], normals[3..5], ...; it
 * returns their number: 1 at a smooth surface point, 2 on a feature edge
 * (the vertex then slides along the edge), 3 at a corner (it stays put),
 * 0 if nothing constrains the point; negative (a VM_ERR_ status) if the
 * projection failed (unknown id, point at a sphere's centre, ...). A
 * surface with one normal per point just writes normals[0..2] and
 * returns 1. Called from one thread at a time unless `reentrant` says
 * otherwise. */
typedef struct vm_surface_ops {
  int (*project)(void *user, int surf_id, const double p[3], double out[3], double normals[9]);
  void *user;
  /* Optional (NULL: project() is used): project() with a hint, an opaque
   * token the last call for the same vertex left in *hint (-1 before the
   * first). The answer is project()'s closest point; where several points
   * are equally close, the hinted one is kept. *hint is updated. The
   * minimizers keep one token per slip vertex, so a vertex that moves a
   * little costs a local search instead of a global one. */
  int (*project_hinted)(void *user, int surf_id, const double p[3], int64_t *hint, double out[3],
                        double normals[9]);
  /* Nonzero: project() and project_hinted() may run on several threads at
   * once, for different points and hints (0, the default: one at a time). */
  int reentrant;
} vm_surface_ops;

/* Analytic surfaces by id, for tests and generated volume meshes. */
typedef struct vm_analytic_surfaces vm_analytic_surfaces;

int vm_analytic_surfaces_create(vm_ctx *ctx, vm_analytic_surfaces **out);
void vm_analytic_surfaces_destroy(vm_analytic_surfaces **p);
/* Add a surface under `surf_id` (an existing id is replaced): the plane
 * through `point` with normal `normal` (normalized here); a sphere; the
 * boundary of the box [lo, hi], whose edges and corners are features of
 * the tangent cone: a projected point lying on two faces (within 1e-9 of
 * the box diagonal) reports 2 normals and slides along the edge, on three
 * faces it reports 3 and stays. VM_ERR_ARG for a zero normal, radius <= 0
 * or lo >= hi in some coordinate. */
int vm_analytic_add_plane(vm_analytic_surfaces *s, int surf_id, const double point[3],
                          const double normal[3]);
int vm_analytic_add_sphere(vm_analytic_surfaces *s, int surf_id, const double center[3],
                           double radius);
int vm_analytic_add_box(vm_analytic_surfaces *s, int surf_id, const double lo[3],
                        const double hi[3]);
/* The ops table for these surfaces (valid while s lives). */
vm_surface_ops vm_analytic_surfaces_ops(vm_analytic_surfaces *s);

/* Boundary conditions of one minimization: classes from m->vflag
 * (FREE / FIXED / SLIP on m->vsurf[v]); for every slip vertex an
 * orthonormal basis Q_k of its admissible directions, L_k = Q_k Q_k^T of
 * rank 0..3 (rank 3 - number of independent constraint normals). For
 * m->dim == 2 every vertex is also constrained to the xy plane. */
typedef struct vm_bc vm_bc;

/* Read the classes of m (not kept: later flag changes need a new vm_bc).
 * surf may be NULL only if no vertex is SLIP (VM_ERR_ARG otherwise); it is
 * copied. The projectors are computed by vm_bc_project / vm_bc_refresh. */
int vm_bc_create(vm_ctx *ctx, const vm_mesh *m, const vm_surface_ops *surf, vm_bc **out);
void vm_bc_destroy(vm_bc **p);

/* V of (33): move every slip vertex of x (3*nv) onto its surface and
 * recompute its L_k there. Fixed and free vertices are not written.
 * Returns VM_OK or the first failing projection's status. */
int vm_bc_project(vm_bc *bc, double *x);
/* Recompute L_k at x without writing x (x already on the surfaces). A
 * vertex at a point one of the last two vm_bc_step calls produced (bit for
 * bit) takes the basis that step computed there, without projecting. */
int vm_bc_refresh(vm_bc *bc, const double *x);
/* The trial point of (33): xout_k = V(x_k + tau L_k dz_k) for every vertex
 * that is not fixed; fixed vertices of xout are not written (the caller
 * keeps them equal to x). L_k are those of the last project/refresh.
 * Returns VM_OK or a failing projection's status. */
int vm_bc_step(vm_bc *bc, const double *x, const double *dz, double tau, double *xout);
/* r_k = L_k r_k for every vertex (fixed vertices: r_k = 0). */
void vm_bc_apply(const vm_bc *bc, double *r);

/* Rank of L_v (0 for fixed vertices; 3 for free vertices in 3D, 2 in 2D)
 * and the orthonormal basis: column j of Q is Q[3*j .. 3*j+2]. */
int vm_bc_basis(const vm_bc *bc, int64_t v, double Q[9]);
/* Vertex class (VM_VERTEX_FREE / _FIXED / _SLIP), and counts. */
int vm_bc_class(const vm_bc *bc, int64_t v);
int64_t vm_bc_count(const vm_bc *bc, int cls);
/* Space dimension the vertices move in (m->dim). */
int vm_bc_dim(const vm_bc *bc);

#ifdef __cplusplus
}
#endif
#endif
