//! `gpuwars tradeoff`: how much accuracy each physics choice buys and what it costs, measured
//! side by side in one run.
//!
//! - **Physics** ([`PhysicsRow`]): a ring of balls orbiting a central attractor and
//!   bouncing off each other, under each choice (integrator, substeps, time step, contact
//!   relaxation, grid cell size, neighbour cap). Error: the position RMS after a fixed time
//!   against the [`reference`](mod@reference) (f64, every pair, 32 substeps per step, same start), and the
//!   contacts the grid's queries missed against a brute-force count. Speed: simulated
//!   seconds per wall second on a larger crowd of the same density.
//! - **Analytic** ([`analytic`]): constant force, head-on collision, circular orbit, per
//!   integrator and time step.
//! - **Game** ([`GameRow`]): a scene (`paper` by default) under the choices that apply to a
//!   game, steps per second and the stage times.
//! - **Features** ([`GameRow`] again): the same scene with a feature off (tricky enemies,
//!   rectangles, shots, vision), to show that a scene costs only what it uses.

pub mod analytic;
pub mod plots;
pub mod reference;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use glam::Vec2;
use serde::{Deserialize, Serialize};

use super::{Outputs, Provenance, write_csv, write_json};
use crate::files::write_atomically;
use crate::game::accuracy::{AuditLength, audit_game};
use crate::game::spec::Machine;
use crate::game::{Game, Options, Scene};
use crate::pipeline::{Pipeline, Profile, Simulation};
use crate::sim::audit::{Accuracy, BODY_WALL, ENEMY_SHIP, SHOT_ENEMY};
use crate::sim::{Boundary, Field, Integrator, KindSpec, Physics, Shape, Sweep, WorldSpec};
use crate::terminal::progress;
use crate::{Device, Error};
use analytic::AnalyticRow;
use reference::Reference;

/// The crowd's time step (s).
const DT: f32 = 1.0 / 60.0;
/// The reference's substeps per step of [`DT`].
const REFERENCE_SUBSTEPS: u32 = 32;
/// The balls' radius.
const RADIUS: f32 = 4.0;
/// Fraction of the crowd's field that balls cover.
const COVER: f64 = 0.04;
/// Speed of a circular orbit at a quarter of the field's side, and the balls' initial
/// speed deviation (units/s).
const ORBIT_SPEED: f32 = 60.0;

/// How `gpuwars tradeoff` runs.
#[derive(Clone, Debug)]
pub struct TradeoffOptions {
    /// The game scene of the game and feature tables (built-in name or file).
    pub scene: Scene,
    /// Small sizes and short runs (CI).
    pub quick: bool,
    /// Seed of every world.
    pub seed: u32,
    /// Where the files go.
    pub out: PathBuf,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// The sizes of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sizes {
    /// Balls of the crowd whose error is measured.
    pub error_bodies: u32,
    /// Simulated seconds after which the error is measured.
    pub error_seconds: f64,
    /// Balls of the crowd whose speed is measured.
    pub speed_bodies: u32,
    /// Wall seconds of each speed measurement.
    pub speed_seconds: f64,
    /// Steps the game plays before it is measured.
    pub game_warmup: u32,
    /// Steps of the game profiled stage by stage (their mean is reported).
    pub profiled_steps: u32,
    /// Steps of the game whose contacts are audited, after the warm-up.
    pub audit_steps: u32,
    /// The analytic cases' time steps.
    pub analytic_dts: [f32; 2],
    /// Bodies of the crowded-cell worlds.
    pub crowded: [u32; 2],
}

impl Sizes {
    /// The sizes of a full run on `device`, or of a quick one.
    fn new(device: &Device, quick: bool) -> Self {
        let gpu = device.kind() == crate::BackendKind::Cuda;
        match (quick, gpu) {
            (true, _) => Sizes {
                error_bodies: 96,
                error_seconds: 0.25,
                speed_bodies: 1024,
                speed_seconds: 0.05,
                game_warmup: 20,
                profiled_steps: 3,
                audit_steps: 40,
                analytic_dts: [1.0 / 30.0, 1.0 / 60.0],
                crowded: [256, 1024],
            },
            (false, false) => Sizes {
                error_bodies: 768,
                error_seconds: 0.25,
                speed_bodies: 16_384,
                // The emulator's figures vary more from second to second.
                speed_seconds: 3.0,
                game_warmup: 600,
                profiled_steps: 30,
                audit_steps: 1200,
                analytic_dts: [1.0 / 60.0, 1.0 / 240.0],
                crowded: [4096, 32_768],
            },
            (false, true) => Sizes {
                error_bodies: 768,
                error_seconds: 0.25,
                speed_bodies: 262_144,
                speed_seconds: 1.0,
                game_warmup: 600,
                profiled_steps: 30,
                audit_steps: 1200,
                analytic_dts: [1.0 / 60.0, 1.0 / 240.0],
                crowded: [4096, 32_768],
            },
        }
    }
}

/// One choice of the crowd table: its physics and its time step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhysicsRow {
    /// What differs from the default.
    pub choice: String,
    /// The integrator.
    pub integrator: Integrator,
    /// Substeps per step.
    pub substeps: u32,
    /// Time step (s).
    pub dt: f64,
    /// Fraction of the push applied.
    pub relaxation: f32,
    /// Pushes averaged over contacts.
    pub averaged: bool,
    /// Grid cell scale.
    pub cell_scale: f32,
    /// Entries examined per query (0: all).
    pub neighbour_cap: u32,
    /// Position RMS against the reference (world units).
    pub position_rms: f64,
    /// Fraction of the brute-force contacts the grid's queries did not count.
    pub contacts_missed: f64,
    /// Steps per wall second on the larger crowd.
    pub steps_per_s: f64,
    /// Simulated seconds per wall second (steps/s × dt).
    pub sim_seconds_per_s: f64,
    /// Whether no other choice is both faster and more accurate.
    pub pareto: bool,
}

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
}

impl GameAccuracy {
    /// The summary of an audit.
    fn of(a: &Accuracy) -> Self {
        GameAccuracy {
            steps: a.steps,
            expected: a.all.expected,
            tunnelling: a.all.tunnelling,
            missed: a.total_missed_per_thousand(),
            shot_enemy: a.missed_per_thousand(SHOT_ENEMY),
            enemy_ship: a.missed_per_thousand(ENEMY_SHIP),
            body_wall: a.missed_per_thousand(BODY_WALL),
            depth_mean: a.depth.mean(),
            depth_max: a.depth.max,
            limit_violations: a.speed_violations + a.energy_violations,
        }
    }
}

/// A step of a world whose bodies all start on one spot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrowdedRow {
    /// Bodies, all in one cell.
    pub bodies: u32,
    /// Entries examined per query (0: all).
    pub neighbour_cap: u32,
    /// The first step's time, the median of three worlds (ms).
    pub step_ms: f64,
    /// Its stages' ms, `stage=ms` joined by spaces.
    pub stages: String,
}

/// The summary of a run, written as JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TradeoffSummary {
    /// Always "tradeoff".
    pub benchmark: String,
    /// Where and when.
    pub machine: Provenance,
    /// Whether it was a quick run.
    pub quick: bool,
    /// The sizes it ran.
    pub sizes: Sizes,
    /// The crowd table.
    pub physics: Vec<PhysicsRow>,
    /// The analytic cases.
    pub analytic: Vec<AnalyticRow>,
    /// The game scene's name.
    pub scene: String,
    /// The game table.
    pub game: Vec<GameRow>,
    /// The feature table.
    pub features: Vec<GameRow>,
    /// Every body in one cell, with and without a cap.
    pub crowded: Vec<CrowdedRow>,
}

/// The crowd's choices: `(dt, physics)`, the default first.
fn crowd_choices() -> Vec<(f32, Physics)> {
    let d = Physics::default();
    let with = |f: &dyn Fn(&mut Physics)| {
        let mut p = d;
        f(&mut p);
        (DT, p)
    };
    let mut choices = vec![
        (DT, d),
        with(&|p| p.integrator = Integrator::ExplicitEuler),
        with(&|p| p.integrator = Integrator::VelocityVerlet),
        (DT * 2.0, d),
        (DT / 2.0, d),
    ];
    for substeps in [2, 4, 8] {
        choices.push(with(&|p| p.substeps = substeps));
    }
    choices.push(with(&|p| p.relaxation = 0.5));
    choices.push(with(&|p| p.averaged = true));
    choices.push(with(&|p| {
        p.averaged = true;
        p.relaxation = 0.5;
    }));
    for scale in [2.0, 4.0] {
        choices.push(with(&|p| p.cell_scale = scale));
    }
    for cap in [4, 8, 16, 32] {
        choices.push(with(&|p| p.neighbour_cap = cap));
    }
    choices
}

/// The crowd of `bodies` balls: a clamped square field whose area is `COVER` balls, a
/// central attractor whose circular orbit at a quarter of the side has speed
/// `ORBIT_SPEED`.
pub fn crowd(bodies: u32, dt: f32, physics: Physics) -> WorldSpec {
    let area = f64::from(bodies) * std::f64::consts::PI * f64::from(RADIUS).powi(2) / COVER;
    let side = area.sqrt() as f32;
    WorldSpec {
        size: Vec2::splat(side),
        dt,
        boundary: Boundary::Clamp,
        vision: 0.0,
        kinds: vec![KindSpec {
            name: "ball".into(),
            shape: Shape::Circle { radius: RADIUS },
            mass: 1.0,
            capacity: bodies,
            energy: 1,
            damage: 0,
            restitution: 0.5,
            max_speed: f32::INFINITY,
            collides_with: vec!["ball".into()],
            lifetime: f32::INFINITY,
            controlled: false,
            sweep: Sweep::Off,
            top_speed: f32::INFINITY,
        }],
        physics,
        field: Field {
            centre: Vec2::splat(side / 2.0),
            strength: ORBIT_SPEED * ORBIT_SPEED * side / 4.0,
            ..Field::default()
        },
    }
}

/// A crowd of `spec` set out by seed `seed`: a ring around the attractor from 0.2 to 0.45
/// of the side from its centre (none near the centre, where the field is singular), each
/// ball on its circular orbit give or take a tenth of [`ORBIT_SPEED`] per axis. Neighbouring
/// orbits shear past each other, so the balls collide.
fn scattered<'d>(device: &'d Device, spec: &WorldSpec, seed: u32) -> Result<Simulation<'d>, Error> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(u64::from(seed));
    let (centre, gm, side) = (spec.field.centre, spec.field.strength, spec.size.x);
    let balls: Vec<_> = (0..spec.kinds[0].capacity)
        .map(|slot| {
            let r = side * rng.random_range(0.2..0.45);
            let (sin, cos) = rng.random_range(0.0..std::f32::consts::TAU).sin_cos();
            let noise = Vec2::new(rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1));
            let vel = Vec2::new(-sin, cos) * (gm / r).sqrt() + noise * ORBIT_SPEED;
            (slot, centre + Vec2::new(cos, sin) * r, vel)
        })
        .collect();
    let mut sim = Simulation::new(device, spec, seed)?;
    sim.place(&balls)?;
    Ok(sim)
}

/// Position RMS against `truth` (same bodies, by slot) and the fraction of brute-force
/// contacts missed, for the crowd of `spec` run for `seconds`.
fn crowd_error(
    device: &Device,
    spec: &WorldSpec,
    seed: u32,
    seconds: f64,
    truth: &Reference,
) -> anyhow::Result<(f64, f64)> {
    // The error follows each body by its slot: bodies must keep theirs.
    let mut spec = spec.clone();
    spec.physics.renumber_every = Some(0);
    let mut sim = scattered(device, &spec, seed)?;
    let steps = (seconds / f64::from(spec.dt)).round() as u32;
    let (mut missed, mut contacts) = (0u64, 0u64);
    let mut before = sim.snapshot()?;
    for _ in 0..steps {
        let mut brute = vec![0u32; before.slots()];
        let world = Reference::new(&spec, &before)?;
        for (i, j, _) in world.overlapping() {
            brute[world.slots[i]] += 1;
            brute[world.slots[j]] += 1;
        }
        sim.step()?;
        let after = sim.snapshot()?;
        for slot in before.live() {
            contacts += u64::from(brute[slot]);
            missed += u64::from(brute[slot].saturating_sub(after.contacts[slot]));
        }
        // This step's end is the next one's start.
        before = after;
    }
    let end = before;
    let sum: f64 = truth
        .slots
        .iter()
        .zip(&truth.pos)
        .map(|(&slot, &p)| (end.bodies.pos[slot].as_dvec2() - p).length_squared())
        .sum();
    let rms = (sum / truth.slots.len().max(1) as f64).sqrt();
    Ok((rms, missed as f64 / contacts.max(1) as f64))
}

/// Steps per second of the crowd of `spec`, queued without waiting, for `time`.
fn crowd_speed(
    device: &Device,
    spec: &WorldSpec,
    seed: u32,
    time: Duration,
) -> anyhow::Result<f64> {
    let mut sim = scattered(device, spec, seed)?;
    sim.step()?;
    let start = Instant::now();
    let mut steps = 0u64;
    while steps < 3 || start.elapsed() < time {
        for _ in 0..8 {
            Pipeline::step(&mut sim)?;
        }
        steps += 8;
        device.synchronize()?;
    }
    Ok(steps as f64 / start.elapsed().as_secs_f64())
}

/// The cap of the crowded-cell rows that have one.
const CROWDED_CAP: u32 = 32;

/// The first step of `bodies` balls on one spot, with `cap`: the median of three worlds.
fn crowded(device: &Device, bodies: u32, cap: u32) -> anyhow::Result<CrowdedRow> {
    let mut spec = crowd(bodies, DT, Physics::default());
    spec.physics.neighbour_cap = cap;
    spec.field = Field::default();
    let spot = spec.size / 2.0;
    let mut runs = Vec::new();
    for _ in 0..3 {
        let mut sim = Simulation::new(device, &spec, 1)?;
        let all: Vec<_> = (0..bodies).map(|s| (s, spot, Vec2::ZERO)).collect();
        sim.place(&all)?;
        let mut profile = Profile::default();
        sim.step_profiled(&mut profile)?;
        runs.push(profile);
    }
    runs.sort_by(|a, b| a.step_seconds().total_cmp(&b.step_seconds()));
    let median = &runs[1];
    let stages = median.stage_line(1e-3, 2);
    Ok(CrowdedRow {
        bodies,
        neighbour_cap: cap,
        step_ms: median.step_seconds() * 1e3,
        stages,
    })
}

/// Marks the rows no other row beats on both error and speed.
fn mark_pareto(rows: &mut [PhysicsRow]) {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.position_rms, r.sim_seconds_per_s))
        .collect();
    for (i, row) in rows.iter_mut().enumerate() {
        let (e, s) = points[i];
        row.pareto = !points
            .iter()
            .any(|&(e2, s2)| e2 <= e && s2 >= s && (e2 < e || s2 > s));
    }
}

/// Marks the game rows no other audited row beats on both contacts missed and simulated
/// seconds per second (rows whose audit found no contact are left off).
fn mark_game_pareto(rows: &mut [GameRow]) {
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
fn game_choices(scene: &Scene) -> Vec<(String, Scene)> {
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
fn feature_choices(scene: &Scene) -> Vec<(String, Scene)> {
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
fn game_row(
    device: &Device,
    (choice, scene): (String, &Scene),
    seed: u32,
    sizes: &Sizes,
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
    let steps_per_s = super::scale::rate(&mut game, time, |g| g.submit(input))?;
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

/// Runs the whole matrix and writes `bench-tradeoff.{csv,md,png,json}`.
pub fn run(device: &Device, options: &TradeoffOptions) -> anyhow::Result<TradeoffSummary> {
    let outputs = Outputs::in_dir(&options.out, "tradeoff")?;
    let machine = Provenance::now(device);
    let sizes = Sizes::new(device, options.quick);
    let choices = crowd_choices();
    let games = game_choices(&options.scene);
    let features = feature_choices(&options.scene);
    let bar = progress(
        (choices.len() + games.len() + features.len() + 1) as u64,
        options.progress,
        "tradeoff",
    );
    let seed = options.seed;

    // The truth: the default crowd's start, in f64 with many substeps.
    let base = crowd(sizes.error_bodies, DT, Physics::default());
    let start = scattered(device, &base, seed)?.snapshot()?;
    let mut truth = Reference::new(&base, &start)?;
    let truth_steps = (sizes.error_seconds / f64::from(DT)).round() as u32;
    for _ in 0..truth_steps {
        truth.advance(f64::from(DT), REFERENCE_SUBSTEPS);
    }

    let mut physics = Vec::new();
    for (dt, p) in choices {
        let label = match dt {
            dt if dt == DT => p.label(),
            dt => format!("dt 1/{:.0}", 1.0 / dt),
        };
        bar.set_message(label.clone());
        let (position_rms, contacts_missed) = crowd_error(
            device,
            &crowd(sizes.error_bodies, dt, p),
            seed,
            sizes.error_seconds,
            &truth,
        )
        .with_context(|| format!("the crowd's error under {label}"))?;
        let steps_per_s = crowd_speed(
            device,
            &crowd(sizes.speed_bodies, dt, p),
            seed,
            Duration::from_secs_f64(sizes.speed_seconds),
        )
        .with_context(|| format!("the crowd's speed under {label}"))?;
        physics.push(PhysicsRow {
            choice: label,
            integrator: p.integrator,
            substeps: p.substeps,
            dt: f64::from(dt),
            relaxation: p.relaxation,
            averaged: p.averaged,
            cell_scale: p.cell_scale,
            neighbour_cap: p.neighbour_cap,
            position_rms,
            contacts_missed,
            steps_per_s,
            sim_seconds_per_s: steps_per_s * f64::from(dt),
            pareto: false,
        });
        bar.inc(1);
    }
    mark_pareto(&mut physics);

    bar.set_message("analytic cases");
    let analytic = analytic::run(device, &sizes.analytic_dts)?;
    bar.inc(1);

    let mut game = Vec::new();
    for (label, scene) in games {
        bar.set_message(format!("{}: {label}", options.scene.name));
        game.push(
            game_row(device, (label.clone(), &scene), seed, &sizes, true)
                .with_context(|| format!("{} under {label}", options.scene.name))?,
        );
        bar.inc(1);
    }
    mark_game_pareto(&mut game);
    let mut feature_rows = Vec::new();
    for (name, scene) in features {
        bar.set_message(format!("{}: {name}", options.scene.name));
        feature_rows.push(
            game_row(device, (name.clone(), &scene), seed, &sizes, false)
                .with_context(|| format!("{} with {name}", options.scene.name))?,
        );
        bar.inc(1);
    }
    let mut crowded_rows = Vec::new();
    for bodies in sizes.crowded {
        for cap in [0, CROWDED_CAP] {
            bar.set_message(format!("{bodies} bodies in one cell, cap {cap}"));
            crowded_rows.push(crowded(device, bodies, cap)?);
        }
    }
    bar.finish_and_clear();

    let summary = TradeoffSummary {
        benchmark: "tradeoff".into(),
        machine,
        quick: options.quick,
        sizes,
        physics,
        analytic,
        scene: options.scene.name.clone(),
        game,
        features: feature_rows,
        crowded: crowded_rows,
    };
    write_csv(&outputs.csv, &summary.physics)?;
    write_json(&outputs.json, &summary)?;
    write_atomically(&outputs.markdown(), summary.to_markdown().as_bytes())?;
    plots::pareto(&outputs.png, &summary)
        .with_context(|| format!("plotting {}", outputs.png.display()))?;
    let game_png = outputs.game_png();
    plots::game_pareto(&game_png, &summary)
        .with_context(|| format!("plotting {}", game_png.display()))?;
    Ok(summary)
}

impl TradeoffSummary {
    /// Every table in Markdown.
    pub fn to_markdown(&self) -> String {
        let m = &self.machine;
        let s = &self.sizes;
        let mut out = format!(
            "Machine: {} ({}), commit {}, {}{}.\n\n",
            m.device,
            m.backend,
            m.commit,
            m.date,
            if self.quick { ", quick run" } else { "" }
        );
        out += &format!(
            "### Physics: a ring of balls around an attractor\n\nError on {} balls after {} s against \
             f64 with every pair tested and {REFERENCE_SUBSTEPS} substeps per step; speed on \
             {} balls. ✓: on the Pareto frontier.\n\n",
            s.error_bodies, s.error_seconds, s.speed_bodies
        );
        out += "| choice | position RMS | contacts missed | steps/s | simulated s/s | frontier |\n";
        out += "|---|---:|---:|---:|---:|:---:|\n";
        for r in &self.physics {
            out += &format!(
                "| {} | {:.3} | {:.2}% | {:.0} | {:.2} | {} |\n",
                r.choice,
                r.position_rms,
                100.0 * r.contacts_missed,
                r.steps_per_s,
                r.sim_seconds_per_s,
                if r.pareto { "✓" } else { "" }
            );
        }
        out += "\n### Analytic cases\n\n| case | measure | integrator | dt | error |\n";
        out += "|---|---|---|---:|---:|\n";
        for r in &self.analytic {
            out += &format!(
                "| {} | {} | {} | {:.5} | {:.3e} |\n",
                r.case, r.measure, r.integrator, r.dt, r.error
            );
        }
        out += &format!(
            "\n### Game: `{}` under each choice\n\nAfter {} steps of play: steps per second, \
             then the contacts of {} steps audited against an exact continuous-time check of \
             the bodies' paths (f64, every pair): contacts found (each from both sides), how \
             many passed between two step ends, and missed per thousand, in all and by class; \
             penetration at a step's end, mean and deepest; body-steps over a limit. ✓: on \
             the Pareto frontier of missed against simulated seconds per second. –: no such \
             contact in the audit.\n\n| choice | steps/s | simulated s/s | contacts | \
             between ends | missed ‰ | shot→enemy ‰ | enemy→ship ‰ | body→wall ‰ | depth \
             mean / max | over a limit | frontier |\n|---|---:|---:|---:|---:|---:|---:|---:|\
             ---:|---:|---:|:---:|\n",
            self.scene, s.game_warmup, s.audit_steps
        );
        let per_thousand = |v: Option<f64>| v.map_or("–".to_owned(), |v| format!("{v:.1}"));
        for r in &self.game {
            let Some(a) = &r.accuracy else { continue };
            out += &format!(
                "| {} | {:.0} | {:.2} | {} | {} | {} | {} | {} | {} | {} / {:.2} | {} | {} |\n",
                r.choice,
                r.steps_per_s,
                r.sim_seconds_per_s,
                a.expected,
                a.tunnelling,
                per_thousand(a.missed),
                per_thousand(a.shot_enemy),
                per_thousand(a.enemy_ship),
                per_thousand(a.body_wall),
                a.depth_mean.map_or("–".to_owned(), |d| format!("{d:.2}")),
                a.depth_max,
                a.limit_violations,
                if r.pareto { "✓" } else { "" }
            );
        }
        for (title, rows) in [
            (
                format!("Game: `{}` under each choice, stage by stage", self.scene),
                &self.game,
            ),
            (
                format!("Features: `{}` with one feature off", self.scene),
                &self.features,
            ),
        ] {
            out += &format!(
                "\n### {title}\n\nAfter {} steps of play; stage times: the mean of {} \
                 profiled steps (µs).\n\n| choice | enemies alive | steps/s | step µs | stages |\n\
                 |---|---:|---:|---:|---|\n",
                s.game_warmup, s.profiled_steps
            );
            for r in rows {
                out += &format!(
                    "| {} | {} | {:.0} | {:.1} | {} |\n",
                    r.choice, r.alive, r.steps_per_s, r.step_us, r.stages
                );
            }
        }
        out += "\n### Every body in one cell\n\nThe first step of a world whose bodies all \
                 start on one spot (median of three).\n\n| bodies | cap | step ms | stages (ms) |\n\
                 |---:|---:|---:|---|\n";
        for r in &self.crowded {
            let cap = match r.neighbour_cap {
                0 => "none".to_owned(),
                cap => cap.to_string(),
            };
            out += &format!(
                "| {} | {cap} | {:.2} | {} |\n",
                r.bodies, r.step_ms, r.stages
            );
        }
        out
    }

    /// The summary as text: the Markdown tables.
    pub fn to_text(&self) -> String {
        self.to_markdown()
    }
}
