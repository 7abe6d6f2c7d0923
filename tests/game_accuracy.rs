//! The game's accuracy in game terms (`gpuwars::game::accuracy`): the contacts of `paper`
//! audited against an exact continuous-time check of the bodies' paths, with the scene's
//! swept contacts and with none, at the scene's step and at twice it. The audit is
//! independent of the kernels (f64, every pair), so the expected contacts are its own.

mod common;

use gpuwars::game::accuracy::{AuditLength, GameAudit, audit_game};
use gpuwars::game::scene::BUILT_IN;
use gpuwars::game::{Game, Options, Scene};
use gpuwars::pipeline::{Lanes, Persistent};
use gpuwars::sim::Sweep;
use gpuwars::sim::audit::{Accuracy, SHOT_ENEMY};
use gpuwars::{Device, Error};

/// `paper` at time step `dt` (its own if `None`), every kind's sweep set to `sweep` if given.
fn paper(dt: Option<f32>, sweep: Option<Sweep>) -> Scene {
    let mut scene = Scene::load("paper").unwrap();
    if let Some(dt) = dt {
        scene.world.dt = dt;
    }
    if let Some(sweep) = sweep {
        for kind in &mut scene.world.kinds {
            kind.sweep = sweep;
        }
    }
    scene
}

/// Long enough for the field to fill and the autopilot's shots to hit a few dozen enemies.
const LENGTH: AuditLength = AuditLength {
    warmup: 600,
    busy_within: 0,
    steps: 1200,
};

/// The audits of `paper` at its own step and at 1/30 s, swept as the scene says and with
/// nothing swept: `[(swept, unswept); 2]`.
fn audits(device: &Device) -> [(Accuracy, Accuracy); 2] {
    [None, Some(1.0 / 30.0)].map(|dt| {
        let audit = |sweep| {
            audit_game(device, &paper(dt, sweep), 1, LENGTH)
                .unwrap()
                .contacts
        };
        (audit(None), audit(Some(Sweep::Off)))
    })
}

fn shots_swept_miss_no_enemy_and_unswept_ones_do(device: &Device) {
    let runs = audits(device);
    for ((swept, unswept), dt) in runs.iter().zip(["1/60", "1/30"]) {
        let (s, u) = (&swept.classes[SHOT_ENEMY], &unswept.classes[SHOT_ENEMY]);
        eprintln!(
            "dt {dt}: swept shot→enemy {s:?}, every contact {:?}; unswept {u:?}, every \
             contact {:?}",
            swept.all, unswept.all
        );
        // Enough shots hit for the figures to mean something.
        assert!(
            s.expected >= 30 && u.expected >= 30,
            "dt {dt}: too few hits"
        );
        // Swept: every contact the exact check finds is counted, tunnelling ones included.
        assert_eq!(s.missed, 0, "dt {dt}: swept shots missed enemies");
        assert_eq!(swept.all.missed, 0, "dt {dt}: swept contacts missed");
        // Unswept: the contacts a test at step ends cannot see are missed, and only those.
        assert!(
            u.tunnelling > 0 && u.missed == u.tunnelling,
            "dt {dt}: {u:?}"
        );
        assert_eq!(unswept.all.missed, unswept.all.tunnelling, "dt {dt}");
        for a in [swept, unswept] {
            assert_eq!(a.speed_violations + a.energy_violations, 0, "dt {dt}");
            assert!(
                a.slots_audited > a.slots_skipped,
                "dt {dt}: mostly renumbered"
            );
        }
    }
    // A larger step skips more: more of the unswept contacts are missed at 1/30 s.
    let rate = |a: &Accuracy| a.missed_per_thousand(SHOT_ENEMY).unwrap();
    assert!(rate(&runs[1].1) > rate(&runs[0].1));
    if device.kind() == gpuwars::BackendKind::Cuda {
        // The GPU plays the same games bit for bit, so its audits are the CPU's.
        assert_eq!(runs, audits(common::cpu()));
    }
}

/// The built-in game scenes (the two scale worlds are too large for an f64 audit of every
/// pair, and have no ship).
const GAME_SCENES: [&str; 5] = ["paper", "arena", "kamikaze", "group", "tricky"];

/// One line of the game's accuracy table (docs/physics.md): the figures of `a`.
fn table_row(scene: &str, dt: &str, sweep: &str, a: &GameAudit) -> String {
    let all = &a.contacts.all;
    let per = |n: u64| {
        all.per_thousand(n)
            .map_or("–".into(), |v| format!("{v:.1}"))
    };
    format!(
        "| {scene} | {dt} | {sweep} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
        all.expected,
        all.tunnelling,
        per(all.missed),
        per(all.extra),
        per(all.wrong_partner),
        per(all.late),
        all.undecidable,
        all.moment_undecidable,
        a.kills_per_shot().map_or("–".into(), |k| format!("{k:.2}")),
    )
}

/// Every built-in game scene at 1/120, 1/60 and 1/30 s, as it sweeps and with nothing
/// swept: its swept pairs' contacts are every one found, once, with the right partner, at
/// its moment; its unswept pairs miss exactly the contacts that began and ended between
/// step ends. Each audit covers the same game time (5 s of play, then 10 s audited).
fn every_game_scene_swept_exact_at_three_steps(device: &Device) {
    eprintln!(
        "| scene | dt | swept | contacts | between ends | missed ‰ | extra ‰ | wrong partner ‰ \
         | late ‰ | undecidable | moment undecidable | kills per shot |"
    );
    for name in GAME_SCENES {
        assert!(
            BUILT_IN.iter().any(|b| b.name == name),
            "{name} is not built in"
        );
        for hz in [120.0, 60.0, 30.0] {
            let length = AuditLength {
                warmup: (5.0 * hz) as u32,
                busy_within: 0,
                steps: (10.0 * hz) as u32,
            };
            for sweep in [None, Some(Sweep::Off)] {
                let mut scene = Scene::load(name).unwrap();
                scene.world.dt = 1.0 / hz;
                if let Some(sweep) = sweep {
                    scene.world.kinds.iter_mut().for_each(|k| k.sweep = sweep);
                }
                let audit = audit_game(device, &scene, 1, length).unwrap();
                let label = if sweep.is_some() {
                    "nothing"
                } else {
                    "as the scene says"
                };
                eprintln!("{}", table_row(name, &format!("1/{hz}"), label, &audit));
                let a = &audit.contacts;
                let at = format!("{name} at 1/{hz} s, swept {label}: {a:?}");
                let s = &a.swept;
                assert_eq!(
                    (s.missed, s.extra, s.wrong_partner, s.late),
                    (0, 0, 0, 0),
                    "{at}"
                );
                let u = &a.unswept;
                assert_eq!((u.extra, u.wrong_partner), (0, 0), "{at}");
                assert_eq!(u.missed, u.tunnelling, "{at}");
                assert!(a.slots_audited > a.slots_skipped, "{at}: mostly renumbered");
                // An enemy killed was a contact the audit found (a shot's or the ship's).
                assert!(
                    audit.kills == 0 || a.all.expected > 0,
                    "{at}: kills, no contact"
                );
                if sweep.is_some() {
                    assert_eq!(s.expected + s.undecidable, 0, "{at}: a pair still swept");
                }
            }
        }
    }
}

/// `arena` squeezed into a field of 32 by 32, its ship made to last: its bodies pile up,
/// each touching far more than the contact log's 16 a slot. The audit plays the game again
/// with room for them, and finds what an audit given that room from the start finds.
fn a_pile_denser_than_the_log_is_audited_whole(device: &Device) {
    let mut scene = Scene::load("arena").unwrap();
    scene.world.size = glam::Vec2::splat(32.0);
    let ship = scene.world.kind_index(&scene.game.ship.kind).unwrap();
    scene.world.kinds[ship].energy = 1_000_000;
    let length = AuditLength {
        warmup: 2,
        busy_within: 0,
        steps: 6,
    };
    // The log as a game makes it overflows in the first steps.
    let mut traced = scene.clone();
    traced.world.physics.trace_paths = true;
    let mut game = Game::with_options(device, &traced, 1, Options::default()).unwrap();
    game.step(None).unwrap();
    match game.pipeline().contact_log(0) {
        Err(Error::ContactLogFull {
            logged, per_slot, ..
        }) => assert!(
            logged > 0 && per_slot == 16,
            "{logged} logged, {per_slot} a slot"
        ),
        other => panic!("a log of 16 a slot held the pile: {other:?}"),
    }
    let audit = audit_game(device, &scene, 1, length).unwrap();
    let mut roomy = scene.clone();
    roomy.world.physics.log_room = 1 << 12;
    assert_eq!(audit, audit_game(device, &roomy, 1, length).unwrap());
    assert_eq!(audit.contacts.steps, 6);
    assert!(
        audit.contacts.all.expected > 1000,
        "a pile: {:?}",
        audit.contacts.all
    );
}

/// An audited game (its narrow phase's logged kernels) is the game it audits, bit for bit:
/// every built-in game scene, swept as it says and with nothing swept, its bodies stepping
/// in three launches and (teams of 8 lanes) in one, and `paper` as a persistent step.
fn an_audited_game_is_the_game_bit_for_bit(device: &Device) {
    let lanes = [Lanes::Auto, Lanes::Fixed(8)].map(|lanes| Options {
        lanes,
        ..Options::default()
    });
    let persistent = Options {
        persistent: Persistent::On,
        ..Options::default()
    };
    for name in GAME_SCENES {
        for sweep in [None, Some(Sweep::Off)] {
            let mut scene = Scene::load(name).unwrap();
            if let Some(sweep) = sweep {
                scene.world.kinds.iter_mut().for_each(|k| k.sweep = sweep);
            }
            let mut traced = scene.clone();
            traced.world.physics.trace_paths = true;
            let runs = match name {
                "paper" => &[lanes[0], lanes[1], persistent][..],
                _ => &lanes[..],
            };
            for &options in runs {
                let [plain, audited] =
                    [&scene, &traced].map(|s| common::game::hash_with(device, s, 1, 180, options));
                assert_eq!(audited, plain, "{name}, sweep {sweep:?}, {options:?}");
            }
        }
    }
}

on_both_backends!(
    an_audited_game_is_the_game_bit_for_bit,
    shots_swept_miss_no_enemy_and_unswept_ones_do,
    every_game_scene_swept_exact_at_three_steps,
    a_pile_denser_than_the_log_is_audited_whole,
);
