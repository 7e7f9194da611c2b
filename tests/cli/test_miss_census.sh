#!/usr/bin/env bash
# tools/miss-census on a shape the simulator makes: every top pipe that `score --misses` lists is
# classed once, by the poses `locate --traces` reports; a folder that is no shape is refused.
source "$(dirname "$0")/common.sh" "$@"

# A long thin Z under the stereo sensor at 1.1 m: some top pipes are missed.
mkdir -p "$work/z"
"$bin" make-pipe --path S100,B90r101,S65,B-90r101,S130 --diameter 14 --out "$work/z/pipe.stl" > /dev/null 2>&1
"$bin" simulate --model "$work/z/pipe.stl" --images 2 --pipes 20 --seed 5 --sensor stereo \
  --camera-height-mm 1100 1150 --out "$work/z/data" > /dev/null 2>&1

"$here/tools/miss-census" --bin "$bin" --json "$work/census.json" "$work/z" > "$work/census.txt" 2>&1 ||
  fail "tools/miss-census failed: $(tail -5 "$work/census.txt")"
grep -qE '^all +[0-9]' "$work/census.txt" || fail "no 'all' row: $(cat "$work/census.txt")"
grep -q 'A1 no candidate region on it' "$work/census.txt" || fail "the classes are not explained"

# The same misses, counted by the scorer itself.
"$bin" eval-bop --dataset "$work/z/data" --out "$work/r.csv" > /dev/null 2>&1
"$bin" score --dataset "$work/z/data" --results "$work/r.csv" --misses "$work/misses.csv" > /dev/null
misses=$(($(wc -l < "$work/misses.csv") - 1))
[ "$misses" -ge 1 ] || fail "no miss to class: the test's shape became too easy"
python3 - "$work/census.json" "$misses" <<'PY' || fail "classes do not add up: $(cat "$work/census.txt")"
import json, sys
c = json.load(open(sys.argv[1]))
assert set(c["all"]) == {"E", "D", "C", "B", "A2", "A1"}, c["all"]
assert sum(c["all"].values()) == int(sys.argv[2]), (c["all"], sys.argv[2])
assert c["shapes"]["z"] == c["all"], c
PY

# Not a shape folder: exit 2, naming it.
mkdir -p "$work/empty"
set +e
"$here/tools/miss-census" --bin "$bin" "$work/empty" > "$work/err.txt" 2>&1
status=$?
set -e
[ "$status" -eq 2 ] || fail "a folder without a shape exited $status, not 2"
grep -q "$work/empty" "$work/err.txt" || fail "the error does not name the folder: $(cat "$work/err.txt")"
echo "1 passed, 0 failed"
