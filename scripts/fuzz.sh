#!/usr/bin/env bash
# Builds the fuzz targets with clang (libFuzzer + ASan + UBSan) and runs each: the request path,
# vehicle profiles from JSON, controllers files and signal-agent manifests, then gpsd reports and
# NMEA logs. Usage: scripts/fuzz.sh [SECONDS]   (default 60 each)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake --preset fuzz
cmake --build --preset fuzz -j2
mkdir -p build-fuzz/corpus build-fuzz/profile_corpus build-fuzz/controllers_corpus build-fuzz/gnss_corpus
cp planner/profiles/*.json build-fuzz/profile_corpus/
cp tests/fuzz/seeds/controllers/*.json build-fuzz/controllers_corpus/
cp tests/fuzz/seeds/gnss/* build-fuzz/gnss_corpus/
build-fuzz/tests/fuzz/router_fuzzer -max_total_time="${1:-60}" -max_len=4096 build-fuzz/corpus
build-fuzz/tests/fuzz/profile_fuzzer -max_total_time="${1:-60}" -max_len=4096 build-fuzz/profile_corpus
build-fuzz/tests/fuzz/controllers_fuzzer -max_total_time="${1:-60}" -max_len=8192 build-fuzz/controllers_corpus
exec build-fuzz/tests/fuzz/gnss_fuzzer -max_total_time="${1:-60}" -max_len=2048 build-fuzz/gnss_corpus
