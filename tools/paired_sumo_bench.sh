#!/usr/bin/env bash
# Compares the CPU time of two builds of mapc on the SUMO users' freeway scenarios on a noisy machine: runs
# `mapc bench CFG --no-sumo --single-core-seeds 10` with each build alternately N times (default 7) and prints the
# median and least CPU time of a run (ms) per build and scenario.
# usage: tools/paired_sumo_bench.sh MAPC_A MAPC_B [N] [SUMOCFG...]
set -euo pipefail
a=$(realpath "${1:?mapc binary A}"); b=$(realpath "${2:?mapc binary B}"); n=${3:-7}; shift $(( $# < 3 ? $# : 3 ))
cd "$(dirname "$0")/.."
cfgs=("$@")
[ ${#cfgs[@]} -gt 0 ] || cfgs=(scenarios/sumo/highway_ramp/highway-ramp.sumocfg scenarios/sumo/ramp_game/ramp.sumocfg
  scenarios/sumo/eccles_interchange/interchangeSim.cfg)
per_run() {
  "$1" bench "$2" --no-sumo --single-core-seeds 10 --seeds 1 --json 2>/dev/null |
    python3 -c "import json, sys; s = json.load(sys.stdin)['single_core']; print(1000 * s['cpu_s'] / s['seeds'])"
}
for cfg in "${cfgs[@]}"; do
  ta=(); tb=()
  for _ in $(seq "$n"); do ta+=("$(per_run "$a" "$cfg")"); tb+=("$(per_run "$b" "$cfg")"); done
  python3 - "$cfg" "${ta[*]}" "${tb[*]}" <<'PY'
import statistics as st, sys
cfg, ta, tb = sys.argv[1], [float(x) for x in sys.argv[2].split()], [float(x) for x in sys.argv[3].split()]
ma, mb = st.median(ta), st.median(tb)
print(f"{cfg}: A {ma:.2f} ms (least {min(ta):.2f}), B {mb:.2f} ms (least {min(tb):.2f}), B against A {100 * (mb / ma - 1):+.1f} %")
PY
done
