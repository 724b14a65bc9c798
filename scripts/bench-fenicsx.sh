#!/usr/bin/env bash
# fdem against FEniCSx on the seed's slab (issue 22, item 2): the same
# problem, mesh (hexahedra of size h split in 6 Tet4), lumped capacity and
# backward Euler (dt = 5e-4 s), on 1 and 2 ranks, h = 0.1 down to 0.0125.
# FEniCSx runs every solver of scripts/peers/slab_fenicsx.py and its best
# counts; fdem runs its default. Both report the time loop per step and
# the largest nodal error at the end against the analytic series, so the
# ratio is taken at equal error. Writes docs/peers-measured.md.
# Usage: scripts/bench-fenicsx.sh   (FDEM=path overrides the binary)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
BIN=${FDEM:-target/release/fdem}
[ -x "$BIN" ] || cargo build --release --bin fdem
PY=/usr/bin/python3
"$PY" -c "import dolfinx" 2>/dev/null || {
  echo "bench-fenicsx: python3-dolfinx is missing (scripts/setup.sh --bench installs it)" >&2
  exit 1
}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
DOC=docs/peers-measured.md
rows=()
for h in 0.1 0.05 0.025 0.0125; do
  # Enough steps for a second or more of stepping at every size.
  case $h in 0.1 | 0.05) steps=20000 ;; *) steps=2000 ;; esac
  end=$(echo "$steps * 0.0005" | bc -l)
  for ranks in 1 2; do
    run=("$BIN" run scenarios/slab-1d.toml --quiet --output "$OUT/f"
      --set bodies.bar.mesh.element_size=$h --set time.end_time=$end --set "output.times=[$end]")
    peer=("$PY" scripts/peers/slab_fenicsx.py --h $h --steps $steps --fdem "$OUT/f/slab-1d_steps/000001.h5")
    if [ "$ranks" -gt 1 ]; then
      run=(mpirun -n 2 --oversubscribe "${run[@]}")
      peer=(mpirun -n 2 --oversubscribe "${peer[@]}")
    fi
    echo "== h=$h ranks=$ranks" >&2
    flog=$("${run[@]}")
    fper=$(echo "$flog" | awk '/^  per step/ {print $3}')
    fsolver=$(echo "$flog" | awk '/^  solver/ {print $2}')
    fits=$(echo "$flog" | awk '/^  steps/ {gsub(/\(/,"",$3); print $3 / $2}')
    plog=$("${peer[@]}" 2>/dev/null | grep -E '^(fenicsx|fdem) ')
    echo "$plog" >&2
    best=$(echo "$plog" | awk '/^fenicsx/ {for(i=1;i<=NF;i++){split($i,a,"="); v[a[1]]=a[2]} if(b==""||v["per_step_us"]<b){b=v["per_step_us"]; s=v["solver"]; e=v["max_error"]; t=v["tets"]}} END{print b, s, e, t}')
    read -r bper bsolver berr tets <<<"$best"
    ferr=$(echo "$plog" | awk '/^fdem/ {split($3,a,"="); print a[2]}')
    all=$(echo "$plog" | awk '/^fenicsx/ {for(i=1;i<=NF;i++){split($i,a,"="); v[a[1]]=a[2]} printf "%s%s %s", sep, v["solver"], v["per_step_us"]; sep="; "}')
    ratio=$(printf '%.2f' "$(echo "$fper / $bper" | bc -l)")
    rows+=("| $h | $tets | $ranks | $fsolver | $(printf '%.2f' "$fits") | $fper | $ferr | $bsolver | $bper | $berr | **$ratio** | $all |")
  done
done
{
  echo "# fdem against FEniCSx on the seed's slab (measured)"
  echo
  echo "Written by \`scripts/bench-fenicsx.sh\` on $(date -u +%Y-%m-%d) at commit \`$(git rev-parse --short HEAD)\`,"
  echo "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores; FEniCSx $("$PY" -c 'import dolfinx; print(dolfinx.__version__)') (Debian python3-dolfinx), PETSc 3.18 under both."
  echo
  echo "Slab 1 m × 0.1 m × 0.1 m (seed 000 sec 4.2), hexahedra of size h split in 6 Tet4, lumped"
  echo "capacity, backward Euler, dt = 5e-4 s, KSP rtol 1e-10 for both. Per step = the time loop"
  echo "divided by the steps (largest over ranks), no set-up or output. Error = the largest nodal"
  echo "|T − T_exact| at the end against the analytic series (computed in the peer script for both)."
  echo "FEniCSx assembles its step matrix once and forms each right-hand side by one matrix-vector"
  echo "product and a constant lifting; its best of CG + Jacobi, CG + GAMG, CG + hypre and Cholesky"
  echo "(MUMPS on 2 ranks) counts. Ratio = fdem's default ÷ FEniCSx's best (issue 22 asks ≤ 0.8)."
  echo
  echo "| h (m) | tets | ranks | fdem default | KSP its/step | fdem per step (us) | fdem error | FEniCSx best | per step (us) | FEniCSx error | ratio | FEniCSx solvers (us/step) |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "Commands: \`[mpirun -n 2 --oversubscribe] fdem run scenarios/slab-1d.toml --set bodies.bar.mesh.element_size=H --set time.end_time=E --set output.times=[E]\`,"
  echo "\`[mpirun -n 2 --oversubscribe] /usr/bin/python3 scripts/peers/slab_fenicsx.py --h H --steps S --fdem <fdem's last step file>\`."
} >"$DOC"
echo "wrote $DOC" >&2
