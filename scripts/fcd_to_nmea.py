#!/usr/bin/python3
"""Writes what a GNSS receiver would have said during a SUMO drive: an NMEA 0183 log (GGA, GSA, GSV,
RMC at 1 Hz, with checksums) from one vehicle's geo fcd output, and the drive's truth as CSV.

    fcd_to_nmea.py --fcd fcd.xml --vehicle probe_0 --out drive.nmea --truth truth.csv
        [--noise-m 3] [--outage START:END] [--speed-without-fix START:END]
        [--garbage 0.05] [--bad-checksums 0.05] [--start-unix T] [--seed 1]

--outage: no fix at all (GGA quality 0, RMC status V, GSA mode 1). --speed-without-fix: a receiver
that still reports speed and course (RMC V) but no position. --garbage: the share of epochs followed
by a line of noise; --bad-checksums: the share of sentences sent with a wrong checksum. Windows are
seconds from the drive's first sample. Times start at --start-unix (default: now minus the drive's
length, so that the fixes are recent but never ahead of the clock).
"""
import argparse
import datetime as dt
import math
import random
import sys
import time
import xml.etree.ElementTree as ET

KNOTS_PER_MPS = 1.0 / 0.514444
EARTH_M = 6371008.8
SATELLITES = [(2, 65, 40, 45), (5, 30, 110, 40), (9, 45, 200, 42), (12, 20, 300, 35), (17, 75, 250, 47), (21, 15, 160, 33),
              (25, 40, 340, 41), (29, 55, 80, 44)]


def checksum(body):
    c = 0
    for ch in body.encode("ascii"):
        c ^= ch
    return c


def sentence(body, wrong=False):
    return "$%s*%02X" % (body, checksum(body) ^ (0x5A if wrong else 0))


def ddmm(value, degrees_digits):
    a = abs(value)
    d = int(a)
    m = (a - d) * 60.0
    if round(m, 4) >= 60.0:
        d, m = d + 1, 0.0
    return ("%0" + str(degrees_digits) + "d%07.4f") % (d, m)


def window(spec):
    if not spec:
        return None
    a, b = spec.split(":")
    return float(a), float(b)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fcd", required=True)
    ap.add_argument("--vehicle", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--truth")
    ap.add_argument("--noise-m", type=float, default=3.0)
    ap.add_argument("--hdop", type=float, default=1.0)
    ap.add_argument("--outage")
    ap.add_argument("--speed-without-fix")
    ap.add_argument("--garbage", type=float, default=0.0)
    ap.add_argument("--bad-checksums", type=float, default=0.0)
    ap.add_argument("--start-unix", type=float)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    samples = []
    for _, e in ET.iterparse(a.fcd, events=("end",)):
        if e.tag == "timestep":
            t = float(e.get("time"))
            for v in e.iter("vehicle"):
                if v.get("id") == a.vehicle:
                    samples.append((t, float(v.get("y")), float(v.get("x")), float(v.get("speed")), float(v.get("angle"))))
            e.clear()
    if len(samples) < 2:
        sys.exit(f"fcd_to_nmea: vehicle {a.vehicle} has {len(samples)} samples in {a.fcd}")
    t0 = samples[0][0]
    duration = samples[-1][0] - t0
    start = a.start_unix if a.start_unix is not None else time.time() - duration - 5.0
    outage, nofix = window(a.outage), window(a.speed_without_fix)
    counts = {"epochs": 0, "fixes": 0, "outage": 0, "speed_without_fix": 0, "garbage": 0, "bad_checksums": 0}
    truth = open(a.truth, "w") if a.truth else None
    if truth:
        truth.write("time,lat,lon,speed_mps,heading_deg\n")
    with open(a.out, "w", newline="") as out:
        def put(body):
            wrong = rng.random() < a.bad_checksums
            counts["bad_checksums"] += 1 if wrong else 0
            out.write(sentence(body, wrong) + "\r\n")

        for t, lat, lon, speed, angle in samples:
            rel = t - t0
            when = dt.datetime.fromtimestamp(start + rel, dt.timezone.utc)
            hms = when.strftime("%H%M%S") + ".%02d" % (when.microsecond // 10000)
            dmy = when.strftime("%d%m%y")
            if truth:
                truth.write(f"{start + rel:.3f},{lat:.7f},{lon:.7f},{speed:.2f},{angle:.1f}\n")
            state = "fix"
            if outage and outage[0] <= rel < outage[1]:
                state = "outage"
            elif nofix and nofix[0] <= rel < nofix[1]:
                state = "speed_without_fix"
            counts["epochs"] += 1
            counts["fixes" if state == "fix" else state] += 1
            n = math.radians(lat)
            plat = lat + math.degrees(rng.gauss(0, a.noise_m) / EARTH_M)
            plon = lon + math.degrees(rng.gauss(0, a.noise_m) / (EARTH_M * math.cos(n)))
            la, ns = ddmm(plat, 2), "N" if plat >= 0 else "S"
            lo, ew = ddmm(plon, 3), "E" if plon >= 0 else "W"
            kn, course = "%.2f" % (speed * KNOTS_PER_MPS), "%.2f" % (angle % 360.0)
            if state == "fix":
                put("GPGGA,%s,%s,%s,%s,%s,1,%02d,%.1f,50.0,M,47.0,M,," % (hms, la, ns, lo, ew, len(SATELLITES), a.hdop))
                used = ",".join("%02d" % s[0] for s in SATELLITES) + "," * (12 - len(SATELLITES))
                put("GPGSA,A,3,%s,%.1f,%.1f,%.1f" % (used, a.hdop * 1.6, a.hdop, a.hdop * 1.3))
                for k in range(2):
                    sats = SATELLITES[4 * k:4 * k + 4]
                    put("GPGSV,2,%d,%02d,%s" % (k + 1, len(SATELLITES), ",".join("%02d,%02d,%03d,%02d" % s for s in sats)))
                put("GPRMC,%s,A,%s,%s,%s,%s,%s,%s,%s,,,A" % (hms, la, ns, lo, ew, kn, course, dmy))
            elif state == "speed_without_fix":
                put("GPGGA,%s,,,,,0,00,,,M,,M,," % hms)
                put("GPRMC,%s,V,,,,,%s,%s,%s,,,N" % (hms, kn, course, dmy))
            else:
                put("GPGGA,%s,,,,,0,00,,,M,,M,," % hms)
                put("GPGSA,A,1,,,,,,,,,,,,,,,")
                put("GPRMC,%s,V,,,,,,,%s,,,N" % (hms, dmy))
            if rng.random() < a.garbage:
                counts["garbage"] += 1
                out.write("".join(rng.choice("abcXYZ0123456789,.;:#@ ") for _ in range(rng.randrange(5, 50))) + "\r\n")
    if truth:
        truth.close()
    print(" ".join(f"{k}={v}" for k, v in counts.items()))


if __name__ == "__main__":
    main()
