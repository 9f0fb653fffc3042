/* lib/core/src/boundary.c: boundary conditions of the minimizers: fixed, free
 * and slip vertices with tangent-cone projectors L_k (30)-(33), and the
 * analytic constraint surfaces (plane, sphere, box). */
#include "varmesh/boundary.h"

#include <math.h>
#include <string.h>

#include "linsolve_private.h"
#include "vec3.h"

enum { SURF_PLANE = 0, SURF_SPHERE = 1, SURF_BOX = 2 };

typedef struct {
  int id;
  int kind;
  double a[6]; /* plane: point, unit normal; sphere: centre, radius; box: lo, hi */
} analytic_surface;

struct vm_analytic_surfaces {
  vm_ctx *ctx;
  int n, cap;
  analytic_surface *s;
};

int vm_analytic_surfaces_create(vm_ctx *ctx, vm_analytic_surfaces **out) {
  if (!out) return vm_error(ctx, VM_ERR_ARG, "vm_analytic_surfaces_create: out is NULL");
  *out = vm_calloc(ctx, 1, sizeof **out);
  if (!*out) return VM_ERR_NOMEM;
  (*out)->ctx = ctx;
  return VM_OK;
}

void vm_analytic_surfaces_destroy(vm_analytic_surfaces **p) {
  if (!p || !*p) return;
  vm_free((*p)->ctx, (*p)->s);
  vm_free((*p)->ctx, *p);
  *p = NULL;
}

static int add_surface(vm_analytic_surfaces *s, int id, int kind, const double a[6]) {
  analytic_surface *slot = NULL;
  for (int i = 0; i < s->n; i++)
    if (s->s[i].id == id) slot = &s->s[i];
  if (!slot) {
    if (s->n == s->cap) {
      int cap = s->cap ? 2 * s->cap : 4;
      analytic_surface *ns = vm_realloc(s->ctx, s->s, (size_t)cap * sizeof *ns);
      if (!ns) return VM_ERR_NOMEM;
      s->s = ns;
      s->cap = cap;
    }
    slot = &s->s[s->n++];
  }
  slot->id = id;
  slot->kind = kind;
  memcpy(slot->a, a, sizeof slot->a);
  return VM_OK;
}

int vm_analytic_add_plane(vm_analytic_surfaces *s, int surf_id, const double point[3],
                          const double normal[3]) {
  if (!s || !point || !normal) return VM_ERR_ARG;
  double len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
  if (!(len > 0) || !isfinite(len))
    return vm_error(s->ctx, VM_ERR_ARG, "plane %d: zero or non-finite normal", surf_id);
  double a[6] = {point[0], point[1], point[2], normal[0] / len, normal[1] / len, normal[2] / len};
  return add_surface(s, surf_id, SURF_PLANE, a);
}

int vm_analytic_add_sphere(vm_analytic_surfaces *s, int surf_id, const double center[3],
                           double radius) {
  if (!s || !center) return VM_ERR_ARG;
  if (!(radius > 0) || !isfinite(radius))
    return vm_error(s->ctx, VM_ERR_ARG, "sphere %d: radius %g", surf_id, radius);
  double a[6] = {center[0], center[1], center[2], radius, 0, 0};
  return add_surface(s, surf_id, SURF_SPHERE, a);
}

int vm_analytic_add_box(vm_analytic_surfaces *s, int surf_id, const double lo[3],
                        const double hi[3]) {
  if (!s || !lo || !hi) return VM_ERR_ARG;
  for (int k = 0; k < 3; k++)
    if (!(lo[k] < hi[k]))
      return vm_error(s->ctx, VM_ERR_ARG, "box %d: lo >= hi in coordinate %d", surf_id, k);
  double a[6] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  return add_surface(s, surf_id, SURF_BOX, a);
}

static int project_plane(const double *a, const double p[3], double out[3], double nrm[9]) {
  double t = (p[0] - a[0]) * a[3] + (p[1] - a[1]) * a[4] + (p[2] - a[2]) * a[5];
  for (int k = 0; k < 3; k++) {
    out[k] = p[k] - t * a[3 + k];
    nrm[k] = a[3 + k];
  }
  return 1;
}

static int project_sphere(const double *a, const double p[3], double out[3], double nrm[9]) {
  double d[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(len > 0) || !isfinite(len)) return VM_ERR_NUMERIC;
  for (int k = 0; k < 3; k++) {
    nrm[k] = d[k] / len;
    out[k] = a[k] + a[3] * nrm[k];
  }
  return 1;
}

/* Closest point of the box's boundary: clamp an outside point, push an
 * inside point to its nearest face; the faces the result lies on give the
 * normals (1 face, 2 on an edge, 3 at a corner). */
static int project_box(const double *a, const double p[3], double out[3], double nrm[9]) {
  const double *lo = a, *hi = a + 3;
  int inside = 1;
  for (int k = 0; k < 3; k++) {
    if (!isfinite(p[k])) return VM_ERR_NUMERIC;
    out[k] = p[k] < lo[k] ? lo[k] : p[k] > hi[k] ? hi[k] : p[k];
    if (p[k] < lo[k] || p[k] > hi[k]) inside = 0;
  }
  if (inside) {
    int kbest = 0, side = 0;
    double dbest = INFINITY;
    for (int k = 0; k < 3; k++) {
      if (p[k] - lo[k] < dbest) {
        dbest = p[k] - lo[k];
        kbest = k;
        side = 0;
      }
      if (hi[k] - p[k] < dbest) {
        dbest = hi[k] - p[k];
        kbest = k;
        side = 1;
      }
    }
    out[kbest] = side ? hi[kbest] : lo[kbest];
  }
  double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
  double tol = 1e-9 * diag;
  int nn = 0;
  for (int k = 0; k < 3; k++) {
    int on_lo = fabs(out[k] - lo[k]) <= tol, on_hi = fabs(out[k] - hi[k]) <= tol;
    if (!on_lo && !on_hi) continue;
    double *n = nrm + 3 * nn++;
    n[0] = n[1] = n[2] = 0;
    n[k] = on_lo ? -1.0 : 1.0;
  }
  return nn;
}

static int analytic_project(void *user, int surf_id, const double p[3], double out[3],
                            double normals[9]) {
  const vm_analytic_surfaces *s = user;
  for (int i = 0; i < s->n; i++) {
    if (s->s[i].id != surf_id) continue;
    switch (s->s[i].kind) {
    case SURF_PLANE: return project_plane(s->s[i].a, p, out, normals);
    case SURF_SPHERE: return project_sphere(s->s[i].a, p, out, normals);
    default: return project_box(s->s[i].a, p, out, normals);
    }
  }
  return VM_ERR_ARG;
}

vm_surface_ops vm_analytic_surfaces_ops(vm_analytic_surfaces *s) {
  vm_surface_ops ops = {analytic_project, s, NULL, 1};
  return ops;
}

struct vm_bc {
  vm_ctx *ctx;
  int64_t nv;
  int dim;
  uint8_t *cls;  /* per vertex: VM_VERTEX_FREE / FIXED / SLIP */
  int32_t *slip; /* per vertex: index among slip vertices or -1 */
  int64_t nslip;
  int64_t *slip_v;  /* slip vertex ids */
  int32_t *surf_id; /* per slip vertex */
  int8_t *rank;     /* per slip vertex */
  double *Q;        /* per slip vertex: 9 (basis columns) */
  int64_t *hint;    /* per slip vertex: the projection's token (surf.project_hinted) */
  /* the last two trial points of vm_bc_step and their bases (per slip
   * vertex: 3, 9 and 1 values), so that vm_bc_refresh at an accepted
   * trial point need not project it again */
  double *trial_x[2], *trial_Q[2];
  int8_t *trial_rank[2];
  int trial_valid[2], trial_next;
  int64_t count[3];
  vm_surface_ops surf;
};

int vm_bc_create(vm_ctx *ctx, const vm_mesh *m, const vm_surface_ops *surf, vm_bc **out) {
  if (!out || !m) return vm_error(ctx, VM_ERR_ARG, "vm_bc_create: NULL argument");
  *out = NULL;
  vm_bc *bc = vm_calloc(ctx, 1, sizeof *bc);
  if (!bc) return VM_ERR_NOMEM;
  bc->ctx = ctx;
  bc->nv = m->nv;
  bc->dim = m->dim == 2 ? 2 : 3;
  size_t nv = m->nv > 0 ? (size_t)m->nv : 1;
  bc->cls = vm_alloc_array(ctx, nv, sizeof *bc->cls);
  bc->slip = vm_alloc_array(ctx, nv, sizeof *bc->slip);
  if (!bc->cls || !bc->slip) goto nomem;
  for (int64_t v = 0; v < m->nv; v++) {
    int c = m->vflag ? m->vflag[v] : VM_VERTEX_FREE;
    if (c != VM_VERTEX_FIXED && c != VM_VERTEX_SLIP) c = VM_VERTEX_FREE;
    bc->cls[v] = (uint8_t)c;
    bc->slip[v] = -1;
    if (c == VM_VERTEX_SLIP) bc->slip[v] = (int32_t)bc->nslip++;
    bc->count[c]++;
  }
  if (bc->nslip > 0) {
    if (!surf || !surf->project) {
      vm_bc_destroy(&bc);
      return vm_error(ctx, VM_ERR_ARG, "slip vertices need constraint surfaces");
    }
    bc->surf = *surf;
    size_t ns = (size_t)bc->nslip;
    bc->slip_v = vm_alloc_array(ctx, ns, sizeof *bc->slip_v);
    bc->surf_id = vm_alloc_array(ctx, ns, sizeof *bc->surf_id);
    bc->rank = vm_alloc_array(ctx, ns, sizeof *bc->rank);
    bc->Q = vm_calloc(ctx, ns * 9, sizeof *bc->Q);
    bc->hint = vm_alloc_array(ctx, ns, sizeof *bc->hint);
    if (!bc->slip_v || !bc->surf_id || !bc->rank || !bc->Q || !bc->hint) goto nomem;
    for (int k = 0; k < 2; k++) {
      bc->trial_x[k] = vm_alloc_array(ctx, 3 * ns, sizeof *bc->trial_x[k]);
      bc->trial_Q[k] = vm_alloc_array(ctx, 9 * ns, sizeof *bc->trial_Q[k]);
      bc->trial_rank[k] = vm_alloc_array(ctx, ns, sizeof *bc->trial_rank[k]);
      if (!bc->trial_x[k] || !bc->trial_Q[k] || !bc->trial_rank[k]) goto nomem;
    }
    for (int64_t v = 0; v < m->nv; v++) {
      int32_t s = bc->slip[v];
      if (s < 0) continue;
      bc->slip_v[s] = v;
      bc->surf_id[s] = m->vsurf ? m->vsurf[v] : -1;
      bc->rank[s] = (int8_t)bc->dim;
      bc->hint[s] = -1;
    }
  }
  *out = bc;
  return VM_OK;
nomem:
  vm_bc_destroy(&bc);
  return VM_ERR_NOMEM;
}

void vm_bc_destroy(vm_bc **p) {
  if (!p || !*p) return;
  vm_bc *bc = *p;
  vm_ctx *ctx = bc->ctx;
  vm_free(ctx, bc->cls);
  vm_free(ctx, bc->slip);
  vm_free(ctx, bc->slip_v);
  vm_free(ctx, bc->surf_id);
  vm_free(ctx, bc->hint);
  for (int k = 0; k < 2; k++) {
    vm_free(ctx, bc->trial_x[k]);
    vm_free(ctx, bc->trial_Q[k]);
    vm_free(ctx, bc->trial_rank[k]);
  }
  vm_free(ctx, bc->rank);
  vm_free(ctx, bc->Q);
  vm_free(ctx, bc);
  *p = NULL;
}

/* Orthonormal basis of the complement of the constraint normals (and of
 * e_z in 2D): Gram-Schmidt on the normals, then the coordinate axes
 * taken greedily by largest remaining length. Returns the rank. */
static int cone_basis(int dim, const double *nrm, int nn, double Q[9]) {
  double U[4][3];
  int nu = 0;
  double cons[4][3];
  int nc = 0;
  for (int i = 0; i < nn && i < 3; i++) memcpy(cons[nc++], nrm + 3 * i, sizeof cons[0]);
  if (dim == 2) {
    cons[nc][0] = cons[nc][1] = 0;
    cons[nc++][2] = 1;
  }
  for (int i = 0; i < nc; i++) {
    double v[3] = {cons[i][0], cons[i][1], cons[i][2]};
    double len0 = sqrt(vm_dot3(v, v));
    if (!(len0 > 0)) continue;
    for (int j = 0; j < nu; j++) {
      double t = vm_dot3(v, U[j]);
      for (int k = 0; k < 3; k++) v[k] -= t * U[j][k];
    }
    double len = sqrt(vm_dot3(v, v));
    if (len <= 1e-8 * len0) continue;
    for (int k = 0; k < 3; k++) U[nu][k] = v[k] / len;
    nu++;
  }
  int rank = 3 - nu;
  for (int r = 0; r < rank; r++) {
    double best[3] = {0, 0, 0}, blen = -1;
    for (int e = 0; e < 3; e++) {
      double v[3] = {0, 0, 0};
      v[e] = 1;
      for (int j = 0; j < nu; j++) {
        double t = vm_dot3(v, U[j]);
        for (int k = 0; k < 3; k++) v[k] -= t * U[j][k];
      }
      for (int j = 0; j < r; j++) {
        double t = vm_dot3(v, Q + 3 * j);
        for (int k = 0; k < 3; k++) v[k] -= t * Q[3 * j + k];
      }
      double len = sqrt(vm_dot3(v, v));
      if (len > blen + 1e-12) {
        blen = len;
        memcpy(best, v, sizeof best);
      }
    }
    for (int k = 0; k < 3; k++) Q[3 * r + k] = best[k] / blen;
  }
  return rank;
}

/* The surface's closest point to p for slip vertex s (its hint kept). */
static int surf_project(vm_bc *bc, int64_t s, const double p[3], double q[3], double nrm[9]) {
  if (bc->surf.project_hinted)
    return bc->surf.project_hinted(bc->surf.user, bc->surf_id[s], p, bc->hint + s, q, nrm);
  return bc->surf.project(bc->surf.user, bc->surf_id[s], p, q, nrm);
}

/* r = Q Q^T r for slip vertex s. */
static void apply_slip(const vm_bc *bc, int64_t s, double r[3]) {
  const double *Q = bc->Q + 9 * s;
  double out[3] = {0, 0, 0};
  for (int j = 0; j < bc->rank[s]; j++) {
    double t = vm_dot3(Q + 3 * j, r);
    for (int k = 0; k < 3; k++) out[k] += t * Q[3 * j + k];
  }
  memcpy(r, out, sizeof out);
}

/* Project slip vertex s from p: the point to q (in 2D with p's z), its
 * basis to Q and *rank. Returns VM_OK or the failure's status, reporting
 * nothing (the callers may run in parallel). */
static int slip_point(vm_bc *bc, int64_t s, const double p[3], double q[3], double Q[9],
                      int8_t *rank) {
  double nrm[9];
  int nn = surf_project(bc, s, p, q, nrm);
  if (nn < 0) return nn;
  if (!isfinite(q[0]) || !isfinite(q[1]) || !isfinite(q[2])) return VM_ERR_NUMERIC;
  if (bc->dim == 2) q[2] = p[2];
  *rank = (int8_t)cone_basis(bc->dim, nrm, nn > 3 ? 3 : nn, Q);
  return VM_OK;
}

enum { SLIP_PROJECT, SLIP_REFRESH, SLIP_STEP };

/* One slip vertex of vm_bc_project / _refresh / _step (the mode). */
static int slip_vertex(vm_bc *bc, int mode, int64_t s, double *x, const double *dz, double tau,
                       double *xout) {
  const int64_t v = bc->slip_v[s];
  double *pv = x + 3 * v, q[3];
  if (mode == SLIP_PROJECT) {
    int st = slip_point(bc, s, pv, q, bc->Q + 9 * s, bc->rank + s);
    if (!st) memcpy(pv, q, sizeof q);
    return st;
  }
  if (mode == SLIP_REFRESH) {
    /* the later trial first: an accepted point is usually the last one tried */
    for (int i = 0; i < 2; i++) {
      int k = i ? bc->trial_next : 1 - bc->trial_next;
      if (!bc->trial_valid[k] || memcmp(pv, bc->trial_x[k] + 3 * s, sizeof q) != 0) continue;
      memcpy(bc->Q + 9 * s, bc->trial_Q[k] + 9 * s, 9 * sizeof *bc->Q);
      bc->rank[s] = bc->trial_rank[k][s];
      return VM_OK;
    }
    return slip_point(bc, s, pv, q, bc->Q + 9 * s, bc->rank + s);
  }
  const int t = bc->trial_next;
  double d[3] = {dz[3 * v], dz[3 * v + 1], dz[3 * v + 2]}, p[3];
  apply_slip(bc, s, d);
  for (int k = 0; k < 3; k++) p[k] = pv[k] + tau * d[k];
  int st = slip_point(bc, s, p, q, bc->trial_Q[t] + 9 * s, bc->trial_rank[t] + s);
  if (st) return st;
  if (bc->dim == 2) q[2] = pv[2];
  memcpy(xout + 3 * v, q, sizeof q);
  memcpy(bc->trial_x[t] + 3 * s, q, sizeof q);
  return VM_OK;
}

/* Every slip vertex in the mode, on several threads where the surfaces
 * allow it (vm_surface_ops.reentrant). Every vertex is done even after a
 * failure, so that the hints, and with them the results, do not depend on
 * the number of threads; the status is the first failing vertex's, in
 * vertex order. */
static int slip_all(vm_bc *bc, int mode, double *x, const double *dz, double tau, double *xout,
                    int64_t *failed) {
  const int64_t ns = bc->nslip;
  int nt = bc->surf.reentrant ? vm_nthreads(bc->ctx) : 1;
  int64_t bad = ns;
  const int par = nt > 1 && ns >= 1024;
  // clang-format off
#pragma omp parallel for num_threads(nt) schedule(dynamic, 64) reduction(min: bad) if (par)
  // clang-format on
  for (int64_t s = 0; s < ns; s++)
    if (slip_vertex(bc, mode, s, x, dz, tau, xout) != VM_OK && s < bad) bad = s;
  *failed = bad < ns ? bad : -1;
  if (bad == ns) return VM_OK;
  /* the status again, on this thread (the surface's answer for that
   * point does not depend on the others) */
  const int64_t v = bc->slip_v[bad];
  double q[3], Q[9], p[3];
  int8_t r;
  memcpy(p, x + 3 * v, sizeof p);
  if (mode == SLIP_STEP) {
    double d[3] = {dz[3 * v], dz[3 * v + 1], dz[3 * v + 2]};
    apply_slip(bc, bad, d);
    for (int k = 0; k < 3; k++) p[k] += tau * d[k];
  }
  int st = slip_point(bc, bad, p, q, Q, &r);
  return st ? st : VM_ERR_NUMERIC;
}

/* The error of a failed projection of vm_bc_project / _refresh. */
static int slip_error(vm_bc *bc, int st, int64_t s) {
  if (st == VM_ERR_NUMERIC)
    return vm_error(bc->ctx, st, "projection of vertex %lld is not finite",
                    (long long)bc->slip_v[s]);
  return vm_error(bc->ctx, st, "projection of vertex %lld onto surface %d failed",
                  (long long)bc->slip_v[s], bc->surf_id[s]);
}

int vm_bc_project(vm_bc *bc, double *x) {
  int64_t s;
  int st = slip_all(bc, SLIP_PROJECT, x, NULL, 0, NULL, &s);
  return st ? slip_error(bc, st, s) : VM_OK;
}

int vm_bc_refresh(vm_bc *bc, const double *x) {
  int64_t s;
  /* x is only read in this mode */
  int st = slip_all(bc, SLIP_REFRESH, (double *)x, NULL, 0, NULL, &s);
  return st ? slip_error(bc, st, s) : VM_OK;
}

int vm_bc_step(vm_bc *bc, const double *x, const double *dz, double tau, double *xout) {
  int nt = vm_nthreads(bc->ctx);
  const int64_t nv = bc->nv;
  const int dim = bc->dim;
#pragma omp parallel for num_threads(nt) schedule(static) if (nv >= VM_PAR_MIN)
  for (int64_t v = 0; v < nv; v++) {
    if (bc->cls[v] != VM_VERTEX_FREE) continue;
    for (int k = 0; k < dim; k++) xout[3 * v + k] = x[3 * v + k] + tau * dz[3 * v + k];
    if (dim == 2) xout[3 * v + 2] = x[3 * v + 2];
  }
  if (bc->nslip == 0) return VM_OK;
  const int t = bc->trial_next;
  bc->trial_valid[t] = 0;
  int64_t s;
  /* x is only read in this mode */
  int st = slip_all(bc, SLIP_STEP, (double *)x, dz, tau, xout, &s);
  if (st) return st;
  bc->trial_valid[t] = 1;
  bc->trial_next = 1 - t;
  return VM_OK;
}

void vm_bc_apply(const vm_bc *bc, double *r) {
  int nt = vm_nthreads(bc->ctx);
  const int64_t nv = bc->nv;
#pragma omp parallel for num_threads(nt) schedule(static) if (nv >= VM_PAR_MIN)
  for (int64_t v = 0; v < nv; v++) {
    double *rv = r + 3 * v;
    switch (bc->cls[v]) {
    case VM_VERTEX_FIXED: rv[0] = rv[1] = rv[2] = 0; break;
    case VM_VERTEX_SLIP: apply_slip(bc, bc->slip[v], rv); break;
    default:
      if (bc->dim == 2) rv[2] = 0;
    }
  }
}

int vm_bc_basis(const vm_bc *bc, int64_t v, double Q[9]) {
  memset(Q, 0, 9 * sizeof *Q);
  switch (bc->cls[v]) {
  case VM_VERTEX_FIXED: return 0;
  case VM_VERTEX_SLIP: {
    int32_t s = bc->slip[v];
    memcpy(Q, bc->Q + 9 * s, 9 * sizeof *Q);
    return bc->rank[s];
  }
  default:
    for (int k = 0; k < bc->dim; k++) Q[3 * k + k] = 1;
    return bc->dim;
  }
}

int vm_bc_class(const vm_bc *bc, int64_t v) { return bc->cls[v]; }

int64_t vm_bc_count(const vm_bc *bc, int cls) { return cls >= 0 && cls < 3 ? bc->count[cls] : 0; }

int vm_bc_dim(const vm_bc *bc) { return bc->dim; }
