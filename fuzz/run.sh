#!/usr/bin/env bash
# Runs fuzz targets one after another, a single process each (the numbers in
# fuzz/README.md were taken this way):
#   fuzz/run.sh SECONDS [TARGET...]     (default: every target, 600 s each)
# New inputs go to fuzz/corpus-full/<target> (not committed), seeded from the
# committed fuzz/corpus/<target> and fuzz/regressions/<target>; the libFuzzer
# log of each run is fuzz/<target>.log. Needs nightly and cargo-fuzz.
# -O -a: optimised, with debug assertions and overflow checks (an integer
# overflow is a crash, not a silent wrap).
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(candump_log candump_screen asc trc blf detect decode_timeline)
for t in "${targets[@]}"; do
    max_len=4096
    [ "$t" = decode_timeline ] && max_len=1024
    # detect starts worker threads; LeakSanitizer reports std's per-thread
    # channel context of a worker still exiting (a race, not a leak).
    leaks=1
    [ "$t" = detect ] && leaks=0
    mkdir -p "fuzz/corpus-full/$t"
    cargo +nightly fuzz run -O -a "$t" "fuzz/corpus-full/$t" "fuzz/corpus/$t" "fuzz/regressions/$t" -- \
        -max_total_time="$secs" -rss_limit_mb=2048 -max_len="$max_len" -timeout=10 \
        -detect_leaks="$leaks" \
        -print_final_stats=1 2>&1 | tee "fuzz/$t.log" | grep -E "^(#[0-9]+ +(INITED|DONE|pulse)|==|SUMMARY|stat::|Done)" || true
done
