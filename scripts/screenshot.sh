#!/bin/sh
# Renders the HTML timeline of a trace in headless Chromium and saves a PNG,
# to check the chart by eye in a real browser. Needs Chromium (Debian:
# `apt-get install -y chromium`); without it this says so and exits 0, so it
# can run anywhere. The project itself never needs Chromium.
#
#   scripts/screenshot.sh [TRACE] [OUT.png] [WIDTH] [HEIGHT]
#   scripts/screenshot.sh fixtures/edge.log target/chart/edge.png
set -eu
trace=${1:-fixtures/s300.log}
png=${2:-target/chart/$(basename "$trace").png}
width=${3:-1000}
height=${4:-900}

browser=""
for b in chromium chromium-browser google-chrome; do
    if command -v "$b" >/dev/null 2>&1; then browser=$b; break; fi
done
if [ -z "$browser" ]; then
    echo "screenshot: skipped, no Chromium found (apt-get install -y chromium)"
    exit 0
fi

bin=${EMCY_DECODE:-}
if [ -z "$bin" ]; then
    cargo build --quiet
    bin=target/debug/emcy-decode
fi
mkdir -p "$(dirname "$png")"
png=$(realpath "$png")
html=$(dirname "$png")/$(basename "$png" .png).html
# Exit 1 (--fail-on) or 2 (malformed lines) still writes the page.
"$bin" --format html "$trace" >"$html" || [ -s "$html" ]
# A throwaway profile: no first-run state, nothing left in $HOME.
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
"$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
    --user-data-dir="$profile" --no-first-run --no-default-browser-check \
    --window-size="$width,$height" --screenshot="$(realpath "$png")" \
    "file://$(realpath "$html")" \
    >/dev/null 2>&1 || { echo "screenshot: chromium failed"; exit 1; }
[ -s "$png" ] || { echo "screenshot: chromium wrote no $png"; exit 1; }
echo "screenshot: $png"
