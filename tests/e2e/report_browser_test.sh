#!/usr/bin/env bash
# Opens the run report (every input, the area log too), a comparison of two runs (--compare)
# and harmoloc-colours' preview of a recording (masks over frames, areas along the run) in a
# real browser (Debian's chromium, headless): each page and each plot it shows
# must load and render with no console message, and the screenshots must not be blank.
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
run="$out/run"  # a run folder as --compare takes it: trajectory.tum and stats.json
mkdir -p "$run"
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --trajectory "$run/trajectory.tum" \
  --fixes "$out/fixes.tum" --link "$out/link.bin" --stats "$run/stats.json" \
  --record-areas "$out/areas.csv" --quiet
head -3 "$out/areas.csv" | tail -1 |
  grep -q ',distrusted_mask,column_sum_[^,]*,.*,side_px_[^,]*,.*,row_sum_[^,]*$' ||
  fail "the area log has no distrusted_mask, column and row columns: $(head -3 "$out/areas.csv" | tail -1)"
# The firmware measures every frame's columns and rows: no '-' (not measured) in any frame's line.
! tail -n +4 "$out/areas.csv" | grep -q ',-' ||
  fail "the firmware's area log has frames without columns: $(tail -n +4 "$out/areas.csv" | grep -m1 ',-')"
"$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --estimate "$run/trajectory.tum" \
  --fixes "$out/fixes.tum" --stats "$run/stats.json" --link "$out/link.bin" \
  --areas "$out/areas.csv" --out "$out/report" --skip-initial 3 --title "browser check" > /dev/null
# Two runs on one page: the fused estimate (run folder, with stats) against the raw fixes.
"$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --compare "fused=$run" \
  "fixes only=$out/fixes.tum" --skip-initial 3 --out "$out/compare" > "$out/compare.txt"
grep -q "^fused " "$out/compare.txt" || { cat "$out/compare.txt"; fail "no fused row in the comparison"; }
# The colour tool's preview of the training run (automatic windows).
"$BIN/harmoloc-colours" --dataset "$WORK/train" --out "$out/colours.toml" \
  --preview "$out/colours" --quiet 2> "$out/colours.txt" ||
  { cat "$out/colours.txt"; fail "harmoloc-colours failed on the training run"; }

# The images a page shows; each listed file must be among them.
page_images() {
  python3 - "$1" << 'EOF'
import re, sys
print(" ".join(re.findall(r'<img src="([^"]+)"', open(sys.argv[1], encoding="utf-8").read())))
EOF
}
expect_images() {
  local page=$1
  shift
  local images
  images=$(page_images "$page")
  for f in "$@"; do
    case " $images " in *" $f "*) ;; *) fail "$page does not show $f (it shows: $images)" ;; esac
  done
}
expect_images "$out/report/index.html" trajectory.svg error.svg error_xy.svg timing.svg stages.svg \
  health.svg sigma.svg areas.svg
expect_images "$out/compare/index.html" compare_error.svg compare_trajectory.svg
[ -n "$(page_images "$out/colours/index.html")" ] || fail "the colours preview shows no image"

# A harness page beside a report that loads every image the report's page names.
write_harness() {
  # shellcheck disable=SC2046  # one argument per image
  python3 - "$1/check.html" $(page_images "$1/index.html") << 'EOF'
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
}
write_harness "$out/report"
write_harness "$out/compare"
write_harness "$out/colours"

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
shoot "file://$out/compare/index.html" "$out/compare.png" "$out/compare.log"
shoot "file://$out/compare/check.html" "$out/compare_check.png" "$out/compare_check.log"
shoot "file://$out/colours/index.html" "$out/colours.png" "$out/colours.log"
shoot "file://$out/colours/check.html" "$out/colours_check.png" "$out/colours_check.log"

# The harness must be able to fail: a missing image is reported.
cp "$out/report/check.html" "$out/report/check_broken.html"
sed -i 's/"trajectory.svg"/"no-such-plot.svg"/' "$out/report/check_broken.html"
timeout 120 "$browser" --headless --no-sandbox --disable-gpu --no-first-run \
  --user-data-dir="$profile" --enable-logging=stderr --v=0 --virtual-time-budget=5000 --screenshot="$out/broken.png" \
  "file://$out/report/check_broken.html" > "$out/broken.log" 2>&1 || true
grep -q "image failed to load: no-such-plot.svg" "$out/broken.log" ||
  { cat "$out/broken.log"; fail "the harness did not report a missing image"; }

# Not blank: the screenshot of the page is a PNG with many distinct colours (plots, text).
for png in "$out/page.png" "$out/compare.png" "$out/colours.png"; do
  python3 - "$png" << 'EOF' || fail "the screenshot $png looks blank"
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
done
echo "report, comparison and colours preview render in $("$browser" --version 2> /dev/null | tr -d '\n') with no console message"
