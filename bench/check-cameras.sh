#!/usr/bin/env bash
# Checks that the camera shipped for each downloaded scene sees the scene: raypipe's view
# probe (host/src/render/view_check.rs) traces a grid of its eye rays and prints a hint
# when the view is blocked by a foreground surface, mostly one wall seen from outside, or
# almost empty. Every scene below must render without a hint. Needs the scenes under
# $RAYPIPE_SCENES (default scenes/; docs/scenes.md); a missing scene is skipped, said so.
set -euo pipefail
cd "$(dirname "$0")/.."
models=${RAYPIPE_SCENES:-scenes}
cargo build --release -q -p raypipe
R=target/release/raypipe
checks=(
  "$models/sponza_dabrovic/sponza.obj.gz fixtures/cameras/sponza.camera"
  "$models/conference/conference.obj.gz fixtures/cameras/conference.camera"
  "$models/sibenik/sibenik.obj.gz fixtures/cameras/sibenik.camera"
  "$models/cornell_box/CornellBox-Original.obj -"
  "$models/stanford_bunny/stanford-bunny.obj -"
  "$models/teapot/teapot.obj -"
)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0
for entry in "${checks[@]}"; do
  read -r obj cam <<<"$entry"
  if [ ! -f "$obj" ]; then echo "skip  $obj (not downloaded)"; continue; fi
  camera=()
  [ "$cam" != - ] && camera=(--camera "$cam")
  hint=$($R render "$obj" "${camera[@]}" --size 64x64 -o "$tmp/x.png" 2>&1 >/dev/null | grep '^hint:' || true)
  if [ -n "$hint" ]; then
    echo "FAIL  $obj ${cam/-/(its own view)}: $hint"
    failed=1
  else
    echo "ok    $obj ${cam/-/(its own view)}"
  fi
done
exit $failed
