#!/usr/bin/env bash
# The zoo's machinery on two small shapes of two images: make-pipe -> simulate (both sensors) ->
# eval-bop --picks -> score --picks, and two bins cleared through `serve` by the stand-in PLC. Checks
# that the table is printed and every figure is in range; not how good the localizer is.
source "$(dirname "$0")/common.sh" "$@"

"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shapes 15,20 --images 2 --jobs 2 --bins 2 \
  --json "$work/zoo.json" > "$work/zoo.txt" 2>&1 || fail "tools/zoo failed: $(tail -20 "$work/zoo.txt")"
grep -qE '^15-arc ' "$work/zoo.txt" || fail "no row for 15-arc: $(cat "$work/zoo.txt")"
grep -q '^overall: recall@5' "$work/zoo.txt" || fail "no overall line: $(cat "$work/zoo.txt")"
python3 - "$work/zoo.json" <<'PY' || fail "figures out of range: $(cat "$work/zoo.txt")"
import json, sys
z = json.load(open(sys.argv[1]))
assert not z["failed"], z["failed"]
assert [r["id"] for r in z["rows"]] == [15, 20]
assert {r["sensor"] for r in z["rows"]} == {"kinect", "stereo"}
for r in z["rows"]:
    s, c = r["score"], r["clear"]
    assert s["images"] == 2 and s["top_pipes"] > 0, s
    for k in ("top_recall_5mm", "pick_rate", "precision_10mm"):
        assert s[k] is None or 0 <= s[k] <= 1, (k, s[k])
    assert 0 <= s["wrong_picks"] <= s["picks"] <= 2, s
    assert c["bins"] == 2 and c["pipes"] == 2 * r["pipes"], c  # each bin held the pile asked for
    assert 0 <= c["taken"] <= c["pipes"] and c["locates"] >= 1, c
    assert 0 <= c["seen_taken"] <= min(c["seen"], c["taken"]) and c["seen"] <= c["pipes"], c  # clearance in view
    assert abs(c["height_mm"] - r["height_mm"]) <= 50, c  # the shape's camera (--clear-camera drawn)
    assert c["stop"] in ("done_none", "limit"), c
    assert c["locates"] >= c["taken"] + 1 or c["stop"] == "limit", c  # each pipe taken by a pick, then DONE_NONE
    # Why the bins stopped: the last LOCATE's poses not handed out, by check (the timing log's counts).
    assert set(c["stop_withheld"]) <= {"ambiguous", "covered", "part_seen", "goes_on", "no_end", "second_search",
                                       "noisy", "took_nothing"} and all(n >= 0 for n in c["stop_withheld"].values()), c
    assert c["stop_found"] >= 0 and all(n <= c["stop_found"] for n in c["stop_withheld"].values()), c
    # ... and of those ambiguous, why: no reason for more poses than are ambiguous.
    assert set(c["stop_ambiguous_why"]) <= {"twin_unresolved", "rival", "slides", "roll", "other_part",
                                            "read_two_ways"}, c
    assert all(0 <= n <= c["stop_withheld"].get("ambiguous", 0) for n in c["stop_ambiguous_why"].values()), c
    # A wrong pick takes nothing on the sim source: the service saw each, and no right pick as one.
    assert c["took_nothing"] == c["wrong"], c
PY
grep -qE ' seen +clear ' "$work/zoo.txt" || fail "no seen/clear columns: $(head -12 "$work/zoo.txt")"
grep -q '^clearing: ' "$work/zoo.txt" || fail "no clearing line: $(tail -8 "$work/zoo.txt")"
# --first-bin: bin 2 alone is the second bin of the run above (the same pile on its first frame,
# its truth in clear-truth-2.jsonl); bin 1's truth is not written again.
head -1 "$work/zoo/shapes/20-3D/clear-truth-2.jsonl" > "$work/bin2-first.jsonl"
head -1 "$work/zoo/shapes/20-3D/clear-truth.jsonl" | cmp -s - "$work/bin2-first.jsonl" &&
  fail "--bins 2: the second bin holds the first bin's pile"
touch -d '2000-01-01' "$work/zoo/shapes/20-3D/clear-truth.jsonl"
"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shapes 20 --images 2 --reuse --first-bin 2 \
  > "$work/zoo8.txt" 2>&1 || fail "--first-bin 2 failed: $(tail -20 "$work/zoo8.txt")"
head -1 "$work/zoo/shapes/20-3D/clear-truth-2.jsonl" | cmp -s - "$work/bin2-first.jsonl" ||
  fail "--first-bin 2: not the pile of the second bin"
[ "$(find "$work/zoo/shapes/20-3D/clear-truth.jsonl" -newer "$work/bin2-first.jsonl")" = "" ] ||
  fail "--first-bin 2: bin 1 cleared too"
if "$here/tools/zoo" --bin "$bin" --out "$work/zoo" --first-bin 0 > "$work/zoo9.txt" 2>&1; then
  fail "--first-bin 0 accepted"
fi
grep -q -- '--first-bin 0' "$work/zoo9.txt" || fail "--first-bin 0: no message naming it: $(cat "$work/zoo9.txt")"
# The camera mounted to see the whole bin while clearing: passed to the sim source.
"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shapes 20 --images 2 --reuse --clear-camera bin \
  > "$work/zoo6.txt" 2>&1 || fail "--clear-camera bin failed: $(tail -20 "$work/zoo6.txt")"
grep -q 'camera_sees_bin = true' "$work/zoo/shapes/20-3D/clear.toml" || fail "--clear-camera bin: not passed to serve"
# A port taken between the zoo choosing it and the service binding it (another process took it):
# the service says so and exits 2, and the zoo starts it again on another port. (With the zoo's
# own interpreter: its stand-in PLC needs pymodbus.)
"$(sed -n '1s/^#!//p' "$here/tools/zoo")" - "$here/tools/zoo" "$bin" "$work/zoo" > "$work/zoo7.txt" 2>&1 <<'PY' || fail "a taken port: $(tail -20 "$work/zoo7.txt")"
import importlib.machinery, importlib.util, json, socket, sys
loader = importlib.machinery.SourceFileLoader("zoo", sys.argv[1])
zoo = importlib.util.module_from_spec(importlib.util.spec_from_loader("zoo", loader))
loader.exec_module(zoo)
squat = socket.socket()
squat.bind(("127.0.0.1", 0))
squat.listen(1)
taken, chosen, free_port = squat.getsockname()[1], [], zoo.free_port
zoo.free_port = lambda: chosen.append(taken if not chosen else free_port()) or chosen[-1]
out = sys.argv[3]
sys.argv = ["zoo", "--bin", sys.argv[2], "--out", out, "--shapes", "20", "--images", "2", "--reuse",
            "--json", out + "/port.json"]
zoo.main()
z = json.load(open(out + "/port.json"))
assert not z["failed"], z["failed"]
assert len(chosen) == 2 and chosen[0] == taken, chosen
PY
grep -q "Address already in use" "$work/zoo/shapes/20-3D/log.txt" || fail "a taken port: the service did not say so"
# The shaker: the same bin, the stand-in PLC shaking it where the DONE_NONE's registers say so. The
# figures at the first DONE_NONE are the run's above; the s_ ones count on to the last LOCATE.
"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shapes 20 --images 2 --reuse --shakes 2 \
  --json "$work/shake.json" > "$work/zoo10.txt" 2>&1 || fail "--shakes 2 failed: $(tail -20 "$work/zoo10.txt")"
grep -q 'shake_after_none = true' "$work/zoo/shapes/20-3D/clear.toml" || fail "--shakes 2: not passed to serve"
grep -q '^with the shaker' "$work/zoo10.txt" || fail "--shakes 2: no shaker line: $(tail -8 "$work/zoo10.txt")"
python3 - "$work/zoo/port.json" "$work/shake.json" <<'PY' || fail "--shakes 2: figures: $(tail -8 "$work/zoo10.txt")"
import json, sys
(a,), (b,) = ([r["clear"] for r in json.load(open(f))["rows"]] for f in sys.argv[1:])
for k in ("pipes", "taken", "seen", "seen_taken", "free_left", "wrong", "took_nothing", "emptied", "locates", "picks",
          "stop", "stops_free", "stops_empty"):
    assert a[k] == b[k], (k, a[k], b[k])
assert a["shakes"] == 0 and a["s_taken"] == a["taken"] and a["s_wrong"] == a["wrong"], a
assert 0 <= b["shakes"] <= 2 * b["pipes"] and b["taken"] <= b["s_taken"] <= b["pipes"], b
assert b["s_wrong"] >= b["wrong"] and b["s_locates"] >= b["locates"] + b["shakes"], b
assert b["s_emptied"] == (b["s_taken"] == b["pipes"]), b
PY
if "$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shakes 21 > "$work/zoo11.txt" 2>&1; then fail "--shakes 21 accepted"; fi
grep -q -- '--shakes 21' "$work/zoo11.txt" || fail "--shakes 21: no message naming it: $(cat "$work/zoo11.txt")"
# A second run on the same folder re-uses the STLs and datasets.
"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shapes 15 --images 2 --reuse --no-clear > "$work/zoo2.txt" 2>&1 ||
  fail "--reuse run failed: $(tail -20 "$work/zoo2.txt")"
grep -qE '^15-arc ' "$work/zoo2.txt" || fail "--reuse: no row"
# ... and under the cell's budget, as the service localizes.
"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --shapes 15 --images 2 --reuse --no-clear --jobs 1 \
  --budget-ms 250 > "$work/zoo4.txt" 2>&1 || fail "--budget-ms run failed: $(tail -20 "$work/zoo4.txt")"
grep -q 'under a 250 ms budget' "$work/zoo4.txt" || fail "--budget-ms: not said: $(head -3 "$work/zoo4.txt")"
grep -qE '^15-arc ' "$work/zoo4.txt" || fail "--budget-ms: no row"
grep -q -- '--budget-ms 250' "$work/zoo/shapes/15-arc/log.txt" || fail "--budget-ms: not passed to eval-bop"
if "$here/tools/zoo" --bin "$bin" --out "$work/zoo" --budget-ms -5 > "$work/zoo5.txt" 2>&1; then
  fail "--budget-ms -5 accepted"
fi
grep -q -- '--budget-ms -5' "$work/zoo5.txt" || fail "--budget-ms -5: no message naming it: $(cat "$work/zoo5.txt")"
# Another seed draws another list of shapes (a held-out zoo); --reuse makes its data anew.
"$here/tools/zoo" --list > "$work/list19.txt"
"$here/tools/zoo" --seed 20 --list > "$work/list20.txt"
"$here/tools/zoo" --seed 20 --list | cmp -s - "$work/list20.txt" || fail "--seed 20: the list is not the same twice"
if cmp -s "$work/list19.txt" "$work/list20.txt"; then fail "--seed 20: the same list as the default"; fi
"$here/tools/zoo" --bin "$bin" --out "$work/zoo" --seed 20 --shapes 15 --images 2 --reuse --no-clear \
  > "$work/zoo7.txt" 2>&1 || fail "--seed 20 run failed: $(tail -20 "$work/zoo7.txt")"
grep -q 'drawn with seed 20' "$work/zoo7.txt" || fail "--seed 20: not said: $(head -3 "$work/zoo7.txt")"
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["seed"] == 20' "$work/zoo/shapes/15-arc/shape.json" ||
  fail "--seed 20 --reuse: the default draw's data kept"
# A bad count is refused, naming the option.
if "$here/tools/zoo" --bin "$bin" --out "$work/zoo" --bins 0 > "$work/zoo3.txt" 2>&1; then fail "--bins 0 accepted"; fi
grep -q -- '--bins 0' "$work/zoo3.txt" || fail "--bins 0: no message naming it: $(cat "$work/zoo3.txt")"
echo "zoo machinery: ok"
