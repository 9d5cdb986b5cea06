#!/usr/bin/env bash
# README command 1: set up, build, and solve the default scene (the cantilever of seed 000,
# section 4.4). Extra arguments go to the driver, e.g. --set "Model/G=0.05".
set -euo pipefail
cd "$(dirname "$0")/.."
PERINOX_TARGETS=perinox ./scripts/setup.sh  # the driver alone: the tests are built by README command 2
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
./build/drivers/perinox run xml/cantilever.xml --output out/cantilever "$@"
echo "Open out/cantilever/deformed.png, or out/cantilever/fields.pvtu in ParaView."
