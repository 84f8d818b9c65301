#!/usr/bin/env python3
"""Writes the CiA 402 drive fixtures (our own frames, candump -L
text; no third-party trace is copied):

- fixtures/cia402-commissioning.log: node 5, a servo drive, commissioned by
  its master: boot-up, device type read (0x1000 = 0x00020192, CiA 402),
  TPDO1 remapped by SDO to statusword + error code (0x1A00, the COB-ID
  re-enabled with a segmented download), RPDO1 to the controlword (0x1600),
  NMT start, the enable sequence 0x06/0x07/0x0F, a fault (fault reaction
  active, fault, error code 0x7305) with its EMCY, a fault reset (controlword
  bit 7), the enable sequence again, recovery to operation enabled, the
  EMCY reset.
- fixtures/cia402-drive.dcf: the DCF of the same drive (the mapping the
  commissioning writes, vendor id 0x6A).
- fixtures/cia402-dcf.log: the same drive's traffic without the SDO
  configuration: only the DCF gives the mapping (decode with
  --dcf 5=fixtures/cia402-drive.dcf).
- fixtures/cia402-unknown.log: node 3, a CiA 402 drive by its device type,
  sending TPDO1 whose mapping nothing gives: nothing is decoded, one note.
- fixtures/cia402-not-drive.log (decoded with --assume-cia402-pdo): node 3,
  an I/O module (device type 0x000F0191, read by an expedited upload after
  its first TPDO1s), node 7, an encoder (0x00010196, read by a segmented
  upload), and node 5, a drive (0x00020192) with its TPDO1/RPDO1 traffic:
  only node 5's PDOs are read as a drive's.
- fixtures/cia402-controlword-read.log: node 5 configured by SDO, in fault;
  the master reads the controlword (0x6040 = 0x008F, bit 7 set) by an SDO
  upload, which is no fault reset; then resets the fault by RPDO (0x0080).
- fixtures/cia402-pdo-read.log: node 6, a drive whose master reads its
  TPDO1 mapping back (0x1A00 subs by expedited uploads, 0x1800 sub 1 by a
  segmented upload) and never writes it: TPDO1 is decoded with it.
- fixtures/sdo-block.log: SDO block transfers, interleaved on two nodes:
  node 4 takes a block download of 0x1F50 (its last segment 0x85), node 3
  gives its device type by a block upload, and a second block download to
  node 4, in sub-blocks of three, is aborted by the node mid sub-block.

Run from the repository root:  python3 scripts/make_cia402_fixtures.py
then refresh the goldens:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import os

BASE = 1700000000  # 2023-11-14T22:13:20Z
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NODE = 5
PERIOD_MS = 10


class Trace:
    def __init__(self):
        self.lines = []
        self.ms = 0.0

    def frame(self, cob_id, data, at_ms=None):
        t = self.ms if at_ms is None else at_ms
        secs = BASE + int(t // 1000)
        micros = int(round((t % 1000) * 1000))
        self.lines.append(
            "(%d.%06d) can0 %03X#%s" % (secs, micros, cob_id, bytes(data).hex().upper())
        )

    def step(self, ms):
        self.ms += ms

    def write(self, name):
        with open(os.path.join(ROOT, "fixtures", name), "w") as f:
            f.write("\n".join(self.lines) + "\n")


def u16(v):
    return [v & 0xFF, (v >> 8) & 0xFF]


def u32(v):
    return [v & 0xFF, (v >> 8) & 0xFF, (v >> 16) & 0xFF, (v >> 24) & 0xFF]


def sdo_write(t, node, index, sub, value, size):
    """An expedited download and its confirmation."""
    cmd = 0x23 | ((4 - size) << 2)
    t.frame(0x600 + node, [cmd] + u16(index) + [sub] + u32(value))
    t.step(1)
    t.frame(0x580 + node, [0x60] + u16(index) + [sub, 0, 0, 0, 0])
    t.step(1)


def sdo_write_segmented(t, node, index, sub, value):
    """A segmented download of four bytes: initiate with size, one segment."""
    t.frame(0x600 + node, [0x21] + u16(index) + [sub] + u32(4))
    t.step(1)
    t.frame(0x580 + node, [0x60] + u16(index) + [sub, 0, 0, 0, 0])
    t.step(1)
    # ccs 0, toggle 0, n = 3 unused bytes, c = 1 (last).
    t.frame(0x600 + node, [0x00 | (3 << 1) | 1] + u32(value) + [0, 0, 0])
    t.step(1)
    t.frame(0x580 + node, [0x20, 0, 0, 0, 0, 0, 0, 0])
    t.step(1)


def sdo_read(t, node, index, sub, value):
    t.frame(0x600 + node, [0x40] + u16(index) + [sub, 0, 0, 0, 0])
    t.step(1)
    t.frame(0x580 + node, [0x43] + u16(index) + [sub] + u32(value))
    t.step(1)


def configure_pdos(t, node):
    # TPDO1: statusword + error code; COB-ID switched off while mapping.
    sdo_write(t, node, 0x1800, 1, 0x80000180 + node, 4)
    sdo_write(t, node, 0x1A00, 0, 0, 1)
    sdo_write(t, node, 0x1A00, 1, 0x60410010, 4)
    sdo_write(t, node, 0x1A00, 2, 0x603F0010, 4)
    sdo_write(t, node, 0x1A00, 0, 2, 1)
    sdo_write_segmented(t, node, 0x1800, 1, 0x00000180 + node)
    # RPDO1: controlword.
    sdo_write(t, node, 0x1400, 1, 0x80000200 + node, 4)
    sdo_write(t, node, 0x1600, 0, 0, 1)
    sdo_write(t, node, 0x1600, 1, 0x60400010, 4)
    sdo_write(t, node, 0x1600, 0, 1, 1)
    sdo_write(t, node, 0x1400, 1, 0x00000200 + node, 4)


def run(t, node, phases):
    """Cycles of RPDO1 (controlword) then TPDO1 (statusword, error code):
    phases are (cycles, controlword, statusword, error code, emcy)."""
    for cycles, cw, sw, ec, emcy in phases:
        for i in range(cycles):
            t.frame(0x200 + node, u16(cw))
            t.step(1)
            t.frame(0x180 + node, u16(sw) + u16(ec))
            if i == 0 and emcy is not None:
                t.step(1)
                t.frame(0x80 + node, emcy)
            t.step(PERIOD_MS - 1)


# The drive's life after NMT start: (cycles, controlword, statusword, error code, EMCY).
LIFE = [
    (5, 0x0000, 0x0250, 0, None),  # switch on disabled
    (3, 0x0006, 0x0231, 0, None),  # shutdown -> ready to switch on
    (3, 0x0007, 0x0233, 0, None),  # switch on -> switched on
    (50, 0x000F, 0x0237, 0, None),  # enable operation -> operation enabled
    # Overvoltage: fault reaction active, then fault; the EMCY comes with it.
    (1, 0x000F, 0x023F, 0x7305, [0x05, 0x73, 0x05, 0, 0, 0, 0, 0]),
    (20, 0x000F, 0x0238, 0x7305, None),
    (3, 0x0080, 0x0250, 0, [0, 0, 0, 0, 0, 0, 0, 0]),  # fault reset
    (3, 0x0006, 0x0231, 0, None),
    (3, 0x0007, 0x0233, 0, None),
    (40, 0x000F, 0x0237, 0, None),  # recovered
]


def commissioning():
    t = Trace()
    t.frame(0x700 + NODE, [0x00])  # boot-up
    t.step(20)
    sdo_read(t, NODE, 0x1000, 0, 0x00020192)
    configure_pdos(t, NODE)
    t.step(10)
    t.frame(0x000, [0x01, NODE])  # NMT start
    t.step(10)
    run(t, NODE, LIFE)
    t.write("cia402-commissioning.log")


def dcf_only():
    t = Trace()
    t.frame(0x700 + NODE, [0x00])
    t.step(20)
    t.frame(0x000, [0x01, NODE])
    t.step(10)
    run(t, NODE, LIFE)
    t.write("cia402-dcf.log")


def unknown():
    t = Trace()
    node = 3
    t.frame(0x700 + node, [0x00])
    t.step(20)
    sdo_read(t, node, 0x1000, 0, 0x00020192)
    t.frame(0x000, [0x01, node])
    t.step(10)
    run(t, node, LIFE[:4])
    t.write("cia402-unknown.log")


DCF = """\
; The DCF of the drive in cia402-commissioning.log (node 5), written by
; scripts/make_cia402_fixtures.py: the mapping its commissioning configures.
[FileInfo]
FileName=cia402-drive.dcf
FileVersion=1
Description=Servo drive, issue 19 fixture

[DeviceInfo]
VendorName=Kollmorgen
VendorNumber=0x0000006A
ProductName=Example servo
ProductNumber=0x00000300

[DeviceComissioning]
NodeID=5
Baudrate=500

[1018sub1]
ParameterName=Vendor-ID
DataType=0x0007
AccessType=ro
DefaultValue=0x0000006A

[1400sub1]
ParameterName=COB-ID used by RPDO
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x200
ParameterValue=$NODEID+0x200

[1600sub0]
ParameterName=Number of mapped objects
DataType=0x0005
AccessType=rw
DefaultValue=1
ParameterValue=1

[1600sub1]
ParameterName=Mapping entry 1
DataType=0x0007
AccessType=rw
DefaultValue=0x60400010
ParameterValue=0x60400010

[1800sub1]
ParameterName=COB-ID used by TPDO
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x180
ParameterValue=$NODEID+0x180

[1A00sub0]
ParameterName=Number of mapped objects
DataType=0x0005
AccessType=rw
DefaultValue=1
ParameterValue=2

[1A00sub1]
ParameterName=Mapping entry 1
DataType=0x0007
AccessType=rw
DefaultValue=0x60410010
ParameterValue=0x60410010

[1A00sub2]
ParameterName=Mapping entry 2
DataType=0x0007
AccessType=rw
DefaultValue=0x00000000
ParameterValue=0x603F0010
"""


def heartbeats(t, nodes, state=0x05):
    for node in nodes:
        t.frame(0x700 + node, [state])
    t.step(1)


def sdo_read_segmented(t, node, index, sub, value):
    """A segmented upload of four bytes: initiate, the size, one segment."""
    t.frame(0x600 + node, [0x40] + u16(index) + [sub, 0, 0, 0, 0])
    t.step(1)
    t.frame(0x580 + node, [0x41] + u16(index) + [sub] + u32(4))
    t.step(1)
    t.frame(0x600 + node, [0x60, 0, 0, 0, 0, 0, 0, 0])
    t.step(1)
    # scs 0, toggle 0, n = 3 unused bytes, c = 1 (last).
    t.frame(0x580 + node, [0x00 | (3 << 1) | 1] + u32(value) + [0, 0, 0])
    t.step(1)


def not_drive():
    t = Trace()
    for node in (3, 5, 7):
        t.frame(0x700 + node, [0x00])
        t.step(1)
    t.frame(0x000, [0x01, 0x00])
    t.step(1)
    sdo_read(t, 5, 0x1000, 0, 0x00020192)
    sdo_read_segmented(t, 7, 0x1000, 0, 0x00010196)
    # Node 3's digital inputs on 0x183 before anyone asked what it is:
    # read as a statusword (0x0237: operation enabled) under the assumption.
    for i in range(3):
        t.frame(0x183, [0x37, 0x02])
        t.step(1)
        run(t, 5, [(1, 0x0006, 0x0231, 0, None)])
        heartbeats(t, (3, 5, 7))
    sdo_read(t, 3, 0x1000, 0, 0x000F0191)
    for i in range(3):
        t.frame(0x183, [0x50, 0x02])
        t.step(1)
        t.frame(0x187, [0x10, 0x27, 0, 0])
        t.step(1)
        heartbeats(t, (3, 5, 7))
    run(t, 5, [(3, 0x0007, 0x0233, 0, None), (3, 0x000F, 0x0237, 0, None)])
    t.write("cia402-not-drive.log")


def controlword_read():
    t = Trace()
    t.frame(0x700 + NODE, [0x00])
    t.step(1)
    sdo_read(t, NODE, 0x1000, 0, 0x00020192)
    configure_pdos(t, NODE)
    t.frame(0x000, [0x01, NODE])
    t.step(1)
    run(t, NODE, LIFE[:6])
    # In fault, the master reads the controlword: the node reports what it
    # holds, bit 7 set. A read commands nothing.
    sdo_read(t, NODE, 0x6040, 0, 0x008F)
    run(t, NODE, [(3, 0x000F, 0x0238, 0x7305, None)])
    # The real fault reset, written by RPDO.
    run(t, NODE, LIFE[6:])
    t.write("cia402-controlword-read.log")


def pdo_read():
    t = Trace()
    node = 6
    t.frame(0x700 + node, [0x00])
    t.step(1)
    sdo_read(t, node, 0x1000, 0, 0x00020192)
    # The master reads TPDO1's mapping and COB-ID back.
    sdo_read(t, node, 0x1A00, 0, 2)
    sdo_read(t, node, 0x1A00, 1, 0x60410010)
    sdo_read(t, node, 0x1A00, 2, 0x603F0010)
    sdo_read_segmented(t, node, 0x1800, 1, 0x00000180 + node)
    t.frame(0x000, [0x01, node])
    t.step(1)
    for cycles, _cw, sw, ec, emcy in LIFE:
        for i in range(cycles):
            t.frame(0x180 + node, u16(sw) + u16(ec))
            if i == 0 and emcy is not None:
                t.step(1)
                t.frame(0x80 + node, emcy)
            t.step(PERIOD_MS)
    t.write("cia402-pdo-read.log")


def crc16(data):
    """CiA 301's block transfer CRC: CRC-16-CCITT from 0."""
    crc = 0
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def block():
    t = Trace()
    for node in (3, 4):
        t.frame(0x700 + node, [0x7F])
        t.step(1)
    image = bytes(range(0x40, 0x40 + 33))  # 33 bytes of "firmware"
    # Node 4: block download of 0x1F50 sub 1, size 33, CRC; node 3: block
    # upload of 0x1000. Frames of the two interleave.
    download = []
    download.append((0x604, [0xC6, 0x50, 0x1F, 0x01] + u32(len(image))))
    download.append((0x584, [0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0]))
    # One sub-block of five segments, the fifth the transfer's last: 0x85,
    # 5 bytes of data and 2 unused.
    for seq in range(1, 6):
        chunk = list(image[(seq - 1) * 7 : seq * 7])
        chunk += [0] * (7 - len(chunk))
        download.append((0x604, [seq | (0x80 if seq == 5 else 0)] + chunk))
    download.append((0x584, [0xA2, 5, 127, 0, 0, 0, 0, 0]))
    crc = crc16(image)
    download.append((0x604, [0xC1 | (2 << 2)] + u16(crc) + [0, 0, 0, 0, 0]))
    download.append((0x584, [0xA1, 0, 0, 0, 0, 0, 0, 0]))
    value = u32(0x000F0191)
    up_crc = crc16(bytes(value))
    upload = [
        (0x603, [0xA4, 0x00, 0x10, 0x00, 127, 0, 0, 0]),
        (0x583, [0xC6, 0x00, 0x10, 0x00] + u32(4)),
        (0x603, [0xA3, 0, 0, 0, 0, 0, 0, 0]),
        (0x583, [0x81] + value + [0, 0, 0]),
        (0x603, [0xA2, 1, 127, 0, 0, 0, 0, 0]),
        (0x583, [0xC1 | (3 << 2)] + u16(up_crc) + [0, 0, 0, 0, 0]),
        (0x603, [0xA1, 0, 0, 0, 0, 0, 0, 0]),
    ]
    for i in range(max(len(download), len(upload))):
        for frames in (download, upload):
            if i < len(frames):
                t.frame(*frames[i])
                t.step(1)
        if i % 4 == 0:
            heartbeats(t, (3, 4), 0x7F)
    # A second block download to node 4 in sub-blocks of three: the node
    # takes the first, then aborts the second (CRC error, say).
    t.frame(0x604, [0xC2, 0x50, 0x1F, 0x02] + u32(100))
    t.step(1)
    t.frame(0x584, [0xA0, 0x50, 0x1F, 0x02, 3, 0, 0, 0])
    t.step(1)
    for seq in (1, 2, 3):
        t.frame(0x604, [seq] + list(image[:7]))
        t.step(1)
    t.frame(0x584, [0xA2, 3, 3, 0, 0, 0, 0, 0])
    t.step(1)
    for seq in (1, 2):
        t.frame(0x604, [seq] + list(image[7:14]))
        t.step(1)
    t.frame(0x584, [0x80, 0x50, 0x1F, 0x02] + u32(0x05040004))
    t.step(1)
    heartbeats(t, (3, 4), 0x7F)
    t.write("sdo-block.log")


def main():
    commissioning()
    dcf_only()
    unknown()
    not_drive()
    controlword_read()
    pdo_read()
    block()
    with open(os.path.join(ROOT, "fixtures", "cia402-drive.dcf"), "w") as f:
        f.write(DCF)


if __name__ == "__main__":
    main()
