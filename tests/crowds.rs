//! Crowds and the budgets: a look examines at most `⌈sight_budget / 3⌉` bodies of a kind
//! in each row of its block, and a body's contacts are sought among at most
//! `⌈contact_budget / 3⌉`, taken evenly from a crowd. Within the budget a look is the plain
//! one, bit for bit; beyond it the game stays deterministic on every schedule, thread count
//! and backend, and a group still gathers from what it samples.

mod common;

use common::game::{gathering, hash_after, hash_with, shuffled_hashes, spread_after_ten_seconds};
use gpuwars::Device;
use gpuwars::game::{Options, Scene};
use gpuwars::pipeline::Lanes;

/// The stress scene: 2,560 enemies of the three machines on one spot, where every body sees
/// every other.
fn one_spot() -> Scene {
    let text = include_str!("../scenes/stress/one-spot.toml");
    Scene::from_toml(text, "scenes/stress/one-spot.toml").unwrap()
}

/// The stress scene with its group enemies short-sighted (12 units of the 32-unit spot): they
/// rarely see the ship, so what they make of the crowd (a sample of some 450 bodies in
/// sight) drives them.
fn one_spot_grouping() -> Scene {
    let mut scene = one_spot();
    let texel = scene.world.kind_index("texel").unwrap();
    scene.game.behaviours[texel].as_mut().unwrap().vision = 12.0;
    scene
}

/// The pile: the stress scene's 2,560 enemies on one spot, every enemy kind colliding with
/// the three, under a contact budget of 384 (128 of a kind a row), which samples their
/// contacts.
fn pile() -> Scene {
    let text = include_str!("../scenes/stress/pile.toml");
    Scene::from_toml(text, "scenes/stress/pile.toml").unwrap()
}

/// `scene` with a sight budget of `budget`.
fn budgeted(scene: &Scene, budget: u32) -> Scene {
    let mut scene = scene.clone();
    scene.world.physics.sight_budget = budget;
    scene
}

/// Asserts that `steps` steps of `scene` end in the same state on 1, 2 and 3 CPU threads
/// and under shuffled schedules, and returns that state's hash.
fn same_on_every_schedule(scene: &Scene, steps: u32) -> u64 {
    let reference = hash_after(common::cpu(), scene, 1, steps);
    for threads in [1, 3] {
        let device = Device::cpu(Some(threads), "tests").unwrap();
        assert_eq!(
            hash_after(&device, scene, 1, steps),
            reference,
            "{threads} threads"
        );
    }
    for (label, hash) in shuffled_hashes(scene, steps) {
        assert_eq!(hash, reference, "{label}");
    }
    reference
}

#[test]
fn a_crowd_on_one_spot_is_the_same_game_on_every_schedule_and_thread_count() {
    // The short-sighted group's sample changes what it does: the budget is at work.
    let grouping = one_spot_grouping();
    let plain = hash_after(common::cpu(), &budgeted(&grouping, 0), 1, 40);
    assert_ne!(hash_after(common::cpu(), &grouping, 1, 40), plain);
    for scene in [one_spot(), grouping] {
        same_on_every_schedule(&scene, 40);
    }
}

#[test]
fn a_pile_on_one_spot_is_the_same_game_on_every_schedule_and_thread_count() {
    let scene = pile();
    let reference = same_on_every_schedule(&scene, 20);
    // The contact budget is at work: without it, another game.
    let mut unbudgeted = scene.clone();
    unbudgeted.world.physics.contact_budget = 0;
    assert_ne!(hash_after(common::cpu(), &unbudgeted, 1, 20), reference);
}

/// On a GPU the machines' looks and the narrow phase are shared by teams of lanes, each lane
/// taking its share of the sample: the same game as the CPU's one thread a body, crowd or
/// pile or not.
fn the_crowd_is_the_cpus_game(device: &Device) {
    for scene in [one_spot(), one_spot_grouping(), pile()] {
        let reference = hash_after(common::cpu(), &scene, 1, 60);
        for lanes in [
            Lanes::Auto,
            Lanes::Fixed(1),
            Lanes::Fixed(8),
            Lanes::Fixed(32),
        ] {
            let options = Options {
                lanes,
                ..Options::default()
            };
            assert_eq!(
                hash_with(device, &scene, 1, 60, options),
                reference,
                "{lanes:?}"
            );
        }
    }
}

fn a_look_within_its_budget_is_the_plain_look(device: &Device) {
    // A budget of 192 takes up to 64 entries of a kind from each run of cells: more than
    // the 48 bodies of the kind and as many as the 64 shots.
    let plain = hash_after(device, &budgeted(&gathering("group"), 0), 1, 600);
    for budget in [192, 1000] {
        let scene = budgeted(&gathering("group"), budget);
        assert_eq!(hash_after(device, &scene, 1, 600), plain, "budget {budget}");
    }
    // A budget some looks exceed: their samples make another game.
    let sampled = hash_after(device, &budgeted(&gathering("group"), 3), 1, 600);
    assert_ne!(sampled, plain);
}

fn a_group_gathers_from_a_sample_of_its_fellows(device: &Device) {
    for budget in [0, 3] {
        let (start, end) = spread_after_ten_seconds(device, &budgeted(&gathering("group"), budget));
        println!("sight budget {budget}: mean nearest fellow {start:.1} -> {end:.1}");
        assert!(end < 0.6 * start, "budget {budget}: {start} -> {end}");
    }
}

on_both_backends!(
    the_crowd_is_the_cpus_game,
    a_look_within_its_budget_is_the_plain_look,
    a_group_gathers_from_a_sample_of_its_fellows,
);
