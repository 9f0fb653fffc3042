/* apps/cli.h: what every varmesh command-line program shares: exit codes,
 * the stderr log callback, strict number parsing, context setup. */
#ifndef VARMESH_APPS_CLI_H
#define VARMESH_APPS_CLI_H

#include <stdio.h>

#include "varmesh/ctx.h"

/* Exit codes shared by every vm-* program (docs/cli.md). */
enum {
  VM_EXIT_OK = 0,
  VM_EXIT_INPUT = 1,   /* bad input file or failed I/O */
  VM_EXIT_USAGE = 2,   /* bad command line */
  VM_EXIT_CHECK = 3,   /* a requested check failed / result not valid */
  VM_EXIT_INTERRUPTED = 4
};

typedef struct vm_cli {
  const char *prog;
  int quiet;   /* suppress info/progress on stderr */
  int verbose;
  vm_ctx *ctx;
} vm_cli;

/* Create the context, install the stderr logger and the surface formats.
 * Exits with VM_EXIT_INPUT if the context cannot be made. */
void vm_cli_init(vm_cli *cli, const char *prog);
void vm_cli_finish(vm_cli *cli);
/* SIGINT and SIGTERM ask the library to stop at the next safe point
 * (vm_ctx_set_interrupt): the stage then writes its best state and exits
 * VM_EXIT_INTERRUPTED; a second signal exits at once with 128 + signal,
 * writing nothing. */
void vm_cli_catch_interrupts(vm_cli *cli);

/* "prog: error: <ctx message>" on stderr. */
void vm_cli_error(const vm_cli *cli, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Usage error: message + hint, returns VM_EXIT_USAGE. */
int vm_cli_usage_error(const vm_cli *cli, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* --help (the usage text on stdout) or --version: returns 1 if `a` is one
 * of them (the program then exits 0), 0 otherwise. */
int vm_cli_info_option(const vm_cli *cli, const char *a, const char *usage);
/* An operand of the command line: `a` goes to the first empty one of
 * *slots[0..n); an option the program did not recognize ("-x") or one
 * operand too many is a usage error. Returns VM_EXIT_OK or VM_EXIT_USAGE. */
int vm_cli_operand(const vm_cli *cli, const char *a, const char **const *slots, int n);
/* The value of --format: the VM_FMT_* of `name` into *fmt, or a usage
 * error (VM_EXIT_USAGE) for a missing or unknown name. */
int vm_cli_format(const vm_cli *cli, const char *name, int *fmt);

/* Strict parsing of an option value: the whole string must be a number in
 * range. Return 0 on success, nonzero (after a usage message) otherwise. */
int vm_cli_double(const vm_cli *cli, const char *opt, const char *s, double lo, double hi,
                  double *out);
int vm_cli_int(const vm_cli *cli, const char *opt, const char *s, long lo, long hi, long *out);

/* Print a double as JSON (null for NaN/Inf). */
void vm_json_double(FILE *f, double x);
/* Print a JSON string literal with escapes. */
void vm_json_string(FILE *f, const char *s);

#endif
