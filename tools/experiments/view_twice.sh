#!/usr/bin/env bash
# What the lane changer's view costs (docs/perf_sim.md, "what the lane changer's view costs"): builds this checkout
# and a copy with view_twice.patch applied (each vehicle's own leader and both sides' neighbours found a second
# time, the result discarded; the runs are unchanged), then compares their CPU time per run on highway_ramp and
# ramp_game with tools/paired_sumo_bench.sh (N alternating runs each, default 7) and their instructions with
# callgrind where valgrind is installed.
# usage: tools/experiments/view_twice.sh [N]
set -euo pipefail
cd "$(dirname "$0")/../.."
n=${1:-7}
wt=target/view-twice-src
git worktree remove --force "$wt" 2>/dev/null || true
git worktree add --detach -f "$wt" HEAD >/dev/null
trap 'git worktree remove --force "$wt" 2>/dev/null || true' EXIT
# (the working tree's own edits too, so that both builds differ by the patch alone)
git diff HEAD | git -C "$wt" apply --allow-empty
git -C "$wt" apply "$PWD/tools/experiments/view_twice.patch"
cargo build --release --bin mapc
CARGO_TARGET_DIR="$PWD/target/view-twice" cargo build --release --bin mapc --manifest-path "$wt/Cargo.toml"
base=target/release/mapc
twice=target/view-twice/release/mapc
cfgs=(scenarios/sumo/highway_ramp/highway-ramp.sumocfg scenarios/sumo/ramp_game/ramp.sumocfg)
tools/paired_sumo_bench.sh "$base" "$twice" "$n" "${cfgs[@]}"
if command -v valgrind >/dev/null; then
  for cfg in "${cfgs[@]}"; do
    for b in "$base" "$twice"; do
      refs=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$b" bench "$cfg" --no-sumo --seeds 1 \
        --single-core-seeds 1 --threads 1 2>&1 | sed -n 's/.*I *refs: *//p')
      echo "$cfg: $b: $refs instructions"
    done
  done
fi
