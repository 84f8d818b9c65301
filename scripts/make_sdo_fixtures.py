#!/usr/bin/env python3
"""Writes fixtures/sdo-startup.log (our own frames, candump -l text; no
third-party trace is copied): a master starting up two nodes by SDO, with
every kind of transfer and every way one can end.

Node 3 is a CiA 402 drive, node 4 a CiA 401 I/O module. Both boot. The
master then:

- reads each node's device type (0x1000) and vendor id (0x1018 sub 1),
  expedited;
- reads node 3's device name (0x1008, "Servo X12", 9 bytes) by a segmented
  upload with its size given, and node 4's (0x1008, "IO4", 3 bytes)
  expedited with its size given;
- writes 20 bytes to node 3's 0x2010 sub 1 by a block download (one
  sub-block of 3 segments, no CRC);
- configures node 3's TPDO1 (0x1800 sub 1, 0x1A00 subs 0-1), expedited;
- writes 70 bytes to node 3's 0x2000 sub 0, segmented (a value over the 64
  bytes shown: its hash is told);
- writes node 4's 0x6200 sub 1, which node 4 aborts (0x06020000, no such
  object);
- downloads 4100 bytes of "firmware" to node 4's 0x1F50 sub 1, segmented
  with its size given (586 segments: over the 4 KiB read segment by
  segment, so counted from the size);
- asks node 3 for 0x2001 sub 0 and gets no answer (unanswered, told 1 s
  later); node 4 raises EMCY 0x8130 half a second after that request;
- asks node 9, which never speaks, for its device type (unanswered, and no
  node 9).

Both heartbeat every 500 ms throughout.

Two copies for `diff`: fixtures/sdo-startup-aborted.log, where node 3
aborts the 70-byte download after its first segment (0x08000020: data
cannot be stored), and fixtures/sdo-startup-retimed.log, the same frames an
hour later with every gap 1.25 times as long.

Run from the repository root:  python3 scripts/make_sdo_fixtures.py
then  python3 scripts/make_pcap_fixtures.py  (fixtures/sdo-startup.pcap)
and refresh the golden outputs:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import os

T0 = 1_700_000_000.0
FIXTURES = os.path.join(os.path.dirname(__file__), "..", "fixtures")


def le(v, n=4):
    return v.to_bytes(n, "little").hex().upper()


def write(file_name, abort_2000=False, stretch=1.0, t0=T0):
    lines = []
    t = [0.0]
    beat = [0.5]

    def add(dt, cob, data):
        t[0] += dt * stretch
        # Heartbeats every 500 ms, between the master's frames.
        while t[0] >= beat[0]:
            for node in (3, 4):
                lines.append(f"({t0 + beat[0]:.6f}) can0 {0x700 + node:03X}#05")
            beat[0] += 0.5
        lines.append(f"({t0 + t[0]:.6f}) can0 {cob:03X}#{data}")

    def idx(index, sub):
        return le(index, 2) + f"{sub:02X}"

    def read(node, index, sub, value, size=4):
        add(0.002, 0x600 + node, f"40{idx(index, sub)}00000000")
        cmd = 0x43 | (4 - size) << 2
        add(0.001, 0x580 + node, f"{cmd:02X}{idx(index, sub)}{le(value)}")

    def write(node, index, sub, value, size=4, abort=None):
        cmd = 0x23 | (4 - size) << 2
        add(0.002, 0x600 + node, f"{cmd:02X}{idx(index, sub)}{le(value)}")
        if abort is None:
            add(0.001, 0x580 + node, f"60{idx(index, sub)}00000000")
        else:
            add(0.001, 0x580 + node, f"80{idx(index, sub)}{le(abort)}")

    def segmented_download(node, index, sub, data, abort=None):
        add(0.002, 0x600 + node, f"21{idx(index, sub)}{le(len(data))}")
        add(0.001, 0x580 + node, f"60{idx(index, sub)}00000000")
        toggle = 0
        for i in range(0, len(data), 7):
            chunk = data[i : i + 7]
            last = i + 7 >= len(data)
            cmd = toggle << 4 | (7 - len(chunk)) << 1 | int(last)
            add(0.001, 0x600 + node, f"{cmd:02X}" + (chunk + bytes(7 - len(chunk))).hex().upper())
            if abort is not None:
                add(0.001, 0x580 + node, f"80{idx(index, sub)}{le(abort)}")
                return
            add(0.001, 0x580 + node, f"{0x20 | toggle << 4:02X}00000000000000")
            toggle ^= 1

    add(0.0, 0x703, "00")
    add(0.001, 0x704, "00")
    read(3, 0x1000, 0, 0x00020192)
    read(3, 0x1018, 1, 0x0000009A)
    read(4, 0x1000, 0, 0x000F0191)
    read(4, 0x1018, 1, 0x0000009A)
    # Node 3's name, segmented upload, size 9: segments of 7 and 2.
    name = b"Servo X12"
    add(0.002, 0x603, "4008100000000000")
    add(0.001, 0x583, "41081000" + le(len(name)))
    toggle = 0
    for i in range(0, len(name), 7):
        chunk = name[i : i + 7]
        last = i + 7 >= len(name)
        add(0.002, 0x603, f"{0x60 | toggle << 4:02X}00000000000000")
        cmd = toggle << 4 | (7 - len(chunk)) << 1 | int(last)
        add(0.001, 0x583, f"{cmd:02X}" + (chunk + bytes(7 - len(chunk))).hex().upper())
        toggle ^= 1
    # Node 4's name, expedited, 3 bytes.
    read(4, 0x1008, 0, int.from_bytes(b"IO4", "little"), size=3)
    # Block download of 20 bytes to node 3's 0x2010 sub 1: initiate (s = 1,
    # no CRC), the node's answer (block size 127), segments 1, 2 and the
    # last 3 (0x83), the acknowledgement of 3, the end (n = 1 unused byte
    # in the last segment: 0xC5) and the node's end response.
    block = bytes(range(0x10, 0x10 + 20))
    add(0.002, 0x603, f"C2{idx(0x2010, 1)}{le(len(block))}")
    add(0.001, 0x583, f"A0{idx(0x2010, 1)}7F000000")
    for seq, i in [(1, 0), (2, 7), (0x83, 14)]:
        chunk = block[i : i + 7]
        add(0.001, 0x603, f"{seq:02X}" + (chunk + bytes(7 - len(chunk))).hex().upper())
    add(0.001, 0x583, "A2037F0000000000")
    add(0.001, 0x603, "C500000000000000")
    add(0.001, 0x583, "A100000000000000")
    # TPDO1 of node 3: disabled, mapped to the statusword, enabled.
    write(3, 0x1800, 1, 0x80000183)
    write(3, 0x1A00, 0, 0, size=1)
    write(3, 0x1A00, 1, 0x60410010)
    write(3, 0x1A00, 0, 1, size=1)
    write(3, 0x1800, 1, 0x00000183)
    # 70 bytes to node 3's 0x2000: shown by its first 64 and its hash.
    segmented_download(3, 0x2000, 0, bytes(range(70)), 0x08000020 if abort_2000 else None)
    # Node 4 has no 0x6200 sub 1.
    write(4, 0x6200, 1, 0xFF, size=1, abort=0x06020000)
    # Firmware to node 4: 4100 bytes.
    segmented_download(4, 0x1F50, 1, bytes((i * 7) & 0xFF for i in range(4100)))
    # Node 3 never answers this one; node 4's EMCY comes 0.5 s later.
    add(0.010, 0x603, f"40{idx(0x2001, 0)}00000000")
    add(0.500, 0x084, "3081110000000000")
    # A scan of an id nobody has.
    add(0.200, 0x609, f"40{idx(0x1000, 0)}00000000")
    add(1.500, 0x603, f"40{idx(0x1000, 0)}00000000")
    add(0.001, 0x583, f"43{idx(0x1000, 0)}{le(0x00020192)}")

    path = os.path.join(FIXTURES, file_name)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"fixtures/{file_name}: {len(lines)} lines")


def main():
    write("sdo-startup.log")
    write("sdo-startup-aborted.log", abort_2000=True)
    write("sdo-startup-retimed.log", stretch=1.25, t0=T0 + 3600)


if __name__ == "__main__":
    main()
