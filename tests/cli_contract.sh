#!/usr/bin/env bash
# Command-line contract test for yawdepth (see docs/formats.md).
#
#   YAWDEPTH=/path/to/yawdepth CALIB=/path/to/calib bash tests/cli_contract.sh [SECTION...]
#
# Runs the named sections (SECTIONS below; ctest runs each as cli_contract_SECTION), or all of them
# in order without one. A section makes the files it reads itself when another section makes them
# (the need_* helpers, unchecked: the section that owns them checks them).
# Prints one line per failed check ("FAIL: ...") and ends with "N passed, M failed".
# Exits 0 only when every check passed. Needs bash, coreutils and awk only.

set -u

# The sections, in the order a run without arguments takes them (tests/CMakeLists.txt reads this line).
SECTIONS="exact paper methods measure calibrate status output columns bad_input help error_analysis files six_dof readme usage"
SELECTED="${*:-$SECTIONS}"
for section in $SELECTED; do
  case " $SECTIONS " in
    *" $section "*) ;;
    *) echo "FAIL: unknown section '$section' (one of: $SECTIONS)"; echo "0 passed, 1 failed"; exit 1 ;;
  esac
done

YAWDEPTH=${YAWDEPTH:-}
CALIB=${CALIB:-}
if [ -z "$YAWDEPTH" ] || [ ! -x "$YAWDEPTH" ]; then
  echo "FAIL: YAWDEPTH is not set to an executable (got '$YAWDEPTH')"
  echo "0 passed, 1 failed"
  exit 1
fi
if [ -z "$CALIB" ] || [ ! -d "$CALIB" ]; then
  echo "FAIL: CALIB is not set to a folder (got '$CALIB')"
  echo "0 passed, 1 failed"
  exit 1
fi

XML="$CALIB/paper_camera.xml"
YML="$CALIB/paper_camera.yaml"
RIG="$CALIB/paper_rig.yaml"

W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_cli.XXXXXX") || { echo "FAIL: mktemp"; echo "0 passed, 1 failed"; exit 1; }
trap '[ -n "${KEEP:-}" ] || rm -rf "$W"' EXIT

PASSED=0
FAILED=0
pass() { PASSED=$((PASSED + 1)); }
fail() { FAILED=$((FAILED + 1)); echo "FAIL: $*"; }

# run OUTPREFIX ARGS...: runs yawdepth, stdout/stderr/rc into OUTPREFIX.{out,err,rc}.
run() {
  local p=$1; shift
  { "$YAWDEPTH" "$@" >"$p.out" 2>"$p.err"; } 2>/dev/null
  echo $? >"$p.rc"
}
rc_of() { cat "$1.rc"; }
lines_of() { awk 'END { print NR }' "$1"; }
# first line of a file, for messages
first() { head -n 1 "$1" 2>/dev/null | cut -c 1-200; }

HEADER='id,frame,x,y,z,xc,yc,zc,sigma_zc,status'

# ---------------------------------------------------------------------------
# Files more than one section reads, each made by one function: by the section that checks them,
# and by need_* (unchecked) when a section that only reads them runs without it.

# Section 1's noise-free scenes: sim_CAM_NAME (CAM xml or yaml) with the options of SCENES.
SCENES=(
  "front:--yaw 0"
  "oblique:--yaw 0.7"
  "side:--yaw 1.5708"
  "turning:--yaw 0.3 --turn-rate 0.02"
  "yawrate:--yaw 0.2 --yaw-rate 0.03"
  "lateral:--yaw 0.5 --lateral-step 0.01"
  "seed:--yaw 0.9 --seed 7 --frames 6"
)
# simulate_scene CAM NAME: runs simulate into $W/sim_CAM_NAME (run's files: $W/sim_CAM_NAME.{out,err,rc}).
simulate_scene() {
  local cam=$1 name=$2 sc opts="" camf
  for sc in "${SCENES[@]}"; do [ "${sc%%:*}" = "$name" ] && opts=${sc#*:}; done
  if [ "$cam" = xml ]; then camf=$XML; else camf=$YML; fi
  # shellcheck disable=SC2086
  run "$W/sim_${cam}_$name" simulate --camera "$camf" --rig "$RIG" --out-dir "$W/sim_${cam}_$name" --points 40 $opts
}
need_scene() { [ -s "$W/sim_$1_$2/tracks.csv" ] || simulate_scene "$1" "$2"; }

# The paper's two images (section 2c), an AprilTag board (2c), the README's worked example.
PE="$W/paper_two"
AT="$W/apriltag"
X="$W/worked"
simulate_paper_two() {
  run "$PE.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$PE" --frames 2 --step -0.0565685 --yaw 0.785398 \
      --pattern chessboard:5x4:0.02 --board-distance 0.62 --blur 0.7 --image-noise 2
}
simulate_apriltag() {
  run "$AT.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$AT" --frames 4 --step 0.01 --yaw 1.5708 \
      --pattern apriltag:36h11:0.05 --tags 2x1 --board-distance 0.6 --board-offset-x -0.02 --blur 0.6 --image-noise 1
}
simulate_worked() {
  run "$X.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$X" --frames 10 --step 0.02 --yaw 1.5708 --points 12 \
    --sigma-px 0.3 --sigma-odom 0.001 --sigma-heading 0.00087266 --sigma-yaw 0.00087266
}
need_paper_two() { [ -s "$PE/motion.csv" ] || simulate_paper_two; }
need_apriltag() { [ -s "$AT/motion.csv" ] || simulate_apriltag; }
need_worked() { [ -s "$X/tracks.csv" ] || simulate_worked; }

# The oblique scene's files as the bad-input and files sections read them: D, M, T.
oblique_inputs() {
  need_scene xml oblique
  D="$W/sim_xml_oblique"
  M="$D/motion.csv"; T="$D/tracks.csv"
}

# Section 9's folder of inputs (F, EF) that its refused() checks are never allowed to change; the
# 6-DoF section's refusals use it too.
files_setup() {
  F="$W/files"
  EF=(estimate --camera "$XML" --rig "$RIG" --motion "$F/m.csv" --tracks "$F/t.csv")
  [ -d "$F" ] && return
  oblique_inputs
  mkdir -p "$F"
  cp "$T" "$F/t.csv"; cp "$M" "$F/m.csv"; cp "$F/t.csv" "$F/t.orig"; cp "$F/m.csv" "$F/m.orig"
  ln "$F/t.csv" "$F/t_hard.csv"; ln -s t.csv "$F/t_soft.csv"
}
# refused NAME WORDS ARGS...: non-zero exit, one line on stderr holding WORDS, inputs unchanged.
refused() {
  local name=$1 words=$2; shift 2
  run "$F/$name" "$@"
  local rc; rc=$(rc_of "$F/$name")
  local msg=""
  [ "$rc" -eq 0 ] && msg="$msg exit 0;"
  [ "$rc" -ge 124 ] && msg="$msg exit $rc (crash or timeout);"
  [ "$(lines_of "$F/$name.err")" -ne 1 ] && msg="$msg $(lines_of "$F/$name.err") lines on stderr;"
  grep -q -F -e "$words" "$F/$name.err" || msg="$msg stderr lacks '$words';"
  cmp -s "$F/t.csv" "$F/t.orig" || msg="$msg the tracks input changed;"
  cmp -s "$F/m.csv" "$F/m.orig" || msg="$msg the motion input changed;"
  if [ -z "$msg" ]; then pass; else fail "files $name:$msg stderr: $(first "$F/$name.err")"; fi
  cp "$F/t.orig" "$F/t.csv"; cp "$F/m.orig" "$F/m.csv"
}

# ---------------------------------------------------------------------------
# Points checker (awk). Joins the estimate and the truth on id.
#   est truth tol minfrac -> prints "OK <nok> <nrows>" or a list of problems.
# Relative error: |p_est - p_true| / |p_true| for (xc,yc,zc) and for (x,y,z),
# plus frame equality. Non-ok rows must hold no number in the numeric fields.
compare_points() {
  awk -F, -v tol="$3" -v minfrac="$4" -v hdr="$HEADER" '
    function isnum(s) { return s ~ /^[ \t]*[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?[ \t]*$/ }
    function isempty(s) { return s ~ /^[ \t]*$/ || tolower(s) ~ /^[ \t]*[-+]?nan[ \t]*$/ }
    FNR == 1 {
      if (FILENAME == ARGV[2]) { if ($0 != hdr) { print "estimate header is \"" $0 "\""; bad = 1 } }
      next
    }
    FILENAME == ARGV[1] {
      sub(/\r$/, "")
      tid[$1] = 1; ntruth++
      tf[$1] = $2
      for (k = 3; k <= 8; k++) tv[$1, k] = $k
      next
    }
    {
      sub(/\r$/, "")
      nrows++
      id = $1
      if (id in seen) { print "id " id " appears twice"; bad = 1 }
      seen[id] = 1
      if (NF != 10) { print "row with " NF " fields: " $0; bad = 1; next }
      if (!(id in tid)) { print "id " id " not in truth"; bad = 1; next }
      if ($10 != "ok") {
        for (k = 3; k <= 9; k++) if (!isempty($k)) { print "non-ok row (" $10 ") holds a number in column " k ": " $0; bad = 1; break }
        if ($10 !~ /^[a-z_]+$/) { print "bad status word: " $10; bad = 1 }
        next
      }
      nok++
      for (k = 3; k <= 9; k++) if (!isnum($k)) { print "ok row with non-number in column " k ": " $0; bad = 1; next }
      if ($2 != tf[id]) { print "id " id ": frame " $2 ", truth frame " tf[id]; bad = 1 }
      if (!($9 > 0)) { print "id " id ": sigma_zc not positive: " $9; bad = 1 }
      for (g = 0; g < 2; g++) {
        b = (g == 0) ? 6 : 3
        d2 = 0; n2 = 0
        for (k = b; k < b + 3; k++) { d = $k - tv[id, k]; d2 += d * d; n2 += tv[id, k] * tv[id, k] }
        rel = sqrt(d2) / (n2 > 0 ? sqrt(n2) : 1)
        if (rel > maxrel[g]) maxrel[g] = rel
      }
    }
    END {
      for (i in tid) if (!(i in seen)) { print "truth id " i " missing from estimate"; bad = 1 }
      if (nrows == 0) { print "no rows"; bad = 1 }
      else if (nok < minfrac * nrows) { print "only " nok " of " nrows " rows ok"; bad = 1 }
      if (maxrel[0] > tol) { printf "max relative error of (xc,yc,zc) %.3g > %g\n", maxrel[0], tol; bad = 1 }
      if (maxrel[1] > tol) { printf "max relative error of (x,y,z) %.3g > %g\n", maxrel[1], tol; bad = 1 }
      if (!bad) printf "OK %d %d %.3g %.3g\n", nok, nrows, maxrel[0], maxrel[1]
    }' "$2" "$1"
}

sec_exact() {
# ---------------------------------------------------------------------------
# 1. Noise-free exactness through the CLI (the scenes: SCENES above).
for cam in xml yaml; do
  if [ "$cam" = xml ]; then CAMF=$XML; TOL=1e-9; else CAMF=$YML; TOL=1e-6; fi
  for sc in "${SCENES[@]}"; do
    name=${sc%%:*}; opts=${sc#*:}
    D="$W/sim_${cam}_$name"
    simulate_scene "$cam" "$name"
    if [ "$(rc_of "$W/sim_${cam}_$name")" -ne 0 ]; then
      fail "simulate $cam $name: exit $(rc_of "$W/sim_${cam}_$name"): $(first "$W/sim_${cam}_$name.err")"
      continue
    fi
    missing=""
    for f in motion.csv motion_truth.csv tracks.csv truth.csv; do [ -s "$D/$f" ] || missing="$missing $f"; done
    if [ -n "$missing" ]; then fail "simulate $cam $name: missing output:$missing"; continue; fi
    pass
    if [ "$(head -n 1 "$D/truth.csv" | tr -d '\r')" = "$HEADER" ]; then pass; else fail "simulate $cam $name: truth.csv header is '$(first "$D/truth.csv")'"; fi
    E="$W/est_${cam}_$name"
    run "$E" estimate --method exact --camera "$CAMF" --rig "$RIG" --motion "$D/motion_truth.csv" --tracks "$D/tracks.csv"
    if [ "$(rc_of "$E")" -ne 0 ]; then fail "estimate exact $cam $name: exit $(rc_of "$E"): $(first "$E.err")"; continue; fi
    res=$(compare_points "$E.out" "$D/truth.csv" "$TOL" 0.9)
    case $res in
      OK*) pass ;;
      *) fail "estimate exact $cam $name ($opts): $(echo "$res" | head -n 3 | tr '\n' ';')" ;;
    esac
  done
done
}

sec_paper() {
# ---------------------------------------------------------------------------
# 2. --method paper on a pure-translation scene.
need_scene xml front
D="$W/sim_xml_front"
if [ -s "$D/tracks.csv" ]; then
  run "$W/paper" estimate --method paper --camera "$XML" --rig "$RIG" --motion "$D/motion_truth.csv" --tracks "$D/tracks.csv"
  if [ "$(rc_of "$W/paper")" -ne 0 ]; then
    fail "estimate --method paper: exit $(rc_of "$W/paper"): $(first "$W/paper.err")"
  else
    res=$(awk -F, 'NR > 1 { n++; if ($10 == "ok") { k++; if (!($8 > 0)) neg++ } }
                   END { if (n == 0 || k < 0.9 * n || neg > 0) print "rows " n+0 ", ok " k+0 ", non-positive zc " neg+0; else print "OK" }' "$W/paper.out")
    if [ "$res" = OK ]; then pass; else fail "estimate --method paper front scene: $res"; fi
    if [ "$(head -n 1 "$W/paper.out")" = "$HEADER" ]; then pass; else fail "estimate --method paper: header '$(first "$W/paper.out")'"; fi
  fi
else
  fail "estimate --method paper: no simulated front scene"
fi
}

sec_methods() {
# ---------------------------------------------------------------------------
# 2b. fused and refine: on noise-free data with a tiny noise model they agree with the truth
# (not to round-off: they are statistical estimators with a diffuse prior), and on noisy data
# they run, report ok rows and write the --outliers file.
TINY=(--sigma-px 1e-4 --sigma-odom 1e-8 --sigma-heading 1e-9 --sigma-yaw 1e-9)
need_scene yaml side
need_scene yaml turning
for m in fused window refine; do
  for name in side turning; do
    D="$W/sim_yaml_$name"
    [ -s "$D/tracks.csv" ] || { fail "estimate $m: no simulated $name scene"; continue; }
    E="$W/nf_${m}_$name"
    run "$E" estimate --method "$m" "${TINY[@]}" --camera "$YML" --rig "$RIG" --motion "$D/motion_truth.csv" --tracks "$D/tracks.csv"
    if [ "$(rc_of "$E")" -ne 0 ]; then fail "estimate $m noise-free $name: exit $(rc_of "$E"): $(first "$E.err")"; continue; fi
    res=$(compare_points "$E.out" "$D/truth.csv" 1e-4 0.9)
    case $res in
      OK*) pass ;;
      *) fail "estimate $m noise-free $name: $(echo "$res" | head -n 3 | tr '\n' ';')" ;;
    esac
  done
  N="$W/noisy_$m"
  run "$N.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$N" --points 20 --yaw 1.2 \
      --sigma-px 0.3 --sigma-odom 0.001 --sigma-heading 0.00087 --sigma-yaw 0.00087 --seed 11
  run "$N.est" estimate --method "$m" --camera "$YML" --rig "$RIG" --motion "$N/motion.csv" --tracks "$N/tracks.csv" \
      --out "$N/points.csv" --outliers "$N/outliers.csv" --ply "$N/points.ply"
  # The PLY cloud: a header naming as many vertices as there are ok rows, then one line per vertex
  # (x y z sigma_z id) whose sigma_z and id are those of the points file.
  ply_ok=$(awk 'NR == FNR { if (FNR > 1) { split($0, f, ","); if (f[10] == "ok") { k++; s[f[1]] = f[9] } } next }
                /^element vertex / { n = $3 } /^end_header/ { body = 1; next }
                body { v++; if (!($5 in s) || ($4 - s[$5]) > 1e-9 * s[$5] || (s[$5] - $4) > 1e-9 * s[$5]) bad = 1 }
                END { print (n == k && v == k && k > 0 && !bad) ? "yes" : "no n=" n " v=" v " ok=" k }' \
               FS=, "$N/points.csv" FS=" " "$N/points.ply" 2>&1)
  [ "$ply_ok" = yes ] && pass || fail "estimate $m --ply: $ply_ok"
  if [ "$(rc_of "$N.est")" -eq 0 ] && [ -s "$N/points.csv" ] && [ -s "$N/outliers.csv" ] &&
     [ "$(head -n 1 "$N/outliers.csv" | tr -d '\r')" = "frame,id,u,v" ] &&
     [ "$(awk -F, 'NR > 1 && $10 == "ok" && $9 > 0 { k++ } END { print k+0 }' "$N/points.csv")" -ge 15 ]; then
    pass
  else
    fail "estimate $m on noisy data: exit $(rc_of "$N.est"): $(first "$N.est.err")"
  fi
done

# refine --threads: the same points with 2 solver threads as with 1 (to the printed digits, within
# the solver's tolerance); 0 threads is refused. No progress line when stderr is not a terminal.
N="$W/noisy_refine"
run "$N.t2" estimate --method refine --threads 2 --camera "$YML" --rig "$RIG" --motion "$N/motion.csv" --tracks "$N/tracks.csv"
res=$(compare_points "$N.t2.out" "$N/points.csv" 1e-6 0.9)
if [ "$(rc_of "$N.t2")" -eq 0 ] && [ ! -s "$N.t2.err" ]; then
  case $res in OK*) pass ;; *) fail "refine --threads 2 differs from 1 thread: $(echo "$res" | head -n 2 | tr '\n' ';')" ;; esac
else
  fail "refine --threads 2: exit $(rc_of "$N.t2"), stderr: $(first "$N.t2.err")"
fi
run "$N.t0" estimate --method refine --threads 0 --camera "$YML" --rig "$RIG" --motion "$N/motion.csv" --tracks "$N/tracks.csv"
[ "$(rc_of "$N.t0")" -ne 0 ] && grep -q -- '--threads' "$N.t0.err" && pass || fail "refine --threads 0 accepted"

# fused on a long, finely sampled log (1000 frames of 0.05 mm, 0.1 mm of odometry noise per
# increment): its sigma stays honest, at least 90 % of the `ok` points within 2 sigma of the truth
# (before key frames: 2-sigma coverage 0.1, errors of 20 sigma). Two seeds, front and side view.
for case in "1 0" "5 1.0"; do
  read -r seed yaw <<<"$case"
  F="$W/fine_$seed"
  run "$F.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$F" --frames 1000 --step 0.00005 --points 100 \
    --sigma-odom 1e-4 --sigma-heading 0.00087 --yaw "$yaw" --seed "$seed"
  run "$F.est" estimate --method fused --camera "$YML" --rig "$RIG" --motion "$F/motion.csv" --tracks "$F/tracks.csv" \
    --sigma-odom 1e-4 --sigma-heading 0.00087
  res=$(awk -F, 'FNR == 1 { next } FILENAME == ARGV[1] { z[$1] = $8; next }
    $10 == "ok" { n++; d = $8 - z[$1]; if (d < 0) d = -d; if (d <= 2 * $9) k++ }
    END { if (n == 0) print "none"; else if (k >= 0.9 * n) print "OK " k "/" n; else print "coverage " k "/" n }' \
    "$F/truth.csv" "$F.est.out")
  if [ "$(rc_of "$F.est")" -eq 0 ]; then
    case $res in OK*) pass ;; *) fail "fused on 0.05 mm steps (seed $seed, yaw $yaw): $res within 2 sigma" ;; esac
  else
    fail "fused on 0.05 mm steps: exit $(rc_of "$F.est"): $(first "$F.est.err")"
  fi
done

# An observation no method can use (u = 1e308; v a million pixels off) is taken out and listed in
# --outliers; its feature is estimated from the rest of its track, by every method.
N="$W/noisy_fused"
if [ -s "$N/tracks.csv" ]; then
  awk -F, -v OFS=, 'NR == 1 { print; next } $2 == 3 && !a { $3 = "1e308"; a = 1 } $2 == 4 && !b { $4 = "-1e6"; b = 1 } { print }' \
    "$N/tracks.csv" >"$N/tracks_bad.csv"
  for m in exact paper fused window refine; do
    run "$N.bad_$m" estimate --method "$m" --camera "$YML" --rig "$RIG" --motion "$N/motion.csv" \
        --tracks "$N/tracks_bad.csv" --out "$N/bad_$m.csv" --outliers "$N/bad_out_$m.csv"
    st=$(awk -F, '$1 == 3 || $1 == 4 { s = s $1 ":" $10 " " } END { print s }' "$N/bad_$m.csv" 2>/dev/null)
    listed=$(awk -F, '($2 == 3 && $3 + 0 > 1e300) || ($2 == 4 && $4 + 0 < -1e5) { k++ } END { print k + 0 }' "$N/bad_out_$m.csv" 2>/dev/null)
    if [ "$(rc_of "$N.bad_$m")" -eq 0 ] && [ "$st" = "3:ok 4:ok " ] && [ "$listed" -eq 2 ]; then
      pass
    else
      fail "estimate $m with an unusable observation: exit $(rc_of "$N.bad_$m"), statuses '$st', listed $listed: $(first "$N.bad_$m.err")"
    fi
  done
  # A noise model that is too tight for the data (no motion noise on dead-reckoned motion): fused
  # rejects the observations and says so ("inconsistent"), never "too_few_frames" for long tracks,
  # and the whole-log check warns that the tracks do not fit the model.
  run "$N.tight" estimate --method fused --camera "$YML" --rig "$RIG" --motion "$N/motion.csv" --tracks "$N/tracks.csv" \
      --sigma-odom 0 --sigma-heading 0 --sigma-yaw 0
  words=$(awk -F, 'NR > 1 { print $10 }' "$N.tight.out" | sort -u | paste -sd ' ')
  long_few=$(awk -F, 'NR == FNR { if (FNR > 1) n[$2]++; next } FNR > 1 && $10 == "too_few_frames" && n[$1] >= 3 { k++ }
                      END { print k + 0 }' "$N/tracks.csv" "$N.tight.out")
  if [ "$(rc_of "$N.tight")" -eq 0 ] && [ "$long_few" -eq 0 ] && grep -q inconsistent "$N.tight.out" &&
     [ "$(wc -l <"$N.tight.err")" -eq 1 ] && grep -q "warning: the tracks do not fit the motion log" "$N.tight.err"; then
    pass
  else
    fail "estimate fused with a too tight noise model: exit $(rc_of "$N.tight"), statuses '$words', $long_few long tracks too_few_frames: $(first "$N.tight.err")"
  fi
else
  fail "estimate: no noisy fused scene for the unusable-observation check"
fi

# A motion row that no motion can be (z = 1e6 m, a heading or yaw of 1e9 rad) is refused with the
# row named, by estimate, measure and track; nothing is written.
N="$W/noisy_fused"
for col in z heading yaw; do
  awk -F, -v OFS=, -v c="$col" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i; print; next }
                               NR == 6 { $k = ($k ~ /./ && c == "z") ? "1e6" : "1e9" } { print }' \
    "$N/motion.csv" >"$N/motion_jump_$col.csv"
  run "$N.jump_$col" estimate --method exact --camera "$YML" --rig "$RIG" --motion "$N/motion_jump_$col.csv" \
      --tracks "$N/tracks.csv" --out "$N/jump_$col.csv"
  if [ "$(rc_of "$N.jump_$col")" -ne 0 ] && [ ! -e "$N/jump_$col.csv" ] && [ "$(lines_of "$N.jump_$col.err")" -eq 1 ] &&
     grep -q "the row of frame" "$N.jump_$col.err"; then
    pass
  else
    fail "estimate with a motion jump in $col: exit $(rc_of "$N.jump_$col"): $(first "$N.jump_$col.err")"
  fi
done
run "$N.jump_track" track --camera "$YML" --rig "$RIG" --motion "$N/motion_jump_z.csv" --out "$N/jump_track.csv"
[ "$(rc_of "$N.jump_track")" -ne 0 ] && [ ! -e "$N/jump_track.csv" ] && grep -q "the row of frame" "$N.jump_track.err" &&
  pass || fail "track with a motion jump: exit $(rc_of "$N.jump_track"): $(first "$N.jump_track.err")"
}

sec_measure() {
# ---------------------------------------------------------------------------
# 2c. measure on rendered images: the paper's two images (chessboard) and an AprilTag board.
simulate_paper_two
run "$PE.m" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PE/motion.csv" --pattern chessboard:5x4:0.02 \
    --sigma-px 0.05 --sigma-odom 1e-5 --sigma-heading 1e-6 --sigma-yaw 1e-6 --report "$PE/report" --out "$PE/points.csv" \
    --ply "$PE/points.ply"
# measure's cloud carries the gray level at each corner (a chessboard corner is mid-gray).
grep -q '^property uchar red$' "$PE/points.ply" 2>/dev/null &&
  awk '/^end_header/ { b = 1; next } b { n++; if ($4 < 30 || $4 > 225 || $4 != $5 || $4 != $6) bad = 1 } END { exit !(n == 20 && !bad) }' \
    "$PE/points.ply" && pass || fail "measure --ply: no gray colour, or not 20 mid-gray vertices"
# track: natural corners of the same two images, gated by the motion; measure --features klt in one go.
run "$PE.t" track --camera "$YML" --rig "$RIG" --motion "$PE/motion.csv" --out "$PE/klt.csv"
if [ "$(rc_of "$PE.t")" -eq 0 ] && [ "$(head -n 1 "$PE/klt.csv" | tr -d '\r')" = "frame,id,u,v" ] &&
   [ "$(awk -F, 'NR > 1 && $1 != f0 { n++ } NR == 2 { f0 = $1 } END { print n + 0 }' "$PE/klt.csv")" -ge 10 ]; then
  pass
else
  fail "track on the paper's two images: exit $(rc_of "$PE.t"): $(first "$PE.t.err")"
fi
# measure --features klt on 8 frames of 8 mm (the two images above are 98 px apart: too far for KLT on
# a chessboard's repeated corners): ok points on the board (at 0.66 m in the last camera; the median,
# as features on the noise of flat areas are not points), and the report's pictures.
PK="$W/klt_board"
run "$PK.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$PK" --frames 8 --step -0.008 --yaw 0.785398 \
    --pattern chessboard:5x4:0.02 --board-distance 0.62 --blur 0.7 --image-noise 2
run "$PK.k" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion.csv" --features klt --sigma-odom 1e-5 \
    --sigma-heading 1e-6 --sigma-yaw 1e-6 --out "$PK/points.csv" --report "$PK/report"
res=$(awk -F, 'NR > 1 && $10 == "ok" { print $8 }' "$PK/points.csv" 2>/dev/null | sort -g |
  awk '{ z[NR] = $1 } END { if (NR < 20) { print NR + 0 " ok"; exit }
    m = z[int((NR + 1) / 2)]; print (m > 0.64 && m < 0.68) ? "OK" : "median zc " m }')
if [ "$(rc_of "$PK.k")" -eq 0 ] && [ "$res" = OK ]; then pass; else
  fail "measure --features klt: exit $(rc_of "$PK.k"), $res: $(first "$PK.k.err")"; fi
[ -s "$PK/report/report.txt" ] && [ -s "$PK/report/overlay.png" ] && [ -s "$PK/report/top_view.png" ] &&
  grep -q '^  ok: ' "$PK/report/report.txt" && pass || fail "measure --features klt --report: report files missing"
# --video: the same images as a numbered sequence (vpVideoReader), the log without its image column:
# the same tracks; a log longer than the video is an error that says so, and nothing is written.
cut -d, -f1-6 "$PK/motion.csv" > "$PK/motion_noimg.csv"
run "$PK.ti" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion.csv" --out "$PK/tracks_img.csv"
run "$PK.tv" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --video "$PK/frame_%04d.png" \
    --out "$PK/tracks_video.csv"
[ "$(rc_of "$PK.ti")" -eq 0 ] && [ "$(rc_of "$PK.tv")" -eq 0 ] && cmp -s "$PK/tracks_img.csv" "$PK/tracks_video.csv" &&
  pass || fail "track --video: exit $(rc_of "$PK.tv"), tracks differ from the images': $(first "$PK.tv.err")"
{ cat "$PK/motion_noimg.csv"; tail -n +2 "$PK/motion_noimg.csv" | awk -F, -v OFS=, '{ $1 = $1 + 8; $4 = $4 - 0.064; print }'; } \
  > "$PK/motion_long.csv"
run "$PK.tl" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_long.csv" --video "$PK/frame_%04d.png" \
    --out "$PK/tracks_long.csv"
[ "$(rc_of "$PK.tl")" -eq 1 ] && [ ! -e "$PK/tracks_long.csv" ] && [ "$(wc -l < "$PK.tl.err")" -eq 1 ] &&
  grep -q "ended after 8 frames; the motion log has 16 rows" "$PK.tl.err" && pass ||
  fail "track --video shorter than the log: exit $(rc_of "$PK.tl"): $(first "$PK.tl.err")"
cp "$PK/frame_0003.png" "$PK/frame_0003.keep"
run "$PK.to" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --video "$PK/frame_%04d.png" \
    --out "$PK/frame_0003.png"
[ "$(rc_of "$PK.to")" -eq 1 ] && cmp -s "$PK/frame_0003.png" "$PK/frame_0003.keep" && grep -q "refusing to overwrite" "$PK.to.err" &&
  pass || fail "track --out onto a frame of its --video sequence: exit $(rc_of "$PK.to"), not refused: $(first "$PK.to.err")"
run "$PK.mv" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion.csv" --pattern chessboard:5x4:0.02 \
    --video "$PK/frame_%04d.png"
[ "$(rc_of "$PK.mv")" -eq 1 ] && grep -q "needs --features klt" "$PK.mv.err" && pass ||
  fail "measure --pattern --video: exit $(rc_of "$PK.mv"), not refused: $(first "$PK.mv.err")"
run "$PK.kv" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --features klt \
    --video "$PK/frame_%04d.png" --sigma-odom 1e-5 --sigma-heading 1e-6 --sigma-yaw 1e-6 --out "$PK/points_video.csv" \
    --report "$PK/report_video"
[ "$(rc_of "$PK.kv")" -eq 0 ] && cmp -s "$PK/points.csv" "$PK/points_video.csv" && [ -s "$PK/report_video/overlay.png" ] &&
  pass || fail "measure --features klt --video: exit $(rc_of "$PK.kv"), points differ: $(first "$PK.kv.err")"
# one_line NAME PREFIX TEXT: the run PREFIX failed with status 1 and exactly one stderr line holding TEXT.
one_line() {
  [ "$(rc_of "$2")" -eq 1 ] && [ "$(lines_of "$2.err")" -eq 1 ] && grep -qF -- "$3" "$2.err" && pass ||
    fail "$1: exit $(rc_of "$2"), $(lines_of "$2.err") stderr lines: $(first "$2.err")"
}
# Bad images and videos (issue #38): a truncated JPEG in the log's image column, a gap in a numbered
# sequence, a bad pattern, a folder, a file that is no movie: each one line, nothing written.
SMALLJPG="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/data/images/small.jpg"
head -c 600 "$SMALLJPG" > "$PK/cut.jpg"
awk -F, -v OFS=, 'NR > 1 && $1 == 3 { $7 = "cut.jpg" } { print }' "$PK/motion.csv" > "$PK/motion_cutjpg.csv"
run "$PK.cj" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_cutjpg.csv" --out "$PK/tracks_cutjpg.csv"
one_line "track on a truncated JPEG" "$PK.cj" "cut.jpg: cannot read image (a truncated JPEG"
[ ! -e "$PK/tracks_cutjpg.csv" ] && pass || fail "track on a truncated JPEG wrote its output"
run "$PK.mj" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_cutjpg.csv" --features klt \
    --out "$PK/points_cutjpg.csv"
one_line "measure --features klt on a truncated JPEG" "$PK.mj" "cut.jpg: cannot read image (a truncated JPEG"
cp "$SMALLJPG" "$PK/whole.jpg"
awk -F, -v OFS=, 'NR > 1 && $1 == 3 { $7 = "whole.jpg" } { print }' "$PK/motion.csv" > "$PK/motion_wholejpg.csv"
run "$PK.wj" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_wholejpg.csv" --out "$PK/tracks_wholejpg.csv"
one_line "track on a whole JPEG of another size" "$PK.wj" "whole.jpg: image is 32x24 but the camera is"
mkdir -p "$PK/gap"
cp "$PK"/frame_000[0-7].png "$PK/gap/" && rm -f "$PK/gap/frame_0003.png"
run "$PK.gap" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --video "$PK/gap/frame_%04d.png" \
    --out "$PK/tracks_gap.csv"
one_line "track --video with a gap" "$PK.gap" "frame_0003.png: missing from the numbered image sequence"
[ ! -e "$PK/tracks_gap.csv" ] && pass || fail "track --video with a gap wrote its output"
for pat in 'x_%999999999d.png' 'x_%04d_%d.png' 'x_%s.png'; do
  run "$PK.pat" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --video "$PK/$pat" \
      --out "$PK/tracks_pat.csv"
  one_line "track --video $pat" "$PK.pat" "--video $PK/$pat: not a numbered image sequence"
  grep -q "NFA" "$PK.pat.err" && fail "track --video $pat: std::regex's message: $(first "$PK.pat.err")"
done
run "$PK.dir" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --video "$PK/gap" \
    --out "$PK/tracks_dir.csv"
one_line "track --video FOLDER" "$PK.dir" "is a folder, not a video file (give a video file, or a numbered image sequence"
printf 'RIFF\020\000\000\000AVI LIST\004\000\000\000hdrlnot a movie' > "$PK/junk.avi"
head -c 3000 "$PK/frame_0000.png" > "$PK/junk.mp4"
for v in junk.avi junk.mp4; do
  run "$PK.jv" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion_noimg.csv" --video "$PK/$v" \
      --out "$PK/tracks_junk.csv"
  one_line "track --video $v (not a movie)" "$PK.jv" "$PK/$v: cannot open"
done
# Output names of 245 to 255 bytes: the temporary file beside them must fit too.
for len in 245 255; do
  long=$(printf "%0$((len - 4))d.csv" 0)
  run "$PK.long" track --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion.csv" --out "$PK/$long"
  [ "$(rc_of "$PK.long")" -eq 0 ] && cmp -s "$PK/$long" "$PK/tracks_img.csv" && pass ||
    fail "track --out of a $len-byte name: exit $(rc_of "$PK.long"): $(first "$PK.long.err")"
done
# '-' is standard output for estimate's and measure's --out only; --ply - is refused (no file named '-').
mkdir -p "$PK/cwd"
ABS_YML=$(realpath "$YML") ABS_RIG=$(realpath "$RIG")
(YAWDEPTH=$(realpath "$YAWDEPTH") && cd "$PK/cwd" &&
  run "$PK.ply" measure --quiet --camera "$ABS_YML" --rig "$ABS_RIG" --motion "$PK/motion.csv" --features klt \
      --out "$PK/points_plydash.csv" --ply - &&
  run "$PK.td" track --quiet --camera "$ABS_YML" --rig "$ABS_RIG" --motion "$PK/motion.csv" --out -)
one_line "measure --ply -" "$PK.ply" "--ply -: standard output cannot take this output"
one_line "track --out -" "$PK.td" "--out -: standard output cannot take this output"
[ -z "$(ls -A "$PK/cwd")" ] && [ ! -e "$PK/points_plydash.csv" ] && pass || fail "--ply - or --out - wrote a file"
# --residual-check off keeps every track the method found ok; on (the default here) cuts some.
run "$PK.ko" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PK/motion.csv" --features klt --sigma-odom 1e-5 \
    --sigma-heading 1e-6 --sigma-yaw 1e-6 --residual-check off --out "$PK/points_off.csv"
a=$(awk -F, 'NR > 1 && $10 == "inconsistent" { k++ } END { print k + 0 }' "$PK/points.csv" 2>/dev/null)
b=$(awk -F, 'NR > 1 && $10 == "inconsistent" { k++ } END { print k + 0 }' "$PK/points_off.csv" 2>/dev/null)
[ "$(rc_of "$PK.ko")" -eq 0 ] && [ "${a:-0}" -gt "${b:-0}" ] && pass ||
  fail "measure --features klt --residual-check off: exit $(rc_of "$PK.ko"), inconsistent $a (on) vs $b (off)"
if [ "$(rc_of "$PE.m")" -eq 0 ] && [ -s "$PE/report/figure.png" ] && [ -s "$PE/report/report.txt" ]; then pass; else
  fail "measure paper setup: exit $(rc_of "$PE.m"): $(first "$PE.m.err")"; fi
res=$(awk -F, 'NR > 1 && $10 == "ok" { k++ } END { print k+0 }' "$PE/points.csv" 2>/dev/null)
if [ "$res" = 20 ]; then pass; else fail "measure paper setup: $res of 20 corners ok"; fi
res=$(awk -F, 'NR > 1 { e = $5; if (e < 0) e = -e; if (e > w) w = e; n++ } END { if (n == 31 && w < 0.0003) print "OK"; else print n " blocks, worst error " w " m" }' "$PE/report/blocks.csv" 2>/dev/null)
if [ "$res" = OK ]; then pass; else fail "measure paper setup block lengths: $res"; fi
res=$(compare_points "$PE/points.csv" "$PE/truth.csv" 2e-3 0.99)
case $res in OK*) pass ;; *) fail "measure paper setup against truth: $(echo "$res" | head -n 2 | tr '\n' ';')" ;; esac

# The same on photo-like renders (JPEG, gamma, vignetting, Bayer, defocus) of a board whose outer
# squares are half as wide: every corner found and measured, blocks within 0.3 mm.
PH="$W/paper_photo"
run "$PH.sim" simulate --camera "$YML" --rig "$RIG" --out-dir "$PH" --frames 2 --step -0.0565685 --yaw 0.785398 \
    --pattern chessboard:5x4:0.02 --board-distance 0.62 --photo --outer-square 0.01
run "$PH.m" measure --quiet --camera "$YML" --rig "$RIG" --motion "$PH/motion.csv" --pattern chessboard:5x4:0.02 \
    --sigma-px 0.05 --sigma-odom 1e-5 --sigma-heading 1e-6 --sigma-yaw 1e-6 --report "$PH/report" --out "$PH/points.csv" \
    --debug-dir "$PH/debug"
if [ -s "$PH/debug/0000_frame_0000.png" ] && [ -s "$PH/debug/0001_frame_0001.png" ]; then pass; else
  fail "measure --debug-dir: pictures missing: $(ls "$PH/debug" 2>&1 | tr '\n' ' ')"; fi
res=$(awk -F, 'NR > 1 && $10 == "ok" { k++ } END { print k+0 }' "$PH/points.csv" 2>/dev/null)
if [ "$(rc_of "$PH.m")" -eq 0 ] && [ "$res" = 20 ]; then pass; else
  fail "measure on photo-like renders: exit $(rc_of "$PH.m"), $res of 20 corners ok: $(first "$PH.m.err")"; fi
res=$(awk -F, 'NR > 1 { e = $5; if (e < 0) e = -e; if (e > w) w = e; n++ } END { if (n == 31 && w < 0.0003) print "OK"; else print n " blocks, worst error " w " m" }' "$PH/report/blocks.csv" 2>/dev/null)
if [ "$res" = OK ]; then pass; else fail "measure on photo-like renders, block lengths: $res"; fi
run "$PH.bad" simulate --camera "$YML" --rig "$RIG" --out-dir "$W/photo_bad" --frames 2 --pattern chessboard:5x4:0.02 --outer-square 0.03
if [ "$(rc_of "$PH.bad")" -ne 0 ] && [ "$(wc -l < "$PH.bad.err")" -eq 1 ] && grep -q "outer" "$PH.bad.err"; then pass; else
  fail "simulate --outer-square wider than a square: exit $(rc_of "$PH.bad"): $(first "$PH.bad.err")"; fi

simulate_apriltag
run "$AT.m" measure --quiet --camera "$YML" --rig "$RIG" --motion "$AT/motion.csv" --pattern apriltag:36h11:0.05 \
    --sigma-px 0.2 --sigma-odom 1e-5 --sigma-heading 1e-6 --sigma-yaw 1e-6 --out "$AT/points.csv"
res=$(awk -F, 'NR > 1 && $10 == "ok" { k++; if ($1 % 5 == 0) c++ } END { print k+0, c+0 }' "$AT/points.csv" 2>/dev/null)
if [ "$(rc_of "$AT.m")" -eq 0 ] && [ "$res" = "10 2" ]; then pass; else
  fail "measure apriltag 2 tags: exit $(rc_of "$AT.m"), ok rows and centres: $res; $(first "$AT.m.err")"; fi
res=$(compare_points "$AT/points.csv" "$AT/truth.csv" 1e-2 0.99)
case $res in OK*) pass ;; *) fail "measure apriltag against truth: $(echo "$res" | head -n 2 | tr '\n' ';')" ;; esac
}

sec_calibrate() {
# ---------------------------------------------------------------------------
# 2d. calibrate-camera on real photographs (tests/data/franka-eye-in-hand, 8 PNG, 9x6 board):
# every image used, the distortion model chosen and said, a picture per image in --debug-dir, the
# RMS within 5 % of OpenCV's 0.245 px (cornerSubPix 11x11, 5 coefficients, same photos: a model
# that does not invert at the image's corners, which yawdepth does not write), and a camera file
# that yawdepth itself reads back.
FR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/data/franka-eye-in-hand"
need_scene xml front # calibrate-rig --hand-eye with a planar log, below
run "$W/franka" calibrate-camera --pattern chessboard:9x6:0.0236 --out "$W/franka_cam" --debug-dir "$W/franka_debug" \
    "$FR"/franka_image-[1-8].png
res=$(awk '/^RMS reprojection error:/ { if ($4 + 0 > 0 && $4 + 0 <= 0.257 && $6 == "(8") print "OK"; else print $0 }' "$W/franka.out")
if [ "$(rc_of "$W/franka")" -eq 0 ] && [ "$res" = OK ]; then pass; else
  fail "calibrate-camera on the franka photos: exit $(rc_of "$W/franka"): $res $(first "$W/franka.err")"; fi
grep -q "^Distortion model: k1" "$W/franka.out" && grep -q "on views left out" "$W/franka.out" && \
  grep -q "^Projection uncertainty" "$W/franka.out" && pass || fail "calibrate-camera: model choice or uncertainty not printed"
[ "$(ls "$W/franka_debug" | wc -l)" -eq 8 ] && pass || fail "calibrate-camera --debug-dir: $(ls "$W/franka_debug" | wc -l) pictures for 8 images"
# Hand-eye calibration from the arm's poses (motion.csv: rMe per photo): ViSP's published eMc
# (0.0577148, -0.0339261, -0.0422745) within 5 mm, and the rig file it writes is a camera_pose.
run "$W/handeye" calibrate-rig --hand-eye eye-in-hand --camera "$W/franka_cam.yaml" --motion "$FR/motion.csv" \
    --pattern chessboard:9x6:0.0236 --out "$W/eMc.yaml"
res=$(awk -F'[][, ]+' '/^camera_pose:/ { dx = $2 - 0.0577148; dy = $3 + 0.0339261; dz = $4 + 0.0422745;
        d = sqrt(dx * dx + dy * dy + dz * dz); if (d < 0.005) print "OK"; else print "distance " d }' "$W/eMc.yaml")
if [ "$(rc_of "$W/handeye")" -eq 0 ] && [ "$res" = OK ]; then pass; else
  fail "calibrate-rig --hand-eye on the franka photos: exit $(rc_of "$W/handeye"): $res $(first "$W/handeye.err")"; fi
# The board scale check's line (docs/formats.md, calibrate-rig: "The board's size").
grep -q "^board scale (from the hand's motion): [0-9.]* +- [0-9.]* times the size given (\(consistent\|mismatch\|unconfirmed\))" \
  "$W/handeye.out" && pass || fail "calibrate-rig --hand-eye: no board scale line: $(grep scale "$W/handeye.out")"
# The board measured from the arm's motion alone (measure, 6-DoF log, the calibrated hand-eye pose, per-pose
# kinematic noise): the report's block lengths within 0.3 mm of 23.6 at the median and the board's origin within
# 5 mm of ViSP's published rMo (0.5364858, 0.1239457, 0.0915574) (the README's franka table has the figures).
run "$W/franka_measure" measure --camera "$W/franka_cam.yaml" --rig "$W/eMc.yaml" --motion "$FR/motion.csv" \
    --pattern chessboard:9x6:0.0236 --motion-noise absolute --report "$W/franka_report" --quiet
res=$(awk '/^all block lengths:/ { m = $5 } /^board pose in the world:/ { gsub(/[(),]/, " "); dx = $8 - 536.4858;
        dy = $9 - 123.9457; dz = $10 - 91.5574; d = sqrt(dx * dx + dy * dy + dz * dz) }
        END { if (m > 23.3 && m < 23.9 && d < 5) print "OK"; else print "median " m " mm, origin " d " mm away" }' \
        "$W/franka_report/report.txt")
if [ "$(rc_of "$W/franka_measure")" -eq 0 ] && [ "$res" = OK ]; then pass; else
  fail "measure on the franka photos from the arm's poses: exit $(rc_of "$W/franka_measure"): $res $(first "$W/franka_measure.err")"; fi
run "$W/handeye_planar" calibrate-rig --hand-eye eye-in-hand --camera "$W/franka_cam.yaml" --motion "$W/sim_xml_front/motion.csv" \
    --pattern chessboard:9x6:0.0236 --out "$W/eMc2.yaml"
[ "$(rc_of "$W/handeye_planar")" -ne 0 ] && grep -q "image\|6-DoF" "$W/handeye_planar.err" && [ ! -e "$W/eMc2.yaml" ] && pass ||
  fail "calibrate-rig --hand-eye with a planar log: exit $(rc_of "$W/handeye_planar"): $(first "$W/handeye_planar.err")"
run "$W/franka_load" simulate --camera "$W/franka_cam.yaml" --rig "$RIG" --out-dir "$W/franka_sim" --frames 2
[ "$(rc_of "$W/franka_load")" -eq 0 ] && pass || fail "the calibrated franka camera does not load: $(first "$W/franka_load.err")"
}

sec_status() {
# ---------------------------------------------------------------------------
# 3. Status words.
S="$W/status"; mkdir -p "$S"
# status_of FILE ID -> status word of that id (or "<missing>")
status_of() { awk -F, -v id="$2" 'NR > 1 && $1 == id { sub(/\r$/, ""); print $10; f = 1 } END { if (!f) print "<missing>" }' "$1"; }
# numbers_in_nonok FILE -> lines of non-ok rows holding a number
numbers_in_nonok() {
  awk -F, 'NR > 1 { sub(/\r$/, ""); if ($10 == "ok") next
                     for (k = 3; k <= 9; k++) if ($k !~ /^[ \t]*$/ && tolower($k) !~ /^[ \t]*[-+]?nan[ \t]*$/) { print; break } }' "$1"
}
# expect_status NAME MOTION TRACKS ID WORD
expect_status() {
  local name=$1 m=$2 t=$3 id=$4 word=$5
  run "$S/$name" estimate --camera "$XML" --rig "$RIG" --motion "$m" --tracks "$t"
  if [ "$(rc_of "$S/$name")" -ne 0 ]; then
    fail "status $name: exit $(rc_of "$S/$name"): $(first "$S/$name.err")"; return
  fi
  local got; got=$(status_of "$S/$name.out" "$id")
  if [ "$got" = "$word" ]; then pass; else fail "status $name: id $id has status '$got', expected '$word'"; fi
  local nn; nn=$(numbers_in_nonok "$S/$name.out")
  if [ -z "$nn" ]; then pass; else fail "status $name: non-ok row holds numbers: $(echo "$nn" | head -n 1)"; fi
}
printf 'frame,x,y,z,heading,yaw\n0,0,0,0,0,0\n1,0,0,0.02,0,0\n' >"$S/motion_fwd.csv"
printf 'frame,x,y,z,heading,yaw\n0,0.1,0,0.3,0.2,0.4\n1,0.1,0,0.3,0.2,0.4\n' >"$S/motion_still.csv"
# too_few_frames: feature 5 seen once, feature 1 seen twice (normal)
printf 'frame,id,u,v\n0,1,400.0,300.0\n1,1,401.0,300.8\n1,5,250.0,200.0\n' >"$S/tracks_few.csv"
expect_status too_few_frames "$S/motion_fwd.csv" "$S/tracks_few.csv" 5 too_few_frames
# no_motion: two identical motion rows
printf 'frame,id,u,v\n0,1,400.0,300.0\n1,1,401.0,300.8\n' >"$S/tracks_still.csv"
expect_status no_motion "$S/motion_still.csv" "$S/tracks_still.csv" 1 no_motion
# degenerate: feature at the focus of expansion (principal point, front view, straight forward)
printf 'frame,id,u,v\n0,3,319.2,241.4\n1,3,319.2,241.4\n' >"$S/tracks_foe.csv"
expect_status degenerate "$S/motion_fwd.csv" "$S/tracks_foe.csv" 3 degenerate
# behind: image motion toward the principal point while moving forward
printf 'frame,id,u,v\n0,4,419.2,241.4\n1,4,417.2,241.4\n' >"$S/tracks_behind.csv"
expect_status behind "$S/motion_fwd.csv" "$S/tracks_behind.csv" 4 behind
# all four situations in one file (mixed with a normal feature) give the same words
printf 'frame,id,u,v\n0,3,319.2,241.4\n1,3,319.2,241.4\n0,4,419.2,241.4\n1,4,417.2,241.4\n0,1,419.2,241.4\n1,1,421.2,241.4\n1,5,250,200\n' >"$S/tracks_mixed.csv"
run "$S/mixed" estimate --camera "$XML" --rig "$RIG" --motion "$S/motion_fwd.csv" --tracks "$S/tracks_mixed.csv"
got="$(status_of "$S/mixed.out" 1) $(status_of "$S/mixed.out" 3) $(status_of "$S/mixed.out" 4) $(status_of "$S/mixed.out" 5)"
if [ "$(rc_of "$S/mixed")" -eq 0 ] && [ "$got" = "ok degenerate behind too_few_frames" ]; then pass
else fail "status mixed file: exit $(rc_of "$S/mixed"), statuses of ids 1 3 4 5 '$got', expected 'ok degenerate behind too_few_frames'"; fi
nn=$(numbers_in_nonok "$S/mixed.out")
if [ -z "$nn" ]; then pass; else fail "status mixed: non-ok row holds numbers: $(echo "$nn" | head -n 1)"; fi
# the ok feature of the mixed file (u-u0 = 100 -> 102 px, moving outward) is in front: zc > 0
zc=$(awk -F, 'NR > 1 && $1 == 1 { print $8 }' "$S/mixed.out")
if awk -v z="$zc" 'BEGIN { exit !(z + 0 > 0) }'; then pass; else fail "status mixed: ok feature 1 has zc '$zc'"; fi
}

sec_output() {
# ---------------------------------------------------------------------------
# 4. Output columns, --out, digits, sigma.
need_scene xml oblique
D="$W/sim_xml_oblique"
if [ -s "$D/tracks.csv" ]; then
  run "$W/o4" estimate --camera "$XML" --rig "$RIG" --motion "$D/motion.csv" --tracks "$D/tracks.csv"
  if [ "$(head -n 1 "$W/o4.out" | tr -d '\r')" = "$HEADER" ] && [ "$(head -n 1 "$W/o4.out")" = "$HEADER" ]; then pass
  else fail "output header is '$(first "$W/o4.out")', expected '$HEADER'"; fi
  mkdir -p "$W/o4dir"
  run "$W/o4f" estimate --camera "$XML" --rig "$RIG" --motion "$D/motion.csv" --tracks "$D/tracks.csv" --out "$W/o4dir/points.csv"
  if [ "$(rc_of "$W/o4f")" -eq 0 ]; then pass; else fail "--out FILE: exit $(rc_of "$W/o4f")"; fi
  if [ -f "$W/o4dir/points.csv" ]; then pass; else fail "--out FILE: file not written"; fi
  if [ ! -s "$W/o4f.out" ]; then pass; else fail "--out FILE: stdout not empty: $(first "$W/o4f.out")"; fi
  if [ -f "$W/o4dir/points.csv" ] && cmp -s "$W/o4dir/points.csv" "$W/o4.out"; then pass; else fail "--out FILE: file differs from standard output"; fi
  left=$(ls -A "$W/o4dir" | grep -v -x points.csv | head -n 3 | tr '\n' ' ')
  if [ -z "$left" ]; then pass; else fail "--out FILE: stray files next to the output: $left"; fi
  # at least 12 significant digits in every number of ok rows (exact zero allowed)
  res=$(awk -F, 'NR > 1 && $10 == "ok" {
      for (k = 3; k <= 9; k++) {
        s = $k; sub(/^[-+]/, "", s); sub(/[eE].*$/, "", s); gsub(/\./, "", s); sub(/^0+/, "", s)
        if (s == "" ) continue
        if (length(s) < 12) { print "column " k " value " $k " has " length(s) " significant digits"; exit }
      } }' "$W/o4.out")
  if [ -z "$res" ]; then pass; else fail "numbers with < 12 significant digits: $res"; fi
  res=$(awk -F, 'NR > 1 && $10 == "ok" { n++; if (!($9 > 0)) { print "id " $1 " sigma_zc " $9; exit } } END { if (n == 0) print "no ok rows" }' "$W/o4.out")
  if [ -z "$res" ]; then pass; else fail "sigma_zc not positive for ok rows: $res"; fi
  # 10 fields on every row
  res=$(awk -F, '{ sub(/\r$/, "") } NF != 10 { print NR ": " NF " fields"; exit }' "$W/o4.out")
  if [ -z "$res" ]; then pass; else fail "output rows without 10 fields: $res"; fi
else
  fail "output columns: no simulated oblique scene"
fi
}

sec_columns() {
# ---------------------------------------------------------------------------
# 5. Column order free, unknown columns ignored (motion and tracks).
need_scene xml turning
D="$W/sim_xml_turning"
if [ -s "$D/tracks.csv" ]; then
  awk -F, -v OFS=, '{ print $6, (NR == 1 ? "comment" : "x" NR), $4, $5, $1, $3, $2 }' "$D/motion.csv" >"$W/motion_perm.csv"
  awk -F, -v OFS=, '{ print $4, $2, (NR == 1 ? "quality" : 0.5), $3, $1 }' "$D/tracks.csv" >"$W/tracks_perm.csv"
  run "$W/c5a" estimate --camera "$XML" --rig "$RIG" --motion "$D/motion.csv" --tracks "$D/tracks.csv"
  run "$W/c5b" estimate --camera "$XML" --rig "$RIG" --motion "$W/motion_perm.csv" --tracks "$D/tracks.csv"
  run "$W/c5c" estimate --camera "$XML" --rig "$RIG" --motion "$D/motion.csv" --tracks "$W/tracks_perm.csv"
  run "$W/c5d" estimate --camera "$XML" --rig "$RIG" --motion "$W/motion_perm.csv" --tracks "$W/tracks_perm.csv"
  if [ "$(rc_of "$W/c5a")" -eq 0 ] && [ -s "$W/c5a.out" ]; then pass; else fail "column order: reference run failed: $(first "$W/c5a.err")"; fi
  for v in b:motion c:tracks d:both; do
    k=${v%%:*}; what=${v#*:}
    if [ "$(rc_of "$W/c5$k")" -eq 0 ] && cmp -s "$W/c5a.out" "$W/c5$k.out"; then pass
    else fail "column order/extra column in $what: exit $(rc_of "$W/c5$k"), output differs: $(first "$W/c5$k.err")"; fi
  done
else
  fail "column order: no simulated turning scene"
fi
}

sec_bad_input() {
# ---------------------------------------------------------------------------
# 6. Bad input.
B="$W/bad"; mkdir -p "$B" "$B/outs"
oblique_inputs
need_paper_two
need_apriltag
: >"$B/empty.csv"
echo 'frame,id,u,v' >"$B/tracks_header_only.csv"
awk -F, -v OFS=, '{ print $1, $2, $3, $5, $6 }' "$M" >"$B/motion_no_z.csv"
awk -F, -v OFS=, 'NR == 3 { $4 = "abc" } { print }' "$M" >"$B/motion_text.csv"
awk -F, -v OFS=, 'NR == 3 { $2 = "nan" } { print }' "$M" >"$B/motion_nan.csv"
awk -F, -v OFS=, 'NR == 3 { $2 = "inf" } { print }' "$M" >"$B/motion_inf.csv"
awk -F, -v OFS=, 'NR == 3 { $3 = "1.5x" } { print }' "$M" >"$B/motion_trailing.csv"
awk -F, -v OFS=, 'NR == 4 { $3 = "abc" } { print }' "$T" >"$B/tracks_text.csv"
awk -F, -v OFS=, 'NR == 4 { $4 = "nan" } { print }' "$T" >"$B/tracks_nan.csv"
awk -F, -v OFS=, 'NR == 4 { $4 = "-inf" } { print }' "$T" >"$B/tracks_inf.csv"
awk '{ print } NR == 3 { print }' "$M" >"$B/motion_dup.csv"
awk 'NR == 3 { keep = $0; next } { print } NR == 4 { print keep }' "$M" >"$B/motion_unsorted.csv"
{ cat "$T"; echo '99,0,300.5,200.5'; } >"$B/tracks_unknown_frame.csv"
printf 'this is not a camera\n{{{ ::: [\n' >"$B/garbage.yaml"
printf 'this is not a camera\n<<<\n' >"$B/garbage.xml"
head -c 4096 /dev/urandom >"$B/random.bin"
awk '/cols: 4/ { sub(/cols: 4/, "cols: 3") } /-0.11042/ { sub(/, 0.00035/, "") } { print }' "$YML" >"$B/three_coeffs.yaml"
echo 'something_else: [1, 2, 3]' >"$B/rig_no_offset.yaml"
echo 'camera_offset: [-0.1503, 0.0]' >"$B/rig_two.yaml"

# bad NAME [--no-out] ARGS... : non-zero exit < 128, one line on stderr, no output file.
bad() {
  local name=$1; shift
  local useout=1
  if [ "${1:-}" = "--no-out" ]; then useout=0; shift; fi
  local out="$B/outs/$name.csv"
  if [ $useout -eq 1 ]; then run "$B/$name" "$@" --out "$out"; else run "$B/$name" "$@"; fi
  local rc; rc=$(rc_of "$B/$name")
  local nl; nl=$(lines_of "$B/$name.err")
  local msg=""
  [ "$rc" -eq 0 ] && msg="$msg exit 0;"
  [ "$rc" -ge 128 ] && msg="$msg exit $rc (crash);"
  [ "$nl" -ne 1 ] && msg="$msg $nl lines on stderr;"
  grep -q "[^[:space:]]" "$B/$name.err" || msg="$msg no reason on stderr;"
  [ $useout -eq 1 ] && [ -e "$out" ] && msg="$msg output file created;"
  if [ -z "$msg" ]; then pass; else fail "bad input $name:$msg stderr: $(first "$B/$name.err")"; fi
}
# measure: bad input.
MEA=(measure --camera "$YML" --rig "$RIG" --pattern chessboard:5x4:0.02)
cut -d, -f1-6 "$PE/motion.csv" > "$PE/motion_noimg.csv"
bad measure_no_image_column "${MEA[@]}" --motion "$PE/motion_noimg.csv"
cp "$PE/motion.csv" "$PE/motion_missing.csv"; sed -i 's/frame_0001.png/nothere.png/' "$PE/motion_missing.csv"
bad measure_missing_image "${MEA[@]}" --motion "$PE/motion_missing.csv"
head -c 300 "$PE/frame_0000.png" > "$PE/trunc.png"; cp "$PE/motion.csv" "$PE/motion_trunc.csv"
sed -i 's/frame_0001.png/trunc.png/' "$PE/motion_trunc.csv"
bad measure_truncated_image "${MEA[@]}" --motion "$PE/motion_trunc.csv"
bad measure_bad_pattern measure --camera "$YML" --rig "$RIG" --motion "$PE/motion.csv" --pattern chessboard:5:0.02
bad measure_bad_motion_noise "${MEA[@]}" --motion "$PE/motion.csv" --motion-noise perpose
bad measure_pattern_not_found measure --camera "$YML" --rig "$RIG" --motion "$AT/motion.csv" --pattern chessboard:5x4:0.02

EST=(estimate --camera "$XML" --rig "$RIG")
bad missing_camera estimate --camera "$B/nope.xml" --rig "$RIG" --motion "$M" --tracks "$T"
bad missing_motion "${EST[@]}" --motion "$B/nope.csv" --tracks "$T"
bad missing_tracks "${EST[@]}" --motion "$M" --tracks "$B/nope.csv"
bad missing_rig estimate --camera "$XML" --rig "$B/nope.yaml" --motion "$M" --tracks "$T"
bad empty_motion "${EST[@]}" --motion "$B/empty.csv" --tracks "$T"
bad empty_tracks "${EST[@]}" --motion "$M" --tracks "$B/empty.csv"
bad header_only_tracks "${EST[@]}" --motion "$M" --tracks "$B/tracks_header_only.csv"
bad motion_no_z "${EST[@]}" --motion "$B/motion_no_z.csv" --tracks "$T"
bad motion_text_number "${EST[@]}" --motion "$B/motion_text.csv" --tracks "$T"
bad motion_trailing_garbage "${EST[@]}" --motion "$B/motion_trailing.csv" --tracks "$T"
bad motion_nan "${EST[@]}" --motion "$B/motion_nan.csv" --tracks "$T"
bad motion_inf "${EST[@]}" --motion "$B/motion_inf.csv" --tracks "$T"
bad tracks_text_number "${EST[@]}" --motion "$M" --tracks "$B/tracks_text.csv"
bad tracks_nan "${EST[@]}" --motion "$M" --tracks "$B/tracks_nan.csv"
bad tracks_inf "${EST[@]}" --motion "$M" --tracks "$B/tracks_inf.csv"
bad duplicated_frame "${EST[@]}" --motion "$B/motion_dup.csv" --tracks "$T"
bad unsorted_frames "${EST[@]}" --motion "$B/motion_unsorted.csv" --tracks "$T"
bad track_unknown_frame "${EST[@]}" --motion "$M" --tracks "$B/tracks_unknown_frame.csv"
bad garbage_camera_yaml estimate --camera "$B/garbage.yaml" --rig "$RIG" --motion "$M" --tracks "$T"
bad garbage_camera_xml estimate --camera "$B/garbage.xml" --rig "$RIG" --motion "$M" --tracks "$T"
bad binary_camera estimate --camera "$B/random.bin" --rig "$RIG" --motion "$M" --tracks "$T"
bad yaml_three_coeffs estimate --camera "$B/three_coeffs.yaml" --rig "$RIG" --motion "$M" --tracks "$T"
bad unknown_camera_name "${EST[@]}" --camera-name nosuchcamera --motion "$M" --tracks "$T"
bad rig_no_offset estimate --camera "$XML" --rig "$B/rig_no_offset.yaml" --motion "$M" --tracks "$T"
bad rig_two_values estimate --camera "$XML" --rig "$B/rig_two.yaml" --motion "$M" --tracks "$T"
bad unknown_option "${EST[@]}" --motion "$M" --tracks "$T" --no-such-option
bad unknown_option_value "${EST[@]}" --motion "$M" --tracks "$T" --no-such-option 3
bad unknown_subcommand --no-out frobnicate --camera "$XML"
# Files that parse but cannot be right: a typo'd rig key, a yaw axis not modelled, a camera whose
# distortion or intrinsics are not a real lens's.
echo 'camera_ofset: [-0.1503, 0.0, 0.0]' >"$B/rig_typo.yaml"
printf 'camera_offset: [-0.1503, 0.0, 0.0]\nyaw_axis: [1, 0, 0]\n' >"$B/rig_axis_x.yaml"
bad rig_typo_key estimate --camera "$XML" --rig "$B/rig_typo.yaml" --motion "$M" --tracks "$T"
bad rig_axis_x estimate --camera "$XML" --rig "$B/rig_axis_x.yaml" --motion "$M" --tracks "$T"
sed 's/-0.11042, 0.43607/1e6, 0.43607/' "$YML" >"$B/k1_huge.yaml"
sed 's/1734.1, 0., 319.2/1e308, 0., 319.2/' "$YML" >"$B/fx_huge.yaml"
sed 's/319.2, 0., 1734.5, 241.4/1e7, 0., 1734.5, 241.4/' "$YML" >"$B/u0_far.yaml"
sed 's/image_width: 640/image_width: 2147483647/' "$YML" >"$B/width_huge.yaml"
for c in k1_huge fx_huge u0_far width_huge; do
  bad "camera_$c" estimate --camera "$B/$c.yaml" --rig "$RIG" --motion "$M" --tracks "$T"
  grep -q -e "implausible camera" -e "image_width" "$B/camera_$c.err" && pass || fail "camera $c: $(first "$B/camera_$c.err")"
done
# Numbers that would give NaN or a raw library error instead of a reason.
bad refine_sigma_px_zero "${EST[@]}" --motion "$M" --tracks "$T" --method refine --sigma-px 0
bad fused_sigma_px_tiny "${EST[@]}" --motion "$M" --tracks "$T" --method fused --sigma-px 1e-300
bad window_sigma_px_zero "${EST[@]}" --motion "$M" --tracks "$T" --method window --sigma-px 0
bad window_outlier_zero "${EST[@]}" --motion "$M" --tracks "$T" --method window --outlier-threshold-px 0
bad refine_robust_zero "${EST[@]}" --motion "$M" --tracks "$T" --method refine --robust-threshold-px 0
bad simulate_huge_blur --no-out simulate --camera "$YML" --rig "$RIG" --out-dir "$B/outs/blur" --frames 2 \
  --pattern chessboard:5x4:0.02 --blur 1e300
tr '\n' '\r' <"$T" >"$B/tracks_cr_only.csv"
bad tracks_cr_only "${EST[@]}" --motion "$M" --tracks "$B/tracks_cr_only.csv"
grep -q "CR-only" "$B/tracks_cr_only.err" && pass || fail "CR-only tracks: $(first "$B/tracks_cr_only.err")"
mkdir -p "$B/dir_image"; sed "s|,frame_|,$PE/frame_|; s|[^,]*frame_0001.png|$B/dir_image|" "$PE/motion.csv" >"$B/motion_dir_image.csv"
bad measure_image_is_folder measure --camera "$YML" --rig "$RIG" --pattern chessboard:5x4:0.02 --motion "$B/motion_dir_image.csv"
grep -q "dir_image: cannot read image (.*is a folder" "$B/measure_image_is_folder.err" && pass ||
  fail "image folder: $(first "$B/measure_image_is_folder.err")"
bad unknown_subcommand_out frobnicate --camera "$XML"
bad unknown_method "${EST[@]}" --motion "$M" --tracks "$T" --method foo
bad negative_sigma_px "${EST[@]}" --motion "$M" --tracks "$T" --sigma-px -1
bad nan_sigma_px "${EST[@]}" --motion "$M" --tracks "$T" --sigma-px nan
bad inf_sigma_odom "${EST[@]}" --motion "$M" --tracks "$T" --sigma-odom inf
bad text_sigma_yaw "${EST[@]}" --motion "$M" --tracks "$T" --sigma-yaw abc
bad binary_tracks "${EST[@]}" --motion "$M" --tracks "$B/random.bin"
bad binary_motion "${EST[@]}" --motion "$B/random.bin" --tracks "$T"
bad missing_tracks_option "${EST[@]}" --motion "$M"
bad missing_camera_option estimate --rig "$RIG" --motion "$M" --tracks "$T"
bad no_subcommand --no-out
bad simulate_missing_out_dir --no-out simulate --camera "$XML" --rig "$RIG"
bad simulate_missing_camera --no-out simulate --camera "$B/nope.xml" --rig "$RIG" --out-dir "$B/simdir"
# --out into a folder that does not exist
run "$B/out_nodir" "${EST[@]}" --motion "$M" --tracks "$T" --out "$B/no/such/dir/points.csv"
rc=$(rc_of "$B/out_nodir"); nl=$(lines_of "$B/out_nodir.err")
if [ "$rc" -ne 0 ] && [ "$rc" -lt 128 ] && [ "$nl" -eq 1 ] && [ ! -e "$B/no" ]; then pass
else fail "bad input --out into missing folder: exit $rc, $nl lines on stderr: $(first "$B/out_nodir.err")"; fi
left=$(ls -A "$B/outs" | head -n 3 | tr '\n' ' ')
if [ -z "$left" ]; then pass; else fail "bad input: files left in the --out folder after failed runs: $left"; fi
}

sec_help() {
# ---------------------------------------------------------------------------
# 7. --help.
run "$W/h_top" --help
if [ "$(rc_of "$W/h_top")" -eq 0 ] && [ -s "$W/h_top.out" ]; then pass; else fail "yawdepth --help: exit $(rc_of "$W/h_top")"; fi
for sub in estimate error-analysis simulate; do
  run "$W/h_$sub" "$sub" --help
  if [ "$(rc_of "$W/h_$sub")" -eq 0 ] && [ -s "$W/h_$sub.out" ]; then pass; else fail "yawdepth $sub --help: exit $(rc_of "$W/h_$sub")"; fi
  if grep -q -e "$sub" "$W/h_top.out"; then pass; else fail "yawdepth --help does not mention $sub"; fi
done
for opt in --camera --rig --motion --tracks --method --sigma-px --sigma-odom --sigma-heading --sigma-yaw --out; do
  if grep -q -e "$opt\\b" "$W/h_estimate.out"; then pass; else fail "yawdepth estimate --help does not mention $opt"; fi
done
for m in paper exact fused refine; do
  if grep -q -e "$m" "$W/h_estimate.out"; then pass; else fail "yawdepth estimate --help does not mention method $m"; fi
done
if grep -q -e '--paper' "$W/h_error-analysis.out"; then pass; else fail "yawdepth error-analysis --help does not mention --paper"; fi
}

sec_error_analysis() {
# ---------------------------------------------------------------------------
# 8. error-analysis --paper.
run "$W/ea" error-analysis --paper
if [ "$(rc_of "$W/ea")" -eq 0 ]; then pass; else fail "error-analysis --paper: exit $(rc_of "$W/ea"): $(first "$W/ea.err")"; fi
for s in '45.84 %' '25.42 %' '13.17 %' '18.17 %' '5.15 %' '5.30 %' '0.15 %' 0.1484 0.0742 0.0297 5.1333e-6; do
  if grep -q -F -e "$s" "$W/ea.out"; then pass; else fail "error-analysis --paper output lacks '$s'"; fi
done
}

sec_files() {
# ---------------------------------------------------------------------------
# 9. Files: no output replaces an input, another output, a device or a read-only file; no input is
#    read without bound; a failed run writes nothing.
oblique_inputs
files_setup
need_paper_two
refused out_is_tracks "is the input --tracks" "${EF[@]}" --out "$F/t.csv"
refused out_is_tracks_dot "is the input --tracks" "${EF[@]}" --out "$F/./t.csv"
refused out_is_tracks_hardlink "is the input --tracks" "${EF[@]}" --out "$F/t_hard.csv"
refused out_is_tracks_symlink "is the input --tracks" "${EF[@]}" --out "$F/t_soft.csv"
refused out_is_motion "is the input --motion" "${EF[@]}" --out "$F/m.csv"
refused outliers_is_tracks "is the input --tracks" "${EF[@]}" --method fused --outliers "$F/t.csv" --out "$F/p.csv"
refused outliers_is_out "are the same file" "${EF[@]}" --method fused --outliers "$F/p.csv" --out "$F/p.csv"
[ -e "$F/p.csv" ] && fail "files: a refused run created its output" || pass
cp "$RIG" "$F/rig.yaml"
refused out_is_rig "is the input --rig" estimate --camera "$XML" --rig "$F/rig.yaml" --motion "$F/m.csv" \
  --tracks "$F/t.csv" --out "$F/rig.yaml"
cmp -s "$RIG" "$F/rig.yaml" && pass || fail "files: the rig input changed"
refused outliers_empty "empty file name" "${EF[@]}" --method fused --outliers ""
refused ply_is_motion "is the input --motion" "${EF[@]}" --ply "$F/m.csv" --out "$F/p.csv"
# --pixel-correlation: only a method that models it, only in [0, 0.99].
refused pixel_correlation_fused "does not model correlated tracker errors" "${EF[@]}" --method fused \
  --pixel-correlation 0.5 --out "$F/p.csv"
refused pixel_correlation_range "pixel-correlation" "${EF[@]}" --method window --pixel-correlation 1.5 --out "$F/p.csv"
refused ply_is_out "are the same file" "${EF[@]}" --ply "$F/p.csv" --out "$F/p.csv"
# Devices and endless inputs: refused at once, never read.
for what in motion tracks camera rig; do
  case $what in
    motion) args=(estimate --camera "$XML" --rig "$RIG" --motion /dev/zero --tracks "$F/t.csv") ;;
    tracks) args=(estimate --camera "$XML" --rig "$RIG" --motion "$F/m.csv" --tracks /dev/zero) ;;
    camera) args=(estimate --camera /dev/zero --rig "$RIG" --motion "$F/m.csv" --tracks "$F/t.csv") ;;
    rig) args=(estimate --camera "$XML" --rig /dev/urandom --motion "$F/m.csv" --tracks "$F/t.csv") ;;
  esac
  { timeout 30 "$YAWDEPTH" "${args[@]}" >"$F/dev_$what.out" 2>"$F/dev_$what.err"; } 2>/dev/null
  rc=$?
  if [ "$rc" -ne 0 ] && [ "$rc" -lt 124 ] && grep -q "character device" "$F/dev_$what.err" &&
     [ "$(lines_of "$F/dev_$what.err")" -eq 1 ]; then pass; else
    fail "files: --$what on a device: exit $rc: $(first "$F/dev_$what.err")"; fi
done
# An endless pipe ends at the size limit, in a one-line error.
{ awk 'BEGIN { print "frame,id,u,v"; for (i = 0; ; i++) print "0," i ",300.5,200.5" }' | timeout 60 "$YAWDEPTH" "${EF[@]:0:7}" --tracks /dev/stdin --max-input-mb 1 \
    >"$F/endless.out" 2>"$F/endless.err"; } 2>/dev/null
rc=$?
if [ "$rc" -ne 0 ] && [ "$rc" -lt 124 ] && grep -q "larger than 1 MiB" "$F/endless.err"; then pass; else
  fail "files: an endless tracks pipe: exit $rc: $(first "$F/endless.err")"; fi
# A 2 MB line is refused without being held (1 MiB per line).
{ printf 'frame,id,u,v\n1,2,'; head -c 2000000 /dev/zero | tr '\0' 7; printf ',4\n'; } >"$F/longline.csv"
refused long_line "line longer than 1 MiB" "${EF[@]:0:7}" --tracks "$F/longline.csv"
# A pipe is read like a file (a FIFO with a writer, and process substitution).
run "$F/reg" "${EF[@]}"
mkfifo "$F/fifo.csv"
# The writer opens the FIFO inside `timeout`: a reader that never opens it must not hang the script.
timeout 60 sh -c 'cat "$1" >"$2"' sh "$F/t.csv" "$F/fifo.csv" &
run "$F/fifo" "${EF[@]:0:7}" --tracks "$F/fifo.csv"
wait
if [ "$(rc_of "$F/fifo")" -eq 0 ] && cmp -s "$F/reg.out" "$F/fifo.out"; then pass; else
  fail "files: tracks from a FIFO differ from the file: exit $(rc_of "$F/fifo"): $(first "$F/fifo.err")"; fi
run "$F/procsub" "${EF[@]:0:7}" --tracks <(cat "$F/t.csv")
if [ "$(rc_of "$F/procsub")" -eq 0 ] && cmp -s "$F/reg.out" "$F/procsub.out"; then pass; else
  fail "files: tracks by process substitution: exit $(rc_of "$F/procsub"): $(first "$F/procsub.err")"; fi
# Outputs onto devices are written through; the device stays a device.
run "$F/null" "${EF[@]}" --out /dev/null
if [ "$(rc_of "$F/null")" -eq 0 ] && [ -c /dev/null ]; then pass; else fail "files: --out /dev/null: exit $(rc_of "$F/null"), $(ls -l /dev/null)"; fi
if [ -c /dev/full ]; then
  refused out_dev_full "No space left" "${EF[@]}" --out /dev/full
  [ -c /dev/full ] && pass || fail "files: /dev/full is no longer a device"
  { "$YAWDEPTH" "${EF[@]}" >/dev/full 2>"$F/stdout_full.err"; } 2>/dev/null
  rc=$?
  if [ "$rc" -ne 0 ] && grep -q -e "standard output" -e "cannot write" "$F/stdout_full.err"; then pass; else
    fail "files: stdout onto /dev/full: exit $rc: $(first "$F/stdout_full.err")"; fi
fi
# /dev/stdout onto a pipe is written through (the link leads to a pipe, not to a file to replace).
"$YAWDEPTH" "${EF[@]}" --out /dev/stdout 2>"$F/devstdout.err" | cat >"$F/devstdout.out"
if [ "${PIPESTATUS[0]}" -eq 0 ] && cmp -s "$F/reg.out" "$F/devstdout.out"; then pass; else
  fail "files: --out /dev/stdout into a pipe: $(first "$F/devstdout.err")"; fi
# A symbolic link is followed (its target replaced, the link kept); a read-only file is refused.
echo old >"$F/target.csv"; ln -s target.csv "$F/link.csv"
run "$F/link" "${EF[@]}" --out "$F/link.csv"
if [ "$(rc_of "$F/link")" -eq 0 ] && [ -L "$F/link.csv" ] && cmp -s "$F/reg.out" "$F/target.csv"; then pass; else
  fail "files: --out onto a symbolic link: exit $(rc_of "$F/link"), link kept: $([ -L "$F/link.csv" ] && echo yes || echo no)"; fi
echo keep >"$F/ro.csv"; chmod 444 "$F/ro.csv"
refused out_read_only "is read-only" "${EF[@]}" --out "$F/ro.csv"
[ "$(cat "$F/ro.csv")" = keep ] && [ ! -w "$F/ro.csv" -o "$(id -u)" -eq 0 ] && pass || fail "files: a read-only output was changed"
# measure, calibrate-camera, calibrate-rig: outputs onto inputs or onto each other.
MEF=(measure --quiet --camera "$YML" --rig "$RIG" --pattern chessboard:5x4:0.02)
cp "$PE/motion.csv" "$F/pe_motion.orig"
refused measure_out_is_motion "is the input --motion" "${MEF[@]}" --motion "$PE/motion.csv" --out "$PE/motion.csv"
refused measure_out_is_image "is the input --motion's image" "${MEF[@]}" --motion "$PE/motion.csv" --out "$PE/frame_0001.png"
refused measure_tracks_out_is_out "are the same file" "${MEF[@]}" --motion "$PE/motion.csv" --tracks-out "$F/q.csv" --out "$F/q.csv"
cmp -s "$PE/motion.csv" "$F/pe_motion.orig" && pass || fail "files: measure changed its motion log"
refused calcam_coverage_is_image "is the input image" calibrate-camera --pattern chessboard:5x4:0.02 --out "$F/cal" \
  --coverage "$PE/frame_0000.png" "$PE/frame_0000.png" "$PE/frame_0001.png"
refused calcam_empty_prefix "not a file prefix" calibrate-camera --pattern chessboard:5x4:0.02 --out "" "$PE/frame_0000.png"
mkdir -p "$F/calx.xml"
refused calcam_xml_is_folder "is a folder" calibrate-camera --pattern chessboard:5x4:0.02 --out "$F/calx" "$PE/frame_0000.png"
[ -e "$F/calx.yaml" ] && fail "files: calibrate-camera wrote PREFIX.yaml though PREFIX.xml is a folder" || pass
touch "$F/debug_is_file"
refused calcam_debug_is_file "is not a folder" calibrate-camera --pattern chessboard:5x4:0.02 --out "$F/cald" \
  --debug-dir "$F/debug_is_file" "$PE/frame_0000.png"
refused measure_debug_is_file "is not a folder" "${MEF[@]}" --motion "$PE/motion.csv" --debug-dir "$F/debug_is_file"
refused calrig_out_is_motion "is the input --motion" calibrate-rig --camera "$YML" --motion "$PE/motion.csv" \
  --pattern chessboard:5x4:0.02 --out "$PE/motion.csv"
cmp -s "$PE/motion.csv" "$F/pe_motion.orig" && pass || fail "files: calibrate-rig changed its motion log"
# An image that is a device, and one whose header declares 32000 x 32000 pixels.
sed "s|,frame_|,$PE/frame_|" "$PE/motion.csv" >"$F/dev_img_motion.csv"; ln -s /dev/zero "$F/zero.png"
sed -i "s|[^,]*frame_0001.png|$F/zero.png|" "$F/dev_img_motion.csv"
refused measure_image_device "character device" "${MEF[@]}" --motion "$F/dev_img_motion.csv"
{ printf '\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR\x00\x00\x7d\x00\x00\x00\x7d\x00\x08\x00\x00\x00\x00'; head -c 1000 /dev/zero; } >"$F/huge.png"
sed "s|,frame_|,$PE/frame_|" "$PE/motion.csv" >"$F/huge_img_motion.csv"
sed -i "s|[^,]*frame_0001.png|$F/huge.png|" "$F/huge_img_motion.csv"
refused measure_image_huge "32000 x 32000" "${MEF[@]}" --motion "$F/huge_img_motion.csv"
printf 'P5\n99999999999999 99999999999999\n255\n' >"$F/huge.pgm"
sed "s|,frame_|,$PE/frame_|; s|[^,]*frame_0001.png|$F/huge.pgm|" "$PE/motion.csv" >"$F/huge_pgm_motion.csv"
refused measure_image_huge_pgm "pixels are read" "${MEF[@]}" --motion "$F/huge_pgm_motion.csv"
}

sec_six_dof() {
# ---------------------------------------------------------------------------
# 6-DoF motion logs (an arm's poses, tx,ty,tz,tux,tuy,tuz) and a camera_pose mount (hand-eye eMc).
files_setup # refused()'s folder
A="$W/arm"; mkdir -p "$A"
printf 'camera_pose: [0.0577148, -0.0339261, -0.0422745, 0.00178253, 0.00917657, 1.58178]\n' >"$A/eMc.yaml"
for path in approach orbit random; do
  D="$A/sim_$path"
  run "$D" simulate --camera "$YML" --rig "$A/eMc.yaml" --out-dir "$D" --arm "$path" --arm-distance 0.7 --points 40 \
    --min-depth 0.5 --max-depth 0.9 --frames 8 --seed 4
  if [ "$(rc_of "$D")" -ne 0 ]; then fail "simulate --arm $path: exit $(rc_of "$D"): $(first "$D.err")"; continue; fi
  case $(head -n 1 "$D/motion.csv") in
    frame,tx,ty,tz,tux,tuy,tuz,yaw) pass ;;
    *) fail "simulate --arm $path: motion.csv header '$(first "$D/motion.csv")'" ;;
  esac
  # The arm's log has no pan joint: without a yaw column the yaw is 0 (and exact).
  cut -d, -f1-7 "$D/motion_truth.csv" >"$D/motion_noyaw.csv"
  for m in exact fused window refine; do
    E="$A/est_${m}_$path"
    # 1e-3 px: far below any tracker, and above the linearisation error of fused's recursive filter
    # (at 1e-4 px fused rejects nearly half of these noise-free observations, and the whole-log check
    # then rightly says the tracks do not fit the model).
    run "$E" estimate --method "$m" --sigma-px 1e-3 --sigma-odom 1e-8 --sigma-rot 1e-9 --camera "$YML" --rig "$A/eMc.yaml" \
      --motion "$D/motion_noyaw.csv" --tracks "$D/tracks.csv"
    if [ "$(rc_of "$E")" -ne 0 ]; then fail "estimate $m 6-DoF $path: exit $(rc_of "$E"): $(first "$E.err")"; continue; fi
    if [ "$m" = exact ]; then tol=1e-6; else tol=1e-3; fi
    res=$(compare_points "$E.out" "$D/truth.csv" "$tol" 0.6)
    case $res in
      OK*) pass ;;
      *) fail "estimate $m 6-DoF $path: $(echo "$res" | head -n 3 | tr '\n' ';')" ;;
    esac
  done
done
# Noisy 6-DoF data: refine's depths within 4 sigma of the truth.
D="$A/noisy"
run "$D" simulate --camera "$YML" --rig "$A/eMc.yaml" --out-dir "$D" --arm orbit --arm-distance 0.7 --points 40 \
  --min-depth 0.5 --max-depth 0.9 --frames 8 --seed 5 --sigma-px 0.3 --sigma-odom 0.001 --sigma-rot 0.0009
run "$A/noisy_refine" estimate --method refine --camera "$YML" --rig "$A/eMc.yaml" --motion "$D/motion.csv" \
  --tracks "$D/tracks.csv" --sigma-yaw 0
res=$(awk -F, 'FNR == 1 { next } FILENAME == ARGV[1] { z[$1] = $8; next }
               $10 == "ok" { n++; e = $8 - z[$1]; if (e < 0) e = -e; if (e > 4 * $9) bad++ }
               END { if (n < 20 || bad > 0) print "ok " n+0 ", beyond 4 sigma " bad+0; else print "OK" }' "$D/truth.csv" "$A/noisy_refine.out")
[ "$res" = OK ] && pass || fail "estimate refine on a noisy 6-DoF orbit: $res"
# A board measured from the arm's poses.
D="$A/board"
run "$D" simulate --camera "$YML" --rig "$A/eMc.yaml" --out-dir "$D" --arm approach --arm-distance 0.6 --frames 4 \
  --pattern chessboard:5x4:0.03 --board-distance 0.6 --supersampling 2
if [ "$(rc_of "$D")" -ne 0 ]; then
  fail "simulate --arm --pattern: exit $(rc_of "$D"): $(first "$D.err")"
else
  run "$A/board_measure" measure --camera "$YML" --rig "$A/eMc.yaml" --motion "$D/motion.csv" \
    --pattern chessboard:5x4:0.03 --method exact --quiet
  res=$(awk -F, 'NR > 1 && $10 == "ok" { n++ } END { print n+0 }' "$A/board_measure.out")
  [ "$(rc_of "$A/board_measure")" -eq 0 ] && [ "$res" -ge 18 ] && pass ||
    fail "measure on a 6-DoF board sequence: exit $(rc_of "$A/board_measure"), $res ok rows: $(first "$A/board_measure.err")"
fi
# Bad 6-DoF input: one reason, non-zero exit.
printf 'camera_offset: [0, 0, 0]\ncamera_pose: [0, 0, 0, 0, 0, 0]\n' >"$A/both.yaml"
refused rig_both_forms "both 'camera_offset' and 'camera_pose'" estimate --camera "$YML" --rig "$A/both.yaml" \
  --motion "$A/sim_orbit/motion.csv" --tracks "$A/sim_orbit/tracks.csv"
printf 'frame,tx,ty,tz,tux,tuy\n0,0,0,0,0,0\n' >"$A/five.csv"
refused motion_missing_tuz "tuz" estimate --camera "$YML" --rig "$A/eMc.yaml" --motion "$A/five.csv" \
  --tracks "$A/sim_orbit/tracks.csv"
refused simulate_arm_with_step "excludes" simulate --camera "$YML" --rig "$A/eMc.yaml" --out-dir "$A/x" --arm orbit --step 0.1
}

sec_readme() {
# The README's worked example, verbatim: its two printed rows (zc 0.9749 and 0.4775 m, sigma_zc
# 0.0889 and 0.0334 m, to 4 decimals: the rows hold 17 digits) and the truth it quotes (0.958 and
# 0.531 m).
simulate_worked
run "$X.est" estimate --camera "$YML" --rig "$RIG" --motion "$X/motion.csv" --tracks "$X/tracks.csv" --out "$X/points.csv"
res=$(awk -F, 'FNR == 1 { next }
  FILENAME == ARGV[1] && FNR <= 3 { t = t sprintf("%.3f ", $8) }
  FILENAME == ARGV[2] && FNR <= 3 { e = e sprintf("%s %.4f %.4f %s ", $2, $8, $9, $10) }
  END { print t "| " e }' "$X/truth.csv" "$X/points.csv" 2>/dev/null)
want='0.958 0.531 | 9 0.9749 0.0889 ok 8 0.4775 0.0334 ok '
[ "$res" = "$want" ] && pass || fail "README worked example: got '$res', README has '$want'"
}

sec_usage() {
# ---------------------------------------------------------------------------
# 8. A command line without surprises (issue #34): usage errors name the command's help, an unknown
# option comes before a missing one (with a suggestion when one is close), renamed options keep
# their old names, --quiet/--verbose/--config/--print-config on every command, settings files,
# progress never on a pipe.
U="$W/usage"
mkdir -p "$U"
need_worked
# usage NAME WANT ARGS...: status 2, exactly the one stderr line WANT, nothing on stdout.
usage() {
  local name=$1 want=$2; shift 2
  run "$U/$name" "$@"
  local got; got=$(cat "$U/$name.err")
  if [ "$(rc_of "$U/$name")" -eq 2 ] && [ "$got" = "$want" ] && [ ! -s "$U/$name.out" ]; then pass; else
    fail "usage $name: exit $(rc_of "$U/$name"), stderr '$got', want '$want'"; fi
}
usage typo "yawdepth estimate: error: unknown option '--sigma-pxx' (did you mean --sigma-px?) (see yawdepth estimate --help)" \
  estimate --sigma-pxx 1
usage short_v "yawdepth estimate: error: unknown option '-v' (see yawdepth estimate --help)" estimate -v
usage cam "yawdepth estimate: error: unknown option '--cam' (did you mean --camera?) (see yawdepth estimate --help)" \
  estimate --cam x
usage far "yawdepth estimate: error: unknown option '--frobnicate' (see yawdepth estimate --help)" \
  estimate --camera "$YML" --frobnicate
usage required "yawdepth estimate: error: --camera is required (see yawdepth estimate --help)" estimate
usage bad_value "yawdepth estimate: error: --method: foo not in {paper,exact,fused,window,refine} (see yawdepth estimate --help)" \
  estimate --camera "$YML" --rig "$RIG" --motion m --tracks t --method foo
usage top_option "yawdepth: error: unknown option '--bogus' (see yawdepth --help)" --bogus
usage no_command "yawdepth: error: no command given (one of estimate, measure, track, error-analysis, simulate, calibrate-camera, calibrate-rig, import, import-bag) (see yawdepth --help)"
usage equals "yawdepth simulate: error: unknown option '--frame' (did you mean --frames?) (see yawdepth simulate --help)" \
  simulate --frame=3
for c in estimate measure track error-analysis simulate calibrate-camera calibrate-rig import import-bag; do
  run "$U/$c.unknown" "$c" --no-such-option
  [ "$(rc_of "$U/$c.unknown")" -eq 2 ] && [ "$(lines_of "$U/$c.unknown.err")" -eq 1 ] &&
    grep -q -F -e "yawdepth $c: error: unknown option '--no-such-option' (see yawdepth $c --help)" "$U/$c.unknown.err" &&
    pass || fail "$c --no-such-option: exit $(rc_of "$U/$c.unknown"): $(first "$U/$c.unknown.err")"
  # Every command knows --quiet, --verbose, --config and --print-config (the unknown option would come first).
  for o in --quiet --verbose; do
    run "$U/$c$o" "$c" "$o" --help
    [ "$(rc_of "$U/$c$o")" -eq 0 ] && grep -q -e "$o" "$U/$c$o.out" && grep -q -e '--config' "$U/$c$o.out" &&
      grep -q -e '--print-config' "$U/$c$o.out" && pass || fail "$c $o --help: exit $(rc_of "$U/$c$o"): $(first "$U/$c$o.err")"
  done
done
run "$U/qv" error-analysis --quiet --verbose
grep -q -F -e "--quiet excludes --verbose" "$U/qv.err" && [ "$(rc_of "$U/qv")" -eq 2 ] && pass || fail "--quiet --verbose: $(first "$U/qv.err")"
# Every angle option says (rad); the one in degrees says so in its name.
for c in simulate calibrate-rig error-analysis estimate; do "$YAWDEPTH" "$c" --help; done >"$U/helps.txt" 2>&1
res=$(awk '/^  --(yaw|yaw-rate|heading|turn-rate|board-tilt|initial-yaw-offset|sigma-heading|sigma-yaw|sigma-rot)[ ,]/ { n++; getline d; if ($0 !~ /\(rad/ && d !~ /\(rad/) print $1 }
           END { print n + 0 }' "$U/helps.txt" | tr '\n' ' ')
case $res in [0-9]*) [ "${res% }" -ge 12 ] && pass || fail "angle options: only $res seen" ;; *) fail "angle options without (rad): $res" ;; esac
grep -q -e '--min-yaw-span-deg' "$U/helps.txt" && pass || fail "calibrate-rig --help lacks --min-yaw-span-deg"

# Renamed options: the old name means the same (identical output) and warns.
run "$U/ea_new" error-analysis --view side --depth 1 --sigma-odom 0.002 --sigma-yaw 0.001 --sigma-px 0.2
run "$U/ea_old" error-analysis --view side --depth 1 --delta-dz 0.002 --delta-yaw 0.001 --delta-u 0.2
if [ "$(rc_of "$U/ea_old")" -eq 0 ] && cmp -s "$U/ea_new.out" "$U/ea_old.out" && [ ! -s "$U/ea_new.err" ] &&
  [ "$(grep -c 'is spelled --sigma-' "$U/ea_old.err")" -eq 3 ]; then pass; else
  fail "error-analysis --delta-* aliases: exit $(rc_of "$U/ea_old"), $(first "$U/ea_old.err")"; fi
run "$U/ea_cam" error-analysis --view side --depth 1 --camera "$XML"
run "$U/ea_kx" error-analysis --view side --depth 1 --kx "$(awk -F'[<>]' '/<px>/ { print $3; exit }' "$XML")"
[ "$(rc_of "$U/ea_cam")" -eq 0 ] && cmp -s "$U/ea_cam.out" "$U/ea_kx.out" && pass ||
  fail "error-analysis --camera is not --kx with the camera's px: $(first "$U/ea_cam.err")"
run "$U/ea_both" error-analysis --camera "$XML" --kx 1000
[ "$(rc_of "$U/ea_both")" -eq 2 ] && grep -q excludes "$U/ea_both.err" && pass || fail "error-analysis --camera --kx: $(first "$U/ea_both.err")"
RS="$U/rigsim"
run "$RS" simulate --camera "$YML" --rig "$RIG" --out-dir "$RS" --frames 7 --step 0 --yaw -0.03 --yaw-rate 0.01 \
  --pattern chessboard:7x5:0.03 --board-distance 0.8 --supersampling 2
run "$RS.old" calibrate-rig --camera "$YML" --motion "$RS/motion.csv" --pattern chessboard:7x5:0.03 --out "$RS/rig.yaml" --min-yaw-span 3
cp "$RS/rig.yaml" "$RS/rig_old.yaml" 2>/dev/null
run "$RS.new" calibrate-rig --camera "$YML" --motion "$RS/motion.csv" --pattern chessboard:7x5:0.03 --out "$RS/rig.yaml" --min-yaw-span-deg 3
if [ "$(rc_of "$RS.old")" -eq 0 ] && cmp -s "$RS.old.out" "$RS.new.out" && cmp -s "$RS/rig.yaml" "$RS/rig_old.yaml" &&
  [ "$(cat "$RS.old.err")" = "yawdepth calibrate-rig: warning: --min-yaw-span is spelled --min-yaw-span-deg now (the old name still works)" ] &&
  [ ! -s "$RS.new.err" ]; then pass; else fail "calibrate-rig --min-yaw-span alias: exit $(rc_of "$RS.old"): $(first "$RS.old.err")"; fi
run "$RS.old30" calibrate-rig --camera "$YML" --motion "$RS/motion.csv" --pattern chessboard:7x5:0.03 --out "$RS/r30.yaml" --min-yaw-span 30
run "$RS.new30" calibrate-rig --camera "$YML" --motion "$RS/motion.csv" --pattern chessboard:7x5:0.03 --out "$RS/r30.yaml" --min-yaw-span-deg 30
[ "$(rc_of "$RS.old30")" -eq 1 ] && cmp -s "$RS.old30.err" "$RS.new30.err" && grep -q 'spanning 30 deg' "$RS.new30.err" && pass ||
  fail "calibrate-rig --min-yaw-span 30 (degrees, both names): $(first "$RS.new30.err")"

# Settings files: read, overridden by the command line, printed, read back.
S="$U/settings"
mkdir -p "$S"
EST=(estimate --camera "$YML" --rig "$RIG" --motion "$X/motion.csv" --tracks "$X/tracks.csv")
run "$S/direct" "${EST[@]}" --method fused --sigma-px 0.5
run "$S/print" "${EST[@]}" --method fused --sigma-px 0.5 --print-config --out "$S/never.csv"
[ "$(rc_of "$S/print")" -eq 0 ] && [ ! -s "$S/print.err" ] && [ ! -e "$S/never.csv" ] &&
  grep -q '^sigma-px = 0.5$' "$S/print.out" && grep -q '^method = "fused"$' "$S/print.out" &&
  grep -q '^# sigma-odom = 0.001$' "$S/print.out" && pass || fail "--print-config: exit $(rc_of "$S/print"): $(first "$S/print.err")"
grep -v '^out = ' "$S/print.out" >"$S/run.toml"
run "$S/back" estimate --config "$S/run.toml"
[ "$(rc_of "$S/back")" -eq 0 ] && cmp -s "$S/direct.out" "$S/back.out" && pass ||
  fail "estimate --config (--print-config's file): not the same points: $(first "$S/back.err")"
run "$S/override" estimate --config "$S/run.toml" --sigma-px 0.3 --method exact
run "$S/plain" "${EST[@]}"
[ "$(rc_of "$S/override")" -eq 0 ] && cmp -s "$S/plain.out" "$S/override.out" && pass ||
  fail "the command line does not override --config: $(first "$S/override.err")"
# One robot file for every command: top-level keys of other commands' options are skipped.
printf '# the robot\ncamera = "%s"\nrig = "%s"\nsigma_px = 0.3\nsigma-odom = 0.001\nsigma-heading = 0.00087266\nsigma-yaw = 0.00087266\n[measure]\npattern = "chessboard:5x4:0.03"\n[simulate]\nframes = 10\nstep = 0.02\nyaw = 1.5708\npoints = 12\n[estimate]\nmethod = "exact"\n' \
  "$YML" "$RIG" >"$S/robot.toml"
run "$S/sim" simulate --config "$S/robot.toml" --out-dir "$S/sim"
run "$S/est" estimate --config "$S/robot.toml" --motion "$S/sim/motion.csv" --tracks "$S/sim/tracks.csv"
run "$S/worked" "${EST[@]}" --sigma-px 0.3 --sigma-odom 0.001 --sigma-heading 0.00087266 --sigma-yaw 0.00087266
[ "$(rc_of "$S/est")" -eq 0 ] && cmp -s "$S/sim/truth.csv" "$X/truth.csv" && cmp -s "$S/est.out" "$S/worked.out" && pass ||
  fail "one robot file for simulate and estimate (the README's worked example): $(first "$S/sim.err") $(first "$S/est.err")"
# The command line overrides the file also by an option that excludes the file's (--yaw, --view).
printf 'view = "side"\ndepth = 1\n' >"$S/view.toml"
run "$S/view_line" error-analysis --config "$S/view.toml" --yaw 0.3
run "$S/view_direct" error-analysis --depth 1 --yaw 0.3
[ "$(rc_of "$S/view_line")" -eq 0 ] && cmp -s "$S/view_line.out" "$S/view_direct.out" && pass ||
  fail "error-analysis --config (view) --yaw: exit $(rc_of "$S/view_line"): $(first "$S/view_line.err")"
# INI as well (';' comments, no quotes), a switch set to true.
printf '; the robot\ncamera=%s\nrig=%s\n[estimate]\nmethod=fused\nsigma-px=0.5\nquiet=true\n' "$YML" "$RIG" >"$S/robot.ini"
run "$S/ini" estimate --config "$S/robot.ini" --motion "$X/motion.csv" --tracks "$X/tracks.csv"
[ "$(rc_of "$S/ini")" -eq 0 ] && cmp -s "$S/direct.out" "$S/ini.out" && [ ! -s "$S/ini.err" ] && pass ||
  fail "estimate --config FILE.ini: $(first "$S/ini.err")"
printf 'sigma-px = 0.3\nsigma-pxx = 1\n' >"$S/typo.toml"
usage config_typo "yawdepth estimate: error: $S/typo.toml:2: unknown key 'sigma-pxx' for yawdepth estimate (did you mean sigma-px?) (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/typo.toml"
printf '[estimate]\nframes = 3\n' >"$S/section.toml"
usage config_section_key "yawdepth estimate: error: $S/section.toml:2: unknown key 'frames' for yawdepth estimate (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/section.toml"
printf '[bogus]\nx = 1\n' >"$S/bogus.toml"
usage config_bad_section "yawdepth estimate: error: $S/bogus.toml: [bogus] is not a yawdepth command (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/bogus.toml"
printf 'sigma-px = "abc"\n' >"$S/value.toml"
usage config_bad_value "yawdepth estimate: error: --sigma-px: 'abc' is not a number (set in $S/value.toml) (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/value.toml"
usage config_missing "yawdepth estimate: error: $S/none.toml: cannot read the settings file (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/none.toml"
printf 'no-gate = maybe\n' >"$S/switch.toml"
usage config_switch "yawdepth track: error: $S/switch.toml:1: 'no-gate' is a switch: true or false, not 'maybe' (see yawdepth track --help)" \
  track --camera "$YML" --motion "$X/motion.csv" --out "$S/t.csv" --config "$S/switch.toml"
# A review's cases: an option whose value was forgotten takes no setting as its value; a '#' in a
# value (CLI11 reads a comment there, even quoted) refused both ways; a folder or no name as --config;
# a [command] section's key over the same top-level key; a setting that needs an excluded one dropped;
# an error about an option of the line not blamed on the file (--outliers is not --out).
printf 'sigma-px = 0.5\n' >"$S/sp.toml"
usage config_forgotten_value "yawdepth estimate: error: --out: 1 required TEXT missing (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/sp.toml" --out
[ ! -e "$U/--sigma-px=0.5" ] && [ ! -e "./--sigma-px=0.5" ] && pass || fail "a setting became --out's value"
usage config_print_hash "yawdepth estimate: error: --print-config: the value of --out (run#2.csv) cannot be written in a settings file (a '#' reads as a comment, or both quotes): give it on the command line (see yawdepth estimate --help)" \
  "${EST[@]}" --out 'run#2.csv' --print-config
printf 'out = "run#2.csv"\n' >"$S/hash.toml"
usage config_read_hash "yawdepth estimate: error: $S/hash.toml:1: 'out': a value with '#' (or ';' in INI), which a settings file reads as a comment: give it on the command line (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/hash.toml"
usage config_folder "yawdepth estimate: error: $S: a folder, not a settings file (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S"
usage config_no_name "yawdepth estimate: error: --config needs a settings file's name (see yawdepth estimate --help)" \
  "${EST[@]}" --config= --print-config
printf 'sigma-px = 0.4\nquiet = true\n[estimate]\nsigma-px = 0.5\nquiet = false\n' >"$S/dup.toml"
run "$S/dup" "${EST[@]}" --config "$S/dup.toml" --print-config
[ "$(rc_of "$S/dup")" -eq 0 ] && grep -q '^sigma-px = 0.5$' "$S/dup.out" && grep -q '^# quiet = false$' "$S/dup.out" && pass ||
  fail "a [estimate] key does not win over the top-level one: $(first "$S/dup.err")"
printf 'camera = "%s"\ncamera-name = "x"\n' "$YML" >"$S/shared_camera.toml"
run "$S/kx" error-analysis --kx 800 --config "$S/shared_camera.toml"
[ "$(rc_of "$S/kx")" -eq 0 ] && [ ! -s "$S/kx.err" ] && pass ||
  fail "error-analysis --kx with a shared camera file: exit $(rc_of "$S/kx"): $(first "$S/kx.err")"
printf 'out = "%s"\n' "$S/o.csv" >"$S/out.toml"
usage config_not_blamed "yawdepth estimate: error: --outliers: At Most 1 required but received 2 (see yawdepth estimate --help)" \
  "${EST[@]}" --config "$S/out.toml" --outliers "$S/a.csv" --outliers "$S/b.csv"

# A negative number, or a list of them, is a value, not an unknown option.
run "$S/negative" calibrate-rig --camera "$YML" --motion "$X/motion.csv" --pattern chessboard:5x4:0.03 --out "$S/r.yaml" \
  --estimate-time-offset --time-offset-range -0.2,0.1 --initial-yaw-offset -0.5 --print-config
[ "$(rc_of "$S/negative")" -eq 0 ] && grep -q '^time-offset-range = \[-0.2, 0.1\]$' "$S/negative.out" &&
  grep -q '^initial-yaw-offset = -0.5$' "$S/negative.out" && pass ||
  fail "negative values: exit $(rc_of "$S/negative"): $(first "$S/negative.err")"
# --verbose: each stage's time on stderr; --quiet: nothing but warnings.
run "$S/verbose" "${EST[@]}" --verbose
[ "$(rc_of "$S/verbose")" -eq 0 ] && grep -q '^yawdepth estimate: done (' "$S/verbose.err" &&
  grep -q '^yawdepth estimate: exact on 12 tracks x 10 frames (' "$S/verbose.err" && cmp -s "$S/verbose.out" "$S/plain.out" &&
  pass || fail "estimate --verbose: $(first "$S/verbose.err")"
# Progress: never when stderr is not a terminal (a render of 300 boards takes over a second).
P="$U/progress"
run "$P" simulate --camera "$YML" --rig "$RIG" --out-dir "$P" --frames 300 --pattern chessboard:9x7:0.03 --supersampling 8
[ "$(rc_of "$P")" -eq 0 ] && [ ! -s "$P.err" ] && pass || fail "simulate with stderr on a file: $(first "$P.err")"
if command -v script >/dev/null 2>&1; then
  # On a terminal (script's pty): the updating line, ended by a newline; none with --quiet.
  script -qec "'$YAWDEPTH' simulate --camera '$YML' --rig '$RIG' --out-dir '$P.tty' --frames 300 --pattern chessboard:9x7:0.03 --supersampling 8" \
    /dev/null </dev/null >"$P.tty.log" 2>&1
  grep -q 'simulate: 300/300 images rendered' "$P.tty.log" && pass || fail "simulate on a terminal shows no progress: $(head -c 200 "$P.tty.log")"
  script -qec "'$YAWDEPTH' simulate --quiet --camera '$YML' --rig '$RIG' --out-dir '$P.ttyq' --frames 300 --pattern chessboard:9x7:0.03 --supersampling 8" \
    /dev/null </dev/null >"$P.ttyq.log" 2>&1
  ! grep -q 'images rendered' "$P.ttyq.log" && pass || fail "simulate --quiet on a terminal shows progress"
fi
}

for section in $SELECTED; do
  "sec_$section"
done

# No stray temporary files anywhere (one check per run: whichever sections ran).
left=$(find "$W" -name '.*.tmp*' | head -3)
[ -z "$left" ] && pass || fail "files: temporary files left: $left"

echo "$PASSED passed, $FAILED failed"
[ "$FAILED" -eq 0 ]
