#!/usr/bin/env bash
# Every GoogleTest suite is named for what it tests and ends in "Test" (SchedulerTest,
# ObjFileTest), so a suite reads as one in a filter, a failure or a fixture's class, and
# never takes a product type's name (Scheduler, Image). Prints each suite that does not.
# Usage: tests/suite_names_check.sh ROOT      (checks ROOT/tests)
#        tests/suite_names_check.sh ROOT --self-test
set -euo pipefail
root=${1:?usage: suite_names_check.sh ROOT [--self-test]}

check() {
  # TEST(Suite, Name), TEST_F, TEST_P, TYPED_TEST, and the suite of an instantiation.
  local found
  found=$(grep -rnoP --include='*.cpp' --include='*.hpp' \
            '^\s*(TEST|TEST_F|TEST_P|TYPED_TEST|TYPED_TEST_P)\(\s*\K\w+|INSTANTIATE_TEST_SUITE_P\(\s*\w+\s*,\s*\K\w+' \
            "$1" | grep -vP ':\w+Test$' || true)
  if [ -n "$found" ]; then
    echo "test suites whose names do not end in \"Test\" (file:line:suite):"
    echo "$found"
    return 1
  fi
}

if [ "${2:-}" = --self-test ]; then
  tree=$(mktemp -d)
  trap 'rm -rf "$tree"' EXIT
  printf 'TEST(SceneTest, Parses) {}\nTEST_F(ObjFileTest, Reads) {}\n' >"$tree/good_test.cpp"
  check "$tree" >/dev/null || { echo "suite_names_check.sh refused good names"; exit 1; }
  printf 'TEST(Scene, Parses) {}\n' >"$tree/bad_test.cpp"
  printf 'INSTANTIATE_TEST_SUITE_P(All, Golden, ::testing::Values(1));\n' >"$tree/bad2_test.cpp"
  out=$(check "$tree") && { echo "suite_names_check.sh passed a suite named Scene"; exit 1; }
  grep -q "bad_test.cpp:1:Scene$" <<<"$out" || { echo "not named: Scene"; echo "$out"; exit 1; }
  grep -q "bad2_test.cpp:1:Golden$" <<<"$out" || { echo "not named: Golden"; echo "$out"; exit 1; }
  echo "suite_names_check.sh names each suite without the suffix and passes the others"
  exit 0
fi
check "$root/tests"
