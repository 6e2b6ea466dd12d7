#!/usr/bin/env bash
# `corridor experiment analytical` end to end: output files, determinism, and clear usage errors.
# Usage: experiment_cli_test.sh CORRIDOR_BINARY SHARED_DATA_DIR
set -euo pipefail
corridor=$1
data=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

"$corridor" experiment analytical --graph simple --graph complex --out "$work/a" --seed 3 > "$work/a.txt"
"$corridor" experiment analytical --graph complex --graph simple --out "$work/b" --seed 3 --threads 1 > /dev/null
for f in simple_fig5 complex_fig6 complex_fig7 complex_fig8a complex_fig8b complex_fig9; do
  for ext in .csv _summary.csv .svg; do
    [[ -s $work/a/$f$ext ]] || fail "missing $f$ext"
  done
  cmp -s "$work/a/$f.csv" "$work/b/$f.csv" || fail "$f.csv differs between runs with the same seed"
done
[[ -s $work/a/simple_report.md && -s $work/a/complex_report.md ]] || fail "missing Markdown reports"
grep -q "### simple fig5" "$work/a.txt" || fail "summary not printed"

# A graph file of our own is accepted and named by its "name".
cat > "$work/tri.json" <<'JSON'
{"format":"corridor-analytical-graph","version":1,"name":"tri","speed_kmh":120,"source":"x","destination":"z",
 "nodes":[{"id":"x","x_km":0,"y_km":0},{"id":"y","x_km":1,"y_km":1},{"id":"z","x_km":2,"y_km":0},{"id":"w","x_km":1,"y_km":-1}],
 "edges":[{"from":"x","to":"y","length_km":1.5},{"from":"y","to":"z","length_km":1.5},
          {"from":"x","to":"w","length_km":1.6},{"from":"w","to":"z","length_km":1.6}]}
JSON
"$corridor" experiment analytical --graph "$work/tri.json" --out "$work/c" --runs 4 --level-runs 5 > /dev/null
[[ -s $work/c/tri_levels.csv && -s $work/c/tri_fig9.svg ]] || fail "custom graph outputs missing"

# An OSM map runs the map protocol.
"$corridor" experiment analytical --graph "$data/osm/monaco.osm.gz" --pairs 20 --out "$work/m" --no-cache > /dev/null
[[ -s $work/m/monaco_fig9.csv && -s $work/m/monaco_levels.svg ]] || fail "map outputs missing"

expect_error() {
  local code=$1 pattern=$2
  shift 2
  set +e
  "$corridor" "$@" > "$work/out.txt" 2> "$work/err.txt"
  local rc=$?
  set -e
  [[ $rc == "$code" ]] || fail "exit $rc (want $code) for: $*"
  grep -q -- "$pattern" "$work/err.txt" || fail "no '$pattern' in: $(cat "$work/err.txt")"
}
expect_error 2 "is none of these" experiment analytical --graph nowhere --out "$work/x"
expect_error 2 "at least 1" experiment analytical --graph simple --out "$work/x" --runs 0
expect_error 2 "threads" experiment analytical --graph simple --out "$work/x" --threads 0
echo '{"format":"corridor-analytical-graph","version":1,"speed_kmh":120,' > "$work/bad.json"
expect_error 1 "not valid JSON" experiment analytical --graph "$work/bad.json" --out "$work/x"
expect_error 2 "required" experiment analytical --graph simple
touch "$work/file"
expect_error 2 "cannot create" experiment analytical --graph simple --out "$work/file/sub"

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "experiment CLI: all checks passed"
