#!/usr/bin/env bash
# `corridor vo synth` and `corridor vo run` end to end: a short synthetic drive on the embedded map,
# the odometry's JSON contract, the plot, the shared KITTI clips, and errors a user can act on.
# Usage: vo_cli_test.sh CORRIDOR SHARED_DATA_DIR
set -euo pipefail
corridor=$1
shared=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }

"$corridor" vo synth --out seq --length-m 80 --seed 3 --min-turn-deg 45 > synth.json
/usr/bin/python3 - synth.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["frames"] > 60 and abs(j["length_m"] - 80) < 2, j
assert j["width"] == 640 and j["height"] == 480 and j["baseline_m"] == 0.3, j
PY
[[ -f seq/calib.txt && -f seq/poses.txt && -f seq/image_0/000000.png && -f seq/image_1/000000.png ]] || fail "synth layout"
[[ $(ls seq/image_0 | wc -l) == $(wc -l < seq/poses.txt) ]] || fail "one pose per frame"

"$corridor" vo run --seq seq --eval --json --out poses.txt --plot traj.png > run.json
/usr/bin/python3 - run.json <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for key in ("t_err_pct", "r_err_deg_per_100m", "ate_rmse_m", "drift_pct", "fps"):
    assert key in j, key
assert j["drift_pct"] < 2.0, j
assert j["ate_rmse_m"] < 0.5, j
assert j["fps"] > 0, j
PY
[[ $(wc -l < poses.txt) == $(wc -l < seq/poses.txt) ]] || fail "estimated poses per frame"
head -c 8 traj.png | od -An -c | grep -q "P   N   G" || fail "plot is not a PNG"

# The human-readable form names every metric.
"$corridor" vo run --seq seq --eval --plot "" --max-frames 30 | grep -q "^t_err" || fail "text output"

# The shared real KITTI clips: short, so scored on 10-50 m segments; the drift stays bounded.
for clip in kitti_clip_1 kitti_clip_2; do
  [[ -d $shared/stereo/$clip ]] || continue
  "$corridor" vo run --seq "$shared/stereo/$clip" --eval --json --out "$clip.txt" --plot "" > "$clip.json"
  /usr/bin/python3 - "$clip.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["drift_pct"] < 5.0 and j["bridged_frames"] == 0, j
PY
done

# Errors: exit 2 for usage, 1 for unusable data, with a message that says what is wrong.
set +e
"$corridor" vo run --seq does-not-exist 2> err.txt; rc=$?
[[ $rc == 1 ]] && grep -q "does not exist" err.txt || fail "missing sequence: rc=$rc $(cat err.txt)"
mkdir noposes && cp -r seq/image_0 seq/image_1 seq/calib.txt noposes/
"$corridor" vo run --seq noposes --eval 2> err.txt; rc=$?
[[ $rc == 2 ]] && grep -q "ground truth" err.txt || fail "--eval without poses: rc=$rc $(cat err.txt)"
"$corridor" vo run --seq seq --detector star 2> err.txt; rc=$?
[[ $rc == 2 ]] && grep -q "censure, fast or harris" err.txt || fail "bad detector: rc=$rc"
"$corridor" vo synth --out x --length-m 5 2> err.txt; rc=$?
[[ $rc == 2 ]] || fail "too short a drive: rc=$rc"
echo "garbage" > noposes/calib.txt
"$corridor" vo run --seq noposes 2> err.txt; rc=$?
[[ $rc == 1 ]] && grep -q "P0 and P1" err.txt || fail "bad calibration: rc=$rc $(cat err.txt)"
set -e
echo "vo cli: all checks passed"
