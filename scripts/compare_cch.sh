#!/usr/bin/env bash
# D* Lite's replans against RoutingKit's CCH, back to back on this machine: for each seed and run,
# `corridor bench replan` (D* Lite on the contraction hierarchy with lazy rises, checked against
# Dijkstra) and RoutingKit's cch_bench (partial customization plus query, checked against its own
# Dijkstra) on the same map with the same kind of update stream. Prints each pair's p50 and p99 and
# their ratios (Corridor / CCH: below 1 is faster), then the worst ratio over all pairs.
#
# Usage: scripts/compare_cch.sh [MAP] [SEEDS] [RUNS]
#   MAP default ../shared/data/osm/porto.osm.pbf; SEEDS default "1 7"; RUNS per seed default 2.
# Environment: CORRIDOR (default build/app/corridor), CCH_DIR (where RoutingKit's anchor is built;
#   default /tmp/cch, built with ../shared/anchors/routingkit-cch/build.sh when missing),
#   TRIPS (10), UPDATES (20).
set -euo pipefail
cd "$(dirname "$0")/.."
corridor=${CORRIDOR:-build/app/corridor}
map=${1:-../shared/data/osm/porto.osm.pbf}
seeds=${2:-1 7}
runs=${3:-2}
trips=${TRIPS:-10}
updates=${UPDATES:-20}
cch_dir=${CCH_DIR:-/tmp/cch}
anchor=../shared/anchors/routingkit-cch
[[ -f $map ]] || { echo "no map at $map" >&2; exit 2; }
if [[ ! -x $cch_dir/cch_bench ]]; then
  [[ -x $anchor/build.sh ]] || { echo "RoutingKit's anchor is not at $anchor" >&2; exit 2; }
  "$anchor/build.sh" "$cch_dir" > /dev/null
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The graph cache is built once, outside the timed runs.
"$corridor" map info --map "$map" > /dev/null 2>&1 || true

pairs=()
for seed in $seeds; do
  for run in $(seq 1 "$runs"); do
    out="$work/s${seed}r${run}"
    "$corridor" bench replan --map "$map" --trips "$trips" --updates "$updates" --seed "$seed" --hierarchy lazy \
      > "$out.corridor.json" 2> "$out.corridor.log"
    "$cch_dir/cch_bench" "$map" "$trips" "$updates" "$seed" > "$out.cch.json" 2> "$out.cch.log"
    pairs+=("$seed:$run:$out")
  done
done

/usr/bin/python3 - "${pairs[@]}" <<'PY'
import json, sys
worst50 = worst99 = 0.0
mismatches = 0
print(f"{'seed':>4} {'run':>3} | {'D* Lite p50':>11} {'p99':>7} | {'CCH p50':>8} {'p99':>7} | {'ratio p50':>9} {'p99':>6} | mismatches")
for arg in sys.argv[1:]:
    seed, run, out = arg.split(":", 2)
    c = json.load(open(out + ".corridor.json"))
    k = json.load(open(out + ".cch.json"))
    d = c["dstar_cch_lazy"]
    r = k["partial_plus_query_ms"]
    m = int(c.get("mismatches", 0)) + int(d.get("mismatches", 0))
    mismatches += m + int(k.get("mismatches", 0))
    q50, q99 = d["p50_ms"] / r["p50"], d["p99_ms"] / r["p99"]
    worst50, worst99 = max(worst50, q50), max(worst99, q99)
    print(f"{seed:>4} {run:>3} | {d['p50_ms']:>8.3f} ms {d['p99_ms']:>7.3f} | {r['p50']:>5.3f} ms {r['p99']:>7.3f} | "
          f"{q50:>9.2f} {q99:>6.2f} | {m} (CCH {k.get('mismatches', 0)})")
print(f"worst ratio over all runs: p50 {worst50:.2f}x, p99 {worst99:.2f}x CCH's; mismatches {mismatches}")
print(f"goal (both <= 0.80x, 0 mismatches): {'met' if worst50 <= 0.8 and worst99 <= 0.8 and mismatches == 0 else 'not met'}")
PY
