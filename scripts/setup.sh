#!/usr/bin/env bash
# Installs what a fresh Debian bookworm machine lacks, then configures and builds perinox in
# ./build (everything, or the targets named in PERINOX_TARGETS). Safe to run again: it installs
# nothing that is already there and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(cmake make g++ trilinos-all-dev libptscotch-dev libeigen3-dev libopenmpi-dev openmpi-bin libmumps-dev libopenblas0-serial
          libexodusii-dev
          libgtest-dev nlohmann-json3-dev python3 python3-matplotlib python3-yaml)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

JOBS=${PERINOX_JOBS:-$(nproc)}
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
# PERINOX_TARGETS: build only these (README command 1 builds the driver alone); default: all.
if [ -n "${PERINOX_TARGETS:-}" ]; then
  # shellcheck disable=SC2086
  cmake --build build -j"$JOBS" --target $PERINOX_TARGETS
else
  cmake --build build -j"$JOBS"
fi
