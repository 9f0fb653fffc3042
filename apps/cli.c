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

static void log_stderr(void *user, int level, const char *msg) {
  const vm_cli *cli = user;
  if (level == VM_LOG_ERROR) return; /* errors are printed by the caller, once */
  if (cli->quiet && level >= VM_LOG_INFO) return;
  if (level == VM_LOG_DEBUG && !cli->verbose) return;
  fprintf(stderr, "%s: %s%s\n", cli->prog, level == VM_LOG_WARN ? "warning: " : "", msg);
}

static volatile int cli_interrupted;

static void on_signal(int sig) {
  if (cli_interrupted) _exit(128 + sig);
  cli_interrupted = 1;
}

void vm_cli_catch_interrupts(vm_cli *cli) {
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  vm_ctx_set_interrupt(cli->ctx, &cli_interrupted);
}

void vm_cli_init(vm_cli *cli, const char *prog) {
  memset(cli, 0, sizeof *cli);
  cli->prog = prog;
  if (vm_ctx_create(&cli->ctx) != VM_OK) {
    fprintf(stderr, "%s: error: out of memory\n", prog);
    exit(VM_EXIT_INPUT);
  }
  vm_ctx_set_log(cli->ctx, log_stderr, cli);
}

void vm_cli_finish(vm_cli *cli) { vm_ctx_destroy(&cli->ctx); }

void vm_cli_error(const vm_cli *cli, const char *fmt, ...) {
  char buf[1200];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  fprintf(stderr, "%s: error: %s\n", cli->prog, buf);
}

int vm_cli_usage_error(const vm_cli *cli, const char *fmt, ...) {
  char buf[1200];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  fprintf(stderr, "%s: error: %s (see %s --help)\n", cli->prog, buf, cli->prog);
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
    vm_cli_usage_error(cli, "%s expects a number in [%g, %g], got '%s'", opt, lo, hi,
                       s ? s : "");
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
