// Hands the linker the board's memory map (`memory.x`) and the runtime's linker script
// (`link.x`, from cortex-m-rt or riscv-rt): without `-Tlink.x` the vector table and
// start-up code are dropped and the "firmware" is an empty ELF.
use std::path::PathBuf;

fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory = if target.starts_with("thumb") {
        "memory-cortex-m.x"
    } else if target.starts_with("riscv32") {
        "memory-riscv.x"
    } else {
        panic!("build for thumbv7em-none-eabihf or riscv32imac-unknown-none-elf (got {target})");
    };
    std::fs::copy(memory, out.join("memory.x")).expect("copy the memory map");
    println!("cargo:rustc-link-search={}", out.display());
    if target.starts_with("riscv32") {
        println!("cargo:rustc-link-arg=-Tmemory.x");
    }
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rerun-if-changed={memory}");
    println!("cargo:rerun-if-changed=build.rs");
}
