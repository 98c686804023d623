#!/usr/bin/env bash
# docs/openapi.yaml through a standard OpenAPI linter, Redocly's (pinned in
# tests/tools/package.json, installed by deploy/install-deps.sh): fails on any error or warning.
# Exits 77 (skipped) where the linter is not installed.
# Usage: tests/openapi_lint.sh SOURCE_DIR
set -euo pipefail
root=$(cd "${1:?usage: openapi_lint.sh SOURCE_DIR}" && pwd)
redocly="$root/tests/tools/node_modules/.bin/redocly"
if [ ! -x "$redocly" ] || ! command -v node >/dev/null; then
  echo "openapi_lint.sh: skipped: the linter is not installed (deploy/install-deps.sh runs npm ci in tests/tools)"
  exit 77
fi
cd "$root/docs"
if ! version=$("$redocly" --version 2>&1); then
  echo "openapi_lint.sh: skipped: the linter does not run under node $(node --version): $version" |
    tail -n 1
  exit 77
fi
status=0
output=$("$redocly" lint openapi.yaml --config redocly.yaml --max-problems 100 --format stylish 2>&1) ||
  status=$?
echo "$output"
if [ "$status" -ne 0 ] && ! grep -q 'Validation failed' <<<"$output"; then
  echo "openapi_lint.sh: skipped: the linter stopped without a verdict (status $status)"
  exit 77
fi
# Warnings fail too: the recommended rules are the bar.
if [ "$status" -ne 0 ] || grep -qE '^ +[0-9]+:[0-9]+ +warning ' <<<"$output"; then
  echo "openapi_lint.sh: docs/openapi.yaml has the problems above"
  exit 1
fi
