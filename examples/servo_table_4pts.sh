#!/usr/bin/env bash
# The evidence table of the 6-DoF servo: servo_ibvs_4pts (ViSP's tutorial-ibvs-4pts on
# vpSimulatorCamera, DepthProvider with its default options) from POSES starting poses (0 is the
# tutorial's, then random ones), each over SEEDS pixel-noise seeds, at SIGMA px. Per starting pose:
# the true depth's mean iterations and path length, then each other depth mode's ratios to it
# (paired: the same pose and noise seed), the worst final error and the number of diverged runs.
# Usage: examples/servo_table_4pts.sh [path/to/servo_ibvs_4pts] [POSES] [SEEDS] [SIGMA]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/servo_table_common.sh"
bin=${1:-build/examples/servo_ibvs_4pts}
poses=${2:-8}
seeds=${3:-5}
sigma=${4:-0.3}
[ -x "$bin" ] || { echo "servo_table_4pts.sh: $bin not found (build the servo_ibvs_4pts target)" >&2; exit 1; }
modes=("true:--depth true" "estimated:--depth estimated" "constant (desired 0.75 m):--depth constant")
echo "| start pose | depth | iterations (mean) | / true | path (m, mean) | / true | worst / true path | worst final error (px) | diverged |"
echo "|---|---|---|---|---|---|---|---|---|"
for pose in $(seq 0 $((poses - 1))); do
  declare -A it=() path=()
  mode_runs "iterations path_length final_error" --pose "$pose" --sigma-px "$sigma" | awk -F'|' -v pose="$pose" '
    { lab = $1; s = $2; it[lab, s] = $3; pa[lab, s] = $4; er[lab, s] = $5; dv[lab] += $6
      if (!(lab in seen)) { seen[lab] = 1; order[++nl] = lab } if (s > ns) ns = s }
    END {
      for (l = 1; l <= nl; l++) { lab = order[l]; si = sp = ri = rp = 0; wr = 0; we = 0
        for (s = 1; s <= ns; s++) { si += it[lab, s]; sp += pa[lab, s]
          ri += it[lab, s] / it["true", s]; r = pa[lab, s] / pa["true", s]; rp += r
          if (r > wr) wr = r; if (er[lab, s] > we) we = er[lab, s] }
        printf "| %s | %s | %.1f | %.3f | %.4f | %.3f | %.3f | %.3f | %d |\n", (pose == 0 ? "0 (tutorial)" : pose), lab,
               si / ns, ri / ns, sp / ns, rp / ns, wr, we, dv[lab] } }'
done
