#!/usr/bin/env bash
# Install the Debian packages fdem needs to build, run and test.
# Idempotent: installs only what is missing; safe to rerun.
set -euo pipefail

PKGS=(
  pkg-config
  build-essential
  libclang-dev        # bindgen (ffi/petsc-sys)
  clang
  petsc-dev           # PETSc 3.18 (real, double, 32-bit PetscInt)
  libopenmpi-dev
  openmpi-bin
  libmetis-dev
  libhdf5-openmpi-dev
  hdf5-tools          # h5dump, used by tests to check output files
  bc                  # arithmetic in scripts/bench.sh
  fonts-dejavu-core   # DejaVuSans.ttf: text in PNG plots (src/io/plot.rs)
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all system packages present"
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install a stable Rust toolchain (rustup) first" >&2
  exit 1
fi
for c in rustfmt clippy; do
  if ! rustup component list --installed 2>/dev/null | grep -q "^$c"; then
    rustup component add "$c" || true
  fi
done
