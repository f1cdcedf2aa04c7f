#!/usr/bin/env bash
# Every accuracy and speed table of the docs, regenerated: each table sits between two markers
#
#   <!-- update_docs: ID -->
#   ...
#   <!-- /update_docs: ID -->
#
# in README.md, docs/*.md or examples/*/README.md, and is the verbatim standard output of the command registered for ID
# below, with a stamp line (the command, its exit status, the commit, the date, the machine) so that
# a stale table shows its age. A benchmark that misses a target it states exits non-zero: its table is
# still written (it shows the miss), the script names it and exits 1.
#
#   tools/update_docs.sh [--build DIR] [ID ...]   regenerate the tables (all, or the IDs given)
#   tools/update_docs.sh --list                   each table: ID, page, stamped commit, and how many
#                                                 commits to modules/, benchmarks/, examples/ or tools/
#                                                 came since (a table with commits since may be stale)
#   tools/update_docs.sh --check                  the markers against the registry: every marker pair
#                                                 well formed and registered, every registered ID on a
#                                                 page exactly once, every table stamped (ctest docs_tables)
#
# The build tree (default build/) must hold the benchmarks and examples (tools/bootstrap.sh build);
# corners-real reads OpenCV's sample photos (apt-get install opencv-doc), import-bag-1gb the npm
# writers of tests/data/bags/writers (npm ci there). Regenerating all of them takes about an hour on
# two cores: bench_import_bag writes 3 GB of bags.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
B=build
mode=update
ids=()
while (($#)); do
  case "$1" in
    --build) B=${2:?--build needs a folder}; shift 2 ;;
    --list) mode=list; shift ;;
    --check) mode=check; shift ;;
    -h|--help) sed -n "2,24p" "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "update_docs.sh: unknown option $1 (see tools/update_docs.sh --help)" >&2; exit 2 ;;
    *) ids+=("$1"); shift ;;
  esac
done
Y=$B/tools/yawdepth

# The registry: ID, then the command (run by bash from the repository's root; $B is the build tree,
# $Y the yawdepth binary). One line per table.
registry() {
  cat <<'EOF'
paper-experiment	examples/paper_experiment.sh "$Y" "$B/paper_experiment"
bench-accuracy	"$B/benchmarks/bench_accuracy"
refine-scale-wall	"$B/benchmarks/bench_refine_scale" --scene wall --points 300,1000 --frames 100,200,500,1000
refine-scale-in-view	"$B/benchmarks/bench_refine_scale" --scene in-view --points 100,1000 --frames 100,200,500 --limit 180
window-30-frames	"$B/benchmarks/bench_accuracy" --trials 100 --frames 30
window-cost	"$B/benchmarks/bench_window" --quick
window-long	"$B/benchmarks/bench_window" --frames 1000 --trials 4 --no-cost
window-long-correlated	"$B/benchmarks/bench_window" --no-cost --frames 600 --trials 4 --pixel-correlation 0.9
active-yaw	"$B/benchmarks/bench_active_yaw" --seeds 20
servo-yawing	examples/servo_table.sh "$B/examples/servo_ibvs_yawing_camera"
servo-pioneer	examples/servo_table_pioneer.sh "$B/examples/servo_pioneer_pan" 10
servo-4pts	examples/servo_table_4pts.sh "$B/examples/servo_ibvs_4pts" 8 5 0.3
castle	"$B/benchmarks/bench_castle"
castle-fused	"$B/benchmarks/bench_castle" --method fused
castle-refine	"$B/benchmarks/bench_castle" --method refine
tracker-errors	"$B/benchmarks/bench_tracker_errors"
wide-baseline	"$B/benchmarks/bench_wide_baseline"
klt-accuracy	"$B/benchmarks/bench_klt" --no-cost
klt-accuracy-fused	"$B/benchmarks/bench_klt" --no-cost --method fused
klt-accuracy-refine	"$B/benchmarks/bench_klt" --no-cost --method refine
klt-cost	"$B/benchmarks/bench_klt" --repeat 3 --max-features 340 --no-accuracy
two-planes	"$B/benchmarks/bench_two_planes"
import-bag-1gb	benchmarks/bench_import_bag.sh "$Y" 1024
franka-measure	examples/franka_measure.sh "$Y"
ros-calibration	/usr/bin/python3 benchmarks/ros_calibration_compare.py --yawdepth "$Y" --data tests/data/franka-eye-in-hand
corners-real	"$B/benchmarks/bench_corners" --set opencv-left:9x6:0.025:$(ls /usr/share/doc/opencv-doc/examples/data/left[01]*.jpg | paste -sd,) --set opencv-right:9x6:0.025:$(ls /usr/share/doc/opencv-doc/examples/data/right[01]*.jpg | paste -sd,)
time-offset	"$B/benchmarks/bench_time_offset"
online-latency	"$B/benchmarks/bench_online" --seconds 10 --max-features 300 --method window --warmup 5
bag-drive	examples/bag_drive/run.sh "$Y"
python-cost	/usr/bin/python3 benchmarks/bench_python.py --build "$B"
EOF
}
command_of() { registry | awk -F'\t' -v id="$1" '$1 == id { print $2 }'; }

pages() { ls README.md docs/*.md examples/*/README.md 2>/dev/null || true; }

# Marker lines, as "PAGE<TAB>LINE<TAB>open|close<TAB>ID".
markers() {
  pages | while read -r p; do
    { grep -n -E '^<!-- /?update_docs: [A-Za-z0-9_-]+ -->$' "$p" || true; } |
      sed -E "s|^([0-9]+):<!-- (/?)update_docs: ([A-Za-z0-9_-]+) -->$|$p\t\1\t\2\t\3|" |
      awk -F'\t' -v OFS='\t' '{ print $1, $2, ($3 == "/" ? "close" : "open"), $4 }'
  done
}

check() {
  local bad=0 m reg id n
  m=$(markers)
  # Pairs: on each page, open ID then close ID, not nested.
  if ! awk -F'\t' '
      $3 == "open"  { if (cur != "") { printf "%s:%d: update_docs: %s opened inside %s\n", $1, $2, $4, cur; bad = 1 }
                      cur = $4; page = $1; next }
      $3 == "close" { if (cur != $4 || page != $1) { printf "%s:%d: update_docs: /%s closes %s\n", $1, $2, $4, (cur == "" ? "nothing" : cur); bad = 1 }
                      cur = "" }
      END { if (cur != "") { printf "%s: update_docs: %s never closed\n", page, cur; bad = 1 } exit bad }' <<<"$m" >&2; then
    bad=1
  fi
  reg=$(registry | cut -f1)
  while read -r id; do
    [ -n "$id" ] || continue
    grep -qx -- "$id" <<<"$reg" || { echo "update_docs.sh: table '$id' ($(awk -F'\t' -v id="$id" '$4 == id && $3 == "open" { print $1 ":" $2 }' <<<"$m")) has no command in the registry" >&2; bad=1; }
  done < <(awk -F'\t' '$3 == "open" { print $4 }' <<<"$m" | sort -u)
  while read -r id; do
    n=$(awk -F'\t' -v id="$id" '$3 == "open" && $4 == id' <<<"$m" | wc -l)
    [ "$n" -eq 1 ] || { echo "update_docs.sh: registered table '$id' is on the pages $n times (expected once)" >&2; bad=1; }
  done <<<"$reg"
  [ "${1:-}" = --no-stamps ] && return "$bad"
  # Every table stamped: the line after the opening marker is the stamp.
  while IFS=$'\t' read -r p l kind id; do
    [ "$kind" = open ] || continue
    sed -n "$((l + 1))p" "$p" | grep -q '^<sub>Generated by `tools/update_docs.sh' ||
      { echo "$p:$((l + 1)): update_docs: table '$id' has no stamp line (run tools/update_docs.sh $id)" >&2; bad=1; }
  done <<<"$m"
  [ "$bad" -eq 0 ] && echo "update_docs.sh: $(registry | wc -l) tables, markers and registry agree"
  return "$bad"
}

list() {
  printf '%-22s %-28s %-10s %s\n' ID PAGE COMMIT "COMMITS SINCE (modules benchmarks examples tools)"
  while IFS=$'\t' read -r p l kind id; do
    [ "$kind" = open ] || continue
    local c since
    c=$(sed -n "$((l + 1))p" "$p" | sed -nE 's/.*commit `([0-9a-f]+)`.*/\1/p')
    if [ -n "$c" ] && git cat-file -e "$c^{commit}" 2>/dev/null; then
      since=$(git rev-list --count "$c..HEAD" -- modules benchmarks examples tools)
    else
      since="?"
    fi
    printf '%-22s %-28s %-10s %s\n' "$id" "$p" "${c:-none}" "$since"
  done < <(markers)
}

machine() {
  local cpu
  cpu=$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2 | sed 's/^ *//;s/  */ /g')
  echo "${cpu:-$(uname -m)}, $(nproc) cores"
}

# Replace table ID's block on PAGE by the stamp and the output file's text in a code block.
replace_block() { # PAGE ID STAMP OUTPUT_FILE
  python3 - "$@" <<'PY'
import sys
page, tid, stamp, out = sys.argv[1:5]
text = open(page, encoding="utf-8").read().split("\n")
body = open(out, encoding="utf-8", errors="replace").read().rstrip("\n")
fence = "```"
while fence in body:
    fence += "`"
o, c = text.index(f"<!-- update_docs: {tid} -->"), text.index(f"<!-- /update_docs: {tid} -->")
text[o + 1:c] = [stamp, fence] + body.split("\n") + [fence]
open(page, "w", encoding="utf-8").write("\n".join(text))
PY
}

update() {
  check --no-stamps >/dev/null || { echo "update_docs.sh: fix the markers first" >&2; return 1; }
  local m commit dirty stamp_machine today failed=() id cmd page rc out t0
  m=$(markers)
  commit=$(git rev-parse --short=10 HEAD)
  dirty=$(git status --porcelain --untracked-files=no -- modules benchmarks examples tools)
  stamp_machine=$(machine)
  today=$(date -u +%Y-%m-%d)
  ((${#ids[@]})) || mapfile -t ids < <(registry | cut -f1)
  out=$(mktemp)
  trap 'rm -f "$out"' RETURN
  for id in "${ids[@]}"; do
    cmd=$(command_of "$id")
    [ -n "$cmd" ] || { echo "update_docs.sh: no table '$id' in the registry" >&2; rm -f "$out.err"; return 2; }
    page=$(awk -F'\t' -v id="$id" '$3 == "open" && $4 == id { print $1 }' <<<"$m")
    t0=$SECONDS rc=0
    echo "== update_docs: $id ($page): $cmd" >&2
    B=$B Y=$Y bash -c "$cmd" >"$out" 2>"$out.err" || rc=$?
    if [ ! -s "$out" ]; then
      echo "update_docs.sh: $id printed nothing (exit $rc); its table is kept:" >&2
      tail -5 "$out.err" >&2
      failed+=("$id")
      continue
    fi
    local shown=${cmd//\"/}
    shown=${shown//\$B/$B}
    shown=${shown//\$Y/$Y}
    replace_block "$page" "$id" \
      "<sub>Generated by \`tools/update_docs.sh $id\`: \`$shown\` (exit $rc, $((SECONDS - t0)) s), commit \`$commit\`${dirty:+ with uncommitted changes}, $today, $stamp_machine.</sub>" \
      "$out"
    [ "$rc" -eq 0 ] || { failed+=("$id"); echo "update_docs.sh: $id exited $rc (a target missed?): its table shows it" >&2; }
  done
  rm -f "$out.err"
  if ((${#failed[@]})); then
    echo "update_docs.sh: not clean: ${failed[*]}" >&2
    return 1
  fi
}

case "$mode" in
  check) check ;;
  list) list ;;
  update) update ;;
esac
