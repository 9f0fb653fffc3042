/* test/io_foam/foam_testlib.h: what the OpenFOAM writer's tests share:
 * conforming cube meshes of hexahedra, prisms, pyramids, tetrahedra or all
 * four, their boundary faces tagged and named, and a small reader of the
 * polyMesh files (ASCII and binary) that knows nothing of the writer. */
#ifndef VM_FOAM_TESTLIB_H
#define VM_FOAM_TESTLIB_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "varmesh/mesh.h"
#include "varmesh/topology.h"

enum { FT_HEX, FT_PRISM, FT_PYRAMID, FT_TET, FT_MIXED, FT_NKIND };
static const char *const ft_name[FT_NKIND] = {"hex", "prism", "pyramid", "tet", "mixed"};

/* How a cube of the lattice is cut: 0 a hexahedron, 1 two prisms (their
 * triangles on the cube's x faces, all along the same diagonal), 2 six
 * pyramids about an added centre vertex, some split into two tetrahedra.
 * The mixed mesh: cubes with k >= n/2 are cut into pyramids, those with
 * j = 0 below them into prisms, the others are hexahedra. */
static inline int ft_cube_cut(int kind, int n, int i, int j, int k) {
  (void)i;
  switch (kind) {
  case FT_HEX: return 0;
  case FT_PRISM: return 1;
  case FT_PYRAMID:
  case FT_TET: return 2;
  default: return k >= n / 2 ? 2 : j == 0 ? 1 : 0;
  }
}

/* sin(pi t) for t = i / n, exactly 0 at both ends */
static inline double ft_bump(int i, int n) {
  return i == 0 || i == n ? 0.0 : sin(3.14159265358979323846 * i / n);
}

/* The unit cube cut into n^3 cubes (n even), vertices moved by a smooth
 * wobble (relative to the cube size; 0: the lattice) that keeps each of
 * the six sides planar. Cells are conforming: a pyramid whose base faces a
 * cut cube or the boundary is split into two tetrahedra along the diagonal
 * through its base's lowest-numbered vertex (in FT_TET and FT_MIXED), so
 * that both sides of a face split it alike, and stays whole against a hex
 * or a prism. */
static vm_mesh *ft_cube(vm_ctx *ctx, int n, int kind, double wobble) {
  vm_mesh *m;
  if (vm_mesh_create(ctx, &m)) return NULL;
  int np = n + 1;
  double a = wobble / n;
  for (int k = 0; k < np; k++)
    for (int j = 0; j < np; j++)
      for (int i = 0; i < np; i++) {
        double u = (double)i / n, v = (double)j / n, w = (double)k / n;
        vm_mesh_add_vertex(m, u + a * ft_bump(i, n) * cos(2 * v + 0.3) * cos(3 * w + 0.7),
                           v + a * ft_bump(j, n) * cos(2 * w + 0.1) * cos(3 * u + 0.5),
                           w + a * ft_bump(k, n) * cos(2 * u + 0.2) * cos(3 * v + 0.4), NULL);
      }
#define FT_V(i, j, k) ((int32_t)(((k)*np + (j)) * np + (i)))
  int hf[6][4], hnv[6];
  vm_elem_faces(VM_HEX, hf, hnv);
  static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (int k = 0; k < n; k++)
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        int32_t c[8];
        for (int q = 0; q < 8; q++) c[q] = FT_V(i + off[q][0], j + off[q][1], k + off[q][2]);
        int cut = ft_cube_cut(kind, n, i, j, k);
        if (cut == 0) {
          vm_mesh_add_element(m, VM_HEX, c);
        } else if (cut == 1) {
          int32_t p1[6] = {FT_V(i, j, k),     FT_V(i, j + 1, k),     FT_V(i, j + 1, k + 1),
                           FT_V(i + 1, j, k), FT_V(i + 1, j + 1, k), FT_V(i + 1, j + 1, k + 1)};
          int32_t p2[6] = {FT_V(i, j, k),     FT_V(i, j + 1, k + 1),     FT_V(i, j, k + 1),
                           FT_V(i + 1, j, k), FT_V(i + 1, j + 1, k + 1), FT_V(i + 1, j, k + 1)};
          vm_mesh_add_element(m, VM_PRISM, p1);
          vm_mesh_add_element(m, VM_PRISM, p2);
        } else {
          double x[3] = {0, 0, 0};
          for (int q = 0; q < 8; q++)
            for (int d = 0; d < 3; d++) x[d] += m->xyz[3 * c[q] + d] / 8;
          int64_t ci;
          vm_mesh_add_vertex(m, x[0], x[1], x[2], &ci);
          for (int f = 0; f < 6; f++) {
            int32_t q[4];
            int dir[3] = {0, 0, 0}; /* the neighbour across face f */
            for (int d = 0; d < 3; d++) {
              int s = 0;
              for (int t = 0; t < 4; t++) s += off[hf[f][t]][d];
              dir[d] = s == 0 ? -1 : s == 4 ? 1 : 0;
            }
            int ni = i + dir[0], nj = j + dir[1], nk = k + dir[2];
            int outside = ni < 0 || nj < 0 || nk < 0 || ni >= n || nj >= n || nk >= n;
            int split = (kind == FT_TET || kind == FT_MIXED) &&
                        (outside || ft_cube_cut(kind, n, ni, nj, nk) == 2);
            for (int t = 0; t < 4; t++) q[t] = c[hf[f][t]];
            if (!split) {
              int32_t py[5] = {q[0], q[3], q[2], q[1], (int32_t)ci};
              vm_mesh_add_element(m, VM_PYRAMID, py);
              continue;
            }
            int lo = 0;
            for (int t = 1; t < 4; t++)
              if (q[t] < q[lo]) lo = t;
            int32_t a0 = q[lo], a1 = q[(lo + 1) % 4], a2 = q[(lo + 2) % 4], a3 = q[(lo + 3) % 4];
            int32_t t1[4] = {a0, a2, a1, (int32_t)ci}, t2[4] = {a0, a3, a2, (int32_t)ci};
            vm_mesh_add_element(m, VM_TET, t1);
            vm_mesh_add_element(m, VM_TET, t2);
          }
        }
      }
#undef FT_V
  return m;
}

/* Tags of the cube's sides (0: no boundary element there). */
enum { FT_WALL = 1, FT_FARFIELD = 2, FT_SYMMETRY = 3, FT_OUTER = 4 };
static const char *const ft_tag_name[5] = {NULL, "wall", "farfield", "symmetry", "outer"};

static inline int ft_side_tag(const vm_mesh *m, const int32_t *v, int nv) {
  int all[6] = {1, 1, 1, 1, 1, 1};
  for (int t = 0; t < nv; t++) {
    const double *x = m->xyz + 3 * (int64_t)v[t];
    all[0] &= x[2] == 0.0;
    all[1] &= x[0] == 1.0;
    all[2] &= x[1] == 0.0;
    all[3] &= x[2] == 1.0;
  }
  return all[0] ? FT_WALL : all[1] ? FT_FARFIELD : all[2] ? FT_SYMMETRY : all[3] ? FT_OUTER : 0;
}

/* Boundary triangles and quads on four sides of the cube: z = 0 "wall",
 * x = 1 "farfield", y = 0 "symmetry", z = 1 "outer" (the sides x = 0 and
 * y = 1 get none); every other one listed with its vertices reversed
 * (pointing into the domain), which the writer must not follow. Adds the
 * field "gmsh:physical" and the names. Returns the number of faces added. */
static inline int64_t ft_tag_boundary(vm_mesh *m) {
  int64_t nf = 0;
  int32_t *fv = NULL;
  uint8_t *fnv = NULL;
  if (vm_mesh_boundary(m, &nf, &fv, &fnv, NULL, NULL)) return -1;
  int64_t ne0 = m->ne, added = 0;
  int32_t *tags = malloc(sizeof *tags * (size_t)(nf + 1));
  for (int64_t f = 0; f < nf; f++) {
    int32_t *v = fv + 4 * f;
    int tg = ft_side_tag(m, v, fnv[f]);
    if (!tg) continue;
    int32_t w[4];
    for (int t = 0; t < fnv[f]; t++) w[t] = (added % 2) ? v[(fnv[f] - t) % fnv[f]] : v[t];
    vm_mesh_add_element(m, fnv[f] == 3 ? VM_TRI : VM_QUAD, w);
    tags[added++] = tg;
  }
  vm_field *ph;
  vm_mesh_add_field(m, "gmsh:physical", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &ph);
  for (int64_t e = 0; e < added; e++) ((int32_t *)ph->data)[ne0 + e] = tags[e];
  for (int t = 1; t <= 4; t++) {
    char key[64];
    snprintf(key, sizeof key, "gmsh:physical_name:2:%d", t);
    vm_mesh_set_attr(m, key, ft_tag_name[t]);
  }
  free(tags);
  vm_free(m->ctx, fv);
  vm_free(m->ctx, fnv);
  return added;
}

/* The reader. */

typedef struct {
  char name[128], type[64], groups[128];
  long long nfaces, start;
} ft_patch;

typedef struct {
  long long npoint, nface, nown, nnbr;
  double *pts;     /* 3 per point */
  long long *fofs; /* nface + 1 offsets into fpts */
  long long *fpts; /* points of every face */
  long long *own, *nbr;
  int npatch;
  ft_patch patch[32];
  int binary[5];  /* format of points, faces, owner, neighbour, boundary */
  char note[256]; /* owner's note */
  char err[600];
} ft_case;

typedef struct {
  const char *s;
  size_t n, p;
  int binary;
  char cls[64], note[256];
} ft_scan;

static inline void ft_skip(ft_scan *f) {
  for (;;) {
    while (f->p < f->n && strchr(" \t\r\n", f->s[f->p])) f->p++;
    if (f->p + 1 < f->n && f->s[f->p] == '/' && f->s[f->p + 1] == '/') {
      while (f->p < f->n && f->s[f->p] != '\n') f->p++;
    } else if (f->p + 1 < f->n && f->s[f->p] == '/' && f->s[f->p + 1] == '*') {
      const char *e = strstr(f->s + f->p + 2, "*/");
      f->p = e ? (size_t)(e - f->s) + 2 : f->n;
    } else {
      return;
    }
  }
}

/* A word (up to a blank or one of ;{}()) into w; 0 if there is none. */
static inline int ft_word(ft_scan *f, char *w, size_t cap) {
  ft_skip(f);
  size_t k = 0;
  while (f->p < f->n && !strchr(" \t\r\n;{}()", f->s[f->p])) {
    if (k + 1 < cap) w[k++] = f->s[f->p];
    f->p++;
  }
  w[k] = 0;
  return k > 0;
}

static inline int ft_char(ft_scan *f, char c) {
  ft_skip(f);
  if (f->p < f->n && f->s[f->p] == c) {
    f->p++;
    return 1;
  }
  return 0;
}

static inline int ft_int(ft_scan *f, long long *v) {
  char w[64], *e;
  if (!ft_word(f, w, sizeof w)) return 0;
  *v = strtoll(w, &e, 10);
  return !*e;
}

/* The rest of an entry up to ';' (consumed) into w. */
static inline void ft_rest(ft_scan *f, char *w, size_t cap) {
  ft_skip(f);
  size_t k = 0;
  while (f->p < f->n && f->s[f->p] != ';') {
    if (k + 1 < cap) w[k++] = f->s[f->p];
    f->p++;
  }
  while (k && strchr(" \t", w[k - 1])) k--;
  w[k] = 0;
  if (k >= 2 && w[0] == '"' && w[k - 1] == '"') {
    memmove(w, w + 1, k - 2);
    w[k - 2] = 0;
  }
  if (f->p < f->n) f->p++;
}

/* FoamFile { ... }: format, class, note; 0 if malformed. */
static inline int ft_header(ft_scan *f) {
  char w[256];
  if (!ft_word(f, w, sizeof w) || strcmp(w, "FoamFile") || !ft_char(f, '{')) return 0;
  f->binary = -1;
  while (!ft_char(f, '}')) {
    char v[256];
    if (!ft_word(f, w, sizeof w)) return 0;
    ft_rest(f, v, sizeof v);
    if (!strcmp(w, "format")) f->binary = !strcmp(v, "binary") ? 1 : !strcmp(v, "ascii") ? 0 : -1;
    if (!strcmp(w, "class")) snprintf(f->cls, sizeof f->cls, "%.60s", v);
    if (!strcmp(w, "note")) snprintf(f->note, sizeof f->note, "%.250s", v);
  }
  return f->binary >= 0;
}

/* A list of n labels: ASCII "n ( a b ... )" or binary "n (raw)", binary
 * empty lists as "n" alone. */
static long long *ft_labels(ft_scan *f, long long *n) {
  if (!ft_int(f, n) || *n < 0) return NULL;
  long long *v = malloc(sizeof *v * (size_t)(*n + 1));
  if (f->binary) {
    if (!*n) return v;
    if (!ft_char(f, '(') || f->p + 4 * (size_t)*n >= f->n) goto bad;
    for (long long i = 0; i < *n; i++) {
      int32_t x;
      memcpy(&x, f->s + f->p + 4 * i, 4);
      v[i] = x;
    }
    f->p += 4 * (size_t)*n;
    if (f->s[f->p++] != ')') goto bad;
    return v;
  }
  if (!ft_char(f, '(')) goto bad;
  for (long long i = 0; i < *n; i++)
    if (!ft_int(f, &v[i])) goto bad;
  if (!ft_char(f, ')')) goto bad;
  return v;
bad:
  free(v);
  return NULL;
}

static char *ft_slurp(const char *path, size_t *len) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  size_t got = fread(s, 1, (size_t)n, fp);
  fclose(fp);
  s[got] = 0;
  *len = got;
  return s;
}

static inline void ft_case_free(ft_case *c) {
  free(c->pts);
  free(c->fofs);
  free(c->fpts);
  free(c->own);
  free(c->nbr);
  memset(c, 0, sizeof *c);
}

/* Read dir/constant/polyMesh; 0 and c->err set on failure. */
static inline int ft_read(const char *dir, ft_case *c) {
  static const char *const obj[5] = {"points", "faces", "owner", "neighbour", "boundary"};
  memset(c, 0, sizeof *c);
  for (int o = 0; o < 5; o++) {
    char path[400];
    snprintf(path, sizeof path, "%.300s/constant/polyMesh/%s", dir, obj[o]);
    size_t len = 0;
    char *s = ft_slurp(path, &len);
    ft_scan f = {s, len, 0, 0, "", ""};
    int ok = s && ft_header(&f);
    c->binary[o] = f.binary;
    if (ok && o == 0) {
      ok = !strcmp(f.cls, "vectorField") && ft_int(&f, &c->npoint) && c->npoint >= 0;
      c->pts = ok ? malloc(sizeof(double) * 3 * (size_t)(c->npoint + 1)) : NULL;
      if (ok && f.binary && c->npoint) {
        ok = ft_char(&f, '(') && f.p + 24 * (size_t)c->npoint < f.n;
        if (ok) memcpy(c->pts, f.s + f.p, 24 * (size_t)c->npoint);
        f.p += 24 * (size_t)c->npoint;
        ok = ok && f.s[f.p++] == ')';
      } else if (ok && !f.binary) {
        ok = ft_char(&f, '(');
        for (long long i = 0; ok && i < c->npoint; i++) {
          char w[64];
          ok = ft_char(&f, '(');
          for (int d = 0; ok && d < 3; d++) {
            char *e;
            ok = ft_word(&f, w, sizeof w);
            c->pts[3 * i + d] = strtod(w, &e);
            ok = ok && !*e;
          }
          ok = ok && ft_char(&f, ')');
        }
        ok = ok && ft_char(&f, ')');
      }
    } else if (ok && o == 1 && f.binary) {
      long long n1, n2;
      ok = !strcmp(f.cls, "faceCompactList") && (c->fofs = ft_labels(&f, &n1)) &&
           (c->fpts = ft_labels(&f, &n2));
      c->nface = ok ? n1 - 1 : 0;
      ok = ok && n1 >= 1 && c->fofs[0] == 0 && c->fofs[n1 - 1] == n2;
    } else if (ok && o == 1) {
      ok = !strcmp(f.cls, "faceList") && ft_int(&f, &c->nface) && ft_char(&f, '(');
      c->fofs = ok ? malloc(sizeof(long long) * (size_t)(c->nface + 1)) : NULL;
      c->fpts = ok ? malloc(sizeof(long long) * (size_t)(4 * c->nface + 1)) : NULL;
      long long tot = 0;
      if (ok) c->fofs[0] = 0;
      for (long long i = 0; ok && i < c->nface; i++) {
        long long k;
        ok = ft_int(&f, &k) && k >= 3 && k <= 4 && ft_char(&f, '(');
        for (long long j = 0; ok && j < k; j++) ok = ft_int(&f, &c->fpts[tot++]);
        ok = ok && ft_char(&f, ')');
        c->fofs[i + 1] = tot;
      }
      ok = ok && ft_char(&f, ')');
    } else if (ok && o == 2) {
      ok = !strcmp(f.cls, "labelList") && (c->own = ft_labels(&f, &c->nown));
      snprintf(c->note, sizeof c->note, "%s", f.note);
    } else if (ok && o == 3) {
      ok = !strcmp(f.cls, "labelList") && (c->nbr = ft_labels(&f, &c->nnbr));
    } else if (ok) {
      long long np;
      ok = !strcmp(f.cls, "polyBoundaryMesh") && ft_int(&f, &np) && np >= 0 && np <= 32 &&
           ft_char(&f, '(');
      c->npatch = ok ? (int)np : 0;
      for (int p = 0; ok && p < c->npatch; p++) {
        ft_patch *q = &c->patch[p];
        char w[256];
        ok = ft_word(&f, q->name, sizeof q->name) && ft_char(&f, '{');
        q->nfaces = q->start = -1;
        while (ok && !ft_char(&f, '}')) {
          char v[256];
          ok = ft_word(&f, w, sizeof w);
          ft_rest(&f, v, sizeof v);
          if (!strcmp(w, "type")) snprintf(q->type, sizeof q->type, "%.60s", v);
          if (!strcmp(w, "inGroups")) snprintf(q->groups, sizeof q->groups, "%.120s", v);
          if (!strcmp(w, "nFaces")) q->nfaces = atoll(v);
          if (!strcmp(w, "startFace")) q->start = atoll(v);
        }
      }
      ok = ok && ft_char(&f, ')');
    }
    /* nothing but comments after the list */
    if (ok) ft_skip(&f);
    ok = ok && f.p == f.n;
    free(s);
    if (!ok) {
      snprintf(c->err, sizeof c->err, "%s: cannot parse (near byte %zu)", path, f.p);
      return 0;
    }
  }
  return 1;
}

/* rm -r (for the tests' temporary directories) */
static inline void ft_rmtree(const char *path) {
  struct stat st;
  if (lstat(path, &st) != 0) return;
  if (S_ISDIR(st.st_mode)) {
    DIR *d = opendir(path);
    struct dirent *e;
    while (d && (e = readdir(d))) {
      if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
      char sub[4096];
      snprintf(sub, sizeof sub, "%.3800s/%.255s", path, e->d_name);
      ft_rmtree(sub);
    }
    if (d) closedir(d);
    rmdir(path);
  } else {
    unlink(path);
  }
}

#endif
