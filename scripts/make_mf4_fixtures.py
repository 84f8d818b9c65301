#!/usr/bin/env python3
"""Writes the MF4 (ASAM MDF 4) fixtures (fixtures/*.mf4) and checks each
with python-can's MF4Reader (through asammdf): every fixture but the damaged
one must read back as exactly the frames it was written with.

Made with python-can 4.6.1 and asammdf 8.8.28 (pip install python-can
asammdf), from the frames of fixtures/s300.log (the S300 sequence: boot-up,
SDO identity reads, EMCYs 0x4310, 0x3120, resets, a second boot-up) plus
frames of our own:

- s300.mf4         python-can's MF4Writer, no compression: asammdf's layout
                   (sorted: one data group per CAN_DataFrame,
                   CAN_ErrorFrame, CAN_RemoteFrame group, 64 fixed data
                   bytes, float64 seconds), channel 1, start 1700000000 s.
- s300.dz.mf4      the same frames through MF4Writer's default compression:
                   DZ blocks, transposed deflate.
- canedge.mf4      by hand (struct), as CANedge firmware 01.xx writes:
                   unfinalized (`UnFinMF `, flags 0x25), the DT block's
                   length 24 and its records running to the end of the file,
                   one unsorted data group (1-byte record ids) with
                   CAN_DataFrame (float64 ns master with a 1e-9 conversion,
                   packed ID/IDE/DLC/DataLength bits), its VLSD group for the
                   data bytes (each frame's VLSD record after the frame, as
                   CANedge writes them), CAN_ErrorFrame, CAN_RemoteFrame and
                   LIN_Frame groups; HD time zone +60 min (times stay UTC).
                   The S300 sequence on channel 1, a remote frame on 0x081
                   and an error frame (neither an EMCY), LIN frames
                   (skipped), a 29-bit frame on channel 2.
- canedge73.mf4    by hand, the newer CANedge layout: unfinalized, one
                   unsorted group per bus/id type/FD kind (CAN1_Rx,
                   CAN1_Rx_IDE, CAN2_Rx_FD_DLC_over_8 and its VLSD group),
                   BusChannel, IDE and EDL virtual channels (cn_type 6,
                   linear conversion to a constant), DataLength = DLC
                   through a value-to-value table, 48-bit microsecond
                   master, 11-bit ids 11 bits wide. S300 on CAN1, node 5's
                   EMCY moved to 29 bits (0x1000085) on CAN1_Rx_IDE, FD
                   frames of 12 and 64 bytes on CAN2.
- sorted-sd.mf4    by hand, finalized and sorted as CANedge's finalized
                   files: CAN_DataFrame with the data bytes in an SD block
                   written after the records (VLSD channel), its data an HL
                   -> DL list of a DT block and a DZ block (deflate) with a
                   record split across the two; the second data group
                   (CAN_RemoteFrame) after the data; uint64 nanosecond
                   master. S300 on channel 3.
- bus-errors.mf4   by hand, the CANedge layout of canedge.mf4: the frames
                   of fixtures/bus-errors.log on channel 1, each error frame
                   with the ErrorType that says its class (python-can reads
                   error frames without their type: it checks their times).
- damaged.mf4      by hand, what a reader must survive: non-zero bytes
                   between blocks, a record id no group declares in the
                   first DT block of a DL (the rest of that block is lost),
                   a frame whose DataLength exceeds its fixed bytes, an
                   EMCY after them, and a last record cut off by the end.

Run from the repository root:  python3 scripts/make_mf4_fixtures.py
then refresh the golden outputs:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import datetime
import os
import re
import struct
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIXTURES = os.path.join(ROOT, "fixtures")
START = 1_700_000_000  # s since the epoch


def s300_frames():
    """(microseconds since START, id, data) of fixtures/s300.log."""
    frames = []
    pattern = re.compile(r"\((\d+)\.(\d{6})\) can0 ([0-9A-F]{3})#([0-9A-F]*)")
    with open(os.path.join(FIXTURES, "s300.log")) as f:
        for line in f:
            m = pattern.match(line)
            if m:
                us = (int(m.group(1)) - START) * 1_000_000 + int(m.group(2))
                frames.append((us, int(m.group(3), 16), bytes.fromhex(m.group(4))))
    return frames


def bus_error_frames():
    """fixtures/bus-errors.log on channel 1: its data frames, and its error
    frames with the ErrorType that says their SocketCAN class (1 bit,
    2 form, 3 stuff, 4 CRC, 5 ACK; 0 for what ErrorType cannot say)."""
    frames = []
    pattern = re.compile(r"\((\d+)\.(\d{6})\) can0 ([0-9A-F]{3}|[0-9A-F]{8})#([0-9A-F]*)")
    with open(os.path.join(FIXTURES, "bus-errors.log")) as f:
        for line in f:
            m = pattern.match(line)
            if not m:
                continue
            us = (int(m.group(1)) - START) * 1_000_000 + int(m.group(2))
            word, data = int(m.group(3), 16), bytes.fromhex(m.group(4))
            if word & 0x20000000:
                kind = 0
                if word & 0x20:
                    kind = 5
                elif word & 0x08:
                    kind = {0x01: 1, 0x02: 2, 0x04: 3}.get(data[2] & 0x7F, 4 if data[3] == 0x08 else 0)
                f_ = frame(us, 1, 0, kind="error")
                f_["error_type"] = kind
                frames.append(f_)
            else:
                frames.append(frame(us, 1, word, data))
    return frames


# A frame: dict(us, channel, id, ext, kind ('data', 'remote', 'error', 'fd'), data)
def frame(us, channel, id_, data=b"", ext=False, kind="data"):
    return dict(us=us, channel=channel, id=id_, ext=ext, kind=kind, data=bytes(data))


def dlc_of(n):
    return n if n <= 8 else [12, 16, 20, 24, 32, 48, 64].index(n) + 9


# ---------------------------------------------------------------- writer --


class Mdf:
    """An MDF 4 file built block by block; links are patched afterwards."""

    def __init__(self, ident=b"MDF     ", unfin_flags=0):
        self.out = bytearray()
        self.out += ident + b"4.11    " + b"CE      " + b"\0" * 4
        self.out += struct.pack("<H", 411) + b"\0" * 30 + struct.pack("<HH", unfin_flags, 0)
        assert len(self.out) == 64
        self.texts = {}

    def align(self):
        while len(self.out) % 8:
            self.out += b"\0"

    def block(self, kind, links, data, length=None):
        self.align()
        at = len(self.out)
        n = 24 + 8 * len(links) + len(data)
        self.out += b"##" + kind + b"\0" * 4
        self.out += struct.pack("<QQ", n if length is None else length, len(links))
        for link in links:
            self.out += struct.pack("<Q", link)
        self.out += data
        return at

    def link(self, block, i, value):
        struct.pack_into("<Q", self.out, block + 24 + 8 * i, value)

    def tx(self, text):
        if text not in self.texts:
            self.texts[text] = self.block(b"TX", [], text.encode() + b"\0")
        return self.texts[text]

    def hd(self, tz_min=0):
        # dg_first, fh, ch, at, ev, comment; start ns, tz, dst, flags (offsets valid)
        data = struct.pack("<QhhBBBB", START * 10**9, tz_min, 0, 2, 0, 0, 0) + b"\0" * 16
        return self.block(b"HD", [0] * 6, data)

    def si_can(self, name):
        return self.block(b"SI", [self.tx(name), 0, 0], bytes([2, 2, 0]) + b"\0" * 5)

    def cc_linear(self, offset, factor):
        data = struct.pack("<BBHHH", 1, 0, 0, 0, 2) + struct.pack("<dd", 0, 0)
        return self.block(b"CC", [0, 0, 0, 0], data + struct.pack("<dd", offset, factor))

    def cc_table(self, pairs):
        vals = [v for p in pairs for v in p]
        data = struct.pack("<BBHHH", 5, 0, 0, 0, len(vals)) + struct.pack("<dd", 0, 0)
        return self.block(b"CC", [0, 0, 0, 0], data + struct.pack(f"<{len(vals)}d", *vals))

    def cn(self, name, kind=0, dtype=0, byte=0, bit=0, bits=8, cc=0, data=0, composition=0,
           sync=0):
        data_ = struct.pack("<BBBBIIIIBBH", kind, sync, dtype, bit, byte, bits, 0, 0, 0, 0, 0)
        data_ += struct.pack("<6d", 0, 0, 0, 0, 0, 0)
        return self.block(b"CN", [0, composition, self.tx(name), 0, cc, data, 0, 0], data_)

    def chain_cn(self, cns):
        for a, b in zip(cns, cns[1:]):
            self.link(a, 0, b)
        return cns[0] if cns else 0

    def cg(self, name, record_id, data_bytes, cn_first=0, si=0, vlsd=False):
        flags = 1 if vlsd else 6  # VLSD, or bus event + plain bus event
        data = struct.pack("<QQHH4sII", record_id, 0, flags, 0, b"\0" * 4, data_bytes, 0)
        return self.block(b"CG", [0, cn_first, self.tx(name) if name else 0, si, 0, 0], data)

    def dg(self, rec_id_size):
        return self.block(b"DG", [0, 0, 0, 0], bytes([rec_id_size]) + b"\0" * 7)

    def save(self, name):
        with open(os.path.join(FIXTURES, name), "wb") as f:
            f.write(self.out)


def can_members(m, prefix, layout):
    """Channels of a CAN structure: (member, byte, bit, bits, extra kwargs)."""
    return [m.cn(f"{prefix}.{member}", byte=byte, bit=bit, bits=bits, **kw)
            for member, byte, bit, bits, kw in layout]


# The CANedge 01.xx CAN_DataFrame record after its 1-byte id: float64
# master, then ID(29)/IDE at byte 8, EDL/DataLength at 12, Dir/BRS/
# BusChannel/DLC at 13, the VLSD offset at 14.
CANEDGE_DATA = [
    ("BusChannel", 13, 2, 2, {}),
    ("ID", 8, 3, 29, {}),
    ("IDE", 8, 0, 1, {}),
    ("DLC", 13, 4, 4, {}),
    ("DataLength", 12, 1, 7, {}),
    ("Dir", 13, 0, 1, {}),
    ("BRS", 13, 1, 1, {}),
    ("EDL", 12, 0, 1, {}),
]


def canedge_record(f, offset):
    word = (f["id"] << 3) | int(f["ext"])
    b12 = (len(f["data"]) << 1) | int(f["kind"] == "fd")
    b13 = (dlc_of(len(f["data"])) << 4) | (f["channel"] << 2)
    return struct.pack("<dIBBQ", f["us"] * 1000.0, word, b12, b13, offset)


def write_canedge(frames, lin):
    m = Mdf(b"UnFinMF ", 0x25)
    hd = m.hd(tz_min=60)
    si = m.si_can("CAN")
    ns = m.cc_linear(0.0, 1e-9)
    dg = m.dg(1)
    # CAN_DataFrame (id 1) + VLSD (id 2)
    vlsd = m.cg("", 2, 0, vlsd=True)
    members = can_members(m, "CAN_DataFrame", CANEDGE_DATA)
    members.append(m.cn("CAN_DataFrame.DataBytes", kind=1, dtype=10, byte=14, bits=64, data=vlsd))
    parent = m.cn("CAN_DataFrame", dtype=10, byte=8, bits=112, composition=m.chain_cn(members))
    master = m.cn("Timestamp", kind=2, dtype=4, bits=64, cc=ns, sync=1)
    data_cg = m.cg("CAN_DataFrame", 1, 22, m.chain_cn([master, parent]), si)
    # CAN_ErrorFrame (id 3): master, BusChannel, ErrorType
    err = [m.cn("CAN_ErrorFrame.BusChannel", byte=8, bits=2), m.cn("CAN_ErrorFrame.ErrorType", byte=8, bit=2, bits=3)]
    err_parent = m.cn("CAN_ErrorFrame", dtype=10, byte=8, bits=8, composition=m.chain_cn(err))
    err_cg = m.cg("CAN_ErrorFrame", 3, 9, m.chain_cn([m.cn("Timestamp", kind=2, dtype=4, bits=64, cc=ns, sync=1), err_parent]), si)
    # CAN_RemoteFrame (id 4): master, ID/IDE at 8, DLC/DataLength/BusChannel at 12
    rtr = [m.cn("CAN_RemoteFrame.ID", byte=8, bit=3, bits=29), m.cn("CAN_RemoteFrame.IDE", byte=8, bits=1),
           m.cn("CAN_RemoteFrame.DLC", byte=12, bit=4, bits=4), m.cn("CAN_RemoteFrame.DataLength", byte=12, bit=4, bits=4),
           m.cn("CAN_RemoteFrame.BusChannel", byte=12, bits=2)]
    rtr_parent = m.cn("CAN_RemoteFrame", dtype=10, byte=8, bits=40, composition=m.chain_cn(rtr))
    rtr_cg = m.cg("CAN_RemoteFrame", 4, 13, m.chain_cn([m.cn("Timestamp", kind=2, dtype=4, bits=64, cc=ns, sync=1), rtr_parent]), si)
    # LIN_Frame (id 5): master, ID, DataLength, 8 data bytes
    lin_m = [m.cn("LIN_Frame.ID", byte=8, bits=6), m.cn("LIN_Frame.DataLength", byte=9, bits=4),
             m.cn("LIN_Frame.DataBytes", dtype=10, byte=10, bits=64)]
    lin_parent = m.cn("LIN_Frame", dtype=10, byte=8, bits=80, composition=m.chain_cn(lin_m))
    lin_cg = m.cg("LIN_Frame", 5, 18, m.chain_cn([m.cn("Timestamp", kind=2, dtype=4, bits=64, cc=ns, sync=1), lin_parent]), 0)
    m.link(data_cg, 0, vlsd)
    m.link(vlsd, 0, err_cg)
    m.link(err_cg, 0, rtr_cg)
    m.link(rtr_cg, 0, lin_cg)
    m.link(dg, 1, data_cg)
    m.link(hd, 0, dg)
    dt = m.block(b"DT", [], b"")  # length 24: not updated
    m.link(dg, 2, dt)
    records = bytearray()
    offset = 0
    events = [("can", f) for f in frames] + [("lin", x) for x in lin]
    events.sort(key=lambda e: e[1]["us"])
    for what, f in events:
        if what == "lin":
            records += bytes([5]) + struct.pack("<dBB8s", f["us"] * 1000.0, f["id"], len(f["data"]), f["data"])
        elif f["kind"] == "error":
            kind = f.get("error_type", 1)
            records += bytes([3]) + struct.pack("<dB", f["us"] * 1000.0, f["channel"] | (kind << 2))
        elif f["kind"] == "remote":
            word = (f["id"] << 3) | int(f["ext"])
            records += bytes([4]) + struct.pack("<dIB", f["us"] * 1000.0, word, (0 << 4) | f["channel"])
        else:
            # The frame, then its VLSD record, as CANedge writes them.
            records += bytes([1]) + canedge_record(f, offset)
            records += bytes([2]) + struct.pack("<I", len(f["data"])) + f["data"]
            offset += 4 + len(f["data"])
    m.out += records
    return m


def write_canedge73(frames):
    m = Mdf(b"UnFinMF ", 0x25)
    hd = m.hd()
    si = m.si_can("CAN")
    us = m.cc_linear(0.0, 1e-6)
    const = {v: m.cc_linear(float(v), 0.0) for v in (0, 1, 2)}
    table = m.cc_table([(i, i) for i in range(9)] + [(9, 12), (10, 16), (11, 20), (12, 24), (13, 32), (14, 48), (15, 64)])
    dg = m.dg(1)

    def group(name, rid, bus, ide, edl, idbits, fixed):
        # record: 48-bit master, ID (idbits) at byte 6, DLC at the top 4 bits after it
        id_bytes = 1 if idbits == 11 else 3  # 11 bits: byte 6 + 3 bits of 7; 29: 6..9
        dlc_byte = 6 + id_bytes
        members = [
            m.cn("CAN_DataFrame.BusChannel", kind=6, bits=0, cc=const[bus]),
            m.cn("CAN_DataFrame.ID", byte=6, bits=idbits),
            m.cn("CAN_DataFrame.IDE", kind=6, bits=0, cc=const[ide]),
            m.cn("CAN_DataFrame.DLC", byte=dlc_byte, bit=4, bits=4),
            m.cn("CAN_DataFrame.DataLength", byte=dlc_byte, bit=4, bits=4, cc=table),
            m.cn("CAN_DataFrame.EDL", kind=6, bits=0, cc=const[edl]),
            m.cn("CAN_DataFrame.Dir", kind=6, bits=0, cc=const[0]),
        ]
        vlsd = 0
        if fixed:
            members.append(m.cn("CAN_DataFrame.DataBytes", dtype=10, byte=dlc_byte + 1, bits=64))
            size = dlc_byte + 1 + 8
        else:
            vlsd = m.cg("", rid + 1, 0, vlsd=True)
            members.append(m.cn("CAN_DataFrame.DataBytes", kind=1, dtype=10, byte=dlc_byte + 1, bits=64, data=vlsd))
            size = dlc_byte + 1 + 8
        parent = m.cn("CAN_DataFrame", dtype=10, byte=6, bits=(size - 6) * 8, composition=m.chain_cn(members))
        master = m.cn("Timestamp", kind=2, dtype=0, bits=48, cc=us, sync=1)
        cg = m.cg(name, rid, size, m.chain_cn([master, parent]), si)
        if vlsd:
            m.link(cg, 0, vlsd)
        return cg, vlsd, dlc_byte

    g1, _, b1 = group("CAN1_Rx", 32, 1, 0, 0, 11, True)
    g2, _, b2 = group("CAN1_Rx_IDE", 34, 1, 1, 0, 29, True)
    g3, v3, b3 = group("CAN2_Rx_FD_DLC_over_8", 40, 2, 0, 1, 11, False)
    m.link(g1, 0, g2)
    m.link(g2, 0, g3)
    m.link(dg, 1, g1)
    m.link(hd, 0, dg)
    dt = m.block(b"DT", [], b"")
    m.link(dg, 2, dt)
    offset = 0
    for f in frames:
        t = struct.pack("<Q", f["us"])[:6]
        dlc = dlc_of(len(f["data"]))
        if f["kind"] == "fd":
            m.out += bytes([40]) + t + struct.pack("<HQ", f["id"] | (dlc << 12), offset)
            m.out += bytes([41]) + struct.pack("<I", len(f["data"])) + f["data"]
            offset += 4 + len(f["data"])
        elif f["ext"]:
            m.out += bytes([34]) + t + struct.pack("<I", f["id"] | (dlc << 28)) + f["data"].ljust(8, b"\0")
        else:
            m.out += bytes([32]) + t + struct.pack("<H", f["id"] | (dlc << 12)) + f["data"].ljust(8, b"\0")
    return m


def sorted_record(f, offset):
    # uint64 ns master, ID(29)+IDE at 8, DataLength at 12, BusChannel at 13, offset at 14
    return struct.pack("<QIBBQ", f["us"] * 1000, (f["id"] << 3) | int(f["ext"]), len(f["data"]), f["channel"], offset)


def write_sorted_sd(frames, remotes):
    m = Mdf()
    hd = m.hd()
    si = m.si_can("CAN")
    ns = m.cc_linear(0.0, 1e-9)
    dg1 = m.dg(0)
    members = [m.cn("CAN_DataFrame.ID", byte=8, bit=3, bits=29), m.cn("CAN_DataFrame.IDE", byte=8, bits=1),
               m.cn("CAN_DataFrame.DataLength", byte=12, bits=8), m.cn("CAN_DataFrame.BusChannel", byte=13, bits=8)]
    data_cn = m.cn("CAN_DataFrame.DataBytes", kind=1, dtype=10, byte=14, bits=64)
    members.append(data_cn)
    parent = m.cn("CAN_DataFrame", dtype=10, byte=8, bits=112, composition=m.chain_cn(members))
    cg1 = m.cg("CAN_DataFrame", 0, 22, m.chain_cn([m.cn("t", kind=2, dtype=0, bits=64, cc=ns, sync=1), parent]), si)
    m.link(dg1, 1, cg1)
    m.link(hd, 0, dg1)
    # Records, split across a DT and a DZ block in the middle of a record.
    sd = bytearray()
    records = bytearray()
    for f in frames:
        records += sorted_record(f, len(sd))
        sd += struct.pack("<I", len(f["data"])) + f["data"]
    cut = 22 * (len(frames) // 2) + 9
    dt = m.block(b"DT", [], bytes(records[:cut]))
    rest = bytes(records[cut:])
    zipped = zlib.compress(rest)
    dz = m.block(b"DZ", [], b"DT" + bytes([0, 0]) + struct.pack("<IQQ", 0, len(rest), len(zipped)) + zipped)
    dl = m.block(b"DL", [0, dt, dz], struct.pack("<BxxxI", 0, 2) + struct.pack("<QQ", 0, cut))
    hl = m.block(b"HL", [dl], struct.pack("<HB5x", 0, 0))
    m.link(dg1, 2, hl)
    # The second data group, after the data: remote frames.
    dg2 = m.dg(0)
    rm = [m.cn("CAN_RemoteFrame.ID", byte=8, bit=3, bits=29), m.cn("CAN_RemoteFrame.IDE", byte=8, bits=1),
          m.cn("CAN_RemoteFrame.DLC", byte=12, bits=8), m.cn("CAN_RemoteFrame.BusChannel", byte=13, bits=8)]
    rparent = m.cn("CAN_RemoteFrame", dtype=10, byte=8, bits=48, composition=m.chain_cn(rm))
    cg2 = m.cg("CAN_RemoteFrame", 0, 14, m.chain_cn([m.cn("t", kind=2, dtype=0, bits=64, cc=ns, sync=1), rparent]), si)
    m.link(dg2, 1, cg2)
    m.link(dg1, 0, dg2)
    rdt = m.block(b"DT", [], b"".join(struct.pack("<QIBB", f["us"] * 1000, f["id"] << 3, 0, f["channel"]) for f in remotes))
    m.link(dg2, 2, rdt)
    # Cycle counts, as a finalized file has them.
    struct.pack_into("<Q", m.out, cg1 + 24 + 6 * 8 + 8, len(frames))
    struct.pack_into("<Q", m.out, cg2 + 24 + 6 * 8 + 8, len(remotes))
    # The signal data last: the records above point into it.
    sdb = m.block(b"SD", [], bytes(sd))
    m.link(data_cn, 5, sdb)
    return m


def write_damaged(frames):
    """Unsorted (1-byte ids), finalized: a DL of two DT blocks; damage."""
    m = Mdf()
    hd = m.hd()
    si = m.si_can("CAN")
    ns = m.cc_linear(0.0, 1e-9)
    dg = m.dg(1)
    members = [m.cn("CAN_DataFrame.ID", byte=8, bits=32), m.cn("CAN_DataFrame.DataLength", byte=12, bits=8),
               m.cn("CAN_DataFrame.BusChannel", byte=13, bits=8), m.cn("CAN_DataFrame.DataBytes", dtype=10, byte=14, bits=64)]
    parent = m.cn("CAN_DataFrame", dtype=10, byte=8, bits=112, composition=m.chain_cn(members))
    cg = m.cg("CAN_DataFrame", 1, 22, m.chain_cn([m.cn("t", kind=2, dtype=0, bits=64, cc=ns, sync=1), parent]), si)
    m.link(dg, 1, cg)
    m.link(hd, 0, dg)

    def rec(f, length=None):
        # ID bit 31 is the IDE bit here (no IDE member).
        word = f["id"] | (0x80000000 if f["ext"] else 0)
        n = len(f["data"]) if length is None else length
        return bytes([1]) + struct.pack("<QIBB8s", f["us"] * 1000, word, n, f["channel"], f["data"])

    m.align()
    m.out += b"\x55" * 16  # not a block
    first = b"".join(rec(f) for f in frames[:3]) + bytes([9]) + b"\xAA" * 30
    dt1 = m.block(b"DT", [], first)
    second = rec(frames[3], length=12) + b"".join(rec(f) for f in frames[4:])
    dt2 = m.block(b"DT", [], second + rec(frames[-1])[:10])
    dl = m.block(b"DL", [0, dt1, dt2], struct.pack("<BxxxI", 0, 2) + struct.pack("<QQ", 0, len(first)))
    m.link(dg, 2, dl)
    return m


# ------------------------------------------------------------- python-can --


def write_python_can(frames, name, compression):
    import can

    path = os.path.join(FIXTURES, name)
    writer = can.MF4Writer(path, compression_level=compression)
    start = datetime.datetime.fromtimestamp(START, datetime.timezone.utc)
    writer._mdf.header.start_time = start
    writer._start_time = writer.last_timestamp = float(START)
    for f in frames:
        writer.on_message_received(can.Message(
            timestamp=START + f["us"] / 1e6, arbitration_id=f["id"], is_extended_id=f["ext"],
            data=f["data"], channel=f["channel"], is_remote_frame=f["kind"] == "remote",
            is_error_frame=f["kind"] == "error", is_fd=f["kind"] == "fd"))
    writer.stop()


def read_back(name):
    """The frames python-can reads, in our frame shape, sorted by time."""
    import can

    out = []
    for msg in can.MF4Reader(os.path.join(FIXTURES, name)):
        kind = "remote" if msg.is_remote_frame else "error" if msg.is_error_frame else "fd" if msg.is_fd else "data"
        data = b"" if kind in ("remote", "error") else bytes(msg.data)
        # An error frame has no id (python-can's default: 0, extended).
        ident, ext = (0, False) if kind == "error" else (msg.arbitration_id, msg.is_extended_id)
        out.append(frame(round((msg.timestamp - START) * 1e6), msg.channel, ident, data, ext, kind))
    return sorted(out, key=key)


def key(f):
    return (f["us"], f["channel"], f["id"], f["kind"], f["data"])


def check(name, frames):
    want = sorted((dict(f, id=0 if f["kind"] == "error" else f["id"],
                        data=b"" if f["kind"] in ("remote", "error") else f["data"]) for f in frames), key=key)
    got = read_back(name)
    assert got == want, f"{name}: python-can reads {len(got)} frames, not the {len(want)} written:\n" + \
        "\n".join(f"{g} != {w}" for g, w in zip(got, want) if g != w)[:2000]
    print(f"{name}: {len(got)} frames, as python-can reads them")


def main():
    s300 = [frame(us, 1, i, d) for us, i, d in s300_frames()]
    write_python_can(s300, "s300.mf4", 0)
    check("s300.mf4", s300)
    write_python_can(s300, "s300.dz.mf4", 2)
    check("s300.dz.mf4", s300)

    extra = [
        frame(1_500_000, 1, 0x081, kind="remote"),
        frame(1_600_000, 1, 0, kind="error"),
        frame(3_500_000, 2, 0x1000085, b"\x10\x43\x08\x01\x00\x00\x00\x00", ext=True),
    ]
    lin = [dict(us=500_000 + 1000 * i, id=0x10 + i, data=bytes(range(i, i + 8))) for i in range(3)]
    canedge = sorted(s300 + extra, key=lambda f: f["us"])
    write_canedge(canedge, lin).save("canedge.mf4")
    check("canedge.mf4", canedge)

    bus = bus_error_frames()
    write_canedge(bus, []).save("bus-errors.mf4")
    check("bus-errors.mf4", [{k: v for k, v in f.items() if k != "error_type"} for f in bus])

    ide = [frame(2_750_000, 1, 0x1000085, b"\x00\x50\x01\x00\x00\x00\x00\x00", ext=True)]
    fd = [frame(2_800_000, 2, 0x085, bytes(range(12)), kind="fd"),
          frame(2_900_000, 2, 0x123, bytes(range(64)), kind="fd")]
    c73 = sorted(s300 + ide + fd, key=lambda f: f["us"])
    write_canedge73(c73).save("canedge73.mf4")
    check("canedge73.mf4", c73)

    s3 = [dict(f, channel=3) for f in s300]
    remotes = [frame(1_700_000, 3, 0x081, kind="remote")]
    write_sorted_sd(s3, remotes).save("sorted-sd.mf4")
    check("sorted-sd.mf4", s3 + remotes)

    damaged = [frame(us, 4, i, d) for us, i, d in s300_frames()][:9]
    damaged.append(frame(9_000_000, 4, 0x085, b"\x00\x81\x11\x00\x00\x00\x00\x00"))
    write_damaged(damaged).save("damaged.mf4")
    print("damaged.mf4: written (not a file python-can must read)")


if __name__ == "__main__":
    main()
