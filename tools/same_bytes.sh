#!/usr/bin/env bash
# Writes what a build of mapc gives on the shipped scenarios, for comparing two builds byte for byte: each
# scenario's `mapc sim X --seeds 4 --json` without its timing fields, and the loops' and trip-info files of three
# SUMO users' scenarios. Then `diff -r OUT_A OUT_B` says whether a change kept every result.
# usage: tools/same_bytes.sh MAPC_BINARY OUT_DIR [EXTRA_SCENARIO...]
set -euo pipefail
bin=$(realpath "${1:?mapc binary}"); out=${2:?output folder}; shift 2
cd "$(dirname "$0")/.."
rm -rf "$out"; mkdir -p "$out/files"
for s in scenarios/sumo/highway_ramp/highway-ramp.sumocfg scenarios/sumo/ramp_game/ramp.sumocfg \
  scenarios/sumo/eccles_interchange/interchangeSim.cfg scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg \
  scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg scenarios/sumo/route_choice/route_choice.sumocfg \
  scenarios/sumo/sumo_rl_3x3grid/3x3grid.sumocfg scenarios/sumo/resco_ingolstadt1/ingolstadt1.sumocfg \
  scenarios/flow_bottleneck.toml scenarios/lane_drop_random.toml scenarios/simple_merge.toml \
  scenarios/i210_window_lanes.toml scenarios/two_lane_merge_av.toml scenarios/i696_window_lanes.toml "$@"; do
  "$bin" sim "$s" --seeds 4 --json 2>/dev/null | grep -v '"wall_s"\|_s_per\|"cpu_s"\|elapsed' > "$out/$(echo "$s" | tr / _).json"
done
"$bin" sim scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg --seeds 1 --first-seed 3 \
  --detector-output "$out/files/a" --tripinfo-output "$out/files/a.trip.xml" >/dev/null 2>&1
"$bin" sim scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg --seeds 1 --first-seed 3 \
  --detector-output "$out/files/b" --tripinfo-output "$out/files/b.trip.xml" >/dev/null 2>&1
"$bin" sim scenarios/sumo/eccles_interchange/interchangeSim.cfg --seeds 1 --first-seed 3 \
  --tripinfo-output "$out/files/c.trip.xml" >/dev/null 2>&1
# (the files' headers carry the date)
find "$out/files" -type f -exec sed -i '/<!--\|generated on\|date=/d' {} +
echo "$out: $(ls "$out" | wc -l) runs, $(find "$out/files" -type f | wc -l) output files"
