/* prism/src/params.h: every internal tunable of the prism stage, in one
 * place, each with its default and the reason for it. The tunables a user
 * sets are vm_prism_opts (varmesh/prism.h); these are the stage's own
 * choices, which its tests and benchmark figures were measured with. A
 * run copies pr_params_default() into its state; the services that work
 * on plain arrays (geom.c, intersect.c) take their part of it. */
#ifndef VARMESH_PRISM_PARAMS_H
#define VARMESH_PRISM_PARAMS_H

/* Columns that may stand up together with their neighbours (the size of
 * stand_with_ring's stack arrays): a vertex of degree 63 or more is left
 * to stand alone. A compile-time constant because it sizes arrays. */
#define PR_RING_MAX 64

/* Bends tried when a column stands up alone (march.c), in layers. */
#define PR_NBENDS 8

/* Column directions and surface geometry (geom.c). */
typedef struct pr_dir_params {
  double visible_min;      /* 0.2: a vertex normal seen by an incident face at
                              n . f below this is replaced by the best visible
                              direction (below 0.2 the prism on that face is
                              close to flat along its side edge) */
  int visible_iter;        /* 200: Badoiu-Clarkson iterations for the best
                              visible direction (the minimum n . f settles
                              within a few dozen on the demo models) */
  double sharp_visibility; /* 0.94: a vertex, or a neighbour of it, whose
                              direction is seen at n . f below this (about
                              20 degrees) is at a sharp edge and is blended */
  double blend_weight;     /* 0.5: weight of the neighbours' mean direction
                              in one blending pass (a Jacobi step halfway) */
  double blend_keep;       /* 0.3: a blended direction is kept if every
                              incident face sees it at n . f >= 0.3 (or
                              better than before) */
  double target_blend[5];  /* {0, 0.25, 0.5, 0.75, 1}: shares of the face
                              normal tried in turn for a prism's target
                              directions, so the target bends as little as
                              needed */
  double target_quality;   /* 0.5: the quality a target must reach to stop
                              bending (a margin: the solve starts far from
                              the barrier) */
  double fair_quality;     /* 0.05: a prism at least this good may be its own
                              target (a fan's exact offset; marching's outer
                              sublayer; the patch solve's upper layers):
                              below it, a target of that shape is nearly
                              flat */
} pr_dir_params;

/* Intersection queries (intersect.c). */
typedef struct pr_isect_params {
  double orient_tol_sq; /* 1e-24: four points are coplanar when
                           |orient|^2 <= 1e-24 |u|^2 |v|^2 |w|^2, i.e. within
                           1e-12 relative (rounding of the double products) */
  double box_pad;       /* 1e-6: triangle boxes padded by this share of the
                           soup's bounding box extents, covering the rounding
                           of the rays to float */
  double ray_extend;    /* 1e-5: relative lengthening of an edge's ray (plus
                           two paddings), so its far end's triangles are
                           candidates despite the float rounding */
  int ray_chunk;        /* 256: edges per OpenMP chunk of the casting loop
                           (dynamic: edge costs vary a lot) */
  int full_query_ratio; /* 4: an incremental query falls back to a full one
                           when more than 1/4 of the faces moved (then the
                           full query is cheaper) */
} pr_isect_params;

typedef struct pr_params {
  /* wall import (prism.c) */
  double degenerate_area;  /* 1e-14: a wall triangle with |e1 x e2| <=
                              1e-14 (|e1|^2 + |e2|^2) is refused as degenerate
                              (no normal to grow along) */
  double smooth_angle_deg; /* 10: a vertex whose incident face normals are all
                              within 10 degrees of its normal is smooth: the
                              first layer stands on the normal there, and the
                              report measures the deviation there */
  int dir_blend_passes;    /* 3: blending passes of the column directions at
                              the wall (marching's base surfaces take none) */
  pr_dir_params dir;

  /* the schedule of layer heights (prism.c) */
  double sched_fit_tol;  /* 1e-9: with both first height and growth given,
                            a layer fits below T if the sum stays below
                            (1 - 1e-9) T (no sliver last layer from rounding) */
  int sched_bisect_iter; /* 200: bisection steps for the growth ratio (far
                            more than double precision needs; cheap) */
  double first_slope;    /* 0.01: neighbouring columns' first heights
                            (opts max_aspect) differ by at most this times
                            their distance; see prism.c's first_heights */
  double region_slope;   /* 0.5: with a thickness per wall face, neighbouring
                            columns' aims differ by at most 0.5 times the
                            wall distance between them (the outer surface
                            rises at most about 27 degrees over a border;
                            a step there made the top layers' faces lean
                            as in the contact zones) */

  /* phase 1, thin layer (thin.c) */
  double thin_height;        /* 0.5: start height, a share of the mean incident
                                edge length (at most T) */
  double thin_limit_height;  /* 1e-6: the height (a share of the start height)
                                at which a prism's limit quality is measured */
  int thin_rounds;           /* 60: halvings at most (2^-60: the limit reached) */
  double thin_quality_share; /* 0.5: a thin prism must keep this share of its
                                limit quality ... */
  double thin_quality_cap;   /* 0.3: ... or this quality, whichever is less */
  double thin_shrink;        /* 0.5: height factor at a poor prism's columns */
  double thin_grade;         /* 0.5: second pass (prisms still poor after
                                thin_rounds): no column higher than a
                                neighbour's plus this share of their edge */
  int thin_grade_sweeps;     /* 2: sweeps of that limit after each halving */

  /* the layer's solves (solve.c) */
  double budget_step_share; /* 0.25: a solve past its budget goes on while its
                               accepted steps sum to less than this share of
                               the budget (the line search still cutting) */
  int budget_fall_window;   /* 10: ... or while F fell by more than ... */
  double budget_fall;       /* 0.01: ... 1 % of itself over the last 10
                               iterations (up to the solve's cap: the demo
                               aircraft's springback at T = 5 % stopped at its
                               budget with F falling 11 % per 10 iterations
                               and 2.2 % of the columns with room short of T;
                               run on to 1 % it settles) */
  double rel_decrease_tol;  /* 1e-5: the solves stop when F falls by less
                               than this, relative ... */
  int rel_decrease_count;   /* 2: ... this many times in a row */
  double hold_tau;          /* 0.25: with o.hold_retries, a solve held
                               past its budget goes on with each step cut
                               below this tried again with the vertices of
                               the prisms that hold it back held still
                               (vm_minimize_options) */

  /* phase 2, springback (springback.c) */
  double springback_grow;     /* 8: target heights grow at most 8 times the
                                 column length per continuation stage */
  int springback_stages;      /* 60: stages at most (8^60: always reaches T) */
  int springback_stage_iter;  /* 5: implicit iterations per intermediate stage
                                 (each starts near its answer) */
  int springback_budget_mult; /* 3: the last stage runs up to 3 times
                                 springback_iter while the step budget is not
                                 spent (the aircraft's wing tips) */

  /* phase 3, cutting (cutting.c) */
  int resolve_rings;  /* 4: rings around the cut columns that move in the
                         local re-solve */
  double cut_floor;   /* 1e-3: targets are not cut below this share of the
                         column's mean edge length (flatter is
                         numerically degenerate) */
  int stuck_rounds;   /* 10: a column cut in this many rounds ... */
  double stuck_ratio; /* 2: ... still longer than twice its target is
                         shortened directly (a fold the solve does not
                         undo) */

  /* phase 4, restoring (restore.c) */
  double restore_qshare;        /* 0.1: a move may not leave a prism below a tenth
                                   of its quality at the start (a share, not a
                                   floor: fan prisms start near 0.01) */
  int restore_quality_rounds;   /* 200: back-off rounds at most for quality */
  double restore_backoff;       /* 0.5: a column sent back halves its step */
  int restore_zone_rings;       /* 3: rings around cut columns that restore with
                                   half steps from the start */
  double restore_zone_alpha;    /* 0.5: the step there */
  double restore_smooth_weight; /* 0.5: a cut column's Laplace-Beltrami step
                                   goes halfway to the projected mean */
  double restore_min_step;      /* 1e-3: steps below this share of T are not taken,
                                   so few columns move and the intersection query
                                   stays incremental */
  double restore_freeze_alpha;  /* 1/64: after six halvings against an
                                   intersection the cap is frozen there */
  int restore_back_rounds;      /* 20: intersection back-off rounds per pass */
  int slot_rounds;              /* 4: rounds of slot opening (restore.c,
                                   open_slots; its clearance is
                                   o.slot_clearance) */
  double slot_face_deg;         /* 60: "faces": the triangle that stops the
                                   ball is within this of opposite */
  double slot_min;              /* 0.3: lowered at most to this share of
                                   the column's aim */
  double slot_qshare;           /* 0.5: a lowering may not leave a prism
                                   below this share of its quality */
  int slot_halvings;            /* 8: halvings of a lowering against that
                                   before the column stays where it was */
  double restore_stop_change;   /* 1e-6: the passes stop when no column moved
                                   more than this share of T */

  /* phase 5, marching (march.c) */
  double split_mul[5];             /* {1, 0.8, 1.25, 0.64, 1.5}: factors of the
                                      schedule's split fraction tried where the
                                      straight split is not valid */
  double end_count_round;          /* 0.5: with a layer count per region, a column
                                      takes as many of the schedule's heights as
                                      fit its aim, the last one counted where
                                      the sum passes the aim by at most half of
                                      it (the nearest level boundary) */
  int end_certify_depth;           /* 6: subdivision levels of the Bernstein
                                      certificate of a pyramid where layers end
                                      (vm_jacobian_certify) */
  double end_short_gain;           /* 0.5: a patch of short columns given the
                                      layers that fit them (end_short) is kept
                                      where its faces' cells below OpenFOAM's
                                      determinant limit fall to at most this
                                      share of what they were: on vm-gen
                                      aircraft and plane.stl no patch lowers
                                      them at all (the transition cells are as
                                      flat), on two spheres 0.03 apart at T =
                                      0.10 they fall 2,409 -> 119 */
  double split_max_frac;           /* 0.9: a changed split never takes more than 90 %
                                      of the remainder (the outer sublayer would be a
                                      sliver) */
  double min_target_height;        /* 1e-4: marching's targets are at least this
                                      share of the mean edge length high (a column
                                      cut to nothing still gets a proper target) */
  double tilt_limit_deg;           /* 5: the first layer's orthogonality target in
                                      degrees (the report counts the smooth columns
                                      beyond it) */
  double ortho_qmin;               /* 0.3: standing up never has to keep a prism
                                      better than this ... */
  double ortho_round_share;        /* 0.5: ... nor, all columns at once, better than
                                      half its quality before */
  double ortho_alone_share;        /* 0.25: a column standing up alone (or with its
                                      ring) keeps its prisms above a quarter of
                                      their quality before */
  int ortho_layers;                /* 24: layers measured when columns stand up */
  int ortho_bend;                  /* 6: layers over which a column bends back to its
                                      course when all stand up at once */
  int ortho_rounds;                /* 100: rounds sending columns back at most */
  int ortho_bends[PR_NBENDS];      /* {6, 12, 9, 18, 0, 3, 2, 1}: bends tried
                                      alone, in layers (0: all measured layers);
                                      the long ones for columns tilted far over */
  int ortho_passes;                /* 4: passes over the columns that went back (a
                                      neighbour standing up can make room) */
  int growth_sweeps;               /* 3: sweeps of the growth relief (march.c) over the
                                      columns off the growth band (a neighbour moved can
                                      make room: 50 -> 27 -> 22 columns on the demo
                                      aircraft at T = 5 % after one sweep and three) */
  double growth_parts[5];          /* {1, 0.75, 0.5, 0.25, 0.125}: shares of the way to
                                      its schedule a column tries, in order */
  double growth_sj_floor;          /* 0.05: the growth relief never lowers a column's
                                      least scaled Jacobian below min(this, its value
                                      before) (issue 24's floor) */
  double ortho_lean_deg;           /* 4.5: the last resort leans by this much, within
                                      the 5 degree target */
  double ortho_high_ratio;         /* 0.5: a first level more than twice as high as
                                      its neighbours' mean is lowered to it */
  double redistribute_tol;         /* 0.05: a column whose levels are all within 5 %
                                      of their layer's scheduled height of the
                                      schedule's place is left as it is */
  int redistribute_sweeps;         /* 3: sweeps over the columns off their schedule
                                      (one refused beside neighbours still off
                                      theirs may fit once they are on it) */
  double redistribute_qshare;      /* 0.1: ... and whose prisms stay above a tenth
                                      of their quality before (a fan's wedge prism
                                      starts near 0.03 and loses more than half of
                                      it as its long first level comes down) */
  double skew_limit;               /* 3.6: the stack smoothing and the columns put
                                      on the schedule may not raise OpenFOAM's
                                      skewness of a face above this (checkMesh
                                      fails at 4) */
  double relief_gamma[10];         /* {0.8, 0.65, 0.5, 0.4, 0.3, 0.2, 0.14, 0.1,
                                     1.25, 1.6}: exponents
                                     tried by the skewness relief (level k of a
                                     skewed column at the share frac_k^gamma of
                                     its length) */
  int relief_sweeps;               /* 3: sweeps of the skewness relief */
  double ortho_relief_deg;         /* 60: the non-orthogonality relief (ortho.c)
                                      weighs faces beyond this angle ... */
  double ortho_relief_active_deg;  /* 65: ... around the vertices of the cells
                                  on faces beyond this (checkMesh's 70 with a
                                  margin) */
  int ortho_relief_sweeps;         /* 20: sweeps at most ... */
  double ortho_relief_gain;        /* 0.01: ... ending when one lowers the count of
                                      faces beyond 70 degrees by less than 1 % */
  double ortho_relief_step;        /* 0.5: a step moves a vertex at most this share
                                      of its local size (the shorter of its wall
                                      edges and its column's span over its cells)
                                      ... */
  int ortho_relief_backtracks;     /* 10: ... halved at most this often */
  double ortho_relief_qshare;      /* 0.5: a step keeps every prism around above
                                      min(ortho_qmin, half its quality before) */
  double ortho_relief_growth_band; /* 1.5: nor takes a ratio of successive
                                 heights outside [G / 1.5, 1.5 G], G the
                                 growth ratio (issue 24's band) */
  double ortho_relief_wmin;        /* 0.1: nor lowers a face's interpolation weight
                                      below this (checkMesh fails at 0.05) */
  double ortho_relief_outer_angle; /* 20: an outer vertex's step keeps the smallest
                                      angle of its outer triangles at least
                                      min(this, what it was): the far field's tets
                                      grow from them (without it, on an M6 wing,
                                      the fill's tets on the envelope with a small
                                      determinant went from 109 to 216) */
  int ortho_relief_outer_tries;    /* 8: the outer vertices' steps of a sweep go as
                                      one batch, the layer's crossings queried
                                      after it; a batch that crosses something new
                                      is undone and taken again without the steps
                                      near the crossing, at most this often (0: the
                                      outer surface does not move) */
  double split_margin;             /* 0.02: the split repair (ortho.c) lowers the
                                      sum of max(0, 0.02 - q)^2 over the tets of
                                      two bottom and two top vertices, q their
                                      det / edge-length product (about 0.7 on a
                                      right prism): a margin, so a repaired cell
                                      is not left at the edge of rounding */
  double split_cos_slack;          /* 0.005: ... and may lower the worst face's
                                      non-orthogonality cosine by this much
                                      (0.3 degrees near 80) where it is beyond
                                      70 degrees already (no more faces beyond 70) */
  double split_qshare;             /* 0.25: ... keeps every prism around above
                                      min(k.ortho_qmin, 0.25 of its quality
                                      before the relief) (the relief's 0.5 left
                                      cells pinned at their floor, holding the
                                      last twisted cells of the coarse
                                      aircraft), and no cell's scaled Jacobian
                                      below the stack's least when it starts */
  int split_rounds;                /* 200: rounds of the repair at most (each a
                                      step at every vertex of a failing cell;
                                      plane.stl at 20 % stops by itself) */
  int split_stall_rounds;          /* 20: the repair stops after this many rounds
                                      without a new least count of failing cells
                                      (vm-gen wing's own vertices at 5 %: 371
                                      from round 60 to 200, 88 s of 107) */
  double det_relief_limit;         /* 0.003: the relief also weighs the cells
                                      whose OpenFOAM determinant (over their
                                      faces inside the hybrid mesh) is below
                                      this, by (log10(0.003 / det))^2, and
                                      visits their vertices (checkMesh fails
                                      below 0.001: a margin) */
  double ortho_relief_fd;          /* 1e-6: finite-difference step of the gradient,
                                      a share of the local size */
  double stack_lean_deg;           /* 45: a prism of layers 1..n-1 whose centroids'
                                      line leans beyond this from its base normal
                                      sends its columns to the stack smoothing */
  int stack_iter;                  /* 20: implicit iterations of the stack
                                      smoothing */
  double tilt_solve_deg;           /* 4.5: smooth columns tilted beyond this go to the
                                      patch solve */
  int solve_rings;                 /* 2: rings of neighbours moving with them */
  double solve_weight;             /* 1e4: weight (12) of the first layer in the patch
                                      (10^2 left 6 of the aircraft's columns tilted) */
  int solve_iter;                  /* 50: Newton iterations per chunk of a patch solve */
  int solve_tries;                 /* 4: solves at most, holding the neighbours one
                                      tilted */
  int solve_chunks;                /* 6: chunks at most (each restarts Newton, which
                                      gets further than one long solve) */

  /* the room the geometry leaves (medial.c, the report) */
  double medial_cap;     /* 4: balls start at 4 T; a radius of 4 T means "at
                            least": the figures only compare it with T */
  double medial_sep_deg; /* 30: triangles whose normal is within 30 degrees of
                            the vertex normal do not stop its ball (a faceted
                            concave surface would stop every ball at once) */
  int medial_iter;       /* 100: shrinking steps at most (a ball halves at
                            worst near a concave fold) */
  double medial_rel_tol; /* 1e-10: a ball is empty if no obstacle is nearer its
                            centre than (1 - 1e-10) r^2, squared (p itself is
                            at r) */
  double medial_floor;   /* 1e-6: a radius below 1e-6 of the mean edge length
                            is 0 (a concave fold's vertex) */
  double medial_room;    /* 1.05: a column has room for T where its radius is
                            at least 1.05 T */
  double gap_share;      /* 0.25: a wall vertex is in a gap narrower than half
                            its triangles' edges where its ball (half the gap)
                            is stopped closer than this share of its mean edge
                            by a triangle facing back (within slot_face_deg of
                            opposite) */

  pr_isect_params isect;
} pr_params;

/* The defaults above. */
static inline pr_params pr_params_default(void) {
  pr_params k = {
      .degenerate_area = 1e-14,
      .smooth_angle_deg = 10,
      .dir_blend_passes = 3,
      .dir = {.visible_min = 0.2,
              .visible_iter = 200,
              .sharp_visibility = 0.94,
              .blend_weight = 0.5,
              .blend_keep = 0.3,
              .target_blend = {0, 0.25, 0.5, 0.75, 1},
              .target_quality = 0.5,
              .fair_quality = 0.05},
      .sched_fit_tol = 1e-9,
      .sched_bisect_iter = 200,
      .first_slope = 0.01,
      .region_slope = 0.5,
      .thin_height = 0.5,
      .thin_limit_height = 1e-6,
      .thin_rounds = 60,
      .thin_quality_share = 0.5,
      .thin_quality_cap = 0.3,
      .thin_shrink = 0.5,
      .thin_grade = 0.5,
      .thin_grade_sweeps = 2,
      .budget_step_share = 0.25,
      .budget_fall_window = 10,
      .budget_fall = 0.01,
      .rel_decrease_tol = 1e-5,
      .rel_decrease_count = 2,
      .hold_tau = 0.25,
      .springback_grow = 8,
      .springback_stages = 60,
      .springback_stage_iter = 5,
      .springback_budget_mult = 3,
      .resolve_rings = 4,
      .cut_floor = 1e-3,
      .stuck_rounds = 10,
      .stuck_ratio = 2,
      .restore_qshare = 0.1,
      .restore_quality_rounds = 200,
      .restore_backoff = 0.5,
      .restore_zone_rings = 3,
      .restore_zone_alpha = 0.5,
      .restore_smooth_weight = 0.5,
      .restore_min_step = 1e-3,
      .restore_freeze_alpha = 1.0 / 64,
      .restore_back_rounds = 20,
      .slot_rounds = 4,
      .slot_face_deg = 60,
      .slot_min = 0.3,
      .slot_qshare = 0.5,
      .slot_halvings = 8,
      .restore_stop_change = 1e-6,
      .split_mul = {1, 0.8, 1.25, 0.64, 1.5},
      .split_max_frac = 0.9,
      .end_count_round = 0.5,
      .end_certify_depth = 6,
      .end_short_gain = 0.5,
      .min_target_height = 1e-4,
      .tilt_limit_deg = 5,
      .medial_cap = 4,
      .medial_sep_deg = 30,
      .medial_iter = 100,
      .medial_rel_tol = 1e-10,
      .medial_floor = 1e-6,
      .medial_room = 1.05,
      .gap_share = 0.25,
      .ortho_qmin = 0.3,
      .ortho_round_share = 0.5,
      .ortho_alone_share = 0.25,
      .ortho_layers = 24,
      .ortho_bend = 6,
      .ortho_rounds = 100,
      .ortho_bends = {6, 12, 9, 18, 0, 3, 2, 1},
      .ortho_passes = 4,
      .growth_sweeps = 3,
      .growth_parts = {1, 0.75, 0.5, 0.25, 0.125},
      .growth_sj_floor = 0.05,
      .ortho_lean_deg = 4.5,
      .ortho_high_ratio = 0.5,
      .redistribute_tol = 0.05,
      .redistribute_sweeps = 3,
      .redistribute_qshare = 0.1,
      .skew_limit = 3.6,
      .relief_gamma = {0.8, 0.65, 0.5, 0.4, 0.3, 0.2, 0.14, 0.1, 1.25, 1.6},
      .relief_sweeps = 3,
      .ortho_relief_deg = 60,
      .ortho_relief_active_deg = 65,
      .ortho_relief_sweeps = 20,
      .ortho_relief_gain = 0.01,
      .ortho_relief_step = 0.5,
      .ortho_relief_backtracks = 10,
      .ortho_relief_qshare = 0.5,
      .ortho_relief_growth_band = 1.5,
      .ortho_relief_wmin = 0.1,
      .ortho_relief_outer_angle = 20,
      .ortho_relief_outer_tries = 8,
      .det_relief_limit = 0.003,
      .ortho_relief_fd = 1e-6,
      .split_margin = 0.02,
      .split_rounds = 200,
      .split_stall_rounds = 20,
      .split_qshare = 0.25,
      .split_cos_slack = 0.005,
      .stack_lean_deg = 45,
      .stack_iter = 20,
      .tilt_solve_deg = 4.5,
      .solve_rings = 2,
      .solve_weight = 1e4,
      .solve_iter = 50,
      .solve_tries = 4,
      .solve_chunks = 6,
      .isect = {.orient_tol_sq = 1e-24,
                .box_pad = 1e-6,
                .ray_extend = 1e-5,
                .ray_chunk = 256,
                .full_query_ratio = 4},
  };
  return k;
}

#endif
