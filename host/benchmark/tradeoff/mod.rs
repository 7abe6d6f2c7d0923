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
mod crowd;
mod game;
pub mod plots;
pub mod reference;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;
use serde::{Deserialize, Serialize};

use super::rounds::Rounds;
use super::{Outputs, Provenance, write_csv, write_json};
use crate::Device;
use crate::files::write_atomically;
use crate::game::accuracy::{AuditLength, audit_game};
use crate::game::{Game, Options, Scene};
use crate::sim::Physics;
use crate::terminal::progress;
use analytic::AnalyticRow;
use crowd::{
    CROWDED_CHOICES, crowd_choices, crowd_error, crowd_rates, crowded, mark_pareto, scattered,
};
pub use crowd::{CrowdedRow, PhysicsRow, crowd};
pub use game::{FrameTiming, GameAccuracy, GameRow};
pub(crate) use game::{Measure, game_choices, game_rows};
use game::{feature_choices, mark_game_pareto};
use reference::Reference;

/// The crowd's time step (s).
const DT: f32 = 1.0 / 60.0;
/// The reference's substeps per step of [`DT`].
const REFERENCE_SUBSTEPS: u32 = 32;

/// How `gpuwars tradeoff` runs.
#[derive(Clone, Debug)]
pub struct TradeoffOptions {
    /// The game scene of the game and feature tables (built-in name or file).
    pub scene: Scene,
    /// The scene as the user named it (`--scene`), for the tables' titles.
    pub scene_given: String,
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
pub struct RunSizes {
    /// Balls of the crowd whose error is measured.
    pub error_bodies: u32,
    /// Simulated seconds after which the error is measured.
    pub error_seconds: f64,
    /// Balls of the crowd whose speed is measured.
    pub speed_bodies: u32,
    /// How every speed is timed: rounds, interleaved across the choices of a table.
    pub speed: Rounds,
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

impl RunSizes {
    /// The sizes of a full run on `device`, or of a quick one.
    pub(crate) fn new(device: &Device, quick: bool) -> Self {
        let gpu = device.kind() == crate::BackendKind::Cuda;
        match (quick, gpu) {
            (true, _) => RunSizes {
                error_bodies: 96,
                error_seconds: 0.25,
                speed_bodies: 1024,
                speed: Rounds {
                    rounds: 3,
                    seconds: 0.02,
                },
                game_warmup: 20,
                profiled_steps: 3,
                audit_steps: 240,
                analytic_dts: [1.0 / 30.0, 1.0 / 60.0],
                crowded: [256, 1024],
            },
            (false, false) => RunSizes {
                error_bodies: 768,
                error_seconds: 0.25,
                speed_bodies: 16_384,
                // The emulator's figures vary more from second to second.
                speed: Rounds {
                    rounds: 5,
                    seconds: 0.6,
                },
                game_warmup: 600,
                profiled_steps: 30,
                audit_steps: 1200,
                analytic_dts: [1.0 / 60.0, 1.0 / 240.0],
                crowded: [4096, 32_768],
            },
            (false, true) => RunSizes {
                error_bodies: 768,
                error_seconds: 0.25,
                speed_bodies: 262_144,
                speed: Rounds {
                    rounds: 5,
                    seconds: 0.2,
                },
                game_warmup: 600,
                profiled_steps: 30,
                audit_steps: 1200,
                analytic_dts: [1.0 / 60.0, 1.0 / 240.0],
                crowded: [4096, 32_768],
            },
        }
    }
}

/// Steps of the scene's game timed before a run, to say what the run will take.
const PROBE_STEPS: u32 = 2;

/// Roughly what a run of `rows` (crowd, game and feature choices) will take, in seconds,
/// from `scene`'s game made and played from `seed` for [`PROBE_STEPS`] steps, and audited
/// for as many: the game rows are most of a slow run, and each is made, played, timed in
/// its rounds (twice if its `frames` are timed too) and (the game table's) audited, a
/// snapshot and the exact check of every pair a step (in a world of millions, most of the
/// run). The crowd's rows are timed in their rounds, their error runs being short.
pub(crate) fn estimate(
    device: &Device,
    (scene, seed): (&Scene, u32),
    sizes: &RunSizes,
    (crowd, games, features): (usize, usize, usize),
    frames: bool,
) -> anyhow::Result<f64> {
    let start = Instant::now();
    let mut game = Game::with_options(device, scene, seed, Options::default())?;
    let made = start.elapsed().as_secs_f64();
    let start = Instant::now();
    for _ in 0..PROBE_STEPS {
        game.step(None)?;
    }
    let step = start.elapsed().as_secs_f64() / f64::from(PROBE_STEPS);
    drop(game);
    let start = Instant::now();
    let probe = AuditLength {
        warmup: 0,
        busy_within: 0,
        steps: PROBE_STEPS,
    };
    audit_game(device, scene, seed, probe)?;
    // Its game made (as above), then each step played, read back and checked.
    let audit_step = ((start.elapsed().as_secs_f64() - made) / f64::from(PROBE_STEPS)).max(step);
    let timed = f64::from(sizes.speed.rounds + 1) * sizes.speed.seconds;
    let warmup = made + f64::from(sizes.game_warmup) * step;
    let frames_timed = if frames { timed } else { 0.0 };
    let played = warmup + f64::from(sizes.profiled_steps) * step + timed + frames_timed;
    let audited = warmup + f64::from(sizes.audit_steps) * audit_step;
    let rows = |n: usize| n as f64;
    Ok(rows(crowd) * timed + rows(games) * (played + audited) + rows(features) * played)
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
    pub sizes: RunSizes,
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

/// Runs the whole matrix and writes `bench-tradeoff.{csv,md,png,json}`.
pub fn run(device: &Device, options: &TradeoffOptions) -> anyhow::Result<TradeoffSummary> {
    let outputs = Outputs::in_dir(&options.out, "tradeoff")?;
    let machine = Provenance::now(device);
    let sizes = RunSizes::new(device, options.quick);
    let choices = crowd_choices();
    let games = game_choices(&options.scene);
    let features = feature_choices(&options.scene);
    let mut bar = progress(
        (choices.len() + games.len() + features.len() + 1) as u64,
        options.progress,
        "tradeoff",
        "choices",
    );
    let seed = options.seed;
    let rows = (choices.len(), games.len(), features.len());
    bar.announce(estimate(
        device,
        (&options.scene, seed),
        &sizes,
        rows,
        false,
    )?);

    // The truth: the default crowd's start, in f64 with many substeps.
    let base = crowd(sizes.error_bodies, DT, Physics::default());
    let start = scattered(device, &base, seed)?.snapshot()?;
    let mut truth = Reference::new(&base, &start)?;
    let truth_steps = (sizes.error_seconds / f64::from(DT)).round() as u32;
    for _ in 0..truth_steps {
        truth.advance(f64::from(DT), REFERENCE_SUBSTEPS);
    }

    let mut physics = Vec::new();
    for &(dt, p) in &choices {
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
            steps_per_s: 0.0,
            steps_per_s_low: 0.0,
            steps_per_s_high: 0.0,
            sim_seconds_per_s: 0.0,
            pareto: false,
            unseparated: String::new(),
        });
    }
    bar.set_message("the crowd's speeds, in rounds");
    let mut sims = choices
        .iter()
        .map(|&(dt, p)| scattered(device, &crowd(sizes.speed_bodies, dt, p), seed))
        .collect::<Result<Vec<_>, _>>()?;
    let rates = crowd_rates(&mut sims, sizes.speed, || bar.inc(0))?;
    for (row, rate) in physics.iter_mut().zip(rates) {
        row.steps_per_s = rate.median;
        (row.steps_per_s_low, row.steps_per_s_high) = (rate.low, rate.high);
        row.sim_seconds_per_s = rate.median * row.dt;
    }
    bar.inc(choices.len() as u64);
    mark_pareto(&mut physics);

    bar.set_message("analytic cases");
    let analytic = analytic::run(device, &sizes.analytic_dts)?;
    bar.inc(1);

    let name = &options.scene_given;
    let mut tick = |choice: &str| {
        bar.set_message(format!("{name}: {choice}"));
        bar.inc(1);
    };
    let audited = Measure {
        audited: true,
        frames: None,
    };
    let mut game = game_rows(device, &games, seed, &sizes, audited, &mut tick)?;
    mark_game_pareto(&mut game);
    let timed = Measure {
        audited: false,
        frames: None,
    };
    let feature_rows = game_rows(device, &features, seed, &sizes, timed, &mut tick)?;
    let mut crowded_rows = Vec::new();
    for bodies in sizes.crowded {
        for choice in CROWDED_CHOICES {
            let (cap, budget) = choice;
            bar.set_message(format!(
                "{bodies} bodies in one cell, cap {cap}, contact budget {budget}"
            ));
            crowded_rows.push(crowded(device, bodies, choice)?);
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
        scene: options.scene_given.clone(),
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

/// How the tables' speeds were taken, for their captions.
const SPEEDS: &str = "each timed in interleaved rounds after a warm-up: the median, and the \
                      slowest and fastest round. ✓: on the Pareto frontier, nothing more \
                      accurate and faster beyond the spreads; ≈ names the choices that beat it \
                      by their medians only, inside the spreads (the run cannot tell them apart).";

/// [`SPEEDS`] for the game table, whose accuracy is its contacts missed.
const SPEEDS_GAME: &str = "each choice's game timed in interleaved rounds with the others \
                           after a warm-up: the median, and the slowest and fastest round. ✓: \
                           on the Pareto frontier of missed against simulated seconds per \
                           second, beyond the spreads; ≈ names the choices it cannot be told \
                           apart from.";

/// A speed as the tables show it: the median, then the slowest and fastest round.
fn speed(median: f64, (low, high): (f64, f64)) -> String {
    format!("{median:.0} ({low:.0}–{high:.0})")
}

/// The frontier column: ✓ for a point on it, with ≈ and the choices it cannot be told
/// apart from.
fn frontier_mark(on: bool, unseparated: &str) -> String {
    match (on, unseparated.is_empty()) {
        (false, _) => String::new(),
        (true, true) => "✓".to_owned(),
        (true, false) => format!("✓ ≈ {unseparated}"),
    }
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
             {} balls, {SPEEDS}\n\n",
            s.error_bodies, s.error_seconds, s.speed_bodies
        );
        out += "| choice | position RMS | contacts missed | steps/s | simulated s/s | frontier |\n";
        out += "|---|---:|---:|---:|---:|:---:|\n";
        for r in &self.physics {
            out += &format!(
                "| {} | {:.3} | {:.2}% | {} | {:.2} | {} |\n",
                r.choice,
                r.position_rms,
                100.0 * r.contacts_missed,
                speed(r.steps_per_s, (r.steps_per_s_low, r.steps_per_s_high)),
                r.sim_seconds_per_s,
                frontier_mark(r.pareto, &r.unseparated)
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
             the bodies' paths (f64, every pair), partner by partner: contacts found (each \
             from both sides), how many passed between two step ends, and per thousand found: \
             missed, extra (counted but not found), wrong partner (counted with another \
             body), late (a swept contact's moment off by more than {} of the motion), then \
             missed by class; pairs f32 cannot decide (their verdict or moment moves within \
             the audit's margin), counted apart; penetration at a step's end, mean and \
             deepest; body-steps over a limit; enemies killed per shot fired, the player's \
             figure. Steps per second: {SPEEDS_GAME} –: no such contact in the audit; a choice \
             that could not be measured says why.\n\n| choice | \
             steps/s | simulated s/s | contacts | between ends | missed ‰ | extra ‰ | wrong \
             partner ‰ | late ‰ | shot→enemy ‰ | enemy→ship ‰ | body→wall ‰ | undecidable | \
             depth mean / max | over a limit | kills per shot | frontier |\n|---|---:|---:|---:|\
             ---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|\n",
            self.scene,
            s.game_warmup,
            s.audit_steps,
            crate::sim::audit::TIME_TOLERANCE
        );
        let per_thousand = |v: Option<f64>| v.map_or("–".to_owned(), |v| format!("{v:.1}"));
        for r in &self.game {
            if let Some(why) = &r.skipped {
                out += &format!("| {} | not measured: {why} |\n", r.choice);
                continue;
            }
            let Some(a) = &r.accuracy else { continue };
            out += &format!(
                "| {} | {} | {:.2} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} / \
                 {:.2} | {} | {} | {} |\n",
                r.choice,
                speed(r.steps_per_s, r.steps_per_s_range),
                r.sim_seconds_per_s,
                a.expected,
                a.tunnelling,
                per_thousand(a.missed),
                per_thousand(a.extra),
                per_thousand(a.wrong_partner),
                per_thousand(a.late),
                per_thousand(a.shot_enemy),
                per_thousand(a.enemy_ship),
                per_thousand(a.body_wall),
                a.undecidable,
                a.depth_mean.map_or("–".to_owned(), |d| format!("{d:.2}")),
                a.depth_max,
                a.limit_violations,
                a.kills_per_shot
                    .map_or("–".to_owned(), |k| format!("{k:.2}")),
                frontier_mark(r.pareto, &r.unseparated.join("; "))
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
                out += &match &r.skipped {
                    Some(why) => format!("| {} | not measured: {why} |\n", r.choice),
                    None => format!(
                        "| {} | {} | {} | {:.1} | {} |\n",
                        r.choice,
                        r.alive,
                        speed(r.steps_per_s, r.steps_per_s_range),
                        r.step_us,
                        r.stages
                    ),
                };
            }
        }
        out += "\n### Every body in one cell\n\nThe first step of a world whose bodies all \
                 start on one spot (median of three).\n\n| bodies | cap | contact budget | step ms | \
                 stages (ms) |\n|---:|---:|---:|---:|---|\n";
        let bound = |n: u32| match n {
            0 => "none".to_owned(),
            n => n.to_string(),
        };
        for r in &self.crowded {
            out += &format!(
                "| {} | {} | {} | {:.2} | {} |\n",
                r.bodies,
                bound(r.neighbour_cap),
                bound(r.contact_budget),
                r.step_ms,
                r.stages
            );
        }
        out
    }

    /// The summary as text: the Markdown tables.
    pub fn to_text(&self) -> String {
        self.to_markdown()
    }
}
