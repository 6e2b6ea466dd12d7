#!/usr/bin/env bash
# SUMO scenarios as a user brings them, end to end:
# - lane permissions: on a net whose shortest way is a bus lane and whose next is a bus-only turn,
#   the EV (class emergency) is routed where SUMO lets it drive and arrives; as a bus it takes the
#   bus lane;
# - a configuration that sets options Corridor owns (its own log, tripinfo output) runs under
#   libsumo, with the run's options set once in a configuration derived into the work directory;
# - a matrix whose runs all fail (the scenario's own demand has a route SUMO refuses) keeps every
#   run as a row with status failed and SUMO's reason, and exits 1 unless --keep-going;
# - a net written by a newer netconvert is refused with a pointer to --rebuild-net, and with it is
#   converted into the work directory, the user's files untouched.
# Usage: permissions_and_status_test.sh CORRIDOR_BINARY SOURCE_DIR
set -euo pipefail
corridor=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

user=$work/user
mkdir -p "$user"
data=$src/tests/data/lane_permissions
netconvert -n "$data/permissions.nod.xml" -e "$data/permissions.edg.xml" -x "$data/permissions.con.xml" --no-turnarounds true \
  --no-warnings -o "$user/permissions.net.xml" > /dev/null
cat > "$user/demand.rou.xml" <<'XML'
<routes>
  <vType id="bus" vClass="bus"/>
  <vehicle id="bus0" type="bus" depart="0"><route edges="SA AB BC CG"/></vehicle>
  <vehicle id="car0" depart="5"><route edges="SA AD DC CG"/></vehicle>
</routes>
XML
cat > "$user/scenario.sumocfg" <<'XML'
<configuration>
  <input><net-file value="permissions.net.xml"/><route-files value="demand.rou.xml"/></input>
  <time><begin value="0"/><end value="600"/></time>
  <report><log value="user.log"/><no-step-log value="true"/></report>
  <output><tripinfo-output value="user-trips.xml"/><summary-output value="summary.xml"/></output>
</configuration>
XML
before=$(cd "$user" && find . -type f | sort | xargs sha256sum)

route_length() {  # tripinfo of run directory $1, vehicle $2
  /usr/bin/python3 - "$1" "$2" <<'PY'
import glob, sys, xml.etree.ElementTree as ET
for f in glob.glob(sys.argv[1] + "/runs/*.tripinfo.xml"):
    for t in ET.parse(f).getroot().iter("tripinfo"):
        if t.get("id") == sys.argv[2]:
            print(float(t.get("routeLength")))
PY
}

# The EV as an emergency vehicle, and as a bus, under libsumo (the configuration sets a log).
for cls in emergency bus; do
  if ! "$corridor" sim --scenario "$user/scenario.sumocfg" --work-dir "$work/$cls" --ev-from SA --ev-to CG --ev-depart-s 10 \
      --signals none --routing dynamic --incidents 0 --ev-vclass "$cls" --libsumo > "$work/$cls.json" 2> "$work/$cls.err"; then
    fail "corridor sim as $cls"
    cat "$work/$cls.err"
    continue
  fi
  grep -q '"ev_arrived": true' "$work/$cls.json" || fail "the EV ($cls) did not arrive"
  grep -q '"status": "ok"' "$work/$cls.json" || fail "the $cls run's record is not ok"
done
length_ev=$(route_length "$work/emergency" ev)
length_bus=$(route_length "$work/bus" ev)
echo "route length as emergency ${length_ev:-none} m, as bus ${length_bus:-none} m"
/usr/bin/python3 -c "import sys; sys.exit(0 if float('${length_ev:-0}') > 900 else 1)" ||
  fail "the emergency vehicle's route (${length_ev:-none} m) is not the long way round SA AD DC CG"
/usr/bin/python3 -c "import sys; sys.exit(0 if 0 < float('${length_bus:-0}') < 850 else 1)" ||
  fail "the bus's route (${length_bus:-none} m) is not the bus lane SA AB BC CG"
grep -q '<log value=".*emergency/runs/dynamic_none.sumo.log"' "$work/emergency/runs/dynamic_none.sumocfg" ||
  fail "the derived configuration does not set the run's log"
[[ $(grep -c '<log ' "$work/emergency/runs/dynamic_none.sumocfg") -eq 1 ]] || fail "the derived configuration sets log more than once"
find "$work/emergency" -name '*summary.xml' | grep -q . || fail "the configuration's summary output is not in the work directory"

# Every run fails: a vehicle of the scenario's own demand is routed over the bus lane.
sed 's/<vehicle id="car0" depart="5"><route edges="SA AD DC CG"\/>/<vehicle id="car0" depart="5"><route edges="SA AB BC CG"\/>/' \
  "$user/demand.rou.xml" > "$user/refused.rou.xml"
sed 's/demand.rou.xml/refused.rou.xml/' "$user/scenario.sumocfg" > "$user/refused.sumocfg"
before=$(cd "$user" && find . -type f | sort | xargs sha256sum)
rc=0
"$corridor" experiment sumo --scenario "$user/refused.sumocfg" --routings static --signals none,corridor --seeds 2 \
  --ev-depart-s 10 --end-s 300 --libsumo --out "$work/refused" > "$work/refused.out" 2> "$work/refused.err" || rc=$?
[[ $rc -eq 1 ]] || fail "a matrix with failed runs exited $rc, not 1"
grep -q "did not complete" "$work/refused.err" || fail "the error does not say runs did not complete: $(tail -2 "$work/refused.err")"
runs=$work/refused/sumo_runs.csv
[[ $(($(wc -l < "$runs") - 1)) -eq 4 ]] || fail "sumo_runs.csv holds $(($(wc -l < "$runs") - 1)) rows for 4 runs"
[[ $(grep -c ',failed,' "$runs") -eq 4 ]] || fail "not every failed run has status failed: $(cat "$runs")"
grep -q "car0" "$runs" || fail "the failed rows do not give SUMO's reason: $(tail -1 "$runs")"
grep -q "did not complete" "$work/refused/sumo_summary.md" || fail "the summary does not list the failed runs"
"$corridor" experiment sumo --collect "$work/refused/runs" --out "$work/refused-again" > /dev/null 2>&1 && fail "--collect of failed runs exited 0"
"$corridor" experiment sumo --collect "$work/refused/runs" --out "$work/refused-again" --keep-going > /dev/null 2>&1 ||
  fail "--collect --keep-going exited non-zero"
cmp -s "$runs" "$work/refused-again/sumo_runs.csv" || fail "collecting again gives other rows"

# A net from a newer netconvert.
mkdir -p "$work/newer"
sed 's/<net version="[^"]*"/<net version="1.99"/' "$user/permissions.net.xml" > "$work/newer/permissions.net.xml"
cp "$user/demand.rou.xml" "$user/scenario.sumocfg" "$work/newer/"
newer_before=$(cd "$work/newer" && find . -type f | sort | xargs sha256sum)
rc=0
"$corridor" sim --scenario "$work/newer/scenario.sumocfg" --work-dir "$work/nw" --ev-from SA --ev-to CG --ev-depart-s 10 \
  --incidents 0 > /dev/null 2> "$work/newer.err" || rc=$?
[[ $rc -eq 1 ]] && grep -q -- "--rebuild-net" "$work/newer.err" || fail "a newer net: exit $rc, $(tail -1 "$work/newer.err")"
"$corridor" sim --scenario "$work/newer/scenario.sumocfg" --work-dir "$work/nw" --ev-from SA --ev-to CG --ev-depart-s 10 \
  --incidents 0 --rebuild-net > "$work/newer.json" 2> "$work/newer.err" || fail "--rebuild-net: $(tail -2 "$work/newer.err")"
grep -q "conversion by the installed one" "$work/newer.err" || fail "the run does not say it converted the net"
grep -q '"ev_arrived": true' "$work/newer.json" || fail "the EV did not arrive on the converted net"
[[ -f "$work/nw/permissions.rebuilt.net.xml" ]] || fail "no converted net in the work directory"
[[ "$newer_before" == "$(cd "$work/newer" && find . -type f | sort | xargs sha256sum)" ]] || fail "the user's files changed"
after=$(cd "$user" && find . -type f | sort | xargs sha256sum)
[[ "$before" == "$after" ]] || fail "the user's scenario directory changed"

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "lane permissions, derived configurations, failed-run rows and net conversion: all checks passed"
