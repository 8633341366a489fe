#!/usr/bin/env bash
# Times two builds of mapc on the same short training run, alternately N times (default 3), and checks that both
# wrote the same log rows (all columns but the wall time). The figures of docs/perf.md "Training speed".
# usage: tools/paired_train.sh MAPC_A MAPC_B [N] [-- TRAIN ARGS]   (default: --distributed --preset paper --seed 7)
set -euo pipefail
a=${1:?mapc binary A}; b=${2:?mapc binary B}; shift 2
n=3; [ $# -gt 0 ] && [ "$1" != "--" ] && { n=$1; shift; }
[ "${1:-}" = "--" ] && shift
args=("$@"); [ ${#args[@]} -gt 0 ] || args=(--distributed --preset paper --seed 7)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for _ in $(seq "$n"); do
  for side in a b; do
    bin=$a; [ $side = b ] && bin=$b
    rm -rf "$tmp/$side"
    /usr/bin/time -f "$side %e s wall, %U s user, %S s kernel" "$bin" train "${args[@]}" --iters 2 --threads 1 \
      -o "$tmp/$side" 2>&1 >/dev/null | tail -1
  done
  cmp <(cut -d, -f1,2,4- "$tmp/a/progress.csv") <(cut -d, -f1,2,4- "$tmp/b/progress.csv") \
    && echo "same log rows" || { echo "the log rows differ"; exit 1; }
done
