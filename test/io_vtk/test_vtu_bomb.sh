#!/usr/bin/env bash
# test/io_vtk/test_vtu_bomb.sh: a compressed VTU inflates no further than a
# bound (issue 21, item 7: a 3.6 MB VTU whose Points inflated to 150 M
# points used 7.8 GB and exited 0). A 0.6 MB file whose zlib blocks of
# zeros claim 400 MiB of points: refused with one line naming the bound, in
# little memory; VM_MAX_INFLATE raises the ratio.
# usage: test_vtu_bomb.sh VM_CONVERT PYTHON
set -u
conv=$1 py=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
"$py" - "$dir/bomb.vtu" <<'END'
import base64, struct, sys, zlib
bs = 32 << 20
nb = 13
block = zlib.compress(bytes(bs), 9)
hdr = struct.pack("<%dQ" % (3 + nb), nb, bs, bs, *([len(block)] * nb))
pts = base64.b64encode(hdr).decode() + base64.b64encode(block * nb).decode()
npts = nb * bs // 24
cells = base64.b64encode(struct.pack("<QQQQ", 1, 8, 8, 8) + zlib.compress(struct.pack("<q", 0))).decode()
open(sys.argv[1], "w").write(f"""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64" compressor="vtkZLibDataCompressor">
<UnstructuredGrid><Piece NumberOfPoints="{npts}" NumberOfCells="1">
<Points><DataArray type="Float64" NumberOfComponents="3" format="binary">{pts}</DataArray></Points>
<Cells><DataArray type="Int64" Name="connectivity" format="binary">{cells}</DataArray>
<DataArray type="Int64" Name="offsets" format="binary">{cells}</DataArray>
<DataArray type="UInt8" Name="types" format="binary">{cells}</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
""")
END
size=$(stat -c %s "$dir/bomb.vtu")
/usr/bin/time -f %M -o "$dir/rss" "$conv" "$dir/bomb.vtu" "$dir/o.vmsh" 2>"$dir/err"
rc=$?
rss=$(cat "$dir/rss" 2>/dev/null | tail -1)
check '[ $rc -eq 1 ] && [ $(grep -c . "$dir/err") -eq 1 ] && grep -q "inflate to more than" "$dir/err" && [ ! -e "$dir/o.vmsh" ]' "a $size-byte VTU claiming 416 MiB of points: refused (exit $rc: $(cat "$dir/err"))"
check '[ -n "$rss" ] && [ "$rss" -lt 200000 ]' "in little memory (peak ${rss:-?} kB)"
VM_MAX_INFLATE=2000 "$conv" "$dir/bomb.vtu" "$dir/o.vmsh" 2>"$dir/err2"
check '! grep -q "inflate to more than" "$dir/err2"' "VM_MAX_INFLATE=2000 lets it inflate (then: $(head -c 150 "$dir/err2"))"
exit $fail
