//! The draws' sine, cosine and logarithm (`elementary`) against `f64`'s, over every input
//! the draws can give them and well beyond: within a few units in the last place of the
//! exact value.

use gpuwars_kernels::elementary::{ln, sin_cos, sin_cos_turns};
use gpuwars_kernels::rng::mt607;

/// The error of `got` against the exact `want`, in units in the last place of `want` as
/// an `f32` (at least the smallest normal's), less `slack`: what the reference itself may
/// be off by.
fn ulps_beyond(got: f32, want: f64, slack: f64) -> f64 {
    let unit = (want.abs().max(f64::from(f32::MIN_POSITIVE)) as f32).to_bits();
    let ulp = f64::from(f32::from_bits(unit + 1)) - f64::from(f32::from_bits(unit));
    ((f64::from(got) - want).abs() - slack).max(0.0) / ulp
}

/// [`ulps_beyond`] with no slack.
fn ulps(got: f32, want: f64) -> f64 {
    ulps_beyond(got, want, 0.0)
}

/// Every `step`-th float from `low` up to `high` (positive, as bits), and both ends.
fn floats(low: f32, high: f32, step: usize) -> impl Iterator<Item = f32> {
    (low.to_bits()..=high.to_bits())
        .step_by(step)
        .chain([high.to_bits()])
        .map(f32::from_bits)
}

#[test]
fn sine_and_cosine_of_turns_are_within_two_ulps() {
    let mut worst: f64 = 0.0;
    let mut check = |t: f32| {
        let (sin, cos) = sin_cos_turns(t);
        let angle = std::f64::consts::TAU * f64::from(t);
        // `f64`'s own rounding of 2πt may put it this far off, which matters near a zero.
        let slack = angle.abs() * f64::EPSILON;
        let e_sin = ulps_beyond(sin, angle.sin(), slack);
        let e_cos = ulps_beyond(cos, angle.cos(), slack);
        assert!(
            e_sin <= 2.0 && e_cos <= 2.0,
            "t {t:e}: {e_sin} {e_cos} ulps"
        );
        worst = worst.max(e_sin.max(e_cos));
    };
    // The uniforms Box–Muller takes, (0, 1], and whole turns either way.
    for t in floats(1e-9, 4.0, 97) {
        check(t);
        check(-t);
    }
    for k in 0..=8 {
        check(k as f32 / 8.0);
    }
    println!("worst {worst} ulps");
}

#[test]
fn sine_and_cosine_of_a_turn_by_a_wandering_enemy_are_within_two_ulps() {
    // The widest turn: the Box–Muller radius of the smallest uniform, a little more.
    let smallest = mt607::to_unit_f32(0);
    let widest = ((-2.0 * f64::from(smallest).ln()).sqrt() * 0.2 * 1.001) as f32;
    assert!(widest > 1.3 && widest < 1.4, "{widest}");
    let mut worst: f64 = 0.0;
    for x in floats(1e-12, widest, 61) {
        for x in [x, -x] {
            let (sin, cos) = sin_cos(x);
            let (want_sin, want_cos) = (f64::from(x).sin(), f64::from(x).cos());
            let (e_sin, e_cos) = (ulps(sin, want_sin), ulps(cos, want_cos));
            assert!(e_sin <= 2.0, "sin {x:e}: {sin} against {want_sin}");
            assert!(e_cos <= 2.0, "cos {x:e}: {cos} against {want_cos}");
            worst = worst.max(e_sin.max(e_cos));
        }
    }
    println!("worst {worst} ulps");
}

#[test]
fn sine_and_cosine_of_wider_angles_go_by_turns() {
    // Past three eighths of a turn the angle is rounded to turns: its error grows with it.
    let mut worst: f64 = 0.0;
    for x in floats(2.3, 7.0, 1009) {
        for x in [x, -x] {
            let (sin, cos) = sin_cos(x);
            // Two roundings of the angle (to turns and back), each within 2⁻²⁴ of it.
            let slack = f64::from(x).abs() * f64::from(f32::EPSILON);
            let e_sin = ulps_beyond(sin, f64::from(x).sin(), slack);
            let e_cos = ulps_beyond(cos, f64::from(x).cos(), slack);
            assert!(e_sin <= 2.0 && e_cos <= 2.0, "{x:e}: {e_sin} {e_cos}");
            worst = worst.max(e_sin.max(e_cos));
        }
    }
    println!("worst {worst} ulps beyond the angle's rounding");
}

#[test]
fn the_logarithm_is_within_two_ulps() {
    let mut worst: f64 = 0.0;
    for u in floats(f32::from_bits(1), f32::MAX, 331) {
        let e = ulps(ln(u), f64::from(u).ln());
        assert!(
            e <= 2.0,
            "ln {u:e}: {} against {}",
            ln(u),
            f64::from(u).ln()
        );
        worst = worst.max(e);
    }
    // Every uniform Box–Muller can take near 1, where the logarithm is smallest.
    for x in (u32::MAX - 4096..=u32::MAX).chain(0..4096) {
        let u = mt607::to_unit_f32(x);
        assert!(ulps(ln(u), f64::from(u).ln()) <= 2.0, "ln {u:e}");
    }
    println!("worst {worst} ulps");
    assert_eq!(ln(1.0), 0.0);
    assert_eq!(ln(0.0), f32::NEG_INFINITY);
    assert_eq!(ln(f32::INFINITY), f32::INFINITY);
    assert!(ln(-1.0).is_nan() && ln(f32::NAN).is_nan() && ln(-0.0) == f32::NEG_INFINITY);
}
