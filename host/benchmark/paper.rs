//! The paper's experiment (section 8, Figure 8): `paper` (up to 8,192 enemies), the autopilot
//! playing, each loop one simulation step and one frame rendered offscreen, for some minutes
//! of wall time; frames per second, second by second, against the paper's two cards. The
//! kernel renderer draws each frame beside the next step (of the world before it), GL after
//! the step; the one loop a second that is profiled runs the two one after the other.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context as _, anyhow};
use glium::Surface;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::plot::{legend, log_range, png};
use super::{Outputs, Provenance, Spread, write_csv, write_json};
use crate::Device;
use crate::camera::{Camera, CameraMode};
use crate::game::scene::built_in;
use crate::game::{Game, Options};
use crate::graphics::Renderer;
use crate::graphics::bodies::BodyRenderer;
use crate::graphics::headless::{Headless, Target};
use crate::graphics::unpack;
use crate::meter::{Second, Seconds};
use crate::pipeline::Profile;
use crate::play::{Flyer, PlayOptions};
use crate::terminal::progress;

/// The paper's Figure 8: frames per second over five minutes, on its two cards.
pub const PAPER_BANDS: [(&str, f64, f64); 2] = [
    ("GeForce 8200M (paper)", 45.0, 58.0),
    ("GeForce 8800GS (paper)", 130.0, 170.0),
];

/// How `bench paper` runs.
#[derive(Clone, Debug)]
pub struct PaperOptions {
    /// Wall time to play.
    pub duration: Duration,
    /// The frames' size in pixels.
    pub size: (u32, u32),
    /// The renderer.
    pub renderer: Renderer,
    /// What the offscreen frames show: the whole field (as the paper's experiment and
    /// earlier runs of this benchmark drew it, so that their summaries compare) or the ship
    /// followed.
    pub camera: Camera,
    /// Seed of the game.
    pub seed: u32,
    /// Where the CSV, PNG and JSON go.
    pub out: PathBuf,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// The summary of a run, written as JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PaperSummary {
    /// Always "paper".
    pub benchmark: String,
    /// Where and when.
    pub machine: Provenance,
    /// The renderer.
    pub renderer: Renderer,
    /// The frames' width and height.
    pub size: (u32, u32),
    /// What the frames showed (the whole field in summaries from before the choice).
    #[serde(default = "super::field_camera")]
    pub camera: CameraMode,
    /// Seconds measured (whole seconds).
    pub seconds: u32,
    /// Frames rendered in all.
    pub frames: u64,
    /// Frames per second over the seconds.
    pub frames_per_s: Spread,
    /// Enemies alive over the seconds.
    pub enemies_alive: Spread,
    /// The profiled steps' time (µs).
    pub step_us: Spread,
    /// The profiled steps' stages, each over the seconds (µs; absent from older summaries).
    #[serde(default)]
    pub stages_us: BTreeMap<String, Spread>,
    /// The renderer's device work per frame (µs).
    pub render_us: Spread,
    /// GL's part of a frame (µs).
    pub gl_us: Spread,
    /// The simulation alone, no frames, measured after the run (steps/s).
    pub sim_only_steps_per_s: f64,
    /// Whether the autopilot lost before the end (the world then stands still).
    pub game_over: bool,
}

/// What draws each frame offscreen.
enum Drawer {
    /// The kernel renderer; its image stays on the device.
    Kernel,
    /// GL without a window, from the interop vertex buffer.
    Gl(Box<(Headless, BodyRenderer, Target)>),
}

impl Drawer {
    fn new(renderer: Renderer, game: &Game, (width, height): (u32, u32)) -> anyhow::Result<Self> {
        Ok(match renderer {
            Renderer::Kernel => Drawer::Kernel,
            Renderer::Interop => {
                let (gl, bodies) = Headless::with_renderer(game)?;
                let target = Target::new(gl.facade(), width, height)?;
                Drawer::Gl(Box::new((gl, bodies, target)))
            }
        })
    }

    /// Queues a step of `game` and draws a frame: the kernel renderer's beside the step, of
    /// the world before it (see [`Game::submit_beside_frame`]); GL's after it.
    fn step_and_frame(
        &mut self,
        game: &mut Game,
        size: (u32, u32),
        camera: &Camera,
    ) -> anyhow::Result<()> {
        match self {
            Drawer::Kernel => game.submit_beside_frame(None, size, camera)?,
            Drawer::Gl(_) => {
                game.submit(None)?;
                self.frame(game, size, camera, false)?;
            }
        }
        Ok(())
    }

    /// Draws one frame of `game` after its queued steps. With `timed`, waits and returns the
    /// device's and GL's seconds for it.
    fn frame(
        &mut self,
        game: &mut Game,
        (width, height): (u32, u32),
        camera: &Camera,
        timed: bool,
    ) -> anyhow::Result<(f64, f64)> {
        let device = game.pipeline().device();
        let start = timed.then(|| device.mark()).transpose()?;
        match self {
            Drawer::Kernel => {
                game.render(width, height, camera, 0.0)?;
                match start {
                    Some(start) => Ok((device.mark()?.seconds_since(&start)?, 0.0)),
                    None => Ok((0.0, 0.0)),
                }
            }
            Drawer::Gl(gl) => {
                let (gl, bodies, target) = &mut **gl;
                let lens = game.lens(camera, width, height, 0.0);
                bodies.update(gl.facade(), &mut game.drawing(), &lens)?;
                let written = match start {
                    Some(start) => device.mark()?.seconds_since(&start)?,
                    None => 0.0,
                };
                let drawing = Instant::now();
                let mut surface = target.surface(gl.facade())?;
                surface.clear_color_and_depth(unpack(lens.background), 0.0);
                bodies.draw(&mut surface, &lens)?;
                gl.facade().finish();
                Ok((written, drawing.elapsed().as_secs_f64()))
            }
        }
    }
}

/// Runs the experiment on `device` and writes its files; returns the summary.
pub fn run(device: &Device, options: &PaperOptions) -> anyhow::Result<PaperSummary> {
    let outputs = Outputs::in_dir(&options.out, "paper")?;
    let scene = built_in("paper").expect("a built-in scene")?;
    let machine = Provenance::now(device);
    let mut game = Game::with_options(device, &scene, options.seed, Options::default())?;
    let mut drawer = Drawer::new(options.renderer, &game, options.size)?;
    let seconds = options.duration.as_secs().max(1) as usize;
    let mut bar = progress(seconds as u64, options.progress, "bench paper", "seconds");
    let mut counter = Seconds::new(Instant::now());
    let mut last = game.status();
    while counter.rows().len() < seconds {
        if counter.wants_sample(Instant::now()) {
            // One step of each second is profiled stage by stage (it waits for the GPU).
            let mut profile = Profile::default();
            game.submit_profiled(None, &mut profile)?;
            let (render, gl) = drawer.frame(&mut game, options.size, &options.camera, true)?;
            counter.sampled(profile, render, gl);
        } else {
            drawer.step_and_frame(&mut game, options.size, &options.camera)?;
        }
        while let Some(status) = game.ready_status()? {
            last = status;
        }
        let closed = counter.rows().len();
        counter.frame(Instant::now(), last.enemies_alive);
        if counter.rows().len() > closed {
            bar.inc(1);
            bar.set_message(format!(
                "{:.0} frames/s",
                counter.rows()[closed].frames_per_s
            ));
        }
    }
    while let Some(status) = game.next_status()? {
        last = status;
    }
    bar.finish_and_clear();
    let sim_only = sim_only_rate(&mut game, options.duration / 10)?;
    finish(
        options,
        machine,
        &counter,
        sim_only,
        last.is_over(),
        &outputs,
    )
}

/// `bench paper --window`: the same experiment in `play`'s window (the autopilot playing,
/// one step per frame, vsync off); the simulation alone is then timed on a new game.
pub fn run_in_window(device: &Device, options: &PaperOptions) -> anyhow::Result<PaperSummary> {
    let outputs = Outputs::in_dir(&options.out, "paper")?;
    let scene = built_in("paper").expect("a built-in scene")?;
    let machine = Provenance::now(device);
    let play = PlayOptions {
        seed: options.seed,
        pilot: Flyer::Auto,
        muted: true,
        vsync: false,
        renderer: options.renderer,
        record: None,
        size: options.size,
        lag: Options::default().lag,
    };
    let (counter, game_over) = crate::play::measure(device, &scene, play, options.duration)?;
    let mut game = Game::with_options(device, &scene, options.seed, Options::default())?;
    let sim_only = sim_only_rate(&mut game, options.duration / 10)?;
    finish(options, machine, &counter, sim_only, game_over, &outputs)
}

/// The summary of `counter`'s seconds, written with them and their plot.
fn finish(
    options: &PaperOptions,
    machine: Provenance,
    counter: &Seconds,
    sim_only: f64,
    game_over: bool,
    outputs: &Outputs,
) -> anyhow::Result<PaperSummary> {
    let rows = counter.rows();
    let summary = PaperSummary {
        benchmark: "paper".into(),
        machine,
        renderer: options.renderer,
        size: options.size,
        camera: options.camera.mode,
        seconds: rows.len() as u32,
        frames: counter.frames(),
        frames_per_s: Spread::of(rows.iter().map(|r| r.frames_per_s)),
        enemies_alive: Spread::of(rows.iter().map(|r| f64::from(r.enemies_alive))),
        step_us: Spread::of(rows.iter().map(|r| r.step_us)),
        stages_us: stage_spreads(counter.stages()),
        render_us: Spread::of(rows.iter().map(|r| r.render_us)),
        gl_us: Spread::of(rows.iter().map(|r| r.gl_us)),
        sim_only_steps_per_s: sim_only,
        game_over,
    };
    write_csv(&outputs.csv, rows)?;
    write_json(&outputs.json, &summary)?;
    frames_over_time(&outputs.png, &summary, rows)
        .with_context(|| format!("plotting {}", outputs.png.display()))?;
    Ok(summary)
}

/// Figure 8 of the paper, redrawn: frames per second against time (log scale), with the
/// paper's two cards as bands.
pub fn frames_over_time(
    path: &Path,
    summary: &PaperSummary,
    rows: &[Second],
) -> anyhow::Result<()> {
    png(path, |area| {
        let bands: Vec<f64> = PAPER_BANDS
            .iter()
            .flat_map(|&(_, lo, hi)| [lo, hi])
            .collect();
        let y = log_range(rows.iter().map(|r| r.frames_per_s), &bands);
        let x_end = rows.len().max(1) as f64;
        let title = format!(
            "paper: frames/s, one step per frame, {} renderer {}x{} ({}, {})",
            summary.renderer.name(),
            summary.size.0,
            summary.size.1,
            summary.machine.device,
            summary.machine.backend
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..x_end, y.log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("frames per second (log)")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let colours = [RGBColor(230, 140, 60), RGBColor(90, 160, 90)];
        for (&(name, lo, hi), colour) in PAPER_BANDS.iter().zip(colours) {
            chart
                .draw_series([Rectangle::new(
                    [(0.0, lo), (x_end, hi)],
                    colour.mix(0.3).filled(),
                )])
                .map_err(|e| anyhow!("{e}"))?
                .label(format!("{name}: {lo:.0}–{hi:.0}"))
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 16, y + 6)], colour.filled())
                });
        }
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(|r| (f64::from(r.second), r.frames_per_s)),
                BLUE.stroke_width(2),
            ))
            .map_err(|e| anyhow!("{e}"))?
            .label(format!(
                "this run: median {:.0} frames/s",
                summary.frames_per_s.median
            ))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLUE.stroke_width(2)));
        legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        Ok(())
    })
}

/// Each stage's spread over `seconds` (each second's stages in step order; a stage missing
/// from some seconds is spread over those that have it).
fn stage_spreads(seconds: &[Vec<(&'static str, f64)>]) -> BTreeMap<String, Spread> {
    let mut series: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for (stage, us) in seconds.iter().flatten() {
        series.entry((*stage).to_string()).or_default().push(*us);
    }
    series
        .into_iter()
        .map(|(stage, us)| (stage, Spread::of(us)))
        .collect()
}

/// Steps per second of the simulation alone (no frames) over about `time` (at least a
/// second and 100 steps).
fn sim_only_rate(game: &mut Game, time: Duration) -> anyhow::Result<f64> {
    let time = time.max(Duration::from_secs(1));
    let start = Instant::now();
    let mut steps = 0u64;
    while steps < 100 || start.elapsed() < time {
        game.submit(None)?;
        steps += 1;
    }
    while game.next_status()?.is_some() {}
    Ok(steps as f64 / start.elapsed().as_secs_f64())
}

impl PaperSummary {
    /// The summary as aligned lines of text.
    pub fn to_text(&self) -> String {
        let f = &self.frames_per_s;
        let rows = [
            ("backend:", self.machine.backend.clone()),
            ("device:", self.machine.device.clone()),
            (
                "renderer:",
                format!(
                    "{} at {}x{}",
                    self.renderer.name(),
                    self.size.0,
                    self.size.1
                ),
            ),
            ("seconds:", self.seconds.to_string()),
            ("frames:", self.frames.to_string()),
            (
                "frames_per_s:",
                format!("min {:.1}  median {:.1}  max {:.1}", f.min, f.median, f.max),
            ),
            ("step_us:", format!("median {:.1}", self.step_us.median)),
            (
                "stages_us:",
                self.stages_us
                    .iter()
                    .map(|(stage, us)| format!("{stage} {:.1}", us.median))
                    .collect::<Vec<_>>()
                    .join("  "),
            ),
            ("render_us:", format!("median {:.1}", self.render_us.median)),
            ("gl_us:", format!("median {:.1}", self.gl_us.median)),
            (
                "sim_only:",
                format!("{:.1} steps/s", self.sim_only_steps_per_s),
            ),
            (
                "enemies_alive:",
                format!("median {:.0}", self.enemies_alive.median),
            ),
            (
                "game_over:",
                if self.game_over { "yes" } else { "no" }.into(),
            ),
        ];
        rows.iter().map(|(k, v)| format!("{k:<16}{v}\n")).collect()
    }
}
