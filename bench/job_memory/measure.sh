#!/usr/bin/env bash
# What a job's tiles cost the coordinator (issue 44, part 3): its RSS before and after
# each of JOBS jobs of 1,048,576 tiles (a 8192x8192 sphere at 8-pixel tiles), bytes per
# tile and RSS per million tiles; a page of GET /v1/jobs/{id}/tiles; and the restart with
# every job stored: seconds from exec to the port file, and RSS once up. Medians of nothing:
# one run, read off /proc. Needs curl and jq.
# Usage: bench/job_memory/measure.sh BUILD_DIR [JOBS]
set -euo pipefail
build=${1:?usage: measure.sh BUILD_DIR [JOBS]}
jobs=${2:-4}
dir=$(mktemp -d)
trap 'kill $pid 2>/dev/null || true; rm -rf "$dir"' EXIT
scene='{"version":1,"image":{"width":8192,"height":8192},"render":{"tile_size":8,"samples_per_pixel":1},
 "camera":{"eye":[0,0,5],"look_at":[0,0,0],"up":[0,1,0],"fov_y":45},"materials":{"m":{"diffuse":[1,0,0]}},
 "lights":[{"type":"point","position":[0,5,5],"intensity":[1,1,1]}],
 "objects":[{"type":"sphere","center":[0,0,0],"radius":1,"material":"m"}]}'
start() {
  rm -f "$dir/port"
  local began=$(date +%s.%N)
  "$build/server/tessera-server" --listen 127.0.0.1:0 --data-dir "$dir/data" --local-workers 0 \
    --port-file "$dir/port" --job-memory-budget 0 --log-level warn >>"$dir/log" 2>&1 &
  pid=$!
  while [ ! -s "$dir/port" ]; do sleep 0.01; done
  up_s=$(awk "BEGIN { printf \"%.2f\", $(date +%s.%N) - $began }")
  url=http://127.0.0.1:$(cat "$dir/port")
}
rss_kib() { awk '/VmRSS/ {print $2}' "/proc/$pid/status"; }
start
base=$(rss_kib)
echo "| jobs of 1,048,576 tiles | RSS, MiB | growth per tile, bytes |"
echo "|---:|---:|---:|"
echo "| 0 | $((base / 1024)) | |"
for n in $(seq 1 "$jobs"); do
  id=$(curl -sf -H 'Content-Type: application/json' -d "{\"name\":\"j$n\",\"scene\":$scene}" "$url/v1/jobs" | jq -r .id)
  rss=$(rss_kib)
  echo "| $n | $((rss / 1024)) | $(( (rss - base) * 1024 / (n * 1048576) )) |"
done
page_s=$(curl -sf -o /dev/null -w '%{time_total}' "$url/v1/jobs/$id/tiles?offset=500000")
echo
echo "a page of 10,000 tiles: ${page_s} s, RSS after $(( $(rss_kib) / 1024 )) MiB"
kill -TERM $pid; wait $pid || true
start
echo "restart with $jobs such jobs stored: up in ${up_s} s, RSS $(( $(rss_kib) / 1024 )) MiB"
