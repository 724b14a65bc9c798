#!/usr/bin/env bash
# Set up if needed, build in release mode, and run the default scenario
# (scenarios/slab-1d.toml, seed 000 sec 4.2) on 2 MPI ranks.
# Usage: scripts/run.sh [SCENARIO] [fdem run options and PETSc options...]
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
bash scripts/setup.sh
cargo build --release --bin fdem
scenario="${1:-scenarios/slab-1d.toml}"
shift || true
stem="$(basename "$scenario" .toml)"
out="output/$stem"
mpirun -n 2 --oversubscribe target/release/fdem run "$scenario" --output "$out" "$@"
echo
echo "Output: $out/$stem.xdmf (open in ParaView), $out/$stem.h5 + $out/${stem}_steps/, $out/${stem}_history.csv"
