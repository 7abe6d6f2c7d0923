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
