#!/usr/bin/env bash
# Every check the project runs: formatting, lints, docs, all tests, and the
# core built without std (thumbv7em) and for WebAssembly.
set -euo pipefail
cd "$(dirname "$0")/.."

for t in thumbv7em-none-eabihf wasm32-unknown-unknown; do
  rustup target list --installed | grep -qx "$t" || rustup target add "$t"
done

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== clippy -D warnings"
cargo clippy --workspace --all-targets -- -D warnings
echo "== rustdoc -D warnings"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
echo "== core without std (thumbv7em-none-eabihf)"
cargo build -p upetrack-core --no-default-features --target thumbv7em-none-eabihf --quiet
echo "== core and synth for wasm32-unknown-unknown"
cargo build -p upetrack-core -p upetrack-synth --no-default-features --target wasm32-unknown-unknown --quiet
echo "== tests"
cargo test --workspace
