#!/usr/bin/env bash
# The default embedded build of raypipe-core has no f64 code: the firmware targets
# emulate double precision in software, so the proof's firmware (every kernel) must link
# none of the compiler's soft-double routines. Checked on the built Cortex-M4F and RV32
# binaries; and, so that the check is seen to bite, the same build with core's
# `f64-fallback` feature must link some. Needs rustup's llvm-tools.
set -euo pipefail
cd "$(dirname "$0")"
rustup component add llvm-tools >/dev/null 2>&1 || true
nm=$(ls -d "$(rustc --print sysroot)"/lib/rustlib/*/bin | head -1)/llvm-nm
# __aeabi_dadd, __adddf3, __muldf3, __extendsfdf2, __truncdfsf2, __floatundidf, …
doubles=' (__aeabi_d[a-z0-9]+|__aeabi_[a-z0-9]*2d|__[a-z]+df[23]|__extendsfdf2|__truncdfsf2|__float[a-z]*df|__fix[a-z]*df[a-z]*)$'
for target in thumbv7em-none-eabihf riscv32imac-unknown-none-elf; do
  cargo build -q --release --target "$target"
  if "$nm" "target/$target/release/raypipe-nostd-proof" | grep -E "$doubles"; then
    echo "$target: the default embedded build links f64 routines (above)"
    exit 1
  fi
  cargo build -q --release --target "$target" --features raypipe-core/f64-fallback --target-dir target/with-f64
  found=$("$nm" "target/with-f64/$target/release/raypipe-nostd-proof" | grep -cE "$doubles" || true)
  if [ "$found" = 0 ]; then
    echo "$target: the check found no f64 routine even with f64-fallback: it cannot see them"
    exit 1
  fi
  echo "$target: no f64 routine in the default build ($found with f64-fallback)"
done
