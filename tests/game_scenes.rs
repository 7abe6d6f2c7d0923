//! Whole games: the stages a scene launches, determinism across backends and thread
//! counts, replays, and the autopilot's survival on the paper's scene.

mod common;

use common::game::{hash_after, hash_with, shuffled_hashes};

use gpuwars::Device;
use gpuwars::demo::{self, DemoFlyer, RunOptions};
use gpuwars::game::Options;
use gpuwars::game::scene::built_in;
use gpuwars::game::{Game, Scene};
use gpuwars::kernels::game::control::{Input, Status};
use gpuwars::kernels::registry;
use gpuwars::pipeline::Lanes;

fn scene(name: &str) -> Scene {
    built_in(name)
        .expect("a built-in scene")
        .expect("it is valid")
}

/// The launches of `steps` steps of `scene` (autopilot or still input), by kernel name.
fn launches(
    scene: &Scene,
    steps: u32,
    autopilot: bool,
) -> std::collections::BTreeMap<&'static str, u64> {
    let mut device = Device::cpu(Some(2), "tests").unwrap();
    device.count_launches(true);
    let mut game = Game::new(&device, scene, 1).unwrap();
    let input = (!autopilot).then(Default::default);
    for _ in 0..steps {
        game.step(input).unwrap();
    }
    drop(game);
    device.launch_counts()
}

#[test]
fn a_scene_launches_only_the_stages_it_uses() {
    let count = |counts: &std::collections::BTreeMap<&str, u64>, name: &str| {
        counts.get(name).copied().unwrap_or(0)
    };
    // The machines launch one of two kernels: with teams of threads (on a GPU, for kinds
    // that expect many neighbours) or without.
    let thinks = |counts: &std::collections::BTreeMap<&str, u64>| {
        count(counts, registry::THINK.name) + count(counts, registry::THINK_IN_TEAMS.name)
    };
    // Kamikazes only, circles only, one wave at the start (then one every 5 s); the shots
    // are swept.
    let k = launches(&scene("kamikaze"), 10, true);
    assert_eq!(thinks(&k), 10);
    assert_eq!(count(&k, registry::COLLIDE_CIRCLES_SWEPT.name), 10);
    for kernel in [registry::COLLIDE, registry::COLLIDE_SWEPT] {
        assert_eq!(
            count(&k, kernel.name),
            0,
            "no rectangles, no rectangle tests"
        );
    }
    // Nothing swept: the narrow phase without swept code, and no more launches.
    let mut unswept = scene("kamikaze");
    for kind in &mut unswept.world.kinds {
        kind.sweep = gpuwars::sim::Sweep::Off;
    }
    let u = launches(&unswept, 10, true);
    assert_eq!(count(&u, registry::COLLIDE_CIRCLES.name), 10);
    assert_eq!(count(&u, registry::COLLIDE_CIRCLES_SWEPT.name), 0);
    assert_eq!(u.values().sum::<u64>(), k.values().sum::<u64>());
    // Every step launches the same sequence: births and the autopilot decide on the device
    // whether there is anything to do.
    for kernel in [
        registry::BIRTHS_AND_COUNT.name,
        registry::MASTER.name,
        registry::TALLY.name,
    ] {
        assert_eq!(count(&k, kernel), 10, "{kernel}");
    }
    // The autopilot leaves each step's input for the next: once more, at set-up, for the
    // first.
    assert_eq!(count(&k, registry::AUTOPILOT.name), 11);
    // Given input: the same launches.
    let still = launches(&scene("kamikaze"), 10, false);
    assert_eq!(still, k);
    // Rectangles: the full narrow phase.
    let a = launches(&scene("arena"), 4, true);
    assert_eq!(count(&a, registry::COLLIDE_SWEPT.name), 4);
    assert_eq!(count(&a, registry::COLLIDE_CIRCLES_SWEPT.name), 0);
    // The paper's seven kinds: their machines in one launch per step.
    let p = launches(&scene("paper"), 2, true);
    assert_eq!(thinks(&p), 2);
    // A world without machines has no think stage at all.
    let mut calm = scene("kamikaze");
    for (kind, behaviour) in calm.world.kinds.iter_mut().zip(&mut calm.game.behaviours) {
        (kind.controlled, *behaviour) = (false, None);
    }
    let c = launches(&calm, 3, true);
    assert_eq!(thinks(&c), 0, "{c:?}");
}

#[test]
fn buffers_are_sized_from_the_scene() {
    for built in gpuwars::game::scene::BUILT_IN {
        let scene = scene(built.name);
        let game = Game::new(common::cpu(), &scene, 1).unwrap();
        let expected: u32 = scene
            .world
            .kinds
            .iter()
            .map(|k| k.capacity.next_multiple_of(32))
            .sum();
        assert_eq!(game.pipeline().layout().slots, expected, "{}", built.name);
    }
}

#[test]
fn the_game_hash_does_not_depend_on_the_emulators_schedule() {
    // Blocks and threads in shuffled orders: a result that depended on which thread ran
    // first (the grid's atomic bucket counts hand out ranks in arrival order) would move.
    // With teams of 8 lanes, the bodies take their step in one launch
    // (`collide_think_integrate`): a body that read another's place or velocity while that
    // one's team moved it would move too (kamikazes ramming a ship that outlives them
    // collide with it nearly every step).
    for (scene, steps) in [(scene("paper"), 120), (doomed(), 300)] {
        let in_order = hash_after(common::cpu(), &scene, 1, steps);
        for (label, hash) in shuffled_hashes(&scene, steps) {
            assert_eq!(hash, in_order, "{}: {label}", scene.name);
        }
    }
}

/// A scene that a still ship loses fast: kamikazes that see the whole field, are born close
/// to it and outlive their hits.
fn doomed() -> Scene {
    let text = common::game::crashing_text()
        .replace("energy = 1\ndamage = 10", "energy = 100000\ndamage = 10");
    Scene::from_toml(&text, "doomed").unwrap()
}

/// Plays a still ship with statuses read `lag` steps late until a status says the game is
/// over; returns the step it ended at and the final state hash.
fn play_until_over(device: &Device, lag: usize) -> (u32, u64) {
    let options = Options {
        lag,
        ..Options::default()
    };
    let mut game = Game::with_options(device, &doomed(), 5, options).unwrap();
    let mut end: Option<u32> = None;
    let note = |end: &mut Option<u32>, status: Status| {
        if status.is_over() && end.is_none() {
            *end = Some(status.step);
        }
    };
    for _ in 0..3000 {
        game.submit(Some(Input::default())).unwrap();
        while let Some(status) = game.ready_status().unwrap() {
            note(&mut end, status);
        }
        if end.is_some() {
            break;
        }
    }
    while let Some(status) = game.next_status().unwrap() {
        note(&mut end, status);
    }
    (
        end.expect("the doomed game ends"),
        game.state_hash().unwrap(),
    )
}

fn the_game_ends_at_the_same_step_whatever_the_lag(device: &Device) {
    let reference = play_until_over(common::cpu(), 1);
    for lag in [1, 3, 17] {
        assert_eq!(play_until_over(device, lag), reference, "lag {lag}");
    }
}

#[test]
fn the_game_hash_does_not_depend_on_the_emulators_thread_count() {
    let scene = scene("paper");
    let hashes: Vec<u64> = [1, 2, 7]
        .into_iter()
        .map(|threads| {
            let device = Device::cpu(Some(threads), "tests").unwrap();
            hash_after(&device, &scene, 1, 240)
        })
        .collect();
    assert!(hashes.iter().all(|&h| h == hashes[0]), "{hashes:x?}");
    let other_seed = hash_after(common::cpu(), &scene, 2, 240);
    assert_ne!(other_seed, hashes[0]);
}

/// Steps each built-in scene is played for the CPU-against-GPU comparison: the large scenes
/// fewer, since the emulation plays them too.
fn comparison_steps(name: &str) -> u32 {
    match name {
        "scale-1m" => 20,
        "scale-16m" => 3,
        _ => 300,
    }
}

#[test]
fn the_gpu_plays_the_same_game_as_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    for built in gpuwars::game::scene::BUILT_IN {
        let scene = scene(built.name);
        let steps = comparison_steps(built.name);
        let cpu = hash_after(common::cpu(), &scene, 1, steps);
        let gpu = hash_after(gpu, &scene, 1, steps);
        println!(
            "{}: {steps} steps: cpu {cpu:#018x}, gpu {gpu:#018x}",
            built.name
        );
        assert_eq!(cpu, gpu, "{}", built.name);
    }
}

fn a_replay_reproduces_the_game(device: &Device) {
    for name in ["kamikaze", "group", "arena"] {
        let scene = scene(name);
        let (report, replay) = demo::demo(device, &scene, 3, 400, RunOptions::default()).unwrap();
        let text = replay.to_json();
        let read = gpuwars::game::replay::Replay::parse(&text, "memory").unwrap();
        let scene_again = read.scene("replay").unwrap();
        let again = demo::replay(device, &scene_again, &read, RunOptions::default()).unwrap();
        assert_eq!(again.state_hash, report.state_hash, "{name}");
        assert_eq!(again.score, report.score);
        assert_eq!(format!("{:#018x}", read.state_hash), report.state_hash);
    }
}

fn the_autopilot_survives_a_minute_of_the_paper_scene(device: &Device) {
    let (report, _) = demo::demo(device, &scene("paper"), 1, 3600, RunOptions::default()).unwrap();
    println!("{}", report.to_text());
    assert_eq!(report.steps, 3600, "the game ended early: {report:?}");
    assert!(!report.game_over);
    assert!(
        report.enemies_killed > 0 && report.enemies_alive > 4096,
        "{report:?}"
    );
}

/// A team of lanes a body folds what its lanes find in the order of one thread (contacts) or
/// merges exact sums (sight): whatever the width, every scene plays the game of one thread a
/// body on the CPU, bit for bit; so does the one launch of the narrow phase, the machines and
/// the integrator (`collide_think_integrate`, which teams wider than one lane get in worlds
/// of circles) against the three launches of one thread a body.
fn teams_of_any_width_play_the_game_of_one_thread_a_body(device: &Device) {
    let hash = |device: &Device, scene: &Scene, lanes: Lanes| {
        let options = Options {
            lanes,
            ..Options::default()
        };
        hash_with(device, scene, 1, 240, options)
    };
    for name in ["paper", "group", "tricky", "arena"] {
        let scene = scene(name);
        let reference = hash(common::cpu(), &scene, Lanes::Fixed(1));
        for lanes in [
            Lanes::Auto,
            Lanes::Fixed(2),
            Lanes::Fixed(8),
            Lanes::Fixed(32),
        ] {
            assert_eq!(
                hash(device, &scene, lanes),
                reference,
                "{name} with {lanes:?}"
            );
        }
    }
}

/// A game's step remakes the free lists of the kinds whose bodies died or were born only,
/// and keeps the others': after every step of `paper` under the autopilot (waves, kills,
/// shots, renumbering), each kind's list is still exactly its usable slots without a live
/// body in slot order, and its count their number (a brute force over the snapshot).
fn a_games_free_lists_are_every_free_slot_after_every_step(device: &Device) {
    let mut game = Game::new(device, &scene("paper"), 4).unwrap();
    let ranges = game.pipeline().layout().ranges.clone();
    let (mut kept, mut remade) = (0, 0);
    let mut last = game.snapshot().unwrap().free.count;
    for step in 0..600 {
        game.step(None).unwrap();
        let s = game.snapshot().unwrap();
        common::sim::checked_free_lists(&s, &ranges, step);
        for (k, &count) in s.free.count.iter().enumerate() {
            match count == last[k] {
                true => kept += 1,
                false => remade += 1,
            }
        }
        last = s.free.count;
    }
    // Both kinds of step were seen: lists that changed and lists that stayed.
    assert!(kept > 0 && remade > 0, "kept {kept}, remade {remade}");
}

on_both_backends!(
    a_games_free_lists_are_every_free_slot_after_every_step,
    teams_of_any_width_play_the_game_of_one_thread_a_body,
    a_replay_reproduces_the_game,
    the_game_ends_at_the_same_step_whatever_the_lag,
    the_autopilot_survives_a_minute_of_the_paper_scene,
);

/// The paper's rule, kept: a ship that never moves nor fires is worn down by the enemies that
/// reach it and loses `paper` well inside five minutes; the autopilot lives at least twice as
/// long and processes more than twice as many enemies meanwhile.
#[test]
fn a_ship_with_no_pilot_loses_the_paper_scene_and_the_autopilot_does_better() {
    let five_minutes = 5 * 60 * 60;
    for seed in [1, 2] {
        let idle = RunOptions {
            pilot: DemoFlyer::None,
            ..RunOptions::default()
        };
        let (lost, _) =
            demo::demo(common::cpu(), &scene("paper"), seed, five_minutes, idle).unwrap();
        assert!(lost.game_over, "seed {seed}: {lost:?}");
        assert_eq!(lost.game_over_reason, "too slow");
        assert!(lost.game_seconds < 200.0, "seed {seed}: {lost:?}");
        let twice = 2 * lost.steps;
        let flown = demo::demo(
            common::cpu(),
            &scene("paper"),
            seed,
            twice,
            RunOptions::default(),
        )
        .unwrap()
        .0;
        assert!(!flown.game_over, "seed {seed}: {flown:?}");
        assert!(
            flown.enemies_killed > 2 * lost.enemies_killed,
            "seed {seed}: the autopilot processed {} enemies, the idle ship {}",
            flown.enemies_killed,
            lost.enemies_killed
        );
    }
}

#[test]
fn a_wave_is_counted_in_the_step_it_arrives() {
    // `paper`: seven waves (one per enemy type, 512 + 6 × 256 enemies) at 0 s, then every 4 s.
    let cpu = common::cpu();
    let mut game = Game::new(cpu, &scene("paper"), 1).unwrap();
    let first = game.step(None).unwrap();
    assert_eq!(first.events.waves, 7);
    assert_eq!(first.events.spawned, 512 + 6 * 256);
    for _ in 1..120 {
        let status = game.step(None).unwrap();
        assert_eq!(status.events.waves, 0, "step {}", status.step);
    }
}
