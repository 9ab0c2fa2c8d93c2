#!/usr/bin/env bash
# raypipe's BVH updates against Embree's on the same vertex buffers: refit, fast
# rebuild and SAH rebuild in milliseconds per million triangles, on one thread and two.
#
#   bench/embree-updates.sh SCENE.aff [EVERY]
#
# raypipe flattens every EVERY-th frame (default 8) of the BART scene into one mesh and
# times its refit, linear BVH and binned SAH; it writes the same frames' vertex buffers,
# which the C harness (bench/embree/updates.c, built here against Debian's
# libembree-dev: `apt-get install libembree-dev`) commits with RTC_BUILD_QUALITY_REFIT,
# LOW (Morton) and MEDIUM (binned SAH). Run it on an idle machine; quote the medians.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:?usage: bench/embree-updates.sh SCENE.aff [EVERY]}
every=${2:-8}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cargo build --release -q -p raypipe
gcc -O2 -o "$work/updates" bench/embree/updates.c -lembree3
echo "== raypipe (1 thread, then 2)"
target/release/raypipe bench-updates "$scene" --every "$every" --threads 1 --dump "$work/frames.bin"
target/release/raypipe bench-updates "$scene" --every "$every" --threads 2 | tail -3
echo "== embree 3 ($(dpkg-query -W -f='${Version}' libembree-dev 2>/dev/null || echo '?'))"
for q in refit low medium; do
  for t in 1 2; do
    "$work/updates" "$work/frames.bin" "$q" "$t"
  done
done
