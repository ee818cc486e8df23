#!/usr/bin/env bash
# Builds the WebAssembly package (an npm package: web/pkg/package.json) with
# wasm-pack, and the sample index; installs the wasm target, wasm-bindgen-cli
# (the exact version in Cargo.lock) and wasm-pack if missing.
set -euo pipefail
cd "$(dirname "$0")/.."
WASM_PACK_VERSION=0.15.1

rustup target list --installed | grep -qx wasm32-unknown-unknown || rustup target add wasm32-unknown-unknown
want=$(awk '/^name = "wasm-bindgen"$/ {getline; gsub(/"/, "", $3); print $3; exit}' Cargo.lock)
have=$(wasm-bindgen --version 2>/dev/null | awk '{print $2}' || true)
if [ "$have" != "$want" ]; then
  echo "installing wasm-bindgen-cli $want"
  cargo install wasm-bindgen-cli --version "=$want" --locked || cargo install wasm-bindgen-cli --version "=$want"
fi
# wasm-pack, pinned; offline: the wasm-bindgen above (--mode no-install), no
# wasm-opt download (--no-opt; wasm-opt runs below when a good one is here).
if [ "$(wasm-pack --version 2>/dev/null | awk '{print $2}')" != "$WASM_PACK_VERSION" ]; then
  echo "installing wasm-pack $WASM_PACK_VERSION"
  cargo install wasm-pack --version "=$WASM_PACK_VERSION" --locked
fi
wasm-pack --quiet build wasm --target web --release --mode no-install --no-opt --no-typescript --out-dir ../web/pkg
if command -v wasm-opt >/dev/null 2>&1 && wasm-opt --version 2>/dev/null | grep -q 'version 1[1-9][0-9]'; then
  wasm-opt -O2 web/pkg/upetrack_wasm_bg.wasm -o web/pkg/upetrack_wasm_bg.wasm || true
fi

# samples/index.json: every sample folder with its files, for the page.
python3 - <<'PY'
import json, os
root = "samples"
out = []
for name in sorted(os.listdir(root)):
    d = os.path.join(root, name)
    if not os.path.isdir(d):
        continue
    files = []
    for dirpath, _, names in os.walk(d):
        for n in names:
            files.append(os.path.relpath(os.path.join(dirpath, n), d).replace(os.sep, "/"))
    readme = ""
    out.append({"name": name, "files": sorted(files)})
with open(os.path.join(root, "index.json"), "w") as f:
    json.dump({"samples": out}, f, indent=1)
PY
echo "web/pkg and samples/index.json are ready"
