#!/usr/bin/env bash
# End-to-end tests of `corridor route`, `corridor map`, `corridor bench replan` and `bench serve` as a user runs them.
# Usage: route_cli_test.sh CORRIDOR_BINARY SHARED_DATA_DIR
set -euo pipefail
corridor=$1
data=$2/osm
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export CORRIDOR_CACHE_DIR=$work/cache
passed=0
failed=0

pass() { passed=$((passed + 1)); }
fail() { echo "FAIL: $*" >&2; failed=$((failed + 1)); }

# check_feature FILE ALGO: a GeoJSON Feature with a LineString in lon,lat and the contract keys.
check_feature() {
  python3 - "$1" "$2" <<'PY'
import json, sys
f = json.load(open(sys.argv[1]))
assert f["type"] == "Feature", f["type"]
g = f["geometry"]
assert g["type"] == "LineString" and len(g["coordinates"]) >= 2, g
for lon, lat in g["coordinates"]:
    assert -180 <= lon <= 180 and -90 <= lat <= 90
p = f["properties"]
for key in ("travel_time_s", "length_m", "algorithm", "nodes"):
    assert key in p, key
assert p["algorithm"] == sys.argv[2], p["algorithm"]
assert p["travel_time_s"] > 0 and p["length_m"] > 0
print(p["travel_time_s"])
PY
}

route_all_algorithms() {  # MAP FROM TO LABEL
  local times=()
  for algo in dstar astar dijkstra; do
    if "$corridor" route --map "$1" --from "$2" --to "$3" --algo "$algo" > "$work/r.json" 2> "$work/err" &&
       t=$(check_feature "$work/r.json" "$algo"); then
      times+=("$t")
    else
      fail "$4 $algo: $(cat "$work/err")"
      return
    fi
  done
  if python3 -c "import sys; t=[float(x) for x in sys.argv[1:]]; sys.exit(0 if max(t)-min(t) <= 1e-9*max(t) else 1)" "${times[@]}"; then
    pass
  else
    fail "$4: algorithms disagree: ${times[*]}"
  fi
}

# 1. Every shared extract, all three algorithms, one cold import and one warm cache run.
route_all_algorithms "$data/monaco.osm.gz" 43.7384,7.4246 43.7496,7.4365 monaco
route_all_algorithms "$data/andorra.osm.pbf" 42.5128977,1.5513077 42.5719099,1.6116162 andorra
route_all_algorithms "$data/liechtenstein.osm.pbf" 47.1707728,9.5171301 47.1162118,9.5237511 liechtenstein
route_all_algorithms "$data/berlin-siegessaeule.osm.gz" 52.5146732,13.3490928 52.5150445,13.3492259 berlin
# The embedded default map needs no --map.
if "$corridor" route --from 43.7384,7.4246 --to 43.7496,7.4365 > "$work/r.json" && check_feature "$work/r.json" dstar > /dev/null; then
  pass
else
  fail "embedded default map"
fi

# 2. Maps never seen before: random clips of the extracts, in every input format, with ways cut at
#    the border. Start and goal are random nodes of drivable ways inside the clip.
python3 - "$data" "$work" <<'PY' > "$work/clips.txt"
import random, sys
data, work = sys.argv[1], sys.argv[2]
random.seed(7)
boxes = {"monaco.osm.gz": (7.409, 43.724, 7.436, 43.750), "andorra.osm.pbf": (1.45, 42.45, 1.72, 42.62),
         "liechtenstein.osm.pbf": (9.48, 47.06, 9.60, 47.24)}
formats = ["osm.pbf", "osm.gz", "osm"]
i = 0
for name, (x0, y0, x1, y1) in boxes.items():
    for k in range(2):
        w, h = (x1 - x0) * random.uniform(0.3, 0.6), (y1 - y0) * random.uniform(0.3, 0.6)
        ax, ay = random.uniform(x0, x1 - w), random.uniform(y0, y1 - h)
        print(f"{data}/{name} {ax:.5f},{ay:.5f},{ax + w:.5f},{ay + h:.5f} {work}/clip{i}.{formats[i % 3]}")
        i += 1
PY
while read -r source bbox clip; do
  osmium extract -b "$bbox" -s smart "$source" -o "$clip" --overwrite 2> /dev/null
  osmium tags-filter "$clip" w/highway=primary,secondary,tertiary,residential -o "$work/roads.opl" -f opl --overwrite 2> /dev/null
  mapfile -t points < <(grep '^n' "$work/roads.opl" | sed -E 's/.* x([-0-9.]+) y([-0-9.]+).*/\2,\1/' | shuf --random-source=<(yes) -n 2)
  if ((${#points[@]} < 2)); then
    fail "clip $clip has no roads"
    continue
  fi
  route_all_algorithms "$clip" "${points[0]}" "${points[1]}" "clip $(basename "$clip") of $(basename "$source")"
done < "$work/clips.txt"

# 3. Bad input gets a clear error and a non-zero exit.
expect_error() {  # EXPECTED_TEXT CMD...
  local text=$1
  shift
  if "$@" > "$work/out" 2> "$work/err"; then
    fail "expected failure: $*"
  elif grep -q -- "$text" "$work/err"; then
    pass
  else
    fail "error for '$*' lacks '$text': $(cat "$work/err")"
  fi
}
expect_error "map file not found" "$corridor" route --map /nope.osm.pbf --from 43.7384,7.4246 --to 43.7496,7.4365
printf 'garbage that is not a pbf' > "$work/bad.osm.pbf"
expect_error "cannot read OSM file" "$corridor" route --map "$work/bad.osm.pbf" --from 43.7384,7.4246 --to 43.7496,7.4365
expect_error "outside the map" "$corridor" route --from 48.85,2.35 --to 43.7496,7.4365
expect_error "expects LAT,LON" "$corridor" route --from 43.7384 --to 43.7496,7.4365
expect_error "not a valid coordinate" "$corridor" route --from 95,7.42 --to 43.7496,7.4365
expect_error "no drivable road within" "$corridor" route --from 43.7300,7.4300 --to 43.7496,7.4365 --max-snap-m 20
expect_error "--algo must be" "$corridor" route --from 43.7384,7.4246 --to 43.7496,7.4365 --algo bfs
expect_error "--vmax-kmh" "$corridor" route --from 43.7384,7.4246 --to 43.7496,7.4365 --vmax-kmh -3
expect_error "--max-snap-m must be" "$corridor" route --from 43.7384,7.4246 --to 43.7496,7.4365 --max-snap-m nan
expect_error "--max-snap-m must be" "$corridor" route --from 43.7384,7.4246 --to 43.7496,7.4365 --max-snap-m -1

# 4. The cache: a second load comes from it, and a graph cache works as --map.
"$corridor" map info --map "$data/monaco.osm.gz" > "$work/info1.json"
"$corridor" map info --map "$data/monaco.osm.gz" > "$work/info2.json"
if grep -q '"loaded_from": "cache"' "$work/info2.json"; then pass; else fail "second load did not use the cache"; fi
"$corridor" map import --input "$data/monaco.osm.gz" --out "$work/monaco.cgr" > /dev/null
route_all_algorithms "$work/monaco.cgr" 43.7384,7.4246 43.7496,7.4365 "graph cache as --map"

# 5. The replanning benchmark keeps its contract keys and never disagrees with Dijkstra.
"$corridor" bench replan --map "$data/monaco.osm.gz" --trips 3 --updates 5 --seed 3 > "$work/bench.json" 2> /dev/null
if python3 - "$work/bench.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for k in ("graph", "dstar", "astar", "dijkstra", "speedup_p50_vs_astar", "speedup_p50_vs_dijkstra", "mismatches"):
    assert k in j, k
for a in ("dstar", "astar", "dijkstra"):
    for q in ("p50_ms", "p95_ms", "max_ms"):
        assert j[a][q] >= 0
assert j["graph"]["nodes"] > 0 and j["replans"] > 0
assert j["mismatches"] == 0, j["mismatches"]
# D* Lite on the hierarchy, eager and with lazy rises, is checked against Dijkstra too.
for h in ("dstar_cch", "dstar_cch_lazy"):
    assert j[h]["count"] == j["replans"], h
    assert j[h]["mismatches"] == 0, (h, j[h]["mismatches"])
assert j["dstar_cch_lazy"]["mean_repairs"] >= 1
PY
then pass; else fail "bench replan output"; fi

# 6. The preemption tables: the JSON contract, and 1/8 of the cells agree.
"$corridor" preemption tables --json > "$work/tables.json"
if python3 - "$work/tables.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
assert set(t) == {"movements", "phases", "high", "low"}, set(t)
assert len(t["movements"]) == 12 and len(t["phases"]) == 8 and t["phases"][0] == "4+7"
assert all(len(row) == 8 for row in t["high"] + t["low"]) and len(t["high"]) == len(t["low"]) == 12
same = sum(h == l for hr, lr in zip(t["high"], t["low"]) for h, l in zip(hr, lr))
assert same * 8 == 96, same
assert t["low"][t["movements"].index("N->S")][t["phases"].index("3+8")] == "4+8"
PY
then pass; else fail "preemption tables --json"; fi
"$corridor" preemption tables | grep -q "agree in 12 of 96 cells" && pass || fail "preemption tables text"

# 6b. Signal costs per movement: a route that crosses signals costs more with their waits than
# without, the rule is echoed, and an unknown rule is a usage error.
from_sig=43.7384,7.4246
to_sig=43.7450,7.4300
if "$corridor" route --from "$from_sig" --to "$to_sig" > "$work/flat.json" 2> /dev/null &&
   "$corridor" route --from "$from_sig" --to "$to_sig" --signals preempted > "$work/pre.json" 2> /dev/null &&
   "$corridor" route --from "$from_sig" --to "$to_sig" --signals normal > "$work/nor.json" 2> /dev/null &&
   python3 - "$work/flat.json" "$work/pre.json" "$work/nor.json" <<'PY'
import json, sys
flat, pre, nor = (json.load(open(f))["properties"] for f in sys.argv[1:])
assert (flat["signal_costs"], pre["signal_costs"], nor["signal_costs"]) == ("flat", "preempted", "normal")
assert len(flat["signals"]) > 0, "the test route should cross a signal"
# Waits only add; the normal program's reds cost more than a preempted transition.
assert flat["travel_time_s"] < pre["travel_time_s"] <= nor["travel_time_s"], (flat["travel_time_s"], pre["travel_time_s"], nor["travel_time_s"])
PY
then pass; else fail "route --signals"; fi
set +e
"$corridor" route --from "$from_sig" --to "$to_sig" --signals sometimes > /dev/null 2> "$work/err"
code=$?
set -e
if [[ $code == 2 ]] && grep -q "flat, preempted or normal" "$work/err"; then pass; else fail "route --signals sometimes: exit $code, $(cat "$work/err")"; fi

# 7. The server load benchmark: a short paced run on the embedded map keeps its keys, answers every
# request, and reads back one per-mission repair sample for each congestion-triggered replan.
"$corridor" bench serve --seconds 1.5 --rate 400 --vehicles 20 --missions 10 --congestion-edges-per-s 400 > "$work/serve.json" 2> /dev/null
if python3 - "$work/serve.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["errors"] == 0, j["errors"]
p, c = j["positions"], j["congestion"]
assert p["count"] > 0 and p["per_s"] > 0 and 0 <= p["p50_ms"] <= p["p99_ms"] <= p["max_ms"], p
assert c["count"] > 0 and c["replan_latency_ms"]["count"] == c["count"], c
s = p["server_side"]
assert s["count"] == p["count"], (s["count"], p["count"])  # every answered position, timed by the server too
lag = p["send_lag_ms"]  # paced: each request left before its answer came, so its lag is under its latency
assert lag["count"] == p["count"] and 0 <= lag["p50_ms"] <= lag["p99_ms"] <= lag["max_ms"] <= p["max_ms"], (lag, p)
after = p["after_send_ms"]  # and the part after it left is under the latency too
assert after["count"] == p["count"] and 0 < after["p50_ms"] <= after["p99_ms"] <= after["max_ms"] <= p["max_ms"], (after, p)
r = c["mission_replans"]
assert r["count"] > 0, r
shares = [b["share"] for b in r["share_within"]]
assert shares == sorted(shares) and shares[-1] == 1.0, shares
assert r["p99_at_most_ms"] is not None and r["p99_at_most_ms"] <= 1000, r
cfg = j["config"]
# By default half the I/O threads repair (server::default_repair_threads), at least one.
assert cfg["server_threads"] == 2 and cfg["repair_threads"] == 1 and cfg["repair_priority"] == 0, cfg
assert cfg["repair_priority_granted"] is None, cfg  # nothing asked for
PY
then pass; else fail "bench serve output: $(head -c 400 "$work/serve.json")"; fi
# With one repair thread at real-time priority: asked for, granted or not (the machine's rights),
# and the run is as complete.
"$corridor" bench serve --seconds 1 --rate 300 --vehicles 10 --missions 5 --congestion-edges-per-s 300 \
  --repair-threads 1 --repair-priority 2 > "$work/serve_rt.json" 2> /dev/null
if python3 - "$work/serve_rt.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["errors"] == 0, j["errors"]
cfg = j["config"]
assert cfg["repair_threads"] == 1 and cfg["server_threads"] == 2 and cfg["repair_priority"] == 2, cfg
assert cfg["repair_priority_granted"] in (True, False), cfg
assert j["congestion"]["mission_replans"]["count"] > 0, j["congestion"]
PY
then pass; else fail "bench serve --repair-priority output: $(head -c 400 "$work/serve_rt.json")"; fi
expect_error "not in range" "$corridor" bench serve --seconds 1 --repair-priority 100
expect_error "not in range" "$corridor" serve --repair-priority -1
expect_error "repair threads 0..64" "$corridor" bench serve --seconds 1 --repair-threads 65
expect_error "not in range" "$corridor" serve --repair-threads 65

echo "$passed passed, $failed failed"
((failed == 0))
