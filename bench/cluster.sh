#!/usr/bin/env bash
# The cluster model's figures in docs/distributed.md: a walkthrough of a scene recorded
# on 1, 2 and 3 MPI workers of this machine (served bricks for a bricked scene), the
# model driven by the one-worker recording and checked against all three, then its
# predictions for Wald & Slusallek's setup (7 clients on 100 Mbit/s, a gigabit server)
# and for a 64-node cluster (gigabit clients, a 10-gigabit server).
#   bench/cluster.sh SCENE [SIZE] [FRAMES|PATH] [CACHE]   e.g. bench/cluster.sh plant.rpsb 640x480 8 256M
# FRAMES orbits the look-at point; a camera path file (see docs/cli.md) walks it.
# Needs a raypipe built with --features mpi and OpenMPI's mpirun.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q --features mpi
R=$PWD/target/release/raypipe
scene=${1:?a scene: a bricked scene (.rpsb) or a scene image}
size=${2:-640x480}
frames=${3:-8}
walk=(--orbit "$frames")
[ -f "$frames" ] && walk=(--camera-path "$(realpath "$frames")")
cache=${4:-256M}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
data=() served=()
case "$scene" in *.rpsb) data=(--mpi-data served --cache "$cache"); served=(--served --cache "$cache") ;; esac
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
for n in 2 3 4; do
  mpirun -n "$n" --oversubscribe "$R" render "$scene" --algo whitted --size "$size" "${walk[@]}" \
    "${data[@]}" --mpi --mpi-record "$work/rec$n.jsonl" -o "$work/m.png" | grep '^path'
done
# This machine: ranks share its cores and talk through memory (links of GB/s; the
# master's polling makes a message's latency about 0.1 ms).
echo "== the model against this machine's runs"
"$R" cluster "$work/rec2.jsonl" "${served[@]}" --workers 1 --client-link 5GB --server-link 5GB \
  --latency 100us --check "$work/rec2.jsonl" "$work/rec3.jsonl" "$work/rec4.jsonl" | grep -E '^(check|measured)'
echo "== Wald & Slusallek 2001: 7 clients on 100 Mbit/s, a gigabit server"
"$R" cluster "$work/rec2.jsonl" "${served[@]}" --workers 1,2,4,7 --client-link 100Mbit --server-link 1Gbit --latency 100us | tail -5
echo "== 64 nodes: gigabit clients, a 10-gigabit server"
"$R" cluster "$work/rec2.jsonl" "${served[@]}" --workers 1,8,16,32,64 --client-link 1Gbit --server-link 10Gbit --latency 50us | tail -6
