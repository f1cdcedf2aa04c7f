#!/usr/bin/env bash
# calibrate-camera's ROS camera_info file (PREFIX_ros.yaml) against ROS's own parser and our reader.
#
#   YAWDEPTH=/path/to/yawdepth bash tests/calibrate_camera_ros.sh
#
# On the real franka photos (tests/data/franka-eye-in-hand), for each distortion model that the
# file can hold (plumb_bob: k4, as k5 does not invert at these photos' corners; rational_polynomial: k8;
# equidistant: fisheye):
# calibrate-camera writes PREFIX.yaml and PREFIX_ros.yaml; ROS's camera_calibration_parsers (the
# parser camera_info_manager loads with; Debian's python3-camera-calibration-parsers) reads
# PREFIX_ros.yaml and its name, size, model, K, D, R and P must equal, exactly, what OpenCV's
# FileStorage reads from PREFIX.yaml (python3-opencv); and yawdepth's own `--camera` reader must
# read both files as the same camera: calibrate-rig --hand-eye with either writes the same rig file,
# byte for byte. Prints one line per failed check and ends with "N passed, M failed".
set -u

YAWDEPTH=${YAWDEPTH:-}
PY=/usr/bin/python3
PASSED=0
FAILED=0
pass() { PASSED=$((PASSED + 1)); }
fail() { FAILED=$((FAILED + 1)); echo "FAIL: $*"; }
finish() { echo "$PASSED passed, $FAILED failed"; [ "$FAILED" -eq 0 ]; exit $?; }

if [ -z "$YAWDEPTH" ] || [ ! -x "$YAWDEPTH" ]; then fail "YAWDEPTH is not an executable (got '$YAWDEPTH')"; finish; fi
if ! "$PY" -c 'import camera_calibration_parsers, cv2' 2>/dev/null; then
  fail "ROS's parser or OpenCV's Python binding is missing: apt-get install python3-camera-calibration-parsers python3-opencv"
  finish
fi
W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_ros.XXXXXX") || { fail mktemp; finish; }
trap '[ -n "${KEEP:-}" ] || rm -rf "$W"' EXIT
FR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/data/franka-eye-in-hand"

# compare CAMERA_NAME MODEL ROS_FILE OPENCV_FILE: prints OK or the differences.
compare() {
  "$PY" - "$@" <<'EOF'
import sys, cv2, camera_calibration_parsers as p
name, model, ros, ocv = sys.argv[1:5]
n, c = p.readCalibration(ros)
fs = cv2.FileStorage(ocv, cv2.FILE_STORAGE_READ)
K = fs.getNode("camera_matrix").mat().flatten().tolist()
D = fs.getNode("distortion_coefficients").mat().flatten().tolist()
W, H = int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real())
bad = []
if n != name: bad.append("camera_name %r" % n)
if c.distortion_model != model: bad.append("distortion_model %s" % c.distortion_model)
if (c.width, c.height) != (W, H): bad.append("size %dx%d against %dx%d" % (c.width, c.height, W, H))
if list(c.K) != K: bad.append("K %s against %s" % (list(c.K), K))
# plumb_bob holds 5 coefficients: OpenCV's YAML may hold 4 (k3 = 0)
Dr = list(c.D)
if Dr[:len(D)] != D or any(v != 0 for v in Dr[len(D):]): bad.append("D %s against %s" % (Dr, D))
if list(c.R) != [1, 0, 0, 0, 1, 0, 0, 0, 1]: bad.append("R %s" % list(c.R))
if list(c.P) != [K[0], 0, K[2], 0, 0, K[4], K[5], 0, 0, 0, 1, 0]: bad.append("P %s" % list(c.P))
print("OK" if not bad else "; ".join(bad))
EOF
}

for spec in k4:plumb_bob k8:rational_polynomial fisheye:equidistant; do
  d=${spec%%:*}
  model=${spec#*:}
  P="$W/cam_$d"
  "$YAWDEPTH" calibrate-camera --quiet --pattern chessboard:9x6:0.0236 --distortion "$d" --camera-name "franka_$d" \
    --out "$P" "$FR"/franka_image-[1-8].png >"$P.out" 2>"$P.err"
  if [ $? -ne 0 ]; then fail "calibrate-camera --distortion $d: $(head -n 1 "$P.err")"; continue; fi
  [ -s "$P.yaml" ] && [ -s "$P.xml" ] && [ -s "${P}_ros.yaml" ] && [ -s "${P}_coverage.png" ] && pass ||
    fail "calibrate-camera --distortion $d: not every file written"
  # ViSP cannot hold a fisheye: its XML says so (and holds ViSP's own approximations), the others do not.
  if [ "$d" = fisheye ]; then grep -q "<lens_model>Kannala-Brandt" "$P.xml"; else ! grep -q "<lens_model>" "$P.xml"; fi &&
    pass || fail "--distortion $d: the ViSP XML's lens_model note is wrong"
  res=$(compare "franka_$d" "$model" "${P}_ros.yaml" "$P.yaml" 2>&1)
  [ "$res" = OK ] && pass || fail "--distortion $d: ROS's parser against PREFIX.yaml: $res"
  for f in "$P.yaml" "${P}_ros.yaml"; do
    "$YAWDEPTH" calibrate-rig --hand-eye eye-in-hand --camera "$f" --motion "$FR/motion.csv" \
      --pattern chessboard:9x6:0.0236 --out "$f.rig" >"$f.rig.out" 2>"$f.rig.err" ||
      fail "--distortion $d: calibrate-rig --camera $(basename "$f"): $(head -n 1 "$f.rig.err")"
  done
  cmp -s "$P.yaml.rig" "${P}_ros.yaml.rig" && pass ||
    fail "--distortion $d: our reader reads PREFIX.yaml and PREFIX_ros.yaml as different cameras"
done
# The auto rule on a narrow real lens: auto never tries fisheye; auto+fisheye scores it and keeps Brown.
"$YAWDEPTH" calibrate-camera --pattern chessboard:9x6:0.0236 --out "$W/auto" "$FR"/franka_image-[1-8].png >"$W/auto.out" 2>&1
! grep -q "Kannala-Brandt" "$W/auto.out" && grep -q "^Distortion model: k1 k2 p1 p2" "$W/auto.out" && pass ||
  fail "--distortion auto tried fisheye or did not keep k1 k2 p1 p2: $(grep '^Distortion model' "$W/auto.out")"
"$YAWDEPTH" calibrate-camera --pattern chessboard:9x6:0.0236 --distortion auto+fisheye --out "$W/autof" \
  "$FR"/franka_image-[1-8].png >"$W/autof.out" 2>&1
grep -q "^    Kannala-Brandt k1..k4 (fisheye): RMS .* on views left out" "$W/autof.out" &&
  grep -q "^Distortion model: k1 k2 p1 p2" "$W/autof.out" && grep -q "distortion_model: plumb_bob" "$W/autof_ros.yaml" && pass ||
  fail "--distortion auto+fisheye: fisheye not scored, or chosen for a narrow lens: $(grep '^Distortion model' "$W/autof.out")"
# cv::fisheye cannot keep fx = fy: refused in one line, nothing written.
"$YAWDEPTH" calibrate-camera --quiet --pattern chessboard:9x6:0.0236 --distortion fisheye --fix-aspect-ratio \
  --out "$W/fa" "$FR"/franka_image-[1-8].png >/dev/null 2>"$W/fa.err"
[ $? -eq 1 ] && [ "$(wc -l <"$W/fa.err")" -eq 1 ] && grep -q "fix-aspect-ratio" "$W/fa.err" && [ ! -e "$W/fa.yaml" ] && pass ||
  fail "--distortion fisheye --fix-aspect-ratio: not refused in one line: $(head -n 2 "$W/fa.err")"
# All or none: an unwritable PREFIX_ros.yaml (a folder) leaves no other file behind.
mkdir -p "$W/clash_ros.yaml"
"$YAWDEPTH" calibrate-camera --quiet --pattern chessboard:9x6:0.0236 --out "$W/clash" "$FR"/franka_image-[1-8].png \
  >/dev/null 2>"$W/clash.err" && fail "calibrate-camera wrote into a folder PREFIX_ros.yaml" || pass
[ -e "$W/clash.yaml" ] || [ -e "$W/clash.xml" ] || [ -e "$W/clash_coverage.png" ] &&
  fail "calibrate-camera left files behind though PREFIX_ros.yaml is a folder: $(ls "$W" | tr '\n' ' ')" || pass
finish
