#!/usr/bin/env bash
# servo_pioneer_extra.sh: docs/accuracy.md's figures on servo_pioneer_pan that its table
# (examples/servo_table_pioneer.sh) does not print.
#   1. Estimated depth, front and side, at each pixel noise in SIGMAS, seeds 1..SEEDS (the table's
#      runs): the first and last iteration at which the provider's estimate of a corner was used
#      (converged_at, over every corner and run) and the convergence revocations summed over the runs.
#   2. The 6-DoF entry point (--pose-api, estimated depth), front and side, 0.1 and 0.6 px, seeds
#      1..3: the iterations' range over these runs, beside the same runs with the planar sample.
# Usage: benchmarks/servo_pioneer_extra.sh [path/to/servo_pioneer_pan] [SEEDS] ["SIGMAS"]
set -euo pipefail
bin=${1:-build/examples/servo_pioneer_pan}
seeds=${2:-10}
sigmas=${3:-"0.1 0.3 0.6"}
[ -x "$bin" ] || { echo "servo_pioneer_extra.sh: $bin not found (build the servo_pioneer_pan target)" >&2; exit 1; }
[[ $seeds =~ ^[1-9][0-9]*$ ]] || { echo "servo_pioneer_extra.sh: SEEDS must be a positive integer" >&2; exit 1; }

# The last two lines of a run: "path_length=... converged_at=I0,I1,I2,I3 revocations=R" and
# "converged iterations=N ..." (or "diverged ...").
runs=0 first=-1 last=-1 revoked=0 unused=0 diverged=0
for scenario in front side; do
  for sigma in $sigmas; do
    for s in $(seq 1 "$seeds"); do
      out=$("$bin" --scenario "$scenario" --seed "$s" --sigma-px "$sigma" --depth estimated --quiet | tail -2) || true
      runs=$((runs + 1))
      case $(tail -1 <<<"$out") in converged*) ;; *) diverged=$((diverged + 1)) ;; esac
      at=$(head -1 <<<"$out" | sed -n 's/.*converged_at=\([-0-9,]*\).*/\1/p')
      r=$(head -1 <<<"$out" | sed -n 's/.*revocations=\([0-9]*\).*/\1/p')
      revoked=$((revoked + r))
      for i in ${at//,/ }; do
        if [ "$i" -lt 0 ]; then unused=$((unused + 1)); continue; fi
        if [ "$first" -lt 0 ] || [ "$i" -lt "$first" ]; then first=$i; fi
        if [ "$i" -gt "$last" ]; then last=$i; fi
      done
    done
  done
done
echo "estimated depth, $runs runs (front, side; $sigmas px; seeds 1-$seeds): estimates used from iteration $first to $last on" \
  "($unused corners never), revocations $revoked, diverged $diverged"

range() { # args... -> "min .. max over N runs"
  local lo=-1 hi=-1 n=0 it
  for scenario in front side; do
    for sigma in 0.1 0.6; do
      for s in 1 2 3; do
        it=$("$bin" --scenario "$scenario" --seed "$s" --sigma-px "$sigma" --depth estimated --quiet "$@" | tail -1 |
          sed -n 's/^converged iterations=\([0-9]*\).*/\1/p') || true
        n=$((n + 1))
        [ -n "$it" ] || { echo "diverged in run $n"; continue; }
        if [ "$lo" -lt 0 ] || [ "$it" -lt "$lo" ]; then lo=$it; fi
        if [ "$it" -gt "$hi" ]; then hi=$it; fi
      done
    done
  done
  echo "$lo .. $hi iterations over $n runs"
}
echo "--pose-api (front, side; 0.1, 0.6 px; seeds 1-3): $(range --pose-api)"
echo "planar sample, the same runs:                     $(range)"
