#!/usr/bin/env bash
# The ROS 1 node's wiring tested as a ROS package is (issue 37): make_drive_bag's bag of the rendered
# drive, `yawdepth measure --bag` on it (the batch reference, check_measure_truth.py --stats), then a
# private roscore on a free port, /use_sim_time, yawdepth_node with the drive's parameters, the
# checker (check_node_clouds.py: stamps, frames, accuracy against the truth and against measure,
# latency per message, /diagnostics) and `rosbag play --clock` of the bag. The node's logic is the
# library's and tested without ROS; this checks only the wiring.
#
# Two rounds on one master: (A) the motion from /tf, the pan from /joint_states, compressed images,
# the node started by the package's launch file; (B) the same drive recorded as a robot with
# robot_state_publisher records it (make_drive_bag --pan-in-tf --raw-images): the motion from
# /odom, the pan link in /tf (a moving mount, published after the odometry), raw images, the node
# started as rosrun starts it.
#
#   YAWDEPTH=.../yawdepth MAKE_DRIVE_BAG=.../make_drive_bag YAWDEPTH_NODE=.../yawdepth_node \
#     [SERVO_CLIENT=.../servo_depths_client] bash tests/ros/node_bag_test.sh
#
# With SERVO_CLIENT, examples/ros/servo_depths_client asks the node's ~depths service for its own
# KLT features' depths every image, checked against the truth (check_servo_depths.py).
#
# Every step is bounded (BUDGET seconds in all, below ctest's TIMEOUT); every process started here
# runs in its own process group and is stopped on every exit path (EXIT, INT, TERM): INT to the
# group, TERM and KILL after a few seconds, then reaped. Needs ROS 1 (roscore, rosbag, rosparam, rospy,
# sensor_msgs, diagnostic_msgs for /usr/bin/python3). KEEP=1 keeps the temporary folder.
set -euo pipefail
YAWDEPTH=${YAWDEPTH:?set YAWDEPTH}
MAKE_DRIVE_BAG=${MAKE_DRIVE_BAG:?set MAKE_DRIVE_BAG}
YAWDEPTH_NODE=${YAWDEPTH_NODE:?set YAWDEPTH_NODE}
PYTHON=${PYTHON:-/usr/bin/python3}     # ROS 1's Debian packages are /usr/bin/python3's, not pyenv's
export PYTHONDONTWRITEBYTECODE=1       # drive_truth.py imported: no __pycache__ in the source tree
SECONDS_OF_DRIVE=${SECONDS_OF_DRIVE:-4}
BUDGET=${BUDGET:-200}                  # s: the whole test but the cleanup (<= 5 x 6 s), below ctest's 240
STOP_GRACE=4                           # s: INT to TERM when stopping a process group (TERM to KILL: 2 s)
here=$(cd "$(dirname "$0")" && pwd)
start_time=$SECONDS

die() { echo "node_bag_test: FAIL: $*" >&2; exit 1; }
remaining() { echo $((BUDGET - (SECONDS - start_time))); }
# The smaller of $1 and the budget left (at least 1 s).
bounded() { local r; r=$(remaining); [ "$r" -lt "$1" ] && echo $((r > 1 ? r : 1)) || echo "$1"; }

# ROS 1's tools and rospy's messages (tools/bootstrap.sh installs them with the node's packages).
missing=()
for tool in roscore rosparam rosbag roslaunch timeout setsid; do
  command -v "$tool" >/dev/null || missing+=("$tool")
done
"$PYTHON" -c 'import rospy, rosgraph, sensor_msgs.point_cloud2, diagnostic_msgs.msg' 2>/dev/null \
  || missing+=("$PYTHON: rospy sensor_msgs diagnostic_msgs")
[ ${#missing[@]} -eq 0 ] || die "missing: ${missing[*]}"

W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_node_bag.XXXXXX") || exit 1
declare -A pid_of=()
started=()   # names, in start order; each pid is its process group's id (setsid)

# stop NAME: its process group stopped: INT as roslaunch stops nodes (roscpp shuts down cleanly on
# it), TERM, then KILL; reaped.
stop() {
  local pg=${pid_of[$1]} sig grace
  for sig in INT TERM KILL; do
    kill -0 -- "-$pg" 2>/dev/null || break
    [ "$sig" = INT ] || echo "node_bag_test: $1 (group $pg) still running: $sig" >&2
    kill "-$sig" -- "-$pg" 2>/dev/null || true
    [ "$sig" = INT ] && grace=$STOP_GRACE || grace=2
    for _ in $(seq $((grace * 10))); do
      kill -0 -- "-$pg" 2>/dev/null || break
      sleep 0.1
    done
  done
  wait "$pg" 2>/dev/null || true
}
stop_all() {
  local i
  for ((i = ${#started[@]} - 1; i >= 0; --i)); do  # the last started first: roscore last
    stop "${started[i]}"
  done
  started=()
}

cleanup() {
  local rc=$?
  trap - EXIT INT TERM
  set +e
  stop_all
  if [ "$rc" -ne 0 ]; then
    for f in roscore node checker client play node_b checker_b play_b; do
      [ "$f" = "${checker_shown:-}" ] && continue
      [ -s "$W/$f.log" ] && { echo "--- $f.log (last 40 lines)"; tail -n 40 "$W/$f.log"; }
    done
  fi
  if [ -n "${KEEP:-}" ]; then echo "kept $W"; else rm -rf "$W"; fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# start NAME CMD...: CMD in its own process group (setsid: its pid is the group's id), output to
# $W/NAME.log.
start() {
  local name=$1; shift
  setsid "$@" >"$W/$name.log" 2>&1 </dev/null &
  pid_of[$name]=$!
  started+=("$name")
}
alive() { kill -0 "${pid_of[$1]}" 2>/dev/null; }
# The services that must outlive every wait: roscore and the round's node, once started.
services=(roscore node)
services_up() {
  local s
  for s in "${services[@]}"; do
    [ -z "${pid_of[$s]:-}" ] || alive "$s" || die "$s exited (see $s.log)"
  done
}
# wait_for NAME SECONDS DESCRIPTION TEST...: polls TEST until it succeeds; fails when NAME exits or
# after SECONDS (bounded by the budget).
wait_for() {
  local name=$1 limit; limit=$(bounded "$2"); local what=$3; shift 3
  local end=$((SECONDS + limit))
  until "$@" >/dev/null 2>&1; do
    alive "$name" || die "$name exited while waiting for $what (see $name.log)"
    services_up
    [ "$SECONDS" -lt "$end" ] || die "no $what after ${limit} s"
    sleep 0.2
  done
}
# finish NAME SECONDS: waits for NAME to exit (bounded), its exit status in $finished_rc.
finish() {
  local limit; limit=$(bounded "$2"); local end=$((SECONDS + limit))
  while alive "$1"; do
    case $1 in checker*) ;; *) services_up ;; esac  # the checker may outlive a node that died after the bag
    [ "$SECONDS" -lt "$end" ] || die "$1 still running after ${limit} s"
    sleep 0.2
  done
  finished_rc=0
  wait "${pid_of[$1]}" || finished_rc=$?
}

# 1. The bag and measure's numbers on it (as drive_bag_measure.sh measures it).
timeout "$(bounded 60)" "$MAKE_DRIVE_BAG" --out "$W/drive.bag" --truth "$W/truth.json" --seconds "$SECONDS_OF_DRIVE" \
  || die "make_drive_bag"
timeout "$(bounded 60)" "$MAKE_DRIVE_BAG" --out "$W/drive_b.bag" --truth "$W/truth_b.json" \
  --seconds "$SECONDS_OF_DRIVE" --pan-in-tf --raw-images || die "make_drive_bag --pan-in-tf --raw-images"
measure_args=(--bag "$W/drive.bag" --image-topic /camera/image_raw/compressed --tf odom:base_link
              --joint-topic /joint_states --joint pan_joint --joint-axis 0,0,1 --joint-origin 0.1,0,0.3
              --features klt --sigma-px 0.5 --motion-noise absolute --sigma-odom 1e-4 --sigma-rot 1e-4
              --sigma-yaw 1e-4 --time-offset -0.03)
echo "+ yawdepth measure ${measure_args[*]} --out points.csv"
t0=$(date +%s.%N)
timeout "$(bounded 90)" "$YAWDEPTH" measure "${measure_args[@]}" --out "$W/points.csv" 2>"$W/measure.err" \
  || { sed 's/^/  | /' "$W/measure.err"; die "yawdepth measure --bag"; }
echo "measure --bag: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s"
"$PYTHON" "$here/check_measure_truth.py" "$W/truth.json" "$W/points.csv" "$W/measure.err" \
  --label "measure --bag (reference)" --stats "$W/measure_stats" || die "measure's own accuracy (check_measure_truth.py)"

# 2. A private master: a free port, ROS_HOME and the logs in the temporary folder, loopback only.
port=$("$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1 ROS_HOME=$W/ros_home ROS_LOG_DIR=$W/ros_log
unset ROS_HOSTNAME ROS_NAMESPACE
mkdir -p "$ROS_HOME" "$ROS_LOG_DIR"
echo "+ roscore -p $port"
start roscore roscore -p "$port"
wait_for roscore 30 "master at $ROS_MASTER_URI" timeout 5 rosparam get /run_id
timeout 10 rosparam set /use_sim_time true || die "rosparam set /use_sim_time true"

# 3. The node with the drive's parameters (the bag's frames, the pan joint on /joint_states about
# base_link's z through (0.1, 0, 0.3), the 30 ms camera latency; the noise as measure's): through
# the package's launch file when the node's folder is the build tree's ROS package (package.xml and
# launch/ beside it: ROS_PACKAGE_PATH finds it, `roslaunch yawdepth yawdepth.launch`), else the
# executable itself with rosrun's arguments. NODE_START=launch or direct chooses.
node_dir=$(cd "$(dirname "$YAWDEPTH_NODE")" && pwd)
if [ -z "${NODE_START:-}" ]; then
  [ -f "$node_dir/package.xml" ] && [ -f "$node_dir/launch/yawdepth.launch" ] && NODE_START=launch || NODE_START=direct
fi
case $NODE_START in
  launch)
    # YAML 1.1 (roslaunch's) reads 1e-4 as a string: 1.0e-4.
    printf '%s\n' "sigma_px: 0.5" "motion_noise: absolute" "sigma_odom: 1.0e-4" "sigma_rot: 1.0e-4" \
      "sigma_yaw: 1.0e-4" >"$W/node_params.yaml"
    launch_args=(use_sim_time:=true image:=/camera/image_raw image_transport:=compressed motion:=tf
                 world_frame:=odom body_frame:=base_link joint:=pan_joint "joint_axis:=[0, 0, 1]"
                 "joint_origin:=[0.1, 0, 0.3]" camera_latency:=0.03 "params:=$W/node_params.yaml")
    export ROS_PACKAGE_PATH=$node_dir${ROS_PACKAGE_PATH:+:$ROS_PACKAGE_PATH}
    echo "+ ROS_PACKAGE_PATH=$node_dir roslaunch --wait yawdepth yawdepth.launch ${launch_args[*]}"
    # roslaunch starts the node in its own session: its stop timeouts short, so that the node is
    # stopped by roslaunch within this script's stop (INT, then TERM after STOP_GRACE).
    start node roslaunch --wait --sigint-timeout 2 --sigterm-timeout 1 yawdepth yawdepth.launch "${launch_args[@]}"
    ;;
  direct)
    node_args=(image:=/camera/image_raw __name:=yawdepth_node
               _image_transport:=compressed _motion:=tf _world_frame:=odom _body_frame:=base_link
               _joint:=pan_joint _joint_axis:=[0,0,1] _joint_origin:=[0.1,0,0.3] _camera_latency:=0.03
               _sigma_px:=0.5 _motion_noise:=absolute _sigma_odom:=1e-4 _sigma_rot:=1e-4 _sigma_yaw:=1e-4)
    echo "+ yawdepth_node ${node_args[*]}"
    start node "$YAWDEPTH_NODE" "${node_args[@]}"
    ;;
  *) die "NODE_START=$NODE_START: launch or direct" ;;
esac

# 4. The checker, connected to the node's clouds with the node subscribed to its inputs; its own
# deadline 10 s inside ours.
checker_timeout=$(( $(bounded 150) - 10 ))
[ "$checker_timeout" -ge 10 ] || checker_timeout=10
start checker "$PYTHON" "$here/check_node_clouds.py" "$W/truth.json" --measure-stats "$W/measure_stats" \
  --ready "$W/ready" --done "$W/done" --node /yawdepth_node --ready-timeout 45 --timeout "$checker_timeout"
wait_for checker 50 "checker ready (connected to the node, the node subscribed)" test -e "$W/ready"
alive node || die "yawdepth_node exited (see node.log)"

# 4b. The servo client (examples/ros/servo_depths_client, when SERVO_CLIENT is set): ViSP's KLT in the
# images, yawdepth_node's ~depths each image, its answers to a CSV (checked after the bag).
if [ -n "${SERVO_CLIENT:-}" ]; then
  echo "+ servo_depths_client image:=/camera/image_raw _image_transport:=compressed _csv:=depths.csv"
  start client "$SERVO_CLIENT" image:=/camera/image_raw _image_transport:=compressed "_csv:=$W/depths.csv"
  wait_for client 30 "servo client subscribed to the images" \
    bash -c 'rostopic info /camera/image_raw/compressed | grep -q servo_depths_client'
fi

# 5. The bag at its own rate, its clock published (-d: a second after advertising before publishing,
# so the node's and the checker's connections are up for the first messages).
# play_bag NAME BAG NODE DONE: rosbag play of BAG as process NAME; the process NODE must outlive it;
# DONE touched after (the checker's cue).
play_bag() {
  local name=$1 bag=$2 node=$3 done_file=$4
  echo "+ rosbag play --clock -q -d 1 $(basename "$bag")"
  start "$name" timeout -k 5 "$(bounded $((SECONDS_OF_DRIVE + 60)))" rosbag play --clock -q -d 1 "$bag"
  finish "$name" $((SECONDS_OF_DRIVE + 70))
  [ "$finished_rc" -eq 0 ] || die "rosbag play $(basename "$bag"): exit $finished_rc"
  alive "$node" || die "yawdepth_node ($node) exited during the bag (see $node.log)"
  touch "$done_file"
}
play_bag play "$W/drive.bag" node "$W/done"

# The servo client stopped (INT: roscpp shuts down, its CSV flushed) and its answers checked.
if [ -n "${SERVO_CLIENT:-}" ]; then
  alive client || die "servo_depths_client exited during the bag (see client.log)"
  kill -INT -- "-${pid_of[client]}" 2>/dev/null || true
  finish client 15
fi

# 6. The checker's verdict.
# verdict CHECKER ROUND NODE: the checker's exit status (its log shown) and the node's warnings on /rosout.
verdict() {
  local checker=$1 round=$2 node=$3 rc rosout_log
  finish "$checker" 160
  rc=$finished_rc
  echo "--- round $round: $node"
  cat "$W/$checker.log"
  checker_shown=$checker
  # The node's warnings and errors, from /rosout's log (its stdout may be lost to a signal).
  rosout_log=$(ls "$ROS_LOG_DIR"/latest/rosout.log 2>/dev/null || true)
  if [ -n "$rosout_log" ] && grep -E -q " (WARN|ERROR|FATAL) $node " "$rosout_log"; then
    echo "$node's warnings and errors on /rosout (first 20):"
    { grep -E " (WARN|ERROR|FATAL) $node " "$rosout_log" || true; } | head -n 20 | cut -c1-400 | sed 's/^/  | /' || true
  fi
  [ "$rc" -eq 0 ] || die "check_node_clouds.py ($node): exit $rc"
}
verdict checker A /yawdepth_node
alive node || die "yawdepth_node exited before the end (see node.log)"
if [ -n "${SERVO_CLIENT:-}" ]; then
  "$PYTHON" "$here/check_servo_depths.py" "$W/truth.json" "$W/depths.csv" || die "the servo client's depths (check_servo_depths.py)"
fi

# 7. Round B: the node (and the client) of round A stopped; on the same master, a node started as
# rosrun starts it, with the motion from /odom, no joint (the pan link is in /tf: a moving mount),
# raw images; its checker; bag B played.
stop node
[ -z "${SERVO_CLIENT:-}" ] || stop client
services=(roscore node_b)
node_b_args=(image:=/camera/image_raw __name:=yawdepth_odom _motion:=odom _camera_latency:=0.03
             _sigma_px:=0.5 _motion_noise:=absolute _sigma_odom:=1e-4 _sigma_rot:=1e-4 _sigma_yaw:=1e-4)
echo "+ yawdepth_node ${node_b_args[*]}"
start node_b "$YAWDEPTH_NODE" "${node_b_args[@]}"
checker_timeout=$(( $(bounded 100) - 10 ))
[ "$checker_timeout" -ge 10 ] || checker_timeout=10
start checker_b "$PYTHON" "$here/check_node_clouds.py" "$W/truth_b.json" --measure-stats "$W/measure_stats" \
  --ready "$W/ready_b" --done "$W/done_b" --node /yawdepth_odom --image-topic /camera/image_raw \
  --measure-label "measure --bag (round A's bag)" \
  --inputs /camera/image_raw /camera/camera_info /tf /tf_static /odom --ready-timeout 45 --timeout "$checker_timeout"
wait_for checker_b 50 "checker B ready (connected to the node, the node subscribed)" test -e "$W/ready_b"
play_bag play_b "$W/drive_b.bag" node_b "$W/done_b"
verdict checker_b B /yawdepth_odom
alive node_b || die "yawdepth_node (round B) exited before the end (see node_b.log)"
echo "node_bag_test: passed ($((SECONDS - start_time)) s)"
