#!/usr/bin/env bash
# The offline tools on a dataset the project makes itself: simulate -> eval-bop -> score, and
# bench --dataset on the same frames; a missing dataset is refused with a message naming it.
source "$(dirname "$0")/common.sh" "$@"

"$bin" make-pipe --preset u --out "$work/u.stl" > /dev/null 2>&1
"$bin" simulate --model "$work/u.stl" --images 2 --pipes 8 --seed 3 --out "$work/ds" > /dev/null 2>&1

"$bin" eval-bop --dataset "$work/ds" --out "$work/r.csv" > /dev/null 2>&1
rows=$(($(wc -l < "$work/r.csv") - 1))
[ "$rows" -ge 2 ] || fail "eval-bop wrote $rows result rows for 2 images of 8 pipes"
"$bin" score --dataset "$work/ds" --results "$work/r.csv" > "$work/score.txt"
grep -qE '^all +2 ' "$work/score.txt" || fail "score has no 'all' row over 2 images: $(cat "$work/score.txt")"

# locate's stdout is its JSON lines alone (log lines go to stderr), so that it can be piped.
"$bin" locate --depth "$work/ds/test/000001/depth/000000.png" --camera "$work/ds/test/000001/scene_camera.json" \
  --model "$work/u.stl" --traces > "$work/locate.jsonl" 2> "$work/locate.log"
python3 - "$work/locate.jsonl" <<'PY' || fail "locate stdout is not JSON lines alone: $(head -3 "$work/locate.jsonl")"
import json, sys
objects = [json.loads(line) for line in open(sys.argv[1]).read().splitlines()]
assert any("outcome" in o for o in objects), "no candidate trace"
# Each candidate's trace holds the poses it reached: its ridge fits and the hypotheses refined.
traces = [o for o in objects if "outcome" in o]
for t in traces:
    for f in t["ridge_fits"] + t["hypotheses"]:
        assert len(f["R"]) == 9 and len(f["t_mm"]) == 3, f
    assert all("residual_mm" in f for f in t["ridge_fits"]) and all("agreement" in h for h in t["hypotheses"]), t
assert any(t["ridge_fits"] and t["hypotheses"] for t in traces), "no candidate reports the poses it reached"
# Each pose says why it is not handed out: no check named where it is pickable, one at least where not.
names = {"ambiguous", "covered", "part_seen", "goes_on", "no_end", "second_search", "noisy"}
poses = [o for o in objects if "rank" in o]
assert poses, "no pose"
for p in poses:
    assert set(p["withheld"]) <= names and (not p["withheld"]) == p["pickable"], p
    # ... and, ambiguous, why: a reason named exactly where it is.
    reasons = {"rival", "slides", "roll", "other_part", "twin_unresolved", "read_two_ways"}
    assert set(p["ambiguous_why"]) <= reasons and bool(p["ambiguous_why"]) == p["ambiguous"], p
PY
grep -q "pipes found" "$work/locate.log" || fail "locate logs no summary on stderr: $(cat "$work/locate.log")"

"$bin" bench --dataset "$work/ds" --rounds 2 > "$work/bench.txt" 2>&1
grep -q '2 rounds over the 2 target frames' "$work/bench.txt" || fail "bench header: $(head -1 "$work/bench.txt")"
for stage in cycle to_pick again zbuffer normals regions 'ridge_icp\*' 'refine\*' 'verify\*'; do
  grep -qE "^${stage} +[0-9.]+ +[0-9.]+ +[0-9.]+$" "$work/bench.txt" || fail "bench prints no median/p95/max for $stage"
done
# Every cycle found something on a simulated bin: its median is a positive time.
awk '$1 == "cycle" && $2 > 0 { ok = 1 } END { exit !ok }' "$work/bench.txt" || fail "bench cycle median not positive"

if "$bin" bench --dataset "$work/nowhere" > "$work/err.txt" 2>&1; then fail "bench on a missing dataset exited 0"; fi
grep -q "nowhere" "$work/err.txt" || fail "the error does not name the dataset: $(cat "$work/err.txt")"
# A command-line error is a start-up error: exit 2 with a message naming the option; --help is 0.
set +e
"$bin" eval-bop --dataset "$work/ds" --out "$work/r.csv" --no-such-option > "$work/err.txt" 2>&1
status=$?
set -e
[ "$status" -eq 2 ] || fail "an unknown option exited $status, not 2"
grep -q "no-such-option" "$work/err.txt" || fail "the error does not name the option: $(cat "$work/err.txt")"
"$bin" eval-bop --help > /dev/null || fail "--help did not exit 0"
# timing-report on a real serve's log (the sim source, plc.mode none): the picks it counts are the
# log's DONE_OK LOCATEs and those it says took nothing the log's last_pick_took_nothing lines.
cat > "$work/serve.toml" <<'EOF'
[model]
preset = "u"
[source]
kind = "sim"
[source.sim]
pipes = 6
seed = 5
[plc]
mode = "none"
[service]
budget_ms = 5000
EOF
timeout 120 "$bin" serve --config "$work/serve.toml" --trigger-ms 50 --cycles 6 --log-dir "$work/serve-log" \
  > "$work/serve.out" 2>&1 || fail "serve on the sim source: $(tail -3 "$work/serve.out")"
"$bin" timing-report "$work/serve-log/timing.jsonl" --png "$work/timing.png" > "$work/report.txt" ||
  fail "timing-report: $(cat "$work/report.txt")"
want=$(python3 - "$work/serve-log/timing.jsonl" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
cycles = [j for j in lines if j.get("event") == "cycle" and j["cmd"] == 1]
assert len(cycles) == 6, len(cycles)
print(f"picks: {sum(j['status'] == 'DONE_OK' for j in cycles)} LOCATEs handed out a pose; "
      f"{sum(j['last_pick_took_nothing'] for j in cycles)} picks took nothing")
PY
)
grep -qF "$want" "$work/report.txt" || fail "timing-report does not say '$want': $(head -3 "$work/report.txt")"

echo "1 passed, 0 failed"
