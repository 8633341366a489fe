#!/usr/bin/env bash
# Size and opening time of `mapc view` pages (docs/perf.md): writes each page, opens it N times in headless
# Chromium from disk, and prints its size and the time from navigation to the first frame drawn (the page's own
# data-ready-ms: data parsed, typed arrays decoded, network and vehicles drawn, time-space diagram rendered).
# Usage: tools/view_timing.sh [N]   (MAPC=path/to/mapc to use another binary; CHROMIUM=... likewise)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-5}
mapc=${MAPC:-target/release/mapc}
[ -n "${MAPC:-}" ] || cargo build --release --quiet
browser=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || command -v google-chrome)}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
policy=policies/simple_merge_outflow.json
pages=(
  "simple_merge_humans|simple_merge"
  "simple_merge_compare|simple_merge --policy $policy --compare"
  "i696_window_policy|scenarios/i696_window.toml --policy $policy"
  "i696_window_compare|scenarios/i696_window.toml --policy $policy --compare"
  "i696_map|maps/i696.osm"
)
printf '%-22s %10s %14s %s\n' page MB vehicle-steps "first frame drawn, ms (median of $n; min-max)"
for entry in "${pages[@]}"; do
  name=${entry%%|*}
  # shellcheck disable=SC2086
  steps=$("$mapc" view ${entry#*|} -o "$out/$name.html" --json |
    python3 -c 'import json,sys; print(sum(p["vehicle_steps"] for p in json.load(sys.stdin)["panes"]))')
  times=()
  for i in $(seq "$n"); do
    t=$("$browser" --headless --no-sandbox --disable-gpu --no-first-run --window-size=1400,1000 \
      --user-data-dir="$out/profile-$name-$i" --dump-dom "file://$out/$name.html" 2>/dev/null |
      grep -o 'data-ready-ms="[0-9]*"' | grep -o '[0-9]*')
    times+=("$t")
  done
  sorted=$(printf '%s\n' "${times[@]}" | sort -n)
  median=$(echo "$sorted" | sed -n "$(((n + 1) / 2))p")
  printf '%-22s %10.2f %14s %s (%s-%s)\n' "$name" "$(echo "$(stat -c %s "$out/$name.html") / 1000000" | bc -l)" \
    "$steps" "$median" "$(echo "$sorted" | head -1)" "$(echo "$sorted" | tail -1)"
done
