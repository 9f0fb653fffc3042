/* lib/gen/src/aircraft.c: the bundled aircraft model: NACA-section wings,
 * stabilizers and fin whose root curves are ports of a fuselage ring grid,
 * joined into one closed, outward-oriented triangulation. */
#include "varmesh/aircraft.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define AC_PI 3.14159265358979323846
#define AC_TWO_PI (2.0 * AC_PI)

/* ---- fuselage: elliptic sections (half-width a = R f, half-height
 * b = kb R f) around the axis z = zc(x), x from 0 (nose) to L (tail) ---- */

typedef struct body {
  double L, R, kb;
  double xn;  /* end of the elliptic nose */
  double xt;  /* start of the tail cone */
  double xce; /* start of the rounded tail tip (length re) */
  double re, fe;
  double droop, upsweep; /* nose axis drop, tail axis rise (times R) */
} body;

/* Section scale f(x) in [0, 1]; 0 at and beyond the two poles. */
static double body_f(const body *b, double x) {
  if (x <= 0 || x >= b->L) return 0;
  if (x < b->xn) {
    double e = 1 - x / b->xn;
    return sqrt(1 - e * e);
  }
  if (x <= b->xt) return 1;
  double xi = (x - b->xt) / (b->xce - b->xt);
  double g = 1 - (1 - b->fe) * pow(xi, 1.6);
  if (x > b->xce) { /* the cap factor has zero slope at xce: C1 join */
    double e = (x - b->xce) / b->re;
    g *= e < 1 ? sqrt(1 - e * e) : 0;
  }
  return g;
}

static double body_zc(const body *b, double x) {
  if (x < b->xn) {
    double e = 1 - (x > 0 ? x : 0) / b->xn;
    return -b->droop * b->R * e * e;
  }
  if (x <= b->xt) return 0;
  double xi = (x - b->xt) / (b->xce - b->xt);
  return b->upsweep * b->R * xi * xi;
}

/* Point of the fuselage at axial position x and angle th (0 = top, pi/2 =
 * the +y side): (x, a sin th, zc + b cos th). Normal d/dx x d/dth points out. */
static void body_point(const body *b, double x, double th, double p[3]) {
  double f = body_f(b, x);
  p[0] = x;
  p[1] = b->R * f * sin(th);
  p[2] = body_zc(b, x) + b->kb * b->R * f * cos(th);
}

/* Negative inside, positive outside, zero on the surface. */
static double body_implicit(const body *b, const double p[3]) {
  double f = body_f(b, p[0]);
  if (!(f > 1e-12)) return 1;
  double y = p[1] / (b->R * f), z = (p[2] - body_zc(b, p[0])) / (b->kb * b->R * f);
  return y * y + z * z - 1;
}

/* Angle th in [0, 2 pi) of a point on (or near) the surface. */
static double body_theta(const body *b, const double p[3]) {
  double f = body_f(b, p[0]);
  double th = atan2(p[1] / (b->R * f), (p[2] - body_zc(b, p[0])) / (b->kb * b->R * f));
  return th < 0 ? th + AC_TWO_PI : th;
}

/* Mean radius of a section, for spacing decisions. */
static double body_rmean(const body *b, double x) {
  return 0.5 * (1 + b->kb) * b->R * body_f(b, x);
}

/* Meridian arc length S(x) of the curve (x, rmean(x)), tabulated. */
typedef struct arclen {
  int n;
  double *x, *s;
} arclen;

static double arc_s(const arclen *a, double x) {
  int lo = 0, hi = a->n - 1;
  if (x <= a->x[0]) return a->s[0];
  if (x >= a->x[hi]) return a->s[hi];
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (a->x[mid] <= x)
      lo = mid;
    else
      hi = mid;
  }
  double t = (x - a->x[lo]) / (a->x[hi] - a->x[lo]);
  return a->s[lo] + t * (a->s[hi] - a->s[lo]);
}

static double arc_x(const arclen *a, double s) {
  int lo = 0, hi = a->n - 1;
  if (s <= a->s[0]) return a->x[0];
  if (s >= a->s[hi]) return a->x[hi];
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (a->s[mid] <= s)
      lo = mid;
    else
      hi = mid;
  }
  double t = (s - a->s[lo]) / (a->s[hi] - a->s[lo]);
  return a->x[lo] + t * (a->x[hi] - a->x[lo]);
}

/* ---- output buffers ---- */

typedef struct builder {
  vm_ctx *ctx;
  double *xyz;
  int64_t nv, vcap;
  int32_t *tri;
  uint8_t *comp;
  int64_t nt, tcap;
} builder;

/* Append a vertex; returns its index, or -1 (VM_ERR_NOMEM recorded). */
static int32_t add_vertex(builder *B, const double p[3]) {
  if (B->nv == B->vcap) {
    int64_t cap = B->vcap ? 2 * B->vcap : 1024;
    if (cap > INT32_MAX) {
      vm_error(B->ctx, VM_ERR_NOMEM, "aircraft: too many vertices");
      return -1;
    }
    double *q = vm_realloc(B->ctx, B->xyz, (size_t)cap * 3 * sizeof *q);
    if (!q) return -1;
    B->xyz = q;
    B->vcap = cap;
  }
  memcpy(B->xyz + 3 * B->nv, p, 3 * sizeof *p);
  return (int32_t)B->nv++;
}

static int add_tri(builder *B, int32_t a, int32_t b, int32_t c, int comp) {
  if (B->nt == B->tcap) {
    int64_t cap = B->tcap ? 2 * B->tcap : 2048;
    if (cap > INT32_MAX) return vm_error(B->ctx, VM_ERR_NOMEM, "aircraft: too many triangles");
    int32_t *t = vm_realloc(B->ctx, B->tri, (size_t)cap * 3 * sizeof *t);
    if (!t) return VM_ERR_NOMEM;
    B->tri = t;
    uint8_t *c8 = vm_realloc(B->ctx, B->comp, (size_t)cap);
    if (!c8) return VM_ERR_NOMEM;
    B->comp = c8;
    B->tcap = cap;
  }
  int32_t *t = B->tri + 3 * B->nt;
  t[0] = a;
  t[1] = b;
  t[2] = c;
  B->comp[B->nt++] = (uint8_t)comp;
  return VM_OK;
}

static double vdist(const builder *B, int32_t a, int32_t b) {
  const double *p = B->xyz + 3 * (int64_t)a, *q = B->xyz + 3 * (int64_t)b;
  return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
              (p[2] - q[2]) * (p[2] - q[2]));
}

/* The quad a-b-c-d (counter-clockwise seen from outside) as triangles:
 * repeated corners (collapsed edges at poles, leading and trailing edges,
 * coarsened rings) leave one triangle or none; a full quad is split along
 * its shorter diagonal. */
static int add_quad(builder *B, int32_t a, int32_t b, int32_t c, int32_t d, int comp) {
  int32_t v[4] = {a, b, c, d}, w[4];
  int n = 0, rc;
  for (int i = 0; i < 4; i++)
    if (n == 0 || v[i] != w[n - 1]) w[n++] = v[i];
  if (n > 1 && w[n - 1] == w[0]) n--;
  if (n < 3) return VM_OK;
  if (n == 3) return add_tri(B, w[0], w[1], w[2], comp);
  if (vdist(B, w[0], w[2]) <= vdist(B, w[1], w[3])) {
    if ((rc = add_tri(B, w[0], w[1], w[2], comp)) != VM_OK) return rc;
    return add_tri(B, w[0], w[2], w[3], comp);
  }
  if ((rc = add_tri(B, w[0], w[1], w[3], comp)) != VM_OK) return rc;
  return add_tri(B, w[1], w[2], w[3], comp);
}

/* ---- lifting surfaces: NACA 4-digit sections on a trapezoid ---- */

typedef struct lsurf {
  int comp;
  int vertical;       /* fin: span along +z, thickness along y */
  double side;        /* +1: span along +y, -1: along -y */
  double x0, z0;      /* leading edge and height at span s = 0 */
  double s_lo, s_tip; /* root search range; end of the trapezoid */
  double c0, c1;      /* chords at s = 0 and s = s_tip */
  double tan_sweep, tan_dihedral;
  double t0, t1;             /* thickness ratios at s = 0 and s = s_tip */
  double m, pc;              /* camber and its chordwise position */
  int ndes;                  /* desired chordwise stations per side */
  double u_le;               /* largest first station that resolves the nose */
  int n, J, K;               /* chord stations per side, span stations, tip stations */
  double psi_le, x_le, x_te; /* most forward root point (see root_at) and x range */
  int32_t *kst;              /* n + 1: the fuselage ring of each station */
  int slot, first;           /* first slot of its port pair, the side in that slot */
  /* root loop of 2n points: 0 leading point, i = 1..n-1 upper (right for the
   * fin), n trailing edge, 2n - i lower; arrays of 2n */
  double *ru, *rpsi, *rs; /* chord parameter, psi (see root_at), span */
  double *rx, *rth;       /* fuselage parameters of the root points */
  int32_t *rvid;
} lsurf;

/* Half-thickness of the closed-trailing-edge NACA 4-digit section; exactly 0
 * at both ends. */
static double naca_thickness(double t, double u) {
  if (u <= 0 || u >= 1) return 0;
  return 5 * t * (0.2969 * sqrt(u) + u * (-0.1260 + u * (-0.3516 + u * (0.2843 - 0.1036 * u))));
}

static void naca_camber(double m, double p, double u, double *yc, double *dyc) {
  if (m == 0) {
    *yc = *dyc = 0;
  } else if (u < p) {
    *yc = m / (p * p) * (2 * p * u - u * u);
    *dyc = 2 * m / (p * p) * (p - u);
  } else {
    *yc = m / ((1 - p) * (1 - p)) * (1 - 2 * p + 2 * p * u - u * u);
    *dyc = 2 * m / ((1 - p) * (1 - p)) * (p - u);
  }
}

/* Surface point at chord parameter u, side sigma, span s, with the section
 * thickness scaled by `thick` (the rounded tip). */
static void ls_point(const lsurf *w, double u, double sigma, double s, double thick, double p[3]) {
  double r = s / w->s_tip;
  double fr = r < 0 ? 0 : r > 1 ? 1 : r;
  double c = w->c0 + (w->c1 - w->c0) * r;
  double t = w->t0 + (w->t1 - w->t0) * fr;
  double yt = thick * naca_thickness(t, u), yc, dyc;
  naca_camber(w->m, w->pc, u, &yc, &dyc);
  double cs = 1 / sqrt(1 + dyc * dyc); /* cos of the camber slope angle */
  double xa = u - sigma * yt * dyc * cs, za = yc + sigma * yt * cs;
  p[0] = w->x0 + s * w->tan_sweep + c * xa;
  if (w->vertical) {
    p[1] = c * za;
    p[2] = w->z0 + s;
  } else {
    p[1] = w->side * s;
    p[2] = w->z0 + s * w->tan_dihedral + c * za;
  }
}

/* Span coordinate where the spanwise line (u, sigma) enters the fuselage,
 * scanning inward from the tip and then bisecting. Returns 0, or -1 if the
 * line never meets the fuselage. */
static int ls_root(const lsurf *w, const body *b, double u, double sigma, double *s_out) {
  const int nscan = 48;
  double p[3], hi = w->s_tip, lo = hi;
  int k;
  ls_point(w, u, sigma, hi, 1, p);
  if (body_implicit(b, p) <= 0) return -1;
  for (k = 1; k <= nscan; k++) {
    lo = w->s_tip - (w->s_tip - w->s_lo) * k / nscan;
    ls_point(w, u, sigma, lo, 1, p);
    if (body_implicit(b, p) < 0) break;
    hi = lo;
  }
  if (k > nscan) return -1;
  for (int it = 0; it < 200; it++) {
    double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    ls_point(w, u, sigma, mid, 1, p);
    if (body_implicit(b, p) < 0)
      lo = mid;
    else
      hi = mid;
  }
  *s_out = hi;
  return 0;
}

/* The root curve parametrized by psi in [-1, 1]: u = psi^2, the upper side
 * for psi > 0 (smooth through the leading edge). */
static int root_at(const lsurf *w, const body *b, double psi, double *u, double *sig, double *s,
                   double p[3]) {
  *u = psi * psi < 1 ? psi * psi : 1;
  *sig = psi < 0 ? -1 : 1;
  if (ls_root(w, b, *u, *sig, s)) return -1;
  ls_point(w, *u, *sig, *s, 1, p);
  return 0;
}

/* Chordwise station distribution: clustered at the leading edge (cosine),
 * moderately at the trailing edge. */
static double station_dist(double t) {
  return 0.3 * (1 - cos(AC_PI * t)) + 0.4 * (1 - cos(0.5 * AC_PI * t));
}

/* The desired chordwise stations of a surface, i = 0..port_nd(w): the
 * distribution above, with one more station near the leading edge where the
 * first one would leave the nose radius unresolved (a sharp-looking edge). */
static int port_nd(const lsurf *w) {
  return w->ndes + (station_dist(1.0 / w->ndes) > 2.5 * w->u_le);
}

static double port_u(const lsurf *w, int i) {
  double u1 = station_dist(1.0 / w->ndes);
  if (i == 0) return 0;
  if (u1 > w->u_le && i == 1) return w->u_le;
  if (u1 > 2.5 * w->u_le) i--;
  return station_dist((double)i / w->ndes);
}

static int ls_alloc(vm_ctx *ctx, lsurf *w) {
  size_t n2 = 2 * (size_t)w->n;
  w->ru = vm_alloc_array(ctx, 5 * n2, sizeof(double));
  w->rvid = vm_alloc_array(ctx, n2, sizeof(int32_t));
  if (!w->ru || !w->rvid) return VM_ERR_NOMEM;
  w->rpsi = w->ru + n2;
  w->rs = w->ru + 2 * n2;
  w->rx = w->ru + 3 * n2;
  w->rth = w->ru + 4 * n2;
  return VM_OK;
}

static void ls_free(vm_ctx *ctx, lsurf *w) {
  vm_free(ctx, w->ru);
  vm_free(ctx, w->rvid);
  vm_free(ctx, w->kst);
  w->ru = NULL;
  w->rvid = NULL;
  w->kst = NULL;
}

static const char *comp_name(int comp) {
  static const char *names[] = {"fuselage",         "right wing",      "left wing",
                                "right stabilizer", "left stabilizer", "fin"};
  return names[comp];
}

/* The x range of the root curve: its most forward point (sampled, then a
 * golden-section search) and the trailing edge. */
static int ls_extent(vm_ctx *ctx, const body *bd, lsurf *w) {
  double u, sg, s, p[3];
  const int ns = 140;
  int kbest = 0;
  double best = HUGE_VAL;
  for (int k = 0; k <= ns; k++) {
    if (root_at(w, bd, -0.7 + 1.4 * k / ns, &u, &sg, &s, p)) goto miss;
    if (p[0] < best) {
      best = p[0];
      kbest = k;
    }
  }
  double a = -0.7 + 1.4 * (kbest > 0 ? kbest - 1 : 0) / ns;
  double c = -0.7 + 1.4 * (kbest < ns ? kbest + 1 : ns) / ns;
  const double gr = 0.5 * (sqrt(5.0) - 1);
  double x1 = c - gr * (c - a), x2 = a + gr * (c - a), f1, f2;
  if (root_at(w, bd, x1, &u, &sg, &s, p)) goto miss;
  f1 = p[0];
  if (root_at(w, bd, x2, &u, &sg, &s, p)) goto miss;
  f2 = p[0];
  for (int it = 0; it < 60; it++) {
    if (f1 < f2) {
      c = x2;
      x2 = x1;
      f2 = f1;
      x1 = c - gr * (c - a);
      if (root_at(w, bd, x1, &u, &sg, &s, p)) goto miss;
      f1 = p[0];
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + gr * (c - a);
      if (root_at(w, bd, x2, &u, &sg, &s, p)) goto miss;
      f2 = p[0];
    }
  }
  w->psi_le = 0.5 * (a + c);
  if (root_at(w, bd, w->psi_le, &u, &sg, &s, p)) goto miss;
  w->x_le = p[0];
  if (root_at(w, bd, 1, &u, &sg, &s, p)) goto miss;
  w->x_te = p[0];
  return VM_OK;
miss:
  return vm_error(ctx, VM_ERR_NUMERIC, "aircraft: %s does not meet the fuselage",
                  comp_name(w->comp));
}

/* The port: the root curve cut at its stations (fuselage rings xs[kst[i]]),
 * by the upper and the lower side at each station strictly inside. Creates
 * the root vertices (loop order, see lsurf). */
static int ls_port(builder *B, const body *bd, lsurf *w, const double *xs) {
  int n = w->n, n2 = 2 * n;
  double u, sg, s, p[3];
  for (int q = 0; q < n2; q++) {
    double psi;
    if (q == 0) {
      psi = w->psi_le;
    } else if (q == n) {
      psi = 1;
    } else {
      double xi = xs[w->kst[q < n ? q : n2 - q]];
      double lo = q < n ? w->psi_le : -1, hi = q < n ? 1 : w->psi_le;
      for (int it = 0; it < 64; it++) {
        double mid = 0.5 * (lo + hi);
        if (root_at(w, bd, mid, &u, &sg, &s, p)) goto miss;
        /* x grows towards +1 on the upper branch, towards -1 on the lower */
        if ((p[0] < xi) == (q < n))
          lo = mid;
        else
          hi = mid;
      }
      psi = 0.5 * (lo + hi);
    }
    if (root_at(w, bd, psi, &u, &sg, &s, p)) goto miss;
    w->ru[q] = u;
    w->rpsi[q] = psi;
    w->rs[q] = s;
    w->rx[q] = p[0];
    w->rth[q] = body_theta(bd, p);
    if ((w->rvid[q] = add_vertex(B, p)) < 0) return VM_ERR_NOMEM;
  }
  /* each branch must advance in x from the leading point to the trailing edge */
  for (int i = 0; i < n; i++) {
    int up0 = i, up1 = i + 1, lo0 = (n2 - i) % n2, lo1 = n2 - i - 1;
    if (!(w->rx[up1] > w->rx[up0]) || !(w->rx[lo1] > w->rx[lo0]))
      return vm_error(B->ctx, VM_ERR_NUMERIC,
                      "aircraft: %s root curve not monotone in x at station %d", comp_name(w->comp),
                      i);
  }
  return VM_OK;
miss:
  return vm_error(B->ctx, VM_ERR_NUMERIC, "aircraft: %s does not meet the fuselage",
                  comp_name(w->comp));
}

/* Blend of the chordwise positions from the root distribution (different on
 * the two sides) to a common one, so the two sides close at the tip. */
static double span_blend(double tau) {
  if (tau <= 0.25) return 0;
  double t = (tau - 0.25) / 0.75;
  return t * t * (3 - 2 * t);
}

/* The surface from the port outward: J stations to s_tip, then K stations
 * of the rounded tip whose last one (zero thickness) closes the surface; the
 * leading and trailing edge vertices of the tip station end those edges.
 * Adds the trailing edge length to *te. */
static int ls_grid(builder *B, const lsurf *w, double *te) {
  vm_ctx *ctx = B->ctx;
  int n = w->n, n2 = 2 * n, nst = w->J + w->K, rc = VM_OK;
  int flip = w->vertical ? 1 : w->side < 0;
  int32_t *prev = vm_alloc_array(ctx, (size_t)n2, sizeof *prev);
  int32_t *cur = vm_alloc_array(ctx, (size_t)n2, sizeof *cur);
  double *ubar = vm_alloc_array(ctx, 2 * (size_t)n2, sizeof *ubar), *ptip = ubar + n2;
  if (!prev || !cur || !ubar) {
    rc = VM_ERR_NOMEM;
    goto done;
  }
  memcpy(prev, w->rvid, (size_t)n2 * sizeof *prev);
  for (int q = 0; q < n2; q++) {
    int i = q <= n ? q : n2 - q;
    ubar[q] = q == 0 ? 0 : q == n ? 1 : 0.5 * (w->ru[i] + w->ru[n2 - i]);
    ptip[q] = q <= n ? sqrt(ubar[q]) : -sqrt(ubar[q]);
  }
  for (int st = 1; st <= nst; st++) {
    for (int q = 0; q < n2; q++) {
      if (st == nst && q > n) { /* zero thickness: the two sides meet */
        cur[q] = cur[n2 - q];
        continue;
      }
      if (st > w->J && (q == 0 || q == n)) { /* rounding of zero radius */
        cur[q] = prev[q];
        continue;
      }
      double u, sig = q <= n ? 1 : -1, s, thick = 1, p[3];
      if (st <= w->J) { /* interpolate in psi: the root's leading point may
                           lie on either side of the section's nose */
        double tau = (double)st / w->J;
        double psi = w->rpsi[q] + span_blend(tau) * (ptip[q] - w->rpsi[q]);
        u = psi * psi;
        sig = psi < 0 ? -1 : 1;
        s = w->rs[q] + tau * (w->s_tip - w->rs[q]);
      } else { /* each section point turns around the camber line on a
                  quarter circle of its own half-thickness */
        int k = st - w->J;
        double phi = 0.5 * AC_PI * k / w->K;
        u = ubar[q];
        s = w->s_tip + w->c1 * naca_thickness(w->t1, u) * sin(phi);
        thick = k == w->K ? 0 : cos(phi);
      }
      ls_point(w, u, sig, s, thick, p);
      if ((cur[q] = add_vertex(B, p)) < 0) {
        rc = VM_ERR_NOMEM;
        goto done;
      }
    }
    for (int q = 0; q < n2; q++) {
      int q1 = (q + 1) % n2;
      rc = flip ? add_quad(B, cur[q], cur[q1], prev[q1], prev[q], w->comp)
                : add_quad(B, prev[q], prev[q1], cur[q1], cur[q], w->comp);
      if (rc != VM_OK) goto done;
    }
    *te += vdist(B, prev[n], cur[n]);
    int32_t *t = prev;
    prev = cur;
    cur = t;
  }
done:
  vm_free(ctx, prev);
  vm_free(ctx, cur);
  vm_free(ctx, ubar);
  return rc;
}

/* ---- the fuselage ring grid ----
 * Every ring has M slots around the fuselage in increasing th; the slots of
 * a port come in pairs (first, first + 1 mod M). Between the first leading
 * edge and the last trailing edge the rings stand at the stations
 * xs[0..nk-1] shared by all ports (constant x, except where they pass
 * through a port). Each port has its own stations among them (kst); a ring
 * holds in the port's pair the port's upper and lower root points of the
 * station at or before it, its leading or trailing edge vertex (both slots)
 * at the ends, and outside the port one vertex in both slots. The quad of
 * the pair between the rings of two consecutive stations of a port is the
 * port itself and is left open; every other quad is emitted, and quads whose
 * corners repeat (collapsed pairs, rings sharing a port point) shrink to
 * triangles or vanish. Towards the poles the rings are interpolated in
 * meridian arc length, and neighbouring slots are merged in groups of 2^lv
 * so the rings keep sensible proportions. */

enum { NPORT = 5 };

typedef struct fus {
  const body *bd;
  int M;
  lsurf *port[NPORT];
  double thnom[NPORT]; /* nominal angle of each port (its leading edge) */
  uint8_t *pairfirst;  /* M: slot is the first of a port pair */
  uint8_t *join;       /* M scratch: slot k is one vertex with slot k + 1 */
  uint8_t *fixed;      /* M scratch */
  int nk;
  double *xs; /* nk ring stations */
  arclen arc;
  double h_ax, h_c;
} fus;

typedef struct ring {
  double *x, *th;
  int32_t *vid;
  int k; /* station ring index, or -1 */
} ring;

static double wrap_near(double t, double ref) {
  return t + AC_TWO_PI * floor((ref - t) / AC_TWO_PI + 0.5);
}

/* Give every run of joined slots one vertex: an already assigned one (port
 * vertices), or a new one at the mean (x, th) of its slots. */
static int ring_finish(builder *B, const fus *F, ring *r) {
  int M = F->M, s0 = -1;
  for (int k = 0; k < M; k++)
    if (!F->join[(k + M - 1) % M]) {
      s0 = k;
      break;
    }
  int k = s0 < 0 ? 0 : s0, done = 0;
  while (done < M) {
    int len = 1;
    while (len < M && F->join[(k + len - 1) % M]) len++;
    int32_t v = -1;
    double sx = 0, sth = 0, th0 = r->th[k];
    for (int q = 0; q < len; q++) {
      int s = (k + q) % M;
      if (r->vid[s] >= 0) v = r->vid[s];
      sx += r->x[s];
      sth += wrap_near(r->th[s], th0);
    }
    if (v < 0) {
      double p[3];
      body_point(F->bd, sx / len, sth / len, p);
      if ((v = add_vertex(B, p)) < 0) return VM_ERR_NOMEM;
    }
    for (int q = 0; q < len; q++) r->vid[(k + q) % M] = v;
    k = (k + len) % M;
    done += len;
  }
  /* the slots must go around once, in order */
  for (k = 0; k < M; k++) {
    int k1 = (k + 1) % M;
    double d = r->th[k1] - r->th[k] + (k1 == 0 ? AC_TWO_PI : 0);
    if (r->vid[k] != r->vid[k1] && !(d > 0))
      return vm_error(B->ctx, VM_ERR_NUMERIC, "aircraft: fuselage ring folds at slot %d", k);
  }
  return VM_OK;
}

/* The station of port w that ring k passes through: the last one at or
 * before the ring; -1 outside the port. */
static int port_station(const lsurf *w, int k) {
  if (k < w->kst[0] || k > w->kst[w->n]) return -1;
  int i = 0;
  while (i < w->n && w->kst[i + 1] <= k) i++;
  return i;
}

/* Station ring k: the ports' root points in their slots, every other slot
 * spread evenly in th between its fixed neighbours. A ring through no port
 * spreads its slots between the ports' nominal angles. */
static int station_ring(builder *B, const fus *F, int k, ring *r) {
  int M = F->M, f0 = -1;
  for (int s = 0; s < M; s++) {
    r->vid[s] = -1;
    r->x[s] = F->xs[k];
    F->fixed[s] = 0;
    F->join[s] = F->pairfirst[s];
  }
  r->k = k;
  for (int p = 0; p < NPORT; p++) {
    const lsurf *w = F->port[p];
    int i = port_station(w, k);
    if (i < 0) continue;
    int n2 = 2 * w->n, up = i, lo = (n2 - i) % n2;
    int q[2] = {w->first > 0 ? up : lo, w->first > 0 ? lo : up};
    for (int h = 0; h < 2; h++) {
      int s = (w->slot + h) % M;
      r->x[s] = w->rx[q[h]];
      r->th[s] = w->rth[q[h]];
      r->vid[s] = w->rvid[q[h]];
      F->fixed[s] = 1;
    }
    if (i > 0 && i < w->n) F->join[w->slot] = 0;
    f0 = w->slot;
  }
  if (f0 < 0)
    for (int p = 0; p < NPORT; p++) {
      const lsurf *w = F->port[p];
      for (int h = 0; h < 2; h++) {
        r->th[(w->slot + h) % M] = F->thnom[p];
        F->fixed[(w->slot + h) % M] = 1;
      }
      f0 = w->slot;
    }
  int f = f0;
  do {
    int g = (f + 1) % M, ng = 0;
    while (!F->fixed[g]) {
      ng++;
      g = (g + (F->pairfirst[g] ? 2 : 1)) % M;
    }
    if (ng > 0) {
      double tf = r->th[f], tg = r->th[g];
      while (tg <= tf) tg += AC_TWO_PI;
      int s = (f + 1) % M;
      for (int q = 1; q <= ng; q++) {
        int len = F->pairfirst[s] ? 2 : 1;
        for (int h = 0; h < len; h++) r->th[(s + h) % M] = tf + (tg - tf) * q / (ng + 1);
        s = (s + len) % M;
      }
    }
    f = g;
  } while (f != f0);
  for (int s = 0; s < M; s++) r->th[s] = wrap_near(r->th[s], AC_TWO_PI * (s + 0.5) / M);
  return ring_finish(B, F, r);
}

/* Quads between consecutive rings, leaving the ports open. */
static int emit_rings(builder *B, const fus *F, const ring *A, const ring *C) {
  int M = F->M;
  for (int k = 0; k < M; k++) {
    int k1 = (k + 1) % M, skip = 0;
    if (A->vid[k] != C->vid[k] && !(C->x[k] > A->x[k]))
      return vm_error(B->ctx, VM_ERR_NUMERIC, "aircraft: fuselage rings cross at slot %d", k);
    for (int p = 0; p < NPORT; p++) {
      const lsurf *w = F->port[p];
      if (w->slot == k && A->k >= 0 && C->k >= 0) {
        int ia = port_station(w, A->k), ic = port_station(w, C->k);
        if (ia >= 0 && ic == ia + 1) skip = 1;
      }
    }
    if (skip) continue;
    int rc = add_quad(B, A->vid[k], C->vid[k], C->vid[k1], A->vid[k1], VM_AIRCRAFT_FUSELAGE);
    if (rc != VM_OK) return rc;
  }
  return VM_OK;
}

/* Rings between A and C (exclusive): each slot moves from A to C evenly in
 * meridian arc length; emits every quad from A up to C. t0, t1: scratch. */
static int lerp_section(builder *B, const fus *F, const ring *A, const ring *C, ring *t0,
                        ring *t1) {
  int M = F->M, rc;
  double dmax = 0;
  for (int k = 0; k < M; k++) {
    double d = arc_s(&F->arc, C->x[k]) - arc_s(&F->arc, A->x[k]);
    if (d > dmax) dmax = d;
  }
  int n = (int)lround(dmax / F->h_ax);
  if (n < 1) n = 1;
  int lvmax = 0;
  while ((M >> (lvmax + 1)) >= 12) lvmax++;
  const ring *prev = A;
  ring *tmp[2] = {t0, t1};
  for (int m = 1; m < n; m++) {
    ring *r = tmp[m % 2];
    double t = (double)m / n, xm = 0;
    for (int k = 0; k < M; k++) {
      double sa = arc_s(&F->arc, A->x[k]), sc = arc_s(&F->arc, C->x[k]);
      r->x[k] = arc_x(&F->arc, sa + t * (sc - sa));
      r->th[k] = A->th[k] + t * (C->th[k] - A->th[k]);
      r->vid[k] = -1;
      xm += r->x[k];
    }
    xm /= M;
    /* fewer distinct vertices where the circumference is small (poles) */
    double want = AC_TWO_PI * body_rmean(F->bd, xm) / F->h_c;
    int lv = 0;
    while (lv < lvmax && (double)(M >> (lv + 1)) >= (want > 8 ? want : 8)) lv++;
    for (int k = 0; k < M; k++)
      F->join[k] = F->pairfirst[k] || (k + 1 < M && (k >> lv) == ((k + 1) >> lv));
    r->k = -1;
    if ((rc = ring_finish(B, F, r)) != VM_OK) return rc;
    if ((rc = emit_rings(B, F, prev, r)) != VM_OK) return rc;
    prev = r;
  }
  return emit_rings(B, F, prev, C);
}

static int pole_ring(builder *B, const fus *F, double x, const ring *like, ring *r) {
  double p[3];
  body_point(F->bd, x, 0, p);
  int32_t v = add_vertex(B, p);
  if (v < 0) return VM_ERR_NOMEM;
  for (int k = 0; k < F->M; k++) {
    r->x[k] = x;
    r->th[k] = like->th[k];
    r->vid[k] = v;
  }
  r->k = -1;
  return VM_OK;
}

static int fuselage(builder *B, fus *F) {
  int M = F->M, rc = VM_OK;
  ring R[4];
  memset(R, 0, sizeof R);
  for (int i = 0; i < 4; i++) {
    R[i].x = vm_alloc_array(B->ctx, 2 * (size_t)M, sizeof(double));
    R[i].vid = vm_alloc_array(B->ctx, (size_t)M, sizeof(int32_t));
    if (!R[i].x || !R[i].vid) {
      rc = VM_ERR_NOMEM;
      goto done;
    }
    R[i].th = R[i].x + M;
  }
  ring *a = &R[0], *c = &R[1], *t;
  if ((rc = station_ring(B, F, 0, c)) != VM_OK) goto done;
  if ((rc = pole_ring(B, F, 0, c, a)) != VM_OK) goto done;
  if ((rc = lerp_section(B, F, a, c, &R[2], &R[3])) != VM_OK) goto done;
  for (int k = 1; k < F->nk; k++) {
    t = a, a = c, c = t;
    if ((rc = station_ring(B, F, k, c)) != VM_OK) goto done;
    if ((rc = emit_rings(B, F, a, c)) != VM_OK) goto done;
  }
  t = a, a = c, c = t;
  if ((rc = pole_ring(B, F, F->bd->L, a, c)) != VM_OK) goto done;
  rc = lerp_section(B, F, a, c, &R[2], &R[3]);
done:
  for (int i = 0; i < 4; i++) {
    vm_free(B->ctx, R[i].x);
    vm_free(B->ctx, R[i].vid);
  }
  return rc;
}

/* The station rings: the union of every port's own chordwise stations
 * (clustered at its leading edge) and of evenly spaced fillers, thinned
 * greedily from the finest spacing up so no two are much closer than the
 * spacing they were asked for; leading and trailing edges always kept. Each
 * port then takes the rings nearest to its own stations. */
typedef struct cand {
  double h, x;
} cand;

static int cmp_cand(const void *a, const void *b) {
  const cand *p = a, *q = b;
  if (p->h != q->h) return p->h < q->h ? -1 : 1;
  return p->x < q->x ? -1 : p->x > q->x;
}

static int cmp_double(const void *a, const void *b) {
  double p = *(const double *)a, q = *(const double *)b;
  return p < q ? -1 : p > q;
}

static int make_stations(vm_ctx *ctx, fus *F, double L) {
  double x0 = HUGE_VAL, x1 = -HUGE_VAL;
  size_t nc = 0, cap = 0;
  for (int p = 0; p < NPORT; p++) {
    x0 = fmin(x0, F->port[p]->x_le);
    x1 = fmax(x1, F->port[p]->x_te);
    cap += (size_t)port_nd(F->port[p]) + 1;
  }
  int nf = (int)ceil((x1 - x0) / F->h_ax);
  cap += (size_t)nf + 1;
  cand *c = vm_alloc_array(ctx, cap, sizeof *c);
  F->xs = vm_alloc_array(ctx, cap, sizeof *F->xs);
  if (!c || !F->xs) {
    vm_free(ctx, c);
    return VM_ERR_NOMEM;
  }
  for (int p = 0; p < NPORT; p++) {
    const lsurf *w = F->port[p];
    int n = port_nd(w);
    double d = w->x_te - w->x_le;
    for (int i = 0; i <= n; i++) {
      double xm = port_u(w, i > 0 ? i - 1 : 0), x = port_u(w, i);
      double xp = port_u(w, i < n ? i + 1 : n);
      c[nc].x = i == 0 ? w->x_le : i == n ? w->x_te : w->x_le + d * x;
      c[nc++].h = i == 0 || i == n ? 0 : d * fmin(x - xm, xp - x);
    }
  }
  for (int j = 1; j < nf; j++) {
    c[nc].x = x0 + (x1 - x0) * j / nf;
    c[nc++].h = F->h_ax;
  }
  qsort(c, nc, sizeof *c, cmp_cand);
  int nk = 0;
  for (size_t i = 0; i < nc; i++) {
    double need = c[i].h > 0 ? 0.6 * c[i].h : 1e-9 * L;
    int ok = 1;
    for (int k = 0; k < nk && ok; k++) ok = fabs(c[i].x - F->xs[k]) >= need;
    if (ok) F->xs[nk++] = c[i].x;
  }
  vm_free(ctx, c);
  qsort(F->xs, (size_t)nk, sizeof *F->xs, cmp_double);
  F->nk = nk;
  /* each port's own stations, moved to the nearest ring (ends exactly) */
  for (int p = 0; p < NPORT; p++) {
    lsurf *w = F->port[p];
    int n = port_nd(w), m = 0;
    double d = w->x_te - w->x_le;
    w->kst = vm_alloc_array(ctx, (size_t)n + 1, sizeof *w->kst);
    if (!w->kst) return VM_ERR_NOMEM;
    for (int i = 0; i <= n; i++) {
      double x = i == 0 ? w->x_le : i == n ? w->x_te : w->x_le + d * port_u(w, i);
      int kb = 0;
      for (int k = 1; k < nk; k++)
        if (fabs(F->xs[k] - x) < fabs(F->xs[kb] - x)) kb = k;
      if (i == n && m > 0 && w->kst[m - 1] >= kb) m--; /* the trailing edge wins */
      if (m == 0 || kb > w->kst[m - 1]) w->kst[m++] = kb;
    }
    w->n = m - 1;
    if (w->n < 2)
      return vm_error(ctx, VM_ERR_NUMERIC, "aircraft: %s root too short", comp_name(w->comp));
  }
  return VM_OK;
}

/* ---- assembly ---- */

vm_aircraft_opts vm_aircraft_opts_default(void) {
  vm_aircraft_opts o;
  memset(&o, 0, sizeof o);
  o.resolution = 4;
  o.length = 15;
  o.span = 13.5;
  o.sweep_deg = 28;
  o.dihedral_deg = 5;
  o.tag_components = 0;
  return o;
}

int vm_gen_aircraft(vm_ctx *ctx, const vm_aircraft_opts *o, vm_mesh **out) {
  return vm_gen_aircraft_info(ctx, o, out, NULL);
}

int vm_gen_aircraft_info(vm_ctx *ctx, const vm_aircraft_opts *o, vm_mesh **out,
                         vm_aircraft_info *info) {
  if (out) *out = NULL;
  if (info) memset(info, 0, sizeof *info);
  if (!ctx || !o || !out)
    return ctx ? vm_error(ctx, VM_ERR_ARG, "aircraft: NULL argument") : VM_ERR_ARG;
  const double L = o->length;
  if (o->resolution < 1 || o->resolution > 32)
    return vm_error(ctx, VM_ERR_ARG, "aircraft: resolution %d not in [1, 32]", o->resolution);
  if (!(L > 0 && L < 1e6))
    return vm_error(ctx, VM_ERR_ARG, "aircraft: length %g not in (0, 1e6)", L);
  if (!(o->span >= 0.35 * L && o->span <= 2.5 * L))
    return vm_error(ctx, VM_ERR_ARG, "aircraft: span %g not in [0.35, 2.5] x length", o->span);
  if (!(o->sweep_deg >= 0 && o->sweep_deg <= 50))
    return vm_error(ctx, VM_ERR_ARG, "aircraft: sweep %g not in [0, 50] degrees", o->sweep_deg);
  if (!(o->dihedral_deg >= -5 && o->dihedral_deg <= 12))
    return vm_error(ctx, VM_ERR_ARG, "aircraft: dihedral %g not in [-5, 12] degrees",
                    o->dihedral_deg);
  const int res = o->resolution;
  const double deg = AC_PI / 180;

  body bd;
  bd.L = L;
  bd.R = 0.056 * L;
  bd.kb = 1.06;
  bd.xn = 0.17 * L;
  bd.xt = 0.60 * L;
  bd.fe = 0.22;
  bd.re = 0.9 * bd.fe * bd.R;
  bd.xce = L - bd.re;
  bd.droop = 0.18;
  bd.upsweep = 0.5;

  /* base spacing: every count below follows from it or from res directly */
  const double h0 = L / (24 + 16 * res);
  const int K = 3;
  lsurf ws[NPORT];
  memset(ws, 0, sizeof ws);
  /* port order around the fuselage (increasing th): fin, right stabilizer,
   * right wing, left wing, left stabilizer */
  lsurf *fin = &ws[0], *hr = &ws[1], *wr = &ws[2], *wl = &ws[3], *hl = &ws[4];

  wr->comp = VM_AIRCRAFT_WING_RIGHT;
  wr->side = 1;
  wr->x0 = 0.37 * L;
  wr->z0 = -0.45 * bd.R;
  wr->c0 = 0.21 * L;
  wr->c1 = 0.28 * wr->c0;
  wr->t0 = 0.14;
  wr->t1 = 0.10;
  wr->m = 0.02;
  wr->pc = 0.4;
  wr->s_tip = 0.5 * o->span - 0.5 * wr->t1 * wr->c1;
  wr->s_lo = 0;
  wr->tan_sweep = tan(o->sweep_deg * deg);
  wr->tan_dihedral = tan(o->dihedral_deg * deg);
  wr->ndes = 4 + 4 * res;

  hr->comp = VM_AIRCRAFT_STAB_RIGHT;
  hr->side = 1;
  hr->x0 = 0.795 * L;
  hr->c0 = 0.125 * L;
  hr->c1 = 0.4 * hr->c0;
  {
    double xr = hr->x0 + 0.3 * hr->c0;
    hr->z0 = body_zc(&bd, xr) + 0.1 * bd.kb * bd.R * body_f(&bd, xr);
  }
  hr->t0 = 0.11;
  hr->t1 = 0.11;
  hr->s_tip = 0.17 * L - 0.5 * hr->t1 * hr->c1;
  hr->s_lo = 0;
  hr->tan_sweep = tan(33 * deg);
  hr->tan_dihedral = tan(6 * deg);
  hr->ndes = 3 + 3 * res;

  fin->comp = VM_AIRCRAFT_FIN;
  fin->vertical = 1;
  fin->side = 1;
  fin->x0 = 0.715 * L;
  fin->z0 = body_zc(&bd, fin->x0) + bd.kb * bd.R * body_f(&bd, fin->x0);
  fin->c0 = 0.19 * L;
  fin->c1 = 0.36 * fin->c0;
  fin->t0 = 0.12;
  fin->t1 = 0.12;
  fin->s_tip = 0.155 * L - 0.5 * fin->t1 * fin->c1;
  fin->s_lo = -2 * bd.kb * bd.R * body_f(&bd, fin->x0);
  fin->tan_sweep = tan(40 * deg);
  fin->ndes = hr->ndes;

  *wl = *wr;
  wl->comp = VM_AIRCRAFT_WING_LEFT;
  wl->side = -1;
  *hl = *hr;
  hl->comp = VM_AIRCRAFT_STAB_LEFT;
  hl->side = -1;

  /* resolve the nose radius (1.1019 t^2 for NACA sections) from resolution 3
   * on; below, the span stations are too far apart for such a fine first
   * chordwise station (it would make slivers along the leading edge) */
  for (int p = 0; p < NPORT; p++) {
    double t = fmin(ws[p].t0, ws[p].t1);
    ws[p].u_le = res >= 3 ? 0.5 * 1.1019 * t * t : 1;
  }

  builder B;
  memset(&B, 0, sizeof B);
  B.ctx = ctx;
  fus F;
  memset(&F, 0, sizeof F);
  F.bd = &bd;
  int rc = VM_OK;
  vm_mesh *m = NULL;
  double te[NPORT] = {0};

  /* nc points around the cabin, a little closer than the rings */
  int nc = (int)lround(AC_TWO_PI * 0.5 * (1 + bd.kb) * bd.R / (0.7 * h0));
  if (nc < 12) nc = 12;
  F.h_c = AC_TWO_PI * 0.5 * (1 + bd.kb) * bd.R / nc;
  F.h_ax = h0;
  for (int p = 0; p < NPORT; p++) {
    F.port[p] = &ws[p];
    if ((rc = ls_extent(ctx, &bd, &ws[p])) != VM_OK) goto fail;
  }
  if ((rc = make_stations(ctx, &F, L)) != VM_OK) goto fail;
  /* ports first: their root vertices are shared by the fuselage */
  for (int p = 0; p < NPORT; p++) {
    if ((rc = ls_alloc(ctx, &ws[p])) != VM_OK) goto fail;
    if ((rc = ls_port(&B, &bd, &ws[p], F.xs)) != VM_OK) goto fail;
  }

  /* span stations from the exposed span */
  for (int p = 0; p < NPORT; p++) {
    lsurf *w = &ws[p];
    double exposed = w->s_tip - w->rs[w->n];
    int J = (int)lround(exposed / (1.5 * h0));
    w->J = J < 3 ? 3 : J;
    w->K = K;
  }

  /* fuselage slots: gaps between the ports from their nominal angles */
  {
    double th_h = hr->rth[0], th_w = wr->rth[0];
    if (!(th_h > 0.2 && th_h < th_w && th_w < AC_PI - 0.2)) {
      rc = vm_error(ctx, VM_ERR_NUMERIC, "aircraft: stabilizer and wing roots out of order");
      goto fail;
    }
    int g1 = (int)lround(nc * th_h / AC_TWO_PI) - 1;
    int g2 = (int)lround(nc * (th_w - th_h) / AC_TWO_PI) - 1;
    int g3 = (int)lround(nc * (AC_TWO_PI - 2 * th_w) / AC_TWO_PI) - 1;
    g1 = g1 < 1 ? 1 : g1;
    g2 = g2 < 1 ? 1 : g2;
    g3 = g3 < 1 ? 1 : g3;
    int M = 2 * g1 + 2 * g2 + g3 + 10;
    F.M = M;
    fin->slot = M - 1;
    fin->first = -1;
    hr->slot = g1 + 1;
    hr->first = 1;
    wr->slot = g1 + g2 + 3;
    wr->first = 1;
    wl->slot = g1 + g2 + g3 + 5;
    wl->first = -1;
    hl->slot = g1 + 2 * g2 + g3 + 7;
    hl->first = -1;
    for (int p = 0; p < NPORT; p++) F.thnom[p] = ws[p].rth[0];
  }
  F.pairfirst = vm_calloc(ctx, 3 * (size_t)F.M, 1);
  if (!F.pairfirst) {
    rc = VM_ERR_NOMEM;
    goto fail;
  }
  F.join = F.pairfirst + F.M;
  F.fixed = F.pairfirst + 2 * F.M;
  for (int p = 0; p < NPORT; p++) F.pairfirst[ws[p].slot] = 1;

  /* meridian arc length table, clustered at the poles */
  F.arc.n = 4097;
  F.arc.x = vm_alloc_array(ctx, 2 * (size_t)F.arc.n, sizeof(double));
  if (!F.arc.x) {
    rc = VM_ERR_NOMEM;
    goto fail;
  }
  F.arc.s = F.arc.x + F.arc.n;
  for (int i = 0; i < F.arc.n; i++) {
    double x = 0.5 * L * (1 - cos(AC_PI * i / (F.arc.n - 1)));
    F.arc.x[i] = x;
    if (i == 0) {
      F.arc.s[i] = 0;
    } else {
      double dx = x - F.arc.x[i - 1], dr = body_rmean(&bd, x) - body_rmean(&bd, F.arc.x[i - 1]);
      F.arc.s[i] = F.arc.s[i - 1] + sqrt(dx * dx + dr * dr);
    }
  }

  if ((rc = fuselage(&B, &F)) != VM_OK) goto fail;
  for (int p = 0; p < NPORT; p++)
    if ((rc = ls_grid(&B, &ws[p], &te[p])) != VM_OK) goto fail;

  if ((rc = vm_mesh_create(ctx, &m)) != VM_OK) goto fail;
  if ((rc = vm_mesh_set_vertices(m, B.nv)) != VM_OK) goto fail;
  memcpy(m->xyz, B.xyz, (size_t)B.nv * 3 * sizeof(double));
  if ((rc = vm_mesh_set_elements(m, B.nt, 3 * B.nt)) != VM_OK) goto fail;
  for (int64_t e = 0; e < B.nt; e++) {
    m->etype[e] = VM_TRI;
    m->eoff[e + 1] = 3 * (e + 1);
  }
  memcpy(m->conn, B.tri, (size_t)B.nt * 3 * sizeof(int32_t));
  if (o->tag_components) {
    vm_field *fl;
    if ((rc = vm_mesh_add_field(m, "component", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &fl)) != VM_OK)
      goto fail;
    int32_t *d = fl->data;
    for (int64_t e = 0; e < B.nt; e++) d[e] = B.comp[e];
  }
  if (info) {
    for (int64_t e = 0; e < B.nt; e++) info->ntri[B.comp[e]]++;
    for (int p = 0; p < NPORT; p++) {
      info->te_length += te[p];
      if (ws[p].comp == VM_AIRCRAFT_WING_RIGHT || ws[p].comp == VM_AIRCRAFT_WING_LEFT)
        info->wing_te_length += te[p];
    }
  }
  *out = m;
  m = NULL;
fail:
  vm_mesh_destroy(&m);
  for (int p = 0; p < NPORT; p++) ls_free(ctx, &ws[p]);
  vm_free(ctx, F.pairfirst);
  vm_free(ctx, F.arc.x);
  vm_free(ctx, F.xs);
  vm_free(ctx, B.xyz);
  vm_free(ctx, B.tri);
  vm_free(ctx, B.comp);
  if (rc != VM_OK && info) memset(info, 0, sizeof *info);
  return rc;
}
