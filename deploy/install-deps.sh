#!/usr/bin/env bash
# Installs every package Tessera needs to build, test and run, from Debian 12.
# This is the one list of dependencies: README, CI and the container build call it.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libboost-dev libboost-system-dev
  nlohmann-json3-dev libsimdjson-dev libglm-dev libembree-dev libopenimageio-dev openimageio-tools
  libpng-dev  # PNGs are written with libpng itself, not OpenImageIO (common/image/png_file.hpp)
  libtinyobjloader-dev libtinygltf-dev  # mesh files: OBJ with MTL, glTF (common/mesh_files/)
  libtbb-dev libsqlite3-dev libssl-dev libcli11-dev libspdlog-dev
  libgtest-dev libgmock-dev
  clang libclang-rt-14-dev  # the scene parser's libFuzzer test (tests/fuzz/run.sh)
  iproute2  # `ip netns`: the multi-host farm test (tests/farm/farm_netns_test.cpp)
  libyaml-cpp-dev shellcheck  # the checks of deploy/ and the protocol's contract with docs/openapi.yaml
  clang-format  # tests/format_check.sh: every C++ file as .clang-format writes it
  ca-certificates  # the system's CAs, which https:// servers are checked against by default
  openssl  # the TLS test makes its CA and certificates with it (tests/farm/farm_tls_test.cpp)
)

if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps.sh: run as root (it calls apt-get)" >&2
  exit 1
fi

# Tools for tests only, never the product: from npm, pinned with their lock file in
# tests/tools/. Only in a checkout (the container build copies this script alone).
tools=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/tests/tools
# Debian's, unless this machine has a Node.js of its own (which Debian's npm would conflict with).
if [ -f "$tools/package-lock.json" ] && ! command -v npm >/dev/null; then
  packages+=(nodejs npm)
fi
# Programs only tests run, against the real thing: in a checkout, not in a container build.
if [ -f "$tools/package-lock.json" ]; then
  packages+=(
    chromium    # the web dashboard's browser test drives it with playwright-core (tests/browser/)
    prometheus  # a real Prometheus scrapes the coordinator (tests/farm/farm_metrics_test.cpp)
    ffmpeg      # tessera render -o movie.mp4 runs it where it is installed (tests/cli_movie_test.cmake)
  )
fi

export DEBIAN_FRONTEND=noninteractive
apt-get update -q
apt-get install -y -q --no-install-recommends "${packages[@]}"

if [ -f "$tools/package-lock.json" ]; then
  # A failed install leaves the linter's test skipped, saying so; it does not stop the build.
  (cd "$tools" && npm ci --no-audit --no-fund --loglevel=error) ||
    echo "install-deps.sh: npm ci in $tools failed; tests/openapi_lint.sh and tests/browser/ will be skipped" >&2
fi
