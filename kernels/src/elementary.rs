//! Sine, cosine and the natural logarithm for the random draws (Box–Muller's normals and
//! the wandering enemies' turns), written with `f32` additions, subtractions,
//! multiplications and one division only. Both targets round each of those the same way
//! (IEEE 754, no fused multiply-adds), so they give the same bits. `libm`'s functions give
//! them too, but on the GPU they are calls into double-precision code that spills the
//! calling kernel's registers; these inline into a few dozen instructions.
//!
//! Each is within two units in the last place of the exact value of its argument
//! (`kernels/tests/elementary.rs` measures them against `f64`).

/// 2π rounded to `f32`.
const TAU: f32 = core::f32::consts::TAU;

/// π/2 rounded to `f32`.
const HALF_PI_HIGH: f32 = core::f32::consts::FRAC_PI_2;
/// `π/2 − HALF_PI_HIGH`.
const HALF_PI_LOW: f32 = -4.371_139e-8;

/// `ln 2` split in two: a high part with few enough bits that its product with any `f32`
/// exponent is exact, and the rest.
const LN2_HIGH: f32 = f32::from_bits(0x3f31_7200); // 0.693145751953125
/// `ln 2 − LN2_HIGH`.
const LN2_LOW: f32 = f32::from_bits(0x35bf_be8e); // 1.4286068e-6

/// `(sin 2πt, cos 2πt)`: the sine and cosine of `t` turns, for any finite `t` (NaN for
/// others). The reduction is exact: `t` less the nearest whole turn, then the quarter and
/// the eighth of a turn by symmetry (each a subtraction of numbers within a factor of two,
/// exact by Sterbenz's lemma), so only the angle of at most an eighth of a turn is rounded
/// (once, by its product with 2π) before the polynomials.
#[inline(always)]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    // `v` in [-1/2, 1/2] (a little more where `t + 1/2` rounds up to the next integer).
    let v = t - crate::math::floor(t + 0.5);
    let a = v.abs();
    // Past a quarter turn: sin(π − θ) = sin θ, cos(π − θ) = −cos θ.
    let past_quarter = a > 0.25;
    let b = if past_quarter { 0.5 - a } else { a };
    // Past an eighth: sin θ = cos(π/2 − θ) and the other way round.
    let past_eighth = b > 0.125;
    let c = if past_eighth { 0.25 - b } else { b };
    let (s, co) = sin_cos_eighth(c * TAU);
    let (sin, cos) = if past_eighth { (co, s) } else { (s, co) };
    let sin = if v < 0.0 { -sin } else { sin };
    let cos = if past_quarter { -cos } else { cos };
    (sin, cos)
}

/// `(sin x, cos x)` for an angle `x` in radians. Up to an eighth of a turn either way the
/// polynomials take `x` itself; up to three eighths, the angle to the quarter turn,
/// `π/2 − |x|`, in two parts (the first subtraction exact by Sterbenz's lemma); beyond,
/// [`sin_cos_turns`] of `x / 2π`, whose rounding adds an error in proportion to `|x|`. (The
/// wandering enemies' widest turn is 1.34 radians.)
#[inline(always)]
pub fn sin_cos(x: f32) -> (f32, f32) {
    let a = x.abs();
    if a > 3.0 * core::f32::consts::FRAC_PI_4 {
        return sin_cos_turns(x * (1.0 / TAU));
    }
    let past_eighth = a > core::f32::consts::FRAC_PI_4;
    let (s, c) = match past_eighth {
        true => {
            let (s, c) = sin_cos_eighth((HALF_PI_HIGH - a) + HALF_PI_LOW);
            (c, s)
        }
        false => sin_cos_eighth(a),
    };
    (if x < 0.0 { -s } else { s }, c)
}

/// Taylor polynomials of the sine and the cosine, for `|x| ≤ π/4` (their next terms are
/// below 2⁻²⁸ there): the sine as `x + x³·p(x²)`, so that it keeps `x`'s relative accuracy.
#[inline(always)]
fn sin_cos_eighth(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let p = -1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5_040.0 + x2 * (1.0 / 362_880.0)));
    let sin = x + x * x2 * p;
    let q = -0.5
        + x2 * (1.0 / 24.0
            + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0))));
    let cos = 1.0 + x2 * q;
    (sin, cos)
}

/// The natural logarithm of `u`: −∞ at zero, NaN below it and for NaN, ∞ at ∞.
///
/// `u = m · 2^e` with `m` in [√½, √2) (exact), then `ln m = 2 atanh s` for
/// `s = (m − 1)/(m + 1)` (`|s| < 0.172`), whose odd series is summed to `s¹¹`, and
/// `e · ln 2` in two parts, the first exact.
#[inline(always)]
pub fn ln(u: f32) -> f32 {
    if u.is_nan() || u < 0.0 {
        return f32::NAN;
    }
    if u == 0.0 {
        return f32::NEG_INFINITY;
    }
    if u == f32::INFINITY {
        return f32::INFINITY;
    }
    // A subnormal is scaled up by 2²³ (exactly) to a normal number first.
    let subnormal = u < f32::MIN_POSITIVE;
    let u = if subnormal { u * 8_388_608.0 } else { u };
    let bits = u.to_bits();
    let mut e = (bits >> 23) as i32 - 127 - if subnormal { 23 } else { 0 };
    let mut m = f32::from_bits(bits & 0x007f_ffff | 0x3f80_0000);
    if m > core::f32::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let q = 1.0 / 3.0 + s2 * (1.0 / 5.0 + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0 + s2 * (1.0 / 11.0))));
    let ln_m = 2.0 * s + 2.0 * s * s2 * q;
    let e = e as f32;
    e * LN2_HIGH + (e * LN2_LOW + ln_m)
}
