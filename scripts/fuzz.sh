#!/usr/bin/env bash
# Builds the request-handling fuzz target with clang (libFuzzer + ASan + UBSan) and runs it.
# Usage: scripts/fuzz.sh [SECONDS]   (default 60)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake --preset fuzz
cmake --build --preset fuzz -j2
mkdir -p build-fuzz/corpus
exec build-fuzz/tests/fuzz/router_fuzzer -max_total_time="${1:-60}" -max_len=4096 build-fuzz/corpus
