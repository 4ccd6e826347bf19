#!/usr/bin/env bash
# CI step: install Debian's Slurm and munge where they are missing, then run the real-Slurm
# test of `vanefit batch --slurm` (tests/slurm/run.sh starts and stops its own munged,
# slurmctld and slurmd; it needs root).
#
#   .ci/slurm.sh            install if missing, then test
#   .ci/slurm.sh install    only install (CI does this early, in the background)
#
# The binary tested is VANEFIT_BIN when set (CI passes the one `cargo test --release` built,
# which pytest uses too); otherwise target/release/vanefit, built here first. Building it in
# CI could compile vanefit and many of its dependencies again: a plain `cargo build`
# resolves the dependencies' features on its own, without CI's test build's dev-dependencies
# and Python crate (measured before Cargo.toml named the dev features: 19 crates, 3 CPU-min).
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
[ "${1:-}" = install ] && exit 0

if [ -z "${VANEFIT_BIN:-}" ]; then
  cargo build --release
fi
tests/slurm/run.sh
