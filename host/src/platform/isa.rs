//! The instruction set the host's hot loops run with, chosen at run time: the kernels in
//! core are written over plain arrays and SIMD types, and a loop compiled for AVX2 turns
//! the 8-wide BVH's node test into one register per plane. The kernels give the same bits
//! either way: Rust never contracts `a * b + c`, and the one fused form, the 8-wide node
//! test's (`RAYPIPE_FMA=0` turns it off), is conservative, so it changes which nodes a
//! walk visits, never the hit.

/// Runs `f`, compiled for AVX2 where the CPU has it (`f` is inlined into the AVX2
/// build), else as built (SSE2 on x86-64).
///
/// Measured with paired runs on 1024² primary rays: 8-wide BVH single rays 2–7% faster
/// than in the SSE2 build, 4-wide BVH single rays within ±6%, and the 4-wide BVH's
/// packet kernel 9% slower (so packets do not come through here).
#[inline(always)]
pub fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_set() {
        // SAFETY: the CPU has every feature `avx2` is compiled for (checked above).
        return unsafe { avx2(f) };
    }
    f()
}

/// Every feature the AVX2 build enables, each checked (a VM may expose
/// AVX2 without BMI; running BMI instructions there would be undefined behaviour).
#[cfg(target_arch = "x86_64")]
fn has_avx2_set() -> bool {
    std::is_x86_feature_detected!("avx")
        && std::is_x86_feature_detected!("avx2")
        && std::is_x86_feature_detected!("bmi1")
        && std::is_x86_feature_detected!("bmi2")
        && std::is_x86_feature_detected!("lzcnt")
        && std::is_x86_feature_detected!("popcnt")
        && std::is_x86_feature_detected!("fma")
}

/// Tells core which optional instruction sets the CPU has (a `no_std` library cannot
/// ask): with AVX, the 8-wide BVH's node test and the packets' leaf entry test run as
/// AVX intrinsics, the node test fused where the CPU has FMA (`RAYPIPE_FMA=0` keeps it
/// unfused); shadow packets of 16 test their rays sixteen lanes at a time, in one
/// AVX-512 register per quantity with AVX-512 F (`RAYPIPE_AVX512=0` in the environment
/// keeps them off it), else in two AVX registers (`RAYPIPE_AVX16=0` keeps them on groups
/// of four lanes), for comparisons. Cheap (the detection is cached); the tracing drivers call it
/// first.
pub fn report_cpu() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX (checked above), as `assume_avx` requires.
            unsafe { raypipe_core::simd::assume_avx() }
        }
    }
    set_fma(std::env::var_os("RAYPIPE_FMA").is_none_or(|v| v != "0"));
    set_avx512(std::env::var_os("RAYPIPE_AVX512").is_none_or(|v| v != "0"));
    set_avx16(std::env::var_os("RAYPIPE_AVX16").is_none_or(|v| v != "0"));
}

/// Lets shadow packets of 16 test their rays sixteen lanes at a time in two AVX registers
/// where the CPU has AVX but not AVX-512 (`on`), or keeps them on groups of four lanes;
/// returns whether the AVX form may now run. For the equivalence suites and comparisons.
pub fn set_avx16(on: bool) -> bool {
    #[cfg(target_arch = "x86_64")]
    return switch(on && std::is_x86_feature_detected!("avx"), raypipe_core::simd::assume_avx16);
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = on;
        false
    }
}

/// Lets the kernels take their AVX-512 forms (`on`, where the CPU has AVX-512 F) or
/// keeps them on the AVX and portable forms; returns whether they now take them. For the
/// equivalence suites, which hold both forms to the single-ray answers.
pub fn set_avx512(on: bool) -> bool {
    #[cfg(target_arch = "x86_64")]
    return switch(on && std::is_x86_feature_detected!("avx512f"), raypipe_core::simd::assume_avx512);
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = on;
        false
    }
}

/// Lets the 8-wide node test take its fused form (`on`, where the CPU has FMA) or keeps
/// it on the unfused one; returns whether it now takes it. For comparisons.
pub fn set_fma(on: bool) -> bool {
    #[cfg(target_arch = "x86_64")]
    return switch(on && std::is_x86_feature_detected!("fma"), raypipe_core::simd::assume_fma);
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = on;
        false
    }
}

/// Sets one of core's switches to `on`, which the caller has checked the CPU supports
/// where it is true; returns it.
#[cfg(target_arch = "x86_64")]
fn switch(on: bool, assume: unsafe fn(bool)) -> bool {
    // SAFETY: with `on`, the CPU has the feature (the callers check it), as each
    // `assume_*` requires.
    unsafe { assume(on) };
    on
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,bmi1,bmi2,lzcnt,popcnt,fma")]
unsafe fn avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}
