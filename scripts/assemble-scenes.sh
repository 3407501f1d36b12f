#!/usr/bin/env bash
# Assembles the paper-like real scenes into assets/real/ (git-ignored), installing the two Debian
# packages they come from when missing.  --small (default): only the FIREPLACE-like scene (CI);
# --all: all five.  Up-to-date scenes are skipped; see scenes/README.md.
set -euo pipefail
cd "$(dirname "$0")/.."

case "${1:---small}" in
  --small) scenes=(fireplace) ;;
  --all) scenes=(--all) ;;
  *) echo "usage: scripts/assemble-scenes.sh [--small|--all]" >&2; exit 2 ;;
esac

packages=(python3 sweethome3d-furniture libcgal-demo)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "assemble-scenes: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Debian's python3: the standard library is all the assembler needs (a pyenv python3 on PATH may lack it).
exec /usr/bin/python3 scenes/assemble_real_scenes.py --out assets/real "${scenes[@]}"
