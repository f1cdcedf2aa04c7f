#!/usr/bin/env bash
# Keeps docs/tutorial.md honest: runs, as written and in order, every fenced code block that follows
# a `<!-- tutorial-test -->` line, in a scratch folder laid out like the repository (build/tools/yawdepth,
# tests/, examples/, calib/ linked in), with bash -euo pipefail. Fails when any command fails.
# Usage: YAWDEPTH=path/to/yawdepth SOURCE_DIR=repo bash tests/docs_tutorial.sh
# Exits 77 (CTest's skip) when the yawdepth under test lacks an option the tutorial uses (--config),
# so a tree built before that option is told apart from a broken tutorial.
set -euo pipefail
Y=${YAWDEPTH:?set YAWDEPTH to the yawdepth executable}
SRC=${SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
DOC=${TUTORIAL:-$SRC/docs/tutorial.md}
[ -x "$Y" ] || { echo "docs_tutorial: $Y is not an executable" >&2; exit 1; }
[ -f "$DOC" ] || { echo "docs_tutorial: $DOC not found" >&2; exit 1; }

if ! "$Y" measure --help 2>/dev/null | grep -q -- '--config'; then
  echo "docs_tutorial: SKIP: this yawdepth has no 'measure --config', which the tutorial uses" >&2
  exit 77
fi

W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
mkdir -p "$W/build/tools"
ln -s "$(readlink -f "$Y")" "$W/build/tools/yawdepth"
for d in tests examples calib; do ln -s "$SRC/$d" "$W/$d"; done

# The marked blocks, in order, as one script: a block starts at the first ``` line after the marker.
script=$W/tutorial_blocks.sh
awk '
  /^<!-- tutorial-test -->[[:space:]]*$/ { armed = 1; next }
  armed && !inside && /^```/ { inside = 1; blocks++; printf "echo \"== docs_tutorial: block %d (line %d)\" >&2\n", blocks, NR; next }
  inside && /^```[[:space:]]*$/ { inside = 0; armed = 0; next }
  inside { print }
  END { if (blocks == 0) exit 1 }
' "$DOC" > "$script" || { echo "docs_tutorial: no <!-- tutorial-test --> block in $DOC" >&2; exit 1; }

echo "docs_tutorial: $(grep -c '^echo "== docs_tutorial' "$script") blocks from $DOC, run in $W" >&2
cd "$W"
start=$SECONDS
bash -euo pipefail "$script"
echo "docs_tutorial: every block ran ($((SECONDS - start)) s)" >&2
