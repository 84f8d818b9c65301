#!/usr/bin/env python3
"""Writes the incident fixtures (our own frames, candump -l text; no
third-party trace is copied), each with a known answer that
tests/integration/incidents.rs checks:

- fixtures/incident-silent-producer.log: nodes 3, 5 and 7 heartbeat every
  100 ms; 5 and 7 consume 3's heartbeat (0x1016 written by SDO, 300 ms).
  Node 3 stops at 5 s; node 5 raises 0x8130 at 5.26 s, before the tool's
  own deadline for 3 passes, node 7 at 5.28 s, and both drop to
  pre-operational. Root: node 3 falling silent.
- fixtures/incident-silent-producer-permuted.log: the same with the node
  numbers permuted (7 is the producer, 3 and 5 consume it): the root is
  the producer whatever its number.
- fixtures/incident-repeated.log: the first fixture's fault twice, 30 s
  apart, the master resetting every node in between: two incidents.
- fixtures/incident-reset-all.log: the master resets every node (NMT
  0x81 to node 0), each boots 150 ms later, the master starts them: no
  incident.
- fixtures/incident-rpdo-timeout.log: node 4 receives node 3's TPDO1
  (0x1400 sub 1 = 0x183 written by SDO); node 3 stops sending at 5 s,
  node 4 raises 0x8250 (RPDO timeout); node 2 stays well. Root: node 3.
- fixtures/incident-undervoltage.log: drives 1 to 5 raise 0x3220 (DC link
  under-voltage) within 20 ms: a common cause, root the first of them.

Run from the repository root:  python3 scripts/make_incident_fixtures.py
"""

import os

BASE = 1700000000  # 2023-11-14T22:13:20Z
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def le(value, size):
    return value.to_bytes(size, "little")


def sdo_write(f, t, node, index, sub, value):
    f.append((t, 0x600 + node, bytes([0x23]) + le(index, 2) + bytes([sub]) + le(value, 4)))
    f.append((t + 0.002, 0x580 + node, bytes([0x60]) + le(index, 2) + bytes([sub, 0, 0, 0, 0])))


def heartbeats(f, node, start, stop, state=0x05, period=0.1, phase=0.0):
    k = 0
    while True:
        t = start + phase + k * period
        if t >= stop:
            break
        f.append((round(t, 6), 0x700 + node, bytes([state])))
        k += 1


def start_up(f, nodes, o=0.0):
    """Boot-ups, pre-operational heartbeats, the master's start at 0.3 s."""
    for i, n in enumerate(nodes):
        f.append((o + 0.01 * i, 0x700 + n, b"\x00"))
        heartbeats(f, n, o + 0.05, o + 0.3, state=0x7F, phase=0.001 * i)
    f.append((o + 0.3, 0x000, b"\x01\x00"))


def silent_producer(producer, consumers, offset=0.0, end=8.0):
    f = []
    o = offset
    start_up(f, [producer] + consumers, o)
    for i, c in enumerate(consumers):
        sdo_write(f, o + 0.1 + 0.01 * i, c, 0x1016, 1, (producer << 16) | 300)
    heartbeats(f, producer, o + 0.31, o + 5.0, phase=0.001)
    for i, c in enumerate(consumers):
        heartbeats(f, c, o + 0.31, o + 5.3, phase=0.003 + 0.002 * i)
        t = o + 5.26 + 0.02 * i
        f.append((t, 0x80 + c, bytes.fromhex("3081110000000000")))
        heartbeats(f, c, t + 0.05, o + end, state=0x7F, phase=0.0)
    return f


def write(name, frames):
    frames.sort(key=lambda x: x[0])
    with open(os.path.join(ROOT, "fixtures", name), "w") as out:
        for t, cob, data in frames:
            out.write(f"({BASE + t:.6f}) can0 {cob:03X}#{data.hex().upper()}\n")


def main():
    write("incident-silent-producer.log", silent_producer(3, [5, 7]))
    write("incident-silent-producer-permuted.log", silent_producer(7, [3, 5]))

    # The master resets everyone at 29.9 s, and it happens again.
    twice = silent_producer(3, [5, 7], end=29.9)
    twice.append((29.9, 0x000, b"\x81\x00"))
    twice += silent_producer(3, [5, 7], offset=30.0)
    write("incident-repeated.log", twice)

    f = []
    start_up(f, [2, 3, 4])
    for n in (2, 3, 4):
        heartbeats(f, n, 0.31, 2.0, phase=0.001 * n)
    f.append((2.0, 0x000, b"\x81\x00"))
    start_up(f, [2, 3, 4], 2.15)
    for n in (2, 3, 4):
        heartbeats(f, n, 2.46, 5.0, phase=0.001 * n)
    write("incident-reset-all.log", f)

    f = []
    start_up(f, [2, 3, 4])
    sdo_write(f, 0.1, 4, 0x1400, 1, 0x183)
    heartbeats(f, 2, 0.31, 8.0, phase=0.002)
    heartbeats(f, 4, 0.31, 8.0, phase=0.004)
    heartbeats(f, 3, 0.31, 5.0, phase=0.003)
    k = 0
    while 0.45 + k * 0.05 < 5.0:
        f.append((round(0.45 + k * 0.05, 6), 0x183, le(k & 0xFFFF, 2)))
        k += 1
    f.append((5.15, 0x084, bytes.fromhex("5082110000000000")))
    write("incident-rpdo-timeout.log", f)

    f = []
    start_up(f, [1, 2, 3, 4, 5])
    for n in range(1, 6):
        heartbeats(f, n, 0.31, 6.0, phase=0.001 * n)
    for i, n in enumerate([4, 2, 5, 1, 3]):
        f.append((3.0 + 0.004 * i, 0x80 + n, bytes.fromhex("2032050000000000")))
    write("incident-undervoltage.log", f)


if __name__ == "__main__":
    main()
