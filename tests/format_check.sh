#!/usr/bin/env bash
# Fails on any C++ file of the tree that clang-format (.clang-format) would change, naming
# each. Skipped (77) where clang-format or the git checkout is missing.
# Usage: tests/format_check.sh SOURCE_DIR
set -euo pipefail
root=${1:?usage: format_check.sh SOURCE_DIR}
cd "$root"
if ! command -v clang-format >/dev/null; then
  echo "skipped: clang-format is not installed (deploy/install-deps.sh installs it)"
  exit 77
fi
if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "skipped: $root is not a git checkout, so its own files cannot be listed"
  exit 77
fi
unformatted=()
while IFS= read -r -d '' file; do
  [ -f "$file" ] || continue  # deleted in the work tree, not yet in the index
  if ! clang-format --dry-run --Werror "$file" >/dev/null 2>&1; then unformatted+=("$file"); fi
done < <(git ls-files -z --cached --others --exclude-standard -- '*.cpp' '*.hpp')
if [ ${#unformatted[@]} -gt 0 ]; then
  echo "clang-format would change ${#unformatted[@]} file(s); run: clang-format -i FILE"
  printf '  %s\n' "${unformatted[@]}"
  exit 1
fi
echo "every C++ file is as clang-format writes it"
