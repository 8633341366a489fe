#!/usr/bin/env bash
# Compares two builds of the simulator bench on a noisy machine: runs them alternately N times (default 25) and
# prints the mean log ratio of their one-core throughput (B against A) with its standard error and the median.
# Build each bench with `cargo bench -p mapc-sim --bench sim_speed --no-run` and copy the binary it names.
# usage: tools/paired_bench.sh BENCH_A BENCH_B [N] [SCENARIO]
set -euo pipefail
a=${1:?bench binary A}; b=${2:?bench binary B}; n=${3:-25}; scenario=${4:-}
rate() { "$1" $scenario | awk '/one core/ { for (i = 1; i <= NF; i++) if ($(i + 1) == "vehicle-steps/s,") print $i }'; }
for _ in $(seq "$n"); do
  echo "$(rate "$a") $(rate "$b")"
done | awk '{ d = log($2 / $1); print d }' | sort -g | awk '{ s += $1; ss += $1 * $1; v[NR] = $1 }
  END {
    m = s / NR; se = sqrt((ss - NR * m * m) / (NR - 1) / NR)
    med = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
    printf "B against A, one-core throughput: %+.2f %% +- %.2f %% (standard error), median %+.2f %%, %d pairs\n",
      100 * m, 100 * se, 100 * med, NR
  }'
