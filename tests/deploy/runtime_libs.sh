#!/usr/bin/env bash
# ctest deploy.runtime_libs: the runtime stage of deploy/docker/Dockerfile installs the
# Debian package of every shared library the built programs link against directly (apt
# brings what those need in turn), and every package it names exists in Debian 12.
# Skipped (exit 77) on a machine without readelf, ldd or dpkg.
#   tests/deploy/runtime_libs.sh SOURCE_DIR BINARY...
set -euo pipefail
source_dir=${1:?usage: runtime_libs.sh SOURCE_DIR BINARY...}
shift
dockerfile=$source_dir/deploy/docker/Dockerfile

for tool in readelf ldd dpkg-query; do
  if ! command -v "$tool" >/dev/null; then
    echo "skipped: $tool is missing (binutils, libc-bin, dpkg)"
    exit 77
  fi
done

# The words of the runtime stage's `apt-get install` (from the last FROM on, continuation
# lines joined), without its options.
mapfile -t listed < <(
  sed -n '/^FROM .*bookworm-slim/,$p' "$dockerfile" | sed -e ':a' -e '/\\$/N; s/\\\n//; ta' |
    grep -o 'apt-get install[^&]*' | tr ' ' '\n' | grep -v -e '^-' -e '^apt-get$' -e '^install$' -e '^$'
)
if [ "${#listed[@]}" -eq 0 ]; then
  echo "FAIL: no apt-get install found in the runtime stage of $dockerfile"
  exit 1
fi
echo "runtime packages: ${listed[*]}"

# Essential in every Debian image: no need to name them.
essential=(libc6 libgcc-s1)
failed=0
# The programs, then Tessera's own shared libraries that they load.
queue=("$@")
for ((next = 0; next < ${#queue[@]}; next++)); do
  binary=${queue[next]}
  linked=$(ldd "$binary")
  own_dir=$(readlink -m "$(dirname "$binary")/../lib/tessera")
  while read -r library; do
    # The loader itself, which ldd names by its path (libc6's, essential).
    [[ $library == ld-linux* ]] && continue
    path=$(awk -v lib="$library" '$1 == lib { print $3 }' <<<"$linked")
    # Tessera's own tracer library: the runtime stage copies lib/tessera/ whole (checked
    # by DeployDocker tests). What each of its builds links is checked in turn.
    if [ -n "$path" ] && [[ $(readlink -f "$path") == "$own_dir"/* ]]; then
      for build in "$own_dir/$library" "$own_dir"/glibc-hwcaps/*/"$library"; do
        # A build with -DTESSERA_TRACER_VARIANTS=OFF has no glibc-hwcaps/ (the pattern
        # then stands for itself).
        [ -e "$build" ] || continue
        [[ " ${queue[*]} " == *" $build "* ]] || queue+=("$build")
      done
      continue
    fi
    if [ -z "$path" ] || [ "$path" = "not" ]; then
      echo "FAIL: $binary needs $library, which is not found here"
      failed=1
      continue
    fi
    # dpkg knows the file under the name it installed, /usr/lib/... or /lib/...
    package=$(dpkg-query -S "$(readlink -f "$path")" 2>/dev/null || dpkg-query -S "$path" 2>/dev/null || true)
    package=${package%%:*}
    if [ -z "$package" ]; then
      echo "FAIL: $library ($path) belongs to no Debian package"
      failed=1
    elif [[ " ${listed[*]} ${essential[*]} " != *" $package "* ]]; then
      echo "FAIL: $(basename "$binary") links $library from $package, which the runtime stage does not install"
      failed=1
    fi
  done < <(readelf -d "$binary" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
done

# Names that exist: apt's lists are there after install-deps.sh's `apt-get update`.
if command -v apt-cache >/dev/null && [ -n "$(apt-cache policy libc6 | sed -n 's/^ *Candidate: //p')" ]; then
  # One look-up for all of them: apt-cache is slow to start.
  known=" $(apt-cache show --no-all-versions "${listed[@]}" 2>/dev/null | sed -n 's/^Package: //p' | tr '\n' ' ') "
  for package in "${listed[@]}"; do
    if [[ "$known" != *" $package "* ]]; then
      echo "FAIL: the runtime stage installs $package, which apt does not know"
      failed=1
    fi
  done
else
  echo "note: apt has no package lists here; the names were not looked up"
fi
[ "$failed" -eq 0 ] && echo "ok: every library the programs need comes from a listed package"
exit "$failed"
