#!/usr/bin/env bash
# Integration test of `corridor serve`: the real server on a loopback port, driven over HTTP and
# WebSocket, then killed with -9 under load and restarted on the same database.
# Usage: server_test.sh CORRIDOR_BINARY
set -uo pipefail
corridor=$1
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
export CORRIDOR_CACHE_DIR=$work/cache
export CORRIDOR_DEV_TOKEN=integration-dev-token-0123456789
TOKEN=$CORRIDOR_DEV_TOKEN
passed=0
failed=0
server_pid=""
cleanup() {
  [[ -n $server_pid ]] && kill -9 "$server_pid" 2> /dev/null
  rm -rf "$work"
}
trap cleanup EXIT
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL: $*" >&2; failed=$((failed + 1)); }
check() { if eval "$2"; then pass; else fail "$1"; fi; }

cat > "$work/config.json" << 'JSON'
{"limits": {"read_timeout_s": 2},
 "tokens": [
  {"token": "viewer-token-0123456789abcdef", "name": "wall", "roles": ["viewer"]},
  {"token": "amb1-vehicle-token-0123456789", "name": "amb1", "roles": ["vehicle"], "vehicle_id": "amb-1"}
]}
JSON

start_server() {
  "$corridor" serve --db "$work/corridor.db" --listen 127.0.0.1:0 --config "$work/config.json" > "$work/serve.out" 2> "$work/serve.err" &
  server_pid=$!
  for _ in $(seq 1 100); do
    port=$(grep -o '127.0.0.1:[0-9]*' "$work/serve.out" 2> /dev/null | head -1 | cut -d: -f2)
    [[ -n $port ]] && return 0
    sleep 0.1
  done
  echo "server did not start: $(cat "$work/serve.err")" >&2
  exit 1
}
api() {  # METHOD PATH [BODY] [TOKEN] -> prints "STATUS BODY"
  local method=$1 path=$2 body=${3:-} token=${4:-$TOKEN}
  curl -s -o "$work/body" -w '%{http_code}' -X "$method" -H "Authorization: Bearer $token" \
    -H 'Content-Type: application/json' ${body:+--data-binary "$body"} "http://127.0.0.1:$port$path"
}
jq_py() { python3 -c "import json,sys; d=json.load(open('$work/body')); print($1)"; }

start_server
check "development token printed" "grep -q 'development token (all roles): $TOKEN' '$work/serve.out'"
check "token never in logs" "! grep -q '$TOKEN' '$work/serve.err'"
check "health" "[[ \$(api GET /v1/health) == 200 ]]"
# A second server on the same database is refused with a clear error, and prints no token.
"$corridor" serve --db "$work/corridor.db" --listen 127.0.0.1:0 > "$work/second.out" 2> "$work/second.err"
second_rc=$?
check "second server on the same database refused" "[[ $second_rc -ne 0 ]] && grep -q 'in use by another corridor server' '$work/second.err'"
check "refused server prints no token" "! grep -q 'development token' '$work/second.out'"
check "first server unaffected" "[[ \$(api GET /v1/health) == 200 ]]"

# A WebSocket client listens for the whole scenario.
python3 "$here/ws_listen.py" 127.0.0.1 "$port" viewer-token-0123456789abcdef 120 > "$work/ws.txt" &
ws_pid=$!
wait_for() {  # SECONDS CONDITION: polls instead of sleeping a fixed time (CI machines are shared)
  local deadline=$((SECONDS + $1))
  while ((SECONDS < deadline)); do
    eval "$2" && return 0
    sleep 0.1
  done
  return 1
}
wait_for 20 "grep -q '\"type\":\"hello\"' '$work/ws.txt'" || fail "stream did not open"

# 1. Create a mission across Monaco.
status=$(api POST /v1/missions '{"vehicle_id":"amb-1","origin":{"lat":43.7384,"lon":7.4246},"destination":{"lat":43.7496,"lon":7.4365},"priority":2}')
check "mission created (201)" "[[ $status == 201 ]]"
mission=$(jq_py "d['id']")
check "mission has route and eta" "[[ \$(jq_py \"d['route']['type'] == 'Feature' and d['eta_s'] > 0\") == True ]]"
jq_py "json.dumps(d['route']['geometry']['coordinates'])" > "$work/coords.json"
jq_py "json.dumps(d['route']['properties']['edges'])" > "$work/edges.json"

# 2. Position updates along the route, with the vehicle's own token.
for i in 2 5 8; do
  pos=$(python3 -c "import json; c=json.load(open('$work/coords.json')); p=c[min($i, len(c)-2)]; print(json.dumps({'lat':p[1],'lon':p[0],'timestamp':$i,'source':'gps'}))")
  status=$(api POST /v1/vehicles/amb-1/position "$pos" amb1-vehicle-token-0123456789)
  check "position $i accepted" "[[ $status == 200 && \$(jq_py \"d['mission'] == $mission\") == True ]]"
done
check "other vehicle's position refused (403)" "[[ \$(api POST /v1/vehicles/amb-2/position '{\"lat\":43.74,\"lon\":7.43,\"timestamp\":1}' amb1-vehicle-token-0123456789) == 403 ]]"

# 3. Congestion on the rest of the route changes it; the stream reports route_changed.
updates=$(python3 -c "import json; e=json.load(open('$work/edges.json')); print(json.dumps({'updates':[{'edge':x,'speed_kmh':2,'expires_in_s':600} for x in e[2:-1]]}))")
status=$(api POST /v1/congestion "$updates")
check "congestion accepted" "[[ $status == 200 && \$(jq_py \"d['routes_changed']\") -ge 1 ]]"
api GET "/v1/missions/$mission" > /dev/null
check "route revision advanced" "[[ \$(jq_py \"d['route_revision']\") -ge 2 ]]"

# 4. Completion at the destination.
# (At t=200: sooner, the jump from the last fix would be faster than a vehicle drives, an outlier.)
status=$(api POST /v1/vehicles/amb-1/position '{"lat":43.7496,"lon":7.4365,"timestamp":200}')
check "mission completes at the destination" "[[ $status == 200 && \$(jq_py \"d['completed']\") == True ]]"
api GET "/v1/missions/$mission" > /dev/null
check "mission state completed" "[[ \$(jq_py \"d['state']\") == completed ]]"

wait_for 30 "grep -q '\"type\":\"mission_completed\"' '$work/ws.txt'"
kill $ws_pid 2> /dev/null
wait $ws_pid 2> /dev/null
check "stream handshake" "grep -q 'STATUS HTTP/1.1 101' '$work/ws.txt'"
for kind in mission_created route_changed position congestion_applied mission_completed; do
  check "stream received $kind" "grep -q '\"type\":\"$kind\"' '$work/ws.txt'"
done

# 5. Auth failures and bad inputs.
check "no token: 401" "[[ \$(api GET /v1/missions '' not-a-valid-token-at-all) == 401 ]]"
check "viewer may not dispatch: 403" "[[ \$(api POST /v1/missions '{}' viewer-token-0123456789abcdef) == 403 ]]"
check "stream without token refused" "python3 '$here/ws_listen.py' 127.0.0.1 $port bad-token 2 | grep -q 401"
check "malformed JSON: 400" "[[ \$(api POST /v1/missions '{\"vehicle_id\":') == 400 && \$(jq_py \"d['error']['code']\") == bad_request ]]"
check "wrong type: 400" "[[ \$(api POST /v1/missions '{\"vehicle_id\":1,\"destination\":{\"lat\":1,\"lon\":1}}') == 400 ]]"
check "coordinates off the map: 422" "[[ \$(api POST /v1/vehicles/amb-1/position '{\"lat\":48.85,\"lon\":2.35,\"timestamp\":1}') == 422 ]]"
check "out-of-range coordinates: 422" "[[ \$(api POST /v1/missions '{\"vehicle_id\":\"x\",\"destination\":{\"lat\":91,\"lon\":1}}') == 422 ]]"
check "unknown mission: 404" "[[ \$(api GET /v1/missions/424242) == 404 ]]"
head -c 2000000 /dev/zero | tr '\0' 'x' > "$work/huge.txt"
huge=$(curl -s -o /dev/null -w '%{http_code}' -X POST -H "Authorization: Bearer $TOKEN" --data-binary @"$work/huge.txt" "http://127.0.0.1:$port/v1/congestion")
check "huge body: 413" "[[ $huge == 413 ]]"
check "server still healthy" "[[ \$(api GET /v1/health) == 200 ]]"
# A slow client (connects, sends half a request, then nothing) is cut off after the read timeout.
slow=$(python3 - "$port" << 'PY'
import socket, sys, time
s = socket.create_connection(("127.0.0.1", int(sys.argv[1])))
s.sendall(b"POST /v1/congestion HTTP/1.1\r\nHost: x\r\nContent-Length: 100\r\n\r\n{")
s.settimeout(10)
start = time.time()
try:
    data = s.recv(4096)
except socket.timeout:
    data = None
elapsed = time.time() - start
print("cut-off" if data == b"" and 1.0 <= elapsed <= 6.0 else f"data={data!r} after {elapsed:.1f}s")
PY
)
check "slow client cut off after the 2 s read timeout ($slow)" "[[ '$slow' == cut-off ]]"
check "server healthy after the slow client" "[[ \$(api GET /v1/health) == 200 ]]"

# 6. kill -9 under load: every acknowledged position is stored, and the active mission resumes.
status=$(api POST /v1/missions '{"vehicle_id":"amb-7","origin":{"lat":43.7384,"lon":7.4246},"destination":{"lat":43.7496,"lon":7.4365}}')
check "second mission created" "[[ $status == 201 ]]"
resumed_id=$(jq_py "d['id']")
: > "$work/acked.txt"
(
  for i in $(seq 1000 1600); do
    code=$(curl -s -o /dev/null -w '%{http_code}' -X POST -H "Authorization: Bearer $TOKEN" \
      --data-binary "{\"lat\":43.7384,\"lon\":7.4246,\"timestamp\":$i}" "http://127.0.0.1:$port/v1/vehicles/amb-7/position")
    [[ $code == 200 ]] && echo "$i" >> "$work/acked.txt"
  done
) &
load_pid=$!
wait_for 60 "[[ \$(wc -l < '$work/acked.txt') -ge 50 ]]"
kill -9 "$server_pid"
wait "$server_pid" 2> /dev/null
server_pid=""
wait $load_pid
acked=$(wc -l < "$work/acked.txt")
check "load was acknowledged before the kill ($acked writes)" "[[ $acked -gt 20 ]]"
missing=$(python3 - "$work/corridor.db" "$work/acked.txt" << 'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
stored = {int(r[0]) for r in db.execute("SELECT timestamp_s FROM positions WHERE vehicle_id='amb-7'")}
acked = {int(l) for l in open(sys.argv[2]) if l.strip()}
print(len(acked - stored))
PY
)
check "no acknowledged write lost ($missing missing)" "[[ $missing == 0 ]]"
start_server
api GET "/v1/missions/$resumed_id" > /dev/null
check "active mission resumed after restart" "[[ \$(jq_py \"d['state']\") == active ]]"
api GET "/v1/missions/$mission" > /dev/null
check "completed mission still readable" "[[ \$(jq_py \"d['state']\") == completed ]]"
check "restart reports the resumed mission" "grep -q '1 active missions resumed' '$work/serve.out'"

echo "$passed passed, $failed failed"
((failed == 0))
