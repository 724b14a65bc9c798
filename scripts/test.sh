#!/usr/bin/env bash
# Set up if needed, then: cargo fmt --check, clippy -D warnings, and every
# test. The validation tests run the fdem binary on 1 rank and under
# `mpirun -n 2` (tests/two_rank.rs, tests/bad_input.rs), so the two-rank
# tests run here too; then a two-rank job runs directly, and ParaView opens
# the output (scripts/paraview-check.sh, which skips itself without pvbatch).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
bash scripts/setup.sh
# The `ci` profile (Cargo.toml): release code without LTO or debug info.
export FDEM_PROFILE=ci

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy -D warnings"
cargo clippy --profile ci --all-targets -- -D warnings
echo "== cargo test (unit, validation, 1 to 4 ranks and 8, oversubscribed)"
cargo test --profile ci --workspace
echo "== mpirun -n 2: two-rank run of the Gmsh block with PETSc options"
out="$(mktemp -d)"
mpirun -n 2 --oversubscribe target/ci/fdem run scenarios/gmsh-block.toml \
  --quiet --output "$out" -ksp_type cg -pc_type gamg -ksp_rtol 1e-12
h5dump -H "$out/gmsh-block.h5" "$out/gmsh-block_steps/000000.h5" >/dev/null
rm -rf "$out"
echo "== ParaView reads the output (scripts/paraview-check.sh)"
bash scripts/paraview-check.sh
echo "== SIGKILL of either rank, restart in place, bitwise (scripts/fault-check.sh)"
bash scripts/fault-check.sh
echo "== all tests passed"
