#!/usr/bin/env bash
# Make the README's viewer screenshot from a real run:
#
#     scripts/viewer_screenshot.sh [OUT.png]        (default docs/img/viewer.png)
#
# Records `ego run emergency-brake -c fuzzy`, opens it in the Rerun viewer on a virtual
# display and saves what the viewer shows (the recording opens at its end). Needs xvfb-run
# and a Vulkan driver (Debian/Ubuntu: apt-get install -y xvfb mesa-vulkan-drivers): the
# viewer renders with software Vulkan there (about 25 s), its OpenGL backend refuses.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/img/viewer.png}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export XDG_CONFIG_HOME="$tmp" XDG_DATA_HOME="$tmp"  # Rerun's settings: not the user's
rerun analytics disable > /dev/null 2>&1 || true      # no first-run banner
python -m ego run emergency-brake -c fuzzy --record "$tmp/eb.rrd" > /dev/null
# the screen is larger than the window, so the pointer (at the screen's centre) hovers nothing
xvfb-run -a -s "-screen 0 3600x2400x24" rerun "$tmp/eb.rrd" --renderer vulkan \
    --window-size 1600x1000 --screenshot-to "$tmp/shot.png" > "$tmp/rerun.log" 2>&1 \
    || { cat "$tmp/rerun.log" >&2; exit 1; }
# the viewer draws at twice the window's size: scale to 1600 px and keep 256 colours (small
# file); written next to OUT first, then moved over it
python - "$tmp/shot.png" "$out" <<'PY'
import os
import sys

from PIL import Image

src, out = sys.argv[1:]
image = Image.open(src).convert("RGB")
image = image.resize((1600, round(image.height * 1600 / image.width)), Image.LANCZOS)
partial = f"{out}.partial.png"
image.quantize(256, method=Image.Quantize.MEDIANCUT).save(partial, optimize=True)
os.replace(partial, out)
print(f"{out}: {image.width}x{image.height}, {os.path.getsize(out) // 1024} KB")
PY
