#!/usr/bin/env bash
# docs/images/report.png: the top of the report `make demo` ends with (sources, the summary table,
# Table 1), as a browser shows it, taken with Debian's headless Chromium (package chromium; not a
# dependency of the build, install it for this script only).
# Usage: scripts/report-screenshot.sh [REPORT_INDEX_HTML] [OUT_PNG]
set -euo pipefail
index=${1:-build/demo/report/index.html}
out=${2:-docs/images/report.png}
[[ -f "$index" ]] || { echo "report-screenshot: $index is not there; run make demo" >&2; exit 1; }
browser=$(command -v chromium || command -v chromium-browser || true)
[[ -n "$browser" ]] || { echo "report-screenshot: no chromium (apt-get install chromium)" >&2; exit 1; }
tmp="$out.tmp.png"
"$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1300,1480 \
  --screenshot="$tmp" "file://$(realpath "$index")" 2>/dev/null
mv "$tmp" "$out"
echo "report-screenshot: wrote $out"
