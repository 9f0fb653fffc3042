#!/usr/bin/env bash
# test/cli/test_docs_cli.sh: the docs keep up with the programs: every
# option of a program appears on its page docs/cli/PROG.md (--help and
# --version are documented once, in docs/cli.md), and docs/cli.md links
# every page. The options come from the program's option table (the hidden
# --list-options), and each is in --help.
set -u
root=$1
shift
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
for prog in "$@"; do
  name=$(basename "$prog")
  page="$root/docs/cli/$name.md"
  check '[ -f "$page" ]' "$name has a page"
  [ -f "$page" ] || continue
  opts=$("$prog" --list-options 2>/dev/null)
  check '[ -n "$opts" ]' "$name --list-options lists options"
  help=$("$prog" --help)
  missing=
  for o in $opts; do
    grep -q -- "$o\b" <<<"$help" || missing="$missing $o"
  done
  check '[ -z "$missing" ]' "$name: every option of its table in --help (missing:${missing:- none})"
  missing=
  for o in $opts; do
    case $o in --help|--version) continue ;; esac
    grep -q -- "$o\b" "$page" || missing="$missing $o"
  done
  check '[ -z "$missing" ]' "$name: every option on its page (missing:${missing:- none})"
  check 'grep -q "(cli/$name.md)" "$root/docs/cli.md"' "docs/cli.md links $name's page"
done
check 'grep -q -- "--help" "$root/docs/cli.md" && grep -q -- "--version" "$root/docs/cli.md"' "docs/cli.md documents --help and --version"
exit $fail
