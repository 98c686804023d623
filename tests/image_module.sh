#!/usr/bin/env bash
# ctest image_files.module: OpenImageIO lives in a module that programs open only to read
# an image or write one that is not a PNG (common/image/image_file_module.hpp).
#   tests/image_module.sh SOURCE_DIR TESSERA TESSERA_SERVER TESSERA_WORKER
# 1. None of the three programs links OpenImageIO, so none loads its libraries at start.
# 2. `tessera render` finds the module from its own directory and writes an EXR; a PNG it
#    writes without opening the module (libpng: common/image/png_file.hpp).
# 3. A `tessera` without the module beside it still writes a PNG; asked for an EXR, it says
#    the module is missing, naming the file it looked for, before it renders anything,
#    exits 1 and writes nothing.
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

is_png() { [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ]; }

if ! "$tessera" render "$scene" --width 8 --height 6 -o "$work/found.exr" >"$work/found.out" 2>&1; then
  fail "render to EXR with the module in place failed: $(cat "$work/found.out")"
elif [ "$(head -c 4 "$work/found.exr" | od -An -tx1 | tr -d ' \n')" != 762f3101 ]; then
  fail "found.exr is not an OpenEXR file"
fi
# The dynamic loader names each file it opens: the module's must not be among them.
if ! LD_DEBUG=files "$tessera" render "$scene" --width 8 --height 6 -o "$work/found.png" \
  >"$work/found-png.out" 2>"$work/found-png.err"; then
  fail "render to PNG with the module in place failed: $(cat "$work/found-png.out" "$work/found-png.err")"
elif ! is_png "$work/found.png"; then
  fail "found.png is not a PNG"
elif ! grep -q 'file=libtessera_tracer' "$work/found-png.err"; then
  fail "LD_DEBUG=files named no library: the check below would prove nothing"
elif grep -E -q 'libtessera_image_files|libOpenImageIO' "$work/found-png.err"; then
  fail "writing a PNG loaded the module: $(grep -E 'libtessera_image_files|libOpenImageIO' "$work/found-png.err" | head -n 1)"
fi

# The program with its tracer library (and that library's glibc-hwcaps builds) but not the
# module.
mkdir -p "$work/bin" "$work/lib"
cp "$tessera" "$work/bin/tessera"
cp -r "$(dirname "$tessera")/../lib/tessera" "$work/lib/tessera"
rm "$work/lib/tessera/libtessera_image_files.so"
if ! "$work/bin/tessera" render "$scene" --width 8 --height 6 -o "$work/without.png" \
  >"$work/without.out" 2>&1; then
  fail "without the module, a render to PNG failed: $(cat "$work/without.out")"
elif ! is_png "$work/without.png"; then
  fail "without the module, without.png is not a PNG"
elif ! cmp -s "$work/without.png" "$work/found.png"; then
  fail "the PNG written without the module differs from the one written with it"
fi
status=0
"$work/bin/tessera" render "$scene" --width 8 --height 6 -o "$work/missing.exr" \
  >"$work/missing.out" 2>"$work/missing.err" || status=$?
[ "$status" -eq 1 ] || fail "without the module, render to EXR exited $status, not 1"
grep -q "cannot load image file support ($work/lib/tessera/libtessera_image_files.so: no such file)" \
  "$work/missing.err" || fail "the error does not name the missing module: $(cat "$work/missing.err")"
grep -q '^rendered' "$work/missing.out" && fail "it rendered before finding the module missing"
[ -e "$work/missing.exr" ] && fail "missing.exr was written"

[ "$failed" -eq 0 ] && echo "ok: no program links OpenImageIO; a PNG is written without the module; for an EXR the module is found, and its absence reported before rendering"
exit "$failed"
