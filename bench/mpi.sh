#!/usr/bin/env bash
# The figures of docs/distributed.md: a scene at 1024x1024 (Whitted: primary and shadow
# rays) rendered by the threaded single process, then across MPI ranks (a master and
# 1, 2, 3 workers; oversubscribed beyond the machine's cores), each the median of three
# runs, with the MPI share of the frame and the bytes sent.
#   bench/mpi.sh SCENE [RANKS...]     e.g. bench/mpi.sh conference.obj.gz 2 3 4
# A camera file beside the repository's (fixtures/cameras/NAME.camera) is used when one
# matches the scene's name.
# Needs a raypipe built with --features mpi and OpenMPI's mpirun.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q --features mpi
R=$PWD/target/release/raypipe
scene=${1:?a scene: OBJ or scene image}
shift
ranks=${*:-2 3 4}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
name=$(basename "$scene"); name=${name%%.*}
camera=()
[ -f "fixtures/cameras/$name.camera" ] && camera=(--camera "$PWD/fixtures/cameras/$name.camera")
case "$scene" in
  *.rpsi) ln -s "$(realpath "$scene")" "$work/scene.rpsi" ;;
  *) "$R" build "$scene" --accel bvh4 "${camera[@]}" -o "$work/scene.rpsi" -q > /dev/null ;;
esac
median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
echo "scene $scene at 1024x1024, whitted"
t=$(for i in 1 2 3; do "$R" render "$work/scene.rpsi" --algo whitted --size 1024x1024 -o "$work/one.png" \
  | sed -n 's/^time .* render \([0-9.]*\) s.*/\1/p'; done | median)
echo "single process   render ${t} s  $(awk -v t="$t" 'BEGIN { printf "%.2f frames/s", 1 / t }')"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
for n in $ranks; do
  out=$(for i in 1 2 3; do
    mpirun -n "$n" --oversubscribe "$R" render "$work/scene.rpsi" --algo whitted --size 1024x1024 \
      -o "$work/mpi.png" --mpi | sed -n 's/^time     render \([0-9.]*\) s.*mpi share \([0-9.]*\)%.*/\1 \2/p'
  done | sort -n | awk '{a[NR]=$0} END {print a[int((NR+1)/2)]}')
  cmp -s "$work/one.png" "$work/mpi.png" || { echo "$n ranks: the image differs"; exit 1; }
  mb=$(mpirun -n "$n" --oversubscribe "$R" render "$work/scene.rpsi" --algo whitted --size 1024x1024 \
      -o "$work/mpi.png" --mpi | awk '/^rank/ { s += $(NF-2) } END { printf "%.2f", s }')
  set -- $out
  echo "$n ranks ($((n - 1)) workers)  render $1 s  $(awk -v t="$1" -v s="$t" 'BEGIN { printf "%.2f frames/s, efficiency %.0f%%", 1 / t, 100 * s / t }')  mpi share $2%  $mb MB sent"
done
