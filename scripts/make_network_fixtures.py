#!/usr/bin/env python3
"""Writes the NMT network fixtures (our own frames, candump -l text; no
third-party trace is copied). Each shows one way a real CANopen network's
NMT and error control traffic reads:

- fixtures/network-reset-scan.log: the NMT master resets every id 1-127 one
  after the other, twice over; only nodes 3, 17 and 42 are on the bus: each
  boots up after its reset, the master sets node 3's producer heartbeat
  time by SDO, starts every node (node 0) and they heartbeat operational.
  The 124 ids that never answer are no nodes, only one line.
- fixtures/network-guarding.log: node 10 is guarded: its guard time
  (0x100C = 100 ms) and life time factor (0x100D = 3) are written by SDO,
  the master asks by remote frame on 0x70A every 100 ms and the node
  answers one byte, the toggle bit alternating. One reply repeats its
  toggle bit, one request gets no reply, then the node is silent for 600 ms
  (longer than its 300 ms life time) while the master keeps asking, and
  answers again. The master also asks id 12, which never answers.
- fixtures/network-nmt-grace.log: nodes 5 and 6 heartbeat every 100 ms. The
  master starts both; node 5's heartbeat 3 ms after the start still says
  pre-operational (it was queued before the node acted on the start), the
  next says operational; node 6 keeps saying pre-operational after the
  grace: it ignored the start. Then node 5 is stopped and reset.
- fixtures/network-drift.log: nodes 7 and 8 are configured by SDO to
  heartbeat every 1.4 s (0x1017); node 7 beats every 1.44 s (drifts),
  node 8 every 1.405 s (within the tolerance).

Run from the repository root:  python3 scripts/make_network_fixtures.py
then refresh the goldens:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import os

BASE = 1700000000  # 2023-11-14T22:13:20Z
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Trace:
    def __init__(self):
        self.frames = []

    def add(self, ms, cob_id, data):
        """A data frame (bytes) or, with data None, a remote frame."""
        self.frames.append((ms, len(self.frames), cob_id, data))

    def write(self, name):
        lines = []
        for ms, _, cob_id, data in sorted(self.frames):
            us = round(ms * 1000)
            stamp = "(%d.%06d)" % (BASE + us // 1_000_000, us % 1_000_000)
            body = "R" if data is None else bytes(data).hex().upper()
            lines.append("%s can0 %03X#%s\n" % (stamp, cob_id, body))
        path = os.path.join(ROOT, "fixtures", name)
        with open(path, "w") as f:
            f.writelines(lines)
        print("wrote", path, len(lines), "frames")


def nmt(t, ms, command, node):
    t.add(ms, 0x000, [command, node])


def sdo_write(t, ms, node, index, sub, value, size):
    """An expedited download of `size` bytes and the node's confirmation."""
    command = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
    payload = list(value.to_bytes(4, "little"))
    t.add(ms, 0x600 + node, [command, index & 0xFF, index >> 8, sub] + payload)
    t.add(ms + 1, 0x580 + node, [0x60, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])


def reset_scan():
    t = Trace()
    present = {3: 0.0, 17: 0.0, 42: 0.0}
    # Two passes over every id, 2 ms apart; the nodes boot 20 ms after
    # the first reset they get.
    ms = 0.0
    for scan in range(2):
        for node in range(1, 128):
            if scan == 1 and node in present:
                continue
            nmt(t, ms, 0x81, node)
            if scan == 0 and node in present:
                present[node] = ms + 20
                t.add(ms + 20, 0x700 + node, [0x00])
            ms += 2
    sdo_write(t, ms + 10, 3, 0x1017, 0, 100, 2)
    start = ms + 50
    nmt(t, start, 0x01, 0)
    for node, boot in present.items():
        beat = boot + 100
        while beat < start + 1500:
            state = 0x05 if beat > start + 10 else 0x7F
            t.add(beat, 0x700 + node, [state])
            beat += 100
    t.write("network-reset-scan.log")


def guarding():
    t = Trace()
    node = 10
    t.add(0, 0x700 + node, [0x00])
    sdo_write(t, 20, node, 0x100C, 0, 100, 2)
    sdo_write(t, 30, node, 0x100D, 0, 3, 1)
    nmt(t, 50, 0x01, node)
    toggle = 0
    state = 0x05
    ms = 100
    for i in range(40):
        t.add(ms, 0x700 + node, None)
        silent = 20 <= i < 26
        if i == 10:
            pass  # no reply to this request
        elif not silent:
            if i == 14:
                toggle ^= 1  # the reply repeats the toggle bit of the one before
            t.add(ms + 2, 0x700 + node, [(toggle << 7) | state])
            toggle ^= 1
        ms += 100
    # An id that never answers.
    for i in range(3):
        t.add(1005 + 100 * i, 0x700 + 12, None)
    t.write("network-guarding.log")


def nmt_grace():
    t = Trace()
    for node in (5, 6):
        t.add(node, 0x700 + node, [0x00])
    nmt(t, 497, 0x01, 5)
    nmt(t, 497.5, 0x01, 6)
    for beat in range(1, 20):
        ms = beat * 100
        # Node 5's heartbeat at 500 ms was queued before the start.
        five = 0x7F if ms <= 500 else 0x05
        if ms > 1200:
            five = 0x04
        t.add(ms + 0, 0x705, [five])
        # Node 6 never acts on it.
        t.add(ms + 3, 0x706, [0x7F])
    nmt(t, 1150, 0x02, 5)
    nmt(t, 1950, 0x81, 5)
    t.add(1990, 0x705, [0x00])
    t.add(2090, 0x705, [0x7F])
    t.write("network-nmt-grace.log")


def drift():
    t = Trace()
    for node, period in ((7, 1440), (8, 1405)):
        sdo_write(t, node, node, 0x1017, 0, 1400, 2)
        ms = 100 + node
        for _ in range(12):
            t.add(ms, 0x700 + node, [0x05])
            ms += period
    t.write("network-drift.log")


if __name__ == "__main__":
    reset_scan()
    guarding()
    nmt_grace()
    drift()
