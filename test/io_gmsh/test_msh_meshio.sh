#!/usr/bin/env bash
# test/io_gmsh/test_msh_meshio.sh: runs test_msh_meshio.py with the first
# python3 that has meshio (the system's python3 first: Debian's
# python3-meshio lives there); exit 77 if none has it.
# usage: test_msh_meshio.sh SCRIPT VM_CONVERT
for py in /usr/bin/python3 python3; do
  if command -v "$py" >/dev/null 2>&1 && "$py" -c "import meshio" >/dev/null 2>&1; then
    exec "$py" "$@"
  fi
done
echo "skip: no python3 with meshio"
exit 77
