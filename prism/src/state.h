/* prism/src/state.h: the per-run state of the layer builder and the
 * helpers its phases share (progress, time, the layer's solves, the
 * layer's intersection query). */
#ifndef VARMESH_PRISM_STATE_H
#define VARMESH_PRISM_STATE_H

#include <stdint.h>
#include <string.h>

#include "geom.h"
#include "intersect.h"
#include "params.h"
#include "varmesh/minimize.h"
#include "varmesh/prism.h"
#include "varmesh/problem.h"

/* Element field holding the per-prism target vertex coordinates. */
#define PRISM_TARGET_FIELD "vm_prism_target"

struct vm_prism {
  vm_ctx *ctx;
  vm_prism_opts o;
  pr_params k;     /* the stage's internal tunables (params.h) */
  double t0;       /* omp_get_wtime() at creation */
  int done;        /* phases completed (vm_prism_phase + 1) */
  int64_t nw, nt;  /* wall vertices and triangles */
  int64_t ned;     /* unique wall edges */
  double *wall;    /* 3*nw, bit-identical copies of the input */
  int32_t *tri;    /* 3*nt */
  double *fnrm;    /* 3*nt unit face normals */
  double *vnrm;    /* 3*nw angle-weighted unit vertex normals */
  double *dir;     /* 3*nw blended column directions (visible from every face) */
  double *elen;    /* nw: mean incident edge length */
  uint8_t *smooth; /* nw: incident face normals within k.smooth_angle_deg of vnrm */
  int64_t *vt_off; /* vertex -> triangles (CSR) */
  int32_t *vt;
  int64_t *vv_off; /* vertex -> neighbour vertices (CSR, sorted) */
  int32_t *vv;
  int32_t *edge; /* 2*ned, a < b */
  int32_t *etri; /* 2*ned triangles on each side (-1: open edge) */
  /* a half model: the wall's open boundary lies in the symmetry plane
   * x[sym_ax] = sym_val and the wall on the side sym_side (+1 or -1) of
   * it; the columns of the vertices in it (onsym[v] = 1, nsym of them)
   * stay in it, bit for bit (sym_ax -1, onsym NULL: a closed wall) */
  int sym_ax;
  double sym_val, sym_side;
  uint8_t *onsym;
  int64_t nsym;

  pr_rt *rt;             /* the run's Embree device (made at the first query) */
  pr_layer_faces *faces; /* the layer's faces for intersection queries */
  vm_mesh *layer;        /* single layer: 2nw vertices, nt prisms, target field */
  vm_problem *prob;
  double *tv;   /* nw: each column's aim T_v <= T (T everywhere unless
                   the options give a thickness per wall face) */
  int regional; /* the options gave a thickness (or a layer count) per wall face */
  int32_t *nlv; /* nw: each column's layer count (the least of its faces', at most
                   what fits its aim),
                   NULL unless the options give a count per wall face; after
                   marching, levels nlv[v]..nlev-1 of column v are its top */
  int ended;    /* pr_end_layers has ended some columns' layers */
  double *h;    /* nw target heights */
  double *cap;  /* nw upper bounds of the thickness left by cutting */
  uint8_t *cut; /* nw: rounds the column was cut in (saturates at 255) */

  /* marching result */
  int nlev;      /* levels (layers + 1); 0 before marching */
  double *lev;   /* nlev * 3 * nw */
  double *sched; /* heights of the schedule (nlayers) */
  double *h1v;   /* nw: each column's first height, the schedule's raised where
                    the wall's edges are long (opts max_aspect); NULL: the
                    schedule's everywhere */

  double *medial; /* nw exterior medial radii (medial.c), NULL until asked */

  vm_prism_report rep;
};

/* Column v's first height: the schedule's, or its own (p->h1v). */
static inline double pr_first_height(const vm_prism *p, int64_t v) {
  return p->h1v ? p->h1v[v] : p->sched[0];
}

/* The wall's connectivity as plain arrays (geom.h). */
static inline pr_surf pr_wall_surf(const vm_prism *p) {
  pr_surf s = {p->nw, p->nt, p->tri, p->vt_off, p->vt, p->vv_off, p->vv, p->sym_ax, p->onsym};
  return s;
}

/* Is column v one of a half model's columns in the symmetry plane? */
static inline int pr_on_sym(const vm_prism *p, int64_t v) { return p->onsym && p->onsym[v]; }

/* The class of a moving vertex of column v in a solve: free, or on a half
 * model's symmetry plane sliding in it (surface 0 of pr_sym_ops). */
static inline uint8_t pr_moving_flag(const vm_prism *p, int64_t v) {
  return pr_on_sym(p, v) ? VM_VERTEX_SLIP : VM_VERTEX_FREE;
}

/* Is point x strictly on the wall's side of the symmetry plane (always,
 * on a closed wall)? */
static inline int pr_sym_inside(const vm_prism *p, const double *x) {
  return p->sym_ax < 0 || (x[p->sym_ax] - p->sym_val) * p->sym_side > 0;
}

/* Prism of triangle t between levels k and k + 1 of the levels L (nw
 * vertices each) into x (18 values). */
static inline void pr_prism_at(const vm_prism *p, const double *L, int64_t t, int k, double *x) {
  size_t lsz = (size_t)(3 * p->nw);
  for (int i = 0; i < 3; i++)
    for (int r = 0; r < 3; r++) {
      x[3 * i + r] = L[k * lsz + 3 * (size_t)p->tri[3 * t + i] + r];
      x[9 + 3 * i + r] = L[(k + 1) * lsz + 3 * (size_t)p->tri[3 * t + i] + r];
    }
}

/* Column v's last level (its top) among nl layers: nl, or its own count
 * where layers end (p->nlv). */
static inline int pr_col_top(const vm_prism *p, int64_t v, int nl) {
  return p->ended && p->nlv[v] < nl ? p->nlv[v] : nl;
}

/* The cell of triangle t in layer k of nl layers where layers end: its
 * type (VM_PRISM; VM_PYRAMID where one column has ended below level k + 1,
 * VM_TET where two have; -1: no cell, all three have) and its vertices as
 * columns col[i] and levels lv[i] in varmesh order. A pyramid's base is
 * the side quad of the two columns going on, its apex the ended column's
 * top; a tet stands on the layer's bottom triangle, its apex the one column
 * going on. Without ending layers, always the prism. */
static inline int pr_cell_nodes(const vm_prism *p, int64_t t, int k, int nl, int32_t *col,
                                int *lv) {
  const int32_t *c = p->tri + 3 * t;
  int ended[3], ne = 0;
  for (int i = 0; i < 3; i++) ne += ended[i] = pr_col_top(p, c[i], nl) <= k;
  if (ne == 0) {
    for (int i = 0; i < 3; i++) {
      col[i] = col[3 + i] = c[i];
      lv[i] = k;
      lv[3 + i] = k + 1;
    }
    return VM_PRISM;
  }
  if (ne == 3) return -1;
  int i = 0;
  while (ended[i] != (ne == 1)) i++; /* the ended one (a pyramid) or the one going on (a tet) */
  int32_t a = c[(i + 1) % 3], b = c[(i + 2) % 3], e = c[i];
  if (ne == 1) {
    int32_t cc[5] = {a, a, b, b, e};
    int ll[5] = {k, k + 1, k + 1, k, pr_col_top(p, e, nl)};
    memcpy(col, cc, sizeof cc);
    memcpy(lv, ll, sizeof ll);
    return VM_PYRAMID;
  }
  int32_t cc[4] = {e, a, b, e};
  int ll[4] = {k, pr_col_top(p, a, nl), pr_col_top(p, b, nl), k + 1};
  memcpy(col, cc, sizeof cc);
  memcpy(lv, ll, sizeof ll);
  return VM_TET;
}

/* The cell's coordinates (3 per vertex) from the levels L (nw vertices
 * each); returns its type as pr_cell_nodes, *nv its vertex count. */
static inline int pr_cell_at(const vm_prism *p, const double *L, int64_t t, int k, int nl,
                             double *x, int *nv) {
  int32_t col[6];
  int lv[6];
  int type = pr_cell_nodes(p, t, k, nl, col, lv);
  *nv = type == VM_PRISM ? 6 : type == VM_PYRAMID ? 5 : type == VM_TET ? 4 : 0;
  for (int i = 0; i < *nv; i++)
    memcpy(x + 3 * i, L + (size_t)lv[i] * (size_t)(3 * p->nw) + 3 * (size_t)col[i], 3 * sizeof *x);
  return type;
}

/* OpenFOAM's cell determinant of cell (t, k) of nl layers at the levels L
 * (a prism, or where layers end a pyramid or a tet: pr_cell_at), every
 * face counted as inside but the wall's (the hybrid mesh's view: the
 * fill's tets stand on the outer surface); INFINITY where there is no
 * cell (ends.c). */
double pr_cell_foam_det(const vm_prism *p, const double *L, int64_t t, int k, int nl);

/* The wall triangle across edge i (tri[i], tri[i + 1]) of triangle t (-1:
 * an open edge). */
static inline int64_t pr_tri_across(const vm_prism *p, int64_t t, int i) {
  int32_t a = p->tri[3 * t + i], b = p->tri[3 * t + (i + 1) % 3];
  for (int64_t m = p->vt_off[a]; m < p->vt_off[a + 1]; m++) {
    int64_t u = p->vt[m];
    const int32_t *c = p->tri + 3 * u;
    if (u != t && (c[0] == b || c[1] == b || c[2] == b)) return u;
  }
  return -1;
}

/* The growth ratio r > 1 of n heights h1 r^k summing to len (h1 n < len),
 * by `iters` bisection steps: the schedule's and a shortened column's. */
double pr_growth_ratio(double h1, int n, double len, int iters);
/* Time since creation. */
double pr_elapsed(const vm_prism *p);
/* Report progress (solver: 1 for a solve's iteration, see vm_prism_progress). */
void pr_progress(vm_prism *p, vm_prism_phase ph, int step, double value, int64_t count, int solver);
/* Time limit left (seconds, +inf if none). */
double pr_time_left(const vm_prism *p);

/* Write the top vertices of the layer from thickness t along unit
 * directions d: top_v = wall_v + t_v d_v. */
void pr_set_top(vm_prism *p, const double *t, const double *d);

/* ---- the layer's solves (solve.c) ---- */

/* Minimize the functional of prob on mesh m with its current targets
 * (implicit or explicit), at most max_iter iterations, reporting progress
 * in phase ph. *iters receives the iterations done. */
int pr_solve(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind, int max_iter,
             vm_prism_phase ph, int *iters);
/* pr_solve with an iteration budget counted in steps: past `budget`
 * iterations it goes on (up to max_iter) while the accepted step lengths
 * sum to less than k.budget_step_share of it (budget <= 0: no budget). */
int pr_solve_budget(vm_prism *p, vm_problem *prob, vm_mesh *m, vm_minimizer_kind kind, int max_iter,
                    int budget, vm_prism_phase ph, int *iters);
/* The single layer's problem (balanced measure, geometric rule), made once. */
int pr_make_problem(vm_prism *p);
/* Targets from heights hv along the blended directions, installed on the
 * layer's problem. */
int pr_set_targets(vm_prism *p, const double *hv);
/* VM_ERR_NUMERIC (naming `when`) if a node of the layer is inverted. */
int pr_check_valid(vm_prism *p, const char *when);
/* The wall vertices of the prisms with a node whose det C <= 0 in the
 * solver's own rounding marked in mark (nw, cleared first); how many such
 * nodes, or a negative status. */
int64_t pr_mark_inverted(vm_prism *p, uint8_t *mark);

/* Intersections of the single layer's faces (top, sides, wall), queried
 * incrementally: marks the wall vertex of every column that carries an
 * intersecting top or side face in `mark` (nw, may be NULL); the number of
 * intersecting face pairs in *npairs (cutting.c). */
int pr_layer_intersections(vm_prism *p, uint8_t *mark, int64_t *npairs);
/* A half model: the vertices of the columns in the symmetry plane put back
 * into it where a step left them off it (counted in rep.sym_snapped: 0
 * when every step kept them there, as each is made to), and the other
 * vertices on or beyond it counted (rep.sym_crossing); report.c. */
void pr_sym_settle(vm_prism *p);
/* The q-quantile of the n values x (sorted in place; report.c). */
double pr_percentile(double *x, int64_t n, double q);

/* ---- the room the geometry leaves (medial.c) ---- */

/* The exterior medial radius (see medial.c) of every vertex of a closed
 * triangulation (xyz, tri: nv vertices, nt triangles; fnrm, vnrm unit face
 * and vertex normals; elen a length per vertex for the floor); hit (may be
 * NULL): the triangle that stopped each ball last, -1 if none did. On a
 * half model (p->sym_ax) the mirror image stops balls too: a hit t + nt
 * is triangle t's image. nt must be p->nt where hit is read. */
int pr_medial_radius_of(vm_prism *p, const double *xyz, const int32_t *tri, const double *fnrm,
                        const double *vnrm, const double *elen, int64_t nv, int64_t nt, double cap,
                        double *radius, int64_t *hit);
/* Does the triangle that stopped a ball (hit, from pr_medial_radius_of;
 * fnrm its unit normals) face back at the ball's vertex normal n (within
 * k.slot_face_deg of opposite: another part, the far side of a slot; a
 * concave fold's triangles stand across)? */
int pr_ball_faces_back(const vm_prism *p, int64_t hit, const double *fnrm, const double *n);

/* ---- layers ending per region (ends.c) ---- */

/* With a layer count per column (p->nlv), after marching: each column
 * with fewer layers than the stack has its levels put along its course at
 * the schedule's first height and its own growth, the levels above its
 * count at its top; a column whose ending leaves a cell invalid (a corner
 * tet, a 3-tet split or a face pyramid not positive, a pyramid not
 * certified) keeps all its layers. Fills the report's ended_columns,
 * ended_kept, pyramids and tets. */
int pr_end_layers(vm_prism *p);

/* ---- the non-orthogonality relief (ortho.c) ---- */

typedef struct pr_ortho_summary {
  int sweeps;
  int64_t moves;                       /* vertex steps kept */
  int64_t over70_before, over70_after; /* internal faces beyond 70 degrees */
  int64_t det_before, det_after;       /* cells with an OpenFOAM determinant below
                                          0.001 (the top of the last layer taken
                                          as inside: the fill's tets stand on it) */
  double cmin_before, cmin_after;      /* the worst face's non-orthogonality cosine */
  int64_t split_before, split_after;   /* prisms not positive in every 3-tet split,
                                          before and after the split repair */
  int64_t split_moves;                 /* the repair's vertex steps kept */
  int split_rounds;                    /* its rounds */
  int64_t outer_moves;                 /* the relief's steps at outer vertices kept */
  int outer_batches_undone;            /* outer batches that crossed something and
                                          were taken again without the steps near it */
  int split_batches_undone;            /* rounds whose outer-vertex batch crossed
                                          something and was taken again step by step */
  double split_sj;                     /* the least scaled Jacobian when it started
                                          (it lowers no cell below) */
  double split_time;                   /* its seconds */
} pr_ortho_summary;

/* Levels 1..nlev-2 moved across their columns, and the outer surface at
 * full thickness in its tangent plane, where the faces of their cells are
 * far from orthogonal (OpenFOAM's measure), every prism kept valid and
 * shaped and the layer free of new crossings (ortho.c says how). */
int pr_ortho_relief(vm_prism *p, pr_ortho_summary *s);
/* OpenFOAM's measures of the layer's faces at levels L (nlev levels of nw
 * vertices): internal faces beyond 70 degrees of non-orthogonality, the
 * largest non-orthogonality (degrees) and the largest skewness (the wall
 * and the outer surface included). */
int pr_foam_figures(const vm_prism *p, const double *L, int nlev, int64_t *over70,
                    double *nonortho_max, double *skew_max, int64_t *det_small);

#endif
