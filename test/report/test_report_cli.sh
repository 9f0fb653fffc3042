#!/usr/bin/env bash
# test/report/test_report_cli.sh: --report end to end: vm-gen rotcube ->
# vm-volume --report writes index.html and its figures (every PNG decodes
# with cairo and is not blank, every link of the page resolves);
# vm-quality --report on a surface draws the surface; the stages' own
# --report: vm-surface (convergence of the adaptation, the surface coloured
# by curvature) and vm-prism (convergence, slices through the layers, the
# surface coloured by the achieved thickness); bad report arguments fail
# with the documented exit codes; no temporary files are left.
set -u
gen=$1 vol=$2 qual=$3 tr=$4 surf=$5 prism=$6
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }

# every src/href of a page names a file next to it that decodes as a PNG
links_ok() {
  local page=$1 base n=0 f
  base=$(dirname "$page")
  for f in $(grep -o -E '(src|href)="[^"]*"' "$page" | sed -E 's/^(src|href)="(.*)"$/\2/' | sort -u); do
    case $f in *://*|/*) echo "  absolute link $f"; return 1 ;; esac
    [ -f "$base/$f" ] || { echo "  broken link $f"; return 1; }
    "$tr" --png "$base/$f" >/dev/null || { echo "  $f does not decode"; return 1; }
    n=$((n + 1))
  done
  [ "$n" -ge 1 ]
}

"$gen" rotcube --n 8 --angle pi/2 "$dir/rc.vmsh"
check '[ $? -eq 0 ]' "vm-gen rotcube"
"$vol" -q --report "$dir/rep" "$dir/rc.vmsh" "$dir/out.vmsh" 2>"$dir/err"
rc=$?
if grep -q "without" "$dir/err"; then
  check '[ $rc -eq 2 ] && [ ! -e "$dir/out.vmsh" ]' "built without cairo: --report is a usage error, found before the run ($(cat "$dir/err"))"
  exit $fail
fi
check '[ $rc -eq 0 ]' "vm-volume --report exits 0 (got $rc: $(cat "$dir/err"))"
check '[ -f "$dir/out.vmsh" ]' "the mesh is written"
for f in index.html convergence.png before-quality.png before-slice.png after-quality.png after-slice.png; do
  check '[ -s "$dir/rep/$f" ]' "rep/$f written"
done
check '"$tr" --png "$dir"/rep/*.png' "every PNG decodes and is not blank"
check 'links_ok "$dir/rep/index.html"' "every link of index.html resolves to a PNG"
check '[ $(grep -c "<img " "$dir/rep/index.html") -eq 5 ]' "five figures on the page"
check 'grep -q "M: start, max, end" "$dir/rep/index.html"' "the run's numbers in the table"

# a surface: the aircraft
"$gen" aircraft --resolution 1 "$dir/air.vmsh"
"$qual" -q --report "$dir/rq" "$dir/air.vmsh" >/dev/null
check '[ $? -eq 0 ] && [ -s "$dir/rq/surface.png" ] && [ -s "$dir/rq/quality.png" ]' "vm-quality --report draws a surface"
check 'links_ok "$dir/rq/index.html"' "its page's links resolve"
"$qual" -q --report "$dir/rv" "$dir/rc.vmsh" >/dev/null
check '[ $? -eq 0 ] && [ -s "$dir/rv/slice.png" ] && [ ! -e "$dir/rv/surface.png" ]' "vm-quality --report slices a volume mesh"

# the stages' reports, on the coarsest aircraft
"$gen" aircraft --resolution 1 "$dir/air.stl" >/dev/null
"$surf" -q --report "$dir/rs" "$dir/air.stl" "$dir/air-s.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && [ -f "$dir/air-s.vmsh" ]' "vm-surface --report exits 0 and writes the mesh (got $rc: $(cat "$dir/err"))"
for f in index.html convergence.png quality.png surface.png; do
  check '[ -s "$dir/rs/$f" ]' "vm-surface: rs/$f written"
done
check 'links_ok "$dir/rs/index.html"' "vm-surface: every link of its page resolves to a PNG"
check 'grep -q "adaptation" "$dir/rs/index.html" && grep -q "mean_curvature" "$dir/rs/index.html"' "vm-surface: the adaptation's numbers, the surface coloured by mean curvature"
OMP_WAIT_POLICY=passive "$prism" -q -n 4 --report "$dir/rp" "$dir/air-s.vmsh" "$dir/air.msh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && [ -f "$dir/air.msh" ]' "vm-prism --report exits 0 and writes the mesh (got $rc: $(cat "$dir/err"))"
for f in index.html convergence.png quality.png slice.png slice-layer.png surface.png; do
  check '[ -s "$dir/rp/$f" ]' "vm-prism: rp/$f written"
done
check '"$tr" --png "$dir"/rp/*.png "$dir"/rs/*.png' "the stages' PNGs decode and are not blank"
check 'links_ok "$dir/rp/index.html"' "vm-prism: every link of its page resolves to a PNG"
check 'grep -q "columns at full thickness" "$dir/rp/index.html" && grep -q "thickness" "$dir/rp/index.html"' "vm-prism: the run's numbers, the surface coloured by thickness"
"$prism" -q --report "$dir/no/such" "$dir/air-s.vmsh" "$dir/air2.msh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/air2.msh" ]' "vm-prism fails before the run when the report cannot be made (got $rc)"
"$surf" -q --report "$dir/no/such" "$dir/air.stl" "$dir/air2.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/air2.vmsh" ]' "vm-surface fails before the run when the report cannot be made (got $rc)"

# errors
"$qual" -q --report "$dir/rf" --report-field nope "$dir/air.vmsh" >/dev/null 2>"$dir/err"
rc=$?
check '[ $rc -eq 2 ] && grep -q "nope" "$dir/err"' "an unknown --report-field is a usage error (got $rc: $(cat "$dir/err"))"
"$qual" -q --report "$dir/air.vmsh" "$dir/air.vmsh" >/dev/null 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ]' "--report on a file that is not a directory exits 1 (got $rc: $(cat "$dir/err"))"
"$vol" -q --report "$dir/no/such" "$dir/rc.vmsh" "$dir/out2.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/out2.vmsh" ]' "vm-volume fails before the run when the report cannot be made (got $rc)"
"$vol" --report 2>/dev/null
check '[ $? -eq 2 ]' "--report without a value is a usage error"
check '[ -z "$(find "$dir" -name "*.tmp.*")" ]' "no temporary files left"
exit $fail
