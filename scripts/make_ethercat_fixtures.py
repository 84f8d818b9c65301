#!/usr/bin/env python3
"""Writes the EtherCAT capture fixtures (fixtures/stoeber-ecat.pcapng and
fixtures/stoeber-ecat.pcap).

Made by this script byte by byte with the struct module (no capture tool,
no third-party library), with the pcap/pcapng writers of
scripts/make_pcap_fixtures.py. Two STÖBER slaves at station addresses 1001
and 1002 on one EtherCAT segment, captured at the master's port
(LINKTYPE_ETHERNET, interface "eth0"); the drives send their emergencies as
the STÖBER EtherCAT manual describes: CoE emergency (mailbox type 3, CoE
service 1), 0x4310 with E82 = 41 when entering the fault, 0x0000 with
E82 = 0x1E when it is acknowledged.

Packet by packet (the Wireshark frame number is the line):
  1  ARP request: not EtherCAT (skipped, not an EtherCAT frame)
  2  BRD of the AL status register 0x0130: EtherCAT, no mailbox
  3  FPWR 1001 @0x1000, CoE SDO request: upload 0x1018 sub 1, on its way
     out (working counter 0: no slave took it yet, not a message)
  4  the same frame back (working counter 1): the request
  5  FPRD 1001 @0x1080: CoE SDO response 0x1018:01 = 0x000000B9 (the
     STÖBER vendor id: profile "stoeber" from the trace); FPRD 1002
     @0x1080 with working counter 0: an empty poll
  6  FPWR 1002 @0x1000: CoE SDO request, upload 0x1003 sub 5
  7  FPRD 1002 @0x1080: CoE SDO abort 0x06090011 (sub-index does not exist)
  8-57  cyclic process data every millisecond: LRW of 64 bytes (working
     counter 3) and empty polls of both mailboxes; 28-37 carry an 802.1Q
     VLAN tag; 40 is EtherCAT in UDP to port 0x88A4 over IPv4
  58  VLAN-tagged: LRW and 1001's emergency 0x4310, register 0x01, E82 = 41
      (0x29), E43 = 0 (the manual's example), mailbox counter 2
  59  1001's mailbox read again: the same emergency with the same counter,
      a retry (the master repeated a read it lost): not a second emergency
  60  1002's emergency 0x3210 (DC link over-voltage) with counter 2, and a
      CoE TxPDO (service 4) of 1001: counted, not read
  61  an EoE mailbox message (type 2) from 1002: counted, not read
  62  damaged: a datagram declares more data than the frame holds
      (malformed line)
  63  both acknowledgments in one frame: 1001 0x0000 E82 = 0x1E (counter
      3) and 1002 0x0000 (counter 3): two events on one line
  64  the last cyclic frame
  65-70  1001's error history (object 0x1003) read over CoE SDO: sub 0 = 2
      entries, sub 1 = 0x4310 (seen in the trace), sub 2 = 0x7305 (raised
      before the trace began)

Run from the repository root:  python3 scripts/make_ethercat_fixtures.py
then refresh the golden outputs:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import hashlib
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_pcap_fixtures import block, epb, options, pcap, shb, write  # noqa: E402

LINKTYPE_ETHERNET = 1
ETHERTYPE_ECAT = 0x88A4
START = 1_700_000_000

APRD, FPRD, FPWR, BRD, LRW = 1, 4, 5, 7, 12
SM0, SM1 = 0x1000, 0x1080
MASTER = bytes([0x02, 0, 0, 0, 0, 0x01])
BROADCAST = bytes([0xFF] * 6)


def datagram(cmd, adp, ado, data, wkc, more, declared=None):
    """Header (command, index, ADP, ADO, length with bit 15 = more
    follows, IRQ), data, working counter."""
    length = len(data) if declared is None else declared
    head = struct.pack("<BBHHHH", cmd, 0, adp, ado, length | (0x8000 if more else 0), 0)
    return head + data + struct.pack("<H", wkc)


def ecat_frame(datagrams):
    """The 2-byte EtherCAT header (length, type 1) and the datagrams, the
    'more follows' bits set on all but the last."""
    body = b""
    for i, (cmd, adp, ado, data, wkc, *rest) in enumerate(datagrams):
        body += datagram(cmd, adp, ado, data, wkc, i + 1 < len(datagrams), *rest)
    return struct.pack("<H", len(body) | 0x1000) + body


def ethernet(payload, ethertype=ETHERTYPE_ECAT, vlan=None):
    head = BROADCAST + MASTER
    if vlan is not None:
        head += struct.pack(">HH", 0x8100, vlan)
    frame = head + struct.pack(">H", ethertype) + payload
    return frame + bytes(max(0, 60 - len(frame)))  # Ethernet's minimum


def udp_ipv4(payload):
    udp = struct.pack(">HHHH", 0x88A4, 0x88A4, 8 + len(payload), 0) + payload
    ip = struct.pack(
        ">BBHHHBBH4s4s",
        0x45, 0, 20 + len(udp), 1, 0x4000, 64, 17, 0,
        bytes([192, 168, 1, 1]), bytes([192, 168, 1, 2]),
    )
    return ethernet(ip + udp, ethertype=0x0800)


def mailbox(kind, counter, body, size=None):
    """Mailbox header (length, address, channel/priority, type | counter
    << 4) and body, padded to the sync manager's size."""
    m = struct.pack("<HHBB", len(body), 0, 0, kind | counter << 4) + body
    return m + bytes((size or len(m)) - len(m))


def coe(service, counter, payload, size=48):
    return mailbox(3, counter, struct.pack("<H", service << 12) + payload, size)


def emcy(code, register, e82, e43=0):
    return struct.pack("<HBBB3s", code, register, e82, e43, bytes(3))


def empty_poll(station):
    return (FPRD, station, SM1, bytes(48), 0)


def lrw():
    return (LRW, 0, 0, bytes(range(64)), 3)


def packets():
    """(milliseconds after START, Ethernet frame)."""
    sdo_request = coe(2, 1, bytes([0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))
    out = [
        (0, bytes.fromhex("ffffffffffff020000000001080600010800060400010200000000"
                          "01c0a80101000000000000c0a80102")),
        (1, ethernet(ecat_frame([(BRD, 0, 0x0130, bytes(2), 2)]))),
        (2, ethernet(ecat_frame([(FPWR, 1001, SM0, sdo_request, 0)]))),
        (2, ethernet(ecat_frame([(FPWR, 1001, SM0, sdo_request, 1)]))),
        (3, ethernet(ecat_frame([
            (FPRD, 1001, SM1, coe(3, 1, bytes([0x43, 0x18, 0x10, 0x01, 0xB9, 0, 0, 0])), 1),
            empty_poll(1002),
        ]))),
        (4, ethernet(ecat_frame([
            (FPWR, 1002, SM0, coe(2, 1, bytes([0x40, 0x03, 0x10, 0x05, 0, 0, 0, 0])), 1),
        ]))),
        (5, ethernet(ecat_frame([
            (FPRD, 1002, SM1, coe(3, 1, bytes([0x80, 0x03, 0x10, 0x05, 0x11, 0x00, 0x09, 0x06])), 1),
        ]))),
    ]
    for i in range(50):
        frame = ecat_frame([lrw(), empty_poll(1001), empty_poll(1002)])
        if i == 32:
            packet = udp_ipv4(frame)
        else:
            packet = ethernet(frame, vlan=5 if 20 <= i < 30 else None)
        out.append((10 + i, packet))
    fault = coe(1, 2, emcy(0x4310, 0x01, 41, 0))
    out += [
        (60, ethernet(ecat_frame([lrw(), (FPRD, 1001, SM1, fault, 1), empty_poll(1002)]), vlan=5)),
        (61, ethernet(ecat_frame([lrw(), (FPRD, 1001, SM1, fault, 1), empty_poll(1002)]))),
        (62, ethernet(ecat_frame([
            lrw(),
            (FPRD, 1001, SM1, coe(4, 3, bytes(8)), 1),
            (FPRD, 1002, SM1, coe(1, 2, emcy(0x3210, 0x05, 7)), 1),
        ]))),
        (63, ethernet(ecat_frame([(FPRD, 1002, SM1, mailbox(2, 1, bytes(20), 48), 1)]))),
        (70, ethernet(ecat_frame([lrw(), (FPRD, 1001, SM1, bytes(8), 1, 200)]))),
        (100, ethernet(ecat_frame([
            lrw(),
            (FPRD, 1001, SM1, coe(1, 3, emcy(0x0000, 0x00, 0x1E)), 1),
            (FPRD, 1002, SM1, coe(1, 3, emcy(0x0000, 0x00, 0x1E)), 1),
        ]))),
        (101, ethernet(ecat_frame([lrw(), empty_poll(1001), empty_poll(1002)]))),
    ]
    # 1001's pre-defined error field (1003h) read over CoE: 2 entries, the
    # newest 0x4310 (seen in the trace), then 0x7305 (raised before it).
    for i, (sub, value) in enumerate([(0, 2), (1, 0x00294310), (2, 0x00017305)]):
        counter = 2 + i
        request = bytes([0x40, 0x03, 0x10, sub, 0, 0, 0, 0])
        response = bytes([0x43, 0x03, 0x10, sub]) + struct.pack("<I", value)
        out.append((110 + 2 * i, ethernet(ecat_frame([(FPWR, 1001, SM0, coe(2, counter, request), 1)]))))
        out.append((111 + 2 * i, ethernet(ecat_frame([(FPRD, 1001, SM1, coe(3, counter + 3, response), 1)]))))
    return out


def main():
    order = "<"
    pkts = packets()
    ng = shb(order)
    ng += block(order, 1, struct.pack(order + "HHI", LINKTYPE_ETHERNET, 0, 0)
                + options(order, [(2, b"eth0"), (9, bytes([9]))]))
    for ms, data in pkts:
        ng += epb(order, 0, (START * 1000 + ms) * 1_000_000, data)
    write("stoeber-ecat.pcapng", ng)
    records = [(START + ms // 1000, (ms % 1000) * 1000, data) for ms, data in pkts]
    write("stoeber-ecat.pcap", pcap(order, False, LINKTYPE_ETHERNET, records))
    fuzz_seeds(pkts)


def fuzz_seeds(pkts):
    """Seeds of the `ethercat` fuzz target (a framing byte, then an
    EtherCAT frame; framing 5 takes the whole packet): each distinct
    EtherCAT frame of the fixture, framed in turn every way."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = os.path.join(root, "fuzz", "corpus", "ethercat")
    os.makedirs(out, exist_ok=True)
    seen = set()
    for i, (_, data) in enumerate(pkts):
        at = 12
        while data[at:at + 2] == b"\x81\x00":
            at += 4
        if data[at:at + 2] != b"\x88\xa4":
            continue
        frame = data[at + 2:]
        if frame in seen:
            continue
        seen.add(frame)
        mode = len(seen) % 6
        seed = bytes([mode]) + (data if mode == 5 else frame)
        name = hashlib.sha1(seed).hexdigest()
        with open(os.path.join(out, name), "wb") as f:
            f.write(seed)
    print(f"fuzz/corpus/ethercat: {len(seen)} seeds")


if __name__ == "__main__":
    main()
