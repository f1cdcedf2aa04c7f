#!/usr/bin/env bash
# yawdepth on a fresh Debian 12 machine: install what is missing, build, then
#   tools/bootstrap.sh demo   run the main job (estimate on a generated sequence)
#   tools/bootstrap.sh test   run the whole test suite (what CI runs)
#   tools/bootstrap.sh build  only install and build
# Needs root or sudo only when packages are missing. BUILD_DIR (default: build) and JOBS may be set.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${BUILD_DIR:-$here/build}
jobs=${JOBS:-$(nproc)}
what=${1:-demo}

packages=(g++ make cmake pkg-config libvisp-dev libopencv-dev libeigen3-dev libapriltag-dev libceres-dev
          catch2 libbenchmark-dev libcli11-dev libyaml-cpp-dev)

install_missing() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  echo "bootstrap: installing ${missing[*]}" >&2
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "bootstrap: need root or sudo to install ${missing[*]}" >&2; exit 1; }
    sudo=(sudo)
  fi
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

build() {
  cmake -S "$here" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build_dir" -j "$jobs"
}

demo() {
  local out="$build_dir/demo" y="$build_dir/tools/yawdepth"
  rm -rf "$out"
  # The paper's camera and rig; the robot drives 10 x 20 mm with the camera at side view, noisy
  # pixels (0.3 px), odometry (1 mm, 0.05 deg) and yaw readings (0.05 deg).
  "$y" simulate --camera "$here/calib/paper_camera.yaml" --rig "$here/calib/paper_rig.yaml" --out-dir "$out" \
      --frames 10 --step 0.02 --yaw 1.5708 --points 12 --min-depth 0.5 --max-depth 2 --seed 7 \
      --sigma-px 0.3 --sigma-odom 0.001 --sigma-heading 0.00087266 --sigma-yaw 0.00087266
  "$y" estimate --camera "$here/calib/paper_camera.yaml" --rig "$here/calib/paper_rig.yaml" \
      --motion "$out/motion.csv" --tracks "$out/tracks.csv" --method exact --out "$out/points.csv"
  echo "== points measured by 'yawdepth estimate --method exact' ($out/points.csv):"
  cat "$out/points.csv"
  echo "== against the truth ($out/truth.csv):"
  awk -F, 'NR==FNR { if (FNR > 1) zt[$1] = $8; next }
           FNR == 1 { next }
           $10 == "ok" { n++; e = ($8 - zt[$1]); se += e * e; me += e; sz += $9 * $9;
                         printf "id %-3s zc %.4f m  true %.4f m  error %+.1f mm  sigma_zc %.1f mm\n", $1, $8, zt[$1], 1000 * e, 1000 * $9 }
           END { if (n) printf "%d points: RMS depth error %.1f mm (mean %+.1f mm: the points share one draw of odometry and yaw noise), RMS predicted sigma %.1f mm\n", n, 1000 * sqrt(se / n), 1000 * me / n, 1000 * sqrt(sz / n) }' \
      "$out/truth.csv" "$out/points.csv"
}

run_tests() {
  ctest --test-dir "$build_dir" --output-on-failure -j "$jobs"
}

case "$what" in
  demo) install_missing; build; demo ;;
  test) install_missing; build; run_tests ;;
  build) install_missing; build ;;
  *) echo "usage: tools/bootstrap.sh [demo|test|build]" >&2; exit 2 ;;
esac
