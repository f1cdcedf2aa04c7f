#!/usr/bin/env bash
# A real robot measurement: the chessboard of ViSP's eye-in-hand data set (tests/data/franka-eye-in-hand:
# 8 photos from a Panda arm and the arm's poses rMe from its forward kinematics) measured from the arm's
# motion alone with `yawdepth measure`, against the printed board (23.6 mm squares) and ViSP's published
# board pose rMo. Prints one row per way of measuring: block lengths (median, 5..95 %, share within
# 0.3 mm of 23.6), flatness (largest distance to the fitted plane) and the board origin's distance
# to ViSP's rMo.
# Usage: examples/franka_measure.sh [path/to/yawdepth] [WORKDIR]
set -euo pipefail
Y=${1:-build/tools/yawdepth}
W=${2:-$(mktemp -d)}
D=$(cd "$(dirname "${BASH_SOURCE[0]}")/../tests/data/franka-eye-in-hand" && pwd)
[ -x "$Y" ] || { echo "franka_measure.sh: $Y not found (build the yawdepth target)" >&2; exit 1; }
mkdir -p "$W"
CAM="$D/franka_camera.xml" # the camera's factory intrinsics, as ViSP's tutorial uses them
BOARD=chessboard:9x6:0.0236
# 1. The hand-eye pose eMc from the same photos and poses (the board's known size sets its scale).
"$Y" calibrate-rig --hand-eye eye-in-hand --camera "$CAM" --motion "$D/motion.csv" --pattern "$BOARD" \
  --out "$W/eMc.yaml" --quiet > "$W/handeye.txt"
# ViSP's published eMc, for comparison.
printf 'camera_pose: [0.0577148, -0.0339261, -0.0422745, 0.00178253, 0.00917657, 1.58178]\n' > "$W/eMc_visp.yaml"

row() { # label rig args...
  local label=$1 rig=$2; shift 2
  if ! "$Y" measure --camera "$CAM" --rig "$rig" --motion "$D/motion.csv" --pattern "$BOARD" --report "$W/report" \
    --out "$W/points.csv" --quiet "$@" 2> "$W/measure.err"; then
    # No report (fewer than 3 points): the statuses say why, from the same run without it.
    "$Y" measure --camera "$CAM" --rig "$rig" --motion "$D/motion.csv" --pattern "$BOARD" --out "$W/points.csv" \
      --quiet "$@" 2> /dev/null || { cat "$W/measure.err" >&2; exit 1; }
    awk -F, -v label="$label" 'NR > 1 { n[$10]++ } END { s = ""; for (k in n) s = s (s == "" ? "" : ", ") n[k] " " k
                                printf "| %s | no board: of %d points, %s | | | | |\n", label, NR - 1, s }' "$W/points.csv"
    return
  fi
  awk -v label="$label" '
    /^all block lengths:/ { med = $5; lo = $9; hi = $11; within = $13 }
    /^distance to fitted plane:/ { flat = $6 }
    /^board pose in the world:/ { gsub(/[(),]/, " "); dx = $8 - 536.4858; dy = $9 - 123.9457; dz = $10 - 91.5574
                                  d = sqrt(dx * dx + dy * dy + dz * dz) }
    END { printf "| %s | %.3f | %.3f .. %.3f | %s %% | %.2f | %.1f |\n", label, med, lo, hi, within, flat, d }' \
    "$W/report/report.txt"
}
echo "| measured with | median block (mm) | 5..95 % (mm) | within 0.3 mm | flatness (mm) | origin to ViSP's rMo (mm) |"
echo "|---|---|---|---|---|---|"
# Plain multi-view triangulation: the poses as measured (no pose noise), least squares, nothing flagged.
# The arm's poses are not that good: the residuals are then many times the model's and every point is
# refused as inconsistent (formats.md, "the tracks do not fit the motion log"), which the row says.
NOPOSE=(--method refine --sigma-odom 0 --sigma-rot 0 --robust-threshold-px 1e6 --outlier-threshold-px 1e6)
row "plain triangulation, ViSP's eMc" "$W/eMc_visp.yaml" "${NOPOSE[@]}"
row "plain triangulation, yawdepth's eMc" "$W/eMc.yaml" "${NOPOSE[@]}"
# refine with the odometry model (each increment errs): the wrong model for forward kinematics.
row "refine, increment noise (1 mm, 0.05 deg)" "$W/eMc.yaml" --motion-noise increment
# refine with per-pose noise: each pose of the arm errs about the truth (forward kinematics).
row "refine, per-pose noise (1 mm, 0.05 deg), ViSP's eMc" "$W/eMc_visp.yaml" --motion-noise absolute
row "refine, per-pose noise (1 mm, 0.05 deg)" "$W/eMc.yaml" --motion-noise absolute
row "refine, per-pose noise (3 mm, 0.3 deg)" "$W/eMc.yaml" --motion-noise absolute --sigma-odom 0.003 --sigma-rot 0.005
