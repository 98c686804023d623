#!/usr/bin/env bash
# The folders depend one way only (docs/architecture.md): fails naming each #include that
# crosses a line the table there draws.
# Usage: tests/layers_check.sh SOURCE_DIR
set -euo pipefail
root=${1:?usage: layers_check.sh SOURCE_DIR}
cd "$root"
status=0
# refuse FOLDER PATTERN WHY: no file under FOLDER (its subfolders excepted where listed
# after a colon) may have an #include matching PATTERN.
refuse() {
  local folder=$1 pattern=$2 why=$3 exclude=${4:-}
  local hits
  hits=$(grep -rnE --include='*.cpp' --include='*.hpp' "^#include [<\"]($pattern)" "$folder" |
         { if [ -n "$exclude" ]; then grep -vE "^($exclude)" || true; else cat; fi; } || true)
  if [ -n "$hits" ]; then
    echo "$folder: $why:"
    echo "$hits" | sed 's/^/  /'
    status=1
  fi
}
refuse common 'boost/|embree|sqlite3|worker/|server/|client/' \
  "the core of common/ stays free of Beast, Embree and SQLite, and of the folders above it" \
  'common/net/'
refuse common 'tiny_obj_loader|tiny_gltf|common/mesh_files/' \
  "only common/mesh_files/ reads mesh formats; the parser sees them through SceneFiles" \
  'common/mesh_files/'
refuse common/mesh_files 'boost/|embree|sqlite3|common/net/|common/protocol/' \
  "mesh files are read with tinyobjloader, tinygltf and common/ alone"
refuse common/protocol 'boost/|common/net/' "the protocol is JSON types only"
refuse common/net 'embree|sqlite3|worker/|server/|client/' "the transport knows only the protocol"
refuse worker 'client/|server/' "the worker links common/net and common/protocol, nothing of client/ or server/"
refuse client 'server/|worker/(worker_daemon|batch_tiles|lease_heartbeat|tile_uploads|render_lease)' \
  "the CLI uses the tracer of worker/, not its daemon, and nothing of server/"
refuse server 'worker/|client/|common/net/' "the coordinator is never a client"
[ "$status" -eq 0 ] && echo "every #include keeps to the layers of docs/architecture.md"
exit "$status"
