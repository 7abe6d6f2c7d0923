//! The audit of whole steps: contacts found, missed, counted twice or left uncertain, sorted
//! into classes, on made-up worlds whose answers are worked out by hand.

use super::*;
use crate::sim::spec::{Boundary, Shape};
use gpuwars_kernels::sim::Touched;

/// A kind of the given shape colliding with `with`: mass 1, energy 100, no limits.
fn kind(name: &str, shape: Shape, with: &[&str]) -> KindSpec {
    KindSpec {
        name: name.into(),
        shape,
        mass: 1.0,
        capacity: 64,
        energy: 100,
        damage: 0,
        restitution: 0.5,
        max_speed: f32::INFINITY,
        collides_with: with.iter().map(|s| s.to_string()).collect(),
        lifetime: f32::INFINITY,
        controlled: false,
        sweep: super::super::spec::Sweep::Off,
        top_speed: f32::INFINITY,
    }
}

fn circle(radius: f32) -> Shape {
    Shape::Circle { radius }
}

fn rect(x: f32, y: f32) -> Shape {
    Shape::Rect {
        half: Vec2::new(x, y),
    }
}

fn world(side: f32, boundary: Boundary, kinds: Vec<KindSpec>) -> WorldSpec {
    let spec = WorldSpec {
        size: Vec2::splat(side),
        dt: 1.0 / 60.0,
        boundary,
        vision: 0.0,
        kinds,
        physics: Default::default(),
        field: Default::default(),
    };
    spec.validate().unwrap();
    spec
}

/// A shot (radius 1) and a controlled enemy (radius 5) that collide.
fn shots_and_enemies(side: f32, boundary: Boundary) -> (WorldSpec, Roles) {
    let mut enemy = kind("enemy", circle(5.0), &[]);
    enemy.controlled = true;
    let spec = world(
        side,
        boundary,
        vec![kind("shot", circle(1.0), &["enemy"]), enemy],
    );
    let roles = Roles::of(&spec, None, Some(0));
    (spec, roles)
}

/// A body over one step.
#[derive(Clone, Copy)]
struct Body {
    kind: u32,
    from: Vec2,
    to: Vec2,
    vel: Vec2,
    energy: i32,
}

fn moving(kind: u32, from: (f32, f32), to: (f32, f32)) -> Body {
    Body {
        kind,
        from: from.into(),
        to: to.into(),
        vel: Vec2::ZERO,
        energy: 1,
    }
}

fn still(kind: u32, at: (f32, f32)) -> Body {
    moving(kind, at, at)
}

/// The arrays of a step end.
#[derive(Clone)]
struct Arrays {
    alive: Vec<u32>,
    kind: Vec<u32>,
    prev: Vec<Vec2>,
    pos: Vec<Vec2>,
    vel: Vec<Vec2>,
    energy: Vec<i32>,
    log: Vec<Touched>,
    renumbered: bool,
}

impl Arrays {
    fn end(&self) -> StepEnd<'_> {
        StepEnd {
            alive: &self.alive,
            kind: &self.kind,
            prev: &self.prev,
            pos: &self.pos,
            vel: &self.vel,
            energy: &self.energy,
            log: &self.log,
            renumbered: self.renumbered,
        }
    }
}

/// The end of the bodies' step, one body a slot, and the end of the next, in which they
/// rest and the kernels counted the contacts `(slot, partner)` of `log` (at the end of the
/// motion) for the step's motion.
fn ends(bodies: &[Body], log: &[(u32, u32)]) -> (Arrays, Arrays) {
    let mut log: Vec<Touched> = log
        .iter()
        .map(|&(slot, other)| Touched {
            slot,
            other,
            time: 1.0,
        })
        .collect();
    log.sort_by_key(|t| (t.slot, t.other));
    let this = Arrays {
        alive: vec![1; bodies.len()],
        kind: bodies.iter().map(|b| b.kind).collect(),
        prev: bodies.iter().map(|b| b.from).collect(),
        pos: bodies.iter().map(|b| b.to).collect(),
        vel: bodies.iter().map(|b| b.vel).collect(),
        energy: bodies.iter().map(|b| b.energy).collect(),
        log: Vec::new(),
        renumbered: false,
    };
    let next = Arrays {
        prev: this.pos.clone(),
        log,
        ..this.clone()
    };
    (this, next)
}

fn audit(spec: &WorldSpec, roles: &Roles, bodies: &[Body], log: &[(u32, u32)]) -> Accuracy {
    let (this, next) = ends(bodies, log);
    let mut accuracy = Accuracy::default();
    accuracy.add_step(spec, roles, &this.end(), &next.end());
    accuracy
}

/// The contacts of a world of two bodies, slot `s` having counted its partner `counted[s]`
/// times.
fn each(counted: [u32; 2]) -> Vec<(u32, u32)> {
    (0..2u32)
        .flat_map(|s| (0..counted[s as usize]).map(move |_| (s, 1 - s)))
        .collect()
}

fn tally(expected: u64, missed: u64, extra: u64, tunnelling: u64) -> Tally {
    Tally {
        expected,
        missed,
        extra,
        tunnelling,
        ..Tally::default()
    }
}

#[test]
fn a_shot_through_an_enemy_between_step_ends_is_a_tunnelling_contact() {
    let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    // 10 units from the enemy's centre at both ends (radii sum to 6), through it between.
    let bodies = [
        moving(0, (40.0, 50.0), (60.0, 50.0)),
        still(1, (50.0, 50.0)),
    ];

    let missed = audit(&spec, &roles, &bodies, &each([0, 0]));
    assert_eq!(missed.classes[SHOT_ENEMY], tally(1, 1, 0, 1));
    // The enemy's side counts too, in no class.
    assert_eq!(missed.all, tally(2, 2, 0, 2));
    assert_eq!(missed.missed_per_thousand(SHOT_ENEMY), Some(1000.0));
    assert_eq!(missed.total_missed_per_thousand(), Some(1000.0));
    assert_eq!((missed.slots_audited, missed.slots_skipped), (2, 0));
    assert_eq!(missed.all.undecidable, 0);
    // No overlap at the end, so no depth.
    assert_eq!(missed.depth.count, 0);

    let found = audit(&spec, &roles, &bodies, &each([1, 1]));
    assert_eq!(found.classes[SHOT_ENEMY], tally(1, 0, 0, 1));
    assert_eq!(found.missed_per_thousand(SHOT_ENEMY), Some(0.0));

    let twice = audit(&spec, &roles, &bodies, &each([2, 1]));
    assert_eq!(twice.all, tally(2, 0, 1, 2));
    // Counted twice with an enemy: an extra shot→enemy contact.
    assert_eq!(twice.classes[SHOT_ENEMY].extra, 1);
}

#[test]
fn a_contact_counted_with_another_body_is_a_wrong_partner_not_a_miss_and_an_extra() {
    let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    // The shot passes through the enemy of slot 1; the enemy of slot 2 is far away.
    let bodies = [
        moving(0, (40.0, 50.0), (60.0, 50.0)),
        still(1, (50.0, 50.0)),
        still(1, (50.0, 90.0)),
    ];
    let accuracy = audit(&spec, &roles, &bodies, &[(0, 2), (1, 0)]);
    assert_eq!(
        accuracy.classes[SHOT_ENEMY],
        Tally {
            wrong_partner: 1,
            ..tally(1, 0, 0, 1)
        }
    );
    // A count would have seen one contact for one expected.
    assert_eq!((accuracy.all.missed, accuracy.all.extra), (0, 0));
}

#[test]
fn a_swept_contact_counted_at_another_moment_is_late() {
    let (mut spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    spec.kinds[0].sweep = super::super::spec::Sweep::On;
    // From 10 left of the enemy's centre to 10 right: the radii sum to 6, so the shot
    // enters at x = -6, at 4 / 20 of the motion.
    let bodies = [
        moving(0, (40.0, 50.0), (60.0, 50.0)),
        still(1, (50.0, 50.0)),
    ];
    let at = |time: f32| {
        let (this, mut next) = ends(&bodies, &[]);
        next.log = [(0, 1), (1, 0)]
            .map(|(slot, other)| Touched { slot, other, time })
            .to_vec();
        let mut accuracy = Accuracy::default();
        accuracy.add_step(&spec, &roles, &this.end(), &next.end());
        accuracy.all
    };
    assert_eq!(at(0.2), tally(2, 0, 0, 2));
    assert_eq!(at(0.20005), tally(2, 0, 0, 2));
    assert_eq!(
        at(0.2002),
        Tally {
            late: 2,
            ..tally(2, 0, 0, 2)
        }
    );
    // At the end, as an unswept pair would count it: late.
    assert_eq!(
        at(1.0),
        Tally {
            late: 2,
            ..tally(2, 0, 0, 2)
        }
    );
}

#[test]
fn a_shot_that_stops_short_or_ends_inside() {
    let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    let short = [
        moving(0, (30.0, 50.0), (43.5, 50.0)),
        still(1, (50.0, 50.0)),
    ];
    assert_eq!(
        audit(&spec, &roles, &short, &each([0, 0])).all,
        Tally::default()
    );
    // Ends 4 from the centre: a contact at the step's end, 2 deep.
    let inside = [
        moving(0, (30.0, 50.0), (46.0, 50.0)),
        still(1, (50.0, 50.0)),
    ];
    let accuracy = audit(&spec, &roles, &inside, &each([1, 0]));
    assert_eq!(accuracy.classes[SHOT_ENEMY], tally(1, 0, 0, 0));
    assert_eq!(accuracy.all, tally(2, 1, 0, 0));
    assert_eq!(accuracy.depth.count, 1);
    assert!((accuracy.depth.sum - 2.0).abs() < 1e-12);
    assert_eq!(accuracy.depth.max, accuracy.depth.sum);
}

#[test]
fn a_grazing_pair_is_undecidable_whatever_was_counted() {
    let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    // Passes exactly 6 from the centre: touching, at the radii's sum.
    let grazing = [
        moving(0, (40.0, 56.0), (60.0, 56.0)),
        still(1, (50.0, 50.0)),
    ];
    for counted in [[1, 0], [0, 0], [1, 1]] {
        let accuracy = audit(&spec, &roles, &grazing, &each(counted));
        let undecidable = |n| Tally {
            undecidable: n,
            ..Tally::default()
        };
        assert_eq!(accuracy.all, undecidable(2));
        assert_eq!(accuracy.classes[SHOT_ENEMY], undecidable(1));
        assert_eq!(accuracy.missed_per_thousand(SHOT_ENEMY), None);
    }

    // Half a unit either side decides it.
    let clear = [
        moving(0, (40.0, 56.5), (60.0, 56.5)),
        still(1, (50.0, 50.0)),
    ];
    let accuracy = audit(&spec, &roles, &clear, &each([0, 0]));
    assert_eq!(
        (accuracy.all.undecidable, accuracy.all),
        (0, Tally::default())
    );
    let through = [
        moving(0, (40.0, 55.5), (60.0, 55.5)),
        still(1, (50.0, 50.0)),
    ];
    let accuracy = audit(&spec, &roles, &through, &each([0, 0]));
    assert_eq!(
        (accuracy.all.undecidable, accuracy.all),
        (0, tally(2, 2, 0, 2))
    );
}

#[test]
fn a_pair_that_overlapped_at_the_start_and_separated_is_no_contact() {
    let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    let bodies = [
        still(1, (50.0, 50.0)),
        moving(0, (52.0, 50.0), (60.0, 50.0)),
    ];
    let accuracy = audit(&spec, &roles, &bodies, &each([1, 1]));
    assert_eq!(accuracy.all, tally(0, 0, 2, 0));
    assert_eq!(accuracy.all.undecidable, 0);
}

#[test]
fn contacts_reach_across_a_wrapping_worlds_seam() {
    let (wrapping, roles) = shots_and_enemies(100.0, Boundary::Wrap);
    // From x = 94 the shot goes 14 units to the right, across the seam to x = 8, through
    // the enemy at x = 1 (7 away at both ends; the radii sum to 6).
    let bodies = [moving(0, (94.0, 50.0), (8.0, 50.0)), still(1, (1.0, 50.0))];
    let accuracy = audit(&wrapping, &roles, &bodies, &each([0, 1]));
    assert_eq!(accuracy.classes[SHOT_ENEMY], tally(1, 1, 0, 1));
    assert_eq!(accuracy.all, tally(2, 1, 0, 2));

    // The same numbers in a clamped world: 93 to 7 units away, never closer.
    let (clamped, roles) = shots_and_enemies(100.0, Boundary::Clamp);
    assert_eq!(
        audit(&clamped, &roles, &bodies, &each([0, 0])).all,
        Tally::default()
    );
}

#[test]
fn an_offset_crossing_half_the_world_is_no_path_through_zero() {
    let (spec, roles) = shots_and_enemies(100.0, Boundary::Wrap);
    // 49.75 apart, then 50.25 (measured as -49.75 the other way round): they stayed half
    // the world apart.
    let bodies = [
        still(1, (10.0, 50.0)),
        moving(0, (59.75, 50.0), (60.25, 50.0)),
    ];
    let accuracy = audit(&spec, &roles, &bodies, &each([0, 0]));
    assert_eq!(
        (accuracy.all, accuracy.all.undecidable),
        (Tally::default(), 0)
    );
}

/// An immovable crate (half extents 10 × 5) and a ball of radius 2.
fn crates_and_balls() -> (WorldSpec, Roles) {
    let mut crate_ = kind("crate", rect(10.0, 5.0), &[]);
    crate_.mass = f32::INFINITY;
    let spec = world(
        200.0,
        Boundary::Clamp,
        vec![crate_, kind("ball", circle(2.0), &["crate"])],
    );
    let roles = Roles::of(&spec, None, None);
    (spec, roles)
}

/// The ball's contacts with a crate at (50, 50), whichever slot comes first.
fn ball_and_crate(ball: Body) -> Tally {
    let (spec, roles) = crates_and_balls();
    let crate_ = still(0, (50.0, 50.0));
    let first = audit(&spec, &roles, &[crate_, ball], &each([0, 0]));
    let second = audit(&spec, &roles, &[ball, crate_], &each([0, 0]));
    assert_eq!(first, second);
    assert_eq!(first.all.undecidable, 0);
    // Counted from the ball's side only.
    assert_eq!(first.classes.keys().collect::<Vec<_>>(), [BODY_WALL]);
    first.classes[BODY_WALL]
}

#[test]
fn a_ball_past_a_crates_corner() {
    // Along x + y = 117: 1/√2 from the corner (60, 55), closer than the radius, while
    // 6 and 4 from the crate at its ends.
    let cut = moving(1, (56.0, 61.0), (64.0, 53.0));
    assert_eq!(ball_and_crate(cut), tally(1, 1, 0, 1));
    // Along x + y = 118: 3/√2 > 2 from the corner, though inside the crate's box grown
    // by the radius.
    let clear = moving(1, (57.0, 61.0), (65.0, 53.0));
    assert_eq!(ball_and_crate(clear), tally(0, 0, 0, 0));
}

#[test]
fn a_ball_through_or_along_a_crates_faces() {
    let through = moving(1, (50.0, 40.0), (50.0, 60.0));
    assert_eq!(ball_and_crate(through), tally(1, 1, 0, 1));
    // 1.5 above the top face.
    let along = moving(1, (30.0, 56.5), (70.0, 56.5));
    assert_eq!(ball_and_crate(along), tally(1, 1, 0, 1));
    let above = moving(1, (30.0, 57.5), (70.0, 57.5));
    assert_eq!(ball_and_crate(above), tally(0, 0, 0, 0));
}

#[test]
fn a_ball_resting_near_a_crates_corner() {
    let (spec, roles) = crates_and_balls();
    let crate_ = still(0, (50.0, 50.0));
    // 1.2 and 1.8 beyond the corner (60, 55) along both axes: inside the grown box both
    // times, within the radius of the corner the first time only.
    let near = audit(
        &spec,
        &roles,
        &[crate_, still(1, (61.2, 56.2))],
        &each([0, 1]),
    );
    assert_eq!(near.classes[BODY_WALL], tally(1, 0, 0, 0));
    let gap = (f64::from(61.2f32) - 60.0).hypot(f64::from(56.2f32) - 55.0);
    assert_eq!(near.depth.count, 1);
    assert!((near.depth.sum - (2.0 - gap)).abs() < 1e-12);
    let far = audit(
        &spec,
        &roles,
        &[crate_, still(1, (61.8, 56.8))],
        &each([0, 0]),
    );
    assert_eq!((far.all, far.depth.count), (Tally::default(), 0));
    // A centre inside: the nearest face (2 away) plus the radius.
    let inside = audit(
        &spec,
        &roles,
        &[crate_, still(1, (58.0, 51.0))],
        &each([1, 1]),
    );
    assert_eq!(inside.all, tally(2, 0, 0, 0));
    assert_eq!((inside.depth.count, inside.depth.max), (1, 4.0));
}

/// Rectangles of half extents 2 × 2 and 3 × 1 (overlapping within 5 × 3 of each other),
/// the first at (50, 50), the second moving.
fn rect_pair(second: Body) -> Accuracy {
    let spec = world(
        100.0,
        Boundary::Clamp,
        vec![
            kind("a", rect(2.0, 2.0), &["b"]),
            kind("b", rect(3.0, 1.0), &[]),
        ],
    );
    let roles = Roles::of(&spec, None, None);
    audit(
        &spec,
        &roles,
        &[still(0, (50.0, 50.0)), second],
        &each([0, 0]),
    )
}

#[test]
fn rectangles_meet_by_their_slabs() {
    let straight = rect_pair(moving(1, (40.0, 52.0), (60.0, 52.0)));
    assert_eq!(straight.classes.keys().collect::<Vec<_>>(), ["a→b"]);
    assert_eq!(straight.classes["a→b"], tally(1, 1, 0, 1));
    let above = rect_pair(moving(1, (40.0, 53.5), (60.0, 53.5)));
    assert_eq!(above.classes["a→b"], Tally::default());
    // Offset from (-7.5, 0) to (0, 7.5): inside at (-4.9, 2.6).
    let diagonal = rect_pair(moving(1, (42.5, 50.0), (50.0, 57.5)));
    assert_eq!(diagonal.classes["a→b"], tally(1, 1, 0, 1));
    // From (-9, 0) to (0, 9): 1/√2 from the corner (-5, 3), yet outside.
    let past = rect_pair(moving(1, (41.0, 50.0), (50.0, 59.0)));
    assert_eq!(past.classes["a→b"], Tally::default());
    assert_eq!(past.all.undecidable, 0);
    // From (-8, 0) to (0, 8): through the corner exactly.
    let corner = rect_pair(moving(1, (42.0, 50.0), (50.0, 58.0)));
    assert_eq!(corner.all.undecidable, 2);
    assert_eq!(
        corner.classes["a→b"],
        Tally {
            undecidable: 1,
            ..Tally::default()
        }
    );
    // At rest 4 × 1 apart: overlaps of 1 and 2, the least is the depth.
    let resting = rect_pair(still(1, (54.0, 51.0)));
    assert_eq!(resting.classes["a→b"], tally(1, 1, 0, 0));
    assert_eq!((resting.depth.count, resting.depth.max), (1, 1.0));
}

#[test]
fn bodies_that_die_after_counting_are_audited_and_renumbered_steps_skipped() {
    let spec = world(
        100.0,
        Boundary::Clamp,
        vec![kind("rock", circle(3.0), &["rock"])],
    );
    let roles = Roles::of(&spec, None, None);
    let bodies = [
        still(0, (50.0, 50.0)),
        still(0, (54.0, 50.0)),
        still(0, (46.0, 50.0)),
        still(0, (50.0, 55.0)),
        still(0, (0.0, 10.0)),
    ];
    let (this, mut next) = ends(&bodies, &[]);
    // Slot 2's body died in the next step, after its narrow phase counted its contacts.
    next.alive[2] = 0;
    let mut accuracy = Accuracy::default();
    accuracy.add_step(&spec, &roles, &this.end(), &next.end());
    assert_eq!((accuracy.slots_audited, accuracy.slots_skipped), (5, 0));
    // Slot 0 touches slots 1, 2 and 3 (4, 4 and 5 away; the radii sum to 6), each of
    // those only slot 0, slot 4 nothing.
    assert_eq!(accuracy.all, tally(6, 6, 0, 0));
    assert_eq!(accuracy.classes["rock→rock"], accuracy.all);
    // Every pair's depth: 2, 2 and 1.
    assert_eq!(accuracy.depth.count, 3);
    assert_eq!((accuracy.depth.sum, accuracy.depth.max), (5.0, 2.0));
    assert_eq!(accuracy.steps, 1);
    // A step that renumbered: no slot holds its body of the step before.
    next.alive[2] = 1;
    next.renumbered = true;
    let mut renumbered = Accuracy::default();
    renumbered.add_step(&spec, &roles, &this.end(), &next.end());
    assert_eq!((renumbered.slots_audited, renumbered.slots_skipped), (0, 5));
    assert_eq!(renumbered.all, Tally::default());
}

#[test]
fn contacts_are_sorted_into_classes() {
    let mut wall = kind("wall", rect(20.0, 20.0), &[]);
    wall.mass = f32::INFINITY;
    let mut enemy = kind("enemy", circle(5.0), &["enemy", "rock"]);
    enemy.controlled = true;
    let spec = world(
        400.0,
        Boundary::Clamp,
        vec![
            kind("ship", circle(8.0), &["enemy", "wall"]),
            kind("shot", circle(1.0), &["enemy", "wall"]),
            wall,
            enemy,
            kind("rock", circle(3.0), &[]),
        ],
    );
    let roles = Roles::of(&spec, Some(0), Some(1));
    assert_eq!(
        roles,
        Roles {
            ship: Some(0),
            shot: Some(1),
            enemies: 1 << 3,
            walls: 1 << 2
        }
    );
    let bodies = [
        // The ship and an enemy 5 apart.
        still(0, (300.0, 300.0)),
        // The shot ends inside the wall and 4 from the enemy of slot 3, having passed
        // through the enemy of slot 4.
        moving(1, (140.0, 100.0), (119.0, 100.0)),
        still(2, (100.0, 100.0)),
        still(3, (119.0, 104.0)),
        still(3, (130.0, 100.0)),
        still(3, (305.0, 300.0)),
        // A rock and an enemy 5 apart, two enemies 8 apart.
        still(4, (300.0, 250.0)),
        still(3, (300.0, 245.0)),
        still(3, (200.0, 300.0)),
        still(3, (208.0, 300.0)),
    ];
    // The ship missed its contact; the shot one of three.
    let counted = [
        (1, 2),
        (1, 3),
        (2, 1),
        (3, 1),
        (4, 1),
        (5, 0),
        (6, 7),
        (7, 6),
        (8, 9),
        (9, 8),
    ];
    let accuracy = audit(&spec, &roles, &bodies, &counted);
    let names: Vec<&str> = accuracy.classes.keys().map(String::as_str).collect();
    let mut expected_names = [
        BODY_WALL,
        ENEMY_SHIP,
        SHOT_ENEMY,
        "enemy→enemy",
        "enemy→rock",
    ];
    expected_names.sort();
    assert_eq!(names, expected_names);
    // The missed one goes to the tunnelling partner first, though the wall's slot is
    // lower.
    assert_eq!(accuracy.classes[SHOT_ENEMY], tally(2, 1, 0, 1));
    assert_eq!(accuracy.classes[BODY_WALL], tally(1, 0, 0, 0));
    assert_eq!(accuracy.classes[ENEMY_SHIP], tally(1, 1, 0, 0));
    assert_eq!(accuracy.classes["enemy→rock"], tally(1, 0, 0, 0));
    assert_eq!(accuracy.classes["enemy→enemy"], tally(2, 0, 0, 0));
    // Every slot's view: the shot's 3, one each for the other nine.
    assert_eq!(accuracy.all, tally(12, 2, 0, 2));

    // Without the tunnelling partner, the lower slot's partner takes the miss.
    let mut slower = bodies;
    slower[1] = still(1, (119.0, 100.0));
    let counted = [
        (1, 3),
        (2, 1),
        (3, 1),
        (5, 0),
        (6, 7),
        (7, 6),
        (8, 9),
        (9, 8),
    ];
    let accuracy = audit(&spec, &roles, &slower, &counted);
    assert_eq!(accuracy.classes[SHOT_ENEMY], tally(1, 0, 0, 0));
    assert_eq!(accuracy.classes[BODY_WALL], tally(1, 1, 0, 0));
}

#[test]
fn limits_are_checked_on_audited_bodies() {
    let mut limited = kind("limited", circle(1.0), &[]);
    limited.max_speed = 10.0;
    let spec = world(100.0, Boundary::Clamp, vec![limited]);
    let roles = Roles::of(&spec, None, None);
    let body = |x: f32, vel: (f32, f32), energy: i32| Body {
        vel: vel.into(),
        energy,
        ..still(0, (x, 50.0))
    };
    let bodies = [
        body(10.0, (0.0, 10.0), 100),
        // Within the margin.
        body(20.0, (10.00005, 0.0), 1),
        body(30.0, (6.0, 8.1), 100),
        body(40.0, (0.0, 0.0), 101),
        body(50.0, (-20.0, 0.0), 102),
        // Not audited: dead at the step's end.
        body(60.0, (-20.0, 0.0), 102),
    ];
    let (mut this, next) = ends(&bodies, &[]);
    this.alive[5] = 0;
    let mut accuracy = Accuracy::default();
    accuracy.add_step(&spec, &roles, &this.end(), &next.end());
    assert_eq!(accuracy.slots_audited, 5);
    assert_eq!(
        (accuracy.speed_violations, accuracy.energy_violations),
        (2, 2)
    );
}
