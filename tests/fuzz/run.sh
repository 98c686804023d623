#!/usr/bin/env bash
# Builds the scene parser's libFuzzer target with clang, AddressSanitizer and UBSan, and
# fuzzes it for a bounded time from the example scenes and the seeds beside this script. Exits non-zero on
# any crash, sanitizer report, leak or hang; 77 (skipped) without clang's fuzzer runtime.
#
# Usage: tests/fuzz/run.sh BUILD_DIR [SECONDS]      (default 60 s)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$1
seconds=${2:-60}

if ! command -v clang++ >/dev/null; then
  echo "fuzz: skipped: clang++ is not installed (deploy/install-deps.sh installs it)"
  exit 77
fi
if ! echo 'extern "C" int LLVMFuzzerTestOneInput(const char*, long) { return 0; }' |
    clang++ -x c++ -fsanitize=fuzzer - -o /dev/null 2>/dev/null; then
  echo "fuzz: skipped: clang has no libFuzzer runtime (package libclang-rt-14-dev)"
  exit 77
fi

mkdir -p "$build"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DTESSERA_FUZZ=ON -DTESSERA_BUILD_TESTS=OFF >"$build/fuzz-configure.log" 2>&1 ||
  { tail -n 30 "$build/fuzz-configure.log"; exit 1; }
cmake --build "$build" --target tessera_scene_fuzzer >"$build/fuzz-build.log" 2>&1 ||
  { tail -n 30 "$build/fuzz-build.log"; exit 1; }

# New inputs go to a scratch corpus, so the repository's seeds stay as they are; crashes
# are written into the build tree, where the message below points. The seeds are the
# scenes the repository has anyway (examples/, examples/animation/ and tests/data/), and
# the few of corpus/ that exist only to seed the fuzzer.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$build/fuzz-artifacts" "$work/new" "$work/seeds"
cp "$root"/examples/*.json "$root"/examples/animation/*.json "$root"/tests/data/*.json "$work/seeds/"
"$build/tessera_scene_fuzzer" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
  -max_len=65536 -print_final_stats=1 -artifact_prefix="$build/fuzz-artifacts/" \
  "$work/new" "$work/seeds" "$here/corpus"
echo "fuzz: no crash, leak or hang in ${seconds} s"
