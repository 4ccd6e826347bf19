#!/usr/bin/env bash
# A short coverage-guided fuzz run per target: every target of fuzz/ for
# FUZZ_SECONDS (default 10) from its committed corpus (fuzz/corpus/<target>), failing on a
# crash, a panic or a hang. The corpus itself is replayed by `cargo test` too
# (tests/hardening/fuzz_corpus.rs); this adds mutations. The long campaigns (10 million executions
# per target) are run by hand, see docs/validation.md, "Hardening".
#
# The cheapest real cargo-fuzz build: unoptimised and without debug information. Measured
# on the 2-core machine with a fuzzer and other builds beside it: cold build 2 min 31 s,
# the whole step 3 min 38 s (an optimised build takes about 6 min; the unoptimised targets
# run at 250 to 25 000 executions per second, enough for a smoke run). A crash's input is
# printed in base64, to be added to fuzz/corpus/<target>/ (which tests/hardening/fuzz_corpus.rs then
# replays) once it is fixed.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"

if ! cargo fuzz --version >/dev/null 2>&1; then
  cargo install cargo-fuzz --locked
fi
# cargo-fuzz passes nightly flags (-Z); the stable toolchain accepts them so.
export RUSTC_BOOTSTRAP=1
export CARGO_PROFILE_DEV_DEBUG=0
cargo fuzz build --dev --sanitizer none

host=$(rustc -vV | sed -n 's/^host: //p')
bin="target/$host/debug"
seconds=${FUZZ_SECONDS:-10}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
for t in $(cargo fuzz list); do
  mkdir -p "$work/$t/new" "$work/$t/crash"
  # New inputs go to a scratch folder: the committed corpus is only read.
  if "$bin/$t" "$work/$t/new" "corpus/$t" -max_total_time="$seconds" -timeout=10 \
    -artifact_prefix="$work/$t/crash/" >"$work/$t/log" 2>&1; then
    echo "fuzz $t: $(grep -E '^#[0-9]+' "$work/$t/log" | tail -1)"
  else
    failed=1
    echo "fuzz $t: FAILED"
    tail -n 40 "$work/$t/log"
    for a in "$work/$t/crash"/*; do
      [ -e "$a" ] || continue
      echo "input $(basename "$a") (base64):"
      base64 "$a"
    done
  fi
done
exit "$failed"
