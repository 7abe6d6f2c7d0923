//! Scripted scenarios: each enemy behaviour doing what the paper says (section 7).

mod common;

use common::game::{
    Enemy, FIRST_ENEMY, aim_at, gathering, live_of, play, scene, spread_after_ten_seconds,
    torus_distance,
};
use gpuwars::Device;
use gpuwars::kernels::game::control::Input;
use gpuwars::kernels::game::fsm::State;

/// The ship's slot in the test scenes.
const SHIP: usize = 0;

fn kamikaze_that_sees_the_ship_hits_it(device: &Device) {
    let enemies = [Enemy {
        name: "polygon",
        machine: "kamikaze",
        count: 1,
        energy: 1,
        // On a 400-wide torus nothing is farther than 283 away.
        vision: 300.0,
        speed: 60.0,
        extra: "",
    }];
    let scene = scene(400.0, "wrap", 100.0, &enemies);
    let (mut attacked_at, mut hit_at, mut distances) = (None, None, Vec::new());
    let mut step = 0;
    let game = play(
        device,
        &scene,
        7,
        600,
        |_| Some(Input::default()),
        |status, snap| {
            step += 1;
            if let Some(&k) = live_of(snap, FIRST_ENEMY).first()
                && snap.bodies.state[k] == State::Attacking as u32
            {
                attacked_at.get_or_insert(step);
                distances.push(torus_distance(
                    snap.bodies.pos[SHIP],
                    snap.bodies.pos[k],
                    400.0,
                ));
            }
            if status.events.ship_hits > 0 {
                hit_at.get_or_insert(step);
            }
        },
    );
    let attacked_at = attacked_at.expect("the kamikaze never attacked");
    let hit_at = hit_at.expect("the kamikaze never hit the ship");
    assert!(
        attacked_at <= 2,
        "it saw the ship only at step {attacked_at}"
    );
    assert!(hit_at > attacked_at);
    // It closes in all the way: every attacking step brings it nearer.
    assert!(
        distances.windows(2).all(|w| w[1] <= w[0] + 1e-3),
        "{distances:?}"
    );
    let status = game.status();
    assert_eq!(
        status.enemies_killed, 1,
        "it should die on the ship: {status:?}"
    );
    assert!(
        status.fps_meter < 60.0,
        "the hit cost the ship no time: {status:?}"
    );
}

fn group_members_end_closer_to_each_other(device: &Device) {
    let (start, end) = spread_after_ten_seconds(device, &gathering("group"));
    println!("group: mean nearest fellow {start:.1} -> {end:.1}");
    assert!(end < 0.6 * start, "group: {start} -> {end}");
    // The same bodies without the group machine do not gather.
    let (start, end) = spread_after_ten_seconds(device, &gathering("kamikaze"));
    println!("kamikaze: mean nearest fellow {start:.1} -> {end:.1}");
    assert!(end > 0.75 * start, "kamikaze: {start} -> {end}");
}

/// Fraction of the shots that hit group enemies in 20 s, fired by a still ship at the
/// nearest one, every time the gun is ready.
fn share_of_shots_that_hit(device: &Device, avoid: &'static str) -> f64 {
    let enemies = [Enemy {
        name: "texel",
        machine: "group",
        count: 96,
        energy: 100,
        vision: 150.0,
        speed: 70.0,
        extra: avoid,
    }];
    let scene = scene(800.0, "wrap", 250.0, &enemies);
    let (mut fired, mut hits) = (0u64, 0u64);
    play(
        device,
        &scene,
        5,
        1200,
        |snap| {
            let nearest = live_of(snap, FIRST_ENEMY).into_iter().min_by(|&a, &b| {
                let d = |k: usize| snap.bodies.pos[k].distance_squared(snap.bodies.pos[SHIP]);
                d(a).total_cmp(&d(b))
            });
            nearest.map(|k| aim_at(snap, SHIP, snap.bodies.pos[k], true))
        },
        |status, snap| {
            fired += u64::from(status.events.shots_fired);
            // A shot touching anything this step is a hit (it dies of it).
            let struck = (0..snap.slots())
                .filter(|&s| snap.bodies.kind[s] == 1 && snap.contacts[s] > 0)
                .count() as u64;
            // The status counts the same hits, and says where the ship is.
            assert_eq!(u64::from(status.events.shot_hits), struck);
            assert_eq!(status.ship, snap.bodies.pos[SHIP]);
            hits += struck;
        },
    );
    assert!(fired > 100, "only {fired} shots were fired");
    hits as f64 / fired as f64
}

fn avoiding_enemies_dodge_more_bullets(device: &Device) {
    let with = share_of_shots_that_hit(device, "avoid_bullets = true");
    let without = share_of_shots_that_hit(device, "avoid_bullets = false");
    println!("shots that hit: {with:.3} avoiding, {without:.3} not avoiding");
    assert!(
        with < 0.8 * without,
        "avoiding {with}, not avoiding {without}"
    );
}

fn tricky_enemy_low_on_energy_escapes_and_recovers(device: &Device) {
    let enemies = [Enemy {
        name: "data",
        machine: "tricky",
        count: 1,
        energy: 4,
        vision: 300.0,
        speed: 60.0,
        extra: "low_energy = 2\nrecovery = 2.0\navoid_bullets = false",
    }];
    let scene = scene(600.0, "wrap", 150.0, &enemies);
    let mut escaped = false;
    let mut log: Vec<(u32, i32, f32)> = Vec::new();
    play(
        device,
        &scene,
        11,
        1200,
        |snap| {
            let target = live_of(snap, FIRST_ENEMY).first().copied();
            let state = target.map(|k| snap.bodies.state[k]);
            escaped |= state == Some(State::Escaping as u32);
            // Shoot it one shot at a time until it runs, then let it go.
            let in_flight = !live_of(snap, 1).is_empty();
            Some(match target {
                Some(k) => aim_at(snap, SHIP, snap.bodies.pos[k], !escaped && !in_flight),
                None => Input::default(),
            })
        },
        |_, snap| {
            if let Some(&k) = live_of(snap, FIRST_ENEMY).first() {
                let d = torus_distance(snap.bodies.pos[SHIP], snap.bodies.pos[k], 600.0);
                log.push((snap.bodies.state[k], snap.bodies.energy[k], d));
            }
        },
    );
    // The last escape (a shot already in flight may interrupt an earlier one).
    let escaping = State::Escaping as u32;
    let last = 1 + log
        .iter()
        .rposition(|e| e.0 == escaping)
        .expect("it never escaped");
    let first = last
        - log[..last]
            .iter()
            .rev()
            .take_while(|e| e.0 == escaping)
            .count();
    assert!(last < log.len(), "it was still escaping at the end");
    let (run, after) = (&log[first..last], log[last]);
    assert!(run[0].1 <= 2, "it escaped with energy {}", run[0].1);
    assert!(
        run.windows(2).all(|w| w[1].1 >= w[0].1),
        "energy fell while escaping"
    );
    assert!(after.1 == 4, "it stopped escaping at energy {}", after.1);
    assert!(
        run.last().unwrap().2 > run[0].2,
        "it did not get away: {run:?}"
    );
}

on_both_backends!(
    kamikaze_that_sees_the_ship_hits_it,
    group_members_end_closer_to_each_other,
    avoiding_enemies_dodge_more_bullets,
    tricky_enemy_low_on_energy_escapes_and_recovers,
);
