//! The narrow phase's geometry and response against cases worked out by hand, and the
//! symmetry that lets both bodies of a pair respond alone.

use glam::Vec2;
use gpuwars::kernels::sim::contact::{Contact, contact, tie_break};
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
