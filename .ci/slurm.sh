#!/usr/bin/env bash
# CI step for the Slurm support: install Debian's Slurm and munge where they are missing,
# then run the real-Slurm test of `vanefit batch --slurm` (tests/slurm/run.sh starts and
# stops its own munged, slurmctld and slurmd; it needs root). Expects a release build
# (target/release).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v slurmctld >/dev/null 2>&1 || ! command -v munged >/dev/null 2>&1; then
  if [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "error: Slurm/munge missing and cannot be installed here (needs root and apt-get)" >&2
    exit 1
  fi
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends slurm-wlm munge
fi
cargo build --release
tests/slurm/run.sh
