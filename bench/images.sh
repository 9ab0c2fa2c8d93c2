#!/usr/bin/env bash
# The image figures of docs/cli.md: Sponza, the conference room, Sibenik and the Cornell box
# with every algorithm, from their cameras, with no hand-placed light (each scene's
# default light is chosen for its camera), and the stats --algo shadow mismatch of each.
# Needs the scenes under $RAYPIPE_SCENES (default scenes/; docs/scenes.md) and ImageMagick's `convert` (to put each scene's four images in
# one row; CONVERT names another binary). Usage: bench/images.sh [size] [path samples]
# (defaults 384, 16)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-384}
spp=${2:-16}
models=${RAYPIPE_SCENES:-scenes}
out=docs/images
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo build --release -q -p raypipe
R=target/release/raypipe
scenes=(
  "sponza $models/sponza_dabrovic/sponza.obj.gz fixtures/cameras/sponza.camera"
  "conference $models/conference/conference.obj.gz fixtures/cameras/conference.camera"
  "sibenik $models/sibenik/sibenik.obj.gz fixtures/cameras/sibenik.camera"
  "cornell $models/cornell_box/CornellBox-Original.obj -"
  "cornell-glossy $models/cornell_box/CornellBox-Glossy.obj -"
)
for entry in "${scenes[@]}"; do
  read -r name obj cam <<<"$entry"
  camera=()
  [ "$cam" != - ] && camera=(--camera "$cam")
  $R build "$obj" "${camera[@]}" -o "$tmp/$name.rpsi" --accel bvh4 2>/dev/null >/dev/null
  row=()
  for algo in cast shadow whitted path; do
    samples=1
    [ "$algo" = path ] && samples=$spp
    /usr/bin/time -f "$name $algo: %e s" $R render "$tmp/$name.rpsi" "${camera[@]}" --size "${size}x${size}" \
      --algo "$algo" --samples "$samples" --bounces 3 -o "$tmp/$name-$algo.png" 2>&1 | grep -E "s$|lights" | tail -2
    row+=("$tmp/$name-$algo.png")
  done
  "${CONVERT:-convert}" "${row[@]}" +append "$out/$name.png"
  echo "$name shadow-caster mismatch: $($R stats "$tmp/$name.rpsi" "${camera[@]}" --size 1024x1024 --algo shadow 2>/dev/null | grep -i "disagree\|mismatch" | head -1)"
done
