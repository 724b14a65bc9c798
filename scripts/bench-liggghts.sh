#!/usr/bin/env bash
# Deposition against DEM spheres (issue 22, item 3): LIGGGHTS 3.8 (Debian
# `liggghts`, installed by scripts/setup.sh --bench) runs
# scripts/peers/deposit_liggghts.in, 2000 spheres of the nut's mass and size
# at the real modulus settled by fdem's criterion (rms speed below 3 cm/s
# after 0.2 s), on 1 and 2 ranks; the ratio is fdem's N = 2000 deposition
# wall time on 2 ranks (FDEM_SECONDS, measured by scripts/bench.sh in the
# same run) over the faster LIGGGHTS run. Writes docs/peers-deposition.md.
# Usage: FDEM_SECONDS=752.7 scripts/bench-liggghts.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
command -v liggghts >/dev/null || { echo "bench-liggghts: liggghts missing (scripts/setup.sh --bench)" >&2; exit 1; }
: "${FDEM_SECONDS:?set FDEM_SECONDS to the N = 2000 fdem deposition wall time on 2 ranks}"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
IN=$(pwd)/scripts/peers/deposit_liggghts.in
rows=()
best=""
for ranks in 1 2; do
  cmd=(liggghts -in "$IN" -log "$OUT/log.$ranks")
  if [ "$ranks" -gt 1 ]; then cmd=(mpirun -n "$ranks" --oversubscribe "${cmd[@]}"); fi
  echo "== LIGGGHTS on $ranks rank(s): ${cmd[*]}" >&2
  t0=$(date +%s.%N)
  (cd "$OUT" && "${cmd[@]}") > "$OUT/out.$ranks"
  t1=$(date +%s.%N)
  wall=$(printf '%.1f' "$(echo "$t1 - $t0" | bc -l)")
  settled=$(sed -n 's/^settled at t = \([0-9.e+-]*\) s.*/\1/p' "$OUT/out.$ranks" | tail -1)
  [ -n "$settled" ] || { echo "bench-liggghts: no 'settled' line" >&2; tail "$OUT/out.$ranks" >&2; exit 1; }
  rows+=("| LIGGGHTS 3.8, 2000 spheres, E = 7.5 GPa | $ranks | $(printf '%.2f' "$settled") | $wall |")
  if [ -z "$best" ] || [ "$(echo "$wall < $best" | bc -l)" = 1 ]; then best=$wall; fi
done
ratio=$(printf '%.1f' "$(echo "$FDEM_SECONDS / $best" | bc -l)")
{
  echo "# Deposition against DEM spheres, measured"
  echo
  echo "Written by \`scripts/bench-liggghts.sh\` on $(date -u +%F), commit $(git rev-parse --short HEAD),"
  echo "$(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1), $(nproc) cores."
  echo
  echo "LIGGGHTS: \`scripts/peers/deposit_liggghts.in\` (the input's header says what it models),"
  echo "settled when the rms speed falls below 3 cm/s after 0.2 s, as fdem's"
  echo "\`scenarios/nut-packing-deposit.toml\`; fdem: that scenario, N = 2000 on 2 ranks,"
  echo "to settled, wall time as measured by \`scripts/bench.sh\` in the same run."
  echo
  echo "| run | ranks | settled at (s) | wall (s) |"
  echo "|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo "| fdem, 2000 nuts (144 Tet4 each), E = 1 MPa | 2 | see docs/benchmarks.md | $FDEM_SECONDS |"
  echo
  echo "Ratio, fdem over the faster LIGGGHTS run: **$ratio** (issue 22 asks at most 10)."
} > docs/peers-deposition.md
cat docs/peers-deposition.md
