#!/usr/bin/env bash
# Opens the run report in a real browser (Debian's chromium, headless): the page and each plot it
# shows must load and render with no console message, and the screenshot must not be blank.
# The page has no script of its own, so a harness page beside it loads every image the page
# names and logs an error for one that fails (a missing file or an SVG that is not well-formed
# XML), which the browser's log then shows. Exits 77 (ctest: skipped) only when chromium is not
# installed; ./run installs it, so CI runs this.
source "$(dirname "$0")/lib.sh" "$@"
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "SKIP: chromium is not installed (apt-get install chromium; ./run setup installs it)"
  exit 77
fi
out="$(cd "$WORK" && pwd)/browser"  # absolute: it goes into file:// URLs
rm -rf "$out"
mkdir -p "$out"
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --trajectory "$out/est.tum" \
  --fixes "$out/fixes.tum" --link "$out/link.bin" --stats "$out/stats.json" --quiet
"$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --estimate "$out/est.tum" \
  --fixes "$out/fixes.tum" --stats "$out/stats.json" --link "$out/link.bin" --out "$out/report" \
  --skip-initial 3 --title "browser check" > /dev/null

images=$(python3 - "$out/report/index.html" << 'EOF'
import re, sys
print(" ".join(re.findall(r'<img src="([^"]+)"', open(sys.argv[1], encoding="utf-8").read())))
EOF
)
for f in trajectory.svg error.svg error_xy.svg timing.svg stages.svg health.svg sigma.svg; do
  case " $images " in *" $f "*) ;; *) fail "the page does not show $f (it shows: $images)" ;; esac
done
python3 - "$out/report/check.html" $images << 'EOF'
import json, sys
srcs = sys.argv[2:]
page = """<!DOCTYPE html><html><head><meta charset="utf-8"></head><body><script>
const srcs = %s;
for (const src of srcs) {
  const img = new Image();
  img.onload = () => { if (!(img.naturalWidth > 0)) console.error("image has no size: " + src); };
  img.onerror = () => console.error("image failed to load: " + src);
  img.src = src;
  document.body.appendChild(img);
}
</script></body></html>
""" % json.dumps(srcs)
open(sys.argv[1], "w", encoding="utf-8").write(page)
EOF

# --no-sandbox: CI runs as root, where chromium's sandbox refuses to start. A profile of its own
# keeps the run independent of HOME (and out of it). The virtual time budget lets every image
# finish loading before the screenshot is taken.
profile="$out/chromium-profile"
shoot() {
  local url=$1 png=$2 log=$3
  timeout 120 "$browser" --headless --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$profile" --enable-logging=stderr --v=0 --virtual-time-budget=5000 --window-size=1000,5000 \
    --screenshot="$png" "$url" > "$log" 2>&1 || { cat "$log"; fail "chromium failed on $url"; }
  test -s "$png" || { cat "$log"; fail "no screenshot of $url"; }
  if grep -E "CONSOLE|Uncaught" "$log"; then fail "console messages on $url (above)"; fi
}
shoot "file://$out/report/index.html" "$out/page.png" "$out/page.log"
shoot "file://$out/report/check.html" "$out/check.png" "$out/check.log"

# The harness must be able to fail: a missing image is reported.
cp "$out/report/check.html" "$out/report/check_broken.html"
sed -i 's/"trajectory.svg"/"no-such-plot.svg"/' "$out/report/check_broken.html"
timeout 120 "$browser" --headless --no-sandbox --disable-gpu --no-first-run \
  --user-data-dir="$profile" --enable-logging=stderr --v=0 --virtual-time-budget=5000 --screenshot="$out/broken.png" \
  "file://$out/report/check_broken.html" > "$out/broken.log" 2>&1 || true
grep -q "image failed to load: no-such-plot.svg" "$out/broken.log" ||
  { cat "$out/broken.log"; fail "the harness did not report a missing image"; }

# Not blank: the screenshot of the page is a PNG with many distinct colours (plots, text).
python3 - "$out/page.png" << 'EOF' || fail "the page's screenshot looks blank"
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
width, height = struct.unpack(">II", data[16:24])
pos, idat = 8, b""
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    if kind == b"IDAT":
        idat += data[pos + 8:pos + 8 + n]
    pos += 12 + n
raw = zlib.decompress(idat)
# Distinct byte pairs in the first rows with content: a blank page has one or two.
distinct = len(set(raw[i:i + 2] for i in range(0, min(len(raw), 4_000_000), 7)))
print(f"screenshot {width}x{height}, {distinct} distinct samples")
sys.exit(0 if distinct > 50 else 1)
EOF
echo "report renders in $("$browser" --version 2> /dev/null | tr -d '\n') with no console message"
