#!/usr/bin/env bash
# Before/after check for changes that must not change results (issues 17, 18):
#   scripts/compare-outputs.sh run DIR [FDEM]   # run the cases with FDEM into DIR
#   scripts/compare-outputs.sh compare REF NEW  # mechanics bitwise, temperatures to 1e-10
# Series are compared in global id order, so outputs of different
# partitions compare.
# Cases: N = 50 deposition, eight-body drop and collision on 1 and 2 ranks
# (trajectories bitwise); two discs, cube stack, hot block on the floor, the
# N = 50 deposition coupled with heat and the N = 50 heat-up on 2 ranks
# (temperatures to round-off, positions bitwise).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
cmd="${1:?usage: compare-outputs.sh run DIR [FDEM] | compare REF NEW}"
case "$cmd" in
  run)
    dir="${2:?output directory}"
    fdem="${3:-${CARGO_TARGET_DIR:-target}/release/fdem}"
    rm -rf "$dir"; mkdir -p "$dir"
    go() { # name ranks scenario [args]
      local name="$1" n="$2" scen="$3"; shift 3
      local s=$SECONDS
      mpirun -n "$n" --oversubscribe "$fdem" run "$scen" --quiet --output "$dir/$name" "$@" > "$dir/$name.log"
      echo "$name: $((SECONDS - s)) s; $(grep -E 'detection' "$dir/$name.log" | head -2 | tr -s ' ' | tr '\n' ';')"
    }
    for n in 1 2; do
      go deposit-$n "$n" scenarios/nut-packing-deposit.toml --set bodies.1.pack.count=50
      go drop8-$n "$n" scenarios/drop8.toml
      go collision-$n "$n" scenarios/collision.toml
    done
    go two-discs 2 scenarios/two-discs.toml
    go cube-stack 2 scenarios/cube-stack.toml
    go hot-block 2 scenarios/hot-block-on-floor.toml
    # The N = 50 deposition coupled with heat: container at 300, nuts at 0,
    # thermal contact detected every step from the mechanics' candidates.
    go coupled 2 scenarios/nut-packing-deposit.toml --set bodies.1.pack.count=50 \
      --set materials.0.conductivity=1.0 --set materials.0.specific_heat=1.0 \
      --set thermal.theta=1.0 --set contact.resistance=0.01 --set contact.every=1 \
      --set bodies.0.initial_temperature=300.0 --set bodies.1.initial_temperature=0.0
    go heatup 2 scenarios/nut-packing-heatup.toml --from "$dir/deposit-2"
    ;;
  compare)
    # The hot block expands with its temperatures: its motion follows them
    # to the solver's tolerance, which depends on the partition.
    python3 scripts/compare_outputs.py "${2:?reference}" "${3:?new}" --tolerant-case hot-block
    ;;
  *) echo "usage: compare-outputs.sh run DIR [FDEM] | compare REF NEW" >&2; exit 2 ;;
esac
