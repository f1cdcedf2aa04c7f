#!/usr/bin/env bash
# The evidence table of the Pioneer servo: servo_pioneer_pan (ViSP's vpSimulatorPioneerPan driven by
# vpServo on four points, DepthProvider with its default options) in the front and side scenarios,
# at each pixel noise in SIGMAS, over SEEDS noise seeds. Per scenario, noise and depth mode: the mean
# iterations, their mean ratio to true depth (paired: the same scenario and noise seed), the worst
# ratio, diverged runs, and the depth used at the end against the truth: mean |error| and the mean
# signed error with its standard error (the bias).
# Usage: examples/servo_table_pioneer.sh [path/to/servo_pioneer_pan] [SEEDS] ["SIGMAS"]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/servo_table_common.sh"
bin=${1:-build/examples/servo_pioneer_pan}
seeds=${2:-10}
sigmas=${3:-"0.1 0.3 0.6"}
[ -x "$bin" ] || { echo "servo_table_pioneer.sh: $bin not found (build the servo_pioneer_pan target)" >&2; exit 1; }
[[ $seeds =~ ^[1-9][0-9]*$ ]] || { echo "servo_table_pioneer.sh: SEEDS must be a positive integer" >&2; exit 1; }
modes=("true:--depth true" "estimated:--depth estimated" "constant 0.6 m:--depth constant")
echo "| scenario | pixel noise | depth | iterations (mean) | / true (mean) | / true (worst) | diverged | end depth error (mean abs) | end depth bias (mean +- s.e.) |"
echo "|---|---|---|---|---|---|---|---|---|"
for scenario in front side; do
  for sigma in $sigmas; do
    mode_runs "iterations depth_error depth_bias" --scenario "$scenario" --sigma-px "$sigma" |
      awk -F'|' -v sc="$scenario" -v sg="$sigma" '
      { lab = $1; s = $2; it[lab, s] = $3; er[lab, s] = $4; bi[lab, s] = $5; dv[lab] += $6
        if (!(lab in seen)) { seen[lab] = 1; order[++nl] = lab } if (s > ns) ns = s }
      END {
        for (l = 1; l <= nl; l++) { lab = order[l]; si = ri = wr = se = sb = sbb = 0
          for (s = 1; s <= ns; s++) { si += it[lab, s]; r = it[lab, s] / it["true", s]; ri += r; if (r > wr) wr = r
            se += er[lab, s]; sb += bi[lab, s]; sbb += bi[lab, s] * bi[lab, s] }
          mb = sb / ns; sd = ns > 1 ? sqrt((sbb - ns * mb * mb) / (ns - 1)) : 0
          printf "| %s | %s px | %s | %.1f | %.3f | %.3f | %d | %.2f %% | %+.2f +- %.2f %% |\n", sc, sg, lab, si / ns, ri / ns, wr,
                 dv[lab], 100 * se / ns, 100 * mb, 100 * sd / sqrt(ns) } }'
  done
done
