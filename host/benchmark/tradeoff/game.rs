//! The game scene under each choice that applies to a game (and what each costs it, from an
//! audit of its contacts), and with one feature off at a time.

use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::RunSizes;
use crate::Device;
use crate::game::accuracy::{AuditLength, GameAudit, audit_game};
use crate::game::spec::Machine;
use crate::game::{Game, Options, Scene};
use crate::pipeline::Profile;
use crate::sim::audit::{BODY_WALL, ENEMY_SHIP, SHOT_ENEMY};
use crate::sim::{Integrator, Physics, Shape, Sweep, WorldSpec};

/// One configuration of the game scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GameRow {
    /// The choice or the feature turned off.
    pub choice: String,
    /// Time step (s).
    pub dt: f64,
    /// Steps per second, the step replayed as a graph.
    pub steps_per_s: f64,
    /// Simulated seconds per wall second (steps/s × dt).
    pub sim_seconds_per_s: f64,
    /// What the choice costs the game, from an audit of its contacts (the game table's
    /// rows; none for the feature table's).
    pub accuracy: Option<GameAccuracy>,
    /// Whether no other row of the game table misses fewer contacts and runs faster.
    pub pareto: bool,
    /// Time per step over profiled steps (µs).
    pub step_us: f64,
    /// Each stage's µs, `stage=µs` joined by spaces.
    pub stages: String,
    /// Enemies alive when measured.
    pub alive: u32,
}

/// The game's accuracy under one choice: its contacts over the audited steps against an
/// exact continuous-time check of the bodies' paths (see [`crate::game::accuracy`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GameAccuracy {
    /// Steps audited.
    pub steps: u64,
    /// Contacts the check found, each from both bodies' sides.
    pub expected: u64,
    /// Of those, how many began and ended between two step ends.
    pub tunnelling: u64,
    /// Contacts missed per thousand found (`None`: none found).
    pub missed: Option<f64>,
    /// Contacts counted with a partner the check finds no contact with, per thousand found.
    pub extra: Option<f64>,
    /// Contacts counted with another body than the one met, per thousand found.
    pub wrong_partner: Option<f64>,
    /// Swept contacts counted at a moment off by more than the tolerance
    /// ([`crate::sim::audit::TIME_TOLERANCE`] of the motion), per thousand found.
    pub late: Option<f64>,
    /// Pairs f32 cannot decide (a contact or not within the margin's sizes), left out of
    /// the others, and expected swept contacts whose moment it cannot decide.
    pub undecidable: u64,
    /// Of the undecidable, those whose moment alone is undecided.
    pub moment_undecidable: u64,
    /// Shots' contacts with enemies missed per thousand.
    pub shot_enemy: Option<f64>,
    /// The ship's contacts with enemies missed per thousand.
    pub enemy_ship: Option<f64>,
    /// Movable bodies' contacts with immovable ones missed per thousand.
    pub body_wall: Option<f64>,
    /// Mean penetration of the contacts overlapping at a step's end (units).
    pub depth_mean: Option<f64>,
    /// The deepest (units).
    pub depth_max: f64,
    /// Body-steps over their kind's speed limit or birth energy.
    pub limit_violations: u64,
    /// Enemies killed per shot fired over the audited steps (`None`: no shot fired).
    pub kills_per_shot: Option<f64>,
}

impl GameAccuracy {
    /// The summary of a game's audit.
    fn of(audit: &GameAudit) -> Self {
        let a = &audit.contacts;
        GameAccuracy {
            steps: a.steps,
            expected: a.all.expected,
            tunnelling: a.all.tunnelling,
            missed: a.total_missed_per_thousand(),
            extra: a.all.per_thousand(a.all.extra),
            wrong_partner: a.all.per_thousand(a.all.wrong_partner),
            late: a.all.per_thousand(a.all.late),
            undecidable: a.all.undecidable + a.all.moment_undecidable,
            moment_undecidable: a.all.moment_undecidable,
            shot_enemy: a.missed_per_thousand(SHOT_ENEMY),
            enemy_ship: a.missed_per_thousand(ENEMY_SHIP),
            body_wall: a.missed_per_thousand(BODY_WALL),
            depth_mean: a.depth.mean(),
            depth_max: a.depth.max,
            limit_violations: a.speed_violations + a.energy_violations,
            kills_per_shot: audit.kills_per_shot(),
        }
    }
}

/// Marks the game rows no other audited row beats on both contacts missed and simulated
/// seconds per second (rows whose audit found no contact are left off).
pub(super) fn mark_game_pareto(rows: &mut [GameRow]) {
    let point = |r: &GameRow| {
        let missed = r.accuracy.as_ref().and_then(|a| a.missed)?;
        Some((missed, r.sim_seconds_per_s))
    };
    let points: Vec<Option<(f64, f64)>> = rows.iter().map(point).collect();
    for (row, p) in rows.iter_mut().zip(&points) {
        row.pareto = p.is_some_and(|(m, s)| {
            !points
                .iter()
                .flatten()
                .any(|&(m2, s2)| m2 <= m && s2 >= s && (m2 < m || s2 > s))
        });
    }
}

/// The game's choices, each a changed copy of `scene`: the physics choices that apply to a
/// game, a coarser and a finer time step, and its swept contacts off (every kind's, the
/// ship's, the shots'; and at the coarser step) or on for every kind of known speed.
pub(super) fn game_choices(scene: &Scene) -> Vec<(String, Scene)> {
    let changed = |label: Option<String>, f: &dyn Fn(&mut WorldSpec)| {
        let mut s = scene.clone();
        f(&mut s.world);
        (label.unwrap_or_else(|| s.world.physics.label()), s)
    };
    let physics = |f: &dyn Fn(&mut Physics)| changed(None, &|w| f(&mut w.physics));
    let coarse = |w: &mut WorldSpec| w.dt *= 2.0;
    let dt_label = |factor: f32| format!("dt 1/{:.0}", 1.0 / (scene.world.dt * factor));
    let unswept = |w: &mut WorldSpec| w.kinds.iter_mut().for_each(|k| k.sweep = Sweep::Off);
    let mut out = vec![
        ("default".to_owned(), scene.clone()),
        physics(&|p| p.integrator = Integrator::ExplicitEuler),
        physics(&|p| p.integrator = Integrator::VelocityVerlet),
        changed(Some(dt_label(2.0)), &coarse),
        changed(Some(dt_label(0.5)), &|w| w.dt *= 0.5),
        physics(&|p| p.substeps = 2),
        physics(&|p| p.substeps = 4),
        physics(&|p| p.averaged = true),
        physics(&|p| p.cell_scale = 2.0),
        physics(&|p| p.neighbour_cap = 32),
        physics(&|p| p.neighbour_cap = 8),
        physics(&|p| p.vision_scale = 0.5),
        physics(&|p| p.sight_budget = 16),
        physics(&|p| p.sight_budget = 0),
        physics(&|p| p.contact_budget = 24),
    ];
    if scene.world.has_swept_pairs() {
        out.push(changed(Some("nothing swept".into()), &unswept));
        out.push(changed(
            Some(format!("{}, nothing swept", dt_label(2.0))),
            &|w| {
                coarse(w);
                unswept(w);
            },
        ));
        let ship = &scene.game.ship;
        for name in [&ship.kind, &ship.shot] {
            let Some(k) = scene.world.kind_index(name) else {
                continue;
            };
            out.push(changed(Some(format!("{name} not swept")), &|w| {
                w.kinds[k].sweep = Sweep::Off;
            }));
        }
    }
    out.push(changed(Some("every kind swept".into()), &|w| {
        for kind in w.kinds.iter_mut().filter(|k| k.speed_bound().is_finite()) {
            kind.sweep = Sweep::On;
        }
    }));
    out
}

/// The scene with one feature off, for each feature the scene has: `(name, scene)`.
pub(super) fn feature_choices(scene: &Scene) -> Vec<(String, Scene)> {
    let mut out = vec![("every feature".to_owned(), scene.clone())];
    let tricky: Vec<String> = scene
        .world
        .kinds
        .iter()
        .zip(&scene.game.behaviours)
        .filter(|(_, b)| b.is_some_and(|b| b.machine == Machine::Tricky))
        .map(|(k, _)| k.name.clone())
        .collect();
    if !tricky.is_empty() {
        let mut s = scene.clone();
        s.game.spawn.waves.retain(|w| !tricky.contains(&w.kind));
        out.push(("no tricky enemies".into(), s));
    }
    if scene.world.has_rects() {
        let mut s = scene.clone();
        for kind in &mut s.world.kinds {
            kind.shape = Shape::Circle {
                radius: kind.shape.reach(),
            };
        }
        out.push(("no rectangles (circles of the same reach)".into(), s));
    }
    let mut s = scene.clone();
    // One shot in a thousand seconds: none in the run. A ship that cannot shoot its way
    // out would be worn down before it is measured: it gets all the energy it can hold, so
    // that the enemies' hits barely move its meter.
    s.game.ship.fire_rate = 1.0e-3;
    if let Some(ship) = scene.world.kind_index(&scene.game.ship.kind) {
        s.world.kinds[ship].energy = i32::MAX / 2;
    }
    out.push(("no shots (and a ship that does not wear down)".into(), s));
    let mut s = scene.clone();
    s.world.physics.vision_scale = 1.0e-3;
    out.push(("no vision (radius ×0.001)".into(), s));
    out
}

/// Steps per second, stage times and enemies alive of `scene`, the autopilot playing,
/// after `warmup` steps, and if `audited` its contacts' audit over as many steps again (a
/// game of its own, the same bit for bit); an error if the game is over before it is
/// measured.
pub(super) fn game_row(
    device: &Device,
    (choice, scene): (String, &Scene),
    seed: u32,
    sizes: &RunSizes,
    audited: bool,
) -> anyhow::Result<GameRow> {
    let mut game = Game::with_options(device, scene, seed, Options::default())?;
    // The autopilot flies.
    let input = None;
    for _ in 0..sizes.game_warmup {
        game.submit(input)?;
    }
    while game.next_status()?.is_some() {}
    if game.status().game_over != 0 {
        // A frozen world would measure nothing.
        anyhow::bail!("the game was over before it was measured");
    }
    let alive = game.snapshot()?.live().count() as u32;
    let time = Duration::from_secs_f64(sizes.speed_seconds);
    let steps_per_s = crate::benchmark::scale::rate(&mut game, time, |g| g.submit(input))?;
    let mut profile = Profile::default();
    for _ in 0..sizes.profiled_steps {
        game.submit_profiled(input, &mut profile)?;
    }
    if game.status().game_over != 0 {
        anyhow::bail!("the game ended while it was measured (a frozen world is cheap)");
    }
    let stages = profile.stage_line(1e-6, 1);
    let accuracy = match audited {
        true => {
            let length = AuditLength {
                warmup: sizes.game_warmup,
                steps: sizes.audit_steps,
            };
            Some(GameAccuracy::of(&audit_game(device, scene, seed, length)?))
        }
        false => None,
    };
    let dt = f64::from(scene.world.dt);
    Ok(GameRow {
        choice,
        dt,
        steps_per_s,
        sim_seconds_per_s: steps_per_s * dt,
        accuracy,
        pareto: false,
        step_us: profile.step_seconds() * 1e6,
        stages,
        alive,
    })
}
