#!/usr/bin/env bash
# Flash, static RAM and measured stack of the smallest firmware of each structure (its
# single-ray kernel and Lambert shading, `--no-default-features --features <s>`) and of
# the full proof, on the emulated Cortex-M4F and RV32IMAC boards; `bvh4,fixed` and
# `bvh8,fixed` are those firmwares with the fixed-point datapath (Q16.16). Prints the README's
# table. Needs qemu-system-arm, qemu-system-riscv32 and rustup's llvm-tools.
set -euo pipefail
cd "$(dirname "$0")"
size=$(ls -d "$(rustc --print sysroot)"/lib/rustlib/*/bin | head -1)/llvm-size
echo "| target | build | flash (text + rodata) B | static RAM (data + bss) B | walk stack B | any-hit stack B | packet-16 stack B | shading stack B |"
echo "|---|---|---|---|---|---|---|---|"
for target in thumbv7em-none-eabihf riscv32imac-unknown-none-elf; do
  for build in grid kd bvh bvh4 bvh8 bvh4,fixed bvh8,fixed all; do
    features=(--no-default-features --features "$build")
    cargo build -q --release --target "$target" "${features[@]}"
    elf="target/$target/release/raypipe-nostd-proof"
    read -r text data bss <<<"$("$size" -A "$elf" | awk '
      $1 ~ /^\.(text|rodata|vector_table|init|trap)/ { t += $2 }
      $1 ~ /^\.data/ { d += $2 }
      $1 ~ /^\.bss/ { b += $2 }
      END { print t + 0, d + 0, b + 0 }')"
    line=$(cargo run -q --release --target "$target" "${features[@]}" 2>/dev/null | awk -v s="${build%%,*}" '
      $1 == s || (s == "all" && $1 != "structure" && $1 != "every") {
        for (i = 2; i <= 5; i++) if ($i > m[i]) m[i] = $i }
      END { print m[2] + 0, m[3] + 0, m[4] + 0, m[5] + 0 }')
    read -r walk any packet shading <<<"$line"
    [ "$build" = all ] || { any="–"; packet="–"; }
    echo "| $target | $build | $text | $((data + bss)) | $walk | $any | $packet | $shading |"
  done
done
