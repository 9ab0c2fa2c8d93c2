#!/bin/sh
# Wald & Slusallek 2001 §7.3 claim SaarCOR "full-screen, 25+ fps for scenes of up to
# several million triangles with three point lights and up to two secondary rays per
# pixel". This builds such a scene — eight copies of the sports car and two armadillos
# (3.1 M triangles) on a mirror floor, three point lights — and simulates one 1024×768
# Whitted frame (reflections, shadows, --max-depth 2) on the `saarcor` preset. Needs the
# sports car and the armadillo under $RAYPIPE_SCENES (default scenes/; docs/scenes.md).
#
#   bench/saarcor_claim.sh [OUT] [simulate options...]     (default OUT: saarcor-claim-out)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-saarcor-claim-out}
[ $# -gt 0 ] && shift
mkdir -p "$out"
scenes=$(cd "${RAYPIPE_SCENES:-$here/../scenes}" && pwd)
cargo build --release -p raypipe --quiet --manifest-path "$here/../Cargo.toml"
printf 'v -20 0 -20\nv 20 0 -20\nv 20 0 20\nv -20 0 20\nf 1 3 2\nf 1 4 3\n' >"$out/floor.obj"
{
    printf '[camera]\neye = [0, 9, 22]\nlook_at = [0, 0.5, 0]\nsize = [1024, 768]\n\n'
    printf '[materials.mirror]\ndiffuse = [0.2, 0.2, 0.2]\nspecular = [0.6, 0.6, 0.6]\nillum = 3\n\n'
    printf '[materials.paint]\ndiffuse = [0.6, 0.1, 0.1]\nspecular = [0.3, 0.3, 0.3]\nshininess = 60\nillum = 2\n\n'
    printf '[[mesh]]\nfile = "floor.obj"\nmaterial = "mirror"\n'
    for i in 0 1 2 3; do
        for j in 0 1; do
            printf '\n[[mesh]]\nfile = "%s/sports_car/sportsCar.obj.gz"\nmaterial = "paint"\ntranslate = [%d, 0, %d]\n' \
                "$scenes" $((i * 3 - 5)) $((j * 7 - 4))
        done
    done
    for x in -8 8; do
        printf '\n[[mesh]]\nfile = "%s/stanford_armadillo/armadillo.obj.gz"\nscale = 0.02\ntranslate = [%d, 1.1, -2]\n' \
            "$scenes" $x
    done
    for p in "[-6, 8, 6]" "[6, 8, 6]" "[0, 10, -8]"; do
        printf '\n[[light]]\nkind = "point"\nposition = %s\ncolor = [0.5, 0.5, 0.5]\n' "$p"
    done
} >"$out/scene.toml"
"$here/../target/release/raypipe" simulate "$out/scene.toml" --preset saarcor --algo whitted --max-depth 2 \
    -o "$out/frame.png" --report "$out/report.json" --quiet "$@"
