//! The narrow phase's geometry and response against cases worked out by hand, and the
//! symmetry that lets both bodies of a pair respond alone.

use glam::Vec2;
use gpuwars::kernels::sim::contact::{Contact, contact, first_overlap, tie_break};
use gpuwars::kernels::sim::kinds::Bound;
use gpuwars::kernels::sim::narrow::respond;
use proptest::prelude::*;

const X: Vec2 = Vec2::X;

fn assert_contact(found: Option<Contact>, normal: Vec2, depth: f32) {
    let c = found.expect("a contact");
    assert!(
        (c.normal - normal).length() < 1e-6,
        "normal {} instead of {normal}",
        c.normal
    );
    assert!(
        (c.depth - depth).abs() < 1e-5,
        "depth {} instead of {depth}",
        c.depth
    );
}

#[test]
fn circles_overlap_by_the_sum_of_radii_minus_the_distance() {
    // Radii 2 and 3, centres 4 apart along (3, 4) / 5: overlap 1.
    let d = Vec2::new(2.4, 3.2);
    assert_contact(
        contact(Bound::Circle(2.0), Bound::Circle(3.0), d, X),
        d / 4.0,
        1.0,
    );
    // Exactly touching is not a contact; nor is anything further.
    assert_eq!(
        contact(
            Bound::Circle(2.0),
            Bound::Circle(3.0),
            Vec2::new(3.0, 4.0),
            X
        ),
        None
    );
    assert_eq!(
        contact(
            Bound::Circle(2.0),
            Bound::Circle(3.0),
            Vec2::new(6.0, 0.0),
            X
        ),
        None
    );
}

#[test]
fn bodies_on_the_same_spot_separate_along_the_tie_break_without_nan() {
    for (a, b) in [
        (Bound::Circle(1.0), Bound::Circle(2.0)),
        (Bound::Circle(1.0), Bound::Rect(Vec2::new(2.0, 3.0))),
        (Bound::Rect(Vec2::new(2.0, 3.0)), Bound::Circle(1.0)),
        (
            Bound::Rect(Vec2::new(2.0, 3.0)),
            Bound::Rect(Vec2::new(1.0, 1.0)),
        ),
    ] {
        let lower = contact(a, b, Vec2::ZERO, tie_break(3, 7)).unwrap();
        let higher = contact(b, a, Vec2::ZERO, tie_break(7, 3)).unwrap();
        assert!(
            lower.normal.is_finite() && lower.depth.is_finite(),
            "{a:?} {b:?}"
        );
        assert_eq!(lower.normal.abs().max_element(), 1.0);
        assert_eq!(higher.normal, -lower.normal);
        assert_eq!(higher.depth, lower.depth);
    }
}

#[test]
fn a_circle_beside_a_rectangle_overlaps_by_its_radius_minus_the_gap() {
    let rect = Bound::Rect(Vec2::new(4.0, 2.0));
    // Circle of radius 1 at the origin, rectangle centred 4.5 to its right: its left side is
    // 0.5 away, so the overlap is 0.5 and the rectangle is pushed along +x.
    assert_contact(
        contact(Bound::Circle(1.0), rect, Vec2::new(4.5, 0.0), X),
        X,
        0.5,
    );
    // Near a corner: the corner (-4, -2) relative to the rectangle is at (0.6, 0.8) from the
    // circle, distance 1, so radius 1.5 overlaps by 0.5 along (0.6, 0.8).
    let d = Vec2::new(4.6, 2.8);
    assert_contact(
        contact(Bound::Circle(1.5), rect, d, X),
        Vec2::new(0.6, 0.8),
        0.5,
    );
    assert_eq!(contact(Bound::Circle(0.9), rect, d, X), None);
}

#[test]
fn a_circle_inside_a_rectangle_leaves_through_the_nearest_side() {
    let rect = Bound::Rect(Vec2::new(4.0, 2.0));
    // The circle's centre is 1.5 above the rectangle's centre: the top side is 0.5 away, so
    // the circle needs 0.5 + its radius 1 to get out upwards, and the rectangle goes down.
    assert_contact(
        contact(Bound::Circle(1.0), rect, Vec2::new(0.0, -1.5), X),
        Vec2::NEG_Y,
        1.5,
    );
}

#[test]
fn rectangles_separate_along_the_axis_of_least_overlap() {
    let a = Bound::Rect(Vec2::new(2.0, 1.0));
    let b = Bound::Rect(Vec2::new(1.0, 1.0));
    // Overlaps: x = 3 - 2.5 = 0.5, y = 2 - 0.5 = 1.5: along x.
    assert_contact(contact(a, b, Vec2::new(2.5, 0.5), X), X, 0.5);
    // x = 3 - 0.5 = 2.5, y = 2 - 1.8 = 0.2: along -y.
    assert_contact(contact(a, b, Vec2::new(-0.5, -1.8), X), Vec2::NEG_Y, 0.2);
    assert_eq!(contact(a, b, Vec2::new(3.0, 0.0), X), None);
}

#[test]
fn an_elastic_head_on_collision_of_equal_masses_swaps_velocities() {
    let (va, vb) = (Vec2::new(3.0, 0.0), Vec2::new(-1.0, 0.0));
    let ra = respond(X, 0.2, (1.0, 1.0), (va, vb), 1.0);
    let rb = respond(-X, 0.2, (1.0, 1.0), (vb, va), 1.0);
    assert_eq!(va + ra.kick, vb);
    assert_eq!(vb + rb.kick, va);
    // Each gives way by half the overlap.
    assert_eq!(ra.push, Vec2::new(-0.1, 0.0));
    assert_eq!(rb.push, Vec2::new(0.1, 0.0));
}

#[test]
fn a_perfectly_inelastic_collision_leaves_the_pair_moving_together() {
    // Masses 1 and 3 (inverse 1 and 1/3): common velocity (1·4 + 3·0) / 4 = 1.
    let (va, vb) = (Vec2::new(4.0, 0.0), Vec2::ZERO);
    let ra = respond(X, 0.4, (1.0, 1.0 / 3.0), (va, vb), 0.0);
    let rb = respond(-X, 0.4, (1.0 / 3.0, 1.0), (vb, va), 0.0);
    assert!(((va + ra.kick).x - 1.0).abs() < 1e-6);
    assert!(((vb + rb.kick).x - 1.0).abs() < 1e-6);
    // The light body takes three quarters of the separation.
    assert!((ra.push.x + 0.3).abs() < 1e-6 && (rb.push.x - 0.1).abs() < 1e-6);
}

#[test]
fn an_immovable_body_does_not_give_way() {
    let wall = respond(X, 1.0, (0.0, 1.0), (Vec2::ZERO, Vec2::new(-2.0, 0.0)), 1.0);
    assert_eq!(wall.push, Vec2::ZERO);
    assert_eq!(wall.kick, Vec2::ZERO);
    let ball = respond(-X, 1.0, (1.0, 0.0), (Vec2::new(-2.0, 0.0), Vec2::ZERO), 1.0);
    assert_eq!(ball.push, Vec2::new(1.0, 0.0));
    assert_eq!(ball.kick, Vec2::new(4.0, 0.0));
    // Two immovable bodies stay put.
    assert_eq!(
        respond(X, 1.0, (0.0, 0.0), (Vec2::ZERO, Vec2::ZERO), 1.0).push,
        Vec2::ZERO
    );
}

fn bound() -> impl Strategy<Value = Bound> {
    prop_oneof![
        (0.1f32..10.0).prop_map(Bound::Circle),
        (0.1f32..10.0, 0.1f32..10.0).prop_map(|(x, y)| Bound::Rect(Vec2::new(x, y))),
    ]
}

proptest! {
    /// Both bodies of a pair find the same contact, mirrored, bit for bit; and the responses
    /// they compute alone conserve momentum.
    #[test]
    fn contacts_and_responses_are_antisymmetric(
        a in bound(), b in bound(),
        dx in -15.0f32..15.0, dy in -15.0f32..15.0,
        va in (-50.0f32..50.0, -50.0f32..50.0), vb in (-50.0f32..50.0, -50.0f32..50.0),
        (ma, mb) in (0.1f32..10.0, 0.1f32..10.0),
        e in 0.0f32..=1.0,
    ) {
        let d = Vec2::new(dx, dy);
        let ab = contact(a, b, d, tie_break(1, 2));
        let ba = contact(b, a, -d, tie_break(2, 1));
        prop_assert_eq!(ab.map(|c| (-c.normal, c.depth)), ba.map(|c| (c.normal, c.depth)));
        if let Some(c) = ab {
            prop_assert!(c.depth > 0.0 && (c.normal.length() - 1.0).abs() < 1e-5);
            let (va, vb) = (Vec2::from(va), Vec2::from(vb));
            let ra = respond(c.normal, c.depth, (1.0 / ma, 1.0 / mb), (va, vb), e);
            let rb = respond(-c.normal, c.depth, (1.0 / mb, 1.0 / ma), (vb, va), e);
            let momentum = ra.kick * ma + rb.kick * mb;
            prop_assert!(momentum.length() <= 1e-3 * (1.0 + (va * ma - vb * mb).length()));
            // The pushes together remove the overlap.
            let separation = (rb.push - ra.push).dot(c.normal);
            prop_assert!((separation - c.depth).abs() <= 1e-4 * c.depth.max(1.0));
        }
    }
}

#[test]
fn a_fast_circle_crossing_another_is_swept_at_the_moment_they_first_touch() {
    // A shot of radius 2 moves from 10 left of an enemy of radius 5 to 10 right of it, one
    // unit off its centre line: it touches when |(x, 1)| = 7, x = −√48, at t = (10 − √48) / 20.
    let (d0, d1) = (Vec2::new(10.0, -1.0), Vec2::new(-10.0, -1.0));
    assert!(contact(Bound::Circle(2.0), Bound::Circle(5.0), d0, X).is_none());
    assert!(contact(Bound::Circle(2.0), Bound::Circle(5.0), d1, X).is_none());
    let s = first_overlap(Bound::Circle(2.0), Bound::Circle(5.0), d0, d1).expect("a swept contact");
    let t = (10.0 - 48f32.sqrt()) / 20.0;
    assert!((s.time - t).abs() < 1e-6, "time {} instead of {t}", s.time);
    // At that moment the enemy is at (√48, −1) from the shot: the normal points there.
    let normal = Vec2::new(48f32.sqrt(), -1.0) / 7.0;
    assert!((s.normal - normal).length() < 1e-5, "normal {}", s.normal);
    // Passing 7.5 off the centre line misses; a path that stops short never touches.
    let wide = first_overlap(
        Bound::Circle(2.0),
        Bound::Circle(5.0),
        Vec2::new(10.0, 7.5),
        Vec2::new(-10.0, 7.5),
    );
    assert_eq!(wide, None);
    let short = first_overlap(
        Bound::Circle(2.0),
        Bound::Circle(5.0),
        Vec2::new(20.0, 0.0),
        Vec2::new(8.0, 0.0),
    );
    assert_eq!(short, None);
}

#[test]
fn a_circle_swept_past_a_rectangle_touches_its_face_or_its_corner() {
    let wall = Bound::Rect(Vec2::new(0.5, 3.0));
    // Head on through the face: the ball (radius 1) touches the face x = −0.5 from the
    // left when its centre is at −1.5, from −10 to +10: t = 8.5 / 20.
    let s = first_overlap(
        Bound::Circle(1.0),
        wall,
        Vec2::new(10.0, 0.0),
        Vec2::new(-10.0, 0.0),
    )
    .expect("through the face");
    assert!((s.time - 8.5 / 20.0).abs() < 1e-6, "time {}", s.time);
    assert_eq!(s.normal, Vec2::X);
    // Past the corner (−0.5, 3) at height 3.6 (in the wall's frame the ball goes from −10 to
    // +10): it touches the corner when its centre is 1 from it, 0.6 above and 0.8 before,
    // at x = −1.3, so t = 8.7 / 20, the normal pointing from the ball to the corner.
    let s = first_overlap(
        Bound::Circle(1.0),
        wall,
        Vec2::new(10.0, -3.6),
        Vec2::new(-10.0, -3.6),
    )
    .expect("past the corner");
    assert!((s.time - 8.7 / 20.0).abs() < 1e-5, "time {}", s.time);
    assert!(
        (s.normal - Vec2::new(0.8, -0.6)).length() < 1e-5,
        "normal {}",
        s.normal
    );
    // Above the corner's reach: nothing.
    let above = first_overlap(
        Bound::Circle(1.0),
        wall,
        Vec2::new(10.0, -4.1),
        Vec2::new(-10.0, -4.1),
    );
    assert_eq!(above, None);
}

/// Whether the straight path from `d0` to `d1` overlaps at any of `n` evenly spaced inner
/// points: the sampled truth the swept test must agree with away from grazing.
fn sampled_overlap(a: Bound, b: Bound, d0: Vec2, d1: Vec2, n: u32) -> Option<f32> {
    (1..n).map(|i| i as f32 / n as f32).find(|&t| {
        let d = d0 + (d1 - d0) * t;
        contact(a, b, d, X).is_some()
    })
}

proptest! {
    /// The swept test is antisymmetric bit for bit, and agrees with a path sampled at 4,000
    /// points on whether the pair meets and (within a sample) when: every contact a dense
    /// sampling sees is found no later than it, and every one found is seen within a sample
    /// of its time unless it only grazes.
    #[test]
    fn sweeps_are_antisymmetric_and_agree_with_a_sampled_path(
        a in bound(), b in bound(),
        d0 in (-30.0f32..30.0, -30.0f32..30.0), d1 in (-30.0f32..30.0, -30.0f32..30.0),
    ) {
        let (d0, d1) = (Vec2::from(d0), Vec2::from(d1));
        prop_assume!(contact(a, b, d0, X).is_none());
        let ab = first_overlap(a, b, d0, d1);
        let ba = first_overlap(b, a, -d0, -d1);
        prop_assert_eq!(ab.map(|s| (s.time, -s.normal)), ba.map(|s| (s.time, s.normal)));
        let n = 4000;
        let sampled = sampled_overlap(a, b, d0, d1, n);
        if let Some(t) = sampled {
            let s = ab.expect("the sampled path overlaps: the sweep must find it");
            prop_assert!(s.time <= t + 1e-4, "found at {} after the sample at {t}", s.time);
            prop_assert!((s.normal.length() - 1.0).abs() < 1e-4);
        } else if let Some(s) = ab {
            // Only a graze can fall between samples: a little farther in, it is seen.
            let grown = |k: Bound| match k {
                Bound::Circle(r) => Bound::Circle(r * 1.01 + 0.05),
                Bound::Rect(h) => Bound::Rect(h * 1.01 + 0.05),
            };
            prop_assert!(
                sampled_overlap(grown(a), grown(b), d0, d1, n).is_some(),
                "found at {} but no sample overlaps, even with the bounds grown", s.time
            );
        }
    }
}
