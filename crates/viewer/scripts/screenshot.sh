#!/usr/bin/env bash
# The viewer's manual check with a screenshot: runs `view-smoke` (the material sphere on
# the CPU backend, 480×360) in a real window under Xvfb with the openbox window manager
# (for the title bar's spp and samples/s), waits, and saves the screen, cropped to the
# window, as docs/viewer.png.
#
#   apt-get install -y xvfb xauth openbox imagemagick
#   cargo build --release -p viewer
#   xvfb-run -a -s "-screen 0 520x420x24" crates/viewer/scripts/screenshot.sh [SECONDS=20]
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=target/release/view-smoke
[ -x "$bin" ] || bin=target/debug/view-smoke
openbox 2>/dev/null &
wm=$!
sleep 1
"$bin" "${TMPDIR:-/tmp}/view-smoke-shot.png" 1000000 480 360 1 >/dev/null &
viewer=$!
sleep "${1:-20}"
import -window root -crop 486x390+17+15 +repage docs/viewer.png
kill "$viewer" "$wm"
echo "wrote docs/viewer.png"
