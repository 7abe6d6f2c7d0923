//! Floating-point functions whose results are exact, so that each target may compute them
//! its own fastest way and still give the same bits.

/// The largest integer not above `x`: IEEE 754's `roundToIntegralTowardNegative` (NaN,
/// infinities and signed zeros as they are).
/// On the GPU it is one instruction (`cvt.rmi.f32.f32`), where `libm::floorf`'s bit
/// manipulation took some twenty; natively, `libm::floorf`.
#[inline(always)]
pub fn floor(x: f32) -> f32 {
    #[cfg(target_arch = "nvptx64")]
    {
        let y: f32;
        // SAFETY: a register-to-register conversion; no memory, no preconditions.
        unsafe {
            core::arch::asm!(
                "cvt.rmi.f32.f32 {y}, {x};",
                y = out(reg32) y,
                x = in(reg32) x,
                options(pure, nomem, nostack)
            )
        };
        y
    }
    #[cfg(not(target_arch = "nvptx64"))]
    libm::floorf(x)
}

/// `x` as an `i32`, as `as` converts it: truncated toward zero, saturated at the type's
/// bounds, NaN to 0. On the GPU one instruction (`cvt.rzi.s32.f32`, which saturates and
/// takes NaN to 0 itself), where `as`'s clamps spelled out took seven; natively, `as`.
#[inline(always)]
pub fn trunc_i32(x: f32) -> i32 {
    #[cfg(target_arch = "nvptx64")]
    {
        let y: i32;
        // SAFETY: a register-to-register conversion; no memory, no preconditions.
        unsafe {
            core::arch::asm!(
                "cvt.rzi.s32.f32 {y}, {x};",
                y = out(reg32) y,
                x = in(reg32) x,
                options(pure, nomem, nostack)
            )
        };
        y
    }
    #[cfg(not(target_arch = "nvptx64"))]
    {
        x as i32
    }
}
