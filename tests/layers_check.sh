#!/usr/bin/env bash
# The folders depend one way only (docs/architecture.md): fails naming each #include that
# crosses a line the table there draws.
# Usage: tests/layers_check.sh SOURCE_DIR
set -euo pipefail
root=${1:?usage: layers_check.sh SOURCE_DIR}
cd "$root"
status=0
# refuse FOLDER PATTERN WHY [EXCEPT]: no file under FOLDER may have an #include matching
# PATTERN, but for the grep lines (FILE:LINE:TEXT) that EXCEPT matches from their start.
# Rules name folders, never files: a new file is checked by the rules of its folder.
refuse() {
  local folder=$1 pattern=$2 why=$3 exclude=${4:-}
  local hits
  # A rule whose folder is gone checks nothing: that is a failure, not a pass.
  [ -d "$folder" ] || { echo "$folder: no such folder; the rule \"$why\" checks nothing"; status=1; return; }
  hits=$(grep -rnE --include='*.cpp' --include='*.hpp' "^#include [<\"]($pattern)" "$folder" |
         { if [ -n "$exclude" ]; then grep -vE "^($exclude)" || true; else cat; fi; } || true)
  if [ -n "$hits" ]; then
    echo "$folder: $why:"
    echo "$hits" | sed 's/^/  /'
    status=1
  fi
}
# common/: each folder uses only those before it, and nothing above common/.
refuse common 'boost/|embree|sqlite3|tracer/|worker/|server/|client/' \
  "common/ includes nothing above it, and only common/net/ uses Beast" 'common/net/'
refuse common/text 'common/' "text/ is common's bottom: it includes no other folder of common/" \
  'common/text/[a-z0-9_]+\.(cpp|hpp):[0-9]+:#include "common/text/'
refuse common/scene 'common/(image|scn|mesh_files|net)/' \
  "the scene format uses text/ and the protocol's types (its asset digests) alone"
refuse common/image 'common/(scn|mesh_files|net)/' "images use the scene format, the protocol's types and text/ alone"
refuse common/scn 'common/(image|mesh_files|net)/' \
  "the .scn importer writes the scene format; it reads no images and knows no wire"
refuse common 'tiny_obj_loader|tiny_gltf|common/mesh_files/' \
  "only common/mesh_files/ reads mesh formats; the parser sees them through SceneFiles" \
  'common/mesh_files/'
refuse common/mesh_files 'boost/|embree|sqlite3|common/net/|common/protocol/' \
  "mesh files are read with tinyobjloader, tinygltf and common/ alone"
refuse common/protocol 'boost/|common/(net|scene|image|scn|mesh_files)/' \
  "the protocol is JSON types only, over text/: the scene format and images are above it"
refuse common/net 'embree|sqlite3' "the transport knows only the protocol"
# The tracer renders a validated scene: no daemon, CLI, coordinator or network in it.
refuse tracer 'boost/|sqlite3|worker/|client/|server/|common/net/|common/protocol/' \
  "the tracer renders a validated Scene and knows nothing of who asked"
refuse worker 'client/|server/' "the worker daemon links tracer/, common/net and common/protocol"
refuse client 'server/|worker/' "the CLI renders with tracer/; it includes neither the worker daemon nor the coordinator"
# The coordinator: farm state and HTTP know nothing of each other; api/ joins them.
refuse server 'tracer/|worker/|client/|common/net/' "the coordinator is never a client and never renders"
refuse server/metrics 'server/' "metrics/ is what the others count into: it includes none of them" \
  'server/metrics/[a-z0-9_]+\.(cpp|hpp):[0-9]+:#include "server/metrics/'
refuse server/farm 'server/(http|api)/|boost/beast' "farm state never includes HTTP or routes"
refuse server/http 'server/(farm|api)/' "HTTP never includes farm state or routes"
[ "$status" -eq 0 ] && echo "every #include keeps to the layers of docs/architecture.md"
exit "$status"
