/* apps/cli.c: shared command-line plumbing for the vm-* programs. */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "varmesh/io.h"

/* A message as it reaches the terminal: control bytes (from a file's
 * contents quoted in a message: escape sequences could drive the terminal)
 * shown as \xHH, and one line. */
static void put_clean(const char *prefix, const char *msg, const char *suffix) {
  fputs(prefix, stderr);
  for (const unsigned char *p = (const unsigned char *)msg; *p; p++) {
    if (*p < 0x20 || *p == 0x7f)
      fprintf(stderr, "\\x%02x", *p);
    else
      fputc(*p, stderr);
  }
  fputs(suffix, stderr);
}

void vm_cli_log(void *user, int level, const char *msg) {
  const vm_cli *cli = user;
  if (level == VM_LOG_ERROR) return; /* errors are printed by the caller, once */
  if (cli->quiet && level >= VM_LOG_INFO) return;
  if (level == VM_LOG_DEBUG && !cli->verbose) return;
  char pre[160];
  snprintf(pre, sizeof pre, "%s: %s", cli->prog, level == VM_LOG_WARN ? "warning: " : "");
  put_clean(pre, msg, "\n");
}

static volatile int cli_interrupted;

/* A stage that stops at a safe point: the first signal asks it to, a
 * second one ends the program at once, without a temporary file left. */
static void on_signal(int sig) {
  if (cli_interrupted) {
    vm_io_remove_temporaries();
    _exit(128 + sig);
  }
  cli_interrupted = 1;
}

/* Every other program (and every program until it asks for the above):
 * the first signal ends it at once, without a temporary file left. */
static void on_signal_exit(int sig) {
  vm_io_remove_temporaries();
  _exit(128 + sig);
}

void vm_cli_catch_interrupts(vm_cli *cli) {
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  vm_ctx_set_interrupt(cli->ctx, &cli_interrupted);
}

/* libgomp reads OMP_WAIT_POLICY once, when it is loaded (before main), and
 * its default spins idle threads for a while, which costs several times the
 * run time beside any other busy process (issue #23). If the variable is
 * unset, set it to passive and execute this program again, once (the
 * second start finds it set); the arguments come from /proc/self/cmdline.
 * If anything fails the program just goes on with the default. */
static void omp_passive_reexec(void) {
#ifdef __linux__
  if (getenv("OMP_WAIT_POLICY")) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 1)) return;
  FILE *f = fopen("/proc/self/cmdline", "rb");
  if (!f) return;
  static char buf[1 << 16];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  int trunc = !feof(f);
  fclose(f);
  if (trunc || n == 0) return;
  buf[n] = 0;
  static char *argv[4096];
  int argc = 0;
  for (size_t k = 0; k < n && argc < 4095; k += strlen(buf + k) + 1) argv[argc++] = buf + k;
  if (argc == 4095) return;
  argv[argc] = NULL;
  fflush(NULL);
  execv("/proc/self/exe", argv);
#endif
}

void vm_cli_init(vm_cli *cli, const char *prog) {
  omp_passive_reexec();
  memset(cli, 0, sizeof *cli);
  cli->prog = prog;
  if (vm_ctx_create(&cli->ctx) != VM_OK) {
    fprintf(stderr, "%s: error: out of memory\n", prog);
    exit(VM_EXIT_INPUT);
  }
  vm_ctx_set_log(cli->ctx, vm_cli_log, cli);
  signal(SIGINT, on_signal_exit);
  signal(SIGTERM, on_signal_exit);
  signal(SIGHUP, on_signal_exit);
}

void vm_cli_finish(vm_cli *cli) { vm_ctx_destroy(&cli->ctx); }

void vm_cli_error(const vm_cli *cli, const char *fmt, ...) {
  char buf[1200];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  char pre[160];
  snprintf(pre, sizeof pre, "%s: error: ", cli->prog);
  put_clean(pre, buf, "\n");
}

int vm_cli_input_error(const vm_cli *cli, const char *path) {
  if (path)
    vm_cli_error(cli, "%s: %s", path, vm_ctx_error(cli->ctx));
  else
    vm_cli_error(cli, "%s", vm_ctx_error(cli->ctx));
  return VM_EXIT_INPUT;
}

int vm_cli_usage_error(const vm_cli *cli, const char *fmt, ...) {
  char buf[1200];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  char pre[160], post[160];
  snprintf(pre, sizeof pre, "%s: error: ", cli->prog);
  snprintf(post, sizeof post, " (see %s --help)\n", cli->prog);
  put_clean(pre, buf, post);
  return VM_EXIT_USAGE;
}

int vm_cli_info_option(const vm_cli *cli, const char *a, const char *usage) {
  if (!strcmp(a, "--help")) {
    fputs(usage, stdout);
    return 1;
  }
  if (!strcmp(a, "--version")) {
    printf("%s (varmesh) %s\n", cli->prog, vm_version());
    return 1;
  }
  return 0;
}

int vm_cli_operand(const vm_cli *cli, const char *a, const char **const *slots, int n) {
  if (a[0] == '-' && a[1]) return vm_cli_usage_error(cli, "unknown option '%s'", a);
  for (int k = 0; k < n; k++)
    if (!*slots[k]) {
      *slots[k] = a;
      return VM_EXIT_OK;
    }
  return vm_cli_usage_error(cli, "too many arguments");
}

int vm_cli_format(const vm_cli *cli, const char *name, int *fmt) {
  int f = name ? vm_format_from_name(name) : VM_FMT_AUTO;
  if (f == VM_FMT_AUTO) return vm_cli_usage_error(cli, "unknown format '%s'", name ? name : "");
  *fmt = f;
  return VM_EXIT_OK;
}

int vm_cli_double(const vm_cli *cli, const char *opt, const char *s, double lo, double hi,
                  double *out) {
  char *e;
  errno = 0;
  double x = s ? strtod(s, &e) : NAN;
  if (!s || !*s || *e || errno || !(x >= lo && x <= hi)) {
    vm_cli_usage_error(cli, "%s expects a number in [%g, %g], got '%s'", opt, lo, hi, s ? s : "");
    return 1;
  }
  *out = x;
  return 0;
}

int vm_cli_int(const vm_cli *cli, const char *opt, const char *s, long lo, long hi, long *out) {
  char *e;
  errno = 0;
  long x = s ? strtol(s, &e, 10) : 0;
  if (!s || !*s || *e || errno || x < lo || x > hi) {
    vm_cli_usage_error(cli, "%s expects an integer in [%ld, %ld], got '%s'", opt, lo, hi,
                       s ? s : "");
    return 1;
  }
  *out = x;
  return 0;
}

void vm_json_double(FILE *f, double x) {
  if (isfinite(x))
    fprintf(f, "%.17g", x);
  else
    fputs("null", f);
}

void vm_json_doubles(FILE *f, const double *x, int n) {
  fputc('[', f);
  for (int k = 0; k < n; k++) {
    if (k) fputs(", ", f);
    vm_json_double(f, x[k]);
  }
  fputc(']', f);
}

void vm_json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (; *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\')
      fprintf(f, "\\%c", c);
    else if (c < 0x20)
      fprintf(f, "\\u%04x", c);
    else
      fputc(c, f);
  }
  fputc('"', f);
}

/* Option tables (cli.h). */

static int pick(const char *v, const char *const *names) {
  for (int i = 0; v && names[i]; i++)
    if (!strcmp(v, names[i])) return i;
  return -1;
}

static int takes_value(const vm_opt *o) {
  return o->kind == VM_OPT_INT || o->kind == VM_OPT_DOUBLE || o->kind == VM_OPT_STRING ||
         o->kind == VM_OPT_CHOICE || (o->kind == VM_OPT_CALL && o->metavar);
}

/* "  -q, --quiet", "  --theta T", "  --repair auto|yes|no" into buf; its length */
static int opt_column(const vm_opt *o, char *buf, size_t n) {
  int len = snprintf(buf, n, "  %s%s%s", o->alias ? o->alias : "", o->alias ? ", " : "", o->name);
  if (o->metavar && len < (int)n)
    len += snprintf(buf + len, n - (size_t)len, " %s", o->metavar);
  else if (o->kind == VM_OPT_CHOICE)
    for (int i = 0; o->choices[i] && (size_t)len < n; i++)
      len += snprintf(buf + len, n - (size_t)len, "%c%s", i ? '|' : ' ', o->choices[i]);
  return len < (int)n ? len : (int)n - 1;
}

/* Help columns wider than this start their help on the next line; help
 * text is wrapped at word boundaries to end before column HELP_LINE_MAX. */
enum { HELP_COLUMN_MAX = 28, HELP_LINE_MAX = 80 };

static void print_wrapped(FILE *f, const char *h, int width) {
  int col = width;
  while (*h) {
    size_t n = strcspn(h, " \n");
    if (*h == ' ' || *h == '\n') {
      if (*h++ == '\n' && *h) col = fprintf(f, "\n%*s", width, "") - 1;
      continue;
    }
    if (col > width && col + 1 + (int)n >= HELP_LINE_MAX)
      col = fprintf(f, "\n%*s", width, "") - 1;
    else if (col > width)
      col += fprintf(f, " ");
    col += (int)fwrite(h, 1, n, f);
    h += n;
  }
  fputc('\n', f);
}

void vm_cli_print_help(const vm_cli_spec *spec, FILE *f) {
  char col[256];
  int width = 0;
  for (const vm_opt *o = spec->opts; o->kind; o++) {
    int len = o->kind == VM_OPT_HEADING ? 0 : opt_column(o, col, sizeof col);
    if (len <= HELP_COLUMN_MAX && len > width) width = len;
  }
  width += 2;
  fputs(spec->usage, f);
  for (const vm_opt *o = spec->opts; o->kind; o++) {
    if (o->kind == VM_OPT_HEADING) {
      fputs(o->help, f);
      continue;
    }
    int len = opt_column(o, col, sizeof col);
    fputs(col, f);
    fprintf(f, len > HELP_COLUMN_MAX ? "\n%*s" : "%*s", len > HELP_COLUMN_MAX ? width : width - len,
            "");
    print_wrapped(f, o->help, width);
  }
  fputs("  --help, --version\n", f);
  if (spec->epilog) fputs(spec->epilog, f);
}

static int choice_error(const vm_cli *cli, const vm_opt *o) {
  if (o->error) return vm_cli_usage_error(cli, "%s %s", o->name, o->error);
  char list[512];
  int len = 0, n = 0;
  while (o->choices[n]) n++;
  for (int i = 0; i < n && len < (int)sizeof list; i++)
    len += snprintf(list + len, sizeof list - (size_t)len, "%s%s",
                    i == 0       ? ""
                    : i == n - 1 ? " or "
                                 : ", ",
                    o->choices[i]);
  return vm_cli_usage_error(cli, "%s expects %s", o->name, list);
}

static int apply(vm_cli *cli, const vm_opt *o, const char *val, void *args) {
  char *at = (char *)args + o->offset;
  long lv;
  int k;
  switch (o->kind) {
  case VM_OPT_FLAG: *(int *)at = o->ival; return VM_EXIT_OK;
  case VM_OPT_INT:
    if (vm_cli_int(cli, o->name, val, (long)o->lo, (long)o->hi, &lv)) return VM_EXIT_USAGE;
    *(int *)at = (int)lv;
    return VM_EXIT_OK;
  case VM_OPT_DOUBLE:
    return vm_cli_double(cli, o->name, val, o->lo, o->hi, (double *)at) ? VM_EXIT_USAGE
                                                                        : VM_EXIT_OK;
  case VM_OPT_STRING:
    if (!val)
      return vm_cli_usage_error(cli, "%s %s", o->name, o->error ? o->error : "expects a value");
    *(const char **)at = val;
    return VM_EXIT_OK;
  case VM_OPT_CHOICE:
    if ((k = pick(val, o->choices)) < 0) return choice_error(cli, o);
    *(int *)at = k;
    return VM_EXIT_OK;
  case VM_OPT_CALL: return o->fn(cli, o, val, args);
  default: return VM_EXIT_OK;
  }
}

int vm_cli_parse(vm_cli *cli, const vm_cli_spec *spec, void *args, int argc, char **argv) {
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    const vm_opt *o = spec->opts;
    while (o->kind && (o->kind == VM_OPT_HEADING ||
                       (strcmp(a, o->name) && !(o->alias && !strcmp(a, o->alias)))))
      o++;
    if (o->kind) {
      const char *val = NULL;
      if (takes_value(o)) val = ++i < argc ? argv[i] : NULL;
      int rc = apply(cli, o, val, args);
      if (rc != VM_EXIT_OK) return rc;
    } else if (!strcmp(a, "--help")) {
      vm_cli_print_help(spec, stdout);
      return VM_EXIT_OK;
    } else if (!strcmp(a, "--version")) {
      printf("%s (varmesh) %s\n", cli->prog, vm_version());
      return VM_EXIT_OK;
    } else if (!strcmp(a, "--list-options")) {
      for (o = spec->opts; o->kind; o++)
        if (o->kind != VM_OPT_HEADING) printf("%s\n", o->name);
      return VM_EXIT_OK;
    } else if (a[0] == '-' && a[1]) {
      return vm_cli_usage_error(cli, "unknown option '%s'", a);
    } else {
      int k = 0;
      while (k < spec->noperands && *(const char **)((char *)args + spec->operand[k])) k++;
      if (k == spec->noperands) return vm_cli_usage_error(cli, "too many arguments");
      *(const char **)((char *)args + spec->operand[k]) = a;
    }
  }
  for (int k = 0; spec->missing && k < spec->noperands; k++)
    if (!*(const char **)((char *)args + spec->operand[k]))
      return vm_cli_usage_error(cli, "%s", spec->missing);
  return VM_CLI_RUN;
}

int vm_cli_opt_quiet(vm_cli *cli, const vm_opt *opt, const char *value, void *args) {
  (void)opt, (void)value, (void)args;
  cli->quiet = 1;
  return VM_EXIT_OK;
}

int vm_cli_opt_verbose(vm_cli *cli, const vm_opt *opt, const char *value, void *args) {
  (void)opt, (void)value, (void)args;
  cli->verbose = 1;
  return VM_EXIT_OK;
}

int vm_cli_volume_output(const vm_cli *cli, const char *path, int fmt) {
  if (fmt == VM_FMT_STL || fmt == VM_FMT_OBJ || fmt == VM_FMT_OFF || fmt == VM_FMT_PLY)
    return vm_cli_usage_error(cli,
                              "%s: %s holds surfaces only and the result is a volume mesh; "
                              "write .vmsh, .vtu, .msh, .su2, .cgns or an OpenFOAM case",
                              path, vm_format_name(fmt));
  return VM_EXIT_OK;
}

int vm_cli_opt_threads(vm_cli *cli, const vm_opt *opt, const char *value, void *args) {
  long n;
  (void)args;
  /* at most 4 threads a core (and 4 on a machine that says nothing): libgomp
   * failed with its own message from 32,768 threads and crashed from 65,536 */
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  long most = 4 * (cores > 0 ? cores : 1);
  if (vm_cli_int(cli, opt->name, value, 0, most, &n)) return VM_EXIT_USAGE;
  vm_ctx_set_threads(cli->ctx, (int)n);
  return VM_EXIT_OK;
}

int vm_cli_opt_format(vm_cli *cli, const vm_opt *opt, const char *value, void *args) {
  if (!value && opt->error) return vm_cli_usage_error(cli, "%s %s", opt->name, opt->error);
  return vm_cli_format(cli, value, (int *)((char *)args + opt->offset));
}

int vm_cli_soup_format(const char *path) {
  int f = vm_format_from_path(path);
  return f == VM_FMT_STL || f == VM_FMT_OBJ || f == VM_FMT_OFF || f == VM_FMT_PLY;
}
