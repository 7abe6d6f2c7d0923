//! The inputs users share and type, generated and mutated: scene files, replays and command
//! lines. Each is accepted or refused with a clear error (on a line of the text, in a few
//! hundred characters, in the file's words rather than Rust's), and none panics, hangs or
//! gives a wrong result: a number read is the number written, a replay read writes back as
//! itself, and a scene that reads plays the same on any thread count.
//!
//! Each property runs `GPUWARS_FUZZ_CASES` cases (default [`DEFAULT_CASES`]), the one that
//! plays scenes a tenth of that; `PROPTEST_RNG_SEED=N` repeats a run. The long run:
//! `GPUWARS_FUZZ_CASES=200000 cargo test --release --test fuzz` (see docs/robustness.md).

use std::path::Path;
use std::time::{Duration, Instant};

use gpuwars::benchmark::compare;
use gpuwars::cli::{BenchCommand, Command};
use gpuwars::demo::{Report, RunOptions, demo};
use gpuwars::files::FileError;
use gpuwars::game::engine::footprint;
use gpuwars::game::replay::{FIRST_VERSION, MAX_STEPS, Replay, VERSION};
use gpuwars::game::scene::BUILT_IN;
use gpuwars::game::{Game, Scene};
use gpuwars::kernels::game::control::Input;
use gpuwars::sim::Shape;
use gpuwars::sim::spec::{MAX_MASS, MIN_MASS};
use gpuwars::{BackendKind, Device};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

/// Cases of each property unless `GPUWARS_FUZZ_CASES` says otherwise.
const DEFAULT_CASES: u32 = 10_000;
/// Longest a single input may take to read (far above what any takes: a hang, not a slow
/// machine).
const PATIENCE: Duration = Duration::from_secs(5);
/// Longest an error may be, file name and line included.
const MAX_ERROR_CHARS: usize = 800;
/// Words of Rust and serde that an error must not speak.
const RUST_WORDS: &[&str] = &[
    "i64",
    "u64",
    "i32",
    "u32",
    "u16",
    "i128",
    "f32",
    "f64",
    "..=",
    "invalid type",
    "invalid value",
    "invalid length",
    "sequence",
    "struct ",
    "invalid digit",
    "Parse",
    "os error",
];

/// Cases of each property.
fn cases() -> u32 {
    std::env::var("GPUWARS_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(DEFAULT_CASES)
}

/// A property of `cases` cases that writes no regression files into the tree. Inputs a
/// property passes over (a changed scene that does not read, for the one that plays them)
/// do not count, however many there are.
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        max_global_rejects: cases.saturating_mul(100),
        ..ProptestConfig::default()
    }
}

/// Runs `read`, which must finish within [`PATIENCE`].
fn timed<T>(what: &str, read: impl FnOnce() -> T) -> Result<T, TestCaseError> {
    let start = Instant::now();
    let out = read();
    let took = start.elapsed();
    prop_assert!(took < PATIENCE, "{what} took {took:?}");
    Ok(out)
}

/// An error a user can act on: short, on a line of `text` when it has one, in words.
fn check_error(e: &FileError, text: &str) -> Result<(), TestCaseError> {
    let lines = text.matches('\n').count() + 1;
    prop_assert!(
        e.line.is_none_or(|line| (1..=lines).contains(&line)),
        "line {:?} of {lines}: {e}",
        e.line
    );
    check_words(e, text)
}

/// An error short and in words; `text` is what it may quote.
fn check_words(e: &FileError, text: &str) -> Result<(), TestCaseError> {
    let shown = e.to_string();
    prop_assert!(shown.chars().count() <= MAX_ERROR_CHARS, "{shown}");
    prop_assert!(!e.problem.is_empty(), "{shown}");
    for word in RUST_WORDS {
        // A value quoted from the text may hold anything.
        let quoted = text.contains(word);
        prop_assert!(quoted || !shown.contains(word), "{shown:?} says `{word}`");
    }
    prop_assert!(!shown.contains('\u{1b}'), "{shown:?}");
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Scenes: one value changed, against the documented rules

/// What a scene's number may be.
#[derive(Clone, Copy, Debug)]
enum Rule {
    /// A number in `(low, high]`, or `[low, high]` when `closed`; compared as it will be
    /// stored (an `f32`) where `stored`, the bound being another value of the file.
    Real {
        low: f32,
        closed: bool,
        high: f32,
        stored: bool,
    },
    /// A whole number in `low..=high`.
    Whole { low: i128, high: i128 },
    /// A mass: `[MIN_MASS, MAX_MASS]`, or infinity.
    Mass,
}

const SIDE: f32 = 1.0e6;

fn above(low: f32, high: f32) -> Rule {
    Rule::Real {
        low,
        closed: false,
        high,
        stored: false,
    }
}

fn within(low: f32, high: f32) -> Rule {
    Rule::Real {
        low,
        closed: true,
        high,
        stored: false,
    }
}

/// `rule` with its upper bound another value of the file: compared as stored.
fn as_stored(rule: Rule) -> Rule {
    match rule {
        Rule::Real {
            low, closed, high, ..
        } => Rule::Real {
            low,
            closed,
            high,
            stored: true,
        },
        rule => rule,
    }
}

fn whole(low: impl Into<i128>, high: impl Into<i128>) -> Rule {
    Rule::Whole {
        low: low.into(),
        high: high.into(),
    }
}

/// One `key = number` line of a scene and where it belongs.
#[derive(Clone, Debug)]
struct Site {
    /// 0-based line.
    line: usize,
    /// `world`, `ship`, `fps`, `spawn`, `waves`, `kinds` or `behaviour`.
    table: &'static str,
    /// The wave's or the kind's index.
    index: usize,
    key: String,
}

impl Site {
    /// The field as errors name it.
    fn field(&self) -> String {
        match self.table {
            "waves" => format!("spawn.waves[{}].{}", self.index, self.key),
            "kinds" => format!("kinds[{}].{}", self.index, self.key),
            "behaviour" => format!("kinds[{}].behaviour.{}", self.index, self.key),
            table => format!("{table}.{}", self.key),
        }
    }

    /// What the value may be in `scene` (the scene as it was), with everything else as it
    /// is there.
    fn rule(&self, scene: &Scene) -> Option<Rule> {
        let kind = scene.world.kinds.get(self.index);
        let behaviour = scene.game.behaviours.get(self.index).copied().flatten();
        let tricky = behaviour.is_some_and(|b| b.machine == gpuwars::game::spec::Machine::Tricky);
        Some(match (self.table, self.key.as_str()) {
            ("world", "dt") => above(0.0, 1.0),
            ("world", "cell") => within(0.0, SIDE),
            ("ship", "fire_rate") => above(0.0, 1000.0),
            ("ship", _) => above(0.0, SIDE),
            ("fps", "start") => above(0.0, 10000.0),
            ("fps", "min") => as_stored(within(0.0, scene.game.fps.start)),
            ("fps", "recovery") => within(0.0, 10000.0),
            ("spawn", "distance") | ("waves", "at" | "speed") => within(0.0, SIDE),
            ("waves", "every") => above(0.0, SIDE),
            ("waves", "times") if scene.game.spawn.waves.get(self.index)?.every.is_none() => {
                whole(1, 1)
            }
            ("waves", "count" | "times") => whole(1, u32::MAX),
            ("kinds", "circle") => above(0.0, SIDE),
            ("kinds", "mass") => Rule::Mass,
            ("kinds", "max_speed" | "lifetime") => above(0.0, f32::INFINITY),
            ("kinds", "restitution") => within(0.0, 1.0),
            ("kinds", "capacity") => whole(1, 1u32 << 24),
            ("kinds", "energy") => whole(1, i32::MAX),
            ("kinds", "damage") => whole(0, i32::MAX),
            ("behaviour", "vision") => above(0.0, SIDE),
            ("behaviour", "speed") => as_stored(above(0.0, kind?.max_speed.min(SIDE))),
            ("behaviour", "low_energy") if tricky => whole(0, kind?.energy - 1),
            ("behaviour", "low_energy") => whole(0, 0),
            ("behaviour", "recovery") if tricky => within(0.0, SIDE),
            ("behaviour", "recovery") => within(0.0, 0.0),
            _ => return None,
        })
    }

    /// The value `scene` holds for this site.
    fn stored(&self, scene: &Scene) -> Option<f64> {
        let (world, game) = (&scene.world, &scene.game);
        let real = |x: f32| Some(f64::from(x));
        match (self.table, self.key.as_str()) {
            ("world", "dt") => real(world.dt),
            ("world", "cell") => real(world.vision),
            ("ship", "speed") => real(game.ship.speed),
            ("ship", "fire_rate") => real(game.ship.fire_rate),
            ("ship", "shot_speed") => real(game.ship.shot_speed),
            ("ship", "autopilot_sight") => real(game.ship.autopilot_sight),
            ("fps", "start") => real(game.fps.start),
            ("fps", "min") => real(game.fps.min),
            ("fps", "recovery") => real(game.fps.recovery),
            ("spawn", "distance") => real(game.spawn.distance),
            ("waves", key) => {
                let wave = game.spawn.waves.get(self.index)?;
                match key {
                    "at" => real(wave.at),
                    "every" => real(wave.every?),
                    "speed" => real(wave.speed),
                    "count" => Some(wave.count.into()),
                    "times" => Some(wave.times.into()),
                    _ => None,
                }
            }
            ("kinds", key) => {
                let kind = world.kinds.get(self.index)?;
                match key {
                    "circle" => match kind.shape {
                        Shape::Circle { radius } => real(radius),
                        Shape::Rect { .. } => None,
                    },
                    "mass" => real(kind.mass),
                    "restitution" => real(kind.restitution),
                    "max_speed" => real(kind.max_speed),
                    "lifetime" => real(kind.lifetime),
                    "capacity" => Some(kind.capacity.into()),
                    "energy" => Some(kind.energy.into()),
                    "damage" => Some(kind.damage.into()),
                    _ => None,
                }
            }
            ("behaviour", key) => {
                let b = game.behaviours.get(self.index).copied().flatten()?;
                match key {
                    "vision" => real(b.vision),
                    "speed" => real(b.speed),
                    "low_energy" => Some(b.low_energy.into()),
                    "recovery" => real(b.recovery),
                    _ => None,
                }
            }
            _ => None,
        }
    }
}

/// Every `key = number` line of `text`, with its table.
fn sites(text: &str) -> Vec<Site> {
    let (mut table, mut waves, mut kinds) = ("", 0usize, 0usize);
    let mut found = Vec::new();
    for (line, content) in text.lines().enumerate() {
        let content = content.trim();
        match content {
            "[world]" => table = "world",
            "[ship]" => table = "ship",
            "[fps]" => table = "fps",
            "[spawn]" => table = "spawn",
            "[[spawn.waves]]" => (table, waves) = ("waves", waves + 1),
            "[[kinds]]" => (table, kinds) = ("kinds", kinds + 1),
            "[kinds.behaviour]" => table = "behaviour",
            _ => {}
        }
        let Some((key, value)) = content.split_once(" = ") else {
            continue;
        };
        let numeric = value.starts_with(|c: char| c.is_ascii_digit() || c == '-');
        if !numeric || table.is_empty() {
            continue;
        }
        let index = match table {
            "waves" => waves - 1,
            "kinds" | "behaviour" => kinds - 1,
            _ => 0,
        };
        found.push(Site {
            line,
            table,
            index,
            key: key.to_owned(),
        });
    }
    found
}

/// A TOML number as a person might write one, near every edge the rules have.
fn number_text() -> impl Strategy<Value = String> {
    let edges = prop::sample::select(vec![
        "0",
        "0.0",
        "-0.0",
        "1",
        "-1",
        "1.0",
        "1e39",
        "-1e39",
        "1e-50",
        "1e-40",
        "1e-38",
        "1.1754944e-38",
        "1.1754943e-38",
        "1.17549435e-38",
        "3.4028235e38",
        "3.4028236e38",
        "1e400",
        "-1e400",
        "1e-400",
        "5e-324",
        "inf",
        "-inf",
        "+inf",
        "nan",
        "-nan",
        "+nan",
        "1000",
        "1000.0000001",
        "10000",
        "10000.000001",
        "1000000",
        "1000000.0000001",
        "999999.99999999",
        "1.00000001",
        "0.99999999",
        "0.016666668",
        "60.0000001",
        "16777216",
        "16777217",
        "16777152",
        "2147483647",
        "2147483648",
        "-2147483648",
        "4294967295",
        "4294967296",
        "9223372036854775807",
        "-9223372036854775808",
        "99999999999999999999",
        "0x10",
        "0xffffffff",
        "0o17",
        "0b101",
        "1_000",
        "1_000.5",
        "+5",
    ])
    .prop_map(str::to_owned);
    prop_oneof![
        3 => edges,
        1 => any::<f64>().prop_map(float_text),
        1 => (-2.0f64..2.0).prop_map(float_text),
        1 => (0.0f64..2e6).prop_map(float_text),
        1 => any::<i64>().prop_map(|v| v.to_string()),
        1 => (0u32..3_000_000).prop_map(|v| v.to_string()),
    ]
}

/// `x` as a TOML float literal.
fn float_text(x: f64) -> String {
    if x.is_nan() {
        "nan".to_owned()
    } else if x.is_infinite() {
        format!("{}inf", if x < 0.0 { "-" } else { "" })
    } else {
        // Debug prints `1.0`, `1e39`, `-1.5e-7`: all TOML floats.
        format!("{x:?}")
    }
}

/// Something that is not a number.
fn not_a_number() -> impl Strategy<Value = String> {
    prop::sample::select(vec![
        "\"12\"",
        "'12'",
        "true",
        "false",
        "[1.0]",
        "[]",
        "{}",
        "{ a = 1 }",
        "1979-05-27",
        "07:32:00",
        "\"\"",
    ])
    .prop_map(str::to_owned)
}

/// A number written as TOML `text`, as written (overflow and underflow kept apart from
/// infinity and 0), and whether it is whole; `None` if it is not a number.
fn written(text: &str) -> Option<(f64, bool)> {
    let plain = text.replace('_', "");
    for (prefix, radix) in [("0x", 16), ("0o", 8), ("0b", 2)] {
        if let Some(digits) = plain.strip_prefix(prefix) {
            return i128::from_str_radix(digits, radix)
                .ok()
                .map(|v| (v as f64, true));
        }
    }
    let is_float = plain.contains(['.', 'e', 'E', 'n', 'i']);
    let x: f64 = plain.parse().ok()?;
    let sign = if plain.starts_with('-') { -1.0 } else { 1.0 };
    let mantissa = plain.split(['e', 'E']).next().unwrap_or_default();
    let x = if x.is_infinite() && !plain.contains("inf") {
        sign * f64::MAX
    } else if x == 0.0 && mantissa.bytes().any(|b| (b'1'..=b'9').contains(&b)) {
        sign * f64::MIN_POSITIVE
    } else {
        x
    };
    Some((x, !is_float))
}

/// Whether `value` (as written) follows `rule`, as the docs state it.
fn follows(rule: Rule, value: &str) -> bool {
    let Some((x, integer)) = written(value) else {
        return false;
    };
    match rule {
        Rule::Whole { low, high } => {
            integer && written_int(value).is_some_and(|v| (low..=high).contains(&v))
        }
        Rule::Real {
            low,
            closed,
            high,
            stored: as_stored,
        } => {
            let (low, high) = (f64::from(low), f64::from(high));
            let compared = if as_stored { f64::from(x as f32) } else { x };
            let inside = if closed {
                compared >= low
            } else {
                compared > low
            } && compared <= high;
            let stored = x as f32;
            let storable = !(x.is_finite() && stored.is_infinite())
                && (x == 0.0 || x.abs() >= f64::from(f32::MIN_POSITIVE));
            inside && storable
        }
        Rule::Mass => {
            let (low, high) = (f64::from(MIN_MASS), f64::from(MAX_MASS));
            (x >= low && x <= high) || x == f64::INFINITY
        }
    }
}

/// An integer literal's value.
fn written_int(text: &str) -> Option<i128> {
    let plain = text.replace('_', "");
    let plain = plain.strip_prefix('+').unwrap_or(&plain);
    for (prefix, radix) in [("0x", 16), ("0o", 8), ("0b", 2)] {
        if let Some(digits) = plain.strip_prefix(prefix) {
            return i128::from_str_radix(digits, radix).ok();
        }
    }
    plain.parse().ok()
}

/// `text` with line `line`'s value replaced by `value`.
fn with_value(text: &str, line: usize, value: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let (key, _) = lines[line].split_once(" = ").expect("a key line");
    lines[line] = format!("{key} = {value}");
    lines.join("\n") + "\n"
}

/// Fields whose own range depends on another's, and what their refusal says: the spawn
/// distance against the field's size.
const ACROSS: &[(&str, &str)] = &[("spawn.distance", "farther than any place of the")];

/// The scenes whose values are changed (the large ones read like the others).
fn base_scenes() -> impl Strategy<Value = usize> {
    0..BUILT_IN.len()
}

proptest! {
    #![proptest_config(config(cases()))]

    /// One number of a built-in scene, written anew: read exactly as written or refused on
    /// its own line and field, as the documented range says.
    #[test]
    fn a_scene_number_is_read_as_written_or_refused_where_it_is(
        scene in base_scenes(),
        pick in any::<prop::sample::Index>(),
        value in prop_oneof![5 => number_text(), 1 => not_a_number()],
    ) {
        let base = BUILT_IN[scene].source;
        let original = Scene::from_toml(base, "base").unwrap();
        let all = sites(base);
        let site = pick.get(&all);
        let Some(rule) = site.rule(&original) else {
            return Err(TestCaseError::reject("not a checked number"));
        };
        let text = with_value(base, site.line, &value);
        let read = timed("a scene", || Scene::from_toml(&text, "fuzzed.toml"))?;
        let field = site.field();
        match (read, follows(rule, &value)) {
            (Ok(scene), true) => {
                let stored = site.stored(&scene).expect("a stored value");
                let (x, _) = written(&value).unwrap();
                let expected = match rule {
                    Rule::Real { .. } | Rule::Mass => f64::from(x as f32),
                    Rule::Whole { .. } => written_int(&value).unwrap() as f64,
                };
                prop_assert!(
                    stored == expected || (stored.is_nan() && expected.is_nan()),
                    "{field} = {value} was read as {stored}"
                );
            }
            (Ok(_), false) => prop_assert!(false, "{field} = {value} was accepted against {rule:?}"),
            (Err(e), follows) => {
                check_error(&e, &text)?;
                if follows {
                    // Only a rule across values may refuse a value in its own range, and it
                    // names another field, or is one of this field's own against another.
                    let own = ACROSS.iter().any(|&(f, says)| f == field && e.problem.contains(says));
                    prop_assert!(e.field != field || own, "{}", e);
                } else {
                    prop_assert_eq!(&e.field, &field, "{}", e);
                    prop_assert_eq!(e.line, Some(site.line + 1), "{}", e);
                }
            }
        }
    }
}

/// Edits to a scene's text: anything TOML has, and what it has not.
fn scene_edit() -> impl Strategy<Value = Edit> {
    let tokens = prop::sample::select(vec![
        "[",
        "]",
        "[[",
        "]]",
        "{",
        "}",
        "=",
        "\"",
        "'",
        ",",
        ".",
        "#",
        "\n",
        "\r\n",
        " ",
        "-",
        "+",
        "e",
        "inf",
        "nan",
        "1e39",
        "1e-50",
        "0x",
        "_",
        "true",
        "\\",
        "\\u0000",
        "\u{feff}",
        "\u{0}",
        "\u{1b}[2J",
        "é",
        "[kinds]",
        "[[kinds]]",
        "[kinds.behaviour]",
        "[[spawn.waves]]",
        "name = \"x\"",
        "x.x.x.x.x.x.x.x.x",
        "capacity = 16777216",
        "energy = 2147483647",
        "mass = inf",
        "\"\"\"",
        "'''",
        "1979-05-27T07:32:00Z",
    ]);
    edit(tokens.prop_map(str::to_owned))
}

/// One change to a text: a character replaced, a token inserted, a range deleted, a line
/// repeated, the text cut.
#[derive(Clone, Debug)]
enum Edit {
    Replace(prop::sample::Index, char),
    Insert(prop::sample::Index, String),
    Delete(prop::sample::Index, usize),
    Repeat(prop::sample::Index, usize),
    Cut(prop::sample::Index),
}

fn edit(tokens: impl Strategy<Value = String> + Clone) -> impl Strategy<Value = Edit> {
    prop_oneof![
        2 => (any::<prop::sample::Index>(), any::<char>()).prop_map(|(at, c)| Edit::Replace(at, c)),
        3 => (any::<prop::sample::Index>(), tokens).prop_map(|(at, t)| Edit::Insert(at, t)),
        2 => (any::<prop::sample::Index>(), 1usize..40).prop_map(|(at, n)| Edit::Delete(at, n)),
        1 => (any::<prop::sample::Index>(), 1usize..300).prop_map(|(at, n)| Edit::Repeat(at, n)),
        1 => any::<prop::sample::Index>().prop_map(Edit::Cut),
    ]
}

/// The char boundary of `text` nearest below `index`'s pick.
fn boundary(text: &str, at: &prop::sample::Index) -> usize {
    let mut at = at.index(text.len() + 1);
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

impl Edit {
    fn apply(&self, text: &mut String) {
        match self {
            Edit::Replace(at, c) => {
                let at = boundary(text, at);
                if let Some(old) = text[at..].chars().next() {
                    text.replace_range(at..at + old.len_utf8(), c.encode_utf8(&mut [0; 4]));
                }
            }
            Edit::Insert(at, token) => {
                let at = boundary(text, at);
                text.insert_str(at, token);
            }
            Edit::Delete(at, n) => {
                let at = boundary(text, at);
                let end = text[at..]
                    .char_indices()
                    .nth(*n)
                    .map_or(text.len(), |(i, _)| at + i);
                text.replace_range(at..end, "");
            }
            Edit::Repeat(at, n) => {
                let at = boundary(text, at);
                let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
                let end = text[at..].find('\n').map_or(text.len(), |i| at + i + 1);
                let line = text[start..end].to_owned();
                text.insert_str(end, &line.repeat(*n));
            }
            Edit::Cut(at) => {
                let at = boundary(text, at);
                text.truncate(at);
            }
        }
    }
}

/// A scene that reads, played a few steps on one emulator thread and on three: the same
/// state, and no fault. Worlds too large to play quickly are skipped.
fn plays_alike(scene: &Scene) -> Result<(), TestCaseError> {
    static DEVICES: std::sync::OnceLock<(Device, Device)> = std::sync::OnceLock::new();
    let (one, three) = DEVICES.get_or_init(|| {
        (
            Device::cpu(Some(1), "fuzz").expect("the CPU emulation"),
            Device::cpu(Some(3), "fuzz").expect("the CPU emulation"),
        )
    });
    let (slots, bytes) = footprint(scene);
    if bytes > 32 << 20 || slots > 1 << 16 {
        return Ok(());
    }
    let hash = |device: &Device| -> Result<u64, TestCaseError> {
        let mut game =
            Game::new(device, scene, 3).map_err(|e| TestCaseError::fail(e.to_string()))?;
        for step in 0..6 {
            let input = (step % 2 == 0).then(Input::default);
            game.step(input)
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        game.state_hash()
            .map_err(|e| TestCaseError::fail(e.to_string()))
    };
    let a = timed("six steps", || hash(one))??;
    let b = timed("six steps", || hash(three))??;
    prop_assert_eq!(a, b, "the state depends on the thread count");
    let (report, _) = demo(one, scene, 3, 6, RunOptions::default())
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    figures_are_plausible(&report)
}

/// Every figure of a demo's report is finite and none is negative (its JSON holds no
/// `null` for a NaN), and its text says no `inf` or `NaN`.
fn figures_are_plausible(report: &Report) -> Result<(), TestCaseError> {
    fn walk(value: &serde_json::Value, path: &str) -> Result<(), TestCaseError> {
        match value {
            serde_json::Value::Null => Err(TestCaseError::fail(format!("{path} is null"))),
            serde_json::Value::Number(n) => {
                let x = n.as_f64().unwrap_or(f64::NAN);
                prop_assert!(x.is_finite() && x >= 0.0, "{} is {}", path, n);
                Ok(())
            }
            serde_json::Value::Array(items) => {
                (items.iter().enumerate()).try_for_each(|(i, v)| walk(v, &format!("{path}[{i}]")))
            }
            serde_json::Value::Object(map) => map
                .iter()
                .try_for_each(|(k, v)| walk(v, &format!("{path}.{k}"))),
            _ => Ok(()),
        }
    }
    walk(&serde_json::to_value(report).unwrap(), "report")?;
    let text = report.to_text();
    for word in text.split(|c: char| !c.is_alphanumeric()) {
        prop_assert!(word != "inf" && word != "NaN", "{}", text);
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(cases()))]

    /// Built-in scenes edited at random, up to three times: read or refused with a clear
    /// error; what reads is a valid scene whose source is the text.
    #[test]
    fn an_edited_scene_reads_or_is_refused_clearly(
        scene in base_scenes(),
        edits in prop::collection::vec(scene_edit(), 1..4),
    ) {
        let mut text = BUILT_IN[scene].source.to_owned();
        for edit in &edits {
            edit.apply(&mut text);
        }
        match timed("a scene", || Scene::from_toml(&text, "edited.toml"))? {
            Ok(scene) => {
                prop_assert!(scene.world.validate().is_ok());
                prop_assert_eq!(&scene.source, &text);
                prop_assert_eq!(Scene::from_toml(&text, "again"), Ok(scene));
            }
            Err(e) => check_error(&e, &text)?,
        }
    }
}

proptest! {
    #![proptest_config(config((cases() / 10).max(1)))]

    /// Scenes with one number changed, that read: they play alike on any thread count.
    #[test]
    fn a_changed_scene_that_reads_plays_alike_on_any_thread_count(
        scene in 0..5usize,
        pick in any::<prop::sample::Index>(),
        value in number_text(),
    ) {
        let base = BUILT_IN[scene].source;
        let all = sites(base);
        let text = with_value(base, pick.get(&all).line, &value);
        match Scene::from_toml(&text, "changed.toml") {
            Ok(scene) => plays_alike(&scene)?,
            Err(_) => return Err(TestCaseError::reject("refused")),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Replays

fn any_input() -> impl Strategy<Value = Input> {
    let stick = prop_oneof![Just(-1000), Just(0), Just(1000), -1000..=1000i32];
    (
        stick.clone(),
        stick,
        prop_oneof![Just(0u32), Just(65535), 0..65536u32],
        0..=1u32,
    )
        .prop_map(|(move_x, move_y, aim, fire)| Input {
            move_x,
            move_y,
            aim,
            fire,
        })
}

/// Any text a name or a scene may hold: quotes, escapes, control characters, any script.
fn any_text() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<String>(),
        "[\"\\\\\n\t\r\u{0}\u{1b}\u{feff}a-z ]{0,40}",
        Just(BUILT_IN[0].source.to_owned()),
    ]
}

prop_compose! {
    fn any_replay()(
        version in FIRST_VERSION..=VERSION,
        scene in any_text(),
        scene_toml in any_text(),
        seed in any::<u32>(),
        backend in prop_oneof![Just(BackendKind::Cpu), Just(BackendKind::Cuda)],
        state_hash in any::<u64>(),
        runs in prop::collection::vec((1usize..50, any_input()), 0..40),
    ) -> Replay {
        let inputs = runs.iter().flat_map(|&(n, input)| std::iter::repeat_n(input, n)).collect();
        Replay { version, scene, scene_toml, seed, backend, state_hash, inputs }
    }
}

/// The replay every mutation starts from.
fn sample_replay() -> Replay {
    let inputs = [
        (12, 0, 0, 0, 0),
        (1, -707, 707, 16384, 1),
        (3, 1000, -1000, 65535, 1),
    ]
    .iter()
    .flat_map(|&(n, x, y, aim, fire)| {
        std::iter::repeat_n(
            Input {
                move_x: x,
                move_y: y,
                aim,
                fire,
            },
            n,
        )
    })
    .collect();
    Replay {
        version: VERSION,
        scene: "kamikaze".into(),
        scene_toml: BUILT_IN[1].source.into(),
        seed: 7,
        backend: BackendKind::Cpu,
        state_hash: 0x0123_4567_89ab_cdef,
        inputs,
    }
}

/// JSON's punctuation: edits that break a file's structure.
const JSON_PUNCTUATION: [&str; 7] = ["{", "}", "[", "]", ",", ":", "\""];

/// Tokens for [`edit`] from JSON's punctuation and `more`.
fn json_tokens(more: &[&'static str]) -> Vec<&'static str> {
    JSON_PUNCTUATION.iter().chain(more).copied().collect()
}

/// Edits to a replay's JSON.
fn replay_edit() -> impl Strategy<Value = Edit> {
    let tokens = prop::sample::select(json_tokens(&[
        "\\",
        "\\u0000",
        "\\ud800",
        "null",
        "true",
        "-",
        "0",
        "-1",
        "1e400",
        "-0",
        "1.5",
        "4294967296",
        "1000001",
        "1000000",
        "999999999999",
        "18446744073709551616",
        "\"inputs\": [],",
        "\"seed\": 1,",
        "[1, 0, 0, 0, 0],",
        "[1000000, 0, 0, 0, 0],",
        "\u{feff}",
        "\n",
        " ",
        "é",
        "\u{1b}[2J",
        "[[[[[[[[[[",
        "\"0xffffffffffffffff\"",
        "\"gpuwars-replay\"",
    ]));
    edit(tokens.prop_map(str::to_owned))
}

proptest! {
    #![proptest_config(config(cases()))]

    /// Any replay writes as JSON that reads back as itself (atomically through a file for
    /// some).
    #[test]
    fn any_replay_reads_back_as_itself(replay in any_replay(), through_a_file in 0..20u8) {
        let json = replay.to_json();
        let read = timed("a replay", || Replay::parse(&json, "written.json"))?;
        prop_assert_eq!(read.as_ref(), Ok(&replay));
        if through_a_file == 0 {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("game.json");
            match replay.save(&path) {
                Ok(()) => prop_assert_eq!(Replay::load(&path), Ok(replay)),
                // A scene too large to save is refused, and nothing is written.
                Err(e) => {
                    prop_assert!(e.problem.contains("not saved"), "{}", e);
                    prop_assert!(!path.exists());
                }
            }
        }
    }

    /// A replay's JSON edited at random, up to three times: read or refused with a clear
    /// error; what reads holds valid inputs and writes back as what it read.
    #[test]
    fn an_edited_replay_reads_or_is_refused_clearly(
        edits in prop::collection::vec(replay_edit(), 1..4),
    ) {
        let mut text = sample_replay().to_json();
        for edit in &edits {
            edit.apply(&mut text);
        }
        match timed("a replay", || Replay::parse(&text, "edited.json"))? {
            Ok(replay) => {
                prop_assert!(replay.inputs.len() as u64 <= MAX_STEPS);
                prop_assert!(replay.inputs.iter().all(|input| input.problem().is_none()));
                prop_assert_eq!(Replay::parse(&replay.to_json(), "again"), Ok(replay));
            }
            Err(e) => check_error(&e, &text)?,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Benchmark summaries

/// A figure of a summary: ordinary, at the edges of a float, or not a number at all.
fn summary_figure() -> impl Strategy<Value = String> {
    let edges = prop::sample::select(vec![
        "0",
        "-0",
        "1",
        "60",
        "5e-324",
        "-5e-324",
        "2.2250738585072014e-308",
        "1e-300",
        "1e300",
        "1e308",
        "-1e308",
        "1.7976931348623157e308",
        "1e400",
        "-1e400",
        "18446744073709551616",
        "\"abc\"",
        "\"60\"",
        "null",
        "true",
        "[]",
        "{}",
    ]);
    prop_oneof![
        3 => edges.prop_map(str::to_owned),
        1 => any::<f64>().prop_filter("finite", |x| x.is_finite()).prop_map(|x| format!("{x:e}")),
    ]
}

/// A summary of `bench scale`'s shape with these figures.
fn summary(figures: &[String; 4]) -> String {
    let [median, p5, rate, bytes] = figures;
    format!(
        r#"{{
  "benchmark": "scale",
  "machine": {{ "backend": "cpu", "device": "CPU emulation", "commit": "abc" }},
  "copy_bandwidth": {median},
  "frames_per_s": {{ "median": {median}, "p5": {p5} }},
  "rows": [
    {{ "enemies": 1024, "steps_per_s": {rate}, "bytes_per_step": {bytes} }},
    {{ "enemies": 2048, "steps_per_s": {p5}, "bytes_per_step": {bytes} }}
  ]
}}
"#
    )
}

/// Edits to a summary's JSON.
fn summary_edit() -> impl Strategy<Value = Edit> {
    let tokens = prop::sample::select(json_tokens(&[
        "null",
        "1e400",
        "-1e308",
        "5e-324",
        "\"x\"",
        "\"benchmark\": \"paper\",",
        "\u{feff}",
        "\u{1b}[2J",
        "\n",
        "[[[[[[[[",
    ]));
    edit(tokens.prop_map(str::to_owned))
}

proptest! {
    #![proptest_config(config(cases()))]

    /// Two summaries with edge figures, edited at random: compared, every change a finite
    /// percent or n/a and every line of the table short; or refused in words, naming the
    /// figure that is not a number.
    #[test]
    fn a_bench_summary_compares_or_is_refused_clearly(
        a in prop::array::uniform4(summary_figure()),
        b in prop::array::uniform4(summary_figure()),
        edits in prop::collection::vec(summary_edit(), 0..3),
    ) {
        let mut b_text = summary(&b);
        for edit in &edits {
            edit.apply(&mut b_text);
        }
        let a_text = summary(&a);
        let read = |text: &str, name: &str| timed("a summary", || compare::parse(text, name));
        let (a_value, b_value) = match (read(&a_text, "a.json")?, read(&b_text, "b.json")?) {
            (Ok(a), Ok(b)) => (a, b),
            (Err(e), _) => return check_error(&e, &a_text),
            (_, Err(e)) => return check_error(&e, &b_text),
        };
        match compare::compare(&a_value, "a.json", &b_value, "b.json") {
            Ok(changes) => {
                for change in &changes {
                    prop_assert!(change.percent().is_none_or(f64::is_finite), "{change:?}");
                }
                for line in compare::to_text(&changes, &a_value, &b_value).lines() {
                    prop_assert!(line.chars().count() < 120, "{line}");
                    prop_assert!(!line.contains("inf") && !line.contains("NaN"), "{line}");
                    prop_assert!(!line.contains('\u{1b}'), "{line:?}");
                }
            }
            Err(e) => {
                let shown = e.to_string();
                prop_assert!(shown.chars().count() <= MAX_ERROR_CHARS, "{shown}");
                let words = shown.contains("not a number (found") || shown.contains("cannot be compared");
                prop_assert!(words, "{shown}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Command lines

/// A flag's value: valid ones, edges, and what a hand slips to.
fn flag_value() -> impl Strategy<Value = String> {
    let words = prop::sample::select(vec![
        "",
        "0",
        "1",
        "-1",
        "4",
        "1024",
        "1025",
        "65536",
        "1000000",
        "1000001",
        "4294967295",
        "4294967296",
        "99999999999999999999",
        "1.5",
        "1e3",
        "0x10",
        " 7 ",
        "x",
        "1920x1080",
        "0x0",
        "16384x16384",
        "16385x1",
        "1x",
        "x1",
        "ax3",
        "paper",
        "kamikaze",
        "nope",
        "/dev/null",
        "/dev/zero",
        "/",
        ".",
        "..",
        "no/such/dir/file",
        "auto",
        "cpu",
        "cuda",
        "none",
        "human",
        "kernel",
        "interop",
        "é",
        "--json",
        "-",
    ]);
    prop_oneof![
        4 => words.prop_map(str::to_owned),
        2 => prop::sample::select(fixture().paths.clone()),
        1 => any::<String>(),
        1 => any::<i64>().prop_map(|v| v.to_string()),
    ]
}

/// Files a command line may name, made once: a scene, a link to it and a second name of
/// it, a replay, a summary, a file not there yet, and their folder. Outputs collide with
/// inputs through them.
struct Fixture {
    _dir: tempfile::TempDir,
    paths: Vec<String>,
}

fn fixture() -> &'static Fixture {
    static FIXTURE: std::sync::OnceLock<Fixture> = std::sync::OnceLock::new();
    FIXTURE.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name);
        std::fs::write(path("k.toml"), BUILT_IN[1].source).unwrap();
        // A symbolic link where anyone may make one; Windows keeps them for administrators
        // (and Wine shows them as files), so there a second hard link stands in.
        #[cfg(unix)]
        std::os::unix::fs::symlink(path("k.toml"), path("link.toml")).unwrap();
        #[cfg(not(unix))]
        std::fs::hard_link(path("k.toml"), path("link.toml")).unwrap();
        std::fs::hard_link(path("k.toml"), path("hard.toml")).unwrap();
        std::fs::write(path("game.json"), sample_replay().to_json()).unwrap();
        let figures = ["60", "50", "1000", "4096"].map(str::to_owned);
        std::fs::write(path("bench-scale.json"), summary(&figures)).unwrap();
        let mut paths: Vec<String> = [
            "k.toml",
            "link.toml",
            "hard.toml",
            "game.json",
            "bench-scale.json",
            "new.png",
        ]
        .iter()
        .map(|name| path(name).to_str().unwrap().to_owned())
        .collect();
        paths.push(dir.path().to_str().unwrap().to_owned());
        paths.push(format!("{}/./k.toml", dir.path().display()));
        // Every file is made before the property's first case and kept until the end.
        let before = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(before, 5);
        Fixture { _dir: dir, paths }
    })
}

/// A command line: a command (or none), flags with and without values, stray words.
fn command_line() -> impl Strategy<Value = Vec<String>> {
    let command = prop::sample::select(vec![
        "demo",
        "play",
        "replay",
        "info",
        "scenes",
        "tradeoff",
        "bench paper",
        "bench scale",
        "bench compare",
        "",
        "x",
    ]);
    let flag = prop::sample::select(vec![
        "--backend",
        "--cpu-threads",
        "--scene",
        "--steps",
        "--seed",
        "--json",
        "--record",
        "--pilot",
        "--screenshot",
        "--frames-every",
        "--size",
        "--render",
        "--lag",
        "--no-graphs",
        "--profile",
        "--mute",
        "--no-vsync",
        "--quick",
        "--out",
        "--max",
        "--seconds",
        "--minutes",
        "--window",
        "--help",
        "--version",
        "-x",
        "--",
    ]);
    let word = prop_oneof![
        2 => (flag, prop::collection::vec(flag_value(), 0..3)).prop_map(|(flag, values)| {
            std::iter::once(flag.to_owned()).chain(values).collect::<Vec<_>>()
        }),
        1 => flag_value().prop_map(|v| vec![v]),
    ];
    (command, prop::collection::vec(word, 0..6)).prop_map(|(command, words)| {
        let mut line: Vec<String> = command.split_whitespace().map(str::to_owned).collect();
        line.extend(words.into_iter().flatten());
        line
    })
}

/// A command line that names only files, from the fixture's: where outputs collide with
/// inputs most often.
fn files_line() -> impl Strategy<Value = Vec<String>> {
    let command = prop::sample::select(vec![
        "demo",
        "play",
        "tradeoff",
        "replay",
        "bench compare",
        "bench paper",
        "bench scale",
    ]);
    let flag = prop::sample::select(vec!["--scene", "--record", "--screenshot", "--out", ""]);
    let path = prop::sample::select(fixture().paths.clone());
    let named = (flag, path).prop_map(|(flag, path)| match flag {
        "" => vec![path],
        flag => vec![flag.to_owned(), path],
    });
    (command, prop::collection::vec(named, 1..4)).prop_map(|(command, named)| {
        let mut line: Vec<String> = command.split_whitespace().map(str::to_owned).collect();
        line.extend(named.into_iter().flatten());
        line
    })
}

/// What the binary checks before it starts a run, none of which may panic; the errors it
/// gives are in words. Nothing is written, and what passes keeps every output off every
/// input and every other output.
fn checks_before_a_game(command: &Command) -> Result<(), TestCaseError> {
    let files = command.files();
    match timed("the files", || files.check())? {
        Ok(()) => {
            // The oracle: the real paths, links followed, are distinct.
            let real = |path: &Path| {
                let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
                let dir = std::fs::canonicalize(dir.unwrap_or(Path::new("."))).ok()?;
                let name = std::fs::canonicalize(path)
                    .ok()
                    .or_else(|| Some(dir.join(path.file_name()?)))?;
                Some(name)
            };
            // An input that is not there is not read over.
            let inputs: Vec<_> = files
                .inputs()
                .filter_map(|(_, p)| std::fs::canonicalize(p).ok())
                .collect();
            let outputs: Vec<_> = files.outputs().map(|(_, p)| real(p)).collect();
            for (i, out) in outputs.iter().enumerate() {
                let Some(out) = out else { continue };
                prop_assert!(!inputs.contains(out), "{out:?} is read and written");
                let again = outputs[..i].iter().flatten().any(|o| o == out);
                prop_assert!(!again, "{out:?} is written twice");
            }
        }
        Err(e) => check_words(&e, "")?,
    }
    let scene = |name: &str| -> Result<(), TestCaseError> {
        // Only names and paths that are quick to read (no game is played).
        if let Err(e) = timed("a scene", || Scene::load(name))? {
            check_words(&e, name)?;
        }
        Ok(())
    };
    match command {
        Command::Demo(args) => {
            if let Err(e) = args.frames(args.size) {
                prop_assert!(e.to_string().starts_with("--frames-every: "), "{e}");
            }
            scene(&args.scene)?;
        }
        Command::Play(args) => scene(&args.scene)?,
        Command::Tradeoff { scene: name, .. } | Command::Tune { scene: name, .. } => scene(name)?,
        Command::Replay { file, .. } => {
            if let Err(e) = timed("a replay", || Replay::load(file))? {
                check_words(&e, &file.display().to_string())?;
            }
        }
        Command::Bench {
            which: BenchCommand::Compare { a, b },
        } => {
            for path in [a, b] {
                if let Err(e) = timed("a summary", || compare::load(path))? {
                    check_words(&e, &path.display().to_string())?;
                }
            }
        }
        // Benchmarks run for minutes: only their files are checked.
        Command::Info { .. } | Command::Scenes | Command::Bench { .. } => {}
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(cases()))]

    /// Command lines: parsed, or refused with clap's usage and an error in words; what
    /// parses passes or fails the checks before a game without a panic.
    #[test]
    fn a_command_line_parses_or_is_refused_clearly(
        line in prop_oneof![3 => command_line(), 1 => files_line()],
    ) {
        let argv = std::iter::once("gpuwars".to_owned()).chain(line.iter().cloned());
        match timed("a command line", || gpuwars::cli::parse_from(argv))? {
            Ok(cli) => {
                if let Some(command) = &cli.command {
                    checks_before_a_game(command)?;
                }
            }
            Err(e) => {
                let shown = e.to_string();
                // clap's `invalid value 'x' for '--flag'` names the flag: words enough.
                for word in RUST_WORDS.iter().filter(|&&w| w != "invalid value") {
                    let typed = line.iter().any(|arg| arg.contains(word));
                    prop_assert!(typed || !shown.contains(word), "{shown:?} says `{word}`");
                }
            }
        }
    }
}
