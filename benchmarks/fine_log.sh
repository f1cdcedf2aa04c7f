#!/usr/bin/env bash
# fine_log.sh: docs/accuracy.md's "fused on long, finely sampled logs" figures. For each seed, a 1000-frame
# log of 0.05 mm steps (our simulator: `yawdepth simulate`, 100 points, yaw 1 rad, odometry noise
# 0.1 mm and 0.05 degree per increment), estimated with each method and the same noise model, and
# every point compared with the truth at the frame it is reported at.
# Usage: benchmarks/fine_log.sh BUILD_DIR [FIRST_SEED LAST_SEED [METHODS]]   (default seeds 1..8, fused)
# Prints per seed and pooled: points, ok, within 2 sigma, coverage, largest |error|/sigma.
set -euo pipefail
build=${1:?usage: fine_log.sh BUILD_DIR [FIRST_SEED LAST_SEED [METHODS]]}
first=${2:-1} last=${3:-8} methods=${4:-fused}
here=$(cd "$(dirname "$0")/.." && pwd)
yd="$build/tools/yawdepth"
[ -x "$yd" ] || { echo "fine_log.sh: $yd not found (build the yawdepth target)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
noise=(--sigma-odom 1e-4 --sigma-heading 0.00087)
printf '%-8s %6s %6s %6s %10s %10s %14s\n' method seed points ok within2 coverage "max|err|/sig"
for m in $methods; do
  : >"$tmp/all.txt"
  for seed in $(seq "$first" "$last"); do
    d="$tmp/s$seed"
    [ -d "$d" ] || "$yd" simulate --camera "$here/calib/paper_camera.yaml" --rig "$here/calib/paper_rig.yaml" \
      --out-dir "$d" --frames 1000 --step 0.00005 --points 100 --yaw 1.0 --seed "$seed" "${noise[@]}" >/dev/null
    "$yd" estimate --camera "$here/calib/paper_camera.yaml" --rig "$here/calib/paper_rig.yaml" \
      --motion "$d/motion.csv" --tracks "$d/tracks.csv" --method "$m" "${noise[@]}" --out "$d/$m.csv" 2>/dev/null
    # truth.csv and the estimate share the columns id,frame,x,y,z,xc,yc,zc,sigma_zc,status.
    awk -F, -v seed="$seed" -v m="$m" '
      FNR == 1 { next }
      NR == FNR { truth[$1 "," $2] = $8; next }
      { n++; if ($10 != "ok") next; ok++; k = $1 "," $2
        if (!(k in truth)) { print "fine_log.sh: no truth for " k > "/dev/stderr"; exit 1 }
        r = ($8 - truth[k]) / $9; if (r < 0) r = -r
        if (r <= 2) within++; if (r > worst) worst = r }
      END { printf "%-8s %6d %6d %6d %6d %10.3f %14.2f\n", m, seed, n, ok, within, ok ? within / ok : 0, worst
            printf "%d %d %d %.6g\n", n, ok, within, worst >> "'"$tmp"'/all.txt" }' "$d/truth.csv" "$d/$m.csv"
  done
  awk -v m="$m" '{ n += $1; ok += $2; w += $3; if ($4 > worst) worst = $4 }
    END { printf "%-8s %6s %6d %6d %6d %10.3f %14.2f\n", m, "all", n, ok, w, ok ? w / ok : 0, worst }' "$tmp/all.txt"
done
