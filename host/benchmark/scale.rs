//! How the game scales: the paper's mix and density (`scale-1m`'s scene, resized) from 1,024
//! enemies up to the largest world that fits, doubling; per size the step's speed and stage
//! times, the bytes it moves against the device's copy bandwidth, and frames per second with
//! the kernel renderer drawing every body (a point at these sizes).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context as _, anyhow, bail};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::plot::{legend, log_range, png};
use super::rounds::Rate;
use super::{Outputs, Provenance, write_csv, write_json};
use crate::backend::floor;
use crate::camera::{Camera, CameraMode, DEFAULT_ZOOM};
use crate::files::{figure, thousands};
use crate::game::scene::built_in;
use crate::game::{Game, Options, Scene};
use crate::pipeline::Profile;
use crate::terminal::progress;
use crate::{Device, Error};

/// The fewest enemies measured.
pub const MIN_ENEMIES: u64 = 1024;
/// The most enemies a world holds (`scale-16m`: every slot of the largest world but the
/// ship's and the shots').
pub const MAX_ENEMIES: u64 = 16_760_000;
/// The enemies of the scene that is resized (`scale-1m`).
const BASE_ENEMIES: u64 = 1_048_576;
/// Enemies per square unit in the paper: 8,192 on a 4096 × 4096 field.
const PAPER_DENSITY: f64 = 8192.0 / (4096.0 * 4096.0);

/// How `bench scale` runs.
#[derive(Clone, Debug)]
pub struct ScaleOptions {
    /// The most enemies to measure (the last size, if it is not a power of two).
    pub max: u64,
    /// Wall time spent on each of the speed and the frame measurements of a size.
    pub time: Duration,
    /// The frames' size in pixels.
    pub size: (u32, u32),
    /// What the frames show: the whole field, or the ship followed at the default zoom
    /// with the radar (the view a player sees).
    pub camera: CameraMode,
    /// Where the CSV, PNG and JSON go.
    pub out: PathBuf,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// The figures of one size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScaleRow {
    /// Enemies, all alive from the first step.
    pub enemies: u64,
    /// Seconds to set the world up.
    pub setup_s: f64,
    /// Steps per second, the step replayed as a CUDA graph (no frames): the median of
    /// [`ROUNDS`] rounds.
    pub steps_per_s: f64,
    /// The slowest round's steps per second.
    pub steps_per_s_low: f64,
    /// The fastest round's.
    pub steps_per_s_high: f64,
    /// Time per step over the profiled steps, stage by stage summed (µs).
    pub step_us: f64,
    /// The launch floor of a step this size: as many one-touch launches as it makes over
    /// its slots, replayed as a graph launched as the step's is (µs; see
    /// `backend::floor`).
    pub floor_us: f64,
    /// Each stage's share of it, in step order: `stage=µs` joined by spaces.
    pub stages: String,
    /// Bytes the step moves by our count (every array element its kernels must touch).
    pub bytes_per_step: u64,
    /// Those bytes over the profiled step time (bytes per second).
    pub achieved_bandwidth: f64,
    /// That over the copy bandwidth measured in the same run.
    pub fraction_of_copy: f64,
    /// Frames per second, one step and one kernel-rendered frame each: the median of
    /// [`ROUNDS`] rounds.
    pub frames_per_s: f64,
    /// The slowest round's frames per second.
    pub frames_per_s_low: f64,
    /// The fastest round's.
    pub frames_per_s_high: f64,
}

/// The summary of a run, written as JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScaleSummary {
    /// Always "scale".
    pub benchmark: String,
    /// Where and when.
    pub machine: Provenance,
    /// A device-to-device copy's bytes (read plus written) per second, measured in the run.
    pub copy_bandwidth: f64,
    /// The frames' width and height.
    pub size: (u32, u32),
    /// What the frames showed (the whole field in summaries from before the choice).
    #[serde(default = "super::field_camera")]
    pub camera: CameraMode,
    /// Why the sizes stopped where they did.
    pub stopped: String,
    /// Every size measured.
    pub rows: Vec<ScaleRow>,
}

/// The enemy counts from [`MIN_ENEMIES`] doubling up to `max`, and `max` itself.
pub fn sizes(max: u64) -> Vec<u64> {
    let max = max.clamp(MIN_ENEMIES, MAX_ENEMIES);
    let mut sizes: Vec<u64> = std::iter::successors(Some(MIN_ENEMIES), |n| Some(n * 2))
        .take_while(|&n| n <= max)
        .collect();
    if sizes.last() != Some(&max) {
        sizes.push(max);
    }
    sizes
}

/// `scale-1m`'s scene resized to `enemies` (a multiple of 8): every wave and its kind's
/// capacity in the same proportions, the field keeping the paper's density.
pub fn scene(enemies: u64) -> anyhow::Result<Scene> {
    if !enemies.is_multiple_of(8) || !(MIN_ENEMIES..=MAX_ENEMIES).contains(&enemies) {
        bail!(
            "{} enemies (allowed a multiple of 8 from {} to {})",
            thousands(enemies),
            thousands(MIN_ENEMIES),
            thousands(MAX_ENEMIES)
        );
    }
    let base = built_in("scale-1m").expect("a built-in scene")?;
    let mut table: toml::Table = toml::from_str(&base.source)?;
    let side = (enemies as f64 / PAPER_DENSITY).sqrt().round();
    table.insert("name".into(), format!("scale-{enemies}").into());
    table.insert(
        "description".into(),
        format!("{enemies} enemies, all alive from the first step: the paper's mix and density")
            .into(),
    );
    let world = table["world"].as_table_mut().context("[world]")?;
    world.insert(
        "size".into(),
        toml::Value::Array(vec![side.into(), side.into()]),
    );
    let mut counts = Vec::new();
    let waves = table["spawn"]["waves"]
        .as_array()
        .context("[[spawn.waves]]")?
        .clone();
    let mut resized = Vec::new();
    for mut wave in waves {
        let wave_table = wave.as_table_mut().context("a wave")?;
        let count = wave_table["count"].as_integer().context("a wave's count")? as u64;
        let count = count * enemies / BASE_ENEMIES;
        wave_table.insert("count".into(), (count as i64).into());
        let kind = wave_table["kind"]
            .as_str()
            .context("a wave's kind")?
            .to_string();
        counts.push((kind, count));
        resized.push(wave);
    }
    table["spawn"]
        .as_table_mut()
        .context("[spawn]")?
        .insert("waves".into(), toml::Value::Array(resized));
    for kind in table["kinds"].as_array_mut().context("[[kinds]]")? {
        let kind = kind.as_table_mut().context("a kind")?;
        let name = kind["name"].as_str().context("a kind's name")?.to_string();
        if let Some((_, count)) = counts.iter().find(|(k, _)| *k == name) {
            kind.insert("capacity".into(), (*count as i64).into());
        }
    }
    let text = toml::to_string(&table)?;
    Ok(Scene::from_toml(&text, &format!("scale-{enemies}"))?)
}

/// Runs the sizes on `device` and writes the files; returns the summary.
pub fn run(device: &Device, options: &ScaleOptions) -> anyhow::Result<ScaleSummary> {
    let outputs = Outputs::in_dir(&options.out, "scale")?;
    let machine = Provenance::now(device);
    let copy_bandwidth = device.copy_bandwidth(u64::MAX)?;
    let sizes = sizes(options.max);
    let mut bar = progress(sizes.len() as u64, options.progress, "bench scale", "sizes");
    let mut rows = Vec::new();
    let mut stopped = format!("the largest size asked for ({})", options.max);
    for enemies in sizes {
        bar.set_message(format!("{enemies} enemies"));
        match measure(device, enemies, options, copy_bandwidth) {
            Ok(row) => rows.push(row),
            Err(e) if matches!(e.downcast_ref::<Error>(), Some(Error::OutOfMemory { .. })) => {
                stopped = format!("{enemies} enemies do not fit: {e}");
                break;
            }
            Err(e) => return Err(e.context(format!("{enemies} enemies"))),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let summary = ScaleSummary {
        benchmark: "scale".into(),
        machine,
        copy_bandwidth,
        size: options.size,
        camera: options.camera,
        stopped,
        rows,
    };
    write_csv(&outputs.csv, &summary.rows)?;
    write_json(&outputs.json, &summary)?;
    scaling(&outputs.png, &summary)
        .with_context(|| format!("plotting {}", outputs.png.display()))?;
    Ok(summary)
}

/// One figure of a scale row.
type Figure = fn(&ScaleRow) -> f64;

/// Steps per second and frames per second against enemies, log-log.
pub fn scaling(path: &Path, summary: &ScaleSummary) -> anyhow::Result<()> {
    png(path, |area| {
        let rows = &summary.rows;
        let x_low = rows.first().map_or(1024.0, |r| r.enemies as f64);
        let x_high = rows
            .last()
            .map_or(2048.0, |r| r.enemies as f64)
            .max(x_low * 2.0);
        let y = log_range(
            rows.iter().flat_map(|r| [r.steps_per_s, r.frames_per_s]),
            &[],
        );
        let title = format!(
            "scaling: the paper's mix and density ({}, {})",
            summary.machine.device, summary.machine.backend
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d((x_low / 1.2..x_high * 1.2).log_scale(), y.log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("enemies (log)")
            .y_desc("per second (log)")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let series: [(&str, RGBColor, Figure); 2] = [
            ("simulation steps/s", BLUE, |r| r.steps_per_s),
            (
                &format!(
                    "frames/s (a step and a kernel-rendered frame each, camera {})",
                    summary.camera.name()
                ),
                RED,
                |r| r.frames_per_s,
            ),
        ];
        for (name, colour, value) in series {
            let points: Vec<(f64, f64)> =
                rows.iter().map(|r| (r.enemies as f64, value(r))).collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| anyhow!("{e}"))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 4, colour.filled())),
                )
                .map_err(|e| anyhow!("{e}"))?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// Timed rounds of each figure of a size: one world at a time fits (the largest take most of
/// the memory), so its rounds follow each other rather than interleave with other sizes'.
pub const ROUNDS: u32 = 5;

/// Runs `work` on `game` in [`ROUNDS`] rounds, each for at least `time / ROUNDS` and 3
/// times, then waits for everything queued; returns runs per second over the rounds.
fn rate(
    game: &mut Game,
    time: Duration,
    mut work: impl FnMut(&mut Game) -> Result<(), Error>,
) -> anyhow::Result<Rate> {
    let mut samples = Vec::with_capacity(ROUNDS as usize);
    for _ in 0..ROUNDS {
        let start = Instant::now();
        let mut runs = 0u64;
        while runs < 3 || start.elapsed() < time / ROUNDS {
            work(game)?;
            runs += 1;
        }
        while game.next_status()?.is_some() {}
        game.pipeline().device().synchronize()?;
        samples.push(runs as f64 / start.elapsed().as_secs_f64());
    }
    Ok(Rate::of(&samples))
}

/// The figures of `enemies`.
fn measure(
    device: &Device,
    enemies: u64,
    options: &ScaleOptions,
    copy_bandwidth: f64,
) -> anyhow::Result<ScaleRow> {
    let scene = scene(enemies)?;
    let start = Instant::now();
    let mut game = Game::with_options(device, &scene, 1, Options::default())?;
    let setup_s = start.elapsed().as_secs_f64();
    // The first step brings every enemy to life.
    game.step(None)?;
    let steps_per_s = rate(&mut game, options.time, |game| game.submit(None))?;
    let mut profile = Profile::default();
    for _ in 0..3 {
        game.submit_profiled(None, &mut profile)?;
    }
    let (width, height) = options.size;
    let camera = Camera::new(options.camera, DEFAULT_ZOOM);
    let frames_per_s = rate(&mut game, options.time, |game| {
        game.submit(None)?;
        game.render(width, height, &camera, 0.0)
    })?;
    let step_s = profile.step_seconds();
    let pipeline = game.pipeline();
    let floor = floor::measure(
        device,
        pipeline.launches_per_step(),
        pipeline.layout().slots,
    )?;
    let bytes: u64 = profile.stages.iter().map(|s| s.bytes).sum();
    let achieved = bytes as f64 / step_s.max(f64::MIN_POSITIVE);
    let stages = profile.stage_line(1e-6, 1);
    Ok(ScaleRow {
        enemies,
        setup_s,
        steps_per_s: steps_per_s.median,
        steps_per_s_low: steps_per_s.low,
        steps_per_s_high: steps_per_s.high,
        step_us: step_s * 1e6,
        floor_us: floor.graph_like_step_s(device.dependent_launch()) * 1e6,
        stages,
        bytes_per_step: bytes,
        achieved_bandwidth: achieved,
        fraction_of_copy: achieved / copy_bandwidth,
        frames_per_s: frames_per_s.median,
        frames_per_s_low: frames_per_s.low,
        frames_per_s_high: frames_per_s.high,
    })
}

impl ScaleSummary {
    /// The summary as a table of text.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "backend: {}   device: {}   copy bandwidth {:.1} GB/s\n",
            self.machine.backend,
            self.machine.device,
            self.copy_bandwidth / 1e9
        );
        out += &format!(
            "{:>10} {:>26} {:>10} {:>10} {:>12} {:>9} {:>26}\n",
            "enemies",
            "steps/s (slowest–fastest)",
            "step µs",
            "floor µs",
            "GB/s",
            "of copy",
            "frames/s (slowest–fastest)"
        );
        let spread = |median: f64, low: f64, high: f64| {
            format!("{} ({}–{})", figure(median), figure(low), figure(high))
        };
        for r in &self.rows {
            out += &format!(
                "{:>10} {:>26} {:>10.1} {:>10.1} {:>12.1} {:>8.1}% {:>26}\n",
                r.enemies,
                spread(r.steps_per_s, r.steps_per_s_low, r.steps_per_s_high),
                r.step_us,
                r.floor_us,
                r.achieved_bandwidth / 1e9,
                100.0 * r.fraction_of_copy,
                spread(r.frames_per_s, r.frames_per_s_low, r.frames_per_s_high),
            );
        }
        out += &format!(
            "frames: {}x{}, camera {}; stopped at {}\n",
            self.size.0,
            self.size.1,
            self.camera.name(),
            self.stopped
        );
        out
    }
}
