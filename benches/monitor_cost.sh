#!/usr/bin/env bash
# The live monitor's cost to a run (issue 29, item 8; docs/monitor.md, "Cost"):
# the same scenario run in alternating rounds with --no-monitor, with the
# monitor on and nobody watching (the default), and with a reader attached
# (`quadsim monitor` printing every instant to /dev/null); per variant the
# median CPU time (user + sys) and wall time of the run's process. An
# optional second binary (BEFORE) is measured in the same rounds, with the
# monitor on and off.
#
#   benches/monitor_cost.sh ROUNDS SCENARIO DURATION_S [BEFORE_BIN]
#   benches/monitor_cost.sh 5 scenarios/herd.toml 2 /tmp/quadsim-main
#
# Runs use --no-log --no-report --threads 1 --quiet (the issue's setting).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=$1 SCN=$2 DUR=$3 BEFORE=${4:-}
BIN=target/release/quadsim
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
run() { # name bin extra...
  local name=$1 bin=$2; shift 2
  /usr/bin/time -f "%U %S %e" -o "$OUT/t" "$bin" run "$SCN" --duration "$DUR" --no-log \
    --no-report --threads 1 --quiet --out "$OUT/run" "$@" >/dev/null 2>"$OUT/err" || {
    cat "$OUT/err" >&2; exit 1; }
  read -r u s e < "$OUT/t"
  echo "$name $(echo "$u + $s" | bc) $e" >> "$OUT/results"
}
watched() { # name bin
  local name=$1 bin=$2 world="cost-$$-$RANDOM"
  "$bin" monitor --world "$world" --frames 1000000000 --timeout 60 >/dev/null 2>&1 &
  local reader=$!
  run "$name" "$bin" --world-name "$world"
  kill "$reader" 2>/dev/null || true
  wait "$reader" 2>/dev/null || true
}
for i in $(seq "$ROUNDS"); do
  run off "$BIN" --no-monitor
  run on-unwatched "$BIN"
  watched on-watched "$BIN"
  if [ -n "$BEFORE" ]; then
    run before-off "$BEFORE" --no-monitor
    run before-on "$BEFORE"
  fi
done
echo "variant rounds median_cpu_s median_wall_s"
for v in off on-unwatched on-watched before-off before-on; do
  grep "^$v " "$OUT/results" >/dev/null || continue
  cpu=$(grep "^$v " "$OUT/results" | awk '{print $2}' | sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}')
  wall=$(grep "^$v " "$OUT/results" | awk '{print $3}' | sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}')
  echo "$v $(grep -c "^$v " "$OUT/results") $cpu $wall"
done
