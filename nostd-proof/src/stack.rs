//! Stack painting: how deep a piece of code goes into the stack, measured, not
//! estimated. The window below the current stack pointer is filled with a pattern, the
//! code runs, and the lowest word it changed tells its depth (the calls' frames, spills
//! and return addresses, as the compiler laid them out for this target).

/// Bytes painted below the stack pointer: more than any kernel may use.
const WINDOW: usize = 256 * 1024;
/// Bytes just below the stack pointer left alone (x86-64's red zone is 128).
const SKIP: usize = 256;
const PAINT: u32 = 0xA5C3_5A3C;

#[inline(always)]
fn stack_pointer() -> usize {
    let sp: usize;
    // SAFETY: reads the stack pointer register; no memory is touched.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        core::arch::asm!("mov {}, rsp", out(reg) sp, options(nomem, nostack, preserves_flags))
    };
    #[cfg(target_arch = "arm")]
    unsafe {
        core::arch::asm!("mov {}, sp", out(reg) sp, options(nomem, nostack, preserves_flags))
    };
    #[cfg(target_arch = "riscv32")]
    unsafe {
        core::arch::asm!("mv {}, sp", out(reg) sp, options(nomem, nostack, preserves_flags))
    };
    sp
}

/// Runs `f` and returns the bytes of stack it used below this function's stack pointer.
#[inline(never)]
pub fn depth_of(f: impl FnOnce()) -> usize {
    let sp = stack_pointer() & !3;
    let top = sp - SKIP;
    let bottom = top - WINDOW;
    // SAFETY: the window lies below the live stack (the boards give the stack megabytes,
    // the build machine's main thread megabytes too), in memory no one else uses while
    // this single thread runs; volatile accesses keep the compiler from reasoning about it.
    unsafe {
        let mut a = bottom;
        while a < top {
            core::ptr::write_volatile(a as *mut u32, PAINT);
            a += 4;
        }
    }
    f();
    let mut a = bottom;
    // SAFETY: as above; the window is still below the stack pointer.
    while a < top && unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
        a += 4;
    }
    sp - a
}
