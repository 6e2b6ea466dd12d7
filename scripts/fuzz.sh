#!/usr/bin/env bash
# Builds the fuzz targets with clang (libFuzzer + ASan + UBSan) and runs each: the request path,
# then vehicle profiles from JSON. Usage: scripts/fuzz.sh [SECONDS]   (default 60 each)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake --preset fuzz
cmake --build --preset fuzz -j2
mkdir -p build-fuzz/corpus build-fuzz/profile_corpus
cp planner/profiles/*.json build-fuzz/profile_corpus/
build-fuzz/tests/fuzz/router_fuzzer -max_total_time="${1:-60}" -max_len=4096 build-fuzz/corpus
exec build-fuzz/tests/fuzz/profile_fuzzer -max_total_time="${1:-60}" -max_len=4096 build-fuzz/profile_corpus
