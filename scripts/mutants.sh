#!/usr/bin/env bash
# Mutation testing of the core's formula and rule modules with cargo-mutants
# (installed from crates.io when missing): each mutant is built and the
# core's own tests (unit and integration) must fail on it. Results go to
# target/mutants/mutants.out (caught.txt, missed.txt, timeout.txt,
# unviable.txt); docs/testing.md lists the missed mutants that are
# equivalent. Not part of CI: about an hour on 2 cores.
#
#   scripts/mutants.sh [extra cargo-mutants arguments, e.g. --list]
set -euo pipefail
cd "$(dirname "$0")/.."
command -v cargo-mutants >/dev/null 2>&1 || cargo install cargo-mutants --locked
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
)
args=()
for f in "${files[@]}"; do args+=(--file "$f"); done
exec cargo mutants --package upetrack-core "${args[@]}" --timeout 120 --output target/mutants "$@" -- --package upetrack-core
