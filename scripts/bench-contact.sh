#!/usr/bin/env bash
# Contact detection against the number of bodies (issue 22, item 5):
# scenarios/bench-contact-lattice.toml, cubes of 48 Tet4 on a regular
# lattice, each overlapping its neighbours by 2 mm, n^3 bodies for
# n = 2 .. 32 (8 to 32,768 bodies), on 1 and 2 ranks. Reports the
# candidate tet pairs of the broad phase, the contact pairs found, the
# detection time (search, separating axes, face clipping both ways: the
# run summary's contact time, max over ranks), both rates per core, and
# the exponent of a least-squares fit time ~ bodies^p over n >= 8.
# Writes docs/contact-measured.md.
# Usage: scripts/bench-contact.sh [MAX_N]   (FDEM=path overrides the binary)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
BIN=${FDEM:-target/release/fdem}
[ -x "$BIN" ] || cargo build --release --bin fdem
MAX_N=${1:-32}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
DOC=docs/contact-measured.md
rows=()
fit=()
for n in 2 4 8 16 32; do
  [ "$n" -le "$MAX_N" ] || continue
  for ranks in 1 2; do
    cmd=("$BIN" run scenarios/bench-contact-lattice.toml --quiet --output "$OUT/lat"
      --set "bodies.cube.lattice.count=[$n,$n,$n]" --set output.every=0)
    if [ "$ranks" -gt 1 ]; then cmd=(mpirun -n "$ranks" --oversubscribe "${cmd[@]}"); fi
    echo "== lattice $n^3 on $ranks rank(s): ${cmd[*]}" >&2
    log=$("${cmd[@]}")
    echo "$log" >&2
    ct=$(echo "$log" | sed -n 's/.*contact \([0-9.]*\) |.*/\1/p')
    st=$(echo "$log" | awk '/^  search/ {print $5}')
    cand=$(echo "$log" | awk '/^  search/ {print $7}')
    pairs=$(echo "$log" | awk '/^  contact / {print $2}')
    tets=$(echo "$log" | awk '/^  mesh/ {print $4}')
    mem=$(echo "$log" | awk '/^  memory/ {print $3}')
    bodies=$((n * n * n))
    # Per core: the time is the slowest rank's, the work is split over the ranks.
    cps=$(echo "$cand / $ct / $ranks" | bc -l)
    pps=$(echo "$pairs / $ct / $ranks" | bc -l)
    rows+=("| $bodies | $ranks | $tets | $cand | $pairs | $st | $ct | $(printf '%.2f' "$(echo "$cps / 1000000" | bc -l)") | $(printf '%.0f' "$pps") | $mem |")
    if [ "$n" -ge 8 ]; then fit+=("$ranks $bodies $ct"); fi
  done
done
# Least squares of log(time) on log(bodies), per rank count.
exponent() {
  printf '%s\n' "${fit[@]}" | awk -v r="$1" '$1 == r { x = log($2); y = log($3); n++; sx += x; sy += y; sxx += x * x; sxy += x * y }
    END { if (n > 1) printf "%.3f", (n * sxy - sx * sy) / (n * sxx - sx * sx); else printf "n/a" }'
}
{
  echo "# Contact detection, measured"
  echo
  echo "Written by \`scripts/bench-contact.sh\` on $(date -u +%Y-%m-%d), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown),"
  echo "$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores."
  echo
  echo "\`scenarios/bench-contact-lattice.toml\`: cubes of 48 Tet4 (0.1 m, h = 0.05 m) on a"
  echo "regular lattice spaced 0.098 m, so every cube overlaps its 26 neighbours by 2 mm;"
  echo "one thermal step, no output. Candidates: the tet pairs the broad phase (one BVH"
  echo "over the rank's tets and the ghosts of its neighbours) gives the narrow phase;"
  echo "contact pairs: those whose volumes overlap (separating axes) with a positive"
  echo "contact surface (each boundary face clipped by the other tet). Detection: the"
  echo "contact time of the run summary (search, narrow phase, surfaces), max over"
  echo "ranks; per core = count / time / ranks."
  echo
  echo "| bodies | ranks | tets | candidate pairs | contact pairs | search (s) | detection (s) | M candidates/s/core | contact pairs/s/core | peak MiB/rank |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  for r in "${rows[@]}"; do echo "$r"; done
  echo
  echo "Fitted exponent p of detection time ~ bodies^p (n >= 8): $(exponent 1) on 1 rank,"
  echo "$(exponent 2) on 2 ranks (1 is linear; n log n over this range fits about 1.1)."
} > "$DOC"
echo "wrote $DOC" >&2
