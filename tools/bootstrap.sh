#!/usr/bin/env bash
# yawdepth on a fresh Debian 12 machine: install what is missing, build, then
#   tools/bootstrap.sh demo   run the main job (estimate on a generated sequence)
#   tools/bootstrap.sh test   run the whole test suite (what CI runs): the Release build and its
#                             tests, then the same tests built with AddressSanitizer and
#                             UndefinedBehaviorSanitizer ($BUILD_DIR-asan, clang), the libFuzzer
#                             targets for a bounded time, clang-tidy, doxygen
#   tools/bootstrap.sh build  only install and build
# demo and build also install the Python module for Debian's python3 (cmake --install --component python).
# Needs root or sudo when packages are missing or the Python module is installed. BUILD_DIR (default: build), JOBS and
# FUZZ_SECONDS (per fuzz target, default 10) may be set.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${BUILD_DIR:-$here/build}
jobs=${JOBS:-$(nproc)}
asan_dir=$build_dir-asan
fuzz_seconds=${FUZZ_SECONDS:-10}
what=${1:-demo}

packages=(g++ make cmake pkg-config libvisp-dev libopencv-dev libeigen3-dev libapriltag-dev libceres-dev
          catch2 libbenchmark-dev libcli11-dev libyaml-cpp-dev
          clang-14 libclang-rt-14-dev llvm-14 clang-tidy-14 doxygen visp-images-data
          python3-camera-calibration-parsers python3-camera-calibration python3-opencv python3-cv-bridge python3-image-geometry
          librosbag-storage-dev libroscpp-core-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev libtf2-msgs-dev
          libtf2-dev python3-rosbag python3-sensor-msgs python3-nav-msgs python3-geometry-msgs python3-tf2-msgs
          libroscpp-dev libimage-transport-dev libcv-bridge-dev libtf2-ros-dev libvisualization-msgs-dev
          libdiagnostic-msgs-dev libstd-msgs-dev python3-gencpp ros-std-msgs
          python3-roslaunch python3-rosmaster rosout python3-rospy python3-rostopic python3-rosparam
          python3-rosservice python3-rostest python3-diagnostic-msgs python3-visualization-msgs
          libsqlite3-dev libzstd-dev liblz4-dev zlib1g-dev zstd python3-ament-package
          pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest python3-matplotlib)
# The ROS 2 bag writers of the tests (tests/data/bags/writers: @mcap/core and ROS 2's CDR from the npm
# registry) run on Node.js: Debian's, unless the machine has one already.
command -v node >/dev/null && command -v npm >/dev/null || packages+=(nodejs npm)

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

stage() { echo "== bootstrap: $*" >&2; }

# The reference writers of the ROS 2 test bags (tests/data/bags/writers/: @mcap/core and Foxglove's
# CDR serializer, from the npm registry, versions pinned by its package-lock.json), for the
# bag_ros2_writers test, when node and npm are on PATH (that test is skipped otherwise).
install_bag_writers() {
  local dir="$here/tests/data/bags/writers"
  [ -d "$dir/node_modules/@mcap/core" ] && return 0
  (cd "$dir" && npm ci --no-audit --no-fund >/dev/null) ||
    { echo "bootstrap: npm ci in $dir failed (the ROS 2 bag writers of the tests)" >&2; return 1; }
}

# Both trees are unity builds (CMake's UNITY_BUILD: a module's sources compiled as one file), which
# parse ViSP's, OpenCV's and Eigen's headers and instantiate their templates once per module instead
# of once per source: measured, the Release tree's compiler time falls from 15.3 to 11.0 CPU-minutes.
# A developer's own tree (plain cmake) compiles file by file, as usual.
unity=(-DCMAKE_UNITY_BUILD=ON)

configure() {
  cmake -S "$here" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_EXPORT_COMPILE_COMMANDS=ON "${unity[@]}" >/dev/null
}

compile() { cmake --build "$build_dir" -j "$jobs"; }

build() {
  configure
  compile
}

# The Python module (when pybind11 was found) installed where Debian's python3 imports it (the
# prefix's dist-packages, /usr/local by default), so that `python3 -c "import yawdepth"` works after
# `demo` or `build`, as root or with sudo (without a password prompt); otherwise it says how.
install_python() {
  [ -f "$build_dir/python/yawdepth/__init__.py" ] || return 0
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    if ! command -v sudo >/dev/null || ! sudo -n true 2>/dev/null; then
      echo "bootstrap: the Python module is built in $build_dir/python (PYTHONPATH=$build_dir/python);" \
           "install it with: sudo cmake --install $build_dir --component python" >&2
      return 0
    fi
    sudo=(sudo -n)
  fi
  "${sudo[@]}" cmake --install "$build_dir" --component python | sed 's/^/bootstrap: /' >&2
}

demo() {
  # The main job: the paper's experiment rendered (its camera, a 20 mm chessboard 620 mm away) and
  # measured with `yawdepth measure`, beside the paper's numbers (examples/paper_experiment.sh).
  local out="$build_dir/paper_experiment"
  "$here/examples/paper_experiment.sh" "$build_dir/tools/yawdepth" "$out"
  echo "== points measured over the 10 side-view frames ($out/ten/points.csv):"
  cat "$out/ten/points.csv"
}

# ctest with every test's TIMEOUT (tests/CMakeLists.txt; --timeout is only the fallback for a test
# without one). The output is kept in <tree>/ctest.log; a test that timed out is named on stderr.
run_ctest() { # tree
  local tree=$1 rc=0
  ctest --test-dir "$tree" --output-on-failure -j "$jobs" --timeout 600 2>&1 | tee "$tree/ctest.log" || rc=$?
  local timed_out
  timed_out=$(grep -E '\*\*\*Timeout' "$tree/ctest.log" | sed -E 's/^ *[0-9]+\/[0-9]+ Test +#[0-9]+: (.*[^ .]) *\.+ *\*\*\*Timeout.*/\1/' || true)
  if [ -n "$timed_out" ]; then
    echo "bootstrap: these tests timed out (hung, or far slower than they should be):" >&2
    sed 's/^/  /' <<<"$timed_out" >&2
  fi
  return "$rc"
}
run_tests() { run_ctest "$build_dir"; }

# "N passed, M failed" over both test trees (from ctest's "... tests passed, M tests failed out of T"
# lines), each other stage (fuzzing, clang-tidy, doxygen) counting as one check; a tree whose tests
# did not run counts as one failure.
passed=0 failed=0
count_ctest() { # tree
  local line f t
  line=$(grep -E '^[0-9]+% tests passed, [0-9]+ tests? failed out of [0-9]+' "$1/ctest.log" 2>/dev/null | tail -1)
  if [ -z "$line" ]; then
    echo "bootstrap: no ctest summary in $1/ctest.log" >&2
    failed=$((failed + 1))
    return
  fi
  f=$(sed -E 's/.* ([0-9]+) tests? failed out of.*/\1/' <<<"$line")
  t=$(sed -E 's/.* out of ([0-9]+).*/\1/' <<<"$line")
  passed=$((passed + t - f)) failed=$((failed + f))
}

# Sanitizer reports are fatal (-fno-sanitize-recover), with symbolised stacks.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
[ -x /usr/bin/llvm-symbolizer-14 ] && export ASAN_SYMBOLIZER_PATH=/usr/bin/llvm-symbolizer-14

# The libraries and the tests (no command line, no benchmarks, no examples, no ROS node (its logic is
# the online module's, tested here; its wiring is tested in the Release tree), no Python module: its
# tests would need the ASan runtime preloaded into python, and they run in the Release tree) built by clang with
# AddressSanitizer + UndefinedBehaviorSanitizer, and the fuzz targets in the same tree. The
# command-line contract runs in the Release tree only (its file parsers are fuzzed here): CI's
# 20-minute budget on 2 cores does not hold both. Without
# NDEBUG: assertions are on. -O1, and -O2 for the modules with per-pixel loops (YAWDEPTH_HOT_MODULES:
# the instrumented camera model and renderer need Eigen's small fixed-size maths inlined, or the
# rendering tests run ten times slower): measured, the tree builds in 405 s instead of 514 s and its
# tests take as long (179 s against 193 s).
build_sanitized() {
  cmake -S "$here" -B "$asan_dir" -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=Debug "${unity[@]}" \
        -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DYAWDEPTH_HOT_MODULE_OPTIONS=-O2 \
        -DYAWDEPTH_SANITIZE=address,undefined -DYAWDEPTH_BUILD_FUZZERS=ON \
        -DYAWDEPTH_BUILD_BENCHMARKS=OFF -DYAWDEPTH_BUILD_EXAMPLES=OFF -DYAWDEPTH_BUILD_TOOLS=OFF \
        -DYAWDEPTH_PYTHON=OFF -DYAWDEPTH_ROS1=OFF >/dev/null
  cmake --build "$asan_dir" -j "$jobs"
}

run_sanitized_tests() { run_ctest "$asan_dir"; }

# Each fuzz target for FUZZ_SECONDS, up to JOBS at a time, from its seed corpus (fuzz/corpus/) and
# the inputs that once crashed it (tests/data/regress/); new inputs go to $asan_dir/fuzz-corpus,
# a crashing input to $asan_dir/fuzz-artifacts (add it to tests/data/regress/<target>/ once fixed).
run_fuzzers() {
  local targets=() pids=() names=() failed=0 t i
  for t in camera_file rig_file motion_csv tracks_csv recording image_file cdr mcap db3; do
    [ -x "$asan_dir/fuzz/fuzz_$t" ] && targets+=("$t") # the bag readers are built when their libraries are found
  done
  mkdir -p "$asan_dir/fuzz-artifacts"
  for t in "${targets[@]}"; do
    local dirs=("$asan_dir/fuzz-corpus/$t" "$here/fuzz/corpus/$t")
    [ -d "$here/tests/data/regress/$t" ] && dirs+=("$here/tests/data/regress/$t")
    mkdir -p "$asan_dir/fuzz-corpus/$t"
    timeout --kill-after=10 $((fuzz_seconds + 120)) \
      "$asan_dir/fuzz/fuzz_$t" -max_total_time="$fuzz_seconds" -timeout=10 -rss_limit_mb=2048 -max_len=8192 \
        -print_final_stats=1 -artifact_prefix="$asan_dir/fuzz-artifacts/$t-" "${dirs[@]}" \
        >"$asan_dir/fuzz-$t.log" 2>&1 &
    pids+=($!) names+=("$t")
    if ((${#pids[@]} >= jobs)); then
      wait "${pids[0]}" || { failed=1; echo "bootstrap: fuzz_${names[0]} failed:" >&2; tail -40 "$asan_dir/fuzz-${names[0]}.log" >&2; }
      pids=("${pids[@]:1}") names=("${names[@]:1}")
    fi
  done
  for i in "${!pids[@]}"; do
    wait "${pids[$i]}" || { failed=1; echo "bootstrap: fuzz_${names[$i]} failed:" >&2; tail -40 "$asan_dir/fuzz-${names[$i]}.log" >&2; }
  done
  for t in "${targets[@]}"; do
    echo "fuzz_$t: $(grep -m1 -o 'stat::number_of_executed_units: [0-9]*' "$asan_dir/fuzz-$t.log" | awk '{print $2}') runs, corpus $(ls "$asan_dir/fuzz-corpus/$t" | wc -l) new inputs"
  done
  return "$failed"
}

# clang-tidy (.clang-tidy) on the library's own sources: every module's sources (not the command
# line, whose parsing and files the contract test and the fuzzers exercise, nor the tests,
# benchmarks, examples or fuzz targets: CI's 20 minutes on 2 cores do not hold them; run
# `run-clang-tidy-14 -p build tools/yawdepth` by hand when changing the CLI).
# The path-sensitive static analyzer (clang-analyzer-*) runs on the modules that read untrusted
# input (core, io, camera, bag: files, parsers, the camera model, bag containers), file by file, with the compile
# commands of a configure-only tree without unity build (the analyzer starts only from functions of
# the main file, which a unity file's included sources are not). The numerical modules, which the
# sanitizer tests run, get the other checks, one unity file per module from the Release tree (their
# .cpp files are reported through HeaderFilterRegex; the configuration is passed, as a unity file in
# a build tree outside the sources has no .clang-tidy above it): each module's headers and templates
# are then walked once instead of once per source.
# A source the Release tree does not compile (refine_unavailable.cpp, built only without Ceres) has
# no compile command and is skipped.
analyzed_modules='core|io|camera|bag'
run_clang_tidy() {
  local other db="$build_dir/tidy-db"
  other=$(cd "$here/modules" && ls -d */ | tr -d / | grep -v -x -E "$analyzed_modules" | paste -sd '|')
  cmake -S "$here" -B "$db" -DCMAKE_BUILD_TYPE=Release -DCMAKE_EXPORT_COMPILE_COMMANDS=ON -DCMAKE_UNITY_BUILD=OFF \
        -DYAWDEPTH_BUILD_TESTS=OFF -DYAWDEPTH_BUILD_BENCHMARKS=OFF -DYAWDEPTH_BUILD_EXAMPLES=OFF \
        -DYAWDEPTH_BUILD_TOOLS=OFF >/dev/null
  { run-clang-tidy-14 -p "$db" -j "$jobs" -quiet "/modules/($analyzed_modules)/src/[^/]*\.cpp$" &&
    run-clang-tidy-14 -p "$build_dir" -j "$jobs" -quiet -config="$(cat "$here/.clang-tidy")" -checks='-clang-analyzer-*' \
      "/modules/($other)/CMakeFiles/yawdepth_($other)\.dir/Unity/unity_[0-9]+_cxx\.cxx$"
  } >"$build_dir/clang-tidy.log" 2>&1 ||
    { grep -E -A3 '(warning|error):' "$build_dir/clang-tidy.log" >&2 || tail -40 "$build_dir/clang-tidy.log" >&2; return 1; }
  echo "clang-tidy: $(grep -c '^clang-tidy' "$build_dir/clang-tidy.log" || true) files, no findings"
}

# The API documentation of the public headers (Doxyfile); any warning fails.
run_doxygen() {
  mkdir -p "$build_dir/doc"
  (cd "$here" && { cat Doxyfile; echo "OUTPUT_DIRECTORY = $build_dir/doc"; } | doxygen - )
  echo "doxygen: $build_dir/doc/html/index.html"
}

# Runs a stage and reports its time; returns its status without stopping the script.
timed() {
  local t0=$SECONDS rc=0
  stage "$1"
  "${@:2}" || rc=$?
  echo "== bootstrap: $1 $([ "$rc" -eq 0 ] && echo done || echo FAILED) in $((SECONDS - t0)) s" >&2
  return "$rc"
}

# The whole suite. A failed build stops it (nothing to test); a failed test stage does not: every
# stage runs, and the closing line counts them all. Stages run side by side so that no core idles:
# clang-tidy needs only the configured tree's compile commands, so it starts at once, at a lower
# priority (nice), and takes the cores whenever a build or test stage leaves one idle (a link, the
# last large file of a build, the longest tests); the Release tests run beside the sanitizer build.
test_all() {
  local t0=$SECONDS rc_release=0 rc_asan_build=0 rc_asan_tests=0 rc_tidy=0
  install_missing
  install_bag_writers
  configure
  timed "clang-tidy" nice -n 10 bash -c "$(declare -p here build_dir jobs analyzed_modules); $(declare -f run_clang_tidy); run_clang_tidy" \
    >"$build_dir/clang-tidy.out" 2>&1 &
  local pid_tidy=$!
  timed "Release build" compile || { wait "$pid_tidy" || true; echo "0 passed, 1 failed (the Release build failed)"; return 1; }

  timed "Release tests" run_tests >"$build_dir/release-tests.out" 2>&1 &
  local pid_release=$!
  timed "sanitizer build (ASan + UBSan, clang)" build_sanitized >"$build_dir/sanitizer-build.out" 2>&1 || rc_asan_build=$?
  wait "$pid_release" || rc_release=$?
  cat "$build_dir/release-tests.out"
  [ "$rc_asan_build" -eq 0 ] || tail -60 "$build_dir/sanitizer-build.out" >&2
  grep '^== bootstrap' "$build_dir/sanitizer-build.out" >&2 || true
  count_ctest "$build_dir"

  if [ "$rc_asan_build" -eq 0 ]; then
    timed "sanitizer tests" run_sanitized_tests >"$asan_dir/sanitizer-tests.out" 2>&1 || rc_asan_tests=$?
    cat "$asan_dir/sanitizer-tests.out"
    count_ctest "$asan_dir"
    if timed "fuzzing (${fuzz_seconds} s per target)" run_fuzzers; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
  else
    failed=$((failed + 2))
  fi
  wait "$pid_tidy" || rc_tidy=$?
  cat "$build_dir/clang-tidy.out" >&2
  if [ "$rc_tidy" -eq 0 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
  if timed "doxygen" run_doxygen; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
  echo "== bootstrap: the whole suite took $((SECONDS - t0)) s" >&2
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
}

case "$what" in
  demo) install_missing; build; install_python; demo ;;
  test) test_all ;;
  build) install_missing; build; install_python ;;
  *) echo "usage: tools/bootstrap.sh [demo|test|build]" >&2; exit 2 ;;
esac
