#!/usr/bin/env python3
"""Writes the fixtures of `emcy-decode diff` (our own frames, candump -l
text; no third-party trace is copied): one machine's start-up told three
ways.

- fixtures/diff-good.log: nodes 2 (an I/O module) and 3 (a CiA 402 drive)
  boot; the master reads their identity (0x1018 sub 1, expedited), sets
  both producer heartbeat times to 1 s (0x1017), maps node 3's TPDO1 to
  the statusword and the position actual value (0x1A00, 0x1800 sub 1),
  starts every node, then enables the drive by controlword (RPDO 0x203);
  both heartbeat every second; node 2 raises 0x4310 at 6 s and clears it
  at 8 s.
- fixtures/diff-aborted.log: the same, but node 2 aborts the write of its
  producer heartbeat time (0x06090030, value range exceeded): the one
  difference `diff` must name.
- fixtures/diff-retimed.log: the same frames an hour later, every frame
  moved by up to 0.4 ms, and other position values in the drive's PDOs:
  only timing and process data differ, so `diff` finds no difference.

Run from the repository root:  python3 scripts/make_diff_fixtures.py
"""

import os

BASE = 1700000000  # 2023-11-14T22:13:20Z
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def le(value, size):
    return value.to_bytes(size, "little")


def sdo_write(frames, t, node, index, sub, value, answer=None):
    """An expedited download of 4 bytes and the node's answer (a confirm,
    or the abort code given)."""
    req = bytes([0x23]) + le(index, 2) + bytes([sub]) + le(value, 4)
    frames.append((t, 0x600 + node, req))
    if answer is None:
        resp = bytes([0x60]) + le(index, 2) + bytes([sub, 0, 0, 0, 0])
    else:
        resp = bytes([0x80]) + le(index, 2) + bytes([sub]) + le(answer, 4)
    frames.append((t + 0.005, 0x580 + node, resp))


def sdo_read(frames, t, node, index, sub, value):
    """An expedited upload of 4 bytes."""
    frames.append((t, 0x600 + node, bytes([0x40]) + le(index, 2) + bytes([sub, 0, 0, 0, 0])))
    frames.append((t + 0.005, 0x580 + node, bytes([0x43]) + le(index, 2) + bytes([sub]) + le(value, 4)))


def start_up(abort_heartbeat=False, position_step=100):
    f = []
    f.append((0.000, 0x702, b"\x00"))
    f.append((0.010, 0x703, b"\x00"))
    sdo_read(f, 0.050, 2, 0x1018, 1, 0x0000009A)
    sdo_read(f, 0.060, 3, 0x1018, 1, 0x0000006A)
    sdo_read(f, 0.070, 3, 0x1000, 0, 0x00020192)
    answer = 0x06090030 if abort_heartbeat else None
    sdo_write(f, 0.100, 2, 0x1017, 0, 1000, answer)
    sdo_write(f, 0.120, 3, 0x1017, 0, 1000)
    sdo_write(f, 0.140, 3, 0x1A00, 0, 0)
    sdo_write(f, 0.150, 3, 0x1A00, 1, 0x60410010)
    sdo_write(f, 0.160, 3, 0x1A00, 2, 0x60640020)
    sdo_write(f, 0.170, 3, 0x1A00, 0, 2)
    sdo_write(f, 0.180, 3, 0x1800, 1, 0x183)
    f.append((0.300, 0x000, b"\x01\x00"))
    # The drive's statusword every 100 ms, the master's controlword at each
    # step of the enable sequence.
    enable = [(1.0, 0x0006), (1.5, 0x0007), (2.0, 0x000F)]
    for t, cw in enable:
        f.append((t - 0.02, 0x203, le(cw, 2)))
    for k in range(4, 100):
        t = k / 10
        if t < 1.0:
            sw = 0x0250
        elif t < 1.5:
            sw = 0x0231
        elif t < 2.0:
            sw = 0x0233
        else:
            sw = 0x0237
        position = (k * position_step) & 0xFFFFFFFF
        f.append((t + 0.003, 0x183, le(sw, 2) + le(position, 4)))
    for s in range(1, 10):
        f.append((s + 0.050, 0x702, b"\x05"))
        f.append((s + 0.060, 0x703, b"\x05"))
    f.append((6.020, 0x082, bytes.fromhex("1043090000000000")))
    f.append((8.020, 0x082, bytes.fromhex("0000000000000000")))
    f.sort(key=lambda x: x[0])
    return f


def write(name, frames, offset=0.0, jitter=False):
    lines = []
    for i, (t, cob, data) in enumerate(frames):
        # A fixed pattern of moves below 0.4 ms: frames are at least 1 ms
        # apart, so the order stays.
        moved = t + offset + ((i * 7919) % 400) / 1e6 if jitter else t + offset
        lines.append(f"({BASE + moved:.6f}) can0 {cob:03X}#{data.hex().upper()}\n")
    with open(os.path.join(ROOT, "fixtures", name), "w") as out:
        out.writelines(lines)


def main():
    write("diff-good.log", start_up())
    write("diff-aborted.log", start_up(abort_heartbeat=True))
    write("diff-retimed.log", start_up(position_step=37), offset=3600.0, jitter=True)


if __name__ == "__main__":
    main()
