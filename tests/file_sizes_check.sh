#!/usr/bin/env bash
# Files stay small enough to read at a sitting: no C++ file of the product over 600 lines,
# no JavaScript file of the dashboard over 500. Prints each one over, with its length.
# Usage: tests/file_sizes_check.sh ROOT              (checks the product's folders in ROOT)
#        tests/file_sizes_check.sh ROOT --self-test
set -euo pipefail
root=${1:?usage: file_sizes_check.sh ROOT [--self-test]}

check() {
  local over status=0
  over=$(cd "$1" && find common tracer worker client server \( -name '*.cpp' -o -name '*.hpp' \) \
           -exec awk 'END { if (NR > 600) print FILENAME ": " NR " lines (C++: at most 600)" }' {} \; \
           2>/dev/null)
  over+=${over:+$'\n'}$(cd "$1" && find server/web -name '*.js' \
            -exec awk 'END { if (NR > 500) print FILENAME ": " NR " lines (JavaScript: at most 500)" }' {} \; \
            2>/dev/null)
  if [ -n "$over" ]; then
    echo "files over their length (split them by what they hold):"
    echo "$over"
    status=1
  fi
  return $status
}

if [ "${2:-}" = --self-test ]; then
  tree=$(mktemp -d)
  trap 'rm -rf "$tree"' EXIT
  mkdir -p "$tree"/{common,tracer,worker,client,server/web}
  seq 600 >"$tree/server/short.cpp"
  seq 500 >"$tree/server/web/short.js"
  check "$tree" >/dev/null || { echo "file_sizes_check.sh refused files within their lengths"; exit 1; }
  seq 601 >"$tree/worker/long.cpp"
  seq 501 >"$tree/server/web/long.js"
  out=$(check "$tree") && { echo "file_sizes_check.sh passed files over their lengths"; exit 1; }
  grep -q "^worker/long.cpp: 601 lines" <<<"$out" || { echo "not named: worker/long.cpp"; echo "$out"; exit 1; }
  grep -q "^server/web/long.js: 501 lines" <<<"$out" || { echo "not named: long.js"; echo "$out"; exit 1; }
  echo "file_sizes_check.sh names each file over its length and passes the others"
  exit 0
fi
check "$root"
