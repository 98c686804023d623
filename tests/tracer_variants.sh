#!/usr/bin/env bash
# ctest tracer.variants: the builds of the tracer's shared library (x86-64, x86-64-v3,
# x86-64-v4: tracer/CMakeLists.txt) compute the same bits.
# 1. None holds a fused multiply-add or a call into libmvec, the two ways a build for a
#    newer CPU could round differently. (A pixel seldom shows a difference in the last bit
#    of a double, so 2 is no proof of this.)
# 2. Every build this CPU can run renders the same pixels, bit for bit, on scenes that
#    cover every shape, light and material path; the others are skipped with a note.
# 3. A program started plainly loads the best build the CPU supports.
#   tests/tracer_variants.sh SOURCE_DIR BINARY_DIR
set -euo pipefail
source_dir=$(realpath "${1:?usage: tracer_variants.sh SOURCE_DIR BINARY_DIR}")
binary_dir=$(realpath "${2:?usage: tracer_variants.sh SOURCE_DIR BINARY_DIR}")
tessera=$binary_dir/client/tessera
library_dir=$binary_dir/lib/tessera
base=$library_dir/libtessera_tracer.so

for tool in idiff objdump readelf; do
  if ! command -v "$tool" >/dev/null; then
    echo "skipped: $tool is missing (openimageio-tools, binutils)"
    exit 77
  fi
done
[ -f "$base" ] || { echo "FAIL: no $base"; exit 1; }

# Which of glibc's x86-64 levels the loader says this CPU supports, best first.
loader=$(readelf -l "$tessera" | sed -n 's/.*Requesting program interpreter: \(.*\)]/\1/p')
mapfile -t supported < <("$loader" --help 2>/dev/null |
  sed -n 's/^ *\(x86-64-v[0-9]\) (supported, searched)$/\1/p')
variants=("$base")
for level in x86-64-v4 x86-64-v3; do
  file=$library_dir/glibc-hwcaps/$level/libtessera_tracer.so
  [ -f "$file" ] || { echo "FAIL: no $file"; exit 1; }
  if [[ " ${supported[*]} " == *" $level "* ]]; then
    variants+=("$file")
  else
    echo "note: this CPU cannot run $level; its build is not compared"
  fi
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0

for file in "$base" "$library_dir"/glibc-hwcaps/*/libtessera_tracer.so; do
  code=$(objdump -d --no-show-raw-insn "$file")
  fused=$(grep -c -E '\<v?f(n?)m(add|sub)[0-9a-z]*\>' <<<"$code" || true)
  vector_math=$(grep -c -E 'call.*<_ZGV' <<<"$code" || true)
  if [ "$fused" -ne 0 ] || [ "$vector_math" -ne 0 ]; then
    echo "FAIL: $file has $fused fused multiply-adds and $vector_math calls into libmvec"
    failed=1
  fi
done

# The file the loader opened for the tracer, from LD_DEBUG's report on stderr.
loaded() { sed -n 's/.*calling init: \(.*libtessera_tracer\.so\)$/\1/p' "$1" | head -n 1; }

# Started plainly, the program gets the best variant the CPU supports.
LD_DEBUG=libs "$tessera" render "$source_dir/examples/point_light.json" -o "$work/plain.exr" \
  --width 16 --height 16 >/dev/null 2>"$work/plain.log"
best=$(realpath "${variants[1]:-$base}")
if [ "$(realpath "$(loaded "$work/plain.log")")" != "$best" ]; then
  echo "FAIL: tessera loaded $(loaded "$work/plain.log"), not $best"
  failed=1
fi

scenes=("$source_dir"/examples/*.json "$source_dir"/bench/scenes/*.json)
[ -f "$binary_dir/examples/mesh.json" ] && scenes+=("$binary_dir/examples/mesh.json")
[ -f "$binary_dir/examples/textured_globe.json" ] &&
  scenes+=("$binary_dir/examples/textured_globe.json")
for index in "${!variants[@]}"; do
  variant=${variants[$index]}
  # LD_LIBRARY_PATH is searched before the RUNPATH, so a directory holding only this
  # variant decides which one loads.
  mkdir -p "$work/$index"
  ln -s "$variant" "$work/$index/libtessera_tracer.so"
  for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .json)-$(basename "$(dirname "$scene")")
    LD_DEBUG=libs LD_LIBRARY_PATH="$work/$index" "$tessera" render "$scene" \
      -o "$work/$index/$name.exr" --width 96 --height 54 --spp 4 --threads 2 \
      >/dev/null 2>"$work/$index/$name.log"
    if [ "$(loaded "$work/$index/$name.log")" != "$work/$index/libtessera_tracer.so" ]; then
      echo "FAIL: $name did not load $variant"
      failed=1
    elif ((index > 0)) &&
      ! idiff -fail 0 -warn 0 "$work/0/$name.exr" "$work/$index/$name.exr" >"$work/diff" 2>&1; then
      echo "FAIL: $name differs between $base and $variant:"
      cat "$work/diff"
      failed=1
    fi
  done
done
[ "$failed" -eq 0 ] &&
  echo "ok: ${#variants[@]} builds of the tracer, ${#scenes[@]} scenes, the same pixels"
exit "$failed"
