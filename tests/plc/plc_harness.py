"""Shared pieces of the PLC-side tests: start `pipeloc serve` on the sim source with a config of
the test's own; the PLC side itself lives in tools/pipeloc_plc.py (also used by tools/plc-client)."""
import atexit
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
from pipeloc_plc import *  # noqa: E402,F401,F403


def scratch_dir(prefix):
    """A temporary folder removed when the test script ends; PIPELOC_KEEP_TEST_DIRS=1 keeps it to look
    into (each test's failure message already holds the service's output)."""
    d = tempfile.mkdtemp(prefix=prefix)
    if os.environ.get("PIPELOC_KEEP_TEST_DIRS") != "1":
        atexit.register(shutil.rmtree, d, True)
    return d


class Service:
    """`pipeloc serve` in a temporary folder with the given TOML sections added."""

    def __init__(self, binary, port, extra_toml="", pipes=12, seed=3, budget_ms=2000, mode="server", env=None,
                 plc_toml=""):
        self.binary = binary
        self.port = port
        self.dir = scratch_dir("pipeloc-plc-test-")
        self.truth = os.path.join(self.dir, "truth.jsonl")
        self.stl = os.path.join(self.dir, "sbend.stl")
        subprocess.run([binary, "make-pipe", "--preset", "sbend", "--ascii", "--out", self.stl], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.config = os.path.join(self.dir, "serve.toml")
        with open(self.config, "w") as f:
            f.write(f"""[model]
stl = "{self.stl}"
[source]
kind = "sim"
[source.sim]
pipes = {pipes}
seed = {seed}
truth_file = "{self.truth}"
[service]
budget_ms = {budget_ms}
[plc]
mode = "{mode}"
address = "127.0.0.1"
port = {port}
{plc_toml}
[log]
dir = "{os.path.join(self.dir, 'log')}"
{extra_toml}
""")
        self.log_path = os.path.join(self.dir, "serve.log")
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen([binary, "serve", "--config", self.config], stdout=self.log,
                                     stderr=subprocess.STDOUT, env=env)
        with open(self.stl) as f:
            self.vertices = [tuple(float(x) for x in line.split()[1:4])
                             for line in f if line.strip().startswith("vertex")][::6]

    def wait_listening(self, timeout=60):
        end = time.time() + timeout
        while time.time() < end:
            if self.proc.poll() is not None:
                raise AssertionError("pipeloc serve exited early:\n" + self.output())
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=0.2).close()
                return
            except OSError:
                time.sleep(0.1)
        raise AssertionError("pipeloc serve did not listen in time:\n" + self.output())

    def output(self):
        if not self.log.closed:
            self.log.flush()
        with open(self.log_path) as f:
            return f.read()

    def truth_of_frame(self, frame):
        with open(self.truth) as f:
            lines = f.readlines()
        for line in lines:
            rec = json.loads(line)
            if rec["frame"] == frame:
                return [([p[0:3], p[3:6], p[6:9]], p[9:12]) for p in rec["model_to_cam"]]
        raise AssertionError(f"no ground truth for frame {frame}")

    def best_error(self, frame, pose):
        return min(mssd(self.vertices, pose, gt) for gt in self.truth_of_frame(frame))

    def stop(self, sig=signal.SIGTERM, timeout=5):
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()
        return self.proc.returncode


