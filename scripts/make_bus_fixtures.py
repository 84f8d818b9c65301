#!/usr/bin/env python3
"""Writes the bus fixtures (our own frames, candump -l text; no third-party
trace is copied). Error frames are written as candump logs them: an 8-digit
id with the error flag 0x20000000 and the SocketCAN error classes of
linux/can/error.h, and the 8 bytes that header defines.

- fixtures/bus-off.log: nodes 5 and 6 heartbeat every 200 ms on can0.
  At 8.0 s a burst of error frames begins (stuff errors in the data field
  with the TX error counter climbing, then TX error passive); node 5
  falls silent during it (it went bus-off: it cannot send) and comes back
  at 10.5 s with EMCY 0x8140 "recovered from bus-off", then heartbeats
  and an EMCY reset. At 14.0 s node 6 is silent for 2 s with no error
  frame on the bus: a heartbeat loss, no bus-off. At 18.0 s the logging
  controller itself goes bus-off and restarts 300 ms later; node 6's EMCY
  0x8110 (CAN overrun) in that burst names it. At 22.0 s a lone no-ACK
  error frame without counters, and at 24.0 s node 6 boots up after
  being silent across it: a bus-off of node 6 inferred from the boot-up.

Run from the repository root:  python3 scripts/make_bus_fixtures.py
then refresh the goldens:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import os

BASE = 1700000000  # 2023-11-14T22:13:20Z
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

ERR = 0x20000000
TX_TIMEOUT, LOSTARB, CRTL, PROT, TRX, ACK, BUSOFF, BUSERROR, RESTARTED, CNT = (
    0x1, 0x2, 0x4, 0x8, 0x10, 0x20, 0x40, 0x80, 0x100, 0x200)


class Trace:
    def __init__(self):
        self.frames = []

    def data(self, t, ident, data):
        self.frames.append((t, "%03X#%s" % (ident, data.hex().upper())))

    def error(self, t, classes, data=bytes(8)):
        self.frames.append((t, "%08X#%s" % (ERR | classes, data.hex().upper())))

    def write(self, name):
        self.frames.sort(key=lambda f: f[0])
        path = os.path.join(ROOT, "fixtures", name)
        with open(path, "w") as out:
            for t, frame in self.frames:
                ms = round(t * 1000)
                out.write("(%d.%06d) can0 %s\n" % (BASE + ms // 1000, (ms % 1000) * 1000, frame))


def heartbeats(trace, node, start, end, period=0.2, state=0x05, skip=()):
    t = start
    while t < end - 1e-9:
        if not any(a <= t < b for a, b in skip):
            trace.data(t, 0x700 + node, bytes([state]))
        t = round(t + period, 3)


def bus_off():
    tr = Trace()
    tr.data(0.0, 0x705, bytes([0]))
    tr.data(0.001, 0x706, bytes([0]))
    # Node 5: silent from its last heartbeat before 8.1 to 10.6.
    heartbeats(tr, 5, 0.2, 30.0, skip=[(8.1, 10.6)])
    # Node 6: silent 14.0-16.0 (no errors), and 22.0-24.0 across a lone
    # error frame, back with a boot-up.
    heartbeats(tr, 6, 0.201, 30.0, skip=[(14.0, 16.0), (22.0, 24.2)])
    # The burst: stuff errors in the data field on transmission, the TX
    # counter climbing; then TX error passive.
    for i in range(12):
        t = round(8.0 + 0.05 * i, 3)
        tec = min(8 * (i + 1), 255)
        tr.error(t, PROT | BUSERROR | CNT, bytes([0, 0, 0x84, 0x0A, 0, 0, tec, 0]))
    tr.error(8.6, CRTL | CNT, bytes([0, 0x20, 0, 0, 0, 0, 128, 0]))
    # Node 5 back: EMCY 0x8140 (register: communication), then its reset.
    tr.data(10.5, 0x085, bytes([0x40, 0x81, 0x11, 0, 0, 0, 0, 0]))
    tr.data(10.7, 0x085, bytes([0, 0, 0, 0, 0, 0, 0, 0]))
    # The logging controller: no ACK, then bus-off, then restarted.
    for i in range(4):
        tr.error(round(18.0 + 0.02 * i, 3), ACK | CNT, bytes([0, 0, 0, 0, 0, 0, 200 + 16 * i, 0]))
    tr.error(18.1, BUSOFF)
    tr.data(18.2, 0x086, bytes([0x10, 0x81, 0x11, 0, 0, 0, 0, 0]))
    tr.error(18.4, RESTARTED)
    tr.data(19.0, 0x086, bytes([0, 0, 0, 0, 0, 0, 0, 0]))
    # A lone no-ACK, node 6 silent across it, back with a boot-up.
    tr.error(22.5, ACK)
    tr.data(24.2, 0x706, bytes([0]))
    tr.write("bus-off.log")


if __name__ == "__main__":
    bus_off()
