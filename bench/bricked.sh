#!/usr/bin/env bash
# The figures of docs/bricked-scenes.md: the generated power plant bricked at 12.5 M
# and 50 M triangles (build time, peak memory against the budget, bytes per triangle
# stored and decompressed, codec rates), rendered at 640x480 with primary and shadow
# rays (Whitted; the plant has no mirrors) through a cache of a quarter of its bricks,
# cold and warm (the same view twice), and primary rays traced with every brick
# resident against the flat image of the same triangles.
#   bench/bricked.sh [WORKDIR] [SIZES]     e.g. bench/bricked.sh /scratch "12500000 50000000"
# Needs about 10 GB of disk and, for the flat 12.5 M image, 4 GB of memory.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
R=$PWD/target/release/raypipe
work=${1:-bench/out/bricked}
sizes=${2:-"12500000 50000000"}
mkdir -p "$work"
cd "$work"
printf 'size 640 480\nframes 2\nkey -45 95 -70   25 40 20\nkey -45 95 -70   25 40 20\n' > same-view.path
for n in $sizes; do
  budget=$(( n >= 50000000 ? 2048 : 1024 ))M
  echo "== power plant, $n triangles, bricked (budget $budget)"
  /usr/bin/time -f "wall %e s, peak RSS %M KB" \
    "$R" build --generate "powerplant:triangles=$n" --accel bvh4 --bricks --memory-budget "$budget" -o "plant-$n.rpsb" -q
  "$R" info "plant-$n.rpsb" --codecs
  images=$("$R" info "plant-$n.rpsb" | sed -n 's/.*images \([0-9.]*\) MiB.*/\1/p')
  cache=$(awk -v m="$images" 'BEGIN { printf "%dM", m / 4 + 1 }')
  echo "-- 640x480 primary and shadow rays, cache $cache (a quarter), cold then warm"
  "$R" render "plant-$n.rpsb" --algo whitted --cache "$cache" --camera-path same-view.path -o "plant-$n.png" -q
  "$R" render "plant-$n.rpsb" --algo whitted --size 640x480 --cache "$cache" -o "plant-$n-one.png" -q
done
n=$(echo "$sizes" | awk '{print $1}')
echo "== two-level overhead: $n triangles, primary rays 640x480, every brick resident"
"$R" build --generate "powerplant:triangles=$n" --accel bvh4 -o "plant-$n.rpsi" -q > /dev/null
"$R" rays "plant-$n.rpsi" --size 640x480 -o rays.npy -q > /dev/null
"$R" trace "plant-$n.rpsi" --rays rays.npy --hits flat.npy --runs 5 -q
"$R" trace "plant-$n.rpsb" --rays rays.npy --hits bricked.npy --runs 5 --cache 64G -q
cmp flat.npy bricked.npy && echo "hits: identical"
