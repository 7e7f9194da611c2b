// systemd's notify protocol without libsystemd: a datagram to $NOTIFY_SOCKET ("READY=1",
// "WATCHDOG=1", "STOPPING=1", "STATUS=..."). Without the variable (not run by systemd) it does
// nothing.
#pragma once

namespace pipeloc {

bool sd_notify_send(const char* state);
// The watchdog interval systemd asks for (WatchdogSec), in ms; 0 when none.
long sd_watchdog_ms();

}  // namespace pipeloc
