//! The `gpuwars` command as a user runs it.

use std::process::Command;

use gpuwars::kernels::registry;
use serde_json::Value;

fn gpuwars(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(args)
        .env_remove("GPUWARS_BACKEND")
        .env_remove("GPUWARS_CPU_THREADS")
        .output()
        .expect("the binary runs")
}

fn gpu_present() -> bool {
    gpuwars::Device::cuda("probe").is_ok()
}

fn info_json(args: &[&str]) -> Value {
    let out = gpuwars(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("info --json prints JSON")
}

#[test]
fn info_json_on_the_cpu_names_the_backend_the_reason_and_every_kernel() {
    let info = info_json(&["info", "--json", "--backend", "cpu", "--cpu-threads", "3"]);
    assert_eq!(info["backend"], "cpu");
    assert!(
        info["backend_reason"]
            .as_str()
            .unwrap()
            .contains("--backend cpu")
    );
    assert_eq!(info["cpu_threads"], 3);
    assert_eq!(info["version"], env!("CARGO_PKG_VERSION"));
    let mut entries: Vec<&str> = info["ptx"]["entry_points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let mut kernels: Vec<&str> = registry::ALL.iter().map(|k| k.name).collect();
    entries.sort_unstable();
    kernels.sort_unstable();
    assert_eq!(entries, kernels);
    assert_eq!(info["ptx"]["missing_kernels"], Value::Array(vec![]));
    assert!(info["ptx"]["bytes"].as_u64().unwrap() > 1000);
}

#[test]
fn auto_picks_the_gpu_when_there_is_one_and_says_why_when_not() {
    let out = gpuwars(&["info", "--json"]);
    assert!(out.status.success());
    let info: Value = serde_json::from_slice(&out.stdout).unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    if gpu_present() {
        assert_eq!(info["backend"], "cuda");
        assert!(info["device"]["name"].as_str().is_some());
    } else {
        assert_eq!(info["backend"], "cpu");
        let reason = info["backend_reason"].as_str().unwrap();
        assert!(!reason.is_empty());
        // Said once, on stderr.
        assert_eq!(
            stderr
                .matches("running the kernels on the CPU emulation")
                .count(),
            1,
            "{stderr}"
        );
        assert!(stderr.contains(reason), "{stderr}");
    }
}

#[test]
fn the_environment_variable_selects_the_backend() {
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["info", "--json"])
        .env("GPUWARS_BACKEND", "cpu")
        .output()
        .unwrap();
    let info: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(info["backend"], "cpu");
}

#[test]
fn asking_for_cuda_without_a_gpu_is_a_clear_error() {
    if gpu_present() {
        eprintln!("skipped: a GPU is present");
        return;
    }
    let out = gpuwars(&["info", "--backend", "cuda"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the CUDA backend is not available"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn bad_flags_name_the_allowed_values() {
    let out = gpuwars(&["info", "--backend", "gpu"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("possible values: auto, cuda, cpu"),
        "{stderr}"
    );
    let out = gpuwars(&["info", "--cpu-threads", "0"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("allowed a whole number from 1 to 1,024"),
        "{stderr}"
    );
    let out = gpuwars(&["demo", "--lanes", "3"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("allowed: auto, 1, 2, 4, 8, 16 or 32"),
        "{stderr}"
    );
}

/// A flag the windowed replay cannot honour is refused before anything is read or opened,
/// not silently ignored.
#[test]
fn a_windowed_replay_refuses_the_headless_run_flags() {
    for flag in [&["--lanes", "8"][..], &["--no-graphs"], &["--profile"]] {
        let mut args = vec!["replay", "no-such-file.json", "--window"];
        args.extend_from_slice(flag);
        let out = gpuwars(&args);
        assert!(!out.status.success(), "{flag:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("apply to a headless replay, not to --window"),
            "{flag:?}: {stderr}"
        );
    }
}

#[test]
fn text_info_names_the_backend() {
    let out = gpuwars(&["info", "--backend", "cpu"]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with(&format!("gpuwars {}", env!("CARGO_PKG_VERSION"))),
        "{stdout}"
    );
    assert!(stdout.contains("backend:      cpu"), "{stdout}");
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "Windows always has its desktop: the bare command plays there"
)]
fn with_no_display_the_default_command_is_the_headless_demo() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("last.png");
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("GPUWARS_SCENE", "kamikaze")
        .env("GPUWARS_STEPS", "30")
        .env("GPUWARS_SCREENSHOT", &shot)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("scene:            kamikaze"), "{stdout}");
    assert!(stdout.contains("steps:            30 "), "{stdout}");
    // Its last frame, and where it went.
    assert!(
        stdout.contains(&format!("screenshot:       {}", shot.display())),
        "{stdout}"
    );
    assert_eq!(image::open(&shot).unwrap().width(), 1920);
    // The environment picks its camera: the whole field is another picture of the game.
    let field = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("GPUWARS_SCENE", "kamikaze")
        .env("GPUWARS_STEPS", "30")
        .env("GPUWARS_SCREENSHOT", &shot)
        .env("GPUWARS_CAMERA", "field")
        .output()
        .unwrap();
    let line = |out: &[u8], key: &str| {
        let text = String::from_utf8_lossy(out).into_owned();
        text.lines().find(|l| l.starts_with(key)).map(str::to_owned)
    };
    let field_out = &field.stdout;
    assert_eq!(
        line(field_out, "state_hash:"),
        line(&out.stdout, "state_hash:")
    );
    assert_ne!(line(field_out, "frame:"), line(&out.stdout, "frame:"));
}

#[test]
fn scenes_lists_every_built_in_scene() {
    let out = gpuwars(&["scenes"]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = stdout
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    let built_in: Vec<&str> = gpuwars::game::scene::BUILT_IN
        .iter()
        .map(|b| b.name)
        .collect();
    assert_eq!(names, built_in);
    assert!(built_in.contains(&"paper"));
}

fn demo_json(args: &[&str]) -> Value {
    let mut all = vec!["demo", "--backend", "cpu", "--json"];
    all.extend_from_slice(args);
    info_json(&all)
}

#[test]
fn demo_prints_every_figure_and_is_repeatable() {
    let report = demo_json(&["--scene", "kamikaze", "--steps", "120", "--seed", "4"]);
    for key in [
        "backend",
        "device",
        "scene",
        "seed",
        "steps",
        "sim_steps_per_s",
        "state_hash",
        "score",
        "enemies_alive",
        "enemies_killed",
        "fps_meter",
        "game_over",
    ] {
        assert!(!report[key].is_null(), "{key} missing from {report}");
    }
    assert_eq!(report["backend"], "cpu");
    assert_eq!(report["scene"], "kamikaze");
    assert_eq!(report["seed"], 4);
    assert_eq!(report["steps"], 120);
    assert_eq!(report["game_over"], false);
    assert!(report["sim_steps_per_s"].as_f64().unwrap() > 0.0);
    let hash = report["state_hash"].as_str().unwrap();
    assert!(hash.len() == 18 && hash.starts_with("0x"), "{hash}");
    let again = demo_json(&["--scene", "kamikaze", "--steps", "120", "--seed", "4"]);
    assert_eq!(again["state_hash"], report["state_hash"]);
    let other = demo_json(&["--scene", "kamikaze", "--steps", "120", "--seed", "5"]);
    assert_ne!(other["state_hash"], report["state_hash"]);
}

#[test]
fn demo_profiles_every_stage_and_runs_the_same_game() {
    let args = ["--scene", "paper", "--steps", "30", "--seed", "2"];
    let plain = demo_json(&args);
    let mut with = args.to_vec();
    with.push("--profile");
    let profiled = demo_json(&with);
    // Stage by stage, the same kernels in the same order: the same game.
    assert_eq!(profiled["state_hash"], plain["state_hash"]);
    let profile = &profiled["profile"];
    assert_eq!(profile["steps"], 30);
    assert!(profile["copy_bandwidth"].as_f64().unwrap() > 0.0);
    // A copy as large as each stage's run, for every stage.
    let copies = profile["stage_copies"].as_array().unwrap();
    assert_eq!(copies.len(), profile["stages"].as_array().unwrap().len());
    assert!(
        copies.iter().all(|c| c.as_f64().unwrap() > 0.0),
        "{copies:?}"
    );
    let stages: Vec<&str> = profile["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["stage"].as_str().unwrap())
        .collect();
    // `paper` has every stage of the pipeline, in the pipeline's order, but `substeps` (it
    // takes one substep a step) and `births` (in a world this small, inside the broad
    // phase's first launch).
    let every: Vec<&str> = (gpuwars::pipeline::Stage::ALL.iter())
        .map(|s| s.name())
        .filter(|&s| s != "substeps" && s != "births")
        .collect();
    assert_eq!(stages, every);
    // A step launches every stage's kernels but the renumbering's, which runs every 16th.
    let launches = |renumber: bool| -> u64 {
        (profile["stages"].as_array().unwrap().iter())
            .filter(|s| (s["stage"] == "renumber") == renumber)
            .map(|s| s["launches"].as_u64().unwrap())
            .sum()
    };
    assert_eq!(
        launches(false),
        plain["launches_per_step"].as_u64().unwrap()
    );
    assert_eq!(launches(true), 2);
    // The stages with a thread a slot read at least one word of every slot.
    let slots = profile["floor"]["threads"].as_u64().unwrap();
    assert!(slots >= 8192, "{slots} slots");
    for s in profile["stages"].as_array().unwrap() {
        if ["births", "broad", "narrow", "integrate", "free"]
            .contains(&s["stage"].as_str().unwrap())
        {
            assert!(s["bytes"].as_u64().unwrap() >= 4 * slots, "{s}");
        }
    }
    // The launch floor: the step's launches over its slots, measured in the same run.
    assert_eq!(profile["floor"]["launches"], plain["launches_per_step"]);
    // (`paper`'s 8,288 slots are few enough for the one-block floor.)
    for variant in ["graph_s", "stream_s", "one_block_s", "ring_s"] {
        assert!(
            profile["floor"][variant].as_f64().unwrap() > 0.0,
            "{variant}"
        );
    }
    // Every status read back at once, or four steps late: the same game.
    let lagged = demo_json(&[
        "--scene", "paper", "--steps", "30", "--seed", "2", "--lag", "1",
    ]);
    assert_eq!(lagged["state_hash"], plain["state_hash"]);
    assert!(plain.get("profile").is_none());
}

#[test]
fn demo_takes_a_scene_file_and_names_the_line_of_a_bad_one() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("mine.toml");
    let source = gpuwars::game::scene::BUILT_IN[1]
        .source
        .replace("name = \"kamikaze\"", "name = \"mine\"");
    std::fs::write(&good, &source).unwrap();
    let report = demo_json(&["--scene", good.to_str().unwrap(), "--steps", "10"]);
    assert_eq!(report["scene"], "mine");

    let bad = dir.path().join("bad.toml");
    let broken = source.replace("capacity = 128", "capacity = 0");
    let line = broken.lines().position(|l| l == "capacity = 0").unwrap() + 1;
    std::fs::write(&bad, &broken).unwrap();
    let out = gpuwars(&["demo", "--backend", "cpu", "--scene", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!(
            "bad.toml:{line}: kinds[2].capacity: 0 is out of range"
        )),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_recorded_demo_replays_to_the_same_hash_and_a_tampered_one_fails() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("game.replay.json");
    let path = file.to_str().unwrap();
    let report = demo_json(&["--scene", "group", "--steps", "150", "--record", path]);
    let replayed = info_json(&["replay", path, "--backend", "cpu", "--json"]);
    assert_eq!(replayed["state_hash"], report["state_hash"]);
    assert_eq!(replayed["steps"], 150);

    let text = std::fs::read_to_string(&file).unwrap();
    let hash = report["state_hash"].as_str().unwrap();
    std::fs::write(&file, text.replace(hash, "0x0000000000000001")).unwrap();
    let out = gpuwars(&["replay", path, "--backend", "cpu"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("recorded ending in 0x0000000000000001"),
        "{stderr}"
    );

    // Watching needs a display (Unix's: Windows always has its desktop); without one, the
    // error says how to check it headless.
    if cfg!(unix) {
        let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
            .args(["--backend", "cpu", "replay", path, "--window"])
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("no display")
                && stderr.contains(&format!("`gpuwars replay {path}` (without --window)")),
            "{stderr}"
        );
    }
    // The window's options need --window.
    let out = gpuwars(&["replay", path, "--render", "interop"]);
    assert_eq!(out.status.code(), Some(2));

    std::fs::write(&file, &text[..text.len() / 2]).unwrap();
    let out = gpuwars(&["replay", path, "--backend", "cpu"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("game.replay.json:"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn demo_writes_a_screenshot_of_the_final_state() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shot.png");
    let shot = path.to_str().unwrap();
    let args = ["--scene", "kamikaze", "--steps", "40", "--screenshot", shot];
    let report = demo_json(&[&args[..], &["--size", "64x48"]].concat());
    let image = image::open(&path).unwrap().to_rgba8();
    assert_eq!(image.dimensions(), (64, 48));
    let hash = report["frame_hash"].as_str().unwrap();
    assert!(hash.starts_with("0x") && hash.len() == 18, "{hash}");
    // The same game draws the same frame.
    let again = demo_json(&[&args[..], &["--size", "64x48"]].concat());
    assert_eq!(again["frame_hash"], report["frame_hash"]);
    // Only the temporary file's rename leaves a file: nothing else in the folder.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // Another camera draws another frame of the same game.
    let sized = [&args[..], &["--size", "64x48"]].concat();
    for camera in [&["--camera", "field"][..], &["--zoom", "8"]] {
        let other = demo_json(&[&sized[..], camera].concat());
        assert_eq!(other["state_hash"], report["state_hash"], "{camera:?}");
        assert_ne!(other["frame_hash"], report["frame_hash"], "{camera:?}");
    }
    for bad in ["0x48", "64", "64x99999", "ax3"] {
        let out = gpuwars(&[
            "demo",
            "--backend",
            "cpu",
            "--screenshot",
            shot,
            "--size",
            bad,
        ]);
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("WIDTHxHEIGHT") && stderr.contains("16,384"),
            "{stderr}"
        );
    }
}

#[test]
fn demo_writes_numbered_frames_and_plays_the_same_game() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().to_str().unwrap();
    let args = ["--scene", "kamikaze", "--steps", "30", "--seed", "3"];
    let plain = demo_json(&args);
    let framed = demo_json(
        &[
            &args[..],
            &["--frames-every", "10", folder, "--size", "32x24"],
        ]
        .concat(),
    );
    assert_eq!(framed["state_hash"], plain["state_hash"]);
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["frame-000010.png", "frame-000020.png", "frame-000030.png"]
    );
    let frame = image::open(dir.path().join("frame-000020.png")).unwrap();
    assert_eq!((frame.width(), frame.height()), (32, 24));
    for (every, folder, says) in [
        ("0", folder, "--frames-every: N: out of range"),
        (
            "5",
            "/no/such/folder",
            "the folder /no/such/folder does not exist",
        ),
    ] {
        let out = gpuwars(&["demo", "--backend", "cpu", "--frames-every", every, folder]);
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(says), "{stderr}");
    }
}

/// Runs `gpuwars --backend cpu ARGS`, which must fail with exit code `code` and, on stderr,
/// each of `says`, and no panic.
fn refused(args: &[&str], code: i32, says: &[&str]) -> String {
    let mut all = vec!["--backend", "cpu"];
    all.extend_from_slice(args);
    let start = std::time::Instant::now();
    let out = gpuwars(&all);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "{args:?}: {stderr}");
    for part in says {
        assert!(stderr.contains(part), "{args:?}: {stderr:?} lacks {part:?}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    // Refused at once, not after a game.
    assert!(
        start.elapsed().as_secs() < 20,
        "{args:?} took {:?}",
        start.elapsed()
    );
    stderr
}

#[test]
fn outputs_replace_only_regular_files_and_are_checked_before_the_game() {
    let dir = tempfile::tempdir().unwrap();
    // Named as a screenshot is (a PNG), so that only its being a folder is wrong.
    let folder = dir.path().join("folder.png");
    std::fs::create_dir(&folder).unwrap();
    let folder = folder.to_str().unwrap();
    // A billion steps: refused at once, not after the game, because of the output.
    let steps = ["demo", "--steps", "1000000"];
    for flag in ["--record", "--screenshot"] {
        let args = [&steps[..], &[flag, folder]].concat();
        refused(&args, 1, &["cannot write: it is a folder, left as it is"]);
    }
    // A screenshot is a PNG: a name for another format is refused before the game, in
    // any case of the extension but `.png`'s.
    for name in ["shot.jpg", "shot", "shot.png.bak", ".png"] {
        let shot = dir.path().join(name);
        let args = [&steps[..], &["--screenshot", shot.to_str().unwrap()]].concat();
        refused(
            &args,
            2,
            &["not a PNG file's name (allowed a name ending in .png)"],
        );
        assert!(!shot.exists());
    }
    assert!(gpuwars::cli::parse_from(["gpuwars", "demo", "--screenshot", "SHOT.PNG"]).is_ok());
    let missing = dir.path().join("missing").join("game.json");
    let args = [&steps[..], &["--record", missing.to_str().unwrap()]].concat();
    refused(&args, 1, &["does not exist"]);
    // Symbolic links (Windows keeps them for administrators, and Wine shows them as files)
    // and named pipes as files in a folder are Unix's.
    #[cfg(unix)]
    {
        let target = dir.path().join("target.json");
        std::fs::write(&target, "kept").unwrap();
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let args = [&steps[..], &["--record", link.to_str().unwrap()]].concat();
        refused(&args, 1, &["symbolic link", "remove the link first"]);
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "kept");
        let pipe = dir.path().join("pipe.json");
        if Command::new("mkfifo")
            .arg(&pipe)
            .status()
            .is_ok_and(|s| s.success())
        {
            let args = [&steps[..], &["--record", pipe.to_str().unwrap()]].concat();
            refused(&args, 1, &["it is a named pipe, left as it is"]);
        }
        // A folder that is there but takes no new file (Linux's /proc, even for root), for
        // a file or for frames: refused before the game, naming the folder.
        if cfg!(target_os = "linux") {
            let args = [&steps[..], &["--record", "/proc/gpuwars.json"]].concat();
            refused(
                &args,
                1,
                &["no file can be made in the folder /proc", "--record"],
            );
            let args = [&steps[..], &["--frames-every", "60", "/proc"]].concat();
            refused(&args, 1, &["no file can be made in the folder /proc"]);
        }
    }
    let mut left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    left.retain(|name| name != "pipe.json");
    let expected: &[&str] = match cfg!(unix) {
        true => &["folder.png", "link.json", "target.json"],
        false => &["folder.png"],
    };
    assert_eq!(left, expected, "nothing is left behind");
}

#[test]
fn inputs_that_would_hang_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().to_str().unwrap();
    refused(&["demo", "--scene", folder], 1, &["it is a folder"]);
    // Devices as files in a folder are Unix's (`/dev`).
    if cfg!(unix) {
        refused(&["demo", "--scene", "/dev/zero"], 1, &["it is a device"]);
        refused(&["replay", "/dev/zero"], 1, &["it is a device"]);
    }
    let pipe = dir.path().join("pipe");
    if Command::new("mkfifo")
        .arg(&pipe)
        .status()
        .is_ok_and(|s| s.success())
    {
        let pipe = pipe.to_str().unwrap();
        refused(&["demo", "--scene", pipe], 1, &["it is a named pipe"]);
        refused(&["replay", pipe], 1, &["it is a named pipe"]);
    }
    // A replay of a billion steps: refused before its inputs are allocated.
    let file = dir.path().join("billion.json");
    let replay = gpuwars::game::replay::Replay {
        version: gpuwars::game::replay::VERSION,
        scene: "kamikaze".into(),
        scene_toml: gpuwars::game::scene::BUILT_IN[1].source.into(),
        seed: 1,
        backend: gpuwars::BackendKind::Cpu,
        state_hash: 0,
        inputs: Vec::new(),
    };
    let text = replay
        .to_json()
        .replace("\"steps\": 0", "\"steps\": 1000000000")
        .replace("\"inputs\": []", "\"inputs\": [[1000000000, 0, 0, 0, 0]]");
    std::fs::write(&file, text).unwrap();
    refused(
        &["replay", file.to_str().unwrap()],
        1,
        &["steps: 1000000000 is out of range (allowed 0 to 1,000,000)"],
    );
    // A world of more slots than any device takes.
    let scene = dir.path().join("huge.toml");
    let source = gpuwars::game::scene::BUILT_IN[1]
        .source
        .replace("capacity = 128", "capacity = 16777216");
    std::fs::write(&scene, source).unwrap();
    refused(
        &["demo", "--scene", scene.to_str().unwrap()],
        1,
        &["slots in all (allowed at most 16,777,216"],
    );
}

#[test]
fn flag_values_are_checked_in_words() {
    let cases: [(&[&str], &str); 11] = [
        (
            &["demo", "--steps", "0"],
            "allowed a whole number from 1 to 1,000,000",
        ),
        (
            &["demo", "--steps", "1000001"],
            "allowed a whole number from 1 to 1,000,000",
        ),
        (&["demo", "--steps", "many"], "not a whole number"),
        (&["demo", "--seed", "4294967296"], "from 0 to 4,294,967,295"),
        (&["demo", "--seed", "1.5"], "not a whole number"),
        (&["demo", "--lag", "0"], "from 1 to 1,024"),
        (&["replay", "x.json", "--lag", "2000"], "from 1 to 1,024"),
        (&["demo", "--size", "0x10"], "WIDTHxHEIGHT"),
        (&["demo", "--zoom", "9"], "allowed a number from 0.001 to 8"),
        (&["demo", "--zoom", "near"], "not a number"),
        (&["demo", "--camera", "sky"], "follow, field"),
    ];
    for (args, says) in cases {
        let stderr = refused(args, 2, &[says]);
        for rust in ["..=", "invalid digit", "ParseIntError", "u64", "u32", "u16"] {
            assert!(!stderr.contains(rust), "{stderr} speaks of `{rust}`");
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path().to_str().unwrap();
    refused(
        &["demo", "--frames-every", "0", dir],
        1,
        &["--frames-every: N: out of range (allowed a whole number from 1 to 1,000,000)"],
    );
    refused(
        &["demo", "--frames-every", "1", "/dev/null"],
        1,
        &["is not a folder"],
    );
}

#[test]
fn a_large_world_on_the_cpu_says_its_size_before_it_is_allocated() {
    let out = tempfile::tempdir().unwrap();
    let out = out.path().to_str().unwrap();
    for command in [
        &["demo", "--scene", "scale-16m", "--steps", "1"][..],
        &["tradeoff", "--quick", "--scene", "scale-16m", "--out", out],
    ] {
        says_its_size_first(command);
    }
}

/// Starts `gpuwars --backend cpu ARGS`, whose first line on stderr must say the size of
/// `scale-16m`'s world, and stops it there.
fn says_its_size_first(args: &[&str]) {
    use std::io::BufRead;
    let mut child = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu"])
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    let stderr = child.stderr.take().unwrap();
    std::io::BufReader::new(stderr)
        .read_line(&mut first)
        .unwrap();
    // The world itself (seconds a step here) is not waited for.
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        first.starts_with("gpuwars: scene `scale-16m` has 16,760,160 slots, which take"),
        "{first}"
    );
    assert!(first.contains("GB of host memory"), "{first}");
}

#[test]
fn an_output_never_replaces_an_input_or_another_output() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let scene = path("k.toml");
    let source = gpuwars::game::scene::BUILT_IN[1].source;
    std::fs::write(&scene, source).unwrap();
    // A symbolic link where anyone may make one; Windows keeps them for administrators (and
    // Wine shows them as files), so there a second hard link stands in.
    #[cfg(unix)]
    std::os::unix::fs::symlink(&scene, path("link.toml")).unwrap();
    #[cfg(not(unix))]
    std::fs::hard_link(&scene, path("link.toml")).unwrap();
    std::fs::hard_link(&scene, path("hard.toml")).unwrap();
    // A scene file named as a screenshot is, so that only the collision is wrong.
    std::fs::write(path("k.png"), source).unwrap();
    let long = ["demo", "--steps", "1000000", "--scene"];
    let cases: [(&[&str], &str, &str); 6] = [
        (&[&scene, "--record", &scene], "--record", "--scene"),
        (
            &[&path("k.png"), "--screenshot", &path("k.png")],
            "--screenshot",
            "--scene",
        ),
        (
            &[&path("link.toml"), "--record", &scene],
            "--record",
            "--scene",
        ),
        (
            &[&scene, "--record", &path("hard.toml")],
            "--record",
            "--scene",
        ),
        (
            &[
                "paper",
                "--record",
                &path("x.png"),
                "--screenshot",
                &path("x.png"),
            ],
            "--screenshot",
            "--record",
        ),
        (
            &[
                "paper",
                "--record",
                &path("x.png"),
                "--screenshot",
                &format!("{}/./x.png", dir.path().display()),
            ],
            "--screenshot",
            "--record",
        ),
    ];
    for (args, output, input) in cases {
        let args = [&long[..], args].concat();
        let says = format!("cannot write ({output}): it is the same file as {input}");
        refused(&args, 1, &[&says, &format!("give {output} another path")]);
    }
    // A frame lands on a file of the run named like one.
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let frame = frames.join("frame-000060.png");
    std::fs::write(&frame, source).unwrap();
    let (frames, frame) = (frames.to_str().unwrap(), frame.to_str().unwrap());
    for args in [
        &["--scene", frame, "--frames-every", "60", frames][..],
        &["--record", frame, "--frames-every", "60", frames],
    ] {
        let args = [&long[..3], args].concat();
        refused(
            &args,
            1,
            &["cannot write (--frames-every): a file it writes would replace"],
        );
    }
    assert_eq!(std::fs::read_to_string(frame).unwrap(), source);
    std::fs::remove_dir_all(frames).unwrap();
    // Play's high scores are read, and rewritten after a game.
    let scores = dir.path().join(gpuwars::game::highscore::FILE_NAME);
    std::fs::write(&scores, "").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args([
            "--backend",
            "cpu",
            "play",
            "--record",
            scores.to_str().unwrap(),
        ])
        .env("GPUWARS_DATA_DIR", dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("cannot write (--record): it is the same file as the high scores"),
        "{stderr}"
    );
    std::fs::remove_file(&scores).unwrap();
    // Tradeoff's tables go into --out, where its scene may be.
    let table = path("bench-tradeoff.csv");
    std::fs::write(&table, source).unwrap();
    let out = dir.path().to_str().unwrap();
    refused(
        &["tradeoff", "--scene", &table, "--out", out],
        1,
        &["cannot write (--out): it is the same file as --scene"],
    );
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), source);
    assert_eq!(std::fs::read_to_string(&table).unwrap(), source);
    let mut left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(
        left,
        [
            "bench-tradeoff.csv",
            "hard.toml",
            "k.png",
            "k.toml",
            "link.toml"
        ]
    );
}

#[test]
fn a_long_path_is_shown_shortened() {
    let long = format!("/no/such/{}/scene.toml", "a".repeat(6000));
    let stderr = refused(&["demo", "--scene", &long], 1, &["scene.toml", "…"]);
    assert!(stderr.len() < 400, "{stderr}");
    let record = format!("/no/such/{}/game.json", "b".repeat(6000));
    let stderr = refused(
        &["demo", "--record", &record],
        1,
        &["cannot write", "game.json"],
    );
    assert!(stderr.len() < 400, "{stderr}");
}

#[test]
fn every_command_checks_its_flags_in_the_same_words() {
    let seeds = [
        vec!["demo"],
        vec!["play"],
        vec!["tradeoff"],
        vec!["bench", "paper"],
    ];
    for command in seeds {
        for (seed, says) in [
            (
                "abc",
                "not a whole number (allowed a whole number from 0 to 4,294,967,295)",
            ),
            (
                "4294967296",
                "out of range (allowed a whole number from 0 to 4,294,967,295)",
            ),
            // A minus sign makes it the flag's value, not another flag.
            (
                "-1",
                "out of range (allowed a whole number from 0 to 4,294,967,295)",
            ),
        ] {
            let args = [&command[..], &["--seed", seed]].concat();
            let stderr = refused(&args, 2, &[says]);
            for rust in ["..=", "invalid digit", "u32"] {
                assert!(!stderr.contains(rust), "{stderr} speaks of `{rust}`");
            }
        }
    }
    // A size with a minus sign is the flag's value, refused by its own check.
    for command in [&["demo"][..], &["play"], &["bench", "paper"]] {
        let args = [command, &["--size", "-3x4"]].concat();
        refused(
            &args,
            2,
            &["invalid value '-3x4' for '--size <SIZE>': not WIDTHxHEIGHT"],
        );
    }
    // `bench paper` counts whole seconds: a run shorter than one is refused, at the edge
    // and below it, as are the range's outsides; a second is taken.
    let allowed = "allowed a number of minutes from 0.0167, one second, to 1440";
    for (minutes, says) in [
        ("0.001", "too short to count"),
        ("0.0166", "too short to count"),
        ("0", "too short to count"),
        ("-0.5", "out of range"),
        ("1440.01", "out of range"),
        ("NaN", "out of range"),
        ("soon", "not a number"),
    ] {
        let says =
            format!("invalid value '{minutes}' for '--minutes <MINUTES>': {says} ({allowed}");
        refused(&["bench", "paper", "--minutes", minutes], 2, &[&says]);
    }
    let help = gpuwars(&["bench", "paper", "--help"]);
    assert!(
        String::from_utf8_lossy(&help.stdout).contains("counted in whole seconds"),
        "{help:?}"
    );
    // A constraint is said in the help and checked with the flag, not after it.
    let stderr = refused(
        &["bench", "scale", "--max", "1025"],
        2,
        &["not a multiple of 8"],
    );
    assert!(stderr.contains("from 1,024 to 16,760,000"), "{stderr}");
    assert!(!stderr.contains("1025 enemies"), "{stderr}");
    let help = gpuwars(&["bench", "scale", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("a multiple of 8 from 1,024 to 16,760,000"),
        "{help}"
    );
}

#[test]
fn more_cpu_threads_than_the_machine_can_use_are_capped_with_a_note() {
    let cpus = std::thread::available_parallelism().unwrap().get();
    let most = cpus * gpuwars::cli::THREADS_PER_CPU;
    let out = gpuwars(&[
        "info",
        "--json",
        "--backend",
        "cpu",
        "--cpu-threads",
        "1024",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let info: Value = serde_json::from_slice(&out.stdout).unwrap();
    if most < 1024 {
        assert_eq!(info["cpu_threads"], most, "{stderr}");
        assert!(
            stderr.contains(&format!("--cpu-threads 1024: using {most}")),
            "{stderr}"
        );
    } else {
        assert_eq!(info["cpu_threads"], 1024);
    }
    let info = info_json(&["info", "--json", "--backend", "cpu", "--cpu-threads", "2"]);
    assert_eq!(info["cpu_threads"], 2);
}

#[test]
#[cfg_attr(
    not(unix),
    ignore = "Windows opens its windows itself: there is no display to lack"
)]
fn play_without_a_display_says_what_to_do_in_words() {
    for display in [None, Some(":987")] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_gpuwars"));
        command
            .args(["--backend", "cpu", "play"])
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("DISPLAY");
        if let Some(display) = display {
            command.env("DISPLAY", display);
        }
        let out = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        match display {
            None => assert_eq!(
                stderr.trim_end(),
                "gpuwars: error: no display to open a window on; `gpuwars demo` plays without one"
            ),
            // A display named but not there is named, with what to do.
            Some(name) => {
                assert!(stderr.contains(name), "{stderr}");
                assert!(stderr.contains("cannot be reached"), "{stderr}");
                assert!(stderr.contains("`gpuwars demo` plays without"), "{stderr}");
            }
        }
    }
}

/// Under an address-space limit too small for the world, the program says what it needs
/// and what is free, and exits with status 1: no allocation aborts it (it used to die with
/// "memory allocation of … bytes failed", status 134). The limit is set in a child shell.
#[test]
#[cfg_attr(not(unix), ignore = "the limit is set with a Unix shell's ulimit")]
fn a_world_larger_than_the_address_space_limit_is_an_error_in_words() {
    let limit_kib = 2_000_000;
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {limit_kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_gpuwars"))
        .args([
            "--backend",
            "cpu",
            "demo",
            "--scene",
            "scale-16m",
            "--steps",
            "1",
        ])
        .env_remove("GPUWARS_CPU_THREADS")
        .output()
        .expect("sh runs");
    // `scale-16m` takes 4.6 GB.
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("needs"), "{stderr}");
    assert!(stderr.contains("ulimit"), "{stderr}");
}

/// The first thing a user reads: the bare command with no display is the headless demo,
/// whose report fits in 25 lines (the colliding pairs in one); `demo --json` keeps every
/// pair and the rule that decided it.
#[test]
#[cfg_attr(
    not(unix),
    ignore = "Windows always has its desktop: the bare command plays there"
)]
fn the_headless_report_is_short_and_the_json_complete() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("GPUWARS_STEPS", "5")
        .env("TMPDIR", dir.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.lines().count() <= 25,
        "{} lines:\n{text}",
        text.lines().count()
    );
    let contacts: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("contacts:"))
        .collect();
    assert_eq!(contacts.len(), 1, "{text}");
    assert!(
        contacts[0].contains("14 colliding pairs of kinds, 14 swept"),
        "{text}"
    );
    let json: Value = serde_json::from_slice(
        &gpuwars(&["--backend", "cpu", "demo", "--steps", "5", "--json"]).stdout,
    )
    .unwrap();
    let pairs = json["contacts"].as_array().unwrap();
    assert_eq!(pairs.len(), 14);
    assert!(pairs.iter().all(|p| {
        p["rule"]
            .as_str()
            .is_some_and(|r| r.contains("per thousand"))
    }));
}

/// `gpuwars tune` on the CPU: it writes a scene that reads, names its choice and what it
/// rejected, plays, and replays to its hash; a target nothing reaches is refused in words
/// naming the fastest choice, and nothing is written; the input is never written over.
#[test]
fn tune_writes_a_scene_that_plays_and_refuses_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let tune_only = |scene: &str, target: &str, out: &std::path::Path, only: &[&str]| {
        let out = out.to_str().unwrap();
        let mut args = vec![
            "--backend",
            "cpu",
            "tune",
            "--scene",
            scene,
            "--steps-per-second",
            target,
            "--quick",
            "--out",
            out,
        ];
        only.iter().for_each(|c| args.extend(["--choice", c]));
        gpuwars(&args)
    };
    let tune =
        |scene: &str, target: &str, out: &std::path::Path| tune_only(scene, target, out, &[]);
    let tuned = dir.path().join("tuned.toml");
    let out = tune("kamikaze", "30", &tuned);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for part in [
        "chosen:",
        "speed:",
        "contacts missed:",
        "rejected:",
        "written:",
    ] {
        assert!(text.contains(part), "{part}: {text}");
    }
    let scene = gpuwars::game::Scene::load(tuned.to_str().unwrap()).unwrap();
    assert_eq!(scene.name, "kamikaze");
    let replay = dir.path().join("tuned.json");
    let (scene, replay) = (tuned.to_str().unwrap(), replay.to_str().unwrap());
    for args in [
        &[
            "demo", "--scene", scene, "--steps", "30", "--record", replay,
        ][..],
        &["replay", replay],
    ] {
        let out = gpuwars(&[&["--backend", "cpu"][..], args].concat());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }

    // Out of reach, with two choices measured: the fastest named is one of them.
    let never = dir.path().join("never.toml");
    let out = tune_only("kamikaze", "1000000000", &never, &["cap 8"]);
    let text = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("no choice holds")
            && (text.contains("the fastest, `default`") || text.contains("the fastest, `cap 8`")),
        "{text}"
    );
    assert!(!never.exists());
    let out = tune_only("kamikaze", "30", &never, &["cap 8", "8 substeps"]);
    let text = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("--choice: `8 substeps` is not a choice") && text.contains("`4 substeps`"),
        "{text}"
    );
    assert!(!never.exists());

    let before = std::fs::read(&tuned).unwrap();
    let out = tune(scene, "30", &tuned);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(std::fs::read(&tuned).unwrap(), before);
}

/// `gpuwars tune --fps` on the CPU: every choice it measured has its frames timed in rounds
/// (slowest ≤ median ≤ fastest), the chosen one's slowest round holds the target with the
/// margin, and the text speaks in frames; one target at a time, one at least.
#[test]
fn tune_for_a_frame_rate_times_frames() {
    let dir = tempfile::tempdir().unwrap();
    let tuned = dir.path().join("tuned.toml");
    let tuned = tuned.to_str().unwrap();
    let base = ["--backend", "cpu", "tune", "--scene", "kamikaze", "--quick"];
    let framed = [
        &base[..],
        &["--fps", "10", "--size", "320x180", "--out", tuned],
    ]
    .concat();
    let out = gpuwars(&[&framed[..], &["--json"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["target"]["frames_per_second"]["fps"], 10.0);
    let rows = report["rows"].as_array().unwrap();
    let measured: Vec<_> = rows.iter().filter(|r| r["skipped"].is_null()).collect();
    assert!(!measured.is_empty());
    for row in &measured {
        let f = &row["frames_per_s"];
        let (low, median, high) = (
            f["low"].as_f64().unwrap(),
            f["median"].as_f64().unwrap(),
            f["high"].as_f64().unwrap(),
        );
        assert!(0.0 < low && low <= median && median <= high, "{row}");
    }
    let chosen = &rows[report["chosen"].as_u64().unwrap() as usize];
    assert!(
        chosen["frames_per_s"]["low"].as_f64().unwrap() >= 12.0,
        "{chosen}"
    );
    // A step of 1/120 s at 10 frames/s is 12 steps a frame, more than `play` plays in one.
    let fine = rows.iter().find(|r| r["choice"] == "dt 1/120").unwrap();
    assert!(
        fine["skipped"]
            .as_str()
            .unwrap()
            .contains("more than the 8"),
        "{fine}"
    );
    // Nor can the scene as given (steps of 1/60 s) be held at 5 frames/s.
    let slow = [&base[..], &["--fps", "5", "--out", tuned]].concat();
    let out = gpuwars(&slow);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("aim at 7.50 frames/s or more"), "{stderr}");
    let out = gpuwars(&framed);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("frames/s") && text.contains("320x180 pixels"),
        "{text}"
    );

    for args in [
        &[
            &base[..],
            &["--fps", "5", "--steps-per-second", "5", "--out", tuned],
        ]
        .concat(),
        &[&base[..], &["--out", tuned]].concat(),
        &[
            &base[..],
            &["--steps-per-second", "5", "--size", "64x64", "--out", tuned],
        ]
        .concat(),
    ] {
        let out = gpuwars(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
}

/// Flag errors in words: the choices the usage shows and where the value came from; bounds
/// held for the number as written; a long or strange value quoted short and escaped.
#[test]
fn flag_values_are_refused_in_words_and_quoted_short() {
    let refused = |args: &[&str]| {
        let out = gpuwars(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let text = refused(&["--dependent-launch", "maybe", "info"]);
    for word in ["on or off", "GPUWARS_DEPENDENT_LAUNCH"] {
        assert!(text.contains(word), "{text}");
    }
    // 8.0000004 rounds to 8 as an f32, but is past the documented 8.
    let text = refused(&["demo", "--zoom", "8.0000004", "--steps", "1"]);
    assert!(text.contains("out of range"), "{text}");
    let long = "9".repeat(100_000);
    let text = refused(&["demo", "--zoom", &long, "--steps", "1"]);
    assert!(text.len() < 1_000, "{} bytes: {}", text.len(), &text[..200]);
    let text = refused(&["demo", "--steps", "1\nrm -rf /"]);
    assert!(text.contains("1\\nrm"), "{text}");
    assert!(!text.contains("1\nrm"), "{text}");
    // A value parser's own words do not quote the value again, whole.
    let text = refused(&["demo", "--lanes", &long, "--steps", "1"]);
    assert!(text.len() < 1_000, "{} bytes: {}", text.len(), &text[..200]);
    // The bare command's settings from the environment are quoted the same way (its
    // demo's, where there is no display: Windows always has its desktop).
    let bare = if cfg!(unix) {
        &["GPUWARS_ZOOM", "GPUWARS_CAMERA"][..]
    } else {
        &[]
    };
    for (variable, value) in [
        ("GPUWARS_ZOOM", long.clone()),
        ("GPUWARS_CAMERA", format!("a\u{1b}[31m{long}")),
    ]
    .into_iter()
    .filter(|(variable, _)| bare.contains(variable))
    {
        let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
            .env(variable, &value)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{variable}: {text}");
        assert!(text.len() < 1_000, "{variable}: {} bytes", text.len());
        assert!(!text.contains('\u{1b}'), "{variable}: {text:?}");
    }
}

/// `replay --window` without a display names the replay as errors name files: a newline
/// in its name escaped, not printed.
#[test]
#[cfg_attr(
    not(unix),
    ignore = "Windows refuses a newline in a file name, and has no display to lack"
)]
fn the_window_refusal_names_the_replay_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let replay = recorded(&dir.path().join("two\nlines.json"));
    let out = windowed(&["replay", replay.to_str().unwrap(), "--window"], None);
    let text = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("two\\nlines"), "{text}");
    assert!(!text.contains("two\nlines"), "{text}");
}

/// A display that accepts the connection and never answers (a fake Wayland socket whose
/// listener holds every connection silently) is an error naming it, for the game and the
/// replay's window alike, not a silent wait for ever (which would hang this test). Unix's
/// only: Windows opens its windows itself, with no display server to wait for.
#[cfg(unix)]
#[test]
fn a_silent_display_is_an_error_naming_it() {
    use std::os::unix::net::UnixListener;
    let dir = tempfile::tempdir().unwrap();
    let socket = dir.path().join("silent-wayland");
    let listener = UnixListener::bind(&socket).unwrap();
    std::thread::spawn(move || {
        let mut held = Vec::new();
        for stream in listener.incoming().flatten() {
            held.push(stream);
        }
    });
    let replay = recorded(&dir.path().join("game.json"));
    for args in [
        vec!["play"],
        vec!["replay", replay.to_str().unwrap(), "--window"],
    ] {
        let out = windowed(&args, Some(&socket));
        let text = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {text}");
        assert!(text.contains("silent-wayland"), "{text}");
        assert!(text.contains("did not answer"), "{text}");
    }
}

/// `gpuwars --backend cpu ARGS` with the display `(variable, value)` (and no other), its
/// temporary files in `tmp`; a short demo of `kamikaze` where the bare command falls back
/// to one.
#[cfg(unix)]
fn on_display(
    args: &[&str],
    (variable, value): (&str, &str),
    tmp: &std::path::Path,
) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(["--backend", "cpu"])
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env(variable, value)
        .env("GPUWARS_STEPS", "5")
        .env("GPUWARS_SCENE", "kamikaze")
        .env("TMPDIR", tmp)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code().unwrap_or(-1), text)
}

/// A display that answers garbage and keeps the connection open, a fake Wayland socket
/// and a fake X server on TCP alike, is refused in words that name it by every command
/// that opens a window (each would wait for ever in the window library otherwise, hanging
/// this test); the bare `gpuwars` plays the demo instead, saying why. So is one that hangs
/// up at once (the library's own "Io error" never shown), and an X display whose server
/// is gone (a stale login's `DISPLAY`).
#[cfg(unix)]
#[test]
fn a_display_that_answers_garbage_is_refused_naming_it() {
    use std::net::TcpListener;
    use std::os::unix::net::UnixListener;
    let dir = tempfile::tempdir().unwrap();
    // What a web server would say, a few KiB of it, and then nothing (the connection held
    // open); or, hanging up, nothing at all.
    fn serve<S: std::io::Write + Send + 'static>(incoming: impl Iterator<Item = S>, hang_up: bool) {
        let garbage = b"HTTP/1.1 400 Bad Request\r\nConnection: keep-alive\r\n\r\n".repeat(80);
        let mut held = Vec::new();
        for mut stream in incoming {
            if !hang_up {
                stream.write_all(&garbage).ok();
                held.push(stream);
            }
        }
    }
    let wayland = dir.path().join("garbled-wayland");
    let hang_up = dir.path().join("hang-up-wayland");
    for (path, hangs) in [(&wayland, false), (&hang_up, true)] {
        let listener = UnixListener::bind(path).unwrap();
        std::thread::spawn(move || serve(listener.incoming().flatten(), hangs));
    }
    // X display n listens on TCP port 6000 + n: the first free port from 6100 up.
    let (x11, port) = (6100..7000)
        .find_map(|port| {
            TcpListener::bind(("127.0.0.1", port))
                .ok()
                .map(|l| (l, port))
        })
        .unwrap();
    std::thread::spawn(move || serve(x11.incoming().flatten(), false));
    let gone = (7000..8000)
        .find(|&port| TcpListener::bind(("127.0.0.1", port)).is_ok())
        .unwrap();
    let x11 = format!("127.0.0.1:{}", port - 6000);
    let gone = format!("127.0.0.1:{}", gone - 6000);
    let replay = recorded(&dir.path().join("game.json"));
    let out = dir.path().to_str().unwrap();
    let commands: [&[&str]; 3] = [
        &["play"],
        &["replay", replay.to_str().unwrap(), "--window"],
        &[
            "bench",
            "paper",
            "--window",
            "--minutes",
            "0.02",
            "--out",
            out,
        ],
    ];
    let displays = [
        (
            ("WAYLAND_DISPLAY", wayland.to_str().unwrap()),
            "garbled-wayland",
            "not in the Wayland protocol",
        ),
        (
            ("DISPLAY", x11.as_str()),
            x11.as_str(),
            "not in the X11 protocol",
        ),
        (
            ("WAYLAND_DISPLAY", hang_up.to_str().unwrap()),
            "hang-up-wayland",
            "closed the connection",
        ),
        (
            ("DISPLAY", gone.as_str()),
            gone.as_str(),
            "cannot be reached",
        ),
    ];
    for (display, name, why) in displays {
        for args in commands {
            let (code, text) = on_display(args, display, dir.path());
            assert_eq!(code, 1, "{args:?} on {display:?}: {text}");
            assert!(
                text.contains(name) && text.contains(why),
                "{args:?}: {text}"
            );
            assert!(!text.contains("Io error"), "{args:?}: {text}");
        }
        let (code, text) = on_display(&[], display, dir.path());
        assert_eq!(code, 0, "bare on {display:?}: {text}");
        assert!(text.contains(name) && text.contains(why), "bare: {text}");
        assert!(
            text.contains("playing the demo without a window instead"),
            "{text}"
        );
    }
}

/// The first line of stderr of `gpuwars ARGS` that contains `needle`, the program stopped
/// once it has come (or `None` if it ended first); stdout is dropped.
fn first_notice(args: &[&std::ffi::OsStr], needle: &str) -> Option<String> {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args(args)
        .env_remove("GPUWARS_CPU_THREADS")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = BufReader::new(child.stderr.take().unwrap());
    let notice = stderr
        .lines()
        .map_while(Result::ok)
        .find(|line| line.contains(needle));
    child.kill().ok();
    child.wait().ok();
    notice
}

/// Long work says how long it will take once its speed is known: a demo of a million
/// enemies for many steps announces its steps per second and what is left, on stderr,
/// beside its JSON (stopped once it has).
#[test]
fn a_long_demo_says_how_long_it_will_take() {
    let args = "--backend cpu demo --scene scale-1m --steps 100000 --json";
    let args: Vec<&std::ffi::OsStr> = args.split(' ').map(std::ffi::OsStr::new).collect();
    let notice = first_notice(&args, "steps/s: about").expect("a notice before the run ends");
    assert!(notice.contains("100,000 steps"), "{notice}");
}

/// A tradeoff of a large scene says what it will take before its first choice is measured,
/// from its game timed first: the notice names its choices, not a rate of choices done
/// (stopped once it has).
#[test]
fn a_long_tradeoff_says_how_long_it_will_take_from_the_start() {
    let dir = tempfile::tempdir().unwrap();
    let args = "--backend cpu tradeoff --quick --scene scale-1m --out";
    let mut args: Vec<&std::ffi::OsStr> = args.split(' ').map(std::ffi::OsStr::new).collect();
    args.push(dir.path().as_os_str());
    let notice = first_notice(&args, "about").expect("a notice before the run ends");
    assert!(notice.starts_with("gpuwars: tradeoff: "), "{notice}");
    assert!(notice.contains(" choices: about "), "{notice}");
    assert!(!notice.contains("choices/s"), "{notice}");
}

/// A bind mount of a folder, undone when dropped; `None` (with the reason printed) where the
/// test may not mount.
struct BindMount(std::path::PathBuf);

impl BindMount {
    fn new(from: &std::path::Path, to: &std::path::Path) -> Option<BindMount> {
        let mounted = Command::new("mount")
            .arg("--bind")
            .arg(from)
            .arg(to)
            .output();
        match mounted {
            Ok(out) if out.status.success() => Some(BindMount(to.to_path_buf())),
            other => {
                let why = match other {
                    Ok(out) => String::from_utf8_lossy(&out.stderr).trim().to_owned(),
                    Err(e) => e.to_string(),
                };
                eprintln!("skipped: cannot make a bind mount here ({why})");
                None
            }
        }
    }
}

impl Drop for BindMount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).output();
    }
}

/// Outputs are refused when they land on an input or another output through a bind mount
/// of its folder: the folder is the same one (device and inode), whatever path reaches it.
/// Nothing is written, and the files are as they were.
#[test]
fn outputs_through_a_bind_mount_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (real, mount) = (dir.path().join("real"), dir.path().join("mount"));
    std::fs::create_dir_all(&real).unwrap();
    std::fs::create_dir_all(&mount).unwrap();
    let Some(_mounted) = BindMount::new(&real, &mount) else {
        return;
    };
    // A scene named like a frame, and frames written into its folder through the mount.
    let scene = real.join("frame-000005.png");
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/paper.toml")).unwrap();
    std::fs::write(&scene, &text).unwrap();
    let frames = [
        "--backend",
        "cpu",
        "demo",
        "--steps",
        "10",
        "--scene",
        scene.to_str().unwrap(),
        "--frames-every",
        "5",
        mount.to_str().unwrap(),
    ];
    // Two outputs, one file: the replay and the screenshot through the mount.
    let record = real.join("y.png");
    let screenshot = mount.join("y.png");
    let both = [
        "--backend",
        "cpu",
        "demo",
        "--steps",
        "10",
        "--record",
        record.to_str().unwrap(),
        "--screenshot",
        screenshot.to_str().unwrap(),
    ];
    for args in [&frames[..], &both[..]] {
        let out = gpuwars(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains("cannot write"), "{stderr}");
    }
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), text);
    assert!(!record.exists());
}

/// A replay of a short demo on the CPU, written at `path`.
fn recorded(path: &std::path::Path) -> std::path::PathBuf {
    let out = gpuwars(&[
        "--backend",
        "cpu",
        "demo",
        "--steps",
        "5",
        "--record",
        path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path.to_path_buf()
}

/// `gpuwars --backend cpu ARGS` with no display but the Wayland socket `wayland`, if any.
fn windowed(args: &[&str], wayland: Option<&std::path::Path>) -> std::process::Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_gpuwars"));
    command
        .args(["--backend", "cpu"])
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    if let Some(socket) = wayland {
        command.env("WAYLAND_DISPLAY", socket);
    }
    command.output().unwrap()
}

/// A built-in scene's name that is also a file here plays the built-in, and says so with
/// the way to play the file; `./name` plays the file, without the note.
#[test]
fn a_file_named_like_a_built_in_is_pointed_out() {
    let dir = tempfile::tempdir().unwrap();
    let source = gpuwars::game::scene::BUILT_IN[1].source;
    let renamed = source.replacen(
        &format!("name = \"{}\"", gpuwars::game::scene::BUILT_IN[1].name),
        "name = \"from the file\"",
        1,
    );
    std::fs::write(dir.path().join("paper"), renamed).unwrap();
    let demo = |scene: &str| {
        Command::new(env!("CARGO_BIN_EXE_gpuwars"))
            .args(["--backend", "cpu", "demo", "--steps", "2", "--scene", scene])
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    let out = demo("paper");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("scene:            paper\n"), "{stdout}");
    let dot = std::path::Path::new(".").join("paper");
    let hint = format!("give `--scene {}`", dot.display());
    assert!(
        stderr.contains("`paper` is a built-in scene") && stderr.contains(&hint),
        "{stderr}"
    );
    let out = demo(dot.to_str().unwrap());
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        stdout.contains("scene:            from the file"),
        "{stdout}"
    );
    assert!(!stderr.contains("built-in scene"), "{stderr}");
}

/// A value refused that came from the environment names its variable, unless the flag was
/// given too (then the flag's value is the one refused).
#[test]
fn a_bad_value_from_the_environment_names_its_variable() {
    let run = |args: &[&str], variable: &str, value: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
            .args(args)
            .env_remove("GPUWARS_BACKEND")
            .env_remove("GPUWARS_CPU_THREADS")
            .env(variable, value)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let stderr = run(&["demo"], "GPUWARS_STEPS", "abc");
    assert!(
        stderr.contains("invalid value 'abc' for '--steps <STEPS>'"),
        "{stderr}"
    );
    assert!(
        stderr.contains("the value is the environment's GPUWARS_STEPS: unset it, or give --steps"),
        "{stderr}"
    );
    let stderr = run(&["info"], "GPUWARS_CPU_THREADS", "0");
    assert!(stderr.contains("GPUWARS_CPU_THREADS"), "{stderr}");
    for given in [&["demo", "--steps", "x"][..], &["demo", "--steps=x"]] {
        let stderr = run(given, "GPUWARS_STEPS", "abc");
        assert!(stderr.contains("invalid value 'x'"), "{stderr}");
        assert!(!stderr.contains("GPUWARS_STEPS"), "{stderr}");
    }
}
