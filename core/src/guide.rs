//! # Firmware guide: from nothing to a running board
//!
//! This page is documentation only. It takes a firmware engineer from an empty folder to
//! raypipe-core tracing on a Cortex-M4F or an RV32 core, and lists what the crate costs:
//! flash per feature, stack per kernel, and the limits the kernels' fixed stacks impose.
//!
//! ## 1. Start from the example crate
//!
//! `examples/firmware/` in this crate's source is a complete firmware crate — copy it
//! beside your copy of raypipe-core and build it. It runs on QEMU's `mps2-an386`
//! (Cortex-M4 with FPU) and `virt` (RV32IMAC) boards and exits 0 when the BVH walk agrees
//! with brute force on every ray of a 32 × 32 view (29 KB of flash on the M4F):
//!
//! ```text
//! rustup target add thumbv7em-none-eabihf riscv32imac-unknown-none-elf
//! sudo apt-get install qemu-system-arm qemu-system-misc
//! cd examples/firmware
//! cargo run --release --target thumbv7em-none-eabihf        # or riscv32imac-unknown-none-elf
//! ```
//!
//! A plain `#![no_std] #![no_main]` crate that only depends on raypipe-core links, but
//! into an empty ELF: with no start-up code and no linker script every function is
//! garbage-collected. A board needs what the example has:
//!
//! | piece | in the example | why |
//! |---|---|---|
//! | a runtime crate | `cortex-m-rt` or `riscv-rt` | reset handler, vector table, `#[entry]` |
//! | a memory map | `memory-cortex-m.x`, `memory-riscv.x` | where flash and RAM are on *your* board |
//! | the runtime's linker script | `build.rs` passes `-Tlink.x` (and `-Tmemory.x` on RISC-V) | places the vector table and sections |
//! | `panic = "abort"` | `[profile.release]` | no unwinding on a board; raypipe-core never panics, the handler is the runtime's requirement |
//! | `lto = true`, `codegen-units = 1` | `[profile.release]` | inlines the kernels; without it flash grows several times |
//! | an image in flash | `include_scene!("../scene.rpsi")` | aligned as [`crate::SceneView::parse`] needs |
//! | a way to speak | `semihosting` | printing and the exit code under a debugger; remove on a real board |
//!
//! The scene image is built on the host with `raypipe build scene.obj --accel bvh4 -o
//! scene.rpsi`; [`crate::SceneView::parse`] validates it once, after which no kernel can
//! index out of bounds or panic.
//!
//! ## 2. Pick the target that matches your C code's float ABI
//!
//! Rust's target decides the float ABI of the library; C code linked with it must use
//! the same (mixing them fails at link time, "uses VFP register arguments").
//!
//! | core | Rust target | C flags (GCC/Clang) |
//! |---|---|---|
//! | Cortex-M4F, M7 (single-precision FPU) | `thumbv7em-none-eabihf` | `-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16` |
//! | Cortex-M4/M7 without the FPU, or soft-float C | `thumbv7em-none-eabi` | `-mcpu=cortex-m4 -mthumb -mfloat-abi=soft` (or `softfp`) |
//! | Cortex-M33 with FPU | `thumbv8m.main-none-eabihf` | `-mcpu=cortex-m33 -mthumb -mfloat-abi=hard -mfpu=fpv5-sp-d16` |
//! | Cortex-M0/M0+ | `thumbv6m-none-eabi` | `-mcpu=cortex-m0plus -mthumb -mfloat-abi=soft` |
//! | RV32IMAC | `riscv32imac-unknown-none-elf` | `-march=rv32imac -mabi=ilp32` |
//! | RV32IMAFC (single-precision FPU) | `riscv32imafc-unknown-none-elf` | `-march=rv32imafc -mabi=ilp32f` |
//!
//! CI builds and runs the first and the RV32IMAC rows; raypipe-core computes in `f32`
//! only (no `f64` code in the default build), so a single-precision FPU is all it uses.
//!
//! ## 3. Features: what each does and costs
//!
//! Flash of the BVH4 firmware of `nostd-proof/` on the Cortex-M4F (its single-ray walk,
//! Lambert shading, number formatting and semihosting):
//!
//! | feature | what it does | flash |
//! |---|---|---|
//! | (default) | `f32` only; image checksum by slicing-by-8, an 8 KiB table | 49,116 B |
//! | `crc-table-1k` | the checksum's 1 KiB table, one byte per step | 39,936 B |
//! | `crc-table-64` | a 64-byte table, four bits per step (wins over `crc-table-1k`) | 39,060 B |
//! | `f64-fallback` | the watertight test recounts edge functions of exactly 0 in `f64` (Woop, Benthin & Wald 2013, §3.3) | 52,672 B |
//!
//! `f64-fallback` decides whether a ray through an edge shared by two triangles reports
//! the same triangle as the host: without it such an edge counts as inside (the ray still
//! hits one of them — no leaks — but maybe the other one), and "one hit whatever the
//! path" holds only for scenes within 4096 units of the origin
//! ([`crate::range::check_scene`] says `FarFromOrigin` beyond). The host renderer, the
//! hardware model and the tests enable it; enable it when firmware must match them bit for
//! bit. On these targets it links the compiler's soft-double routines (3.5 KB).
//!
//! ## 4. Stack
//!
//! Measured worst case over every eye ray of the test scene (the stack painted and read
//! back under QEMU), Cortex-M4F / RV32IMAC, in bytes:
//!
//! | kernel | stack |
//! |---|---|
//! | grid walk ([`crate::traverse::grid`]) | 432 / 452 |
//! | kd-tree walk | 1,112 / 1,104 |
//! | binary BVH walk | 1,056 / 1,076 |
//! | 4-wide BVH walk | 1,832 / 1,884 |
//! | 8-wide BVH walk | 3,528 / 3,572 |
//! | 4-wide BVH walk, fixed-point Q16.16 | 2,680 / 2,560 |
//! | generic walk ([`crate::traverse::walk::trace_walk`], every structure inlined) | 3,728 / 3,876 |
//! | any-hit query ([`crate::traverse::occlusion::occluded`]) | 3,672 / 3,716 |
//! | packets of 16 rays (a walk per lane, in lock-step) | 47,380 / 60,868 |
//! | Lambert shading | 256 / 256 |
//! | Whitted and path shading | 952 / 1,064 |
//!
//! Give the main stack at least the walk you use plus 1 KiB for your own code; packets
//! are for cores with tens of KiB of RAM to spare.
//!
//! ## 5. Depth limits
//!
//! The walks keep fixed-capacity stacks, so the image validator refuses deeper trees:
//! binary BVHs and kd-trees at most [`crate::image::MAX_TREE_DEPTH`] (64) levels, 4- and
//! 8-wide BVHs at most [`crate::image::MAX_WIDE_DEPTH`] (32; a wide walk keeps up to
//! `width − 1` entries per level: 100 entries, 1.2 KB, for the 4-wide BVH). raypipe's
//! builder keeps within them (the deepest wide BVH of the project's test scenes has 21
//! levels).
//!
//! ## 6. From C
//!
//! `capi/` in this crate's source builds raypipe-core as a static library with a C
//! header (`capi/include/raypipe.h`): build it with
//! `cargo build --release --manifest-path core/capi/Cargo.toml --target <target>` and
//! link `libraypipe_capi.a`; `capi/examples/trace.c` is a complete program. Its entry
//! points return an `RP_OK`/`RP_ERR_*` status, `rp_status_string` names it, `rp_version` reports the
//! library's version, and hits carry the geometric normal, material and object ids.
