//! The crowd: a ring of balls around a central attractor under each physics choice, its
//! error against the reference and its speed; and every ball of a world in one cell.

use glam::Vec2;
use serde::{Deserialize, Serialize};

use super::DT;
use super::reference::Reference;
use crate::benchmark::rounds::{Point, Rate, Rounds, frontier, interleaved};
use crate::pipeline::{Pipeline, Profile, Simulation};
use crate::sim::{Boundary, Field, Integrator, KindSpec, Physics, Shape, Sweep, WorldSpec};
use crate::{Device, Error};

/// The balls' radius.
const RADIUS: f32 = 4.0;
/// Fraction of the crowd's field that balls cover.
const COVER: f64 = 0.04;
/// Speed of a circular orbit at a quarter of the field's side, and the balls' initial
/// speed deviation (units/s).
const ORBIT_SPEED: f32 = 60.0;

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
    /// Steps per wall second on the larger crowd: the median of the timed rounds.
    pub steps_per_s: f64,
    /// The slowest round's steps per second.
    pub steps_per_s_low: f64,
    /// The fastest round's.
    pub steps_per_s_high: f64,
    /// Simulated seconds per wall second (the median steps/s × dt).
    pub sim_seconds_per_s: f64,
    /// Whether no other choice is both more accurate and faster beyond the speeds' spreads
    /// (see [`crate::benchmark::rounds::frontier`]).
    pub pareto: bool,
    /// The choices that beat this one by their median speeds alone, inside the spreads
    /// (`; ` between them): the run cannot tell them apart.
    pub unseparated: String,
}

/// A step of a world whose bodies all start on one spot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrowdedRow {
    /// Bodies, all in one cell.
    pub bodies: u32,
    /// Entries examined per query (0: all).
    pub neighbour_cap: u32,
    /// Bodies of one kind a body's contacts are sought among (0: all).
    #[serde(default)]
    pub contact_budget: u32,
    /// The first step's time, the median of three worlds (ms).
    pub step_ms: f64,
    /// Its stages' ms, `stage=ms` joined by spaces.
    pub stages: String,
}

/// The crowd's choices: `(dt, physics)`, the default first.
pub(super) fn crowd_choices() -> Vec<(f32, Physics)> {
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
pub(super) fn scattered<'d>(
    device: &'d Device,
    spec: &WorldSpec,
    seed: u32,
) -> Result<Simulation<'d>, Error> {
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
pub(super) fn crowd_error(
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

/// Steps per second of each of `sims` (crowds made by [`scattered`]), timed in interleaved
/// `rounds` after one step each; `tick` after each round.
pub(super) fn crowd_rates(
    sims: &mut [Simulation],
    rounds: Rounds,
    tick: impl FnMut(),
) -> anyhow::Result<Vec<Rate>> {
    for sim in sims.iter_mut() {
        sim.step()?;
    }
    interleaved(
        sims,
        rounds,
        |sim| {
            const BATCH: u64 = 8;
            for _ in 0..BATCH {
                Pipeline::step(sim)?;
            }
            sim.device().synchronize()?;
            Ok(BATCH)
        },
        tick,
    )
}

/// The crowded cell's choices, `(neighbour_cap, contact_budget)`: neither bound, a cap of
/// 32, a contact budget of 384 (128 entries of the run).
pub(super) const CROWDED_CHOICES: [(u32, u32); 3] = [(0, 0), (32, 0), (0, 384)];

/// The first step of `bodies` balls on one spot, with the cap and the contact budget of
/// `choice` (see [`CROWDED_CHOICES`]): the median of three worlds.
pub(super) fn crowded(
    device: &Device,
    bodies: u32,
    (cap, budget): (u32, u32),
) -> anyhow::Result<CrowdedRow> {
    let mut spec = crowd(bodies, DT, Physics::default());
    spec.physics.neighbour_cap = cap;
    spec.physics.contact_budget = budget;
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
        contact_budget: budget,
        step_ms: median.step_seconds() * 1e3,
        stages,
    })
}

/// Marks the rows on the Pareto frontier of error against simulated seconds per second,
/// beyond the speeds' spreads, and the rows each cannot be separated from.
pub(super) fn mark_pareto(rows: &mut [PhysicsRow]) {
    let points: Vec<Option<Point>> = rows
        .iter()
        .map(|r| {
            let steps = Rate {
                median: r.steps_per_s,
                low: r.steps_per_s_low,
                high: r.steps_per_s_high,
            };
            Some(Point {
                error: r.position_rms,
                speed: steps.scaled(r.dt),
            })
        })
        .collect();
    let names: Vec<String> = rows.iter().map(|r| r.choice.clone()).collect();
    for (row, (on, unseparated)) in rows.iter_mut().zip(frontier(&points)) {
        row.pareto = on;
        let names: Vec<&str> = unseparated.iter().map(|&i| names[i].as_str()).collect();
        row.unseparated = names.join("; ");
    }
}
