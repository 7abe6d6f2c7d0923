//! Replays: the per-step [`Input`] of one game, with what it takes to run it again (the scene's
//! TOML text, the seed) and the final state hash it must reproduce.
//!
//! The file is JSON, versioned, with the inputs run-length encoded one run per line:
//!
//! ```json
//! {
//!   "format": "gpuwars-replay",
//!   "version": 2,
//!   "scene": "paper",
//!   "scene_toml": "<the whole scene TOML text>",
//!   "seed": 1,
//!   "backend": "cpu",
//!   "steps": 3600,
//!   "state_hash": "0x0123456789abcdef",
//!   "inputs": [
//!     [12, 0, 0, 0, 0],
//!     [1, -707, 707, 16384, 1]
//!   ]
//! }
//! ```
//!
//! Each run is `[repeat, move_x, move_y, aim, fire]`. Reading checks everything and reports
//! the line and the field of the first problem, in words (never a Rust type), quoting at
//! most a short excerpt of a value; it never panics. A replay holds at most [`MAX_STEPS`]
//! steps, its scene at most [`MAX_SCENE_BYTES`] bytes, and its file at most
//! [`MAX_REPLAY_BYTES`] bytes: anything larger is refused before its inputs are allocated.

use std::path::Path;

use gpuwars_kernels::game::control::Input;

use super::Scene;
use super::scene::SceneError;
use crate::BackendKind;
use crate::files::positioned::{Doc, Entry, Node, Value};
use crate::files::{MAX_SCENE_BYTES, excerpt, json_problem, line_of, read_text, thousands};

/// The `format` of every replay file.
pub const FORMAT: &str = "gpuwars-replay";
/// The `version` this build writes. Version 2 began when worlds of 8,192 slots and more
/// began renumbering their bodies by default (`Physics::renumber_every`), which changed
/// the game those scenes play.
pub const VERSION: u64 = 2;
/// The oldest `version` this build reads: a version-1 replay is played as it was recorded,
/// its scene never renumbering (see [`Replay::scene`]).
pub const FIRST_VERSION: u64 = 1;
/// The most steps a replay, and a game played without a window, may hold: 4.6 hours of
/// game time at 60 steps a second, 16 MB of inputs in memory.
pub const MAX_STEPS: u64 = 1_000_000;
/// Most bytes of a replay file: more than a replay of [`MAX_STEPS`] steps, each a run of
/// its own, and a scene of [`MAX_SCENE_BYTES`] bytes, escaped, take.
pub const MAX_REPLAY_BYTES: u64 = 64 << 20;

/// The keys read first, before the syntax is judged.
const HEADER: [&str; 2] = ["format", "version"];
/// The keys of the top-level object, in the order they are written.
const KEYS: &str = "format, version, scene, scene_toml, seed, backend, steps, state_hash, inputs";

/// One recorded game.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Replay {
    /// The file's version: [`VERSION`] for a game this build records.
    pub version: u64,
    /// Short name of the scene (`paper`, …).
    pub scene: String,
    /// The whole TOML text of the scene, so that the replay does not depend on a file that may
    /// change.
    pub scene_toml: String,
    /// The game's random seed.
    pub seed: u32,
    /// The backend that recorded it (informational: every backend gives the same hash).
    pub backend: BackendKind,
    /// The state hash after the last step.
    pub state_hash: u64,
    /// The input of each step, in order.
    pub inputs: Vec<Input>,
}

/// What is wrong with a replay file, and where (see [`crate::files::FileError`]).
pub type ReplayError = crate::files::FileError;

impl Replay {
    /// The JSON text (runs merged, one run per line).
    pub fn to_json(&self) -> String {
        let runs: Vec<String> = self
            .inputs
            .chunk_by(|a, b| a == b)
            .map(|run| {
                let i = run[0];
                let n = run.len();
                format!(
                    "    [{n}, {}, {}, {}, {}]",
                    i.move_x, i.move_y, i.aim, i.fire
                )
            })
            .collect();
        let inputs = if runs.is_empty() {
            "[]".to_owned()
        } else {
            format!("[\n{}\n  ]", runs.join(",\n"))
        };
        // Value's Display escapes a string exactly as JSON needs, and cannot fail.
        let string = |s: &str| serde_json::Value::from(s).to_string();
        format!(
            "{{\n  \"format\": {},\n  \"version\": {},\n  \"scene\": {},\n  \
             \"scene_toml\": {},\n  \"seed\": {},\n  \"backend\": {},\n  \"steps\": {},\n  \
             \"state_hash\": \"0x{:016x}\",\n  \"inputs\": {inputs}\n}}\n",
            string(FORMAT),
            self.version,
            string(&self.scene),
            string(&self.scene_toml),
            self.seed,
            string(&self.backend.to_string()),
            self.inputs.len(),
            self.state_hash,
        )
    }

    /// Parses and validates; `origin` names the file in errors. A byte-order mark at the
    /// start is skipped, as the scene reader does.
    pub fn parse(text: &str, origin: &str) -> Result<Replay, ReplayError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let doc = Doc { text, origin };
        let entries = read_header(&doc)?;
        let fields = read_fields(&entries, None)?;
        let missing = |key: &str| missing(&doc, key);
        let version = fields.version.ok_or_else(|| missing("version"))?;
        let scene = fields.scene.ok_or_else(|| missing("scene"))?;
        let scene_toml = fields.scene_toml.ok_or_else(|| missing("scene_toml"))?;
        let seed = fields.seed.ok_or_else(|| missing("seed"))?;
        let backend = fields.backend.ok_or_else(|| missing("backend"))?;
        let (steps, steps_line) = fields.steps.ok_or_else(|| missing("steps"))?;
        let state_hash = fields.state_hash.ok_or_else(|| missing("state_hash"))?;
        let runs = fields.inputs.ok_or_else(|| missing("inputs"))?;

        // The runs were checked to add up to at most MAX_STEPS as they were read.
        let total: u64 = runs.iter().map(|&(repeat, _)| repeat).sum();
        let steps_error = |problem: String| ReplayError::new(origin, steps_line, "steps", problem);
        if total != steps {
            return Err(steps_error(format!(
                "{steps} does not match the inputs, whose runs add up to {total} steps"
            )));
        }
        // Reserved up front (at most MAX_STEPS inputs) so that a failure is an error, not
        // an abort.
        let mut inputs = Vec::new();
        usize::try_from(total)
            .ok()
            .and_then(|total| inputs.try_reserve_exact(total).ok())
            .ok_or_else(|| steps_error(format!("{steps} steps do not fit in memory")))?;
        for (repeat, input) in runs {
            // Each repeat is at most `total`, which fits in a usize (reserved above).
            inputs.extend(std::iter::repeat_n(input, repeat as usize));
        }
        Ok(Replay {
            version,
            scene,
            scene_toml,
            seed,
            backend,
            state_hash,
            inputs,
        })
    }

    /// The replay's scene, read from its `scene_toml` (`origin` names it in errors), as the
    /// game that recorded it played it: a replay older than [`VERSION`] was recorded before
    /// worlds renumbered their bodies by default, so its scene renumbers only if it says so.
    pub fn scene(&self, origin: &str) -> Result<Scene, SceneError> {
        let mut scene = Scene::from_toml(&self.scene_toml, origin)?;
        if scene.name != self.scene {
            let problem = format!(
                "\"{}\" is not the name of the scene its scene_toml holds (\"{}\")",
                excerpt(&self.scene),
                excerpt(&scene.name)
            );
            return Err(SceneError::new(origin, None, "scene", problem));
        }
        if self.version < VERSION {
            scene.world.physics.renumber_every.get_or_insert(0);
        }
        Ok(scene)
    }

    /// Reads and parses a file: a regular file of at most [`MAX_REPLAY_BYTES`] bytes of
    /// UTF-8 (see [`crate::files::read_text`]).
    pub fn load(path: &Path) -> Result<Replay, ReplayError> {
        let text = read_text(path, MAX_REPLAY_BYTES)?;
        let origin = path.display().to_string();
        Replay::parse(&text, &origin).map_err(|e| match Scene::from_toml(&text, &origin) {
            // A scene given where a replay was asked for: say so, not how JSON differs.
            Ok(scene) => ReplayError {
                line: None,
                problem: format!(
                    "not a replay but the scene `{}` (a replay is the JSON file `--record` \
                     writes; a scene is given with `--scene`)",
                    excerpt(&scene.name)
                ),
                ..e
            },
            Err(_) => e,
        })
    }

    /// Writes atomically (see [`crate::files::write_atomically`]): an existing regular file
    /// is replaced only on success, anything else at `path` is left alone, and on failure
    /// nothing is left behind. A replay that could not be read back (an input out of range,
    /// too many steps, too large a scene) is refused before anything is written.
    pub fn save(&self, path: &Path) -> Result<(), ReplayError> {
        self.check(&path.display().to_string())?;
        crate::files::write_atomically(path, self.to_json().as_bytes())
    }

    /// What [`Replay::parse`] would refuse in this replay's file.
    fn check(&self, origin: &str) -> Result<(), ReplayError> {
        if self.inputs.len() as u64 > MAX_STEPS {
            let problem = format!(
                "{} steps is out of range (allowed 0 to {}); not saved",
                thousands(self.inputs.len() as u64),
                thousands(MAX_STEPS)
            );
            return Err(ReplayError::new(origin, None, "inputs", problem));
        }
        if self.scene_toml.len() as u64 > MAX_SCENE_BYTES {
            let problem = scene_too_large(self.scene_toml.len()) + "; not saved";
            return Err(ReplayError::new(origin, None, "scene_toml", problem));
        }
        for (step, input) in self.inputs.iter().enumerate() {
            if let Some((field, allowed)) = input.problem() {
                let problem = format!("out of range (allowed {allowed}) in {input:?}; not saved");
                return Err(ReplayError::new(
                    origin,
                    None,
                    format!("inputs[{step}].{field}"),
                    problem,
                ));
            }
        }
        Ok(())
    }
}

/// The problem of a scene text of `bytes` bytes.
fn scene_too_large(bytes: usize) -> String {
    format!(
        "the scene is {} bytes (allowed at most {})",
        thousands(bytes as u64),
        thousands(MAX_SCENE_BYTES)
    )
}

/// Reads the top-level object's `format` and `version`, and only then, if they are right,
/// says what is wrong with the JSON after them: a file of another version is reported as
/// such, not as broken or as a pile of keys this build does not know. Returns the object's
/// entries, the text then known to be JSON.
fn read_header<'a>(doc: &'a Doc<'a>) -> Result<Vec<Entry<'a>>, ReplayError> {
    let (root, syntax) = Node::json(doc);
    let Value::Table(entries) = root.value()? else {
        return Err(root.expected("a replay (a JSON object)"));
    };
    // serde_json stops at the syntax error: what comes after it is never read, nor the
    // value of a key without its `:`.
    let (keys, in_value) = syntax
        .as_ref()
        .map_or((entries.len(), None), |s| (s.keys, s.in_value));
    let read = entries.get(..keys).unwrap_or(&entries);
    let header = read_fields(read, Some(in_value != Some(false)))?;
    if let Some(s) = syntax {
        // The key whose value serde_json was reading; its `:` is read with the value, but for
        // `format` and `version` before their readers take over.
        let key = s.keys.checked_sub(1).and_then(|k| entries.get(k));
        let blame = match (key, s.in_value) {
            (Some(e), Some(value)) if value || !HEADER.contains(&&*e.key) => &*e.key,
            _ => "",
        };
        let line = (s.error.line() > 0).then_some(s.error.line());
        let problem = json_problem(&s.error);
        return Err(ReplayError::new(doc.origin, line, blame, problem));
    }
    header.format.ok_or_else(|| missing(doc, "format"))?;
    header.version.ok_or_else(|| missing(doc, "version"))?;
    Ok(entries)
}

/// The error of a top-level `key` the replay lacks, at the line where its object ends.
fn missing(doc: &Doc<'_>, key: &str) -> ReplayError {
    let end = doc
        .text
        .rfind('}')
        .map(|at| line_of(doc.text.as_bytes(), at));
    let problem = match end {
        Some(line) => format!("missing (the replay's object ends at line {line} without it)"),
        None => "missing".to_owned(),
    };
    ReplayError::new(doc.origin, end, key, problem)
}

/// The values of the top-level keys, each read in the order written; `steps` with the line of
/// its key.
#[derive(Default)]
struct Fields {
    format: Option<()>,
    version: Option<u64>,
    scene: Option<String>,
    scene_toml: Option<String>,
    seed: Option<u32>,
    backend: Option<BackendKind>,
    steps: Option<(u64, Option<usize>)>,
    state_hash: Option<u64>,
    inputs: Option<Vec<(u64, Input)>>,
}

/// Reads the entries of the top-level object (see [`Fields`]); with `header`, only `format`
/// and `version`, and the value of the last entry only if `header` is true.
fn read_fields(entries: &[Entry<'_>], header: Option<bool>) -> Result<Fields, ReplayError> {
    let mut f = Fields::default();
    for (i, entry) in entries.iter().enumerate() {
        let node = &entry.node;
        let text = || node.string("a string");
        let read = header != Some(false) || i + 1 < entries.len();
        match &*entry.key {
            key if header.is_some() && !HEADER.contains(&key) => {}
            // A key without its `:` is seen (twice, say), its value never read.
            "format" if !read => store(&mut f.format, entry, || Ok(()))?,
            "version" if !read => store(&mut f.version, entry, || Ok(VERSION))?,
            "format" => store(&mut f.format, entry, || match text()? {
                format if format == FORMAT => Ok(()),
                other => Err(node.fail(format!(
                    "\"{}\" is not a GpuWars replay (allowed {FORMAT:?})",
                    excerpt(&other)
                ))),
            })?,
            "version" => store(&mut f.version, entry, || {
                let allowed = span(FIRST_VERSION, VERSION);
                whole(node, &allowed, |v| {
                    u64::try_from(v)
                        .ok()
                        .filter(|v| (FIRST_VERSION..=VERSION).contains(v))
                        .ok_or_else(|| {
                            format!("unsupported version {v} (this build reads versions {allowed})")
                        })
                })
            })?,
            "scene" => store(&mut f.scene, entry, text)?,
            "scene_toml" => store(&mut f.scene_toml, entry, || {
                let toml = text()?;
                match toml.len() as u64 > MAX_SCENE_BYTES {
                    true => Err(node.fail(scene_too_large(toml.len()))),
                    false => Ok(toml),
                }
            })?,
            "seed" => store(&mut f.seed, entry, || ranged(node, 0, u32::MAX))?,
            "backend" => store(&mut f.backend, entry, || {
                node.choice(
                    "backend",
                    &[("cpu", BackendKind::Cpu), ("cuda", BackendKind::Cuda)],
                )
            })?,
            "steps" => store(&mut f.steps, entry, || {
                // Found, as before, only if written without escapes.
                let plain = node.text().get(entry.key_span.clone()) == Some("\"steps\"");
                let line = plain.then(|| line_of(node.text().as_bytes(), entry.key_span.start));
                Ok((ranged(node, 0, MAX_STEPS)?, line))
            })?,
            "state_hash" => store(&mut f.state_hash, entry, || {
                parse_hash(&text()?).map_err(|problem| node.fail(problem))
            })?,
            "inputs" => store(&mut f.inputs, entry, || read_runs(node))?,
            _ => {
                let problem = format!("unknown key (allowed {KEYS})");
                return Err(entry.fail(problem));
            }
        }
    }
    Ok(f)
}

/// Reads the value of `entry` into `slot`; a key may appear once.
fn store<T>(
    slot: &mut Option<T>,
    entry: &Entry<'_>,
    read: impl FnOnce() -> Result<T, ReplayError>,
) -> Result<(), ReplayError> {
    if slot.is_some() {
        return Err(entry.fail("appears twice"));
    }
    *slot = Some(read()?);
    Ok(())
}

/// `0x` and 16 hex digits (either case).
fn parse_hash(s: &str) -> Result<u64, String> {
    s.strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .filter(|digits| digits.len() == 16 && digits.bytes().all(|b| b.is_ascii_hexdigit()))
        .and_then(|digits| u64::from_str_radix(digits, 16).ok())
        .ok_or_else(|| {
            let s = excerpt(s);
            format!("\"{s}\" is not a hash (allowed \"0x\" and 16 hex digits)")
        })
}

/// A whole number, turned into a `T` by `convert` (whose error is the problem); `allowed`
/// says what it may be, for the error about a value of another type.
fn whole<T>(
    node: &Node<'_>,
    allowed: &str,
    convert: impl FnOnce(i128) -> Result<T, String>,
) -> Result<T, ReplayError> {
    match node.integer(format_args!("a whole number (allowed {allowed})"))? {
        Some(v) => convert(v).map_err(|problem| node.fail(problem)),
        None => Err(node.fail(format!(
            "{} is out of range (allowed {allowed})",
            node.written()
        ))),
    }
}

/// `v` as a `T` in `lo..=hi`.
fn in_range<T: TryFrom<i128> + Into<i128> + Copy>(v: i128, lo: T, hi: T) -> Result<T, String> {
    T::try_from(v)
        .ok()
        .filter(|&t| (lo.into()..=hi.into()).contains(&t.into()))
        .ok_or_else(|| format!("{v} is out of range (allowed {})", span(lo, hi)))
}

/// `lo to hi`, with thousands separated.
fn span(lo: impl Into<i128>, hi: impl Into<i128>) -> String {
    format!("{} to {}", thousands(lo), thousands(hi))
}

/// An integer in `lo..=hi`.
fn ranged<T: TryFrom<i128> + Into<i128> + Copy>(
    node: &Node<'_>,
    lo: T,
    hi: T,
) -> Result<T, ReplayError> {
    whole(node, &span(lo, hi), |v| in_range(v, lo, hi))
}

/// The numbers of a run after the repeat, in file order.
const INPUT_FIELDS: [&str; 4] = ["move_x", "move_y", "aim", "fire"];

/// Stores `v` as number `k` of an [`Input`] (see [`INPUT_FIELDS`]), saturated to the field's
/// type (a negative value becomes `u32::MAX` in an unsigned one, so that it stays out of
/// range); returns whether `v` fitted unchanged.
fn set(input: &mut Input, k: usize, v: i128) -> bool {
    let signed = i32::try_from(v).unwrap_or(if v < 0 { i32::MIN } else { i32::MAX });
    let unsigned = u32::try_from(v).unwrap_or(u32::MAX);
    match k {
        0 => input.move_x = signed,
        1 => input.move_y = signed,
        2 => input.aim = unsigned,
        _ => input.fire = unsigned,
    }
    v == if k < 2 {
        signed.into()
    } else {
        unsigned.into()
    }
}

/// Number `k` of an input, checked by [`Input::problem`] on an input that is all zeros but
/// for it (so the ranges are the kernels' own).
fn input_number(node: &Node<'_>, k: usize) -> Result<i128, ReplayError> {
    let allowed = move |v| {
        let mut probe = Input::default();
        let fits = set(&mut probe, k, v);
        (probe.problem().map(|(_, allowed)| allowed), fits)
    };
    // The largest integer is out of any range the field has, if it has one.
    let any = allowed(i128::MAX).0.unwrap_or("any 32-bit integer");
    whole(node, any, |v| match allowed(v) {
        (Some(allowed), _) => Err(format!("{v} is out of range (allowed {allowed})")),
        (None, false) => Err(format!("{v} does not fit in 32 bits")),
        (None, true) => Ok(v),
    })
}

/// The `inputs` array: its runs as `(repeat, input)`, checked to add up to at most
/// [`MAX_STEPS`] as they are read, so that the error points at the run that passes it. A run
/// is read without a path, named only in an error.
fn read_runs(node: &Node<'_>) -> Result<Vec<(u64, Input)>, ReplayError> {
    const RUN: &str = "[repeat, move_x, move_y, aim, fire]";
    let (a_run, repeats) = (format!("a run {RUN}"), span(1, MAX_STEPS));
    let mut runs = Vec::new();
    let mut total = 0;
    for (i, run) in node.items(&format!("an array of runs {RUN}"))?.enumerate() {
        let name = |e: ReplayError, field: &str| ReplayError {
            field: format!("inputs[{i}]{field}"),
            ..e
        };
        // At the closing bracket, where the count is known.
        let length = |found: usize| {
            let numbers = match found {
                1 => "number",
                _ => "numbers",
            };
            let problem = format!("has {found} {numbers}, expected 5: {RUN}");
            name(run.fail_at(run.span().end.saturating_sub(1), problem), "")
        };
        let mut numbers = run.items(&a_run).map_err(|e| name(e, ""))?;
        let repeat = numbers.next().ok_or_else(|| length(0))?;
        let repeat = whole(&repeat, &repeats, |v| {
            let repeat = in_range(v, 1, MAX_STEPS)?;
            match total + repeat {
                sum if sum > MAX_STEPS => Err(format!(
                    "the runs so far add up to {} steps (allowed at most {})",
                    thousands(sum),
                    thousands(MAX_STEPS)
                )),
                _ => Ok(repeat),
            }
        })
        .map_err(|e| name(e, ".repeat"))?;
        let mut input = Input::default();
        for (k, field) in INPUT_FIELDS.into_iter().enumerate() {
            let number = numbers.next().ok_or_else(|| length(k + 1))?;
            let v = input_number(&number, k).map_err(|e| name(e, &format!(".{field}")))?;
            set(&mut input, k, v);
        }
        match numbers.count() {
            0 => {}
            more => return Err(length(1 + INPUT_FIELDS.len() + more)),
        }
        total += repeat;
        runs.push((repeat, input));
    }
    Ok(runs)
}
