//! The rule that decides which pairs are swept (`gpuwars::sim::spec::miss_fraction` and
//! `WorldSpec::pair_sweeps`), at every travel from 10⁻³⁰ to 10³⁰ of the contact: its figure
//! against a numerical integration in f64 written here, its verdict, and its words.

mod common;

use common::sim::{circle, kind, world};
use glam::Vec2;
use gpuwars::sim::spec::{SWEEP_ABOVE, miss_fraction};
use gpuwars::sim::{Boundary, Sweep};

/// Nodes and weights of 8-point Gauss–Legendre quadrature on [−1, 1].
const GAUSS: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// `∫ f` over `[a, b]`, in `panels` panels of 8-point Gauss–Legendre.
fn integrate(f: impl Fn(f64) -> f64, (a, b): (f64, f64), panels: u32) -> f64 {
    let h = (b - a) / f64::from(panels);
    (0..panels)
        .map(|i| {
            let mid = a + h * (f64::from(i) + 0.5);
            GAUSS
                .iter()
                .map(|&(x, w)| w * f(mid + 0.5 * h * x))
                .sum::<f64>()
                * 0.5
                * h
        })
        .sum()
}

/// The missed fraction worked out from its definition, apart from the code under test: a
/// pass at offset `y = u·reach` (`u` uniform in [0, 1]) has a chord `2·reach·√(1 − u²)`,
/// missed with probability `max(0, 1 − chord / travel)`. With `s = travel / (2·reach)` and
/// `u = cos θ` (θ the chord's half-angle, `sin θ` its half length over the reach), the
/// fraction is `∫ max(0, 1 − sin θ / s) sin θ dθ` over [0, π/2]: the chords shorter than the
/// travel are those of `θ` below `asin s` (all of them from `s = 1`). Integrated over that
/// range, where the integrand is smooth.
fn reference(travel: f64, reach: f64) -> f64 {
    let s = travel / (2.0 * reach);
    if s == 0.0 {
        return 0.0;
    }
    let end = if s < 1.0 {
        s.asin()
    } else {
        std::f64::consts::FRAC_PI_2
    };
    integrate(|t| (1.0 - t.sin() / s) * t.sin(), (0.0, end), 64)
}

/// Travels from 10⁻³⁰ to 10³⁰ times the reach (and the edges: 0, exactly the diameter and
/// one ulp either side, f32's largest), against reaches from 10⁻³ to 10⁶: the figure is
/// finite, in [0, 1] (1 where π/(4s) is under f64's last place), within 10⁻⁹ (relative) of the integration, and never falls as the
/// travel grows.
#[test]
fn the_missed_fraction_is_right_at_every_travel() {
    for reach in [1.0e-3, 1.0, 7.0, 1.0e6] {
        let diameter = 2.0 * reach;
        let mut travels: Vec<f64> = (-300..=300)
            .map(|e| reach * 10f64.powf(f64::from(e) / 10.0))
            .collect();
        travels.extend([
            0.0,
            diameter,
            diameter.next_down(),
            diameter.next_up(),
            f64::from(f32::MAX),
            2.0 * f64::from(f32::MAX),
        ]);
        travels.sort_by(f64::total_cmp);
        let mut last = 0.0;
        for travel in travels {
            let got = miss_fraction(travel, reach);
            let want = reference(travel, reach);
            let at = format!("travel {travel:e}, reach {reach}: {got:e} against {want:e}");
            assert!(got.is_finite() && (0.0..=1.0).contains(&got), "{at}");
            assert!((got - want).abs() <= 1e-9 * want, "{at}");
            assert!(got >= last, "{at}: falls from {last:e}");
            last = got;
        }
    }
    // The small-travel limit: t² / (24·reach²).
    let got = miss_fraction(1.0e-12, 1.0);
    assert!((got / (1.0e-24 / 24.0) - 1.0).abs() < 1e-9, "{got:e}");
}

/// Two kinds closing at `speed` each, of radius `radius`, at time step `dt`: whether the
/// automatic rule sweeps them, and its words.
fn rule(speed: f32, radius: f32, dt: f32) -> (bool, String) {
    let mut a = kind("a", circle(radius), 32, &["b"]);
    let mut b = kind("b", circle(radius), 32, &[]);
    for k in [&mut a, &mut b] {
        k.max_speed = speed;
        k.sweep = Sweep::Auto;
    }
    let mut spec = world(Vec2::splat(1000.0), Boundary::Wrap, vec![a, b]);
    spec.dt = dt;
    spec.validate().unwrap();
    let pair = spec.pair_sweeps().remove(0);
    (pair.swept, pair.rule)
}

/// The verdict follows the figure at every extreme, and its words hold no `inf`, `NaN` or
/// minus sign and no figure longer than a person reads: a slow pair at a tiny step is not
/// swept (the old formula said 500 per thousand there, and at smaller steps a negative
/// figure of 24 digits); speed limits near f32's largest, whose sum overflows f32, are
/// swept, their travel written in scientific notation.
#[test]
fn the_rule_decides_and_speaks_finitely_at_the_extremes() {
    let cases = [
        (1.0, 5.0, 1.0e-9, false),
        (1.0, 5.0, 1.0e-5, false),
        (100.0, 5.0, 1.0 / 60.0, true),
        (f32::MAX, 5.0, 1.0 / 60.0, true),
        (f32::MAX / 2.0, 1.0e-3, 1.0, true),
        (1.0e-30, 1.0e6, 1.0e-5, false),
    ];
    for (speed, radius, dt, swept) in cases {
        let (got, words) = rule(speed, radius, dt);
        assert_eq!(got, swept, "{speed} {radius} {dt}: {words}");
        assert!(!words.contains("inf") && !words.contains("NaN"), "{words}");
        assert!(!words.contains('-') || words.contains("e-"), "{words}");
        let longest = words.split_whitespace().map(str::len).max().unwrap();
        assert!(longest <= 12, "{words}");
    }
    // The threshold: a pair just past it is swept, one just short of it is not.
    let mut low = 0.0f64;
    let mut high = 10.0;
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        match miss_fraction(mid, 10.0) > SWEEP_ABOVE {
            true => high = mid,
            false => low = mid,
        }
    }
    assert!(miss_fraction(high, 10.0) > SWEEP_ABOVE && miss_fraction(low, 10.0) <= SWEEP_ABOVE);
}
