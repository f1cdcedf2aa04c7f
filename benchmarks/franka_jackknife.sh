#!/usr/bin/env bash
# franka_jackknife.sh: how well the 8 photos and arm poses of tests/data/franka-eye-in-hand fix the
# board's scale and flatness (docs/arms.md's "How well can these 8 poses fix the scale?" and
# "Flatness is the board's"). With the hand-eye pose calibrated on all 8 photos (as
# examples/franka_measure.sh does), `yawdepth measure` is run on subsets of the photos:
#   1. leave-one-out, per-pose noise (refine, --motion-noise absolute, 1 mm and 0.05 deg) and plain
#      triangulation (the poses as exact): the range of the median block length over the 8 runs and
#      its jackknife standard error, sqrt((n - 1) / n * sum (m_i - mean)^2);
#   2. photos 1-4 and 5-8 alone (per-pose noise): the median block length of each;
#   3. the corners' signed distances to their own fitted plane (plane.csv) measured from photos 1-4
#      and from 5-8, and from the odd and the even photos: their correlation over the corners both
#      measured (a plane's normal has no preferred sign: a negative value would mean the same
#      pattern with the normal flipped).
# Usage: benchmarks/franka_jackknife.sh [path/to/yawdepth] [WORKDIR]
set -euo pipefail
Y=${1:-build/tools/yawdepth}
W=${2:-$(mktemp -d)}
D=$(cd "$(dirname "${BASH_SOURCE[0]}")/../tests/data/franka-eye-in-hand" && pwd)
[ -x "$Y" ] || { echo "franka_jackknife.sh: $Y not found (build the yawdepth target)" >&2; exit 1; }
mkdir -p "$W"
CAM="$D/franka_camera.xml"
BOARD=chessboard:9x6:0.0236
for f in "$D"/franka_image-*.png; do ln -sf "$f" "$W/"; done
"$Y" calibrate-rig --hand-eye eye-in-hand --camera "$CAM" --motion "$D/motion.csv" --pattern "$BOARD" \
  --out "$W/eMc.yaml" --quiet > "$W/handeye.txt"

subset() { # name photo-numbers... -> $W/NAME.csv, the motion log's header and those photos' rows
  local name=$1; shift
  awk -F, -v keep=" $* " 'NR == 1 || index(keep, " " $1 " ") > 0' "$D/motion.csv" > "$W/$name.csv"
}
NOPOSE=(--method refine --sigma-odom 0 --sigma-rot 0 --robust-threshold-px 1e6 --outlier-threshold-px 1e6)
median() { # name args... -> the median block length (mm); the report in $W/NAME.report
  local name=$1; shift
  "$Y" measure --camera "$CAM" --rig "$W/eMc.yaml" --motion "$W/$name.csv" --pattern "$BOARD" \
    --report "$W/$name.report" --out "$W/$name.points.csv" --quiet "$@"
  awk '/^all block lengths:/ { print $5 }' "$W/$name.report/report.txt"
}
jackknife() { # label args...
  local label=$1; shift
  local all=() i
  for i in 1 2 3 4 5 6 7 8; do
    subset "out$i" $(seq 1 8 | grep -vx "$i")
    all+=("$(median "out$i" "$@")")
  done
  printf '%s\n' "${all[@]}" | awk -v label="$label" '
    { m[NR] = $1; s += $1; if (NR == 1 || $1 < lo) lo = $1; if ($1 > hi) hi = $1 }
    END { n = NR; mean = s / n; for (i = 1; i <= n; i++) ss += (m[i] - mean) ^ 2
          se = sqrt((n - 1) / n * ss)
          printf "%s: leave-one-out medians %.3f .. %.3f mm, jackknife s.e. %.3f mm (%.2f %% of 23.6)\n",
                 label, lo, hi, se, 100 * se / 23.6 }'
}
jackknife "per-pose noise (1 mm, 0.05 deg)" --motion-noise absolute
jackknife "plain triangulation" "${NOPOSE[@]}"
subset first 1 2 3 4
subset second 5 6 7 8
subset odd 1 3 5 7
subset even 2 4 6 8
echo "per-pose noise, photos 1-4 alone: median $(median first --motion-noise absolute) mm;" \
  "photos 5-8 alone: $(median second --motion-noise absolute) mm"
median odd --motion-noise absolute > /dev/null
median even --motion-noise absolute > /dev/null
correlation() { # a b -> the correlation of plane_distance over the ids both have
  awk -F, 'FNR == 1 { f++; next } f == 1 { d[$1] = $9; next } ($1 in d) { n++; x = d[$1]; y = $9
             sx += x; sy += y; sxx += x * x; syy += y * y; sxy += x * y }
           END { printf "%.2f over %d corners", (n * sxy - sx * sy) / sqrt((n * sxx - sx * sx) * (n * syy - sy * sy)), n }' \
    "$W/$1.report/plane.csv" "$W/$2.report/plane.csv"
}
echo "distance to the plane, photos 1-4 against 5-8: correlation $(correlation first second);" \
  "odd against even photos: $(correlation odd even)"
