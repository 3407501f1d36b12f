#!/usr/bin/env bash
# Makes the self-contained GPU bundle that scripts/gpu-check.sh runs on a machine that has a GPU but
# none of our Debian packages (gpu/README.md): linespace-gpu and linespace-validate (stripped), every
# shared library they load, Debian's loader and libc among them, the Vulkan loader, and the real
# scenes the check uses, packed as one gzip archive (Embree, which the validator links as the CPU
# peer, is 42 MiB of the 68 MiB unpacked; packed, the whole is 27 MiB).
#   scripts/make-gpu-bundle.sh [--build DIR] [--no-build] [--out ARCHIVE]
#     --build DIR     the CMake build folder (default build/release; built here if out of date,
#                     unless --no-build)
#     --out ARCHIVE   default build/gpu-bundle.tar.gz; the unpacked tree is left beside it
#                     (build/gpu-bundle/) for running here
# Programs in the bundle run as bin/linespace-gpu and bin/linespace-validate: small sh wrappers that
# start libexec/PROGRAM with lib/ld-linux-x86-64.so.2 --library-path lib, so neither the host's
# glibc nor its library path take part; then lib-driver/ (what a GPU driver needs, below), then
# LINESPACE_EXTRA_LIBRARY_PATH (gpu-check.sh sets it to the Vulkan drivers' folders).
# Exit status: 0, or 2 with a one-line reason.
set -euo pipefail
cd "$(dirname "$0")/.."

build=build/release
no_build=0
archive=build/gpu-bundle.tar.gz
limit_mib=62   # what the device tool carries is 64 MiB with the working tree (~2 MiB)
fail() { echo "make-gpu-bundle: $*" >&2; exit 2; }
while (($#)); do
  case $1 in
    --build) (($# >= 2)) || fail "--build needs a folder"; build=$2; shift 2 ;;
    --no-build) no_build=1; shift ;;
    --out) (($# >= 2)) || fail "--out needs a file name"; archive=$2; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) fail "unknown argument '$1' (see --help)" ;;
  esac
done
[[ $archive == *.tar.gz ]] || fail "--out must end in .tar.gz"
[[ -f $build/CMakeCache.txt ]] || fail "$build is not a configured build folder (scripts/setup.sh makes build/release)"
[[ $(uname -m) == x86_64 ]] || fail "the bundle is for x86-64 machines; this one is $(uname -m)"
if ((!no_build)); then
  nice -n 10 cmake --build "$build" --target linespace-gpu linespace-validate >/dev/null ||
    fail "building linespace-gpu and linespace-validate in $build failed"
fi

name=gpu-bundle
stage=$(dirname "$archive")/$name
rm -rf "$stage"
mkdir -p "$stage"/{bin,libexec,lib,lib-driver,scenes}

programs=("$build/gpu/linespace-gpu" "$build/validate/linespace-validate")
for p in "${programs[@]}"; do
  [[ -x $p ]] || fail "$p is missing"
  strip --strip-unneeded -o "$stage/libexec/$(basename "$p")" "$p"
done

# Every library the programs need, by the name the loader looks for (their sonames), dereferenced.
# Beside them: the loader; the rest of libc's family, which a Vulkan driver may need (libdl,
# libpthread, librt); TBB's allocator, which TBB opens itself when it is there.
declare -A libs=()
while read -r soname path; do
  [[ -n $path && -e $path ]] && libs[$soname]=$path
done < <(ldd "${programs[@]}" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}')
for extra in libdl.so.2 libpthread.so.0 librt.so.1 libtbbmalloc.so.2; do
  path=$(ldconfig -p | awk -v n="$extra" '$1 == n && /x86-64/ && !f {print $NF; f = 1}')
  [[ -n $path ]] && libs[$extra]=$path
done
[[ -n ${libs[libvulkan.so.1]:-} ]] || fail "linespace-gpu does not load libvulkan.so.1: is this the Vulkan build?"
loader=$(ldd "${programs[0]}" | awk '$1 ~ /ld-linux-x86-64/ && !f {print $1; f = 1}')
[[ -e $loader ]] || fail "cannot find the program loader (ld-linux-x86-64.so.2)"
cp -L "$loader" "$stage/lib/ld-linux-x86-64.so.2"
for soname in "${!libs[@]}"; do cp -L "${libs[$soname]}" "$stage/lib/$soname"; done
# lib-driver/: what a GPU driver's Vulkan library itself needs and a bare host may lack, or have built
# against a newer glibc than the bundle's (NVIDIA's needs libglvnd's libGLdispatch; its X11 side,
# libX11 and libXext).  Searched after lib/ and before the driver's own folders.
for soname in libGLdispatch.so.0 libGLX.so.0 libEGL.so.1 libX11.so.6 libXext.so.6 libxcb.so.1 libXau.so.6 \
              libXdmcp.so.6 libbsd.so.0 libmd.so.0; do
  path=$(ldconfig -p | awk -v n="$soname" '$1 == n && /x86-64/ && !f {print $NF; f = 1}')
  [[ -n $path ]] || fail "$soname is missing (scripts/setup.sh installs libglvnd0, libglx0, libegl1, libx11-6, libxext6)"
  libs[$soname]=$path
  cp -L "$path" "$stage/lib-driver/$soname"
done

for p in "${programs[@]}"; do
  program=$(basename "$p")
  cat > "$stage/bin/$program" <<EOF
#!/bin/sh
# $program from the bundle: its own loader and libraries (scripts/make-gpu-bundle.sh).
case \$0 in */*) here=\${0%/*} ;; *) here=. ;; esac
b=\$(cd "\$here/.." && pwd -P) || exit 2
p=\$b/lib:\$b/lib-driver
[ -n "\${LINESPACE_EXTRA_LIBRARY_PATH:-}" ] && p=\$p:\$LINESPACE_EXTRA_LIBRARY_PATH
exec "\$b/lib/ld-linux-x86-64.so.2" --library-path "\$p" "\$b/libexec/$program" "\$@"
EOF
  chmod +x "$stage/bin/$program"
done

# The smallest real scenes (scripts/assemble-scenes.sh; scenes/README.md), where they were assembled.
scenes=()
for s in bunny fireplace breakfast; do
  if [[ -f assets/real/$s.glb ]]; then cp "assets/real/$s.glb" "$stage/scenes/"; scenes+=("$s"); fi
done
[[ -f assets/real/CREDITS.md && ${#scenes[@]} -gt 0 ]] && cp assets/real/CREDITS.md "$stage/scenes/"
((${#scenes[@]})) || echo "make-gpu-bundle: no real scenes in assets/real (scripts/assemble-scenes.sh --all makes them); the bundle has the built-in ones only" >&2

{
  echo "linespace GPU bundle"
  echo "commit: $(git rev-parse HEAD 2>/dev/null || echo unknown)$(git diff --quiet HEAD 2>/dev/null || echo ' (with uncommitted changes)')"
  echo "made: $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(. /etc/os-release && echo "$PRETTY_NAME")"
  echo "scenes: ${scenes[*]:-none}"
  echo "libraries (Debian packages):"
  for f in "$stage"/lib/* "$stage"/lib-driver/*; do
    soname=$(basename "$f")
    src=${libs[$soname]:-$loader}
    real=$(readlink -f "$src")
    pkg=$( (dpkg -S "$real" || dpkg -S "${real#/usr}") 2>/dev/null | head -1 | cut -d: -f1 || true)
    ver=$([[ -n $pkg ]] && dpkg-query -W -f='${Version}' "$pkg" 2>/dev/null || true)
    printf '  %-28s %9d  %s %s\n' "$soname" "$(stat -c %s "$f")" "${pkg:-?}" "$ver"
  done
} > "$stage/MANIFEST"

tar -C "$(dirname "$stage")" -czf "$archive.tmp" "$name"
mv "$archive.tmp" "$archive"
unpacked=$(du -sb "$stage" | cut -f1)
packed=$(stat -c %s "$archive")
mib() { awk -v b="$1" 'BEGIN {printf "%.1f", b / 1048576}'; }
shipped=("$stage"/lib/*.so* "$stage"/lib-driver/*.so*)
echo "make-gpu-bundle: $archive $(mib "$packed") MiB ($stage unpacked: $(mib "$unpacked") MiB, ${#shipped[@]} libraries, scenes: ${scenes[*]:-built-in only})"
((packed <= limit_mib * 1048576)) || fail "$archive is $(mib "$packed") MiB, over the $limit_mib MiB that may be carried with the working tree"
