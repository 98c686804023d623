#!/usr/bin/env bash
# The image's HEALTHCHECK: GET /healthz from the coordinator in this container, with bash
# alone (the slim image has no curl). Exit 0: healthy.
#
#   tessera-healthcheck [HOST:PORT]   default: $TESSERA_HEALTH_ADDR, else 127.0.0.1:8640
set -euo pipefail

# A worker serves nothing over HTTP: in its container, being alive is all there is to check.
if [ "$(cat /proc/1/comm 2>/dev/null || true)" = tessera-worker ]; then
  exit 0
fi

address=${1:-${TESSERA_HEALTH_ADDR:-127.0.0.1:8640}}
host=${address%:*}
port=${address##*:}

# bash's /dev/tcp: a refused connection fails here, and the check with it.
if ! exec 3<>"/dev/tcp/$host/$port"; then
  echo "tessera-healthcheck: nothing listens on $address" >&2
  exit 1
fi
printf 'GET /healthz HTTP/1.1\r\nHost: %s\r\nConnection: close\r\n\r\n' "$address" >&3
status_line=""
read -r -t 5 status_line <&3 || true
case "$status_line" in
  "HTTP/1."[01]" 200 "*) exit 0 ;;
  *)
    echo "tessera-healthcheck: GET http://$address/healthz answered: ${status_line:-nothing}" >&2
    exit 1
    ;;
esac
