//! Renumbering moves each kind's bodies to the slots of its range in the grid's order and
//! changes nothing else: the same bodies, bit for bit, as in a world that never renumbers;
//! the same game on every thread count, schedule and backend; explosions still burst
//! where the enemies died.

mod common;

use common::game::crashing_text;
use common::sim::{circle, kind, ten_thousand, world};
use glam::Vec2;
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::demo::{self, RunOptions};
use gpuwars::game::replay::{FIRST_VERSION, Replay, VERSION};
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, Scene};
use gpuwars::pipeline::Simulation;
use gpuwars::sim::layout::{Layout, space};
use gpuwars::sim::{Boundary, Snapshot, WorldSpec};
use rand::Rng;
use rand::seq::SliceRandom;

/// A live body's state without its slot, as bits: kind; position, velocity, force and
/// facing; energy, machine state and age.
type Body = (u32, [u32; 8], i32, u32, u32);

/// The live bodies of `s`, sorted: what a renumbering must leave as it is.
fn bodies(s: &Snapshot) -> Vec<Body> {
    let b = &s.bodies;
    let mut all: Vec<Body> = s
        .live()
        .map(|i| {
            let v = [b.pos[i], b.vel[i], b.force[i], b.dir[i]];
            let bits = v.map(|v| [v.x.to_bits(), v.y.to_bits()]).concat();
            (
                b.kind[i],
                bits.try_into().unwrap(),
                b.energy[i],
                b.state[i],
                b.age[i],
            )
        })
        .collect();
    all.sort_unstable();
    all
}

/// `spec` renumbering every `every` steps (0: never).
fn renumbering(spec: &WorldSpec, every: u32) -> WorldSpec {
    let mut spec = spec.clone();
    spec.physics.renumber_every = Some(every);
    spec
}

/// The 10,000-body world (collisions, deaths, shots), stepped 40 times without renumbering,
/// renumbering every step and every third step: the same bodies, bit for bit. Each body
/// sums its contacts in the grid's order, which renumbering keeps.
fn renumbering_changes_no_body(device: &Device) {
    let (spec, scatter) = ten_thousand();
    let run = |every: u32| {
        let mut sim = Simulation::new(device, &renumbering(&spec, every), 7).unwrap();
        for &(kind, count, speed) in &scatter {
            sim.scatter(kind, count, speed).unwrap();
        }
        for _ in 0..40 {
            sim.step().unwrap();
        }
        (sim.snapshot().unwrap(), sim.free_counts().unwrap())
    };
    let (never, never_free) = run(0);
    assert!(never.live().count() < 10_000, "some bodies died");
    for every in [1, 3] {
        let (renumbered, free) = run(every);
        assert_eq!(free, never_free, "every {every}: free slots per kind");
        assert!(
            bodies(&renumbered) == bodies(&never),
            "every {every}: the bodies differ"
        );
        let moved = never.live().zip(renumbered.live()).any(|(a, b)| a != b);
        assert!(moved, "every {every}: the bodies kept their slots");
    }
}

/// Bodies placed at rest in random slots, far enough apart never to touch: after one step
/// that renumbers, each kind's bodies fill the front of its range in the order of their
/// cells (row-major), those of one cell in the order of their old slots, each with its own
/// state.
fn renumbering_puts_each_kind_in_the_grids_order(device: &Device) {
    let a = kind("a", circle(1.0), 300, &["a", "b"]);
    let b = kind("b", circle(2.0), 100, &["a", "b"]);
    let spec = renumbering(&world(Vec2::splat(512.0), Boundary::Wrap, vec![a, b]), 1);
    let (layout, grid) = (Layout::new(&spec), space(&spec));
    let mut rng = common::rng_for("grid order", 0);
    // Points of a 16-unit lattice, shuffled: no two bodies within 4 units.
    let mut points: Vec<Vec2> = (0..32 * 32)
        .map(|i| Vec2::new((i % 32) as f32, (i / 32) as f32) * 16.0 + Vec2::splat(4.0))
        .collect();
    points.shuffle(&mut rng);
    let mut placed = Vec::new();
    for (k, count) in [(0, 250), (1, 80)] {
        let range = layout.ranges[k];
        let mut slots: Vec<u32> = (range.start..range.end()).collect();
        slots.shuffle(&mut rng);
        for &slot in &slots[..count] {
            let pos = points.pop().unwrap();
            // A velocity of its own names the body; too slow to leave its cell in a step.
            let vel = Vec2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
            placed.push((slot, pos, vel));
        }
    }
    let run = |every: u32| {
        let mut sim = Simulation::new(device, &renumbering(&spec, every), 1).unwrap();
        sim.place(&placed).unwrap();
        sim.step().unwrap();
        sim.snapshot().unwrap()
    };
    let (never, renumbered) = (run(0), run(1));
    assert!(bodies(&renumbered) == bodies(&never));
    for (k, range) in layout.ranges.iter().enumerate() {
        let mut expected: Vec<(u32, u32, Vec2)> = placed
            .iter()
            .filter(|&&(slot, _, _)| never.bodies.kind[slot as usize] == k as u32)
            .map(|&(slot, pos, vel)| (grid.cell_of(pos), slot, vel))
            .collect();
        expected.sort_by_key(|&(cell, slot, _)| (cell, slot));
        for slot in range.start..range.end() {
            let rank = (slot - range.start) as usize;
            let live = renumbered.bodies.alive[slot as usize] != 0;
            assert_eq!(live, rank < expected.len(), "kind {k}: slot {slot}");
            if live {
                let (cell, old, vel) = expected[rank];
                assert_eq!(
                    renumbered.bodies.vel[slot as usize], vel,
                    "kind {k}: slot {slot} holds the body of slot {old} (cell {cell})"
                );
                assert_eq!(
                    renumbered.bodies.pos[slot as usize],
                    never.bodies.pos[old as usize]
                );
            }
        }
    }
}

/// A scene that crashes enemies into one another, renumbering every step.
fn crashing_renumbered() -> Scene {
    let text = format!("{}\n[physics]\nrenumber_every = 1\n", crashing_text());
    Scene::from_toml(&text, "crashing, renumbered").unwrap()
}

/// With renumbering every step, each kill still bursts once, at the slot where the enemy
/// died (the explosions' test for a death moves with the bodies).
fn kills_burst_where_renumbered_enemies_died(device: &Device) {
    let scene = crashing_renumbered();
    let mut game = Game::new(device, &scene, 3).unwrap();
    let particles = |g: &Game| g.pipeline().particles().unwrap().expect("explosions");
    let mut p0 = particles(&game);
    let burst = p0.burst;
    let (n, dt) = (burst.per_kill.get() as usize, scene.world.dt);
    let mut kills = 0;
    for step in 0..300 {
        let status = game.step(None).unwrap();
        let (b1, p1) = (game.snapshot().unwrap(), particles(&game));
        let mut bursts = 0;
        for first in (0..p1.particles.life.len()).step_by(n) {
            let (life, pos) = (p1.particles.life[first], p1.particles.pos[first]);
            let aged = p0.particles.life[first] == life + 1
                && pos == p0.particles.pos[first] + p0.particles.vel[first] * dt;
            if life == 0 || aged {
                continue;
            }
            let owner = burst.first_slot as usize + first / n;
            assert_eq!(
                b1.bodies.alive[owner], 0,
                "step {step}: {owner} burst alive"
            );
            assert_eq!(pos, b1.bodies.pos[owner], "step {step}: where {owner} died");
            bursts += 1;
        }
        assert_eq!(bursts, status.events.kills, "step {step}: a burst per kill");
        kills += bursts;
        p0 = p1;
    }
    assert!(kills >= 20, "only {kills} enemies died");
}

/// The state hash after `steps` autopilot steps of `scene`.
fn hash_after(device: &Device, scene: &Scene, steps: u32) -> u64 {
    let mut game = Game::new(device, scene, 5).unwrap();
    for _ in 0..steps {
        game.step(None).unwrap();
    }
    game.state_hash().unwrap()
}

#[test]
fn a_renumbering_game_is_the_same_on_every_thread_count_and_schedule() {
    let scene = crashing_renumbered();
    let one = hash_after(&Device::cpu(Some(1), "tests").unwrap(), &scene, 150);
    let three = hash_after(&Device::cpu(Some(3), "tests").unwrap(), &scene, 150);
    let shuffled = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed: 4 }, "tests").unwrap();
    assert_eq!(one, three);
    assert_eq!(one, hash_after(&shuffled, &scene, 150));
    if let Some(gpu) = common::gpu() {
        assert_eq!(one, hash_after(gpu, &scene, 150), "the GPU");
    }
}

/// A replay recorded before renumbering (version 1, whose scene has no `renumber_every`)
/// plays its scene as it was played then, never renumbering, and reaches its recorded hash;
/// read as the current version, the same inputs play another game.
fn a_replay_from_before_renumbering_plays_as_recorded(device: &Device) {
    let mut then = built_in("paper").unwrap().unwrap();
    assert!(then.world.physics.renumber_every.is_none());
    then.world.physics.renumber_every = Some(0);
    let (report, mut recorded) = demo::demo(device, &then, 2, 60, RunOptions::default()).unwrap();
    // The scene's text is the built-in one, without the key, as a version-1 build wrote it.
    recorded.version = FIRST_VERSION;
    let old = Replay::parse(&recorded.to_json(), "version 1").unwrap();
    let replayed = |replay: &Replay| {
        let scene = replay.scene("the replay").unwrap();
        demo::replay(device, &scene, replay, RunOptions::default())
            .unwrap()
            .state_hash
    };
    assert_eq!(replayed(&old), report.state_hash);
    let now = Replay {
        version: VERSION,
        ..old
    };
    assert_ne!(replayed(&now), report.state_hash);
}

on_both_backends!(
    renumbering_changes_no_body,
    renumbering_puts_each_kind_in_the_grids_order,
    kills_burst_where_renumbered_enemies_died,
    a_replay_from_before_renumbering_plays_as_recorded,
);
