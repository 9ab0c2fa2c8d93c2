#!/usr/bin/env bash
# Runs every fuzz target for SECONDS each (default 20) from its committed seed corpus
# (new inputs go to a scratch corpus, so the seeds stay as committed). CI runs this; run
# it longer by hand, e.g. `tests/fuzz/run.sh 3600`, or one target without end with
# `cargo +nightly fuzz run --fuzz-dir tests/fuzz -O <target> /tmp/c tests/fuzz/corpus/<target>`.
# A crash is saved under tests/fuzz/artifacts/<target>/; make it a regression test.
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-20}
# The build is most of CI's fuzzing step. cargo-fuzz builds with one codegen unit and
# AddressSanitizer unless told: the parsers are safe Rust (core forbids `unsafe` outside
# its SIMD module), so the sanitizer finds little here, and the two doubled the build on
# two cores (about 15 minutes against 7 with 16 units and none). A long hunt by hand may
# want them back: FUZZ_SANITIZER=address FUZZ_CODEGEN_UNITS=1 tests/fuzz/run.sh 3600.
sanitizer=${FUZZ_SANITIZER:-none}
codegen_units=${FUZZ_CODEGEN_UNITS:-16}
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
for target in scene_image bricked instanced aff obj_mtl npy camera_file hw_config dramsim3_ini gltf ply streamed_meshes scene_file sweep_spec cluster_recording; do
  mkdir -p "$scratch/$target"
  out=$(cargo +nightly fuzz run --fuzz-dir tests/fuzz -O -s "$sanitizer" --codegen-units "$codegen_units" "$target" "$scratch/$target" "tests/fuzz/corpus/$target" \
    -- -max_total_time="$seconds" -max_len=8192 -print_final_stats=1 2>&1) || {
    echo "$out" | tail -40
    echo "fuzz target $target failed (input saved under tests/fuzz/artifacts/$target/)"
    exit 1
  }
  runs=$(echo "$out" | grep -oE "stat::number_of_executed_units: *[0-9]+" | grep -oE "[0-9]+$" || echo "?")
  echo "fuzz $target: $runs executions in ${seconds}s, no finding"
done
