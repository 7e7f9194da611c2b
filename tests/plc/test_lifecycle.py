"""The service's lifecycle from outside: bad start-up input gives a clear message and a non-zero
exit; systemd's notify protocol (READY, WATCHDOG, STOPPING) over a real datagram socket; SIGTERM
during a cycle ends the process cleanly within a second; the OpenNI2 Dummy device as a source.
usage: test_lifecycle.py PIPELOC_BINARY PORT"""
import json
import os
import signal
import socket
import subprocess
import sys
import time
import unittest

from plc_harness import BUSY, LOCATE, STATUS, Plc, Service, scratch_dir

BINARY, PORT = sys.argv[1], int(sys.argv[2])
# A sanitizer build runs the service many times slower (ThreadSanitizer about 30 times: a SIGTERM
# answered in 32 ms takes about 1 s); its script says by how much, and the time bounds grow with it.
SLOWDOWN = float(os.environ.get("PIPELOC_TEST_SLOWDOWN", "1"))


def serve_with(config_text, *args, timeout=60):
    d = scratch_dir("pipeloc-life-")
    path = os.path.join(d, "c.toml")
    with open(path, "w") as f:
        f.write(config_text)
    out = subprocess.run([BINARY, "serve", "--config", path, "--log-dir", os.path.join(d, "log")] + list(args),
                         capture_output=True, text=True, timeout=timeout)
    return out.returncode, out.stdout + out.stderr, path


class StartUp(unittest.TestCase):
    def test_bad_input_stops_with_a_message(self):
        cases = [
            ("[model]\npreset = \"sbend\"\n[plc]\nbase = 70000\n", "plc.base"),
            ("[model]\npreset = \"sbend\"\n[source]\nkind = \"usb\"\n", "source.kind"),
            ("[model]\nstl = \"missing.stl\"\n", "missing.stl"),
            ("[plc]\nmode = \"none\"\n", "model"),
            ("[model]\npreset = \"sbend\"\n[source]\nkind = \"replay\"\n[source.replay]\npath = \"nowhere\"\n",
             "nowhere"),
            ("[model]\npreset = \"sbend\"\n[source]\nkind = \"openni2\"\n[source.openni2]\nuri = \"no-such-device\"\n",
             "no-such-device"),
            ("[model]\npreset = \"sbend\"\n[locate]\nthreads = 0\n", "locate.threads"),
            ("[model]\npreset = \"sbend\"\nmodel = 3\n", "model.model"),
            ("[model]\npreset = \"sbend\"\n[plc]\naddress = \"localhost\"\n", "plc.address"),
            ("[model]\npreset = \"sbend\"\n[plc]\naddress = \"999.1.1.1\"\n", "plc.address"),
            ("[model]\npreset = \"sbend\"\n[plc]\nrobot_from_camera = [2,0,0,0, 0,2,0,0, 0,0,2,0, 0,0,0,1]\n",
             "plc.robot_from_camera"),
        ]
        for text, named in cases:
            code, out, path = serve_with(text)
            self.assertNotEqual(code, 0, text)
            self.assertIn(named, out, text)
            if named.startswith("plc."):
                self.assertEqual(code, 2, text)  # a config error: exit 2, never "ready"
                self.assertNotIn("ready", out, text)
            self.assertNotIn("Segmentation", out)
        with socket.socket() as taken:  # a port somebody else holds
            taken.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # TIME_WAIT of an earlier run
            taken.bind(("127.0.0.1", PORT + 100))
            taken.listen(1)
            code, out, _ = serve_with(f"[model]\npreset = \"sbend\"\n[plc]\nport = {PORT + 100}\n")
            self.assertNotEqual(code, 0)
            self.assertIn(f"cannot listen on 127.0.0.1:{PORT + 100}", out)

    def test_openni2_dummy_as_source(self):
        code, out, _ = serve_with("[model]\npreset = \"sbend\"\n[source]\nkind = \"openni2\"\n"
                                  "[source.openni2]\nuri = \"Dummy\"\n[plc]\nmode = \"none\"\n", "--cycles", "3")
        self.assertEqual(code, 0, out)
        self.assertIn("320x240", out)
        # The Dummy's frames hold a few hundred readings: the service says so, it does not guess.
        self.assertEqual(out.count("frame_invalid"), 3, out)


class Record(unittest.TestCase):
    def test_record_writes_a_dataset_eval_bop_reads(self):
        d = scratch_dir("pipeloc-record-")
        out = subprocess.run([BINARY, "record", "--frames", "3", "--out", d], capture_output=True, text=True,
                             timeout=120)
        self.assertEqual(out.returncode, 0, out.stdout + out.stderr)
        for i in range(3):
            self.assertTrue(os.path.exists(os.path.join(d, "test", "000001", "depth", f"{i:06d}.png")))
            self.assertTrue(os.path.exists(os.path.join(d, "test", "000001", f"preview_{i:06d}.png")))
        ev = subprocess.run([BINARY, "eval-bop", "--dataset", d, "--out", os.path.join(d, "r.csv")],
                            capture_output=True, text=True, timeout=120)
        self.assertEqual(ev.returncode, 0, ev.stdout + ev.stderr)
        with open(os.path.join(d, "r.csv")) as f:
            self.assertTrue(f.readline().startswith("scene_id,im_id,obj_id,score,R,t,time"))
        # The Dummy device's frames are nearly empty: record says so and stops instead of writing them.
        cfg = os.path.join(d, "dummy.toml")
        with open(cfg, "w") as f:
            f.write("[model]\npreset = \"sbend\"\n[source]\nkind = \"openni2\"\n[source.openni2]\nuri = \"Dummy\"\n")
        dummy = subprocess.run([BINARY, "record", "--config", cfg, "--frames", "1", "--out", os.path.join(d, "dummy")],
                               capture_output=True, text=True, timeout=120)
        self.assertNotEqual(dummy.returncode, 0)
        self.assertIn("frame_invalid", dummy.stdout + dummy.stderr)


class Running(unittest.TestCase):
    def test_systemd_notify_and_sigterm_during_a_cycle(self):
        notify_path = os.path.join(scratch_dir("pipeloc-notify-"), "notify.sock")
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        sock.bind(notify_path)
        sock.settimeout(30)
        env = dict(os.environ, NOTIFY_SOCKET=notify_path, WATCHDOG_USEC="300000")
        # A slow configuration: many pipes, every start run to the end, many hypotheses.
        slow = ("[locate]\ninitial_rotations = 12\nicp_continued_states = 24\nicp_max_iterations = 300\n"
                "icp_probe_iterations = 100\nicp_probe_cell_mm = 2\nicp_fine_iterations = 300\n"
                "verify_hypotheses = 24\n")
        svc = Service(BINARY, PORT, extra_toml=slow, pipes=40, budget_ms=20000, env=env)
        try:
            messages = []
            while not any("READY=1" in m for m in messages):
                messages.append(sock.recv(4096).decode())
            while not any("WATCHDOG=1" in m for m in messages):
                messages.append(sock.recv(4096).decode())
            svc.wait_listening()
            plc = Plc(PORT)
            plc.req_id += 1
            plc.client.write_registers(0, [LOCATE, plc.req_id], slave=1)
            time.sleep(0.2)
            self.assertEqual(plc.read()[STATUS], BUSY, "the cycle is still running")
            plc.close()
            start = time.time()
            svc.proc.send_signal(signal.SIGTERM)
            code = svc.proc.wait(timeout=5 * SLOWDOWN)
            took = time.time() - start
            print(f"SIGTERM during a cycle: exit {code} after {took * 1000:.0f} ms")
            self.assertEqual(code, 0)
            self.assertLess(took, 1.0 * SLOWDOWN)
            sock.settimeout(1 * SLOWDOWN)
            while not any("STOPPING=1" in m for m in messages):
                messages.append(sock.recv(4096).decode())
            # The cycle cut short is logged as cut by the shutdown, not as an exhausted budget.
            with open(os.path.join(svc.dir, "log", "timing.jsonl")) as f:
                cycles = [json.loads(line) for line in f if '"event":"cycle"' in line]
            self.assertEqual(cycles[-1]["error"], "shutdown", cycles[-1])
            self.assertFalse(cycles[-1]["budget_exhausted"])
        finally:
            svc.stop()
            sock.close()

    def test_sighup_stops_cleanly_with_stopping(self):
        notify_path = os.path.join(scratch_dir("pipeloc-notify-"), "notify.sock")
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        sock.bind(notify_path)
        sock.settimeout(30)
        svc = Service(BINARY, PORT, env=dict(os.environ, NOTIFY_SOCKET=notify_path))
        try:
            messages = []
            while not any("READY=1" in m for m in messages):
                messages.append(sock.recv(4096).decode())
            svc.proc.send_signal(signal.SIGHUP)
            code = svc.proc.wait(timeout=5 * SLOWDOWN)
            self.assertEqual(code, 0)  # today's main: killed by the signal (-1), no STOPPING
            sock.settimeout(1 * SLOWDOWN)
            while not any("STOPPING=1" in m for m in messages):
                messages.append(sock.recv(4096).decode())
            self.assertIn("stopping: Hangup", svc.output())
        finally:
            svc.stop()
            sock.close()


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
