#!/usr/bin/env bash
# A recording as a robot writes it, measured as it is (docs/formats.md, "Timestamped recordings"):
# one rendered board sequence measured from today's frame-based log, and from the same scene as a
# ROS user has it: poses at 200 Hz in a REP 103 world (x forward, z up) as a TUM trajectory and as
# an EuRoC CSV, images at 30 Hz named by their timestamps (seconds; nanoseconds with EuRoC's
# data.csv) with a camera latency of 35 ms, and the camera mount as base_link -> optical frame. The
# block lengths must agree within 0.1 mm; `import` must give the frame-based log back; bad
# recordings get their one-line reason and nothing written.
#
#   YAWDEPTH=/path/to/yawdepth CALIB=/path/to/calib bash tests/recording_cli.sh
#
# Needs bash, coreutils, awk and python3 (its standard library only).
set -u
YAWDEPTH=${YAWDEPTH:?set YAWDEPTH}
CALIB=${CALIB:?set CALIB}
W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_rec.XXXXXX") || exit 1
trap '[ -n "${KEEP:-}" ] || rm -rf "$W"' EXIT
PASSED=0 FAILED=0
pass() { PASSED=$((PASSED + 1)); }
fail() { FAILED=$((FAILED + 1)); echo "FAIL: $*"; }
check() { local what=$1; shift; if "$@"; then pass; else fail "$what"; fi; }

cam=$CALIB/paper_camera.yaml
rig=$CALIB/paper_rig.yaml
pattern=chessboard:5x4:0.02
exact=(--sigma-px 0.05 --sigma-odom 1e-5 --sigma-heading 1e-6 --sigma-rot 1e-6 --sigma-yaw 1e-6 --quiet)

# The scene, as a ROS recording and in today's frame-based form (examples/ros_recording).
bash "$(dirname "${BASH_SOURCE[0]}")/../examples/ros_recording/make_recording.sh" "$YAWDEPTH" "$W/rec" >/dev/null ||
  { fail "make_recording.sh"; echo "$PASSED passed, $FAILED failed"; exit 1; }
ln -s rec/frames "$W/sim"
for f in groundtruth.txt:traj.tum groundtruth.csv:groundtruth.csv rgb:rgb cam0:cam0 rig.yaml:rig_ros.yaml; do
  ln -s "rec/${f%%:*}" "$W/${f##*:}"
done

blocks() { awk -F, 'NR > 1 { printf "%s %s %s %.9f\n", $1, $2, $3, $4 }' "$1/blocks.csv"; }
same_blocks() { # two report folders: every block, lengths within 0.1 mm
  paste -d' ' <(blocks "$1") <(blocks "$2") |
    awk 'BEGIN { bad = 0 } { if ($1 != $5 || $2 != $6 || $3 != $7) bad = 1; d = $4 - $8; if (d < 0) d = -d; if (d > 1e-4) bad = 1; n++ }
         END { exit (bad || n < 10) }'
}

"$YAWDEPTH" measure --camera "$cam" --rig "$rig" --motion "$W/sim/motion.csv" --pattern "$pattern" "${exact[@]}" \
  --report "$W/frames" --out "$W/frames.csv"
check "measure, frame-based" test -s "$W/frames/blocks.csv"

"$YAWDEPTH" measure --camera "$cam" --rig "$W/rig_ros.yaml" --motion "$W/traj.tum" --images "$W/rgb" --time-offset 0.035 \
  --pattern "$pattern" "${exact[@]}" --report "$W/tum" --out "$W/tum.csv" 2>"$W/tum.err"
check "measure, TUM and timestamped images" test -s "$W/tum/blocks.csv"
check "TUM: block lengths within 0.1 mm of the frame-based log's" same_blocks "$W/frames" "$W/tum"

"$YAWDEPTH" measure --camera "$cam" --rig "$W/rig_ros.yaml" --motion "$W/groundtruth.csv" --images "$W/cam0/data.csv" \
  --time-offset 0.035 --pattern "$pattern" "${exact[@]}" --report "$W/euroc" --out "$W/euroc.csv"
check "EuRoC: block lengths within 0.1 mm of the frame-based log's" same_blocks "$W/frames" "$W/euroc"

# The offset from the rig file; a wrong one moves every pose, and the blocks with them.
cp "$W/rig_ros.yaml" "$W/rig_offset.yaml" && echo "time_offset: 0.035" >>"$W/rig_offset.yaml"
"$YAWDEPTH" measure --camera "$cam" --rig "$W/rig_offset.yaml" --motion "$W/traj.tum" --images "$W/rgb" \
  --pattern "$pattern" "${exact[@]}" --report "$W/rigoff" --out "$W/rigoff.csv"
check "the rig file's time_offset is used" same_blocks "$W/frames" "$W/rigoff"
"$YAWDEPTH" measure --camera "$cam" --rig "$W/rig_ros.yaml" --motion "$W/traj.tum" --images "$W/rgb" --time-offset 0.005 \
  --pattern "$pattern" "${exact[@]}" --report "$W/wrong" --out "$W/wrong.csv" 2>/dev/null
# At constant velocity the relative motion, hence the blocks, cannot tell a time offset; where the
# board is in the world can: 30 ms at 0.24 m/s is 7 mm.
moved() { paste -d, "$1/plane.csv" "$2/plane.csv" | awk -F, 'NR > 1 { d = $3 - $12; if (d < 0) d = -d; if (d > m) m = d } END { exit !(m > 0.005) }'; }
check "a 30 ms error of the offset moves the board in the world" moved "$W/tum" "$W/wrong"
check "TUM and EuRoC put it at one place" bash -c "! { $(declare -f moved); moved '$W/tum' '$W/euroc'; }"

# import: the frame-based log back, with its images and t.
"$YAWDEPTH" import --motion "$W/traj.tum" --images "$W/rgb" --time-offset 0.035 --out-dir "$W/imported" >"$W/import.out"
check "import: writes motion.csv" test -s "$W/imported/motion.csv"
check "import: says what it matched" grep -q "10 images (30.0 Hz), 10 matched" "$W/import.out"
check "import: frame, t and image columns" bash -c "head -1 '$W/imported/motion.csv' | grep -q '^frame,t,tx,ty,tz,tux,tuy,tuz,yaw,image$'"
"$YAWDEPTH" measure --camera "$cam" --rig "$W/rig_ros.yaml" --motion "$W/imported/motion.csv" --pattern "$pattern" \
  "${exact[@]}" --report "$W/imp" --out "$W/imp.csv"
check "import: measure on it gives the same blocks" same_blocks "$W/frames" "$W/imp"

# Bad recordings: one line, status 1, nothing written.
bad() { # what expected-words args...
  local what=$1 words=$2; shift 2
  rm -f "$W/bad.csv"
  "$YAWDEPTH" "$@" >"$W/bad.out" 2>"$W/bad.err"
  local rc=$?
  if [ "$rc" -ne 1 ] || [ "$(wc -l <"$W/bad.err")" -ne 1 ] || ! grep -q -- "$words" "$W/bad.err" || [ -e "$W/bad.csv" ]; then
    fail "$what (rc $rc): $(head -2 "$W/bad.err")"
  else
    pass
  fi
}
m=(measure --camera "$cam" --rig "$W/rig_ros.yaml" --pattern "$pattern" --quiet --out "$W/bad.csv")
bad "TUM without --images" "needs --images" "${m[@]}" --motion "$W/traj.tum"
awk 'NR == 1 { print "t,tx,ty,tz,qx,qy,qz,qw"; next } { printf "%.0f,%s,%s,%s,%s,%s,%s,%s\n", $1 * 1e9, $2, $3, $4, $5, $6, $7, $8 }' \
  "$W/traj.tum" >"$W/ns.csv"
bad "seconds against nanoseconds" "nanoseconds against seconds" "${m[@]}" --motion "$W/ns.csv" --images "$W/rgb"
sed '3s/^[0-9.]*/1699999999.0/' "$W/traj.tum" >"$W/back.tum"
bad "a timestamp that goes back" "back.tum:3: time 1699999999 s goes back" "${m[@]}" --motion "$W/back.tum" --images "$W/rgb"
sed '2s/ [^ ]* [^ ]* [^ ]* [^ ]*$/ 0 0 0 0/' "$W/traj.tum" >"$W/zero.tum"
bad "a quaternion of norm 0" "zero.tum:2: the quaternion (qx, qy, qz, qw) has norm 0" "${m[@]}" --motion "$W/zero.tum" --images "$W/rgb"
mkdir -p "$W/named" && ln -s "$W/sim/frame_0000.png" "$W/named/frame_0000.png"
bad "an image name that is not a timestamp" "frame_0000.png: the image name is not a timestamp" "${m[@]}" --motion "$W/traj.tum" --images "$W/named"
bad "--images with a frame-based log" "is frame-based" "${m[@]}" --motion "$W/sim/motion.csv" --images "$W/rgb"
bad "calibrate-rig --estimate-time-offset on a frame-based log" "needs a timestamped motion log" \
  calibrate-rig --camera "$cam" --motion "$W/sim/motion.csv" --pattern "$pattern" --estimate-time-offset --out "$W/bad.csv"
bad "calibrate-rig --estimate-time-offset: a fit at no offset" "time offset: the calibration failed at every offset" \
  calibrate-rig --camera "$cam" --motion "$W/traj.tum" --images "$W/rgb" --pattern "$pattern" --estimate-time-offset \
  --quiet --out "$W/bad.csv"
bad "calibrate-rig --hand-eye --estimate-time-offset: a planar robot's poses turn about one axis" \
  "time offset: the calibration failed at every offset" \
  calibrate-rig --hand-eye eye-in-hand --camera "$cam" --motion "$W/traj.tum" --images "$W/rgb" --pattern "$pattern" \
  --estimate-time-offset --quiet --out "$W/bad.csv"
bad "import: nothing written on error" "needs --images" import --motion "$W/traj.tum" --out-dir "$W/bad.csv"

echo "$PASSED passed, $FAILED failed"
[ "$FAILED" -eq 0 ]
