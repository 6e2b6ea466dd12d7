#!/usr/bin/env bash
# The SUMO closed loop end to end, on a small grid and on Monaco: the EV arrives, at least one
# preemption starts and is released, every preempted light is back on its program, no collision,
# no safety violation, the same seed gives the same numbers, libsumo agrees with libtraci, and the
# loop also runs through a live `corridor serve` (--server).
# Usage: closed_loop_test.sh CORRIDOR_BINARY SHARED_DATA_DIR
set -euo pipefail
corridor=$1
data=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
failures=0

check() {
  local name=$1 scenario=$2
  shift 2
  "$corridor" sim --scenario "$scenario" --work-dir "$work/$name" --routing dynamic --signals corridor "$@" > "$work/$name.1.json"
  "$corridor" sim --scenario "$scenario" --work-dir "$work/$name" --routing dynamic --signals corridor "$@" > "$work/$name.2.json"
  if ! /usr/bin/python3 - "$work/$name.1.json" "$work/$name.2.json" "$name" <<'PY'
import json, sys
a, b, name = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3]
problems = []
if not a["ev_arrived"]: problems.append("the EV did not arrive")
if a["preemptions_started"] < 1: problems.append("no preemption started")
if a["preemptions_released"] < 1: problems.append("no preemption released")
if a["lights_taken_over"] < 1 or a["lights_back_on_program"] != a["lights_taken_over"]:
    problems.append(f"lights back on program {a['lights_back_on_program']} of {a['lights_taken_over']}")
if a["collisions"] != 0: problems.append(f"{a['collisions']} collisions")
if a["safety_violations"]: problems.append("safety violations: " + "; ".join(a["safety_violations"][:3]))
if a != b: problems.append("two runs with the same seed differ: " + str({k: (a[k], b[k]) for k in a if a[k] != b[k]}))
print(f"{name}: travel {a['ev_travel_time_s']} s, stops {a['ev_stops']}, preempted {a['preempted_signals']}, "
      f"route changes {a['route_changes']}, others' mean time loss {a['others_mean_time_loss_s']:.1f} s")
for p in problems: print(f"FAIL {name}: {p}")
sys.exit(1 if problems else 0)
PY
  then
    failures=$((failures + 1))
  fi
}

check grid grid --volume 400 --seed 3
check monaco "$data/osm/monaco.osm.gz" --volume 400 --seed 2

# libsumo (SUMO in-process) and libtraci (SUMO over a socket) run the same simulation.
"$corridor" sim --scenario grid --work-dir "$work/grid" --routing dynamic --signals corridor --volume 400 --seed 3 \
  --libsumo > "$work/grid.libsumo.json"
if ! cmp -s "$work/grid.1.json" "$work/grid.libsumo.json"; then
  echo "FAIL: libsumo and libtraci runs differ:"
  diff "$work/grid.1.json" "$work/grid.libsumo.json" || true
  failures=$((failures + 1))
fi

# Through a running server (--server): the server plans, replans and preempts; the loop mirrors its
# held lights onto SUMO. SUMO keeps wall-clock pace, so this uses a 3x3 grid and a short trip.
netgenerate --grid --grid.number 3 --grid.length 200 --default.lanenumber 2 --default-junction-type traffic_light \
  --tls.default-type static --no-turnarounds true -o "$work/small.net.xml" > /dev/null 2>&1
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
token=closed-loop-test-token-0123456789
CORRIDOR_DEV_TOKEN=$token "$corridor" serve --map "$work/small.net.xml" --db "$work/server.db" \
  --listen "127.0.0.1:$port" > "$work/serve.log" 2>&1 &
server_pid=$!
trap 'kill $server_pid 2> /dev/null; rm -rf "$work"' EXIT
for _ in $(seq 1 100); do
  curl -sf -H "Authorization: Bearer $token" "http://127.0.0.1:$port/v1/health" > /dev/null && break
  sleep 0.1
done
"$corridor" sim --scenario "$work/small.net.xml" --work-dir "$work/server-run" --volume 300 --seed 1 --ev-depart-s 5 \
  --server "http://127.0.0.1:$port" --token "$token" > "$work/server.json"
if ! /usr/bin/python3 - "$work/server.json" <<'PY'
import json, sys
a = json.load(open(sys.argv[1]))
problems = []
if not a["ev_arrived"]: problems.append("the EV did not arrive")
if a["preempted_signals"] < 1: problems.append("the server held no light")
if a["lights_taken_over"] < 1 or a["lights_back_on_program"] != a["lights_taken_over"]:
    problems.append(f"lights back on program {a['lights_back_on_program']} of {a['lights_taken_over']}")
if a["collisions"] != 0: problems.append(f"{a['collisions']} collisions")
print(f"server: travel {a['ev_travel_time_s']} s, stops {a['ev_stops']}, lights held {a['preempted_signals']}")
for p in problems: print(f"FAIL server: {p}")
sys.exit(1 if problems else 0)
PY
then
  failures=$((failures + 1))
fi
# Noisy GPS with an outage: the loop posts noisy fixes, HDOP over 10 in the outage, and the EV's
# onboard odometry as source "vo" meanwhile; the server's matcher keeps the mission on track.
"$corridor" sim --scenario "$work/small.net.xml" --work-dir "$work/server-run" --volume 300 --seed 2 --ev-depart-s 5 \
  --server "http://127.0.0.1:$port" --token "$token" --gps-noise-m 5 --gps-outage 5:20 > "$work/noisy.json"
if ! /usr/bin/python3 - "$work/noisy.json" "$work/server.db" <<'PY'
import json, sqlite3, sys
a = json.load(open(sys.argv[1]))
db = sqlite3.connect(sys.argv[2])
counts = dict(((s, d), n) for s, d, n in db.execute(
    "SELECT source, disposition, COUNT(*) FROM positions WHERE vehicle_id='ev-dynamic_corridor' GROUP BY 1, 2"))
states = [s for (s,) in db.execute("SELECT state FROM missions ORDER BY id")]
problems = []
if not a["ev_arrived"]: problems.append("the EV did not arrive with noisy GPS")
if counts.get(("vo", "followed"), 0) < 5: problems.append(f"too few odometry positions followed: {counts}")
if counts.get(("gps", "low_accuracy"), 0) < 5: problems.append(f"the outage's fixes were not flagged: {counts}")
if states[-1] != "completed": problems.append(f"the noisy mission ended {states[-1]}")
if a["lights_back_on_program"] != a["lights_taken_over"]: problems.append("a light was not restored")
print(f"noisy: travel {a['ev_travel_time_s']} s, positions {counts}")
for p in problems: print(f"FAIL noisy GPS: {p}")
sys.exit(1 if problems else 0)
PY
then
  failures=$((failures + 1))
fi
# GPS options need a server.
if "$corridor" sim --scenario grid --work-dir "$work/x" --gps-noise-m 5 > /dev/null 2> "$work/gps.txt" || ! grep -q "give --server" "$work/gps.txt"; then
  echo "FAIL: --gps-noise-m without --server was not refused: $(cat "$work/gps.txt")"
  failures=$((failures + 1))
fi
# A server on another map is refused with a clear message.
set +e
"$corridor" sim --scenario grid --work-dir "$work/wrong" --server "http://127.0.0.1:$port" --token "$token" \
  > /dev/null 2> "$work/wrong.txt"
rc=$?
set -e
if [[ $rc == 0 ]] || ! grep -q "is not this SUMO network" "$work/wrong.txt"; then
  echo "FAIL: a server on another map was not refused: $(cat "$work/wrong.txt")"
  failures=$((failures + 1))
fi

# A SUMO that cannot start gives a clear error, not a hang.
set +e
"$corridor" sim --scenario "$work/missing.net.xml" --work-dir "$work/x" > /dev/null 2> "$work/err.txt"
rc=$?
set -e
if [[ $rc == 0 ]] || ! grep -q "does not exist" "$work/err.txt"; then
  echo "FAIL: a missing scenario file was not reported: $(cat "$work/err.txt")"
  failures=$((failures + 1))
fi

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "closed loop: all checks passed"
