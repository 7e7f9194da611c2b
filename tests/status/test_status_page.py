"""The status page from outside, as an integrator and a monitoring system see it: `pipeloc serve`
on the sim source with [status] on, a PLC (pymodbus) driving LOCATE, NEXT, CLEAR_ERROR and a bad
command; then /metrics parsed by prometheus_client's parser and compared with what the PLC saw,
/api/status checked, /overlay.png decoded, and / loaded by a real headless Chromium: the DOM says
the overlay image loaded (its natural width) and the screenshot shows the overlay's legend.
usage: test_status_page.py PIPELOC_BINARY MODBUS_PORT HTTP_PORT"""
import json
import os
import shutil
import struct
import subprocess
import sys
import time
import unittest
import urllib.request
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "plc"))
from plc_harness import *  # noqa: E402,F401,F403
from prometheus_client.parser import text_string_to_metric_families  # noqa: E402

BINARY, PORT, HTTP = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
URL = f"http://127.0.0.1:{HTTP}"


def get(path, timeout=5):
    with urllib.request.urlopen(URL + path, timeout=timeout) as r:
        return r.status, r.headers.get("Content-Type", ""), r.read()


def decode_png(data):
    """8-bit RGB or RGBA PNG -> (width, height, rows of (r, g, b) tuples); enough for screenshots."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and colour in (2, 6), (depth, colour)
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * channels:x * channels + 3]) for x in range(width)])
        prev = line
    return width, height, rows


class StatusPage(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.svc = Service(BINARY, PORT, budget_ms=2000, extra_toml=f"""[status]
enabled = true
address = "127.0.0.1"
port = {HTTP}
refresh_s = 2
""")
        cls.svc.wait_listening()
        cls.plc = Plc(PORT)
        # What the PLC did and saw, to compare the page's figures with.
        cls.locates, cls.picks, cls.statuses = [], 0, {DONE_OK: 0, DONE_NONE: 0, STATUS_ERROR: 0}
        for _ in range(4):
            regs = cls.plc.command(LOCATE)
            cls.locates.append(regs)
            cls.statuses[regs[STATUS]] += 1
            cls.picks += regs[STATUS] == DONE_OK
        cls.last_locate = cls.locates[-1]
        cls.next = cls.plc.command(NEXT)
        cls.picks += cls.next[STATUS] == DONE_OK
        cls.plc.command(CLEAR_ERROR)
        cls.plc.command(9)  # not a command: ERROR 5
        cls.commands = 7
        # The page learns of a command just after the PLC does, and of clients every 250 ms.
        end = time.time() + 20
        while time.time() < end:
            s = json.loads(get("/api/status")[2])
            if sum(s["commands"].values()) == cls.commands and s["clients"] and s["overlay_cycle"] > 0:
                break
            time.sleep(0.1)

    @classmethod
    def tearDownClass(cls):
        cls.plc.close()
        code = cls.svc.stop()
        assert code == 0, f"serve exited {code}:\n{cls.svc.output()}"

    def test_metrics_parse_and_match_what_the_plc_saw(self):
        status, ctype, body = get("/metrics")
        self.assertEqual(status, 200)
        self.assertIn("version=0.0.4", ctype)
        fams = {f.name: f for f in text_string_to_metric_families(body.decode())}
        def value(name, **labels):
            for f in fams.values():
                for s in f.samples:
                    if s.name == name and all(s.labels.get(k) == v for k, v in labels.items()):
                        return s.value
            self.fail(f"no sample {name} {labels}")
        self.assertEqual(fams["pipeloc_cycle_seconds"].type, "histogram")
        self.assertEqual(value("pipeloc_cycle_seconds_count"), len(self.locates))
        self.assertEqual(value("pipeloc_cycle_seconds_bucket", le="+Inf"), len(self.locates))
        buckets = [(float(s.labels["le"]), s.value) for s in fams["pipeloc_cycle_seconds"].samples
                   if s.name == "pipeloc_cycle_seconds_bucket"]
        self.assertEqual([c for _, c in buckets], sorted(c for _, c in buckets))  # cumulative
        cycle_s = sum(r[CYCLE_MS] for r in self.locates) / 1000  # CYCLE_MS is rounded to 1 ms
        self.assertAlmostEqual(value("pipeloc_cycle_seconds_sum"), cycle_s, delta=0.001 * len(self.locates))
        for name, code in (("DONE_OK", DONE_OK), ("DONE_NONE", DONE_NONE), ("ERROR", STATUS_ERROR)):
            self.assertEqual(value("pipeloc_cycles_total", status=name), self.statuses[code], name)
        self.assertEqual(value("pipeloc_commands_total", command="locate"), 4)
        self.assertEqual(value("pipeloc_commands_total", command="next"), 1)
        self.assertEqual(value("pipeloc_commands_total", command="clear_error"), 1)
        self.assertEqual(value("pipeloc_commands_total", command="other"), 1)
        self.assertEqual(value("pipeloc_errors_total", code="5", error="bad_command"), 1)
        self.assertEqual(value("pipeloc_picks_total"), self.picks)
        self.assertEqual(value("pipeloc_picks_took_nothing_total"), 0)  # the sim source took each pipe picked
        self.assertGreater(value("pipeloc_heartbeats_total"), 0)
        self.assertEqual(value("pipeloc_healthy"), 1)
        self.assertGreaterEqual(value("pipeloc_plc_clients"), 1)
        self.assertAlmostEqual(value("pipeloc_frame_age_seconds"), self.last_locate[FRAME_AGE_MS] / 1000, delta=0.001)
        self.assertEqual(value("pipeloc_budget_seconds"), 2.0)
        print("metrics: %d families; cycle sum %.3f s over %d LOCATEs, %d picks" %
              (len(fams), value("pipeloc_cycle_seconds_sum"), len(self.locates), self.picks))

    def test_api_status_json(self):
        status, ctype, body = get("/api/status")
        self.assertEqual(ctype, "application/json")
        s = json.loads(body)
        last = s["last_locate"]
        self.assertEqual(last["req_id"], self.last_locate[ACK_ID])
        self.assertEqual(last["count"], self.last_locate[COUNT])
        self.assertEqual(len(s["poses"]), min(16, self.last_locate[COUNT]))
        if self.last_locate[STATUS] == DONE_OK:
            x, y, z = (f32(self.last_locate, POSE + 2 * i) for i in range(3))
            for got, want in zip(s["poses"][0]["xyz_mm"], (x, y, z)):
                self.assertAlmostEqual(got, want, delta=0.01)
            self.assertAlmostEqual(s["poses"][0]["score"], f32(self.last_locate, SCORE), delta=1e-5)
        self.assertEqual((s["picks"], s["picks_took_nothing"]), (self.picks, 0))
        self.assertEqual(s["recent"][0]["command"], "unknown")
        self.assertEqual(s["recent"][0]["error"], "bad_command")
        self.assertEqual(len(s["history"]["cycle_ms"]), 4)
        self.assertTrue(any(c["address"] == "127.0.0.1" and c["requests"] > 0 for c in s["clients"]), s["clients"])
        self.assertIn('status.port = %d  # TCP port (0: any free one)' % HTTP, s["config"])
        # The model as the start-up log has it: D, L and its near twins (or none).
        self.assertRegex(s["model"], r"tube diameter D [0-9.]+ mm, .*near symmetr")

    def test_overlay_png(self):
        status, ctype, body = get("/overlay.png")
        self.assertEqual(ctype, "image/png")
        w, h, _ = decode_png(body)
        self.assertEqual((w, h), (640, 480))  # the sim's camera

    def test_port_taken_is_a_start_up_error(self):
        with open(self.svc.config) as f:
            text = f.read().replace(f"port = {PORT}\n", f"port = {PORT + 2000}\n")
        config = os.path.join(self.svc.dir, "second.toml")
        with open(config, "w") as f:
            f.write(text)
        r = subprocess.run([BINARY, "serve", "--config", config], capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(f"status: cannot listen on 127.0.0.1:{HTTP}", r.stderr)

    def test_page_in_headless_chromium(self):
        chromium = shutil.which("chromium") or shutil.which("chromium-browser")
        self.assertIsNotNone(chromium, "chromium not installed (tools/setup installs it)")
        work = scratch_dir("pipeloc-status-chromium-")
        common = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                  "--user-data-dir=" + os.path.join(work, "profile"), "--window-size=1280,1000"]
        dom = subprocess.run(common + ["--dump-dom", URL + "/"], capture_output=True, text=True, timeout=120).stdout
        self.assertIn("pipeloc status", dom)
        # The img's onload writes its natural width into the DOM: the overlay really loaded.
        self.assertIn('data-loaded-width="640"', dom)
        for text in ("cycle time, trigger to result [ms]", "LOCATE cycles", "budget 2000 ms", "PLC clients connected",
                     "Config in effect", "X mm"):
            self.assertIn(text, dom)
        shot = os.path.join(work, "status.png")
        subprocess.run(common + ["--screenshot=" + shot, URL + "/"], capture_output=True, timeout=120)
        with open(shot, "rb") as f:
            w, h, rows = decode_png(f.read())
        # The overlay's legend: a box of (20, 20, 20) whose padding rows are runs of 150 px and more
        # (no text or depth shading makes such runs), with the pick's colour (255, 30, 30) inside it.
        legend = None
        for y in range(h):
            run = 0
            for x in range(w):
                run = run + 1 if rows[y][x] == (20, 20, 20) else 0
                if run >= 150:
                    legend = (x - run + 1, y)
                    break
            if legend:
                break
        self.assertIsNotNone(legend, "no overlay legend in the screenshot")
        x0, y0 = legend
        pick = sum(rows[y][x] == (255, 30, 30) for y in range(y0, min(h, y0 + 80)) for x in range(x0, min(w, x0 + 180)))
        self.assertGreater(pick, 10, "the legend has no PICK colour")
        print(f"screenshot {w}x{h}: overlay legend at x {x0}, y {y0}, {pick} PICK pixels ({shot})")


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
