/* apps/cli.h: what every varmesh command-line program shares: exit codes,
 * the stderr log callback, strict number parsing, context setup. */
#ifndef VARMESH_APPS_CLI_H
#define VARMESH_APPS_CLI_H

#include <stddef.h>
#include <stdio.h>

#include "varmesh/ctx.h"

/* Exit codes shared by every vm-* program (docs/cli.md). */
enum {
  VM_EXIT_OK = 0,
  VM_EXIT_INPUT = 1, /* bad input file or failed I/O */
  VM_EXIT_USAGE = 2, /* bad command line */
  VM_EXIT_CHECK = 3, /* a requested check failed / result not valid */
  VM_EXIT_INTERRUPTED = 4
};

typedef struct vm_cli {
  const char *prog;
  int quiet; /* suppress info/progress on stderr */
  int verbose;
  vm_ctx *ctx;
} vm_cli;

/* Create the context, install the stderr logger and the surface formats.
 * Exits with VM_EXIT_INPUT if the context cannot be made. */
void vm_cli_init(vm_cli *cli, const char *prog);
void vm_cli_finish(vm_cli *cli);
/* The log callback vm_cli_init installs (user: the vm_cli): warnings, and
 * info unless quiet, on stderr with control bytes escaped. */
void vm_cli_log(void *user, int level, const char *msg);
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
/* "prog: error: <path>: <ctx message>" (without "<path>: " if path is NULL)
 * on stderr; returns VM_EXIT_INPUT. */
int vm_cli_input_error(const vm_cli *cli, const char *path);
/* Usage error: message + hint, returns VM_EXIT_USAGE. */
int vm_cli_usage_error(const vm_cli *cli, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* For a program that parses its command line itself (vm-prism; the others
 * use an option table, below):
 * --help (the usage text on stdout) or --version: returns 1 if `a` is one
 * of them (the program then exits 0), 0 otherwise. */
int vm_cli_info_option(const vm_cli *cli, const char *a, const char *usage);
/* An operand of the command line: `a` goes to the first empty one of
 * *slots[0..n); an option the program did not recognize ("-x") or one
 * operand too many is a usage error. Returns VM_EXIT_OK or VM_EXIT_USAGE. */
int vm_cli_operand(const vm_cli *cli, const char *a, const char **const *slots, int n);
/* The value of --format: the VM_FMT_* of `name` into *fmt, or a usage
 * error (VM_EXIT_USAGE) for a missing or unknown name. */
int vm_cli_format(const vm_cli *cli, const char *name, int *fmt);

/* For a stage whose result is a volume mesh (vm-prism, vm-fill, vm-volume):
 * a usage error (VM_EXIT_USAGE, nothing read or written) if `fmt` holds
 * surfaces only (STL, OBJ, OFF, PLY), else VM_EXIT_OK. */
int vm_cli_volume_output(const vm_cli *cli, const char *path, int fmt);

/* Option tables. A program describes its options once, in a static const
 * array of vm_opt ended by {0}; vm_cli_parse reads the command line from
 * it, and --help prints the usage text made from it. Values land in the
 * program's own struct of settings (`args`) at each option's `offset`.
 *
 *   VM_OPT_HEADING  not an option: `help` is printed as is (a heading, a
 *                   paragraph, a second usage line)
 *   VM_OPT_FLAG     no value: int at offset = `ival`
 *   VM_OPT_INT      int at offset, an integer in [lo, hi] (vm_cli_int)
 *   VM_OPT_DOUBLE   double at offset, a number in [lo, hi] (vm_cli_double)
 *   VM_OPT_STRING   const char * at offset = the value as given
 *   VM_OPT_CHOICE   int (or an enum) at offset = the index of the value in
 *                   `choices` (NULL-terminated); metavar defaults to "a|b|c"
 *   VM_OPT_CALL     fn(cli, opt, value, args) does it all; it takes a value
 *                   if and only if it has a metavar
 *
 * A value is always the next argument ("--theta 0.5"). `error`, if set,
 * is the usage error for a missing value, or a bad choice, after the
 * option's name ("expects a directory" -> "--report expects a directory");
 * without it a choice says "expects a, b or c" and a string "expects a
 * value". `help` is one paragraph, wrapped at word boundaries to 80
 * columns ('\n' breaks a line). */
typedef enum {
  VM_OPT_END = 0,
  VM_OPT_HEADING,
  VM_OPT_FLAG,
  VM_OPT_INT,
  VM_OPT_DOUBLE,
  VM_OPT_STRING,
  VM_OPT_CHOICE,
  VM_OPT_CALL
} vm_opt_kind;

typedef struct vm_opt vm_opt;
/* Returns VM_EXIT_OK, or an exit code after printing why (vm_cli_usage_error). */
typedef int (*vm_opt_fn)(vm_cli *cli, const vm_opt *opt, const char *value, void *args);

struct vm_opt {
  const char *name;  /* "--theta" */
  const char *alias; /* "-q", or NULL */
  vm_opt_kind kind;
  size_t offset;       /* offsetof(program's args, field) */
  const char *metavar; /* "T" in "--theta T"; NULL for flags */
  const char *help;
  double lo, hi; /* INT, DOUBLE: the accepted range */
  int ival;      /* FLAG: the value stored */
  const char *const *choices;
  vm_opt_fn fn;
  const char *error;
};

typedef struct vm_cli_spec {
  const char *usage; /* --help's text before the options: usage, description */
  const vm_opt *opts;
  const char *epilog; /* after the options ("exit: ...") */
  size_t operand[3];  /* offsets of the operands (const char *) in args, in order */
  int noperands;
  const char *missing; /* the usage error when an operand is missing; NULL: the
                          program checks */
} vm_cli_spec;

/* Returned by vm_cli_parse when the program should go on. */
enum { VM_CLI_RUN = -1 };

/* Parse argv[0..argc) (the program name not included) in order: options
 * by the table (--help, --version and the hidden --list-options, which
 * prints every option's long name on a line, are always there), other
 * arguments into the operands. Returns VM_CLI_RUN, or the code to exit
 * with: VM_EXIT_OK after --help/--version/--list-options, VM_EXIT_USAGE
 * (or a callback's code) after one usage error on stderr. */
int vm_cli_parse(vm_cli *cli, const vm_cli_spec *spec, void *args, int argc, char **argv);
/* --help's text, as vm_cli_parse prints it. */
void vm_cli_print_help(const vm_cli_spec *spec, FILE *f);

/* Callbacks for the options most programs share:
 *   -q, --quiet       cli->quiet = 1
 *   -v, --verbose     cli->verbose = 1 (debug messages too)
 *   --threads N       vm_ctx_set_threads, N in [0, 4 x the online cores]
 *   --format F        int at offset = vm_cli_format(F); a missing value is
 *                     `error` if the option has one */
int vm_cli_opt_quiet(vm_cli *cli, const vm_opt *opt, const char *value, void *args);
int vm_cli_opt_verbose(vm_cli *cli, const vm_opt *opt, const char *value, void *args);
int vm_cli_opt_threads(vm_cli *cli, const vm_opt *opt, const char *value, void *args);
int vm_cli_opt_format(vm_cli *cli, const vm_opt *opt, const char *value, void *args);
/* Does the path name a polygon soup format (.stl .obj .off .ply: no shared
 * vertices promised, the surface stage repairs it)? */
int vm_cli_soup_format(const char *path);
#define VM_CLI_OPT_QUIET(help)                                                                     \
  { "--quiet", "-q", VM_OPT_CALL, 0, NULL, help, .fn = vm_cli_opt_quiet }
#define VM_CLI_OPT_VERBOSE(help)                                                                   \
  { "--verbose", "-v", VM_OPT_CALL, 0, NULL, help, .fn = vm_cli_opt_verbose }
#define VM_CLI_OPT_THREADS                                                                         \
  {                                                                                                \
    "--threads", NULL, VM_OPT_CALL, 0, "N", "OpenMP threads (results do not depend on it)",        \
        .fn = vm_cli_opt_threads                                                                   \
  }

/* Strict parsing of an option value: the whole string must be a number in
 * range. Return 0 on success, nonzero (after a usage message) otherwise. */
int vm_cli_double(const vm_cli *cli, const char *opt, const char *s, double lo, double hi,
                  double *out);
int vm_cli_int(const vm_cli *cli, const char *opt, const char *s, long lo, long hi, long *out);

/* Print a double as JSON (null for NaN/Inf). */
void vm_json_double(FILE *f, double x);
/* Print n doubles as a JSON array. */
void vm_json_doubles(FILE *f, const double *x, int n);
/* Print a JSON string literal with escapes. */
void vm_json_string(FILE *f, const char *s);

#endif
