#!/usr/bin/env bash
# ctest deploy.shellcheck: the project's shell scripts pass shellcheck, at its default
# severity. Skipped (exit 77) where shellcheck is missing; deploy/install-deps.sh
# installs it.
#   tests/deploy/shellcheck.sh SOURCE_DIR
set -euo pipefail
cd "${1:?usage: shellcheck.sh SOURCE_DIR}"

if ! command -v shellcheck >/dev/null; then
  echo "skipped: shellcheck is not installed (deploy/install-deps.sh installs it)"
  exit 77
fi

scripts=(.ci/run bench/run bench/farm bench/farm_frames bench/memory)
while IFS= read -r -d '' script; do
  scripts+=("$script")
done < <(find deploy tests/deploy tests/fuzz -type f \( -name '*.sh' -o -name '*.sbatch' \) -print0 | sort -z)

echo "shellcheck $(shellcheck --version | sed -n 's/^version: //p') on ${#scripts[@]} scripts"
failed=0
for script in "${scripts[@]}"; do
  if shellcheck "$script"; then
    echo "ok: $script"
  else
    failed=1
  fi
done
exit "$failed"
