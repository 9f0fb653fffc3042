/* prism/src/intersect.c: intersecting triangle pairs found with Embree's
 * BVH collision query (rtcCollide) and decided by sign tests in double,
 * collected and sorted so the result never depends on thread timing. */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "prism_private.h"
#include "varmesh/topology.h"

typedef struct {
  const double *xyz;
  const int32_t *tri;
  const int32_t *group;
  int64_t ntri;
  float *box; /* 6 per triangle, rounded outwards */
  /* results, appended under the spin lock */
  atomic_flag lock;
  int64_t n, cap;
  int64_t *pairs;
  int nomem;
} collide_data;

static void tri_bounds(const struct RTCBoundsFunctionArguments *a) {
  const collide_data *d = a->geometryUserPtr;
  const float *b = d->box + 6 * (size_t)a->primID;
  a->bounds_o->lower_x = b[0];
  a->bounds_o->lower_y = b[1];
  a->bounds_o->lower_z = b[2];
  a->bounds_o->upper_x = b[3];
  a->bounds_o->upper_y = b[4];
  a->bounds_o->upper_z = b[5];
}

/* orient(a, b, c, d) = (a - d) . ((b - d) x (c - d)), with a tolerance
 * relative to the lengths involved: 0 when the four points are coplanar
 * within rounding. */
static int orient(const double *a, const double *b, const double *c, const double *d) {
  double u[3], v[3], w[3], x[3];
  for (int k = 0; k < 3; k++) {
    u[k] = a[k] - d[k];
    v[k] = b[k] - d[k];
    w[k] = c[k] - d[k];
  }
  pr_cross(v, w, x);
  double o = pr_dot(u, x);
  double s = pr_norm(u) * pr_norm(v) * pr_norm(w);
  if (fabs(o) <= 1e-12 * s) return 0;
  return o > 0 ? 1 : -1;
}

/* Does segment pq cross the interior of triangle abc (strictly)? */
static int seg_tri(const double *p, const double *q, const double *a, const double *b,
                   const double *c) {
  int o1 = orient(a, b, c, p), o2 = orient(a, b, c, q);
  if (o1 == 0 || o2 == 0 || o1 == o2) return 0;
  int s1 = orient(p, q, a, b), s2 = orient(p, q, b, c), s3 = orient(p, q, c, a);
  return s1 != 0 && s1 == s2 && s2 == s3;
}

/* Triangles i, j of the data intersect (see vm_prism_find_intersections). */
static int tri_pair(const collide_data *d, int64_t i, int64_t j) {
  const int32_t *A = d->tri + 3 * i, *B = d->tri + 3 * j;
  int shared = 0, sa = -1, sb = -1;
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++)
      if (A[a] == B[b]) {
        shared++;
        sa = a;
        sb = b;
      }
  if (shared >= 2) return 0;
  const double *x = d->xyz;
#define P(v) (x + 3 * (int64_t)(v))
  if (shared == 1) {
    int a1 = A[(sa + 1) % 3], a2 = A[(sa + 2) % 3], b1 = B[(sb + 1) % 3], b2 = B[(sb + 2) % 3];
    return seg_tri(P(a1), P(a2), P(B[0]), P(B[1]), P(B[2])) ||
           seg_tri(P(b1), P(b2), P(A[0]), P(A[1]), P(A[2]));
  }
  for (int k = 0; k < 3; k++) {
    if (seg_tri(P(A[k]), P(A[(k + 1) % 3]), P(B[0]), P(B[1]), P(B[2]))) return 1;
    if (seg_tri(P(B[k]), P(B[(k + 1) % 3]), P(A[0]), P(A[1]), P(A[2]))) return 1;
  }
  return 0;
#undef P
}

static void collide(void *user, struct RTCCollision *c, unsigned int n) {
  collide_data *d = user;
  for (unsigned int k = 0; k < n; k++) {
    int64_t i = c[k].primID0, j = c[k].primID1;
    if (i >= j) continue;
    if (d->group && d->group[i] >= 0 && d->group[i] == d->group[j]) continue;
    const float *bi = d->box + 6 * i, *bj = d->box + 6 * j;
    if (bi[0] > bj[3] || bj[0] > bi[3] || bi[1] > bj[4] || bj[1] > bi[4] || bi[2] > bj[5] ||
        bj[2] > bi[5])
      continue;
    if (!tri_pair(d, i, j)) continue;
    while (atomic_flag_test_and_set_explicit(&d->lock, memory_order_acquire)) {
    }
    if (d->n == d->cap) {
      int64_t nc = d->cap ? 2 * d->cap : 256;
      int64_t *np = realloc(d->pairs, (size_t)nc * 2 * sizeof *np);
      if (!np) {
        d->nomem = 1;
        atomic_flag_clear_explicit(&d->lock, memory_order_release);
        continue;
      }
      d->pairs = np;
      d->cap = nc;
    }
    d->pairs[2 * d->n] = i;
    d->pairs[2 * d->n + 1] = j;
    d->n++;
    atomic_flag_clear_explicit(&d->lock, memory_order_release);
  }
}

static int cmp_pair(const void *a, const void *b) {
  const int64_t *x = a, *y = b;
  if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
  return (x[1] > y[1]) - (x[1] < y[1]);
}

static float down(double v) {
  float f = (float)v;
  if ((double)f > v) f = nextafterf(f, -INFINITY);
  return f;
}
static float up(double v) {
  float f = (float)v;
  if ((double)f < v) f = nextafterf(f, INFINITY);
  return f;
}

int vm_prism_find_intersections(vm_ctx *ctx, const double *xyz, int64_t ntri,
                                const int32_t *tri, const int32_t *group, int64_t *npairs,
                                int64_t **pairs) {
  if (npairs) *npairs = 0;
  if (pairs) *pairs = NULL;
  if (!xyz || !tri || ntri < 0 || !npairs)
    return vm_error(ctx, VM_ERR_ARG, "vm_prism_find_intersections: bad argument");
  if (ntri > UINT32_MAX / 2)
    return vm_error(ctx, VM_ERR_ARG, "vm_prism_find_intersections: too many triangles");
  if (ntri < 2) return VM_OK;
  collide_data d;
  memset(&d, 0, sizeof d);
  atomic_flag_clear(&d.lock);
  d.xyz = xyz;
  d.tri = tri;
  d.group = group;
  d.ntri = ntri;
  d.box = vm_alloc_array(ctx, (size_t)ntri * 6, sizeof *d.box);
  if (!d.box) return VM_ERR_NOMEM;
  for (int64_t t = 0; t < ntri; t++) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) {
        double v = xyz[3 * (int64_t)tri[3 * t + i] + k];
        lo[k] = v < lo[k] ? v : lo[k];
        hi[k] = v > hi[k] ? v : hi[k];
      }
    for (int k = 0; k < 3; k++) {
      d.box[6 * t + k] = down(lo[k]);
      d.box[6 * t + 3 + k] = up(hi[k]);
    }
  }
  int st = VM_OK;
  RTCDevice dev = rtcNewDevice(NULL);
  if (!dev) {
    vm_free(ctx, d.box);
    return vm_error(ctx, VM_ERR_BACKEND, "embree: cannot create a device");
  }
  RTCScene scene = rtcNewScene(dev);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(g, (unsigned int)ntri);
  rtcSetGeometryUserData(g, &d);
  rtcSetGeometryBoundsFunction(g, tri_bounds, NULL);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(scene);
  enum RTCError err = rtcGetDeviceError(dev);
  if (err == RTC_ERROR_NONE) {
    rtcCollide(scene, scene, collide, &d);
    err = rtcGetDeviceError(dev);
  }
  rtcReleaseScene(scene);
  rtcReleaseDevice(dev);
  vm_free(ctx, d.box);
  if (err != RTC_ERROR_NONE) {
    free(d.pairs);
    return vm_error(ctx, VM_ERR_BACKEND, "embree: collision query failed (error %d)", (int)err);
  }
  if (d.nomem) {
    free(d.pairs);
    return vm_error(ctx, VM_ERR_NOMEM, "embree: out of memory collecting intersections");
  }
  /* Embree may report a pair more than once: sort, then drop repeats */
  if (d.n > 1) qsort(d.pairs, (size_t)d.n, 2 * sizeof *d.pairs, cmp_pair);
  int64_t n = 0;
  for (int64_t k = 0; k < d.n; k++)
    if (n == 0 || cmp_pair(d.pairs + 2 * k, d.pairs + 2 * (n - 1))) {
      d.pairs[2 * n] = d.pairs[2 * k];
      d.pairs[2 * n + 1] = d.pairs[2 * k + 1];
      n++;
    }
  *npairs = n;
  if (pairs && n) {
    *pairs = vm_alloc_array(ctx, (size_t)(2 * n), sizeof **pairs);
    if (!*pairs) st = VM_ERR_NOMEM;
    else memcpy(*pairs, d.pairs, (size_t)(2 * n) * sizeof **pairs);
  }
  free(d.pairs);
  return st;
}

int pr_layer_intersections(vm_prism *p, uint8_t *mark, int64_t *npairs) {
  vm_ctx *ctx = p->ctx;
  int64_t nw = p->nw, nt = p->nt, ned = p->ned;
  int64_t nf = nt + 2 * ned + nt;
  int32_t *tri = vm_alloc_array(ctx, (size_t)(3 * nf), sizeof *tri);
  int32_t *grp = vm_alloc_array(ctx, (size_t)nf, sizeof *grp);
  if (!tri || !grp) {
    vm_free(ctx, tri);
    vm_free(ctx, grp);
    return VM_ERR_NOMEM;
  }
  /* faces: [0, nt) tops, [nt, nt + 2 ned) sides, then the wall */
  for (int64_t t = 0; t < nt; t++) {
    for (int i = 0; i < 3; i++) {
      tri[3 * t + i] = (int32_t)(p->tri[3 * t + i] + nw);
      tri[3 * (nt + 2 * ned + t) + i] = p->tri[3 * t + i];
    }
    grp[t] = -1;
    grp[nt + 2 * ned + t] = 0;
  }
  for (int64_t e = 0; e < ned; e++) {
    int32_t a = p->edge[2 * e], b = p->edge[2 * e + 1];
    int32_t *s = tri + 3 * (nt + 2 * e);
    s[0] = a;
    s[1] = b;
    s[2] = (int32_t)(b + nw);
    s[3] = a;
    s[4] = (int32_t)(b + nw);
    s[5] = (int32_t)(a + nw);
    grp[nt + 2 * e] = grp[nt + 2 * e + 1] = -1;
  }
  int64_t np = 0, *pairs = NULL;
  int st = vm_prism_find_intersections(ctx, p->layer->xyz, nf, tri, grp, &np,
                                       mark ? &pairs : NULL);
  vm_free(ctx, tri);
  vm_free(ctx, grp);
  if (st) return st;
  if (mark) {
    memset(mark, 0, (size_t)nw);
    for (int64_t k = 0; k < 2 * np; k++) {
      int64_t f = pairs[k];
      int32_t owner[2] = {-1, -1};
      if (f < nt) {
        owner[0] = (int32_t)f;
      } else if (f < nt + 2 * ned) {
        int64_t e = (f - nt) / 2;
        owner[0] = p->etri[2 * e];
        owner[1] = p->etri[2 * e + 1];
      }
      for (int o = 0; o < 2; o++)
        if (owner[o] >= 0)
          for (int i = 0; i < 3; i++) mark[p->tri[3 * (int64_t)owner[o] + i]] = 1;
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
