#!/usr/bin/env bash
# The file readers under AddressSanitizer and UndefinedBehaviorSanitizer (tests/sanitize/): builds
# perinox_core, its unit tests and the readers' fuzzer with the sanitizers in build-sanitize/ and
# runs them (about two minutes). Run after scripts/setup.sh (it needs the same packages); CI runs it
# after the suite. Extra arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${PERINOX_JOBS:-$(nproc)}
cmake -S tests/sanitize -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build-sanitize -j"$JOBS"
cd build-sanitize
ctest --output-on-failure "$@"
