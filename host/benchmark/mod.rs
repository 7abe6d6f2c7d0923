//! `gpuwars bench`: the paper's experiment (section 8, Figure 8) and how the game scales,
//! written as CSV, PNG plots and JSON summaries, and compared run against run.
//!
//! - [`paper`]: scene `paper`, the autopilot playing, one simulation step and one rendered
//!   frame per loop as in the paper, second by second.
//! - [`scale`]: the paper's mix and density from 1,024 enemies up to the largest world that
//!   fits the device, doubling.
//! - [`compare`]: the change between two summaries, figure by figure.
//! - [`rounds`]: speeds timed in interleaved rounds, with their spread.
//! - [`tradeoff`]: speed against accuracy for each physics choice (`gpuwars tradeoff`).
//! - [`tune`]: the most accurate choice that holds a speed, written as a scene (`gpuwars
//!   tune`).

pub mod compare;
pub mod paper;
pub mod plot;
pub mod rounds;
pub mod scale;
pub mod tradeoff;
pub mod tune;

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use anyhow::Context as _;
use serde::{Deserialize, Serialize};

use crate::Device;
use crate::backend::device_name;
use crate::camera::CameraMode;
use crate::files::{FileError, io_words, shown, write_atomically};

/// Where and when a benchmark ran.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// `cuda` or `cpu`.
    pub backend: String,
    /// The GPU's name, or the CPU emulation and its threads.
    pub device: String,
    /// The commit the binary was built from.
    pub commit: String,
    /// When the run started (RFC 3339, UTC).
    pub date: String,
    /// The command line that ran it.
    pub command: String,
}

impl Provenance {
    /// Where `device` is, now.
    pub fn now(device: &Device) -> Self {
        Provenance {
            backend: device.kind().to_string(),
            device: device_name(device),
            commit: env!("GPUWARS_COMMIT").to_string(),
            date: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
            command: std::env::args().collect::<Vec<_>>().join(" "),
        }
    }
}

/// The least, the median, the mean and the largest of a series.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Smallest value.
    pub min: f64,
    /// Median (the mean of the middle two for an even count).
    pub median: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Largest value.
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (all zero when there are none; NaNs are left out).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut v: Vec<f64> = values.into_iter().filter(|x| !x.is_nan()).collect();
        if v.is_empty() {
            return Spread::default();
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        };
        Spread {
            min: v[0],
            median,
            mean: v.iter().sum::<f64>() / n as f64,
            max: v[n - 1],
        }
    }
}

/// The files of one run: `DIR/bench-NAME.{csv,png,json}`.
pub struct Outputs {
    /// The CSV table.
    pub csv: PathBuf,
    /// The plot.
    pub png: PathBuf,
    /// The summary.
    pub json: PathBuf,
}

impl Outputs {
    /// The files of benchmark `name` in `dir`.
    pub fn at(dir: &Path, name: &str) -> Self {
        let file = |ext: &str| dir.join(format!("bench-{name}.{ext}"));
        Outputs {
            csv: file("csv"),
            png: file("png"),
            json: file("json"),
        }
    }

    /// The files of benchmark `name` in `dir`, made if missing.
    pub fn in_dir(dir: &Path, name: &str) -> anyhow::Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| {
            let problem = format!("cannot make the output folder: {}", io_words(&e));
            FileError::new(&shown(dir), None, "--out", problem)
        })?;
        Ok(Outputs::at(dir, name))
    }

    /// The tables in Markdown, beside the others (written by `tradeoff`).
    pub fn markdown(&self) -> PathBuf {
        self.png.with_extension("md")
    }

    /// A second plot, of the game scene, beside the first (written by `tradeoff`).
    pub fn game_png(&self) -> PathBuf {
        let stem = self.png.file_stem().unwrap_or_default().to_string_lossy();
        self.png.with_file_name(format!("{stem}-game.png"))
    }
}

/// The camera of summaries written before frames could follow the ship: the whole field.
fn field_camera() -> CameraMode {
    CameraMode::Field
}

/// Writes `rows` as CSV (a header from the field names), atomically.
fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> anyhow::Result<()> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    for row in rows {
        writer.serialize(row)?;
    }
    let bytes = writer.into_inner().context("finishing the CSV")?;
    Ok(write_atomically(path, &bytes)?)
}

/// Writes `value` as pretty JSON, atomically.
fn write_json<T: Serialize>(path: &Path, value: &T) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    Ok(write_atomically(path, text.as_bytes())?)
}
