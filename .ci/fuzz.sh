#!/usr/bin/env bash
# A short coverage-guided fuzz run per target: every target of fuzz/ for FUZZ_SECONDS
# (default 10) from its committed corpus (fuzz/corpus/<target>), failing on a crash, a panic
# or a hang. The corpus itself is replayed by `cargo test` too (tests/hardening/fuzz_corpus.rs); this
# adds mutations. The long campaigns (10 million executions per target) are run by hand with
# cargo-fuzz, see docs/validation.md, "Hardening".
#
#   .ci/fuzz.sh          build, then run every target
#   .ci/fuzz.sh build    only build (CI starts this early, in the background)
#   .ci/fuzz.sh run      only run (expects the build)
#
# The build is the one `cargo fuzz build --dev --sanitizer none` (cargo-fuzz 0.13) makes,
# done by cargo directly: the same rustc flags, the same --target (so that build scripts and
# proc-macros are not instrumented), the same folder (fuzz/target/<host>/debug). CI thereby
# needs no `cargo install cargo-fuzz`, a compile of its own of about a minute on a clean
# machine. Unoptimised and without debug information: the cheapest real libFuzzer build (an
# optimised one takes about 6 min on the 2-core machine; the unoptimised targets run at 250
# to 25 000 executions per second, enough for a smoke run).
#
# Targets run FUZZ_JOBS at a time (default: the number of cores), each on its own core for
# its FUZZ_SECONDS, as when they ran one after the other on an otherwise idle machine.
# A crash's input is printed in base64, to be added to fuzz/corpus/<target>/ (which
# tests/hardening/fuzz_corpus.rs then replays) once it is fixed.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
what=${1:-all}

host=$(rustc -vV | sed -n 's/^host: //p')
bin="target/$host/debug"
# The targets: the [[bin]] names of fuzz/Cargo.toml (what `cargo fuzz list` prints).
targets=$(sed -n '/^\[\[bin\]\]/{n;s/^name = "\(.*\)"$/\1/p}' Cargo.toml)
[ -n "$targets" ] || { echo "fuzz: no targets found in fuzz/Cargo.toml" >&2; exit 1; }

if [ "$what" = all ] || [ "$what" = build ]; then
  flags="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4"
  flags+=" -Cllvm-args=-sanitizer-coverage-inline-8bit-counters"
  flags+=" -Cllvm-args=-sanitizer-coverage-pc-table"
  flags+=" -Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing"
  flags+=" -Cllvm-args=-simplifycfg-branch-fold-threshold=0"
  flags+=" -Cllvm-args=-sanitizer-coverage-stack-depth -Cdebug-assertions"
  RUSTFLAGS="$flags" CARGO_PROFILE_DEV_DEBUG=0 CARGO_INCREMENTAL=0 \
    cargo build --manifest-path Cargo.toml --target "$host" --bins
fi
[ "$what" = all ] || [ "$what" = run ] || exit 0

seconds=${FUZZ_SECONDS:-10}
jobs=${FUZZ_JOBS:-$(nproc)}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fuzz_one() { # fuzz_one TARGET: exit status 0 if no crash, panic or hang
  local t=$1
  mkdir -p "$work/$t/new" "$work/$t/crash"
  # New inputs go to a scratch folder: the committed corpus is only read.
  "$bin/$t" "$work/$t/new" "corpus/$t" -max_total_time="$seconds" -timeout=10 \
    -artifact_prefix="$work/$t/crash/" >"$work/$t/log" 2>&1
}
report() { # report TARGET STATUS
  local t=$1
  if [ "$2" -eq 0 ]; then
    echo "fuzz $t: $(grep -E '^#[0-9]+' "$work/$t/log" | tail -1)"
  else
    echo "fuzz $t: FAILED"
    tail -n 40 "$work/$t/log"
    for a in "$work/$t/crash"/*; do
      [ -e "$a" ] || continue
      echo "input $(basename "$a") (base64):"
      base64 "$a"
    done
  fi
}
failed=0
set -- $targets
while [ $# -gt 0 ]; do
  batch=()
  pids=()
  while [ $# -gt 0 ] && [ ${#batch[@]} -lt "$jobs" ]; do
    fuzz_one "$1" &
    pids+=($!)
    batch+=("$1")
    shift
  done
  for i in "${!batch[@]}"; do
    rc=0
    wait "${pids[$i]}" || rc=$?
    report "${batch[$i]}" "$rc"
    [ "$rc" -eq 0 ] || failed=1
  done
done
exit "$failed"
