//! The game's accuracy in game terms (`gpuwars::game::accuracy`): the contacts of `paper`
//! audited against an exact continuous-time check of the bodies' paths, with the scene's
//! swept contacts and with none, at the scene's step and at twice it. The audit is
//! independent of the kernels (f64, every pair), so the expected contacts are its own.

mod common;

use gpuwars::Device;
use gpuwars::game::Scene;
use gpuwars::game::accuracy::{AuditLength, audit_game};
use gpuwars::sim::Sweep;
use gpuwars::sim::audit::{Accuracy, SHOT_ENEMY};

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
    steps: 1200,
};

/// The audits of `paper` at its own step and at 1/30 s, swept as the scene says and with
/// nothing swept: `[(swept, unswept); 2]`.
fn audits(device: &Device) -> [(Accuracy, Accuracy); 2] {
    [None, Some(1.0 / 30.0)].map(|dt| {
        let audit = |sweep| audit_game(device, &paper(dt, sweep), 1, LENGTH).unwrap();
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

on_both_backends!(shots_swept_miss_no_enemy_and_unswept_ones_do);
