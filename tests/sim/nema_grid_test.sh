#!/usr/bin/env bash
# The seed's Fig. 11 set-up: the NEMA grid and traffic injected on the EV's static route. Oracles:
# every light of the net runs a NEMA program (no link ever goes from green to red without 3 s of
# yellow and 2 s of all-red; no two links green together that the junction makes foes, except a
# yielding 'g'; every link green at some point of the cycle); a run with --inject-vph puts the
# injected flow on the EV's route (its vehicles drive exactly the EV's first edges), the EV arrives,
# the lights recover, no safety violation.
# Usage: nema_grid_test.sh CORRIDOR_BINARY
set -euo pipefail
corridor=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}

"$corridor" sim --scenario nema-grid --work-dir "$work/g" --volume 400 --inject-vph 600 --seed 2 --libsumo \
  --signals corridor --routing static --run-name inj > "$work/run.json"
/usr/bin/python3 - "$work" <<'PY'
import glob, json, sys, xml.etree.ElementTree as ET
work = sys.argv[1]
problems = []
net = ET.parse(glob.glob(f"{work}/g/nema_grid*.net.xml")[0]).getroot()
foes, legs = {}, {}
for j in net.iter("junction"):
    if j.get("type") != "traffic_light": continue
    foes[j.get("id")] = [r.get("foes")[::-1] for r in j.iter("request")]  # foes[i][k]: link k is a foe of link i
    legs[j.get("id")] = len({lane.rsplit("_", 1)[0] for lane in j.get("incLanes").split()})
logics = list(net.iter("tlLogic"))
if len(logics) != len(foes): problems.append(f"{len(logics)} programs for {len(foes)} lights: one program per light expected")
for logic in logics:
    tls = logic.get("id")
    phases = [(float(p.get("duration")), p.get("state")) for p in logic.iter("phase")]
    n = len(phases[0][1])
    ever_green = [False] * n
    for i, (dur, st) in enumerate(phases):
        for a in range(n):
            if st[a] in "Gg": ever_green[a] = True
            for b in range(n):
                if a != b and st[a] == "G" and st[b] == "G" and foes[tls][a][b] == "1":
                    problems.append(f"{tls} phase {i}: links {a} and {b} are foes and both G")
        nxt_dur, nxt = phases[(i + 1) % len(phases)]
        for a in range(n):
            if st[a] in "Gg" and nxt[a] == "r": problems.append(f"{tls} phase {i}: link {a} goes green -> red without yellow")
            if st[a] == "y" and (dur < 3 or nxt[a] != "r" or nxt_dur < 2): problems.append(f"{tls} phase {i}: link {a}'s clearance is short")
    if not all(ever_green): problems.append(f"{tls}: links {[a for a in range(n) if not ever_green[a]]} are never green")
    if legs[tls] == 4 and len([p for p in phases if "y" not in p[1] and set(p[1]) != {"r"}]) < 5:
        problems.append(f"{tls}: a four-legged junction with fewer than 5 green steps, not a NEMA 8-phase cycle")
r = json.load(open(f"{work}/run.json"))
if not r["ev_arrived"]: problems.append("the EV did not arrive")
if r["safety_violations"]: problems.append("; ".join(r["safety_violations"][:3]))
if r["lights_taken_over"] < 1 or r["lights_back_on_program"] != r["lights_taken_over"]: problems.append("lights not back on program")
if r["volume"] != 600 or not r["inject_on_route"]: problems.append("the record does not carry the injected volume")
inject = ET.parse(f"{work}/g/runs/inj.inject.rou.xml").getroot()
edges = inject.find("route").get("edges").split()
if edges[0] != r["ev_from"] or edges[-1] != r["ev_to"]: problems.append("the injected route is not the EV's")
trips = [t for t in ET.parse(f"{work}/g/runs/inj.tripinfo.xml").getroot().iter("tripinfo") if t.get("id").startswith("inject")]
if len(trips) < 50: problems.append(f"only {len(trips)} injected vehicles ran (600 veh/h expected)")
print(f"{len(logics)} NEMA programs checked; {len(trips)} injected vehicles; EV {r['ev_travel_time_s']} s")
for p in problems[:20]: print("FAIL", p)
sys.exit(1 if problems else 0)
PY
