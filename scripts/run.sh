#!/usr/bin/env bash
# Set-up, build and the main job. Until the server lands, the main job is a route on the embedded map.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake --preset default
cmake --build --preset default -j2 --target corridor
exec ./build/app/corridor route --from 43.7384,7.4246 --to 43.7496,7.4365 "$@"
