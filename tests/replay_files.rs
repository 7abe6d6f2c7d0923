//! Replay files: the round trip, atomic saves, and the errors a broken file gets (the line and
//! the field of the problem, and what is allowed), never a panic.

use std::path::Path;

use gpuwars::game::replay::{FIRST_VERSION, Replay, ReplayError, VERSION};
use gpuwars::kernels::game::control::Input;
use proptest::prelude::*;

fn input(move_x: i32, move_y: i32, aim: u32, fire: u32) -> Input {
    Input {
        move_x,
        move_y,
        aim,
        fire,
    }
}

/// A replay with runs of equal inputs, single ones, each field at both ends of its range, and
/// a scene text that needs escaping.
fn sample() -> Replay {
    let runs = [
        (12, input(0, 0, 0, 0)),
        (1, input(-707, 707, 16384, 1)),
        (1, input(-1000, 1000, 65535, 0)),
        (3, input(1000, -1000, 0, 1)),
        (1, input(5, -5, 100, 1)),
        (1, input(5, -5, 100, 0)),
        (7, input(0, 0, 0, 0)),
        (2, input(1, 2, 3, 1)),
    ];
    Replay {
        version: VERSION,
        scene: "paper".into(),
        scene_toml: "name = \"paper\"\n# a \\ and a \"quote\",\ta tab, ünïcödé ✓\n[world]\n".into(),
        seed: u32::MAX,
        backend: gpuwars::BackendKind::Cpu,
        state_hash: 0x0123_4567_89ab_cdef,
        inputs: runs
            .iter()
            .flat_map(|&(n, input)| std::iter::repeat_n(input, n))
            .collect(),
    }
}

/// The runs of `inputs`, merged the slow way.
fn brute_runs(inputs: &[Input]) -> Vec<(usize, Input)> {
    let mut runs: Vec<(usize, Input)> = Vec::new();
    for &input in inputs {
        match runs.last_mut() {
            Some((n, last)) if *last == input => *n += 1,
            _ => runs.push((1, input)),
        }
    }
    runs
}

/// The runs of `json`, read back line by line as `(repeat, input)`: every line of the
/// `inputs` array must hold exactly one run.
fn run_lines(json: &str) -> Vec<(usize, Input)> {
    let lines: Vec<&str> = json.lines().collect();
    let start = lines
        .iter()
        .position(|line| line.starts_with("  \"inputs\": "))
        .expect("an inputs line");
    if lines[start] == "  \"inputs\": []" {
        return Vec::new();
    }
    assert_eq!(lines[start], "  \"inputs\": [", "{json}");
    let end = start
        + lines[start..]
            .iter()
            .position(|line| *line == "  ]")
            .expect("an end");
    assert_eq!(lines[end + 1..], ["}"], "{json}");
    let runs = &lines[start + 1..end];
    runs.iter()
        .enumerate()
        .map(|(i, line)| {
            // A comma after each run but the last.
            let comma = if i + 1 < runs.len() { "," } else { "" };
            let inner = line
                .strip_prefix("    [")
                .and_then(|s| s.strip_suffix(comma))
                .and_then(|s| s.strip_suffix(']'));
            let numbers: Vec<i64> = inner
                .unwrap_or_else(|| panic!("a run line is one array: {line:?}"))
                .split(", ")
                .map(|n| n.parse().expect("an integer"))
                .collect();
            let [repeat, x, y, aim, fire] = numbers[..] else {
                panic!("a run line holds 5 numbers: {line:?}");
            };
            let input = input(x as i32, y as i32, aim as u32, fire as u32);
            (repeat as usize, input)
        })
        .collect()
}

/// Checks `to_json` against the slow merge and `parse` against the original.
fn check_round_trip(replay: &Replay) {
    let json = replay.to_json();
    assert_eq!(run_lines(&json), brute_runs(&replay.inputs), "{json}");
    assert_eq!(Replay::parse(&json, "round trip").as_ref(), Ok(replay));
}

#[test]
fn round_trip_merges_runs_one_per_line() {
    let replay = sample();
    check_round_trip(&replay);
    let json = replay.to_json();
    assert!(json.contains("\n  \"steps\": 28,\n"), "{json}");
    assert!(
        json.contains("\n  \"state_hash\": \"0x0123456789abcdef\",\n"),
        "{json}"
    );
    assert!(json.contains("\n    [12, 0, 0, 0, 0],\n"), "{json}");
    assert!(json.contains("\n    [2, 1, 2, 3, 1]\n  ]\n}\n"), "{json}");
}

#[test]
fn round_trip_of_an_empty_replay() {
    let replay = Replay {
        inputs: Vec::new(),
        ..sample()
    };
    assert!(replay.to_json().contains("\"inputs\": []"));
    check_round_trip(&replay);
}

#[test]
fn reads_any_layout_and_either_case_of_hash() {
    // Keys in another order, all on one line, hash in capitals.
    let text = r#"{"inputs": [[2, 1, -1, 7, 1]], "steps": 2, "seed": 3, "backend": "cuda",
        "state_hash": "0X00000000000000FF", "scene_toml": "", "scene": "x",
        "version": 1, "format": "gpuwars-replay"}"#;
    let replay = Replay::parse(text, "compact").expect("a valid replay");
    assert_eq!(replay.version, FIRST_VERSION);
    assert_eq!(replay.state_hash, 0xff);
    assert_eq!(replay.inputs, vec![input(1, -1, 7, 1); 2]);
}

#[test]
fn save_load_and_replace() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("game.json");
    let first = sample();
    first.save(&path).expect("saved");
    assert_eq!(Replay::load(&path).as_ref(), Ok(&first));

    let second = Replay {
        seed: 7,
        inputs: first.inputs[3..9].to_vec(),
        ..first.clone()
    };
    second.save(&path).expect("saved over the first");
    assert_eq!(Replay::load(&path).as_ref(), Ok(&second));
    assert_eq!(
        entries(dir.path()),
        ["game.json"],
        "no temporary file is left"
    );
}

#[test]
fn save_into_a_missing_directory_fails_cleanly() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("missing").join("game.json");
    let e = sample().save(&path).expect_err("no such directory");
    assert_eq!(e.line, None);
    assert!(
        e.to_string().starts_with(&path.display().to_string()),
        "{e}"
    );
    assert!(entries(dir.path()).is_empty(), "nothing is left behind");
}

#[test]
fn save_refuses_what_could_not_be_read_back() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("game.json");
    let mut replay = sample();
    replay.inputs[20].aim = 70000;
    let e = replay.save(&path).expect_err("aim out of range");
    assert_eq!(e.field, "inputs[20].aim");
    assert!(e.problem.contains("0 to 65535"), "{e}");
    assert!(entries(dir.path()).is_empty(), "nothing is written");
}

#[test]
fn load_of_a_missing_file() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("absent.json");
    let e = Replay::load(&path).expect_err("no such file");
    assert_eq!((e.line, e.field.as_str()), (None, ""));
    let expected = format!("{}: cannot read: ", path.display());
    assert!(e.to_string().starts_with(&expected), "{e}");
}

#[test]
fn load_of_a_file_that_is_not_text() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("binary.json");
    let mut bytes = sample().to_json().into_bytes();
    let third_line = bytes.iter().position(|&b| b == b'\n').expect("lines") + 1;
    let third_line = third_line
        + bytes[third_line..]
            .iter()
            .position(|&b| b == b'\n')
            .unwrap();
    bytes[third_line + 4] = 0xff;
    std::fs::write(&path, bytes).expect("written");
    let e = Replay::load(&path).expect_err("not UTF-8");
    assert_eq!(e.line, Some(3), "{e}");
}

/// A scene file given as a replay is named as what it is, not as broken JSON.
#[test]
fn a_scene_given_as_a_replay_is_named() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("arena.toml");
    let source = gpuwars::game::scene::BUILT_IN[1].source;
    std::fs::write(&path, source).expect("written");
    let e = Replay::load(&path).expect_err("a scene");
    let name = gpuwars::game::scene::BUILT_IN[1].name;
    assert!(
        e.problem
            .contains(&format!("not a replay but the scene `{name}`")),
        "{e}"
    );
    // Text that is neither keeps the JSON reader's words.
    std::fs::write(&path, "name = ").expect("written");
    let e = Replay::load(&path).expect_err("neither");
    assert!(e.problem.contains("not a JSON value"), "{e}");
}

fn entries(dir: &Path) -> Vec<String> {
    let entries = std::fs::read_dir(dir).expect("a readable directory");
    let mut names: Vec<String> = entries
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

/// The sample's text with the first `from` replaced by `to`, and the line of the change.
fn mutate(from: &str, to: &str) -> (String, usize) {
    let text = sample().to_json();
    let at = text
        .find(from)
        .unwrap_or_else(|| panic!("{from:?} is in the sample"));
    let mutated = format!("{}{to}{}", &text[..at], &text[at + from.len()..]);
    let line = mutated[..at].matches('\n').count() + 1;
    (mutated, line)
}

/// The index of the run that the first `from` of the sample's text is in.
fn run_index(from: &str) -> usize {
    let text = sample().to_json();
    let at = text.find(from).expect("in the sample");
    text[..at].matches("\n    [").count()
}

/// Parses `text`, which must fail at `line` on `field`, with each of `shows` in the message.
fn expect_error(text: &str, line: Option<usize>, field: &str, shows: &[&str]) -> ReplayError {
    let e = Replay::parse(text, "bad.json").expect_err("a broken replay");
    let shown = e.to_string();
    assert_eq!((e.line, e.field.as_str()), (line, field), "{shown}");
    let place = line.map_or(String::new(), |line| format!(":{line}"));
    let field_part = if field.is_empty() {
        String::new()
    } else {
        format!("{field}: ")
    };
    let prefix = format!("bad.json{place}: {field_part}");
    assert!(shown.starts_with(&prefix), "{shown}");
    for part in shows {
        assert!(shown.contains(part), "{shown:?} does not show {part:?}");
    }
    e
}

/// A run of the sample that is written once.
const RUN: &str = "[1, 5, -5, 100, 1]";

#[test]
fn wrong_types() {
    let (text, line) = mutate("\"seed\": 4294967295", "\"seed\": \"one\"");
    expect_error(
        &text,
        Some(line),
        "seed",
        &["expected a whole number (allowed 0 to 4,294,967,295), found \"one\""],
    );

    let (text, line) = mutate("\"scene\": \"paper\"", "\"scene\": 5");
    expect_error(&text, Some(line), "scene", &["expected a string"]);

    let (text, line) = mutate("\"version\": 2", "\"version\": null");
    expect_error(&text, Some(line), "version", &["null", "allowed 1 to 2"]);

    let run = run_index(RUN);
    let (text, line) = mutate(RUN, "[1, 5, -5, 100]");
    let field = format!("inputs[{run}]");
    expect_error(&text, Some(line), &field, &["4 numbers", "expected 5"]);

    let (text, line) = mutate(RUN, "[1, 5, -5, 100, 1, 0]");
    expect_error(&text, Some(line), &field, &["6 numbers", "expected 5"]);

    let (text, line) = mutate(RUN, "{\"repeat\": 1}");
    expect_error(
        &text,
        Some(line),
        &field,
        &["expected a run [repeat, move_x, move_y, aim, fire], found an object"],
    );

    let (text, line) = mutate(RUN, "[1, 5, -5, 100.5, 1]");
    let field = format!("inputs[{run}].aim");
    expect_error(&text, Some(line), &field, &["100.5", "0 to 65535"]);

    let (text, line) = mutate(RUN, "[1, 5, true, 100, 1]");
    let field = format!("inputs[{run}].move_y");
    expect_error(&text, Some(line), &field, &["true", "-1000 to 1000"]);

    let (text, line) = mutate(RUN, "[1, 5, -5]");
    expect_error(&text, Some(line), &format!("inputs[{run}]"), &["3 numbers"]);
    let (text, line) = mutate(RUN, "[1]");
    expect_error(
        &text,
        Some(line),
        &format!("inputs[{run}]"),
        &["has 1 number,"],
    );

    // The backend is one this build has, as written.
    for other in ["bogus", "CPU", ""] {
        let (text, line) = mutate("\"backend\": \"cpu\"", &format!("\"backend\": \"{other}\""));
        expect_error(&text, Some(line), "backend", &["allowed `cpu` or `cuda`"]);
    }
    let (text, _) = mutate("\"backend\": \"cpu\"", "\"backend\": \"cuda\"");
    let replay = Replay::parse(&text, "cuda.json").unwrap();
    assert_eq!(replay.backend, gpuwars::BackendKind::Cuda);
}

/// The scene's name is the one its TOML holds: a replay whose two disagree is refused
/// when its scene is read, naming both.
#[test]
fn the_scene_named_is_the_scene_held() {
    let mut replay = sample();
    replay.scene_toml = gpuwars::game::scene::BUILT_IN[0].source.to_owned();
    assert_eq!(replay.scene("r.json").unwrap().name, "paper");
    replay.scene = "arena".into();
    let e = replay.scene("r.json").unwrap_err();
    assert_eq!(e.field, "scene", "{e}");
    assert!(
        e.to_string()
            .contains("\"arena\" is not the name of the scene its scene_toml holds (\"paper\")"),
        "{e}"
    );
}

#[test]
fn out_of_range() {
    let run = run_index(RUN);
    let number = |name: &str| format!("inputs[{run}].{name}");
    let cases = [
        (
            "[1, 5, -5, 70000, 1]",
            "aim",
            "70000 is out of range (allowed 0 to 65535)",
        ),
        (
            "[1, 5, -5, -1, 1]",
            "aim",
            "-1 is out of range (allowed 0 to 65535)",
        ),
        (
            "[1, 1001, -5, 100, 1]",
            "move_x",
            "1001 is out of range (allowed -1000 to 1000)",
        ),
        (
            "[1, 5, -1001, 100, 1]",
            "move_y",
            "-1001 is out of range (allowed -1000 to 1000)",
        ),
        (
            "[1, 9999999999, -5, 100, 1]",
            "move_x",
            "9999999999 is out of range (allowed -1000",
        ),
        (
            "[1, 5, -5, 100, 2]",
            "fire",
            "2 is out of range (allowed 0 or 1)",
        ),
        (
            "[0, 5, -5, 100, 1]",
            "repeat",
            "0 is out of range (allowed 1 to 1,000,000)",
        ),
        (
            "[1000000, 5, -5, 100, 1]",
            "repeat",
            "(allowed at most 1,000,000)",
        ),
    ];
    for (to, name, shows) in cases {
        let (text, line) = mutate(RUN, to);
        expect_error(&text, Some(line), &number(name), &[shows]);
    }

    let (text, line) = mutate("\"seed\": 4294967295", "\"seed\": -1");
    expect_error(
        &text,
        Some(line),
        "seed",
        &["-1 is out of range (allowed 0 to 4,294,967,295)"],
    );

    let (text, line) = mutate("\"seed\": 4294967295", "\"seed\": 4294967296");
    expect_error(&text, Some(line), "seed", &["4294967296 is out of range"]);

    let (text, line) = mutate("\"steps\": 28", "\"steps\": 1000001");
    expect_error(&text, Some(line), "steps", &["allowed 0 to 1,000,000"]);
}

#[test]
fn wrong_keys() {
    let (text, line) = mutate("\"seed\"", "\"extra\": 1,\n  \"seed\"");
    expect_error(
        &text,
        Some(line),
        "extra",
        &["unknown key", "format, version"],
    );

    let (text, line) = mutate("\"backend\"", "\"seed\": 1,\n  \"backend\"");
    expect_error(&text, Some(line), "seed", &["appears twice"]);

    // A missing key is placed where the object ends without it.
    let (text, _) = mutate("  \"backend\": \"cpu\",\n", "");
    let end = text.lines().count();
    expect_error(
        &text,
        Some(end),
        "backend",
        &["missing", &format!("ends at line {end}")],
    );

    let (text, _) = mutate("  \"format\": \"gpuwars-replay\",\n", "");
    let end = text.lines().count();
    expect_error(&text, Some(end), "format", &["missing"]);
}

#[test]
fn wrong_format_or_version() {
    let (text, line) = mutate("\"gpuwars-replay\"", "\"gpuwars-save\"");
    expect_error(
        &text,
        Some(line),
        "format",
        &["\"gpuwars-save\"", "\"gpuwars-replay\""],
    );

    for (version, problem) in [
        (
            0,
            "unsupported version 0 (this build reads versions 1 to 2)",
        ),
        (
            3,
            "unsupported version 3 (this build reads versions 1 to 2)",
        ),
    ] {
        let (text, line) = mutate("\"version\": 2", &format!("\"version\": {version}"));
        expect_error(&text, Some(line), "version", &[problem]);
    }

    // A later version's new keys do not hide the version.
    let (text, line) = mutate("\"version\": 2", "\"version\": 3");
    let text = text.replace("\"seed\"", "\"new_key\": [1, 2],\n  \"seed\"");
    expect_error(&text, Some(line), "version", &["unsupported version 3"]);
}

#[test]
fn steps_must_match_the_runs() {
    let (text, line) = mutate("\"steps\": 28", "\"steps\": 29");
    expect_error(&text, Some(line), "steps", &["29", "28"]);

    // The line comes from the text, not from a layout.
    let text = text.replace("\n  ", " ");
    expect_error(&text, Some(1), "steps", &["29", "28"]);
}

#[test]
fn bad_hash() {
    let hash = "\"0x0123456789abcdef\"";
    for bad in [
        "\"0x0123\"",
        "\"0x0123456789abcdeg\"",
        "\"0123456789abcdef01\"",
        "\"0x+123456789abcdef\"",
    ] {
        let (text, line) = mutate(hash, bad);
        expect_error(&text, Some(line), "state_hash", &[bad, "16 hex digits"]);
    }
    let (text, line) = mutate(hash, "81985529216486895");
    expect_error(
        &text,
        Some(line),
        "state_hash",
        &["expected a string, found 81985529216486895"],
    );
}

#[test]
fn not_json() {
    let text = sample().to_json();
    let lines = text.lines().count();
    let e = expect_error(
        &format!("{text}x"),
        Some(lines + 1),
        "",
        &["more text after the end of the JSON value"],
    );
    assert_eq!(e.file, "bad.json");
    expect_error("[1, 2]", Some(1), "", &["a replay (a JSON object)"]);
    expect_error("", Some(1), "", &["the text ends where a value should be"]);
    // serde_json's jargon is said in words.
    let text = "{\"format\": \"gpuwars-replay";
    let e = expect_error(text, Some(1), "format", &["the text ends inside a string"]);
    assert!(!e.to_string().contains("EOF"), "{e}");
    expect_error("{1: 2}", Some(1), "", &["a key must be a \"string\""]);
    let text = "{\"format\": \"a\u{0}b\"}";
    let e = expect_error(
        text,
        Some(1),
        "format",
        &["a control character inside a string"],
    );
    assert!(!e.to_string().contains("u{"), "{e}");
}

#[test]
fn truncated_files() {
    let text = sample().to_json();
    // The last cut leaves out only the closing brace and newline.
    let cuts = [
        0,
        1,
        30,
        text.len() / 3,
        text.len() / 2,
        text.len() * 4 / 5,
        text.len() - 2,
    ];
    for mut cut in cuts {
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        let cut_text = &text[..cut];
        let e = Replay::parse(cut_text, "cut.json").expect_err("a truncated file");
        // serde_json reports running out where the text ends.
        let end = cut_text.matches('\n').count() + 1;
        assert_eq!(e.line, Some(end), "cut at {cut}: {e}");
        assert!(e.problem.starts_with("the text ends "), "cut at {cut}: {e}");
    }
}

fn any_input() -> impl Strategy<Value = Input> {
    let edge = prop_oneof![Just(-1000), Just(0), Just(1000), -1000..=1000];
    (
        edge.clone(),
        edge,
        prop_oneof![Just(0), Just(65535), 0..=65535u32],
        0..=1u32,
    )
        .prop_map(|(x, y, aim, fire)| input(x, y, aim, fire))
}

proptest! {
    // No regression files: this test writes nothing into the tree.
    #![proptest_config(ProptestConfig {
        cases: 48,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn round_trip_of_random_inputs(
        alphabet in prop::collection::vec(any_input(), 1..4),
        picks in prop::collection::vec(any::<prop::sample::Index>(), 0..300),
    ) {
        // Few distinct inputs, so that runs form.
        let inputs = picks.iter().map(|pick| *pick.get(&alphabet)).collect();
        check_round_trip(&Replay { inputs, ..sample() });
    }

    #[test]
    fn truncation_never_panics(cut in any::<prop::sample::Index>()) {
        let text = sample().to_json();
        // Any cut but the one that leaves out just the final newline.
        let mut cut = cut.index(text.len() - 1);
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        prop_assert!(Replay::parse(&text[..cut], "cut.json").is_err());
    }

    #[test]
    fn byte_edits_never_panic(at in any::<prop::sample::Index>(), byte in any::<u8>()) {
        let mut bytes = sample().to_json().into_bytes();
        let at = at.index(bytes.len());
        bytes[at] = byte;
        let text = String::from_utf8_lossy(&bytes);
        if let Err(e) = Replay::parse(&text, "edited.json") {
            let lines = text.matches('\n').count() + 1;
            prop_assert!(e.line.is_none_or(|line| (1..=lines).contains(&line)), "{}", e);
        }
    }
}

#[test]
fn a_byte_order_mark_is_skipped_as_in_a_scene() {
    let text = format!("\u{feff}{}", sample().to_json());
    assert_eq!(Replay::parse(&text, "bom.json"), Ok(sample()));
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("bom.json");
    std::fs::write(&path, &text).expect("written");
    assert_eq!(Replay::load(&path), Ok(sample()));
}

#[test]
fn a_billion_steps_are_refused_before_anything_is_allocated() {
    let (text, line) = mutate("\"steps\": 28", "\"steps\": 1000000000");
    let text = text.replace(RUN, "[999999975, 5, -5, 100, 1]");
    expect_error(
        &text,
        Some(line),
        "steps",
        &["1000000000 is out of range (allowed 0 to 1,000,000)"],
    );
    // The runs alone: refused at the run that passes the limit, on its line.
    let (text, line) = mutate(RUN, "[999999975, 5, -5, 100, 1]");
    let run = run_index(RUN);
    let field = format!("inputs[{run}].repeat");
    expect_error(
        &text,
        Some(line),
        &field,
        &["out of range (allowed 1 to 1,000,000)"],
    );
    let (text, line) = mutate(RUN, "[999990, 5, -5, 100, 1]");
    expect_error(
        &text,
        Some(line),
        &field,
        &["the runs so far add up to 1,000,007 steps (allowed at most 1,000,000)"],
    );
    // Exactly the limit reads.
    let (text, _) = mutate(RUN, "[999973, 5, -5, 100, 1]");
    let text = text.replace("\"steps\": 28", "\"steps\": 1000000");
    let replay = Replay::parse(&text, "limit.json").expect("at the limit");
    assert_eq!(replay.inputs.len(), 1_000_000);
}

#[test]
fn errors_speak_of_the_file_not_of_rust() {
    let run = run_index(RUN);
    let cases = [
        ("\"seed\": 4294967295", "\"seed\": 1.5", "seed", "found 1.5"),
        (
            "\"seed\": 4294967295",
            "\"seed\": [1]",
            "seed",
            "found an array",
        ),
        (
            "\"seed\": 4294967295",
            "\"seed\": 1e30",
            "seed",
            "1e30 is out of range",
        ),
        (
            "\"scene\": \"paper\"",
            "\"scene\": null",
            "scene",
            "expected a string, found null",
        ),
        (
            "\"scene\": \"paper\"",
            "\"scene\": {}",
            "scene",
            "found an object",
        ),
        (
            "\"version\": 2",
            "\"version\": true",
            "version",
            "found true",
        ),
        (RUN, "[1, 5, -5, \"up\", 1]", "aim", "found \"up\""),
        (
            RUN,
            "[1, 5, -5, 100, 100000000000000000000]",
            "fire",
            "is out of range",
        ),
    ];
    for (from, to, field, says) in cases {
        let (text, line) = mutate(from, to);
        let field = match field {
            "aim" | "fire" => format!("inputs[{run}].{field}"),
            key => key.to_owned(),
        };
        let e = expect_error(&text, Some(line), &field, &[says]);
        for rust in [
            "i64",
            "u64",
            "i128",
            "u32",
            "invalid type",
            "map",
            "sequence",
            "unit",
        ] {
            assert!(!e.to_string().contains(rust), "{e} speaks of `{rust}`");
        }
    }
    expect_error(
        "[1, 2]",
        Some(1),
        "",
        &["expected a replay (a JSON object), found an array"],
    );
}

#[test]
fn errors_quote_only_an_excerpt_of_a_huge_value() {
    let huge = "y".repeat(100_000);
    let cases = [
        ("\"gpuwars-replay\"", format!("\"{huge}\""), "format"),
        (
            "\"0x0123456789abcdef\"",
            format!("\"{huge}\""),
            "state_hash",
        ),
        (
            "\"seed\": 4294967295",
            format!("\"seed\": \"{huge}\""),
            "seed",
        ),
    ];
    for (from, to, field) in cases {
        let (text, line) = mutate(from, &to);
        let e = expect_error(&text, Some(line), field, &["…"]);
        assert!(e.to_string().len() < 400, "{e}");
    }
    let (text, line) = mutate("\"seed\"", &format!("\"{huge}\": 1,\n  \"seed\""));
    let e = Replay::parse(&text, "key.json").expect_err("an unknown key");
    assert_eq!(e.line, Some(line));
    assert!(e.to_string().len() < 400, "{e}");
}

#[test]
fn nesting_too_deep_has_a_line() {
    let (text, line) = mutate(RUN, &format!("{}1{}", "[".repeat(1000), "]".repeat(1000)));
    let e = Replay::parse(&text, "deep.json").expect_err("too deep");
    assert_eq!(e.line, Some(line), "{e}");
}

#[test]
fn only_regular_files_of_a_bounded_size_are_read() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let e = Replay::load(dir.path()).expect_err("a folder");
    assert!(e.problem.contains("it is a folder"), "{e}");
    // Devices and named pipes as files in a folder are Unix's.
    #[cfg(unix)]
    {
        let e = Replay::load(Path::new("/dev/zero")).expect_err("a device");
        assert!(e.problem.contains("it is a device"), "{e}");
        let fifo = dir.path().join("pipe.json");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|status| status.success()) {
            let e = Replay::load(&fifo).expect_err("a named pipe");
            assert!(e.problem.contains("it is a named pipe"), "{e}");
        }
    }
    let big = dir.path().join("big.json");
    let file = std::fs::File::create(&big).expect("created");
    file.set_len(gpuwars::game::replay::MAX_REPLAY_BYTES + 1)
        .expect("a sparse file");
    let e = Replay::load(&big).expect_err("too large");
    assert!(e.problem.contains("(allowed at most 67,108,864)"), "{e}");
}

#[test]
fn save_leaves_what_it_does_not_own_alone() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let folder = dir.path().join("folder");
    std::fs::create_dir(&folder).expect("a folder");
    let e = sample().save(&folder).expect_err("a folder");
    assert!(e.problem.contains("it is a folder, left as it is"), "{e}");
    assert!(folder.is_dir());

    // Symbolic links (which Windows gives only to administrators and Wine shows as files)
    // and named pipes as files in a folder are Unix's.
    #[cfg(unix)]
    {
        let target = dir.path().join("target.json");
        std::fs::write(&target, "kept").expect("written");
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink("target.json", &link).expect("a symbolic link");
        let e = sample().save(&link).expect_err("a symbolic link");
        let advice = format!("give {}", target.display());
        assert!(
            e.problem.contains("symbolic link") && e.problem.contains(&advice),
            "{e}"
        );
        assert!(e.problem.contains("remove the link first"), "{e}");
        assert!(link.symlink_metadata().unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "kept");

        let fifo = dir.path().join("pipe.json");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|status| status.success()) {
            let e = sample().save(&fifo).expect_err("a named pipe");
            assert!(
                e.problem.contains("it is a named pipe, left as it is"),
                "{e}"
            );
            use std::os::unix::fs::FileTypeExt;
            assert!(fifo.symlink_metadata().unwrap().file_type().is_fifo());
        }
    }
    let mut names = entries(dir.path());
    names.retain(|name| name != "pipe.json");
    let expected: &[&str] = match cfg!(unix) {
        true => &["folder", "link.json", "target.json"],
        false => &["folder"],
    };
    assert_eq!(names, expected, "nothing is left behind");
    assert!(entries(&folder).is_empty());
}
