//! MT607 against a naive reference that regenerates all 19 words at once,
//! the way dcmt's `genrand_mt` does, instead of the one-word update.

use gpuwars_kernels::rng::mt607::{self, Mt607, Mt607Params};

/// Straightforward MT607: block refill, explicit index, tempering spelled
/// out with the literal shifts 12, 7, 15, 18.
struct Naive {
    a: u32,
    b: u32,
    c: u32,
    x: [u32; 19],
    i: usize,
}

impl Naive {
    fn new(p: Mt607Params, seed: u32) -> Self {
        let mut x = [0u32; 19];
        x[0] = seed;
        for k in 1..19 {
            x[k] = 1812433253u32
                .wrapping_mul(x[k - 1] ^ (x[k - 1] >> 30))
                .wrapping_add(k as u32);
        }
        Naive {
            a: p.matrix_a,
            b: p.mask_b,
            c: p.mask_c,
            x,
            i: 19,
        }
    }

    fn next(&mut self) -> u32 {
        if self.i == 19 {
            let old = self.x;
            let mut new = [0u32; 19];
            // x[k + 19] = x[k + 9] ^ twist(x[k], x[k + 1]) over the sequence
            // old ++ new.
            let seq = |k: usize, new: &[u32; 19]| if k < 19 { old[k] } else { new[k - 19] };
            for k in 0..19 {
                let y = (seq(k, &new) & 0xffff_fffe) | (seq(k + 1, &new) & 1);
                let mag = if y & 1 == 1 { self.a } else { 0 };
                new[k] = seq(k + 9, &new) ^ (y >> 1) ^ mag;
            }
            self.x = new;
            self.i = 0;
        }
        let mut y = self.x[self.i];
        self.i += 1;
        y ^= y >> 12;
        y ^= (y << 7) & self.b;
        y ^= (y << 15) & self.c;
        y ^= y >> 18;
        y
    }
}

/// Parameter sets from dcmt (seed 4172, ids 0, 1, 13, 65535; see
/// tests/rng_dcmt.rs at the repository root for the source), plus a made-up one.
const PARAMS: [Mt607Params; 5] = [
    Mt607Params::new(0xe98e_0000, 0xddee_7380, 0x6f7a_8000),
    Mt607Params::new(0xf03e_0001, 0x32f7_7780, 0xef65_8000),
    Mt607Params::new(0xb753_000d, 0x2665_7980, 0xf7d3_8000),
    Mt607Params::new(0x827a_ffff, 0xd955_7780, 0x6e57_8000),
    Mt607Params::new(0xffff_ffff, 0xffff_ffff, 0xffff_ffff),
];

const SEEDS: [u32; 4] = [0, 1, 777, 0xdead_beef];

#[test]
fn matches_naive_reference() {
    for p in PARAMS {
        for seed in SEEDS {
            let mut fast = Mt607::new(p, seed);
            let mut naive = Naive::new(p, seed);
            for k in 0..20_000 {
                assert_eq!(
                    fast.next_u32(),
                    naive.next(),
                    "{p:x?} seed {seed} output {k}"
                );
            }
        }
    }
}

#[test]
fn borrowed_state_functions_match_struct() {
    let p = PARAMS[2];
    let mut g = Mt607::new(p, 99);
    let mut state = mt607::seed_state(99);
    let mut index = 0u32;
    for _ in 0..1000 {
        let raw = mt607::step(&mut state, &mut index, p.matrix_a);
        assert_eq!(g.next_u32(), mt607::temper(raw, &p));
    }
    assert_eq!((g.state, g.index), (state, index));
    assert_eq!(mt607::next_u32_in(&mut state, &mut index, &p), g.next_u32());
}

#[test]
fn floats_follow_the_sample_conversion() {
    assert_eq!(mt607::to_unit_f32(0), 1.0 / 4_294_967_296.0);
    // (float)0xffffffff rounds to 2^32, so the top of the range is 1.0.
    assert_eq!(mt607::to_unit_f32(u32::MAX), 1.0);
    assert_eq!(mt607::to_unit_f32(0x8000_0000), 0.5);
    let p = PARAMS[0];
    let mut g = Mt607::new(p, 5);
    let mut naive = Naive::new(p, 5);
    for _ in 0..10_000 {
        let want = ((naive.next() as f32) + 1.0) / 4_294_967_296.0;
        let got = g.next_f32();
        assert_eq!(got.to_bits(), want.to_bits());
        assert!(got > 0.0 && got <= 1.0);
    }
}

#[test]
fn normal_pairs_follow_box_muller() {
    let p = PARAMS[1];
    let mut g = Mt607::new(p, 11);
    let mut naive = Naive::new(p, 11);
    let (mut sum, mut sum_sq, n) = (0.0f64, 0.0f64, 100_000);
    for _ in 0..n / 2 {
        let u1 = ((naive.next() as f32) + 1.0) / 4_294_967_296.0;
        let u2 = ((naive.next() as f32) + 1.0) / 4_294_967_296.0;
        let r = (-2.0 * u1.ln()).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u2;
        let (z0, z1) = g.next_normal_pair();
        // libm and the host libm may differ in the last bits.
        assert!((z0 - r * phi.cos()).abs() <= 1e-5 * (1.0 + r));
        assert!((z1 - r * phi.sin()).abs() <= 1e-5 * (1.0 + r));
        for z in [z0, z1] {
            assert!(z.is_finite());
            sum += f64::from(z);
            sum_sq += f64::from(z) * f64::from(z);
        }
    }
    let mean = sum / f64::from(n);
    let var = sum_sq / f64::from(n) - mean * mean;
    assert!(mean.abs() < 0.02, "mean {mean}");
    assert!((var - 1.0).abs() < 0.02, "variance {var}");
}

#[test]
fn the_first_normal_alone_is_the_pairs_first() {
    let mut g = Mt607::new(PARAMS[2], 5);
    // The smallest and largest uniforms too: the ends of the logarithm's range.
    let mut pairs = vec![(mt607::to_unit_f32(0), 0.5), (1.0, 1.0), (1.0, 0.25)];
    pairs.extend((0..20_000).map(|_| (g.next_f32(), g.next_f32())));
    for (u1, u2) in pairs {
        let (first, _) = mt607::box_muller(u1, u2);
        assert_eq!(
            mt607::box_muller_first(u1, u2).to_bits(),
            first.to_bits(),
            "u1 {u1:e}, u2 {u2:e}"
        );
    }
}

#[test]
fn plain_data_layout() {
    use core::mem::{align_of, size_of};
    assert_eq!(size_of::<Mt607Params>(), 12);
    assert_eq!(size_of::<Mt607>(), 4 * (3 + 19 + 1));
    assert_eq!(align_of::<Mt607>(), 4);
}
