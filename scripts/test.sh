#!/usr/bin/env bash
# Every check the project runs: formatting, lints, docs, all Rust tests, the
# core built without std (thumbv7em) and for WebAssembly, and the browser
# tests of the demo page, and the Python package's tests. Installs what it
# needs (targets, wasm-bindgen-cli, Chromium, playwright-core, a Python venv
# with maturin, numpy, pytest and pyrealsense2) when missing.
set -euo pipefail
cd "$(dirname "$0")/.."

for t in thumbv7em-none-eabihf wasm32-unknown-unknown; do
  rustup target list --installed | grep -qx "$t" || rustup target add "$t"
done

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== no module cycles (scripts/module_cycles.py; the fixtures must fail)"
python3 scripts/module_cycles.py
for fixture in module-cycle folder-cycle; do
  if python3 scripts/module_cycles.py "tests/data/$fixture" >/dev/null; then
    echo "module_cycles.py missed the cycle of tests/data/$fixture"; exit 1
  fi
done
echo "== file sizes (scripts/file_sizes.py)"
python3 scripts/file_sizes.py
echo "== clippy -D warnings"
cargo clippy --workspace --all-targets -- -D warnings
echo "== rustdoc -D warnings"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
echo "== core without std (thumbv7em-none-eabihf)"
cargo build -p upetrack-core --no-default-features --target thumbv7em-none-eabihf --quiet
echo "== core and synth for wasm32-unknown-unknown"
cargo build -p upetrack-core -p upetrack-synth --no-default-features --target wasm32-unknown-unknown --quiet
echo "== fuzz targets: seeds and saved regressions replayed (scripts/fuzz-replay.sh)"
./scripts/fuzz-replay.sh
echo "== tests"
cargo test --workspace

echo "== web page build"
./scripts/build-web.sh
cargo build --release -p upetrack-cli --quiet
echo "== browser tests (headless Chromium)"
if ! command -v chromium >/dev/null 2>&1; then
  apt-get update -qq && apt-get install -y -qq --no-install-recommends chromium >/dev/null
fi
(cd tests/browser && npm ci --no-audit --no-fund --silent && node run.mjs)

echo "== Python package: pip install ./python into a venv, then pytest"
if ! ldconfig -p | grep -q libusb-1.0; then
  # pyrealsense2's runtime, for the example played from genuine recordings.
  apt-get update -qq && apt-get install -y -qq --no-install-recommends libusb-1.0-0 >/dev/null
fi
venv=target/python-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check numpy pytest mypy pyrealsense2==2.59.1.11053
"$venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps ./python
UPETRACK_BIN="$PWD/target/release/upetrack" "$venv/bin/python" -m pytest -q python/tests
echo "== the type stubs against the built module (mypy's stubtest)"
(cd python && "../$venv/bin/python" -m mypy.stubtest --ignore-disjoint-bases upetrack._upetrack)
