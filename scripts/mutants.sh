#!/usr/bin/env bash
# Mutation testing with cargo-mutants (installed from crates.io when
# missing): each mutant is built and the crate's own tests (unit and
# integration) must fail on it. Results go to target/mutants-<crate>/
# mutants.out (caught.txt, missed.txt, timeout.txt, unviable.txt);
# docs/testing.md lists the counts and the missed mutants that are
# equivalent. Not part of CI: an hour or more per crate on 2 cores.
#
#   scripts/mutants.sh [core|recordings|io] [extra cargo-mutants arguments, e.g. --list]
set -euo pipefail
cd "$(dirname "$0")/.."
command -v cargo-mutants >/dev/null 2>&1 || cargo install cargo-mutants --locked
crate=${1:-core}
[ $# -gt 0 ] && shift
case "$crate" in
  core)
    package=upetrack-core
    files=(
      core/src/upe/registration.rs
      core/src/upe/occlusion.rs
      core/src/upe/resampling.rs
      core/src/polyline.rs
      core/src/visibility.rs
      core/src/upe/mod.rs
      core/src/upe/slide.rs
      core/src/upe/length.rs
      core/src/upe/free_space.rs
      core/src/perception/evidence.rs
      core/src/metrics.rs
      core/src/perception/segmentation.rs
      core/src/perception/initialisation/skeleton.rs
      core/src/perception/initialisation/graph.rs
      core/src/perception/initialisation/candidates.rs
      core/src/perception/initialisation/lift.rs
      core/src/perception/initialisation/mod.rs
      core/src/params.rs
      core/src/validation.rs
    ) ;;
  recordings)
    # The parsers' bounds: the SQLite reader, the chunked containers' shared
    # rules, the one image decoding path, the store and rosbag2.
    package=upetrack-recordings
    files=(
      recordings/src/sqlite.rs
      recordings/src/chunks.rs
      recordings/src/images.rs
      recordings/src/store.rs
      recordings/src/rosbag2.rs
    ) ;;
  io)
    # The input rules io's own tests cover (the rest is tested through the
    # command, in cli/tests, which this run does not build).
    package=upetrack-io
    files=(
      io/src/capped.rs
      io/src/open.rs
      io/src/decode.rs
      io/src/archive.rs
    ) ;;
  *) echo "unknown crate $crate (core, recordings or io)"; exit 2 ;;
esac
args=()
for f in "${files[@]}"; do args+=(--file "$f"); done
exec cargo mutants --package "$package" "${args[@]}" --timeout 120 --output "target/mutants-$crate" "$@" -- --package "$package"
