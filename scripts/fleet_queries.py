#!/usr/bin/env python3
"""Runs the DuckDB queries of docs/fleet.md on the repository's fixtures,
as a fleet's daily run would on its traces, and prints their results (the
outputs shown in docs/fleet.md come from this script).

Needs two things the tests do not:
- the release binary, target/release/emcy-decode (cargo build --release
  --locked): a debug build decodes the fixtures too, but this script runs
  the binary at that path only, as a fleet's image would;
- DuckDB's Python package (pip install duckdb), which runs the queries.
Without either it says which on one line and exits 2. Run from the
repository root:
    cargo build --release --locked && pip install duckdb
    python3 scripts/fleet_queries.py
"""

import glob
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor


def missing(what):
    """Says what the script needs on one line and exits 2, as a usage error."""
    print(f"fleet_queries: needs {what}", file=sys.stderr)
    sys.exit(2)


try:
    import duckdb
except ImportError:
    missing("DuckDB's Python package: pip install duckdb")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.path.join(ROOT, "target", "release", "emcy-decode")

QUERIES = {
    "which codes across the fleet": """
        SELECT code, count(*) AS raised,
               count(DISTINCT file || '/' || channel || '/' || node) AS nodes
        FROM read_ndjson('{out}/*.ndjson', union_by_name = true)
        WHERE type = 'emcy' AND code <> '0x0000'
        GROUP BY code ORDER BY raised DESC, code LIMIT 8""",
    "nodes that lose heartbeats most": """
        SELECT file, channel, node, heartbeat.lost AS outages,
               heartbeat.silent_at_end AS silent_at_end
        FROM read_ndjson('{out}/*.ndjson', union_by_name = true)
        WHERE type = 'node' AND (heartbeat.lost > 0 OR heartbeat.silent_at_end)
        ORDER BY outages DESC, file, node""",
    "mean time in error per firmware": """
        SELECT m.firmware, count(*) AS nodes,
               round(avg(n.time_in_error), 3) AS mean_time_in_error_s
        FROM read_ndjson('{out}/*.ndjson', union_by_name = true) AS n
        JOIN read_csv('{machines}') AS m USING (file)
        WHERE n.type = 'node' AND n.time_in_error IS NOT NULL
        GROUP BY m.firmware ORDER BY mean_time_in_error_s DESC""",
}


def decode(trace, out):
    """The map step: one trace, one NDJSON file (exit 1 = errors found,
    not a failure)."""
    name = os.path.join(out, os.path.basename(trace) + ".ndjson")
    with open(name, "wb") as f:
        rc = subprocess.run(
            [BINARY, "--format", "ndjson", trace], stdout=f, stderr=subprocess.DEVNULL
        ).returncode
    if rc not in (0, 1):
        sys.exit(f"{trace}: exit {rc}")


def main():
    if not os.access(BINARY, os.X_OK):
        missing(f"the release binary {BINARY}: cargo build --release --locked")
    os.chdir(ROOT)
    traces = sorted(
        t
        for pattern in ("fixtures/*.log", "fixtures/*.asc", "fixtures/*.pcapng")
        for t in glob.glob(pattern)
        if not t.endswith(".td.log")
    )
    with tempfile.TemporaryDirectory() as out:
        with ThreadPoolExecutor(max_workers=os.cpu_count()) as pool:
            list(pool.map(lambda t: decode(t, out), traces))
        con = duckdb.connect()
        for title, sql in QUERIES.items():
            print(f"-- {title}")
            print(con.sql(sql.format(out=out, machines="docs/fleet/machines.csv")))


if __name__ == "__main__":
    main()
