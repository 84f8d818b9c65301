#!/usr/bin/env python3
"""Writes fixtures/sync-gaps.log (our own frames, candump -l text; no
third-party trace is copied): a machine whose SYNC producer stumbles.

A master sends SYNC (0x080) every 10 ms; two drives (nodes 1 and 2) answer
each SYNC with TPDO1 (0x181, 0x182, 8 bytes) and receive RPDO1 (0x201,
0x202, 4 bytes) from the master; both heartbeat every 100 ms. At 1.0 s the
SYNC producer skips four cycles (a 50 ms gap, the SYNC at 1.05 s ends it)
and node 2 reports EMCY 0x8240 (SYNC error) 2 ms after that SYNC. At 1.8 s
SYNC stops for good while the heartbeats go on to 2.2 s. Times carry a
deterministic jitter of up to 0.3 ms on the PDOs.

Run from the repository root:  python3 scripts/make_sync_fixtures.py
"""

T0 = 1_700_000_000.0


def main():
    frames = []

    def add(t, cob, data):
        frames.append((round(T0 + t, 6), cob, data))

    # Heartbeats every 100 ms, nodes 1 and 2, from 0 to 2.2 s.
    for i in range(23):
        add(i * 0.1 + 0.0005, 0x701, "05")
        add(i * 0.1 + 0.0007, 0x702, "05")
    sync_times = [i * 0.01 for i in range(101)]  # 0 .. 1.0 s
    sync_times += [1.05 + i * 0.01 for i in range(76)]  # 1.05 .. 1.80 s
    for k, t in enumerate(sync_times):
        add(t, 0x080, "")
        jitter = ((k * 37) % 7) * 0.00005
        add(t + 0.0002 + jitter, 0x181, f"{k % 256:02X}00000000001027")
        add(t + 0.0004 + jitter, 0x182, f"{k % 256:02X}00000000002027")
        add(t + 0.0006, 0x201, "0F000000")
        add(t + 0.0008, 0x202, "0F000000")
    add(1.052, 0x082, "4082110000000000")
    frames.sort(key=lambda f: f[0])
    with open("fixtures/sync-gaps.log", "w") as out:
        for t, cob, data in frames:
            out.write(f"({t:.6f}) can0 {cob:03X}#{data}\n")


if __name__ == "__main__":
    main()
