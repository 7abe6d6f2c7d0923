//! `gpuwars bench`: short runs of the paper's experiment and of the scaling on the CPU
//! emulation write a CSV, a PNG and a JSON that parse and agree with each other, and
//! `bench compare` reads two of them.

use std::path::Path;
use std::process::Command;

use gpuwars::benchmark::Spread;
use gpuwars::benchmark::paper::PaperSummary;
use gpuwars::benchmark::scale::{self, ScaleRow, ScaleSummary};
use gpuwars::camera::CameraMode;
use gpuwars::meter::Second;
use proptest::prelude::*;

fn gpuwars(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu"])
        .args(args)
        .output()
        .expect("the binary runs")
}

fn ok(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn rows<T: serde::de::DeserializeOwned>(path: &Path) -> Vec<T> {
    csv::Reader::from_path(path)
        .unwrap()
        .deserialize()
        .collect::<Result<_, _>>()
        .unwrap()
}

fn plot_size(path: &Path) -> (u32, u32) {
    let plot = image::open(path).unwrap();
    (plot.width(), plot.height())
}

fn paper_run(dir: &Path, seed: &str) -> PaperSummary {
    paper_run_with(dir, seed, &[])
}

/// A short `bench paper` into `dir` with `more` flags.
fn paper_run_with(dir: &Path, seed: &str, more: &[&str]) -> PaperSummary {
    let mut args = vec![
        "bench",
        "paper",
        "--minutes",
        "0.04",
        "--size",
        "320x180",
        "--seed",
        seed,
        "--out",
        dir.to_str().unwrap(),
        "--json",
    ];
    args.extend(more);
    let out = ok(&gpuwars(&args));
    let printed: PaperSummary = serde_json::from_str(&out).unwrap();
    let written: PaperSummary =
        serde_json::from_slice(&std::fs::read(dir.join("bench-paper.json")).unwrap()).unwrap();
    assert_eq!(printed, written);
    written
}

/// A short `bench scale` up to `max` enemies into `dir` with `more` flags: what it prints.
fn scale_run(dir: &Path, max: &str, more: &[&str]) -> String {
    let mut args = vec![
        "bench",
        "scale",
        "--max",
        max,
        "--seconds",
        "0.05",
        "--size",
        "320x180",
        "--out",
        dir.to_str().unwrap(),
        "--json",
    ];
    args.extend(more);
    ok(&gpuwars(&args))
}

#[test]
fn bench_paper_writes_a_table_a_plot_and_a_summary_that_agree() {
    let dir = tempfile::tempdir().unwrap();
    let summary = paper_run(dir.path(), "1");
    let seconds: Vec<Second> = rows(&dir.path().join("bench-paper.csv"));
    assert_eq!(seconds.len() as u32, summary.seconds);
    assert!(summary.seconds >= 2, "{summary:?}");
    assert_eq!(
        seconds.iter().map(|s| s.second).collect::<Vec<_>>(),
        (1..=summary.seconds).collect::<Vec<_>>()
    );
    assert_eq!(
        summary.frames_per_s,
        Spread::of(seconds.iter().map(|s| s.frames_per_s))
    );
    // Frames counted second by second add up to the frames drawn (each second's rate is
    // its frames over a little more than a second).
    let counted: f64 = seconds.iter().map(|s| s.frames_per_s).sum();
    assert!(
        counted <= summary.frames as f64 + 1.0,
        "{counted} {summary:?}"
    );
    for s in &seconds {
        assert!(s.frames_per_s > 0.0 && s.enemies_alive > 0 && s.step_us > 0.0);
        assert!(s.master_us + s.physics_us + s.ai_us <= s.step_us * 1.0001);
    }
    assert!(summary.sim_only_steps_per_s > 0.0);
    assert_eq!(summary.machine.backend, "cpu");
    assert_eq!(summary.camera, CameraMode::Field);
    assert_eq!(plot_size(&dir.path().join("bench-paper.png")), (1280, 720));
}

/// The view a player sees by default, the ship followed with the radar, measured when
/// asked; a window's frames are `play`'s, so the two flags are refused together.
#[test]
fn bench_paper_measures_the_followed_view_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let summary = paper_run_with(dir.path(), "1", &["--camera", "follow"]);
    assert_eq!(summary.camera, CameraMode::Follow);
    assert!(
        summary.frames > 0 && summary.render_us.median > 0.0,
        "{summary:?}"
    );
    let out = gpuwars(&["bench", "paper", "--camera", "follow", "--window"]);
    assert!(!out.status.success());
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(
        text.contains("--camera") && text.contains("--window"),
        "{text}"
    );
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "drives the window with Linux tools (xvfb-run, xdotool): scripts/windows-check plays a Wine window instead"
)]
fn bench_paper_runs_in_the_window_too() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_gpuwars"))
        .args([
            "--backend",
            "cpu",
            "bench",
            "paper",
            "--window",
            "--minutes",
            "0.04",
            "--size",
            "320x180",
            "--json",
            "--out",
        ])
        .arg(dir.path())
        .env("GPUWARS_DATA_DIR", dir.path())
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs (see scripts/setup)");
    let summary: PaperSummary = serde_json::from_str(&ok(&out)).unwrap();
    let seconds: Vec<Second> = rows(&dir.path().join("bench-paper.csv"));
    // The window shows `play`'s view, and the summary says so.
    assert_eq!(summary.camera, CameraMode::Follow);
    assert_eq!(seconds.len() as u32, summary.seconds);
    assert!(
        summary.seconds >= 2 && summary.frames_per_s.median > 0.0,
        "{summary:?}"
    );
    // The window's frames are timed too: the renderer's device work and GL's part.
    assert!(seconds.iter().all(|s| s.render_us > 0.0 && s.gl_us > 0.0));
}

#[test]
fn bench_scale_measures_each_size_and_compare_reads_two_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = scale_run(dir.path(), "3000", &[]);
    let summary: ScaleSummary = serde_json::from_str(&out).unwrap();
    let table: Vec<ScaleRow> = rows(&dir.path().join("bench-scale.csv"));
    assert_eq!(table, summary.rows);
    let sizes: Vec<u64> = table.iter().map(|r| r.enemies).collect();
    assert_eq!(sizes, [1024, 2048, 3000]);
    for r in &table {
        assert!(r.steps_per_s > 0.0 && r.frames_per_s > 0.0 && r.bytes_per_step > 0);
        assert!(r.floor_us > 0.0);
        // Medians of timed rounds, inside their spreads.
        assert!(r.steps_per_s_low <= r.steps_per_s && r.steps_per_s <= r.steps_per_s_high);
        assert!(r.frames_per_s_low <= r.frames_per_s && r.frames_per_s <= r.frames_per_s_high);
        let rate = r.bytes_per_step as f64 / (r.step_us / 1e6);
        assert!((r.achieved_bandwidth - rate).abs() <= rate * 1e-9);
        assert!((r.fraction_of_copy - rate / summary.copy_bandwidth).abs() < 1e-9);
    }
    assert_eq!(plot_size(&dir.path().join("bench-scale.png")), (1280, 720));
    // The whole field unless asked; a summary from before the choice reads as that.
    assert_eq!(summary.camera, CameraMode::Field);
    let mut older: serde_json::Value = serde_json::from_str(&out).unwrap();
    older.as_object_mut().unwrap().remove("camera");
    let older: ScaleSummary = serde_json::from_value(older).unwrap();
    assert_eq!(older.camera, CameraMode::Field);
    // The view a player sees, measured as asked.
    let followed = tempfile::tempdir().unwrap();
    let out = scale_run(followed.path(), "1024", &["--camera", "follow"]);
    let summary: ScaleSummary = serde_json::from_str(&out).unwrap();
    assert_eq!(summary.camera, CameraMode::Follow);
    assert!(summary.rows.iter().all(|r| r.frames_per_s > 0.0));
    // A run against itself: each size's rates are medians inside both spreads, marked so.
    let scale_json = dir.path().join("bench-scale.json");
    let scale_json = scale_json.to_str().unwrap();
    let text = ok(&gpuwars(&["bench", "compare", scale_json, scale_json]));
    for figure in ["steps_per_s", "frames_per_s"] {
        let line = (text.lines())
            .find(|l| l.contains(&format!("rows[enemies=1024].{figure} ")))
            .unwrap_or_else(|| panic!("{figure}: {text}"));
        assert!(line.ends_with(" ≈"), "{line}");
    }

    // Compare: two runs of one benchmark, figure by figure; two benchmarks are refused.
    let other = tempfile::tempdir().unwrap();
    paper_run(dir.path(), "1");
    paper_run(other.path(), "2");
    let (a, b) = (
        dir.path().join("bench-paper.json"),
        other.path().join("bench-paper.json"),
    );
    let text = ok(&gpuwars(&[
        "bench",
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
    ]));
    assert!(text.contains("frames_per_s.median"), "{text}");
    let mixed = gpuwars(&[
        "bench",
        "compare",
        a.to_str().unwrap(),
        dir.path().join("bench-scale.json").to_str().unwrap(),
    ]);
    assert_eq!(mixed.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&mixed.stderr).contains("cannot be compared"));
    let bogus = gpuwars(&["bench", "compare", a.to_str().unwrap(), "Cargo.toml"]);
    assert!(String::from_utf8_lossy(&bogus.stderr).contains("Cargo.toml:1"));
}

#[test]
fn scaled_scenes_keep_the_papers_mix_and_density() {
    for enemies in [1024u64, 8192, 1 << 20, 3000, scale::MAX_ENEMIES] {
        let scene = scale::scene(enemies).unwrap();
        let waves = &scene.game.spawn.waves;
        let total: u64 = waves.iter().map(|w| u64::from(w.count)).sum();
        assert_eq!(total, enemies);
        // A quarter polygons, an eighth of each of the six other types.
        let polygons = waves.iter().find(|w| w.kind == "polygon").unwrap().count;
        assert_eq!(u64::from(polygons), enemies / 4);
        let area = f64::from(scene.world.size.x) * f64::from(scene.world.size.y);
        let density = enemies as f64 / area;
        let paper = 8192.0 / (4096.0 * 4096.0);
        assert!((density / paper - 1.0).abs() < 1e-3, "{enemies}: {density}");
    }
    assert!(scale::scene(1000).is_err());
    assert!(scale::scene(scale::MAX_ENEMIES + 8).is_err());
}

proptest! {
    #[test]
    fn spread_is_the_sorted_series_extremes_and_middle(values in prop::collection::vec(-1e6f64..1e6, 1..50)) {
        let s = Spread::of(values.iter().copied());
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        prop_assert_eq!(s.min, sorted[0]);
        prop_assert_eq!(s.max, sorted[n - 1]);
        let below = sorted.iter().filter(|&&v| v < s.median).count();
        let above = sorted.iter().filter(|&&v| v > s.median).count();
        prop_assert!(below <= n / 2 && above <= n / 2);
        let mean = values.iter().sum::<f64>() / n as f64;
        prop_assert!((s.mean - mean).abs() <= 1e-9 * mean.abs().max(1.0));
    }
}

/// Runs `bench compare A B` on two summaries written from `a` and `b`.
fn compare(a: &str, b: &str) -> std::process::Output {
    let dir = tempfile::tempdir().unwrap();
    let (pa, pb) = (dir.path().join("a.json"), dir.path().join("b.json"));
    std::fs::write(&pa, a).unwrap();
    std::fs::write(&pb, b).unwrap();
    gpuwars(&[
        "bench",
        "compare",
        pa.to_str().unwrap(),
        pb.to_str().unwrap(),
    ])
}

fn compare_error(a: &str, b: &str) -> String {
    let out = compare(a, b);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    for jargon in ["EOF", "os error", "column", "panicked"] {
        assert!(!stderr.contains(jargon), "{stderr}");
    }
    stderr
}

#[test]
fn compare_refuses_figures_that_are_not_numbers_and_prints_what_means_something() {
    let summary = |median: &str| {
        format!(r#"{{"benchmark": "paper", "frames_per_s": {{"median": {median}, "p5": 2}}}}"#)
    };
    let stderr = compare_error(&summary("60"), &summary("\"abc\""));
    assert!(
        stderr.contains("b.json: frames_per_s.median: not a number (found \"abc\")"),
        "{stderr}"
    );
    let stderr = compare_error(&summary("null"), &summary("60"));
    assert!(
        stderr.contains("a.json: frames_per_s.median: not a number"),
        "{stderr}"
    );
    let stderr = compare_error(&summary("1e400"), &summary("60"));
    assert!(stderr.contains("a number too large to read"), "{stderr}");
    let stderr = compare_error("{\"benchmark\": ", &summary("60"));
    assert!(
        stderr.contains("a.json:1: not a benchmark summary: the text ends"),
        "{stderr}"
    );
    let stderr = compare_error(&summary("60"), &summary("-60"));
    assert!(
        stderr.contains("b.json: frames_per_s.median: -60.000 is below 0"),
        "{stderr}"
    );
    // A vanishing or zero figure has no change in percent; huge ones are readable (a
    // figure that may be negative, which a rate may not).
    let summary = |median: &str| {
        format!(r#"{{"benchmark": "paper", "drift": {{"median": {median}, "p5": 2}}}}"#)
    };
    for (a, b) in [("5e-324", "1"), ("0", "1"), ("-1e308", "1e308")] {
        let out = compare(&summary(a), &summary(b));
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text
            .lines()
            .find(|l| l.starts_with("drift.median"))
            .unwrap_or_else(|| panic!("{text}"));
        assert!(line.len() < 80, "{line}");
        assert!(!line.contains("inf"), "{line}");
        if a != "-1e308" {
            assert!(line.ends_with("n/a"), "{line}");
        } else {
            assert!(
                line.contains("-1.000e308") && line.ends_with("+200.0%"),
                "{line}"
            );
        }
    }
}

#[test]
fn compare_reads_only_regular_files_of_a_bounded_size() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.json");
    std::fs::write(&a, r#"{"benchmark": "paper"}"#).unwrap();
    let a = a.to_str().unwrap();
    let refused = |other: &str, says: &str| {
        let out = gpuwars(&["bench", "compare", a, other]);
        assert_eq!(out.status.code(), Some(1));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(says), "{stderr}");
        assert!(!stderr.contains("os error"), "{stderr}");
    };
    // Devices as files in a folder are Unix's (`/dev`).
    if cfg!(unix) {
        refused("/dev/zero", "it is a device");
    }
    refused(dir.path().to_str().unwrap(), "it is a folder");
    refused("/no/such.json", "no such file");
    let pipe = dir.path().join("pipe");
    if Command::new("mkfifo")
        .arg(&pipe)
        .status()
        .is_ok_and(|s| s.success())
    {
        refused(pipe.to_str().unwrap(), "it is a named pipe");
    }
}
