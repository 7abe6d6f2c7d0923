//! Arithmetic whose results are exact, so that each target may compute it its own fastest
//! way and still give the same bits: floating-point functions, and integer division by a
//! divisor fixed at launch.

use glam::Vec2;

use crate::{DevSlice, Thread, kernel_args};

/// A 32-bit divisor with its reciprocal, made once (on the host, at launch) so that each
/// thread divides by a multiplication: `u32`'s division is some twenty instructions on the
/// GPU and tens of cycles on a CPU, where the one particle a thread of the explosions
/// divided its index by its kill's count was most of the emulator's time in that kernel.
/// The reciprocal is `⌈2⁶⁴ / d⌉`, whose product with any 32-bit `n`, shifted right by 64,
/// is `⌊n / d⌋` exactly (Lemire, Kaser and Kurz, "Faster remainder by direct computation",
/// 2019: Theorem 1 with N = 32, F = 64); `kernels/tests/exact_math.rs` checks it against
/// `/` and `%` at the edges.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Divisor {
    /// `⌈2⁶⁴ / d⌉`, as `u64` wraps it (0 for `d` = 1, where every quotient is `n` itself).
    reciprocal: u64,
    /// The divisor, at least 1.
    d: u32,
    /// Keeps the struct free of implicit padding.
    reserved: u32,
}

impl Default for Divisor {
    /// 1, the divisor that leaves every number as it is.
    fn default() -> Divisor {
        Divisor::new(1)
    }
}

impl Divisor {
    /// `d` and its reciprocal; `d` must not be zero (panics, at compile time in a constant).
    pub const fn new(d: u32) -> Divisor {
        assert!(d != 0, "a divisor is at least 1");
        Divisor {
            reciprocal: (u64::MAX / d as u64).wrapping_add(1),
            d,
            reserved: 0,
        }
    }

    /// The divisor.
    #[inline(always)]
    pub fn get(self) -> u32 {
        self.d
    }

    /// `⌊n / d⌋`.
    #[inline(always)]
    pub fn quotient(self, n: u32) -> u32 {
        match self.reciprocal {
            0 => n,
            r => ((r as u128 * n as u128) >> 64) as u32,
        }
    }

    /// `n mod d`.
    #[inline(always)]
    pub fn remainder(self, n: u32) -> u32 {
        n - self.quotient(n) * self.d
    }
}

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

/// The squares of lengths from 2⁻⁵⁰ to 2⁵⁰ (both included): where the GPU's correctly rounded
/// square root and reciprocal take no special case (see [`recip_sqrt`]).
pub const PLAIN_SQUARES: core::ops::RangeInclusive<f32> =
    f32::from_bits((127 - 100) << 23)..=f32::from_bits((127 + 100) << 23);

/// `1 / sqrt(x)` with each step correctly rounded (`1.0 / sqrt(x)`, bit for bit), for `x`
/// in [`PLAIN_SQUARES`]. On the GPU the ten instructions that `sqrt.rn.f32` and
/// `rcp.rn.f32` run for such an `x`, without the range checks and branches around them
/// (which doubled a look's cost of normalising an offset, taken by a few lanes of a warp
/// at a time); [`check_recip_sqrt`] compares the two over every `f32` of the range on the
/// GPU (`tests/exact.rs`).
/// Natively, the division of the square root.
#[inline(always)]
pub fn recip_sqrt(x: f32) -> f32 {
    #[cfg(target_arch = "nvptx64")]
    {
        let r: f32;
        // SAFETY: register-to-register arithmetic; no memory, no preconditions.
        unsafe {
            core::arch::asm!(
                "{{",
                ".reg .f32 %y, %s, %h, %e;",
                // The square root: an estimate of its reciprocal, one Newton step.
                "rsqrt.approx.ftz.f32 %y, {x};",
                "mul.ftz.f32 %s, {x}, %y;",
                "mul.ftz.f32 %h, %y, 0f3F000000;",
                "neg.f32 %e, %s;",
                "fma.rn.f32 %e, %e, %s, {x};",
                "fma.rn.f32 %s, %e, %h, %s;",
                // Its reciprocal: an estimate, one Newton step.
                "rcp.approx.ftz.f32 %y, %s;",
                "neg.f32 %h, %y;",
                "fma.rn.f32 %e, %h, %s, 0f3F800000;",
                "fma.rn.f32 {r}, %y, %e, %y;",
                "}}",
                r = out(reg32) r,
                x = in(reg32) x,
                options(pure, nomem, nostack)
            )
        };
        r
    }
    #[cfg(not(target_arch = "nvptx64"))]
    {
        1.0 / sqrt(x)
    }
}

kernel_args! {
    /// Arguments of [`check_recip_sqrt`].
    pub struct RecipSqrtCheckArgs {
        /// The first `f32` checked, as its bits.
        pub first: u32,
        /// How many consecutive bit patterns from `first` are checked.
        pub count: u32,
        /// Output: the number of patterns whose [`recip_sqrt`] differs from `1.0 /
        /// sqrt(x)` (element 0), and the largest such pattern (element 1); zero before.
        pub found: DevSlice<u32>,
    }
}

/// Patterns a thread of [`check_recip_sqrt`] checks, one after another.
pub const RECIP_SQRT_CHECKS_PER_THREAD: u32 = 64;

/// Thread `i` compares [`recip_sqrt`] with the division of the correctly rounded square root
/// for [`RECIP_SQRT_CHECKS_PER_THREAD`] consecutive patterns of the range from its `i`-th
/// share on, bit for bit, and adds its mismatches to `found`.
#[inline(always)]
pub fn check_recip_sqrt(t: Thread, args: &RecipSqrtCheckArgs) {
    let from = t.global().saturating_mul(RECIP_SQRT_CHECKS_PER_THREAD);
    let to = from
        .saturating_add(RECIP_SQRT_CHECKS_PER_THREAD)
        .min(args.count);
    let (mut mismatches, mut largest) = (0, 0);
    for i in from..to {
        let bits = args.first.wrapping_add(i);
        let x = f32::from_bits(bits);
        if recip_sqrt(x).to_bits() != (1.0 / sqrt(x)).to_bits() {
            mismatches += 1;
            largest = bits;
        }
    }
    if mismatches > 0 {
        args.found.atomic_add(0, mismatches);
        args.found.atomic_max(1, largest);
    }
}

/// `v` scaled to length 1, or `None` where that is not finite or `v` is zero: `glam`'s
/// `Vec2::try_normalize`, bit for bit, through [`sqrt`] (and [`recip_sqrt`] where the
/// square of the length allows).
#[inline(always)]
pub fn try_normalize(v: Vec2) -> Option<Vec2> {
    let length2 = v.length_squared();
    if cfg!(target_arch = "nvptx64") && PLAIN_SQUARES.contains(&length2) {
        // The reciprocal of a length from 2⁻⁵⁰ to 2⁵⁰: finite and positive.
        return Some(v * recip_sqrt(length2));
    }
    let rcp = 1.0 / sqrt(length2);
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
