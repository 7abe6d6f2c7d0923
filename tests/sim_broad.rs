//! The grid broad phase finds exactly the contacts a brute-force check of every pair finds,
//! on random worlds and on the layouts that break grids: everything in one cell, bodies on
//! cell borders, on the world's edges and across its seams, no bodies, full capacity.

mod common;

use common::sim::{Expected, brute_force, circle, close, kind, rect, world};
use glam::Vec2;
use gpuwars::Device;
use gpuwars::pipeline::Simulation;
use gpuwars::sim::{Boundary, WorldSpec};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// Places `positions` in the first slots of each kind (in kind order), steps once, and checks
/// every slot's contacts, damage, push and kick against the brute-force reference.
fn check_step(device: &Device, spec: &WorldSpec, positions: &[(usize, Vec2, Vec2)]) {
    let mut sim = Simulation::new(device, spec, 7).unwrap();
    let mut next = vec![0u32; spec.kinds.len()];
    let placed: Vec<(u32, Vec2, Vec2)> = positions
        .iter()
        .map(|&(k, pos, vel)| {
            let slot = sim.layout().ranges[k].start + next[k];
            next[k] += 1;
            (slot, pos, vel)
        })
        .collect();
    sim.place(&placed).unwrap();
    let before = sim.snapshot().unwrap();
    let Expected {
        count,
        push,
        kick,
        damage,
    } = brute_force(spec, sim.space(), &before);
    sim.step().unwrap();
    let after = sim.snapshot().unwrap();
    assert_eq!(after.contacts, count, "contacts per slot");
    for s in before.live() {
        assert_eq!(
            after.bodies.energy[s],
            before.bodies.energy[s] - damage[s],
            "energy of slot {s}"
        );
        let expected_vel = before.bodies.vel[s] + kick[s];
        if after.bodies.alive[s] != 0 && spec.boundary == Boundary::Wrap {
            // Without forces, the step moves a body by its new velocity times dt plus its
            // push, around the torus.
            let expected_move = expected_vel * spec.dt + push[s];
            let space = sim.space();
            let (expected_pos, _) =
                space.confine(before.bodies.pos[s] + expected_move, expected_vel);
            let miss = space.offset(expected_pos, after.bodies.pos[s]);
            // The kernel adds the move's parts in its own order: a few units in the last
            // place of a coordinate far from the origin (an ulp is 0.008 at 85,000).
            let rounding = 4.0 * f32::EPSILON * expected_pos.abs().max_element();
            assert!(
                miss.length() <= 1e-4 * expected_move.length().max(1.0) + rounding,
                "slot {s} is at {} instead of {expected_pos}",
                after.bodies.pos[s]
            );
            assert!(
                close(after.bodies.vel[s], expected_vel, 1e-4),
                "velocity of slot {s}"
            );
        }
    }
}

fn two_kind_world(size: Vec2, boundary: Boundary, radius: f32, capacity: u32) -> WorldSpec {
    let mut a = kind("a", circle(radius), capacity, &["a", "b"]);
    a.damage = 2;
    let mut b = kind("b", rect(radius * 0.8, radius * 0.5), capacity, &["a"]);
    b.damage = 3;
    b.mass = 4.0;
    world(size, boundary, vec![a, b])
}

/// A position strategy that favours the cases grids get wrong.
fn position(size: Vec2, cell: Vec2) -> impl Strategy<Value = Vec2> {
    let border = (0u32..64, 0u32..64).prop_map(move |(i, j)| {
        Vec2::new((i as f32 * cell.x) % size.x, (j as f32 * cell.y) % size.y)
    });
    let edge = (any::<bool>(), 0.0f32..1.0).prop_map(move |(low, t)| {
        let x = if low { 0.0 } else { size.x - size.x * 1e-6 };
        Vec2::new(x, t * size.y)
    });
    let anywhere = (0.0f32..1.0, 0.0f32..1.0).prop_map(move |(x, y)| Vec2::new(x, y) * size);
    prop_oneof![4 => anywhere, 2 => border, 1 => edge, 1 => Just(Vec2::ZERO)]
}

/// The world's boundary: wrapping or clamping.
fn boundary(wrap: bool) -> Boundary {
    if wrap {
        Boundary::Wrap
    } else {
        Boundary::Clamp
    }
}

/// Random bodies as `check_step` places them: (kind, position, velocity).
fn placed(bodies: Vec<(usize, Vec2, (f32, f32))>) -> Vec<(usize, Vec2, Vec2)> {
    bodies
        .into_iter()
        .map(|(k, p, v)| (k, p, Vec2::from(v)))
        .collect()
}

fn random_worlds(device: &Device) {
    let strategy = (
        (20.0f32..300.0, 20.0f32..300.0),
        0.5f32..12.0,
        any::<bool>(),
        0usize..120,
    )
        .prop_flat_map(|((w, h), radius, wrap, n)| {
            let size = Vec2::new(w, h);
            let boundary = boundary(wrap);
            let spec = two_kind_world(size, boundary, radius, 128);
            let space = gpuwars::sim::layout::space(&spec);
            let cell = size / Vec2::new(space.cols as f32, space.rows as f32);
            let body = (
                0usize..2,
                position(size, cell),
                (-30.0f32..30.0, -30.0f32..30.0),
            );
            (Just(spec), prop::collection::vec(body, n))
        });
    let mut runner = TestRunner::new(Config {
        cases: 48,
        ..Config::default()
    });
    runner
        .run(&strategy, |(spec, bodies)| {
            check_step(device, &spec, &placed(bodies));
            Ok(())
        })
        .unwrap();
}

/// A field far larger than its bodies need: the grid has at most `BUCKETS_PER_SLOT`
/// buckets a slot (its cost follows the bodies, not the field's area), and still finds
/// exactly the pairs brute force finds, wherever the bodies are.
fn sparse_fields(device: &Device) {
    use gpuwars::sim::layout::{BUCKETS_PER_SLOT, Layout, space};
    let strategy =
        (1e4f32..1e6, 1e4f32..1e6, any::<bool>(), 0usize..40).prop_flat_map(|(w, h, wrap, n)| {
            let size = Vec2::new(w, h);
            let boundary = boundary(wrap);
            let spec = two_kind_world(size, boundary, 4.0, 40);
            let space = space(&spec);
            let cell = size / Vec2::new(space.cols as f32, space.rows as f32);
            // Half of them near one spot, so that some pairs touch.
            let near = (0.0f32..40.0, 0.0f32..40.0).prop_map(|(x, y)| Vec2::new(x, y));
            let place = prop_oneof![position(size, cell), near];
            let body = (0usize..2, place, (-30.0f32..30.0, -30.0f32..30.0));
            (Just(spec), prop::collection::vec(body, n))
        });
    let mut runner = TestRunner::new(Config {
        cases: 24,
        ..Config::default()
    });
    runner
        .run(&strategy, |(spec, bodies)| {
            let (space, slots) = (space(&spec), Layout::new(&spec).slots);
            let buckets = u64::from(space.cols) * u64::from(space.rows) * 2;
            prop_assert!(
                buckets <= BUCKETS_PER_SLOT * u64::from(slots),
                "{buckets} buckets for {slots} slots"
            );
            check_step(device, &spec, &placed(bodies));
            Ok(())
        })
        .unwrap();
}

fn everything_in_one_cell(device: &Device) {
    let spec = two_kind_world(Vec2::splat(400.0), Boundary::Clamp, 3.0, 200);
    // 300 bodies on 4 spots, all inside one cell: every pair on a spot overlaps.
    let bodies: Vec<_> = (0..300)
        .map(|i| {
            let spot = Vec2::new(100.0 + (i % 2) as f32, 100.0 + (i % 4 / 2) as f32);
            (i % 2, spot, Vec2::ZERO)
        })
        .collect();
    check_step(device, &spec, &bodies);
}

fn seams_edges_and_borders(device: &Device) {
    for boundary in [Boundary::Wrap, Boundary::Clamp] {
        let spec = two_kind_world(Vec2::new(100.0, 60.0), boundary, 2.0, 64);
        let space = gpuwars::sim::layout::space(&spec);
        let cell = spec.size / Vec2::new(space.cols as f32, space.rows as f32);
        let mut bodies = vec![
            // Across the vertical and horizontal seams, and at all four corners.
            (0, Vec2::new(0.5, 30.0), Vec2::ZERO),
            (0, Vec2::new(99.0, 30.5), Vec2::ZERO),
            (0, Vec2::new(50.0, 0.2), Vec2::ZERO),
            (1, Vec2::new(50.5, 59.5), Vec2::ZERO),
            (0, Vec2::new(0.0, 0.0), Vec2::ZERO),
            (0, Vec2::new(99.9, 59.9), Vec2::ZERO),
            (1, Vec2::new(99.9, 0.0), Vec2::ZERO),
            (0, Vec2::new(0.0, 59.9), Vec2::ZERO),
        ];
        // Pairs straddling every interior cell border.
        for c in 1..space.cols.min(20) {
            let x = c as f32 * cell.x;
            bodies.push((0, Vec2::new(x - 0.1, 20.0), Vec2::ZERO));
            bodies.push((1, Vec2::new(x + 0.1, 20.5), Vec2::ZERO));
        }
        check_step(device, &spec, &bodies);
    }
}

fn a_grid_narrower_than_three_cells(device: &Device) {
    // Cells of at least 2 × 4.5: 2 columns and 1 row, so the 3×3 block would visit cells
    // twice on a wrapping world.
    let spec = two_kind_world(Vec2::new(20.0, 12.0), Boundary::Wrap, 4.5, 16);
    let space = gpuwars::sim::layout::space(&spec);
    assert!(space.cols < 3 && space.rows < 3, "{space:?}");
    let bodies: Vec<_> = (0..16)
        .map(|i| {
            (
                i % 2,
                Vec2::new(i as f32 * 1.25, (i * 7 % 12) as f32),
                Vec2::ZERO,
            )
        })
        .collect();
    check_step(device, &spec, &bodies);
}

fn no_bodies_and_full_capacity(device: &Device) {
    let spec = two_kind_world(Vec2::splat(300.0), Boundary::Wrap, 2.0, 100);
    check_step(device, &spec, &[]);
    let bodies: Vec<_> = (0..200)
        .map(|i| {
            let p = Vec2::new((i * 37 % 300) as f32, (i * 91 % 300) as f32 * 0.99);
            (i % 2, p, Vec2::ZERO)
        })
        .collect();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    sim.scatter(0, 100, 5.0).unwrap();
    sim.scatter(1, 100, 5.0).unwrap();
    assert_eq!(sim.free_counts().unwrap(), [0, 0]);
    assert!(sim.scatter(0, 1, 5.0).is_err());
    check_step(device, &spec, &bodies);
}

on_both_backends!(
    random_worlds,
    sparse_fields,
    everything_in_one_cell,
    seams_edges_and_borders,
    a_grid_narrower_than_three_cells,
    no_bodies_and_full_capacity,
);
