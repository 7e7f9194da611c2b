"""Raw-socket Modbus TCP peers for the hostile-client tests: a client that times each request, a
probe that polls STATUS..HEARTBEAT and records the worst response and the longest heartbeat gap,
and the PLC's handshake. Raw sockets, not pymodbus: the timing is the client's own, nothing
retried or buffered behind the test's back."""
import os
import socket
import struct
import threading
import time

STATUS, ACK_ID, HEARTBEAT, LOCATE = 10, 11, 13, 1
MAP_SIZE = 45  # registers 0..44 (REGISTERS.md)
# Under the sanitizers the service runs slower (TSan about 30 times): time bounds and budgets grow.
SLOWDOWN = float(os.environ.get("PIPELOC_TEST_SLOWDOWN", "1"))


class Closed(Exception):
    pass


class Raw:
    """One Modbus TCP connection; `source` picks the local address (127.0.0.2 plays the PLC)."""

    def __init__(self, port, source="127.0.0.1", timeout=2.0):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock.bind((source, 0))
        self.sock.settimeout(timeout)
        start = time.perf_counter()
        self.sock.connect(("127.0.0.1", port))
        self.connect_s = time.perf_counter() - start
        self.tid = 0

    def close(self):
        self.sock.close()

    def send(self, data):
        self.sock.sendall(data)

    def recv_exact(self, n):
        out = b""
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            if not chunk:
                raise Closed()
            out += chunk
        return out

    def request(self, pdu, unit=1):
        """(reply PDU, seconds from send to the whole reply)."""
        self.tid = (self.tid + 1) & 0xFFFF
        start = time.perf_counter()
        self.sock.sendall(struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, unit) + pdu)
        tid, proto, length, _ = struct.unpack(">HHHB", self.recv_exact(7))
        body = self.recv_exact(length - 1)
        assert tid == self.tid and proto == 0, (tid, self.tid, proto)
        return body, time.perf_counter() - start

    def read(self, address, count):
        body, dt = self.request(struct.pack(">BHH", 3, address, count))
        assert body[0] == 3, f"read {address}+{count}: exception {body.hex()}"
        return list(struct.unpack(f">{count}H", body[2:])), dt

    def write(self, address, values):
        pdu = struct.pack(f">BHHB{len(values)}H", 16, address, len(values), 2 * len(values), *values)
        body, dt = self.request(pdu)
        assert body[0] == 16, f"write {address}: exception {body.hex()}"
        return dt


class Probe(threading.Thread):
    """Reads STATUS..HEARTBEAT every `period_s`. Records: the worst response, the longest time between
    two heartbeat changes, connects (connect + first reply) and reconnects (evicted or dropped)."""

    def __init__(self, port, source="127.0.0.1", period_s=0.01):
        super().__init__(daemon=True)
        self.port, self.source, self.period_s = port, source, period_s
        self.stop = threading.Event()
        self.worst_s = 0.0
        self.responses = 0
        self.heartbeat_gap_s = 0.0
        self.accept_s = []
        self.reconnects = 0
        self.errors = []

    def connect(self):
        start = time.perf_counter()
        c = Raw(self.port, self.source)
        c.read(STATUS, 4)
        self.accept_s.append(time.perf_counter() - start)
        return c

    def run(self):
        c = self.connect()
        last_beat, last_change = None, time.perf_counter()
        while not self.stop.is_set():
            try:
                regs, dt = c.read(STATUS, 4)
            except (Closed, OSError) as e:
                self.reconnects += 1
                self.errors.append(repr(e))
                c.close()
                c = self.connect()
                continue
            now = time.perf_counter()
            self.responses += 1
            self.worst_s = max(self.worst_s, dt)
            if regs[3] != last_beat:
                if last_beat is not None:
                    self.heartbeat_gap_s = max(self.heartbeat_gap_s, now - last_change)
                last_beat, last_change = regs[3], now
            time.sleep(self.period_s)
        self.heartbeat_gap_s = max(self.heartbeat_gap_s, time.perf_counter() - last_change)
        c.close()

    def finish(self):
        self.stop.set()
        self.join(10)
        return self


def handshake(client, command, req_id, timeout_s=10.0 * SLOWDOWN, period_s=0.01):
    """CMD and REQ_ID in one FC16 write, then STATUS/ACK_ID until ACK_ID == REQ_ID: the PLC's side
    of REGISTERS.md. Returns (STATUS, worst response in s)."""
    worst = client.write(0, [command, req_id])
    end = time.time() + timeout_s
    while time.time() < end:
        regs, dt = client.read(STATUS, 2)
        worst = max(worst, dt)
        if regs[1] == req_id:
            return regs[0], worst
        time.sleep(period_s)
    raise AssertionError(f"no ACK_ID {req_id} within {timeout_s} s")
