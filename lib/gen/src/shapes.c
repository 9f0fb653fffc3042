/* gen/src/shapes.c: generated test surfaces (icosphere, torus, cylinder,
 * cube, box, lens) appended to a mesh. */
#include "varmesh/shapes.h"

#include <math.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* splitmix64 as a uniform double in [0, 1): the jitter sequence. The
 * meshes of the tests and benchmarks depend on these exact bits. */
static double splitmix_unit(uint64_t *s) {
  uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}

static double jitter_amount(const vm_gen_jitter *j) { return j && j->amount > 0 ? j->amount : 0; }

/* Undo a partial append: the counts go back, the arrays stay valid. */
static int rollback(vm_mesh *m, int64_t nv0, int64_t ne0, int st) {
  m->nv = nv0;
  m->ne = ne0;
  return st;
}

static int add_tri(vm_mesh *m, int64_t a, int64_t b, int64_t c) {
  int32_t t[3] = {(int32_t)a, (int32_t)b, (int32_t)c};
  return vm_mesh_add_element(m, VM_TRI, t);
}

static int add_point(vm_mesh *m, const double *c, double x, double y, double z, int64_t *index) {
  if (c) return vm_mesh_add_vertex(m, c[0] + x, c[1] + y, c[2] + z, index);
  return vm_mesh_add_vertex(m, x, y, z, index);
}

/* ---- icosphere ---- */

/* Edge (a, b) -> its midpoint vertex: open addressing on the packed pair. */
typedef struct {
  int64_t *key;
  int32_t *val;
  int64_t cap;
} edge_map;

typedef struct {
  double *p; /* 3 per vertex, relative to the centre */
  int32_t n;
  double radius;
  int project; /* put midpoints on the sphere now */
} ico_points;

static int32_t midpoint(ico_points *P, edge_map *em, int32_t a, int32_t b) {
  int64_t lo = a < b ? a : b, hi = a < b ? b : a;
  int64_t key = lo * 0x100000000ll + hi;
  uint64_t h = (uint64_t)key * 0x9e3779b97f4a7c15ull;
  int64_t i = (int64_t)(h % (uint64_t)em->cap);
  while (em->key[i] != -1) {
    if (em->key[i] == key) return em->val[i];
    i = (i + 1) % em->cap;
  }
  double p[3], *q = P->p + 3 * (int64_t)P->n;
  for (int k = 0; k < 3; k++) p[k] = 0.5 * (P->p[3 * a + k] + P->p[3 * b + k]);
  if (P->project) {
    double l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int k = 0; k < 3; k++) q[k] = P->radius * p[k] / l;
  } else {
    memcpy(q, p, sizeof p);
  }
  em->key[i] = key;
  em->val[i] = P->n;
  return P->n++;
}

int vm_gen_icosphere(vm_mesh *m, const double centre[3], double radius, int level, unsigned flags,
                     const vm_gen_jitter *jitter) {
  vm_ctx *ctx = m->ctx;
  if (!(radius > 0) || level < 0 || level > 12 || (flags & ~(unsigned)VM_GEN_PROJECT_AT_END))
    return vm_error(ctx, VM_ERR_ARG, "icosphere: radius %g level %d flags %u", radius, level,
                    flags);
  const double t = (1.0 + sqrt(5.0)) / 2.0;
  const double V[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  const int32_t F[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  int64_t ntri = (int64_t)20 << (2 * level), nvert = ntri / 2 + 2;
  int64_t nv0 = m->nv, ne0 = m->ne;
  if (nv0 + nvert > INT32_MAX) return vm_error(ctx, VM_ERR_ARG, "icosphere: too many vertices");
  int project_at_end = (flags & VM_GEN_PROJECT_AT_END) != 0;
  ico_points P = {vm_alloc_array(ctx, (size_t)nvert, 3 * sizeof(double)), 0, radius,
                  !project_at_end};
  int32_t *tri = vm_alloc_array(ctx, (size_t)ntri, 3 * sizeof(int32_t));
  int32_t *tri2 = vm_alloc_array(ctx, (size_t)ntri, 3 * sizeof(int32_t));
  edge_map em = {NULL, NULL, 3 * ntri + 17};
  em.key = vm_alloc_array(ctx, (size_t)em.cap, sizeof *em.key);
  em.val = vm_alloc_array(ctx, (size_t)em.cap, sizeof *em.val);
  int st = VM_OK;
  if (!P.p || !tri || !tri2 || !em.key || !em.val) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int i = 0; i < 12; i++) {
    double l = sqrt(V[i][0] * V[i][0] + V[i][1] * V[i][1] + V[i][2] * V[i][2]);
    for (int k = 0; k < 3; k++) P.p[3 * i + k] = project_at_end ? V[i][k] : radius * V[i][k] / l;
  }
  P.n = 12;
  int64_t nt = 20;
  memcpy(tri, F, sizeof F);
  for (int lv = 0; lv < level; lv++) {
    /* each triangle into four: corners first, the middle one last */
    int64_t cap = 4 * 3 * nt + 17;
    em.cap = cap;
    for (int64_t i = 0; i < cap; i++) em.key[i] = -1;
    for (int64_t f = 0; f < nt; f++) {
      int32_t a = tri[3 * f], b = tri[3 * f + 1], c = tri[3 * f + 2];
      int32_t ab = midpoint(&P, &em, a, b), bc = midpoint(&P, &em, b, c),
              ca = midpoint(&P, &em, c, a);
      int32_t q[12] = {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca};
      memcpy(tri2 + 12 * f, q, sizeof q);
    }
    int32_t *sw = tri;
    tri = tri2;
    tri2 = sw;
    nt *= 4;
  }
  if (project_at_end)
    for (int32_t v = 0; v < P.n; v++) {
      double *p = P.p + 3 * (int64_t)v;
      double l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int k = 0; k < 3; k++) p[k] = radius * p[k] / l;
    }
  double amount = jitter_amount(jitter);
  if (amount > 0) {
    double h = radius * 1.1 / (1 << level); /* about the mean edge length */
    uint64_t s = jitter->seed;
    for (int32_t v = 0; v < P.n; v++) {
      double *p = P.p + 3 * (int64_t)v, d[3];
      for (int k = 0; k < 3; k++) d[k] = amount * h * (2 * splitmix_unit(&s) - 1);
      for (int k = 0; k < 3; k++) p[k] += d[k];
      double l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int k = 0; k < 3; k++) p[k] *= radius / l;
    }
  }
  for (int32_t v = 0; v < P.n && !st; v++) {
    const double *p = P.p + 3 * (int64_t)v;
    st = add_point(m, centre, p[0], p[1], p[2], NULL);
  }
  for (int64_t f = 0; f < nt && !st; f++)
    st = add_tri(m, nv0 + tri[3 * f], nv0 + tri[3 * f + 1], nv0 + tri[3 * f + 2]);
done:
  vm_free(ctx, P.p);
  vm_free(ctx, tri);
  vm_free(ctx, tri2);
  vm_free(ctx, em.key);
  vm_free(ctx, em.val);
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

/* ---- torus and cylinder ---- */

int vm_gen_torus(vm_mesh *m, const double centre[3], double R, double r, int nu, int nv, int cells,
                 const vm_gen_jitter *jitter, double *H) {
  vm_ctx *ctx = m->ctx;
  if (!(r > 0) || !(R > r) || nu < 3 || nv < 3 || (int64_t)nu * nv > INT32_MAX - m->nv ||
      cells < VM_GEN_TORUS_TRI || cells > VM_GEN_TORUS_QUAD)
    return vm_error(ctx, VM_ERR_ARG, "torus: R %g r %g nu %d nv %d cells %d", R, r, nu, nv, cells);
  int64_t nv0 = m->nv, ne0 = m->ne;
  double amount = jitter_amount(jitter);
  uint64_t s = jitter ? jitter->seed : 0;
  int st = VM_OK;
  for (int i = 0; i < nu && !st; i++)
    for (int j = 0; j < nv && !st; j++) {
      double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      if (amount > 0) {
        u += amount * 2 * M_PI / nu * (2 * splitmix_unit(&s) - 1);
        v += amount * 2 * M_PI / nv * (2 * splitmix_unit(&s) - 1);
      }
      st = add_point(m, centre, (R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v),
                     NULL);
      if (H) H[(int64_t)i * nv + j] = (R + 2 * r * cos(v)) / (2 * r * (R + r * cos(v)));
    }
  for (int i = 0; i < nu && !st; i++)
    for (int j = 0; j < nv && !st; j++) {
      int32_t a = (int32_t)(nv0 + i * nv + j), b = (int32_t)(nv0 + ((i + 1) % nu) * nv + j),
              c = (int32_t)(nv0 + ((i + 1) % nu) * nv + (j + 1) % nv),
              d = (int32_t)(nv0 + i * nv + (j + 1) % nv);
      /* (a, b, c, d) is counter-clockwise seen from outside: d_u x d_v is outward */
      if (cells == VM_GEN_TORUS_QUAD) {
        int32_t q[4] = {a, b, c, d};
        st = vm_mesh_add_element(m, VM_QUAD, q);
      } else if (cells == VM_GEN_TORUS_TRI_ALT && (i + j) % 2) {
        st = add_tri(m, a, b, d);
        if (!st) st = add_tri(m, b, c, d);
      } else {
        st = add_tri(m, a, b, c);
        if (!st) st = add_tri(m, a, c, d);
      }
    }
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

int vm_gen_cylinder(vm_mesh *m, double r, double h, int na, int nz, const vm_gen_jitter *jitter) {
  vm_ctx *ctx = m->ctx;
  if (!(r > 0) || !(h > 0) || na < 3 || nz < 2 || (int64_t)na * nz > INT32_MAX - m->nv)
    return vm_error(ctx, VM_ERR_ARG, "cylinder: r %g h %g na %d nz %d", r, h, na, nz);
  int64_t nv0 = m->nv, ne0 = m->ne;
  double amount = jitter_amount(jitter);
  uint64_t s = jitter ? jitter->seed : 0;
  int st = VM_OK;
  for (int k = 0; k < nz && !st; k++)
    for (int i = 0; i < na && !st; i++) {
      double u = 2 * M_PI * i / na, z = h * k / (nz - 1);
      if (amount > 0 && k > 0 && k < nz - 1) {
        u += amount * 2 * M_PI / na * (2 * splitmix_unit(&s) - 1);
        z += amount * h / (nz - 1) * (2 * splitmix_unit(&s) - 1);
      }
      st = vm_mesh_add_vertex(m, r * cos(u), r * sin(u), z, NULL);
    }
  for (int k = 0; k + 1 < nz && !st; k++)
    for (int i = 0; i < na && !st; i++) {
      int64_t a = nv0 + k * na + i, b = nv0 + k * na + (i + 1) % na,
              c = nv0 + (k + 1) * na + (i + 1) % na, d = nv0 + (k + 1) * na + i;
      st = add_tri(m, a, b, c);
      if (!st) st = add_tri(m, a, c, d);
    }
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

/* ---- an isolated wing ---- */

int vm_gen_wing(vm_mesh *m, int nc, int ns, double thickness, double sweep_deg) {
  vm_ctx *ctx = m->ctx;
  if (nc < 4 || ns < 1 || nc > 100000 || ns > 100000 ||
      2 * (int64_t)nc * (ns + 1) > INT32_MAX - m->nv || !(thickness > 0 && thickness <= 0.5) ||
      !(sweep_deg >= 0 && sweep_deg <= 60))
    return vm_error(ctx, VM_ERR_ARG, "wing: chordwise %d spanwise %d thickness %g sweep %g", nc, ns,
                    thickness, sweep_deg);
  const double root = 0.806, tip = 0.455, span = 1.196;
  const double tsw = tan(sweep_deg * M_PI / 180);
  int64_t nv0 = m->nv, ne0 = m->ne, np = 2 * (int64_t)nc;
  int st = VM_OK;
  /* section point i of 2 nc: 0 the trailing edge, 1..nc the upper side to
   * the leading edge (x_k, k = nc - i), nc + 1..2 nc - 1 the lower side */
  for (int j = 0; j <= ns && !st; j++) {
    double s = (double)j / ns, c = root + (tip - root) * s, y = span * s, x0 = y * tsw;
    for (int64_t i = 0; i < np && !st; i++) {
      int64_t k = i <= nc ? nc - i : i - nc;
      double x = 0.5 * (1 - cos(M_PI * (double)k / nc)), t = thickness;
      double z = k == nc ? 0
                         : 5 * t *
                               (0.2969 * sqrt(x) - 0.1260 * x - 0.3516 * x * x +
                                0.2843 * x * x * x - 0.1036 * x * x * x * x);
      st = vm_mesh_add_vertex(m, x0 + c * x, y, i <= nc ? c * z : -c * z, NULL);
    }
  }
#define WV(j, i) (nv0 + (int64_t)(j)*np + ((i) % np))
  for (int j = 0; j < ns && !st; j++)
    for (int64_t i = 0; i < np && !st; i++) {
      st = add_tri(m, WV(j, i), WV(j, i + 1), WV(j + 1, i + 1));
      if (!st) st = add_tri(m, WV(j, i), WV(j + 1, i + 1), WV(j + 1, i));
    }
  /* the caps: strips between the upper and lower point of each x_k; the
   * root cap runs against the sides' edges there, the tip cap the other
   * way */
  for (int cap = 0; cap < 2 && !st; cap++) {
    int j = cap ? ns : 0;
    for (int64_t k = 0; k < nc && !st; k++) {
      int64_t u0 = WV(j, nc - k), u1 = WV(j, nc - k - 1), l0 = WV(j, nc + k),
              l1 = WV(j, nc + k + 1);
      if (k + 1 == nc) l1 = u1; /* the trailing edge: one point */
      if (k == 0) {
        st = cap ? add_tri(m, u0, l1, u1) : add_tri(m, u0, u1, l1);
      } else if (k + 1 == nc) {
        st = cap ? add_tri(m, u0, l0, u1) : add_tri(m, u0, u1, l0);
      } else {
        st = cap ? add_tri(m, u0, l1, u1) : add_tri(m, u0, u1, l1);
        if (!st) st = cap ? add_tri(m, u0, l0, l1) : add_tri(m, u0, l1, l0);
      }
    }
  }
#undef WV
  if (st) return rollback(m, nv0, ne0, st);
  /* outward: the enclosed volume positive, else every triangle turned */
  double vol = 0;
  for (int64_t e = ne0; e < m->ne; e++) {
    const int32_t *t = m->conn + m->eoff[e];
    const double *a = m->xyz + 3 * (int64_t)t[0], *b = m->xyz + 3 * (int64_t)t[1],
                 *c = m->xyz + 3 * (int64_t)t[2];
    vol += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  if (vol < 0)
    for (int64_t e = ne0; e < m->ne; e++) {
      int32_t *t = m->conn + m->eoff[e], x = t[1];
      t[1] = t[2];
      t[2] = x;
    }
  return VM_OK;
}

/* ---- cube and box ---- */

/* The two triangles of the lattice square v[0..3] (counter-clockwise seen
 * from +e_a), on the low side (normal -e_a) reversed. */
static int add_square(vm_mesh *m, const int32_t v[4], int low_side) {
  if (low_side) {
    int st = add_tri(m, v[0], v[2], v[1]);
    return st ? st : add_tri(m, v[0], v[3], v[2]);
  }
  int st = add_tri(m, v[0], v[1], v[2]);
  return st ? st : add_tri(m, v[0], v[2], v[3]);
}

int vm_gen_cube(vm_mesh *m, int n) {
  vm_ctx *ctx = m->ctx;
  if (n < 1 || n > 1000) return vm_error(ctx, VM_ERR_ARG, "cube: n %d", n);
  int64_t nv0 = m->nv, ne0 = m->ne;
  int N = n + 1;
  int32_t *id = vm_alloc_array(ctx, (size_t)N * N * N, sizeof *id);
  if (!id) return VM_ERR_NOMEM;
  int st = VM_OK;
  /* vertices: the surface points of the (n+1)^3 lattice */
  for (int i = 0; i < N && !st; i++)
    for (int j = 0; j < N && !st; j++)
      for (int k = 0; k < N && !st; k++) {
        int32_t *p = id + ((int64_t)i * N + j) * N + k;
        *p = -1;
        if (i == 0 || j == 0 || k == 0 || i == n || j == n || k == n) {
          int64_t v;
          st = vm_mesh_add_vertex(m, (double)i / n, (double)j / n, (double)k / n, &v);
          *p = (int32_t)v;
        }
      }
  /* faces: axis a fixed at side s; (u, w) the other two axes, e_u x e_w = e_a */
  for (int a = 0; a < 3 && !st; a++)
    for (int side = 0; side < 2 && !st; side++) {
      int u = (a + 1) % 3, w = (a + 2) % 3;
      for (int p = 0; p < n && !st; p++)
        for (int q = 0; q < n && !st; q++) {
          static const int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
          int32_t v[4];
          for (int r = 0; r < 4; r++) {
            int c[3];
            c[a] = side * n;
            c[u] = p + du[r];
            c[w] = q + dw[r];
            v[r] = id[((int64_t)c[0] * N + c[1]) * N + c[2]];
          }
          st = add_square(m, v, !side);
        }
    }
  vm_free(ctx, id);
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

int vm_gen_box(vm_mesh *m, const double lo[3], const double hi[3], const int n[3]) {
  vm_ctx *ctx = m->ctx;
  for (int k = 0; k < 3; k++)
    if (!(lo[k] < hi[k]) || n[k] < 1 || n[k] > 1000)
      return vm_error(ctx, VM_ERR_ARG, "box: axis %d: [%g, %g] in %d", k, lo[k], hi[k], n[k]);
  int64_t nv0 = m->nv, ne0 = m->ne;
  int64_t N[3] = {n[0] + 1, n[1] + 1, n[2] + 1};
  int32_t *id = vm_alloc_array(ctx, (size_t)(N[0] * N[1] * N[2]), sizeof *id);
  if (!id) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < N[0] * N[1] * N[2]; i++) id[i] = -1;
  int st = VM_OK;
  for (int a = 0; a < 3 && !st; a++) {
    int u = (a + 1) % 3, w = (a + 2) % 3; /* e_u x e_w = e_a */
    for (int side = 0; side < 2 && !st; side++) {
      /* the face's lattice points, each vertex made on its first use; one
       * formula per coordinate, so faces meeting at an edge agree */
      for (int j = 0; j <= n[w] && !st; j++)
        for (int i = 0; i <= n[u] && !st; i++) {
          int c[3];
          c[a] = side ? n[a] : 0;
          c[u] = i;
          c[w] = j;
          int32_t *p = id + (c[0] * N[1] + c[1]) * N[2] + c[2];
          if (*p >= 0) continue;
          double x[3];
          for (int k = 0; k < 3; k++)
            x[k] = c[k] == n[k] ? hi[k] : lo[k] + (hi[k] - lo[k]) * c[k] / n[k];
          int64_t v;
          st = vm_mesh_add_vertex(m, x[0], x[1], x[2], &v);
          *p = (int32_t)v;
        }
      for (int j = 0; j < n[w] && !st; j++)
        for (int i = 0; i < n[u] && !st; i++) {
          static const int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
          int32_t v[4];
          for (int r = 0; r < 4; r++) {
            int c[3];
            c[a] = side ? n[a] : 0;
            c[u] = i + du[r];
            c[w] = j + dw[r];
            v[r] = id[(c[0] * N[1] + c[1]) * N[2] + c[2]];
          }
          st = add_square(m, v, !side);
        }
    }
  }
  vm_free(ctx, id);
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

/* ---- hemisphere ---- */

int vm_gen_hemisphere(vm_mesh *m, double radius, int n) {
  vm_ctx *ctx = m->ctx;
  if (n < 2 || n % 2 || n > 1000 || !(radius > 0))
    return vm_error(ctx, VM_ERR_ARG, "hemisphere: n %d (even, 2..1000), radius %g", n, radius);
  int64_t nv0 = m->nv, ne0 = m->ne, N = n + 1, h = n / 2;
  int32_t *id = vm_alloc_array(ctx, (size_t)(N * N * N), sizeof *id);
  if (!id) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < N * N * N; i++) id[i] = -1;
  int st = VM_OK;
  for (int a = 0; a < 3 && !st; a++) {
    int u = (a + 1) % 3, w = (a + 2) % 3; /* e_u x e_w = e_a */
    for (int side = 0; side < 2 && !st; side++) {
      if (a == 2 && !side) continue; /* the cube's bottom: below the plane */
      for (int j = 0; j <= n && !st; j++)
        for (int i = 0; i <= n && !st; i++) {
          int c[3];
          c[a] = side ? n : 0;
          c[u] = i;
          c[w] = j;
          if (c[2] < h) continue;
          int32_t *p = id + (c[0] * N + c[1]) * N + c[2];
          if (*p >= 0) continue;
          /* the equal-angle cube-sphere: the row c[2] = n / 2 at z = 0 exactly */
          double t[3];
          for (int k = 0; k < 3; k++) t[k] = tan((2.0 * c[k] / n - 1) * M_PI / 4);
          double r = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]), x[3];
          for (int k = 0; k < 3; k++) x[k] = radius * t[k] / r;
          if (c[2] == h) x[2] = 0;
          int64_t v;
          st = vm_mesh_add_vertex(m, x[0], x[1], x[2], &v);
          *p = (int32_t)v;
        }
      for (int j = 0; j < n && !st; j++)
        for (int i = 0; i < n && !st; i++) {
          static const int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
          int32_t v[4];
          int below = 0;
          for (int r = 0; r < 4; r++) {
            int c[3];
            c[a] = side ? n : 0;
            c[u] = i + du[r];
            c[w] = j + dw[r];
            below |= c[2] < h;
            v[r] = below ? -1 : id[(c[0] * N + c[1]) * N + c[2]];
          }
          if (!below) st = add_square(m, v, !side);
        }
    }
  }
  vm_free(ctx, id);
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

/* ---- lens ---- */

/* Stitch ring a (na vertices from a0, angles 2 pi (i + oa) / na) to ring b
 * (outer, nb from b0) with triangles oriented along +z x radial (flip: the
 * other way), advancing on the ring whose next angle is smaller. */
static int stitch(vm_mesh *m, int32_t a0, int na, double oa, int32_t b0, int nb, double ob,
                  int flip) {
  int i = 0, k = 0, st = 0;
  while (i < na || k < nb) {
    double an = 2 * M_PI * (i + 1 + oa) / na, bn = 2 * M_PI * (k + 1 + ob) / nb;
    int32_t A = a0 + i % na, B = b0 + k % nb, t[3];
    if (k >= nb || (i < na && an < bn)) {
      t[0] = A, t[1] = B, t[2] = a0 + (i + 1) % na;
      i++;
    } else {
      t[0] = A, t[1] = B, t[2] = b0 + (k + 1) % nb;
      k++;
    }
    if (flip) {
      int32_t s = t[1];
      t[1] = t[2];
      t[2] = s;
    }
    if ((st = vm_mesh_add_element(m, VM_TRI, t))) return st;
  }
  return VM_OK;
}

int vm_gen_lens(vm_mesh *m, double R, double d, double h) {
  vm_ctx *ctx = m->ctx;
  if (!(R > 0) || !(d >= 0) || !(d < R) || !(h > 0) || !(R * acos(d / R) / h < 1e5))
    return vm_error(ctx, VM_ERR_ARG, "lens: R %g d %g h %g", R, d, h);
  int64_t nv0 = m->nv, ne0 = m->ne;
  double phim = acos(d / R);
  int nr = (int)ceil(R * phim / h);
  if (nr < 1) nr = 1;
  int *cnt = vm_alloc_array(ctx, (size_t)(nr + 1), sizeof *cnt);
  int32_t *start = vm_alloc_array(ctx, (size_t)(2 * nr + 1), sizeof *start);
  double *off = vm_alloc_array(ctx, (size_t)(2 * nr + 1), sizeof *off);
  int st = VM_OK;
  if (!cnt || !start || !off) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  for (int j = 1; j <= nr; j++) {
    double rj = R * sin(phim * j / nr);
    cnt[j] = (int)fmax(6, round(2 * M_PI * rj / h));
  }
  /* ring index r = 0..2nr-2: upper rings j = 1..nr then lower j = nr-1..1 */
  int nring = 2 * nr - 1;
  for (int r = 0; r < nring && !st; r++) {
    int j = r < nr ? r + 1 : 2 * nr - 1 - r;
    double sgn = r < nr ? 1 : -1;
    double phi = phim * j / nr, rr = R * sin(phi), z = j == nr ? 0.0 : sgn * (R * cos(phi) - d);
    off[r] = 0.5 * (j % 2);
    start[r] = (int32_t)m->nv;
    for (int i = 0; i < cnt[j] && !st; i++) {
      double th = 2 * M_PI * (i + off[r]) / cnt[j];
      st = vm_mesh_add_vertex(m, rr * cos(th), rr * sin(th), z, NULL);
    }
  }
  int64_t top = -1, bot = -1;
  if (!st) st = vm_mesh_add_vertex(m, 0, 0, R - d, &top);
  if (!st) st = vm_mesh_add_vertex(m, 0, 0, -(R - d), &bot);
  for (int i = 0; i < cnt[1] && !st; i++) { /* pole fans */
    st = add_tri(m, top, start[0] + i, start[0] + (i + 1) % cnt[1]);
    if (!st) st = add_tri(m, bot, start[nring - 1] + (i + 1) % cnt[1], start[nring - 1] + i);
  }
  for (int r = 0; r + 1 < nr && !st; r++) /* upper: ring r inside ring r+1 */
    st = stitch(m, start[r], cnt[r + 1], off[r], start[r + 1], cnt[r + 2], off[r + 1], 0);
  for (int r = nr; r < nring && !st; r++) { /* lower: ring r inside ring r-1 */
    int ja = 2 * nr - 1 - r, jb = ja + 1;
    st = stitch(m, start[r], cnt[ja], off[r], start[r - 1], cnt[jb], off[r - 1], 1);
  }
done:
  vm_free(ctx, cnt);
  vm_free(ctx, start);
  vm_free(ctx, off);
  return st ? rollback(m, nv0, ne0, st) : VM_OK;
}

int vm_gen_spindle(vm_mesh *m, int ns, double gap) {
  if (!m || ns < 3 || !(gap > 0 && gap < 0.2)) return VM_ERR_ARG;
  const double z[] = {-0.8, -0.6, -0.35, -0.1, 0, 0.2, 0.45, 0.45 + gap, 0.7, 0.85};
  const int nz = (int)(sizeof z / sizeof z[0]);
  int st = vm_mesh_set_vertices(m, 2 + (int64_t)nz * ns);
  if (st) return st;
  m->dim = 3;
  m->xyz[0] = 0, m->xyz[1] = 0, m->xyz[2] = -1;
  m->xyz[3] = 0, m->xyz[4] = 0, m->xyz[5] = 1;
  for (int k = 0; k < nz; k++)
    for (int s = 0; s < ns; s++) {
      double r = 0.5 * (1 - fabs(z[k])), a = 2 * M_PI * s / ns;
      double *p = m->xyz + 3 * (2 + (int64_t)k * ns + s);
      p[0] = r * cos(a), p[1] = r * sin(a), p[2] = z[k];
    }
  for (int s = 0; s < ns && !st; s++) {
    int32_t a = 2 + s, b = 2 + (s + 1) % ns;
    int32_t t[3] = {0, b, a};
    st = vm_mesh_add_element(m, VM_TRI, t);
    int32_t c = 2 + (nz - 1) * ns + s, d = 2 + (nz - 1) * ns + (s + 1) % ns;
    int32_t u[3] = {1, c, d};
    if (!st) st = vm_mesh_add_element(m, VM_TRI, u);
  }
  for (int k = 0; k + 1 < nz && !st; k++)
    for (int s = 0; s < ns && !st; s++) {
      int32_t a = 2 + k * ns + s, b = 2 + k * ns + (s + 1) % ns, c = a + ns, d = b + ns;
      int32_t t0[3] = {a, b, d}, t1[3] = {a, d, c};
      st = vm_mesh_add_element(m, VM_TRI, t0);
      if (!st) st = vm_mesh_add_element(m, VM_TRI, t1);
    }
  return st;
}
