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

# The scene in today's form: ten side-view frames 8 mm apart, rendered.
"$YAWDEPTH" simulate --camera "$cam" --rig "$rig" --out-dir "$W/sim" --frames 10 --step 0.008 --yaw 1.5708 \
  --board-offset-x -0.035 --pattern "$pattern" --board-distance 0.62 --blur 0.7 --image-noise 2 >/dev/null ||
  { fail "simulate"; echo "$PASSED passed, $FAILED failed"; exit 1; }

# The same scene as a ROS recording (python3: the poses at 200 Hz between the frames, which move at
# constant velocity, so that interpolating them back is exact; the REP 103 frames; the image names).
python3 - "$W" "$rig" <<'PY' || { fail "writing the recording"; echo "$PASSED passed, $FAILED failed"; exit 1; }
import csv, math, os, sys
w, rig_path = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(os.path.join(w, "sim", "motion.csv"))))
T0, RATE_IMG, RATE_POSE, LATENCY = 1700000000.0, 30.0, 200.0, 0.035
def matmul(a, b): return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
def matvec(a, v): return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]
def T(a): return [[a[j][i] for j in range(3)] for i in range(3)]
def roty(h): c, s = math.cos(h), math.sin(h); return [[c, 0, s], [0, 1, 0], [-s, 0, c]]
def quat(R):  # Hamilton (x, y, z, w)
    tr = R[0][0] + R[1][1] + R[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2; return ((R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s, 0.25 * s)
    i = max(range(3), key=lambda k: R[k][k]); j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1.0 + R[i][i] - R[j][j] - R[k][k]) * 2
    q = [0.0] * 3; q[i] = 0.25 * s; q[j] = (R[j][i] + R[i][j]) / s; q[k] = (R[k][i] + R[i][k]) / s
    return (q[0], q[1], q[2], (R[k][j] - R[j][k]) / s)
def thetau(R):  # from the quaternion: stable at every angle, pi included
    x, y, z, w = quat(R); n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-15: return (0.0, 0.0, 0.0)
    a = 2 * math.atan2(n, w)
    if a > math.pi: a -= 2 * math.pi
    return (a * x / n, a * y / n, a * z / n)
# ROS world W (x forward, y left, z up) from the camera-convention world w; base_link b in the vision frame v.
WRw = [[0, 0, 1], [-1, 0, 0], [0, -1, 0]]
vRb = T(WRw)
f = [float(r["frame"]) for r in rows]
def pose(frame):  # wMv at a fractional frame: constant velocity between (and beyond) the rows
    i = min(max(int(math.floor(frame - f[0])), 0), len(rows) - 2); s = frame - f[i]
    a, b = rows[i], rows[i + 1]
    p = [float(a[k]) + s * (float(b[k]) - float(a[k])) for k in "xyz"]
    h = float(a["heading"]) + s * (float(b["heading"]) - float(a["heading"]))
    return roty(h), p
def ros(frame):
    R, p = pose(frame); return matmul(matmul(WRw, R), vRb), matvec(WRw, p)
t_first = T0 + LATENCY - 0.05; t_last = T0 + LATENCY + (len(rows) - 1) / RATE_IMG + 0.05
n = int(round((t_last - t_first) * RATE_POSE))
tum = open(os.path.join(w, "traj.tum"), "w"); tum.write("# timestamp tx ty tz qx qy qz qw\n")
euroc = open(os.path.join(w, "groundtruth.csv"), "w")
euroc.write("#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n")
for i in range(n + 1):
    t = t_first + i / RATE_POSE
    frame = f[0] + (t - T0 - LATENCY) * RATE_IMG
    R, p = ros(frame); qx, qy, qz, qw = quat(R)
    tum.write("%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n" % (t, p[0], p[1], p[2], qx, qy, qz, qw))
    ns = int(round(t_first * 1e9)) + i * 5000000
    euroc.write("%d,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n" % (ns, p[0], p[1], p[2], qw, qx, qy, qz))
os.makedirs(os.path.join(w, "rgb")); os.makedirs(os.path.join(w, "cam0", "data"))
lst = open(os.path.join(w, "cam0", "data.csv"), "w"); lst.write("#timestamp [ns],filename\n")
for k, r in enumerate(rows):
    t = T0 + k / RATE_IMG
    src = os.path.join(w, "sim", r["image"])
    os.symlink(src, os.path.join(w, "rgb", "%.6f.png" % t))
    ns = "%d" % round(t * 1e9)
    os.symlink(src, os.path.join(w, "cam0", "data", ns + ".png")); lst.write("%s,%s.png\n" % (ns, ns))
# base_link -> camera optical frame: bMc = bMv vMc(yaw), the camera at the paper rig's offset.
off = [float(v) for v in open(rig_path).read().split("[")[1].split("]")[0].split(",")]
yaw = float(rows[0]["yaw"]); Ry = roty(yaw)
R = matmul(T(vRb), Ry); t = matvec(T(vRb), matvec(Ry, off))
tu = thetau(R)
open(os.path.join(w, "rig_ros.yaml"), "w").write("camera_pose: [%.17g, %.17g, %.17g, %.17g, %.17g, %.17g]\n" % (t[0], t[1], t[2], tu[0], tu[1], tu[2]))
PY

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
bad "import: nothing written on error" "needs --images" import --motion "$W/traj.tum" --out-dir "$W/bad.csv"

echo "$PASSED passed, $FAILED failed"
[ "$FAILED" -eq 0 ]
