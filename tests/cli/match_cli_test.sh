#!/usr/bin/env bash
# `corridor match` as a user runs it: a GPX and a CSV trace on the embedded map give the JSON
# contract (points, way_names, route, points_per_s); a GPX without times, or with one time for all
# its points, is matched by its geometry and says it had no timing; a multipath fix is flagged as
# an outlier; bad traces give a clear error and exit 1.
# Usage: match_cli_test.sh CORRIDOR_BINARY
set -uo pipefail
corridor=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export CORRIDOR_CACHE_DIR=$work/cache
passed=0
failed=0
check() { if eval "$2"; then passed=$((passed + 1)); else echo "FAIL: $1" >&2; failed=$((failed + 1)); fi; }

# A drive along a real Monaco route: the route's own geometry, one fix every ~12 m, 1 s apart.
"$corridor" route --from 43.7384,7.4246 --to 43.7496,7.4365 > "$work/route.json"
python3 - "$work" << 'PY'
import json, math, sys
work = sys.argv[1]
c = json.load(open(f"{work}/route.json"))["geometry"]["coordinates"]
pts = []
for (x0, y0), (x1, y1) in zip(c, c[1:]):
    d = math.hypot((x1 - x0) * 80000, (y1 - y0) * 111000)
    n = max(1, int(d / 12))
    pts += [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n) for k in range(n)]
with open(f"{work}/trace.csv", "w") as f:
    f.write("time,lat,lon,hdop\n")
    for i, (x, y) in enumerate(pts):
        f.write(f"{i},{y + (0.00002 if i % 2 else -0.00002)},{x},1.0\n")
with open(f"{work}/outlier.csv", "w") as f:  # fix 30 thrown 65 m north, as multipath does
    f.write("time,lat,lon,hdop\n")
    for i, (x, y) in enumerate(pts):
        f.write(f"{i},{y + (0.000585 if i == 30 else 0.0)},{x},1.0\n")
with open(f"{work}/trace.gpx", "w") as f:
    f.write('<?xml version="1.0"?><gpx version="1.1" xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>')
    for i, (x, y) in enumerate(pts):
        f.write(f'<trkpt lat="{y}" lon="{x}"><time>2024-05-01T12:{i // 60:02d}:{i % 60:02d}Z</time><hdop>1.2</hdop></trkpt>')
    f.write("</trkseg></trk></gpx>")
for name, stamp in (("untimed", lambda i: ""), ("same-time", lambda i: "<time>2024-05-01T12:00:00Z</time>")):
    with open(f"{work}/{name}.gpx", "w") as f:  # common exports: no timing at all
        f.write('<?xml version="1.0"?><gpx version="1.1" xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>')
        for i, (x, y) in enumerate(pts):
            f.write(f'<trkpt lat="{y}" lon="{x}">{stamp(i)}</trkpt>')
        f.write("</trkseg></trk></gpx>")
PY
for kind in csv gpx; do
  "$corridor" match --trace "$work/trace.$kind" --json --out "$work/out.$kind.geojson" > "$work/match.$kind.json" 2> "$work/err"
  check "$kind: exit 0" "[[ $? -eq 0 ]]"
  check "$kind: the JSON contract" "python3 -c \"
import json; d=json.load(open('$work/match.$kind.json'))
p=d['points']; assert len(p) > 50 and all(k in p[0] for k in ('lat','lon','edge','osm_way_id','name','offset_m','distance_m','matched'))
assert sum(x['matched'] for x in p) == len(p), 'every fix on the route is matched'
assert d['route']['type'] in ('LineString','MultiLineString') and d['points_per_s'] > 0
assert len(d['way_names']) >= 2 and all(a != b for a, b in zip(d['way_names'], d['way_names'][1:])), d['way_names']
\""
  check "$kind: --out is a GeoJSON Feature" "python3 -c \"import json; assert json.load(open('$work/out.$kind.geojson'))['type'] == 'Feature'\""
done

# Without timing: matched by geometry, and the output says so.
for kind in untimed same-time; do
  "$corridor" match --trace "$work/$kind.gpx" --json > "$work/match.$kind.json" 2> "$work/err"
  check "$kind GPX: exit 0" "[[ $? -eq 0 ]]"
  check "$kind GPX: says it had no timing" "grep -q 'no timing' '$work/err'"
  check "$kind GPX: matched by geometry, timing none, no times" "python3 -c \"
import json; d=json.load(open('$work/match.$kind.json')); p=d['points']
assert d['timing'] == 'none', d['timing']
assert sum(x['matched'] for x in p) >= 0.95 * len(p), sum(x['matched'] for x in p)
assert all(x['time_s'] is None for x in p)
assert len(d['way_names']) >= 2
\""
done
check "a timed trace says its timing was measured" "python3 -c \"import json; assert json.load(open('$work/match.gpx.json'))['timing'] == 'measured'\""

# A multipath fix is set aside, flagged, and placed on the road where its neighbours put the vehicle.
"$corridor" match --trace "$work/outlier.csv" --json > "$work/outlier.json" 2> "$work/err"
check "outlier: exit 0" "[[ $? -eq 0 ]]"
check "outlier: flagged and placed on the road" "python3 -c \"
import json; p=json.load(open('$work/outlier.json'))['points']
assert p[30]['outlier'] and p[30]['matched'] and p[30]['distance_m'] > 40, p[30]
assert sum(x['outlier'] for x in p) == 1, [i for i, x in enumerate(p) if x['outlier']]
assert all(x['matched'] for x in p)
\""

expect_error() {  # name, file content, message fragment
  printf '%s' "$2" > "$work/bad"
  "$corridor" match --trace "$work/bad" --json > /dev/null 2> "$work/err"
  local rc=$?
  check "$1: exit 1 (got $rc)" "[[ $rc -eq 1 ]]"
  check "$1: says '$3' ($(head -c 200 "$work/err"))" "grep -qi -- '$3' '$work/err'"
}
expect_error "empty trace" "" "empty"
expect_error "unsorted times" $'time,lat,lon\n5,43.7384,7.4246\n4,43.7385,7.4247\n' "earlier than the one before"
expect_error "NaN" $'time,lat,lon\n0,nan,7.4246\n' "not a finite number"
expect_error "GPX that is not XML" '<gpx><trkpt lat="1" lon="2"><time>x' "not well-formed"
expect_error "GPX with some points timed and some not" \
  '<gpx><trk><trkseg><trkpt lat="43.7384" lon="7.4246"><time>2024-05-01T12:00:00Z</time></trkpt><trkpt lat="43.7385" lon="7.4247"/></trkseg></trk></gpx>' \
  "timed throughout or not at all"
expect_error "a trace entirely off the map" $'time,lat,lon\n0,48.85,2.35\n1,48.8501,2.3501\n' "within reach of a road"
"$corridor" match --trace "$work/nowhere.csv" > /dev/null 2> "$work/err"
check "missing file: exit 1" "[[ $? -eq 1 ]] && grep -q 'not found' '$work/err'"

echo "$passed passed, $failed failed"
((failed == 0))
