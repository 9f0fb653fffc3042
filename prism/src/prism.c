/* prism/src/prism.c: the layer builder's run: options, wall import and
 * adjacency, the schedule of heights, the state's life, the phases in
 * order (vm_prism_run). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "state.h"

const char *vm_prism_phase_name(vm_prism_phase ph) {
  static const char *const names[] = {"thin", "springback", "cut", "restore", "march"};
  return (int)ph >= 0 && ph < VM_PRISM_NPHASES ? names[ph] : "unknown";
}

const char *vm_prism_march_step_name(int k) {
  static const char *const names[VM_PRISM_NMARCH_STEPS] = {
      "splits",           "stack_smoothing", "redistribution",  "orthogonal_first_level",
      "orthogonal_solve", "skewness_relief", "nonortho_relief", "growth_relief"};
  return k >= 0 && k < VM_PRISM_NMARCH_STEPS ? names[k] : "unknown";
}

double vm_prism_yplus_height(double yplus, double reynolds, double ref_length) {
  if (!(yplus > 0) || !(ref_length > 0) || !(reynolds >= 10 && reynolds <= 1e12) ||
      !isfinite(yplus) || !isfinite(ref_length))
    return NAN;
  double cf = pow(2 * log10(reynolds) - 0.65, -2.3);
  return yplus * ref_length / (reynolds * sqrt(0.5 * cf));
}

vm_prism_opts vm_prism_opts_default(void) {
  vm_prism_opts o;
  memset(&o, 0, sizeof o);
  o.thickness = 0;
  o.nlayers = 20;
  o.first_height = 0;
  o.growth = 1.2;
  o.max_aspect = 30;
  o.theta = 0.8;
  o.cut_factor = 0.85;
  o.springback_iter = 100;
  o.hold_retries = 0;
  o.slot_clearance = 0.5;
  o.resolve_iter = 6;
  o.max_cut_rounds = 400;
  o.smooth_iter = 30;
  o.march_iter = 8;
  o.ortho_weight = 10;
  o.drop_quality = 0;
  o.full_tol = 0.01;
  o.time_limit = 0;
  o.check_incremental = 0;
  o.orient = 1;
  o.growth_relief = 1;
  o.end_short = 1;
  return o;
}

double pr_elapsed(const vm_prism *p) { return omp_get_wtime() - p->t0; }

double pr_time_left(const vm_prism *p) {
  if (vm_ctx_interrupted(p->ctx)) return 0;
  return p->o.time_limit > 0 ? p->o.time_limit - pr_elapsed(p) : INFINITY;
}

void pr_progress(vm_prism *p, vm_prism_phase ph, int step, double value, int64_t count,
                 int solver) {
  if (!p->o.progress) return;
  vm_prism_progress pg = {ph, step, value, count, pr_elapsed(p), solver};
  p->o.progress(p->o.user, &pg);
}

static int check_opts(vm_ctx *ctx, const vm_prism_opts *o) {
  if (!(o->thickness > 0) || !isfinite(o->thickness))
    return vm_error(ctx, VM_ERR_ARG, "prism: thickness %g must be positive", o->thickness);
  if (o->nlayers < 1 || o->nlayers > 1000)
    return vm_error(ctx, VM_ERR_ARG, "prism: %d layers (1..1000)", o->nlayers);
  if (!(o->first_height > 0) && !(o->growth >= 1))
    return vm_error(ctx, VM_ERR_ARG, "prism: give a first height or a growth ratio >= 1");
  if (o->first_height > 0 && o->first_height > o->thickness)
    return vm_error(ctx, VM_ERR_ARG, "prism: first height %g exceeds the thickness %g",
                    o->first_height, o->thickness);
  if (o->growth > 0 && !(o->growth >= 1 && o->growth <= 10))
    return vm_error(ctx, VM_ERR_ARG, "prism: growth ratio %g (1..10)", o->growth);
  if (!(o->max_aspect >= 0) || !isfinite(o->max_aspect))
    return vm_error(ctx, VM_ERR_ARG, "prism: max aspect %g (>= 0; 0: off)", o->max_aspect);
  if (!(o->theta > 0 && o->theta < 1))
    return vm_error(ctx, VM_ERR_ARG, "prism: theta %g not in (0, 1)", o->theta);
  if (!(o->cut_factor >= 0.5 && o->cut_factor < 1))
    return vm_error(ctx, VM_ERR_ARG, "prism: cut factor %g not in [0.5, 1)", o->cut_factor);
  if (!(o->slot_clearance >= 0 && o->slot_clearance <= 2))
    return vm_error(ctx, VM_ERR_ARG, "prism: slot clearance %g (0..2; 0: off)", o->slot_clearance);
  if (o->hold_retries != 0 && o->hold_retries != 1)
    return vm_error(ctx, VM_ERR_ARG, "prism: hold_retries %d (0 or 1)", o->hold_retries);
  if (o->springback_iter < 0 || o->resolve_iter < 0 || o->max_cut_rounds < 0 ||
      o->smooth_iter < 0 || o->march_iter < 0)
    return vm_error(ctx, VM_ERR_ARG, "prism: negative iteration limit");
  if (o->symmetry_axis < -1 || o->symmetry_axis > 3 ||
      (o->symmetry_axis > 0 && !isfinite(o->symmetry_value)))
    return vm_error(ctx, VM_ERR_ARG, "prism: symmetry axis %d (-1..3) or value %g",
                    o->symmetry_axis, o->symmetry_value);
  if (!(o->ortho_weight >= 1) || !isfinite(o->ortho_weight))
    return vm_error(ctx, VM_ERR_ARG, "prism: orthogonality weight %g (>= 1)", o->ortho_weight);
  if (!(o->drop_quality >= 0 && o->drop_quality < 1) || !(o->full_tol >= 0 && o->full_tol < 1))
    return vm_error(ctx, VM_ERR_ARG, "prism: drop quality or full tolerance out of [0, 1)");
  return VM_OK;
}

double pr_growth_ratio(double h1, int n, double len, int iters) {
  double lo = 1, hi = 2;
  while (h1 * (pow(hi, n) - 1) / (hi - 1) < len) hi *= 2;
  for (int it = 0; it < iters; it++) {
    double mid = 0.5 * (lo + hi);
    if (h1 * (pow(mid, n) - 1) / (mid - 1) < len)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

/* The schedule of layer heights h_k = h1 r^k summing to T. */
static int build_schedule(vm_prism *p) {
  const vm_prism_opts *o = &p->o;
  const pr_params *kp = &p->k;
  int n = o->nlayers;
  double T = o->thickness, r = o->growth, h1 = o->first_height;
  if (h1 > 0 && r >= 1) {
    /* both given: keep the growth law, as many layers as fit (<= n); the
     * last one takes the remainder */
    double s = 0;
    int k = 0;
    while (k < n && s + h1 * pow(r, k) < T * (1 - kp->sched_fit_tol)) s += h1 * pow(r, k++);
    if (k < n) n = k + 1;
  } else if (h1 > 0) {
    /* solve h1 (r^n - 1)/(r - 1) = T for r >= 1 by bisection */
    if (h1 * n >= T) {
      r = 1;
      h1 = T / n;
    } else {
      r = pr_growth_ratio(h1, n, T, kp->sched_bisect_iter);
    }
  } else {
    h1 = r == 1 ? T / n : T * (r - 1) / (pow(r, n) - 1);
  }
  p->sched = vm_alloc_array(p->ctx, (size_t)n, sizeof *p->sched);
  if (!p->sched) return VM_ERR_NOMEM;
  double s = 0;
  for (int k = 0; k < n; k++) {
    p->sched[k] = h1 * pow(r, k);
    if (k == n - 1 || s + p->sched[k] > T) p->sched[k] = T - s;
    s += p->sched[k];
  }
  p->rep.layers_requested = n;
  p->rep.first_height = p->sched[0];
  p->rep.growth = r;
  return VM_OK;
}

static int cmp_i32(const void *a, const void *b) {
  int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

typedef struct {
  int32_t a, b, t;
} half_edge;

static int cmp_he(const void *x, const void *y) {
  const half_edge *a = x, *b = y;
  if (a->a != b->a) return a->a < b->a ? -1 : 1;
  if (a->b != b->b) return a->b < b->b ? -1 : 1;
  return (a->t > b->t) - (a->t < b->t);
}

static int cmp_pair(const void *x, const void *y) {
  const int32_t *a = x, *b = y;
  if (a[0] != b[0]) return a[0] < b[0] ? -1 : 1;
  return (a[1] > b[1]) - (a[1] < b[1]);
}

int vm_prism_half_plane(vm_ctx *ctx, const vm_mesh *wall, int *axis, double *value) {
  *axis = -1;
  *value = 0;
  int64_t ne = 0;
  for (int64_t e = 0; e < wall->ne; e++)
    ne += wall->etype[e] == VM_TRI ? 3 : wall->etype[e] == VM_QUAD ? 4 : 0;
  if (!ne) return 0;
  int32_t *ed = vm_alloc_array(ctx, (size_t)(2 * ne), sizeof *ed);
  if (!ed) return VM_ERR_NOMEM;
  int64_t k = 0;
  for (int64_t e = 0; e < wall->ne; e++) {
    int n = wall->etype[e] == VM_TRI ? 3 : wall->etype[e] == VM_QUAD ? 4 : 0;
    const int32_t *c = wall->conn + wall->eoff[e];
    for (int i = 0; i < n; i++, k++) {
      int32_t a = c[i], b = c[(i + 1) % n];
      ed[2 * k] = a < b ? a : b;
      ed[2 * k + 1] = a < b ? b : a;
    }
  }
  qsort(ed, (size_t)ne, 2 * sizeof *ed, cmp_pair);
  int found = 0, live[3] = {1, 1, 1};
  double c0[3] = {0, 0, 0};
  for (int64_t i = 0; i < ne;) {
    int64_t j = i + 1;
    while (j < ne && ed[2 * j] == ed[2 * i] && ed[2 * j + 1] == ed[2 * i + 1]) j++;
    if (j - i == 1)
      for (int s = 0; s < 2; s++) {
        const double *x = wall->xyz + 3 * (int64_t)ed[2 * i + s];
        for (int a = 0; a < 3; a++) {
          if (!found) c0[a] = x[a];
          live[a] = live[a] && x[a] == c0[a];
        }
        found = 1;
      }
    i = j;
  }
  vm_free(ctx, ed);
  for (int a = 0; found && a < 3; a++)
    if (live[a]) {
      *axis = a;
      *value = c0[a];
      return 1;
    }
  return 0;
}

/* An open wall: a half model if its open boundary lies in a plane x, y or
 * z = const, bit for bit (the one asked for, o.symmetry_axis 1..3, or the
 * one it lies in, 0), in simple loops, the wall on one side of it. Sets
 * the plane and the columns in it; refuses anything else with where. */
static int half_model(vm_prism *p, int64_t open) {
  vm_ctx *ctx = p->ctx;
  const vm_prism_opts *o = &p->o;
  static const char axn[] = "xyz";
  if (o->symmetry_axis < 0)
    return vm_error(ctx, VM_ERR_ARG, "prism: the wall is not closed (%lld open edges)",
                    (long long)open);
  uint8_t *deg = vm_calloc(ctx, (size_t)p->nw, sizeof *deg);
  if (!deg) return VM_ERR_NOMEM;
  int64_t first = -1;
  for (int64_t e = 0; e < p->ned; e++)
    if (p->etri[2 * e + 1] < 0)
      for (int s = 0; s < 2; s++) {
        int32_t v = p->edge[2 * e + s];
        if (deg[v] < 255) deg[v]++;
        if (first < 0) first = v;
      }
  int64_t nb = 0;
  for (int64_t v = 0; v < p->nw; v++) {
    if (!deg[v]) continue;
    nb++;
    if (deg[v] != 2) {
      const double *x = p->wall + 3 * v;
      int d = deg[v];
      vm_free(ctx, deg);
      return vm_error(ctx, VM_ERR_ARG,
                      "prism: the wall's open boundary is not a set of simple loops: %d open "
                      "edges meet at (%g, %g, %g)",
                      d, x[0], x[1], x[2]);
    }
  }
  /* the plane: asked for, or the axis on which every border vertex has
   * the first one's coordinate exactly */
  int ax = o->symmetry_axis - 1;
  double c = o->symmetry_value;
  if (ax < 0) {
    for (int a = 0; a < 3 && ax < 0; a++) {
      double c0 = p->wall[3 * first + a];
      int all = 1;
      for (int64_t v = 0; v < p->nw && all; v++)
        if (deg[v]) all = p->wall[3 * v + a] == c0;
      if (all) {
        ax = a;
        c = c0;
      }
    }
  }
  if (ax < 0) {
    /* no such plane: the nearest one (the axis whose border coordinates
     * spread least, at their midrange) and its farthest vertex */
    double best = INFINITY, bc = 0;
    int ba = 0;
    for (int a = 0; a < 3; a++) {
      double lo = INFINITY, hi = -INFINITY;
      for (int64_t v = 0; v < p->nw; v++)
        if (deg[v]) {
          lo = fmin(lo, p->wall[3 * v + a]);
          hi = fmax(hi, p->wall[3 * v + a]);
        }
      if (hi - lo < best) {
        best = hi - lo;
        ba = a;
        bc = 0.5 * (lo + hi);
      }
    }
    int64_t far = first;
    for (int64_t v = 0; v < p->nw; v++)
      if (deg[v] && fabs(p->wall[3 * v + ba] - bc) > fabs(p->wall[3 * far + ba] - bc)) far = v;
    const double *x = p->wall + 3 * far;
    vm_free(ctx, deg);
    return vm_error(ctx, VM_ERR_ARG,
                    "prism: the wall is not closed (%lld open edges) and its open boundary is "
                    "not in a plane x, y or z = const, as a half model's is: the nearest is "
                    "%c = %g, and the border vertex (%g, %g, %g) is %g off it (vm-surface puts "
                    "a half model's border on its plane)",
                    (long long)open, axn[ba], bc, x[0], x[1], x[2], fabs(x[ba] - bc));
  }
  /* every border vertex exactly in it (the plane asked for) */
  for (int64_t v = 0; v < p->nw; v++)
    if (deg[v] && p->wall[3 * v + ax] != c) {
      int64_t far = v;
      for (int64_t u = v; u < p->nw; u++)
        if (deg[u] && fabs(p->wall[3 * u + ax] - c) > fabs(p->wall[3 * far + ax] - c)) far = u;
      const double *x = p->wall + 3 * far;
      vm_free(ctx, deg);
      return vm_error(ctx, VM_ERR_ARG,
                      "prism: the wall's open boundary is not on the symmetry plane %c = %g: "
                      "the border vertex (%g, %g, %g) is %g off it",
                      axn[ax], c, x[0], x[1], x[2], fabs(x[ax] - c));
    }
  /* the wall on one side: the side of the vertex farthest from the plane */
  int64_t far = 0;
  for (int64_t v = 1; v < p->nw; v++)
    if (fabs(p->wall[3 * v + ax] - c) > fabs(p->wall[3 * far + ax] - c)) far = v;
  double side = p->wall[3 * far + ax] > c ? 1 : -1;
  for (int64_t v = 0; v < p->nw; v++) {
    const double *x = p->wall + 3 * v;
    if (deg[v] || (x[ax] - c) * side > 0) continue;
    vm_free(ctx, deg);
    return vm_error(ctx, VM_ERR_ARG,
                    "prism: the half model's wall %s its symmetry plane %c = %g at (%g, %g, "
                    "%g), away from its open boundary",
                    (x[ax] - c) * side < 0 ? "crosses" : "touches", axn[ax], c, x[0], x[1], x[2]);
  }
  for (int64_t v = 0; v < p->nw; v++) deg[v] = deg[v] ? 1 : 0;
  p->onsym = deg;
  p->nsym = nb;
  p->sym_ax = ax;
  p->sym_val = c;
  p->sym_side = side;
  vm_log(ctx, VM_LOG_INFO,
         "prism: a half model: the wall's open boundary (%lld edges, %lld vertices) lies in the "
         "symmetry plane %c = %g; its columns stay in it",
         (long long)open, (long long)nb, axn[ax], c);
  return VM_OK;
}

static int build_adjacency(vm_prism *p) {
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt;
  p->vt_off = vm_calloc(ctx, (size_t)nw + 1, sizeof *p->vt_off);
  p->vt = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *p->vt);
  half_edge *he = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *he);
  if (!p->vt_off || !p->vt || !he) {
    vm_free(ctx, he);
    return VM_ERR_NOMEM;
  }
  for (int64_t k = 0; k < 3 * nt; k++) p->vt_off[p->tri[k] + 1]++;
  for (int64_t v = 0; v < nw; v++) p->vt_off[v + 1] += p->vt_off[v];
  int64_t *fill = vm_alloc_array(ctx, (size_t)nw + 1, sizeof *fill);
  if (!fill) {
    vm_free(ctx, he);
    return VM_ERR_NOMEM;
  }
  memcpy(fill, p->vt_off, (size_t)(nw + 1) * sizeof *fill);
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) p->vt[fill[p->tri[3 * t + i]]++] = (int32_t)t;
  for (int64_t t = 0; t < nt; t++)
    for (int i = 0; i < 3; i++) {
      int32_t a = p->tri[3 * t + i], b = p->tri[3 * t + (i + 1) % 3];
      he[3 * t + i] = (half_edge){a < b ? a : b, a < b ? b : a, (int32_t)t};
    }
  qsort(he, (size_t)(3 * nt), sizeof *he, cmp_he);
  int64_t ned = 0;
  for (int64_t k = 0; k < 3 * nt; k++)
    if (k == 0 || he[k].a != he[k - 1].a || he[k].b != he[k - 1].b) ned++;
  p->ned = ned;
  p->edge = vm_alloc_array(ctx, (size_t)(2 * ned), sizeof *p->edge);
  p->etri = vm_alloc_array(ctx, (size_t)(2 * ned), sizeof *p->etri);
  p->vv_off = vm_calloc(ctx, (size_t)nw + 1, sizeof *p->vv_off);
  p->vv = vm_alloc_array(ctx, (size_t)(2 * ned), sizeof *p->vv);
  p->elen = vm_calloc(ctx, (size_t)nw, sizeof *p->elen);
  if (!p->edge || !p->etri || !p->vv_off || !p->vv || !p->elen) {
    vm_free(ctx, he);
    vm_free(ctx, fill);
    return VM_ERR_NOMEM;
  }
  /* non-manifold edges counted once each, as vm-surface's repair counts
   * them: the first one, and how many triangles share it, for the message */
  int64_t nonman = 0, nm_first = -1, nm_count = 0, run = 0;
  for (int64_t k = 0, e = -1; k < 3 * nt; k++) {
    if (k == 0 || he[k].a != he[k - 1].a || he[k].b != he[k - 1].b) {
      run = 1;
      e++;
      p->edge[2 * e] = he[k].a;
      p->edge[2 * e + 1] = he[k].b;
      p->etri[2 * e] = he[k].t;
      p->etri[2 * e + 1] = -1;
    } else if (p->etri[2 * e + 1] < 0) {
      run++;
      p->etri[2 * e + 1] = he[k].t;
    } else {
      if (++run == 3) nonman++;
      if (nonman == 1) {
        nm_first = e;
        nm_count = run;
      }
    }
  }
  vm_free(ctx, he);
  if (nonman) {
    vm_free(ctx, fill);
    const double *a = p->wall + 3 * (int64_t)p->edge[2 * nm_first],
                 *b = p->wall + 3 * (int64_t)p->edge[2 * nm_first + 1];
    return vm_error(ctx, VM_ERR_ARG,
                    "prism: non-manifold wall: %lld edges are shared by more than two "
                    "triangles; the first, (%g, %g, %g)-(%g, %g, %g), by %lld",
                    (long long)nonman, a[0], a[1], a[2], b[0], b[1], b[2], (long long)nm_count);
  }
  /* a closed, consistently oriented wall: every edge has two triangles
   * that run through it in opposite directions */
  int64_t open = 0, flipped = 0;
  for (int64_t e = 0; e < ned; e++) {
    if (p->etri[2 * e + 1] < 0) {
      open++;
      continue;
    }
    int dirs = 0;
    for (int s = 0; s < 2; s++) {
      const int32_t *c = p->tri + 3 * (int64_t)p->etri[2 * e + s];
      for (int i = 0; i < 3; i++)
        if (c[i] == p->edge[2 * e] && c[(i + 1) % 3] == p->edge[2 * e + 1]) dirs++;
    }
    if (dirs != 1) flipped++;
  }
  if (flipped) {
    vm_free(ctx, fill);
    return vm_error(ctx, VM_ERR_ARG, "prism: the wall is not consistently oriented (%lld edges)",
                    (long long)flipped);
  }
  int st = open ? half_model(p, open) : VM_OK;
  if (!open && p->o.symmetry_axis > 0)
    st = vm_error(ctx, VM_ERR_ARG,
                  "prism: a symmetry plane was asked for, but the wall is closed (a half "
                  "model's wall is open, its border in the plane)");
  if (st < 0) {
    vm_free(ctx, fill);
    return st;
  }
  for (int64_t e = 0; e < ned; e++) {
    p->vv_off[p->edge[2 * e] + 1]++;
    p->vv_off[p->edge[2 * e + 1] + 1]++;
  }
  for (int64_t v = 0; v < nw; v++) p->vv_off[v + 1] += p->vv_off[v];
  memcpy(fill, p->vv_off, (size_t)(nw + 1) * sizeof *fill);
  for (int64_t e = 0; e < ned; e++) {
    int32_t a = p->edge[2 * e], b = p->edge[2 * e + 1];
    p->vv[fill[a]++] = b;
    p->vv[fill[b]++] = a;
    double l = vm_dist3(p->wall + 3 * (int64_t)a, p->wall + 3 * (int64_t)b);
    p->elen[a] += l;
    p->elen[b] += l;
  }
  vm_free(ctx, fill);
  for (int64_t v = 0; v < nw; v++) {
    int64_t d = p->vv_off[v + 1] - p->vv_off[v];
    qsort(p->vv + p->vv_off[v], (size_t)d, sizeof *p->vv, cmp_i32);
    if (d) p->elen[v] /= (double)d;
  }
  return VM_OK;
}

/* f graded along the wall from below: f[v] = min over u of (f[u] + slope
 * * the shortest wall-edge path from u to v), by Dijkstra's method from
 * every vertex at once (a binary heap; the result is the unique fixed
 * point, whatever order ties are taken in). */
static int grade_along_wall(vm_prism *p, double *f, double slope) {
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw;
  /* heap of (value, vertex), lazily updated: at most nw + one entry per
   * directed edge */
  int64_t cap = nw + p->vv_off[nw], n = 0;
  struct he {
    double a;
    int32_t v;
  } *hp = vm_alloc_array(ctx, (size_t)cap, sizeof *hp);
  uint8_t *done = vm_calloc(ctx, (size_t)nw, sizeof *done);
  if (!hp || !done) {
    vm_free(ctx, hp);
    vm_free(ctx, done);
    return VM_ERR_NOMEM;
  }
#define HE_LESS(x, y) ((x).a < (y).a || ((x).a == (y).a && (x).v < (y).v))
#define HE_PUSH(A, V)                                                                              \
  do {                                                                                             \
    int64_t i_ = n++;                                                                              \
    struct he e_ = {(A), (V)};                                                                     \
    while (i_ > 0 && HE_LESS(e_, hp[(i_ - 1) / 2])) {                                              \
      hp[i_] = hp[(i_ - 1) / 2];                                                                   \
      i_ = (i_ - 1) / 2;                                                                           \
    }                                                                                              \
    hp[i_] = e_;                                                                                   \
  } while (0)
  for (int64_t v = 0; v < nw; v++) HE_PUSH(f[v], (int32_t)v);
  const double s = slope;
  while (n > 0) {
    struct he top = hp[0], last = hp[--n];
    int64_t i = 0;
    for (;;) {
      int64_t c = 2 * i + 1;
      if (c >= n) break;
      if (c + 1 < n && HE_LESS(hp[c + 1], hp[c])) c++;
      if (!HE_LESS(hp[c], last)) break;
      hp[i] = hp[c];
      i = c;
    }
    if (n > 0) hp[i] = last;
    int32_t v = top.v;
    if (done[v] || top.a > f[v]) continue;
    done[v] = 1;
    for (int64_t j = p->vv_off[v]; j < p->vv_off[v + 1]; j++) {
      int32_t u = p->vv[j];
      double a = f[v] + s * vm_dist3(p->wall + 3 * (int64_t)v, p->wall + 3 * (int64_t)u);
      if (!done[u] && a < f[u]) {
        f[u] = a;
        HE_PUSH(a, u);
      }
    }
  }
#undef HE_PUSH
#undef HE_LESS
  vm_free(ctx, hp);
  vm_free(ctx, done);
  return VM_OK;
}

/* With a thickness per wall face, each column's aim p->tv (on entry the
 * least of its triangles') graded along the wall at k.region_slope. */
static int region_aims(vm_prism *p) {
  return p->regional ? grade_along_wall(p, p->tv, p->k.region_slope) : VM_OK;
}

/* With a layer count per wall face, each column's count (on entry the
 * least of its faces') at most the schedule's layers that fit its graded
 * aim: the count of the first heights whose sum is nearest to it (the sum
 * may pass it by half the last height). Where a thicker region's columns
 * are shortened towards a thinner one, their layers then end one or a few
 * at a time along the slope, on the schedule's heights, instead of all at
 * the border in a fan of pyramids around one apex (on vm-gen aircraft at
 * resolution 1, fuselage at 10 of 20 layers: 2,005 faces beyond 70
 * degrees with the counts ending at the border, as against 1,246 with no
 * region). */
static void region_counts(vm_prism *p) {
  if (!p->nlv) return;
  int n = p->rep.layers_requested;
  for (int64_t v = 0; v < p->nw; v++) {
    /* a column aiming at T keeps its count (the schedule's last height
     * may be a short remainder: --first-height with --growth) */
    if (!(p->tv[v] < p->o.thickness)) continue;
    double s = 0;
    int k = 1;
    for (; k < n; k++) {
      s += p->sched[k - 1];
      if (s >= p->tv[v] - p->k.end_count_round * p->sched[k - 1]) break;
    }
    if (k < p->nlv[v]) p->nlv[v] = k;
  }
}

/* Each column's first height where the schedule's would make its cells
 * too thin for their width (opts max_aspect, without a first height asked
 * for): at least the longest wall edge at the column's vertex over
 * max_aspect, at most its aim over the layer count (equal heights). The
 * longest edge of every triangle at the vertex, so each of a prism's three
 * columns is at least its own width over max_aspect. On the demo aircraft
 * at T = 5 % (20 layers, growth 1.2: first height 0.0040 on wall edges up
 * to 0.6) 4,693 cells of the hybrid mesh failed OpenFOAM's determinant
 * check, 2,734 of them in the second layer; at max_aspect 30, 364 (the
 * sheared cells of leaning columns, and tets). p->h1v stays NULL where no
 * column is raised (the stage as before, bit for bit). */
static int first_heights(vm_prism *p) {
  double A = p->o.max_aspect, h1 = p->sched[0];
  int n = p->rep.layers_requested;
  p->rep.first_height_max = h1;
  if (!(A > 0) || n < 2) return VM_OK;
  double *h = vm_calloc(p->ctx, (size_t)p->nw, sizeof *h);
  if (!h) return VM_ERR_NOMEM;
  for (int64_t t = 0; t < p->nt; t++) {
    const int32_t *c = p->tri + 3 * t;
    double a = 0;
    for (int i = 0; i < 3; i++) {
      double l = vm_dist3(p->wall + 3 * (int64_t)c[i], p->wall + 3 * (int64_t)c[(i + 1) % 3]);
      a = l > a ? l : a;
    }
    for (int i = 0; i < 3; i++) h[c[i]] = a > h[c[i]] ? a : h[c[i]];
  }
  int64_t raised = 0;
  if (p->o.first_height > 0) {
    /* the height asked for (a y+) is kept; said where it is too thin */
    for (int64_t v = 0; v < p->nw; v++) raised += h[v] / A > h1 && p->tv[v] / n > h1;
    if (raised)
      vm_log(p->ctx, VM_LOG_INFO,
             "prism: the first height %g asked for makes the cells at %lld of %lld columns more "
             "than %g times wider than high (OpenFOAM's determinant check may fail there)",
             h1, (long long)raised, (long long)p->nw, A);
    vm_free(p->ctx, h);
    return VM_OK;
  }
  /* graded along the wall (the first heights of neighbouring columns
   * differ by at most k.first_slope times their distance): where they
   * jump, a level's height jumps with them (level k of two columns
   * differing in h1 by dh differ by up to about 8 dh halfway up at 20
   * layers), and the faces between layers lean */
  for (int64_t v = 0; v < p->nw; v++) h[v] = -h[v] / A;
  int st = grade_along_wall(p, h, p->k.first_slope);
  if (st < 0) {
    vm_free(p->ctx, h);
    return st;
  }
  for (int64_t v = 0; v < p->nw; v++) {
    double want = -h[v], equal = p->tv[v] / n;
    want = want < equal ? want : equal;
    h[v] = want > h1 ? want : h1;
    if (h[v] > h1) {
      raised++;
      if (h[v] > p->rep.first_height_max) p->rep.first_height_max = h[v];
    }
  }
  p->rep.first_raised = raised;
  if (!raised) {
    vm_free(p->ctx, h);
    return VM_OK;
  }
  p->h1v = h;
  vm_log(p->ctx, VM_LOG_INFO,
         "prism: first height %g, raised up to %g at %lld of %lld columns so no cell is more "
         "than %g times wider than high where the thickness allows (their layers grow more "
         "slowly; --max-aspect)",
         h1, p->rep.first_height_max, (long long)raised, (long long)p->nw, A);
  return VM_OK;
}

int vm_prism_create(vm_ctx *ctx, const vm_mesh *wall, const vm_prism_opts *opts, vm_prism **out) {
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_prism_create: out is NULL");
  *out = NULL;
  if (!wall) return vm_error(ctx, VM_ERR_ARG, "vm_prism_create: wall is NULL");
  vm_prism_opts o = opts ? *opts : vm_prism_opts_default();
  int st = check_opts(ctx, &o);
  if (st) return st;
  /* a wall that names its symmetry plane (the surface stage's output): that
   * plane, unless the options ask otherwise */
  int sax;
  double sval;
  if (o.symmetry_axis == 0 && (st = vm_mesh_get_symmetry_plane(wall, &sax, &sval)) != 0) {
    if (st < 0) return st;
    o.symmetry_axis = sax + 1;
    o.symmetry_value = sval;
  }
  int64_t nt = 0;
  for (int64_t e = 0; e < wall->ne; e++)
    nt += wall->etype[e] == VM_TRI ? 1 : wall->etype[e] == VM_QUAD ? 2 : 0;
  if (nt == 0) return vm_error(ctx, VM_ERR_ARG, "prism: the wall has no triangles");
  if (nt > INT32_MAX / 8 || wall->nv > INT32_MAX / 64)
    return vm_error(ctx, VM_ERR_ARG, "prism: the wall is too large");
  vm_prism *p = vm_calloc(ctx, 1, sizeof *p);
  if (!p) return VM_ERR_NOMEM;
  p->ctx = ctx;
  p->o = o;
  p->k = pr_params_default();
  p->t0 = omp_get_wtime();
  p->nt = nt;
  p->sym_ax = -1;
  int32_t *map = vm_alloc_array(ctx, (size_t)(wall->nv ? wall->nv : 1), sizeof *map);
  p->tri = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *p->tri);
  if (!map || !p->tri) {
    vm_free(ctx, map);
    vm_prism_destroy(&p);
    return VM_ERR_NOMEM;
  }
  /* a thickness per wall face: one per triangle here, the least per
   * column below */
  double *tri_T = NULL;
  int32_t *tri_n = NULL; /* a layer count per wall face, the same way */
  if (o.elem_layers && !(tri_n = vm_alloc_array(ctx, (size_t)nt, sizeof *tri_n))) {
    vm_free(ctx, map);
    vm_prism_destroy(&p);
    return VM_ERR_NOMEM;
  }
  if (o.elem_thickness || o.elem_layers) {
    tri_T = vm_alloc_array(ctx, (size_t)nt, sizeof *tri_T);
    if (!tri_T) {
      vm_free(ctx, tri_n);
      vm_free(ctx, map);
      vm_prism_destroy(&p);
      return VM_ERR_NOMEM;
    }
  }
  for (int64_t v = 0; v < wall->nv; v++) map[v] = -1;
  int64_t k = 0;
  for (int64_t e = 0; e < wall->ne; e++) {
    const int32_t *c = wall->conn + wall->eoff[e];
    if (wall->etype[e] != VM_TRI && wall->etype[e] != VM_QUAD) continue;
    if (tri_n) {
      int32_t ne_ = o.elem_layers[e];
      if (ne_ < 1 || ne_ > o.nlayers) {
        vm_free(ctx, map);
        vm_free(ctx, tri_T);
        vm_free(ctx, tri_n);
        vm_prism_destroy(&p);
        return vm_error(ctx, VM_ERR_ARG,
                        "prism: wall element %lld's layer count %d is not in [1, %d] (the "
                        "layer count)",
                        (long long)e, (int)ne_, o.nlayers);
      }
      tri_n[k / 3] = ne_;
      if (wall->etype[e] == VM_QUAD) tri_n[k / 3 + 1] = ne_;
    }
    if (tri_T) {
      double Te = o.elem_thickness ? o.elem_thickness[e] : o.thickness;
      if (!(Te > 0 && Te <= o.thickness)) {
        vm_free(ctx, map);
        vm_free(ctx, tri_T);
        vm_free(ctx, tri_n);
        vm_prism_destroy(&p);
        return vm_error(ctx, VM_ERR_ARG,
                        "prism: wall element %lld's thickness %g is not in (0, %g] (the "
                        "thickness)",
                        (long long)e, Te, o.thickness);
      }
      tri_T[k / 3] = Te;
      if (wall->etype[e] == VM_QUAD) tri_T[k / 3 + 1] = Te;
    }
    if (wall->etype[e] == VM_TRI) {
      for (int i = 0; i < 3; i++) p->tri[k++] = c[i];
    } else {
      static const int sp[6] = {0, 1, 2, 0, 2, 3};
      for (int i = 0; i < 6; i++) p->tri[k++] = c[sp[i]];
    }
  }
  /* the options' arrays are read here only */
  p->o.elem_thickness = NULL;
  p->o.elem_layers = NULL;
  p->regional = tri_T != NULL;
  /* the schedule (options only): a face of n layers aims at no more than
   * the sum of its first n heights */
  if ((st = build_schedule(p))) {
    vm_free(ctx, map);
    vm_free(ctx, tri_T);
    vm_free(ctx, tri_n);
    vm_prism_destroy(&p);
    return st;
  }
  for (int64_t t = 0; tri_n && t < nt; t++) {
    int n = tri_n[t] < p->rep.layers_requested ? tri_n[t] : p->rep.layers_requested;
    double s = 0;
    for (int j = 0; j < n; j++) s += p->sched[j];
    /* the schedule's own sum where the count is the stack's (bit for bit T) */
    if (n < p->rep.layers_requested && !o.elem_thickness && s < tri_T[t]) tri_T[t] = s;
    tri_n[t] = n;
  }
  for (int64_t i = 0; i < 3 * nt; i++) map[p->tri[i]] = 0;
  int64_t nw = 0;
  for (int64_t v = 0; v < wall->nv; v++)
    if (map[v] == 0) map[v] = (int32_t)nw++;
  for (int64_t i = 0; i < 3 * nt; i++) p->tri[i] = map[p->tri[i]];
  p->nw = nw;
  /* each column's aim: T, or the least of its triangles' (graded along
   * the wall once the adjacency is known: region_aims) */
  p->tv = vm_alloc_array(ctx, (size_t)nw, sizeof *p->tv);
  if (!p->tv) {
    vm_free(ctx, map);
    vm_free(ctx, tri_T);
    vm_free(ctx, tri_n);
    vm_prism_destroy(&p);
    return VM_ERR_NOMEM;
  }
  if (tri_n) {
    if (!(p->nlv = vm_alloc_array(ctx, (size_t)nw, sizeof *p->nlv))) {
      vm_free(ctx, map);
      vm_free(ctx, tri_T);
      vm_free(ctx, tri_n);
      vm_prism_destroy(&p);
      return VM_ERR_NOMEM;
    }
    for (int64_t v = 0; v < nw; v++) p->nlv[v] = INT32_MAX;
    for (int64_t t = 0; t < nt; t++)
      for (int i = 0; i < 3; i++) {
        int32_t v = p->tri[3 * t + i];
        if (tri_n[t] < p->nlv[v]) p->nlv[v] = tri_n[t];
      }
    vm_free(ctx, tri_n);
  }
  for (int64_t v = 0; v < nw; v++) p->tv[v] = tri_T ? INFINITY : o.thickness;
  for (int64_t t = 0; tri_T && t < nt; t++)
    for (int i = 0; i < 3; i++) {
      int32_t v = p->tri[3 * t + i];
      if (tri_T[t] < p->tv[v]) p->tv[v] = tri_T[t];
    }
  vm_free(ctx, tri_T);
  p->wall = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *p->wall);
  if (!p->wall) {
    vm_free(ctx, map);
    vm_prism_destroy(&p);
    return VM_ERR_NOMEM;
  }
  for (int64_t v = 0; v < wall->nv; v++)
    if (map[v] >= 0) memcpy(p->wall + 3 * (int64_t)map[v], wall->xyz + 3 * v, 3 * sizeof *p->wall);
  vm_free(ctx, map);
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = p->tri + 3 * t;
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
      vm_prism_destroy(&p);
      return vm_error(ctx, VM_ERR_ARG, "prism: wall triangle %lld repeats a vertex", (long long)t);
    }
  }
  if ((st = build_adjacency(p))) {
    vm_prism_destroy(&p);
    return st;
  }
  p->fnrm = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *p->fnrm);
  p->vnrm = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *p->vnrm);
  p->dir = vm_alloc_array(ctx, (size_t)(3 * nw), sizeof *p->dir);
  p->smooth = vm_calloc(ctx, (size_t)nw, sizeof *p->smooth);
  p->h = vm_alloc_array(ctx, (size_t)nw, sizeof *p->h);
  p->cap = vm_alloc_array(ctx, (size_t)nw, sizeof *p->cap);
  p->cut = vm_calloc(ctx, (size_t)nw, sizeof *p->cut);
  if (!p->fnrm || !p->vnrm || !p->dir || !p->smooth || !p->h || !p->cap || !p->cut ||
      (st = region_aims(p)) < 0) {
    vm_prism_destroy(&p);
    return st < 0 ? st : VM_ERR_NOMEM;
  }
  region_counts(p);
  if ((st = first_heights(p)) < 0) {
    vm_prism_destroy(&p);
    return st;
  }
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = p->tri + 3 * t;
    double e1[3], e2[3], n[3];
    for (int i = 0; i < 3; i++) {
      e1[i] = p->wall[3 * (int64_t)c[1] + i] - p->wall[3 * (int64_t)c[0] + i];
      e2[i] = p->wall[3 * (int64_t)c[2] + i] - p->wall[3 * (int64_t)c[0] + i];
    }
    vm_cross3(e1, e2, n);
    double a = vm_norm3(n), l = vm_dot3(e1, e1) + vm_dot3(e2, e2);
    if (!(a > p->k.degenerate_area * l)) {
      vm_prism_destroy(&p);
      return vm_error(ctx, VM_ERR_ARG, "prism: wall triangle %lld is degenerate", (long long)t);
    }
  }
  /* outward: the enclosed volume is positive */
  /* (a half model's from a point on its symmetry plane: the plane's cap
   * closing it adds nothing) */
  double vol = 0;
  for (int64_t t = 0; t < nt; t++) {
    double a[3], b[3], c[3], x[3];
    memcpy(a, p->wall + 3 * (int64_t)p->tri[3 * t], sizeof a);
    memcpy(b, p->wall + 3 * (int64_t)p->tri[3 * t + 1], sizeof b);
    memcpy(c, p->wall + 3 * (int64_t)p->tri[3 * t + 2], sizeof c);
    if (p->sym_ax >= 0) {
      a[p->sym_ax] -= p->sym_val;
      b[p->sym_ax] -= p->sym_val;
      c[p->sym_ax] -= p->sym_val;
    }
    vm_cross3(b, c, x);
    vol += vm_dot3(a, x);
  }
  if (vol < 0 && o.orient) {
    /* the layer grows outside: every triangle turned (the consistency of
     * neighbours' orientations, checked above, is kept) */
    for (int64_t t = 0; t < nt; t++) {
      int32_t c1 = p->tri[3 * t + 1];
      p->tri[3 * t + 1] = p->tri[3 * t + 2];
      p->tri[3 * t + 2] = c1;
    }
    p->rep.reoriented = 1;
    vm_log(ctx, VM_LOG_WARN,
           "prism: the wall is oriented inwards (enclosed volume %g): its %lld triangles are "
           "turned so that the layer grows outside",
           vol / 6, (long long)nt);
  } else if (!(vol > 0)) {
    vm_prism_destroy(&p);
    return vm_error(ctx, VM_ERR_ARG, "prism: the wall is oriented inwards (enclosed volume %g)",
                    vol / 6);
  }
  pr_surf ws = pr_wall_surf(p);
  int64_t first_blind = 0;
  int64_t blind = pr_surface_dirs(ctx, &ws, &p->k.dir, p->wall, p->fnrm, p->vnrm, p->dir,
                                  p->k.dir_blend_passes, &first_blind);
  if (blind) {
    const double *x = p->wall + 3 * first_blind;
    int st = vm_error(ctx, VM_ERR_ARG,
                      "prism: at %lld wall vertices no direction sees every incident triangle "
                      "(the wall folds back or ends in a spike there), e.g. at (%g, %g, %g)",
                      (long long)blind, x[0], x[1], x[2]);
    vm_prism_destroy(&p);
    return st;
  }
  const double smooth_cos = cos(p->k.smooth_angle_deg * PR_PI / 180);
  for (int64_t v = 0; v < nw; v++) {
    int sm = 1;
    for (int64_t j = p->vt_off[v]; j < p->vt_off[v + 1]; j++)
      if (vm_dot3(p->vnrm + 3 * v, p->fnrm + 3 * (int64_t)p->vt[j]) < smooth_cos) sm = 0;
    p->smooth[v] = (uint8_t)sm;
    p->h[v] = p->tv[v];
    p->cap[v] = p->tv[v];
  }
  p->rep.sym_axis = p->sym_ax;
  p->rep.sym_value = p->sym_val;
  p->rep.sym_columns = p->nsym;
  p->rep.wall_vertices = nw;
  p->rep.wall_triangles = nt;
  p->rep.thickness = o.thickness;
  *out = p;
  return VM_OK;
}

void vm_prism_destroy(vm_prism **pp) {
  if (!pp || !*pp) return;
  vm_prism *p = *pp;
  vm_ctx *ctx = p->ctx;
  vm_problem_destroy(&p->prob);
  pr_layer_faces_destroy(ctx, &p->faces);
  pr_rt_destroy(&p->rt);
  vm_mesh_destroy(&p->layer);
  void *arrays[] = {p->wall, p->tri,    p->fnrm,   p->vnrm, p->dir,  p->elen, p->smooth, p->vt_off,
                    p->vt,   p->vv_off, p->vv,     p->edge, p->etri, p->h,    p->cap,    p->cut,
                    p->lev,  p->sched,  p->medial, p->tv,   p->nlv,  p->h1v,  p->onsym};
  for (size_t i = 0; i < sizeof arrays / sizeof *arrays; i++) vm_free(ctx, arrays[i]);
  vm_free(ctx, p);
  *pp = NULL;
}

const vm_mesh *vm_prism_layer(const vm_prism *p) { return p ? p->layer : NULL; }

void pr_set_top(vm_prism *p, const double *t, const double *d) {
  double *top = p->layer->xyz + 3 * p->nw;
  for (int64_t v = 0; v < p->nw; v++)
    for (int k = 0; k < 3; k++) top[3 * v + k] = p->wall[3 * v + k] + t[v] * d[3 * v + k];
}

/* Every phase not done yet, in order: the first warning, or an error. */
static int run_phases(vm_prism *p) {
  int warn = 0, st;
  int (*const phase[])(vm_prism *) = {vm_prism_thin, vm_prism_springback, vm_prism_cut,
                                      vm_prism_restore, vm_prism_march};
  for (int k = p->done; k < VM_PRISM_NPHASES; k++) {
    st = phase[k](p);
    pr_sym_settle(p);
    p->rep.peak_mb[k] = vm_peak_memory_mb();
    if (st < 0) return st;
    if (st == VM_WARN_TIME) p->rep.timed_out = 1;
    if (st > 0 && !warn) warn = st;
  }
  if (p->rep.timed_out) warn = VM_WARN_TIME;
  if (vm_ctx_interrupted(p->ctx)) return VM_ERR_INTERRUPTED;
  return warn;
}

int vm_prism_run(vm_ctx *ctx, const vm_mesh *wall, const vm_prism_opts *opts, vm_mesh **out,
                 vm_prism_report *report) {
  if (report) memset(report, 0, sizeof *report);
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_prism_run: out is NULL");
  *out = NULL;
  vm_prism *p = NULL;
  int st = vm_prism_create(ctx, wall, opts, &p);
  if (st < 0) return st;
  double t0 = pr_elapsed(p);
  const double *radius;
  if ((st = vm_prism_medial_radius(p, &radius)) < 0) {
    vm_prism_destroy(&p);
    return st;
  }
  p->rep.medial_time = pr_elapsed(p) - t0;
  st = run_phases(p);
  /* the figures first: time_total is the run's, not the result's */
  vm_prism_report r;
  vm_prism_get_report(p, &r);
  if (report) *report = r;
  if (st >= 0 || st == VM_ERR_INTERRUPTED) {
    int s2 = vm_prism_result(p, out);
    if (s2 < 0) st = s2;
  }
  vm_prism_destroy(&p);
  return st;
}
