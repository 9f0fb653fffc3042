#!/usr/bin/env bash
# test/fuzz/build.sh [OUTDIR]: build the libFuzzer reader harnesses
# (fuzz-<reader>), the sanitized corpus replay (replay) and the seed
# generator (gen_corpus) with clang, compiling the sources of lib/io and the
# context, mesh and topology of lib/core directly (the meson build is not
# touched). Default OUTDIR:
# build-fuzz/ at the top of the tree. Needs clang and libclang-rt-dev.
# Options: --regen-corpus also rewrites test/fuzz/corpus/*/gen-* with gen_corpus.
# Environment: CC (default clang); FUZZ_CFLAGS, extra flags for everything
# (e.g. -fno-sanitize=pointer-overflow to fuzz past a known finding).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
regen=0
if [ "${1:-}" = "--regen-corpus" ]; then regen=1; shift; fi
out=${1:-$root/build-fuzz}
CC=${CC:-clang}
readers="vmsh vmsht vtk vtu msh medit stl obj off ply su2"

# the sources of lib/io (every format; CGNS without libcgns), taken from its
# meson.build so a new reader is fuzzed without editing this script, and the
# parts of lib/core they use (context, mesh, topology; the rest of the core
# needs OpenMP and nothing of it is reached from a reader)
io_srcs=$(awk '/^io_sources = files\(/ {f=1; next} f && /^\)/ {f=0} f' "$root/lib/io/meson.build" |
  grep -o "src/[A-Za-z0-9_]*\.c" | sed "s|^|$root/lib/io/|")
[ -n "$io_srcs" ] || { echo "build.sh: no io_sources in lib/io/meson.build" >&2; exit 1; }
lib_srcs="$root/lib/core/src/ctx.c $root/lib/core/src/mesh.c $root/lib/core/src/topology.c $io_srcs"

common=(-std=c11 -D_POSIX_C_SOURCE=200809L -g -O1 -fno-omit-frame-pointer
        -Wall -Wextra -Wpedantic -Wno-unknown-pragmas
        -I"$root/lib/core/include" -I"$root/lib/io/include" -I"$root/lib/internal"
        -I"$root/lib/core/src" -I"$root/lib/io/src")
san=(-fsanitize=address,undefined -fno-sanitize-recover=all)
read -r -a extra <<<"${FUZZ_CFLAGS:-}"
san+=("${extra[@]}") # last, so that they can turn sanitizer checks off

mkdir -p "$out/obj-fuzz" "$out/obj-san"
# library objects twice: with fuzzer coverage (for the harnesses) and without
# (for replay, which has its own main)
objs_fuzz=() objs_san=()
for s in $lib_srcs; do
  b=$(basename "$s" .c)
  "$CC" "${common[@]}" "${san[@]}" -fsanitize=fuzzer-no-link -c "$s" -o "$out/obj-fuzz/$b.o"
  "$CC" "${common[@]}" "${san[@]}" -c "$s" -o "$out/obj-san/$b.o"
  objs_fuzz+=("$out/obj-fuzz/$b.o")
  objs_san+=("$out/obj-san/$b.o")
done
for r in $readers; do
  "$CC" "${common[@]}" "${san[@]}" -fsanitize=fuzzer -DVM_FUZZ_READER="\"$r\"" \
    "$here/fuzz_reader.c" "${objs_fuzz[@]}" -lm -o "$out/fuzz-$r"
done
# CGNS: a structure-aware harness (fuzz_cgns.c) that writes each input's
# file with libcgns and reads it back; cgns.c compiled again with libcgns
# (the objects above have CGNS compiled out). Only where libcgns-dev is.
ncgns=0
if [ -f /usr/include/cgnslib.h ]; then
  "$CC" "${common[@]}" "${san[@]}" -fsanitize=fuzzer-no-link -DVM_HAVE_CGNS \
    -c "$root/lib/io/src/cgns.c" -o "$out/obj-fuzz/cgns-lib.o"
  objs_cgns=()
  for o in "${objs_fuzz[@]}"; do
    [ "$(basename "$o")" = cgns.o ] && o="$out/obj-fuzz/cgns-lib.o"
    objs_cgns+=("$o")
  done
  "$CC" "${common[@]}" "${san[@]}" -fsanitize=fuzzer "$here/fuzz_cgns.c" "${objs_cgns[@]}" \
    -lcgns -lm -o "$out/fuzz-cgns"
  ncgns=1
fi
"$CC" "${common[@]}" "${san[@]}" "$here/replay.c" "${objs_san[@]}" -lm -o "$out/replay"
"$CC" "${common[@]}" "$here/gen_corpus.c" "${objs_san[@]}" "${san[@]}" -lm -o "$out/gen_corpus"
echo "build.sh: built $(( $(echo $readers | wc -w) + ncgns )) fuzzers, replay and gen_corpus in $out"
if [ "$regen" = 1 ]; then
  rm -f "$here"/corpus/*/gen-*
  "$out/gen_corpus" "$here/corpus"
  echo "build.sh: regenerated $here/corpus/*/gen-*"
fi
