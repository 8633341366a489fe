#!/usr/bin/env bash
# The set of real merges a policy is checked on before it is trusted elsewhere: windows cut with
# `mapc window --match simple_merge` around motorway merges of three real maps (I-696, Flow's I-210, osm2streets'
# Arizona Loop 101), the paper's I-696 window and the Simple Merge itself.
#
#   tools/merge_set.sh cut                  # (re)write scenarios/merges/*.toml and their graphs
#   tools/merge_set.sh eval POLICY...       # one markdown row per merge: humans, then each policy (100 seeds)
#   tools/merge_set.sh fit-cut              # (re)write scenarios/fitted/*.toml: merges refused at the Simple
#                                           # Merge's lengths, cut with --fit, and merges that fit cut as short
#   tools/merge_set.sh fit-eval POLICY...   # the same rows for scenarios/fitted/
#
# MAPC (default target/release/mapc), SEEDS (default 100).
set -euo pipefail
cd "$(dirname "$0")/.."
MAPC=${MAPC:-target/release/mapc}
SEEDS=${SEEDS:-100}
DIR=scenarios/merges

# name, map, merge junction (the source map's id)
MERGES=(
  "i696_26913188 maps/i696.osm osm:26913188"
  "i696_61860349 maps/i696.osm osm:61860349"
  "i696_61860453 maps/i696.osm osm:61860453"
  "i696_62339771 maps/i696.osm osm:62339771"
  "i696_61860343 maps/i696.osm osm:61860343"
  "i210_300944078 maps/i210.net.xml osm:300944078"
  "i210_300944436 maps/i210.net.xml osm:300944436"
  "arizona_5134463770 maps/arizona_highways.osm osm:5134463770"
)

# Merges whose Simple Merge window is refused (a length short on the map), cut with --fit: name, map, merge,
# --fit-floor. The last two are far below the default floor of 0.5.
FITTED=(
  "i210_1686590993 maps/i210.net.xml osm:1686590993 0.5"
  "i696_61855155 maps/i696.osm osm:61855155 0.5"
  "i210_300944703 maps/i210.net.xml osm:300944703 0.5"
  "i5_1864943558 maps/i5_exit_ramp.osm osm:1864943558 0.18"
  "i210_1842086610 maps/i210.net.xml osm:1842086610 0.13"
)
# Merges that fit, cut again matched to a Simple Merge as short as a fitted window (530 m before the merge, as
# I-210's osm:1686590993 has; 112.9 m before and a 112.1 m ramp, as I-5's osm:1864943558): the same merge and
# demand, the window alone shorter. name, map, merge, its full-length scenario, the source's pre_merge_m and
# merge_m (each after a 100 m entry road).
SHORTENED=(
  "i696_window_530 scenarios/i696.corridor.graph.json osm:61862553 scenarios/i696_window.toml 430.0 100.0"
  "i696_window_i5 scenarios/i696.corridor.graph.json osm:61862553 scenarios/i696_window.toml 12.9 12.1"
  "i210_300944436_530 maps/i210.net.xml osm:300944436 scenarios/merges/i210_300944436.toml 430.0 100.0"
)
FIT_DIR=scenarios/fitted

fit_cut() {
  mkdir -p "$FIT_DIR"
  for m in "${FITTED[@]}"; do
    read -r name map junction floor <<<"$m"
    "$MAPC" window "$map" --junction "$junction" --match simple_merge --fit --fit-floor "$floor" \
      -o "$FIT_DIR/$name.toml" >/dev/null
    echo "wrote $FIT_DIR/$name.toml"
  done
  for m in "${SHORTENED[@]}"; do
    read -r name map junction _ pre ramp <<<"$m"
    local source="$FIT_DIR/source_$name.toml"
    sed -e "s/^pre_merge_m = 500.0\$/pre_merge_m = $pre/" -e "s/^merge_m = 100.0\$/merge_m = $ramp/" \
      -e "s/^name = \"simple_merge\"\$/name = \"source_$name\"/" scenarios/simple_merge.toml >"$source"
    grep -q "^pre_merge_m = $pre\$" "$source" && grep -q "^merge_m = $ramp\$" "$source"
    "$MAPC" window "$map" --junction "$junction" --match "$source" -o "$FIT_DIR/$name.toml" >/dev/null
    echo "wrote $FIT_DIR/$name.toml"
  done
}

cut() {
  mkdir -p "$DIR"
  for m in "${MERGES[@]}"; do
    read -r name map junction <<<"$m"
    "$MAPC" window "$map" --junction "$junction" --match simple_merge -o "$DIR/$name.toml" >/dev/null
    echo "wrote $DIR/$name.toml"
  done
}

# mean ± ci95 (change vs humans, disjoint?) from mapc eval --json
row_cell() {
  python3 -c '
import json, sys
r = json.load(sys.stdin)
o, c = r["outflow"], r["comparison"]
mark = "disjoint" if c["outflow_ci_disjoint"] else "overlap"
if r.get("withheld"):
    mark = "not deployed: humans drive"
print("%.1f ± %.1f (%+.1f %%, %s)" % (o["mean"], o["ci95"], c["outflow_change_pct"], mark), end="")'
}

# the merge's regime under humans (mapc sim's report over 3 seeds): who has priority, the main road's speed
# against free flow, the merging road's queue
regime_cell() {
  python3 -c '
import json, sys
r = json.load(sys.stdin)["regime"]["merges"]
m = r[0] if len(r) == 1 else next(x for x in r if x["name"].startswith("merge"))
main = next(a for a in m["approaches"] if a["main_line"])
ramp = next(a for a in m["approaches"] if not a["main_line"])
who = "both" if main["major"] and ramp["major"] else ("main road" if main["major"] else "merging road")
print("%s; main road at %.0f %%, queue %.0f m" % (who, 100 * main["speed_ratio"], ramp["mean_queue_m"]), end="")'
}

evaluate() {
  local scenarios=(simple_merge scenarios/i696_window.toml)
  for m in "${MERGES[@]}"; do
    read -r name _ _ <<<"$m"
    scenarios+=("$DIR/$name.toml")
  done
  evaluate_on "$@"
}

fit_evaluate() {
  local scenarios=()
  for m in "${FITTED[@]}"; do
    read -r name _ <<<"$m"
    scenarios+=("$FIT_DIR/$name.toml")
  done
  for m in "${SHORTENED[@]}"; do
    read -r name _ _ full _ <<<"$m"
    [[ " ${scenarios[*]} " == *" $full "* ]] || scenarios+=("$full")
    scenarios+=("$FIT_DIR/$name.toml")
  done
  evaluate_on "$@"
}

# one row per scenario of the caller's `scenarios`
evaluate_on() {
  printf '| merge | priority; humans near the merge | humans (veh/h) |'
  for p in "$@"; do printf ' %s |' "$(basename "$p" .json)"; done
  printf '\n|---|---|---|'
  for _ in "$@"; do printf -- '---|'; done
  printf '\n'
  for s in "${scenarios[@]}"; do
    local first=1
    for p in "$@"; do
      json=$("$MAPC" eval --policy "$p" --scenario "$s" --seeds "$SEEDS" --json)
      if [ $first = 1 ]; then
        human=$(python3 -c 'import json,sys; b=json.load(sys.stdin)["baseline"]["outflow"]; print("%.1f ± %.1f" % (b["mean"], b["ci95"]))' <<<"$json")
        regime=$("$MAPC" sim --scenario "$s" --seeds 3 --json | regime_cell)
        printf '| %s | %s | %s |' "$(basename "$s" .toml)" "$regime" "$human"
        first=0
      fi
      printf ' %s |' "$(row_cell <<<"$json")"
    done
    printf '\n'
  done
}

case "${1:-}" in
  cut) cut ;;
  eval) shift; [ $# -ge 1 ] || { echo "usage: $0 eval POLICY..." >&2; exit 2; }; evaluate "$@" ;;
  fit-cut) fit_cut ;;
  fit-eval) shift; [ $# -ge 1 ] || { echo "usage: $0 fit-eval POLICY..." >&2; exit 2; }; fit_evaluate "$@" ;;
  *) echo "usage: $0 cut | eval POLICY... | fit-cut | fit-eval POLICY..." >&2; exit 2 ;;
esac
