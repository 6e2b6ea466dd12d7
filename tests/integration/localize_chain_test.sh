#!/usr/bin/env bash
# The localizer's whole chain: a synthetic stereo drive along a real route of the embedded map
# (`corridor vo synth`), GPS simulated from its truth with a 60 s outage, and `corridor localize
# --server` fusing GPS and the stereo odometry and feeding a live `corridor serve` that has an
# active mission for the vehicle. The mission must keep advancing through the outage on source
# "vo" positions and complete at the destination.
# Usage: localize_chain_test.sh CORRIDOR_BINARY
set -uo pipefail
corridor=$1
work=$(mktemp -d)
export CORRIDOR_CACHE_DIR=$work/cache
export CORRIDOR_DEV_TOKEN=localize-dev-token-0123456789ab
TOKEN=$CORRIDOR_DEV_TOKEN
passed=0
failed=0
server_pid=""
cleanup() {
  [[ -n $server_pid ]] && kill "$server_pid" 2> /dev/null
  rm -rf "$work"
}
trap cleanup EXIT
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL: $*" >&2; failed=$((failed + 1)); }
check() { if eval "$2"; then pass; else fail "$1"; fi; }

# 1. The drive: 1 km with real turns, 10 frames a second.
"$corridor" vo synth --out "$work/drive" --length-m 1000 --seed 7 > "$work/synth.json" 2> "$work/synth.err" ||
  { echo "vo synth failed: $(tail -3 "$work/synth.err")" >&2; exit 1; }

# 2. Where it starts and ends, as the localizer puts them (no server yet).
"$corridor" localize --seq "$work/drive" --truth "$work/drive/drive.csv" --gps-outage 30:60 --json > "$work/offline.json" 2> "$work/offline.err" ||
  { echo "localize failed: $(tail -3 "$work/offline.err")" >&2; exit 1; }
read -r lat0 lon0 lat1 lon1 outage_share <<< "$(python3 -c "
import json; d=json.load(open('$work/offline.json')); p=d['points']
print(p[0]['lat'], p[0]['lon'], p[-1]['lat'], p[-1]['lon'], d['summary']['outage_correct_edge_share'])")"
check "offline: the odometry kept the road through most of the outage ($outage_share)" "python3 -c 'import sys; sys.exit(0 if $outage_share >= 0.6 else 1)'"

# 3. A live server with a mission for amb-1 from the drive's start to its end.
"$corridor" serve --db "$work/corridor.db" --listen 127.0.0.1:0 > "$work/serve.out" 2> "$work/serve.err" &
server_pid=$!
for _ in $(seq 1 100); do
  port=$(grep -o '127.0.0.1:[0-9]*' "$work/serve.out" 2> /dev/null | head -1 | cut -d: -f2)
  [[ -n $port ]] && break
  sleep 0.1
done
[[ -n ${port:-} ]] || { echo "server did not start: $(cat "$work/serve.err")" >&2; exit 1; }
url=http://127.0.0.1:$port
mission=$(curl -s -X POST "$url/v1/missions" -H "Authorization: Bearer $TOKEN" \
  -d "{\"vehicle_id\":\"amb-1\",\"origin\":{\"lat\":$lat0,\"lon\":$lon0},\"destination\":{\"lat\":$lat1,\"lon\":$lon1},\"priority\":2}" |
  python3 -c "import json,sys; print(json.load(sys.stdin)['id'])")
check "mission created" "[[ -n '$mission' ]]"

# 4. The localizer feeds it, ten times faster than the drive.
"$corridor" localize --seq "$work/drive" --truth "$work/drive/drive.csv" --gps-outage 30:60 \
  --server "$url" --vehicle amb-1 --token "$TOKEN" --speedup 10 > "$work/live.json" 2> "$work/live.err"
check "localize --server ran" "[[ $? -eq 0 ]]"
read -r posted_gps posted_vo completed <<< "$(python3 -c "
import json; d=json.load(open('$work/live.json')); print(d['posted_gps'], d['posted_vo'], d['mission_completed'])" 2> /dev/null)"
check "GPS positions were posted ($posted_gps)" "[[ ${posted_gps:-0} -gt 10 ]]"
check "odometry positions were posted through the outage ($posted_vo)" "[[ ${posted_vo:-0} -ge 40 ]]"
check "the mission completed at the destination" "[[ '$completed' == 'True' ]]"
state=$(curl -s "$url/v1/missions/$mission" -H "Authorization: Bearer $TOKEN" | python3 -c "import json,sys; print(json.load(sys.stdin)['state'])")
check "mission state is completed ($state)" "[[ '$state' == completed ]]"

# 5. The server followed the odometry: source "vo" positions stored against the mission, every one
#    followed (each moved the mission's D* Lite start). The drive may pass its own end point before
#    it finishes, which completes the mission there; later positions belong to no mission.
kill "$server_pid"; wait "$server_pid" 2> /dev/null; server_pid=""
read -r vo_with_mission vo_followed <<< "$(python3 - "$work/corridor.db" "$mission" << 'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
q = "SELECT COUNT(*), SUM(disposition='followed') FROM positions WHERE mission_id=? AND source='vo'"
n, followed = db.execute(q, (int(sys.argv[2]),)).fetchone()
print(n, followed or 0)
PY
)"
check "source vo positions were stored for the mission ($vo_with_mission)" "[[ ${vo_with_mission:-0} -ge 20 ]]"
check "every one of them was followed ($vo_followed of $vo_with_mission)" "[[ '${vo_followed:-0}' == '${vo_with_mission:-x}' ]]"

echo "$passed passed, $failed failed"
((failed == 0))
