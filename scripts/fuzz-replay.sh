#!/usr/bin/env bash
# Replays every fuzz target's seeds (fuzz/seeds/<target>/) and saved
# regression inputs (fuzz/regressions/<target>/: inputs that once crashed or
# that stand for a bad-input catalogue entry) once each, on stable Rust: the
# targets are built as plain binaries (libFuzzer runs the files given to it
# and exits non-zero on a crash). Fuzzing itself needs cargo-fuzz; see
# docs/testing.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet --manifest-path fuzz/Cargo.toml --release
targets=$(sed -n 's/^name = "\(.*\)"$/\1/p' fuzz/Cargo.toml | grep -v '^upetrack-fuzz$')
status=0
for t in $targets; do
  inputs=()
  for d in "fuzz/seeds/$t" "fuzz/regressions/$t"; do
    [ -d "$d" ] && while IFS= read -r -d '' f; do inputs+=("$f"); done < <(find "$d" -type f -print0)
  done
  if [ ${#inputs[@]} -eq 0 ]; then
    echo "fuzz target $t has no seeds"; status=1; continue
  fi
  if fuzz/target/release/"$t" "${inputs[@]}" > "fuzz/target/replay-$t.log" 2>&1; then
    echo "fuzz target $t: ${#inputs[@]} inputs replayed, no crash"
  else
    echo "fuzz target $t CRASHED on a replayed input:"; tail -20 "fuzz/target/replay-$t.log"; status=1
  fi
done
exit $status
