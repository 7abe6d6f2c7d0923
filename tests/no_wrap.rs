//! Counters, the score and energies at the largest values a scene allows: they saturate
//! instead of wrapping, the same on both backends (issue: a ship whose energy is the largest
//! allowed died of an overflow at its first recovery tick).

mod common;

use common::game::play;
use gpuwars::Device;
use gpuwars::game::Scene;
use gpuwars::kernels::game::control::{Input, Status};

/// A scene whose ship has `ship_energy` and recovers every step, and whose one enemy kind
/// (`energy` each, living `lifetime` seconds) is spawned `count` at a time every step.
fn scene(ship_energy: i32, energy: i32, lifetime: f32, count: u32) -> Scene {
    let text = format!(
        r#"name = "limits"
description = "values at their limits"
[world]
size = [1000.0, 1000.0]
dt = 0.016666668
boundary = "clamp"
[ship]
kind = "ship"
speed = 200.0
fire_rate = 10.0
shot = "shot"
shot_speed = 600.0
autopilot_sight = 150.0
[fps]
start = 60.0
min = 12.0
recovery = 10000.0
[spawn]
distance = 300.0
[[spawn.waves]]
kind = "enemy"
at = 0.0
count = {count}
every = 0.016666668
times = 1000
[[kinds]]
name = "ship"
circle = 10.0
mass = 20.0
capacity = 1
energy = {ship_energy}
[[kinds]]
name = "shot"
circle = 2.0
mass = 0.1
capacity = 32
energy = 1
[[kinds]]
name = "enemy"
circle = 4.0
mass = 1.0
capacity = 64
energy = {energy}
lifetime = {lifetime}
[kinds.behaviour]
machine = "kamikaze"
vision = 50.0
speed = 40.0
"#
    );
    Scene::from_toml(&text, "limits.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// The statuses of `steps` steps of `scene` with nobody flying.
fn statuses(device: &Device, scene: &Scene, steps: u32) -> Vec<Status> {
    let mut seen = Vec::new();
    play(
        device,
        scene,
        5,
        steps,
        |_| Some(Input::default()),
        |status, _| seen.push(*status),
    );
    seen
}

fn a_ship_at_the_largest_energy_recovers_without_dying(device: &Device) {
    let scene = scene(i32::MAX, 1, 1000.0, 1);
    let seen = statuses(device, &scene, 20);
    for status in &seen {
        assert!(!status.is_over(), "step {}: {status:?}", status.step);
        assert_eq!(status.fps_meter, 60.0, "step {}", status.step);
    }
}

fn the_score_saturates_and_never_goes_back(device: &Device) {
    // Each enemy is worth i32::MAX and lives three steps: three deaths pass u32::MAX.
    let scene = scene(600, i32::MAX, 0.05, 2);
    let seen = statuses(device, &scene, 30);
    let last = seen.last().unwrap();
    assert!(last.enemies_killed >= 3, "{last:?}");
    assert_eq!(last.score, u32::MAX, "{last:?}");
    for pair in seen.windows(2) {
        assert!(pair[1].score >= pair[0].score, "{pair:?}");
        assert!(pair[1].enemies_killed >= pair[0].enemies_killed, "{pair:?}");
    }
    // Below the limit the score is exact: the kills times the energy.
    let first = seen.iter().find(|s| s.enemies_killed > 0).unwrap();
    let exact = u64::from(first.enemies_killed) * i32::MAX as u64;
    assert_eq!(u64::from(first.score), exact.min(u64::from(u32::MAX)));
}

on_both_backends!(
    a_ship_at_the_largest_energy_recovers_without_dying,
    the_score_saturates_and_never_goes_back,
);
