#!/usr/bin/env bash
# The drive past a board (make_drive.sh) measured from its bags and from yawdepth's own files, one
# table row per input, and the issue's check (#32): a bag measures as well as the same scene given in
# yawdepth's own files.
#
#   examples/bag_drive/run.sh YAWDEPTH [WORKDIR] [FRAMES]
#
# For each bag input (ROS 1 with raw images, ROS 1 with the PNG-compressed ones, ROS 1 with the
# poses from /tf instead of /odom, MCAP raw, MCAP compressed):
#   yawdepth import-bag BAG --out-dir D --image-topic T --camera-info-topic /camera/camera_info
#       --odom-topic /odom (or --tf odom:base_link) --camera-frame camera_optical_frame
#       --joint-topic /joint_states --joint pan_joint --time-offset -0.04
#   yawdepth measure --camera D/camera.yaml --rig D/rig.yaml --motion D/motion.csv --pattern chessboard:5x4:0.02
# and the same measure on simulate's own files (sim/motion.csv, planar, with its images; and the same
# log in the 6-DoF form import-bag writes, tx,ty,tz,tux,tuy,tuz, so that the noise model is the
# bags'). Columns: input, images in the motion log, images where the board was found, points ok,
# depth RMSE against the truth (mm), median |depth error| / sigma_zc, the RMS distance of the
# corners from their true places in the odometry's world (mm: at constant velocity a wrong time
# offset leaves the depths but moves the board, 4 mm for the 40 ms latency), median block length
# (mm; 20 is the board's). A last row imports the ROS 1 bag without --time-offset, which must come
# out worse (the latency is in the bag). A second table measures the textured wall the board hangs on
# by natural features (measure --features klt) from the same inputs, against the wall's plane
# (compare.py wall): each bag within 10 % of the direct files' depth RMSE, and no warning.
# Exit status 1 when a bag's depth RMSE or world RMS exceeds the 6-DoF direct files' by more than
# 10 %, it has fewer points ok, the last row is not worse, or the wall's check fails; 77 when a writer's prerequisites (make_drive.sh) or `yawdepth import-bag` are missing.
set -uo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
y=${1:?usage: run.sh YAWDEPTH [WORKDIR] [FRAMES]}
w=${2:-$(mktemp -d "${TMPDIR:-/tmp}/bag_drive.XXXXXX")}
frames=${3:-70}
pattern=chessboard:5x4:0.02
noise=(--sigma-odom 0.0002)
mkdir -p "$w"
w=$(cd "$w" && pwd)

writers=${YAWDEPTH_BAG_WRITERS:-$here/../../tests/data/bags/writers}
if ! /usr/bin/python3 -c 'import rosbag, sensor_msgs.msg, nav_msgs.msg, geometry_msgs.msg, tf2_msgs.msg' 2>/dev/null ||
  ! command -v node >/dev/null || [ ! -d "$writers/node_modules/@mcap/core" ]; then
  echo "run.sh: SKIP: needs /usr/bin/python3 with rosbag and the ROS message modules (Debian's python3-rosbag," \
    "python3-sensor-msgs, python3-nav-msgs, python3-geometry-msgs, python3-tf2-msgs), node and" \
    "$writers/node_modules (npm ci --no-audit --no-fund there)"
  exit 77
fi
bash "$here/make_drive.sh" "$y" "$w/drive" "$frames"
rc=$?
[ "$rc" -eq 3 ] && { echo "run.sh: SKIP: a bag writer's prerequisites are missing (see above)"; exit 77; }
[ "$rc" -eq 0 ] || { echo "run.sh: make_drive.sh failed ($rc)" >&2; exit 1; }
if ! "$y" import-bag --help >/dev/null 2>&1; then
  echo "run.sh: SKIP: $y has no import-bag command (the bags are in $w/drive)"
  exit 77
fi
sim=$w/drive/sim
stamps=$w/drive/plan/stamps.csv

# The direct log in the 6-DoF form: theta-u = (0, heading, 0).
awk -F, 'NR == 1 { print "frame,tx,ty,tz,tux,tuy,tuz,yaw,image"; next } { print $1 "," $2 "," $3 "," $4 ",0," $5 ",0," $6 "," $7 }' \
  "$sim/motion.csv" >"$sim/motion_6dof.csv"

rows=() failed=0
slug() { local s=${1//[^A-Za-z0-9]/_}; echo "$w/$s"; }
measure() { # NAME CAMERA RIG MOTION
  local name=$1 f
  f=$(slug "$name")
  if ! "$y" measure --camera "$2" --rig "$3" --motion "$4" --pattern "$pattern" "${noise[@]}" \
    --out "$f.points.csv" --report "$f.report" >"$f.measure.log" 2>&1; then
    echo "run.sh: $name: measure failed:" >&2; tail -3 "$f.measure.log" >&2
    failed=1; return 1
  fi
  rows+=("$(python3 "$here/compare.py" "$name" "$4" "$f.points.csv" "$f.report" "$f.measure.log" "$sim" "$stamps")")
}
# The textured wall around the board, measured by natural features (`measure --features klt`, the
# defaults: fused, the residual check on) from the same images.
wall_rows=()
measure_wall() { # NAME CAMERA RIG MOTION
  local name=$1 f
  f=$(slug "$name")
  if ! "$y" measure --camera "$2" --rig "$3" --motion "$4" --features klt "${noise[@]}" \
    --out "$f.klt.csv" >"$f.klt.log" 2>&1; then
    echo "run.sh: $name: measure --features klt failed:" >&2; tail -3 "$f.klt.log" >&2
    failed=1; return 1
  fi
  wall_rows+=("$(python3 "$here/compare.py" "$name" "$4" "$f.klt.csv" "$f.report" "$f.klt.log" "$sim" "$stamps" wall)")
}
measure "simulate's files (planar)" "$here/../../calib/paper_camera.xml" "$here/../../calib/paper_rig.yaml" "$sim/motion.csv"
measure "simulate's files (6-DoF)" "$here/../../calib/paper_camera.xml" "$here/../../calib/paper_rig.yaml" "$sim/motion_6dof.csv"
measure_wall "simulate's files (planar)" "$here/../../calib/paper_camera.xml" "$here/../../calib/paper_rig.yaml" "$sim/motion.csv"
measure_wall "simulate's files (6-DoF)" "$here/../../calib/paper_camera.xml" "$here/../../calib/paper_rig.yaml" "$sim/motion_6dof.csv"

bag_input() { # NAME BAG IMAGE_TOPIC POSE_ARGS...
  local name=$1 bag=$2 topic=$3; shift 3
  local d
  d=$(slug "import $name")
  if ! "$y" import-bag "$bag" --out-dir "$d" --image-topic "$topic" --camera-info-topic /camera/camera_info "$@" \
    --camera-frame camera_optical_frame --joint-topic /joint_states --joint pan_joint --time-offset "${offset:--0.04}" \
    >"$d.log" 2>&1; then
    echo "run.sh: $name: import-bag failed:" >&2; tail -3 "$d.log" >&2
    failed=1; return 1
  fi
  measure "$name" "$d/camera.yaml" "$d/rig.yaml" "$d/motion.csv"
  [ -n "${offset:-}" ] || measure_wall "$name" "$d/camera.yaml" "$d/rig.yaml" "$d/motion.csv"
}
bag_input "ROS 1 bag, image_raw" "$w/drive/drive.bag" /camera/image_raw --odom-topic /odom
bag_input "ROS 1 bag, compressed" "$w/drive/drive.bag" /camera/image_raw/compressed --odom-topic /odom
bag_input "ROS 1 bag, --tf" "$w/drive/drive.bag" /camera/image_raw --tf odom:base_link
bag_input "MCAP, image_raw" "$w/drive/drive.mcap" /camera/image_raw --odom-topic /odom
bag_input "MCAP, compressed" "$w/drive/drive.mcap" /camera/image_raw/compressed --odom-topic /odom
# The latency is in the bag: without --time-offset (0 instead of -0.04) the board must come out worse.
offset=0 bag_input "no --time-offset (ROS 1; must be worse)" "$w/drive/drive.bag" /camera/image_raw --odom-topic /odom

echo "| input | images | board found | points ok | depth RMSE (mm) | median abs(error)/sigma | world RMS (mm) | block median (mm) |"
echo "|---|---|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
# The check: each bag against the 6-DoF direct row (columns: 5 points ok, 6 depth RMSE, 8 world RMS):
# no fewer points ok, and both RMS errors within 10 % (plus 0.01 mm for the printed digits).
printf '%s\n' "${rows[@]}" | awk -F'|' '
  function trim(s) { gsub(/^ +| +$/, "", s); return s }
  function num(s) { s = trim(s); return s ~ /^[0-9.]+$/ ? s + 0 : -1 }
  { name = trim($2); ok = $5 + 0; rmse = num($6); wrms = num($8) }
  name == "simulate'"'"'s files (6-DoF)" { ref_ok = ok; ref = rmse; wref = wrms; have = 1; next }
  name ~ /^(ROS|MCAP)/ {
    n++
    if (!have || ref < 0 || wref < 0 || rmse < 0 || wrms < 0 || ok < ref_ok || rmse > 1.1 * ref + 0.01 || wrms > 1.1 * wref + 0.01) {
      bad = 1
      print "run.sh: FAIL: " name ": " ok " points ok, depth RMSE " rmse " mm, world RMS " wrms " mm; the 6-DoF direct files: " ref_ok ", " ref " mm, " wref " mm"
    }
  }
  name == "no --time-offset (ROS 1; must be worse)" {
    if (wrms >= 0 && wrms <= 1.1 * wref + 0.01) { bad = 1; print "run.sh: FAIL: without --time-offset the board is where it should be: is the latency in the bag?" }
    lat = 1
  }
  END { if (!lat) { print "run.sh: FAIL: the import without --time-offset did not run"; bad = 1 }
        if (n != 5) { print "run.sh: FAIL: " n " of 5 bag inputs measured"; bad = 1 } exit bad }' || failed=1
echo
echo "The wall, natural features (measure --features klt):"
echo
echo "| input | images | points | points ok | depth RMSE (mm) | median abs(error)/sigma | within 2 sigma | worst abs(error)/depth (%) | warnings |"
echo "|---|---|---|---|---|---|---|---|---|"
printf '%s\n' "${wall_rows[@]}"
# The check: each bag against the 6-DoF direct row (columns: 5 points ok, 6 depth RMSE, 10
# warnings): at least 98 % of its points ok, the depth RMSE within 10 %, no warning on any row (the
# rig and log are right).
printf '%s\n' "${wall_rows[@]}" | awk -F'|' '
  function trim(s) { gsub(/^ +| +$/, "", s); return s }
  function num(s) { s = trim(s); return s ~ /^[0-9.]+$/ ? s + 0 : -1 }
  { name = trim($2); ok = $5 + 0; rmse = num($6); warned = $10 + 0 }
  warned > 0 { bad = 1; print "run.sh: FAIL: " name ": measure --features klt warned on a right rig and log" }
  name == "simulate'"'"'s files (6-DoF)" { ref_ok = ok; ref = rmse; have = 1; next }
  name ~ /^(ROS|MCAP)/ {
    n++
    if (!have || ref < 0 || rmse < 0 || ok < 0.98 * ref_ok || rmse > 1.1 * ref + 0.01) {
      bad = 1
      print "run.sh: FAIL: wall: " name ": " ok " points ok, depth RMSE " rmse " mm; the 6-DoF direct files: " ref_ok ", " ref " mm"
    }
  }
  END { if (n != 5) { print "run.sh: FAIL: wall: " n " of 5 bag inputs measured"; bad = 1 } exit bad }' || failed=1
[ "$failed" -eq 0 ] && echo "run.sh: every bag within 10 % of the direct files' depth and world RMS (the board) and depth RMSE (the wall's natural features), and worse without the time offset ($w)"
exit "$failed"
