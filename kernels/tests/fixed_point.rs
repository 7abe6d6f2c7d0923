//! The fixed-point scale of the enemies' sight sums (`fixed_scale`): a power of two that keeps
//! a component as large as the bound below 2³⁰, and the finest such, checked in `f64` for
//! bounds across the whole `f32` range, on and next to every power of two.

use gpuwars_kernels::game::ai::fixed_scale;

#[test]
fn the_scale_is_the_finest_power_of_two_below_two_to_the_thirty() {
    let mut bounds = vec![
        0.0f32,
        1e-40,
        1e-30,
        1e-3,
        0.5,
        1.5,
        80.0,
        90.0,
        139.99,
        1e6,
        f32::MAX,
    ];
    for e in -126..=127 {
        let p = 2f32.powi(e);
        bounds.extend([p.next_down(), p, p.next_up()]);
    }
    let limit = 2f64.powi(30);
    for bound in bounds {
        let scale = fixed_scale(bound);
        assert!(
            scale.is_normal() && scale.to_bits() & 0x7f_ffff == 0,
            "{bound}: {scale} is not a power of two"
        );
        let scaled = f64::from(bound) * f64::from(scale);
        assert!(scaled < limit, "{bound} at {scale} reaches 2^30");
        if scale < 2f32.powi(127) {
            assert!(
                2.0 * scaled >= limit,
                "{bound}: {scale} is not the finest scale"
            );
        }
    }
}
