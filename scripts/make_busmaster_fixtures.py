#!/usr/bin/env python3
"""Writes the BUSMASTER log fixtures (fixtures/*.busmaster.log).

Made by this script from the scenarios of fixtures/make_fixtures.py (the
frames of fixtures/s300.log, stoeber.log, ...), written the way the
BUSMASTER versions seen in real logs write them (no real log is copied):

- s300.busmaster.log        2.0-style: ***HEX***, ***SYSTEM MODE***, a start
                            date, ids as 0x081, every frame once (Rx,
                            channel 1): the times of day on the start date
                            equal the candump log's Unix times.
- stoeber.busmaster.log     1.6.4-style: ***DEC***, ***ABSOLUTE MODE*** (time
                            since logging started), ids %04d, bytes %03d,
                            CRLF line ends.
- festo.busmaster.log       ***HEX***, ***RELATIVE MODE*** (each stamp the
                            delta to the previous frame), ids without 0x.
- canopennode.busmaster.log 1.6.3-style: no base and no mode line; decimal
                            ids and 3-digit bytes, so the numbers say DEC
                            (an empty frame comes first, before any byte
                            tells); time of day on the start date.
- edge.busmaster.log        three appended sessions: 2.0 DEC, then 2.0 HEX
                            (29-bit 'x', remote 'sr' and 'xr' with their DLC's
                            bytes, 's-fd', 'ERR' frames), then 2.4 HEX
                            (8-digit ids, channel numbers from 0, unpadded
                            millisecond times); a LIN session between them
                            (its lines skipped); a malformed line last (a
                            3-digit byte in a HEX session).

Run from the repository root:  python3 scripts/make_busmaster_fixtures.py
then refresh the golden outputs:
  UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::
"""

import datetime
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "fixtures"))
from make_fixtures import BASE, SCENARIOS  # noqa: E402

FIXTURES = os.path.join(ROOT, "fixtures")


def utc(t):
    return datetime.datetime.fromtimestamp(BASE + t, datetime.timezone.utc)


def start_line(t):
    """***START DATE AND TIME d:m:yyyy h:m:s:ms*** (fields unpadded)."""
    s = utc(t)
    return (f"***START DATE AND TIME {s.day}:{s.month}:{s.year} "
            f"{s.hour}:{s.minute}:{s.second}:{s.microsecond // 1000:03d}***")


def end_line(t):
    s = utc(t)
    return (f"***END DATE AND TIME {s.day}:{s.month}:{s.year} "
            f"{s.hour}:{s.minute}:{s.second}:{s.microsecond // 1000:03d}***")


def header(version, base, mode, start, channels=(1, 2), protocol="CAN"):
    out = [
        f"***BUSMASTER Ver {version}***",
        f"***PROTOCOL {protocol}***",
        "***NOTE: PLEASE DO NOT EDIT THIS DOCUMENT***",
        "***[START LOGGING SESSION]***",
        start_line(start),
    ]
    if base:
        out.append(f"***{base}***")
    if mode:
        out.append(f"***{mode} MODE***")
        out.append("***START CHANNEL BAUD RATE***")
        for c in channels:
            out.append(f"***CHANNEL {c} - Simulation - 500000 bps***")
        out.append("***END CHANNEL BAUD RATE***")
        out.append("***START DATABASE FILES (DBF/DBC)***")
        out.append("***END DATABASE FILES (DBF/DBC)***")
        out.append("***<Time><Tx/Rx><Channel><CAN ID><Type><DLC><DataBytes>***")
    return out


def footer(end):
    return [end_line(end), "***[STOP LOGGING SESSION]***"]


def clock(secs, tenths_of_ms=True, pad=True):
    """H:M:S:F: F in 1/10000 s (4 digits) or unpadded milliseconds (2.4)."""
    whole = int(round(secs * 10000))
    h, rest = divmod(whole // 10000, 3600)
    m, s = divmod(rest, 60)
    frac = whole % 10000
    if not tenths_of_ms:
        return f"{h:02d}:{m:02d}:{s:02d}:{frac // 10}"
    if pad:
        return f"{h:02d}:{m:02d}:{s:02d}:{frac:04d}"
    return f"{h}:{m}:{s}:{frac:04d}"


def time_of_day(t):
    s = utc(t)
    return s.hour * 3600 + s.minute * 60 + s.second + s.microsecond / 1e6


TYPES = {"d": "s", "x": "x", "r": "sr", "fd": "s-fd"}


def frame_line(e, stamp, base, direction="Rx", channel=None, id_style="0x", remote_bytes=False):
    t, ch, kind, ident, data = e
    channel = ch + 1 if channel is None else channel
    raw = bytes.fromhex(data)
    if kind == "err":
        return f"{stamp} {direction} {channel} 0 ERR Bus Off"
    ext = kind == "x"
    if kind == "r":
        ext = ident > 0x7FF
    typ = TYPES[kind] if not (kind == "r" and ext) else "xr"
    if base == "DEC":
        idt = f"{ident:010d}" if ext else f"{ident:04d}"
        nums = [f"{b:03d}" for b in raw]
    else:
        if id_style == "0x":
            idt = f"0x{ident:08X}" if ext else f"0x{ident:03X}"
        elif id_style == "8":
            idt = f"{ident:08X}"
        else:
            idt = f"{ident:08X}" if ext else f"{ident:03X}"
        nums = [f"{b:02X}" for b in raw]
    n = len(raw)
    if kind == "r":
        # A remote request: its DLC, and (as 2.0 writes them) that many zeros.
        n = 8
        nums = (["000"] if base == "DEC" else ["00"]) * 8 if remote_bytes else []
    # BUSMASTER ends every frame line with a blank.
    return f"{stamp} {direction} {channel} {idt} {typ} {n} " + "".join(x + " " for x in nums)


def s300():
    entries = SCENARIOS["s300"]
    out = header("2.0.0", "HEX", "SYSTEM", -0.5)
    for e in entries:
        out.append(frame_line(e, clock(time_of_day(e[0])), "HEX", "Rx"))
    out += footer(entries[-1][0] + 1)
    return "\n".join(out) + "\n"


def stoeber():
    entries = SCENARIOS["stoeber"]
    out = header("1.6.4", "DEC", "ABSOLUTE", 0)
    for e in entries:
        out.append(frame_line(e, clock(e[0]), "DEC", "Rx"))
    out += footer(entries[-1][0] + 1)
    return "\r\n".join(out) + "\r\n"


def festo():
    entries = SCENARIOS["festo"]
    out = header("1.6.4", "HEX", "RELATIVE", 0)
    prev = 0.0
    for e in entries:
        out.append(frame_line(e, clock(e[0] - prev), "HEX", "Rx", id_style="plain"))
        prev = e[0]
    out += footer(entries[-1][0] + 1)
    return "\n".join(out) + "\n"


def canopennode():
    entries = SCENARIOS["canopennode"]
    out = header("1.6.3", None, None, -1)
    # An empty frame first: no byte to tell the base, the id width guesses.
    out.append(frame_line((0, 0, "d", 0x080, ""), clock(time_of_day(-0.5), pad=False), "DEC", "Tx"))
    for e in entries:
        out.append(frame_line(e, clock(time_of_day(e[0]), pad=False), "DEC", "Tx"))
    out += ["***END DATE AND TIME ***", "***[STOP LOGGING SESSION]***"]
    return "\r\n".join(out) + "\r\n"


def edge():
    entries = SCENARIOS["edge"]
    first = [e for e in entries if e[0] < 0.25]
    second = [e for e in entries if 0.25 <= e[0] < 1.45]
    third = [e for e in entries if e[0] >= 1.45]
    out = header("2.0.0", "DEC", "SYSTEM", -0.5)
    for e in first:
        out.append(frame_line(e, clock(time_of_day(e[0])), "DEC"))
    out += footer(0.25)
    out.append("")
    # A LIN session: its lines are not CAN frames.
    out += header("2.0.0", "HEX", "SYSTEM", 0.26, channels=(1,), protocol="LIN")
    out.append(f"{clock(time_of_day(0.27))} Rx 1 0x01 s 2 12 34 ")
    out += footer(0.28)
    out.append("")
    out += header("2.0.0", "HEX", "SYSTEM", 0.29)
    for e in second:
        out.append(frame_line(e, clock(time_of_day(e[0])), "HEX", remote_bytes=True))
    out += footer(1.45)
    out.append("")
    out += header("2.4.0", "HEX", "SYSTEM", 1.46)
    for e in third:
        out.append(frame_line(e, clock(time_of_day(e[0]), tenths_of_ms=False), "HEX",
                              id_style="8"))
    # Malformed: a three-digit (decimal) byte in a HEX session.
    out.append(f"{clock(time_of_day(2.0), tenths_of_ms=False)} Rx 0 00000081 s 1 123 ")
    out += footer(2.1)
    return "\n".join(out) + "\n"


FILES = {
    "s300.busmaster.log": s300,
    "stoeber.busmaster.log": stoeber,
    "festo.busmaster.log": festo,
    "canopennode.busmaster.log": canopennode,
    "edge.busmaster.log": edge,
}


def main():
    for name, make in FILES.items():
        with open(os.path.join(FIXTURES, name), "w", newline="") as f:
            f.write(make())


if __name__ == "__main__":
    main()
