"""DESIGN.md's handshake driven by a real Modbus client (pymodbus) against `pipeloc serve` on the
sim source: LOCATE, NEXT through every result to "no further result", CLEAR_ERROR, a bad command,
the heartbeat, and exception replies that leave the server serving.
usage: test_handshake.py PIPELOC_BINARY PORT"""
import math
import socket
import sys
import time
import unittest

from plc_harness import *  # noqa: F401,F403

BINARY, PORT = sys.argv[1], int(sys.argv[2])


class Handshake(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.svc = Service(BINARY, PORT)
        cls.svc.wait_listening()
        cls.plc = Plc(PORT)

    @classmethod
    def tearDownClass(cls):
        cls.plc.close()
        code = cls.svc.stop()
        assert code == 0, f"serve exited {code}:\n{cls.svc.output()}"

    def locate_until_found(self, tries=4):
        for _ in range(tries):
            regs = self.plc.command(LOCATE)
            self.assertIn(regs[STATUS], (DONE_OK, DONE_NONE), f"status {regs[STATUS]} error {regs[ERROR]}")
            if regs[STATUS] == DONE_OK:
                return regs
        self.fail("no pose in %d LOCATEs" % tries)

    def assert_pose_nan(self, regs):
        for i in range(POSE, POSE_END, 2):
            self.assertTrue(math.isnan(f32(regs, i)), f"register {i} is not NaN")

    def test_1_locate_next_clear(self):
        regs = self.locate_until_found()
        frame = u32(regs, CYCLES)  # the sim delivers one frame per LOCATE
        self.assertEqual(regs[ERROR], 0)
        self.assertGreaterEqual(regs[COUNT], 1)
        self.assertEqual(regs[INDEX], 0)
        self.assertGreater(regs[CYCLE_MS], 0)
        score = f32(regs, SCORE)
        self.assertTrue(0 < score <= 1, score)
        # Euler angles and quaternion describe the same rotation.
        rot, t = decode_pose(regs)
        q = [f32(regs, QUAT + 2 * i) for i in range(4)]
        self.assertAlmostEqual(sum(v * v for v in q), 1.0, places=4)
        rq = rot_quat(*q)
        for r in range(3):
            for c in range(3):
                self.assertAlmostEqual(rot[r][c], rq[r][c], places=4)
        # What it saw and did not hand out: the pose came from a region.
        self.assertGreaterEqual(regs[REGIONS], 1)
        self.assertEqual(regs[HELD] == 0, regs[HELD_WHY] == 0)
        err = self.svc.best_error(frame, (rot, t))
        print(f"LOCATE: {regs[COUNT]} poses, first within {err:.2f} mm of a true pipe (frame {frame})")
        self.assertLessEqual(err, 10.0)

        # NEXT walks the ranked results, then reports that there is no further one.
        count = regs[COUNT]
        for index in range(1, count):
            regs = self.plc.command(NEXT)
            self.assertEqual(regs[STATUS], DONE_OK)
            self.assertEqual(regs[INDEX], index)
            self.assertEqual(regs[COUNT], count)
            self.assertFalse(math.isnan(f32(regs, POSE)))
        regs = self.plc.command(NEXT)
        self.assertEqual(regs[STATUS], STATUS_ERROR)
        self.assertEqual(regs[ERROR], 6)
        self.assert_pose_nan(regs)

        regs = self.plc.command(CLEAR_ERROR)
        self.assertEqual(regs[STATUS], READY)
        self.assertEqual(regs[ERROR], 0)
        self.assert_pose_nan(regs)

    def test_2_bad_command(self):
        regs = self.plc.command(9)
        self.assertEqual(regs[STATUS], STATUS_ERROR)
        self.assertEqual(regs[ERROR], 5)
        self.assert_pose_nan(regs)
        regs = self.plc.command(CLEAR_ERROR)
        self.assertEqual(regs[STATUS], READY)

    def test_3_heartbeat(self):
        first = self.plc.read()[HEARTBEAT]
        time.sleep(1.1)
        later = self.plc.read()[HEARTBEAT]
        self.assertGreaterEqual((later - first) % 65536, 2, "HEARTBEAT moves at least twice a second")

    def test_4_exceptions(self):
        c = self.plc.client
        # A service-owned register.
        rr = c.write_register(STATUS, 7, slave=1)
        self.assertTrue(rr.isError())
        self.assertEqual(rr.exception_code, 2)
        rr = c.write_registers(CMD, [1, 2, 3], slave=1)  # CMD, REQ_ID and a reserved register
        self.assertTrue(rr.isError())
        # Past the map.
        rr = c.read_holding_registers(0, SIZE + 1, slave=1)
        self.assertTrue(rr.isError())
        self.assertEqual(rr.exception_code, 2)
        # Tables that do not exist.
        self.assertTrue(c.read_coils(0, 1, slave=1).isError())
        self.assertTrue(c.read_input_registers(0, 1, slave=1).isError())
        # An illegal function (0x41 is not a Modbus function), answered without stalling the
        # server (libmodbus would sleep its 0.5 s response timeout before this reply).
        start = time.time()
        reply = raw_request(PORT, bytes([0x41, 0, 0]))
        self.assertLess(time.time() - start, 0.25)
        self.assertEqual(reply[0], 0xC1)
        self.assertEqual(reply[1], 1)
        # Garbage and a half request cost only their own connection.
        with socket.create_connection(("127.0.0.1", PORT)) as s:
            s.sendall(b"\xff" * 40)
        half = socket.create_connection(("127.0.0.1", PORT))
        half.sendall(bytes([0, 1, 0, 0, 0, 6, 1, 3]))  # header and function code, no address
        start = time.time()
        regs = self.plc.read()
        self.assertLess(time.time() - start, 1.0)
        half.close()
        self.assertEqual(regs[STATUS], READY)
        # ... and the service still does its work.
        regs = self.locate_until_found()
        self.assertEqual(regs[STATUS], DONE_OK)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
