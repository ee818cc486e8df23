#!/usr/bin/env bash
# Builds the page and serves the repository at http://127.0.0.1:${PORT:-8000}/web/
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/build-web.sh
port=${PORT:-8000}
echo "open http://127.0.0.1:$port/web/"
exec python3 -m http.server "$port" --bind 127.0.0.1
