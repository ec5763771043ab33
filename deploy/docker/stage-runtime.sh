#!/usr/bin/env bash
# Stages what the runtime image needs from a build folder:
#   STAGE/usr/local/bin/{gdvr-server,gdvr,gdvr-farm,gdvr-render,gdvr-healthcheck}
#   STAGE/usr/local/share/gdvr/{ocio,scenes}
#   STAGE/runtime-packages.txt   the Debian packages owning every shared library
#                                the binaries load (computed, not hand-kept, so a
#                                new dependency cannot be forgotten in the image)
# usage: stage-runtime.sh BUILD_DIR STAGE_DIR
set -euo pipefail
build=${1:?usage: stage-runtime.sh BUILD_DIR STAGE_DIR}
stage=${2:?usage: stage-runtime.sh BUILD_DIR STAGE_DIR}
src=$(cd "$(dirname "$0")/../.." && pwd)

mkdir -p "$stage/usr/local/bin" "$stage/usr/local/share/gdvr"
bins=("$build/bin/gdvr-server" "$build/bin/gdvr" "$build/bin/gdvr-farm" "$build/bin/gdvr-render")
for b in "${bins[@]}"; do
  [ -x "$b" ] || { echo "stage-runtime: $b was not built" >&2; exit 1; }
  install -m 0755 -s "$b" "$stage/usr/local/bin/" 2>/dev/null || install -m 0755 "$b" "$stage/usr/local/bin/"
done
install -m 0755 "$src/deploy/docker/gdvr-healthcheck" "$stage/usr/local/bin/"
cp -r "$src/data/ocio" "$stage/usr/local/share/gdvr/ocio"
cp -r "$src/scenes" "$stage/usr/local/share/gdvr/scenes"

# ldd prints "libfoo.so.1 => /lib/x86_64-linux-gnu/libfoo.so.1 (0x...)". On
# merged-/usr Debian 12, dpkg may know a library under /usr/lib or /lib only,
# so ask for both spellings.
owner() {
  local f=$1 alt
  case "$f" in /usr/*) alt=${f#/usr} ;; *) alt=/usr$f ;; esac
  dpkg-query -S "$f" 2>/dev/null || dpkg-query -S "$alt" 2>/dev/null || dpkg-query -S "$(readlink -f "$f")" 2>/dev/null || true
}
: > "$stage/runtime-packages.txt.tmp"
for lib in $(ldd "${bins[@]}" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u); do
  pkg=$(owner "$lib" | head -n1 | cut -d: -f1)
  if [ -z "$pkg" ]; then echo "stage-runtime: no Debian package owns $lib" >&2; exit 1; fi
  echo "$pkg" >> "$stage/runtime-packages.txt.tmp"
done
sort -u "$stage/runtime-packages.txt.tmp" > "$stage/runtime-packages.txt"
rm "$stage/runtime-packages.txt.tmp"
echo "stage-runtime: $(wc -l < "$stage/runtime-packages.txt") runtime packages: $(tr '\n' ' ' < "$stage/runtime-packages.txt")"
