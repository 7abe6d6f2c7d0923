//! A wandering enemy turns its heading by a normal draw times `WANDER_TURN`, and takes the
//! turn's sine and cosine from one `libm::sincosf` call rather than `sinf` and `cosf`. That
//! keeps every game the same only if `sincosf` is those two bit for bit over every angle a
//! turn can take: checked here against the largest normal the generator can draw.

use gpuwars_kernels::game::ai::WANDER_TURN;
use gpuwars_kernels::rng::mt607;

/// The largest angle a turn can take: the Box–Muller radius of the smallest uniform.
fn widest_turn() -> f32 {
    let smallest = mt607::to_unit_f32(0);
    let largest_normal = (-2.0 * f64::from(smallest).ln()).sqrt();
    // Room for the rounding of the radius and of the product.
    (largest_normal * f64::from(WANDER_TURN) * 1.001) as f32
}

#[test]
fn sincos_is_sin_and_cos_over_every_turn() {
    let widest = widest_turn();
    assert!(widest > 1.3 && widest < 1.4, "{widest}");
    // Every 509th float from 0 to the widest turn, of both signs, and the ends (a sweep of
    // every float up to 8 found no difference either).
    let top = widest.to_bits();
    let mut bits: Vec<u32> = (0..=top).step_by(509).collect();
    bits.extend([top, 1, 0x3f49_0fda, 0x3f49_0fdb]);
    for b in bits {
        for x in [f32::from_bits(b), -f32::from_bits(b)] {
            let (sin, cos) = libm::sincosf(x);
            assert_eq!(sin.to_bits(), libm::sinf(x).to_bits(), "sin {x:e}");
            assert_eq!(cos.to_bits(), libm::cosf(x).to_bits(), "cos {x:e}");
        }
    }
}
