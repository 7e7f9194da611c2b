"""firmware-host/PipelocHandshake.st, read as a PLC programmer would copy it: on a timeout the
function block must report 100 (no answer within Timeout) or 101 (heartbeat lost) from the timers'
outputs *before* it resets the Watch timer (TON: IN := FALSE clears Q). Today's main reset it
first, so every timeout came out as 101. A textual check: the repository has no ST runtime.
usage: test_handshake_st.py [PATH_TO_ST]"""
import os
import re
import sys

here = os.path.dirname(os.path.abspath(__file__))
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "firmware-host", "PipelocHandshake.st")
with open(path) as f:
    text = re.sub(r"\(\*.*?\*\)", "", f.read(), flags=re.S)  # comments out
branch = text.split("ELSIF Watch.Q OR BeatTimer.Q THEN", 1)[1].split("END_IF;\n20:", 1)[0]
uses_q = branch.find("IF Watch.Q THEN ErrorCode := 100")
resets = branch.find("Watch(IN := FALSE)")
assert uses_q >= 0 and resets >= 0, "timeout branch not found as expected"
assert uses_q < resets, "Watch.Q is read after Watch(IN := FALSE) cleared it: a timeout is reported as 101"
print("PipelocHandshake.st: timeout code read before the timer reset")
