#!/usr/bin/env bash
# ctest deploy.kustomize_build: kustomize renders deploy/k8s (with stand-in tokens, as a
# user would create them), and every workload refers to the generated Secret by its
# hashed name. Offline; skipped (exit 77) where neither kustomize nor kubectl is installed
# (Debian 12 packages neither: the YAML checks of tessera_deploy_tests run everywhere).
#   tests/deploy/kustomize_build.sh SOURCE_DIR
set -euo pipefail
source_dir=${1:?usage: kustomize_build.sh SOURCE_DIR}

if command -v kustomize >/dev/null; then
  render=(kustomize build)
elif command -v kubectl >/dev/null; then
  render=(kubectl kustomize)
else
  echo "skipped: neither kustomize nor kubectl is installed"
  exit 77
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$source_dir/deploy/k8s" "$work/k8s"
cp -r "$source_dir/deploy/k8s-tls" "$work/k8s-tls"
for token in api worker metrics; do
  echo "stand-in-$token-token" >"$work/k8s/$token.token"
done
if ! "${render[@]}" "$work/k8s" >"$work/rendered.yaml" 2>"$work/errors"; then
  echo "FAIL: ${render[*]} deploy/k8s:"
  cat "$work/errors"
  exit 1
fi

failed=0
secret=$(sed -n 's/^  name: \(tessera-tokens-[a-z0-9]\{6,\}\)$/\1/p' "$work/rendered.yaml")
if [ -z "$secret" ]; then
  echo "FAIL: no generated Secret tessera-tokens-HASH in the output"
  failed=1
fi
uses=$(grep -c "secretName: $secret\$" "$work/rendered.yaml" || true)
if [ "$uses" -ne 2 ]; then
  echo "FAIL: $uses workloads use Secret $secret, expected the coordinator and the workers"
  failed=1
fi
if grep -q 'secretName: tessera-tokens$' "$work/rendered.yaml"; then
  echo "FAIL: a workload still names the Secret without its hash"
  failed=1
fi
for kind in Namespace Secret Service StatefulSet Deployment ScaledObject; do
  grep -q "^kind: $kind\$" "$work/rendered.yaml" || { echo "FAIL: no $kind rendered"; failed=1; }
done
# KEDA makes the workers' HorizontalPodAutoscaler from the ScaledObject; a second one would
# fight it over the replica count.
if grep -q '^kind: HorizontalPodAutoscaler$' "$work/rendered.yaml"; then
  echo "FAIL: a HorizontalPodAutoscaler is rendered beside KEDA's ScaledObject"
  failed=1
fi

# The TLS overlay beside it: the coordinator gets its certificate and key, the workers only the CA,
# and both speak https://.
for file in tls.crt tls.key ca.crt; do
  echo "stand-in $file" >"$work/k8s-tls/$file"
done
if ! "${render[@]}" "$work/k8s-tls" >"$work/tls.yaml" 2>"$work/errors"; then
  echo "FAIL: ${render[*]} deploy/k8s-tls:"
  cat "$work/errors"
  exit 1
fi
tls_secret=$(sed -n 's/^  name: \(tessera-tls-[a-z0-9]\{6,\}\)$/\1/p' "$work/tls.yaml")
for wanted in "secretName: $tls_secret" "--tls-cert" "/run/secrets/tessera-tls/tls.crt" \
  "https://tessera-coordinator:8640" "scheme: HTTPS" "key: ca.crt"; do
  grep -q -- "$wanted" "$work/tls.yaml" || { echo "FAIL: deploy/k8s-tls renders no \"$wanted\""; failed=1; }
done
if [ -z "$tls_secret" ] || [ "$(grep -c "secretName: $tls_secret\$" "$work/tls.yaml")" -ne 2 ]; then
  echo "FAIL: the coordinator and the workers do not both mount Secret tessera-tls-HASH"
  failed=1
fi
[ "$failed" -eq 0 ] && echo "ok: ${render[*]} renders deploy/k8s and deploy/k8s-tls; the workloads use Secret $secret"
exit "$failed"
