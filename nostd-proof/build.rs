// The proof runs as an ordinary process on the build machine, so it links the C
// library for process start-up (`__libc_start_main`) and `memcpy`; raypipe-core itself
// needs neither std nor alloc.
fn main() {
    println!("cargo:rustc-link-lib=c");
}
