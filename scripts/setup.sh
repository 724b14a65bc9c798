#!/usr/bin/env bash
# Install the Debian packages fdem needs to build, run and test.
# Idempotent: installs only what is missing; safe to rerun.
#
# Opt-in: `FDEM_PARAVIEW=1 bash scripts/setup.sh` or `bash scripts/setup.sh
# --paraview` also installs ParaView (pvbatch), its Python module and Xvfb
# for scripts/paraview-check.sh. They are large (~1 GB), so the default
# setup leaves them out and the check skips itself. `--bench` adds the
# FEniCSx peer of scripts/bench-fenicsx.sh (python3-dolfinx, python3-h5py)
# and the LIGGGHTS peer of scripts/bench-liggghts.sh (liggghts).
set -euo pipefail

paraview="${FDEM_PARAVIEW:-0}"
for arg in "$@"; do
  case "$arg" in
    --paraview) paraview=1 ;;
    --bench) bench=1 ;;
    *) echo "setup: unknown argument $arg (known: --paraview, --bench)" >&2; exit 2 ;;
  esac
done

PKGS=(
  pkg-config
  build-essential
  libclang-dev        # bindgen (ffi/petsc-sys)
  clang
  petsc-dev           # PETSc 3.18 (real, double, 32-bit PetscInt)
  libopenmpi-dev
  openmpi-bin
  libmetis-dev
  libtrilinos-zoltan-dev  # Zoltan: recursive coordinate bisection (parallel/rcb.rs)
  libhdf5-openmpi-dev
  hdf5-tools          # h5dump, used by tests to check output files
  bc                  # arithmetic in scripts/bench.sh
  python3             # scripts/fault_check.py (standard library only)
  procps              # pgrep: scripts/fault_check.py finds the ranks to kill
  fonts-dejavu-core   # DejaVuSans.ttf: text in PNG plots (src/io/plot.rs)
)
if [ "${bench:-0}" = 1 ]; then
  # The peer of scripts/bench-fenicsx.sh (issue 22), and h5py to read
  # fdem's output there.
  PKGS+=(python3-dolfinx python3-h5py liggghts)
fi
# ParaView already here (another package brought it): the check of
# scripts/paraview-check.sh runs, so it gets what it renders with.
if command -v pvbatch >/dev/null 2>&1; then paraview=1; fi
if [ "$paraview" = 1 ]; then
  # pvbatch + paraview.simple, and a virtual X server to render under.
  PKGS+=(paraview python3-paraview xvfb xauth)
fi

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
