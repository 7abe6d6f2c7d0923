//! Explosions: each kill bursts into its kind's particles at the place it died, every other
//! particle moves, slows and fades by the scene's numbers, the same on every schedule and
//! backend; a scene without `[effects]` launches nothing for them.

mod common;

use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, Scene};
use gpuwars::kernels::registry;
use gpuwars::pipeline::ParticleSnapshot;
use gpuwars::sim::Snapshot;
use gpuwars::sim::layout::Layout;

use common::game::{crashing, without_effects};

fn scene(name: &str) -> Scene {
    built_in(name).unwrap().unwrap()
}

/// `name` with its `[effects]` table taken out.
fn without_effects_named(name: &str) -> Scene {
    without_effects(&scene(name))
}

/// Checks one step of every particle against the rules worked out here from the bodies
/// before (`b0`) and after (`b1`) the step; returns how many enemies burst.
fn check_step(
    scene: &Scene,
    layout: &Layout,
    b0: &Snapshot,
    b1: &Snapshot,
    p0: &ParticleSnapshot,
    p1: &ParticleSnapshot,
) -> u32 {
    let burst = p1.burst;
    let n = burst.per_kill.get() as usize;
    let dt = scene.world.dt;
    let mut bursts = 0;
    for p in 0..p1.particles.life.len() {
        let owner = burst.first_slot as usize + p / n;
        let kind = b1.bodies.kind[owner] as usize;
        let enemy = scene.game.behaviours[kind].is_some();
        let usable = (owner as u32) < layout.ranges[kind].end();
        let died = enemy && usable && b0.bodies.alive[owner] != 0 && b1.bodies.alive[owner] == 0;
        if died {
            if p % n == 0 {
                bursts += 1;
            }
            assert_eq!(
                p1.particles.pos[p], b1.bodies.pos[owner],
                "particle {p} is born where {owner} died"
            );
            assert_eq!(
                p1.particles.kind[p], b1.bodies.kind[owner],
                "particle {p} takes its kind"
            );
            let life = p1.particles.life[p];
            assert!(
                (burst.lifetime - burst.lifetime / 3..=burst.lifetime).contains(&life),
                "particle {p}: life {life} of {}",
                burst.lifetime
            );
            // Away from the enemy at a third of the burst's speed to all of it, in its
            // share of the circle.
            let away = p1.particles.vel[p] - b1.bodies.vel[owner] * 0.25;
            let speed = away.length();
            let slack = 1e-3 * burst.speed;
            assert!(
                speed >= burst.speed / 3.0 - slack && speed <= burst.speed + slack,
                "particle {p}: speed {speed}"
            );
            let turn = away.y.atan2(away.x).rem_euclid(std::f32::consts::TAU);
            let share = std::f32::consts::TAU / n as f32;
            let j = (p % n) as f32;
            assert!(
                turn >= j * share - 1e-3 && turn <= (j + 1.0) * share + 1e-3,
                "particle {p}: heading {turn} outside share {j}"
            );
        } else if p0.particles.life[p] > 0 {
            assert_eq!(
                p1.particles.pos[p],
                p0.particles.pos[p] + p0.particles.vel[p] * dt,
                "particle {p} moves"
            );
            assert_eq!(
                p1.particles.vel[p],
                p0.particles.vel[p] * burst.keep,
                "particle {p} slows"
            );
            assert_eq!(
                p1.particles.life[p],
                p0.particles.life[p] - 1,
                "particle {p} ages"
            );
        } else {
            assert_eq!(p1.particles.life[p], 0, "particle {p} stays gone");
            assert_eq!(
                (p1.particles.pos[p], p1.particles.vel[p]),
                (p0.particles.pos[p], p0.particles.vel[p])
            );
        }
    }
    bursts
}

fn kills_burst_where_the_enemies_died(device: &Device) {
    let scene = crashing();
    let mut game = Game::new(device, &scene, 3).unwrap();
    let particles = |g: &Game| g.pipeline().particles().unwrap().expect("explosions");
    let (mut b0, mut p0) = (game.snapshot().unwrap(), particles(&game));
    assert_eq!(p0.shown(), 0, "nothing has died yet");
    let (mut kills, mut shown_most) = (0, 0);
    for step in 0..300 {
        let status = game.step(None).unwrap();
        let (b1, p1) = (game.snapshot().unwrap(), particles(&game));
        let bursts = check_step(&scene, game.pipeline().layout(), &b0, &b1, &p0, &p1);
        assert_eq!(
            bursts, status.events.kills,
            "step {step}: one burst per kill"
        );
        kills += bursts;
        shown_most = shown_most.max(p1.shown());
        (b0, p0) = (b1, p1);
    }
    assert!(kills >= 20, "only {kills} enemies died");
    assert!(shown_most >= 12, "at most {shown_most} particles shown");
}

/// The particles' hash after `steps` autopilot steps of `scene`.
fn particles_after(device: &Device, scene: &Scene, seed: u32, steps: u32) -> u64 {
    let mut game = Game::new(device, scene, seed).unwrap();
    for _ in 0..steps {
        game.submit(None).unwrap();
    }
    game.pipeline().particles().unwrap().unwrap().hash()
}

#[test]
fn particles_are_the_same_on_every_thread_count_and_schedule() {
    let scene = crashing();
    let reference = particles_after(common::cpu(), &scene, 1, 240);
    for threads in [1, 2, 7] {
        let device = Device::cpu(Some(threads), "tests").unwrap();
        let hash = particles_after(&device, &scene, 1, 240);
        assert_eq!(hash, reference, "{threads} threads");
    }
    for seed in [1, 2] {
        let device = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed }, "tests").unwrap();
        let hash = particles_after(&device, &scene, 1, 240);
        assert_eq!(hash, reference, "shuffle seed {seed}");
    }
}

#[test]
fn the_gpu_makes_the_same_particles_as_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    let mut scenes: Vec<_> = ["paper", "kamikaze", "group", "tricky", "arena"]
        .into_iter()
        .map(|name| (name, scene(name), 1200))
        .collect();
    scenes.push(("crashing", crashing(), 300));
    for (name, scene, steps) in scenes {
        let cpu = particles_after(common::cpu(), &scene, 1, steps);
        assert_eq!(particles_after(gpu, &scene, 1, steps), cpu, "{name}");
    }
}

fn explosions_leave_the_game_untouched(device: &Device) {
    let hash = |scene: &Scene| {
        let mut game = Game::new(device, scene, 4).unwrap();
        for _ in 0..200 {
            game.submit(None).unwrap();
        }
        game.state_hash().unwrap()
    };
    assert_eq!(hash(&crashing()), hash(&without_effects(&crashing())));
}

/// Launches of the explosions' kernel, and of all kernels, in `steps` steps of `scene` on a
/// fresh emulator.
fn launches(scene: &Scene, steps: u32) -> (u64, u64) {
    let mut device = Device::cpu(Some(2), "tests").unwrap();
    device.count_launches(true);
    let mut game = Game::new(&device, scene, 1).unwrap();
    for _ in 0..steps {
        game.step(None).unwrap();
    }
    drop(game);
    let counts = device.launch_counts();
    let burst = counts
        .get(registry::BURST_AND_FADE.name)
        .copied()
        .unwrap_or(0);
    (burst, counts.values().sum())
}

#[test]
fn a_scene_without_explosions_launches_nothing_for_them() {
    let (burst, all) = launches(&scene("kamikaze"), 5);
    let (burst_without, all_without) = launches(&without_effects_named("kamikaze"), 5);
    assert_eq!(
        (burst, burst_without),
        (5, 0),
        "one launch a step, only with effects"
    );
    assert_eq!(all, all_without + 5);
    let game = Game::new(common::cpu(), &without_effects_named("kamikaze"), 1).unwrap();
    assert!(game.pipeline().particles().unwrap().is_none());
    // One kill's worth of particles per enemy slot, padding included.
    let game = Game::new(common::cpu(), &scene("kamikaze"), 1).unwrap();
    let particles = game.pipeline().particles().unwrap().unwrap();
    let burst = particles.burst;
    assert_eq!(
        particles.particles.life.len() as u32,
        (burst.end_slot - burst.first_slot) * burst.per_kill.get()
    );
}

on_both_backends!(
    kills_burst_where_the_enemies_died,
    explosions_leave_the_game_untouched
);
