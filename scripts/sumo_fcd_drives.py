#!/usr/bin/env python3
"""Ground-truth vehicle trajectories from SUMO (fcd output) for map-matching studies.

Builds a SUMO net from an OSM extract, routes N long "probe" drives (ids probe_0 .. probe_{N-1})
through light random background traffic, runs sumo with geo fcd output for the probes only, and
summarises every usable drive in DIR/drives.json.

    scripts/sumo_fcd_drives.py --osm /work/shared/data/osm/monaco.osm.gz --out /tmp/fcd/monaco

Outputs in DIR:
    <name>.net.xml       the SUMO net (keeps the OSM projection, so fcd can be written as lon/lat)
    probes.rou.xml       the probe vehicles with explicit routes
    background.rou.xml   background traffic (randomTrips, prefix bg_)
    fcd.xml              <timestep time=..><vehicle id=probe_i x=LON y=LAT angle=DEG speed=MPS lane=.. pos=../>
    tripinfo.xml         SUMO trip statistics (all vehicles)
    drives.json          per usable probe: id, depart, arrival, duration, samples, length
    *.log                tool logs

Only the Python standard library and SUMO's own tools are used. Exits non-zero when fewer than
--drives/2 usable drives remain.
"""

import argparse
import gzip
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from xml.sax.saxutils import quoteattr

PROBE_PREFIX = "probe_"


class Failure(Exception):
    pass


def log(msg):
    print(f"[sumo_fcd_drives] {msg}", file=sys.stderr, flush=True)


def run(cmd, logfile, env):
    """Runs a tool, sending its output to logfile; raises Failure with the log tail if it fails."""
    log("$ " + " ".join(cmd))
    with open(logfile, "w") as out:
        rc = subprocess.call(cmd, stdout=out, stderr=subprocess.STDOUT, env=env)
    if rc != 0:
        with open(logfile, errors="replace") as f:
            tail = "".join(f.readlines()[-15:])
        raise Failure(f"{os.path.basename(cmd[0])} failed (exit {rc}); see {logfile}:\n{tail}")


def up_to_date(target, *sources):
    if not os.path.exists(target):
        return False
    t = os.path.getmtime(target)
    return all(os.path.getmtime(s) <= t for s in sources if s and os.path.exists(s))


def osm_name(path):
    base = os.path.basename(path)
    return base.split(".")[0] or "net"


def build_net(osm, out, env, rebuild):
    """OSM (.osm, .osm.gz, .osm.pbf) -> SUMO net, with the netconvert options of sim/scenario_builder.cpp."""
    name = osm_name(osm)
    net = os.path.join(out, name + ".net.xml")
    if not rebuild and up_to_date(net, osm, os.path.abspath(__file__)):
        log(f"net {net} is up to date")
        return net
    src = osm
    if osm.endswith(".pbf"):
        if not shutil.which("osmium"):
            raise Failure("netconvert cannot read .pbf and osmium (osmium-tool) is not installed")
        src = os.path.join(out, name + ".osm")
        run(["osmium", "cat", "--overwrite", "-o", src, osm], os.path.join(out, "osmium.log"), env)
    run(["netconvert", "--osm-files", src,
         "--geometry.remove", "--ramps.guess", "--junctions.join",
         "--tls.guess-signals", "--tls.discard-simple", "--tls.join",
         "--keep-edges.by-vclass", "passenger", "--remove-edges.isolated",
         "--no-turnarounds", "true", "--output.street-names", "true",
         "-o", net], os.path.join(out, "netconvert.log"), env)
    if src != osm:
        os.remove(src)  # the converted .osm is large and only needed by netconvert
    return net


def read_net(net):
    """Edge id -> (length m, speed m/s) of non-internal edges, and whether the net has a geo projection."""
    edges = {}
    has_proj = False
    opener = gzip.open if net.endswith(".gz") else open
    with opener(net, "rb") as f:
        edge_id, internal, seen_lane = None, False, False
        for event, el in ET.iterparse(f, events=("start", "end")):
            if event == "start":
                if el.tag == "edge":
                    edge_id = el.get("id")
                    internal = el.get("function") == "internal"
                    seen_lane = False
                elif el.tag == "lane" and edge_id and not internal and not seen_lane:
                    edges[edge_id] = (float(el.get("length")), float(el.get("speed")))
                    seen_lane = True
                elif el.tag == "location":
                    proj = el.get("projParameter", "!")
                    has_proj = proj not in ("!", "")
            else:
                if el.tag == "edge":
                    edge_id = None
                el.clear()
    return edges, has_proj


def random_trips(tools, net, out_prefix, env, python, extra):
    script = os.path.join(tools, "randomTrips.py")
    if not os.path.exists(script):
        raise Failure(f"randomTrips.py not found at {script} (install sumo-tools or set SUMO_HOME)")
    trips, routes = out_prefix + ".trips.xml", out_prefix + ".rou.xml"
    run([python, script, "-n", net, "-o", trips, "-r", routes, "--validate",
         "--vehicle-class", "passenger", "--vclass", "passenger"] + extra,
        out_prefix + ".log", env)
    return routes


def read_routes(routes):
    """[(vehicle id, [edges])] from a duarouter route file (vehicles with embedded routes)."""
    result = []
    for _, el in ET.iterparse(routes, events=("end",)):
        if el.tag == "vehicle":
            route = el.find("route")
            if route is None:
                alts = el.find("routeDistribution")
                route = alts.findall("route")[-1] if alts is not None else None
            if route is not None and route.get("edges"):
                result.append((el.get("id"), route.get("edges").split()))
            el.clear()
    return result


def make_probes(args, tools, net, edges, env, python):
    """Routes candidate long trips and keeps N of them as probe_0 .. probe_{N-1}."""
    n_cand = max(args.drives * args.candidates, args.drives + 10)
    cand_prefix = os.path.join(args.out, "probe_candidates")
    random_trips(tools, net, cand_prefix, env, python,
                 ["--seed", str(args.seed), "--prefix", "cand_", "--begin", "0", "--end", str(n_cand),
                  "--period", "1", "--min-distance", str(args.min_distance), "--fringe-factor", "2",
                  "--remove-loops"])
    cands = []
    for vid, route in read_routes(cand_prefix + ".rou.xml"):
        if not all(e in edges for e in route):
            continue
        length = sum(edges[e][0] for e in route)
        freeflow = sum(edges[e][0] / max(edges[e][1], 0.1) for e in route)
        cands.append((vid, route, length, freeflow))
    if not cands:
        raise Failure("randomTrips produced no routable probe candidates; try a smaller --min-distance")
    rng = random.Random(args.seed)
    rng.shuffle(cands)
    # Free-flow time underestimates real travel time (junctions, signals, traffic), so a route whose
    # free-flow time reaches the minimum duration is a safe pick; fill up with the longest others.
    good = [c for c in cands if c[3] >= args.min_duration_s]
    rest = sorted((c for c in cands if c[3] < args.min_duration_s), key=lambda c: -c[3])
    chosen = (good + rest)[: args.drives]
    log(f"{len(cands)} routable candidates, {len(good)} with free-flow time >= {args.min_duration_s:g} s; "
        f"using {len(chosen)} probes")
    probes = os.path.join(args.out, "probes.rou.xml")
    with open(probes, "w") as f:
        f.write("<routes>\n")
        f.write('    <vType id="probe" vClass="passenger" color="1,0,0"/>\n')
        for i, (vid, route, length, freeflow) in enumerate(chosen):
            depart = args.probe_begin + i * args.probe_headway
            f.write(f'    <vehicle id="{PROBE_PREFIX}{i}" type="probe" depart="{depart:.2f}" departLane="best" '
                    f'departSpeed="max">\n')
            f.write(f'        <!-- from {vid}: {length:.0f} m, free-flow {freeflow:.0f} s -->\n')
            f.write(f'        <route edges={quoteattr(" ".join(route))}/>\n')
            f.write("    </vehicle>\n")
        f.write("</routes>\n")
    return probes, [f"{PROBE_PREFIX}{i}" for i in range(len(chosen))]


def make_background(args, tools, net, env, python, probe_end):
    if args.background <= 0:
        return None
    bg_end = probe_end + args.background_tail
    period = bg_end / args.background
    return random_trips(tools, net, os.path.join(args.out, "background"), env, python,
                        ["--seed", str(args.seed + 1), "--prefix", "bg_", "--begin", "0", "--end", f"{bg_end:g}",
                         "--period", f"{period:.6f}", "--min-distance", "300", "--fringe-factor", "5"])


def run_sumo(args, tools, net, route_files, probe_ids, env):
    """Runs sumo under TraCI so that it stops as soon as every probe has arrived (or at --end-s)."""
    fcd = os.path.join(args.out, "fcd.xml")
    tripinfo = os.path.join(args.out, "tripinfo.xml")
    sumo_log = os.path.join(args.out, "sumo.log")
    cmd = ["sumo", "-n", net, "-r", ",".join(route_files),
           "--begin", "0", "--end", f"{args.end_s:g}", "--step-length", "1", "--seed", str(args.seed),
           "--step-method.ballistic", "true" if args.step_method == "ballistic" else "false",
           "--fcd-output", fcd, "--fcd-output.geo", "true", "--device.fcd.explicit", ",".join(probe_ids),
           "--tripinfo-output", tripinfo, "--tripinfo-output.write-unfinished", "true",
           "--no-step-log", "true", "--ignore-route-errors", "true", "--duration-log.statistics", "true",
           "--log", sumo_log]
    if tools not in sys.path:
        sys.path.append(tools)
    os.environ["SUMO_HOME"] = env["SUMO_HOME"]
    try:
        import traci
    except ImportError as e:
        raise Failure(f"cannot import traci from {tools}: {e}")
    log("$ " + " ".join(cmd) + "   (under TraCI, stops when all probes arrived)")
    t0 = time.time()
    pending, teleported = set(probe_ids), set()
    with open(os.path.join(args.out, "sumo.stdout.log"), "w") as out:
        try:
            traci.start(cmd, stdout=out)
            while pending and traci.simulation.getTime() < args.end_s:
                traci.simulationStep()
                pending.difference_update(traci.simulation.getArrivedIDList())
                teleported.update(v for v in traci.simulation.getStartingTeleportIDList() if v.startswith(PROBE_PREFIX))
                if traci.simulation.getMinExpectedNumber() == 0:
                    break
            end = traci.simulation.getTime()
            traci.close()
        except traci.exceptions.TraCIException as e:
            raise Failure(f"sumo failed: {e}; see {sumo_log}")
        except traci.exceptions.FatalTraCIError as e:
            raise Failure(f"sumo failed: {e}; see {sumo_log}")
    log(f"sumo stopped at t={end:g} s ({len(pending)} probes still driving) after {time.time() - t0:.0f} s wall time")
    return fcd, tripinfo, sumo_log, teleported


def haversine(lon1, lat1, lon2, lat2):
    r = 6371008.8
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dp, dl = p2 - p1, math.radians(lon2 - lon1)
    a = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
    return 2 * r * math.asin(math.sqrt(min(1.0, a)))


def read_fcd(fcd, probe_ids):
    """Per probe: samples, first/last time, geo path length, largest time gap, whether coords look geo."""
    wanted = set(probe_ids)
    stats = {}
    now = None
    for event, el in ET.iterparse(fcd, events=("start", "end")):
        if event == "start":
            if el.tag == "timestep":
                now = float(el.get("time"))
            continue
        if el.tag == "vehicle":
            vid = el.get("id")
            if vid in wanted:
                x, y = float(el.get("x")), float(el.get("y"))
                s = stats.get(vid)
                if s is None:
                    s = stats[vid] = {"samples": 0, "first": now, "last": now, "geo_length": 0.0, "max_gap": 0.0,
                                      "lon": x, "lat": y, "geo": True}
                else:
                    s["geo_length"] += haversine(s["lon"], s["lat"], x, y)
                    s["max_gap"] = max(s["max_gap"], now - s["last"])
                    s["last"], s["lon"], s["lat"] = now, x, y
                s["samples"] += 1
                if not (-180.0 <= x <= 180.0 and -90.0 <= y <= 90.0):
                    s["geo"] = False
        elif el.tag == "timestep":
            el.clear()
    return stats


def read_tripinfo(tripinfo, probe_ids):
    wanted = set(probe_ids)
    info = {}
    for _, el in ET.iterparse(tripinfo, events=("end",)):
        if el.tag == "tripinfo":
            if el.get("id") in wanted:
                info[el.get("id")] = {k: el.get(k) for k in (
                    "depart", "arrival", "duration", "routeLength", "waitingTime", "waitingCount", "timeLoss",
                    "rerouteNo", "vaporized")}
            el.clear()
    return info


def read_teleports(sumo_log):
    """Vehicle ids that SUMO teleported (their trajectories jump, so they are no ground truth)."""
    teleported = set()
    if os.path.exists(sumo_log):
        pat = re.compile(r"Teleporting vehicle '([^']+)'")
        with open(sumo_log, errors="replace") as f:
            for line in f:
                m = pat.search(line)
                if m:
                    teleported.add(m.group(1))
    return teleported


def summarise(args, name, probe_ids, fcd, tripinfo, sumo_log, teleported):
    samples = read_fcd(fcd, probe_ids)
    trips = read_tripinfo(tripinfo, probe_ids)
    teleported = teleported | read_teleports(sumo_log)
    drives, rejected = [], []
    for vid in probe_ids:
        s, t = samples.get(vid), trips.get(vid)
        reason = None
        if s is None or t is None:
            reason = "never inserted"
        elif float(t["arrival"]) < 0:
            reason = f"did not arrive by the end time ({args.end_s:g} s)"
        elif t.get("vaporized"):
            reason = f"removed by SUMO ({t['vaporized']})"
        elif vid in teleported:
            reason = "teleported (trajectory jumps)"
        elif s["max_gap"] > 1.5:
            reason = f"gap of {s['max_gap']:g} s in fcd samples"
        elif not s["geo"]:
            reason = "fcd coordinates are not lon/lat"
        elif float(t["duration"]) < args.min_duration_s:
            reason = f"shorter than {args.min_duration_s:g} s ({float(t['duration']):g} s)"
        if reason:
            rejected.append({"id": vid, "reason": reason})
            continue
        drives.append({
            "id": vid,
            "depart_s": float(t["depart"]),
            "arrival_s": float(t["arrival"]),
            "duration_s": float(t["duration"]),
            "samples": s["samples"],
            "first_sample_s": s["first"],
            "last_sample_s": s["last"],
            "length_m": round(float(t["routeLength"]), 1),
            "geo_path_length_m": round(s["geo_length"], 1),
            "waiting_time_s": float(t["waitingTime"]),
            "stops": int(t["waitingCount"]),
            "time_loss_s": float(t["timeLoss"]),
        })
    result = {
        "map": name,
        "osm": os.path.abspath(args.osm),
        "net": os.path.abspath(os.path.join(args.out, name + ".net.xml")),
        "fcd": os.path.abspath(fcd),
        "fcd_format": "per <timestep time=s>: <vehicle id x=lon y=lat angle=deg(0=north, clockwise) "
                      "speed=m/s lane pos=m .../>",
        "step_length_s": 1.0,
        "step_method": args.step_method,
        "seed": args.seed,
        "requested_drives": args.drives,
        "background_vehicles": args.background,
        "min_duration_s": args.min_duration_s,
        "end_s": args.end_s,
        "drives": drives,
        "rejected": rejected,
    }
    with open(os.path.join(args.out, "drives.json"), "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")
    return drives, rejected


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--osm", required=True, help="OSM extract (.osm, .osm.gz or .osm.pbf)")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--drives", type=int, default=12, help="number of probe drives")
    ap.add_argument("--seed", type=int, default=42)
    ap.add_argument("--min-duration-s", type=float, default=180.0, help="drop probe drives shorter than this")
    ap.add_argument("--background", type=int, default=300, help="number of background vehicles (0: none)")
    ap.add_argument("--min-distance", type=float, default=1500.0,
                    help="straight-line distance between probe origin and destination (m)")
    ap.add_argument("--candidates", type=int, default=4, help="candidate trips routed per probe")
    ap.add_argument("--probe-begin", type=float, default=120.0, help="departure of probe_0 (s)")
    ap.add_argument("--probe-headway", type=float, default=30.0, help="time between probe departures (s)")
    ap.add_argument("--background-tail", type=float, default=900.0,
                    help="background departures continue this long after the last probe departs (s)")
    ap.add_argument("--end-s", type=float, default=3600.0, help="simulation end time (s)")
    ap.add_argument("--rebuild", action="store_true", help="rebuild the net even if it is up to date")
    # SUMO's default (Euler) update moves a vehicle by its end-of-step speed over the whole step, so
    # the speed written with a position is not the rate at which the positions change: a vehicle
    # braking to a stop covers less ground than its speeds say, which puts a speed-aided smoother a
    # few metres ahead of it at every stop. The ballistic update moves it by the mean of the two
    # speeds, as a body with constant acceleration over the step moves, and a receiver's Doppler
    # speed is that rate. docs/experiments/localization.md gives the figures with both.
    ap.add_argument("--step-method", choices=("ballistic", "euler"), default="ballistic",
                    help="SUMO's position update (default ballistic: positions integrate the speeds)")
    args = ap.parse_args()

    if args.drives < 1:
        ap.error("--drives must be at least 1")
    if not os.path.exists(args.osm):
        ap.error(f"OSM file '{args.osm}' does not exist")
    for tool in ("netconvert", "sumo"):
        if not shutil.which(tool):
            ap.error(f"{tool} is not installed (SUMO)")
    sumo_home = os.environ.get("SUMO_HOME") or "/usr/share/sumo"
    tools = os.path.join(sumo_home, "tools")
    env = dict(os.environ, SUMO_HOME=sumo_home)
    python = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
    os.makedirs(args.out, exist_ok=True)
    for stale in ("fcd.xml", "tripinfo.xml", "drives.json", "sumo.log"):
        if os.path.exists(os.path.join(args.out, stale)):
            os.remove(os.path.join(args.out, stale))

    t0 = time.time()
    name = osm_name(args.osm)
    net = build_net(args.osm, args.out, env, args.rebuild)
    edges, has_proj = read_net(net)
    if not has_proj:
        raise Failure(f"{net} has no geo projection; fcd cannot be written as lon/lat")
    probes, probe_ids = make_probes(args, tools, net, edges, env, python)
    probe_end = args.probe_begin + (len(probe_ids) - 1) * args.probe_headway
    background = make_background(args, tools, net, env, python, probe_end)
    fcd, tripinfo, sumo_log, teleported = run_sumo(args, tools, net, [probes] + ([background] if background else []),
                                                   probe_ids, env)
    drives, rejected = summarise(args, name, probe_ids, fcd, tripinfo, sumo_log, teleported)

    for r in rejected:
        log(f"dropped {r['id']}: {r['reason']}")
    if drives:
        durs = [d["duration_s"] for d in drives]
        lens = [d["length_m"] for d in drives]
        span = (f"duration {min(durs):.0f}-{max(durs):.0f} s (median {sorted(durs)[len(durs) // 2]:.0f}), "
                f"length {min(lens) / 1000:.1f}-{max(lens) / 1000:.1f} km (total {sum(lens) / 1000:.1f} km)")
    else:
        span = "no drives"
    print(f"{name}: {len(drives)}/{len(probe_ids)} usable drives, {span}, "
          f"{sum(d['samples'] for d in drives)} fcd samples -> {os.path.join(args.out, 'drives.json')} "
          f"({time.time() - t0:.0f} s)")
    if len(drives) < args.drives / 2:
        raise Failure(f"only {len(drives)} usable drives of {args.drives} requested (need at least "
                      f"{args.drives / 2:g}); see 'rejected' in {os.path.join(args.out, 'drives.json')}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Failure as e:
        print(f"sumo_fcd_drives: error: {e}", file=sys.stderr)
        sys.exit(1)
