# Sourced by the linespace-profile checks: the programs of BUILD_DIR ($1), a scratch folder removed
# on exit, and fail().
set -euo pipefail
build=$1
cpu=$build/cpu/linespace-cpu
profile=$build/cpu/linespace-profile
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
