#!/usr/bin/env bash
# ctest deploy.systemd_verify: systemd itself parses the units of deploy/systemd (a
# misspelt directive is only a warning to systemd, so any message fails the test), and
# rates their exposure as well hardened. Skipped (exit 77) without systemd-analyze.
#   tests/deploy/systemd_verify.sh SOURCE_DIR
set -euo pipefail
source_dir=${1:?usage: systemd_verify.sh SOURCE_DIR}

if ! command -v systemd-analyze >/dev/null; then
  echo "skipped: systemd-analyze is not installed (Debian package systemd)"
  exit 77
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# verify insists that ExecStart's program exists: stand /bin/true in for the binaries,
# which need not be installed on this machine.
for unit in "$source_dir"/deploy/systemd/*.service; do
  sed 's#/usr/local/bin/tessera-[a-z]*#/bin/true#' "$unit" >"$work/$(basename "$unit")"
done
# A template is verified through an instance of it.
ln -s 'tessera-worker@.service' "$work/tessera-worker@1.service"

failed=0
for unit in tessera-server.service tessera-worker@1.service; do
  if ! messages=$(cd "$work" && systemd-analyze verify "./$unit" 2>&1) || [ -n "$messages" ]; then
    echo "FAIL: systemd-analyze verify $unit:"
    echo "$messages"
    failed=1
    continue
  fi
  # Exposure from 0 (locked down) to 10 (unprotected); --threshold is in tenths.
  exposure=$(cd "$work" && systemd-analyze security --offline=yes "./$unit" 2>&1 | tail -n 1)
  if ! (cd "$work" && systemd-analyze security --offline=yes --threshold=20 "./$unit" >/dev/null 2>&1); then
    echo "FAIL: $unit is not hardened enough: $exposure (at most 2.0)"
    failed=1
    continue
  fi
  echo "ok: $unit ($exposure)"
done
exit "$failed"
