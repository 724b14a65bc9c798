#!/usr/bin/env bash
# Issue 22 item 6: strong scaling 1 -> 2 ranks of the N = 2000 deposition and
# heat-up, as the ratio of per-step times (1 rank over 2 ranks) in three pairs
# run alternately (1 rank, then 2, three times over), and the median of the
# three; writes docs/strong-scaling-measured.md.
#   scripts/bench-strong-scaling.sh CHECKPOINT [COUNT]
# CHECKPOINT: a deposited (settled) checkpoint of scenarios/nut-packing-deposit.toml;
# COUNT: the nuts of the deposition window (2000, the paper's run).
# Three windows:
# - deposition: its first 0.1 s from the start (nuts falling, first impacts),
#   per substep of mechanics, set-up excluded;
# - settled bed: CHECKPOINT continued 2 steps (0.02 s) without the settle
#   test, where most of a deposition's time goes;
# - heat-up: scenarios/nut-packing-heatup.toml on CHECKPOINT, 80 steps, per
#   thermal step of the time loop.
set -euo pipefail
shopt -s inherit_errexit
cd "$(dirname "$0")/.."
source scripts/env.sh
BIN=${FDEM:-${CARGO_TARGET_DIR:-target}/release/fdem}
[ -x "$BIN" ] || cargo build --release --bin fdem
ck=${1:?usage: scripts/bench-strong-scaling.sh CHECKPOINT [COUNT]}
count=${2:-2000}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
DOC=docs/strong-scaling-measured.md

# The checkpoint's time (s) and substeps: the second and third of /state/scalars.
scalar() {
  h5dump -d /state/scalars -y -w 1 "$ck" | awk -v k="$1" '/^ *[-0-9.e+]+,?$/ { n++; gsub(/[ ,]/, ""); if (n == k) print }'
}
t_ck=$(scalar 2)
s_ck=$(scalar 3)
[ -n "$t_ck" ] && [ -n "$s_ck" ] || { echo "no time or substeps in $ck" >&2; exit 1; }
t_end=$(printf '%.6f' "$(echo "$t_ck + 0.02" | bc -l)")

# per_step KIND RANKS ARGS...: runs fdem and prints the per-step time:
# mechanics per substep (ms, set-up excluded; KIND bed: a restart, whose
# summary counts the checkpoint's substeps too) or thermal per step (us).
per_step() {
  local kind=$1 n=$2
  shift 2
  # A fresh directory: a restart would continue a series found there.
  rm -rf "$OUT/run"
  local cmd=("$BIN" run "$@" --quiet --output "$OUT/run")
  [ "$n" -gt 1 ] && cmd=(mpirun -n "$n" --oversubscribe "${cmd[@]}")
  echo "== $kind on $n rank(s): ${cmd[*]}" >&2
  local log
  log=$("${cmd[@]}")
  echo "$log" >&2
  if [ "$kind" = heat ]; then
    echo "$log" | awk '/^  per step/ {print $3}'
  else
    local line mt setup subs
    line=$(echo "$log" | grep '^  mechanics')
    subs=$(echo "$line" | awk '{print $5}')
    [ "$kind" = bed ] && subs=$((subs - ${s_ck%.*}))
    mt=$(echo "$line" | sed -n 's/.*per step), \([0-9.]*\) s (.*/\1/p')
    setup=$(echo "$line" | sed -n 's/.*s (\([0-9.]*\) s set-up.*/\1/p')
    printf '%.3f\n' "$(echo "($mt - $setup) / $subs * 1000" | bc -l)"
  fi
}

# window LABEL KIND UNIT ARGS...: three alternated pairs, one table row each,
# then the median ratio.
section=()
window() {
  local label=$1 kind=$2 unit=$3
  shift 3
  local ratios=() p one two r
  section+=("" "### $label" "" "\`fdem run $*\` (OUT for the output directory)" ""
    "| pair | 1 rank ($unit per step) | 2 ranks ($unit per step) | 1 rank / 2 ranks |" "|---|---|---|---|")
  for p in 1 2 3; do
    one=$(per_step "$kind" 1 "$@")
    two=$(per_step "$kind" 2 "$@")
    r=$(printf '%.2f' "$(echo "$one / $two" | bc -l)")
    ratios+=("$r")
    section+=("| $p | $one | $two | $r |")
  done
  local median
  median=$(printf '%s\n' "${ratios[@]}" | sort -n | sed -n 2p)
  section+=("" "Median strong scaling: **$median** (issue 22 asks at least 1.8).")
  medians+=("$label: $median")
}
medians=()

dep=(scenarios/nut-packing-deposit.toml --set "bodies.1.pack.count=$count"
  --set time.end_time=0.1 --set output.checkpoint=false)
window "N = $count deposition, first 0.1 s" mech ms "${dep[@]}"
bed=(scenarios/nut-packing-deposit.toml --restart "$ck" --set "bodies.1.pack.count=$count" --set "time.end_time=$t_end"
  --set mechanics.settle=none --set output.checkpoint=false)
window "settled bed, 2 more steps" bed ms "${bed[@]}"
heat=(scenarios/nut-packing-heatup.toml --set "bodies.1.mesh.file=$ck")
window "heat-up of the deposited packing, 80 steps" heat us "${heat[@]}"

{
  echo "<!-- Written by scripts/bench-strong-scaling.sh; do not edit. -->"
  echo "Strong scaling 1 -> 2 ranks (issue 22 item 6), measured $(date -u +%Y-%m-%d) at commit"
  echo "\`$(git rev-parse --short HEAD 2>/dev/null || echo unknown)\` on $(nproc) cores"
  echo "($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')): per-step"
  echo "times, three pairs run alternately (1 rank, then 2), and the median of"
  echo "their ratios. The mechanics is bitwise the same on 1 and 2 ranks, so both"
  echo "runs of a pair do the same substeps."
  printf '%s\n' "${section[@]}"
} | sed "s|$OUT/run|OUT|g; s|$ck|CHECKPOINT|g" > "$DOC"
printf 'strong scaling medians: %s\n' "${medians[@]}" >&2
