#!/usr/bin/env bash
# README command 1: install, build, and render the built-in default scene with exact BVHs.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=out/cornell
build/release/cpu/linespace-cpu render --scene builtin:cornell --schedule bvh --spp 16 --bounces 3 --size 512x512 --out "$out"
echo "images: $out/image.png (tone-mapped), $out/total.exr and $out/bounce_*.exr (linear); report: $out/report.json"
