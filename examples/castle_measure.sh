#!/usr/bin/env bash
# Natural features on someone else's sequence: Debian's visp-images-data mbt-depth/Castle-simu (40
# rendered 640x480 images of a castle model and a cube, the camera's ground-truth pose cMo per frame)
# measured with the command line alone: its poses turned into a 6-DoF motion log, then
# `yawdepth track` (KLT with the epipolar gate) and `yawdepth estimate` (fused, the residual check
# on), and the same in one go with `yawdepth measure --features klt --ply`. Prints the commands'
# summaries and the cloud's size; bench_castle compares such points with the sequence's depth maps.
# Usage: examples/castle_measure.sh [path/to/yawdepth] [WORKDIR] [DATA]
set -euo pipefail
Y=${1:-build/tools/yawdepth}
W=${2:-$(mktemp -d)}
D=${3:-/usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu}
[ -x "$Y" ] || { echo "castle_measure.sh: $Y not found (build the yawdepth target)" >&2; exit 1; }
[ -d "$D/CameraPose" ] || { echo "castle_measure.sh: $D has no CameraPose folder (apt-get install visp-images-data)" >&2; exit 1; }
mkdir -p "$W"

# The camera (Config/chateau.xml: 700 px, principal point (320, 240), no distortion), as a ViSP camera file.
cat > "$W/castle_camera.xml" <<'EOF'
<?xml version="1.0"?>
<root>
  <camera>
    <name>castle</name>
    <image_width>640</image_width>
    <image_height>480</image_height>
    <model>
      <type>perspectiveProjWithoutDistortion</type>
      <px>700</px>
      <py>700</py>
      <u0>320</u0>
      <v0>240</v0>
    </model>
  </camera>
</root>
EOF
# No pan joint: the camera is the vision frame.
printf 'camera_offset: [0.0, 0.0, 0.0]\n' > "$W/castle_rig.yaml"

# The motion log: each frame's wMc = cMo^-1 (world = the object's frame) as tx,ty,tz and theta-u.
{
  echo "frame,tx,ty,tz,tux,tuy,tuz,image"
  for k in $(seq 1 40); do
    awk -v k="$k" -v img="$(printf '%s/Images/Image_%04d.pgm' "$D" "$k")" '
      NR <= 3 { for (j = 1; j <= 4; ++j) M[NR, j] = $j }
      END {
        for (i = 1; i <= 3; ++i) for (j = 1; j <= 3; ++j) R[i, j] = M[j, i]   # R = (cRo)^T
        for (i = 1; i <= 3; ++i) t[i] = -(R[i, 1] * M[1, 4] + R[i, 2] * M[2, 4] + R[i, 3] * M[3, 4])
        vx = R[3, 2] - R[2, 3]; vy = R[1, 3] - R[3, 1]; vz = R[2, 1] - R[1, 2]
        s = 0.5 * sqrt(vx * vx + vy * vy + vz * vz); c = 0.5 * (R[1, 1] + R[2, 2] + R[3, 3] - 1)
        a = atan2(s, c); f = (s > 1e-12) ? a / (2 * s) : 0.5
        printf "%d,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%s\n", k, t[1], t[2], t[3], f * vx, f * vy, f * vz, img
      }' "$(printf '%s/CameraPose/Camera_%03d.txt' "$D" "$k")"
  done
} > "$W/motion.csv"

# The poses are a renderer's: exact up to their 7 printed digits (0.1 mm and 0.1 mrad per pose).
NOISE=(--motion-noise absolute --sigma-odom 1e-4 --sigma-rot 1e-4)
echo "== yawdepth track"
"$Y" track --camera "$W/castle_camera.xml" --rig "$W/castle_rig.yaml" --motion "$W/motion.csv" \
  --out "$W/tracks.csv" "${NOISE[@]}"
echo "== yawdepth estimate (fused, residual check on)"
"$Y" estimate --camera "$W/castle_camera.xml" --rig "$W/castle_rig.yaml" --motion "$W/motion.csv" \
  --tracks "$W/tracks.csv" --method fused --residual-check on "${NOISE[@]}" --out "$W/points.csv"
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "status") s = i; next } { n[$s]++ }
  END { for (k in n) printf "  %s: %d\n", k, n[k] }' "$W/points.csv" | sort
echo "== yawdepth measure --features klt --ply"
"$Y" measure --camera "$W/castle_camera.xml" --rig "$W/castle_rig.yaml" --motion "$W/motion.csv" --features klt \
  "${NOISE[@]}" --out "$W/points_measure.csv" --ply "$W/castle.ply"
echo "cloud: $W/castle.ply, $(awk '/^element vertex/ { print $3 }' "$W/castle.ply") points"
