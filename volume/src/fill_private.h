/* volume/src/fill_private.h: what fill.c shares with fill_fv.c (the fill
 * stage's internals, not an API). */
#ifndef VM_FILL_PRIVATE_H
#define VM_FILL_PRIVATE_H

#include "varmesh/fill.h"
#include "varmesh/mesh.h"

/* A triangular face of a 3D cell: its vertices sorted, the cell, and the
 * face's index among the cell's faces (vm_elem_faces). */
typedef struct {
  int32_t v[3];
  int32_t cell;
  int32_t face;
} tface;

/* Every triangular face of the 3D cells, sorted by its vertex set (then
 * cell): the two sides of an interior face are neighbours. */
int fill_tri_faces(vm_ctx *ctx, const vm_mesh *m, tface **out, int64_t *n);
/* Have a and b the same vertices? */
int fill_same_face(const tface *a, const tface *b);

/* Seconds on the monotonic clock. */
double fill_now(void);
/* Three vertex indices in ascending order. */
void fill_sort3(int32_t v[3]);

/* The largest ring of tets around an edge that edge removal takes */
enum { FILL_RING_MAX = 7 };
/* The triangulations of the convex polygon 0..n-1 (n <= FILL_RING_MAX):
 * each a list of n - 2 triangles (i < j < k), into tri (at most 42 of
 * them, Catalan(5)); returns how many. */
int fill_polygon_triangulations(int n, int tri[][FILL_RING_MAX - 2][3]);
/* The pairs pr[0..n) (the other two vertices of each tet around an edge,
 * 3 <= n <= FILL_RING_MAX) chained into a cycle w[0..n); 0 if they close
 * no single cycle of all n (an open fan, a pinched ring). */
int fill_ring_cycle(int n, const int64_t (*pr)[2], int64_t *w);

/* The flips (vm_fill_fv_flips), then, if any, the relief (at most
 * `sweeps`) starting from the vertices of the rings they changed; the
 * figures after into *after (unchanged if no flip). */
int fill_fv_flips_relief(vm_ctx *ctx, vm_mesh *m, int64_t e0, int64_t first, int sweeps,
                         int64_t *nflips, vm_fill_fv_figures *after, int64_t *moved);

#endif
