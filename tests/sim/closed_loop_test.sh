#!/usr/bin/env bash
# The SUMO closed loop end to end, on a small grid and on Monaco: the EV arrives, at least one
# preemption starts and is released, every preempted light is back on its program, no collision,
# no safety violation, the same seed gives the same numbers, and libsumo agrees with libtraci.
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
