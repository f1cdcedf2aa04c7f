#!/usr/bin/env bash
# The evidence table of the servo integration: iterations to converge and final error of
# servo_ibvs_yawing_camera for true, constant (50 % and 200 % too far, 50 % too near) and
# estimated depth, front and side view, each over SEEDS noise seeds (default 5).
# Usage: examples/servo_table.sh [path/to/servo_ibvs_yawing_camera] [SEEDS]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/servo_table_common.sh"
bin=${1:-build/examples/servo_ibvs_yawing_camera}
seeds=${2:-5}
[ -x "$bin" ] || { echo "servo_table.sh: $bin not found (build the servo_ibvs_yawing_camera target)" >&2; exit 1; }
run() { # view label args...
  local view=$1 label=$2; shift 2
  local its=() errs=() diverged=0
  for s in $(seq 1 "$seeds"); do
    local last
    last=$(last_lines 1 "$bin" --view "$view" --seed "$s" --png none --quiet "$@")
    diverged=$((diverged + $(not_converged "$last")))
    its+=("$(field iterations "$last")")
    errs+=("$(field final_error "$last")")
  done
  printf '%s\n' "${its[@]}" | awk -v view="$view" -v label="$label" -v div="$diverged" -v errs="${errs[*]}" '
    { s += $1; if (NR == 1 || $1 < mn) mn = $1; if ($1 > mx) mx = $1 }
    END { n = split(errs, e, " "); me = 0; for (i = 1; i <= n; i++) if (e[i] > me) me = e[i];
          printf "| %-5s | %-28s | %7.1f | %4d .. %-4d | %6.3f | %d |\n", view, label, s / NR, mn, mx, me, div }'
}
echo "| view  | depth                        | mean iterations | min .. max | worst final error (px) | diverged |"
echo "|-------|------------------------------|-----------------|------------|------------------------|----------|"
for view in front side; do
  run "$view" "true" --depth true
  run "$view" "constant, 50 % too far" --depth constant --constant-error 0.5
  run "$view" "constant, 200 % too far" --depth constant --constant-error 2.0
  run "$view" "constant, 50 % too near" --depth constant --constant-error -0.5
  run "$view" "estimated (prior 1 m)" --depth estimated
  run "$view" "estimated + yaw helper" --depth estimated --yaw-helper
done
