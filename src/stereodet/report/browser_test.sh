#!/usr/bin/env bash
# The report in a real browser: headless Chromium opens OUT/report/index.html from a file URL, and
#   - the DOM after its script ran holds every figure of OUT/report/figures/ (fig-ID and an <svg>),
#     and the page's own count (body data-figures) equals it;
#   - the console shows only the page's own line "stereodet-report: N figures drawn, N in data"
#     (any other message, an error, an uncaught exception, a refused load, fails the test; Chromium
#     logs every console message at one level, so the test accepts that one line and nothing else);
#   - the worst frames' views are linked: the evaluation keeps its records (--records), so the page
#     has a table of the frames with most FNs / FPs, and the DOM holds one link
#     (a.stereodet-view-link) per view file of OUT/report/views/, each to a file that is there
#     (a frame with most FNs and most FPs is linked twice, to the same files).
#   - a screenshot is not blank (enough non-white pixels and colours).
# Usage: browser_test.sh STEREODET_BIN DATA_DIR WORK_DIR [--control]
#   --control adds one console.error() to the generated page: the test must then fail (ctest runs
#   it as cli.report.browser_control and expects that failure), so a console check that sees nothing is caught.
# Exit 0: passed; 1: failed; 77: Chromium is not installed (ctest reports the test as skipped).
set -euo pipefail
bin=$1 data=$2 work=$3 control=${4:-}

browser=""
for candidate in chromium chromium-browser google-chrome; do
  if command -v "$candidate" >/dev/null 2>&1; then browser=$(command -v "$candidate"); break; fi
done
if [[ -z "$browser" ]]; then
  echo "SKIPPED: no Chromium (Debian package chromium; scripts/install-deps.sh installs it)"
  exit 77
fi

rm -rf "$work"
mkdir -p "$work"
"$bin" eval --gt "$data" --det "$data/det" --out "$work/eval" --records --report >"$work/eval.log"
report="$work/eval/report"
index="$report/index.html"
if [[ "$control" == --control ]]; then
  sed -i 's|</body>|<script>console.error("control: an error on the page")</script></body>|' "$index"
fi

# Chromium as root needs --no-sandbox; no network: every host name resolves to nothing.
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars --no-first-run
       --host-resolver-rules="MAP * ~NOTFOUND" --user-data-dir="$work/profile")
timeout 120 "$browser" "${flags[@]}" --enable-logging=stderr --v=0 --dump-dom "file://$index" \
  >"$work/dom.html" 2>"$work/console.log"
timeout 120 "$browser" "${flags[@]}" --window-size=1400,1000 --screenshot="$work/screenshot.png" \
  "file://$index" >/dev/null 2>&1

/usr/bin/python3 - "$report" "$work" <<'PY'
import os, re, struct, sys, zlib
report, work = sys.argv[1], sys.argv[2]
failures = []
ids = sorted(f[:-4] for f in os.listdir(os.path.join(report, "figures")) if f.endswith(".svg"))
dom = open(os.path.join(work, "dom.html"), encoding="utf-8").read()
if not ids:
    failures.append("no figures in " + report)
missing = [i for i in ids if f'id="fig-{i}"' not in dom or f'id="{i}" class="plot"' not in dom]
if missing:
    failures.append(f"{len(missing)} figures not in the DOM, e.g. {missing[:3]}")
m = re.search(r'<body[^>]*data-figures="(\d+)"', dom)
if not m or int(m.group(1)) != len(ids):
    failures.append(f"the page counted {m.group(1) if m else 'no'} figures, the folder has {len(ids)}")

views_dir = os.path.join(report, "views")
view_files = sorted(f for f in os.listdir(views_dir)) if os.path.isdir(views_dir) else []
links = re.findall(r'<a class="stereodet-view-link"[^>]*href="([^"]+)"', dom)
if not view_files:
    failures.append("no frame views in " + views_dir)
if sorted(set(os.path.basename(l) for l in links)) != view_files:
    failures.append(f"the DOM's view links ({len(set(links))} files) are not the {len(view_files)} view files")
dangling = [l for l in links if not os.path.isfile(os.path.join(report, l))]
if dangling:
    failures.append(f"view links to missing files: {dangling[:3]}")
if 'id="worst-frames"' not in dom:
    failures.append("no worst-frames table in the DOM")

console = [l for l in open(os.path.join(work, "console.log"), errors="replace") if ":CONSOLE" in l]
expected = f'"stereodet-report: {len(ids)} figures drawn, {len(ids)} in data"'
own = [l for l in console if expected in l]
others = [l.strip() for l in console if expected not in l]
if len(own) != 1:
    failures.append(f"the page's console line {expected} was seen {len(own)} times")
if others:
    failures.append("console messages: " + " | ".join(others[:5]))

# The screenshot: decode the PNG (8-bit RGB or RGBA, no interlace) and count non-white pixels.
png = open(os.path.join(work, "screenshot.png"), "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n", "screenshot is not a PNG"
pos, idat, width = 8, b"", 0
while pos < len(png):
    length, kind = struct.unpack(">I4s", png[pos:pos + 8])
    body = png[pos + 8:pos + 8 + length]
    if kind == b"IHDR":
        width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
        assert depth == 8 and colour in (2, 6) and interlace == 0, "unexpected PNG format"
        channels = 3 if colour == 2 else 4
    elif kind == b"IDAT":
        idat += body
    pos += 12 + length
raw, stride = zlib.decompress(idat), width * channels
rows, prev = [], bytearray(stride)
for y in range(height):
    f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for x in range(stride):
        a = line[x - channels] if x >= channels else 0
        b, c = prev[x], prev[x - channels] if x >= channels else 0
        if f == 1: line[x] = (line[x] + a) & 255
        elif f == 2: line[x] = (line[x] + b) & 255
        elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(bytes(line)); prev = line
pixels = [r[x:x + 3] for r in rows for x in range(0, stride, channels)]
non_white = sum(1 for p in pixels if p != b"\xff\xff\xff")
colours = len(set(pixels))
if non_white < 0.01 * len(pixels) or colours < 16:
    failures.append(f"screenshot looks blank: {non_white} of {len(pixels)} pixels not white, {colours} colours")

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print(f"passed: {len(ids)} figures and {len(links)} frame-view links in the DOM, console clean, screenshot {width}x{height} with "
      f"{100 * non_white / len(pixels):.1f}% non-white pixels, {colours} colours")
PY
