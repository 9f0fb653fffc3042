/* lib/report/src/report.c: reports with pictures: quality histograms, convergence
 * plots, a software-rendered surface, planar slices of volume meshes (PNG,
 * drawn with cairo) and the index.html that shows them. */
#include "varmesh/report.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "varmesh/io.h"

#ifndef VM_HAVE_CAIRO
#define VM_HAVE_CAIRO 0
#endif
#if VM_HAVE_CAIRO
#include <cairo.h>
#endif

#define HIST_MAX_PHASES 16
#define VM_PI 3.14159265358979323846

struct vm_report_history {
  vm_ctx *ctx;
  int64_t n, cap;
  int *iter;
  double *F, *eps;
  int64_t *M;
  uint8_t *phase;
  int nphase;
  char *phases[HIST_MAX_PHASES];
};

typedef struct {
  char *key;
  char *value; /* NULL: a heading row */
} report_row;

typedef struct {
  char *file;
  char *caption;
  int w, h;
} report_fig;

struct vm_report {
  vm_ctx *ctx;
  char *dir;
  char *tmp; /* where the files are written until vm_report_write publishes
                them: beside dir if it is missing, else inside it; NULL
                once published (made again by the next figure) */
  char *title;
  report_row *rows;
  int nrows, caprows;
  report_fig *figs;
  int nfigs, capfigs;
};

int vm_report_available(void) { return VM_HAVE_CAIRO; }

/* ---- strings ------------------------------------------------------------ */

static char *vformat(vm_ctx *ctx, const char *fmt, va_list ap) {
  va_list aq;
  va_copy(aq, ap);
  int n = vsnprintf(NULL, 0, fmt, aq);
  va_end(aq);
  if (n < 0) n = 0;
  char *s = vm_malloc(ctx, (size_t)n + 1);
  if (s) vsnprintf(s, (size_t)n + 1, fmt, ap);
  return s;
}

static char *format(vm_ctx *ctx, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static char *format(vm_ctx *ctx, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  char *s = vformat(ctx, fmt, ap);
  va_end(ap);
  return s;
}

#if VM_HAVE_CAIRO
static int valid_name(const char *name) {
  size_t n = name ? strlen(name) : 0;
  if (n == 0 || n > 100) return 0;
  for (size_t i = 0; i < n; i++) {
    char c = name[i];
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
          c == '_'))
      return 0;
  }
  return 1;
}
#endif

static void html_text(FILE *f, const char *s) {
  for (; s && *s; s++) {
    switch (*s) {
    case '&': fputs("&amp;", f); break;
    case '<': fputs("&lt;", f); break;
    case '>': fputs("&gt;", f); break;
    case '"': fputs("&quot;", f); break;
    default: fputc(*s, f);
    }
  }
}

/* ---- convergence history ------------------------------------------------ */

int vm_report_history_create(vm_ctx *ctx, vm_report_history **out) {
  *out = vm_calloc(ctx, 1, sizeof **out);
  if (!*out) return VM_ERR_NOMEM;
  (*out)->ctx = ctx;
  return VM_OK;
}

void vm_report_history_destroy(vm_report_history **p) {
  if (!p || !*p) return;
  vm_report_history *h = *p;
  vm_ctx *ctx = h->ctx;
  vm_free(ctx, h->iter);
  vm_free(ctx, h->F);
  vm_free(ctx, h->eps);
  vm_free(ctx, h->M);
  vm_free(ctx, h->phase);
  for (int i = 0; i < h->nphase; i++) vm_free(ctx, h->phases[i]);
  vm_free(ctx, h);
  *p = NULL;
}

int vm_report_history_add(vm_report_history *h, const char *phase, int total_iter, double F,
                          int64_t M, double eps) {
  if (h->n == h->cap) {
    size_t cap = h->cap ? (size_t)h->cap * 2 : 256;
    int *it = vm_realloc(h->ctx, h->iter, cap * sizeof *it);
    if (it) h->iter = it;
    double *f = it ? vm_realloc(h->ctx, h->F, cap * sizeof *f) : NULL;
    if (f) h->F = f;
    double *ep = f ? vm_realloc(h->ctx, h->eps, cap * sizeof *ep) : NULL;
    if (ep) h->eps = ep;
    int64_t *mm = ep ? vm_realloc(h->ctx, h->M, cap * sizeof *mm) : NULL;
    if (mm) h->M = mm;
    uint8_t *ph = mm ? vm_realloc(h->ctx, h->phase, cap * sizeof *ph) : NULL;
    if (!ph) return VM_ERR_NOMEM;
    h->phase = ph;
    h->cap = (int64_t)cap;
  }
  if (!phase) phase = "";
  int k = 0;
  while (k < h->nphase && strcmp(h->phases[k], phase)) k++;
  if (k == h->nphase) {
    if (h->nphase == HIST_MAX_PHASES) {
      k = HIST_MAX_PHASES - 1; /* more phase names than anyone draws: lump them */
    } else {
      h->phases[k] = vm_strdup(h->ctx, phase);
      if (!h->phases[k]) return VM_ERR_NOMEM;
      h->nphase++;
    }
  }
  h->iter[h->n] = total_iter;
  h->F[h->n] = F;
  h->M[h->n] = M;
  h->eps[h->n] = eps;
  h->phase[h->n] = (uint8_t)k;
  h->n++;
  return VM_OK;
}

int64_t vm_report_history_count(const vm_report_history *h) { return h ? h->n : 0; }

/* ---- the report and its page --------------------------------------------- */

#if VM_HAVE_CAIRO
/* Remove the flat temporary directory d and what is in it. */
static void remove_tmp(const char *d) {
  DIR *dd = opendir(d);
  struct dirent *e;
  while (dd && (e = readdir(dd)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) unlinkat(dirfd(dd), e->d_name, 0);
  if (dd) closedir(dd);
  rmdir(d);
}

/* r->tmp: a fresh temporary directory, inside r->dir if it exists (its
 * files are moved into it), else beside it (renamed to it); a short name,
 * whatever the length of r->dir's. */
static int make_tmp(vm_report *r) {
  vm_ctx *ctx = r->ctx;
  static unsigned long counter;
  struct stat st;
  int inside = stat(r->dir, &st) == 0;
  const char *slash = strrchr(r->dir, '/');
  int dl = slash ? (int)(slash - r->dir + 1) : 0;
  char *t = inside
                ? format(ctx, "%s/.vmreport.tmp.%ld.%lu", r->dir, (long)getpid(), ++counter)
                : format(ctx, "%.*s.vmreport.tmp.%ld.%lu", dl, r->dir, (long)getpid(), ++counter);
  if (!t) return VM_ERR_NOMEM;
  if (mkdir(t, 0777) != 0) {
    int e = errno;
    vm_free(ctx, t);
    return vm_error(ctx, VM_ERR_IO, "%s: cannot create: %s", r->dir, strerror(e));
  }
  r->tmp = t;
  return VM_OK;
}

/* Rename r->tmp/name to r->dir/name. */
static int move_into_place(vm_report *r, const char *name) {
  vm_ctx *ctx = r->ctx;
  int st = VM_OK;
  char *a = format(ctx, "%s/%s", r->tmp, name), *b = format(ctx, "%s/%s", r->dir, name);
  if (!a || !b)
    st = VM_ERR_NOMEM;
  else if (rename(a, b) != 0)
    st = vm_error(ctx, VM_ERR_IO, "%s: cannot move into place: %s", b, strerror(errno));
  vm_free(ctx, a);
  vm_free(ctx, b);
  return st;
}

/* Put the files of r->tmp in place: the whole directory renamed to r->dir
 * if that is still missing, else file by file into it (index.html last),
 * so that a failure before this (a full disk) leaves no partial report. */
static int publish(vm_report *r) {
  vm_ctx *ctx = r->ctx;
  int st = VM_OK;
  if (rename(r->tmp, r->dir) != 0) {
    DIR *dd = opendir(r->tmp);
    if (!dd) return vm_error(ctx, VM_ERR_IO, "%s: %s", r->tmp, strerror(errno));
    struct dirent *e;
    int index = 0;
    while (st == VM_OK && (e = readdir(dd))) {
      if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
      if (!strcmp(e->d_name, "index.html")) {
        index = 1;
        continue;
      }
      st = move_into_place(r, e->d_name);
    }
    closedir(dd);
    if (st == VM_OK && index) {
      st = move_into_place(r, "index.html");
    }
    remove_tmp(r->tmp);
  }
  vm_free(ctx, r->tmp);
  r->tmp = NULL;
  return st;
}
#endif

int vm_report_create(vm_ctx *ctx, const char *dir, const char *title, vm_report **out) {
  *out = NULL;
#if !VM_HAVE_CAIRO
  (void)dir;
  (void)title;
  return vm_error(ctx, VM_ERR_UNSUPPORTED,
                  "reports need cairo, and this varmesh was built without it (install "
                  "libcairo2-dev and reconfigure)");
#else
  if (!dir || !*dir) return vm_error(ctx, VM_ERR_ARG, "report: empty directory name");
  struct stat st;
  if (stat(dir, &st) == 0) {
    if (!S_ISDIR(st.st_mode))
      return vm_error(ctx, VM_ERR_IO, "%s: exists and is not a directory", dir);
    if (access(dir, W_OK | X_OK) != 0)
      return vm_error(ctx, VM_ERR_IO, "%s: not writable: %s", dir, strerror(errno));
  }
  vm_report *r = vm_calloc(ctx, 1, sizeof *r);
  if (!r) return VM_ERR_NOMEM;
  r->ctx = ctx;
  r->dir = vm_strdup(ctx, dir);
  r->title = vm_strdup(ctx, title ? title : "varmesh report");
  if (!r->dir || !r->title) {
    vm_report_destroy(&r);
    return VM_ERR_NOMEM;
  }
  /* the temporary directory now: a bad --report fails before the run */
  int s2 = make_tmp(r);
  if (s2 < 0) {
    vm_report_destroy(&r);
    return s2;
  }
  *out = r;
  return VM_OK;
#endif
}

void vm_report_destroy(vm_report **p) {
  if (!p || !*p) return;
  vm_report *r = *p;
  vm_ctx *ctx = r->ctx;
  for (int i = 0; i < r->nrows; i++) {
    vm_free(ctx, r->rows[i].key);
    vm_free(ctx, r->rows[i].value);
  }
  for (int i = 0; i < r->nfigs; i++) {
    vm_free(ctx, r->figs[i].file);
    vm_free(ctx, r->figs[i].caption);
  }
  vm_free(ctx, r->rows);
  vm_free(ctx, r->figs);
#if VM_HAVE_CAIRO
  if (r->tmp) remove_tmp(r->tmp); /* never published: nothing of it stays */
#endif
  vm_free(ctx, r->tmp);
  vm_free(ctx, r->dir);
  vm_free(ctx, r->title);
  vm_free(ctx, r);
  *p = NULL;
}

/* Takes ownership of key and value (both freed on failure). */
static int push_row(vm_report *r, char *key, char *value, int heading) {
  if (!key || (!heading && !value)) {
    vm_free(r->ctx, key);
    vm_free(r->ctx, value);
    return VM_ERR_NOMEM;
  }
  if (r->nrows == r->caprows) {
    int cap = r->caprows ? 2 * r->caprows : 32;
    report_row *rows = vm_realloc(r->ctx, r->rows, (size_t)cap * sizeof *rows);
    if (!rows) {
      vm_free(r->ctx, key);
      vm_free(r->ctx, value);
      return VM_ERR_NOMEM;
    }
    r->rows = rows;
    r->caprows = cap;
  }
  r->rows[r->nrows].key = key;
  r->rows[r->nrows].value = value;
  r->nrows++;
  return VM_OK;
}

int vm_report_heading(vm_report *r, const char *heading) {
  return push_row(r, vm_strdup(r->ctx, heading ? heading : ""), NULL, 1);
}

int vm_report_row(vm_report *r, const char *key, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  char *v = vformat(r->ctx, fmt, ap);
  va_end(ap);
  return push_row(r, vm_strdup(r->ctx, key ? key : ""), v, 0);
}

int vm_report_quality_rows(vm_report *r, const char *heading, const vm_quality *q) {
  int st = heading ? vm_report_heading(r, heading) : VM_OK;
  if (st >= 0)
    st = vm_report_row(r, "elements measured", "%lld (dimension %d)%s", (long long)q->measured,
                       q->top_dim, q->skipped ? ", lower-dimensional ones skipped" : "");
  if (st >= 0)
    st = vm_report_row(r, "M (inverted quadrature simplices)", "%lld in %lld elements",
                       (long long)q->all.inverted_nodes, (long long)q->all.inverted_elems);
  if (st >= 0 && q->measured) {
    st = vm_report_row(r, "phi_min (shape)", "%.4e", q->all.phi_min);
    if (st >= 0 && isfinite(q->all.psi_min))
      st = vm_report_row(r, "psi_min (volume)", "%.4e", q->all.psi_min);
    if (st >= 0)
      st = vm_report_row(r, "scaled Jacobian", "min %.4f, p1 %.4f, p5 %.4f, median %.4f",
                         q->all.sj_min, q->sj_p01, q->sj_p05, q->sj_p50);
    for (int t = 0; t < VM_NTYPES && st >= 0; t++) {
      const vm_type_quality *tq = &q->type[t];
      if (!tq->count) continue;
      st = vm_report_row(
          r, vm_elem_name(t), "%lld elements, M %lld, phi_min %.4e, scaled Jacobian min %.4f",
          (long long)tq->count, (long long)tq->inverted_nodes, tq->phi_min, tq->sj_min);
    }
  }
  return st;
}

/* A mesh out to a far field (boundaries named "wall" and "farfield"): the
 * middle slice shows the far field and the model as a dot, so two more
 * slices zoom on the wall: a window of the wall's bounding box and a sixth
 * of its size around it, the plane across the wall's middle-sized extent
 * at a fifth of it from the centre (through a wing of an aircraft). */
static int near_wall_slices(vm_report *r, const char *prefix, const char *label, const vm_mesh *m) {
  vm_ctx *ctx = r->ctx;
  const vm_field *ph = vm_mesh_find_field(m, "gmsh:physical", VM_FIELD_ELEMENT);
  int32_t wall = -1, far = -1;
  for (int i = 0; i < m->nattr; i++) {
    const char *k = m->attrs[i].key, *v = m->attrs[i].value;
    if (strncmp(k, "gmsh:physical_name:2:", 21)) continue;
    if (!strcmp(v, "wall")) wall = (int32_t)atol(k + 21);
    if (!strcmp(v, "farfield")) far = (int32_t)atol(k + 21);
  }
  if (!ph || ph->type != VM_FIELD_I32 || ph->ncomp != 1 || wall < 0 || far < 0) return VM_OK;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int64_t e = 0; e < m->ne; e++) {
    if (vm_elem_dim(m->etype[e]) != 2 || ((const int32_t *)ph->data)[e] != wall) continue;
    for (int64_t j = m->eoff[e]; j < m->eoff[e + 1]; j++)
      for (int k = 0; k < 3; k++) {
        lo[k] = fmin(lo[k], m->xyz[3 * m->conn[j] + k]);
        hi[k] = fmax(hi[k], m->xyz[3 * m->conn[j] + k]);
      }
  }
  if (!(hi[0] >= lo[0])) return VM_OK;
  int ord[3] = {0, 1, 2}; /* axes by extent */
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      if (hi[ord[j]] - lo[ord[j]] < hi[ord[i]] - lo[ord[i]]) {
        int t = ord[i];
        ord[i] = ord[j];
        ord[j] = t;
      }
  int axis = ord[1];
  double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
  double value = 0.5 * (lo[axis] + hi[axis]) + 0.2 * (hi[axis] - lo[axis]);
  double wlo[3], whi[3];
  for (int k = 0; k < 3; k++) wlo[k] = lo[k] - ext / 6, whi[k] = hi[k] + ext / 6;
  char name[128];
  snprintf(name, sizeof name, "%sslice-near", prefix);
  char *cap = format(ctx,
                     "%s: near the wall: the elements cut by the plane %c = %.6g, in a window of "
                     "the wall's bounding box and a sixth of its size around it, coloured by "
                     "their scaled Jacobian.",
                     label, "xyz"[axis], value);
  int st =
      cap ? vm_report_slice_window(r, name, cap, m, axis, value, NULL, wlo, whi) : VM_ERR_NOMEM;
  vm_free(ctx, cap);
  if (st >= 0 && vm_mesh_find_field(m, "layer", VM_FIELD_ELEMENT)) {
    snprintf(name, sizeof name, "%sslice-near-layer", prefix);
    cap = format(ctx, "%s: the same, coloured by the element field 'layer' (-1: the fill).", label);
    st = cap ? vm_report_slice_window(r, name, cap, m, axis, value, "layer", wlo, whi)
             : VM_ERR_NOMEM;
    vm_free(ctx, cap);
  }
  /* a half model: its symmetry plane, the layer's cells and the tets on it
   * (cut a hair inside the domain) */
  const char *axn = "xyz";
  int ax;
  double c;
  if (st >= 0 && vm_mesh_get_symmetry_plane(m, &ax, &c) > 0) {
    double side = hi[ax] - c >= c - lo[ax] ? 1 : -1;
    double v = c + side * 1e-7 * ext;
    snprintf(name, sizeof name, "%ssymmetry", prefix);
    int layer = vm_mesh_find_field(m, "layer", VM_FIELD_ELEMENT) != NULL;
    cap = format(ctx,
                 "%s: the symmetry plane %c = %.6g of the half model: the cells on it (cut %.3g "
                 "inside), in a window of the wall's bounding box and a sixth of its size around "
                 "it, coloured by %s.",
                 label, axn[ax], c, 1e-7 * ext,
                 layer ? "the element field 'layer' (-1: the fill)" : "their scaled Jacobian");
    st = cap ? vm_report_slice_window(r, name, cap, m, ax, v, layer ? "layer" : NULL, wlo, whi)
             : VM_ERR_NOMEM;
    vm_free(ctx, cap);
  }
  return st;
}

int vm_report_mesh(vm_report *r, const char *prefix, const char *label, const vm_mesh *m,
                   const vm_quality_opts *opts, const char *surface_field) {
  vm_ctx *ctx = r->ctx;
  if (!prefix) prefix = "";
  if (!label) label = "mesh";
  vm_quality q;
  int st = vm_mesh_quality(m, opts, &q);
  if (st >= 0) st = vm_report_quality_rows(r, label, &q);
  char name[128], *cap = NULL;
  int64_t counts[VM_NTYPES];
  vm_mesh_count_types(m, counts);
  int64_t n2 = counts[VM_TRI] + counts[VM_QUAD], n3 = m->ne - n2;
  if (st >= 0) {
    snprintf(name, sizeof name, "%squality", prefix);
    cap = format(ctx,
                 "%s: histograms of the scaled Jacobian of every element (red: inverted) and "
                 "of phi, the minimum shape quality det C/(|C|^2/d)^(d/2) of each element's "
                 "quadrature simplices, per element type (1: ideal, <= 0: inverted).",
                 label);
    st = cap ? vm_report_histograms(r, name, cap, m, opts) : VM_ERR_NOMEM;
    vm_free(ctx, cap);
  }
  if (st >= 0 && n3 > 0) {
    double lo[3], hi[3];
    vm_mesh_bounds(m, lo, hi);
    int axis = 2;
    for (int i = 1; i >= 0; i--)
      if (hi[i] - lo[i] > hi[axis] - lo[axis]) axis = i;
    snprintf(name, sizeof name, "%sslice", prefix);
    cap = format(ctx,
                 "%s: the volume elements cut by the plane %c = %.6g (the middle of the "
                 "bounding box), coloured by their scaled Jacobian (red: inverted, yellow: "
                 "degenerate, blue: ideal), with the cuts of their faces drawn.",
                 label, "xyz"[axis], 0.5 * (lo[axis] + hi[axis]));
    st = cap ? vm_report_slice(r, name, cap, m, axis, NAN, NULL) : VM_ERR_NOMEM;
    vm_free(ctx, cap);
    if (st >= 0 && vm_mesh_find_field(m, "layer", VM_FIELD_ELEMENT)) {
      /* prism layers: the same cut coloured by layer index */
      snprintf(name, sizeof name, "%sslice-layer", prefix);
      cap = format(ctx,
                   "%s: the same slice coloured by the element field 'layer' (0 at the "
                   "wall).",
                   label);
      st = cap ? vm_report_slice(r, name, cap, m, axis, NAN, "layer") : VM_ERR_NOMEM;
      vm_free(ctx, cap);
    }
  }
  if (st >= 0 && n3 > 0) st = near_wall_slices(r, prefix, label, m);
  if (st >= 0 && n2 > 0 && m->dim == 3) {
    static const char *const defaults[] = {"mean_curvature_filtered", "mean_curvature"};
    const char *field = surface_field;
    for (int i = 0; i < 2 && !field; i++)
      if (vm_mesh_find_field(m, defaults[i], VM_FIELD_VERTEX) ||
          vm_mesh_find_field(m, defaults[i], VM_FIELD_ELEMENT))
        field = defaults[i];
    snprintf(name, sizeof name, "%ssurface", prefix);
    cap = format(ctx, "%s: its triangles and quads, flat-shaded and coloured by %s.", label,
                 field ? field
                       : "the scaled Jacobian (red: inverted, yellow: degenerate, blue: ideal)");
    st = cap ? vm_report_surface(r, name, cap, m, field, NULL) : VM_ERR_NOMEM;
    vm_free(ctx, cap);
  }
  return st;
}

int vm_report_write(vm_report *r) {
  vm_ctx *ctx = r->ctx;
#if VM_HAVE_CAIRO
  if (!r->tmp) {
    int s0 = make_tmp(r);
    if (s0 < 0) return s0;
  }
  char *path = format(ctx, "%s/index.html", r->tmp);
#else
  char *path = format(ctx, "%s/index.html", r->dir);
#endif
  if (!path) return VM_ERR_NOMEM;
  vm_outfile *of;
  int st = vm_outfile_open(ctx, path, &of);
  vm_free(ctx, path);
  if (st < 0) return st;
  FILE *f = vm_outfile_fp(of);
  fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>", f);
  html_text(f, r->title);
  fputs("</title>\n<style>\n"
        "body { font-family: sans-serif; margin: 1.5em auto; max-width: 1100px; color: #222; }\n"
        "table { border-collapse: collapse; margin: 1em 0; }\n"
        "td, th { border: 1px solid #ccc; padding: 3px 10px; text-align: left; }\n"
        "th { background: #eef; }\n"
        "td.v { font-family: monospace; }\n"
        "figure { margin: 2em 0; }\n"
        "img { max-width: 100%; height: auto; border: 1px solid #ddd; }\n"
        "figcaption { color: #444; margin-top: 0.3em; }\n"
        "</style>\n</head>\n<body>\n<h1>",
        f);
  html_text(f, r->title);
  fprintf(f, "</h1>\n<p>varmesh %s</p>\n", vm_version());
  if (r->nrows) {
    fputs("<table>\n", f);
    for (int i = 0; i < r->nrows; i++) {
      if (!r->rows[i].value) {
        fputs("<tr><th colspan=\"2\">", f);
        html_text(f, r->rows[i].key);
        fputs("</th></tr>\n", f);
      } else {
        fputs("<tr><td>", f);
        html_text(f, r->rows[i].key);
        fputs("</td><td class=\"v\">", f);
        html_text(f, r->rows[i].value);
        fputs("</td></tr>\n", f);
      }
    }
    fputs("</table>\n", f);
  }
  for (int i = 0; i < r->nfigs; i++) {
    const report_fig *g = &r->figs[i];
    fputs("<figure id=\"", f);
    html_text(f, g->file);
    fputs("\">\n<a href=\"", f);
    html_text(f, g->file);
    fputs("\"><img src=\"", f);
    html_text(f, g->file);
    fprintf(f, "\" width=\"%d\" height=\"%d\" alt=\"", g->w, g->h);
    html_text(f, g->caption ? g->caption : g->file);
    fputs("\"></a>\n", f);
    if (g->caption) {
      fputs("<figcaption>", f);
      html_text(f, g->caption);
      fputs("</figcaption>\n", f);
    }
    fputs("</figure>\n", f);
  }
  fputs("</body>\n</html>\n", f);
  st = vm_outfile_commit(&of);
#if VM_HAVE_CAIRO
  if (st >= 0) st = publish(r);
#endif
  return st;
}

#if VM_HAVE_CAIRO

/* Record a written figure (a second figure of the same file replaces the
 * first one's caption and size). */
static int add_figure(vm_report *r, const char *file, const char *caption, int w, int h) {
  vm_ctx *ctx = r->ctx;
  char *cap = caption ? vm_strdup(ctx, caption) : NULL;
  if (caption && !cap) return VM_ERR_NOMEM;
  for (int i = 0; i < r->nfigs; i++)
    if (!strcmp(r->figs[i].file, file)) {
      vm_free(ctx, r->figs[i].caption);
      r->figs[i].caption = cap;
      r->figs[i].w = w;
      r->figs[i].h = h;
      return VM_OK;
    }
  char *fn = vm_strdup(ctx, file);
  if (!fn) {
    vm_free(ctx, cap);
    return VM_ERR_NOMEM;
  }
  if (r->nfigs == r->capfigs) {
    int n = r->capfigs ? 2 * r->capfigs : 8;
    report_fig *g = vm_realloc(ctx, r->figs, (size_t)n * sizeof *g);
    if (!g) {
      vm_free(ctx, cap);
      vm_free(ctx, fn);
      return VM_ERR_NOMEM;
    }
    r->figs = g;
    r->capfigs = n;
  }
  r->figs[r->nfigs].file = fn;
  r->figs[r->nfigs].caption = cap;
  r->figs[r->nfigs].w = w;
  r->figs[r->nfigs].h = h;
  r->nfigs++;
  return VM_OK;
}

/* ---- canvas: a cairo image surface written to DIR/name.png ------------- */

typedef struct {
  cairo_surface_t *s;
  cairo_t *cr;
  int w, h;
} canvas;

static int canvas_open(vm_report *r, canvas *c, int w, int h) {
  c->w = w;
  c->h = h;
  c->s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  c->cr = cairo_create(c->s);
  if (cairo_status(c->cr) != CAIRO_STATUS_SUCCESS) {
    int st = vm_error(r->ctx, VM_ERR_NOMEM, "report: cairo cannot make a %dx%d image: %s", w, h,
                      cairo_status_to_string(cairo_status(c->cr)));
    cairo_destroy(c->cr);
    cairo_surface_destroy(c->s);
    c->cr = NULL;
    c->s = NULL;
    return st;
  }
  cairo_set_source_rgb(c->cr, 1, 1, 1);
  cairo_paint(c->cr);
  cairo_select_font_face(c->cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_line_join(c->cr, CAIRO_LINE_JOIN_ROUND);
  return VM_OK;
}

static void canvas_free(canvas *c) {
  if (c->cr) cairo_destroy(c->cr);
  if (c->s) cairo_surface_destroy(c->s);
  c->cr = NULL;
  c->s = NULL;
}

static cairo_status_t png_write(void *closure, const unsigned char *data, unsigned int len) {
  return fwrite(data, 1, len, (FILE *)closure) == len ? CAIRO_STATUS_SUCCESS
                                                      : CAIRO_STATUS_WRITE_ERROR;
}

/* Write the canvas to DIR/name.png, add it to the page, free the canvas. */
static int canvas_finish(vm_report *r, canvas *c, const char *name, const char *caption) {
  vm_ctx *ctx = r->ctx;
  int st = VM_OK;
  if (cairo_status(c->cr) != CAIRO_STATUS_SUCCESS)
    st = vm_error(ctx, VM_ERR_NOMEM, "report: %s: drawing failed: %s", name,
                  cairo_status_to_string(cairo_status(c->cr)));
  char *file = format(ctx, "%s.png", name);
  if (st >= 0 && !r->tmp) st = make_tmp(r);
  char *path = st >= 0 ? format(ctx, "%s/%s.png", r->tmp, name) : NULL;
  if (st >= 0 && (!file || !path)) st = VM_ERR_NOMEM;
  vm_outfile *of = NULL;
  if (st >= 0) st = vm_outfile_open(ctx, path, &of);
  if (st >= 0) {
    cairo_surface_flush(c->s);
    cairo_status_t cs = cairo_surface_write_to_png_stream(c->s, png_write, vm_outfile_fp(of));
    if (cs != CAIRO_STATUS_SUCCESS) {
      int e = errno;
      vm_outfile_abort(&of);
      /* named as it would have been: the temporary folder is gone */
      st = vm_error(ctx, VM_ERR_IO, "%s/%s: cannot write: %s", r->dir, file,
                    cs == CAIRO_STATUS_WRITE_ERROR && e ? strerror(e) : cairo_status_to_string(cs));
    } else {
      st = vm_outfile_commit(&of);
    }
  }
  if (st >= 0) st = add_figure(r, file, caption, c->w, c->h);
  vm_free(ctx, file);
  vm_free(ctx, path);
  canvas_free(c);
  return st;
}

/* ---- drawing helpers ------------------------------------------------------ */

typedef struct {
  double r, g, b;
} rgb;

/* Colormaps as evenly spaced control points, interpolated linearly. */
static const double cmap_viridis[9][3] = {{68, 1, 84},    {71, 45, 123},  {59, 82, 139},
                                          {44, 114, 142}, {33, 145, 140}, {40, 174, 128},
                                          {94, 201, 98},  {173, 220, 48}, {253, 231, 37}};
/* blue (low) - white - red (high), for signed fields (curvature) */
static const double cmap_diverging[9][3] = {{33, 102, 172},  {67, 147, 195},  {146, 197, 222},
                                            {209, 229, 240}, {247, 247, 247}, {253, 219, 199},
                                            {244, 165, 130}, {214, 96, 77},   {178, 24, 43}};
/* red (inverted) - yellow (degenerate) - blue (ideal), for quality in [-1, 1] */
static const double cmap_quality[11][3] = {{165, 0, 38},    {215, 48, 39},   {244, 109, 67},
                                           {253, 174, 97},  {254, 224, 144}, {255, 255, 191},
                                           {224, 243, 248}, {171, 217, 233}, {116, 173, 209},
                                           {69, 117, 180},  {49, 54, 149}};

enum { CMAP_VIRIDIS, CMAP_DIVERGING, CMAP_QUALITY };

static rgb colormap(int which, double t) {
  const double(*tab)[3] = which == CMAP_DIVERGING ? cmap_diverging
                          : which == CMAP_QUALITY ? cmap_quality
                                                  : cmap_viridis;
  int n = which == CMAP_QUALITY ? 11 : 9;
  if (!(t >= 0)) t = 0; /* also NaN */
  if (t > 1) t = 1;
  double x = t * (n - 1);
  int i = (int)x;
  if (i >= n - 1) i = n - 2;
  double f = x - i;
  rgb c = {(tab[i][0] + f * (tab[i + 1][0] - tab[i][0])) / 255,
           (tab[i][1] + f * (tab[i + 1][1] - tab[i][1])) / 255,
           (tab[i][2] + f * (tab[i + 1][2] - tab[i][2])) / 255};
  return c;
}

/* A value's place on a colour scale. */
typedef struct {
  int map;
  double lo, hi;
} scale;

static double scale_t(const scale *s, double v) {
  return s->hi > s->lo ? (v - s->lo) / (s->hi - s->lo) : 0.5;
}

/* Text with its anchor at (x, y): ax 0 left, 0.5 centre, 1 right; ay 0 top,
 * 0.5 middle, 1 baseline. */
static void text(cairo_t *cr, double x, double y, double size, double ax, double ay,
                 const char *s) {
  cairo_text_extents_t te;
  cairo_set_font_size(cr, size);
  cairo_text_extents(cr, s, &te);
  double asc = 0.72 * size;
  cairo_move_to(cr, x - ax * te.x_advance, y + (1 - ay) * asc);
  cairo_show_text(cr, s);
}

static void text_vertical(cairo_t *cr, double x, double y, double size, const char *s) {
  cairo_save(cr);
  cairo_translate(cr, x, y);
  cairo_rotate(cr, -VM_PI / 2);
  text(cr, 0, 0, size, 0.5, 0.5, s);
  cairo_restore(cr);
}

static void fmt_num(char *buf, size_t n, double v) {
  if (v == 0 || (fabs(v) >= 1e-3 && fabs(v) < 1e5))
    snprintf(buf, n, "%.4g", v);
  else
    snprintf(buf, n, "%.2e", v);
}

/* A plot area and its axes' ranges. */
typedef struct {
  double x0, y0, w, h; /* pixels */
  double xlo, xhi, ylo, yhi;
  int ylog;
} panel;

static double map_x(const panel *p, double x) {
  return p->x0 + (x - p->xlo) / (p->xhi - p->xlo) * p->w;
}

static double map_y(const panel *p, double y) {
  double t = p->ylog ? (log10(y) - log10(p->ylo)) / (log10(p->yhi) - log10(p->ylo))
                     : (y - p->ylo) / (p->yhi - p->ylo);
  return p->y0 + p->h * (1 - t);
}

static double nice_step(double range, int nticks) {
  double raw = range / nticks;
  if (!(raw > 0) || !isfinite(raw)) return 1;
  double mag = pow(10, floor(log10(raw))), f = raw / mag;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
}

/* Decades around [lo, hi] (both > 0). */
static void log_range(double lo, double hi, double *plo, double *phi) {
  double a = floor(log10(lo)), b = ceil(log10(hi));
  if (b <= a) b = a + 1;
  *plo = pow(10, a);
  *phi = pow(10, b);
}

/* Frame, grid, ticks and labels of a panel. ymin_label: text for the bottom
 * edge of a log axis (NULL: none). */
static void draw_axes(cairo_t *cr, const panel *p, const char *title, const char *xlabel,
                      const char *ylabel, const char *ymin_label) {
  char buf[64];
  cairo_set_line_width(cr, 1);
  /* x ticks */
  double step = nice_step(p->xhi - p->xlo, 6);
  for (double x = ceil(p->xlo / step) * step; x <= p->xhi + 1e-9 * step; x += step) {
    double X = floor(map_x(p, x)) + 0.5;
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, X, p->y0);
    cairo_line_to(cr, X, p->y0 + p->h);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    fmt_num(buf, sizeof buf, fabs(x) < 1e-9 * step ? 0 : x);
    text(cr, X, p->y0 + p->h + 5, 11, 0.5, 0, buf);
  }
  /* y ticks */
  if (p->ylog) {
    int a = (int)lround(log10(p->ylo)), b = (int)lround(log10(p->yhi));
    int every = (b - a + 7) / 8;
    if (every < 1) every = 1;
    for (int k = a; k <= b; k++) {
      double Y = floor(map_y(p, pow(10, k))) + 0.5;
      cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
      cairo_move_to(cr, p->x0, Y);
      cairo_line_to(cr, p->x0 + p->w, Y);
      cairo_stroke(cr);
      if ((k - a) % every || (k == a && ymin_label)) continue;
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      if (k >= -3 && k <= 4)
        snprintf(buf, sizeof buf, "%g", pow(10, k));
      else
        snprintf(buf, sizeof buf, "1e%d", k);
      text(cr, p->x0 - 5, Y, 11, 1, 0.5, buf);
    }
    if (ymin_label) {
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      text(cr, p->x0 - 5, p->y0 + p->h, 11, 1, 0.5, ymin_label);
    }
  } else {
    double ys = nice_step(p->yhi - p->ylo, 5);
    for (double y = ceil(p->ylo / ys) * ys; y <= p->yhi + 1e-9 * ys; y += ys) {
      double Y = floor(map_y(p, y)) + 0.5;
      cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
      cairo_move_to(cr, p->x0, Y);
      cairo_line_to(cr, p->x0 + p->w, Y);
      cairo_stroke(cr);
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      fmt_num(buf, sizeof buf, fabs(y) < 1e-9 * ys ? 0 : y);
      text(cr, p->x0 - 5, Y, 11, 1, 0.5, buf);
    }
  }
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_rectangle(cr, floor(p->x0) + 0.5, floor(p->y0) + 0.5, floor(p->w), floor(p->h));
  cairo_stroke(cr);
  cairo_set_source_rgb(cr, 0, 0, 0);
  if (title) text(cr, p->x0, p->y0 - 8, 13, 0, 1, title);
  if (xlabel) text(cr, p->x0 + p->w / 2, p->y0 + p->h + 22, 12, 0.5, 0, xlabel);
  if (ylabel) text_vertical(cr, p->x0 - 52, p->y0 + p->h / 2, 12, ylabel);
}

/* Plot area of a cell (x, y, w, h) of the figure. */
static panel cell_panel(double x, double y, double w, double h) {
  panel p = {x + 68, y + 30, w - 68 - 18, h - 30 - 48, 0, 1, 0, 1, 0};
  return p;
}

/* A vertical colour bar at (x, y, w, h) with its scale's ends and middle. */
static void colour_bar(cairo_t *cr, double x, double y, double w, double h, const scale *s,
                       const char *label) {
  int n = (int)h;
  for (int i = 0; i < n; i++) {
    rgb c = colormap(s->map, 1 - (i + 0.5) / n);
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    cairo_rectangle(cr, x, y + i, w, 1);
    cairo_fill(cr);
  }
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_set_line_width(cr, 1);
  cairo_rectangle(cr, floor(x) + 0.5, floor(y) + 0.5, floor(w), floor(h));
  cairo_stroke(cr);
  char buf[64];
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  for (int k = 0; k <= 2; k++) {
    double v = s->lo + (s->hi - s->lo) * k / 2;
    fmt_num(buf, sizeof buf, fabs(v) < 1e-12 * (s->hi - s->lo) ? 0 : v);
    text(cr, x + w + 5, y + h - h * k / 2, 11, 0, 0.5, buf);
  }
  if (label) text(cr, x + w / 2, y - 10, 12, 0.5, 1, label);
}

/* ---- quality histograms --------------------------------------------------- */

#define HIST_BINS 40

static void hist_panel(cairo_t *cr, panel *p, const double *v, const uint8_t *et, int64_t n,
                       int type, const char *title, const char *xlabel) {
  int64_t bins[HIST_BINS] = {0}, count = 0, neg = 0, mx = 1;
  double vmin = INFINITY;
  for (int64_t i = 0; i < n; i++) {
    if (isnan(v[i]) || (type >= 0 && et[i] != type)) continue;
    double x = v[i];
    int b = (int)floor((x + 1) / 2 * HIST_BINS);
    if (b < 0) b = 0;
    if (b >= HIST_BINS) b = HIST_BINS - 1;
    bins[b]++;
    count++;
    neg += x <= 0;
    if (x < vmin) vmin = x;
  }
  for (int b = 0; b < HIST_BINS; b++)
    if (bins[b] > mx) mx = bins[b];
  p->xlo = -1;
  p->xhi = 1;
  p->ylo = 0;
  p->yhi = mx * 1.08;
  p->ylog = 0;
  draw_axes(cr, p, title, xlabel, "elements", NULL);
  for (int b = 0; b < HIST_BINS; b++) {
    if (!bins[b]) continue;
    double lo = -1 + 2.0 * b / HIST_BINS, hi = lo + 2.0 / HIST_BINS;
    double X0 = map_x(p, lo) + 0.5, X1 = map_x(p, hi) - 0.5;
    double Y = map_y(p, (double)bins[b]);
    if (p->y0 + p->h - Y < 2) Y = p->y0 + p->h - 2; /* a lone element stays visible */
    rgb c = colormap(CMAP_QUALITY, (lo + hi) / 4 + 0.5);
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    cairo_rectangle(cr, X0, Y, X1 - X0, p->y0 + p->h - Y);
    cairo_fill_preserve(cr);
    cairo_set_source_rgba(cr, 0, 0, 0, 0.5);
    cairo_set_line_width(cr, 0.6);
    cairo_stroke(cr);
  }
  char buf[160];
  if (count)
    snprintf(buf, sizeof buf, "%lld elements, min %.4f, %lld at or below 0", (long long)count, vmin,
             (long long)neg);
  else
    snprintf(buf, sizeof buf, "no elements");
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  text(cr, p->x0 + 8, p->y0 + 8, 11, 0, 0, buf);
}

int vm_report_histograms(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                         const vm_quality_opts *opts) {
  vm_ctx *ctx = r->ctx;
  if (!valid_name(name)) return vm_error(ctx, VM_ERR_ARG, "report: bad figure name");
  size_t ne = (size_t)(m->ne ? m->ne : 1);
  double *sj = vm_alloc_array(ctx, ne, sizeof *sj);
  double *phi = vm_alloc_array(ctx, ne, sizeof *phi);
  vm_quality q;
  int st = sj && phi ? vm_mesh_element_quality(m, opts, &q, sj, phi) : VM_ERR_NOMEM;
  int types[VM_NTYPES], nt = 0;
  if (st >= 0)
    for (int t = 0; t < VM_NTYPES; t++)
      if (q.type[t].count) types[nt++] = t;
  canvas c = {0};
  int W = 1000, cols = nt > 1 ? 2 : 1, rows = (nt + cols - 1) / cols;
  int H = 50 + 300 + rows * 270;
  if (st >= 0) st = canvas_open(r, &c, W, H);
  if (st >= 0) {
    cairo_t *cr = c.cr;
    cairo_set_source_rgb(cr, 0, 0, 0);
    text(cr, 20, 14, 16, 0, 0,
         "Element quality: scaled Jacobian, and phi = det C / (|C|^2/d)^(d/2) per element type");
    panel p = cell_panel(0, 50, W, 300);
    hist_panel(cr, &p, sj, m->etype, m->ne, -1, "scaled Jacobian (min over corners), all types",
               "scaled Jacobian");
    for (int i = 0; i < nt; i++) {
      double cw = (double)W / cols;
      panel pp = cell_panel((i % cols) * cw, 350 + (i / cols) * 270.0, cw, 270);
      char title[96];
      snprintf(title, sizeof title, "phi, %s (min over its %s simplices)", vm_elem_name(types[i]),
               opts && opts->rule == VM_RULE_GEOMETRIC ? "geometric-rule" : "corner");
      hist_panel(cr, &pp, phi, m->etype, m->ne, types[i], title, "phi");
    }
    st = canvas_finish(r, &c, name, caption);
  }
  canvas_free(&c);
  vm_free(ctx, sj);
  vm_free(ctx, phi);
  return st;
}

/* ---- convergence ------------------------------------------------------------ */

/* Line through the samples accepted by `keep`, broken at rejected ones;
 * y_of maps a sample to its panel value. */
static void history_line(cairo_t *cr, const panel *p, const vm_report_history *h, int which) {
  int pen = 0;
  cairo_set_line_width(cr, 1.4);
  for (int64_t i = 0; i < h->n; i++) {
    double y;
    if (which == 0) {
      y = h->M[i] > 0 ? (double)h->M[i] : p->ylo; /* M = 0 on the bottom edge */
    } else {
      y = which == 1 ? h->F[i] : h->eps[i];
      if (!isfinite(y) || (p->ylog && y <= 0)) {
        pen = 0;
        continue;
      }
    }
    if (y < p->ylo) y = p->ylo;
    if (y > p->yhi) y = p->yhi;
    double X = map_x(p, h->iter[i]), Y = map_y(p, y);
    if (pen)
      cairo_line_to(cr, X, Y);
    else
      cairo_move_to(cr, X, Y);
    pen = 1;
  }
  if (h->n == 1) cairo_rel_line_to(cr, 1, 0);
  cairo_stroke(cr);
}

/* y range of F (which 1) or eps (2): log when every finite value is > 0. */
static int value_range(const vm_report_history *h, int which, double *lo, double *hi) {
  double a = INFINITY, b = -INFINITY;
  int pos = 1, any = 0;
  for (int64_t i = 0; i < h->n; i++) {
    double y = which == 1 ? h->F[i] : h->eps[i];
    if (!isfinite(y)) continue;
    if (which == 2 && y <= 0) continue; /* eps <= 0: not drawn */
    any = 1;
    if (y <= 0) pos = 0;
    if (y < a) a = y;
    if (y > b) b = y;
  }
  if (!any) {
    *lo = 1;
    *hi = 10;
    return 1;
  }
  if (pos) {
    log_range(a, b, lo, hi);
    return 1;
  }
  double pad = b > a ? 0.05 * (b - a) : fabs(a) > 0 ? 0.05 * fabs(a) : 1;
  *lo = a - pad;
  *hi = b + pad;
  return 0;
}

int vm_report_convergence(vm_report *r, const char *name, const char *caption,
                          const vm_report_history *h) {
  vm_ctx *ctx = r->ctx;
  if (!valid_name(name)) return vm_error(ctx, VM_ERR_ARG, "report: bad figure name");
  vm_report_history empty = {0};
  if (!h) h = &empty;
  canvas c = {0};
  int W = 1000, H = 50 + 3 * 250;
  int st = canvas_open(r, &c, W, H);
  if (st < 0) return st;
  cairo_t *cr = c.cr;
  cairo_set_source_rgb(cr, 0, 0, 0);
  char buf[128];
  snprintf(buf, sizeof buf, "Convergence: %lld iterations", (long long)h->n);
  text(cr, 20, 14, 16, 0, 0, buf);
  double xlo = h->n ? h->iter[0] : 0, xhi = h->n ? h->iter[h->n - 1] : 1;
  if (xhi <= xlo) xhi = xlo + 1;
  int64_t mmax = 1;
  for (int64_t i = 0; i < h->n; i++)
    if (h->M[i] > mmax) mmax = h->M[i];
  panel p[3];
  static const char *const titles[3] = {"M: inverted quadrature simplices", "F: the functional",
                                        "epsilon (untangling; t in quasi-isometric continuation)"};
  static const char *const ylabels[3] = {"M", "F", "epsilon"};
  static const double colours[3][3] = {{0.75, 0.1, 0.1}, {0.1, 0.3, 0.7}, {0.1, 0.55, 0.25}};
  for (int k = 0; k < 3; k++) {
    p[k] = cell_panel(0, 50 + 250.0 * k, W, 250);
    p[k].xlo = xlo;
    p[k].xhi = xhi;
    if (k == 0) {
      p[k].ylog = 1;
      double a, b;
      log_range(1, (double)mmax, &a, &b);
      p[k].ylo = 0.5; /* the bottom edge stands for M = 0 */
      p[k].yhi = b;
    } else {
      p[k].ylog = value_range(h, k, &p[k].ylo, &p[k].yhi);
    }
    draw_axes(cr, &p[k], titles[k], k == 2 ? "iteration" : NULL, ylabels[k], k == 0 ? "0" : NULL);
    /* phase boundaries, named in the top panel */
    double last_label = -1e9;
    for (int64_t i = 0; i < h->n; i++) {
      if (i > 0 && h->phase[i] == h->phase[i - 1]) continue;
      double X = floor(map_x(&p[k], h->iter[i])) + 0.5;
      if (i > 0) {
        static const double dash[2] = {4, 3};
        cairo_set_dash(cr, dash, 2, 0);
        cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
        cairo_set_line_width(cr, 1);
        cairo_move_to(cr, X, p[k].y0);
        cairo_line_to(cr, X, p[k].y0 + p[k].h);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
      }
      if (k == 0 && X - last_label > 70) {
        cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
        text(cr, X + 4, p[k].y0 + 4, 11, 0, 0, h->phases[h->phase[i]]);
        last_label = X;
      }
    }
    cairo_set_source_rgb(cr, colours[k][0], colours[k][1], colours[k][2]);
    cairo_save(cr);
    cairo_rectangle(cr, p[k].x0, p[k].y0 - 1, p[k].w, p[k].h + 2);
    cairo_clip(cr);
    history_line(cr, &p[k], h, k);
    cairo_restore(cr);
  }
  if (h->n) {
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    snprintf(buf, sizeof buf, "M: %lld after the first iteration, %lld at the end",
             (long long)h->M[0], (long long)h->M[h->n - 1]);
    /* on the title row, clear of the phase names inside the panel */
    text(cr, p[0].x0 + p[0].w, p[0].y0 - 8, 11, 1, 1, buf);
  }
  return canvas_finish(r, &c, name, caption);
}

/* ---- a rendered surface ------------------------------------------------------ */

vm_report_view vm_report_view_default(void) {
  vm_report_view v = {-60, 25, 1000, 700, -1};
  return v;
}

typedef struct {
  double depth;
  int64_t id;
} depth_key;

static int cmp_depth(const void *a, const void *b) {
  const depth_key *x = a, *y = b;
  if (x->depth != y->depth) return x->depth < y->depth ? -1 : 1;
  return (x->id > y->id) - (x->id < y->id);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double field_value(const vm_field *f, int64_t i) {
  return f->type == VM_FIELD_F64 ? ((const double *)f->data)[i * f->ncomp]
                                 : (double)((const int32_t *)f->data)[i * f->ncomp];
}

/* Find a field by name, element fields first; VM_ERR_ARG naming what the
 * mesh has when it is absent. */
static int find_field(vm_ctx *ctx, const vm_mesh *m, const char *name, const vm_field **out) {
  *out = vm_mesh_find_field(m, name, VM_FIELD_ELEMENT);
  if (!*out) *out = vm_mesh_find_field(m, name, VM_FIELD_VERTEX);
  if (*out) return VM_OK;
  char have[256] = "";
  size_t len = 0;
  for (int i = 0; i < m->nfield && len + 1 < sizeof have; i++) {
    int n = snprintf(have + len, sizeof have - len, "%s%s", i ? ", " : "", m->fields[i].name);
    if (n < 0) break;
    len += (size_t)n;
  }
  return vm_error(ctx, VM_ERR_ARG, "report: the mesh has no field '%s' (fields: %s)", name,
                  m->nfield ? have : "none");
}

/* Colour scale of values (2nd to 98th percentile; symmetric and diverging
 * when they change sign). */
static int value_scale(vm_ctx *ctx, const double *v, int64_t n, scale *s) {
  double *w = vm_alloc_array(ctx, (size_t)(n ? n : 1), sizeof *w);
  if (!w) return VM_ERR_NOMEM;
  int64_t k = 0;
  for (int64_t i = 0; i < n; i++)
    if (isfinite(v[i])) w[k++] = v[i];
  qsort(w, (size_t)k, sizeof *w, cmp_double);
  double lo = k ? w[(k - 1) * 2 / 100] : 0, hi = k ? w[(k - 1) * 98 / 100] : 1;
  if (k && hi <= lo) {
    lo = w[0];
    hi = w[k - 1];
  }
  vm_free(ctx, w);
  if (lo < 0 && hi > 0) {
    double a = fmax(-lo, hi);
    s->map = CMAP_DIVERGING;
    s->lo = -a;
    s->hi = a;
  } else {
    s->map = CMAP_VIRIDIS;
    s->lo = lo;
    s->hi = hi > lo ? hi : lo + (lo != 0 ? fabs(lo) : 1);
  }
  return VM_OK;
}

int vm_report_surface(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                      const char *field, const vm_report_view *view) {
  vm_ctx *ctx = r->ctx;
  if (!valid_name(name)) return vm_error(ctx, VM_ERR_ARG, "report: bad figure name");
  vm_report_view vw = view ? *view : vm_report_view_default();
  if (vw.width < 100 || vw.width > 8000 || vw.height < 100 || vw.height > 8000)
    return vm_error(ctx, VM_ERR_ARG, "report: image size %dx%d out of range", vw.width, vw.height);
  if (m->dim == 2) vw.elevation = 90; /* a planar mesh is seen from above */
  const vm_field *f = NULL;
  if (field) {
    int st = find_field(ctx, m, field, &f);
    if (st < 0) return st;
  }
  int64_t nf = 0;
  for (int64_t e = 0; e < m->ne; e++) nf += vm_elem_dim(m->etype[e]) == 2;
  if (!nf) return vm_error(ctx, VM_ERR_ARG, "report: %s: no triangles or quads to draw", name);

  double *val = vm_alloc_array(ctx, (size_t)nf, sizeof *val);
  double *sx = vm_alloc_array(ctx, (size_t)nf * 4, sizeof *sx);
  double *sy = vm_alloc_array(ctx, (size_t)nf * 4, sizeof *sy);
  double *shade = vm_alloc_array(ctx, (size_t)nf, sizeof *shade);
  depth_key *order = vm_alloc_array(ctx, (size_t)nf, sizeof *order);
  uint8_t *fnv = vm_alloc_array(ctx, (size_t)nf, 1); /* vertices of each face */
  double *sj = field ? NULL : vm_alloc_array(ctx, (size_t)m->ne, sizeof *sj);
  canvas c = {0};
  int st = val && sx && sy && shade && order && fnv && (field || sj) ? VM_OK : VM_ERR_NOMEM;
  if (st >= 0 && !field) st = vm_mesh_element_quality(m, NULL, NULL, sj, NULL);
  if (st < 0) goto out;

  /* eye: unit vector towards the viewer; right = z x eye, up = eye x right */
  double az = vw.azimuth * VM_PI / 180, el = vw.elevation * VM_PI / 180;
  double eye[3] = {cos(el) * cos(az), cos(el) * sin(az), sin(el)};
  double rt[3] = {-eye[1], eye[0], 0};
  double rl = hypot(rt[0], rt[1]);
  if (rl < 1e-9) {
    rt[0] = 1; /* looking straight down (or up): x to the right */
    rt[1] = 0;
  } else {
    rt[0] /= rl;
    rt[1] /= rl;
  }
  double up[3] = {eye[1] * rt[2] - eye[2] * rt[1], eye[2] * rt[0] - eye[0] * rt[2],
                  eye[0] * rt[1] - eye[1] * rt[0]};
  /* light from the viewer's upper left */
  double L[3];
  for (int i = 0; i < 3; i++) L[i] = 0.8 * eye[i] + 0.45 * up[i] - 0.35 * rt[i];
  double ll = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
  for (int i = 0; i < 3; i++) L[i] /= ll;

  double bx0 = INFINITY, bx1 = -INFINITY, by0 = INFINITY, by1 = -INFINITY, elen = 0;
  int64_t nedge = 0, k = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 2) continue;
    int nv = vm_elem_nverts(t);
    const int32_t *cv = m->conn + m->eoff[e];
    double nrm[3] = {0, 0, 0}, depth = 0, fv = 0;
    for (int i = 0; i < nv; i++) {
      const double *a = m->xyz + 3 * cv[i], *b = m->xyz + 3 * cv[(i + 1) % nv];
      nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
      nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
      nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
      double X = a[0] * rt[0] + a[1] * rt[1] + a[2] * rt[2];
      double Y = -(a[0] * up[0] + a[1] * up[1] + a[2] * up[2]);
      sx[4 * k + i] = X;
      sy[4 * k + i] = Y;
      depth += a[0] * eye[0] + a[1] * eye[1] + a[2] * eye[2];
      if (X < bx0) bx0 = X;
      if (X > bx1) bx1 = X;
      if (Y < by0) by0 = Y;
      if (Y > by1) by1 = Y;
      if (f && f->location == VM_FIELD_VERTEX) fv += field_value(f, cv[i]);
    }
    for (int i = 0; i < nv; i++) {
      int j = (i + 1) % nv;
      elen += hypot(sx[4 * k + j] - sx[4 * k + i], sy[4 * k + j] - sy[4 * k + i]);
      nedge++;
    }
    double nl = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    double lam = nl > 0 ? fabs(nrm[0] * L[0] + nrm[1] * L[1] + nrm[2] * L[2]) / nl : 0;
    shade[k] = 0.35 + 0.65 * lam;
    val[k] = !f ? sj[e] : f->location == VM_FIELD_VERTEX ? fv / nv : field_value(f, e);
    fnv[k] = (uint8_t)nv;
    order[k].depth = depth / nv;
    order[k].id = k;
    k++;
  }
  scale sc = {CMAP_QUALITY, -1, 1};
  if (f) st = value_scale(ctx, val, nf, &sc);
  if (st < 0) goto out;
  qsort(order, (size_t)nf, sizeof *order, cmp_depth); /* far to near */

  st = canvas_open(r, &c, vw.width, vw.height);
  if (st < 0) goto out;
  cairo_t *cr = c.cr;
  double ml = 20, mr = 150, mt = 50, mb = 20;
  double dx = bx1 - bx0, dy = by1 - by0;
  double s =
      fmin((vw.width - ml - mr) / (dx > 0 ? dx : 1), (vw.height - mt - mb) / (dy > 0 ? dy : 1));
  double ox = ml + 0.5 * (vw.width - ml - mr - s * dx) - s * bx0;
  double oy = mt + 0.5 * (vw.height - mt - mb - s * dy) - s * by0;
  int edges = vw.edges > 0 || (vw.edges < 0 && nedge && s * elen / nedge >= 5);
  for (int64_t i = 0; i < nf; i++) {
    int64_t q = order[i].id;
    for (int j = 0; j < fnv[q]; j++) {
      double X = ox + s * sx[4 * q + j], Y = oy + s * sy[4 * q + j];
      if (j)
        cairo_line_to(cr, X, Y);
      else
        cairo_move_to(cr, X, Y);
    }
    cairo_close_path(cr);
    rgb col = isnan(val[q]) ? (rgb){0.6, 0.6, 0.6} : colormap(sc.map, scale_t(&sc, val[q]));
    cairo_set_source_rgb(cr, col.r * shade[q], col.g * shade[q], col.b * shade[q]);
    cairo_fill_preserve(cr);
    /* the same colour along the border hides antialiasing seams */
    cairo_set_line_width(cr, 0.6);
    cairo_stroke_preserve(cr);
    if (edges) {
      cairo_set_source_rgba(cr, 0, 0, 0, 0.45);
      cairo_set_line_width(cr, 0.5);
      cairo_stroke(cr);
    } else {
      cairo_new_path(cr);
    }
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  char buf[200];
  snprintf(buf, sizeof buf, "%s: %lld faces, view azimuth %g, elevation %g", name, (long long)nf,
           vw.azimuth, vw.elevation);
  text(cr, 20, 14, 15, 0, 0, buf);
  colour_bar(cr, vw.width - 110, 90, 22, vw.height - 160, &sc, field ? field : "scaled Jacobian");
  st = canvas_finish(r, &c, name, caption);
out:
  canvas_free(&c);
  vm_free(ctx, val);
  vm_free(ctx, sx);
  vm_free(ctx, sy);
  vm_free(ctx, shade);
  vm_free(ctx, order);
  vm_free(ctx, fnv);
  vm_free(ctx, sj);
  return st;
}

/* ---- a slice through a volume mesh ------------------------------------------ */

static const int edges_tet[][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
static const int edges_pyr[][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}};
static const int edges_prism[][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5},
                                     {5, 3}, {0, 3}, {1, 4}, {2, 5}};
static const int edges_hex[][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                   {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

static int elem_edges(int t, const int (**ed)[2]) {
  switch (t) {
  case VM_TET: *ed = edges_tet; return 6;
  case VM_PYRAMID: *ed = edges_pyr; return 8;
  case VM_PRISM: *ed = edges_prism; return 9;
  case VM_HEX: *ed = edges_hex; return 12;
  default: *ed = NULL; return 0;
  }
}

typedef struct {
  double ang;
  int id;
} angle_key;

static int cmp_angle(const void *a, const void *b) {
  const angle_key *x = a, *y = b;
  if (x->ang != y->ang) return x->ang < y->ang ? -1 : 1;
  return (x->id > y->id) - (x->id < y->id);
}

/* Signed distance of a vertex from the plane; a vertex on it counts as above. */
static int above(double d) { return d >= 0; }

int vm_report_slice(vm_report *r, const char *name, const char *caption, const vm_mesh *m, int axis,
                    double value, const char *field) {
  return vm_report_slice_window(r, name, caption, m, axis, value, field, NULL, NULL);
}

int vm_report_slice_window(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                           int axis, double value, const char *field, const double wlo[3],
                           const double whi[3]) {
  vm_ctx *ctx = r->ctx;
  if (!valid_name(name)) return vm_error(ctx, VM_ERR_ARG, "report: bad figure name");
  if (axis < 0 || axis > 2) return vm_error(ctx, VM_ERR_ARG, "report: slice axis %d", axis);
  const vm_field *f = NULL;
  if (field) {
    int st = find_field(ctx, m, field, &f);
    if (st < 0) return st;
  }
  int64_t n3 = 0;
  for (int64_t e = 0; e < m->ne; e++) n3 += vm_elem_dim(m->etype[e]) == 3;
  if (!n3) return vm_error(ctx, VM_ERR_ARG, "report: %s: no volume elements to slice", name);
  int a0 = axis == 0 ? 1 : 0, a1 = axis == 2 ? 1 : 2; /* in-plane axes */
  double lo[3], hi[3];
  vm_mesh_bounds(m, lo, hi);
  if (isnan(value)) value = 0.5 * (lo[axis] + hi[axis]);
  if (wlo && whi)
    for (int k = 0; k < 3; k++)
      if (k != axis) lo[k] = wlo[k], hi[k] = whi[k];

  /* the cut polygon of every element the plane crosses: up to 12 points */
  double *sj = f ? NULL : vm_alloc_array(ctx, (size_t)m->ne, sizeof *sj);
  int64_t *cut = vm_alloc_array(ctx, (size_t)n3, sizeof *cut);
  double *val = vm_alloc_array(ctx, (size_t)n3, sizeof *val);
  int st = (f || sj) && cut && val ? VM_OK : VM_ERR_NOMEM;
  if (st >= 0 && !f) st = vm_mesh_element_quality(m, NULL, NULL, sj, NULL);
  canvas c = {0};
  if (st < 0) goto out;
  int64_t ncut = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int t = m->etype[e];
    if (vm_elem_dim(t) != 3) continue;
    const int32_t *cv = m->conn + m->eoff[e];
    int nv = vm_elem_nverts(t), na = 0, out0 = 0, out1 = 0, out2 = 0, out3 = 0;
    for (int i = 0; i < nv; i++) {
      const double *x = m->xyz + 3 * cv[i];
      na += above(x[axis] - value);
      out0 += x[a0]<lo[a0], out1 += x[a0]> hi[a0], out2 += x[a1]<lo[a1], out3 += x[a1]> hi[a1];
    }
    if (na == 0 || na == nv) continue;
    /* outside the window (all its vertices beyond one side of it) */
    if (wlo && (out0 == nv || out1 == nv || out2 == nv || out3 == nv)) continue;
    const int(*ed)[2];
    int nedges = elem_edges(t, &ed), np = 0;
    double fv = 0;
    for (int i = 0; i < nedges; i++) {
      int p = cv[ed[i][0]], q = cv[ed[i][1]];
      double dp = m->xyz[3 * p + axis] - value, dq = m->xyz[3 * q + axis] - value;
      if (above(dp) == above(dq)) continue;
      double s = dp / (dp - dq);
      if (f && f->location == VM_FIELD_VERTEX)
        fv += field_value(f, p) + s * (field_value(f, q) - field_value(f, p));
      np++;
    }
    val[ncut] = !f ? sj[e] : f->location == VM_FIELD_VERTEX ? fv / np : field_value(f, e);
    cut[ncut++] = e;
  }
  scale sc = {CMAP_QUALITY, -1, 1};
  if (f) {
    st = value_scale(ctx, val, ncut, &sc);
    if (st < 0) goto out;
    if (sc.map == CMAP_VIRIDIS) {
      /* min..max, not percentiles: a layer index shows every layer */
      double a = INFINITY, b = -INFINITY;
      for (int64_t i = 0; i < ncut; i++)
        if (isfinite(val[i])) {
          a = fmin(a, val[i]);
          b = fmax(b, val[i]);
        }
      if (b > a) {
        sc.lo = a;
        sc.hi = b;
      }
    }
  }

  int W = 1000, H = 900;
  st = canvas_open(r, &c, W, H);
  if (st < 0) goto out;
  cairo_t *cr = c.cr;
  double ml = 70, mr = 150, mt = 50, mb = 50;
  double dx = hi[a0] - lo[a0], dy = hi[a1] - lo[a1];
  if (!(dx > 0)) dx = 1;
  if (!(dy > 0)) dy = 1;
  double s = fmin((W - ml - mr) / dx, (H - mt - mb) / dy);
  double ox = ml + 0.5 * (W - ml - mr - s * dx) - s * lo[a0];
  double oy = mt + 0.5 * (H - mt - mb - s * dy) + s * hi[a1]; /* y up */
  cairo_set_source_rgb(cr, 0.97, 0.97, 0.97);
  cairo_rectangle(cr, ox + s * lo[a0], oy - s * hi[a1], s * dx, s * dy);
  cairo_fill(cr);
  cairo_save(cr);
  cairo_rectangle(cr, ox + s * lo[a0], oy - s * hi[a1], s * dx, s * dy);
  cairo_clip(cr); /* a window: the cells crossing its border are cut at it */
  /* pass 0 fills the cut polygons in element order, pass 1 draws the cuts
   * of the element faces on top, so folded (tangled) cells show their lines */
  for (int pass = 0; pass < 2; pass++) {
    for (int64_t i = 0; i < ncut; i++) {
      int64_t e = cut[i];
      int t = m->etype[e];
      const int32_t *cv = m->conn + m->eoff[e];
      if (pass == 0) {
        const int(*ed)[2];
        int nedges = elem_edges(t, &ed), np = 0;
        double px[12], py[12], cx = 0, cy = 0;
        for (int j = 0; j < nedges; j++) {
          const double *p = m->xyz + 3 * cv[ed[j][0]], *q = m->xyz + 3 * cv[ed[j][1]];
          double dp = p[axis] - value, dq = q[axis] - value;
          if (above(dp) == above(dq)) continue;
          double u = dp / (dp - dq);
          px[np] = p[a0] + u * (q[a0] - p[a0]);
          py[np] = p[a1] + u * (q[a1] - p[a1]);
          cx += px[np];
          cy += py[np];
          np++;
        }
        angle_key ak[12];
        for (int j = 0; j < np; j++) {
          ak[j].ang = atan2(py[j] - cy / np, px[j] - cx / np);
          ak[j].id = j;
        }
        qsort(ak, (size_t)np, sizeof *ak, cmp_angle);
        for (int j = 0; j < np; j++) {
          double X = ox + s * px[ak[j].id], Y = oy - s * py[ak[j].id];
          if (j)
            cairo_line_to(cr, X, Y);
          else
            cairo_move_to(cr, X, Y);
        }
        cairo_close_path(cr);
        rgb col = isnan(val[i]) ? (rgb){0.6, 0.6, 0.6} : colormap(sc.map, scale_t(&sc, val[i]));
        cairo_set_source_rgb(cr, col.r, col.g, col.b);
        cairo_set_line_width(cr, 0.6);
        cairo_fill_preserve(cr);
        cairo_stroke(cr);
      } else {
        int faces[6][4], nfv[6];
        int nfaces = vm_elem_faces(t, faces, nfv);
        for (int fc = 0; fc < nfaces; fc++) {
          double qx[4], qy[4];
          int nq = 0;
          for (int j = 0; j < nfv[fc]; j++) {
            const double *p = m->xyz + 3 * cv[faces[fc][j]];
            const double *q = m->xyz + 3 * cv[faces[fc][(j + 1) % nfv[fc]]];
            double dp = p[axis] - value, dq = q[axis] - value;
            if (above(dp) == above(dq)) continue;
            double u = dp / (dp - dq);
            qx[nq] = p[a0] + u * (q[a0] - p[a0]);
            qy[nq] = p[a1] + u * (q[a1] - p[a1]);
            nq++;
          }
          for (int j = 0; j + 1 < nq; j += 2) {
            cairo_move_to(cr, ox + s * qx[j], oy - s * qy[j]);
            cairo_line_to(cr, ox + s * qx[j + 1], oy - s * qy[j + 1]);
          }
        }
      }
    }
    if (pass == 1) {
      cairo_set_source_rgba(cr, 0, 0, 0, 0.7);
      cairo_set_line_width(cr, ncut > 20000 ? 0.3 : 0.7);
      cairo_stroke(cr);
    }
  }
  cairo_restore(cr);
  /* frame with the bounding box's coordinates */
  static const char axn[3] = {'x', 'y', 'z'};
  char buf[200];
  panel p = {ox + s * lo[a0], oy - s * hi[a1], s * dx, s * dy, lo[a0], hi[a0], lo[a1], hi[a1], 0};
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_set_line_width(cr, 1);
  cairo_rectangle(cr, p.x0, p.y0, p.w, p.h);
  cairo_stroke(cr);
  char lab[2] = {axn[a0], 0};
  fmt_num(buf, sizeof buf, lo[a0]);
  text(cr, p.x0, p.y0 + p.h + 6, 11, 0, 0, buf);
  fmt_num(buf, sizeof buf, hi[a0]);
  text(cr, p.x0 + p.w, p.y0 + p.h + 6, 11, 1, 0, buf);
  text(cr, p.x0 + p.w / 2, p.y0 + p.h + 6, 12, 0.5, 0, lab);
  lab[0] = axn[a1];
  fmt_num(buf, sizeof buf, lo[a1]);
  text(cr, p.x0 - 6, p.y0 + p.h, 11, 1, 1, buf);
  fmt_num(buf, sizeof buf, hi[a1]);
  text(cr, p.x0 - 6, p.y0, 11, 1, 0, buf);
  text(cr, p.x0 - 6, p.y0 + p.h / 2, 12, 1, 0.5, lab);
  cairo_set_source_rgb(cr, 0, 0, 0);
  snprintf(buf, sizeof buf, "%s: plane %c = %.6g, %lld of %lld volume elements cut", name,
           axn[axis], value, (long long)ncut, (long long)n3);
  text(cr, 20, 14, 15, 0, 0, buf);
  colour_bar(cr, W - 110, 90, 22, H - 180, &sc, field ? field : "scaled Jacobian");
  st = canvas_finish(r, &c, name, caption);
out:
  canvas_free(&c);
  vm_free(ctx, sj);
  vm_free(ctx, cut);
  vm_free(ctx, val);
  return st;
}

#else /* !VM_HAVE_CAIRO */

static int no_cairo(vm_report *r) {
  return vm_error(r->ctx, VM_ERR_UNSUPPORTED,
                  "reports need cairo, and this varmesh was built "
                  "without it");
}

int vm_report_histograms(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                         const vm_quality_opts *opts) {
  (void)name, (void)caption, (void)m, (void)opts;
  return no_cairo(r);
}

int vm_report_convergence(vm_report *r, const char *name, const char *caption,
                          const vm_report_history *h) {
  (void)name, (void)caption, (void)h;
  return no_cairo(r);
}

vm_report_view vm_report_view_default(void) {
  vm_report_view v = {-60, 25, 1000, 700, -1};
  return v;
}

int vm_report_surface(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                      const char *field, const vm_report_view *view) {
  (void)name, (void)caption, (void)m, (void)field, (void)view;
  return no_cairo(r);
}

int vm_report_slice(vm_report *r, const char *name, const char *caption, const vm_mesh *m, int axis,
                    double value, const char *field) {
  (void)name, (void)caption, (void)m, (void)axis, (void)value, (void)field;
  return no_cairo(r);
}

#endif /* VM_HAVE_CAIRO */
