#!/usr/bin/env bash
# test/lint/test_format.sh: every C, C++ and header file of the project
# follows the committed .clang-format (clang-format 14). Prints the files
# that do not, with the first lines clang-format would change.
set -u
root=${1:?usage: test_format.sh SOURCE_ROOT}
cf=$(command -v clang-format || true)
if [ -z "$cf" ]; then echo "skip: clang-format is not installed"; exit 77; fi
cd "$root" || exit 1
bad=0
while IFS= read -r f; do
  if ! "$cf" --style=file "$f" | cmp -s - "$f"; then
    echo "not formatted: $f"
    "$cf" --style=file "$f" | diff "$f" - | head -n 8
    bad=$((bad + 1))
  fi
done < <(git ls-files -- '*.c' '*.h' '*.cpp' 2>/dev/null ||
         find lib surface volume prism apps test bench -name '*.[ch]' -o -name '*.cpp')
if [ "$bad" -gt 0 ]; then echo "FAIL: $bad files differ from .clang-format (run clang-format -i on them)"; exit 1; fi
echo "ok: every source file follows .clang-format"
