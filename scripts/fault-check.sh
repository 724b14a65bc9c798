#!/usr/bin/env bash
# Faults (issue 16): SIGKILL either rank of a 2-rank run at a random moment,
# 20 times on the N = 50 nut deposition and 20 times on the two bars; after
# each kill the output must be readable and a restart in place (`--output D
# --restart D/<stem>_checkpoint.h5`) continues the series; every finished
# chain must be bitwise the uninterrupted run (scripts/fault_check.py).
# Usage: scripts/fault-check.sh [--kills N] [--seed S] [deposit] [two-bars]
# Output: $FDEM_FAULT_OUT (default target/fault-check).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
target="${CARGO_TARGET_DIR:-target}"
profile="${FDEM_PROFILE:-release}"
fdem="$target/$profile/fdem"
if [ ! -x "$fdem" ]; then
  cargo build --profile "$profile" --bin fdem
fi
for tool in python3 h5dump mpirun pgrep; do
  command -v "$tool" >/dev/null || { echo "fault-check: $tool not found (bash scripts/setup.sh)" >&2; exit 1; }
done
out="${FDEM_FAULT_OUT:-$target/fault-check}"
python3 scripts/fault_check.py --fdem "$fdem" --out "$out" "$@"
