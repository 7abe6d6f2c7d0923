//! The game scene under each choice that applies to a game (and what each costs it, from an
//! audit of its contacts), and with one feature off at a time.

use serde::{Deserialize, Serialize};

use super::RunSizes;
use crate::benchmark::rounds::{Point, Rate, frontier, interleaved};
use crate::camera::Camera;
use crate::files::figure;
use crate::game::accuracy::{AuditLength, GameAudit, audit_game};
use crate::game::engine::footprint;
use crate::game::spec::Machine;
use crate::game::{Game, Options, Scene};
use crate::pipeline::Profile;
use crate::play::MAX_CATCH_UP;
use crate::sim::audit::{BODY_WALL, ENEMY_SHIP, SHOT_ENEMY};
use crate::sim::{Integrator, Physics, Shape, Sweep, WorldSpec};
use crate::{BackendKind, Device, Error};

/// One configuration of the game scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GameRow {
    /// The choice or the feature turned off.
    pub choice: String,
    /// Time step (s).
    pub dt: f64,
    /// Why the choice was not measured (it does not apply to the scene, or its game ended
    /// first), in words; `None` where it was, and the figures below hold.
    pub skipped: Option<String>,
    /// Steps per second, the step replayed as a graph: the median of the timed rounds.
    pub steps_per_s: f64,
    /// The slowest and the fastest round's steps per second.
    pub steps_per_s_range: (f64, f64),
    /// Simulated seconds per wall second (the median steps/s × dt).
    pub sim_seconds_per_s: f64,
    /// What the choice costs the game, from an audit of its contacts (the game table's
    /// rows; none for the feature table's).
    pub accuracy: Option<GameAccuracy>,
    /// Whether no other row of the game table misses fewer contacts and runs faster beyond
    /// the speeds' spreads (see [`crate::benchmark::rounds::frontier`]).
    pub pareto: bool,
    /// The rows that beat this one on the frontier by their median speeds alone, inside the
    /// spreads: the run cannot tell them apart.
    pub unseparated: Vec<String>,
    /// Time per step over profiled steps (µs).
    pub step_us: f64,
    /// Each stage's µs, `stage=µs` joined by spaces.
    pub stages: String,
    /// Enemies alive when measured.
    pub alive: u32,
    /// Frames per second over the timed rounds, each frame the steps due at the asked rate
    /// and the frame drawn as `play` draws it (`tune --fps`; `None` where not asked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames_per_s: Option<Rate>,
}

/// What [`game_rows`] measures of each choice besides its speed in steps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Measure {
    /// Its contacts, audited over a game of its own.
    pub audited: bool,
    /// Its frames, timed as `play` draws them.
    pub frames: Option<FrameTiming>,
}

/// Frames timed as `play` draws them, for `tune --fps`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTiming {
    /// Frames a second; each frame plays the steps due in 1/fps seconds of game time.
    pub fps: f64,
    /// The frame's width and height in pixels (`play`'s window).
    pub size: (u32, u32),
}

impl FrameTiming {
    /// Whether `play` keeps the game time of a scene of time step `dt` at this frame rate:
    /// a frame's share of game time is at most the [`MAX_CATCH_UP`] steps `play` plays in a
    /// frame (beyond them the game slows down); an error in words where it is not.
    pub fn keeps_game_time(&self, dt: f32) -> Result<(), String> {
        let steps = 1.0 / (self.fps * f64::from(dt));
        let lowest = 1.0 / (MAX_CATCH_UP as f64 * f64::from(dt));
        match steps <= MAX_CATCH_UP as f64 {
            true => Ok(()),
            false => Err(format!(
                "at {} frames/s a frame is {} steps of {} s, more than the {MAX_CATCH_UP} \
                 `play` plays in a frame (the game would slow down): aim at {} frames/s or \
                 more",
                figure(self.fps),
                figure(steps),
                figure(f64::from(dt)),
                figure(lowest)
            )),
        }
    }

    /// One frame of `game`, whose steps due not yet played (a fraction of one) are
    /// `banked`: those steps, then the kernel renderer's frame as `play` shows it, read
    /// back where the window uploads it (the CPU emulation), left in device memory where
    /// CUDA hands it to GL.
    fn frame(self, game: &mut Game, banked: &mut f64) -> Result<(), Error> {
        // At most `MAX_CATCH_UP` steps: only a rate that `keeps_game_time` is timed.
        *banked += 1.0 / (self.fps * f64::from(game.scene().world.dt));
        let due = banked.floor();
        *banked -= due;
        for _ in 0..due as u64 {
            game.submit(None)?;
        }
        while game.next_status()?.is_some() {}
        let (width, height) = self.size;
        game.render(width, height, &Camera::default(), (1.0 / self.fps) as f32)?;
        match game.pipeline().device().kind() {
            BackendKind::Cpu => game.pipeline().frame().map(drop),
            BackendKind::Cuda => game.pipeline().device().synchronize(),
        }
    }
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

/// Marks the game rows on the Pareto frontier of contacts missed against simulated
/// seconds per second, beyond the speeds' spreads (rows skipped, or whose audit found no
/// contact, are left off), and the rows each cannot be separated from.
pub(super) fn mark_game_pareto(rows: &mut [GameRow]) {
    let points: Vec<Option<Point>> = rows
        .iter()
        .map(|r| {
            let missed = r.accuracy.as_ref().and_then(|a| a.missed)?;
            let (low, high) = r.steps_per_s_range;
            let steps = Rate {
                median: r.steps_per_s,
                low,
                high,
            };
            r.skipped.is_none().then_some(Point {
                error: missed,
                speed: steps.scaled(r.dt),
            })
        })
        .collect();
    let names: Vec<String> = rows.iter().map(|r| r.choice.clone()).collect();
    for (row, (on, unseparated)) in rows.iter_mut().zip(frontier(&points)) {
        row.pareto = on;
        row.unseparated = unseparated.into_iter().map(|i| names[i].clone()).collect();
    }
}

/// The game's choices, each a changed copy of `scene`: the physics choices that apply to a
/// game, a coarser and a finer time step, and its swept contacts off (every kind's, the
/// ship's, the shots'; and at the coarser step) or on for every kind of known speed.
pub(crate) fn game_choices(scene: &Scene) -> Vec<(String, Scene)> {
    let changed = |label: Option<String>, f: &dyn Fn(&mut WorldSpec)| {
        let mut s = scene.clone();
        f(&mut s.world);
        (label.unwrap_or_else(|| s.world.physics.label()), s)
    };
    let physics = |f: &dyn Fn(&mut Physics)| changed(None, &|w| f(&mut w.physics));
    let coarse = |w: &mut WorldSpec| w.dt *= 2.0;
    // `dt 1/30`, or `dt 1.2 s` where the step is no whole fraction of a second.
    let dt_label = |factor: f32| {
        let dt = scene.world.dt * factor;
        let hz = 1.0 / f64::from(dt);
        match (hz - hz.round()).abs() < 1e-4 * hz {
            true => format!("dt 1/{hz:.0}"),
            false => format!("dt {} s", crate::files::number(dt)),
        }
    };
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

/// Most steps a game is played, past its warm-up, until its ship first fires (so that an
/// audit starting there sees shots meet enemies): a minute at 60 Hz.
const BUSY_WITHIN: u32 = 3600;

/// A choice's game, played past its warm-up; or why it cannot be measured.
fn warmed<'d>(
    device: &'d Device,
    scene: &Scene,
    seed: u32,
    sizes: &RunSizes,
) -> Result<(Game<'d>, u32), String> {
    scene
        .validate()
        .map_err(|e| format!("does not apply to this scene ({}: {})", e.field, e.problem))?;
    let mut game =
        Game::with_options(device, scene, seed, Options::default()).map_err(|e| e.to_string())?;
    let steps = |game: &mut Game| -> Result<(), crate::Error> {
        for _ in 0..sizes.game_warmup {
            game.submit(None)?;
        }
        while game.next_status()?.is_some() {}
        Ok(())
    };
    steps(&mut game).map_err(|e| e.to_string())?;
    if game.status().game_over != 0 {
        return Err(over_before(sizes.game_warmup));
    }
    let alive = game.snapshot().map_err(|e| e.to_string())?.live().count() as u32;
    Ok((game, alive))
}

/// Why a game that ended after `steps` could not be measured, and what to do.
fn over_before(steps: u32) -> String {
    format!(
        "its game was over after {steps} steps, before it was measured: the autopilot lost (a \
         ship with more energy, or a lower fps.min, lasts longer)"
    )
}

/// The rows of `choices` (`(label, scene)`), the autopilot playing each from `seed`: each
/// game warmed up, then timed in interleaved rounds with the others (as many at a time as
/// fit in half the device's free memory), in steps and, if `measure` asks, in frames;
/// profiled, and if `measure` asks its contacts audited over a game of its own, the same bit
/// for bit. A choice that cannot be measured is a row that says why. `tick` is called as
/// each choice is done.
pub(crate) fn game_rows(
    device: &Device,
    choices: &[(String, Scene)],
    seed: u32,
    sizes: &RunSizes,
    measure: Measure,
    mut tick: impl FnMut(&str),
) -> anyhow::Result<Vec<GameRow>> {
    let free = device.memory()?.map_or(u64::MAX, |(free, _)| free / 2);
    let mut rows = Vec::with_capacity(choices.len());
    let mut start = 0;
    while start < choices.len() {
        // The next group: as many choices as fit together, one at least.
        let mut end = start + 1;
        let mut bytes = footprint(&choices[start].1).1;
        while end < choices.len() {
            bytes = bytes.saturating_add(footprint(&choices[end].1).1);
            if bytes > free {
                break;
            }
            end += 1;
        }
        rows.extend(group_rows(
            device,
            &choices[start..end],
            seed,
            sizes,
            measure,
            &mut tick,
        )?);
        start = end;
    }
    Ok(rows)
}

/// [`game_rows`] of one group, timed together.
fn group_rows(
    device: &Device,
    choices: &[(String, Scene)],
    seed: u32,
    sizes: &RunSizes,
    measure: Measure,
    tick: &mut impl FnMut(&str),
) -> anyhow::Result<Vec<GameRow>> {
    let mut warm: Vec<Result<(Game, u32), String>> = choices
        .iter()
        .map(|(_, scene)| {
            (measure.frames)
                .map_or(Ok(()), |timing| timing.keeps_game_time(scene.world.dt))
                .and_then(|()| warmed(device, scene, seed, sizes))
        })
        .collect();
    let mut games: Vec<&mut Game> = warm.iter_mut().flatten().map(|(g, _)| g).collect();
    // The autopilot flies.
    let rates = interleaved(
        &mut games,
        sizes.speed,
        |game| {
            const BATCH: u64 = 8;
            for _ in 0..BATCH {
                game.submit(None)?;
            }
            while game.next_status()?.is_some() {}
            game.pipeline().device().synchronize()?;
            Ok(BATCH)
        },
        || {},
    )?;
    let mut frame_rates = match measure.frames {
        Some(timing) => {
            let mut framed: Vec<(&mut Game, f64)> = games.into_iter().map(|g| (g, 0.0)).collect();
            interleaved(
                &mut framed,
                sizes.speed,
                |(game, banked)| {
                    timing.frame(game, banked)?;
                    Ok(1)
                },
                || {},
            )?
        }
        None => Vec::new(),
    }
    .into_iter();
    let mut rates = rates.into_iter();
    let mut rows = Vec::with_capacity(choices.len());
    for ((choice, scene), warm) in choices.iter().zip(warm) {
        let dt = f64::from(scene.world.dt);
        let row = match warm {
            Ok((mut game, alive)) => {
                let rate = rates.next().unwrap_or_default();
                let frames_per_s = frame_rates.next();
                measured(device, &mut game, (scene, seed), sizes, measure.audited)?.map(
                    |(stages, step_us, accuracy)| GameRow {
                        choice: choice.clone(),
                        dt,
                        skipped: None,
                        steps_per_s: rate.median,
                        steps_per_s_range: (rate.low, rate.high),
                        sim_seconds_per_s: rate.median * dt,
                        accuracy,
                        pareto: false,
                        unseparated: Vec::new(),
                        step_us,
                        stages,
                        alive,
                        frames_per_s,
                    },
                )
            }
            Err(why) => Err(why),
        };
        rows.push(row.unwrap_or_else(|why| GameRow::skipped(choice, dt, why)));
        tick(choice);
    }
    Ok(rows)
}

/// A timed game's stage times (over profiled steps), mean step (µs) and its contacts'
/// audit, if asked for.
type Measured = (String, f64, Option<GameAccuracy>);

/// A timed game's [`Measured`], its contacts audited if `audited`; `Err` with the reason
/// where its game ended meanwhile.
fn measured(
    device: &Device,
    game: &mut Game,
    (scene, seed): (&Scene, u32),
    sizes: &RunSizes,
    audited: bool,
) -> anyhow::Result<Result<Measured, String>> {
    let mut profile = Profile::default();
    for _ in 0..sizes.profiled_steps {
        game.submit_profiled(None, &mut profile)?;
    }
    if game.status().game_over != 0 {
        return Ok(Err(
            "its game ended while it was timed (a frozen world is cheap): the autopilot lost"
                .to_owned(),
        ));
    }
    let accuracy = match audited {
        true => {
            let length = AuditLength {
                warmup: sizes.game_warmup,
                busy_within: BUSY_WITHIN,
                steps: sizes.audit_steps,
            };
            Some(GameAccuracy::of(&audit_game(device, scene, seed, length)?))
        }
        false => None,
    };
    let stages = profile.stage_line(1e-6, 1);
    Ok(Ok((stages, profile.step_seconds() * 1e6, accuracy)))
}

impl GameRow {
    /// The row of a choice that could not be measured, and why.
    fn skipped(choice: &str, dt: f64, why: String) -> GameRow {
        GameRow {
            choice: choice.to_owned(),
            dt,
            skipped: Some(why),
            steps_per_s: 0.0,
            steps_per_s_range: (0.0, 0.0),
            sim_seconds_per_s: 0.0,
            accuracy: None,
            pareto: false,
            unseparated: Vec::new(),
            step_us: 0.0,
            stages: String::new(),
            alive: 0,
            frames_per_s: None,
        }
    }
}
