#!/usr/bin/env bash
# A robot's recording of a drive past a board, as the bags a ROS robot writes, with known truth.
#
#   examples/bag_drive/make_drive.sh YAWDEPTH OUT [FRAMES]
#
# `yawdepth simulate` renders the drive (the paper's camera and 150 mm lever arm, calib/): a 5x4
# chessboard of 20 mm squares, 0.62 m to the side, passed at 0.1 m/s (FRAMES images at 20 Hz over
# 0.35 m, default 70 = 3.5 s; fewer frames cover the same path faster) on a gentle turn toward the
# board (4 deg to the right) while the pan joint turns from 78 to 98 deg to follow it, so the board
# crosses the image from the left edge to the right. One board: simulate renders a single one. The
# odometry is dead-reckoned with 0.2 mm of noise per image increment (per axis); the pan readings
# are exact.
# Then the same drive as bags (drive_plan.py computes every message once; frames, times and the
# 40 ms image latency are described there):
#   OUT/sim/           simulate's own files: motion.csv (the odometry, pan and images),
#                      motion_truth.csv, truth.csv (the true corners), frame_NNNN.png
#   OUT/drive.bag      ROS 1 (rosbag, Debian's python3-rosbag): /camera/image_raw (mono8),
#                      /camera/image_raw/compressed (PNG), /camera/camera_info, /odom, /tf,
#                      /joint_states, /tf_static
#   OUT/drive.mcap     ROS 2 MCAP (zstd chunks; @mcap/core): the same topics with the ROS 2 types
#   OUT/plan/          the messages' values (plan.json) and stamps.csv, each image stamp's frame
# Needs /usr/bin/python3 with rosbag and the ROS message modules (python3-rosbag, python3-sensor-msgs,
# python3-nav-msgs, python3-geometry-msgs, python3-tf2-msgs), node and tests/data/bags/writers'
# npm packages (npm ci --no-audit --no-fund there). Without them that bag is not written (a note
# says so) and the exit status is 3.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
y=${1:?usage: make_drive.sh YAWDEPTH OUT [FRAMES]}
out=${2:?usage: make_drive.sh YAWDEPTH OUT [FRAMES]}
frames=${3:-70}
cam=$root/calib/paper_camera.xml
rig=$root/calib/paper_rig.yaml
writers=${YAWDEPTH_BAG_WRITERS:-$root/tests/data/bags/writers}
per() { awk -v v="$1" -v n="$frames" 'BEGIN { printf "%.9g", v / (n - 1) }'; }
rm -rf "$out"
mkdir -p "$out"
"$y" simulate --camera "$cam" --rig "$rig" --out-dir "$out/sim" --frames "$frames" \
  --step "$(per 0.35)" --yaw 1.36 --yaw-rate "$(per 0.35)" --turn-rate "$(per 0.07)" \
  --pattern chessboard:5x4:0.02 --board-distance 0.62 --board-offset-x -0.06 --wall 0.03 --blur 0.7 --image-noise 2 \
  --sigma-odom 0.0002 --seed 3 >/dev/null
/usr/bin/python3 "$here/drive_plan.py" "$out/sim" "$cam" "$rig" "$out/plan"
status=0
if /usr/bin/python3 -c 'import rosbag, sensor_msgs.msg, nav_msgs.msg, geometry_msgs.msg, tf2_msgs.msg' 2>/dev/null; then
  /usr/bin/python3 "$here/write_ros1_bag.py" "$out/plan" "$out/drive.bag"
  # Read back by rosbag: each topic's type, count and rate.
  /usr/bin/python3 -c '
import sys, rosbag
info = rosbag.Bag(sys.argv[1]).get_type_and_topic_info()
for topic, t in sorted(info.topics.items()):
    print("  %s: %d %s%s" % (topic, t.message_count, t.msg_type, " at %.1f Hz" % t.frequency if t.frequency else ""))
' "$out/drive.bag"
else
  echo "make_drive.sh: no ROS 1 bag: /usr/bin/python3 cannot import rosbag and the message modules" >&2
  status=3
fi
if command -v node >/dev/null && [ -d "$writers/node_modules/@mcap/core" ]; then
  node "$here/write_mcap.mjs" "$out/plan" "$out/drive.mcap" "$writers"
  node "$here/write_mcap.mjs" --check "$out/drive.mcap" "$writers" # read back by @mcap/core and the CDR reader
else
  echo "make_drive.sh: no MCAP bag: needs node and $writers/node_modules (npm ci --no-audit --no-fund there)" >&2
  status=3
fi
exit $status
