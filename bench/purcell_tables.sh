#!/bin/sh
# Purcell et al. 2002's Tables 2 and 3 and the figures in the text behind Figures 7–9,
# measured with `raypipe stream` and printed beside the paper's (docs/stream-model.md).
# The bunny comes from $RAYPIPE_SCENES/stanford_bunny/stanford-bunny.obj (default
# scenes/; docs/scenes.md); Soda Hall and the forest are raypipe's procedural stand-ins.
#
#   bench/purcell_tables.sh [OUT] [stream options...]     (default OUT: purcell-out)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-purcell-out}
[ $# -gt 0 ] && shift
mkdir -p "$out"
scenes=$(cd "${RAYPIPE_SCENES:-$here/../scenes}" && pwd)
cargo build --release -p raypipe --quiet --manifest-path "$here/../Cargo.toml"
rp="$here/../target/release/raypipe"
bunny="$scenes/stanford_bunny/stanford-bunny.obj"

run() { # NAME SCENE ARGS...: one frame, its report in $out/NAME.json
    name=$1 scene=$2
    shift 2
    "$rp" stream "$scene" --no-charts -o "$out/$name.png" --report "$out/$name.json" "$@" >"$out/$name.txt"
}

# The paper's grids: minimal dimension 64 for the bunny, 128 for the large scenes (§4.1).
for view in outside inside; do
    [ -f "$out/building-$view.rpsi" ] ||
        "$rp" build --generate building --view $view --accel grid --grid-min-dim 128 -o "$out/building-$view.rpsi" >/dev/null
done
for view in top inside; do
    [ -f "$out/forest-$view.rpsi" ] ||
        "$rp" build --generate forest --view $view --accel grid --grid-min-dim 128 -o "$out/forest-$view.rpsi" >/dev/null
done

big="--size 1024x1024"
for s in building-outside building-inside forest-top forest-inside; do
    [ -f "$out/$s-multipass.json" ] && [ -z "${PURCELL_RERUN:-}" ] && continue
    run "$s-multipass" "$out/$s.rpsi" $big "$@"
    run "$s-branching" "$out/$s.rpsi" $big --arch branching "$@"
    run "$s-nocache" "$out/$s.rpsi" $big --cache off "$@"
    run "$s-branching-nocache" "$out/$s.rpsi" $big --arch branching --cache off "$@"
done
g="--grid-min-dim 64"
run bunny-optimal "$bunny" $g $big --oracle optimal "$@"
run bunny-unrolled "$bunny" $g $big --unroll traverse=4,intersect=2 "$@"
run bunny-unrolled-suppressed "$bunny" $g $big --unroll traverse=4,intersect=2 --suppress "$@"
# Whitted: "a pair of reflection and refraction rays, and a set of shadow rays" per hit
# (§3.1.4), so the bunny is glass (illum 7: Fresnel reflection and refraction).
printf '[materials.glass]\ndiffuse = [0.2, 0.2, 0.2]\nspecular = [0.8, 0.8, 0.8]\nillum = 7\nior = 1.5\n\n' >"$out/glass-bunny.toml"
printf '[[mesh]]\nfile = "%s"\nmaterial = "glass"\n' "$bunny" >>"$out/glass-bunny.toml"
# Two framings: raypipe's default camera (the bunny's box fills 44% of the screen) and
# one as close as the box allows to the paper's "82% of pixels" hitting the bunny
# (§4.3): a 17° field of view, 77%.
for framing in "" "-framed"; do
    f=""
    [ -n "$framing" ] && f="--fov 17"
    run "bunny$framing-multipass" "$bunny" $g $big $f "$@"
    run "bunny$framing-nocache" "$bunny" $g $big $f --cache off "$@"
    run "bunny$framing-branching" "$bunny" $g $big $f --arch branching "$@"
    run "bunny$framing-branching-nocache" "$bunny" $g $big $f --arch branching --cache off "$@"
    # Table 3: the extensions on the branching machine, against ray casting at 1024² (the
    # path tracer at 256², 64 samples of 2 bounces, as in the paper).
    run "bunny$framing-shadow" "$bunny" $g $big $f --arch branching --algo shadow "$@"
    run "bunny$framing-whitted" "$out/glass-bunny.toml" $g $big $f --arch branching --algo whitted --max-depth 2 "$@"
    run "bunny$framing-path" "$bunny" $g --size 256x256 --samples 64 --bounces 2 $f --arch branching --algo path "$@"
done
python3 "$here/purcell_tables.py" "$out"
