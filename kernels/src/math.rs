//! Floating-point functions whose results are exact, so that each target may compute them
//! its own fastest way and still give the same bits.

use glam::Vec2;

/// The PTX instruction `$instruction` on the 32-bit register `$x`, giving a `$result`.
#[cfg(target_arch = "nvptx64")]
macro_rules! one_instruction {
    ($instruction:literal, $x:expr, $result:ty) => {{
        let y: $result;
        // SAFETY: a register-to-register operation; no memory, no preconditions.
        unsafe {
            core::arch::asm!(
                concat!($instruction, " {y}, {x};"),
                y = out(reg32) y,
                x = in(reg32) $x,
                options(pure, nomem, nostack)
            )
        };
        y
    }};
}

/// The largest integer not above `x`: IEEE 754's `roundToIntegralTowardNegative` (NaN,
/// infinities and signed zeros as they are).
/// On the GPU it is one instruction (`cvt.rmi.f32.f32`), where `libm::floorf`'s bit
/// manipulation took some twenty; natively, `libm::floorf`.
#[inline(always)]
pub fn floor(x: f32) -> f32 {
    #[cfg(target_arch = "nvptx64")]
    return one_instruction!("cvt.rmi.f32.f32", x, f32);
    #[cfg(not(target_arch = "nvptx64"))]
    libm::floorf(x)
}

/// `x` as an `i32`, as `as` converts it: truncated toward zero, saturated at the type's
/// bounds, NaN to 0. On the GPU one instruction (`cvt.rzi.s32.f32`, which saturates and
/// takes NaN to 0 itself), where `as`'s clamps spelled out took seven; natively, `as`.
#[inline(always)]
pub fn trunc_i32(x: f32) -> i32 {
    #[cfg(target_arch = "nvptx64")]
    return one_instruction!("cvt.rzi.s32.f32", x, i32);
    #[cfg(not(target_arch = "nvptx64"))]
    {
        x as i32
    }
}

/// The square root of `x`, correctly rounded (IEEE 754's `squareRoot`). On the GPU one
/// instruction (`sqrt.rn.f32`), where `libm::sqrtf`, which `glam`'s lengths also call, is
/// integer arithmetic and a table lookup (some fifty instructions); natively,
/// `libm::sqrtf`, an instruction of its own. Both round correctly, so they agree bit for bit.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(target_arch = "nvptx64")]
    return one_instruction!("sqrt.rn.f32", x, f32);
    #[cfg(not(target_arch = "nvptx64"))]
    libm::sqrtf(x)
}

/// `v`'s length: `glam`'s `Vec2::length`, bit for bit, through [`sqrt`].
#[inline(always)]
pub fn length(v: Vec2) -> f32 {
    sqrt(v.length_squared())
}

/// `v` scaled to length 1, or `None` where that is not finite or `v` is zero: `glam`'s
/// `Vec2::try_normalize`, bit for bit, through [`sqrt`].
#[inline(always)]
pub fn try_normalize(v: Vec2) -> Option<Vec2> {
    let rcp = 1.0 / length(v);
    (rcp.is_finite() && rcp > 0.0).then(|| v * rcp)
}

/// [`try_normalize`], or zero where there is none: `glam`'s `Vec2::normalize_or_zero`.
#[inline(always)]
pub fn normalize_or_zero(v: Vec2) -> Vec2 {
    try_normalize(v).unwrap_or(Vec2::ZERO)
}

/// `v` scaled down to length `max` (at least 0) if it is longer: `glam`'s
/// `Vec2::clamp_length_max`, bit for bit, through [`sqrt`].
#[inline(always)]
pub fn clamp_length_max(v: Vec2, max: f32) -> Vec2 {
    let length2 = v.length_squared();
    if length2 > max * max {
        max * (v / sqrt(length2))
    } else {
        v
    }
}
