#!/usr/bin/env bash
# Issue 18 scaling measurements: peak memory per rank (VmHWM, the largest
# over ranks, from the run summary) of the N = 2000 heat-up and of the first
# 0.1 s of the N = 2000 deposition on 1, 2, 4 and 8 ranks (oversubscribed on
# small machines: only memory and answers count there), less the baseline
# of an almost empty run on the same rank count; writes docs/scaling-measured.md.
#   scripts/bench-scaling.sh [CHECKPOINT]   # a deposited N = 2000 checkpoint
# Without CHECKPOINT, the N = 2000 packing is deposited first (about 25 min
# on 2 ranks of a 2-core machine).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
BIN=${FDEM:-${CARGO_TARGET_DIR:-target}/release/fdem}
[ -x "$BIN" ] || cargo build --release --bin fdem
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
DOC=docs/scaling-measured.md
ck=${1:-}
if [ -z "$ck" ]; then
  mpirun -n 2 --oversubscribe "$BIN" run scenarios/nut-packing-deposit.toml --quiet --output "$OUT/dep" >&2
  ck="$OUT/dep/nut-packing-deposit_checkpoint.h5"
fi
# peak RANKS SCENARIO [args]: prints "peak_MiB wall_s sent_max sent_mean"
peak() {
  local n=$1; shift
  local t0 t1 log
  t0=$(date +%s.%N)
  log=$(mpirun -n "$n" --oversubscribe "$BIN" run "$@" --quiet --output "$OUT/run")
  t1=$(date +%s.%N)
  echo "$log" >&2
  local sent
  sent=$(echo "$log" | awk '/^  traffic/ {print $2, $12}')
  echo "$(echo "$log" | awk '/memory/ {print $3}') $(printf '%.1f' "$(echo "$t1 - $t0" | bc -l)") ${sent:-- -}"
}
declare -A base heat dep heat_t dep_t smax smean
for n in 1 2 4 8; do
  echo "== $n rank(s)" >&2
  read -r base[$n] _ _ _ < <(peak "$n" scenarios/thermal-stress-element.toml)
  read -r heat[$n] heat_t[$n] _ _ < <(peak "$n" scenarios/nut-packing-heatup.toml \
    --set "bodies.1.mesh.file=$ck")
  read -r dep[$n] dep_t[$n] smax[$n] smean[$n] < <(peak "$n" scenarios/nut-packing-deposit.toml \
    --set time.end_time=0.1 --set output.checkpoint=false)
done
ratio() { # value base one_rank one_base ranks -> (value-base) / ((one-one_base)/ranks)
  echo "$1 $2 $3 $4 $5" | awk '{ printf "%.2f", ($1 - $2) / (($3 - $4) / $5) }'
}
{
  echo "# Memory per rank against the number of ranks (measured)"
  echo
  echo "Written by \`scripts/bench-scaling.sh\` on $(date -u +%Y-%m-%d) at commit \`$(git rev-parse --short HEAD 2>/dev/null || echo unknown)\`,"
  echo "$(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB; ranks beyond the cores are oversubscribed."
  echo
  echo "Peak = VmHWM per rank, the largest over the ranks (run summary). Baseline = the same"
  echo "for \`scenarios/thermal-stress-element.toml\` (6 tets: MPI, PETSc, HDF5). Ratio ="
  echo "(peak − baseline) / ((1-rank peak − 1-rank baseline) / ranks): 1.0 is perfect 1/P;"
  echo "issue 18 asks at most 1.3 at 8 ranks."
  echo
  echo "| ranks | baseline MiB | N = 2000 heat-up MiB | ratio | wall s | N = 2000 deposition, first 0.1 s, MiB | ratio | wall s |"
  echo "|---|---|---|---|---|---|---|---|"
  for n in 1 2 4 8; do
    echo "| $n | ${base[$n]} | ${heat[$n]} | $(ratio "${heat[$n]}" "${base[$n]}" "${heat[1]}" "${base[1]}" "$n") | ${heat_t[$n]} | ${dep[$n]} | $(ratio "${dep[$n]}" "${base[$n]}" "${dep[1]}" "${base[1]}" "$n") | ${dep_t[$n]} |"
  done
  echo
  echo "OUT is a scratch directory, CK the deposited N = 2000 checkpoint."
  echo
  echo "## Bytes sent per substep (N = 2000 deposition, first 0.1 s)"
  echo
  echo "Bytes each rank sends to other ranks per explicit substep, averaged over the run's substeps"
  echo "(halo exchange of positions, velocities and forces; ghost refresh and pair balancing at the"
  echo "detections), from the run summary's \`traffic\` line: the largest over the ranks, and the mean."
  echo
  echo "| ranks | max B/substep/rank | mean B/substep/rank |"
  echo "|---|---|---|"
  for n in 2 4 8; do echo "| $n | ${smax[$n]} | ${smean[$n]} |"; done
  echo
  echo "## Commands"
  echo
  echo "- \`mpirun -n P --oversubscribe fdem run scenarios/thermal-stress-element.toml --quiet --output OUT\`"
  echo "- \`mpirun -n P --oversubscribe fdem run scenarios/nut-packing-heatup.toml --set bodies.1.mesh.file=CK --quiet --output OUT\`"
  echo "- \`mpirun -n P --oversubscribe fdem run scenarios/nut-packing-deposit.toml --set time.end_time=0.1 --set output.checkpoint=false --quiet --output OUT\`"
} > "$DOC"
echo "wrote $DOC" >&2
