#!/usr/bin/env python3
"""Runs emcy-decode over the real-world traces and compares with SOURCES.md.

The traces (written by other tools and people, collected in
../shared/realworld-traces with a SOURCES.md table of the frame and EMCY
counts independent readers report) are not ours to commit; this script only
reads them where they are:

    scripts/realworld.py [--bin target/release/emcy-decode] [--traces DIR]

For each row it runs `emcy-decode -q --format ndjson FILE` and compares the
input object's `frames` and `emcy` with the table ("19 or 20" accepts
either). The machine networks under `canopen/` have a table of their own
that gives the rows each file holds in words ("11 283 frames", "45 422
rows"): every one of them must be read as a frame or reported malformed, and
for each the script prints what the tool found on the network (nodes, their
states, supervision, drives, notes). Prints one line per trace (more for a
network) and exits 1 when any differs or cannot be read. Python standard
library only.
"""

import argparse
import re
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def rows(sources):
    """(trace, accepted frame counts, accepted EMCY counts) per table row."""
    for line in sources.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 7 or not cells[0] or cells[0].startswith(("trace", "---")):
            continue
        try:
            frames = {int(x) for x in cells[4].split(" or ")}
            emcy = {int(x) for x in cells[5].split(" or ")}
        except ValueError:
            continue
        yield cells[0], frames, emcy


def read(binary, path):
    """(frames, emcy, malformed, exit code, first stderr line) of one trace."""
    run = subprocess.run(
        [str(binary), "-q", "--format", "ndjson", str(path)],
        capture_output=True,
        check=False,
    )
    stderr = run.stderr.decode("utf-8", "replace").strip().splitlines()
    for line in run.stdout.splitlines():
        obj = json.loads(line)
        if obj.get("type") == "input":
            return obj["frames"], obj["emcy"], obj["malformed"], run.returncode, stderr[:1]
    return None, None, None, run.returncode, stderr[:1]


def networks(sources):
    """(trace, rows it holds) per row of the canopen/ table."""
    for line in sources.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 5 or not cells[0].startswith("canopen/"):
            continue
        held = re.search(r"(\d[\d ]*) (?:frames|rows)", cells[4])
        if held:
            yield cells[0], int(held.group(1).replace(" ", ""))


def story(binary, path):
    """What the tool reads on a network: the input, its nodes, its notes."""
    run = subprocess.run(
        [str(binary), "--format", "ndjson", str(path)], capture_output=True, check=False
    )
    objects = [json.loads(line) for line in run.stdout.splitlines() if line.strip()]
    notes = run.stderr.decode("utf-8", "replace").strip().splitlines()
    return objects, notes, run.returncode


def describe(objects):
    """One line per node the tool reports, and counts of the events."""
    lines = []
    events = {}
    for obj in objects:
        kind = obj.get("type")
        if kind == "node":
            said = [f"state {obj.get('nmt_state') or '-'}"]
            beat = obj.get("heartbeat") or {}
            if beat.get("period") is not None or beat.get("timeout") is not None:
                via = beat.get("via") or "heartbeat"
                said.append(f"{via} {beat.get('period')} s, lost {beat.get('lost', 0)}x")
            if obj.get("device_type"):
                said.append(f"device type {obj['device_type']}")
            if obj.get("axis"):
                said.append(f"drive {obj['axis'].get('state') or 'state unknown'}")
            said.append(f"{obj.get('emcy_count', 0)} EMCY")
            lines.append(f"      node {obj.get('node')}: {', '.join(said)}")
        elif kind not in ("input", "summary", None):
            events[kind] = events.get(kind, 0) + 1
    counted = ", ".join(f"{n} {k}" for k, n in sorted(events.items()))
    lines.append(f"      events: {counted or 'none'}")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", default=ROOT / "target/release/emcy-decode", type=pathlib.Path)
    parser.add_argument(
        "--traces", default=ROOT.parent / "shared/realworld-traces", type=pathlib.Path
    )
    args = parser.parse_args()
    sources = args.traces / "SOURCES.md"
    if not sources.is_file():
        sys.exit(f"error: {sources} not found (give --traces DIR)")
    if not args.bin.is_file():
        sys.exit(f"error: {args.bin} not found (cargo build --release, or give --bin)")
    failed = 0
    total = 0
    for trace, frames, emcy in rows(sources):
        total += 1
        got_frames, got_emcy, malformed, code, err = read(args.bin, args.traces / trace)
        ok = got_frames in frames and got_emcy in emcy and code == 0
        failed += not ok
        want = f"{'/'.join(map(str, sorted(frames)))} frames {'/'.join(map(str, sorted(emcy)))} EMCY"
        got = f"{got_frames} frames {got_emcy} EMCY {malformed} malformed, exit {code}"
        note = f"  {err[0]}" if err and not ok else ""
        print(f"{'ok  ' if ok else 'FAIL'} {trace}: {got} (want {want}){note}")
    print(f"{total - failed} of {total} traces read as the independent readers do")
    held_total = 0
    for trace, held in networks(sources):
        held_total += 1
        objects, notes, code = story(args.bin, args.traces / trace)
        inputs = [o for o in objects if o.get("type") == "input"]
        if not inputs:
            failed += 1
            print(f"FAIL {trace}: no input object, exit {code}  {notes[:1]}")
            continue
        i = inputs[0]
        ok = i["frames"] + i["malformed"] == held and code in (0, 1)
        failed += not ok
        print(
            f"{'ok  ' if ok else 'FAIL'} {trace}: {i.get('format')} {i['frames']} frames "
            f"+ {i['malformed']} malformed of {held} rows, {i['emcy']} EMCY, "
            f"{len(notes)} notes, exit {code}"
        )
        for line in describe(objects):
            print(line)
    print(f"{held_total} machine networks")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
