#!/usr/bin/env bash
# Runs fuzz targets one after another, a single process each (the numbers in
# fuzz/README.md were taken this way):
#   fuzz/run.sh SECONDS [TARGET...]     (default: every target, 600 s each)
# New inputs go to fuzz/corpus-full/<target> (not committed), seeded from the
# fixtures of the target's format, the committed fuzz/corpus/<target> and
# fuzz/regressions/<target>; the libFuzzer log of each run is
# fuzz/<target>.log. Needs nightly and cargo-fuzz.
# -O -a: optimised, with debug assertions and overflow checks (an integer
# overflow is a crash, not a silent wrap).
#
# Exits non-zero when any target fails to build, crashes, or does not run
# to its time: a fuzz run that did not run is a failure, never a success.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-600}
shift || true
targets=("$@")
all=(candump_log candump_screen asc trc busmaster blf pcap ethercat mf4 detect decode_timeline dcf)
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")

# The fixtures each target starts from (by the format it forces).
fixtures_of() {
    case "$1" in
        candump_log) ls fixtures/*.log fixtures/baseline/*.log | grep -v busmaster ;;
        candump_screen) ls fixtures/*.txt ;;
        asc) ls fixtures/*.asc ;;
        trc) ls fixtures/*.trc ;;
        busmaster) ls fixtures/*.busmaster.log ;;
        blf) ls fixtures/*.blf ;;
        pcap) ls fixtures/*.pcap fixtures/*.pcapng ;;
        mf4) ls fixtures/*.mf4 ;;
        detect) ls fixtures/*.log fixtures/*.txt fixtures/*.asc fixtures/*.trc fixtures/*.blf fixtures/*.pcap fixtures/*.pcapng fixtures/*.mf4 fixtures/*.gz ;;
        # Seeds of its own shape (a framing byte, an EtherCAT frame) in
        # fuzz/corpus/ethercat, written by scripts/make_ethercat_fixtures.py.
        ethercat | decode_timeline) ;;
        # Seeded in fuzz/corpus/dcf (the fixture DCF behind a node byte).
        dcf) ;;
        *) echo "unknown target $1 (known: ${all[*]})" >&2; return 1 ;;
    esac
}

failed=()
for t in "${targets[@]}"; do
    max_len=4096
    [ "$t" = decode_timeline ] && max_len=1024
    # MF4 files put their metadata first: a few KiB before any record.
    [ "$t" = mf4 ] && max_len=16384
    # detect starts worker threads; LeakSanitizer reports std's per-thread
    # channel context of a worker still exiting (a race, not a leak).
    leaks=1
    [ "$t" = detect ] && leaks=0
    seeds=$(fixtures_of "$t") || { failed+=("$t (unknown)"); continue; }
    mkdir -p "fuzz/corpus-full/$t"
    for f in $seeds; do cp -n "$f" "fuzz/corpus-full/$t/" 2>/dev/null || true; done
    # Only directories that exist: libFuzzer stops on a missing one.
    dirs=("fuzz/corpus-full/$t")
    for d in "fuzz/corpus/$t" "fuzz/regressions/$t"; do
        [ -d "$d" ] && dirs+=("$d")
    done
    status=0
    cargo +nightly fuzz run -O -a "$t" "${dirs[@]}" -- \
        -max_total_time="$secs" -rss_limit_mb=2048 -max_len="$max_len" -timeout=10 \
        -detect_leaks="$leaks" -print_final_stats=1 >"fuzz/$t.log" 2>&1 || status=$?
    grep -E "^(#[0-9]+ +(INITED|DONE)|==|SUMMARY|stat::number_of_executed_units|Done)" "fuzz/$t.log" || true
    # A run that ended by its time says "Done N runs in S second(s)".
    ran=$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\1 \2/p' "fuzz/$t.log" | tail -1)
    if [ "$status" -ne 0 ] || [ -z "$ran" ] || [ "${ran#* }" -lt $((secs - 1)) ]; then
        echo "FAILED: $t (exit $status; ${ran:-no run}; see fuzz/$t.log)" >&2
        failed+=("$t")
    else
        echo "ok: $t: ${ran% *} runs in ${ran#* } s"
    fi
done
if [ ${#failed[@]} -gt 0 ]; then
    echo "fuzz/run.sh: failed: ${failed[*]}" >&2
    exit 1
fi
