#!/usr/bin/env bash
# test/pipeline/test_pipeline.sh: examples/Makefile on a tiny generated
# aircraft: the first run builds every stage that exists (vm-prism is left
# out until it is built); a second run does nothing; changing one stage's
# options re-runs that stage and its dependents only; a failing stage makes
# make fail with the stage's exit code and leaves no target and no
# temporary file. Exit 77 if make is not installed.
set -u
examples=$1 bin=$(dirname "$2") make=${3:-}
if [ -z "$make" ]; then
  echo "skip: make is not installed"
  exit 77
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() {
  if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; tail -n 15 "$dir/log" 2>/dev/null; fail=1; fi
}
have_prism=0
[ -x "$bin/vm-prism" ] && have_prism=1
have_fill=0
[ $have_prism -eq 1 ] && [ -x "$bin/vm-fill" ] && have_fill=1
nrep=$((1 + have_prism + have_fill))
nexp=$((2 + 3 * have_fill))

# run the pipeline with stage options "$@" (VAR=value ...); the log lists
# the stages that ran, one "== stage: target" line each
run() {
  "$make" -C "$examples" --no-print-directory VM_BIN="$bin" OUT="$dir/out" \
    GEN_OPTS="--resolution 1" "$@" >"$dir/log" 2>&1
}
ran() { grep -c "^== $1:" "$dir/log"; }
stages() { grep "^== " "$dir/log" | sed 's/^== \([a-z]*\):.*/\1/' | sort | uniq -c | tr -s ' ' | tr '\n' ';'; }
base=(SURFACE_OPTS="curvature -q")

run "${base[@]}"
rc=$?
check '[ $rc -eq 0 ]' "first run succeeds (exit $rc)"
[ $rc -eq 0 ] || tail -n 20 "$dir/log"
out=$dir/out
for f in aircraft.stl aircraft.surface.vmsh aircraft.msh aircraft.vtu \
         aircraft-report-surface/index.html aircraft-report-surface/surface.png \
         aircraft-report-surface/quality.txt; do
  check '[ -s "$out/$f" ]' "$f made"
done
if [ $have_prism -eq 1 ]; then
  check '[ -s "$out/aircraft.prism.vmsh" ] && [ -s "$out/aircraft-report-prism/index.html" ]' "prism stage made"
fi
if [ $have_fill -eq 1 ]; then
  check '[ -s "$out/aircraft.fill.vmsh" ] && [ -s "$out/aircraft-report-fill/index.html" ]' "fill stage made"
  check '[ -s "$out/aircraft.su2" ] && [ -s "$out/aircraft.cgns" ] && [ -s "$out/aircraft.foam/constant/polyMesh/owner" ] && [ -s "$out/aircraft.foam/0/U" ] && [ -s "$out/aircraft.foam/system/fvSchemes" ]' "solver exports made: .su2, .cgns, the OpenFOAM case with its case files"
fi
check '[ $(ran model) -eq 1 ] && [ $(ran surface) -eq 1 ] && [ $(ran exports) -eq $nexp ]' "each stage once: $(stages)"

run "${base[@]}"
rc=$?
check '[ $rc -eq 0 ] && grep -q "Nothing to be done" "$dir/log" && [ -z "$(grep "^== " "$dir/log")" ]' "second run does nothing: $(cat "$dir/log")"
"$make" -C "$examples" --no-print-directory -q VM_BIN="$bin" OUT="$dir/out" GEN_OPTS="--resolution 1" "${base[@]}" all
check '[ $? -eq 0 ]' "make -q: everything is up to date"

run "${base[@]}" CONVERT_OPTS="--binary"
rc=$?
check '[ $rc -eq 0 ] && [ "$(stages)" = " $nexp exports;" ]' "changing CONVERT_OPTS re-runs the exports only: $(stages)"
run "${base[@]}" CONVERT_OPTS="--binary" REPORT_OPTS="--report-field mean_curvature"
rc=$?
check '[ $rc -eq 0 ] && [ "$(stages)" = " $nrep reports;" ]' "changing REPORT_OPTS re-runs the reports only: $(stages)"
run SURFACE_OPTS="curvature -q --smooth 3" CONVERT_OPTS="--binary" REPORT_OPTS="--report-field mean_curvature"
rc=$?
want=" $nexp exports; $nrep reports; 1 surface;"
[ $have_prism -eq 1 ] && want=" $nexp exports; 1 prism; $nrep reports; 1 surface;"
[ $have_fill -eq 1 ] && want=" $nexp exports; 1 fill; 1 prism; $nrep reports; 1 surface;"
check '[ $rc -eq 0 ] && [ "$(stages)" = "$want" ]' "changing SURFACE_OPTS re-runs the surface and what depends on it, not the model: $(stages)"
run SURFACE_OPTS="curvature -q --smooth 3" CONVERT_OPTS="--binary" REPORT_OPTS="--report-field mean_curvature"
check '[ $? -eq 0 ] && grep -q "Nothing to be done" "$dir/log"' "and then nothing again"
touch "$out/aircraft.stl"
run SURFACE_OPTS="curvature -q --smooth 3" CONVERT_OPTS="--binary" REPORT_OPTS="--report-field mean_curvature"
rc=$?
check '[ $rc -eq 0 ] && [ "$(stages)" = "$want" ]' "a newer model re-runs everything after it: $(stages)"

# a failing stage: vm-surface's usage error (exit 2)
run SURFACE_OPTS="--no-such-option"
rc=$?
check '[ $rc -ne 0 ] && grep -q "aircraft.surface.vmsh\] Error 2" "$dir/log"' "a failing stage fails make with its exit code (make $rc): $(grep Error "$dir/log")"
check '[ ! -e "$out/aircraft.surface.vmsh" ]' "no stale surface left"
check '[ -z "$(find "$out" -name ".tmp.*" -o -name "*.tmp")" ]' "no temporary files left"
run "${base[@]}" CONVERT_OPTS="--no-such-option"
rc=$?
check '[ $rc -ne 0 ] && [ ! -e "$out/aircraft.msh" ] && grep -q "Error 2" "$dir/log"' "a failing export leaves no export (make $rc)"
run "${base[@]}" REPORT_OPTS="--report-field nope"
rc=$?
check '[ $rc -ne 0 ] && [ ! -e "$out/aircraft-report-surface" ] && [ ! -e "$out/aircraft-report-surface.tmp" ]' "a failing report leaves no report directory (make $rc)"
run "${base[@]}"
check '[ $? -eq 0 ] && [ -s "$out/aircraft-report-surface/index.html" ]' "back to working options: rebuilt"

# a model given by path, named after its file
cp "$out/aircraft.stl" "$dir/wing.stl"
run "${base[@]}" MODEL="$dir/wing.stl" surface
rc=$?
check '[ $rc -eq 0 ] && [ -s "$out/wing.surface.vmsh" ] && [ "$(stages)" = " 1 surface;" ]' "MODEL=path: the surface of wing.stl only: $(stages)"
if [ $have_prism -eq 0 ]; then
  run "${base[@]}" prism
  check '[ $? -ne 0 ] && grep -q "vm-prism is not built" "$dir/log"' "make prism says vm-prism is not built"
fi
run "${base[@]}" clean
rc=$?
check '[ $rc -eq 0 ] && [ -z "$(ls "$out" | grep aircraft)" ]' "clean removes the aircraft's files: $(ls "$out" | tr '\n' ' ')"
exit $fail
