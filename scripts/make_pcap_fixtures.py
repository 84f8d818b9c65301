#!/usr/bin/env python3
"""Writes the pcap and pcapng fixtures (fixtures/*.pcap, fixtures/*.pcapng).

They were made by this script, byte by byte with the struct module (no
capture tool, no third-party library), from the frames of
fixtures/s300.log (the S300 sequence: boot-up, SDO identity reads, EMCYs
0x4310, 0x3120, resets, a second boot-up) plus frames of our own:

- s300.pcap           pcap, microseconds, little-endian file,
                      LINKTYPE_CAN_SOCKETCAN (227) with the id word
                      big-endian as the link type defines; channel "0".
- s300.ns-be.pcap     pcap, nanoseconds, big-endian file, LINUX_SLL (113),
                      the id word in the file's (big-endian) byte order.
- s300.swapped.pcap   pcap, microseconds, little-endian, link type 227 with
                      the id word stored little-endian, as scapy writes it:
                      the reader detects it and says so in a note.
- s300.pcapng         pcapng, little-endian: interface 0 "can0" LINUX_SLL
                      with if_tsresol 9 (ns) carrying the S300 sequence;
                      interface 1 "lin0" LIN (212) with LIN packets
                      (skipped); interface 2 "can1" LINUX_SLL2 with
                      if_tsresol 2^-10 s and node 5's EMCYs; interface 3
                      without if_name (channel "3"), LINUX_SLL, if_tsoffset
                      1700000000 s, an ARP packet (another protocol:
                      skipped) and node 6's EMCYs; a name resolution and an
                      interface statistics block (not lines).
- sdo-startup.pcap    pcap, link type 227: fixtures/sdo-startup.log (written
                      by scripts/make_sdo_fixtures.py, run that first).
- bus-errors.pcap     pcap, link type 227: fixtures/bus-errors.log with
                      its error frames (written by fixtures/make_fixtures.py,
                      run that first).
- network-guarding.pcap  pcap, link type 227: fixtures/network-guarding.log,
                      its guard requests as remote frames (CAN_RTR_FLAG).
- sync-gaps.pcap      pcap, link type 227: fixtures/sync-gaps.log (written by
                      scripts/make_sync_fixtures.py, run that first).
- mixed.pcapng        pcapng, big-endian section: link type 227 (id word
                      big-endian) and LINUX_SLL with CAN FD (a 72-byte
                      canfd_frame, FD by length, and protocol 0x000D), a
                      classic EMCY, an FD frame, a remote frame, an error
                      frame and an extended frame on EMCY ids (none of them
                      an EMCY), an EMCY too short to decode; then damage: a
                      block declaring 4 GiB, a packet on an interface no
                      block declares, a classic frame of 9 bytes, and a
                      last EMCY after them (reading goes on).

Run from the repository root:  python3 scripts/make_pcap_fixtures.py
then refresh the golden outputs:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import os
import re
import struct

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIXTURES = os.path.join(ROOT, "fixtures")

EFF = 0x80000000
RTR = 0x40000000
ERR = 0x20000000


def s300_frames():
    """(seconds, microseconds, id, data) of fixtures/s300.log."""
    frames = []
    pattern = re.compile(r"\((\d+)\.(\d{6})\) can0 ([0-9A-F]{3})#([0-9A-F]*)")
    with open(os.path.join(FIXTURES, "s300.log")) as f:
        for line in f:
            m = pattern.match(line)
            if m:
                frames.append(
                    (int(m[1]), int(m[2]), int(m[3], 16), bytes.fromhex(m[4]))
                )
    return frames


def log_frames(name):
    """(seconds, microseconds, id word, data) of a candump log fixture,
    error frames (id with the error flag) included."""
    frames = []
    pattern = re.compile(r"\((\d+)\.(\d{6})\) can0 ([0-9A-F]{3}|[0-9A-F]{8})#(R|[0-9A-F]*)$")
    with open(os.path.join(FIXTURES, name)) as f:
        for line in f:
            m = pattern.match(line.strip())
            if m:
                word = int(m[3], 16)
                data = b""
                if m[4] == "R":
                    word |= 0x40000000  # CAN_RTR_FLAG: a remote request
                else:
                    data = bytes.fromhex(m[4])
                frames.append((int(m[1]), int(m[2]), word, data))
    return frames


def can_frame(order, word, data, fd_flags=0, pad_to=None):
    """struct can_frame / canfd_frame: id word, length, flags, 2 reserved."""
    body = struct.pack(order + "I", word) + bytes([len(data), fd_flags, 0, 0]) + data
    if pad_to is not None:
        body += bytes(pad_to - len(body))
    return body


def sll(protocol, frame):
    """LINUX_SLL header: packet type 1 (broadcast), ARPHRD_CAN (280)."""
    return struct.pack(">HHH8sH", 1, 280, 0, bytes(8), protocol) + frame


def sll2(protocol, ifindex, frame):
    """LINUX_SLL2 header: protocol, reserved, ifindex, ARPHRD_CAN, type, addr."""
    return struct.pack(">HHIHBB8s", protocol, 0, ifindex, 280, 1, 0, bytes(8)) + frame


# ---- pcap ------------------------------------------------------------------------------


def pcap(order, nanos, linktype, records):
    magic = 0xA1B23C4D if nanos else 0xA1B2C3D4
    out = struct.pack(order + "IHHiIII", magic, 2, 4, 0, 0, 262144, linktype)
    for secs, frac, data in records:
        out += struct.pack(order + "IIII", secs, frac, len(data), len(data)) + data
    return out


# ---- pcapng ----------------------------------------------------------------------------


def block(order, kind, body):
    body += bytes(-len(body) % 4)
    length = 12 + len(body)
    return struct.pack(order + "II", kind, length) + body + struct.pack(order + "I", length)


def options(order, opts):
    out = b""
    for code, value in opts:
        out += struct.pack(order + "HH", code, len(value)) + value
        out += bytes(-len(value) % 4)
    if opts:
        out += bytes(4)  # opt_endofopt
    return out


def shb(order):
    body = struct.pack(order + "IHHq", 0x1A2B3C4D, 1, 0, -1)
    body += options(order, [(4, b"scripts/make_pcap_fixtures.py")])  # shb_userappl
    return block(order, 0x0A0D0D0A, body)


def idb(order, linktype, opts):
    return block(order, 1, struct.pack(order + "HHI", linktype, 0, 0) + options(order, opts))


def epb(order, iface, units, data):
    body = struct.pack(
        order + "IIIII", iface, units >> 32, units & 0xFFFFFFFF, len(data), len(data)
    )
    return block(order, 6, body + data)


def write(name, data):
    with open(os.path.join(FIXTURES, name), "wb") as f:
        f.write(data)
    print(f"fixtures/{name}: {len(data)} bytes")


def main():
    frames = s300_frames()

    # s300.pcap: 227, id word big-endian, file little-endian, microseconds.
    write(
        "s300.pcap",
        pcap(
            "<",
            False,
            227,
            [(s, us, can_frame(">", ident, data)) for s, us, ident, data in frames],
        ),
    )

    # s300.ns-be.pcap: LINUX_SLL, big-endian file (and id word), nanoseconds.
    write(
        "s300.ns-be.pcap",
        pcap(
            ">",
            True,
            113,
            [
                (s, us * 1000 + 7, sll(0x000C, can_frame(">", ident, data)))
                for s, us, ident, data in frames
            ],
        ),
    )

    # s300.swapped.pcap: 227 with the id word little-endian (scapy).
    write(
        "s300.swapped.pcap",
        pcap(
            "<",
            False,
            227,
            [(s, us, can_frame("<", ident, data)) for s, us, ident, data in frames],
        ),
    )

    # s300.pcapng: four interfaces, little-endian.
    o = "<"
    out = shb(o)
    out += idb(o, 113, [(2, b"can0"), (3, b"bench 3 drive bus"), (9, bytes([9]))])
    out += idb(o, 212, [(2, b"lin0")])
    out += idb(o, 276, [(2, b"can1"), (9, bytes([0x80 | 10]))])
    out += idb(o, 113, [(14, struct.pack(o + "q", 1700000000))])
    # A name resolution block (one IPv4 record, then the end): not a line.
    nrb = struct.pack(o + "HH", 1, 8) + bytes([10, 0, 0, 1]) + b"rig\0" + bytes(4)
    out += block(o, 4, nrb)
    lin_at = {3: b"\x3c\x01\x02\x03\x04\x05\x06\x07\x08\x99", 12: b"\x7d\x10\x20\xaa"}
    for i, (s, us, ident, data) in enumerate(frames):
        ns = (s * 1_000_000 + us) * 1000
        out += epb(o, 0, ns, sll(0x000C, can_frame(o, ident, data)))
        if i in lin_at:
            out += epb(o, 1, ns // 1000 + 1, lin_at[i])
    # can1 (2^-10 s ticks): node 5 raises 0x2310 (1/1024 s after a second)
    # and resets it half a second later.
    out += epb(o, 2, 1024 * 1700000008 + 1, sll2(0x000C, 4, can_frame(o, 0x85, bytes([0x10, 0x23, 0x03, 0, 0, 0, 0, 0]))))
    out += epb(o, 2, 1024 * 1700000008 + 512, sll2(0x000C, 4, can_frame(o, 0x85, bytes(8))))
    # Interface 3: no name, if_tsoffset; an ARP packet (skipped), node 6.
    arp = struct.pack(">HHH8sH", 0, 1, 6, bytes(8), 0x0806) + bytes(28)
    out += epb(o, 3, 9_000_000, arp)
    out += epb(o, 3, 9_500_000, sll(0x000C, can_frame(o, 0x86, bytes([0x00, 0x50, 0x01, 0, 0, 0, 0, 0]))))
    # Interface statistics for can0: not a line.
    out += block(o, 5, struct.pack(o + "III", 0, 0, 0))
    write("s300.pcapng", out)

    # mixed.pcapng: a big-endian section, FD, the frames that are not EMCYs,
    # then damage.
    o = ">"
    out = shb(o)
    out += idb(o, 227, [(2, b"vcan0"), (9, bytes([6]))])
    out += idb(o, 113, [(2, b"vcan1"), (9, bytes([6]))])
    t = 1700000000_000000
    emcy = bytes([0x10, 0x43, 0x09, 0x01, 0, 0, 0, 0])
    reset = bytes(8)
    packets = [
        (0, can_frame(">", 0x701, b"\x00")),  # boot-up of node 1
        (0, can_frame(">", 0x81, emcy)),  # EMCY 0x4310
        (0, can_frame(">", 0x81, emcy, fd_flags=0x01, pad_to=72)),  # FD by length: no EMCY
        (1, sll(0x000D, can_frame(o, 0x82, emcy[:3] + bytes(9), fd_flags=0x05))),  # FD: no EMCY
        (0, can_frame(">", RTR | 0x81, b"")),  # remote: no EMCY
        (0, can_frame(">", ERR | 0x04, bytes([0, 0x04, 0, 0, 0, 0, 0, 0]))),  # error frame
        (1, sll(0x000C, can_frame(o, EFF | 0x81, emcy))),  # extended 0x81: no EMCY
        (1, sll(0x000C, can_frame(o, 0x82, b"\x10\x43"))),  # too short to decode
        (1, sll(0x000C, can_frame(o, 0x82, bytes([0x30, 0x81, 0x11, 0, 0, 0, 0, 0])))),
    ]
    for i, (iface, data) in enumerate(packets):
        out += epb(o, iface, t + i * 100_000, data)
    # A block declaring 4 GiB (its bytes are skipped to the next block).
    bad = bytearray(epb(o, 0, t + 1_000_000, can_frame(">", 0x81, reset)))
    bad[4:8] = struct.pack(">I", 0xFFFFFFFF)
    out += bytes(bad)
    out += epb(o, 7, t + 1_100_000, can_frame(">", 0x81, reset))  # no interface 7
    nine = bytes([0x10, 0x43, 0x09, 0x01, 0, 0, 0, 0, 0])
    out += epb(o, 1, t + 1_200_000, sll(0x000C, can_frame(o, 0x81, nine)))  # 9 bytes
    out += epb(o, 0, t + 1_300_000, can_frame(">", 0x81, reset))  # the reset, read
    write("mixed.pcapng", out)

    # network-guarding.pcap: node guarding, its requests remote frames.
    write(
        "network-guarding.pcap",
        pcap(
            "<",
            False,
            227,
            [
                (s, us, can_frame(">", word, data))
                for s, us, word, data in log_frames("network-guarding.log")
            ],
        ),
    )

    # sync-gaps.pcap: fixtures/sync-gaps.log (SYNC, PDOs and heartbeats
    # with periods, SYNC gaps), so that timing every frame decoded (pcap)
    # can be held to timing the candump hot loop's lines.
    write(
        "sync-gaps.pcap",
        pcap(
            "<",
            False,
            227,
            [
                (s, us, can_frame(">", word, data))
                for s, us, word, data in log_frames("sync-gaps.log")
            ],
        ),
    )

    # sdo-startup.pcap: fixtures/sdo-startup.log (every kind of SDO
    # transfer), for the cross-check of our SDO decoding with tshark's.
    write(
        "sdo-startup.pcap",
        pcap(
            "<",
            False,
            227,
            [
                (s, us, can_frame(">", word, data))
                for s, us, word, data in log_frames("sdo-startup.log")
            ],
        ),
    )

    # bus-errors.pcap: fixtures/bus-errors.log (SYNC with a gap, a burst of
    # error frames of every class the kernel sends, counters rising to bus
    # off), link type 227, id word big-endian, as candump would capture it.
    write(
        "bus-errors.pcap",
        pcap(
            "<",
            False,
            227,
            [(s, us, can_frame(">", word, data)) for s, us, word, data in log_frames("bus-errors.log")],
        ),
    )


if __name__ == "__main__":
    main()
