//! The kernels' square root and the lengths built on it (`gpuwars_kernels::math`): the root
//! is correctly rounded (checked against `f64`'s, which rounds to `f32` without error for a
//! square root), so the GPU's `sqrt.rn.f32` gives the same bits; the vector functions give
//! `glam`'s results bit for bit, so that moving to them changes no game.

use glam::Vec2;
use gpuwars_kernels::math;

/// Every 65,537th bit pattern (positive and negative, normal, subnormal, zero, infinite and
/// NaN alike), with the edges of each class.
fn floats() -> impl Iterator<Item = f32> {
    let edges = [
        0.0,
        -0.0,
        f32::MIN_POSITIVE,
        f32::MIN_POSITIVE.next_down(),
        f32::from_bits(1),
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1.0,
        2.0,
        4.0f32.next_down(),
    ];
    (0..=u32::MAX)
        .step_by(65_537)
        .map(f32::from_bits)
        .chain(edges)
}

#[test]
fn the_square_root_is_correctly_rounded() {
    for x in floats() {
        let got = math::sqrt(x);
        let want = f64::from(x).sqrt() as f32;
        assert!(
            got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
            "sqrt({x:e} = {:#010x}) = {got:e}, correctly rounded {want:e}",
            x.to_bits()
        );
    }
}

#[test]
fn the_lengths_are_glams_bit_for_bit() {
    let same = |a: Vec2, b: Vec2| a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits();
    let xs: Vec<f32> = floats().step_by(97).collect();
    for (i, &x) in xs.iter().enumerate() {
        for &y in xs.iter().skip(i % 13).step_by(13) {
            let v = Vec2::new(x, y);
            assert_eq!(
                math::length(v).to_bits(),
                v.length().to_bits(),
                "length {v:?}"
            );
            match (math::try_normalize(v), v.try_normalize()) {
                (Some(a), Some(b)) => assert!(same(a, b), "try_normalize {v:?}: {a:?} {b:?}"),
                (a, b) => assert_eq!(a.is_none(), b.is_none(), "try_normalize {v:?}"),
            }
            assert!(
                same(math::normalize_or_zero(v), v.normalize_or_zero()),
                "normalize_or_zero {v:?}"
            );
            for max in [0.0, 1.0, 70.0, 1e30] {
                let (a, b) = (math::clamp_length_max(v, max), v.clamp_length_max(max));
                assert!(
                    same(a, b) || (a.is_nan() || b.is_nan()) && a.is_nan() == b.is_nan(),
                    "clamp_length_max {v:?} {max}: {a:?} {b:?}"
                );
            }
        }
    }
}

/// Divisors at the edges: every one to 1,024 (the explosions' counts among them), each
/// power of two with its neighbours, the largest prime, three times 2³⁰ and the largest.
fn divisors() -> impl Iterator<Item = u32> {
    let powers = (1..32).flat_map(|k| {
        let p = 1u32 << k;
        [p - 1, p, p + 1]
    });
    (1..=1024)
        .chain(powers)
        .chain([4_294_967_291, 3 << 30, u32::MAX - 1, u32::MAX])
}

/// Numerators at the edges for `d`: zero, the first and last multiples of `d` with their
/// neighbours, the largest, and a sweep across the range.
fn numerators(d: u32) -> impl Iterator<Item = u32> {
    let last = u32::MAX / d * d;
    let edges = [0, 1, d - 1, d, d.saturating_add(1), 2 * (d / 2)];
    let top = [last.wrapping_sub(1), last, last.saturating_add(1)];
    let wide = [u32::MAX - 1, u32::MAX, 1 << 31, (1 << 31) - 1];
    edges
        .into_iter()
        .chain(top)
        .chain(wide)
        .chain((0..=u32::MAX).step_by(40_009_379))
}

#[test]
fn a_divisor_divides_as_the_division_does() {
    for d in divisors() {
        let divisor = math::Divisor::new(d);
        assert_eq!(divisor.get(), d);
        for n in numerators(d) {
            assert_eq!(divisor.quotient(n), n / d, "{n} / {d}");
            assert_eq!(divisor.remainder(n), n % d, "{n} mod {d}");
        }
    }
}

#[test]
fn the_default_divisor_is_one() {
    let one = math::Divisor::default();
    assert_eq!(one, math::Divisor::new(1));
    assert_eq!(
        (one.quotient(u32::MAX), one.remainder(u32::MAX)),
        (u32::MAX, 0)
    );
}

#[test]
#[should_panic(expected = "a divisor is at least 1")]
fn zero_is_no_divisor() {
    math::Divisor::new(0);
}
