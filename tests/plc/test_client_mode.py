"""Client mode: the service polls a PLC (a pymodbus server) for CMD/REQ_ID and writes the result
block, STATUS and ACK_ID there. The PLC goes away and comes back; the service reconnects and
serves the next request; the heartbeat moves again.
usage: test_client_mode.py PIPELOC_BINARY PORT"""
import os
import socket
import subprocess
import sys
import time
import unittest

from pymodbus.client import ModbusTcpClient

from plc_harness import *  # noqa: F401,F403

BINARY, PORT = sys.argv[1], int(sys.argv[2])
HERE = os.path.dirname(os.path.abspath(__file__))


def start_plc(registers=100):
    proc = subprocess.Popen([sys.executable, os.path.join(HERE, "fake_plc.py"), str(PORT), str(registers)])
    end = time.time() + 20
    while time.time() < end:
        try:
            socket.create_connection(("127.0.0.1", PORT), timeout=0.2).close()
            return proc
        except OSError:
            time.sleep(0.05)
    proc.kill()
    raise AssertionError("the fake PLC did not start")


class PlcSide:
    def __init__(self):
        self.c = ModbusTcpClient("127.0.0.1", port=PORT, timeout=3)
        assert self.c.connect()

    def read(self, count=SIZE):
        rr = self.c.read_holding_registers(0, count, slave=1)
        assert not rr.isError(), rr
        return rr.registers

    def command(self, cmd, req_id, timeout=30, count=SIZE):
        assert not self.c.write_registers(CMD, [cmd, req_id], slave=1).isError()
        end = time.time() + timeout
        while time.time() < end:
            regs = self.read(count)
            if regs[ACK_ID] == req_id:
                return regs
            time.sleep(0.02)
        raise AssertionError(f"no ACK_ID {req_id}")


class ClientMode(unittest.TestCase):
    def test_poll_and_reconnect(self):
        plc_proc = start_plc()
        svc = Service(BINARY, PORT, mode="client", extra_toml="", seed=7, plc_toml="write_held = true")
        try:
            plc = PlcSide()
            regs = plc.command(LOCATE, 1)
            self.assertIn(regs[STATUS], (DONE_OK, DONE_NONE))
            self.assertGreaterEqual(regs[REGIONS], 1)  # HELD .. REGIONS written too
            if regs[STATUS] == DONE_OK:
                err = svc.best_error(u32(regs, CYCLES), decode_pose(regs))
                print(f"client mode: pose {err:.2f} mm from a true pipe")
                self.assertLessEqual(err, 10.0)
            beat = plc.read()[HEARTBEAT]
            time.sleep(0.6)
            self.assertGreater(plc.read()[HEARTBEAT], beat)
            plc.c.close()

            # The PLC goes away ...
            plc_proc.kill()
            plc_proc.wait()
            time.sleep(1.5)
            self.assertIsNone(svc.proc.poll(), "the service keeps running without its PLC")
            # ... and comes back (a restarted PLC: its registers start from zero again), programmed
            # for the map without HELD .. REGIONS (plc.write_held set all the same): the service says
            # so once and runs as before.
            plc_proc = start_plc(POSE_END)
            plc = PlcSide()
            end = time.time() + 15
            while time.time() < end and plc.read(POSE_END)[HEARTBEAT] == 0:
                time.sleep(0.1)
            self.assertGreater(plc.read(POSE_END)[HEARTBEAT], 0, "the heartbeat tells the PLC the link is back")
            regs = plc.read(POSE_END)  # a restarted PLC's zeros are no command: nothing runs, no error
            self.assertEqual((regs[STATUS], regs[ERROR], regs[ACK_ID]), (READY, 0, 0))
            regs = plc.command(LOCATE, 2, count=POSE_END)
            self.assertIn(regs[STATUS], (DONE_OK, DONE_NONE))
            regs = plc.command(LOCATE, 3, count=POSE_END)
            self.assertIn(regs[STATUS], (DONE_OK, DONE_NONE))
            plc.c.close()
            self.assertIn("lost", svc.output())
            self.assertEqual(svc.output().count("refused registers 42..44"), 1, svc.output())
        finally:
            code = svc.stop()
            plc_proc.kill()
            plc_proc.wait()
        self.assertEqual(code, 0, svc.output())

    def test_registers_beyond_qz_left_alone_by_default(self):
        """Without plc.write_held a PLC block programmed for 0..41 is never written beyond it, however
        large the PLC's area: its registers 42..44 keep what the PLC holds there."""
        plc_proc = start_plc()
        svc = Service(BINARY, PORT, mode="client", extra_toml="", seed=7)
        try:
            plc = PlcSide()
            for req_id in (1, 2, 3):
                regs = plc.command(LOCATE, req_id)
                if regs[STATUS] == DONE_OK:  # a pose, so REGIONS would be at least 1 if written
                    break
            self.assertEqual(regs[STATUS], DONE_OK)
            self.assertEqual(regs[HELD:SIZE], [0, 0, 0])
            plc.c.close()
        finally:
            code = svc.stop()
            plc_proc.kill()
            plc_proc.wait()
        self.assertEqual(code, 0, svc.output())


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
