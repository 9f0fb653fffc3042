#!/usr/bin/env bash
# test/fuzz/build.sh [OUTDIR]: build the libFuzzer reader harnesses
# (fuzz-<reader>), the sanitized corpus replay (replay) and the seed
# generator (gen_corpus) with clang, compiling the reader sources of lib/ and
# surface/ directly (the meson build is not touched). Default OUTDIR:
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
readers="vmsh vmsht vtk vtu msh medit stl obj off ply"

# the foundation sources of lib/ (context, mesh, I/O, every format), taken
# from lib/meson.build so a new reader is fuzzed without editing this script
lib_srcs=$(awk '/^lib_base_sources = files\(/{f=1; next} f && /\)/{f=0} f' \
  "$root/lib/meson.build" | grep -o "src/[A-Za-z0-9_]*\.c" | sed "s|^|$root/lib/|")
[ -n "$lib_srcs" ] || { echo "build.sh: no lib_base_sources in lib/meson.build" >&2; exit 1; }
lib_srcs="$lib_srcs $root/lib/src/quadrature.c"
surf_srcs="$root/surface/src/surface_io.c"
for f in "$root"/surface/src/io_*.c; do surf_srcs="$surf_srcs $f"; done

common=(-std=c11 -D_POSIX_C_SOURCE=200809L -g -O1 -fno-omit-frame-pointer
        -Wall -Wextra -Wpedantic -Wno-unknown-pragmas
        -I"$root/lib/include" -I"$root/lib/src" -I"$root/surface/include")
san=(-fsanitize=address,undefined -fno-sanitize-recover=all)
read -r -a extra <<<"${FUZZ_CFLAGS:-}"
san+=("${extra[@]}") # last, so that they can turn sanitizer checks off

mkdir -p "$out/obj-fuzz" "$out/obj-san"
# library objects twice: with fuzzer coverage (for the harnesses) and without
# (for replay, which has its own main)
objs_fuzz=() objs_san=()
for s in $lib_srcs $surf_srcs; do
  b=$(basename "$s" .c)
  case "$s" in */surface/*) b="surface_$b" ;; esac
  "$CC" "${common[@]}" "${san[@]}" -fsanitize=fuzzer-no-link -c "$s" -o "$out/obj-fuzz/$b.o"
  "$CC" "${common[@]}" "${san[@]}" -c "$s" -o "$out/obj-san/$b.o"
  objs_fuzz+=("$out/obj-fuzz/$b.o")
  objs_san+=("$out/obj-san/$b.o")
done
for r in $readers; do
  "$CC" "${common[@]}" "${san[@]}" -fsanitize=fuzzer -DVM_FUZZ_READER="\"$r\"" \
    "$here/fuzz_reader.c" "${objs_fuzz[@]}" -lm -o "$out/fuzz-$r"
done
"$CC" "${common[@]}" "${san[@]}" "$here/replay.c" "${objs_san[@]}" -lm -o "$out/replay"
"$CC" "${common[@]}" "$here/gen_corpus.c" "${objs_san[@]}" "${san[@]}" -lm -o "$out/gen_corpus"
echo "build.sh: built $(echo $readers | wc -w) fuzzers, replay and gen_corpus in $out"
if [ "$regen" = 1 ]; then
  rm -f "$here"/corpus/*/gen-*
  "$out/gen_corpus" "$here/corpus"
  echo "build.sh: regenerated $here/corpus/*/gen-*"
fi
