#!/usr/bin/env bash
# Installs what is missing, builds, runs the whole test suite, then the sanitizer and fuzz runs.
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/install-deps.sh
deploy/build.sh
ctest --test-dir build --output-on-failure -j"${JOBS:-2}"
deploy/sanitize.sh
