#!/usr/bin/env bash
# ctest image_files.module: OpenImageIO lives in a module that programs open only to read
# or write an image (common/image_file_module.hpp).
#   tests/image_module.sh SOURCE_DIR TESSERA TESSERA_SERVER TESSERA_WORKER
# 1. None of the three programs links OpenImageIO, so none loads its libraries at start.
# 2. `tessera render` finds the module from its own directory and writes a PNG.
# 3. A `tessera` without the module beside it says so, naming the file it looked for,
#    before it renders anything, exits 1 and writes nothing.
set -euo pipefail
source_dir=$1 tessera=$2 server=$3 worker=$4
failed=0
fail() { echo "FAIL: $*"; failed=1; }

for program in "$tessera" "$server" "$worker"; do
  if ldd "$program" | grep -q 'libOpenImageIO'; then
    fail "$(basename "$program") links OpenImageIO: $(ldd "$program" | grep libOpenImageIO | head -n 1)"
  fi
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$source_dir/examples/showcase.json

if ! "$tessera" render "$scene" --width 8 --height 6 -o "$work/found.png" >"$work/found.out" 2>&1; then
  fail "render with the module in place failed: $(cat "$work/found.out")"
elif [ "$(head -c 8 "$work/found.png" | od -An -tx1 | tr -d ' \n')" != 89504e470d0a1a0a ]; then
  fail "found.png is not a PNG"
fi

# The program with its tracer library (and that library's glibc-hwcaps builds) but not the
# module.
mkdir -p "$work/bin" "$work/lib"
cp "$tessera" "$work/bin/tessera"
cp -r "$(dirname "$tessera")/../lib/tessera" "$work/lib/tessera"
rm "$work/lib/tessera/libtessera_image_files.so"
status=0
"$work/bin/tessera" render "$scene" --width 8 --height 6 -o "$work/missing.png" \
  >"$work/missing.out" 2>"$work/missing.err" || status=$?
[ "$status" -eq 1 ] || fail "without the module, render exited $status, not 1"
grep -q "cannot load image file support ($work/lib/tessera/libtessera_image_files.so: no such file)" \
  "$work/missing.err" || fail "the error does not name the missing module: $(cat "$work/missing.err")"
grep -q '^rendered' "$work/missing.out" && fail "it rendered before finding the module missing"
[ -e "$work/missing.png" ] && fail "missing.png was written"

[ "$failed" -eq 0 ] && echo "ok: no program links OpenImageIO; the module is found, and its absence reported before rendering"
exit "$failed"
