#!/usr/bin/env bash
# Installs missing dependencies, then configures and builds the release preset.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/configure.sh release >/dev/null
cmake --build --preset release -j "$(nproc)"
