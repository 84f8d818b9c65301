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
- fixtures/lss-time.log: an LSS session. The master sends every node to
  waiting, asks for non-configured nodes (one answers), selects one by its
  identity (vendor 0xA5, product 0x1234, revision 0x00010002, serial
  0xBEEF), gives it node-id 5, bit timing 500 kbit/s (table 0 index 2) and
  has it store them; then a second node (serial 0xBEF0) is refused
  node-id 200 (out of range) and given 6; an inquiry reads node-id 6
  back; the new bit rate is activated; nodes 5 and 6 boot up. A TIME
  producer sends a stamp every second, its clock 1.5 s ahead of the
  trace's and gaining 2 ms a stamp.

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


def pad(data):
    return bytes(data) + bytes(8 - len(data))


def lss_time():
    tr = Trace()
    master = lambda t, data: tr.data(t, 0x7E5, pad(data))
    node = lambda t, data: tr.data(t, 0x7E4, pad(data))

    def select(t, serial):
        for i, value in enumerate([0xA5, 0x1234, 0x00010002, serial]):
            master(round(t + 0.01 * i, 3), [0x40 + i] + list(value.to_bytes(4, "little")))
        node(round(t + 0.045, 3), [0x44])

    master(0.5, [0x04, 0])
    master(0.6, [0x4C])
    node(0.61, [0x50])
    select(1.0, 0xBEEF)
    master(1.1, [0x11, 5])
    node(1.11, [0x11, 0])
    master(1.2, [0x13, 0, 2])
    node(1.21, [0x13, 0])
    master(1.3, [0x17])
    node(1.31, [0x17, 0])
    master(1.4, [0x04, 0])
    select(2.0, 0xBEF0)
    master(2.1, [0x11, 200])
    node(2.11, [0x11, 1])
    master(2.2, [0x11, 6])
    node(2.21, [0x11, 0])
    master(3.0, [0x5E])
    node(3.01, [0x5E, 6])
    master(3.1, [0x04, 0])
    master(3.5, [0x15, 0xE8, 0x03])
    tr.data(4.6, 0x705, bytes([0]))
    tr.data(4.61, 0x706, bytes([0]))
    # TIME: the producer's clock 1.5 s ahead, gaining 2 ms a stamp.
    for i in range(6):
        ms = (BASE + i) * 1000 + 1500 + 2 * i
        days, in_day = divmod(ms, 86_400_000)
        data = (in_day).to_bytes(4, "little") + (days - 5113).to_bytes(2, "little")
        tr.data(float(i), 0x100, data)
    tr.write("lss-time.log")


if __name__ == "__main__":
    bus_off()
    lss_time()
