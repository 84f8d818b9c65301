#!/usr/bin/env python3
"""Writes fixtures/identity.log (our own frames, candump -l text; no
third-party trace is copied): a master reading who is on the bus.

Nodes 2 (a CiA 401 I/O module of a vendor our profiles do not know) and 5
(a Kollmorgen CiA 402 drive) boot. The master reads each node's device type
(0x1000) and identity object (0x1018 subs 1-4) by expedited uploads; node
5's device name (0x1008, "AKD Servo Drive", 15 bytes) by a segmented upload
with its size given; node 2's software version (0x100A, "1.02", 4 bytes)
expedited. Node 5's hardware version (0x1009) is asked and never answered.
Both heartbeat every second; node 5 raises 0x4310 at 2.5 s.

Run from the repository root:  python3 scripts/make_identity_fixtures.py
"""

T0 = 1_700_000_000.0


def le32(v):
    return v.to_bytes(4, "little").hex().upper()


def main():
    lines = []
    t = [0.0]

    def add(dt, cob, data):
        t[0] += dt
        lines.append(f"({T0 + t[0]:.6f}) can0 {cob:03X}#{data}")

    def read(node, index, sub, value):
        idx = index.to_bytes(2, "little").hex().upper()
        add(0.002, 0x600 + node, f"40{idx}{sub:02X}00000000")
        add(0.001, 0x580 + node, f"43{idx}{sub:02X}{le32(value)}")

    add(0.0, 0x702, "00")
    add(0.001, 0x705, "00")
    for node, identity in [
        (2, [0x000F0191, 0x0000009A, 0x00000401, 0x00010003, 0x00C0FFEE]),
        (5, [0x00020192, 0x0000006A, 0x00001234, 0x00010002, 0x00ABCDEF]),
    ]:
        read(node, 0x1000, 0, identity[0])
        for sub, value in enumerate(identity[1:], start=1):
            read(node, 0x1018, sub, value)
    # Node 5's device name, segmented: size 15, segments of 7, 7 and 1.
    name = b"AKD Servo Drive"
    add(0.002, 0x605, "4008100000000000")
    add(0.001, 0x585, "41081000" + le32(len(name)))
    toggle = 0
    for i in range(0, len(name), 7):
        chunk = name[i : i + 7]
        last = i + 7 >= len(name)
        add(0.002, 0x605, f"{0x60 | toggle << 4:02X}00000000000000")
        cmd = toggle << 4 | (7 - len(chunk)) << 1 | int(last)
        add(0.001, 0x585, f"{cmd:02X}" + (chunk + bytes(7 - len(chunk))).hex().upper())
        toggle ^= 1
    # Node 2's software version, expedited (4 bytes: n = 0, e = s = 1).
    add(0.002, 0x602, "400A100000000000")
    add(0.001, 0x582, "430A1000" + b"1.02".hex().upper())
    # Node 5's hardware version: asked, never answered.
    add(0.002, 0x605, "4009100000000000")
    # Heartbeats, operational, every second; node 5's EMCY at 2.5 s.
    for k in range(1, 4):
        t[0] = float(k)
        add(0.0, 0x702, "05")
        add(0.001, 0x705, "05")
        if k == 2:
            t[0] = 2.5
            add(0.0, 0x085, "1043080000000000")
    with open("fixtures/identity.log", "w") as out:
        out.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
