#!/usr/bin/env bash
# test/io_foam/test_foam_checkmesh.sh: OpenFOAM's checkMesh says "Mesh OK."
# of every case the foam writer writes: the cube meshes of foam_cases
# (hexahedra, prisms, pyramids, tetrahedra, all four; named boundaries;
# ASCII and binary), vm-gen's rotated cube at angle 0 (hexahedra and
# tetrahedra) through vm-convert, and a vm-prism layer on a sphere written
# straight to a case, whose patches are the wall (type wall) and the outer
# surface (type patch); writing again into a case keeps its 0/ and system/;
# thin first layers pass the determinant check of -allGeometry with
# vm-prism's default --max-aspect and fail it without.
# potentialFoam, when installed, runs on the mixed cube's patches. Skipped
# (77) when checkMesh is not installed. vm-quality's count of OpenFOAM's
# negative volumes and face pyramids equals checkMesh's on tangled rotated
# cubes (hexahedra, and the mixed cells; at 7pi/8, where no cell is
# degenerate: at pi/2 and pi cells collapse onto coincident points, which
# checkMesh reports as open cells, and the counts differ in rounding).
# usage: test_foam_checkmesh.sh FOAM_CASES VM_GEN VM_CONVERT VM_PRISM VM_QUALITY
set -u
cases=$1 gen=$2 conv=$3 prism=$4 quality=$5
if ! command -v checkMesh >/dev/null 2>&1; then
  echo "skip: checkMesh (OpenFOAM) not on PATH"
  exit 77
fi
# OpenFOAM's programs find their etc/ through WM_PROJECT_DIR; Debian's
# packages keep it in /usr/share/openfoam without setting the variable
if [ -z "${WM_PROJECT_DIR:-}" ]; then
  for d in /usr/share/openfoam /usr/lib/openfoam/openfoam*; do
    if [ -f "$d/etc/controlDict" ]; then
      export WM_PROJECT_DIR=$d
      break
    fi
  done
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
mesh_ok() {
  checkMesh -case "$1" >"$1.log" 2>&1
  if grep -q "^Mesh OK\.$" "$1.log"; then return 0; fi
  tail -20 "$1.log" | sed 's/^/    /'
  return 1
}

"$cases" "$dir"
check '[ $? -eq 0 ]' "foam_cases writes the cube cases"
for c in "$dir"/*.foam; do
  mesh_ok "$c"
  rc=$?
  cells=$(grep -E "^ +(hexahedra|prisms|pyramids|tetrahedra): +[1-9]" "$c.log" | tr -s ' ' | tr '\n' ',')
  check '[ $rc -eq 0 ]' "checkMesh: $(basename "$c") is OK (${cells% ,})"
done
check 'grep -q "symmetryPlane" "$dir/mixed.foam/constant/polyMesh/boundary"' "the symmetry side is a symmetryPlane patch"

"$gen" rotcube --n 6 "$dir/h.vmsh" && "$gen" rotcube --n 6 --tets "$dir/t.vmsh"
check '[ $? -eq 0 ]' "vm-gen rotcube at angle 0, hexahedra and tetrahedra"
"$conv" "$dir/h.vmsh" "$dir/h.foam" 2>/dev/null
check '[ $? -eq 0 ] && mesh_ok "$dir/h.foam"' "vm-convert h.vmsh h.foam: checkMesh OK"
"$conv" --binary --format foam "$dir/t.vmsh" "$dir/t" 2>/dev/null
check '[ $? -eq 0 ] && mesh_ok "$dir/t"' "vm-convert --binary --format foam t.vmsh t: checkMesh OK"

# vm-quality counts what checkMesh counts: the same geometry, cell by cell
for kind in hex mixed; do
  opt=; [ $kind = mixed ] && opt=--mixed
  "$gen" rotcube --n 8 --angle 7pi/8 $opt "$dir/tg.vmsh" && "$conv" "$dir/tg.vmsh" "$dir/tg.foam" 2>/dev/null
  checkMesh -case "$dir/tg.foam" >"$dir/tg.log" 2>&1
  neg=$(sed -n 's/.*Number of negative volume cells: \([0-9]*\).*/\1/p' "$dir/tg.log")
  pyr=$(sed -n 's/.*Error in face pyramids: \([0-9]*\) faces.*/\1/p' "$dir/tg.log")
  own=$("$quality" "$dir/tg.vmsh" | sed -n "s/^OpenFOAM's checkMesh: \([0-9]*\) cells of volume <= 0, \([0-9]*\) face pyramids.*/\1 \2/p")
  check '[ -n "$pyr" ] && [ "$own" = "${neg:-0} $pyr" ]' "tangled $kind cube: vm-quality's OpenFOAM counts ($own) are checkMesh's (${neg:-0} $pyr)"
done

# a solver on the patches: potentialFoam on the mixed cube, the symmetry
# side with OpenFOAM's symmetryPlane condition (refused on a patch of
# another type), slip walls, the far field at fixed pressure, the uncovered
# sides (defaultFaces) as the inflow
if command -v potentialFoam >/dev/null 2>&1; then
  c="$dir/mixed.foam"
  mkdir -p "$c/0"
  field() { # class object dimensions value wall farfield defaultFaces
    printf 'FoamFile { version 2.0; format ascii; class %s; object %s; }\n' "$1" "$2"
    printf 'dimensions %s;\ninternalField uniform %s;\nboundaryField\n{\n' "$3" "$4"
    printf '    wall { type %s; }\n    outer { type %s; }\n' "$5" "$5"
    printf '    farfield { type %s; }\n    symmetry { type symmetryPlane; }\n' "$6"
    printf '    defaultFaces { type %s; }\n}\n' "$7"
  }
  field volVectorField U "[0 1 -1 0 0 0 0]" "(0 0 0)" slip zeroGradient \
    "fixedValue; value uniform (1 0 0)" >"$c/0/U"
  field volScalarField p "[0 2 -2 0 0 0 0]" 0 zeroGradient "fixedValue; value uniform 0" \
    zeroGradient >"$c/0/p"
  cat >"$c/system/fvSchemes" <<'END'
FoamFile { version 2.0; format ascii; class dictionary; object fvSchemes; }
ddtSchemes { default steadyState; }
gradSchemes { default leastSquares; }
divSchemes { default none; div(phi,U) bounded Gauss linear; div(div(phi,U)) Gauss linear; }
laplacianSchemes { default Gauss linear corrected; }
interpolationSchemes { default linear; }
snGradSchemes { default corrected; }
END
  cat >"$c/system/fvSolution" <<'END'
FoamFile { version 2.0; format ascii; class dictionary; object fvSolution; }
solvers { Phi { solver GAMG; smoother DIC; tolerance 1e-06; relTol 0.01; } p { $Phi; } }
potentialFlow { nNonOrthogonalCorrectors 3; }
END
  potentialFoam -case "$c" -writep >"$c.pf.log" 2>&1
  rc=$?
  check '[ $rc -eq 0 ] && ! grep -q "FATAL" "$c.pf.log" && [ "$(grep -v "^$" "$c.pf.log" | tail -1)" = End ]' "potentialFoam runs on mixed.foam's patches (exit $rc)"
  [ $rc -eq 0 ] || tail -15 "$c.pf.log" | sed 's/^/    /'
else
  echo "skip: potentialFoam not on PATH"
fi

# the prism layer: boundaries "wall" and "outer", nothing in defaultFaces
"$prism" -q -t 0.2 -n 4 "$dir/sphere.stl" "$dir/p.foam" 2>"$dir/p.err"
check '[ $? -eq 0 ] && mesh_ok "$dir/p.foam"' "vm-prism sphere.stl p.foam: checkMesh OK"
check 'grep -q "^    prisms: *1280$" "$dir/p.foam.log"' "1280 prisms"
b="$dir/p.foam/constant/polyMesh/boundary"
check '[ "$(sed -n "s/^ *type *\(.*\);/\1/p" "$b" | tr "\n" " ")" = "wall patch " ] && grep -q "^    wall$" "$b" && grep -q "^    outer$" "$b" && ! grep -q defaultFaces "$b"' "patches wall (type wall) and outer (type patch), no defaultFaces"
check '! grep -q defaultFaces "$dir/p.err"' "no warning about unnamed boundary faces"
tail -n 25 "$dir/p.foam.log" | sed 's/^/    /'

# into an existing case: 0/ and system/ stay, the mesh is replaced
mkdir -p "$dir/p.foam/0" && echo "user data" >"$dir/p.foam/0/U"
echo "// the user's" >>"$dir/p.foam/system/controlDict"
cp "$dir/p.foam/system/controlDict" "$dir/cd.before"
"$conv" "$dir/h.vmsh" "$dir/p.foam" 2>/dev/null
check '[ $? -eq 0 ] && mesh_ok "$dir/p.foam" && grep -q "^    hexahedra: *216$" "$dir/p.foam.log"' "written again into the case: the hexahedra replace the prisms"
check 'grep -q "user data" "$dir/p.foam/0/U" && cmp -s "$dir/cd.before" "$dir/p.foam/system/controlDict"' "0/U and system/controlDict kept"
check '[ -z "$(ls -A "$dir/p.foam/constant" | grep "^\.")" ]' "no temporary directory left in constant/"
# thin first layers: 20 layers at growth 1.2 put the first cell at 1/110 of
# the sphere's wall edges, which OpenFOAM's determinant check (with
# -allGeometry) fails; by default (--max-aspect 30) every column's first
# height is raised to its longest wall edge / 30 and its layers grow more
# slowly, and the check passes; --max-aspect 0 keeps the schedule's first
# height everywhere (the check fails: the test can tell them apart)
for a in default 0; do
  opt=; [ $a = 0 ] && opt="--max-aspect 0"
  "$prism" -q --json -t 0.3 -n 20 $opt "$dir/sphere.stl" "$dir/thin$a.foam" >"$dir/thin$a.json" 2>"$dir/thin$a.err"
  check '[ $? -eq 0 ]' "vm-prism -t 0.3 -n 20${opt:+ $opt} sphere.stl"
  checkMesh -case "$dir/thin$a.foam" -allGeometry >"$dir/thin$a.log" 2>&1
done
check 'grep -q "^Mesh OK\.$" "$dir/thindefault.log" && grep -q "Cell determinant check OK" "$dir/thindefault.log"' "default first heights: checkMesh -allGeometry OK (least determinant $(sed -n 's/.*Cell determinant (wellposedness) : minimum: \([0-9.e-]*\).*/\1/p' "$dir/thindefault.log"))"
check 'grep -q "small determinant" "$dir/thin0.log"' "--max-aspect 0: cells with a small determinant ($(sed -n 's/.*number of cells: //p' "$dir/thin0.log"))"
num() { sed -n "s/.*\"$1\": \([0-9.eE+-]*\).*/\1/p" "$2"; } # a number of the JSON summary
raised=$(num first_raised "$dir/thindefault.json") wv=$(num wall_vertices "$dir/thindefault.json")
gmax=$(num growth_max "$dir/thindefault.json")
check '[ -n "$raised" ] && [ "$raised" = "$wv" ] && awk "BEGIN{exit !($gmax <= 1.2 + 1e-6)}"' "every column's first height raised ($raised of $wv), largest growth $gmax <= 1.2"
check '[ "$(num first_raised "$dir/thin0.json")" = 0 ]' "--max-aspect 0 raises none"
exit $fail
