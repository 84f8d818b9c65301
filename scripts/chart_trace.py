#!/usr/bin/env python3
"""Writes a candump log for looking at the timeline chart of a long, busy
trace (a user's words: "a one-hour 12-node trace with 1,776 errors is a
barcode"). Deterministic (fixed seed); nothing in it comes from a real
trace.

- 12 nodes on can0, one hour from 2023-11-14 08:00:00 UTC;
- heartbeats every second (operational), node 7's cable pulled for two
  minutes (an outage), node 11 reset once (boot-up);
- about 150 errors per node, about 1,800 in all: each node raises codes
  of a few classes (some of one class, so the legend shows shades),
  lasting from 50 ms to a few minutes, cleared by a reset frame;
  node 3 flaps (many errors of under a second: merged bars).

    python3 scripts/chart_trace.py > /tmp/hour.log
    cargo run --release -- --format html /tmp/hour.log > /tmp/hour.html
    scripts/screenshot.sh /tmp/hour.log /tmp/hour.png 1600 1000
"""

import random
import sys

START = 1_699_948_800  # 2023-11-14 08:00:00 UTC
HOUR = 3600.0
NODES = range(1, 13)
CODES = [
    0x2310, 0x2320, 0x3110, 0x3120, 0x3210, 0x3220, 0x4210, 0x4310,
    0x5113, 0x6010, 0x7121, 0x8110, 0x8130, 0x8611, 0xFF01, 0xFF02,
]
REGISTER = {0x2: 0x03, 0x3: 0x05, 0x4: 0x09, 0x5: 0x01, 0x6: 0x01,
            0x7: 0x81, 0x8: 0x11, 0xF: 0x81}


def main() -> None:
    rnd = random.Random(20)
    frames = []  # (time, text)
    for node in NODES:
        frames.append((0.0005 * node, f"{0x700 + node:03X}#00"))
        pulled = (1500.0, 1620.0) if node == 7 else None
        t = 1.0
        while t < HOUR:
            if not (pulled and pulled[0] <= t < pulled[1]):
                frames.append((t + 0.001 * node, f"{0x700 + node:03X}#05"))
            t += 1.0
        if node == 11:
            frames.append((2400.0005, f"{0x70B:03X}#00"))
        codes = rnd.sample(CODES, 4)
        t = rnd.uniform(5, 40)
        n = 0
        while t < HOUR - 1 and n < 150:
            code = rnd.choice(codes)
            if node == 3 and 600 < t < 900:
                length = rnd.uniform(0.05, 0.5)
            else:
                length = rnd.choice([rnd.uniform(0.05, 2)] * 3
                                    + [rnd.uniform(2, 20)] * 2
                                    + [rnd.uniform(20, 90)])
            reg = REGISTER.get(code >> 12, 0x01)
            data = f"{code & 0xFF:02X}{code >> 8:02X}{reg:02X}0000000000"
            frames.append((t, f"{0x80 + node:03X}#{data}"))
            end = min(t + length, HOUR - 0.5)
            frames.append((end, f"{0x80 + node:03X}#0000000000000000"))
            n += 1
            gap = 1.0 if node == 3 and 600 < t < 900 else rnd.uniform(1, 16)
            t = end + gap
    frames.sort(key=lambda f: f[0])
    out = sys.stdout
    for t, text in frames:
        us = round(t * 1_000_000)
        out.write(f"({START + us // 1_000_000}.{us % 1_000_000:06d}) can0 {text}\n")


if __name__ == "__main__":
    main()
