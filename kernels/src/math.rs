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
