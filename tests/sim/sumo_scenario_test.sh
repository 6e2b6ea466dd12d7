#!/usr/bin/env bash
# A user's own SUMO scenario (.sumocfg), end to end:
# - bad scenarios (missing file, missing route file, a net newer than SUMO) exit 1 with the reason;
# - a copy of cologne8 with several route files, a detector additional and a traffic-light program
#   of its own runs unchanged: the EV (corridor+bluelight) arrives, lights are back on program, no
#   collision or safety violation, and every output lands in the work directory, none beside the
#   user's files;
# - the matrix emitted as command lines, run by GNU parallel and collected, gives the same tables
#   as the same matrix run in-process.
# Usage: sumo_scenario_test.sh CORRIDOR_BINARY SHARED_DATA_DIR
set -euo pipefail
corridor=$1
data=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

expect_exit_1() {
  local what=$1 needle=$2
  shift 2
  local rc=0
  "$@" > "$work/out.txt" 2> "$work/err.txt" || rc=$?
  if [[ $rc -ne 1 ]]; then fail "$what: exit $rc, expected 1"; cat "$work/err.txt"; return; fi
  grep -q -- "$needle" "$work/err.txt" || { fail "$what: the error does not say '$needle':"; cat "$work/err.txt"; }
}

# The user's scenario: cologne8's net and demand, a second route file, a detector file that writes
# its own output, and a traffic-light program of the user's (the net's first one, renamed).
user=$work/user
mkdir -p "$user/net" "$user/demand"
cp "$data/sumo/cologne8/cologne8.net.xml" "$user/net/"
cp "$data/sumo/cologne8/cologne8.rou.xml" "$user/demand/"
cat > "$user/demand/extra.rou.xml" <<'XML'
<routes>
  <trip id="extra_0" depart="25300" from="-23283579#1" to="23283436"/>
  <trip id="extra_1" depart="25310" from="-28675510#11" to="28675510#7"/>
</routes>
XML
/usr/bin/python3 - "$user/net/cologne8.net.xml" "$user/programs.add.xml" <<'PY'
import re, sys
net = open(sys.argv[1]).read()
logic = re.search(r'<tlLogic .*?</tlLogic>', net, re.S).group(0)
logic = re.sub(r'programID="[^"]*"', 'programID="user"', logic, count=1)
open(sys.argv[2], "w").write("<additional>\n" + logic + "\n</additional>\n")
PY
lane=$(grep -o '<lane id="[^":]*_0"' "$user/net/cologne8.net.xml" | head -1 | sed 's/<lane id="//; s/"//')
# An induction loop, and lane-area (e2) detectors on the approach lanes of the net's first traffic
# light: their jam lengths become the queue estimate there.
/usr/bin/python3 - "$user/net/cologne8.net.xml" "$lane" > "$user/detectors.add.xml" <<'PY'
import sys, xml.etree.ElementTree as ET
net = ET.parse(sys.argv[1]).getroot()
length = {l.get("id"): float(l.get("length")) for e in net.iter("edge") for l in e.iter("lane")}
tls = next(j for j in net.iter("junction") if j.get("type") == "traffic_light")
print("<additional>")
print(f'  <inductionLoop id="d0" lane="{sys.argv[2]}" pos="1" period="60" file="detector_out.xml"/>')
for i, lane in enumerate(l for l in tls.get("incLanes").split() if not l.startswith(":")):
    print(f'  <laneAreaDetector id="e2_{i}" lane="{lane}" pos="0" length="{length[lane] - 0.5:.2f}" friendlyPos="true" '
          f'period="60" file="e2_out.xml"/>')
print("</additional>")
PY
cat > "$user/scenario.sumocfg" <<'XML'
<configuration>
  <input>
    <net-file value="net/cologne8.net.xml"/>
    <route-files value="demand/cologne8.rou.xml,demand/extra.rou.xml"/>
    <additional-files value="programs.add.xml, detectors.add.xml"/>
  </input>
  <time><begin value="7:00:00"/><end value="25800"/></time>
  <output><summary-output value="summary.xml"/></output>
</configuration>
XML
before=$(cd "$user" && find . -type f | sort | xargs sha256sum)

# Bad scenarios.
expect_exit_1 "missing scenario" "does not exist" "$corridor" sim --scenario "$work/none.sumocfg" --work-dir "$work/bad"
sed 's|demand/extra.rou.xml|demand/gone.rou.xml|' "$user/scenario.sumocfg" > "$user/../missing-route.sumocfg"
sed -i 's|value="net/|value="user/net/|; s|value="demand/|value="user/demand/|g; s|value="programs|value="user/programs|; s|detectors.add|user/detectors.add|' \
  "$work/missing-route.sumocfg"
expect_exit_1 "missing route file" "gone.rou.xml" "$corridor" sim --scenario "$work/missing-route.sumocfg" --work-dir "$work/bad"
mkdir -p "$work/newer"
sed 's/<net version="1.9"/<net version="1.99"/' "$user/net/cologne8.net.xml" > "$work/newer/cologne8.net.xml"
printf '<configuration><net-file value="cologne8.net.xml"/></configuration>\n' > "$work/newer/newer.sumocfg"
expect_exit_1 "net newer than SUMO" "newer than the installed SUMO" "$corridor" sim --scenario "$work/newer/newer.sumocfg" \
  --work-dir "$work/bad"
expect_exit_1 "experiment on a missing scenario" "does not exist" "$corridor" experiment sumo --scenario "$work/none.sumocfg" \
  --out "$work/bad-exp" --seeds 1

# One run of the user's scenario.
"$corridor" sim --scenario "$user/scenario.sumocfg" --work-dir "$work/run" --signals corridor+bluelight --seed 2 \
  --ev-depart-s 120 --libsumo > "$work/run.json" 2> "$work/run.err" || { fail "corridor sim on the user's scenario"; cat "$work/run.err"; }
/usr/bin/python3 - "$work/run.json" <<'PY' || failures=$((failures + 1))
import json, sys
a = json.load(open(sys.argv[1]))
problems = []
if not a["ev_arrived"]: problems.append("the EV did not arrive")
if a["preemptions_started"] < 1: problems.append("no preemption started")
if a["lights_taken_over"] < 1 or a["lights_back_on_program"] != a["lights_taken_over"]:
    problems.append(f"lights back on program {a['lights_back_on_program']} of {a['lights_taken_over']}")
if a["collisions"] != 0: problems.append(f"{a['collisions']} collisions")
if a["safety_violations"]: problems.append("safety violations: " + "; ".join(a["safety_violations"][:3]))
if a["ev_depart_s"] != 25320: problems.append(f"the EV departed at {a['ev_depart_s']}, not begin + 120 = 25320")
if a["others"] < 200: problems.append(f"only {a['others']} other vehicles: the scenario's demand did not run")
if a["approaches_with_detectors"] < 1: problems.append("no approach took its queue from the user's e2 detectors")
print(f"user scenario: travel {a['ev_travel_time_s']} s, preempted {a['preempted_signals']}, others {a['others']}, "
      f"approaches on e2 detectors {a['approaches_with_detectors']}")
for p in problems: print("FAIL user scenario:", p)
sys.exit(1 if problems else 0)
PY
after=$(cd "$user" && find . -type f | sort | xargs sha256sum)
[[ "$before" == "$after" ]] || fail "the user's scenario directory changed: $(diff <(echo "$before") <(echo "$after") | head -5)"
grep -q 'id="extra_1"' "$work"/run/runs/*.tripinfo.xml || fail "the second route file's trips did not run"
find "$work/run" -name '*detector_out.xml' | grep -q . || fail "the detector output is not in the work directory"
find "$work/run" -name '*summary.xml' | grep -q . || fail "the configuration's summary output is not in the work directory"

# The same matrix, in-process and as emitted jobs run by GNU parallel.
matrix=(--scenario "$user/scenario.sumocfg" --demand-scale 1 --seeds 2 --routings dynamic --signals none,corridor
        --ev-depart-s 120 --libsumo)
"$corridor" experiment sumo "${matrix[@]}" --out "$work/inproc" > /dev/null 2> "$work/inproc.err" ||
  { fail "experiment sumo in-process"; tail "$work/inproc.err"; }
"$corridor" experiment sumo "${matrix[@]}" --out "$work/jobs" --emit-jobs "$work/jobs.txt" > /dev/null
[[ $(wc -l < "$work/jobs.txt") -eq 6 ]] || fail "expected 6 job lines (2 seeds x (baseline + 2 strategies)), got $(wc -l < "$work/jobs.txt")"
(cd / && parallel -j2 --halt now,fail=1 < "$work/jobs.txt") || fail "a job line failed under GNU parallel"
"$corridor" experiment sumo --collect "$work/jobs/runs" --out "$work/jobs" > /dev/null || fail "--collect"
if ! cmp -s "$work/inproc/sumo_runs.csv" "$work/jobs/sumo_runs.csv"; then
  fail "emitted and in-process runs differ:"
  diff "$work/inproc/sumo_runs.csv" "$work/jobs/sumo_runs.csv" | head -10
fi
cmp -s "$work/inproc/sumo_summary.csv" "$work/jobs/sumo_summary.csv" || fail "the summaries differ"
[[ $(wc -l < "$work/jobs/sumo_runs.csv") -eq 5 ]] || fail "sumo_runs.csv should hold 4 runs"
mkdir -p "$work/empty"
expect_exit_1 "collect from an empty directory" "no run records" "$corridor" experiment sumo --collect "$work/empty" --out "$work/c"

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "user scenario, bad scenarios and the emit/collect round trip: all checks passed"
