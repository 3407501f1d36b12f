#!/usr/bin/env bash
# README command 1: install, build, and render the built-in default scene with exact BVHs (the README's
# first picture, docs/images/cornell.png, is this image.png).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=out/cornell
build/release/cpu/linespace-cpu render --scene builtin:cornell --schedule bvh --spp 64 --bounces 3 --size 384x384 --out "$out"
echo "images: $out/image.png (auto exposure), $out/total.exr and $out/bounce_*.exr (linear); report: $out/report.json"
