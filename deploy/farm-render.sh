#!/usr/bin/env bash
# Renders one scene through a coordinator and local workers on this machine:
# starts tessera-server with its local workers, submits the scene with
# `tessera submit --wait` (progress shows as it renders), writes the image, stops the server.
#
# Usage: deploy/farm-render.sh SCENE.json OUT.png
# Environment: TESSERA_BUILD_DIR  where the binaries were built (default: build)
set -euo pipefail

if [ $# -ne 2 ]; then
  echo "usage: $0 SCENE.json OUT.png" >&2
  exit 2
fi
scene=$1
out=$2
build=${TESSERA_BUILD_DIR:-build}
work=$(mktemp -d)
server_pid=

stop_server() {
  if [ -n "$server_pid" ] && kill -0 "$server_pid" 2>/dev/null; then
    kill -TERM "$server_pid"
    wait "$server_pid" || true
  fi
  rm -rf "$work"
}
trap stop_server EXIT

"$build/server/tessera-server" --listen 127.0.0.1:0 --port-file "$work/port" \
  --data-dir "$work/data" --log-level warn &
server_pid=$!

# Wait for the server to listen (it writes its port once bound).
for _ in $(seq 1 200); do
  [ -s "$work/port" ] && break
  kill -0 "$server_pid" 2>/dev/null || { echo "tessera-server failed to start" >&2; exit 1; }
  sleep 0.05
done
[ -s "$work/port" ] || { echo "tessera-server did not start listening" >&2; exit 1; }

"$build/client/tessera" --server "http://127.0.0.1:$(cat "$work/port")" \
  submit "$scene" --wait -o "$out"
