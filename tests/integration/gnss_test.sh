#!/usr/bin/env bash
# GPS from receivers through gpsd, on NMEA written from a SUMO drive on Monaco (noise, an outage, a
# stretch where the receiver reports speed but no fix, garbage lines, bad checksums):
# - corridor localize --nmea decodes the log through gpsd: fixes without a 2D/3D mode are refused
#   and counted, bad checksums are dropped, the positions follow the drive's truth;
# - corridor localize --gpsd reads gpsfake's replay of the same log through libgps and posts each
#   position to a corridor serve, which takes them;
# - a receiver that goes away mid-drive ends the run with what it had, saying so;
# - a file that is not NMEA, and a gpsd that is not there, are clear errors.
# Usage: gnss_test.sh CORRIDOR_BINARY SOURCE_DIR
set -uo pipefail
corridor=$1
src=$2
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2> /dev/null; done
  pkill -f "gpsfake.*$work" 2> /dev/null
  rm -rf "$work"
}
trap cleanup EXIT
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
export CORRIDOR_CACHE_DIR=$work/cache
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

# A SUMO drive on Monaco, and what its receiver would have logged.
/usr/bin/python3 "$src/scripts/sumo_fcd_drives.py" --osm "$src/maps/data/monaco.osm.gz" --out "$work/fcd" --drives 2 \
  > "$work/fcd.log" 2>&1 || { fail "sumo_fcd_drives"; tail "$work/fcd.log"; exit 1; }
vehicle=$(/usr/bin/python3 -c "import json; print(json.load(open('$work/fcd/drives.json'))['drives'][0]['id'])")
/usr/bin/python3 "$src/scripts/fcd_to_nmea.py" --fcd "$work/fcd/fcd.xml" --vehicle "$vehicle" --out "$work/drive.nmea" \
  --truth "$work/truth.csv" --noise-m 3 --outage 100:130 --speed-without-fix 150:160 --garbage 0.05 --bad-checksums 0.03 \
  > "$work/nmea.txt" || { fail "fcd_to_nmea"; exit 1; }
echo "NMEA log: $(cat "$work/nmea.txt")"

# Scores positions (JSON array or {"points": [...]}) against the truth: the share within 15 m.
score() {
  /usr/bin/python3 - "$1" "$work/truth.csv" << 'PY'
import csv, json, math, sys
d = json.load(open(sys.argv[1]))
pts = d["points"] if isinstance(d, dict) else d
truth = [(float(r["time"]), float(r["lat"]), float(r["lon"])) for r in csv.DictReader(open(sys.argv[2]))]
def near(t):
    return min(truth, key=lambda r: abs(r[0] - t))
good = 0
for p in pts:
    _, la, lo = near(p["time_s"])
    dy = (p["lat"] - la) * 111195.0
    dx = (p["lon"] - lo) * 111195.0 * math.cos(math.radians(la))
    good += math.hypot(dx, dy) <= 15.0
print(f"{good / max(1, len(pts)):.3f} {len(pts)}")
PY
}

# 1. The recorded log, decoded by a private gpsd.
"$corridor" localize --nmea "$work/drive.nmea" --json > "$work/nmea.json" 2> "$work/nmea.err" || { fail "localize --nmea"; cat "$work/nmea.err"; }
/usr/bin/python3 - "$work/nmea.json" "$work/nmea.txt" << 'PY' || failures=$((failures + 1))
import json, sys
d = json.load(open(sys.argv[1]))["summary"]
made = dict(kv.split("=") for kv in open(sys.argv[2]).read().split())
r = d["receiver"]
problems = []
# Every epoch with a fix whose RMC arrived intact becomes one; none without a 2D/3D mode does.
if not (0.8 * int(made["fixes"]) <= r["fixes"] <= int(made["fixes"])):
    problems.append(f"{r['fixes']} fixes from {made['fixes']} epochs with a fix")
refused = r["refused"].get("no 2D/3D fix", 0)
if refused < 0.8 * (int(made["outage"]) + int(made["speed_without_fix"])):
    problems.append(f"only {refused} reports refused for no fix, of {made['outage']} + {made['speed_without_fix']} without one")
if r.get("bad_checksums", 0) != int(made["bad_checksums"]):
    problems.append(f"{r.get('bad_checksums')} bad checksums found, {made['bad_checksums']} written")
print(f"--nmea: {r['fixes']} fixes, refused {r['refused']}, bad checksums {r.get('bad_checksums', 0)}")
for p in problems: print("FAIL --nmea:", p)
sys.exit(1 if problems else 0)
PY
read -r share n <<< "$(score "$work/nmea.json")"
echo "--nmea: $n positions, $share within 15 m of the truth"
/usr/bin/python3 -c "import sys; sys.exit(0 if $share >= 0.8 else 1)" || fail "--nmea: only $share of the positions within 15 m of the truth"

# 2. A live receiver: gpsfake replays the log to a gpsd, localize reads it and feeds a server.
export CORRIDOR_DEV_TOKEN=gnss-test-token-0123456789
http=$(free_port)
"$corridor" serve --db "$work/c.db" --listen "127.0.0.1:$http" > "$work/serve.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do curl -sf "127.0.0.1:$http/v1/health" > /dev/null && break; sleep 0.2; done
gport=$(free_port)
gpsfake -1 -p -q -c 0.02 -P "$gport" "$work/drive.nmea" > /dev/null 2> "$work/gpsfake.err" &
fake=$!
pids+=($fake)
for _ in $(seq 50); do (echo > "/dev/tcp/127.0.0.1/$gport") 2> /dev/null && break; sleep 0.2; done
"$corridor" localize --gpsd "127.0.0.1:$gport" --gpsd-idle-s 3 --json --out "$work/live.json" --server "http://127.0.0.1:$http" \
  --vehicle "gps unit 1" --token "$CORRIDOR_DEV_TOKEN" > "$work/live.out" 2> "$work/live.err" || { fail "localize --gpsd"; tail "$work/live.err"; }
wait "$fake" 2> /dev/null
summary=$(tail -1 "$work/live.out")
echo "--gpsd: $summary"
/usr/bin/python3 - "$summary" "$work/nmea.txt" << 'PY' || failures=$((failures + 1))
import json, sys
s = json.loads(sys.argv[1])["summary"]
made = dict(kv.split("=") for kv in open(sys.argv[2]).read().split())
problems = []
if s["receiver"]["fixes"] < 0.8 * int(made["fixes"]): problems.append(f"{s['receiver']['fixes']} fixes of {made['fixes']}")
if s["receiver"]["refused"].get("no 2D/3D fix", 0) < int(made["outage"]) // 2: problems.append(f"no-fix reports not refused: {s['receiver']}")
if s.get("posted_gps", 0) < 0.8 * int(made["fixes"]): problems.append(f"only {s.get('posted_gps')} positions posted")
for p in problems: print("FAIL --gpsd:", p)
sys.exit(1 if problems else 0)
PY
read -r share n <<< "$(score "$work/live.json")"
echo "--gpsd: $n positions, $share within 15 m of the truth"
/usr/bin/python3 -c "import sys; sys.exit(0 if $share >= 0.8 else 1)" || fail "--gpsd: only $share within 15 m of the truth"
curl -s "127.0.0.1:$http/v1/vehicles" -H "Authorization: Bearer $CORRIDOR_DEV_TOKEN" | grep -q '"gps unit 1"' ||
  fail "the server has no position of the receiver's vehicle"

# 3. The receiver goes away mid-drive: the run ends with what it had, and says why.
gport=$(free_port)
gpsfake -p -q -c 0.05 -P "$gport" "$work/drive.nmea" > /dev/null 2>&1 &
fake=$!
for _ in $(seq 50); do (echo > "/dev/tcp/127.0.0.1/$gport") 2> /dev/null && break; sleep 0.2; done
( sleep 8; kill "$fake" ) &
start=$(date +%s)
"$corridor" localize --gpsd "127.0.0.1:$gport" --gpsd-idle-s 3 > "$work/lost.out" 2> "$work/lost.err"
rc=$?
took=$(( $(date +%s) - start ))
echo "receiver gone: exit $rc after ${took} s; $(tr -d '\n ' < "$work/lost.out" | head -c 300)"
[[ $rc -eq 0 ]] || fail "localize exited $rc when the receiver went away"
grep -q '"ended": "\(disconnected\|idle\)"' "$work/lost.out" || fail "the summary does not say the receiver's stream ended"
((took < 30)) || fail "localize took ${took} s to notice the receiver was gone"

# 4. Bad input.
cp "$src/tests/data/lane_permissions/permissions.nod.xml" "$work/not.nmea"
"$corridor" localize --nmea "$work/not.nmea" > /dev/null 2> "$work/bad.err"
rc=$?
[[ $rc -eq 2 ]] && grep -q "holds no NMEA sentence" "$work/bad.err" || fail "a file that is not NMEA: exit $rc, $(cat "$work/bad.err")"
: > "$work/empty.nmea"
"$corridor" localize --nmea "$work/empty.nmea" > /dev/null 2> "$work/bad.err"
[[ $? -eq 2 ]] || fail "an empty NMEA log: $(cat "$work/bad.err")"
"$corridor" localize --gpsd "127.0.0.1:$(free_port)" > /dev/null 2> "$work/bad.err"
rc=$?
[[ $rc -ne 0 ]] && grep -q "cannot connect to gpsd" "$work/bad.err" || fail "no gpsd: exit $rc, $(cat "$work/bad.err")"
"$corridor" localize --gpsd "127.0.0.1" > /dev/null 2> "$work/bad.err"
[[ $? -eq 2 ]] || fail "--gpsd without a port: $(cat "$work/bad.err")"

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "gpsd and NMEA: all checks passed"
