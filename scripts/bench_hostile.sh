#!/usr/bin/env bash
# The readers' work and memory on hostile recordings against the genuine ones
# they were made from: `upetrack track` on each, wall time and peak resident
# memory (GNU time), and how it ended. Make the files first:
#   python3 scripts/hostile_recordings.py OUT_DIR
#   scripts/bench_hostile.sh OUT_DIR [path/to/upetrack]
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:?usage: bench_hostile.sh OUT_DIR [UPETRACK]}
exe=${2:-target/release/upetrack}
dlo=tests/recordings/dlo.json
out=$(mktemp)
printf '%-40s %8s %10s  %s\n' file seconds "peak MB" "how it ended"
for f in tests/recordings/librealsense.db3 tests/recordings/librealsense.bag tests/recordings/ros2_png.mcap "$dir"/*; do
  args=(track "$f" --out "$out.json")
  case "$f" in *librealsense* | *db3-* | *bag-*) args+=(--dlo "$dlo") ;; esac
  set +e
  /usr/bin/time -f '%e %M' -o "$out.time" "$exe" "${args[@]}" >"$out.log" 2>&1
  rc=$?
  set -e
  read -r secs kb < <(tail -1 "$out.time")
  if [ $rc -eq 0 ]; then ended="tracked: $(grep -o '[0-9]* frames tracked' "$out.log" | head -1)"; else ended="refused: $(grep -v '^Command' "$out.log" | tail -1 | cut -c1-90)"; fi
  printf '%-40s %8s %10d  %s\n' "$(basename "$f")" "$secs" $((kb / 1024)) "$ended"
done
rm -f "$out" "$out".*
