#!/usr/bin/env python3
"""The map-matching study over maps, GPS noise levels and seeds, as docs/experiments/localization.md
reports it: means over seeds of `corridor bench match --fcd ...` (correct edge by time, RMSE, RMSE
over the fixes with a true edge, and the share of a 60 s outage on the correct edge).

    scripts/sumo_fcd_drives.py --osm ../shared/data/osm/monaco.osm.gz --out /tmp/fcd/monaco   # once per map
    scripts/match_grid.py --fcd-root /tmp/fcd --seeds 1-10 --label HEAD

FCD_ROOT holds one folder per map, named as the OSM file's first dot-separated part (monaco,
liechtenstein, andorra, porto), each with the fcd.xml that sumo_fcd_drives.py wrote. Runs go two
at a time. --json FILE keeps every run's totals, so two labels can be compared cell by cell with
--compare OLD.json NEW.json. Extra arguments after -- go to `corridor bench match`.
"""

import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

MAPS = {
    "liechtenstein": "liechtenstein.osm.pbf",
    "andorra": "andorra.osm.pbf",
    "monaco": "monaco.osm.gz",
    "porto": "porto.osm.pbf",
}
FIGURES = [
    ("correct_edge_hmm_by_time", "edge %", 100.0, 2),
    ("rmse_hmm_m", "RMSE m", 1.0, 2),
    ("rmse_hmm_on_graph_m", "RMSE on graph m", 1.0, 2),
    ("outage_correct_edge_share", "outage %", 100.0, 2),
    ("outage_rmse_m", "outage RMSE m", 1.0, 1),
]


def seeds_of(text):
    out = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            out.extend(range(int(a), int(b) + 1))
        else:
            out.append(int(part))
    return out


def run_one(args, name, sigma, seed):
    fcd = os.path.join(args.fcd_root, name, "fcd.xml")
    cmd = [args.bin, "bench", "match", "--map", os.path.join(args.osm_dir, MAPS[name]), "--fcd", fcd,
           "--prefix", "probe_", "--noise-m", str(sigma), "--outage-s", str(args.outage_s),
           "--outliers", str(args.outliers), "--seed", str(seed)] + args.extra
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return (name, sigma, seed), json.loads(out)["total"]


def means(results, keys):
    table = {}
    for (name, sigma, _seed), total in results.items():
        cell = table.setdefault((name, sigma), {k: [] for k, *_ in FIGURES})
        for k, *_ in FIGURES:
            cell[k].append(total[k])
    return {key: {k: sum(v) / len(v) for k, v in cell.items()} for key, cell in table.items() if key in keys}


def print_table(label, cells, sigmas, names):
    print(f"## {label}")
    print("| map | σ | " + " | ".join(h for _, h, *_ in FIGURES) + " |")
    print("|---|---|" + "---|" * len(FIGURES))
    for name in names:
        for sigma in sigmas:
            c = cells.get((name, sigma))
            if c:
                print(f"| {name} | {sigma:g} | " + " | ".join(f"{c[k] * s:.{d}f}" for k, _, s, d in FIGURES) + " |")


def load(path):
    with open(path) as f:
        raw = json.load(f)
    return {(r["map"], r["sigma"], r["seed"]): r["total"] for r in raw["runs"]}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bin", default="build/app/corridor")
    p.add_argument("--fcd-root", default="/tmp/fcd")
    p.add_argument("--osm-dir", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "osm"))
    p.add_argument("--maps", default="liechtenstein,andorra,monaco,porto")
    p.add_argument("--sigmas", default="5,10,15")
    p.add_argument("--seeds", default="1-10")
    p.add_argument("--outage-s", type=float, default=60.0)
    p.add_argument("--outliers", type=float, default=0.02)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--label", default="run")
    p.add_argument("--json", help="write every run's totals here")
    p.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="compare two --json files, cell by cell")
    p.add_argument("extra", nargs="*", help="after --: more arguments for bench match")
    args = p.parse_args()
    names = [n for n in args.maps.split(",") if n]
    sigmas = [float(s) for s in args.sigmas.split(",")]
    if args.compare:
        old, new = load(args.compare[0]), load(args.compare[1])
        common = set(old) & set(new)
        keys = {(n, s) for n, s, _ in common}
        a, b = means({k: old[k] for k in common}, keys), means({k: new[k] for k in common}, keys)
        print(f"## {args.compare[0]} → {args.compare[1]} ({len(common)} runs in common)")
        print("| map | σ | " + " | ".join(h for _, h, *_ in FIGURES) + " |")
        print("|---|---|" + "---|" * len(FIGURES))
        for name in names:
            for sigma in sigmas:
                if (name, sigma) in a:
                    print(f"| {name} | {sigma:g} | " + " | ".join(
                        f"{a[(name, sigma)][k] * s:.{d}f} → {b[(name, sigma)][k] * s:.{d}f}" for k, _, s, d in FIGURES) + " |")
        return 0
    for name in names:
        if name not in MAPS:
            sys.exit(f"unknown map {name}; known: {', '.join(MAPS)}")
        if not os.path.exists(os.path.join(args.fcd_root, name, "fcd.xml")):
            sys.exit(f"no {args.fcd_root}/{name}/fcd.xml: run scripts/sumo_fcd_drives.py first")
    jobs = [(n, s, seed) for n in names for s in sigmas for seed in seeds_of(args.seeds)]
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for key, total in pool.map(lambda j: run_one(args, *j), jobs):
            results[key] = total
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"label": args.label, "runs": [{"map": k[0], "sigma": k[1], "seed": k[2], "total": v}
                                                      for k, v in results.items()]}, f)
    print_table(f"{args.label}: means over seeds {args.seeds}", means(results, {(n, s) for n in names for s in sigmas}),
                sigmas, names)
    return 0


if __name__ == "__main__":
    sys.exit(main())
