// The proof runs in three places. On the build machine it is an ordinary process, so it
// links the C library for process start-up (`__libc_start_main`), `memcpy` and `write`.
// On a Cortex-M4F (thumbv7em-none-eabihf) and on RV32IMAC (riscv32imac-unknown-none-elf)
// it is bare-metal firmware for QEMU's `mps2-an386` and `virt` boards: cortex-m-rt or
// riscv-rt start it, and this script hands their linker scripts the board's memory map.
use std::path::PathBuf;

fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory = if target.starts_with("thumb") {
        Some("memory-cortex-m.x")
    } else if target.starts_with("riscv32") {
        Some("memory-riscv.x")
    } else {
        None
    };
    match memory {
        Some(file) => {
            std::fs::copy(file, out.join("memory.x")).expect("copy the memory map");
            println!("cargo:rustc-link-search={}", out.display());
            if target.starts_with("riscv32") {
                println!("cargo:rustc-link-arg=-Tmemory.x");
            }
            println!("cargo:rustc-link-arg=-Tlink.x");
            println!("cargo:rerun-if-changed={file}");
        }
        None => println!("cargo:rustc-link-lib=c"),
    }
    println!("cargo:rerun-if-changed=build.rs");
}
