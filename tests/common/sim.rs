//! Worlds for the simulation tests, and a brute-force reference for the broad phase.

use glam::Vec2;
use gpuwars::kernels::sim::contact::{contact, tie_break};
use gpuwars::kernels::sim::narrow::{inverse_mass, respond};
use gpuwars::kernels::sim::{KindInfo, SlotRange, Space};
use gpuwars::sim::layout::kind_table;
use gpuwars::sim::{Boundary, KindSpec, Shape, Snapshot, Sweep, WorldSpec};

/// A kind with everything but the name, shape and capacity set to plain defaults: mass 1,
/// energy 100, no damage, restitution 0.5, no speed limit, no lifetime, no controller,
/// colliding with the listed kinds.
pub fn kind(name: &str, shape: Shape, capacity: u32, collides_with: &[&str]) -> KindSpec {
    KindSpec {
        name: name.into(),
        shape,
        mass: 1.0,
        capacity,
        energy: 100,
        damage: 0,
        restitution: 0.5,
        max_speed: f32::INFINITY,
        collides_with: collides_with.iter().map(|s| s.to_string()).collect(),
        lifetime: f32::INFINITY,
        controlled: false,
        sweep: Sweep::Off,
        top_speed: f32::INFINITY,
    }
}

/// A circle bound.
pub fn circle(radius: f32) -> Shape {
    Shape::Circle { radius }
}

/// A rectangle bound.
pub fn rect(half_x: f32, half_y: f32) -> Shape {
    Shape::Rect {
        half: Vec2::new(half_x, half_y),
    }
}

/// A world of the given size and boundary with a 1/60 s step and no vision.
pub fn world(size: Vec2, boundary: Boundary, kinds: Vec<KindSpec>) -> WorldSpec {
    WorldSpec {
        size,
        dt: 1.0 / 60.0,
        boundary,
        vision: 0.0,
        kinds,
        physics: Default::default(),
        field: Default::default(),
    }
}

/// The 10,000-body world of the determinism tests: a ship, three kinds of enemy (two circles
/// and a rectangle) that bump into each other and the ship, and shots that hurt enemies and
/// die on them, in a 2048 × 2048 wrapping world.
pub fn ten_thousand() -> (WorldSpec, Vec<(usize, u32, f32)>) {
    let mut ship = kind("ship", circle(8.0), 1, &["polygon", "shader", "data"]);
    ship.mass = 20.0;
    ship.damage = 1;
    let enemies = ["ship", "polygon", "shader", "data", "shot"];
    let polygon = kind("polygon", circle(4.0), 6000, &enemies);
    let mut shader = kind("shader", circle(6.0), 2000, &enemies);
    shader.mass = 2.0;
    let mut data = kind("data", rect(5.0, 3.0), 1000, &enemies);
    data.mass = 1.5;
    data.restitution = 0.9;
    let mut shot = kind("shot", circle(1.5), 999, &["polygon", "shader", "data"]);
    shot.energy = 1;
    shot.damage = 10;
    shot.mass = 0.1;
    shot.max_speed = 400.0;
    // Data blocks wear down whatever they touch, so enemies die too.
    data.damage = 1;
    let spec = world(
        Vec2::splat(2048.0),
        Boundary::Wrap,
        vec![ship, polygon, shader, data, shot],
    );
    // (kind, count, speed): 10,000 bodies in all.
    let scatter = vec![
        (0, 1, 0.0),
        (1, 6000, 20.0),
        (2, 2000, 15.0),
        (3, 1000, 10.0),
        (4, 999, 200.0),
    ];
    (spec, scatter)
}

/// What the narrow phase should find for each slot of `before`: the number of contacts,
/// the summed push and kick, and the energy lost, from every pair of live bodies (O(n²)).
pub struct Expected {
    /// Contacts per slot.
    pub count: Vec<u32>,
    /// Push per slot, summed in slot order.
    pub push: Vec<Vec2>,
    /// Kick per slot, summed in slot order.
    pub kick: Vec<Vec2>,
    /// Energy lost per slot.
    pub damage: Vec<i32>,
}

/// The brute-force reference: every ordered pair of live bodies through the same contact
/// test and response as the kernels, without any grid.
pub fn brute_force(spec: &WorldSpec, space: &Space, before: &Snapshot) -> Expected {
    let kinds: Vec<KindInfo> = kind_table(spec);
    let n = before.slots();
    let mut e = Expected {
        count: vec![0; n],
        push: vec![Vec2::ZERO; n],
        kick: vec![Vec2::ZERO; n],
        damage: vec![0; n],
    };
    let live: Vec<usize> = before.live().collect();
    for &a in &live {
        let ka = &kinds[before.bodies.kind[a] as usize];
        for &b in &live {
            let kb = &kinds[before.bodies.kind[b] as usize];
            if a == b || !ka.collides_with(before.bodies.kind[b]) {
                continue;
            }
            let d = space.offset(before.bodies.pos[a], before.bodies.pos[b]);
            let Some(c) = contact(ka.bound(), kb.bound(), d, tie_break(a as u32, b as u32)) else {
                continue;
            };
            let r = respond(
                c.normal,
                c.depth,
                (
                    inverse_mass(before.bodies.mass[a]),
                    inverse_mass(before.bodies.mass[b]),
                ),
                (before.bodies.vel[a], before.bodies.vel[b]),
                ka.restitution.max(kb.restitution),
            );
            e.count[a] += 1;
            e.push[a] += r.push;
            e.kick[a] += r.kick;
            e.damage[a] += kb.damage;
        }
    }
    e
}

/// Whether `a` and `b` agree to within `tol` times the larger of 1 and their size.
pub fn close(a: Vec2, b: Vec2, tol: f32) -> bool {
    (a - b).length() <= tol * a.length().max(b.length()).max(1.0)
}

/// Each kind's free slots, checked against `s`: its list must be exactly its usable slots of
/// `ranges` without a live body, in slot order, and its count their number (a brute force
/// over the snapshot; `step` names the step in a failure).
pub fn checked_free_lists(s: &Snapshot, ranges: &[SlotRange], step: usize) -> Vec<Vec<u32>> {
    let mut lists = Vec::new();
    for (k, range) in ranges.iter().enumerate() {
        let free: Vec<u32> = (range.start..range.end())
            .filter(|&i| s.bodies.alive[i as usize] == 0)
            .collect();
        assert_eq!(
            s.free.count[k] as usize,
            free.len(),
            "step {step}, kind {k}"
        );
        let start = range.start as usize;
        assert_eq!(
            s.free.list[start..start + free.len()],
            free[..],
            "step {step}, kind {k}"
        );
        lists.push(free);
    }
    lists
}
