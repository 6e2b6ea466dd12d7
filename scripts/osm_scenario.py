#!/usr/bin/python3
"""Builds a SUMO scenario from an OpenStreetMap extract, as a traffic engineer would: a net with
signals guessed and joined, joined junctions (netconvert's cluster_* junctions), OSM's lane access
tags read, and bus lanes on a share of the multi-lane arterials (their rightmost lane allow="bus"),
plus random passenger demand over one hour and a .sumocfg. Corridor has never seen such a scenario:
it is what `corridor experiment sumo --scenario DIR/NAME.sumocfg` is tried on.

Usage: osm_scenario.py --osm FILE --out DIR [--bbox W,S,E,N] [--name NAME] [--bus-lane-share 0.33]
                       [--vph 1500] [--seed 1]
Needs SUMO's netconvert and tools (SUMO_HOME, default /usr/share/sumo) and osmium-tool.
"""
import argparse
import os
import random
import subprocess
import sys

SUMO_HOME = os.environ.setdefault("SUMO_HOME", "/usr/share/sumo")
sys.path.append(os.path.join(SUMO_HOME, "tools"))
import sumolib  # noqa: E402

ARTERIALS = {"highway.trunk", "highway.primary", "highway.secondary", "highway.tertiary"}


def run(cmd, log):
    with open(log, "w") as out:
        if subprocess.call(cmd, stdout=out, stderr=subprocess.STDOUT) != 0:
            sys.exit(f"osm_scenario: {' '.join(cmd)} failed; see {log}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--osm", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bbox", help="W,S,E,N in degrees: cut the extract to this box first")
    ap.add_argument("--name", default="osm")
    ap.add_argument("--bus-lane-share", type=float, default=1 / 3,
                    help="share of the multi-lane arterials whose rightmost lane becomes a bus lane")
    ap.add_argument("--vph", type=float, default=1500.0, help="passenger vehicles per hour of demand")
    ap.add_argument("--end", type=float, default=3600.0)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    if not 0.0 <= a.bus_lane_share <= 1.0:
        sys.exit("osm_scenario: --bus-lane-share must be in [0, 1]")
    os.makedirs(a.out, exist_ok=True)
    osm = a.osm
    if a.bbox:
        osm = os.path.join(a.out, a.name + ".osm.gz")
        run(["osmium", "extract", "--overwrite", "-b", a.bbox, a.osm, "-o", osm], os.path.join(a.out, "osmium.log"))
    elif osm.endswith(".pbf"):
        osm = os.path.join(a.out, a.name + ".osm.gz")
        run(["osmium", "cat", "--overwrite", a.osm, "-o", osm], os.path.join(a.out, "osmium.log"))
    base = os.path.join(a.out, a.name + ".base.net.xml")
    run(["netconvert", "--osm-files", osm, "--geometry.remove", "--ramps.guess", "--junctions.join",
         "--tls.guess-signals", "--tls.discard-simple", "--tls.join", "--osm.lane-access", "true",
         "--keep-edges.by-vclass", "passenger,bus", "--remove-edges.isolated", "--no-turnarounds", "true",
         "--no-warnings", "-o", base], os.path.join(a.out, "netconvert.log"))

    net = sumolib.net.readNet(base)
    arterials = sorted((e for e in net.getEdges() if e.getFunction() == "" and e.getLaneNumber() >= 2
                        and e.getType() in ARTERIALS), key=lambda e: e.getID())
    rng = random.Random(a.seed)
    bus = rng.sample(arterials, int(round(len(arterials) * a.bus_lane_share)))
    patch = os.path.join(a.out, a.name + ".bus.edg.xml")
    with open(patch, "w") as f:
        f.write("<edges>\n")
        for e in bus:
            f.write(f'  <edge id="{e.getID()}"><lane index="0" allow="bus"/></edge>\n')
        f.write("</edges>\n")
    net_file = os.path.join(a.out, a.name + ".net.xml")
    run(["netconvert", "--sumo-net-file", base, "-e", patch, "--no-warnings", "-o", net_file],
        os.path.join(a.out, "netconvert-bus.log"))

    routes = os.path.join(a.out, a.name + ".rou.xml")
    run(["/usr/bin/python3", os.path.join(SUMO_HOME, "tools", "randomTrips.py"), "-n", net_file,
         "-o", os.path.join(a.out, a.name + ".trips.xml"), "-r", routes, "--seed", str(a.seed), "--begin", "0",
         "--end", f"{a.end:g}", "--period", f"{3600.0 / a.vph:.6f}", "--fringe-factor", "5",
         "--min-distance", "300", "--prefix", "veh", "--validate"], os.path.join(a.out, "randomTrips.log"))
    cfg = os.path.join(a.out, a.name + ".sumocfg")
    with open(cfg, "w") as f:
        f.write(f"""<configuration>
  <input>
    <net-file value="{os.path.basename(net_file)}"/>
    <route-files value="{os.path.basename(routes)}"/>
  </input>
  <time><begin value="0"/><end value="{a.end:g}"/></time>
  <processing><time-to-teleport value="300"/><ignore-route-errors value="true"/></processing>
  <report><log value="{a.name}.log"/></report>
</configuration>
""")
    tls = sum(1 for _ in net.getTrafficLights())
    clusters = sum(1 for n in net.getNodes() if n.getID().startswith("cluster"))
    print(f"{cfg}: {len(net.getEdges())} edges, {tls} traffic lights, {clusters} joined junctions, "
          f"{len(bus)} of {len(arterials)} multi-lane arterials with a bus lane")


if __name__ == "__main__":
    main()
