#!/usr/bin/env bash
# Set-up, build and the main job: the dispatch server on the embedded Monaco map, on
# 127.0.0.1:8080, with its database in ./corridor.db. It prints a development token at start
# (fixed by CORRIDOR_DEV_TOKEN when set). Extra arguments go to `corridor serve`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake --preset default
cmake --build --preset default -j2 --target corridor
exec ./build/app/corridor serve "$@"
