#!/usr/bin/env bash
# import-bag and measure --bag on ROS 1 bags written by real rosbag (tests/data/bags): the written
# files read as they are by estimate and measure, measure --bag against measure on the imported
# files and against the board's truth, and bad input: one line, status 1, nothing written.
#
#   YAWDEPTH=/path/to/yawdepth BAGS=/path/to/tests/data/bags bash tests/import_bag_cli.sh
#
# Needs bash, coreutils, awk and python3 (its standard library only).
set -u
YAWDEPTH=${YAWDEPTH:?set YAWDEPTH}
BAGS=${BAGS:?set BAGS}
W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_bag.XXXXXX") || exit 1
trap '[ -n "${KEEP:-}" ] || rm -rf "$W"' EXIT
PASSED=0 FAILED=0
pass() { PASSED=$((PASSED + 1)); }
fail() { FAILED=$((FAILED + 1)); echo "FAIL: $*"; }
check() { local what=$1; shift; if "$@"; then pass; else fail "$what"; fi; }

check "--version lists the bag formats" bash -c "'$YAWDEPTH' --version | grep -q '^bag formats read: ros1'"

# import-bag: the outputs and the summary.
start=$(date +%s.%N)
"$YAWDEPTH" import-bag "$BAGS/robot.bag" --out-dir "$W/robot" --image-topic /camera/image_raw --odom-topic /odom \
  >"$W/robot.out" 2>"$W/robot.err"
check "import-bag: status 0" test $? -eq 0
end=$(date +%s.%N)
echo "import-bag robot.bag: $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", b - a }') s"
for f in motion.csv camera.yaml rig.yaml; do check "import-bag writes $f" test -s "$W/robot/$f"; done
check "import-bag: 14 images written" test "$(ls "$W/robot/images" | wc -l)" -eq 14
check "import-bag: the summary's topics" grep -q "/odom (nav_msgs/Odometry): 71 messages" "$W/robot.out"
check "import-bag: the summary's counts" grep -q "22 read.*22 kept, 14 matched; skipped: 1 before the motion, 1 after it, 6 in its gaps" "$W/robot.out"
check "import-bag: nothing on stderr" test ! -s "$W/robot.err"
check "import-bag: the frame-based 6-DoF log" bash -c "head -1 '$W/robot/motion.csv' | grep -q '^frame,t,tx,ty,tz,tux,tuy,tuz,yaw,image$'"
check "import-bag: images relative to the folder" bash -c "sed -n 2p '$W/robot/motion.csv' | grep -q ',images/1700000000020000000.png$'"
check "import-bag: no staging folder left" bash -c "! ls -a '$W/robot' | grep -q import-bag"

# estimate reads the written files as they are: tracks of world points projected through them.
python3 - "$W/robot" >"$W/tracks.csv" <<'PY'
import math, sys
d = sys.argv[1]
def rod(w):
    t = math.sqrt(sum(x * x for x in w))
    if t < 1e-12:
        return [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    k = [x / t for x in w]; c, s = math.cos(t), math.sin(t)
    K = [[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]]
    KK = [[sum(K[i][m] * K[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    return [[(i == j) + s * K[i][j] + (1 - c) * KK[i][j] for j in range(3)] for i in range(3)]
def pose(v):
    return rod(v[3:6]), v[0:3]
def mul(a, b):
    Ra, ta = a; Rb, tb = b
    R = [[sum(Ra[i][m] * Rb[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    return R, [sum(Ra[i][m] * tb[m] for m in range(3)) + ta[i] for i in range(3)]
def nums(line):
    return [float(x) for x in line.split("[")[1].split("]")[0].split(",")]
rig = [l for l in open(d + "/rig.yaml") if l.startswith("camera_pose:")][0]
bMc = pose(nums(rig))
cam = open(d + "/camera.yaml").read()
def block(name):
    s = cam.split(name + ":")[1].split("data:")[1]
    return [float(x) for x in s.split("[")[1].split("]")[0].split(",")]
K = block("camera_matrix"); D = block("distortion_coefficients")
rows = [l.strip().split(",") for l in open(d + "/motion.csv")][1:]
pts = [(3.0, -0.4 + 0.4 * i, 0.3 + 0.35 * j) for i in range(3) for j in range(3)]  # ahead of the robot, in odom
print("frame,id,u,v")
for r in rows:
    wMc = mul(pose([float(x) for x in r[2:8]]), bMc)
    R, t = wMc
    for pid, P in enumerate(pts):
        q = [sum(R[m][i] * (P[m] - t[m]) for m in range(3)) for i in range(3)]  # cMw P
        x, y = q[0] / q[2], q[1] / q[2]
        r2 = x * x + y * y
        k1, k2, p1, p2, k3 = D[:5]
        f = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 ** 3
        xd = x * f + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * f + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        print("%s,%d,%.9f,%.9f" % (r[0], pid, K[0] * xd + K[2], K[4] * yd + K[5]))
PY
"$YAWDEPTH" estimate --camera "$W/robot/camera.yaml" --rig "$W/robot/rig.yaml" --motion "$W/robot/motion.csv" \
  --tracks "$W/tracks.csv" --method exact --sigma-px 0.05 --out "$W/est.csv" 2>"$W/est.err"
check "estimate on the imported files: status 0" test $? -eq 0
# Each point's depth in the last camera against the truth: the camera frame of the last row.
ok_near() {
  python3 - "$W/robot" "$W/est.csv" <<'PY'
import sys, math
est = [l.strip().split(",") for l in open(sys.argv[2])][1:]
ok = [r for r in est if r[-1] == "ok"]
# The points ahead (x = 3 m in odom) seen from the robot at x <= 0.5 m: depths 2.3 to 3.3 m.
good = [r for r in ok if 2.0 < float(r[7]) < 3.5]
sys.exit(0 if len(ok) >= 5 and len(good) == len(ok) else 1)
PY
}
check "estimate: the points at their depths" ok_near

# measure --bag: a chessboard rendered through the bag's camera and motion.
mkdir -p "$W/tmp"
TMPDIR="$W/tmp" "$YAWDEPTH" measure --bag "$BAGS/measure.bag" --image-topic /camera/image_raw/compressed \
  --odom-topic /odom --pattern chessboard:9x6:0.04 --method fused --quiet --out "$W/mb.csv" --ply "$W/mb.ply" 2>"$W/mb.err"
check "measure --bag: status 0 ($(head -1 "$W/mb.err"))" test $? -eq 0
check "measure --bag: the temporary folder removed" test -z "$(ls -A "$W/tmp")"
board_ok() { # all 54 corners on the board's plane x = 1.45 m of odom: each within 1 cm, on average within 2 mm
  awk 'BEGIN { n = 0; bad = 0 } /^end_header/ { body = 1; next }
       body { n++; d = $1 - 1.45; s += d; if (d < 0) d = -d; if (d > 0.01) bad++ }
       END { m = s / n; if (m < 0) m = -m; exit !(n == 54 && bad == 0 && m < 0.002) }' "$W/mb.ply"
}
check "measure --bag: the board's corners on its plane" board_ok
"$YAWDEPTH" import-bag "$BAGS/measure.bag" --out-dir "$W/meas" --image-topic /camera/image_raw/compressed --odom-topic /odom --quiet
"$YAWDEPTH" measure --camera "$W/meas/camera.yaml" --rig "$W/meas/rig.yaml" --motion "$W/meas/motion.csv" \
  --pattern chessboard:9x6:0.04 --method fused --quiet --out "$W/mi.csv"
check "measure on the imported files = measure --bag" cmp -s "$W/mb.csv" "$W/mi.csv"
check "import-bag: compressed images written as they came (.png)" bash -c "ls '$W/meas/images' | grep -q '\\.png$'"

# Usage: without --bag, --camera, --rig and --motion are required; the bag options need --bag.
"$YAWDEPTH" measure --pattern chessboard:9x6:0.04 --motion x.csv --rig r.yaml >/dev/null 2>"$W/u.err"
check "measure without --camera: status 2" test $? -eq 2
check "measure without --camera: named" grep -q -- "--camera is required" "$W/u.err"
"$YAWDEPTH" measure --camera c.yaml --rig r.yaml --motion m.csv --image-topic /x --pattern chessboard:9x6:0.04 >/dev/null 2>"$W/u.err"
check "a bag option without --bag: status 2" test $? -eq 2
"$YAWDEPTH" measure --bag "$BAGS/robot.bag" --motion m.csv --image-topic /x --pattern chessboard:9x6:0.04 >/dev/null 2>"$W/u.err"
check "--bag with --motion: status 2" test $? -eq 2

# Bad input: one line, status 1, nothing written.
bad() { # what expected-words args...
  local what=$1 words=$2; shift 2
  rm -rf "$W/bad"
  "$YAWDEPTH" "$@" >"$W/bad.out" 2>"$W/bad.err"
  local rc=$?
  if [ "$rc" -ne 1 ] || [ "$(wc -l <"$W/bad.err")" -ne 1 ] || ! grep -q -- "$words" "$W/bad.err" || [ -e "$W/bad" ]; then
    fail "$what (rc $rc): $(head -2 "$W/bad.err")"
  else
    pass
  fi
}
ib=(import-bag "$BAGS/robot.bag" --out-dir "$W/bad")
bad "a missing topic, the bag's topics listed" "no topic /nope (--image-topic); the bag has: .*/camera/image_raw (sensor_msgs/Image, 22 messages)" \
  "${ib[@]}" --image-topic /nope --odom-topic /odom
bad "a wrong message type" "/pose (--odom-topic) is geometry_msgs/PoseStamped, not nav_msgs/Odometry" \
  "${ib[@]}" --image-topic /camera/image_raw --odom-topic /pose
bad "a TF chain that does not connect" "no chain from world to nowhere in /tf and /tf_static (frames: base_link, camera_link" \
  "${ib[@]}" --image-topic /camera/image_raw --tf world:nowhere
bad "no motion source" "one of --odom-topic, --pose-topic or --tf" "${ib[@]}" --image-topic /camera/image_raw
bad "two motion sources" "not --odom-topic and --tf" "${ib[@]}" --image-topic /camera/image_raw --odom-topic /odom --tf world:base_link
bad "an unknown joint" "/joint_states has no joint tilt (joints: pan_joint, wheel)" \
  "${ib[@]}" --image-topic /camera/image_raw --odom-topic /odom --joint-topic /joint_states --joint tilt
bad "images of another size than camera_info" "is 16 x 12 pixels, /cam/big_info says 20 x 15" \
  import-bag "$BAGS/camera_cases.bag" --out-dir "$W/bad" --image-topic /cam/image_raw --camera-info-topic /cam/big_info --odom-topic /odom
bad "an unknown distortion model" "distortion model 'fisheye_xyz'" \
  import-bag "$BAGS/camera_cases.bag" --out-dir "$W/bad" --image-topic /cam/image_raw --camera-info-topic /cam/fisheye_xyz_info --odom-topic /odom
head -c 90000 "$BAGS/robot.bag" >"$W/cut.bag"
bad "a truncated bag" "cut.bag: truncated or corrupt" \
  import-bag "$W/cut.bag" --out-dir "$W/bad" --image-topic /camera/image_raw --odom-topic /odom
mkfifo "$W/pipe.bag" && { timeout 20 cat "$BAGS/robot.bag" >"$W/pipe.bag" 2>/dev/null & }
bad "a ROS 1 bag from a pipe" "pipe.bag: a ROS 1 bag is read from a regular file (its index is at its end), not a pipe" \
  import-bag "$W/pipe.bag" --out-dir "$W/bad" --image-topic /camera/image_raw --odom-topic /odom
bad "measure --bag: the import's error" "no topic /nope" \
  measure --bag "$BAGS/robot.bag" --image-topic /nope --odom-topic /odom --pattern chessboard:9x6:0.04 --out "$W/bad"
# A camera_info that changes: a warning, the import done.
"$YAWDEPTH" import-bag "$BAGS/camera_cases.bag" --out-dir "$W/changes" --image-topic /cam/image_raw --odom-topic /odom \
  --quiet 2>"$W/changes.err"
check "a changing camera_info: status 0" test $? -eq 0
check "a changing camera_info: warned" grep -q "^yawdepth import-bag: warning: /cam/camera_info: camera_info changes during the bag" "$W/changes.err"

echo "$PASSED passed, $FAILED failed"
[ "$FAILED" -eq 0 ]
