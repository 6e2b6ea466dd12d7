#!/usr/bin/python3
"""corridor serve driving field signal controllers over NTCIP 1202, against corridor signal-agent,
with Net-SNMP's own snmpget/snmpset as the independent client that watches the agents:

- a mission whose vehicle drives through a signal: the agent sees preemptControlState go to 1 at
  the planned start and back to 0 after the vehicle passed, preemptState reaches dwell before the
  vehicle arrives, the call record holds its times (SNMPv3 authPriv on that controller), and no two
  conflicting movements are ever green at any controller during the whole test;
- the agent killed mid-hold: the server reports the controller unreachable, keeps serving the API
  and the other signals, and clears the call when the agent returns;
- the server killed mid-hold: restarted on its database it takes the call as its own again (no
  second call), and a server that has no record of it (a fresh database) clears the orphaned call;
- a wrong community (unreachable: agents drop it), an SNMP error status (a preempt the controller
  does not have: degraded, the call denied) and a timeout (no agent: unreachable, with backoff).

Usage: ntcip_test.py CORRIDOR_BINARY
"""
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

CORRIDOR = sys.argv[1]
WORK = tempfile.mkdtemp(prefix="ntcip-test-")
TOKEN = "ntcip-test-token-0123456789"
P = "1.3.6.1.4.1.1206.4.2.1"
failures = []
procs = []


def fail(msg):
    print("FAIL:", msg, flush=True)
    failures.append(msg)


def free_udp_block(n):
    for base in range(21000, 60000, 97):
        ok = True
        for p in range(base, base + n):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                s.bind(("127.0.0.1", p))
            except OSError:
                ok = False
            finally:
                s.close()
            if not ok:
                break
        if ok:
            return base
    raise RuntimeError("no free UDP port block")


def free_tcp():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def start(args, log):
    env = dict(os.environ, CORRIDOR_DEV_TOKEN=TOKEN)
    p = subprocess.Popen([CORRIDOR] + args, stdout=open(log, "w"), stderr=subprocess.STDOUT, env=env)
    procs.append(p)
    return p


def wait_for(pred, timeout, what):
    end = time.time() + timeout
    while time.time() < end:
        try:
            v = pred()
            if v:
                return v
        except Exception:
            pass
        time.sleep(0.2)
    fail(f"timed out after {timeout} s waiting for {what}")
    return None


class Server:
    def __init__(self, controllers, db, name):
        self.port = free_tcp()
        self.url = f"http://127.0.0.1:{self.port}"
        self.args = ["serve", "--db", db, "--listen", f"127.0.0.1:{self.port}", "--controllers", controllers]
        self.log = os.path.join(WORK, name + ".log")
        self.proc = start(self.args, self.log)
        wait_for(lambda: self.get("/v1/health"), 30, f"{name} to listen")

    def call(self, method, path, body=None):
        req = urllib.request.Request(self.url + path, method=method, data=None if body is None else json.dumps(body).encode(),
                                     headers={"Authorization": "Bearer " + TOKEN})
        with urllib.request.urlopen(req, timeout=10) as r:
            data = r.read()
            return json.loads(data) if r.headers.get("Content-Type", "").startswith("application/json") else data.decode()

    def get(self, path):
        return self.call("GET", path)

    def post(self, path, body):
        return self.call("POST", path, body)

    def kill(self):
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait()


def snmpget(port, oids, community="public", timeout=1):
    out = subprocess.run(["snmpget", "-v2c", "-c", community, "-t", str(timeout), "-r", "0", "-Oqv", f"127.0.0.1:{port}"] + oids,
                         capture_output=True, text=True)
    if out.returncode != 0:
        return None
    vals = out.stdout.split()
    return [int(v) if v.lstrip("-").isdigit() else None for v in vals]


def haversine(a, b):
    la1, lo1, la2, lo2 = map(math.radians, (a[1], a[0], b[1], b[0]))
    h = math.sin((la2 - la1) / 2) ** 2 + math.cos(la1) * math.cos(la2) * math.sin((lo2 - lo1) / 2) ** 2
    return 2 * 6371008.8 * math.asin(math.sqrt(h))


class Monitor(threading.Thread):
    """Polls every agent's greens (and the watched ones' call and preempt states) with snmpget."""

    def __init__(self, manifest):
        super().__init__(daemon=True)
        self.manifest = manifest
        self.stop = False
        self.timeline = {}  # port -> [(t, control list, preempt state list)]
        self.watch = set()
        self.violations = []
        self.samples = 0

    def run(self):
        while not self.stop:
            for c in self.manifest:
                port = c["port"]
                groups = (len(c["phases"]) + 7) // 8
                oids = [f"{P}.1.4.1.4.{g}" for g in range(1, groups + 1)]
                n = len(c["preempts"])
                if port in self.watch:
                    oids += [f"{P}.6.3.1.2.{k}" for k in range(1, n + 1)] + [f"{P}.6.2.1.16.{k}" for k in range(1, n + 1)]
                vals = snmpget(port, oids)
                if vals is None or len(vals) != len(oids):
                    continue
                self.samples += 1
                green = set()
                for g in range(groups):
                    for k in range(8):
                        if (vals[g] or 0) & (1 << k):
                            green.add(8 * g + k + 1)
                for a, b in c.get("conflicts", []):
                    if a in green and b in green:
                        self.violations.append(f"{c['id']}: phases {a} and {b} green together at {time.time():.1f}")
                if port in self.watch:
                    self.timeline.setdefault(port, []).append((time.time(), vals[groups:groups + n], vals[groups + n:]))
            time.sleep(0.25)


def route_coords(mission):
    return mission["route"]["geometry"]["coordinates"]


def point_at(coords, d):
    """The point d metres along the polyline, and the heading there."""
    for a, b in zip(coords, coords[1:]):
        seg = haversine(a, b)
        if d <= seg or b is coords[-1]:
            f = 0 if seg == 0 else min(1.0, d / seg)
            p = (a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f)
            heading = (math.degrees(math.atan2((b[0] - a[0]) * math.cos(math.radians(a[1])), b[1] - a[1])) + 360) % 360
            return p, heading
        d -= seg
    return coords[-1], 0.0


def along(coords, p):
    """Distance along the polyline of its point nearest to p."""
    best, best_d, acc = None, 0.0, 0.0
    for a, b in zip(coords, coords[1:]):
        seg = haversine(a, b)
        for i in range(21):
            q = (a[0] + (b[0] - a[0]) * i / 20, a[1] + (b[1] - a[1]) * i / 20)
            dist = haversine(q, p)
            if best is None or dist < best:
                best, best_d = dist, acc + seg * i / 20
        acc += seg
    return best_d


def drive(server, vehicle, coords, speed, until_d, stop_event=None):
    """Posts positions at 1 Hz along coords at speed m/s up to until_d metres; returns when done."""
    total = sum(haversine(a, b) for a, b in zip(coords, coords[1:]))
    t0 = time.time()
    while True:
        d = min(until_d, total, (time.time() - t0) * speed)
        p, heading = point_at(coords, d)
        try:
            server.post(f"/v1/vehicles/{vehicle}/position",
                        {"lat": p[1], "lon": p[0], "heading_deg": heading, "speed_mps": speed, "timestamp": time.time(), "source": "gps"})
        except urllib.error.URLError:
            pass
        if d >= min(until_d, total) or (stop_event is not None and stop_event.is_set()):
            return
        time.sleep(1.0)


def main():
    first_port = free_udp_block(8)
    state = os.path.join(WORK, "agent-state")
    manifest_file = os.path.join(WORK, "agents.json")
    agent_args = ["signal-agent", "--listen", f"127.0.0.1:{first_port}", "--manifest", manifest_file,
                             "--read-community", "public", "--write-community", "private", "--state-dir", state,
                             "--v3-user", "corridor", "--v3-auth-password", "authpass123", "--v3-priv-password", "privpass123",
                             "--call-timeout-s", "120"]
    agent = start(agent_args, os.path.join(WORK, "agent.log"))
    wait_for(lambda: os.path.exists(manifest_file), 30, "the agents' manifest")
    manifest = json.load(open(manifest_file))
    print(f"{len(manifest)} agents from port {first_port}", flush=True)
    # Net-SNMP's own tools against the agent, unchanged: a walk of one controller.
    walk = subprocess.run(["snmpwalk", "-v2c", "-c", "public", "-On", f"127.0.0.1:{first_port}", P], capture_output=True, text=True)
    if walk.returncode != 0 or f".{P}.6.2.1.16.1 = INTEGER: 2" not in walk.stdout:
        fail("snmpwalk of the agent: " + walk.stdout[-300:] + walk.stderr[-300:])
    v3 = subprocess.run(["snmpget", "-v3", "-u", "corridor", "-l", "authPriv", "-a", "SHA", "-A", "authpass123", "-x", "AES", "-X",
                         "privpass123", "-Oqv", f"127.0.0.1:{first_port}", f"{P}.6.1.0"], capture_output=True, text=True)
    if v3.returncode != 0 or v3.stdout.strip() != str(len(manifest[0]["preempts"])):
        fail("snmpget -v3 authPriv of the agent: " + v3.stdout + v3.stderr)
    monitor = Monitor(manifest)
    monitor.start()

    # Where a mission crosses a signal: the README's trip across Monaco, planned once to find it.
    probe_db = os.path.join(WORK, "probe.db")
    probe = Server(manifest_file, probe_db, "probe")
    m = probe.post("/v1/missions", {"vehicle_id": "probe", "origin": {"lat": 43.7384, "lon": 7.4246},
                                    "destination": {"lat": 43.7496, "lon": 7.4365}, "priority": 2})
    probe.kill()
    coords = route_coords(m)
    first = min(m["preemption"], key=lambda e: e["arrival_s"])
    signal_id = first["signal"]
    signal_at = (first["location"]["lon"], first["location"]["lat"])
    cross_d = along(coords, signal_at)
    # Start 150 m before the signal, so that its call comes early.
    start_d = max(0.0, cross_d - 150.0)

    # The main server: the crossed signal's controller over SNMPv3 authPriv, the others v2c.
    main_controllers = json.load(open(manifest_file))
    server_probe = Server(manifest_file, os.path.join(WORK, "probe2.db"), "probe2")
    sig_json = server_probe.get(f"/v1/signals/{signal_id}")
    server_probe.kill()
    controller_id = sig_json["field"]["controller"]
    target = next(c for c in main_controllers if c["id"] == controller_id)
    port = target["port"]
    target["snmp"] = {"version": "v3", "user": "corridor", "auth_password": "authpass123", "priv_password": "privpass123"}
    controllers_file = os.path.join(WORK, "controllers.json")
    json.dump(main_controllers, open(controllers_file, "w"))
    monitor.watch.add(port)
    db = os.path.join(WORK, "corridor.db")
    server = Server(controllers_file, db, "serve")
    wait_for(lambda: server.get(f"/v1/signals/{signal_id}")["field"]["link"] == "up", 20, "the v3 controller's link up")

    def mission(vehicle):
        p, h = point_at(coords, start_d)
        server.post(f"/v1/vehicles/{vehicle}/position",
                    {"lat": p[1], "lon": p[0], "heading_deg": h, "speed_mps": 0, "timestamp": time.time(), "source": "gps"})
        return server.post("/v1/missions", {"vehicle_id": vehicle, "destination": {"lat": 43.7496, "lon": 7.4365}, "priority": 2})

    def control(p=port):
        tl = monitor.timeline.get(p, [])
        return tl[-1] if tl else None

    def call_on():
        c = control()
        return c is not None and 1 in c[1]

    # 1. A mission through the signal.
    m1 = mission("amb-1")
    entry = next((e for e in m1["preemption"] if e["signal"] == signal_id), None)
    if entry is None:
        fail(f"the mission's schedule has no entry at signal {signal_id}")
    speed = 6.0  # slower than planned: the server's predictions run ahead of the vehicle, never behind
    # The mission's own route, from where the vehicle stands.
    coords1 = route_coords(server.get(f"/v1/missions/{m1['id']}"))
    cross1 = along(coords1, signal_at)
    t_start = time.time()
    # Through the signal and 60 m on: enough for its hold to end; the rest of the route is not the test's.
    drive_thread = threading.Thread(target=drive, args=(server, "amb-1", coords1, speed, cross1 + 60.0))
    drive_thread.start()
    crossing_time = t_start + cross1 / speed
    drive_thread.join()
    time.sleep(12)
    tl = monitor.timeline.get(port, [])
    on = [t for t, ctlv, st in tl if 1 in ctlv]
    dwell = [t for t, ctlv, st in tl if 6 in st]
    if not on:
        fail("the agent never saw preemptControlState go to 1")
    else:
        sched = server.get(f"/v1/missions/{m1['id']}")["preemption"]
        e = next((x for x in sched if x["signal"] == signal_id), None)
        planned = e["start_s"] if e else None
        print(f"call on at +{on[0] - t_start:.1f} s (planned start +{planned - t_start if planned else float('nan'):.1f} s), "
              f"off after +{on[-1] - t_start:.1f} s; vehicle at the stop line +{crossing_time - t_start:.1f} s", flush=True)
        if planned is not None and abs(on[0] - planned) > 3.0:
            fail(f"the call went on {on[0] - planned:+.1f} s from its planned start")
        if not dwell or dwell[0] >= crossing_time:
            fail(f"preemptState did not reach dwell before the vehicle's arrival (dwell {dwell[:1]}, arrival {crossing_time:.1f})")
        if on[-1] < crossing_time - 1.0:
            fail(f"the call went off {crossing_time - on[-1]:.1f} s before the vehicle passed")
        if on[-1] > crossing_time + 20.0:
            fail(f"the call stayed on {on[-1] - crossing_time:.1f} s after the vehicle passed")
    calls = server.get(f"/v1/signals/{signal_id}/calls")["calls"]
    c1 = next((c for c in calls if c.get("vehicle_id") == "amb-1"), None)
    if c1 is None:
        fail(f"no call record for amb-1 at signal {signal_id}: {calls}")
    else:
        missing = [k for k in ("request_s", "grant_s", "release_s", "clear_s") if k not in c1]
        if missing or c1["outcome"] != "served":
            fail(f"the call record is incomplete or not served: {c1}")
        elif not (c1["request_s"] <= c1["grant_s"] <= c1["release_s"] <= c1["clear_s"]):
            fail(f"the call record's times are out of order: {c1}")
    csv = server.get(f"/v1/missions/{m1['id']}/calls?format=csv")
    if not csv.startswith("id,signal,controller,mission_id,vehicle_id") or "amb-1" not in csv:
        fail("the mission's call records as CSV: " + csv[:200])
    field = server.get(f"/v1/signals/{signal_id}")["field"]
    if field.get("answers", 0) < 5:
        fail("the controller answered fewer than 5 requests")
    print(f"SNMP round trip over v3 authPriv: p50 {field.get('rtt_p50_ms', float('nan')):.2f} ms, "
          f"p99 {field.get('rtt_p99_ms', float('nan')):.2f} ms over {field['answers']} answers", flush=True)
    server.post(f"/v1/missions/{m1['id']}/cancel", {})

    # 2. The agent killed mid-hold.
    m2 = mission("amb-2")
    stop2 = threading.Event()
    d2 = threading.Thread(target=drive, args=(server, "amb-2", route_coords(server.get(f"/v1/missions/{m2['id']}")), 1.0, 1e9, stop2))
    d2.start()
    wait_for(call_on, 60, "amb-2's call on the agent")
    agent.send_signal(signal.SIGKILL)
    agent.wait()
    t_kill = time.time()
    if not wait_for(lambda: server.get(f"/v1/signals/{signal_id}")["field"]["link"] == "unreachable", 30, "the link reported unreachable"):
        pass
    print(f"link unreachable {time.time() - t_kill:.1f} s after the agent died", flush=True)
    t0 = time.time()
    health = server.get("/v1/health")
    others = server.get("/v1/signals")["signals"]
    if time.time() - t0 > 2.0 or not health or len(others) != len(manifest):
        fail("the API was slow or incomplete while a controller was down")
    stop2.set()
    d2.join()
    server.post(f"/v1/missions/{m2['id']}/cancel", {})
    agent = start(agent_args, os.path.join(WORK, "agent2.log"))
    wait_for(lambda: server.get(f"/v1/signals/{signal_id}")["field"]["link"] == "up", 60, "the link up again")

    def cleared(vehicle):
        calls = server.get(f"/v1/signals/{signal_id}/calls")["calls"]
        c = next((x for x in calls if x.get("vehicle_id") == vehicle), None)
        return c if c and "clear_s" in c else None

    c2 = wait_for(lambda: cleared("amb-2"), 30, "amb-2's call cleared after the agent returned")
    if c2:
        print(f"amb-2's call: {c2['outcome']}", flush=True)
    time.sleep(2)
    if call_on():
        fail("the agent has a call on after the cancelled mission's call was cleared")

    # 3. The server killed mid-hold, restarted on its database: the call is its own again.
    m3 = mission("amb-3")
    wait_for(call_on, 60, "amb-3's call on the agent")
    server.kill()
    time.sleep(3)
    if not call_on():
        fail("the agent dropped the call as soon as the server died (its watchdog is 120 s here)")
    server = Server(controllers_file, db, "serve-restarted")
    time.sleep(6)
    records = server.get(f"/v1/signals/{signal_id}/calls")["calls"]
    server.post(f"/v1/missions/{m3['id']}/cancel", {})
    wait_for(lambda: not call_on(), 20, "amb-3's call removed after its cancel")
    # A server with no record of the call (a fresh database) finds it orphaned and clears it.
    m4 = mission("amb-4")
    wait_for(call_on, 60, "amb-4's call on the agent")
    server.kill()
    server = Server(controllers_file, os.path.join(WORK, "fresh.db"), "serve-fresh")
    wait_for(lambda: not call_on(), 20, "the orphaned call cleared by a fresh server")
    orphan = wait_for(lambda: [c for c in server.get(f"/v1/signals/{signal_id}/calls")["calls"] if c["outcome"] == "orphan_cleared"], 10,
                      "an orphan_cleared call record")
    if orphan:
        print(f"orphaned call cleared: {orphan[0]}", flush=True)
    del m4, records
    server.kill()

    # 4. A wrong community, an SNMP error status, and no agent at all.
    wrong = json.load(open(manifest_file))
    for c in wrong:
        c["snmp"]["write_community"] = "wrong-community"
    json.dump(wrong, open(os.path.join(WORK, "wrong.json"), "w"))
    s4 = Server(os.path.join(WORK, "wrong.json"), os.path.join(WORK, "wrong.db"), "serve-wrong")
    f = wait_for(lambda: s4.get(f"/v1/signals/{signal_id}")["field"] if s4.get(f"/v1/signals/{signal_id}")["field"]["link"] == "unreachable" else None,
                 30, "a wrong community reported unreachable")
    if f:
        print(f"wrong community: {f['link']} ({f.get('error', '')})", flush=True)
    s4.kill()

    bad = json.load(open(manifest_file))
    tb = next(c for c in bad if c["id"] == controller_id)
    for p_ in tb["preempts"]:
        p_["number"] += 8  # inputs the controller does not have
    json.dump(bad, open(os.path.join(WORK, "bad-preempt.json"), "w"))
    server = Server(os.path.join(WORK, "bad-preempt.json"), os.path.join(WORK, "bad.db"), "serve-bad-preempt")
    m5 = mission("amb-5")
    degraded = wait_for(lambda: server.get(f"/v1/signals/{signal_id}")["field"]
                        if server.get(f"/v1/signals/{signal_id}")["field"]["link"] == "degraded" else None, 90,
                        "an SNMP error status reported as a degraded link")
    if degraded:
        print(f"error status: {degraded['link']} ({degraded.get('error', '')})", flush=True)
    server.post(f"/v1/missions/{m5['id']}/cancel", {})
    denied = wait_for(lambda: [c for c in server.get(f"/v1/signals/{signal_id}/calls")["calls"] if c["outcome"] == "denied"], 30,
                      "the refused call recorded as denied")
    del denied
    server.kill()

    none = json.load(open(manifest_file))
    for c in none:
        c["port"] = c["port"] + 2000  # nothing listens there
    json.dump(none, open(os.path.join(WORK, "none.json"), "w"))
    s6 = Server(os.path.join(WORK, "none.json"), os.path.join(WORK, "none.db"), "serve-none")
    wait_for(lambda: all(s["field"]["link"] == "unreachable" for s in s6.get("/v1/signals")["signals"]), 30,
             "every controller unreachable when nothing answers")
    t0 = time.time()
    s6.post("/v1/missions", {"vehicle_id": "amb-6", "origin": {"lat": 43.7384, "lon": 7.4246},
                             "destination": {"lat": 43.7496, "lon": 7.4365}, "priority": 2})
    if time.time() - t0 > 2.0:
        fail(f"creating a mission took {time.time() - t0:.1f} s while no controller answers")
    s6.kill()

    monitor.stop = True
    monitor.join()
    print(f"safety monitor: {monitor.samples} samples of the agents' greens, {len(monitor.violations)} conflicts", flush=True)
    if monitor.samples < 50:
        fail(f"the safety monitor read only {monitor.samples} samples")
    for v in monitor.violations[:5]:
        fail("conflicting greens: " + v)


try:
    main()
finally:
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                p.kill()
    if failures:
        print(f"{len(failures)} failure(s); logs in {WORK}")
        for name in sorted(os.listdir(WORK)):
            if name.endswith(".log"):
                print(f"--- {name} (end)")
                print(open(os.path.join(WORK, name)).read()[-1500:])
    else:
        shutil.rmtree(WORK, ignore_errors=True)
        print("NTCIP: call, grant, release and clear; faults; no conflicting greens: all checks passed")
sys.exit(1 if failures else 0)
