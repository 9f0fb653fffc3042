/* test/aircraft/test_aircraft.c: the generated aircraft is one closed,
 * 2-manifold, outward-oriented surface without degenerate or intersecting
 * triangles, with sharp trailing edges, deterministic, and round-trips. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/aircraft.h"
#include "varmesh/io.h"
#include "vmtest.h"

#define T_PI 3.14159265358979323846

typedef struct stats {
  int64_t nv, nt;
  int64_t bad_edges;     /* edges not shared by exactly two triangles */
  int64_t misoriented;   /* edges whose two triangles run the same way */
  int64_t bad_vertices;  /* unused vertices or fans that are not one cycle */
  int64_t degenerate;    /* triangles with (relative) zero area */
  int64_t intersections; /* pairs of triangles sharing at most one vertex that cross */
  double volume, area, min_angle, max_aspect, mean_aspect;
  double bb[6];
  int64_t nsharp; /* convex edges with dihedral angle above 60 degrees */
  double sharp_len, sharp_aft_len, sharp_ymin, sharp_ymax;
} stats;

static void sub(const double *a, const double *b, double *r) {
  r[0] = a[0] - b[0];
  r[1] = a[1] - b[1];
  r[2] = a[2] - b[2];
}
static void cross(const double *a, const double *b, double *r) {
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static double norm(const double *a) { return sqrt(dot(a, a)); }

static double orient(const double *a, const double *b, const double *c, const double *d) {
  double u[3], v[3], w[3], n[3];
  sub(b, a, u);
  sub(c, a, v);
  sub(d, a, w);
  cross(u, v, n);
  return dot(n, w);
}

/* 2D orientation in the coordinate plane (i, j). */
static double orient2(const double *a, const double *b, const double *c, int i, int j) {
  return (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]);
}

/* Is x inside triangle abc (all in the plane (i, j)), boundary included? */
static int inside2(const double *x, const double *a, const double *b, const double *c, int i,
                   int j) {
  double o1 = orient2(a, b, x, i, j), o2 = orient2(b, c, x, i, j), o3 = orient2(c, a, x, i, j);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

/* Do segments pq and ab cross properly in the plane (i, j)? */
static int cross2(const double *p, const double *q, const double *a, const double *b, int i,
                  int j) {
  double o1 = orient2(p, q, a, i, j), o2 = orient2(p, q, b, i, j);
  double o3 = orient2(a, b, p, i, j), o4 = orient2(a, b, q, i, j);
  return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

/* Does the segment pq meet the triangle abc (touching counts)? Points within
 * a relative 1e-9 of the plane count as on it; a segment in the plane is
 * tested in 2D. */
static int seg_tri(const double *p, const double *q, const double *a, const double *b,
                   const double *c) {
  double u[3], v[3], n[3], w[3];
  sub(b, a, u);
  sub(c, a, v);
  cross(u, v, n);
  sub(q, p, w);
  double tol = 1e-9 * norm(n) * norm(w);
  double d1 = orient(a, b, c, p), d2 = orient(a, b, c, q);
  int s1 = d1 > tol ? 1 : d1 < -tol ? -1 : 0, s2 = d2 > tol ? 1 : d2 < -tol ? -1 : 0;
  if (s1 * s2 > 0) return 0;
  /* project on the coordinate plane most parallel to the triangle */
  int ax = fabs(n[0]) > fabs(n[1]) ? (fabs(n[0]) > fabs(n[2]) ? 0 : 2)
                                   : (fabs(n[1]) > fabs(n[2]) ? 1 : 2);
  int i = (ax + 1) % 3, j = (ax + 2) % 3;
  if (s1 == 0 && s2 == 0)
    return inside2(p, a, b, c, i, j) || inside2(q, a, b, c, i, j) || cross2(p, q, a, b, i, j) ||
           cross2(p, q, b, c, i, j) || cross2(p, q, c, a, i, j);
  if (s1 == 0) return inside2(p, a, b, c, i, j);
  if (s2 == 0) return inside2(q, a, b, c, i, j);
  double e1 = orient(p, q, a, b), e2 = orient(p, q, b, c), e3 = orient(p, q, c, a);
  return (e1 >= 0 && e2 >= 0 && e3 >= 0) || (e1 <= 0 && e2 <= 0 && e3 <= 0);
}

typedef struct {
  int64_t key; /* min << 32 | max */
  int32_t t, dir, opp;
} hedge;

static int cmp_hedge(const void *a, const void *b) {
  const hedge *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->t < y->t ? -1 : x->t > y->t;
}

typedef struct {
  double lo;
  int32_t t;
} boxkey;

static int cmp_box(const void *a, const void *b) {
  const boxkey *x = a, *y = b;
  if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
  return x->t < y->t ? -1 : x->t > y->t;
}

static const double *P(const vm_mesh *m, int32_t v) { return m->xyz + 3 * (int64_t)v; }

static int64_t self_intersections(const vm_mesh *m) {
  int64_t nt = m->ne, hits = 0;
  double *bb = malloc(sizeof(double) * 6 * (size_t)nt);
  boxkey *k = malloc(sizeof *k * (size_t)nt);
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = m->conn + 3 * t;
    for (int d = 0; d < 3; d++) {
      double lo = P(m, c[0])[d], hi = lo;
      for (int j = 1; j < 3; j++) {
        double x = P(m, c[j])[d];
        lo = x < lo ? x : lo;
        hi = x > hi ? x : hi;
      }
      bb[6 * t + d] = lo;
      bb[6 * t + 3 + d] = hi;
    }
    k[t].lo = bb[6 * t];
    k[t].t = (int32_t)t;
  }
  qsort(k, (size_t)nt, sizeof *k, cmp_box);
  for (int64_t i = 0; i < nt; i++) {
    int32_t a = k[i].t;
    const int32_t *ca = m->conn + 3 * (int64_t)a;
    for (int64_t j = i + 1; j < nt && k[j].lo <= bb[6 * a + 3]; j++) {
      int32_t b = k[j].t;
      const int32_t *cb = m->conn + 3 * (int64_t)b;
      if (bb[6 * b + 1] > bb[6 * a + 4] || bb[6 * a + 1] > bb[6 * b + 4] ||
          bb[6 * b + 2] > bb[6 * a + 5] || bb[6 * a + 2] > bb[6 * b + 5])
        continue;
      int shared = 0, sa = -1, sb = -1;
      for (int x = 0; x < 3; x++)
        for (int y = 0; y < 3; y++)
          if (ca[x] == cb[y]) {
            shared++;
            sa = x;
            sb = y;
          }
      int hit = 0;
      if (shared == 0) {
        for (int e = 0; e < 3 && !hit; e++) {
          hit |= seg_tri(P(m, ca[e]), P(m, ca[(e + 1) % 3]), P(m, cb[0]), P(m, cb[1]), P(m, cb[2]));
          hit |= seg_tri(P(m, cb[e]), P(m, cb[(e + 1) % 3]), P(m, ca[0]), P(m, ca[1]), P(m, ca[2]));
        }
      } else if (shared == 1) { /* the edges opposite the shared vertex */
        hit = seg_tri(P(m, ca[(sa + 1) % 3]), P(m, ca[(sa + 2) % 3]), P(m, cb[0]), P(m, cb[1]),
                      P(m, cb[2])) ||
              seg_tri(P(m, cb[(sb + 1) % 3]), P(m, cb[(sb + 2) % 3]), P(m, ca[0]), P(m, ca[1]),
                      P(m, ca[2]));
      }
      if (hit) {
        if (hits < 5) fprintf(stderr, "  triangles %d and %d intersect\n", a, b);
        hits++;
      }
    }
  }
  free(bb);
  free(k);
  return hits;
}

static void analyze(const vm_mesh *m, stats *s) {
  memset(s, 0, sizeof *s);
  int64_t nt = m->ne, nv = m->nv;
  s->nv = nv;
  s->nt = nt;
  s->min_angle = 180;
  for (int d = 0; d < 3; d++) {
    s->bb[d] = HUGE_VAL;
    s->bb[3 + d] = -HUGE_VAL;
  }
  for (int64_t v = 0; v < nv; v++)
    for (int d = 0; d < 3; d++) {
      double x = m->xyz[3 * v + d];
      s->bb[d] = x < s->bb[d] ? x : s->bb[d];
      s->bb[3 + d] = x > s->bb[3 + d] ? x : s->bb[3 + d];
    }
  double diag =
      sqrt(pow(s->bb[3] - s->bb[0], 2) + pow(s->bb[4] - s->bb[1], 2) + pow(s->bb[5] - s->bb[2], 2));
  /* per-triangle measures */
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *c = m->conn + 3 * t;
    const double *a = P(m, c[0]), *b = P(m, c[1]), *q = P(m, c[2]);
    double u[3], v[3], n[3], l[3];
    sub(b, a, u);
    sub(q, a, v);
    cross(u, v, n);
    double ar = 0.5 * norm(n);
    s->area += ar;
    cross(b, q, n);
    s->volume += dot(a, n) / 6;
    const double *pp[3] = {a, b, q};
    for (int e = 0; e < 3; e++) {
      double w[3];
      sub(pp[(e + 1) % 3], pp[e], w);
      l[e] = norm(w);
    }
    if (ar <= 1e-14 * diag * diag) s->degenerate++;
    for (int e = 0; e < 3; e++) { /* angle at corner e, opposite edge (e+1) */
      double w1[3], w2[3];
      sub(pp[(e + 1) % 3], pp[e], w1);
      sub(pp[(e + 2) % 3], pp[e], w2);
      double ang = atan2(2 * ar, dot(w1, w2)) * 180 / T_PI;
      if (ang < s->min_angle) s->min_angle = ang;
    }
    double lmax = fmax(l[0], fmax(l[1], l[2]));
    double asp = ar > 0 ? lmax * (l[0] + l[1] + l[2]) / (4 * sqrt(3.0) * ar) : HUGE_VAL;
    s->mean_aspect += asp / nt;
    if (asp > s->max_aspect) s->max_aspect = asp;
  }
  /* edges: each shared by exactly two triangles running opposite ways */
  hedge *h = malloc(sizeof *h * 3 * (size_t)nt);
  for (int64_t t = 0; t < nt; t++)
    for (int e = 0; e < 3; e++) {
      int32_t a = m->conn[3 * t + e], b = m->conn[3 * t + (e + 1) % 3];
      hedge *x = &h[3 * t + e];
      x->key = a < b ? (int64_t)a << 32 | b : (int64_t)b << 32 | a;
      x->t = (int32_t)t;
      x->dir = a < b;
      x->opp = m->conn[3 * t + (e + 2) % 3];
    }
  qsort(h, 3 * (size_t)nt, sizeof *h, cmp_hedge);
  for (int64_t i = 0; i < 3 * nt;) {
    int64_t j = i;
    while (j < 3 * nt && h[j].key == h[i].key) j++;
    if (j - i != 2) {
      s->bad_edges++;
    } else if (h[i].dir == h[i + 1].dir) {
      s->misoriented++;
    } else {
      /* dihedral angle; t1 is the triangle running a -> b */
      const hedge *h1 = h[i].dir ? &h[i] : &h[i + 1], *h2 = h[i].dir ? &h[i + 1] : &h[i];
      int32_t a = (int32_t)(h[i].key >> 32), b = (int32_t)(h[i].key & 0xffffffff);
      double n1[3], n2[3], u[3], v[3], w[3];
      const int32_t *c1 = m->conn + 3 * (int64_t)h1->t, *c2 = m->conn + 3 * (int64_t)h2->t;
      sub(P(m, c1[1]), P(m, c1[0]), u);
      sub(P(m, c1[2]), P(m, c1[0]), v);
      cross(u, v, n1);
      sub(P(m, c2[1]), P(m, c2[0]), u);
      sub(P(m, c2[2]), P(m, c2[0]), v);
      cross(u, v, n2);
      double l1 = norm(n1), l2 = norm(n2);
      if (l1 > 0 && l2 > 0) {
        double cs = dot(n1, n2) / (l1 * l2);
        sub(P(m, h2->opp), P(m, a), w);
        if (cs < 0.5 && dot(n1, w) < 0) {
          sub(P(m, b), P(m, a), u);
          double len = norm(u), bis = n1[0] / l1 + n2[0] / l2;
          s->nsharp++;
          s->sharp_len += len;
          if (bis > 0) s->sharp_aft_len += len;
          double ymin = fmin(P(m, a)[1], P(m, b)[1]), ymax = fmax(P(m, a)[1], P(m, b)[1]);
          if (s->nsharp == 1 || ymin < s->sharp_ymin) s->sharp_ymin = ymin;
          if (s->nsharp == 1 || ymax > s->sharp_ymax) s->sharp_ymax = ymax;
        }
      }
    }
    i = j;
  }
  free(h);
  /* vertices: the link of every vertex is a single cycle */
  int64_t *start = calloc((size_t)nv + 1, sizeof *start);
  int32_t *lsrc = malloc(sizeof *lsrc * 3 * (size_t)nt),
          *ldst = malloc(sizeof *ldst * 3 * (size_t)nt);
  for (int64_t k = 0; k < 3 * nt; k++) start[m->conn[k] + 1]++;
  for (int64_t v = 0; v < nv; v++) start[v + 1] += start[v];
  int64_t *fill = malloc(sizeof *fill * (size_t)nv);
  memcpy(fill, start, sizeof *fill * (size_t)nv);
  for (int64_t t = 0; t < nt; t++)
    for (int e = 0; e < 3; e++) {
      int32_t v = m->conn[3 * t + e];
      int64_t k = fill[v]++;
      lsrc[k] = m->conn[3 * t + (e + 1) % 3];
      ldst[k] = m->conn[3 * t + (e + 2) % 3];
    }
  for (int64_t v = 0; v < nv; v++) {
    int64_t b = start[v], deg = start[v + 1] - b;
    if (deg < 3) {
      s->bad_vertices++;
      continue;
    }
    int32_t cur = lsrc[b];
    int64_t steps = 0;
    do {
      int64_t k, found = 0;
      for (k = b; k < b + deg; k++)
        if (lsrc[k] == cur) found++;
      if (found != 1) break;
      for (k = b; lsrc[k] != cur; k++) {
      }
      cur = ldst[k];
      steps++;
    } while (cur != lsrc[b] && steps <= deg);
    if (steps != deg || cur != lsrc[b]) s->bad_vertices++;
  }
  free(start);
  free(lsrc);
  free(ldst);
  free(fill);
  s->intersections = self_intersections(m);
}

static void print_stats(const char *what, const stats *s) {
  fprintf(stderr,
          "%s: %lld triangles, %lld vertices, bbox [%.4g %.4g] x [%.4g %.4g] x [%.4g %.4g]\n"
          "  volume %.6g, area %.6g, min angle %.3g deg, aspect max %.3g mean %.3g\n"
          "  sharp convex edges %lld, length %.5g (aft-facing %.5g), y in [%.4g, %.4g]\n",
          what, (long long)s->nt, (long long)s->nv, s->bb[0], s->bb[3], s->bb[1], s->bb[4],
          s->bb[2], s->bb[5], s->volume, s->area, s->min_angle, s->max_aspect, s->mean_aspect,
          (long long)s->nsharp, s->sharp_len, s->sharp_aft_len, s->sharp_ymin, s->sharp_ymax);
}

static void check_model(vm_ctx *ctx, const vm_aircraft_opts *o, const char *what) {
  vm_mesh *m = NULL;
  vm_aircraft_info info;
  int rc = vm_gen_aircraft_info(ctx, o, &m, &info);
  CHECK(rc == VM_OK && m, "%s: generate: %d %s", what, rc, vm_ctx_error(ctx));
  if (!m) return;
  CHECK(vm_mesh_check(m) == VM_OK, "%s: mesh_check: %s", what, vm_ctx_error(ctx));
  int64_t counts[VM_NTYPES];
  vm_mesh_count_types(m, counts);
  CHECK(m->dim == 3 && counts[VM_TRI] == m->ne, "%s: not all triangles", what);
  int64_t sum = 0;
  for (int c = 0; c < VM_AIRCRAFT_NCOMP; c++) {
    CHECK(info.ntri[c] > 0, "%s: component %d empty", what, c);
    sum += info.ntri[c];
  }
  CHECK(sum == m->ne, "%s: component counts %lld vs %lld", what, (long long)sum, (long long)m->ne);
  stats s;
  analyze(m, &s);
  print_stats(what, &s);
  fprintf(stderr,
          "  trailing edges by construction %.5g (wings %.5g); per component:", info.te_length,
          info.wing_te_length);
  for (int c = 0; c < VM_AIRCRAFT_NCOMP; c++) fprintf(stderr, " %lld", (long long)info.ntri[c]);
  fputc('\n', stderr);
  double L = o->length;
  CHECK(s.bad_edges == 0, "%s: %lld edges not shared by two triangles", what,
        (long long)s.bad_edges);
  CHECK(s.misoriented == 0, "%s: %lld inconsistently oriented edges", what,
        (long long)s.misoriented);
  CHECK(s.bad_vertices == 0, "%s: %lld non-manifold or unused vertices", what,
        (long long)s.bad_vertices);
  CHECK(s.degenerate == 0, "%s: %lld degenerate triangles", what, (long long)s.degenerate);
  CHECK(s.intersections == 0, "%s: %lld intersecting triangle pairs", what,
        (long long)s.intersections);
  CHECK(s.volume > 0, "%s: volume %g not positive", what, s.volume);
  CHECK(s.min_angle > 1.0, "%s: min angle %g", what, s.min_angle);
  /* bounding box: nose at 0, tail tip at L, wing tips at +-span/2 */
  CHECK_NEAR(s.bb[0], 0, 1e-9 * L, "x min");
  /* a long, strongly swept wing may reach aft of the tail tip */
  CHECK(s.bb[3] >= L * (1 - 1e-9) && s.bb[3] < 1.6 * L, "%s: x max %g", what, s.bb[3]);
  if (o->span <= 0.9 * L && o->sweep_deg <= 30) CHECK_NEAR(s.bb[3], L, 1e-9 * L, "x max");
  CHECK_NEAR(s.bb[1], -0.5 * o->span, 1e-3 * L, "y min");
  CHECK_NEAR(s.bb[4], 0.5 * o->span, 1e-3 * L, "y max");
  CHECK(s.bb[5] - s.bb[2] > 0.15 * L && s.bb[5] - s.bb[2] < 0.35 * L, "%s: height %g", what,
        s.bb[5] - s.bb[2]);
  /* plausible size: a cylinder of the fuselage's size is a lower bound */
  CHECK(s.volume > 0.5 * T_PI * pow(0.05 * L, 2) * L && s.volume < 0.05 * L * L * L,
        "%s: volume %g implausible", what, s.volume);
  /* sharp trailing edges: present, about as long as built, reaching the wing
   * tips; from resolution 3 on the leading edges are resolved, so the
   * trailing edges are the only sharp edges, else the aft-facing ones */
  CHECK(s.nsharp >= 5, "%s: only %lld sharp edges", what, (long long)s.nsharp);
  CHECK(fabs(s.sharp_aft_len - info.te_length) < 0.1 * info.te_length,
        "%s: aft-facing sharp edges %g long, trailing edges %g", what, s.sharp_aft_len,
        info.te_length);
  if (o->resolution >= 3)
    CHECK(s.sharp_len < 1.02 * s.sharp_aft_len, "%s: %g of %g sharp length does not face aft", what,
          s.sharp_len - s.sharp_aft_len, s.sharp_len);
  CHECK(info.wing_te_length > 2 * (0.5 * o->span - 0.06 * L),
        "%s: wing trailing edges %g too short", what, info.wing_te_length);
  CHECK(s.sharp_ymax > 0.45 * o->span && s.sharp_ymin < -0.45 * o->span,
        "%s: sharp edges span y [%g, %g]", what, s.sharp_ymin, s.sharp_ymax);
  vm_mesh_destroy(&m);
}

static void check_determinism(vm_ctx *ctx) {
  vm_aircraft_opts o = vm_aircraft_opts_default();
  o.resolution = 2;
  vm_mesh *a = NULL, *b = NULL;
  vm_gen_aircraft(ctx, &o, &a);
  vm_gen_aircraft(ctx, &o, &b);
  CHECK(a && b && a->nv == b->nv && a->ne == b->ne, "determinism: sizes");
  if (a && b && a->nv == b->nv && a->ne == b->ne) {
    CHECK(!memcmp(a->xyz, b->xyz, sizeof(double) * 3 * (size_t)a->nv), "determinism: xyz");
    CHECK(!memcmp(a->conn, b->conn, sizeof(int32_t) * 3 * (size_t)a->ne), "determinism: conn");
  }
  vm_mesh_destroy(&a);
  vm_mesh_destroy(&b);
}

static void check_roundtrip(vm_ctx *ctx) {
  vm_aircraft_opts o = vm_aircraft_opts_default();
  o.resolution = 1;
  o.tag_components = 1;
  vm_mesh *m = NULL, *r = NULL;
  vm_aircraft_info info;
  CHECK(vm_gen_aircraft_info(ctx, &o, &m, &info) == VM_OK, "roundtrip: generate");
  if (!m) return;
  char path[64];
  /* .vmsh keeps everything, including the component field */
  snprintf(path, sizeof path, "test_aircraft_%ld.vmsh", (long)getpid());
  CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) == VM_OK, "write vmsh: %s",
        vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &r) == VM_OK, "read vmsh: %s", vm_ctx_error(ctx));
  if (r) {
    CHECK(r->nv == m->nv && r->ne == m->ne && r->dim == 3, "vmsh: sizes");
    if (r->nv == m->nv && r->ne == m->ne) {
      CHECK(!memcmp(r->xyz, m->xyz, sizeof(double) * 3 * (size_t)m->nv), "vmsh: xyz");
      CHECK(!memcmp(r->conn, m->conn, sizeof(int32_t) * 3 * (size_t)m->ne), "vmsh: conn");
    }
    vm_field *f = vm_mesh_find_field(r, "component", VM_FIELD_ELEMENT);
    CHECK(f && f->type == VM_FIELD_I32 && f->ncomp == 1, "vmsh: component field");
    if (f && f->type == VM_FIELD_I32) {
      const int32_t *d = f->data;
      int64_t cnt[VM_AIRCRAFT_NCOMP] = {0}, bad = 0;
      for (int64_t e = 0; e < r->ne; e++) {
        if (d[e] >= 0 && d[e] < VM_AIRCRAFT_NCOMP)
          cnt[d[e]]++;
        else
          bad++;
      }
      CHECK(bad == 0, "vmsh: %lld component values out of range", (long long)bad);
      for (int c = 0; c < VM_AIRCRAFT_NCOMP; c++)
        CHECK(cnt[c] == info.ntri[c], "vmsh: component %d has %lld triangles, info %lld", c,
              (long long)cnt[c], (long long)info.ntri[c]);
    }
  }
  vm_mesh_destroy(&r);
  unlink(path);
  /* STL through the surface formats: same triangles (vertices merged by
   * coordinates, so all of them must be distinct points) */
  o.tag_components = 0;
  vm_mesh_destroy(&m);
  vm_gen_aircraft(ctx, &o, &m);
  snprintf(path, sizeof path, "test_aircraft_%ld.stl", (long)getpid());
  CHECK(vm_mesh_write(ctx, m, path, VM_FMT_AUTO, NULL) == VM_OK, "write stl: %s",
        vm_ctx_error(ctx));
  CHECK(vm_mesh_read(ctx, path, VM_FMT_AUTO, &r) == VM_OK, "read stl: %s", vm_ctx_error(ctx));
  if (r) {
    CHECK(r->nv == m->nv && r->ne == m->ne, "stl: %lld/%lld vertices, %lld/%lld triangles",
          (long long)r->nv, (long long)m->nv, (long long)r->ne, (long long)m->ne);
    stats a, b;
    analyze(m, &a);
    analyze(r, &b);
    CHECK(b.bad_edges == 0 && b.misoriented == 0 && b.bad_vertices == 0, "stl: topology");
    CHECK_NEAR(b.volume, a.volume, 1e-12 * a.volume, "stl: volume");
  }
  vm_mesh_destroy(&r);
  vm_mesh_destroy(&m);
  unlink(path);
}

static void check_errors(vm_ctx *ctx) {
  vm_aircraft_opts o = vm_aircraft_opts_default();
  vm_mesh *m = (vm_mesh *)&o;
  o.resolution = 0;
  CHECK(vm_gen_aircraft(ctx, &o, &m) == VM_ERR_ARG && !m, "resolution 0");
  o = vm_aircraft_opts_default();
  o.span = 3 * o.length;
  CHECK(vm_gen_aircraft(ctx, &o, &m) == VM_ERR_ARG, "span too large");
  o = vm_aircraft_opts_default();
  o.length = NAN;
  CHECK(vm_gen_aircraft(ctx, &o, &m) == VM_ERR_ARG, "NaN length");
  o = vm_aircraft_opts_default();
  o.sweep_deg = 60;
  CHECK(vm_gen_aircraft(ctx, &o, &m) == VM_ERR_ARG, "sweep 60");
  CHECK(vm_gen_aircraft(ctx, NULL, &m) == VM_ERR_ARG, "NULL options");
  /* every allocation failure is reported and leaks nothing */
  o = vm_aircraft_opts_default();
  o.resolution = 1;
  o.tag_components = 1;
  long live = vm_ctx_alloc_live(ctx);
  int n, rc = VM_ERR_NOMEM, bad = 0;
  for (n = 1; n < 10000 && rc == VM_ERR_NOMEM; n++) {
    vm_ctx_set_alloc_fail(ctx, n);
    m = NULL;
    rc = vm_gen_aircraft(ctx, &o, &m);
    vm_ctx_set_alloc_fail(ctx, 0);
    if (rc == VM_ERR_NOMEM && (m || vm_ctx_alloc_live(ctx) != live)) bad++;
    vm_mesh_destroy(&m);
  }
  CHECK(rc == VM_OK && bad == 0, "allocation failures: rc %d after %d, %d leaking", rc, n, bad);
  CHECK(vm_ctx_alloc_live(ctx) == live, "leak after allocation-failure loop");
}

int main(void) {
  vm_ctx *ctx;
  if (vm_ctx_create(&ctx) != VM_OK) return 1;
  vm_aircraft_opts o = vm_aircraft_opts_default();
  for (int r = 1; r <= 2; r++) {
    char what[64];
    o.resolution = r;
    snprintf(what, sizeof what, "resolution %d", r);
    check_model(ctx, &o, what);
  }
  o = vm_aircraft_opts_default();
  check_model(ctx, &o, "default (resolution 4)");
  /* other planforms */
  o.resolution = 2;
  o.span = 0.4 * o.length;
  o.sweep_deg = 0;
  o.dihedral_deg = -3;
  check_model(ctx, &o, "short straight wing");
  o.span = 2.2 * o.length;
  o.sweep_deg = 45;
  o.dihedral_deg = 8;
  o.length = 3;
  o.span = 2.2 * o.length;
  check_model(ctx, &o, "long swept wing, length 3");
  check_determinism(ctx);
  check_roundtrip(ctx);
  check_errors(ctx);
  vm_ctx_destroy(&ctx);
  return vmtest_end("aircraft");
}
