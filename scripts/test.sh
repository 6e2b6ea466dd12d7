#!/usr/bin/env bash
# Set-up, build and the whole test suite: what `.ci/run` runs and README's second command.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake --preset default
cmake --build --preset default -j2
ctest --preset default -j2
