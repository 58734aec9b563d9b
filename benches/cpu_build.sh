#!/usr/bin/env bash
# Builds quadsim for this machine's CPU (the documented build setting of
# docs/performance.md: RUSTFLAGS="-C target-cpu=native", in its own target
# directory, target/native) and checks that it gives the portable build's
# bits: the trot and the herd scenarios run by both binaries must write the
# same log.mcap bytes and the same summary.json, its wall-clock `timing`
# block aside. Prints the native binary's path on success.
#
#   benches/cpu_build.sh [seconds]    # simulated seconds per scenario (default 2)
#
# CI runs it (.ci/run) with CPU_BUILD_RUSTFLAGS="-D warnings", which is
# added to the native build's flags. The portable binary is built first if
# needed (cargo build --release).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-2}"
cargo build --release --quiet --bin quadsim
RUSTFLAGS="-C target-cpu=native ${CPU_BUILD_RUSTFLAGS:-}" cargo build --release --quiet --bin quadsim --target-dir target/native
portable=target/release/quadsim
native=target/native/release/quadsim
out=target/cpu-build-bits
rm -rf "$out"
for scenario in trot herd; do
  for build in portable native; do
    "${!build}" run "scenarios/$scenario.toml" --duration "$seconds" --threads 2 \
      --out "$out/$build/$scenario" --quiet --no-report --no-monitor > /dev/null
  done
  cmp "$out/portable/$scenario/log.mcap" "$out/native/$scenario/log.mcap"
  python3 - "$out/portable/$scenario/summary.json" "$out/native/$scenario/summary.json" <<'PY'
import json, sys
def without_timing(path):
    d = json.load(open(path))
    d.pop("timing", None)
    # shortest round-trip reprs: equal text is equal bits (-0.0 and NaN too)
    return json.dumps(d, sort_keys=True)
if without_timing(sys.argv[1]) != without_timing(sys.argv[2]):
    sys.exit(f"summary.json differs between the portable and the native build: {sys.argv[1:]}")
PY
  echo "$scenario: the native build gives the portable build's bits (log.mcap, summary.json)" >&2
done
echo "$native"
