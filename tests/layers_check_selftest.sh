#!/usr/bin/env bash
# layers_check.sh can fail: in a tree of one file per rule that crosses it, each is named;
# in a tree where each folder includes only what it may, none is.
# Usage: tests/layers_check_selftest.sh TESTS_DIR
set -euo pipefail
check=${1:?usage: layers_check_selftest.sh TESTS_DIR}/layers_check.sh
tree=$(mktemp -d)
trap 'rm -rf "$tree"' EXIT
skeleton() {
  for folder in common/text common/scene common/image common/scn common/mesh_files common/protocol \
                common/net tracer worker client server/metrics server/http server/farm server/api; do
    mkdir -p "$tree/$folder"
  done
}
put() { mkdir -p "$tree/$(dirname "$1")"; printf '#include "%s"\n' "$2" >"$tree/$1"; }
skeleton
put server/farm/a.cpp server/http/router.hpp
put server/http/b.cpp server/farm/scheduler.hpp
put worker/c.cpp client/main.hpp
put client/d.cpp worker/worker_daemon.hpp
put common/scene/e.cpp tracer/renderer.hpp
put common/text/f.cpp common/scene/scene.hpp
put tracer/g.cpp server/farm/store.hpp
if out=$(bash "$check" "$tree" 2>&1); then
  echo "layers_check.sh passed a tree that crosses every line:"; echo "$out"; exit 1
fi
status=0
for file in server/farm/a.cpp server/http/b.cpp worker/c.cpp client/d.cpp common/scene/e.cpp \
            common/text/f.cpp tracer/g.cpp; do
  grep -q "^  $file:1:" <<<"$out" || { echo "not named: $file"; status=1; }
done
rm -rf "${tree:?}"/*
skeleton
put server/api/a.cpp server/farm/scheduler.hpp
put server/api/b.cpp server/http/router.hpp
put worker/c.cpp tracer/renderer.hpp
put client/d.cpp tracer/local_render.hpp
put common/image/e.cpp common/scene/scene.hpp
bash "$check" "$tree" || { echo "layers_check.sh refused what the layers allow"; status=1; }
[ "$status" -eq 0 ] && echo "layers_check.sh names every crossing and passes what is allowed"
exit "$status"
