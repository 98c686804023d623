#!/usr/bin/env bash
# The dashboard's files (server/web/) and its browser test (tests/browser/) through eslint's
# recommended rules and prettier's format, both pinned in tests/tools/package.json and
# configured beside it: fails on any finding of either. With --self-test, shows that each
# fails on a file that breaks it. Exits 77 (skipped) where the tools are not installed.
# Usage: tests/web_lint.sh SOURCE_DIR [--self-test]
set -euo pipefail
root=$(cd "${1:?usage: web_lint.sh SOURCE_DIR [--self-test]}" && pwd)
tools="$root/tests/tools"
eslint="$tools/node_modules/.bin/eslint"
prettier="$tools/node_modules/.bin/prettier"
if [ ! -x "$eslint" ] || [ ! -x "$prettier" ] || ! command -v node >/dev/null; then
  echo "web_lint.sh: skipped: eslint and prettier are not installed (deploy/install-deps.sh runs npm ci in tests/tools)"
  exit 77
fi
if ! "$eslint" --version >/dev/null 2>&1; then
  echo "web_lint.sh: skipped: eslint does not run under node $(node --version)"
  exit 77
fi
# lint DIR: both tools over DIR's server/web/ and tests/browser/; prints what they found.
lint() {
  local status=0
  (cd "$1" && "$eslint" --config "$tools/eslint.config.mjs" --max-warnings 0 server/web tests/browser) ||
    status=1
  (cd "$1" && "$prettier" --config "$tools/prettier.config.json" --check \
    'server/web/**/*.{js,css,html}' 'tests/browser/**/*.mjs') || status=1
  return "$status"
}
if [ "${2:-}" != --self-test ]; then
  lint "$root" || { echo "web_lint.sh: the files above have findings"; exit 1; }
  echo "web_lint.sh: eslint and prettier find nothing in server/web/ and tests/browser/"
  exit 0
fi
tree=$(mktemp -d)
trap 'rm -rf "$tree"' EXIT
mkdir -p "$tree/server/web" "$tree/tests/browser"
printf "export const fine = 'yes';\n" >"$tree/tests/browser/fine.mjs"
# An unused variable, formatted as prettier would: eslint alone must fail.
printf "const unused = 1;\nexport const used = 2;\n" >"$tree/server/web/a.js"
if out=$(lint "$tree" 2>&1) || ! grep -q "no-unused-vars" <<<"$out"; then
  echo "web_lint.sh: eslint let an unused variable through:"; echo "$out"; exit 1
fi
# Clean code, badly formatted: prettier alone must fail.
printf 'export const used   =  "two";\n' >"$tree/server/web/a.js"
if out=$(lint "$tree" 2>&1) || ! grep -q "a.js" <<<"$out" || grep -q "no-unused-vars" <<<"$out"; then
  echo "web_lint.sh: prettier let a misformatted file through:"; echo "$out"; exit 1
fi
printf "export const used = 'two';\n" >"$tree/server/web/a.js"
lint "$tree" >/dev/null 2>&1 || { echo "web_lint.sh: a clean tree was refused"; exit 1; }
echo "web_lint.sh: eslint and prettier each fail on a file that breaks them, and pass a clean one"
