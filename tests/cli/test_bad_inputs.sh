#!/usr/bin/env bash
# Bad inputs to the offline commands and serve (issue 21, item 7): each is refused with exit 2 and
# a message naming the file (or option) and what was expected, never silence, a wrong answer or
# a raw exception. Data made here with the simulator and a small PNG writer.
source "$(dirname "$0")/common.sh" "$@"
passed=0

# expect_refused WHAT PATTERN... -- CMD...: CMD exits 2 and its stderr matches every PATTERN.
expect_refused() {
  local what="$1"; shift
  local patterns=()
  while [ "$1" != "--" ]; do patterns+=("$1"); shift; done
  shift
  set +e
  "$@" > "$work/out.txt" 2> "$work/err.txt"
  local status=$?
  set -e
  [ "$status" -eq 2 ] || fail "$what: exit $status, not 2 (stderr: $(tail -2 "$work/err.txt"))"
  for p in "${patterns[@]}"; do
    grep -qE -- "$p" "$work/err.txt" || fail "$what: the message lacks '$p': $(tail -2 "$work/err.txt")"
  done
  passed=$((passed + 1))
}

# A 16-bit grey PNG of one value.
png16() {
  /usr/bin/python3 - "$@" <<'PY'
import struct, sys, zlib
path, w, h, value = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
raw = b"".join(b"\0" + struct.pack(">H", value) * w for _ in range(h))
chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
with open(path, "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
PY
}

"$bin" make-pipe --preset u --out "$work/u.stl" > /dev/null 2>&1
"$bin" simulate --model "$work/u.stl" --images 1 --pipes 6 --seed 5 --out "$work/ds" > /dev/null 2>&1
scene="$work/ds/test/000001"
cam="$scene/scene_camera.json"
depth="$scene/depth/000000.png"

# A depth image of another size than its camera's (320x240 against 640x480 intrinsics).
png16 "$work/small.png" 320 240 1000
expect_refused "locate, depth size" "small.png" "320x240" "640x480" "scene_camera.json" -- \
  "$bin" locate --depth "$work/small.png" --camera "$cam" --model "$work/u.stl"
cp -r "$work/ds" "$work/ds_small"
cp "$work/small.png" "$work/ds_small/test/000001/depth/000000.png"
expect_refused "eval-bop, depth size" "000000.png" "320x240" "640x480" -- \
  "$bin" eval-bop --dataset "$work/ds_small" --out "$work/r.csv"
printf '[model]\npreset = "u"\n[source]\nkind = "replay"\n[source.replay]\npath = "%s"\n[plc]\nmode = "none"\n' \
  "$work/ds_small" > "$work/replay.toml"
expect_refused "serve on replay, depth size" "000000.png" "320x240" "640x480" -- \
  timeout 60 "$bin" serve --config "$work/replay.toml" --cycles 1 --log-dir "$work/log"

# A frame with no depth at all: said, not an empty result that looks like an empty bin.
png16 "$work/zero.png" 640 480 0
expect_refused "locate, no depth" "zero.png" "0 of 307200 pixels" "ERROR 2" -- \
  "$bin" locate --depth "$work/zero.png" --camera "$cam" --model "$work/u.stl"

# cam_R_w2c that is no rotation (a scale), and one that is a reflection.
/usr/bin/python3 - "$cam" "$work" <<'PY'
import json, sys
cams = json.load(open(sys.argv[1]))
cams["0"]["cam_R_w2c"] = [2, 0, 0, 0, -1, 0, 0, 0, -1]
json.dump(cams, open(sys.argv[2] + "/scaled.json", "w"))
cams["0"]["cam_R_w2c"] = [1, 0, 0, 0, 1, 0, 0, 0, -1]
json.dump(cams, open(sys.argv[2] + "/mirror.json", "w"))
PY
expect_refused "cam_R_w2c scaled" "scaled.json" "image 0" "cam_R_w2c" "orthonormal" -- \
  "$bin" locate --depth "$depth" --camera "$work/scaled.json" --model "$work/u.stl"
expect_refused "cam_R_w2c mirror" "mirror.json" "image 0" "cam_R_w2c" "reflection" -- \
  "$bin" locate --depth "$depth" --camera "$work/mirror.json" --model "$work/u.stl"

# An unknown sub-table, as an unknown key is.
printf '[locate]\nmax_candidates = 8\n[locate.extra]\nfoo = 1\n' > "$work/sub.toml"
expect_refused "[locate.extra]" "sub.toml" "locate.extra" "unknown section" -- \
  "$bin" locate --depth "$depth" --camera "$cam" --model "$work/u.stl" --config "$work/sub.toml"

# A 50 m pipe: refused by its extent, before anything is sized from it (it asked for tens of GB).
expect_refused "50 m pipe" "big.stl" "50000 mm" "3000 mm" -- \
  "$bin" make-pipe --path S50000 --diameter 20 --out "$work/big.stl"
[ ! -e "$work/big.stl" ] || fail "make-pipe wrote the 50 m pipe it refused"

# A text file given as STL.
printf 'this is a note about the pipe, not a model; it is long enough for a binary STL header and count\n' \
  > "$work/note.stl"
expect_refused "text as STL" "note.stl" "not an STL file: it is text" -- \
  "$bin" locate --depth "$depth" --camera "$cam" --model "$work/note.stl"
grep -q "announces" "$work/err.txt" && fail "text as STL: still read as a binary STL: $(tail -1 "$work/err.txt")"

# timing-report on a log with a field of the wrong type: file, line, field.
cat > "$work/timing.jsonl" <<'EOF'
{"event":"start","unix_ms":1795496073000}
{"event":"cycle","cmd":1,"trigger_unix_ms":1795496073579.5,"cycle_ms":120.5,"budget_ms":250.0,"status":"DONE_OK","error":"none"}
{"event":"cycle","cmd":1,"trigger_unix_ms":1795496073779.5,"cycle_ms":"slow","budget_ms":250.0,"status":"DONE_OK","error":"none"}
EOF
expect_refused "timing-report, bad field" "timing.jsonl" "line 3" "cycle_ms" "expected a number" -- \
  "$bin" timing-report "$work/timing.jsonl" --png "$work/t.png"
grep -q "json.exception" "$work/err.txt" && fail "timing-report: a raw json exception: $(tail -1 "$work/err.txt")"

# Options the chosen mode ignores are refused on the command line.
expect_refused "serve --trigger-ms in server mode" "trigger-ms" "plc.mode" -- \
  timeout 60 "$bin" serve --trigger-ms 100 --cycles 1 --log-dir "$work/log"
expect_refused "bench --dataset with --frames" "frames" "dataset" -- \
  "$bin" bench --dataset "$work/ds" --frames 3
expect_refused "bench --rounds without --dataset" "rounds" -- "$bin" bench --rounds 2 --frames 1

# make-pipe with a diameter of 0 or below (nan too).
for d in 0 -20 nan; do
  expect_refused "make-pipe --diameter $d" "diameter" -- "$bin" make-pipe --preset u --diameter "$d" --out "$work/d.stl"
done
echo "$passed passed, 0 failed"
