#!/usr/bin/env bash
# The ROS 1 node's wiring tested as a ROS package is (issue 37): make_drive_bag's bag of the rendered
# drive, `yawdepth measure --bag` on it (the batch reference, check_measure_truth.py --stats), then a
# private roscore on a free port, /use_sim_time, yawdepth_node with the drive's parameters, the
# checker (check_node_clouds.py: stamps, frames, accuracy against the truth and against measure,
# latency per message, /diagnostics) and `rosbag play --clock` of the bag. The node's logic is the
# library's and tested without ROS; this checks only the wiring.
#
#   YAWDEPTH=.../yawdepth MAKE_DRIVE_BAG=.../make_drive_bag YAWDEPTH_NODE=.../yawdepth_node \
#     bash tests/ros/node_bag_test.sh
#
# Every step is bounded (BUDGET seconds in all, below ctest's TIMEOUT); every process started here
# runs in its own process group and is stopped on every exit path (EXIT, INT, TERM): TERM to the
# group, KILL after a few seconds, then reaped. Needs ROS 1 (roscore, rosbag, rosparam, rospy,
# sensor_msgs, diagnostic_msgs for /usr/bin/python3). KEEP=1 keeps the temporary folder.
set -euo pipefail
YAWDEPTH=${YAWDEPTH:?set YAWDEPTH}
MAKE_DRIVE_BAG=${MAKE_DRIVE_BAG:?set MAKE_DRIVE_BAG}
YAWDEPTH_NODE=${YAWDEPTH_NODE:?set YAWDEPTH_NODE}
PYTHON=${PYTHON:-/usr/bin/python3}     # ROS 1's Debian packages are /usr/bin/python3's, not pyenv's
SECONDS_OF_DRIVE=${SECONDS_OF_DRIVE:-4}
BUDGET=${BUDGET:-210}                  # s: the whole test, below ctest's TIMEOUT (240) for the cleanup
STOP_GRACE=5                           # s: TERM to KILL when stopping a process group
here=$(cd "$(dirname "$0")" && pwd)
start_time=$SECONDS

die() { echo "node_bag_test: FAIL: $*" >&2; exit 1; }
remaining() { echo $((BUDGET - (SECONDS - start_time))); }
# The smaller of $1 and the budget left (at least 1 s).
bounded() { local r; r=$(remaining); [ "$r" -lt "$1" ] && echo $((r > 1 ? r : 1)) || echo "$1"; }

W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_node_bag.XXXXXX") || exit 1
declare -A pid_of=()
started=()   # names, in start order; each pid is its process group's id (setsid)

stop_all() {
  local name pg i alive
  for ((i = ${#started[@]} - 1; i >= 0; --i)); do  # the last started first: roscore last
    pg=${pid_of[${started[i]}]}
    kill -TERM -- "-$pg" 2>/dev/null || true
    for _ in $(seq $((STOP_GRACE * 10))); do
      kill -0 -- "-$pg" 2>/dev/null || break
      sleep 0.1
    done
    if kill -0 -- "-$pg" 2>/dev/null; then
      echo "node_bag_test: ${started[i]} (group $pg) still running after TERM + ${STOP_GRACE} s: KILL" >&2
      kill -KILL -- "-$pg" 2>/dev/null || true
    fi
    wait "$pg" 2>/dev/null || true
  done
  started=()
}

cleanup() {
  local rc=$?
  trap - EXIT INT TERM
  set +e
  stop_all
  if [ "$rc" -ne 0 ]; then
    for f in roscore node checker play; do
      [ "$f" = checker ] && [ -n "${checker_shown:-}" ] && continue
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
# wait_for NAME SECONDS DESCRIPTION TEST...: polls TEST until it succeeds; fails when NAME exits or
# after SECONDS (bounded by the budget).
wait_for() {
  local name=$1 limit; limit=$(bounded "$2"); local what=$3; shift 3
  local end=$((SECONDS + limit))
  until "$@" >/dev/null 2>&1; do
    alive "$name" || die "$name exited while waiting for $what (see $name.log)"
    [ "$SECONDS" -lt "$end" ] || die "no $what after ${limit} s"
    sleep 0.2
  done
}
# finish NAME SECONDS: waits for NAME to exit (bounded), its exit status in $finished_rc.
finish() {
  local limit; limit=$(bounded "$2"); local end=$((SECONDS + limit))
  while alive "$1"; do
    [ "$SECONDS" -lt "$end" ] || die "$1 still running after ${limit} s"
    sleep 0.2
  done
  finished_rc=0
  wait "${pid_of[$1]}" || finished_rc=$?
}

# 1. The bag and measure's numbers on it (as drive_bag_measure.sh measures it).
timeout "$(bounded 60)" "$MAKE_DRIVE_BAG" --out "$W/drive.bag" --truth "$W/truth.json" --seconds "$SECONDS_OF_DRIVE" \
  || die "make_drive_bag"
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
# base_link's z through (0.1, 0, 0.3), the 30 ms camera latency; the noise as measure's).
node_args=(image:=/camera/image_raw __name:=yawdepth_node
           _image_transport:=compressed _motion:=tf _world_frame:=odom _body_frame:=base_link
           _joint:=pan_joint _joint_axis:=[0,0,1] _joint_origin:=[0.1,0,0.3] _camera_latency:=0.03
           _sigma_px:=0.5 _motion_noise:=absolute _sigma_odom:=1e-4 _sigma_rot:=1e-4 _sigma_yaw:=1e-4)
echo "+ yawdepth_node ${node_args[*]}"
start node "$YAWDEPTH_NODE" "${node_args[@]}"

# 4. The checker, connected to the node's clouds with the node subscribed to its inputs.
start checker "$PYTHON" "$here/check_node_clouds.py" "$W/truth.json" --measure-stats "$W/measure_stats" \
  --ready "$W/ready" --done "$W/done" --node /yawdepth_node --ready-timeout 45 \
  --timeout "$(( $(bounded 150) - 10 ))"
wait_for checker 50 "checker ready (connected to the node, the node subscribed)" test -e "$W/ready"
alive node || die "yawdepth_node exited (see node.log)"

# 5. The bag at its own rate, its clock published (-d: a second after advertising before publishing,
# so the node's and the checker's connections are up for the first messages).
echo "+ rosbag play --clock -q -d 1 drive.bag"
start play timeout -k 5 "$(bounded $((SECONDS_OF_DRIVE + 60)))" rosbag play --clock -q -d 1 "$W/drive.bag"
finish play $((SECONDS_OF_DRIVE + 70))
[ "$finished_rc" -eq 0 ] || die "rosbag play: exit $finished_rc"
alive node || die "yawdepth_node exited during the bag (see node.log)"
touch "$W/done"

# 6. The checker's verdict.
finish checker 160
checker_rc=$finished_rc
cat "$W/checker.log"
checker_shown=1
if grep -E -q '\[(WARN|ERROR|FATAL)\]' "$W/node.log"; then
  echo "yawdepth_node's warnings and errors (first 20):"
  grep -E '\[(WARN|ERROR|FATAL)\]' "$W/node.log" | head -n 20 | sed 's/^/  | /'
fi
alive node || die "yawdepth_node exited before the end (see node.log)"
[ "$checker_rc" -eq 0 ] || die "check_node_clouds.py: exit $checker_rc"
echo "node_bag_test: passed ($((SECONDS - start_time)) s)"
