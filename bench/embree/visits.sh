#!/bin/sh
# Node visits, leaves and triangle blocks per ray in Embree beside raypipe's, on the same
# rays: is it the tree or the cost of a visit that differs?
#
# Debian's Embree is built without its statistics counters, so this script builds
# Embree 3.13.5 from its release tag with EMBREE_STAT_COUNTERS (AVX-512 and SSE2 kernels,
# triangles only, internal tasking) into a cache directory, links bench/embree/rays.c
# against it, traces the rays once (the counters slow Embree down: its times here mean
# nothing) and prints its per-ray counters, then `raypipe stats --rays` on the same rays.
#
#   bench/embree/visits.sh TRIS.npy RAYS.npy IMAGE.rpsi [intersect1|occluded1]
#
# TRIS.npy, RAYS.npy and IMAGE.rpsi as bench/embree_harness.py keeps them (`--keep DIR`:
# DIR/SCENE/tris.npy, bounce.npy, bvh8.rpsi, ...). Needs git, cmake, g++ and a release build of raypipe.
set -eu
[ $# -ge 3 ] || { echo "usage: $0 TRIS.npy RAYS.npy IMAGE.rpsi [intersect1|occluded1]" >&2; exit 2; }
tris=$1 rays=$2 image=$3 mode=${4:-intersect1}
case $mode in intersect1) query=closest ;; occluded1) query=any ;;
  *) echo "$0: $mode: not a mode (intersect1, occluded1)" >&2; exit 2 ;; esac
for f in "$tris" "$rays" "$image"; do [ -r "$f" ] || { echo "$0: $f: cannot read it" >&2; exit 1; }; done
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cache=${RAYPIPE_EMBREE_STATS_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/raypipe-embree-stats}
lib=$cache/build/libembree3.so
if [ ! -e "$lib" ]; then
  mkdir -p "$cache"
  [ -d "$cache/src" ] || git clone --quiet --depth 1 --branch v3.13.5 https://github.com/embree/embree "$cache/src"
  cmake -S "$cache/src" -B "$cache/build" -DCMAKE_BUILD_TYPE=Release -DEMBREE_STAT_COUNTERS=ON \
    -DEMBREE_TUTORIALS=OFF -DEMBREE_ISPC_SUPPORT=OFF -DEMBREE_TASKING_SYSTEM=INTERNAL \
    -DEMBREE_MAX_ISA=NONE -DEMBREE_ISA_SSE2=ON -DEMBREE_ISA_SSE42=OFF -DEMBREE_ISA_AVX=OFF \
    -DEMBREE_ISA_AVX2=OFF -DEMBREE_ISA_AVX512=ON -DEMBREE_GEOMETRY_CURVE=OFF \
    -DEMBREE_GEOMETRY_GRID=OFF -DEMBREE_GEOMETRY_POINT=OFF -DEMBREE_GEOMETRY_SUBDIVISION=OFF \
    -DEMBREE_GEOMETRY_USER=OFF -DEMBREE_GEOMETRY_INSTANCE=OFF -DEMBREE_GEOMETRY_QUAD=OFF >/dev/null
  cmake --build "$cache/build" --target embree -j "$(nproc)" >/dev/null
fi
gcc -O2 -o "$cache/rays" "$root/bench/embree/rays.c" -I"$cache/src/include" -L"$cache/build" -lembree3 -lm -lpthread
echo "== Embree 3.13.5 ($mode, MEDIUM build), per ray:"
# Embree prints its counters when it exits: the per-traversal block of the query's kind.
LD_LIBRARY_PATH=$cache/build "$cache/rays" "$tris" "$rays" "$mode" 1 1 medium \
  | sed -n '/PER TRAVERSAL/,/USER/p' | grep -E '#(nodes|leaves|prims) ' | grep -v nan \
  | sed 's/#prims /#blocks/; s/, 100% active//'
echo "== raypipe ($query), per ray:"
"$root/target/release/raypipe" stats "$image" --rays "$rays" --query "$query" | tail -5
