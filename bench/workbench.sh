#!/bin/sh
# The architect's four questions on the conference room and the Stanford bunny
# (saarcor preset, 512×384, kd-tree), one sweep each, with their plots, and energy per
# frame and per ray for every preset. Needs the conference room and the bunny under
# $RAYPIPE_SCENES (default: scenes/ at the repository root; docs/scenes.md says where to
# download them). Writes its figures to OUT; docs/workbench/ holds the committed ones.
#
#   bench/workbench.sh [OUT]        (default OUT: workbench-out)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-workbench-out}
mkdir -p "$out"
cargo build --release -p raypipe --quiet --manifest-path "$here/../Cargo.toml"
rp="$here/../target/release/raypipe"
scenes=${RAYPIPE_SCENES:-$here/../scenes}
conf=conference.obj.gz
bunny=stanford-bunny.obj
for s in cache bound scaling; do
    "$rp" sweep "$here/sweeps/$s.toml" -o "$out/$s"
done
for scene in $conf $bunny; do
    case $scene in $conf) name=conference ;; *) name=bunny ;; esac
    # Q1: what cache size — frame rate over node × triangle cache, and traffic.
    "$rp" plot "$out/cache.jsonl" --where "scene=*$scene" --x cache.nodes.size_bytes --y cache.triangles.size_bytes \
        --value fps -o "$out/q1-cache-fps-$name.png"
    "$rp" plot "$out/cache.jsonl" --where "scene=*$scene" --where cache.triangles.size_bytes=65536 \
        --x cache.nodes.size_bytes --y hit_rate.nodes --log-x -o "$out/q1-node-hit-rate-$name.png"
    # Q2: memory- or compute-bound — stall reasons under each memory model.
    "$rp" plot "$out/bound.jsonl" --where "scene=*$scene" --x memory.model --stack stall.traversal \
        -o "$out/q2-traversal-stalls-$name.png"
    # Q3: scaling — frame rate over units × threads for each packet size.
    for p in 16 64; do
        "$rp" plot "$out/scaling.jsonl" --where "scene=*$scene" --where packet_size=$p --x traversal.units \
            --y traversal.threads --value fps -o "$out/q3-scaling-fps-$name-packet$p.png"
    done
    "$rp" plot "$out/scaling.jsonl" --where "scene=*$scene" --where traversal.threads=16 --x traversal.units \
        --y fps --series packet_size -o "$out/q3-fps-by-units-$name.png"
    # Q4: where stalls come from — traversal stall reasons as units are added.
    "$rp" plot "$out/scaling.jsonl" --where "scene=*$scene" --where traversal.threads=16 --where packet_size=64 \
        --x traversal.units --stack stall.traversal -o "$out/q4-traversal-stalls-$name.png"
done
# Energy per frame and per ray of every preset.
for preset in saarcor minimal; do
    "$rp" simulate "$scenes/conference/$conf" --camera "$here/../fixtures/cameras/conference.camera" \
        --size 512x384 --accel kd --preset $preset -o "$out/energy-conference-$preset.png" \
        --report "$out/energy-conference-$preset.json" | grep -E "^(energy|at )"
    "$rp" simulate "$scenes/stanford_bunny/$bunny" --size 512x384 --accel kd --preset $preset \
        -o "$out/energy-bunny-$preset.png" --report "$out/energy-bunny-$preset.json" | grep -E "^(energy|at )"
done
