"""The handshake by hand, as a PLC programmer would try it with mbpoll (README's command lines):
write CMD=1 and REQ_ID, wait for ACK_ID, read the pose as floats (ABCD = mbpoll -B), compare with
the simulator's ground truth. mbpoll numbers registers from 1: register N is reference N+1.
usage: test_mbpoll.py PIPELOC_BINARY PORT"""
import re
import subprocess
import sys
import time
import unittest

from plc_harness import Service, mssd, rot_zyx

BINARY, PORT = sys.argv[1], int(sys.argv[2])


def mbpoll(*args):
    cmd = ["mbpoll", "-m", "tcp", "-p", str(PORT), "-a", "1", "-1", "-0"] + list(args)
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=10)
    return out.returncode, out.stdout + out.stderr


def values(text):
    return {int(m.group(1)): m.group(2) for m in re.finditer(r"^\[(\d+)\]:\s+(\S+)", text, re.M)}


class Mbpoll(unittest.TestCase):
    def test_locate_by_hand(self):
        svc = Service(BINARY, PORT, seed=5)
        try:
            svc.wait_listening()
            for req_id in (11, 12, 13):
                # -0: register numbers from 0, like the map. CMD=1 at 0, REQ_ID at 1, one FC16 write.
                code, out = mbpoll("-r", "0", "-t", "4", "127.0.0.1", "1", str(req_id))
                self.assertEqual(code, 0, out)
                end = time.time() + 30
                while time.time() < end:
                    code, out = mbpoll("-r", "10", "-c", "2", "-t", "4", "127.0.0.1")
                    regs = values(out)
                    if int(regs.get(11, -1)) == req_id:
                        break
                    time.sleep(0.05)
                self.assertEqual(int(regs[11]), req_id, out)
                if int(regs[10]) == 2:  # DONE_OK
                    break
            self.assertEqual(int(regs[10]), 2, "no pose in three LOCATEs")
            code, out = mbpoll("-r", "18", "-c", "1", "-t", "4:int", "-B", "127.0.0.1")
            frame = int(values(out)[18])
            code, out = mbpoll("-r", "20", "-c", "7", "-t", "4:float", "-B", "127.0.0.1")
            self.assertEqual(code, 0, out)
            f = values(out)
            x, y, z, rx, ry, rz, score = (float(f[20 + 2 * i]) for i in range(7))
            err = min(mssd(svc.vertices, (rot_zyx(rx, ry, rz), [x, y, z]), gt) for gt in svc.truth_of_frame(frame))
            print(f"mbpoll: pose x {x} y {y} z {z} rx {rx} ry {ry} rz {rz} score {score}: {err:.2f} mm off")
            self.assertLessEqual(err, 10.0)
            # Writing a service-owned register is refused with an exception.
            code, out = mbpoll("-r", "10", "-t", "4", "127.0.0.1", "0")
            self.assertNotEqual(code, 0)
            self.assertIn("Illegal data address", out)
        finally:
            self.assertEqual(svc.stop(), 0, svc.output())


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
