#!/usr/bin/env bash
# ctest deploy.slurm_workers: deploy/slurm/tessera-workers.sbatch, run as Slurm would run
# it but with a stand-in srun that records its arguments, starts one worker per node with
# the CPUs Slurm reserved, for the coordinator given, with the token from a file; and
# refuses to start without a coordinator or a readable token.
#   tests/deploy/slurm_workers.sh SOURCE_DIR
set -euo pipefail
script=${1:?usage: slurm_workers.sh SOURCE_DIR}/deploy/slurm/tessera-workers.sbatch

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir "$work/bin"
cat >"$work/bin/srun" <<'SRUN'
#!/usr/bin/env bash
printf '%s\n' "$@" >"$SRUN_LOG"
SRUN
chmod +x "$work/bin/srun"
echo secret >"$work/worker.token"

run() {
  env -u TESSERA_SERVER -u TESSERA_WORKER PATH="$work/bin:$PATH" SRUN_LOG="$work/srun.args" HOME="$work" \
    SLURM_JOB_ID=42 SLURM_JOB_NUM_NODES=3 SLURM_CPUS_PER_TASK=12 "$@"
}

failed=0
fail() {
  echo "FAIL: $*"
  failed=1
}

run TESSERA_WORKER_TOKEN_FILE="$work/worker.token" bash "$script" http://coordinator:8640 >"$work/out" 2>&1 ||
  { echo "FAIL: the batch script failed:"; cat "$work/out"; exit 1; }
mapfile -t args <"$work/srun.args"
expected=(--ntasks-per-node=1 --cpus-per-task=12 --kill-on-bad-exit=0
  tessera-worker --server http://coordinator:8640 --threads 12 --token-file "$work/worker.token")
if [ "${args[*]}" = "${expected[*]}" ]; then
  echo "ok: srun starts one worker per node with the CPUs of its task"
else
  fail "srun got: ${args[*]}"$'\n'"  expected: ${expected[*]}"
fi

# refused SCRIPT_ARGS... with TOKEN_FILE: the script must exit 2 before it runs srun.
refused() {
  local what=$1 token_file=$2 code=0
  shift 2
  rm -f "$work/srun.args"
  run TESSERA_WORKER_TOKEN_FILE="$token_file" bash "$script" "$@" >/dev/null 2>&1 || code=$?
  if [ "$code" -eq 2 ] && [ ! -e "$work/srun.args" ]; then
    echo "ok: $what: exit 2, no srun"
  else
    fail "$what: exit $code$([ -e "$work/srun.args" ] && echo ', srun ran')"
  fi
}
refused "no coordinator URL" "$work/worker.token"
refused "no token file" "$work/missing.token" http://coordinator:8640
exit "$failed"
