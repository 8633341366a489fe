#!/usr/bin/env bash
# Zero-shot: policies trained on one scenario, evaluated with 10 % AVs (`--av-share 0.1`; the Simple Merge with its
# own 10 %) on the others, driving
# everywhere in their controlled region, under `simple-merge-regime` (only one-lane merges the humans congest;
# elsewhere the AVs drive as humans) and under `measured` (only where the policy first beats the humans on 20
# calibration seeds of its own). One markdown row per scenario and
# policy: humans, policy everywhere, policy under the rule (outflow veh/h, mean +- 95 % CI, and the change; the
# mean speed's change beside it: where every vehicle of a fixed number arrives, the outflow cannot change).
#
#   tools/zero_shot.sh [POLICY...]    # default: the Simple Merge's and the bottleneck's policies
#
# MAPC (default target/release/mapc), SEEDS (default 100), SCENARIOS (space-separated, default the six below).
set -euo pipefail
cd "$(dirname "$0")/.."
MAPC=${MAPC:-target/release/mapc}
SEEDS=${SEEDS:-100}
POLICIES=("$@")
[ ${#POLICIES[@]} -gt 0 ] || POLICIES=(policies/simple_merge_outflow.json policies/flow_bottleneck_av10_outflow.json)
# the Simple Merge has its own AV flows: no --av-share there
DEFAULT_SCENARIOS=(
  scenarios/simple_merge.toml
  scenarios/flow_bottleneck.toml
  scenarios/sumo/highway_ramp/highway-ramp.sumocfg
  scenarios/sumo/ramp_game/ramp.sumocfg
  scenarios/sumo/eccles_interchange/interchangeSim.cfg
  scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg
)
read -r -a SCENARIOS <<< "${SCENARIOS:-${DEFAULT_SCENARIOS[*]}}"

# outflow of one eval: "humans|policy|change"
run() {
  local share=(--av-share 0.1)
  [ "$(basename "$2")" != simple_merge.toml ] || share=()
  "$MAPC" eval --policy "$1" --scenario "$2" "${share[@]}" --seeds "$SEEDS" --deploy "$3" --json 2>/dev/null |
    python3 -c '
import json, sys
j = json.load(sys.stdin)
def f(o):
    return "%.1f ± %.1f" % (o["mean"], o["ci95"])
h, p = j["baseline"]["outflow"], j["outflow"]
d = 100.0 * (p["mean"] - h["mean"]) / h["mean"]
disjoint = p["mean"] - p["ci95"] > h["mean"] + h["ci95"] or p["mean"] + p["ci95"] < h["mean"] - h["ci95"]
ds = 100.0 * (j["speed"]["mean"] - j["baseline"]["speed"]["mean"]) / j["baseline"]["speed"]["mean"]
print("%s|%s (%+.1f %%%s; speed %+.1f %%)" % (f(h), f(p), d, ", CIs disjoint" if disjoint else "", ds))'
}

echo "| scenario | policy | humans | policy everywhere | policy, simple-merge-regime | policy, measured |"
echo "|---|---|---|---|---|---|"
for s in "${SCENARIOS[@]}"; do
  for p in "${POLICIES[@]}"; do
    every=$(run "$p" "$s" everywhere)
    rule=$(run "$p" "$s" simple-merge-regime)
    measured=$(run "$p" "$s" measured)
    echo "| $(basename "$s") | $(basename "$p" .json) | ${every%%|*} | ${every#*|} | ${rule#*|} | ${measured#*|} |"
  done
done
