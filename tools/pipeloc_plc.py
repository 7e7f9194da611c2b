"""Talking to pipeloc as a PLC does, with pymodbus (Debian's python3-pymodbus): the register map
and handshake of firmware-host/REGISTERS.md, float decoding, pose comparison. Used by
tools/plc-client and by the PLC tests."""
import math
import socket
import struct
import time

from pymodbus.client import ModbusTcpClient

CMD, REQ_ID, STATUS, ACK_ID, ERROR, HEARTBEAT, COUNT, INDEX = 0, 1, 10, 11, 12, 13, 14, 15
CYCLE_MS, FRAME_AGE_MS, CYCLES, POSE, SCORE, QUAT, POSE_END = 16, 17, 18, 20, 32, 34, 42
HELD, HELD_WHY, REGIONS, SIZE = 42, 43, 44, 45
# HELD_WHY's bits: the checks that held the LOCATE's poses back (REGISTERS.md).
HELD_WHY_NAMES = ["ambiguous", "covered", "part seen", "goes on", "no end", "unsure", "noisy", "took nothing"]
LOCATE, NEXT, CLEAR_ERROR = 1, 2, 3
READY, BUSY, DONE_OK, DONE_NONE, STATUS_ERROR = 0, 1, 2, 3, 4


def f32(regs, at):
    """float32, ABCD: high word first."""
    return struct.unpack(">f", struct.pack(">HH", regs[at], regs[at + 1]))[0]


def u32(regs, at):
    return (regs[at] << 16) | regs[at + 1]


def held_why(bits):
    """HELD_WHY as names."""
    return [name for k, name in enumerate(HELD_WHY_NAMES) if bits & (1 << k)]


def what_is_left(regs):
    """With DONE_NONE, what REGISTERS.md's "What a DONE_NONE says" reads into HELD and REGIONS:
    "held" (poses held back: pipes the cell cannot pick as they lie, shake the bin), "regions"
    (pipe-like regions, none confirmed: shake once where the empty bin gives none, then refill) or
    "none" (no pipe seen: refill)."""
    return "held" if regs[HELD] > 0 else "regions" if regs[REGIONS] > 0 else "none"


def rot_zyx(rx, ry, rz):
    """R = Rz(rz) Ry(ry) Rx(rx), degrees: the ZYX convention of the pose registers."""
    a, b, c = (math.radians(v) for v in (rz, ry, rx))
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return [[ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
            [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
            [-sb, cb * sc, cb * cc]]


def rot_quat(w, x, y, z):
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def decode_pose(regs):
    """(R, t) of the pose registers, with R from the Euler angles."""
    x, y, z, rx, ry, rz = (f32(regs, POSE + 2 * i) for i in range(6))
    return rot_zyx(rx, ry, rz), [x, y, z]


def mssd(vertices, pose_a, pose_b):
    """Largest vertex distance between two poses (the models here have no symmetry)."""
    (ra, ta), (rb, tb) = pose_a, pose_b
    worst = 0.0
    for v in vertices:
        d2 = 0.0
        for r in range(3):
            pa = ra[r][0] * v[0] + ra[r][1] * v[1] + ra[r][2] * v[2] + ta[r]
            pb = rb[r][0] * v[0] + rb[r][1] * v[1] + rb[r][2] * v[2] + tb[r]
            d2 += (pa - pb) ** 2
        worst = max(worst, d2)
    return math.sqrt(worst)


class Plc:
    """A PLC as Modbus TCP client of the service, doing DESIGN.md's handshake."""

    def __init__(self, port, host="127.0.0.1", source=None):
        self.client = ModbusTcpClient(host, port=port, timeout=3,
                                      source_address=(source, 0) if source else None)
        assert self.client.connect(), f"cannot connect to {host}:{port}"
        self.req_id = self.read()[ACK_ID]

    def read(self, address=0, count=SIZE):
        rr = self.client.read_holding_registers(address, count, slave=1)
        assert not rr.isError(), f"read {address}+{count}: {rr}"
        return rr.registers

    def command(self, cmd, timeout=30):
        """CMD and REQ_ID in one FC16 write; wait for ACK_ID == REQ_ID; the whole map."""
        self.req_id = (self.req_id + 1) % 65536
        wr = self.client.write_registers(CMD, [cmd, self.req_id], slave=1)
        assert not wr.isError(), f"write CMD/REQ_ID: {wr}"
        end = time.time() + timeout
        while time.time() < end:
            regs = self.read()
            if regs[ACK_ID] == self.req_id:
                return regs
            time.sleep(0.005)
        raise AssertionError(f"no ACK_ID {self.req_id} within {timeout} s")

    def close(self):
        self.client.close()


def raw_request(port, pdu, unit=1, transaction=0x1234, timeout=2.0):
    """Sends one Modbus TCP frame with this PDU; returns the reply's PDU (b'' if none)."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(struct.pack(">HHHB", transaction, 0, len(pdu) + 1, unit) + pdu)
        header = s.recv(7)
        if len(header) < 7:
            return b""
        length = struct.unpack(">H", header[4:6])[0]
        return s.recv(length - 1)
