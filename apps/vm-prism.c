/* apps/vm-prism.c: the prism stage: a closed triangulated wall (a .vmsh
 * from vm-surface, or STL/OBJ/OFF/PLY directly) in, a thick, valid,
 * multi-layer prismatic mesh out (Section 6.2 of the paper). */
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "cli_report.h"
#include "cli_verify.h"
#include "varmesh/cleanup.h"
#include "varmesh/io.h"
#include "varmesh/quadrature.h"
#include "varmesh/prism.h"
#include "varmesh/repair.h"
#include "varmesh/surface.h"

typedef struct {
  vm_cli *cli;
  int last_phase;
  vm_report_history *hist; /* --report: every solver iteration and cutting round */
  int total;               /* samples so far (the history's x axis) */
  double F;                /* the last functional, carried through cutting rounds */
  const char *in;          /* the run's first line, once the wall is accepted */
  const vm_mesh *m;
  double L;
  const vm_prism_opts *o;
} progress_state;

/* The run's first line, before its first progress (or error) line: the
 * wall was accepted. */
static void announce(progress_state *ps) {
  if (!ps->in) return;
  if (!ps->cli->quiet)
    fprintf(stderr, "vm-prism: %s: %lld wall triangles, model length %g, thickness %g, %d layers\n",
            ps->in, (long long)ps->m->ne, ps->L, ps->o->thickness, ps->o->nlayers);
  ps->in = NULL;
}

static void progress(void *user, const vm_prism_progress *p) {
  progress_state *ps = user;
  announce(ps);
  if (ps->hist) {
    /* M: intersecting pairs while cutting (the barrier keeps every prism
     * valid, so 0 elsewhere) */
    if (p->solver) ps->F = p->value;
    if (p->solver || p->phase == VM_PRISM_PHASE_CUT)
      vm_report_history_add(ps->hist, vm_prism_phase_name(p->phase), ++ps->total, ps->F,
                            p->phase == VM_PRISM_PHASE_CUT && !p->solver ? (int64_t)p->value : 0,
                            NAN);
  }
  if (ps->cli->quiet) return;
  /* a solve's iterations every 10th; the phases' own steps (cutting
   * rounds, marching's layers) each, the others every 10th */
  static const char *const what[] = {"height", "F", "pairs", "mean t/T", "height"};
  int first = (int)p->phase != ps->last_phase;
  if (p->solver) {
    if (first || p->step % 10 == 0) {
      fprintf(stderr, "%-10s %5d  %-8s %.6g  ", vm_prism_phase_name(p->phase), p->step, "F",
              p->value);
      if (p->count >= 0) fprintf(stderr, "inverted %lld  ", (long long)p->count);
      fprintf(stderr, "%7.2fs\n", p->elapsed);
    }
  } else if (first || p->phase == VM_PRISM_PHASE_CUT || p->phase == VM_PRISM_PHASE_MARCH ||
             p->step % 10 == 0) {
    fprintf(stderr, "%-10s %5d  %-8s %.6g  %7.2fs\n", vm_prism_phase_name(p->phase), p->step,
            what[p->phase], p->value, p->elapsed);
  }
  ps->last_phase = (int)p->phase;
}

/* The wall's field f added to the prism mesh r (*g, and its row size in
 * bytes), unless the prism stage writes a field of that name itself: then
 * 0, said on stderr. < 0: out of memory. */
static int carry_field(vm_cli *cli, const vm_field *f, vm_mesh *r, vm_field **g, size_t *row) {
  if (vm_mesh_find_field(r, f->name, f->location)) {
    if (!cli->quiet)
      fprintf(stderr,
              "vm-prism: warning: the wall's %s field '%s' is not carried up the columns: the "
              "prism stage writes its own\n",
              f->location == VM_FIELD_VERTEX ? "vertex" : "element", f->name);
    return 0;
  }
  int st = vm_mesh_add_field(r, f->name, f->location, f->type, f->ncomp, g);
  if (st < 0) return st;
  *row = (f->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t)) * (size_t)f->ncomp;
  return 1;
}

/* Copy the vertex fields of the wall mesh w onto the prism mesh r, whose
 * vertex k*nw + l is level k of the column on the l-th wall vertex used by
 * a triangle or quad of w (in w's order, as vm_prism_create numbers them):
 * the column takes its wall vertex's value; a 'fixed' field only on the
 * wall itself. Fields the prism stage writes itself win. */
static int pass_wall_fields(vm_cli *cli, const vm_mesh *w, vm_mesh *r, int64_t nw) {
  /* where layers end, the result names each vertex's column */
  const vm_field *colf = vm_mesh_find_field(r, VM_PRISM_FIELD_COLUMN, VM_FIELD_VERTEX);
  const int32_t *col = colf ? colf->data : NULL;
  if (nw <= 0 || (!col && r->nv % nw)) return VM_OK;
  int64_t nlev = r->nv / nw, n = 0;
  int32_t *src = vm_alloc_array(w->ctx, (size_t)nw, sizeof *src);
  uint8_t *used = vm_calloc(w->ctx, (size_t)w->nv + 1, 1);
  int st = (!src || !used) ? VM_ERR_NOMEM : VM_OK;
  for (int64_t e = 0; st == VM_OK && e < w->ne; e++)
    if (w->etype[e] == VM_TRI || w->etype[e] == VM_QUAD)
      for (int64_t k = w->eoff[e]; k < w->eoff[e + 1]; k++) used[w->conn[k]] = 1;
  for (int64_t v = 0; st == VM_OK && v < w->nv; v++)
    if (used[v]) {
      if (n == nw) break;
      src[n++] = (int32_t)v;
    }
  if (n != nw) st = VM_OK; /* not the numbering expected: pass nothing */
  for (int i = 0; st == VM_OK && n == nw && i < w->nfield; i++) {
    const vm_field *f = &w->fields[i];
    if (f->location != VM_FIELD_VERTEX) continue;
    vm_field *g;
    size_t row;
    int c = carry_field(cli, f, r, &g, &row);
    if (c < 0) st = c;
    if (c <= 0) continue;
    int fixed = !strcmp(f->name, "fixed");
    if (col) {
      /* a 'fixed' field on the wall only: the wall's vertices are the
       * first nw */
      for (int64_t x = 0; x < (fixed ? nw : r->nv); x++)
        memcpy((char *)g->data + (size_t)x * row, (const char *)f->data + (size_t)src[col[x]] * row,
               row);
      continue;
    }
    int64_t levels = fixed ? 1 : nlev;
    for (int64_t k = 0; k < levels; k++)
      for (int64_t l = 0; l < nw; l++)
        memcpy((char *)g->data + (size_t)(k * nw + l) * row,
               (const char *)f->data + (size_t)src[l] * row, row);
  }
  vm_free(w->ctx, src);
  vm_free(w->ctx, used);
  return st;
}

/* Copy the element fields of the wall w onto the prism mesh r: the wall's
 * triangles (quads as two, in w's element order, as vm_prism_create splits
 * them) are r's nt columns; every prism of column t, and its wall and outer
 * faces, take the value of the wall element t came from. Fields the prism
 * stage writes itself win (said on stderr). */
static int pass_wall_element_fields(vm_cli *cli, const vm_mesh *w, vm_mesh *r, int64_t nt) {
  int nel = 0;
  for (int i = 0; i < w->nfield; i++) nel += w->fields[i].location == VM_FIELD_ELEMENT;
  /* where layers end, the result names each element's wall face */
  const vm_field *wff = vm_mesh_find_field(r, VM_PRISM_FIELD_WALL_FACE, VM_FIELD_ELEMENT);
  const int32_t *wf = wff ? wff->data : NULL;
  if (!nel || nt <= 0 || (!wf && (r->ne % nt || r->ne / nt < 3))) return VM_OK;
  int32_t *src = vm_alloc_array(w->ctx, (size_t)nt, sizeof *src);
  if (!src) return vm_error(cli->ctx, VM_ERR_NOMEM, "out of memory");
  int64_t n = 0;
  for (int64_t e = 0; e < w->ne && n <= nt; e++) {
    int k = w->etype[e] == VM_TRI ? 1 : w->etype[e] == VM_QUAD ? 2 : 0;
    for (int i = 0; i < k && n < nt; i++) src[n++] = (int32_t)e;
  }
  int st = VM_OK;
  for (int i = 0; st == VM_OK && n == nt && i < w->nfield; i++) {
    const vm_field *f = &w->fields[i];
    if (f->location != VM_FIELD_ELEMENT) continue;
    vm_field *g;
    size_t row;
    int c = carry_field(cli, f, r, &g, &row);
    if (c < 0) st = c;
    if (c <= 0) continue;
    for (int64_t e = 0; e < r->ne; e++)
      memcpy((char *)g->data + (size_t)e * row,
             (const char *)f->data + (size_t)src[wf ? wf[e] : e % nt] * row, row);
  }
  vm_free(w->ctx, src);
  return st;
}

/* vm-surface's check of the wall for self-intersections (CGAL, exact
 * predicates), before anything is built: a wall crossing itself cannot
 * carry valid layers, and the cutting would spend minutes finding that
 * out. The wall's triangles (quads split as vm_prism_create splits them);
 * a wall that is not a manifold triangle surface is left to the stage's
 * own checks. Returns the exit code; with npairs, a wall that intersects
 * itself is not an error: the count goes to *npairs (the caller sends the
 * wall through the surface stage, whose repair unites overlapping parts and
 * heals a part that crosses itself, or refuses it). */
static int check_wall_intersections(vm_cli *cli, const char *in, const vm_mesh *w,
                                    int64_t *npairs) {
  vm_mesh *t = NULL;
  int64_t nt = 0, count = 0;
  int32_t *pairs = NULL;
  for (int64_t e = 0; e < w->ne; e++)
    nt += w->etype[e] == VM_TRI ? 1 : w->etype[e] == VM_QUAD ? 2 : 0;
  int64_t *from = vm_alloc_array(cli->ctx, (size_t)(nt ? nt : 1), sizeof *from);
  int st = from ? vm_mesh_create(cli->ctx, &t) : VM_ERR_NOMEM;
  if (st == VM_OK && !(st = vm_mesh_set_vertices(t, w->nv)) &&
      !(st = vm_mesh_set_elements(t, nt, 3 * nt))) {
    t->dim = 3;
    memcpy(t->xyz, w->xyz, (size_t)(3 * w->nv) * sizeof *t->xyz);
    int64_t k = 0;
    for (int64_t e = 0; e < w->ne; e++) {
      const int32_t *c = w->conn + w->eoff[e];
      static const int sp[2][3] = {{0, 1, 2}, {0, 2, 3}};
      int ns = w->etype[e] == VM_TRI ? 1 : w->etype[e] == VM_QUAD ? 2 : 0;
      for (int s = 0; s < ns; s++, k++) {
        t->etype[k] = VM_TRI;
        t->eoff[k + 1] = 3 * (k + 1);
        for (int i = 0; i < 3; i++) t->conn[3 * k + i] = c[sp[s][i]];
        from[k] = e;
      }
    }
    st = vm_surface_self_intersections(t, &count, &pairs);
  }
  int rc = VM_EXIT_OK;
  if (st == VM_ERR_NOMEM) {
    rc = vm_cli_input_error(cli, NULL);
  } else if (st == VM_OK && count > 0 && npairs) {
    *npairs = count; /* the caller sends the wall through the surface stage */
  } else if (st == VM_OK && count > 0) {
    double c[3] = {0, 0, 0};
    const int32_t *tri = t->conn + 3 * (int64_t)pairs[0];
    for (int i = 0; i < 3; i++)
      for (int d = 0; d < 3; d++) c[d] += t->xyz[3 * (int64_t)tri[i] + d] / 3;
    vm_cli_error(cli,
                 "%s: the wall intersects itself: %lld pairs of triangles intersect, e.g. "
                 "elements %lld and %lld near (%g, %g, %g); repair it first (vm-surface)",
                 in, (long long)count, (long long)from[pairs[0]], (long long)from[pairs[1]], c[0],
                 c[1], c[2]);
    rc = VM_EXIT_INPUT;
  }
  vm_free(cli->ctx, pairs);
  vm_free(cli->ctx, from);
  vm_mesh_destroy(&t);
  return rc;
}

typedef struct {
  const char *in, *out, *report;
  const char *region;        /* --region-thickness FIELD:ID=X,... */
  const char *region_layers; /* --region-layers FIELD:ID=N,... */
  const char *symmetry;      /* --symmetry auto | none | AXIS=VALUE */
  double T_abs, T_rel;
  double yplus, reynolds, ref_length; /* --yplus: the first height by the flat plate */
  int growth_given;                   /* --growth given (else solved for a first height) */
  double min_reach;                   /* --min-reach: percent, 0: never an exit for it */
  int keep_wall;                      /* --keep-wall: no surface stage on a wall with needles */
  int json, fout;
  vm_prism_opts o;
  vm_write_opts wo;
} args;

/* --growth R: as given (without it, a first height solves for the ratio). */
static int opt_growth(vm_cli *cli, const vm_opt *opt, const char *value, void *p) {
  args *a = p;
  if (vm_cli_double(cli, opt->name, value, 1, 10, &a->o.growth)) return VM_EXIT_USAGE;
  a->growth_given = 1;
  return VM_EXIT_OK;
}

/* -t: the thickness relative to the model's length (it overrides -T). */
static int opt_thickness_rel(vm_cli *cli, const vm_opt *opt, const char *value, void *p) {
  args *a = p;
  if (vm_cli_double(cli, opt->name, value, 1e-300, 10, &a->T_rel)) return VM_EXIT_USAGE;
  a->T_abs = 0;
  return VM_EXIT_OK;
}

/* --region-thickness SPEC on the wall m: one thickness per element into
 * *out (m->ne, vm_free'd by the caller), the unit `unit` (1: absolute, or
 * the model's length `length`), T the thickness elsewhere; *tmax the
 * largest; opt names the option in messages. With count set
 * (--region-layers), the same with layer counts, whole numbers in [1, T]
 * (T the stack's count, unit 1). */
typedef struct {
  int32_t id, order; /* the value, its place in the list */
  double x;          /* its thickness */
  int64_t hits;      /* wall faces with it */
} region_item;

static int cmp_region_item(const void *a, const void *b) {
  const region_item *p = a, *q = b;
  if (p->id != q->id) return p->id < q->id ? -1 : 1;
  return (p->order > q->order) - (p->order < q->order);
}

static int region_values(vm_cli *cli, const char *opt, int count, const char *spec,
                         const vm_mesh *m, double unit, double length, double T, double **out,
                         double *tmax) {
  *out = NULL;
  region_item *items = NULL;
  size_t n = 0, cap = 0;
  const char *X = count ? "N" : "X";
  const char *colon = strrchr(spec, ':');
  if (!colon || colon == spec || !colon[1])
    return vm_cli_usage_error(cli, "%s '%s': expects FIELD:ID=%s,...", opt, spec, X);
  char name[256];
  size_t nl = (size_t)(colon - spec);
  if (nl >= sizeof name) return vm_cli_usage_error(cli, "%s: the field name is too long", opt);
  memcpy(name, spec, nl);
  name[nl] = 0;
  const vm_field *f = vm_mesh_find_field(m, name, VM_FIELD_ELEMENT);
  if (!f || f->type != VM_FIELD_I32 || f->ncomp != 1)
    return vm_cli_usage_error(cli,
                              "%s: the wall has no int element field '%s' (one "
                              "value per face)",
                              opt, name);
  const int32_t *id = f->data;
  double *et = vm_alloc_array(cli->ctx, (size_t)(m->ne ? m->ne : 1), sizeof *et);
  if (!et) return vm_cli_usage_error(cli, "%s: out of memory", opt);
  for (int64_t e = 0; e < m->ne; e++) et[e] = T;
  *tmax = T;
  const char *s = colon + 1;
  for (int item = 1;; item++) {
    char *end;
    errno = 0;
    long long k = strtoll(s, &end, 10);
    if (end == s || *end != '=' || errno || k < INT32_MIN || k > INT32_MAX) {
      vm_free(cli->ctx, et);
      vm_free(cli->ctx, items);
      return vm_cli_usage_error(cli, "%s: item %d ('%s'): expects ID=%s", opt, item, s, X);
    }
    s = end + 1;
    double x = strtod(s, &end);
    if (count && !(end == s || (*end && *end != ',')) && !(x == floor(x) && x >= 1 && x <= T)) {
      vm_free(cli->ctx, et);
      vm_free(cli->ctx, items);
      return vm_cli_usage_error(cli, "%s: item %d: '%.*s' is not a layer count in [1, %g] (-n)",
                                opt, item, (int)strcspn(s, ","), s, T);
    }
    if (end == s || (*end && *end != ',') || !(x > 0) || !isfinite(x * unit)) {
      vm_free(cli->ctx, et);
      vm_free(cli->ctx, items);
      return vm_cli_usage_error(cli, "%s: item %d: '%.*s' is not a positive %s", opt, item,
                                (int)strcspn(s, ","), s, count ? "layer count" : "thickness");
    }
    if (!count && !(x * unit >= 1e-9 * length)) {
      vm_free(cli->ctx, et);
      vm_free(cli->ctx, items);
      return vm_cli_usage_error(cli,
                                "%s: item %d: %g is below 1e-9 of the model's "
                                "length %g (the layers would vanish in rounding)",
                                opt, item, x * unit, length);
    }
    if (n == cap) {
      size_t c2 = cap ? 2 * cap : 16;
      region_item *g = vm_realloc(cli->ctx, items, c2 * sizeof *g);
      if (!g) {
        vm_free(cli->ctx, et);
        vm_free(cli->ctx, items);
        return vm_cli_usage_error(cli, "%s: out of memory", opt);
      }
      items = g;
      cap = c2;
    }
    items[n] = (region_item){(int32_t)k, (int32_t)n, x * unit, 0};
    n++;
    if (x * unit > *tmax) *tmax = x * unit;
    if (!*end) break;
    s = end + 1;
  }
  /* by value (a value given twice: the later one), then one binary
   * search per element: linear in the list and the wall, whatever the
   * list */
  qsort(items, n, sizeof *items, cmp_region_item);
  size_t u = 0;
  for (size_t i = 0; i < n; i++) {
    if (u && items[u - 1].id == items[i].id)
      items[u - 1] = items[i];
    else
      items[u++] = items[i];
  }
  for (int64_t e = 0; e < m->ne; e++) {
    size_t lo = 0, hi = u;
    while (lo < hi) {
      size_t mid = lo + (hi - lo) / 2;
      if (items[mid].id < id[e])
        lo = mid + 1;
      else
        hi = mid;
    }
    if (lo < u && items[lo].id == id[e]) {
      et[e] = items[lo].x;
      items[lo].hits += m->etype[e] == VM_TRI || m->etype[e] == VM_QUAD;
    }
  }
  size_t missing = 0, first = 0;
  for (size_t i = 0; i < u; i++)
    if (!items[i].hits && !missing++) first = i;
  if (missing == 1)
    vm_log(cli->ctx, VM_LOG_WARN, "%s: no wall face has %s = %d", opt, name, items[first].id);
  else if (missing > 1)
    vm_log(cli->ctx, VM_LOG_WARN, "%s: no wall face has %s = %d, nor %zu other values of the list",
           opt, name, items[first].id, missing - 1);
  vm_free(cli->ctx, items);
  *out = et;
  return VM_EXIT_OK;
}

/* The smallest angle (degrees) of triangle e of m. */
static double tri_min_angle(const vm_mesh *m, int64_t e) {
  const int32_t *c = m->conn + m->eoff[e];
  double amin = 180;
  for (int i = 0; i < 3; i++) {
    const double *p = m->xyz + 3 * (int64_t)c[i], *q = m->xyz + 3 * (int64_t)c[(i + 1) % 3],
                 *r = m->xyz + 3 * (int64_t)c[(i + 2) % 3];
    double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    double v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    double x[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double a = atan2(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]),
                     u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) *
               180 / 3.14159265358979323846;
    if (a < amin) amin = a;
  }
  return amin;
}

/* Triangles of the wall m under `deg` degrees (vm-surface's needles), the
 * smallest angle of all in *amin. */
static int64_t wall_needles(const vm_mesh *m, double deg, double *amin) {
  int64_t n = 0;
  *amin = 180;
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI) continue;
    double a = tri_min_angle(m, e);
    n += a < deg;
    if (a < *amin) *amin = a;
  }
  return n;
}

/* The wall m through the surface stage as vm-surface's defaults take it
 * (repaired, slivers removed, the input remeshed to sizes from its
 * curvature where needles are left, adapted by the 2D functional), in
 * place: the layers are then those of `vm-surface IN W; vm-prism W`. `why`
 * is said first; keep_ok: --keep-wall would take the wall as it is (named
 * in the messages); *nneedle, *amin: the triangles under 1 degree and the
 * smallest angle, before and then after. */
static int surface_stage(vm_cli *cli, const char *in, vm_mesh *m, const char *why, int keep_ok,
                         int64_t *nneedle, double *amin, char *said, size_t nsaid) {
  vm_log(cli->ctx, VM_LOG_WARN,
         "%s: %s; the wall goes through the surface stage first, as vm-surface would take "
         "it%s",
         in, why, keep_ok ? " (--keep-wall: as it is)" : "");
  vm_surface_opts so = vm_surface_opts_default();
  so.soup = vm_cli_soup_format(in);
  /* a model no repair can close is refused here, its message naming
   * vm-surface --wrap: wrapping changes the shape, which the user decides
   * (vm-surface wraps such a model by default, saying so) */
  so.wrap = 0;
  vm_mesh_apply_fixed_field(m);
  int64_t ne = m->ne;
  vm_surface_summary s;
  vm_cli_catch_interrupts(cli);
  int st = vm_surface_run(cli->ctx, m, &so, &s);
  if (st == VM_ERR_INTERRUPTED) {
    vm_cli_error(cli, "%s: interrupted in the surface stage; nothing written", in);
    return VM_EXIT_INTERRUPTED;
  }
  if (st < 0) {
    /* an open wall is refused either way, and so is one that is not a
     * manifold or crosses itself (the message names vm-surface --wrap):
     * no --keep-wall advice then */
    int closed_only =
        s.repair.refused == VM_REPAIR_NONMANIFOLD || s.repair.refused == VM_REPAIR_CROSSING;
    vm_cli_error(cli, "%s: the surface stage: %s%s", in, vm_ctx_error(cli->ctx),
                 s.open                    ? " (the layer needs a closed wall)"
                 : keep_ok && !closed_only ? " (--keep-wall extrudes the wall as it is)"
                                           : "");
    return VM_EXIT_INPUT;
  }
  if (s.adapted && s.adapt.flipped > 0)
    vm_log(cli->ctx, VM_LOG_WARN, "%s: the surface stage's adaptation flipped %lld triangles", in,
           (long long)s.adapt.flipped);
  double amin0 = *amin;
  *nneedle = wall_needles(m, 1.0, amin);
  snprintf(said, nsaid,
           "%lld -> %lld triangles (%s), smallest angle %.3g -> %.3g deg, %lld under 1 degree "
           "left",
           (long long)ne, (long long)m->ne,
           s.remeshed ? "remeshed to sizes from the curvature" : "the input's vertices", amin0,
           *amin, (long long)*nneedle);
  if (!cli->quiet) fprintf(stderr, "vm-prism: %s: surface stage: %s\n", in, said);
  return VM_EXIT_OK;
}

/* The folds of the wall m taken out (vm_surface_unblind), said on stderr;
 * those left are the prism stage's to refuse, with where. */
static int unblind_wall(vm_cli *cli, const char *in, vm_mesh *m, vm_unblind_report *rp) {
  vm_unblind_opts uo = vm_unblind_opts_default();
  vm_unblind_report r;
  int st = vm_surface_unblind(m, &uo, &r);
  *rp = r;
  /* a wall that is not a manifold, consistently oriented triangle surface
   * is left as it is: the prism stage refuses it with its own message */
  if (st == VM_ERR_ARG) return VM_EXIT_OK;
  if (st < 0) {
    vm_cli_error(cli, "%s: %s", in, vm_ctx_error(cli->ctx));
    return VM_EXIT_INPUT;
  }
  if (r.caps_in > 0)
    vm_log(cli->ctx, VM_LOG_WARN,
           "%s: %lld wall triangles have an angle within 0.1 degrees of 180 (caps: their apex on "
           "their long edge); %lld flips of that edge %s %lld of them out",
           in, (long long)r.caps_in, (long long)r.cap_flips, r.undone ? "would have taken" : "took",
           (long long)(r.undone ? 0 : r.caps_in - r.caps));
  if (r.blind_in > 0)
    vm_log(cli->ctx, VM_LOG_WARN,
           "%s: the wall folds back at %lld vertices (no direction sees every incident triangle "
           "there, e.g. at (%g, %g, %g)): %lld edge collapses and %lld flips %s %lld of them "
           "out, moving the surface by at most %g%s",
           in, (long long)r.blind_in, r.at_in[0], r.at_in[1], r.at_in[2], (long long)r.collapses,
           (long long)r.flips, r.undone ? "would have taken" : "took",
           (long long)(r.blind_in - r.blind), r.max_dev,
           r.undone ? " (undone: they made triangles intersect)" : "");
  return VM_EXIT_OK;
}

#define A(f) offsetof(args, f)
static const vm_opt opts[] = {
    {"--thickness", "-T", VM_OPT_DOUBLE, A(T_abs), "X", "total thickness, absolute", .lo = 1e-300,
     .hi = 1e300},
    {"--thickness-rel", "-t", VM_OPT_CALL, 0, "F",
     "total thickness as a fraction of the model's length (largest bounding-box extent; "
     "default 0.05)",
     .fn = opt_thickness_rel},
    {"--layers", "-n", VM_OPT_INT, A(o.nlayers), "N", "number of layers (default 20)", .lo = 1,
     .hi = 1000},
    {"--first-height", NULL, VM_OPT_DOUBLE, A(o.first_height), "H",
     "height of the first layer (absolute)", .lo = 1e-300, .hi = 1e300},
    {"--growth", NULL, VM_OPT_CALL, 0, "R",
     "ratio of successive layer heights (default 1.2; with --first-height or --yplus and no "
     "--growth the ratio is solved for, so the layers fill the thickness; with both, the growth "
     "law is kept and fewer layers may be made)",
     .fn = opt_growth},
    {"--max-aspect", NULL, VM_OPT_DOUBLE, A(o.max_aspect), "A",
     "without --first-height or --yplus: a column's first height is at least the longest wall "
     "edge at it over A, its layers growing more slowly (default 30: OpenFOAM's determinant "
     "check fails near 40; 0: the same first height everywhere)",
     .lo = 0, .hi = 1e300},
    {"--yplus", NULL, VM_OPT_DOUBLE, A(yplus), "Y",
     "first-layer height for a target y+ by the flat-plate estimate (needs --reynolds; "
     "docs/prism.md)",
     .lo = 1e-6, .hi = 1e4},
    {"--reynolds", NULL, VM_OPT_DOUBLE, A(reynolds), "RE",
     "Reynolds number over the reference length, for --yplus (10 to 1e12)", .lo = 10, .hi = 1e12},
    {"--ref-length", NULL, VM_OPT_DOUBLE, A(ref_length), "L",
     "reference length of --reynolds (default the model's length)", .lo = 1e-300, .hi = 1e300},
    {"--region-thickness", NULL, VM_OPT_STRING, A(region), "FIELD:ID=X,...",
     "thickness per region of the wall: the int element field FIELD (vm-gen's 'component', "
     "'gmsh:physical', ...) and, for some of its values ID, the thickness X in the unit of "
     "-t or -T (a share of the model's length by default); other faces keep -t / -T. The "
     "layer count is the same everywhere (see --region-layers); thinner regions keep the "
     "first height and grow more slowly, and thicker columns are shortened near a border so "
     "the outer surface rises at most at a slope of 0.5",
     .error = "expects FIELD:ID=X,..."},
    {"--region-layers", NULL, VM_OPT_STRING, A(region_layers), "FIELD:ID=N,...",
     "layer count per region of the wall (FIELD as for --region-thickness): faces with value "
     "ID get N layers (1..-n), the others -n. A region's layers keep the first height and the "
     "growth, so it is as thick as its N first layers (unless --region-thickness gives its "
     "thickness); where counts meet, the extra layers end in pyramids and tetrahedra",
     .error = "expects FIELD:ID=N,..."},
    {"--springback-iter", NULL, VM_OPT_INT, A(o.springback_iter), "N",
     "implicit iterations of the springback (default 100; up to 3N while the line search keeps "
     "cutting the step or F still falls by more than 1 % per 10 iterations)",
     .lo = 0, .hi = 100000000},
    {"--hold-retries", NULL, VM_OPT_FLAG, A(o.hold_retries), NULL,
     "where the springback's solve is still held past its budget (a few prisms that cannot "
     "reach their targets cutting every step short), go on retrying each short step with "
     "those prisms' vertices held still: more columns reach T on thick layers, in more time, "
     "and the cells are not better everywhere (docs/prism.md; default: off)",
     .ival = 1},
    {"--slot-clearance", NULL, VM_OPT_DOUBLE, A(o.slot_clearance), "S",
     "where the layer's outer surface faces another part's closer than S times its local "
     "outer edge (a slot cutting left between two parts' layers), lower the columns until it "
     "does not, down to 0.3 of their aim, so the fill's tets across the slot are not flat "
     "(default 0.5; 0: off, the layers stop where cutting leaves them)",
     .lo = 0, .hi = 2},
    {"--resolve-iter", NULL, VM_OPT_INT, A(o.resolve_iter), "N",
     "implicit iterations after each cutting round (default 6)", .lo = 0, .hi = 100000000},
    {"--cut-rounds", NULL, VM_OPT_INT, A(o.max_cut_rounds), "N",
     "cutting rounds at most (default 400)", .lo = 0, .hi = 100000000},
    {"--cut-factor", NULL, VM_OPT_DOUBLE, A(o.cut_factor), "F",
     "target height reduction per cut (default 0.85)", .lo = 0.5, .hi = 0.999},
    {"--smooth-iter", NULL, VM_OPT_INT, A(o.smooth_iter), "N",
     "restoration / smoothing passes (default 30)", .lo = 0, .hi = 100000000},
    {"--march-iter", NULL, VM_OPT_INT, A(o.march_iter), "N",
     "explicit iterations per split (default 8)", .lo = 0, .hi = 100000000},
    {"--ortho-weight", NULL, VM_OPT_DOUBLE, A(o.ortho_weight), "W",
     "weight of the inner sublayer when splitting (default 10)", .lo = 1, .hi = 1e300},
    {"--drop-quality", NULL, VM_OPT_DOUBLE, A(o.drop_quality), "Q",
     "drop the outermost layer if its minimum scaled Jacobian is below Q (default 0: keep)",
     .lo = 0, .hi = 0.999},
    {"--no-end-short", NULL, VM_OPT_FLAG, A(o.end_short), NULL,
     "keep every layer in short columns (by default, where the layer has cells below "
     "OpenFOAM's determinant limit, a squeezed patch of short columns takes the schedule's "
     "layers that fit it, ending in pyramids and tets, if that halves such cells around it)",
     .ival = 0},
    {"--symmetry", NULL, VM_OPT_STRING, A(symmetry), "PLANE",
     "a half model: y=0 (x=C, y=C or z=C) is its symmetry plane, which the wall's open "
     "boundary must lie in exactly; the columns there stay in it, and the layer's faces on it "
     "form the boundary 'symmetry' (default auto: an open wall whose border lies in such a "
     "plane is a half model; none: an open wall is refused)",
     .error = "expects auto, none or a plane such as y=0"},
    {"--no-orient", NULL, VM_OPT_FLAG, A(o.orient), NULL,
     "refuse a wall oriented inwards (default: its triangles are turned, with a warning, so "
     "the layer grows outside)",
     .ival = 0},
    {"--keep-wall", NULL, VM_OPT_FLAG, A(keep_wall), NULL,
     "extrude the wall as it is, also where it has needles (triangles under 1 degree; by "
     "default such a wall first goes through the surface stage as vm-surface's defaults "
     "would: repaired, the needles remeshed away, adapted)",
     .ival = 1},
    {"--min-reach", NULL, VM_OPT_DOUBLE, A(min_reach), "P",
     "exit 5 if fewer than P % of the columns the geometry leaves room for (exterior medial "
     "radius >= 1.05 T) reach the full thickness (default 0: never; the mesh is still written)",
     .lo = 0, .hi = 100},
    {"--time-limit", NULL, VM_OPT_DOUBLE, A(o.time_limit), "S", "seconds for the whole run",
     .lo = 1e-300, .hi = 1e300},
    VM_CLI_OPT_THREADS,
    {"--format", NULL, VM_OPT_CALL, A(fout), "F",
     "output format (vmsh, msh, vtu, vtk, cgns, su2, foam)", .fn = vm_cli_opt_format,
     .error = "expects a format name"},
    {"--binary", NULL, VM_OPT_FLAG, A(wo.binary), NULL, "binary output where the format has both",
     .ival = 1},
    {"--report", NULL, VM_OPT_STRING, A(report), "DIR",
     "write DIR/index.html with pictures: convergence (F per solver iteration, pairs per "
     "cutting round), quality histograms, slices through the layers, the surface coloured by "
     "the achieved thickness",
     .error = "expects a directory"},
    {"--json", NULL, VM_OPT_FLAG, A(json), NULL, "JSON summary on stdout", .ival = 1},
    {"--check-incremental", NULL, VM_OPT_FLAG, A(o.check_incremental), NULL,
     "check every incremental intersection query against a full one (slow; for tests)", .ival = 1},
    VM_CLI_OPT_QUIET("no progress on stderr"),
    VM_CLI_OPT_VERBOSE("debug messages too (the non-orthogonality relief's sweeps)"),
    {0}};

static const vm_cli_spec spec = {
    "usage: vm-prism [options] IN OUT\n"
    "Build a thick multi-layer prism mesh outside the closed triangulated wall IN\n"
    "(.vmsh, .stl, .obj, .off, .ply, ...; one oriented inwards is turned, with a\n"
    "warning): thin layer, elastic springback,\n"
    "cutting of self-intersections (Embree), thickness restoration with smoothing,\n"
    "marching split into layers. OUT by extension: .vmsh .msh (Gmsh 4.1) .vtu .vtk\n"
    ".cgns .su2 .foam (wall and outer boundary as separate families / markers /\n"
    "patches; .foam is an OpenFOAM case directory).\n",
    opts,
    "exit: 0 valid layers; 1 bad input (a self-intersecting wall, ...) or I/O;\n"
    "2 usage; 3 inverted prisms or intersections remain (the mesh is still\n"
    "written); 4 interrupted or stopped by --time-limit (the mesh so far written);\n"
    "5 valid layers, but fewer columns with room reach T than --min-reach asks\n",
    {A(in), A(out)},
    2,
    "need IN and OUT"};

/* The model's length: the largest extent of the wall's bounding box (a
 * half model's: of the whole model, its mirror image in its symmetry
 * plane included). */
static double model_length(vm_ctx *ctx, const vm_mesh *m) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int64_t e = 0; e < m->ne; e++) {
    if (m->etype[e] != VM_TRI && m->etype[e] != VM_QUAD) continue;
    for (int64_t k = m->eoff[e]; k < m->eoff[e + 1]; k++)
      for (int c = 0; c < 3; c++) {
        double v = m->xyz[3 * (int64_t)m->conn[k] + c];
        lo[c] = fmin(lo[c], v);
        hi[c] = fmax(hi[c], v);
      }
  }
  int ax;
  double c;
  if (vm_prism_half_plane(ctx, m, &ax, &c) > 0) {
    double r = fmax(fabs(hi[ax] - c), fabs(lo[ax] - c));
    lo[ax] = c - r;
    hi[ax] = c + r;
  }
  return fmax(fmax(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]);
}

/* --symmetry: auto, none, or AXIS=VALUE (x, y or z; a finite number). */
static int symmetry_opt(vm_cli *cli, const char *v, vm_prism_opts *o) {
  if (!strcmp(v, "auto")) {
    o->symmetry_axis = 0;
    return VM_EXIT_OK;
  }
  if (!strcmp(v, "none")) {
    o->symmetry_axis = -1;
    return VM_EXIT_OK;
  }
  const char *ax = strchr("xyz", v[0]);
  char *end = NULL;
  double c = v[0] && ax && v[1] == '=' ? strtod(v + 2, &end) : NAN;
  if (!ax || !end || end == v + 2 || *end || !isfinite(c))
    return vm_cli_usage_error(cli, "--symmetry '%s': expects auto, none or a plane such as y=0", v);
  o->symmetry_axis = (int)(ax - "xyz") + 1;
  o->symmetry_value = c;
  return VM_EXIT_OK;
}

/* Intersecting pairs of the written mesh's layers (the final check). */
static int count_pairs(vm_cli *cli, const vm_mesh *res, int64_t wall_vertices, int64_t *npairs) {
  uint8_t *wall = vm_calloc(cli->ctx, (size_t)res->nv, 1);
  if (!wall) return vm_error(cli->ctx, VM_ERR_NOMEM, "out of memory");
  for (int64_t v = 0; v < wall_vertices; v++) wall[v] = 1;
  int st = vm_prism_mesh_intersections(cli->ctx, res, wall, npairs);
  vm_free(cli->ctx, wall);
  return st;
}

/* Exit code of a valid run whose columns with room fall short of
 * --min-reach. */
enum { EXIT_SHORT = 5 };

static void print_summary(const char *out, const vm_prism_report *r, int64_t npairs, int rc,
                          int interrupted, int timed_out) {
  int bad = r->inverted > 0 || npairs > 0;
  char ends[128] = "", raised[96] = "";
  if (r->first_raised)
    snprintf(raised, sizeof raised, " to %g at %lld columns", r->first_height_max,
             (long long)r->first_raised);
  if (r->pyramids || r->tets)
    snprintf(ends, sizeof ends, " (and %lld pyramids, %lld tets where layers end)",
             (long long)r->pyramids, (long long)r->tets);
  fprintf(stderr,
          "vm-prism: %s: %lld prisms%s in %d layers (first %g%s, growth %g), %.1f%% of columns at "
          "full thickness, thickness/T min %.3f mean %.3f, inverted corner tets %lld, prisms not "
          "positive in every 3-tet split %lld, min "
          "scaled Jacobian %.3f, normal deviation max %.2f deg (%lld of %lld smooth vertices "
          "above 5 deg), intersecting pairs %lld, max "
          "growth %.3f, OpenFOAM non-orthogonality max %.1f deg (%lld faces beyond 70), "
          "skewness max %.2f, room for T at %.1f%% of columns (%.1f%% of those at full "
          "thickness), fill of the allowed thickness %.3f, %.2f s%s\n",
          out, (long long)r->prisms, ends, r->layers, r->first_height, raised, r->growth,
          100 * r->full_fraction, r->thick_min, r->thick_mean, (long long)r->inverted,
          (long long)r->split_negative, r->sj_min, r->normal_dev_max,
          (long long)r->normal_dev_over5, (long long)r->smooth_vertices, (long long)npairs,
          r->growth_max, r->nonortho_max, (long long)r->nonortho_over70, r->skew_max,
          100 * r->medial_room, 100 * r->medial_reach, r->medial_fill, r->time_total,
          rc == VM_EXIT_CHECK ? "  -- NOT VALID"
          : (interrupted || timed_out) && bad
              ? (timed_out ? "  -- time limit reached, NOT VALID" : "  -- interrupted, NOT VALID")
          : timed_out   ? "  -- time limit reached"
          : interrupted ? "  -- interrupted"
                        : "");
}

static void print_json(const char *in, const char *out, const vm_prism_report *rp, double L,
                       int64_t npairs, int64_t needles_in, int surface, int64_t needles,
                       const vm_unblind_report *folds, int rc, int verified, int interrupted,
                       int timed_out) {
  const vm_prism_report r = *rp;
  printf("{\"input\": ");
  vm_json_string(stdout, in);
  printf(", \"output\": ");
  vm_json_string(stdout, out);
  printf(", \"valid\": %s, \"verified\": %s, \"interrupted\": %s, \"timed_out\": %s, "
         "\"wall_vertices\": %lld, "
         "\"wall_triangles\": %lld, \"prisms\": %lld, \"layers_requested\": %d, \"layers\": %d, "
         "\"thickness\": ",
         rc == VM_EXIT_OK || rc == EXIT_SHORT ? "true" : "false", verified ? "true" : "false",
         interrupted ? "true" : "false", timed_out ? "true" : "false", (long long)r.wall_vertices,
         (long long)r.wall_triangles, (long long)r.prisms, r.layers_requested, r.layers);
  vm_json_double(stdout, r.thickness);
  printf(", \"model_length\": ");
  vm_json_double(stdout, L);
  printf(", \"first_height\": ");
  vm_json_double(stdout, r.first_height);
  printf(", \"first_height_max\": ");
  vm_json_double(stdout, r.first_height_max);
  printf(", \"first_raised\": %lld, \"growth\": ", (long long)r.first_raised);
  vm_json_double(stdout, r.growth);
  printf(", \"reoriented\": %s, \"needles_in\": %lld, \"surface_stage\": %s, \"needles\": %lld",
         r.reoriented ? "true" : "false", (long long)needles_in, surface ? "true" : "false",
         (long long)needles);
  printf(", \"folded_in\": %lld, \"folded\": %lld, \"caps_in\": %lld, \"caps\": %lld",
         (long long)folds->blind_in, (long long)folds->blind, (long long)folds->caps_in,
         (long long)folds->caps);
  printf(", \"ended_columns\": %lld, \"ended_kept\": %lld, \"pyramids\": %lld, \"tets\": %lld",
         (long long)r.ended_columns, (long long)r.ended_kept, (long long)r.pyramids,
         (long long)r.tets);
  printf(", \"short_ended\": %lld", (long long)r.short_ended);
  if (r.sym_axis >= 0) {
    printf(", \"symmetry_plane\": \"%c=%.17g\", \"symmetry_columns\": %lld, "
           "\"symmetry_snapped\": %lld, \"symmetry_crossing\": %lld",
           "xyz"[r.sym_axis], r.sym_value, (long long)r.sym_columns, (long long)r.sym_snapped,
           (long long)r.sym_crossing);
  } else {
    printf(", \"symmetry_plane\": null");
  }
  printf(", \"full_fraction\": ");
  vm_json_double(stdout, r.full_fraction);
  printf(", \"thickness_min\": ");
  vm_json_double(stdout, r.thick_min);
  printf(", \"thickness_mean\": ");
  vm_json_double(stdout, r.thick_mean);
  printf(", \"inverted_corner_tets\": %lld, \"split_negative\": %lld, \"intersecting_pairs\": "
         "%lld, \"sj_min\": ",
         (long long)r.inverted, (long long)r.split_negative, (long long)npairs);
  vm_json_double(stdout, r.sj_min);
  printf(", \"normal_dev_max_deg\": ");
  vm_json_double(stdout, r.normal_dev_max);
  printf(", \"thickness_max\": ");
  vm_json_double(stdout, r.thick_max);
  printf(", \"normal_dev_mean_deg\": ");
  vm_json_double(stdout, r.normal_dev_mean);
  printf(", \"smooth_vertices\": %lld, \"normal_dev_over_5deg\": %lld",
         (long long)r.smooth_vertices, (long long)r.normal_dev_over5);
  printf(", \"normal_dev_p99_deg\": ");
  vm_json_double(stdout, r.normal_dev_p99);
  printf(", \"normal_dev_all_max_deg\": ");
  vm_json_double(stdout, r.normal_dev_all_max);
  printf(", \"normal_dev_all_p99_deg\": ");
  vm_json_double(stdout, r.normal_dev_all_p99);
  printf(", \"growth_max\": ");
  vm_json_double(stdout, r.growth_max);
  printf(", \"growth_p99\": ");
  vm_json_double(stdout, r.growth_p99);
  printf(", \"growth_band_share\": ");
  vm_json_double(stdout, r.growth_band_share);
  printf(", \"growth_respaced\": %lld", (long long)r.growth_respaced);
  printf(", \"nonortho_over_70deg\": %lld, \"nonortho_max_deg\": ", (long long)r.nonortho_over70);
  vm_json_double(stdout, r.nonortho_max);
  printf(", \"skewness_max\": ");
  vm_json_double(stdout, r.skew_max);
  printf(", \"det_small\": %lld", (long long)r.det_small);
  printf(", \"medial\": {\"room\": ");
  vm_json_double(stdout, r.medial_room);
  printf(", \"reach\": ");
  vm_json_double(stdout, r.medial_reach);
  printf(", \"short\": %lld, \"fill\": ", (long long)r.medial_short);
  vm_json_double(stdout, r.medial_fill);
  printf(", \"fill_rest\": ");
  vm_json_double(stdout, r.medial_fill_rest);
  printf(", \"narrow_gap\": %lld, \"narrow_gap_min\": ", (long long)r.narrow_gap);
  vm_json_double(stdout, r.narrow_gap_min);
  printf(", \"time\": %.3f}", r.medial_time);
  printf(", \"springback_iterations\": %d, \"held_steps\": %d, \"cut_rounds\": %d, "
         "\"cut_pairs_first\": %lld, \"slots_lowered\": %lld, "
         "\"time\": {",
         r.springback_iter, r.held_steps, r.cut_rounds, (long long)r.cut_pairs_first,
         (long long)r.slots_lowered);
  for (int k = 0; k < VM_PRISM_NPHASES; k++)
    printf("\"%s\": %.3f, ", vm_prism_phase_name((vm_prism_phase)k), r.time[k]);
  printf("\"total\": %.3f}, \"march_time\": {", r.time_total);
  for (int k = 0; k < VM_PRISM_NMARCH_STEPS; k++)
    printf("%s\"%s\": %.3f", k ? ", " : "", vm_prism_march_step_name(k), r.march_time[k]);
  printf("}, \"peak_mb\": {");
  for (int k = 0; k < VM_PRISM_NPHASES; k++)
    printf("\"%s\": %.1f, ", vm_prism_phase_name((vm_prism_phase)k), r.peak_mb[k]);
  printf("\"run\": %.1f}}\n", vm_peak_memory_mb());
}

/* --report: the wall coloured by its columns' fill of the allowed
 * thickness (the wall's vertices and triangles of the result, with the
 * fill field). */
static int report_fill(vm_ctx *ctx, vm_report *report, const vm_mesh *res, int64_t nw) {
  const vm_field *ff = vm_mesh_find_field(res, VM_PRISM_FIELD_FILL, VM_FIELD_VERTEX);
  const vm_field *ph = vm_mesh_find_field(res, VM_PRISM_FIELD_PHYS, VM_FIELD_ELEMENT);
  if (!ff || !ph) return VM_OK;
  vm_mesh *w = NULL;
  vm_field *f;
  int st = vm_mesh_create(ctx, &w);
  if (st >= 0) st = vm_mesh_set_vertices(w, nw);
  if (st >= 0) memcpy(w->xyz, res->xyz, (size_t)(3 * nw) * sizeof *w->xyz);
  const int32_t *tag = ph->data;
  for (int64_t e = 0; st >= 0 && e < res->ne; e++)
    if (res->etype[e] == VM_TRI && tag[e] == VM_PRISM_TAG_WALL)
      st = vm_mesh_add_element(w, VM_TRI, res->conn + res->eoff[e]);
  if (st >= 0) st = vm_mesh_add_field(w, VM_PRISM_FIELD_FILL, VM_FIELD_VERTEX, VM_FIELD_F64, 1, &f);
  if (st >= 0) {
    memcpy(f->data, ff->data, (size_t)nw * sizeof(double));
    st = vm_report_surface(report, "fill",
                           "The wall coloured by its columns' fill of what the geometry allows: "
                           "thickness / min(T, exterior medial radius), at most 1 (1: the "
                           "column reached all the room it has).",
                           w, VM_PRISM_FIELD_FILL, NULL);
  }
  vm_mesh_destroy(&w);
  return st;
}

/* --report: the run's rows, then the standard pictures (cli_report.c). */
static int write_report(vm_cli *cli, vm_report **rep, const char *dir, const char *in,
                        const char *out, const vm_prism_report *rp, double L, int64_t npairs,
                        int rc, int verified, const vm_mesh *res, const vm_report_history *hist,
                        const char *surface) {
  vm_report *report = *rep;
  const vm_prism_report r = *rp;
  int st2 = vm_report_heading(report, "run");
  if (st2 >= 0) st2 = vm_report_row(report, "input, output", "%s, %s", in, out);
  if (st2 >= 0 && surface)
    st2 =
        vm_report_row(report, "surface stage (the wall had needles under 1 degree)", "%s", surface);
  if (st2 >= 0)
    st2 = vm_report_row(report, "wall triangles, prisms, layers (requested)", "%lld, %lld, %d (%d)",
                        (long long)r.wall_triangles, (long long)r.prisms, r.layers,
                        r.layers_requested);
  if (st2 >= 0)
    st2 =
        vm_report_row(report, "thickness T (of the model's length), first height, growth",
                      "%g (%.3g), %g, %g", r.thickness, r.thickness / L, r.first_height, r.growth);
  if (st2 >= 0 && (r.ended_columns > 0 || r.ended_kept > 0))
    st2 = vm_report_row(report,
                        "layers ending (per region, short columns): columns ended, of them "
                        "short, columns kept whole, pyramids, tets",
                        "%lld, %lld, %lld, %lld, %lld", (long long)r.ended_columns,
                        (long long)r.short_ended, (long long)r.ended_kept, (long long)r.pyramids,
                        (long long)r.tets);
  if (st2 >= 0)
    st2 = vm_report_row(report, "columns at full thickness", "%.1f %%", 100 * r.full_fraction);
  if (st2 >= 0)
    st2 = vm_report_row(report, "thickness / T: min, mean, max", "%.3f, %.3f, %.3f", r.thick_min,
                        r.thick_mean, r.thick_max);
  if (st2 >= 0)
    st2 = vm_report_row(report,
                        "inverted corner tets, prisms not positive in every 3-tet split, "
                        "intersecting pairs, min scaled Jacobian",
                        "%lld, %lld, %lld, %.3g", (long long)r.inverted,
                        (long long)r.split_negative, (long long)npairs, r.sj_min);
  if (st2 >= 0)
    st2 = vm_report_row(report, "first layer off the wall normal: smooth vertices; all",
                        "max %.2f deg, p99 %.2f deg, %lld of %lld above 5 deg; max %.2f deg, "
                        "p99 %.2f deg",
                        r.normal_dev_max, r.normal_dev_p99, (long long)r.normal_dev_over5,
                        (long long)r.smooth_vertices, r.normal_dev_all_max, r.normal_dev_all_p99);
  if (st2 >= 0)
    st2 = vm_report_row(report, "growth of successive heights (columns' largest ratio)",
                        "max %.3f, p99 %.3f; %.2f %% of the columns within [1/1.5, 1.5] x %g "
                        "(%lld re-spaced by the growth relief)",
                        r.growth_max, r.growth_p99, 100 * r.growth_band_share, r.growth,
                        (long long)r.growth_respaced);
  if (st2 >= 0)
    st2 = vm_report_row(report, "faces as OpenFOAM measures them",
                        "max non-orthogonality %.1f deg, %lld faces beyond 70 deg, max skewness "
                        "%.2f, %lld prisms with a cell determinant below 0.001",
                        r.nonortho_max, (long long)r.nonortho_over70, r.skew_max,
                        (long long)r.det_small);
  if (st2 >= 0)
    st2 = vm_report_row(report,
                        "room for T (exterior medial radius >= 1.05 T): columns, of those at "
                        "full thickness, short",
                        "%.1f %%, %.1f %%, %lld", 100 * r.medial_room, 100 * r.medial_reach,
                        (long long)r.medial_short);
  if (st2 >= 0)
    st2 = vm_report_row(report,
                        "fill of the allowed thickness, achieved / min(T, radius): mean, mean "
                        "where there is no room for T",
                        "%.3f, %.3f", r.medial_fill, r.medial_fill_rest);
  if (st2 >= 0)
    st2 = vm_report_row(report,
                        "wall vertices in a gap narrower than half their edges (narrowest gap)",
                        "%lld (%g)", (long long)r.narrow_gap, r.narrow_gap_min);
  if (st2 >= 0) st2 = report_fill(cli->ctx, report, res, r.wall_vertices);
  if (st2 >= 0)
    st2 = vm_report_row(report,
                        "springback iterations, cutting rounds (pairs at first), columns "
                        "lowered to open slots",
                        "%d, %d (%lld), %lld", r.springback_iter, r.cut_rounds,
                        (long long)r.cut_pairs_first, (long long)r.slots_lowered);
  char times[256];
  int len = 0;
  for (int k = 0; k < VM_PRISM_NPHASES && len < (int)sizeof times; k++)
    len += snprintf(times + len, sizeof times - (size_t)len, "%s%s %.2f s", k ? ", " : "",
                    vm_prism_phase_name((vm_prism_phase)k), r.time[k]);
  if (st2 >= 0)
    st2 = vm_report_row(report, "time per phase", "%s (%.2f s in all)", times, r.time_total);
  if (st2 >= 0)
    st2 =
        vm_report_row(report, "valid, verified (exact)", "%s, %s",
                      rc == VM_EXIT_OK || rc == EXIT_SHORT ? "yes" : "no", verified ? "yes" : "no");
  int rrc = vm_cli_report_result(cli, rep, dir, st2, "prism layers", res, "thickness", hist,
                                 "Convergence of the run: the functional F per solver "
                                 "iteration (springback, the solves after cutting, "
                                 "marching), the intersecting pairs left per cutting round "
                                 "in the M panel (0 elsewhere: every prism stays valid); "
                                 "dashed lines separate the phases.");
  return rrc;
}

int main(int argc, char **argv) {
  vm_cli cli;
  vm_cli_init(&cli, "vm-prism");
  args a = {.T_rel = 0.05,
            .fout = VM_FMT_AUTO,
            .o = vm_prism_opts_default(),
            .wo = vm_write_opts_default()};
  vm_mesh *m = NULL, *res = NULL;
  double *elem_T = NULL;  /* --region-thickness: one per wall element */
  int32_t *elem_n = NULL; /* --region-layers: one per wall element */
  vm_report *report = NULL;
  vm_report_history *hist = NULL;
  int rc = vm_cli_parse(&cli, &spec, &a, argc - 1, argv + 1);
  if (rc != VM_CLI_RUN) goto done;
  rc = VM_EXIT_OK;
  if (a.fout == VM_FMT_AUTO && (a.fout = vm_format_from_path(a.out)) == VM_FMT_AUTO) {
    rc = vm_cli_usage_error(&cli, "cannot tell the output format of '%s' (use --format)", a.out);
    goto done;
  }
  if ((rc = vm_cli_volume_output(&cli, a.out, a.fout)) != VM_EXIT_OK) goto done;
  if (a.fout == VM_FMT_CGNS && !vm_have_cgns()) {
    vm_cli_error(&cli, "this build has no CGNS support (libcgns)");
    rc = VM_EXIT_USAGE;
    goto done;
  }
  if (vm_mesh_read(cli.ctx, a.in, VM_FMT_AUTO, &m) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  double L = model_length(cli.ctx, m);
  if (!(L > 0)) {
    vm_cli_error(&cli, "%s: no triangles (or all in one point)", a.in);
    rc = VM_EXIT_INPUT;
    goto done;
  }
  /* needles: the columns over rows of them fall short (the springback's
   * line search is held by their prisms: vm-gen wing at T = 20 %, 3.7 % of
   * the columns with room reach T, 99.9 % through the surface stage). So by
   * default such a wall goes through the surface stage here, as vm-surface
   * would take it: the same layers as the two runs. Slivers alone (1 to 15
   * degrees) do not send it there: on them the stage is not better
   * everywhere (docs/prism.md). */
  double needle_min = 180;
  int64_t nneedle = wall_needles(m, 1.0, &needle_min), needles_in = nneedle;
  int surface_ran = 0;
  char surface_said[256] = "";
  vm_unblind_report folds; /* vm-prism's own pass (the surface stage's is said there) */
  memset(&folds, 0, sizeof folds);
  /* a wall that intersects itself (the parts of an assembly overlapping:
   * a wing through a fuselage; a part folded locally) goes there too: the
   * surface stage's repair replaces overlapping closed parts by their union
   * and heals a part that crosses itself (or refuses it) */
  int64_t wall_pairs = 0;
  if (!a.keep_wall && (rc = check_wall_intersections(&cli, a.in, m, &wall_pairs)) != VM_EXIT_OK)
    goto done;
  if (wall_pairs > 0) {
    char why[256];
    snprintf(why, sizeof why,
             "the wall intersects itself (%lld pairs of triangles): overlapping closed parts are "
             "replaced by their union, a part crossing itself is healed",
             (long long)wall_pairs);
    if ((rc = surface_stage(&cli, a.in, m, why, 0, &nneedle, &needle_min, surface_said,
                            sizeof surface_said)) != VM_EXIT_OK)
      goto done;
    surface_ran = 1;
    L = model_length(cli.ctx, m);
  } else if (nneedle > 0 && a.keep_wall) {
    vm_log(cli.ctx, VM_LOG_WARN,
           "%s: %lld triangles under 1 degree (smallest %.3g): columns over needles fall short "
           "of T (vm-gen wing at T = 20 %%: 3.7 %% of its columns reach T, 99.9 %% after the "
           "surface stage); --keep-wall extrudes the wall as it is",
           a.in, (long long)nneedle, needle_min);
  } else if (nneedle > 0) {
    char why[256];
    snprintf(why, sizeof why,
             "%lld triangles under 1 degree (smallest %.3g): the columns over them would fall "
             "short of T",
             (long long)nneedle, needle_min);
    if ((rc = surface_stage(&cli, a.in, m, why, 1, &nneedle, &needle_min, surface_said,
                            sizeof surface_said)) != VM_EXIT_OK)
      goto done;
    surface_ran = 1;
    L = model_length(cli.ctx, m);
  }
  /* a wall that folds back on itself somewhere (a triangle turned over
   * onto its neighbours, needles folded against theirs, the rim of a
   * plate of no thickness) has vertices no column direction can stand on:
   * the folds are taken out by local flips and collapses first (the
   * surface stage ends with the same step) */
  if (!a.keep_wall && (rc = unblind_wall(&cli, a.in, m, &folds)) != VM_EXIT_OK) goto done;
  vm_prism_opts *o = &a.o;
  if (a.symmetry && (rc = symmetry_opt(&cli, a.symmetry, o)) != VM_EXIT_OK) goto done;
  o->thickness = a.T_abs > 0 ? a.T_abs : a.T_rel * L;
  /* a thickness lost in rounding against the model's coordinates is a
   * usage error, not a bad wall */
  if (!(o->thickness >= 1e-9 * L) || !isfinite(o->thickness)) {
    rc = vm_cli_usage_error(&cli,
                            "the thickness %g is below 1e-9 of the model's length %g: the layers "
                            "would vanish in rounding (give a larger -T or -t)",
                            o->thickness, L);
    goto done;
  }
  if (a.region) {
    double tmax = 0;
    if ((rc = region_values(&cli, "--region-thickness", 0, a.region, m, a.T_abs > 0 ? 1 : L, L,
                            o->thickness, &elem_T, &tmax)) != VM_EXIT_OK)
      goto done;
    /* the schedule is the thickest region's */
    o->thickness = tmax;
    o->elem_thickness = elem_T;
  }
  if (a.region_layers) {
    double nmax = 0, *en = NULL;
    if ((rc = region_values(&cli, "--region-layers", 1, a.region_layers, m, 1, 1, o->nlayers, &en,
                            &nmax)) != VM_EXIT_OK)
      goto done;
    elem_n = vm_alloc_array(cli.ctx, (size_t)(m->ne ? m->ne : 1), sizeof *elem_n);
    if (!elem_n) {
      vm_free(cli.ctx, en);
      vm_cli_error(&cli, "out of memory");
      rc = VM_EXIT_INPUT;
      goto done;
    }
    for (int64_t e = 0; e < m->ne; e++) elem_n[e] = (int32_t)en[e];
    vm_free(cli.ctx, en);
    o->elem_layers = elem_n;
  }
  if (a.yplus > 0 || a.reynolds > 0 || a.ref_length > 0) {
    if (!(a.yplus > 0) || !(a.reynolds > 0)) {
      rc = vm_cli_usage_error(&cli, "--yplus needs --reynolds (and --reynolds, --ref-length "
                                    "are for --yplus)");
      goto done;
    }
    if (o->first_height > 0) {
      rc = vm_cli_usage_error(&cli, "give --first-height or --yplus, not both");
      goto done;
    }
    double Lr = a.ref_length > 0 ? a.ref_length : L;
    o->first_height = vm_prism_yplus_height(a.yplus, a.reynolds, Lr);
    if (!(o->first_height > 0)) {
      rc = vm_cli_usage_error(&cli, "--yplus %g at Reynolds number %g over %g gives no height",
                              a.yplus, a.reynolds, Lr);
      goto done;
    }
    vm_log(cli.ctx, VM_LOG_INFO,
           "first height %g for y+ %g at Reynolds number %g over the length %g (flat "
           "plate, Schlichting's Cf)",
           o->first_height, a.yplus, a.reynolds, Lr);
  }
  /* a first height alone: the growth ratio is solved for */
  if (o->first_height > 0 && !a.growth_given) o->growth = 0;
  if (o->first_height > 0 && !(o->first_height < o->thickness)) {
    rc = vm_cli_usage_error(&cli, "--first-height %g is not below the thickness %g",
                            o->first_height, o->thickness);
    goto done;
  }
  if ((rc = check_wall_intersections(&cli, a.in, m, NULL)) != VM_EXIT_OK) goto done;
  /* the report is made (or refused) before the run */
  if (a.report) {
    char title[512];
    snprintf(title, sizeof title, "vm-prism: %s", a.in);
    if ((rc = vm_cli_report_open(&cli, a.report, title, &report, &hist)) != VM_EXIT_OK) goto done;
  }
  progress_state ps = {&cli, -1, hist, 0, NAN, a.in, m, L, o};
  o->progress = progress;
  o->user = &ps;
  vm_cli_catch_interrupts(&cli);
  vm_prism_report r;
  int st = vm_prism_run(cli.ctx, m, o, &res, &r);
  if (st >= 0 && o->growth == 0 && r.growth > 1.5)
    vm_log(cli.ctx, VM_LOG_WARN,
           "the growth ratio solved for the first height %g is %.3g: more layers (-n) or a "
           "smaller thickness would keep it near 1.2",
           r.first_height, r.growth);
  if (st < 0 && st != VM_ERR_INTERRUPTED) {
    /* no wall triangles counted: the wall or the options were refused */
    if (r.wall_triangles == 0) {
      vm_cli_error(&cli, "%s: %s", a.in, vm_ctx_error(cli.ctx));
    } else {
      announce(&ps);
      vm_cli_error(&cli, "%s", vm_ctx_error(cli.ctx));
    }
    rc = VM_EXIT_INPUT;
    goto done;
  }
  announce(&ps);
  /* nothing is lost: the wall's vertex fields (the surface stage's
   * curvature, ...) go up every column; then the final check, on the mesh
   * that is written */
  int64_t npairs = 0;
  if (pass_wall_fields(&cli, m, res, r.wall_vertices) < 0 ||
      pass_wall_element_fields(&cli, m, res, r.wall_triangles) < 0 ||
      count_pairs(&cli, res, r.wall_vertices, &npairs) < 0 ||
      /* the numbering's keys served the passing above: not written */
      (vm_mesh_find_field(res, VM_PRISM_FIELD_COLUMN, VM_FIELD_VERTEX) &&
       vm_mesh_remove_field(res, VM_PRISM_FIELD_COLUMN, VM_FIELD_VERTEX) < 0) ||
      (vm_mesh_find_field(res, VM_PRISM_FIELD_WALL_FACE, VM_FIELD_ELEMENT) &&
       vm_mesh_remove_field(res, VM_PRISM_FIELD_WALL_FACE, VM_FIELD_ELEMENT) < 0) ||
      vm_mesh_write(cli.ctx, res, a.out, a.fout, &a.wo) < 0) {
    rc = vm_cli_input_error(&cli, NULL);
    goto done;
  }
  /* the time limit is an interruption too (as in vm-volume): the layers
   * are not what was asked for */
  int timed_out = st != VM_ERR_INTERRUPTED && r.timed_out;
  if (st == VM_ERR_INTERRUPTED || timed_out)
    rc = VM_EXIT_INTERRUPTED;
  else if (r.inverted > 0 || npairs > 0)
    rc = VM_EXIT_CHECK;
  if (st >= 0 && r.split_negative > 0)
    vm_log(cli.ctx, VM_LOG_WARN,
           "%lld prisms are not positive in every 3-tet split (the split repair could not "
           "untwist them; valid as prisms, but a solver that splits prisms into tets fails "
           "there; vm-quality lists the count)",
           (long long)r.split_negative);
  if (st >= 0 && r.medial_short > 0) {
    int64_t room = (int64_t)llround(r.medial_room * (double)r.wall_vertices);
    vm_log(cli.ctx, VM_LOG_WARN,
           "%lld of the %lld columns the geometry leaves room for (exterior medial radius >= "
           "1.05 T) end short of T (%.1f %% reach it)",
           (long long)r.medial_short, (long long)room, 100 * r.medial_reach);
  }
  int verified = 0;
  if (rc == VM_EXIT_OK) {
    /* before success is reported, vm-quality --verify's exact checks (CGAL
     * predicates, nothing shared with the solver or Embree): every corner
     * tet positive, outer faces crossing neither each other nor the wall */
    int vrc = vm_cli_verify(&cli, a.out, res, VM_RULE_CORNER, 0, NULL);
    if (vrc != VM_EXIT_OK) rc = vrc;
    verified = vrc == VM_EXIT_OK;
    if (verified && !cli.quiet)
      fprintf(stderr,
              "vm-prism: %s: verify: every corner tet positive, no outer faces crossing "
              "each other or the wall (exact)\n",
              a.out);
  }
  if (rc == VM_EXIT_OK && a.min_reach > 0 && 100 * r.medial_reach < a.min_reach) {
    fprintf(stderr,
            "vm-prism: %s: %.1f %% of the columns with room reach the full thickness, fewer than "
            "--min-reach %g %% (the mesh is written)\n",
            a.out, 100 * r.medial_reach, a.min_reach);
    rc = EXIT_SHORT;
  }
  if (!cli.quiet) print_summary(a.out, &r, npairs, rc, st == VM_ERR_INTERRUPTED, timed_out);
  if (rc == VM_EXIT_INTERRUPTED) /* said even with -q: the mesh written is not the one asked for */
    fprintf(stderr,
            "vm-prism: %s: %s after %.2f s: %d of %d layers, %.1f%% of columns at full "
            "thickness; %s: %lld inverted corner tets, %lld pairs of outer/wall faces crossing\n",
            a.out, timed_out ? "stopped at the time limit" : "interrupted", r.time_total, r.layers,
            r.layers_requested, 100 * r.full_fraction,
            r.inverted > 0 || npairs > 0 ? "NOT VALID" : "not verified", (long long)r.inverted,
            (long long)npairs);
  if (a.json)
    print_json(a.in, a.out, &r, L, npairs, needles_in, surface_ran, nneedle, &folds, rc, verified,
               st == VM_ERR_INTERRUPTED, timed_out);
  if (report) {
    int rrc = write_report(&cli, &report, a.report, a.in, a.out, &r, L, npairs, rc, verified, res,
                           hist, surface_ran ? surface_said : NULL);
    if (rrc != VM_EXIT_OK && rc == VM_EXIT_OK) rc = rrc;
  }
done:
  vm_free(cli.ctx, elem_T);
  vm_free(cli.ctx, elem_n);
  vm_report_destroy(&report);
  vm_report_history_destroy(&hist);
  vm_mesh_destroy(&res);
  vm_mesh_destroy(&m);
  vm_cli_finish(&cli);
  return rc;
}
