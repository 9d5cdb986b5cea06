#!/usr/bin/env bash
# README command 2: set up, build, and run the whole test suite (unit, verification, MPI,
# bad input) with CTest. Extra arguments go to ctest, e.g. -L mpi.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cd build
ctest --output-on-failure -j"${PERINOX_JOBS:-$(nproc)}" "$@"
