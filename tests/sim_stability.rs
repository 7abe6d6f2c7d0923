//! Stability at the extremes: time steps from 10⁻⁵ s to the largest allowed, bodies fast
//! enough to cross cells in a step, every body in one cell, bodies on cell borders and world
//! edges, worlds where f32 spacing matters, bodies on one spot, extreme masses, kinds at
//! capacity, and random worlds under random physics choices. Each case asserts invariants:
//! every live body finite and inside the world, counts and free lists consistent, the
//! contacts the brute-force reference finds, the same hash on any schedule.

mod common;

use common::sim::{brute_force, circle, kind, rect, world};
use glam::Vec2;
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::game::{Game, Scene};
use gpuwars::pipeline::Simulation;
use gpuwars::sim::layout::{Layout, space};
use gpuwars::sim::{Boundary, Integrator, Snapshot, WorldSpec};
use proptest::prelude::*;

/// Every live body finite and inside the world (`[0, size]` when clamped, `[0, size)` when
/// wrapped); each kind's live bodies and free slots add up to its capacity, and its free
/// list holds exactly its free slots, in slot order.
fn assert_invariants(spec: &WorldSpec, s: &Snapshot) {
    let layout = Layout::new(spec);
    for slot in s.live() {
        let (p, v) = (s.pos[slot], s.vel[slot]);
        assert!(p.is_finite() && v.is_finite(), "slot {slot}: {p} {v}");
        let inside = match spec.boundary {
            Boundary::Clamp => p.cmpge(Vec2::ZERO).all() && p.cmple(spec.size).all(),
            Boundary::Wrap => p.cmpge(Vec2::ZERO).all() && p.cmplt(spec.size).all(),
        };
        assert!(inside, "slot {slot} at {p} is outside {}", spec.size);
    }
    for (k, range) in layout.ranges.iter().enumerate() {
        let slots = range.start as usize..range.end() as usize;
        let free: Vec<u32> = slots
            .clone()
            .filter(|&i| s.alive[i] == 0)
            .map(|i| i as u32)
            .collect();
        assert_eq!(
            s.free_counts[k] as usize,
            free.len(),
            "kind {k}'s free count"
        );
        let listed = &s.free_list[range.start as usize..range.start as usize + free.len()];
        assert_eq!(listed, free.as_slice(), "kind {k}'s free list");
    }
}

/// A colliding world of `n` circles in a 400 × 400 box.
fn box_world(n: u32, boundary: Boundary) -> WorldSpec {
    world(
        Vec2::splat(400.0),
        boundary,
        vec![kind("b", circle(5.0), n, &["b"])],
    )
}

#[test]
fn every_time_step_from_ten_microseconds_to_the_largest_keeps_bodies_finite_and_inside() {
    for dt in [1.0e-5, 1.0e-3, 1.0 / 60.0, 0.25, 1.0] {
        for boundary in [Boundary::Clamp, Boundary::Wrap] {
            let mut spec = box_world(300, boundary);
            spec.dt = dt;
            let mut sim = Simulation::new(common::cpu(), &spec, 5).unwrap();
            sim.scatter(0, 300, 200.0).unwrap();
            for _ in 0..20 {
                sim.step().unwrap();
            }
            let s = sim.snapshot().unwrap();
            assert_invariants(&spec, &s);
            assert_eq!(s.live().count(), 300, "dt {dt}");
        }
    }
}

/// A ball of radius 1 fired at 3,000 units/s at a wall 1 unit thick: at 1/60 s it moves 50
/// units a step and passes through. It is caught when a substep moves it less than the
/// distance at which its centre is still on the near side of the wall's middle (half the
/// thickness plus its radius): then the narrow phase pushes it back and the impulse turns
/// it round.
fn fast_bodies_tunnel_through_a_thin_wall_unless_substeps_catch_them(device: &Device) {
    let (speed, half, radius) = (3000.0f32, 0.5f32, 1.0f32);
    let run = |substeps: u32| {
        let mut ball = kind("ball", circle(radius), 1, &["wall"]);
        ball.restitution = 1.0;
        let mut wall = kind("wall", rect(half, 300.0), 1, &[]);
        wall.mass = f32::INFINITY;
        let mut spec = world(Vec2::splat(1000.0), Boundary::Clamp, vec![ball, wall]);
        spec.physics.substeps = substeps;
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        let wall_slot = sim.layout().ranges[1].start;
        // The ball's path crosses the wall's middle between two whole steps.
        sim.place(&[
            (0, Vec2::new(287.0, 500.0), Vec2::new(speed, 0.0)),
            (wall_slot, Vec2::new(500.0, 500.0), Vec2::ZERO),
        ])
        .unwrap();
        for _ in 0..8 {
            sim.step().unwrap();
        }
        let s = sim.snapshot().unwrap();
        assert_invariants(&spec, &s);
        (s.pos[0], s.vel[0], spec.dt)
    };
    let (through, _, dt) = run(1);
    assert!(
        through.x > 500.0,
        "one substep: the ball crossed, at {through}"
    );
    let needed = (speed * dt / (half + radius)).ceil() as u32;
    let (caught, vel, _) = run(needed);
    assert!(
        caught.x < 500.0,
        "{needed} substeps: the ball is at {caught}"
    );
    assert!(vel.x < 0.0, "{needed} substeps: it bounced ({vel})");
}

/// 4,096 bodies on one spot. Without a cap every body counts 4,095 contacts; with a cap of
/// 32 each query examines 32 entries (its own among them for the first 32 slots), so at
/// most 32 contacts: the work of a crowded cell is bounded by the cap. Summed pushes throw bodies far across the field;
/// averaged and halved, each moves at most half a contact's push (a quarter of the depth).
fn a_crowded_cell_costs_what_the_cap_allows(device: &Device) {
    let n = 4096u32;
    let (radius, centre) = (4.0f32, Vec2::splat(1000.0));
    let run = |cap: u32, averaged: bool, relaxation: f32| {
        let mut spec = world(
            Vec2::splat(2000.0),
            Boundary::Clamp,
            vec![kind("b", circle(radius), n, &["b"])],
        );
        spec.physics.neighbour_cap = cap;
        spec.physics.averaged = averaged;
        spec.physics.relaxation = relaxation;
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        let all: Vec<_> = (0..n).map(|s| (s, centre, Vec2::ZERO)).collect();
        sim.place(&all).unwrap();
        sim.step().unwrap();
        let s = sim.snapshot().unwrap();
        assert_invariants(&spec, &s);
        let farthest = s
            .live()
            .map(|i| (s.pos[i] - centre).length())
            .fold(0.0f32, f32::max);
        (s.contacts.iter().copied().max().unwrap(), farthest)
    };
    let (contacts, _) = run(0, false, 1.0);
    assert_eq!(contacts, n - 1);
    let (contacts, summed) = run(32, false, 1.0);
    assert_eq!(contacts, 32);
    // Each contact pushes by half the depth (2 r / 2 = r), up to 32 of them the same way.
    assert!(summed > 10.0 * radius, "{summed}");
    let (contacts, relaxed) = run(32, true, 0.5);
    assert_eq!(contacts, 32);
    assert!(relaxed <= radius / 2.0 + 1e-3, "{relaxed}");
}

/// Bodies placed exactly on cell borders, on the world's edges and corners: the contacts
/// each counts are those the brute-force reference finds, on a wrapping and a clamped
/// world (contacts reach across the seams of the wrapping one).
fn contacts_on_cell_borders_and_world_edges_match_brute_force(device: &Device) {
    for boundary in [Boundary::Wrap, Boundary::Clamp] {
        let spec = world(
            Vec2::splat(120.0),
            boundary,
            vec![kind("b", circle(3.0), 200, &["b"])],
        );
        let space = space(&spec);
        let cell = spec.size.x / space.cols as f32;
        let mut places = Vec::new();
        // Every cell corner, and a neighbour 5 units along x (overlapping: 5 < 6).
        for i in 0..=space.cols {
            for j in 0..=space.rows {
                let p = Vec2::new(i as f32 * cell, j as f32 * cell).min(spec.size - 1e-3);
                places.push(p);
                places.push(Vec2::new((p.x + 5.0) % spec.size.x, p.y));
            }
        }
        places.truncate(200);
        let bodies: Vec<_> = places
            .iter()
            .enumerate()
            .map(|(s, &p)| (s as u32, p, Vec2::ZERO))
            .collect();
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        sim.place(&bodies).unwrap();
        let before = sim.snapshot().unwrap();
        sim.step().unwrap();
        let after = sim.snapshot().unwrap();
        let expected = brute_force(&spec, &space, &before);
        assert!(expected.count.iter().any(|&c| c > 0));
        assert_eq!(after.contacts, expected.count, "{boundary:?}");
        assert_invariants(&spec, &after);
    }
}

/// A world of the largest side (10⁶), where f32 positions are 1/16 apart near the far
/// corner: bodies there still find the contacts brute force finds and stay finite.
fn where_f32_spacing_is_coarse_contacts_are_still_found(device: &Device) {
    let spec = world(
        Vec2::splat(1.0e6),
        Boundary::Wrap,
        vec![kind("b", circle(2.0), 64, &["b"])],
    );
    let corner = Vec2::splat(999_900.0);
    let bodies: Vec<_> = (0..64u32)
        .map(|s| {
            let at = corner + Vec2::new((s % 8) as f32 * 3.0, (s / 8) as f32 * 3.0);
            (s, at, Vec2::new(1.0, -1.0))
        })
        .collect();
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    sim.place(&bodies).unwrap();
    let space = space(&spec);
    for _ in 0..10 {
        let before = sim.snapshot().unwrap();
        sim.step().unwrap();
        let after = sim.snapshot().unwrap();
        assert_eq!(after.contacts, brute_force(&spec, &space, &before).count);
        assert_invariants(&spec, &after);
    }
}

/// Two bodies on exactly the same spot part along ±x (the lower slot to −x), by equal
/// amounts, and the result is the same on every schedule.
fn bodies_on_one_spot_part_deterministically(device: &Device) {
    let spec = box_world(2, Boundary::Clamp);
    let run = |device: &Device| {
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        let spot = Vec2::splat(200.0);
        sim.place(&[(0, spot, Vec2::ZERO), (1, spot, Vec2::ZERO)])
            .unwrap();
        sim.step().unwrap();
        let s = sim.snapshot().unwrap();
        assert_invariants(&spec, &s);
        (s.pos[0] - spot, s.pos[1] - spot, s.state_hash())
    };
    let (a, b, hash) = run(device);
    assert_eq!(a, Vec2::new(-5.0, 0.0));
    assert_eq!(b, Vec2::new(5.0, 0.0));
    let shuffled = Device::cpu_scheduled(Some(3), Schedule::Shuffled { seed: 4 }, "tests").unwrap();
    assert_eq!(run(&shuffled).2, hash);
}

/// The lightest and heaviest masses a kind may have, and immovable bodies, colliding:
/// every body stays finite, immovable ones do not move.
fn extreme_masses_stay_finite(device: &Device) {
    let masses = [1.0e-30f32, 1.0e30, f32::INFINITY];
    let kinds = masses
        .iter()
        .enumerate()
        .map(|(k, &m)| {
            let mut spec = kind(&format!("m{k}"), circle(5.0), 50, &["m0", "m1", "m2"]);
            spec.mass = m;
            spec
        })
        .collect();
    let spec = world(Vec2::splat(100.0), Boundary::Wrap, kinds);
    let mut sim = Simulation::new(device, &spec, 3).unwrap();
    for k in 0..3 {
        sim.scatter(k, 50, 30.0).unwrap();
    }
    let start = sim.snapshot().unwrap();
    let immovable = sim.layout().ranges[2];
    for _ in 0..30 {
        sim.step().unwrap();
    }
    let s = sim.snapshot().unwrap();
    assert_invariants(&spec, &s);
    assert!(s.contacts.iter().any(|&c| c > 0));
    for slot in immovable.start..immovable.end() {
        let slot = slot as usize;
        // Immovable bodies keep their velocity (no impulse moves them) and go where it takes
        // them: 30 steps of it, wrapped.
        assert_eq!(s.vel[slot], start.vel[slot], "slot {slot}");
    }
}

/// With a cap the grid orders large buckets in runs and merges them: the grid it builds is
/// the counting order's, bit for bit. A cap too large to bind changes nothing else, so the
/// two worlds (piles of 1 to 700 bodies on a few spots, and bodies scattered between) step
/// to the same state.
fn the_bounded_grid_order_is_the_counting_order(device: &Device) {
    let run = |cap: u32| {
        let mut spec = world(
            Vec2::splat(600.0),
            Boundary::Wrap,
            vec![
                kind("a", circle(3.0), 1500, &["a", "b"]),
                kind("b", circle(5.0), 300, &["a"]),
            ],
        );
        spec.physics.neighbour_cap = cap;
        let mut sim = Simulation::new(device, &spec, 8).unwrap();
        sim.scatter(1, 300, 20.0).unwrap();
        // Piles of 700, 300, 129, 65, 64, 1 and 241 bodies of kind a, in one cell each.
        let mut slot = 0u32;
        let mut piles = Vec::new();
        for (k, size) in [700u32, 300, 129, 65, 64, 1, 241].into_iter().enumerate() {
            let spot = Vec2::new(40.0 + 80.0 * k as f32, 300.0);
            piles.extend((0..size).map(|i| (slot + i, spot, Vec2::ZERO)));
            slot += size;
        }
        sim.place(&piles).unwrap();
        for _ in 0..3 {
            sim.step().unwrap();
        }
        sim.snapshot().unwrap()
    };
    let (counted, merged) = (run(0), run(gpuwars::sim::spec::MAX_SLOTS));
    assert_eq!(counted.state_hash(), merged.state_hash());
    assert_eq!(counted.contacts, merged.contacts);
}

on_both_backends!(
    the_bounded_grid_order_is_the_counting_order,
    fast_bodies_tunnel_through_a_thin_wall_unless_substeps_catch_them,
    a_crowded_cell_costs_what_the_cap_allows,
    contacts_on_cell_borders_and_world_edges_match_brute_force,
    where_f32_spacing_is_coarse_contacts_are_still_found,
    bodies_on_one_spot_part_deterministically,
    extreme_masses_stay_finite,
);

/// `paper` with its enemy kinds' capacity cut to 40 and spawning as usual: the master
/// thread hands out only free slots, so every kind stays at or under its capacity, and its
/// free list stays exact, while the waves ask for far more.
#[test]
fn kinds_at_capacity_refuse_spawns_gracefully() {
    let mut scene = Scene::load("paper").unwrap();
    let (ship, shot) = (scene.game.ship.kind.clone(), scene.game.ship.shot.clone());
    for k in &mut scene.world.kinds {
        if k.name != ship && k.name != shot {
            k.capacity = 40;
        }
    }
    let mut game = Game::new(common::cpu(), &scene, 1).unwrap();
    let world_spec = scene.world.clone();
    let mut full = false;
    for _ in 0..20 {
        for _ in 0..30 {
            game.step(None).unwrap();
        }
        let s = game.snapshot().unwrap();
        assert_invariants(&world_spec, &s);
        full |= s
            .free_counts
            .iter()
            .zip(&world_spec.kinds)
            .any(|(&f, k)| f == 0 && k.capacity == 40);
    }
    assert!(full, "some kind must have filled up");
}

/// An hour of game time of `paper` on the CPU, the autopilot playing, games back to back
/// (a new seed when one ends): the invariants every minute of game time. Opt-in: about ten
/// minutes on two cores. Recorded in `docs/stability.md`.
#[test]
#[ignore = "an hour of game time: GPUWARS_SOAK=1 cargo test --release --test sim_stability -- --ignored --nocapture"]
fn an_hour_of_paper_keeps_every_invariant() {
    if std::env::var_os("GPUWARS_SOAK").is_none() {
        eprintln!("skipped: set GPUWARS_SOAK=1 to play an hour of game time");
        return;
    }
    let scene = Scene::load("paper").unwrap();
    let hour = (3600.0 / scene.world.dt).round() as u64;
    let minute = hour / 60;
    let start = std::time::Instant::now();
    let (mut played, mut games, mut hashes) = (0u64, 0u32, Vec::new());
    while played < hour {
        games += 1;
        let mut game = Game::new(common::cpu(), &scene, games).unwrap();
        loop {
            let status = game.step(None).unwrap();
            played += 1;
            if played % minute == 0 {
                assert_invariants(&scene.world, &game.snapshot().unwrap());
            }
            if status.game_over != 0 || played == hour {
                break;
            }
        }
        hashes.push(game.state_hash().unwrap());
    }
    let seconds = start.elapsed().as_secs_f64();
    eprintln!(
        "soak: {played} steps ({games} games) in {seconds:.0} s, {:.0} steps/s; final hashes {hashes:x?}",
        played as f64 / seconds
    );
}

/// A world of 1 to 3 kinds, circles or rectangles, wrapping or clamped, under any
/// choice of integrator, substeps, relaxation, cell scale and cap.
fn random_world() -> impl Strategy<Value = (WorldSpec, u32)> {
    let kinds = prop::collection::vec(
        (
            prop::bool::ANY,
            1.0f32..12.0,
            prop_oneof![Just(f32::INFINITY), 0.01f32..100.0],
            0.0f32..=1.0,
            1u32..80,
        ),
        1..=3,
    );
    let physics = (
        0usize..3,
        1u32..=8,
        0.05f32..=1.0,
        prop::bool::ANY,
        1.0f32..4.0,
        prop_oneof![Just(0u32), 1u32..64],
    );
    (
        kinds,
        physics,
        prop::bool::ANY,
        50.0f32..600.0,
        prop_oneof![Just(1.0e-5f32), 1.0e-3f32..=1.0],
        any::<u32>(),
    )
        .prop_map(|(kinds, physics, wraps, side, dt, seed)| {
            let names: Vec<String> = (0..kinds.len()).map(|k| format!("k{k}")).collect();
            let all: Vec<&str> = names.iter().map(String::as_str).collect();
            let kinds = kinds
                .into_iter()
                .enumerate()
                .map(|(k, (is_circle, size, mass, restitution, capacity))| {
                    let shape = if is_circle {
                        circle(size)
                    } else {
                        rect(size, size / 2.0)
                    };
                    let mut spec = kind(&names[k], shape, capacity, &all);
                    spec.mass = mass;
                    spec.restitution = restitution;
                    spec
                })
                .collect();
            let boundary = if wraps {
                Boundary::Wrap
            } else {
                Boundary::Clamp
            };
            let mut spec = world(Vec2::splat(side), boundary, kinds);
            spec.dt = dt;
            let (integrator, substeps, relaxation, averaged, cell_scale, cap) = physics;
            spec.physics.integrator = Integrator::ALL[integrator];
            spec.physics.substeps = substeps;
            spec.physics.relaxation = relaxation;
            spec.physics.averaged = averaged;
            spec.physics.cell_scale = cell_scale;
            spec.physics.neighbour_cap = cap;
            (spec, seed)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random worlds under random choices: valid, finite, inside, consistent, and the same
    /// bits on one emulator thread and on three with a shuffled schedule.
    #[test]
    fn any_world_under_any_choice_stays_finite_consistent_and_deterministic(
        (spec, seed) in random_world()
    ) {
        prop_assert!(spec.validate().is_ok(), "{:?}", spec.validate());
        let one = Device::cpu(Some(1), "tests").unwrap();
        let three =
            Device::cpu_scheduled(Some(3), Schedule::Shuffled { seed: u64::from(seed) }, "tests").unwrap();
        let run = |device: &Device| {
            let mut sim = Simulation::new(device, &spec, seed).unwrap();
            for (k, kind) in spec.kinds.iter().enumerate() {
                sim.scatter(k, kind.capacity, 100.0).unwrap();
            }
            for _ in 0..5 {
                sim.step().unwrap();
            }
            sim.snapshot().unwrap()
        };
        let (a, b) = (run(&one), run(&three));
        assert_invariants(&spec, &a);
        prop_assert_eq!(a.state_hash(), b.state_hash());
    }
}
