#!/usr/bin/env bash
# The GPU bundle (scripts/make-gpu-bundle.sh) runs with a cleared environment and nothing of the host
# but its Vulkan driver; the library check of scripts/gpu_check.py finds a library the bundle lacks;
# a driver file that names its library bare is resolved to a path the bundle's loader can open, also
# when only LD_LIBRARY_PATH leads to it (where the original file fails).
#   tests/gpu_bundle/check_bundle.sh BUILD_DIR      (ctest; needs a Vulkan device: lavapipe in CI)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "$1" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
say() { echo "check_bundle: $*"; }
die() { echo "check_bundle: FAILED: $*" >&2; exit 1; }

(cd "$root" && scripts/make-gpu-bundle.sh --build "$build" --no-build --out "$tmp/gpu-bundle.tar.gz")
mkdir "$tmp/unpacked"
tar -C "$tmp/unpacked" -xzf "$tmp/gpu-bundle.tar.gz"
b=$tmp/unpacked/gpu-bundle

# 1. A cleared environment and an empty library path: both programs run, and agree with the CPU.
env -i LD_LIBRARY_PATH= "$b/bin/linespace-gpu" devices > "$tmp/devices.txt" || die "linespace-gpu devices failed"
grep -q '\[default\]' "$tmp/devices.txt" || die "no default device in: $(cat "$tmp/devices.txt")"
env -i LD_LIBRARY_PATH= "$b/bin/linespace-validate" hits --scene builtin:cornell --structure f-ls:3:6 --count 500 \
  > "$tmp/hits.txt" || die "linespace-validate hits failed: $(cat "$tmp/hits.txt")"
grep -q '500 compared, 0 mismatches' "$tmp/hits.txt" || die "hits: $(cat "$tmp/hits.txt")"
say "bundle runs with env -i: $(head -1 "$tmp/devices.txt")"

# 2. Every object the loader maps comes from the bundle, but the Vulkan drivers and what they need.
libs() {
  env -i LD_DEBUG=files "$b/lib/ld-linux-x86-64.so.2" --library-path "$b/lib:$b/lib-driver" "$b/libexec/linespace-gpu" \
    devices 2> "$tmp/$1.log" > /dev/null || die "linespace-gpu devices under LD_DEBUG failed"
  python3 "$root/scripts/gpu_check.py" libs "$tmp/$1.log" "$b" > "$tmp/$1.txt"
}
libs whole || die "a library came from the host: $(cat "$tmp/whole.txt")"
say "$(head -1 "$tmp/whole.txt")"

# 3. Planted: the bundle without its libpng.  The loader falls back on the host's copy (through the
#    host's ld.so.cache), and the check must name it.
rm "$b/lib/libpng16.so.16"
if libs planted; then die "a bundle without libpng16 passed the library check: $(cat "$tmp/planted.txt")"; fi
grep -q 'libpng16.so.16.*NOT from the bundle' "$tmp/planted.txt" || die "the check did not name libpng16: $(cat "$tmp/planted.txt")"
say "a missing libpng16 is reported"

# 4. A driver file naming its library by a bare name gets an absolute path, and the device runs through it.
lvp=$(python3 - <<'PY'
import glob, json
for f in sorted(glob.glob("/usr/share/vulkan/icd.d/lvp_icd*.json")):
    lib = json.load(open(f))["ICD"]["library_path"]
    if "x86_64" in f:
        print(lib)
PY
)
[[ -n $lvp ]] || die "no lavapipe driver file in /usr/share/vulkan/icd.d"
mkdir "$tmp/icd-in"
printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "%s", "api_version": "1.3.0"}}\n' \
  "$(basename "$lvp")" > "$tmp/icd-in/bare.json"
VK_DRIVER_FILES=$tmp/icd-in/bare.json python3 "$root/scripts/gpu_check.py" icd "$tmp/icd-out" > "$tmp/icd.txt"
files=$(sed -n 's/^VK_DRIVER_FILES=//p' "$tmp/icd.txt")
[[ $files == "$tmp/icd-out/"*.json ]] || die "no patched driver file: $(cat "$tmp/icd.txt")"
resolved=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["ICD"]["library_path"])' "$files")
[[ $(readlink -f "$resolved") == $(readlink -f "$lvp") ]] || die "bare $(basename "$lvp") resolved to '$resolved', not $lvp"
env -i VK_DRIVER_FILES="$files" "$b/bin/linespace-gpu" devices | grep -q llvmpipe || die "lavapipe did not run through $files"
say "bare $(basename "$lvp") resolved to $resolved"

# 5. The case the rewrite is for: a driver named bare, in a folder only LD_LIBRARY_PATH names (as a
#    container's GPU driver often is).  The bundle's loader cannot find it from the original file;
#    from the rewritten one, with the folder passed on, it runs.
mkdir -p "$tmp/driver/lib" "$tmp/driver/share/vulkan/icd.d"
cp "$lvp" "$tmp/driver/lib/libplanteddriver.so.0"
printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "libplanteddriver.so.0", "api_version": "1.3.0"}}\n' \
  > "$tmp/driver/share/vulkan/icd.d/planted_icd.json"
if env -i VK_DRIVER_FILES="$tmp/driver/share/vulkan/icd.d/planted_icd.json" "$b/bin/linespace-gpu" devices > /dev/null 2>&1; then
  die "the bundle found a driver that only LD_LIBRARY_PATH names without being told (the case proves nothing)"
fi
XDG_DATA_DIRS=$tmp/driver/share LD_LIBRARY_PATH=$tmp/driver/lib python3 "$root/scripts/gpu_check.py" icd "$tmp/icd-planted" \
  > "$tmp/icd-planted.txt"
files=$(sed -n 's/^VK_DRIVER_FILES=//p' "$tmp/icd-planted.txt" | tr ':' '\n' | grep planted_icd || true)
extra=$(sed -n 's/^LINESPACE_EXTRA_LIBRARY_PATH=//p' "$tmp/icd-planted.txt")
[[ -n $files ]] || die "the planted driver file was not rewritten: $(cat "$tmp/icd-planted.txt")"
env -i VK_DRIVER_FILES="$files" LINESPACE_EXTRA_LIBRARY_PATH="$extra" "$b/bin/linespace-gpu" devices | grep -q llvmpipe ||
  die "the rewritten driver file did not load: $(cat "$tmp/icd-planted.txt")"
say "a driver only LD_LIBRARY_PATH names loads from its rewritten file"
