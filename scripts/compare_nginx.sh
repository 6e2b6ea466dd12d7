#!/usr/bin/env bash
# The position path against nginx, back to back on this machine: wrk posts position reports for
# many vehicles with rising timestamps (../shared/anchors/wrk/positions.lua) to `corridor serve` on
# the embedded Monaco map (every report map-matched and durable before its answer), then the same
# script and flags to nginx answering `return 200`. Prints each side's rate, p50 and p99, and the
# ratios; repeats RUNS times, alternating, and gives the worst ratio.
#
# Usage: scripts/compare_nginx.sh [RUNS] [DURATION_S] [CONNECTIONS]   (defaults 3, 15, 200)
# Environment: CORRIDOR (default build/app/corridor). Needs wrk and nginx (Debian wrk, nginx-light).
set -euo pipefail
cd "$(dirname "$0")/.."
corridor=${CORRIDOR:-build/app/corridor}
runs=${1:-3}
duration=${2:-15}
connections=${3:-200}
anchor=../shared/anchors/wrk/positions.lua
for tool in wrk nginx; do
  command -v "$tool" > /dev/null || { echo "$tool is not installed (apt-get install wrk nginx-light)" >&2; exit 2; }
done
[[ -f $anchor ]] || { echo "the wrk anchor is not at $anchor" >&2; exit 2; }
work=$(mktemp -d)
server_pid="" nginx_pid=""
cleanup() {
  [[ -n $server_pid ]] && kill "$server_pid" 2> /dev/null
  [[ -n $nginx_pid ]] && kill "$nginx_pid" 2> /dev/null
  rm -rf "$work"
}
trap cleanup EXIT
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

token=compare-nginx-token-0123456789abcdef
sed "s/token/\"$token\"/" "$anchor" > "$work/pos.lua"

nginx_port=$(free_port)
mkdir -p "$work/nginx"
cat > "$work/nginx/nginx.conf" <<EOF
worker_processes 2;
pid $work/nginx/nginx.pid;
error_log $work/nginx/error.log;
daemon off;
events { worker_connections 4096; }
http {
  access_log off;
  client_body_temp_path $work/nginx;
  server { listen 127.0.0.1:$nginx_port; location / { return 200 '{"ok":true}'; } }
}
EOF
nginx -c "$work/nginx/nginx.conf" -p "$work/nginx" &
nginx_pid=$!

server_port=$(free_port)
CORRIDOR_DEV_TOKEN=$token "$corridor" serve --db "$work/corridor.db" --listen "127.0.0.1:$server_port" > "$work/serve.log" 2>&1 &
server_pid=$!
for _ in $(seq 1 200); do
  curl -sf -H "Authorization: Bearer $token" "http://127.0.0.1:$server_port/v1/health" > /dev/null &&
    curl -sf "http://127.0.0.1:$nginx_port/" > /dev/null && break
  sleep 0.1
done

bench() {  # bench URL OUT
  wrk -t2 -c"$connections" -d"${duration}s" --latency -s "$work/pos.lua" "$1" > "$2"
}
for run in $(seq 1 "$runs"); do
  bench "http://127.0.0.1:$server_port" "$work/corridor.$run.txt"
  bench "http://127.0.0.1:$nginx_port" "$work/nginx.$run.txt"
done
stored=$(/usr/bin/python3 -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute("SELECT COUNT(*) FROM positions").fetchone()[0])' "$work/corridor.db")

/usr/bin/python3 - "$work" "$runs" "$stored" <<'PY'
import re, sys
work, runs, stored = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def parse(path):
    t = open(path).read()
    rate = float(re.search(r"Requests/sec:\s+([\d.]+)", t).group(1))
    total = int(re.search(r"(\d+) requests in", t).group(1))
    def pct(p):
        m = re.search(rf"^\s+{p}%\s+([\d.]+)(us|ms|s)\s*$", t, re.M)
        v, u = float(m.group(1)), m.group(2)
        return v / 1000 if u == "us" else v * 1000 if u == "s" else v
    non2xx = re.search(r"Non-2xx or 3xx responses: (\d+)", t)
    errors = re.search(r"Socket errors: (.*)", t)
    return rate, pct(50), pct(99), total, int(non2xx.group(1)) if non2xx else 0, errors.group(1) if errors else ""
worst_rate, worst_p99 = 1e9, 0.0
answered = 0
print(f"{'run':>3} | {'corridor /s':>11} {'p50':>7} {'p99':>7} | {'nginx /s':>9} {'p50':>7} {'p99':>7} | {'rate ratio':>10} {'p99 ratio':>9}")
for r in range(1, runs + 1):
    c = parse(f"{work}/corridor.{r}.txt")
    n = parse(f"{work}/nginx.{r}.txt")
    answered += c[3] - c[4]
    rr, pr = c[0] / n[0], c[2] / n[2]
    worst_rate, worst_p99 = min(worst_rate, rr), max(worst_p99, pr)
    extra = f"  corridor non-2xx {c[4]} {c[5]}".rstrip() if c[4] or c[5] else ""
    print(f"{r:>3} | {c[0]:>11.0f} {c[1]:>5.2f}ms {c[2]:>5.2f}ms | {n[0]:>9.0f} {n[1]:>5.2f}ms {n[2]:>5.2f}ms | {rr:>10.2f} {pr:>9.2f}{extra}")
print(f"worst over runs: rate {worst_rate:.2f}x nginx's, p99 {worst_p99:.2f}x nginx's")
print(f"reports answered 2xx: {answered}, stored: {stored}")
print(f"goal (rate >= 0.50x, p99 <= 2x): {'met' if worst_rate >= 0.5 and worst_p99 <= 2.0 else 'not met'}")
PY
