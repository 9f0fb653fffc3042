/* volume/src/slip.c: slip boundary conditions of the volume stage: the
 * boundary surface of the input mesh becomes the reference surface of the
 * surface stage's closest-point projectors (CGAL AABB trees), its sharp
 * edges feature lines (vertices slide along them), its corners fixed.
 * A vertex off the features slides on its own patch (the faces it can
 * reach without crossing a sharp edge), never across a sharp edge onto
 * another face: while inverted elements are allowed (penalty untangling),
 * a projection onto the whole surface would let a face vertex jump onto
 * the neighbouring face and fold the elements at the edge flat.
 * Surface ids: 0..npatch-1 the patches, npatch + k - 1 feature line k. */
#include "varmesh/slip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/features.h"
#include "varmesh/quality.h"
#include "varmesh/project.h"
#include "varmesh/repair.h"
#include "varmesh/topology.h"

struct vm_volume_slip {
  vm_ctx *ctx;
  vm_surface_projector *proj; /* the whole surface and its feature lines */
  int32_t npatch;
  vm_surface_projector **patch; /* one per patch */
  int64_t nb;                   /* boundary vertices */
  int32_t *bvert;               /* their indices in the volume mesh */
};

void vm_volume_slip_destroy(vm_volume_slip **p) {
  if (!p || !*p) return;
  vm_volume_slip *s = *p;
  vm_surface_projector_destroy(&s->proj);
  for (int32_t k = 0; s->patch && k < s->npatch; k++) vm_surface_projector_destroy(&s->patch[k]);
  vm_free(s->ctx, s->patch);
  vm_free(s->ctx, s->bvert);
  vm_free(s->ctx, s);
  *p = NULL;
}

static int slip_project(void *user, int surf_id, const double p[3], double out[3],
                        double normals[9]) {
  vm_volume_slip *s = user;
  vm_surface_ops ops;
  if (surf_id < 0) return VM_ERR_ARG;
  if (surf_id < s->npatch) {
    ops = vm_surface_projector_ops(s->patch[surf_id]);
    return ops.project(ops.user, 0, p, out, normals);
  }
  ops = vm_surface_projector_ops(s->proj);
  return ops.project(ops.user, surf_id - s->npatch + 1, p, out, normals);
}

static int slip_project_hinted(void *user, int surf_id, const double p[3], int64_t *hint,
                               double out[3], double normals[9]) {
  vm_volume_slip *s = user;
  vm_surface_ops ops;
  if (surf_id < 0) return VM_ERR_ARG;
  if (surf_id < s->npatch) {
    ops = vm_surface_projector_ops(s->patch[surf_id]);
    return ops.project_hinted(ops.user, 0, p, hint, out, normals);
  }
  ops = vm_surface_projector_ops(s->proj);
  return ops.project_hinted(ops.user, surf_id - s->npatch + 1, p, hint, out, normals);
}

vm_surface_ops vm_volume_slip_ops(vm_volume_slip *s) {
  vm_surface_ops ops = {slip_project, s, slip_project_hinted, 1};
  return ops;
}

typedef struct {
  int32_t a, b, face;
} face_edge;

static int cmp_face_edge(const void *x, const void *y) {
  const face_edge *p = x, *q = y;
  if (p->a != q->a) return p->a < q->a ? -1 : 1;
  if (p->b != q->b) return p->b < q->b ? -1 : 1;
  return p->face < q->face ? -1 : p->face > q->face;
}

static int32_t uf_find(int32_t *par, int32_t x) {
  while (par[x] != x) x = par[x] = par[par[x]];
  return x;
}

/* The edges of the faces of b, once per face (smaller vertex first), into
 * fe (room for every face corner), sorted; with `only`, just the edges
 * whose two ends are marked in it. Their number. */
static int64_t face_edges(const vm_mesh *b, const uint8_t *only, face_edge *fe) {
  int64_t k = 0;
  for (int64_t e = 0; e < b->ne; e++) {
    int64_t o = b->eoff[e], n = b->eoff[e + 1] - o;
    for (int64_t i = 0; i < n; i++) {
      int32_t u = b->conn[o + i], w = b->conn[o + (i + 1) % n];
      if (only && (!only[u] || !only[w])) continue;
      fe[k].a = u < w ? u : w;
      fe[k].b = u < w ? w : u;
      fe[k].face = (int32_t)e;
      k++;
    }
  }
  qsort(fe, (size_t)k, sizeof *fe, cmp_face_edge);
  return k;
}

/* Patches of the surface b: faces connected across non-feature edges.
 * fpatch[face] in 0..*npatch-1 (numbered by their first face). */
static int find_patches(vm_ctx *ctx, const vm_mesh *b, const vm_surface_features *f,
                        int32_t *fpatch, int32_t *npatch) {
  int64_t nfe = b->eoff[b->ne];
  face_edge *fe = vm_alloc_array(ctx, (size_t)nfe + 1, sizeof *fe);
  face_edge *feat = vm_alloc_array(ctx, (size_t)f->nedge + 1, sizeof *feat);
  int32_t *par = vm_alloc_array(ctx, (size_t)b->ne + 1, sizeof *par);
  if (!fe || !feat || !par) {
    vm_free(ctx, fe);
    vm_free(ctx, feat);
    vm_free(ctx, par);
    return VM_ERR_NOMEM;
  }
  for (int64_t e = 0; e < b->ne; e++) par[e] = (int32_t)e;
  int64_t k = face_edges(b, NULL, fe);
  for (int64_t i = 0; i < f->nedge; i++) {
    int32_t u = f->edge[2 * i], w = f->edge[2 * i + 1];
    feat[i].a = u < w ? u : w;
    feat[i].b = u < w ? w : u;
    feat[i].face = 0;
  }
  qsort(feat, (size_t)f->nedge, sizeof *feat, cmp_face_edge);
  for (int64_t i = 0; i + 1 < k; i++) {
    if (fe[i].a != fe[i + 1].a || fe[i].b != fe[i + 1].b) continue;
    face_edge key = {fe[i].a, fe[i].b, 0};
    if (f->nedge && bsearch(&key, feat, (size_t)f->nedge, sizeof *feat, cmp_face_edge)) continue;
    int32_t x = uf_find(par, fe[i].face), y = uf_find(par, fe[i + 1].face);
    if (x != y) par[x > y ? x : y] = x < y ? x : y;
  }
  int32_t n = 0;
  for (int64_t e = 0; e < b->ne; e++) fpatch[e] = -1;
  for (int64_t e = 0; e < b->ne; e++) {
    int32_t r = uf_find(par, (int32_t)e);
    if (fpatch[r] < 0) fpatch[r] = n++;
    fpatch[e] = fpatch[r];
  }
  *npatch = n;
  vm_free(ctx, fe);
  vm_free(ctx, feat);
  vm_free(ctx, par);
  return VM_OK;
}

/* The unit normal of face e of the surface b at its corner v (the cross
 * product of the two edges there; zero if v is not a vertex of e or the
 * corner is degenerate). A fold inside a quad (a bow tie) shows as
 * opposite corner normals, where the face's mean normal hides it. */
static void corner_normal(const vm_mesh *b, int64_t e, int32_t v, double nrm[3]) {
  int64_t o = b->eoff[e], n = b->eoff[e + 1] - o;
  nrm[0] = nrm[1] = nrm[2] = 0;
  for (int64_t i = 0; i < n; i++) {
    if (b->conn[o + i] != v) continue;
    const double *p = b->xyz + 3 * (int64_t)v;
    const double *q = b->xyz + 3 * (int64_t)b->conn[o + (i + 1) % n];
    const double *r = b->xyz + 3 * (int64_t)b->conn[o + (i + n - 1) % n];
    double a[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    double c[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    nrm[0] = a[1] * c[2] - a[2] * c[1];
    nrm[1] = a[2] * c[0] - a[0] * c[2];
    nrm[2] = a[0] * c[1] - a[1] * c[0];
  }
  double l = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
  for (int k = 0; k < 3 && l > 0; k++) nrm[k] /= l;
}

/* Feature edges made by a fold, not by the shape: where the input's
 * boundary elements are tangled (vt[v]: surface vertex v belongs to a
 * volume element with a corner tet not positive), the boundary surface
 * folds back on itself and its faces meet at nearly 180 degrees. Edges with
 * both ends in such elements and a dihedral angle of at least
 * VM_SLIP_FOLD_DEG are dropped from f (rebuilt with corner_deg): otherwise the
 * fold's edges become feature lines and its turns fixed corners, and the
 * vertices that must move to unfold it cannot (the SOS-hex bunny of issue
 * 23: 183 such corners). So are the turns of a feature line by
 * VM_SLIP_FOLD_DEG or more at such vertices. *ndropped: how many edges and
 * turns. */
static int drop_fold_edges(vm_ctx *ctx, const vm_mesh *b, const uint8_t *vt, double corner_deg,
                           vm_surface_features *f, int64_t *ndropped) {
  *ndropped = 0;
  face_edge *fe = vm_alloc_array(ctx, (size_t)b->eoff[b->ne] + 1, sizeof *fe);
  int32_t *keep = vm_alloc_array(ctx, (size_t)f->nedge + 1, 2 * sizeof *keep);
  int32_t *deg = vm_calloc(ctx, (size_t)b->nv + 1, sizeof *deg);
  int32_t *nb2 = vm_alloc_array(ctx, (size_t)b->nv + 1, 2 * sizeof *nb2);
  uint8_t *corner = vm_calloc(ctx, (size_t)b->nv + 1, 1);
  int st = VM_OK;
  if (!fe || !keep || !deg || !nb2 || !corner) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  /* the folds: edges between tangled vertices whose two faces' corner
   * normals at the edge's ends turn by VM_SLIP_FOLD_DEG or more (kept in fe's
   * first nfold entries, sorted) */
  int64_t k = face_edges(b, vt, fe), nfold = 0;
  const double cthr = cos(VM_SLIP_FOLD_DEG * 3.14159265358979323846 / 180.0);
  for (int64_t i = 0; i + 1 < k; i++) {
    if (fe[i].a != fe[i + 1].a || fe[i].b != fe[i + 1].b) continue;
    double nn[4][3];
    corner_normal(b, fe[i].face, fe[i].a, nn[0]);
    corner_normal(b, fe[i].face, fe[i].b, nn[1]);
    corner_normal(b, fe[i + 1].face, fe[i].a, nn[2]);
    corner_normal(b, fe[i + 1].face, fe[i].b, nn[3]);
    int fold = 0;
    for (int x = 0; x < 2; x++)
      for (int y = 2; y < 4; y++)
        fold |= nn[x][0] * nn[y][0] + nn[x][1] * nn[y][1] + nn[x][2] * nn[y][2] <= cthr;
    if (fold) fe[nfold++] = (face_edge){fe[i].a, fe[i].b, 0};
  }
  int64_t nk = 0;
  for (int64_t i = 0; i < f->nedge; i++) {
    int32_t u = f->edge[2 * i], w = f->edge[2 * i + 1];
    face_edge key = {u < w ? u : w, u < w ? w : u, 0};
    if (nfold && bsearch(&key, fe, (size_t)nfold, sizeof *fe, cmp_face_edge)) continue;
    keep[2 * nk] = u;
    keep[2 * nk + 1] = w;
    nk++;
  }
  *ndropped = f->nedge - nk;
  /* a feature line folded back on itself (a vertex pushed along a sharp
   * edge past its neighbour) turns by nearly 180 degrees at tangled
   * vertices: those turns are not corners either; the corners are given
   * explicitly (every other turn beyond corner_deg) and the rebuild turns
   * none itself */
  for (int64_t i = 0; i < nk; i++)
    for (int j = 0; j < 2; j++) {
      int32_t v = keep[2 * i + j];
      if (deg[v] < 2) nb2[2 * v + deg[v]] = keep[2 * i + 1 - j];
      deg[v]++;
    }
  int64_t unturned = 0;
  for (int64_t v = 0; v < b->nv; v++) {
    if (deg[v] != 2) continue;
    double turn = vm_surface_turning_deg(b->xyz, (int32_t)v, nb2[2 * v], nb2[2 * v + 1]);
    if (!(turn > corner_deg)) continue;
    if (vt[v] && turn >= VM_SLIP_FOLD_DEG)
      unturned++;
    else
      corner[v] = 1;
  }
  *ndropped += unturned;
  if (*ndropped > 0) {
    vm_surface_features g;
    memset(&g, 0, sizeof g);
    if ((st = vm_surface_features_from_edges(b, nk, keep, corner, 180, &g)) < 0) goto done;
    vm_surface_features_free(ctx, f);
    *f = g;
  }
done:
  vm_free(ctx, fe);
  vm_free(ctx, keep);
  vm_free(ctx, deg);
  vm_free(ctx, nb2);
  vm_free(ctx, corner);
  return st;
}

/* Surface vertices (of b, bvert: their volume vertices) that belong to a
 * volume element of m with a corner tet not positive. */
static int tangled_vertices(vm_ctx *ctx, const vm_mesh *m, const int32_t *bvert, int64_t nb,
                            uint8_t **out, int64_t *ntangled) {
  *out = NULL;
  *ntangled = 0;
  double *sj = vm_alloc_array(ctx, (size_t)m->ne + 1, sizeof *sj);
  uint8_t *vt = vm_calloc(ctx, (size_t)m->nv + 1, 1), *bt = vm_calloc(ctx, (size_t)nb + 1, 1);
  int st = !sj || !vt || !bt ? VM_ERR_NOMEM : vm_mesh_element_quality(m, NULL, NULL, sj, NULL);
  if (st >= 0) {
    for (int64_t e = 0; e < m->ne; e++)
      if (!isnan(sj[e]) && sj[e] <= 0)
        for (int64_t i = m->eoff[e]; i < m->eoff[e + 1]; i++) vt[m->conn[i]] = 1;
    for (int64_t i = 0; i < nb; i++) *ntangled += bt[i] = vt[bvert[i]];
    *out = bt;
    bt = NULL;
  }
  vm_free(ctx, sj);
  vm_free(ctx, vt);
  vm_free(ctx, bt);
  return st;
}

/* The faces of patch p of b as a mesh of their own. */
static int patch_mesh(vm_ctx *ctx, const vm_mesh *b, const int32_t *fpatch, int32_t p, int32_t *g2l,
                      vm_mesh **out) {
  vm_mesh *pm = NULL;
  int st = vm_mesh_create(ctx, &pm);
  for (int64_t v = 0; v < b->nv; v++) g2l[v] = -1;
  for (int64_t e = 0; st >= 0 && e < b->ne; e++) {
    if (fpatch[e] != p) continue;
    int32_t q[4];
    int64_t o = b->eoff[e], n = b->eoff[e + 1] - o;
    for (int64_t i = 0; st >= 0 && i < n; i++) {
      int32_t v = b->conn[o + i];
      if (g2l[v] < 0) {
        int64_t idx = 0;
        st = vm_mesh_add_vertex(pm, b->xyz[3 * v], b->xyz[3 * v + 1], b->xyz[3 * v + 2], &idx);
        g2l[v] = (int32_t)idx;
      }
      q[i] = g2l[v];
    }
    if (st >= 0) st = vm_mesh_add_element(pm, b->etype[e], q);
  }
  if (st < 0) {
    vm_mesh_destroy(&pm);
    return st;
  }
  *out = pm;
  return VM_OK;
}

/* The boundary faces of m as a surface mesh on the boundary vertices only
 * (local numbering; g2l maps volume -> surface vertices, -1 elsewhere).
 * strict: faces shared by more than two elements are an error (else they
 * are not boundary faces and are left out). */
static int boundary_surface(vm_ctx *ctx, const vm_mesh *m, int strict, vm_mesh **bout,
                            int32_t **bvert, int64_t *nb, double *lift) {
  int64_t nface = 0, nonman = 0;
  int32_t *fv = NULL, *g2l = NULL, *bv = NULL;
  uint8_t *fnv = NULL;
  vm_mesh *b = NULL;
  int st = vm_mesh_boundary(m, &nface, &fv, &fnv, NULL, &nonman);
  if (st < 0) return st;
  if (nonman > 0 && strict) {
    st = vm_error(ctx, VM_ERR_ARG,
                  "slip boundary: %lld faces are shared by more than two "
                  "elements (non-manifold mesh)",
                  (long long)nonman);
    goto fail;
  }
  if (nface == 0) {
    st = vm_error(ctx, VM_ERR_ARG, "slip boundary: the mesh has no boundary faces");
    goto fail;
  }
  g2l = vm_alloc_array(ctx, (size_t)m->nv, sizeof *g2l);
  if (!g2l) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  for (int64_t v = 0; v < m->nv; v++) g2l[v] = -1;
  int64_t n = 0;
  for (int64_t f = 0; f < nface; f++)
    for (int k = 0; k < fnv[f]; k++)
      if (g2l[fv[4 * f + k]] < 0) g2l[fv[4 * f + k]] = (int32_t)n++;
  /* a planar mesh's boundary is edges: a wall standing on them, as high as
   * a hundredth of their extent, has the same distances in the plane (a
   * point of the plane is nearest a wall at the wall's foot) */
  int edges = fnv[0] == 2;
  if (edges && !lift) {
    st = vm_error(ctx, VM_ERR_ARG, "slip boundary: the mesh has no volume elements");
    goto fail;
  }
  int64_t nall = edges ? 2 * n : n;
  bv = vm_alloc_array(ctx, (size_t)nall, sizeof *bv);
  if (!bv || (st = vm_mesh_create(ctx, &b)) < 0 || (st = vm_mesh_set_vertices(b, nall)) < 0) {
    st = st < 0 ? st : VM_ERR_NOMEM;
    goto fail;
  }
  for (int64_t v = 0; v < m->nv; v++)
    if (g2l[v] >= 0) {
      bv[g2l[v]] = (int32_t)v;
      memcpy(b->xyz + 3 * g2l[v], m->xyz + 3 * v, 3 * sizeof(double));
    }
  if (lift) *lift = 0;
  if (edges) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = 0; i < n; i++)
      for (int k = 0; k < 3; k++) {
        lo[k] = fmin(lo[k], b->xyz[3 * i + k]);
        hi[k] = fmax(hi[k], b->xyz[3 * i + k]);
      }
    double h = hypot(hypot(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]) / 100;
    if (!(h > 0) || !isfinite(h)) h = 1;
    for (int64_t i = 0; i < n; i++) {
      bv[n + i] = bv[i];
      memcpy(b->xyz + 3 * (n + i), b->xyz + 3 * i, 3 * sizeof(double));
      b->xyz[3 * (n + i) + 2] += h;
    }
    *lift = h;
  }
  for (int64_t f = 0; f < nface; f++) {
    int32_t q[4];
    for (int k = 0; k < fnv[f]; k++) q[k] = g2l[fv[4 * f + k]];
    if (edges) {
      q[2] = (int32_t)(q[1] + n);
      q[3] = (int32_t)(q[0] + n);
    }
    if ((st = vm_mesh_add_element(b, fnv[f] == 3 ? VM_TRI : VM_QUAD, q)) < 0) goto fail;
  }
  vm_free(ctx, fv);
  vm_free(ctx, fnv);
  vm_free(ctx, g2l);
  *bout = b;
  *bvert = bv;
  *nb = nall;
  return VM_OK;
fail:
  vm_free(ctx, fv);
  vm_free(ctx, fnv);
  vm_free(ctx, g2l);
  vm_free(ctx, bv);
  vm_mesh_destroy(&b);
  return st;
}

int vm_volume_slip_create(vm_ctx *ctx, vm_mesh *m, double feature_deg, double corner_deg,
                          vm_volume_slip **out, vm_volume_slip_info *info) {
  if (!ctx || !m || !out) return VM_ERR_ARG;
  *out = NULL;
  if (!(feature_deg > 0 && feature_deg <= 180) || !(corner_deg > 0 && corner_deg <= 180))
    return vm_error(ctx, VM_ERR_ARG, "slip boundary: angles must lie in (0, 180] degrees");
  int64_t counts[VM_NTYPES];
  if (vm_mesh_count_types(m, counts) != 3)
    return vm_error(ctx, VM_ERR_ARG, "slip boundary: the mesh has no volume elements");
  vm_volume_slip *s = vm_calloc(ctx, 1, sizeof *s);
  if (!s) return VM_ERR_NOMEM;
  s->ctx = ctx;
  vm_mesh *b = NULL;
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  int32_t *vsurf = NULL, *fpatch = NULL, *vpatch = NULL;
  uint8_t *vt = NULL;
  int64_t ntangled = 0, nfold = 0;
  int st = boundary_surface(ctx, m, 1, &b, &s->bvert, &s->nb, NULL);
  if (st < 0) goto fail;
  if ((st = vm_surface_detect_features(b, feature_deg, corner_deg, &f)) < 0) goto fail;
  if ((st = tangled_vertices(ctx, m, s->bvert, s->nb, &vt, &ntangled)) < 0) goto fail;
  if (ntangled > 0 && (st = drop_fold_edges(ctx, b, vt, corner_deg, &f, &nfold)) < 0) goto fail;
  if ((st = vm_surface_projector_create(ctx, b, &f, &s->proj)) < 0) goto fail;
  vsurf = vm_alloc_array(ctx, (size_t)s->nb, sizeof *vsurf);
  fpatch = vm_alloc_array(ctx, (size_t)b->ne, sizeof *fpatch);
  vpatch = vm_alloc_array(ctx, (size_t)b->nv, sizeof *vpatch);
  if (!vsurf || !fpatch || !vpatch) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  if ((st = find_patches(ctx, b, &f, fpatch, &s->npatch)) < 0) goto fail;
  if (!(s->patch = vm_calloc(ctx, (size_t)s->npatch, sizeof *s->patch))) {
    st = VM_ERR_NOMEM;
    goto fail;
  }
  for (int32_t p = 0; p < s->npatch; p++) {
    vm_mesh *pm = NULL;
    if ((st = patch_mesh(ctx, b, fpatch, p, vpatch, &pm)) < 0) goto fail;
    st = vm_surface_projector_create(ctx, pm, NULL, &s->patch[p]);
    vm_mesh_destroy(&pm);
    if (st < 0) goto fail;
  }
  /* a vertex off the features lies in the patch of any of its faces */
  for (int64_t v = 0; v < b->nv; v++) vpatch[v] = -1;
  for (int64_t e = 0; e < b->ne; e++)
    for (int64_t i = b->eoff[e]; i < b->eoff[e + 1]; i++) vpatch[b->conn[i]] = fpatch[e];
  /* the reference is this very surface: feature vertices lie exactly on
   * their lines; the tolerance only absorbs rounding */
  double lo[3], hi[3], diag = vm_mesh_bounds(b, lo, hi);
  if ((st = vm_surface_projector_assign(s->proj, b, &f, 1e-9 * diag, vsurf)) < 0) goto fail;
  vm_volume_slip_info inf;
  memset(&inf, 0, sizeof inf);
  inf.nboundary = s->nb;
  inf.lines = f.nline;
  for (int64_t i = 0; i < s->nb; i++) {
    int32_t v = s->bvert[i];
    if (m->vflag[v] == VM_VERTEX_FIXED) {
      inf.nkept_fixed++;
    } else if (vsurf[i] < 0) {
      m->vflag[v] = VM_VERTEX_FIXED;
      m->vsurf[v] = -1;
      inf.ncorner++;
    } else {
      m->vflag[v] = VM_VERTEX_SLIP;
      m->vsurf[v] = vsurf[i] == 0 ? vpatch[i] : s->npatch + vsurf[i] - 1;
      if (vsurf[i] == 0)
        inf.nsurface++;
      else
        inf.nline++;
    }
  }
  inf.patches = s->npatch;
  inf.fold_edges = nfold;
  if (info) *info = inf;
  vm_free(ctx, vt);
  vm_free(ctx, vsurf);
  vm_free(ctx, fpatch);
  vm_free(ctx, vpatch);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&b);
  *out = s;
  return VM_OK;
fail:
  vm_free(ctx, vt);
  vm_free(ctx, vsurf);
  vm_free(ctx, fpatch);
  vm_free(ctx, vpatch);
  vm_surface_features_free(ctx, &f);
  vm_mesh_destroy(&b);
  vm_volume_slip_destroy(&s);
  return st;
}

int vm_volume_slip_distance(vm_volume_slip *s, const vm_mesh *m, double *maxdist) {
  if (!s || !m || !maxdist) return VM_ERR_ARG;
  double *pts = vm_alloc_array(s->ctx, (size_t)s->nb, 3 * sizeof(double));
  double *d = vm_alloc_array(s->ctx, (size_t)s->nb, sizeof(double));
  int st = VM_ERR_NOMEM;
  if (pts && d) {
    for (int64_t i = 0; i < s->nb; i++)
      memcpy(pts + 3 * i, m->xyz + 3 * (int64_t)s->bvert[i], 3 * sizeof(double));
    st = vm_surface_projector_distance(s->proj, s->nb, pts, d);
    if (st >= 0) {
      double mx = 0;
      for (int64_t i = 0; i < s->nb; i++) mx = fmax(mx, d[i]);
      *maxdist = mx;
    }
  }
  vm_free(s->ctx, pts);
  vm_free(s->ctx, d);
  return st;
}

struct vm_volume_shape {
  vm_ctx *ctx;
  vm_mesh *b;     /* the recorded boundary surface */
  int32_t *bvert; /* its vertices in the volume mesh */
  int64_t nb;
  double diag;
  double lift; /* a planar mesh: the height of the wall on its boundary edges */
};

void vm_volume_shape_destroy(vm_volume_shape **p) {
  if (!p || !*p) return;
  vm_volume_shape *s = *p;
  vm_mesh_destroy(&s->b);
  vm_free(s->ctx, s->bvert);
  vm_free(s->ctx, s);
  *p = NULL;
}

int vm_volume_shape_create(vm_ctx *ctx, const vm_mesh *m, vm_volume_shape **out) {
  if (!ctx || !m || !out) return VM_ERR_ARG;
  *out = NULL;
  vm_volume_shape *s = vm_calloc(ctx, 1, sizeof *s);
  if (!s) return VM_ERR_NOMEM;
  s->ctx = ctx;
  int st = boundary_surface(ctx, m, 0, &s->b, &s->bvert, &s->nb, &s->lift);
  if (st < 0) {
    vm_volume_shape_destroy(&s);
    return st;
  }
  double lo[3], hi[3];
  s->diag = vm_mesh_bounds(s->b, lo, hi);
  *out = s;
  return VM_OK;
}

int vm_volume_shape_deviation(vm_volume_shape *s, const vm_mesh *m, double *dist, double *diag,
                              double at[3]) {
  if (!s || !m) return VM_ERR_ARG;
  for (int64_t i = 0; i < s->nb; i++)
    if (s->bvert[i] >= m->nv) return vm_error(s->ctx, VM_ERR_ARG, "shape: not the recorded mesh");
  vm_mesh *now = NULL;
  int st = vm_mesh_clone(s->b, &now);
  if (st < 0) return st;
  for (int64_t i = 0; i < s->nb; i++) {
    memcpy(now->xyz + 3 * i, m->xyz + 3 * (int64_t)s->bvert[i], 3 * sizeof(double));
    if (s->lift > 0 && i >= s->nb / 2) now->xyz[3 * i + 2] += s->lift;
  }
  double ab = 0, ba = 0, ab_at[3] = {0, 0, 0}, ba_at[3] = {0, 0, 0};
  st = vm_surface_hausdorff_at(s->b, now, s->diag / 200, &ab, &ba, ab_at, ba_at);
  vm_mesh_destroy(&now);
  if (st < 0) return st;
  if (dist) *dist = fmax(ab, ba);
  if (diag) *diag = s->diag;
  if (at) memcpy(at, ab >= ba ? ab_at : ba_at, 3 * sizeof(double));
  return VM_OK;
}

/* Whether every edge of the surface b is shared by exactly two faces. */
static int surface_closed(vm_ctx *ctx, const vm_mesh *b, int *closed) {
  face_edge *fe = vm_alloc_array(ctx, (size_t)b->eoff[b->ne] + 1, sizeof *fe);
  if (!fe) return VM_ERR_NOMEM;
  int64_t k = face_edges(b, NULL, fe);
  int ok = k > 0;
  for (int64_t i = 0; i < k && ok;) {
    int64_t j = i;
    while (j < k && fe[j].a == fe[i].a && fe[j].b == fe[i].b) j++;
    ok = j - i == 2;
    i = j;
  }
  vm_free(ctx, fe);
  *closed = ok;
  return VM_OK;
}

int vm_volume_shape_fixed_outside(vm_volume_shape *s, const vm_mesh *m, int64_t *count,
                                  int64_t *first) {
  if (!s || !m || !count || !first) return VM_ERR_ARG;
  *count = 0;
  *first = -1;
  uint8_t *onb = vm_calloc(s->ctx, (size_t)m->nv + 1, 1);
  if (!onb) return VM_ERR_NOMEM;
  for (int64_t i = 0; i < s->nb; i++)
    if (s->bvert[i] < m->nv) onb[s->bvert[i]] = 1;
  int64_t n = 0;
  for (int64_t v = 0; v < m->nv; v++) n += !onb[v] && m->vflag[v] == VM_VERTEX_FIXED;
  int32_t *ids = NULL;
  double *pts = NULL;
  int8_t *in = NULL;
  int st = VM_OK, closed = 0;
  /* the inside of an open or non-manifold boundary is not defined */
  if (n == 0 || (st = surface_closed(s->ctx, s->b, &closed)) < 0 || !closed) goto done;
  ids = vm_alloc_array(s->ctx, (size_t)n, sizeof *ids);
  pts = vm_alloc_array(s->ctx, (size_t)n, 3 * sizeof *pts);
  in = vm_alloc_array(s->ctx, (size_t)n, sizeof *in);
  if (!ids || !pts || !in) {
    st = VM_ERR_NOMEM;
    goto done;
  }
  n = 0;
  for (int64_t v = 0; v < m->nv; v++)
    if (!onb[v] && m->vflag[v] == VM_VERTEX_FIXED) {
      ids[n] = (int32_t)v;
      memcpy(pts + 3 * n++, m->xyz + 3 * v, 3 * sizeof(double));
    }
  /* on the surface or within rounding of it (-1): not counted */
  if ((st = vm_surface_inside(s->b, n, pts, 1e-9 * s->diag, in)) < 0) goto done;
  for (int64_t i = 0; i < n; i++)
    if (in[i] == 0 && !(*count)++) *first = ids[i];
done:
  vm_free(s->ctx, in);
  vm_free(s->ctx, pts);
  vm_free(s->ctx, ids);
  vm_free(s->ctx, onb);
  return st;
}
