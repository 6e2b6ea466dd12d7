#!/usr/bin/env bash
# The closed loop through a live server two ways, on the same seeds: the in-process mirror (the
# server's held lights copied onto SUMO's) and NTCIP (SUMO's lights behind virtual NTCIP 1202
# controllers that the server drives over SNMP). Prints one line per run, the medians per mode,
# and the SNMP round trips the server measured. SUMO keeps wall-clock pace, so each run takes
# about as long as the EV's trip plus --ev-depart-s.
#
# Usage: scripts/ntcip_loop.sh SCENARIO [SEEDS] [EV_DEPART_S]
#   SCENARIO: grid, or a SUMO .sumocfg / .net.xml
#   SEEDS: e.g. "1 2 3" (default)   EV_DEPART_S: default 60
# Environment: CORRIDOR (default build/app/corridor), WORK (default a temporary directory).
set -euo pipefail
cd "$(dirname "$0")/.."
corridor=${CORRIDOR:-build/app/corridor}
scenario=${1:?usage: scripts/ntcip_loop.sh SCENARIO [SEEDS] [EV_DEPART_S]}
seeds=${2:-1 2 3}
depart=${3:-60}
work=${WORK:-$(mktemp -d)}
mkdir -p "$work"
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
token=ntcip-loop-token-0123456789abcdef
server_pid=""
cleanup() { [[ -n $server_pid ]] && kill "$server_pid" 2> /dev/null || true; }
trap cleanup EXIT

# The server's map is the scenario's own .net.xml: for grid, the net a first run writes.
case $scenario in
  grid)
    "$corridor" sim --scenario grid --work-dir "$work/net" --no-ev --ev-depart-s 1 --end-s 5 > /dev/null
    net=$(ls "$work"/net/*.net.xml | head -1)
    ;;
  *.sumocfg)
    net=$(/usr/bin/python3 -c 'import sys, os, xml.etree.ElementTree as E
c = sys.argv[1]; n = E.parse(c).getroot().find("input/net-file").get("value")
print(os.path.join(os.path.dirname(os.path.abspath(c)), n))' "$scenario")
    ;;
  *) net=$scenario ;;
esac
echo "scenario $scenario, net $net, seeds $seeds, EV departs at $depart s; work $work"

free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

start_server() {  # start_server DB [--controllers FILE]
  local db=$1
  shift
  port=$(free_port)
  CORRIDOR_DEV_TOKEN=$token "$corridor" serve --map "$net" --db "$db" --listen "127.0.0.1:$port" "$@" > "$db.log" 2>&1 &
  server_pid=$!
  for _ in $(seq 1 300); do
    curl -sf -H "Authorization: Bearer $token" "http://127.0.0.1:$port/v1/health" > /dev/null && return 0
    sleep 0.2
  done
  echo "the server did not start: $(tail -3 "$db.log")" >&2
  exit 1
}

results=()
for mode in mirror ntcip; do
  for seed in $seeds; do
    run="$work/$mode-$seed"
    mkdir -p "$run"
    extra=()
    if [[ $mode == ntcip ]]; then
      agent_port=$((17000 + seed * 200))
      "$corridor" signal-agent --map "$net" --listen "127.0.0.1:$agent_port" --manifest "$run/agents.json" --manifest-only > /dev/null
      start_server "$run/server.db" --controllers "$run/agents.json"
      extra=(--ntcip --ntcip-listen "127.0.0.1:$agent_port")
    else
      start_server "$run/server.db"
    fi
    "$corridor" sim --scenario "$scenario" --work-dir "$run/sim" --seed "$seed" --ev-depart-s "$depart" \
      --server "http://127.0.0.1:$port" --token "$token" "${extra[@]}" > "$run/result.json" 2> "$run/sim.log" || {
      echo "$mode seed $seed: the run failed: $(tail -3 "$run/sim.log")" >&2
    }
    curl -sf -H "Authorization: Bearer $token" "http://127.0.0.1:$port/v1/signals" > "$run/signals.json" || echo '{}' > "$run/signals.json"
    kill "$server_pid"
    wait "$server_pid" 2> /dev/null || true
    server_pid=""
    results+=("$mode:$seed:$run")
  done
done

/usr/bin/python3 - "${results[@]}" <<'PY'
import json, statistics, sys
rows = {}
rtts = []
for arg in sys.argv[1:]:
    mode, seed, run = arg.split(":", 2)
    try:
        r = json.load(open(f"{run}/result.json"))
    except Exception:
        print(f"{mode:6} seed {seed}: no result")
        continue
    rows.setdefault(mode, []).append(r)
    print(f"{mode:6} seed {seed}: EV {'arrived' if r['ev_arrived'] else 'did not arrive'}, travel {r['ev_travel_time_s']:.1f} s, "
          f"stops {r['ev_stops']}, lights held {r['preempted_signals']}, back on program {r['lights_back_on_program']}/{r['lights_taken_over']}, "
          f"collisions {r['collisions']}, safety violations {len(r['safety_violations'])}, others' mean time loss {r['others_mean_time_loss_s']:.1f} s")
    if mode == "ntcip":
        sig = json.load(open(f"{run}/signals.json")).get("signals", [])
        for s in sig:
            f = s.get("field") or {}
            if f.get("answers"):
                rtts.append((f["answers"], f.get("rtt_p50_ms"), f.get("rtt_p99_ms")))
for mode, rs in rows.items():
    t = [r["ev_travel_time_s"] for r in rs if r["ev_arrived"]]
    loss = [r["others_mean_time_loss_s"] for r in rs]
    print(f"{mode}: median EV travel {statistics.median(t) if t else float('nan'):.1f} s over {len(t)}/{len(rs)} arrived, "
          f"median others' time loss {statistics.median(loss):.1f} s, "
          f"safety violations {sum(len(r['safety_violations']) for r in rs)}, collisions {sum(r['collisions'] for r in rs)}")
if "mirror" in rows and "ntcip" in rows:
    a = statistics.median([r["ev_travel_time_s"] for r in rows["mirror"]])
    b = statistics.median([r["ev_travel_time_s"] for r in rows["ntcip"]])
    print(f"NTCIP against mirror: {b - a:+.1f} s ({(b - a) / a * 100:+.1f} %) in the median EV travel time")
if rtts:
    n = sum(a for a, _, _ in rtts)
    p50 = statistics.median([p for _, p, _ in rtts if p is not None])
    p99 = max(p for _, _, p in rtts if p is not None)
    print(f"SNMP per command (the server's round trips): {n} answers over {len(rtts)} controllers, "
          f"median of the controllers' p50 {p50:.2f} ms, worst controller's p99 {p99:.2f} ms")
PY
