# What the servo evidence tables share (sourced by servo_table.sh, servo_table_4pts.sh and
# servo_table_pioneer.sh): one run's closing lines and the fields the tables read from them.

# last_lines N BIN ARGS...: the run's last N lines (a diverged run's exit status is not an error here).
last_lines() {
  local n=$1; shift
  "$@" | tail -"$n" || true
}

# field NAME TEXT: the number after NAME= in TEXT (empty when TEXT has none).
field() { sed -n "s/.*$1=\([0-9.eE+-]*\).*/\1/p" <<<"$2"; }

# not_converged TEXT: 0 when the last line of TEXT says converged, else 1.
not_converged() { case $(tail -1 <<<"$1") in converged*) echo 0 ;; *) echo 1 ;; esac; }

# mode_runs "FIELD..." ARGS...: for each "label:args" of the caller's modes and each seed 1..$seeds,
# one quiet run of $bin with ARGS, the seed and the mode's args; prints label|seed|FIELD...|diverged.
mode_runs() {
  local fields=$1 m s f out line
  shift
  for m in "${modes[@]}"; do
    for s in $(seq 1 "$seeds"); do
      out=$(last_lines 2 "$bin" "$@" --seed "$s" --quiet ${m#*:})
      line="${m%%:*}|$s"
      for f in $fields; do line+="|$(field "$f" "$out")"; done
      echo "$line|$(not_converged "$out")"
    done
  done
}
