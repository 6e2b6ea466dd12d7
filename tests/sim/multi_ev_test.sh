#!/usr/bin/env bash
# Several EVs in one SUMO run (`corridor sim --evs 3`): the second and third cross the first's
# lights from other approaches at the same predicted time, so their claims conflict and the engine
# arbitrates by priority. Oracles: every EV arrives; the first (highest priority) is never
# deferred and the others are deferred at least once over the seeds; no safety violation, no
# collision, and every light taken over is back on its program; the time–space record is written,
# each EV's distance never decreases and each signal's distance lies on its trajectory.
# Usage: multi_ev_test.sh CORRIDOR_BINARY
set -euo pipefail
corridor=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}

for seed in 1 5; do
  "$corridor" sim --scenario grid --work-dir "$work/grid" --volume 1200 --seed "$seed" --incidents 0 --libsumo \
    --signals corridor --evs 3 --time-space --run-name "s$seed" > "$work/s$seed.json"
done
/usr/bin/python3 - "$work" <<'PY'
import csv, json, sys
work = sys.argv[1]
problems = []
deferred_lower = 0
for seed in (1, 5):
    r = json.load(open(f"{work}/s{seed}.json"))
    evs = r["evs"]
    if len(evs) != 3: problems.append(f"seed {seed}: {len(evs)} EVs reported, 3 expected")
    prios = [e["trip"]["priority"] for e in evs]
    if prios != sorted(prios, reverse=True) or len(set(prios)) != len(prios):
        problems.append(f"seed {seed}: priorities {prios} do not fall with the EV's index")
    for e in evs:
        if not e["arrived"]: problems.append(f"seed {seed}: {e['id']} did not arrive")
        if e["preempted_signals"] < 1: problems.append(f"seed {seed}: no light preempted for {e['id']}")
    if evs[0]["deferrals"] != 0: problems.append(f"seed {seed}: the highest-priority EV was deferred")
    deferred_lower += sum(e["deferrals"] for e in evs[1:])
    if r["deferrals"] != sum(e["deferrals"] for e in evs): problems.append(f"seed {seed}: deferrals do not add up")
    if r["safety_violations"]: problems.append(f"seed {seed}: " + "; ".join(r["safety_violations"][:3]))
    if r["collisions"]: problems.append(f"seed {seed}: {r['collisions']} collisions")
    if r["lights_taken_over"] < 1 or r["lights_back_on_program"] != r["lights_taken_over"]:
        problems.append(f"seed {seed}: lights back {r['lights_back_on_program']} of {r['lights_taken_over']}")
    if r["ev_travel_time_s"] != evs[0]["travel_time_s"]: problems.append(f"seed {seed}: ev_travel_time_s is not the first EV's")
    track = {}
    for row in csv.DictReader(open(f"{work}/grid/runs/s{seed}.ev_trajectory.csv")):
        track.setdefault(row["ev"], []).append((float(row["t_s"]), float(row["distance_m"])))
    if sorted(track) != sorted(e["id"] for e in evs): problems.append(f"seed {seed}: trajectories of {sorted(track)}")
    for ev, pts in track.items():
        if any(b[1] < a[1] - 1e-6 for a, b in zip(pts, pts[1:])): problems.append(f"seed {seed}: {ev}'s distance decreases")
    for row in csv.DictReader(open(f"{work}/grid/runs/s{seed}.ev_signals.csv")):
        pts = track.get(row["ev"], [])
        if pts and not (0.0 <= float(row["distance_m"]) <= pts[-1][1] + 1.0):
            problems.append(f"seed {seed}: signal {row['tls']} at {row['distance_m']} m is off {row['ev']}'s path")
            break
    svg = open(f"{work}/grid/runs/s{seed}.time_space.svg").read()
    if svg.count("<polyline") != 3: problems.append(f"seed {seed}: the time-space diagram has {svg.count('<polyline')} tracks")
    print(f"seed {seed}: " + ", ".join(f"{e['id']} {e['travel_time_s']:.0f} s deferred {e['deferrals']}" for e in evs))
if deferred_lower < 1: problems.append("no lower-priority EV was ever deferred: the claims did not conflict")
for p in problems: print("FAIL", p)
sys.exit(1 if problems else 0)
PY
