/* varmesh/prism.h: thick multi-layer prismatic meshes on a closed
 * triangulated wall by the method of the paper's Section 6.2: a thin layer
 * along blended vertex normals, elastic springback to the requested
 * thickness (implicit solver, per-prism targets), cutting of
 * self-intersections found with Embree, restoration of thickness with
 * Laplace-Beltrami smoothing, and the marching split into sublayers
 * (explicit solver, orthogonalizing weights). Every prism of every layer
 * stays valid (all quadrature simplices of the geometric rule positive,
 * hence every corner tet positive) at every step. */
#ifndef VARMESH_PRISM_H
#define VARMESH_PRISM_H

#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Names used on the output mesh. */
#define VM_PRISM_FIELD_LAYER "layer"         /* i32 per element: 0 at the wall; -1 on faces */
#define VM_PRISM_FIELD_THICKNESS "thickness" /* f64 per vertex: achieved column thickness */
#define VM_PRISM_FIELD_PHYS "gmsh:physical"  /* i32 per element: family tag below */
#define VM_PRISM_FIELD_MEDIAL                                                                      \
  "medial_radius" /* f64 per vertex: the column's exterior                                         \
                     medial radius (vm_prism_medial_radius) */
/* f64 per vertex: min(1, thickness / min(T_v, medial_radius)), T_v the
 * column's own aim (T unless vm_prism_opts.elem_thickness is given) */
#define VM_PRISM_FIELD_FILL "fill"
/* f64 per vertex: the column's own aim T_v; written only when
 * vm_prism_opts.elem_thickness is given */
#define VM_PRISM_FIELD_TARGET "target_thickness"
/* Where layers end (vm_prism_opts.elem_layers), the numbering is no
 * longer column by column in layers, so the result says where each vertex
 * and element comes from: i32 per vertex, the wall vertex of its column
 * (0..nw-1, vm_prism_create's numbering); i32 per element, the wall
 * triangle its stack stands on (0..nt-1, quads split as vm_prism_create
 * splits them) */
#define VM_PRISM_FIELD_COLUMN "column"
#define VM_PRISM_FIELD_WALL_FACE "wall_face"
enum {
  VM_PRISM_TAG_WALL = 1,    /* wall triangles (the input surface) */
  VM_PRISM_TAG_OUTER = 2,   /* outer boundary triangles */
  VM_PRISM_TAG_VOLUME = 3,  /* the prisms */
  VM_PRISM_TAG_SYMMETRY = 4 /* a half model's faces on its symmetry plane */
};

/* Phases, in order (progress and timings). */
typedef enum {
  VM_PRISM_PHASE_THIN = 0,
  VM_PRISM_PHASE_SPRINGBACK = 1,
  VM_PRISM_PHASE_CUT = 2,
  VM_PRISM_PHASE_RESTORE = 3,
  VM_PRISM_PHASE_MARCH = 4,
  VM_PRISM_NPHASES = 5
} vm_prism_phase;

/* Name of a phase ("thin", "springback", "cut", "restore", "march"). */
const char *vm_prism_phase_name(vm_prism_phase ph);

/* The marching's steps, in order (their seconds are in the report). */
#define VM_PRISM_NMARCH_STEPS 8
/* Name of a marching step k ("splits", "stack_smoothing",
 * "redistribution", "orthogonal_first_level", "orthogonal_solve",
 * "skewness_relief", "nonortho_relief", "growth_relief"; "unknown" out of
 * range). */
const char *vm_prism_march_step_name(int k);

typedef struct vm_prism_progress {
  vm_prism_phase phase;
  int step;       /* solver iteration, cutting round, smoothing pass or layer */
  double value;   /* phase-specific: F (solves), intersecting pairs (cut),
                     mean thickness / T (restore), layer height (march) */
  int64_t count;  /* phase-specific: inverted nodes (solves), prisms to cut */
  double elapsed; /* seconds since the layer was created */
  int solver;     /* 1: an iteration of a solve (step: iteration, value: F,
                     count: inverted nodes or -1 where not computed) inside
                     any phase, including marching's splits and its last
                     solve of tilted columns */
} vm_prism_progress;

typedef void (*vm_prism_progress_fn)(void *user, const vm_prism_progress *p);

typedef struct vm_prism_opts {
  double thickness;      /* T, absolute, > 0 (required) */
  int nlayers;           /* N >= 1 (default 20) */
  double first_height;   /* h1 > 0, or <= 0: from growth (default 0) */
  double growth;         /* ratio r >= 1 of successive heights, or <= 0: from
                            first_height (default 1.2); if both are given, the
                            growth law is kept and the layer count may drop */
  double max_aspect;     /* without first_height: a column's first height is
                            at least the longest wall edge at its vertex over
                            this (at most its aim over the layer count, equal
                            heights), its growth ratio smaller so its layers
                            still fill it: no cell wider than max_aspect times
                            its height where the thickness allows. OpenFOAM's
                            cell determinant falls below its 0.001 at about
                            39 for a right prism on an equilateral triangle
                            (0.0025 at 30); sheared cells fall sooner.
                            Default 30; 0: the schedule's first height
                            everywhere. With first_height (a y+ asked for)
                            the wall's cells keep that height */
  double theta;          /* of the balanced measure (default 0.8) */
  double cut_factor;     /* target height reduction per cut, in (0.5, 1) (default 0.85) */
  int springback_iter;   /* implicit iterations of the springback at full height
                            (default 100; it stops earlier once F stagnates, and
                            goes on, up to 3 times as many, while the accepted
                            steps sum to less than a quarter of it or F still
                            falls by more than 1 % over 10 iterations) */
  int hold_retries;      /* 1: a springback solve still held past its budget
                            (the line search cut short by a few prisms that
                            cannot reach their targets) goes on with held
                            retries (vm_minimize_options.hold_tau): more
                            columns reach T on thick layers, in more time,
                            and the cells are not better everywhere
                            (docs/prism.md); 0 (default): off */
  double slot_clearance; /* where the outer surface faces another part's
                            closer than this share of its local outer edge
                            (the exterior medial radius of the outer surface:
                            a slot cutting left between two parts' layers),
                            the columns are lowered until it does not, down
                            to 0.3 of their aim: the fill's tets across the
                            slot are not flat (default 0.5; 0: off) */
  int resolve_iter;      /* implicit iterations after each cutting round, around
                            the cut columns only (default 6) */
  int max_cut_rounds;    /* default 400; rounds with few pairs are cheap */
  int smooth_iter;       /* restoration / smoothing passes (default 30) */
  int march_iter;        /* explicit iterations per split (default 8) */
  double ortho_weight;   /* weight (12) of the inner sublayer in marching (default 10) */
  double drop_quality;   /* drop the outermost remainder if its minimum scaled
                            Jacobian is below this (default 0: never) */
  double full_tol;       /* a column is at full thickness if >= (1 - full_tol) T
                            (default 0.01) */
  double time_limit;     /* seconds for the whole run, <= 0: none */
  int check_incremental; /* 1: compare every incremental intersection query
                            with a full one, an error (VM_ERR_NUMERIC) if
                            they differ; for tests (default 0: the
                            incremental answer is trusted, twice as fast) */
  int growth_relief;     /* 1 (default): last, the columns whose ratios of
                            successive heights leave the band [r / 1.5, 1.5 r]
                            are re-spaced along their own course towards their
                            schedule, where no cell gets worse by any of the
                            checks OpenFOAM and the stage make (prism/src/march.c,
                            growth_relief); 0: off (for comparison) */
  int end_short;         /* 1 (default): where the layer has cells below
                            OpenFOAM's determinant limit, the columns shorter
                            than their aim (a squeeze) are given the
                            schedule's layers that fit their length, ending in
                            pyramids and tets as --region-layers does; kept if
                            that halves those cells (prism/src/ends.c); 0: off */
  int symmetry_axis;     /* a half model: 0 (default), an open wall whose open
                            boundary lies in a plane x, y or z = const (bit for
                            bit) is a half model cut there, and the layer ends
                            on that plane (the side faces of its border columns
                            form the boundary `symmetry`); 1, 2, 3: the plane is
                            x, y or z = symmetry_value, as asked (a border off
                            it is refused); -1: an open wall is refused */
  double symmetry_value;
  int orient; /* 1 (default): a wall oriented inwards (negative
                 enclosed volume) has its triangles turned, with a
                 warning on the log, so the layer grows outside;
                 0: such a wall is refused */
  /* NULL (default): every column aims at `thickness`. Else one thickness
   * per element of the wall (its triangles' and quads'; other elements'
   * entries are not read), each in (0, thickness]: a column aims at the
   * least of its wall faces' values, graded along the wall so that
   * neighbouring columns' aims differ by at most a slope of 0.5 (the
   * thicker side is shortened near the border: a step would make the outer
   * surface a cliff). The schedule is the thickest column's; thinner ones
   * keep its first height and grow more slowly. Full thickness, the room
   * the geometry leaves and the fill are each column's against its own
   * aim. Read by vm_prism_create only. */
  const double *elem_thickness;
  /* NULL (default): every column has nlayers layers. Else one layer count
   * per element of the wall (as elem_thickness), each in [1, nlayers]: the
   * stack over a face stops after its count, the layers it has following
   * the schedule's first height and growth (so, without elem_thickness, a
   * face of n layers aims at the sum of the schedule's first n heights). A
   * column has the least count of its faces, and at most as many of the
   * schedule's heights as fit its (graded) aim: where a thicker region is
   * shortened towards a thinner one, its layers end a few at a time along
   * the slope. Over a face whose columns' counts differ, the layers above
   * the smaller counts end in pyramids (one column ended) and tetrahedra
   * (two ended), conformally. Where ending a column's layers makes a cell
   * invalid (a corner tet, a 3-tet split or a face pyramid not positive, a
   * pyramid not certified) or a face more skewed than before and than
   * OpenFOAM's limit with a margin, the column gives a layer back, up to
   * all of them (the report counts those kept whole). Read by
   * vm_prism_create only. */
  const int32_t *elem_layers;
  vm_prism_progress_fn progress;
  void *user;
} vm_prism_opts;

/* The defaults above. The stage's internal tunables (tolerances, rounds,
 * quality floors, ...) are not options; they are named, with their
 * defaults and reasons, in prism/src/params.h. */
vm_prism_opts vm_prism_opts_default(void);

/* First-layer height for a target y+ by the flat-plate estimate: the
 * turbulent skin friction of Schlichting, Cf = (2 log10 Re - 0.65)^-2.3,
 * gives the friction velocity u_tau = U sqrt(Cf / 2), and y = y+ nu / u_tau
 * with nu = U L / Re, i.e. h1 = yplus L / (Re sqrt(Cf / 2)). reynolds: the
 * Reynolds number over the reference length ref_length (the length unit of
 * the result). NAN unless yplus > 0, ref_length > 0 and 10 <= reynolds <=
 * 1e12. An estimate for sizing, as every mesher's y+ calculator: the
 * solver's y+ follows the actual flow. */
double vm_prism_yplus_height(double yplus, double reynolds, double ref_length);

/* The summary of a run (every figure is measured, not assumed). */
typedef struct vm_prism_report {
  int64_t wall_vertices, wall_triangles, prisms;
  int layers_requested, layers; /* layers is less if the remainder was dropped */
  double thickness;             /* T */
  double first_height, growth;  /* of the schedule used */
  double first_height_max;      /* the largest column's first height (max_aspect) */
  int64_t first_raised;         /* columns whose first height max_aspect raised */
  double thin_min, thin_max;    /* heights of the thin layer */
  int springback_iter;          /* implicit iterations, all solves */
  int held_steps;               /* steps of the single layer's solves taken with the
                                   vertices of the prisms that held the full step
                                   back held still (vm_minimize_options.hold_tau) */
  int cut_rounds;
  int64_t cut_pairs_first;      /* intersecting pairs found in the first round */
  int64_t intersections;        /* pairs left at the end (0 unless limits hit) */
  int64_t narrow_gap;           /* wall vertices in a gap narrower than half
                                   their triangles' edges (facing back: not a
                                   concave fold): the layer's cells and the
                                   fill's tets are flat there whatever the
                                   stage does */
  double narrow_gap_min;        /* the narrowest such gap (twice the radius), 0
                                   if none */
  double narrow_gap_at[3];      /* where: its wall vertex */
  int64_t slots_lowered;        /* columns lowered so the outer surface does not
                                   face another part's closer than
                                   slot_clearance times its local edge (the
                                   fill's tets there would be flat) */
  double full_fraction;         /* columns at full thickness (their own aim T_v) */
  double thick_min, thick_mean; /* achieved thickness / T_v over columns */
  double thick_max;             /* > 1 where springback left a column longer than T */
  int64_t inverted;             /* corner tets with det <= 0 in the final mesh */
  double sj_min;                /* minimum scaled Jacobian of the prisms */
  int64_t split_negative;       /* prisms not positive in every 3-tet split
                                   (a tet of two bottom and two top vertices
                                   with det <= 0: a solver splitting prisms
                                   into tets fails there) */
  double normal_dev_max;        /* degrees: first-layer side edges vs the wall's
                                   vertex normal, at smooth vertices */
  double normal_dev_mean;
  int64_t smooth_vertices;                       /* vertices where normal_dev is measured */
  int64_t normal_dev_over5;                      /* of those, deviating by more than 5 degrees */
  double normal_dev_p99;                         /* the 99th percentile at smooth vertices */
  double normal_dev_all_max, normal_dev_all_p99; /* the same at every wall vertex
                                                    (sharp edges: against the
                                                    angle-weighted vertex normal) */
  double growth_max;                             /* max h_{k+1}/h_k over columns */
  double growth_p99;        /* the 99th percentile of the columns' largest ratio */
  double growth_band_share; /* columns whose every ratio lies within
                               [1/1.5, 1.5] x the growth ratio */
  int64_t growth_respaced;  /* columns the growth relief re-spaced
                               (vm_prism_opts.growth_relief) */
  /* the layer's faces as OpenFOAM's checkMesh measures them: internal
   * faces whose non-orthogonality is beyond 70 degrees, the largest
   * non-orthogonality (degrees), the largest skewness (the wall and the
   * outer surface included; checkMesh fails at 4) */
  int64_t nonortho_over70;
  double nonortho_max, skew_max;
  /* cells (prisms, and where layers end pyramids and tets) whose OpenFOAM
   * cell determinant is below 0.001 (checkMesh -allGeometry fails them;
   * over the faces inside the hybrid mesh: the top of the last layer
   * counts as inside, the fill's tets stand on it) */
  int64_t det_small;
  /* the room the geometry leaves (vm_prism_medial_radius; all 0 if it was
   * not computed): a column has room for T where its wall vertex's
   * exterior medial radius is at least 1.05 T */
  double medial_room;      /* share of the columns with room */
  double medial_reach;     /* of those, the share at full thickness (1 if none) */
  int64_t medial_short;    /* columns with room short of full thickness */
  double medial_fill;      /* mean over all columns of min(1, achieved / min(T, radius)):
                              the layer's fill of what the geometry allows */
  double medial_fill_rest; /* the same over the columns without room (1 if none) */
  double medial_time;      /* seconds spent computing the radii */
  /* with a layer count per wall face (vm_prism_opts.elem_layers): the
   * columns ended below the stack's layer count, those kept whole because
   * ending them would have made a cell invalid, and the cells that end
   * the layers (prisms counts only whole prisms) */
  int64_t ended_columns, ended_kept, pyramids, tets;
  int64_t short_ended;           /* columns given fewer layers by end_short (kept) */
  double time[VM_PRISM_NPHASES]; /* seconds per phase */
  double time_total;
  double march_time[VM_PRISM_NMARCH_STEPS]; /* seconds per marching step */
  /* the process's peak resident memory (MiB, vm_peak_memory_mb) when each
   * phase ended: the phase that raised it is the one whose figure is
   * above its predecessor's (0: the phase did not run) */
  double peak_mb[VM_PRISM_NPHASES];
  int reoriented; /* the wall was oriented inwards and its triangles were turned */
  /* a half model: the symmetry plane x[sym_axis] = sym_value (sym_axis -1:
   * a closed wall), the columns in it, how many of their vertices had to
   * be put back into it after a step (0: every step kept them there
   * exactly) and how many other vertices of the layer are on or beyond it */
  int sym_axis;
  double sym_value;
  int64_t sym_columns, sym_snapped, sym_crossing;
  int timed_out; /* 1: the time limit stopped a phase (vm_prism_run returns VM_WARN_TIME) */
} vm_prism_report;

/* The stage in one call: the layers on the wall `wall` (see
 * vm_prism_create for what it accepts) with options `opts` (NULL: the
 * defaults; thickness is required).
 * Output: *out the result mesh (see vm_prism_result; free with
 * vm_mesh_destroy), *report its figures (see vm_prism_get_report; may be
 * NULL).
 * Returns VM_OK; a warning (VM_WARN_MAXITER: a limit stopped a phase with
 * valid layers, e.g. cutting out of rounds or marching ending early;
 * VM_WARN_TIME, which wins over VM_WARN_MAXITER: the time limit stopped a
 * phase, report->timed_out set), with *out and *report filled; VM_ERR_INTERRUPTED (the
 * context was interrupted), also with *out and *report filled as far as
 * the run came; or an error, with *out NULL: the wall or the options
 * refused (VM_ERR_ARG, *report all zero) or a phase failed
 * (VM_ERR_NUMERIC, VM_ERR_BACKEND, VM_ERR_NOMEM; *report holds the
 * figures so far, report->wall_triangles > 0). */
int vm_prism_run(vm_ctx *ctx, const vm_mesh *wall, const vm_prism_opts *opts, vm_mesh **out,
                 vm_prism_report *report);

/* ---- step by step (tests, tools that look at the layer between phases) ---- */

typedef struct vm_prism vm_prism;

/* Create the layer builder for a wall: the triangles (VM_TRI; quads are
 * split into two) of `wall`, a closed surface oriented outwards; the layer
 * grows on the side the normals point to. Other element types are ignored.
 * The wall is copied. Vertices not used by a triangle are dropped (the
 * output wall keeps the used ones in their original order).
 * A wall oriented inwards is turned (opts->orient, the default; the
 * output's wall faces are then the input's reversed) or refused.
 * Errors: VM_ERR_ARG (no triangles, bad options, a degenerate triangle, an
 * open, non-manifold, inconsistently or (without orient) inwards oriented wall, a vertex
 * where no direction sees every incident face), VM_ERR_NOMEM. */
int vm_prism_create(vm_ctx *ctx, const vm_mesh *wall, const vm_prism_opts *opts, vm_prism **out);
void vm_prism_destroy(vm_prism **p);

/* The phases, to be called in this order (vm_prism_run calls them all).
 * Each returns VM_OK, a warning (VM_WARN_MAXITER: a limit stopped it with
 * a valid layer; VM_WARN_TIME) or an error. After each of them the current
 * single layer is valid. */
int vm_prism_thin(vm_prism *p);
int vm_prism_springback(vm_prism *p);
int vm_prism_cut(vm_prism *p);
int vm_prism_restore(vm_prism *p);
int vm_prism_march(vm_prism *p);

/* The current single layer (before marching) as a prism mesh: vertices
 * 0..nw-1 the wall (FIXED), nw..2nw-1 the outer surface; one prism per
 * wall triangle. Owned by p; valid until the next call on p. */
const vm_mesh *vm_prism_layer(const vm_prism *p);

/* The result: N-layer prism mesh (after vm_prism_march) with vertices
 * column by column in layers (vertex k*nw + v is level k of column v; with
 * a layer count per wall face, the levels above a column's own count are
 * left out and the numbering is the same order without them), the
 * cells layer by layer (prisms, and where layers end pyramids and tets),
 * then the wall triangles and the outer triangles as boundary faces; fields VM_PRISM_FIELD_LAYER,
 * VM_PRISM_FIELD_THICKNESS, VM_PRISM_FIELD_PHYS and attributes "gmsh:physical_name:2:1" = "wall",
 * "gmsh:physical_name:2:2" = "outer", "gmsh:physical_name:3:3" = "layer".
 * Wall vertices are FIXED and bit-identical to the input. Free with
 * vm_mesh_destroy. Before marching, the single layer is returned. */
int vm_prism_result(vm_prism *p, vm_mesh **out);

/* The exterior medial radius of every wall vertex (nw values, owned by p):
 * the radius of the largest ball that touches the wall at the vertex from
 * outside, its centre on the vertex's angle-weighted normal, and holds no
 * other point of the wall (shrinking balls on Embree point queries, exact
 * distances in double; triangles within 30 degrees of the vertex normal do
 * not stop a ball, so a faceted concave surface reads as its curvature
 * radius, not 0). Radii are at most 4 T (a ball that never shrinks). A
 * straight column taller than its radius meets the column of another wall
 * point: where it is below T the geometry does not allow the full
 * thickness. Computed at the first call (vm_prism_run calls it after
 * vm_prism_create); the figures of vm_prism_get_report use it. Errors:
 * VM_ERR_NOMEM, VM_ERR_BACKEND. */
int vm_prism_medial_radius(vm_prism *p, const double **radius);

/* The symmetry plane of a half model's wall (its triangles and quads):
 * 1 with *axis (0, 1, 2: x, y, z) and *value where the wall has open
 * edges and every vertex on them has the same coordinate on that axis,
 * bit for bit; 0 where the wall is closed or its border is not so; a
 * negative status (out of memory). */
int vm_prism_half_plane(vm_ctx *ctx, const vm_mesh *wall, int *axis, double *value);

/* Figures of the run so far (final figures after vm_prism_march). */
int vm_prism_get_report(vm_prism *p, vm_prism_report *r);

/* ---- intersection detection (Embree BVH, exact-sign tests in double) ---- */

/* Pairs of intersecting triangles among `ntri` triangles (3 vertex indices
 * each into xyz). Triangles sharing an edge are never reported; triangles
 * sharing one vertex are reported if their opposite edges cross the other;
 * if `group` is not NULL, pairs with group[a] == group[b] >= 0 are skipped
 * (e.g. the wall against itself). Output: *npairs pairs (a < b), sorted,
 * in *pairs (2 per pair, vm_malloc; may be NULL to count only).
 * The result does not depend on thread timing. */
int vm_prism_find_intersections(vm_ctx *ctx, const double *xyz, int64_t ntri, const int32_t *tri,
                                const int32_t *group, int64_t *npairs, int64_t **pairs);

/* Boundary-face intersections of a volume mesh: its boundary triangles
 * (quads split) against each other, except pairs that both lie on `wall`
 * vertices only (wall[v] != 0 for wall vertices; NULL: no exception).
 * *npairs counts intersecting pairs. */
int vm_prism_mesh_intersections(vm_ctx *ctx, const vm_mesh *m, const uint8_t *wall,
                                int64_t *npairs);

#ifdef __cplusplus
}
#endif
#endif
