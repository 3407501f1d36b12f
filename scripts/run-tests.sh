#!/usr/bin/env bash
# README command 2: install, build, and run the whole test suite (CI runs exactly this).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
ctest --preset release
