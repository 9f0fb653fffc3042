/* prism/src/intersect.c: intersecting triangle pairs: every edge of the
 * triangle soup is cast as an Embree ray against a user geometry holding
 * the triangles in double precision; each candidate on the ray's path is
 * decided by sign tests in double; hits are collected, then sorted, so the
 * result never depends on thread timing. */
#include "intersect.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom.h"
#include "varmesh/prism.h"
#include "varmesh/topology.h"

struct pr_rt {
  vm_ctx *ctx;
  RTCDevice dev;
  /* the first error Embree reported since the last query looked (written
   * under a critical section: the callback may run on any thread) */
  int failed;
  enum RTCError code;
  char msg[256];
};

static void rt_error(void *user, enum RTCError code, const char *str) {
  pr_rt *rt = user;
#pragma omp critical(vm_prism_embree_error)
  if (!rt->failed) {
    rt->failed = 1;
    rt->code = code;
    snprintf(rt->msg, sizeof rt->msg, "%s", str ? str : "");
  }
}

int pr_rt_create(vm_ctx *ctx, pr_rt **out) {
  *out = NULL;
  pr_rt *rt = vm_calloc(ctx, 1, sizeof *rt);
  if (!rt) return VM_ERR_NOMEM;
  rt->dev = rtcNewDevice(NULL);
  if (!rt->dev) {
    enum RTCError code = rtcGetDeviceError(NULL);
    vm_free(ctx, rt);
    return vm_error(ctx, VM_ERR_BACKEND, "embree: cannot create a device (error %d)", (int)code);
  }
  rtcSetDeviceErrorFunction(rt->dev, rt_error, rt);
  rt->ctx = ctx;
  *out = rt;
  return VM_OK;
}

void pr_rt_destroy(pr_rt **prt) {
  if (!prt || !*prt) return;
  pr_rt *rt = *prt;
  rtcReleaseDevice(rt->dev);
  vm_free(rt->ctx, rt);
  *prt = NULL;
}

/* The device's error since the last look, copied to the context (VM_OK if
 * none); `code` is what rtcGetDeviceError returned. */
static int rt_status(vm_ctx *ctx, pr_rt *rt, enum RTCError code, const char *what);

int pr_rt_check(vm_ctx *ctx, pr_rt *rt, const char *what) {
  return rt_status(ctx, rt, rtcGetDeviceError(rt->dev), what);
}

static int rt_status(vm_ctx *ctx, pr_rt *rt, enum RTCError code, const char *what) {
  if (!rt->failed && code == RTC_ERROR_NONE) return VM_OK;
  int st;
  if (rt->failed)
    st = vm_error(ctx, VM_ERR_BACKEND, "embree: %s failed (error %d: %s)", what, (int)rt->code,
                  rt->msg);
  else
    st = vm_error(ctx, VM_ERR_BACKEND, "embree: %s failed (error %d)", what, (int)code);
  rt->failed = 0;
  return st;
}

typedef struct {
  float *box; /* first (pr_tri_scene): 6 per primitive, rounded outwards and padded */
  const double *xyz;
  const int32_t *tri;
  const int32_t *group;
  double orient_tol_sq;
  int64_t ntri;
  const int32_t *map; /* primitive -> triangle (NULL: the identity) */
} soup;

static void box_bounds(const struct RTCBoundsFunctionArguments *a) {
  /* the user data's first member is its box array (pr_tri_scene) */
  const float *const *box = a->geometryUserPtr;
  const float *b = *box + 6 * (size_t)a->primID;
  a->bounds_o->lower_x = b[0];
  a->bounds_o->lower_y = b[1];
  a->bounds_o->lower_z = b[2];
  a->bounds_o->upper_x = b[3];
  a->bounds_o->upper_y = b[4];
  a->bounds_o->upper_z = b[5];
}

/* The boxes of primitives 0..nprim-1 (triangle prims[q], or q), rounded
 * outwards to float and padded by pad: 6 floats each in box. */
static void tri_boxes(const double *xyz, const int32_t *tri, const int32_t *prims, int64_t nprim,
                      double pad, float *box) {
#pragma omp parallel for schedule(static)
  for (int64_t q = 0; q < nprim; q++) {
    int64_t t = prims ? prims[q] : q;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) {
        double v = xyz[3 * (int64_t)tri[3 * t + i] + k];
        lo[k] = v < lo[k] ? v : lo[k];
        hi[k] = v > hi[k] ? v : hi[k];
      }
    for (int k = 0; k < 3; k++) {
      box[6 * q + k] = pr_float_down(lo[k] - pad);
      box[6 * q + 3 + k] = pr_float_up(hi[k] + pad);
    }
  }
}

/* A committed scene of one user geometry over nprim boxes (box_bounds
 * reads them from data's first member). refit != 0: a scene whose tree
 * is refitted, not rebuilt, when its geometry is committed again (*geom:
 * the geometry, held by the scene). */
static RTCScene user_scene(RTCDevice dev, int64_t nprim, void *data, RTCIntersectFunctionN isect,
                           RTCOccludedFunctionN occl, int refit, RTCGeometry *geom) {
  RTCScene scene = rtcNewScene(dev);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST | (refit ? RTC_SCENE_FLAG_DYNAMIC : 0));
  rtcSetSceneBuildQuality(scene, refit ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
  if (refit) rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
  rtcSetGeometryUserPrimitiveCount(g, (unsigned int)nprim);
  rtcSetGeometryUserData(g, data);
  rtcSetGeometryBoundsFunction(g, box_bounds, NULL);
  if (isect) rtcSetGeometryIntersectFunction(g, isect);
  if (occl) rtcSetGeometryOccludedFunction(g, occl);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(scene);
  if (geom) *geom = g;
  return scene;
}

RTCScene pr_tri_scene(pr_rt *rt, const double *xyz, const int32_t *tri, const int32_t *prims,
                      int64_t nprim, double pad, float *box, void *data,
                      RTCIntersectFunctionN isect, RTCOccludedFunctionN occl) {
  tri_boxes(xyz, tri, prims, nprim, pad, box);
  return user_scene(rt->dev, nprim, data, isect, occl, 0, NULL);
}

/* orient(a, b, c, d) = (a - d) . ((b - d) x (c - d)), with a tolerance
 * relative to the lengths involved: 0 when the four points are coplanar
 * within rounding. */
static int orient(const double *a, const double *b, const double *c, const double *d,
                  double tol_sq) {
  double u[3], v[3], w[3], x[3];
  for (int k = 0; k < 3; k++) {
    u[k] = a[k] - d[k];
    v[k] = b[k] - d[k];
    w[k] = c[k] - d[k];
  }
  vm_cross3(v, w, x);
  double o = vm_dot3(u, x);
  /* |o| <= tol |u| |v| |w|, squared: no square roots on this hot path */
  double s2 = vm_dot3(u, u) * vm_dot3(v, v) * vm_dot3(w, w);
  if (o * o <= tol_sq * s2) return 0;
  return o > 0 ? 1 : -1;
}

/* Does segment pq cross the interior of triangle abc (strictly)? */
static int seg_tri(const double *p, const double *q, const double *a, const double *b,
                   const double *c, double tol_sq) {
  int o1 = orient(a, b, c, p, tol_sq), o2 = orient(a, b, c, q, tol_sq);
  if (o1 == 0 || o2 == 0 || o1 == o2) return 0;
  int s1 = orient(p, q, a, b, tol_sq), s2 = orient(p, q, b, c, tol_sq),
      s3 = orient(p, q, c, a, tol_sq);
  return s1 != 0 && s1 == s2 && s2 == s3;
}

/* One edge of the soup, cast as a ray; hits are triangles its segment
 * crosses, collected in a growing list (plain malloc: these run on many
 * threads, and the context's allocator is not thread-safe). */
typedef struct {
  struct RTCIntersectContext rtc; /* first: Embree passes a pointer to it */
  const soup *d;
  int32_t a, b;  /* the edge's vertices */
  int32_t group; /* group of the edge (-1: none) */
  int64_t n, cap;
  int32_t *hit;
  int nomem;
} edge_ray;

static void push_hit(edge_ray *r, int32_t t) {
  if (r->n == r->cap) {
    int64_t nc = r->cap ? 2 * r->cap : 16;
    int32_t *np = realloc(r->hit, (size_t)nc * sizeof *np);
    if (!np) {
      r->nomem = 1;
      return;
    }
    r->hit = np;
    r->cap = nc;
  }
  r->hit[r->n++] = t;
}

static void edge_intersect(const struct RTCIntersectFunctionNArguments *args) {
  if (!args->valid[0]) return;
  edge_ray *r = (edge_ray *)args->context;
  const soup *d = r->d;
  int32_t t = d->map ? d->map[args->primID] : (int32_t)args->primID;
  const int32_t *T = d->tri + 3 * (int64_t)t;
  if (T[0] == r->a || T[1] == r->a || T[2] == r->a || T[0] == r->b || T[1] == r->b || T[2] == r->b)
    return; /* touching at a shared vertex only, unless coplanar */
  if (r->group >= 0 && d->group && d->group[t] == r->group) return;
  const double *x = d->xyz;
  if (seg_tri(x + 3 * (int64_t)r->a, x + 3 * (int64_t)r->b, x + 3 * (int64_t)T[0],
              x + 3 * (int64_t)T[1], x + 3 * (int64_t)T[2], d->orient_tol_sq))
    push_hit(r, t);
  /* the hit is never committed, so traversal visits every candidate */
}

static void edge_occluded(const struct RTCOccludedFunctionNArguments *args) { (void)args; }

typedef struct {
  int32_t a, b, t;
} half_edge;

struct pr_soup {
  pr_rt *rt; /* borrowed */
  pr_isect_params k;
  int64_t ntri, ned;
  int32_t *tri;   /* 3 per triangle */
  int32_t *group; /* NULL or 1 per triangle */
  half_edge *he;  /* half-edges sorted by (a, b, t) */
  int64_t *eb;    /* edge k: he[eb[k] .. eb[k+1]) */
  int64_t nv;     /* 1 + the largest vertex index */
  /* the last query of pr_soup_intersections_cached: its coordinates and
   * its pairs (cached = 0: none yet) */
  int cached, check; /* check: compare each incremental answer with a full query */
  double *last_xyz;
  int64_t nlast, *last_pairs;
  /* the scene of all triangles, kept between queries: rebuilt by a full
   * query, refitted (boxes recomputed, the tree's shape kept) by an
   * incremental one. The incremental query's fixed cost was this scene's
   * build: 0.27 s of a 0.3 s query on 355 k faces with 54 of them moved
   * (the aircraft at resolution 8), and restoring makes about 40 such
   * queries. spad: the padding its boxes were made with. */
  RTCScene scene;
  RTCGeometry geom;
  double spad;
  soup sd;
};

static int cmp_he(const void *x, const void *y) {
  const half_edge *a = x, *b = y;
  if (a->a != b->a) return a->a < b->a ? -1 : 1;
  if (a->b != b->b) return a->b < b->b ? -1 : 1;
  return (a->t > b->t) - (a->t < b->t);
}

static int cmp_pair(const void *a, const void *b) {
  const int64_t *x = a, *y = b;
  if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
  return (x[1] > y[1]) - (x[1] < y[1]);
}

/* (edge, triangle) hits: every edge of the soup in `edges` (NULL: all
 * ned) cast against the triangles in `prims` (NULL: all ntri), appended to
 * the list *found_out of 2 * *nfound_out values (malloc'd; NULL, 0 to
 * start one). On an error the list is freed and emptied. */
static int collect_hits(vm_ctx *ctx, pr_soup *so, const double *xyz, const int32_t *prims,
                        int64_t nprim, const int64_t *edges, int64_t nedge, int rebuild,
                        int64_t **found_out, int64_t *nfound_out) {
  const int32_t *tri = so->tri, *group = so->group;
  const half_edge *he = so->he;
  const int64_t *eb = so->eb;
  if (!prims) nprim = so->ntri;
  if (!edges) nedge = so->ned;
  if (nprim < 1 || nedge < 1) return VM_OK;
  soup local = {NULL, xyz, tri, group, so->k.orient_tol_sq, so->ntri, prims};
  double glo[3] = {INFINITY, INFINITY, INFINITY}, ghi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int64_t t = 0; t < 3 * so->ntri; t++)
    for (int k = 0; k < 3; k++) {
      double v = xyz[3 * (int64_t)tri[t] + k];
      glo[k] = v < glo[k] ? v : glo[k];
      ghi[k] = v > ghi[k] ? v : ghi[k];
    }
  /* padding covers the rounding of the rays to float */
  double pad = so->k.box_pad * (ghi[0] - glo[0] + ghi[1] - glo[1] + ghi[2] - glo[2]);
  RTCDevice dev = so->rt->dev;
  const int chunk = so->k.ray_chunk;
  const double extend = so->k.ray_extend;
  RTCScene scene;
  soup *dp = &local;
  if (prims) {
    local.box = vm_alloc_array(ctx, (size_t)nprim * 6, sizeof *local.box);
    if (!local.box) return VM_ERR_NOMEM;
    scene = pr_tri_scene(so->rt, xyz, tri, prims, nprim, pad, local.box, &local, edge_intersect,
                         edge_occluded);
  } else {
    /* all triangles: the soup's own scene, refitted where it may be (the
     * boxes any padding at least the one asked for: the candidates are a
     * superset, the exact tests decide, so the hits are the same) */
    dp = &so->sd;
    if (!dp->box && !(dp->box = vm_alloc_array(ctx, (size_t)nprim * 6, sizeof *dp->box)))
      return VM_ERR_NOMEM;
    dp->xyz = xyz;
    dp->tri = tri;
    dp->group = group;
    dp->orient_tol_sq = so->k.orient_tol_sq;
    dp->ntri = so->ntri;
    dp->map = NULL;
    if (so->scene && !rebuild && pad <= so->spad) {
      tri_boxes(xyz, tri, NULL, nprim, so->spad, dp->box);
      rtcCommitGeometry(so->geom);
      rtcCommitScene(so->scene);
    } else {
      if (so->scene) rtcReleaseScene(so->scene);
      so->spad = 2 * pad;
      tri_boxes(xyz, tri, NULL, nprim, so->spad, dp->box);
      so->scene = user_scene(dev, nprim, dp, edge_intersect, edge_occluded, 1, &so->geom);
    }
    scene = so->scene;
    pad = so->spad;
  }
  enum RTCError err = rtcGetDeviceError(dev);
  /* (edge, triangle) hits, appended by the threads in any order (the
   * pairs made of them are sorted) */
  int64_t nfound = *nfound_out, capfound = nfound;
  int64_t *found = *found_out;
  int nomem = 0;
  if (err == RTC_ERROR_NONE) {
#pragma omp parallel
    {
      edge_ray r;
      memset(&r, 0, sizeof r);
      r.d = dp;
      int64_t ln = 0, lcap = 0;
      int64_t *loc = NULL;
#pragma omp for schedule(dynamic, chunk)
      for (int64_t q = 0; q < nedge; q++) {
        int64_t e = edges ? edges[q] : q;
        int32_t a = he[eb[e]].a, b = he[eb[e]].b;
        const double *pa = xyz + 3 * (int64_t)a, *pb = xyz + 3 * (int64_t)b;
        double dir[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        double len = vm_normalize3(dir);
        if (!(len > 0)) continue;
        /* an edge whose triangles are all of one group tests only others */
        r.group = -1;
        if (group) {
          int32_t g0 = group[he[eb[e]].t];
          int same = g0 >= 0;
          for (int64_t k = eb[e]; k < eb[e + 1] && same; k++) same = group[he[k].t] == g0;
          if (same) r.group = g0;
        }
        r.a = a;
        r.b = b;
        r.n = 0;
        rtcInitIntersectContext(&r.rtc);
        struct RTCRayHit rh;
        memset(&rh, 0, sizeof rh);
        rh.ray.org_x = (float)pa[0];
        rh.ray.org_y = (float)pa[1];
        rh.ray.org_z = (float)pa[2];
        rh.ray.dir_x = (float)dir[0];
        rh.ray.dir_y = (float)dir[1];
        rh.ray.dir_z = (float)dir[2];
        rh.ray.tnear = 0;
        rh.ray.tfar = (float)(len * (1 + extend) + 2 * pad);
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &r.rtc, &rh);
        for (int64_t k = 0; k < r.n; k++) {
          if (ln == lcap) {
            int64_t nc = lcap ? 2 * lcap : 64;
            int64_t *np = realloc(loc, (size_t)nc * 2 * sizeof *np);
            if (!np) {
              r.nomem = 1;
              break;
            }
            loc = np;
            lcap = nc;
          }
          loc[2 * ln] = e;
          loc[2 * ln + 1] = r.hit[k];
          ln++;
        }
      }
#pragma omp critical(vm_prism_found)
      {
        if (r.nomem) nomem = 1;
        if (ln && !nomem) {
          if (nfound + ln > capfound) {
            int64_t nc = (nfound + ln) * 2;
            int64_t *np = realloc(found, (size_t)nc * 2 * sizeof *np);
            if (np) {
              found = np;
              capfound = nc;
            } else {
              nomem = 1;
            }
          }
          if (!nomem) {
            memcpy(found + 2 * nfound, loc, (size_t)ln * 2 * sizeof *loc);
            nfound += ln;
          }
        }
      }
      free(loc);
      free(r.hit);
    }
    err = rtcGetDeviceError(dev);
  }
  if (prims) {
    rtcReleaseScene(scene);
    vm_free(ctx, local.box);
  }
  if (err != RTC_ERROR_NONE || so->rt->failed || nomem) {
    /* the kept scene is not trusted after a failure */
    if (!prims && so->scene) {
      rtcReleaseScene(so->scene);
      so->scene = NULL;
    }
    free(found);
    *found_out = NULL;
    *nfound_out = 0;
    if (nomem) {
      so->rt->failed = 0;
      return vm_error(ctx, VM_ERR_NOMEM, "embree: out of memory collecting hits");
    }
    return rt_status(ctx, so->rt, err, "ray query");
  }
  *found_out = found;
  *nfound_out = nfound;
  return VM_OK;
}

/* (edge, triangle) hits -> pairs of triangles (every triangle on the
 * edge against the one it crosses), plus `nkeep` pairs given, sorted,
 * repeats dropped. */
static int hits_to_pairs(vm_ctx *ctx, const pr_soup *so, const int64_t *found, int64_t nfound,
                         const int64_t *keep, int64_t nkeep, int64_t *npairs, int64_t **pairs) {
  *npairs = 0;
  if (pairs) *pairs = NULL;
  const int32_t *tri = so->tri, *group = so->group;
  const half_edge *he = so->he;
  const int64_t *eb = so->eb;
  int st = VM_OK;
  int64_t n = 0, cap = 0;
  int64_t *pp = NULL;
  if (nkeep) {
    cap = nkeep + 64;
    pp = vm_alloc_array(ctx, (size_t)cap * 2, sizeof *pp);
    if (!pp) return VM_ERR_NOMEM;
    memcpy(pp, keep, (size_t)nkeep * 2 * sizeof *pp);
    n = nkeep;
  }
  for (int64_t k = 0; k < nfound && st == VM_OK; k++) {
    int64_t e = found[2 * k], t = found[2 * k + 1];
    for (int64_t j = eb[e]; j < eb[e + 1]; j++) {
      int64_t s = he[j].t;
      if (s == t) continue;
      if (group && group[s] >= 0 && group[s] == group[t]) continue;
      const int32_t *A = tri + 3 * s, *B = tri + 3 * t;
      int shared = 0;
      for (int i = 0; i < 3; i++)
        for (int m = 0; m < 3; m++) shared += A[i] == B[m];
      if (shared >= 2) continue;
      if (n == cap) {
        int64_t nc = cap ? 2 * cap : 64;
        int64_t *np = vm_realloc(ctx, pp, (size_t)nc * 2 * sizeof *np);
        if (!np) {
          st = VM_ERR_NOMEM;
          break;
        }
        pp = np;
        cap = nc;
      }
      pp[2 * n] = s < t ? s : t;
      pp[2 * n + 1] = s < t ? t : s;
      n++;
    }
  }
  if (st) {
    vm_free(ctx, pp);
    return st;
  }
  if (n > 1) qsort(pp, (size_t)n, 2 * sizeof *pp, cmp_pair);
  int64_t u = 0;
  for (int64_t k = 0; k < n; k++)
    if (u == 0 || cmp_pair(pp + 2 * k, pp + 2 * (u - 1))) {
      pp[2 * u] = pp[2 * k];
      pp[2 * u + 1] = pp[2 * k + 1];
      u++;
    }
  *npairs = u;
  if (pairs && u)
    *pairs = pp;
  else
    vm_free(ctx, pp);
  return VM_OK;
}

int pr_soup_intersections(vm_ctx *ctx, pr_soup *so, const double *xyz, int64_t *npairs,
                          int64_t **pairs) {
  *npairs = 0;
  if (pairs) *pairs = NULL;
  if (so->ntri < 2) return VM_OK;
  int64_t *found = NULL, nfound = 0;
  int st = collect_hits(ctx, so, xyz, NULL, 0, NULL, 0, 1, &found, &nfound);
  if (st) return st;
  st = hits_to_pairs(ctx, so, found, nfound, NULL, 0, npairs, pairs);
  free(found);
  return st;
}

/* Remember xyz and the answer for the next incremental query. */
static int soup_remember(vm_ctx *ctx, pr_soup *so, const double *xyz, const int64_t *pp,
                         int64_t n) {
  so->cached = 0;
  if (!so->last_xyz) {
    so->last_xyz = vm_alloc_array(ctx, (size_t)(3 * (so->nv ? so->nv : 1)), sizeof *xyz);
    if (!so->last_xyz) return VM_ERR_NOMEM;
  }
  vm_free(ctx, so->last_pairs);
  so->last_pairs = NULL;
  so->nlast = 0;
  if (n) {
    so->last_pairs = vm_alloc_array(ctx, (size_t)(2 * n), sizeof *pp);
    if (!so->last_pairs) return VM_ERR_NOMEM;
    memcpy(so->last_pairs, pp, (size_t)(2 * n) * sizeof *pp);
  }
  memcpy(so->last_xyz, xyz, (size_t)(3 * so->nv) * sizeof *xyz);
  so->nlast = n;
  so->cached = 1;
  return VM_OK;
}

int pr_soup_intersections_cached(vm_ctx *ctx, pr_soup *so, const double *xyz, int64_t *npairs,
                                 int64_t **pairs) {
  *npairs = 0;
  if (pairs) *pairs = NULL;
  if (so->ntri < 2) return VM_OK;
  int64_t ntri = so->ntri, nv = so->nv, *pp = NULL, n = 0;
  int st = VM_OK;
  uint8_t *moved = NULL, *chg = NULL;
  int32_t *prims = NULL;
  int64_t *edges = NULL, *keep = NULL, *hits = NULL, nhits = 0;
  int64_t nchg = 0;
  if (so->cached) {
    moved = vm_alloc_array(ctx, (size_t)nv, sizeof *moved);
    chg = vm_alloc_array(ctx, (size_t)ntri, sizeof *chg);
    if (!moved || !chg) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    for (int64_t v = 0; v < nv; v++)
      moved[v] = memcmp(xyz + 3 * v, so->last_xyz + 3 * v, 3 * sizeof *xyz) != 0;
    for (int64_t t = 0; t < ntri; t++) {
      const int32_t *T = so->tri + 3 * t;
      chg[t] = moved[T[0]] || moved[T[1]] || moved[T[2]];
      nchg += chg[t];
    }
  }
  double tq0 = omp_get_wtime();
  int full = !so->cached || so->k.full_query_ratio * nchg > ntri;
  if (full) {
    /* nothing to start from, or most faces moved: the full query */
    st = pr_soup_intersections(ctx, so, xyz, &n, &pp);
  } else {
    /* pairs between two unmoved faces are those of the last query; a pair
     * with a moved face is found by an edge of the moved face crossing any
     * face, or by any edge crossing the moved face */
    int64_t nedge = 0, nkeep = 0;
    prims = vm_alloc_array(ctx, (size_t)(nchg ? nchg : 1), sizeof *prims);
    edges = vm_alloc_array(ctx, (size_t)(so->ned ? so->ned : 1), sizeof *edges);
    keep = vm_alloc_array(ctx, (size_t)(2 * (so->nlast ? so->nlast : 1)), sizeof *keep);
    if (!prims || !edges || !keep) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    nchg = 0;
    for (int64_t t = 0; t < ntri; t++)
      if (chg[t]) prims[nchg++] = (int32_t)t;
    for (int64_t e = 0; e < so->ned; e++)
      for (int64_t k = so->eb[e]; k < so->eb[e + 1]; k++)
        if (chg[so->he[k].t]) {
          edges[nedge++] = e;
          break;
        }
    for (int64_t k = 0; k < so->nlast; k++) {
      const int64_t *q = so->last_pairs + 2 * k;
      if (!chg[q[0]] && !chg[q[1]]) {
        keep[2 * nkeep] = q[0];
        keep[2 * nkeep + 1] = q[1];
        nkeep++;
      }
    }
    if (nchg) {
      st = collect_hits(ctx, so, xyz, NULL, 0, edges, nedge, 0, &hits, &nhits);
      if (!st) st = collect_hits(ctx, so, xyz, prims, nchg, NULL, 0, 0, &hits, &nhits);
    }
    if (!st) st = hits_to_pairs(ctx, so, hits, nhits, keep, nkeep, &n, &pp);
    if (!st && so->check) {
      int64_t nf = 0, *pf = NULL;
      st = pr_soup_intersections(ctx, so, xyz, &nf, &pf);
      if (!st && (nf != n || (n && memcmp(pf, pp, (size_t)(2 * n) * sizeof *pp))))
        st = vm_error(ctx, VM_ERR_NUMERIC,
                      "intersections: the incremental query found %lld pairs, the full one %lld",
                      (long long)n, (long long)nf);
      vm_free(ctx, pf);
    }
  }
  if (!st) st = soup_remember(ctx, so, xyz, pp, n);
  vm_log(ctx, VM_LOG_DEBUG, "intersections: %s query, %lld of %lld faces moved, %lld pairs, %.3f s",
         full ? "full" : "incremental", (long long)nchg, (long long)ntri, (long long)n,
         omp_get_wtime() - tq0);
  if (!st) {
    *npairs = n;
    if (pairs && n) {
      *pairs = pp;
      pp = NULL;
    }
  }
done:
  if (st) so->cached = 0;
  vm_free(ctx, pp);
  vm_free(ctx, moved);
  vm_free(ctx, chg);
  vm_free(ctx, prims);
  vm_free(ctx, edges);
  vm_free(ctx, keep);
  free(hits);
  return st;
}

void pr_soup_destroy(vm_ctx *ctx, pr_soup **ps) {
  if (!ps || !*ps) return;
  pr_soup *s = *ps;
  vm_free(ctx, s->tri);
  vm_free(ctx, s->group);
  vm_free(ctx, s->he);
  vm_free(ctx, s->eb);
  vm_free(ctx, s->last_xyz);
  vm_free(ctx, s->last_pairs);
  if (s->scene) rtcReleaseScene(s->scene);
  vm_free(ctx, s->sd.box);
  vm_free(ctx, s);
  *ps = NULL;
}

int pr_soup_create(vm_ctx *ctx, pr_rt *rt, const pr_isect_params *k, int64_t ntri,
                   const int32_t *tri, const int32_t *group, int check, pr_soup **out) {
  *out = NULL;
  if (ntri < 0 || ntri > INT32_MAX / 4)
    return vm_error(ctx, VM_ERR_ARG, "intersections: %lld triangles", (long long)ntri);
  pr_soup *s = vm_calloc(ctx, 1, sizeof *s);
  if (!s) return VM_ERR_NOMEM;
  size_t n = (size_t)(ntri ? ntri : 1);
  s->rt = rt;
  s->k = *k;
  s->check = check != 0;
  s->ntri = ntri;
  s->tri = vm_alloc_array(ctx, 3 * n, sizeof *s->tri);
  s->group = group ? vm_alloc_array(ctx, n, sizeof *s->group) : NULL;
  s->he = vm_alloc_array(ctx, 3 * n, sizeof *s->he);
  s->eb = vm_alloc_array(ctx, 3 * n + 1, sizeof *s->eb);
  if (!s->tri || (group && !s->group) || !s->he || !s->eb) {
    pr_soup_destroy(ctx, &s);
    return VM_ERR_NOMEM;
  }
  memcpy(s->tri, tri, (size_t)(3 * ntri) * sizeof *tri);
  if (group) memcpy(s->group, group, (size_t)ntri * sizeof *group);
  for (int64_t t = 0; t < ntri; t++)
    for (int i = 0; i < 3; i++) {
      int32_t a = tri[3 * t + i], b = tri[3 * t + (i + 1) % 3];
      s->he[3 * t + i] = (half_edge){a < b ? a : b, a < b ? b : a, (int32_t)t};
    }
  qsort(s->he, (size_t)(3 * ntri), sizeof *s->he, cmp_he);
  for (int64_t k = 0; k < 3 * ntri; k++)
    if (k == 0 || s->he[k].a != s->he[k - 1].a || s->he[k].b != s->he[k - 1].b) s->eb[s->ned++] = k;
  s->eb[s->ned] = 3 * ntri;
  for (int64_t k = 0; k < 3 * ntri; k++)
    if (tri[k] >= s->nv) s->nv = tri[k] + 1;
  *out = s;
  return VM_OK;
}

int vm_prism_find_intersections(vm_ctx *ctx, const double *xyz, int64_t ntri, const int32_t *tri,
                                const int32_t *group, int64_t *npairs, int64_t **pairs) {
  if (npairs) *npairs = 0;
  if (pairs) *pairs = NULL;
  if (!xyz || !tri || ntri < 0 || !npairs)
    return vm_error(ctx, VM_ERR_ARG, "vm_prism_find_intersections: bad argument");
  if (ntri < 2) return VM_OK;
  /* one query: its own device, the stage's default parameters */
  pr_params k = pr_params_default();
  pr_rt *rt = NULL;
  pr_soup *s = NULL;
  int st = pr_rt_create(ctx, &rt);
  if (!st) st = pr_soup_create(ctx, rt, &k.isect, ntri, tri, group, 0, &s);
  if (!st) st = pr_soup_intersections(ctx, s, xyz, npairs, pairs);
  pr_soup_destroy(ctx, &s);
  pr_rt_destroy(&rt);
  return st;
}

#define QUAD_TRIS 4 /* triangles per side quad */

struct pr_layer_faces {
  int64_t nw, nt, ned;
  int32_t *tri;  /* 3 nt wall triangles */
  int32_t *edge; /* 2 ned wall edges */
  pr_soup *soup;
  double *xyz; /* 3 (2 nw + ned): wall, top, then the side quads' centres */
};

void pr_layer_faces_destroy(vm_ctx *ctx, pr_layer_faces **plf) {
  if (!plf || !*plf) return;
  pr_layer_faces *lf = *plf;
  pr_soup_destroy(ctx, &lf->soup);
  vm_free(ctx, lf->tri);
  vm_free(ctx, lf->edge);
  vm_free(ctx, lf->xyz);
  vm_free(ctx, lf);
  *plf = NULL;
}

/* The faces of the single layer: [0, nt) tops, [nt, nt + 4 ned) sides,
 * then the wall (group 0). A side face is the bilinear quad over a wall
 * edge; it is split into four triangles around its centre (the quad's
 * value at (1/2, 1/2), vertex 2 nw + e), not into two along a diagonal:
 * where a column fans far from its neighbours (a sharp trailing edge) a
 * diagonal split makes the two side quads of a valid prism that meet at
 * that column cross each other, and cutting would shorten a column that
 * nothing blocks. */
int pr_layer_faces_create(vm_ctx *ctx, pr_rt *rt, const pr_isect_params *k, int check, int64_t nw,
                          int64_t nt, const int32_t *wtri, int64_t ned, const int32_t *edge,
                          pr_layer_faces **out) {
  *out = NULL;
  int64_t nf = nt + QUAD_TRIS * ned + nt;
  if (2 * nw + ned > INT32_MAX)
    return vm_error(ctx, VM_ERR_ARG, "intersections: %lld layer vertices",
                    (long long)(2 * nw + ned));
  pr_layer_faces *lf = vm_calloc(ctx, 1, sizeof *lf);
  if (!lf) return VM_ERR_NOMEM;
  lf->nw = nw;
  lf->nt = nt;
  lf->ned = ned;
  lf->tri = vm_alloc_array(ctx, (size_t)(3 * nt), sizeof *lf->tri);
  lf->edge = vm_alloc_array(ctx, (size_t)(2 * ned), sizeof *lf->edge);
  lf->xyz = vm_alloc_array(ctx, (size_t)(3 * (2 * nw + ned)), sizeof *lf->xyz);
  int32_t *tri = vm_alloc_array(ctx, (size_t)(3 * nf), sizeof *tri);
  int32_t *grp = vm_alloc_array(ctx, (size_t)nf, sizeof *grp);
  if (!tri || !grp || !lf->tri || !lf->edge || !lf->xyz) {
    vm_free(ctx, tri);
    vm_free(ctx, grp);
    pr_layer_faces_destroy(ctx, &lf);
    return VM_ERR_NOMEM;
  }
  memcpy(lf->tri, wtri, (size_t)(3 * nt) * sizeof *wtri);
  memcpy(lf->edge, edge, (size_t)(2 * ned) * sizeof *edge);
  for (int64_t t = 0; t < nt; t++) {
    for (int i = 0; i < 3; i++) {
      tri[3 * t + i] = (int32_t)(wtri[3 * t + i] + nw);
      tri[3 * (nt + QUAD_TRIS * ned + t) + i] = wtri[3 * t + i];
    }
    grp[t] = -1;
    grp[nt + QUAD_TRIS * ned + t] = 0;
  }
  for (int64_t e = 0; e < ned; e++) {
    int32_t a = edge[2 * e], b = edge[2 * e + 1];
    int32_t q[4] = {a, b, (int32_t)(b + nw), (int32_t)(a + nw)}, c = (int32_t)(2 * nw + e);
    int32_t *s = tri + 3 * (nt + QUAD_TRIS * e);
    for (int i = 0; i < QUAD_TRIS; i++) {
      s[3 * i] = q[i];
      s[3 * i + 1] = q[(i + 1) % 4];
      s[3 * i + 2] = c;
      grp[nt + QUAD_TRIS * e + i] = -1;
    }
  }
  int st = pr_soup_create(ctx, rt, k, nf, tri, grp, check, &lf->soup);
  vm_free(ctx, tri);
  vm_free(ctx, grp);
  if (st) {
    pr_layer_faces_destroy(ctx, &lf);
    return st;
  }
  *out = lf;
  return VM_OK;
}

int pr_layer_faces_query(vm_ctx *ctx, pr_layer_faces *lf, const double *x, uint8_t *mark,
                         int64_t *npairs) {
  int64_t nw = lf->nw, nt = lf->nt, ned = lf->ned;
  double *y = lf->xyz;
  memcpy(y, x, (size_t)(6 * nw) * sizeof *y);
  for (int64_t e = 0; e < ned; e++) {
    int64_t a = lf->edge[2 * e], b = lf->edge[2 * e + 1];
    for (int k = 0; k < 3; k++)
      y[3 * (2 * nw + e) + k] =
          0.25 * (x[3 * a + k] + x[3 * b + k] + x[3 * (a + nw) + k] + x[3 * (b + nw) + k]);
  }
  int64_t np = 0, *pairs = NULL;
  int st = pr_soup_intersections_cached(ctx, lf->soup, y, &np, mark ? &pairs : NULL);
  if (st) return st;
  if (mark) {
    memset(mark, 0, (size_t)nw);
    /* the columns that carry each face: a top face's three, a side face's
     * two (the side edges its quad spans; both prisms on that wall edge
     * use them); the wall carries none. Marking whole neighbouring prisms
     * would cut about four times as many columns as needed. */
    for (int64_t k = 0; k < 2 * np; k++) {
      int64_t f = pairs[k];
      if (f < nt) {
        for (int i = 0; i < 3; i++) mark[lf->tri[3 * f + i]] = 1;
      } else if (f < nt + QUAD_TRIS * ned) {
        int64_t e = (f - nt) / QUAD_TRIS;
        mark[lf->edge[2 * e]] = 1;
        mark[lf->edge[2 * e + 1]] = 1;
      }
    }
  }
  vm_free(ctx, pairs);
  *npairs = np;
  return VM_OK;
}

int vm_prism_mesh_intersections(vm_ctx *ctx, const vm_mesh *m, const uint8_t *wall,
                                int64_t *npairs) {
  if (!m || !npairs) return vm_error(ctx, VM_ERR_ARG, "vm_prism_mesh_intersections: NULL");
  *npairs = 0;
  int64_t nf = 0;
  int32_t *fv = NULL;
  uint8_t *fnv = NULL;
  int st = vm_mesh_boundary(m, &nf, &fv, &fnv, NULL, NULL);
  if (st) return st;
  int64_t ntri = 0;
  for (int64_t f = 0; f < nf; f++) ntri += fnv[f] == 4 ? 2 : fnv[f] == 3 ? 1 : 0;
  int32_t *tri = vm_alloc_array(ctx, (size_t)(3 * (ntri ? ntri : 1)), sizeof *tri);
  int32_t *grp = vm_alloc_array(ctx, (size_t)(ntri ? ntri : 1), sizeof *grp);
  if (!tri || !grp) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  int64_t k = 0;
  for (int64_t f = 0; f < nf; f++) {
    const int32_t *c = fv + 4 * f;
    if (fnv[f] < 3) continue;
    static const int sp[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (int s = 0; s < (fnv[f] == 4 ? 2 : 1); s++) {
      int onwall = wall != NULL;
      for (int i = 0; i < 3; i++) {
        tri[3 * k + i] = c[sp[s][i]];
        if (wall && !wall[c[sp[s][i]]]) onwall = 0;
      }
      grp[k++] = onwall ? 0 : -1;
    }
  }
  st = vm_prism_find_intersections(ctx, m->xyz, ntri, tri, grp, npairs, NULL);
done:
  vm_free(ctx, fv);
  vm_free(ctx, fnv);
  vm_free(ctx, tri);
  vm_free(ctx, grp);
  return st;
}
