#!/usr/bin/env bash
# scripts/gpu-check.sh on a planted bundle whose programs print known answers: a hits check with 3
# mismatches, an rmse that differs between CPU and device, a step that runs past the time budget,
# libraries from the host.  The check must exit 1 and its gpu-check.md and gpu-check.json must say
# each of these; the bench ratios must be those of the planted MRays/s.
#   tests/gpu_bundle/check_report.sh        (ctest; needs no Vulkan device)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
die() { echo "check_report: FAILED: $*" >&2; exit 1; }
b=$tmp/bundle
mkdir -p "$b"/{bin,lib,libexec}
loader=$(ldd /bin/true | awk '$1 ~ /ld-linux-x86-64/ && !f {print $1; f = 1}')
cp -L "$loader" "$b/lib/ld-linux-x86-64.so.2"
cp /bin/true "$b/libexec/linespace-gpu"   # loads the host's libc: the library check must object

cat > "$b/bin/linespace-gpu" <<'SH'
#!/bin/sh
case $1 in
  devices) echo '{"devices": [{"index": 0, "name": "Planted GPU", "type": "discrete", "api_version": "1.3.0",
             "driver_name": "planted", "driver_info": "1.0", "compute": true, "default": true}]}' ;;
  bench) echo '{"results": [{"structure": "bvh", "mrays_per_s": 100.0}, {"structure": "2l-bvh", "mrays_per_s": 50.0},
           {"structure": "f-ls:8:6", "mrays_per_s": 400.0}, {"structure": "2l-ls:4:6", "mrays_per_s": 150.0}]}' ;;
  *) exit 2 ;;
esac
SH
cat > "$b/bin/linespace-validate" <<'SH'
#!/bin/sh
cmd=$1; shift
structure= out= device=
while [ $# -gt 0 ]; do
  case $1 in --structure) structure=$2 ;; --out) out=$2 ;; --device) device=$2 ;; esac
  shift
done
case $cmd in
  candidates) echo "candidates, planted: 38880 compared, 0 mismatches" ;;
  hits)
    if [ "$structure" = bvh ]; then
      echo "hits, planted: 500 compared, 3 mismatches"
      echo "  ray 7: t=1 (0x3f800000) instance=0 triangle=4 | t=1.00000012 (0x3f800001) instance=0 triangle=4"
      exit 1
    fi
    echo "hits, planted: 500 compared, 0 mismatches" ;;
  rmse)
    mkdir -p "$out"
    f=0.01; [ "$device" = gpu ] && f=0.0100001
    printf '{"rows": [{"structure": "bvh", "start_bounce": 1, "rmse": 0.0, "mrays_per_s": 1.0},
      {"structure": "f-ls:8:6", "start_bounce": 1, "rmse": %s, "mrays_per_s": 2.0}]}\n' "$f" > "$out/rmse.json"
    [ "$device" = gpu ] && exec sleep 100   # past the budget: gpu-check must stop it
    ;;
esac
SH
chmod +x "$b/bin/"*

set +e
"$root/scripts/gpu-check.sh" --quick --bundle "$b" --out "$tmp/out" --budget 12 > "$tmp/stdout" 2> "$tmp/stderr"
rc=$?
set -e
md=$tmp/out/gpu-check.md
[[ $rc == 1 ]] || die "exit $rc, not 1: $(cat "$tmp/stderr")"
[[ -f $md && -f $tmp/out/gpu-check.json && -f $tmp/out/gpu-check-logs.tar.gz ]] || die "missing outputs: $(ls "$tmp/out")"
expect() { grep -qF -- "$1" "$md" || die "gpu-check.md lacks '$1':
$(cat "$md")"; }
expect "device: **Planted GPU** (discrete, Vulkan 1.3.0), driver planted 1.0"
expect "| hits | builtin:cornell | bvh | 500 | 3 | exit 1 |"
expect "ray 7: t=1 (0x3f800000) instance=0 triangle=4 | t=1.00000012 (0x3f800001)"
expect "| candidates | builtin:cornell | f-ls:8:6 | 38880 | 0 | ok |"
expect "| builtin:cornell | f-ls:8:6 | 400.00 | 4.00 | 377.0 | 5.33 |"
expect "| builtin:cornell | 2l-bvh | 50.00 | 0.50 | 34.3 | 0.49 |"
expect "| builtin:cornell | f-ls:8:6 | 0.01 | 0.0100001 | **no** |"
expect "| rmse-gpu | "
grep -q '^| rmse-gpu | [0-9]* | [0-9.]* | timed out |' "$md" || die "rmse-gpu is not 'timed out': $(grep rmse-gpu "$md")"
grep -q 'not from the bundle though they should be: [1-9]' "$md" || die "host libraries not reported"
python3 - "$tmp/out/gpu-check.json" <<'PY' || die "gpu-check.json: $(head -c 2000 "$tmp/out/gpu-check.json")"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["passed"] is False
assert "hits bvh on builtin:cornell: 3 mismatches" in r["problems"], r["problems"]
assert any(p.startswith("rmse of f-ls:8:6 from bounce 1") for p in r["problems"]), r["problems"]
assert any(p.startswith("rmse (rmse-gpu): timed out") for p in r["problems"]), r["problems"]
assert r["device"]["name"] == "Planted GPU"
PY
echo "check_report: a planted mismatch, rmse difference, time-out and host library are each reported"
