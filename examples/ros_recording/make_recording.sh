#!/usr/bin/env bash
# A recording as a ROS robot writes it, of a scene with known truth: ten side-view images of a 20 mm
# chessboard rendered by `yawdepth simulate` (the paper's camera and rig, 8 mm between images), then
# written the way a robot and its tools record them:
#   OUT/groundtruth.txt     the body's poses at 200 Hz as a TUM trajectory, in a REP 103 world
#                           (x forward, y left, z up), base_link axes likewise
#   OUT/groundtruth.csv     the same poses as an EuRoC CSV (nanoseconds)
#   OUT/rgb/                the images at 30 Hz named by their camera timestamps (s), taken 35 ms
#                           after those stamps on the poses' clock (--time-offset 0.035)
#   OUT/cam0/data.csv       the same images as EuRoC lists them (ns), in OUT/cam0/data/
#   OUT/rig.yaml            the camera mount, base_link to the optical frame, as tf_echo prints it
#   OUT/frames/             the scene in yawdepth's own frame-based form (motion.csv, images, truth)
#
#   examples/ros_recording/make_recording.sh [YAWDEPTH_BINARY] [OUT]
#
# Needs python3 (its standard library). The poses between images move at constant velocity, so
# interpolating them back at the images' times is exact: measuring OUT as a recording gives the
# frame-based numbers (tests/recording_cli.sh checks it).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
y=${1:-$here/build/tools/yawdepth}
out=${2:-$here/build/ros_recording}
rig=$here/calib/paper_rig.yaml
rm -rf "$out"
mkdir -p "$out"
"$y" simulate --camera "$here/calib/paper_camera.yaml" --rig "$rig" --out-dir "$out/frames" --frames 10 --step 0.008 \
  --yaw 1.5708 --board-offset-x -0.035 --pattern chessboard:5x4:0.02 --board-distance 0.62 --blur 0.7 --image-noise 2 \
  >/dev/null
python3 - "$out" "$rig" <<'PY'
import csv, math, os, sys
w, rig_path = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(os.path.join(w, "frames", "motion.csv"))))
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
tum = open(os.path.join(w, "groundtruth.txt"), "w"); tum.write("# timestamp tx ty tz qx qy qz qw\n")
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
    src = os.path.join("..", "frames", r["image"])
    os.symlink(src, os.path.join(w, "rgb", "%.6f.png" % t))
    ns = "%d" % round(t * 1e9)
    os.symlink(os.path.join("..", src), os.path.join(w, "cam0", "data", ns + ".png")); lst.write("%s,%s.png\n" % (ns, ns))
# base_link -> camera optical frame: bMc = bMv vMc(yaw), the camera at the paper rig's offset.
off = [float(v) for v in open(rig_path).read().split("[")[1].split("]")[0].split(",")]
yaw = float(rows[0]["yaw"]); Ry = roty(yaw)
R = matmul(T(vRb), Ry); t = matvec(T(vRb), matvec(Ry, off))
tu = thetau(R)
qx, qy, qz, qw = quat(R)
open(os.path.join(w, "rig.yaml"), "w").write(
    "# base_link -> camera_optical_frame, as `rosrun tf tf_echo base_link camera_optical_frame` prints it:\n"
    "# translation [x, y, z] (m), then the quaternion [x, y, z, w]\n"
    "camera_pose: [%.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g]\n" % (t[0], t[1], t[2], qx, qy, qz, qw))
PY
echo "$out: groundtruth.txt (TUM), groundtruth.csv (EuRoC), rgb/ and cam0/ (images by timestamp), rig.yaml"
