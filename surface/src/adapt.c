/* surface/src/adapt.c: curvature-adapted optimization of a surface mesh
 * with the 2D functional (20) on the core minimizer: metric (1 + c|H|) I,
 * tangent-frame measure, slip on the reference surface and feature lines. */
#include "varmesh/adapt.h"

#include <math.h>
#include <omp.h>
#include <string.h>

#include "varmesh/surface_mesh.h"
#include "vec3.h"
#include "varmesh/cleanup.h"
#include "varmesh/features.h"
#include "varmesh/minimize.h"
#include "varmesh/problem.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

vm_adapt_opts vm_adapt_opts_default(void) {
  vm_adapt_opts o;
  memset(&o, 0, sizeof o);
  o.c = -4.0;
  o.filter.threshold = -4.0;
  o.filter.cap = -1.0;
  o.filter.smooth = 2;
  o.feature_angle = 20.0;
  o.corner_angle = 50.0;
  o.cone_angle = 60.0;
  o.theta = 0.8;
  o.max_iter = 200;
  o.rounds = 5;
  return o;
}

double vm_surface_min_angle(const vm_mesh *m) {
  double mn = 180.0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (t != VM_TRI && t != VM_QUAD) continue;
    double a = vm_surface_elem_min_angle(m, m->xyz, e);
    if (a < mn) mn = a;
  }
  return mn;
}

double vm_surface_mean_edge(const vm_mesh *m) {
  double s = 0;
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    int k = vm_elem_nverts(m->etype[e]);
    const int32_t *c = m->conn + m->eoff[e];
    for (int a = 0; a < k; a++) {
      const double *p = m->xyz + 3 * (int64_t)c[a], *q = m->xyz + 3 * (int64_t)c[(a + 1) % k];
      double d[3];
      vm_sub3(q, p, d);
      s += vm_norm3(d);
      n++;
    }
  }
  return n ? s / (double)n : 0;
}

/* Mean edge length and bounding box diagonal of the 2D elements. */
static void mesh_scales(const vm_mesh *m, double *h, double *diag) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2) continue;
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++, n++)
      for (int r = 0; r < 3; r++) {
        double x = m->xyz[3 * (int64_t)m->conn[k] + r];
        if (x < lo[r]) lo[r] = x;
        if (x > hi[r]) hi[r] = x;
      }
  }
  *h = vm_surface_mean_edge(m);
  double d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  *diag = n ? vm_norm3(d) : 0;
}

typedef struct {
  vm_mesh *m;
  vm_problem *prob;
  vm_surface_projector *hproj; /* interpolates Href at moved vertices */
  const double *Href;
  double c;
  double *g, *Hx;
  double sqrt3_4;
} adapt_state;

/* Metric g = 1 + c|H(x)| at the vertices x, and the ideal target size that
 * makes the total target area equal the metric area of the mesh. */
static int update_metric(adapt_state *s, const double *x) {
  vm_mesh *m = s->m;
  int st = vm_surface_projector_interpolate(s->hproj, s->Href, m->nv, x, s->Hx);
  if (st) return st;
  for (int64_t v = 0; v < m->nv; v++) s->g[v] = 1.0 + s->c * fabs(s->Hx[v]);
  if ((st = vm_problem_set_metric_scalar(s->prob, s->g))) return st;
  double Ag = 0, ideal = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (t != VM_TRI && t != VM_QUAD) continue;
    int k = vm_elem_nverts(t);
    const int32_t *c = m->conn + m->eoff[e];
    double n[3] = {0, 0, 0}, gm = 0;
    for (int a = 0; a < k; a++) {
      double cr[3];
      vm_cross3(x + 3 * (int64_t)c[a], x + 3 * (int64_t)c[(a + 1) % k], cr);
      for (int r = 0; r < 3; r++) n[r] += cr[r];
      gm += s->g[c[a]];
    }
    Ag += gm / k * 0.5 * vm_norm3(n);
    ideal += t == VM_TRI ? s->sqrt3_4 : 1.0;
  }
  if (!(Ag > 0) || !(ideal > 0))
    return vm_error(m->ctx, VM_ERR_ARG, "adapt: the surface has no area");
  return vm_problem_set_target_ideal(s->prob, sqrt(Ag / ideal));
}

typedef struct {
  const vm_adapt_opts *o;
  int round, done;
} monitor_state;

static void forward_monitor(void *user, const vm_iter_info *it) {
  monitor_state *ms = user;
  if (!ms->o->monitor) return;
  vm_adapt_progress p;
  p.round = ms->round;
  p.iter = it->iter;
  p.total_iter = ms->done + it->iter;
  p.F = it->F;
  p.grad_norm = it->grad_norm;
  p.tau = it->tau;
  p.elapsed = it->elapsed;
  ms->o->monitor(ms->o->user, &p);
}

/* Newell normal (twice the vector area) of 2D element e at x. */
static void element_normals_one(const vm_mesh *m, const double *x, int64_t e, double n[3]) {
  int k = vm_elem_nverts(m->etype[e]);
  const int32_t *c = m->conn + m->eoff[e];
  n[0] = n[1] = n[2] = 0;
  for (int a = 0; a < k; a++) {
    double cr[3];
    vm_cross3(x + 3 * (int64_t)c[a], x + 3 * (int64_t)c[(a + 1) % k], cr);
    for (int r = 0; r < 3; r++) n[r] += cr[r];
  }
}

static void element_normals(const vm_mesh *m, const double *x, double *n) {
  for (int64_t e = 0; e < m->ne; e++) element_normals_one(m, x, e, n + 3 * e);
}

/* First element with a corner triangle of zero area to working precision
 * (doubled area below 1e-12 of its squared longest edge, as the repair
 * judges it), or -1. The barrier measure is infinite on such an element.
 * *overflow: the products overflowed there (coordinates too large for
 * double precision areas), which is not a zero area. */
static int64_t first_degenerate(const vm_mesh *m, int *overflow) {
  *overflow = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int k = vm_elem_nverts(m->etype[e]);
    const int32_t *c = m->conn + m->eoff[e];
    for (int a = 0; a < (k == 3 ? 1 : k); a++) {
      const double *p = m->xyz + 3 * (int64_t)c[a];
      const double *q = m->xyz + 3 * (int64_t)c[(a + 1) % k];
      const double *r = m->xyz + 3 * (int64_t)c[(a + k - 1) % k];
      double u[3], v[3], w[3], n[3];
      vm_sub3(q, p, u);
      vm_sub3(r, p, v);
      vm_sub3(r, q, w);
      vm_cross3(u, v, n);
      double l2 = fmax(vm_dot3(u, u), fmax(vm_dot3(v, v), vm_dot3(w, w)));
      double a2 = vm_norm3(n);
      if (!isfinite(a2) || !isfinite(l2)) {
        *overflow = 1;
        return e;
      }
      if (!(a2 > 1e-12 * l2)) return e;
    }
  }
  return -1;
}

int vm_surface_adapt(vm_mesh *m, vm_surface_projector *ref, const vm_adapt_opts *opts,
                     vm_adapt_result *res) {
  if (!m) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  vm_adapt_opts o = opts ? *opts : vm_adapt_opts_default();
  vm_adapt_result r;
  memset(&r, 0, sizeof r);
  r.stop = "none";
  if (res) *res = r;
  double t0 = omp_get_wtime();
  if (m->dim != 3) return vm_error(ctx, VM_ERR_ARG, "adapt: the mesh is not a surface in 3D");
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 2 || counts[VM_TRI] + counts[VM_QUAD] != m->ne)
    return vm_error(ctx, VM_ERR_ARG, "adapt: the mesh must have only triangles and quads");
  if (!(o.theta >= 0 && o.theta <= 1) || o.max_iter < 0 || o.rounds < 1 ||
      !(o.feature_angle > 0 && o.feature_angle <= 180) || !(o.corner_angle > 0) || !isfinite(o.c) ||
      !isfinite(o.filter.threshold) || isnan(o.filter.cap) || o.filter.smooth < 0)
    return vm_error(ctx, VM_ERR_ARG, "adapt: invalid options");
  int overflow;
  int64_t bad = first_degenerate(m, &overflow);
  if (bad >= 0) {
    const double *p = m->xyz + 3 * (int64_t)m->conn[m->eoff[bad]];
    if (overflow)
      return vm_error(ctx, VM_ERR_ARG,
                      "adapt: element %lld at (%g, %g, %g): its area overflows double precision "
                      "(coordinates too large); scale the surface down",
                      (long long)bad, p[0], p[1], p[2]);
    return vm_error(ctx, VM_ERR_ARG,
                    "adapt: zero-area element %lld at (%g, %g, %g); repair the surface first",
                    (long long)bad, p[0], p[1], p[2]);
  }

  const int64_t nv = m->nv;
  const size_t n1 = nv > 0 ? (size_t)nv : 1;
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  vm_surface_projector *own = NULL, *hproj = NULL;
  vm_problem *prob = NULL;
  vm_minimizer *mz = NULL;
  int32_t *vs = vm_alloc_array(ctx, n1, sizeof *vs);
  double *x0 = vm_alloc_array(ctx, 3 * n1, sizeof *x0);
  double *en0 = vm_alloc_array(ctx, 3 * (m->ne > 0 ? (size_t)m->ne : 1), sizeof *en0);
  uint8_t *flag0 = vm_alloc_array(ctx, n1, sizeof *flag0);
  int32_t *surf0 = vm_alloc_array(ctx, n1, sizeof *surf0);
  double *Href = vm_alloc_array(ctx, n1, sizeof *Href);
  double *g = vm_alloc_array(ctx, n1, sizeof *g);
  double *Hx = vm_alloc_array(ctx, n1, sizeof *Hx);
  int st = VM_OK, flags_set = 0, saved = 0;
  if (!flag0 || !surf0 || !Href || !g || !Hx || !vs || !x0 || !en0) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(flag0, m->vflag, (size_t)nv * sizeof *flag0);
  memcpy(surf0, m->vsurf, (size_t)nv * sizeof *surf0);
  memcpy(x0, m->xyz, 3 * (size_t)nv * sizeof *x0);
  saved = 1;
  element_normals(m, m->xyz, en0);

  /* features and the surfaces the vertices stay on */
  if ((st = vm_surface_detect_features_cones(m, o.feature_angle, o.corner_angle, o.cone_angle, &f,
                                             NULL)))
    goto done;
  if ((st = vm_surface_projector_create(ctx, m, &f, &own))) goto done;
  hproj = own;
  vm_surface_ops ops = vm_surface_projector_ops(ref ? ref : own);

  /* curvature of the starting surface, filtered */
  double h, diag;
  mesh_scales(m, &h, &diag);
  if (!(h > 0)) {
    st = vm_error(ctx, VM_ERR_ARG, "adapt: the mesh has no edges of positive length");
    goto done;
  }
  vm_curvature_filter filt = o.filter;
  if (filt.threshold < 0) filt.threshold = -filt.threshold / diag;
  if (filt.cap < 0) filt.cap = -filt.cap / h;
  double c = o.c < 0 ? -o.c * h : o.c;
  r.c = c;
  r.threshold = filt.threshold;
  r.cap = filt.cap;
  if ((st = vm_surface_mean_curvature(m, Href, NULL, NULL, NULL))) goto done;
  if ((st = vm_curvature_filter_apply(m, &filt, Href))) goto done;

  /* vertex classes: the reference line each feature vertex lies on */
  if ((st = vm_surface_projector_assign(ref ? ref : own, m, &f, 1e-3 * h, vs))) goto done;
  flags_set = 1;
  for (int64_t v = 0; v < nv; v++) {
    if (m->vflag[v] == VM_VERTEX_FIXED) continue;
    m->vflag[v] = vs[v] < 0 ? VM_VERTEX_FIXED : VM_VERTEX_SLIP;
    m->vsurf[v] = vs[v] < 0 ? -1 : vs[v];
  }
  for (int64_t v = 0; v < nv; v++) {
    if (m->vflag[v] == VM_VERTEX_FIXED)
      r.nfixed++;
    else if (m->vsurf[v] == 0)
      r.nsmooth++;
    else
      r.nline_vertices++;
  }
  r.ncorner = f.ncorner;
  r.nline = f.nline;
  r.min_angle_before = vm_surface_min_angle(m);

  /* the functional (20) */
  if ((st = vm_problem_create(ctx, m, &prob))) goto done;
  vm_measure_params prm;
  memset(&prm, 0, sizeof prm);
  prm.theta = o.theta;
  if ((st = vm_problem_set_measure(prob, VM_MEASURE_BALANCED, &prm))) goto done;
  adapt_state as = {m, prob, hproj, Href, c, g, Hx, sqrt(3.0) / 4.0};
  if ((st = vm_minimizer_create(ctx, prob,
                                o.implicit ? VM_MINIMIZER_IMPLICIT : VM_MINIMIZER_EXPLICIT, &mz)))
    goto done;
  if ((st = vm_minimizer_set_surfaces(mz, &ops))) goto done;
  monitor_state ms = {&o, 0, 0};
  int per_round = (o.max_iter + o.rounds - 1) / o.rounds;
  for (int round = 1; round <= o.rounds && r.iterations < o.max_iter; round++) {
    if ((st = update_metric(&as, m->xyz))) goto done;
    if ((st = vm_problem_update_normals(prob, NULL))) goto done;
    vm_minimize_options mo = vm_minimize_options_default();
    mo.max_iter = per_round < o.max_iter - r.iterations ? per_round : o.max_iter - r.iterations;
    mo.rel_decrease_tol = 1e-7;
    mo.grad_rtol = 1e-8;
    mo.stats_every = 0;
    mo.precond = VM_PRECOND_JACOBI;
    if (o.time_limit > 0) {
      double left = o.time_limit - (omp_get_wtime() - t0);
      if (left <= 0) {
        st = VM_WARN_TIME;
        r.stop = vm_stop_reason_name(VM_STOP_TIME);
        break;
      }
      mo.time_limit = left;
    }
    ms.round = round;
    mo.monitor = forward_monitor;
    mo.user = &ms;
    if ((st = vm_minimizer_set_options(mz, &mo))) goto done;
    vm_minimize_result mr;
    st = vm_minimizer_run(mz, m->xyz, &mr);
    if (round == 1) r.F_initial = mr.F_initial;
    r.F = mr.F;
    r.iterations += mr.iterations;
    ms.done = r.iterations;
    r.rounds = round;
    r.stop = vm_stop_reason_name(mr.reason);
    if (st == VM_WARN_MAXITER) st = VM_OK;
    if (st) break;
  }
  if (st < 0 && st != VM_ERR_INTERRUPTED) goto done;
  {
    int keep = st;
    /* flips: elements whose orientation reversed (by construction of the
     * barrier measure there are none; this is an independent check) */
    for (int64_t e = 0; e < m->ne; e++) {
      double n1[3];
      element_normals_one(m, m->xyz, e, n1);
      if (vm_dot3(n1, en0 + 3 * e) <= 0) r.flipped++;
    }
    r.min_angle_after = vm_surface_min_angle(m);
    /* distance of the vertices to the reference */
    double dmax = 0;
    for (int64_t v = 0; v < nv; v++) {
      double q[3], nr[9], d[3];
      int nn = ops.project(ops.user, 0, m->xyz + 3 * v, q, nr);
      if (nn < 0) {
        st = nn;
        goto done;
      }
      vm_sub3(q, m->xyz + 3 * v, d);
      if (vm_norm3(d) > dmax) dmax = vm_norm3(d);
    }
    r.max_distance = dmax;
    st = vm_surface_curvature(m, &filt, NULL);
    if (!st) st = keep;
  }
done:
  /* a failed call leaves the mesh as it was (an interrupted one keeps the
   * last accepted iterate) */
  if (st < 0 && st != VM_ERR_INTERRUPTED && saved) memcpy(m->xyz, x0, 3 * (size_t)nv * sizeof *x0);
  if (flags_set) {
    memcpy(m->vflag, flag0, (size_t)nv * sizeof *flag0);
    memcpy(m->vsurf, surf0, (size_t)nv * sizeof *surf0);
  }
  vm_minimizer_destroy(&mz);
  vm_problem_destroy(&prob);
  vm_surface_projector_destroy(&own);
  vm_surface_features_free(ctx, &f);
  vm_free(ctx, vs);
  vm_free(ctx, x0);
  vm_free(ctx, en0);
  vm_free(ctx, flag0);
  vm_free(ctx, surf0);
  vm_free(ctx, Href);
  vm_free(ctx, g);
  vm_free(ctx, Hx);
  r.elapsed = omp_get_wtime() - t0;
  if (res) *res = r;
  return st;
}
