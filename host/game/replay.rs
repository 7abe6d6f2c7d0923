//! Replays: the per-step [`Input`] of one game, with what it takes to run it again (the scene's
//! TOML text, the seed) and the final state hash it must reproduce.
//!
//! The file is JSON, versioned, with the inputs run-length encoded one run per line:
//!
//! ```json
//! {
//!   "format": "gpuwars-replay",
//!   "version": 1,
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

use std::cell::Cell;
use std::fmt::{self, Display};
use std::path::Path;

use gpuwars_kernels::game::control::Input;

use crate::files::{MAX_SCENE_BYTES, excerpt, json_problem, line_of, read_text, thousands};
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};

/// The `format` of every replay file.
pub const FORMAT: &str = "gpuwars-replay";
/// The `version` this build reads and writes.
pub const VERSION: u64 = 1;
/// The most steps a replay, and a game played without a window, may hold: 4.6 hours of
/// game time at 60 steps a second, 16 MB of inputs in memory.
pub const MAX_STEPS: u64 = 1_000_000;
/// Most bytes of a replay file: more than a replay of [`MAX_STEPS`] steps, each a run of
/// its own, and a scene of [`MAX_SCENE_BYTES`] bytes, escaped, take.
pub const MAX_REPLAY_BYTES: u64 = 64 << 20;

/// The keys of the top-level object, in the order they are written.
const KEYS: [&str; 9] = [
    "format",
    "version",
    "scene",
    "scene_toml",
    "seed",
    "backend",
    "steps",
    "state_hash",
    "inputs",
];

/// One recorded game.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Replay {
    /// Short name of the scene (`paper`, …).
    pub scene: String,
    /// The whole TOML text of the scene, so that the replay does not depend on a file that may
    /// change.
    pub scene_toml: String,
    /// The game's random seed.
    pub seed: u32,
    /// The backend that recorded it (informational: every backend gives the same hash).
    pub backend: String,
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
            "{{\n  \"format\": {},\n  \"version\": {VERSION},\n  \"scene\": {},\n  \
             \"scene_toml\": {},\n  \"seed\": {},\n  \"backend\": {},\n  \"steps\": {},\n  \
             \"state_hash\": \"0x{:016x}\",\n  \"inputs\": {inputs}\n}}\n",
            string(FORMAT),
            string(&self.scene),
            string(&self.scene_toml),
            self.seed,
            string(&self.backend),
            self.inputs.len(),
            self.state_hash,
        )
    }

    /// Parses and validates; `origin` names the file in errors. A byte-order mark at the
    /// start is skipped, as the scene reader does.
    pub fn parse(text: &str, origin: &str) -> Result<Replay, ReplayError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // The header first: a file of another version is reported as such, not as a pile of
        // keys this build does not know.
        let header = read_fields(text, origin, true)?;
        let missing = |key: &str| ReplayError::new(origin, None, key, "missing");
        header.format.ok_or_else(|| missing("format"))?;
        header.version.ok_or_else(|| missing("version"))?;

        let fields = read_fields(text, origin, false)?;
        let scene = fields.scene.ok_or_else(|| missing("scene"))?;
        let scene_toml = fields.scene_toml.ok_or_else(|| missing("scene_toml"))?;
        let seed = fields.seed.ok_or_else(|| missing("seed"))?;
        let backend = fields.backend.ok_or_else(|| missing("backend"))?;
        let steps = fields.steps.ok_or_else(|| missing("steps"))?;
        let state_hash = fields.state_hash.ok_or_else(|| missing("state_hash"))?;
        let runs = fields.inputs.ok_or_else(|| missing("inputs"))?;

        // The runs were checked to add up to at most MAX_STEPS as they were read.
        let total: u64 = runs.iter().map(|&(repeat, _)| repeat).sum();
        let steps_error =
            |problem: String| ReplayError::new(origin, key_line(text, "steps"), "steps", problem);
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
            scene,
            scene_toml,
            seed,
            backend,
            state_hash,
            inputs,
        })
    }

    /// Reads and parses a file: a regular file of at most [`MAX_REPLAY_BYTES`] bytes of
    /// UTF-8 (see [`crate::files::read_text`]).
    pub fn load(path: &Path) -> Result<Replay, ReplayError> {
        let text = read_text(path, MAX_REPLAY_BYTES)?;
        Replay::parse(&text, &path.display().to_string())
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

/// The line of the top-level key `key` in the JSON object `text`, if it is written plainly
/// (without escapes). serde_json gives no positions for values that parsed fine.
fn key_line(text: &str, key: &str) -> Option<usize> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'{' | b'[' => depth += 1,
            b'}' | b']' => depth = depth.saturating_sub(1),
            b'"' => {
                let start = i + 1;
                i = start;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                let is_key = depth == 1
                    && text
                        .get(i + 1..)
                        .is_some_and(|rest| rest.trim_start().starts_with(':'));
                if is_key && text.get(start..i) == Some(key) {
                    return Some(line_of(bytes, start));
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// The problem of a scene text of `bytes` bytes.
fn scene_too_large(bytes: usize) -> String {
    format!(
        "the scene is {} bytes (allowed at most {})",
        thousands(bytes as u64),
        thousands(MAX_SCENE_BYTES)
    )
}

/// The visitor methods for the JSON values a reader does not take: each is a [`refusal`]
/// that says what it found in words (`"ten"`, `an array`), never in serde's terms.
macro_rules! refuse {
    ($($kind:ident),*) => { $(refuse!(@ $kind);)* };
    (@ bool) => {
        fn visit_bool<E: de::Error>(self, v: bool) -> Result<Self::Value, E> {
            Err(refusal(&self, v))
        }
    };
    (@ integer) => {
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
            Err(refusal(&self, v))
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
            Err(refusal(&self, v))
        }
    };
    (@ float) => {
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
            Err(refusal(&self, format_args!("{v:?}")))
        }
    };
    (@ str) => {
        fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
            Err(refusal(&self, format_args!("\"{}\"", excerpt(v))))
        }
    };
    (@ null) => {
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            Err(refusal(&self, "null"))
        }
    };
    (@ array) => {
        fn visit_seq<A: SeqAccess<'de>>(self, _: A) -> Result<Self::Value, A::Error> {
            Err(refusal(&self, "an array"))
        }
    };
    (@ object) => {
        fn visit_map<A: MapAccess<'de>>(self, _: A) -> Result<Self::Value, A::Error> {
            Err(refusal(&self, "an object"))
        }
    };
}

/// The error of a `visitor` given a value it does not take: what it expected, and what it
/// `found`.
fn refusal<'de, E: de::Error>(visitor: &impl Visitor<'de>, found: impl Display) -> E {
    let expected: &dyn de::Expected = visitor;
    E::custom(format_args!("expected {expected}, found {found}"))
}

/// Runs the strict reader (or, with `header_only`, the one that reads only `format` and
/// `version`) over the whole text.
fn read_fields(text: &str, origin: &str, header_only: bool) -> Result<Fields, ReplayError> {
    let blame = Blame::default();
    let mut json = serde_json::Deserializer::from_str(text);
    let seed = Top {
        blame: &blame,
        header_only,
    };
    let fields = seed.deserialize(&mut json).and_then(|fields| {
        json.end()?;
        Ok(fields)
    });
    fields.map_err(|e| {
        let line = (e.line() > 0).then_some(e.line());
        let field = blame.0.take().unwrap_or_default();
        ReplayError::new(origin, line, field, json_problem(&e))
    })
}

/// The name of the value a parse error happened in. serde_json knows the line of an error but
/// not which key it was under, so the readers below note it on the way out.
#[derive(Default)]
struct Blame(Cell<Option<String>>);

impl Blame {
    /// Names `field` as where `result`'s error happened, unless a value inside it already was.
    fn name<T, E>(&self, field: impl Display, result: Result<T, E>) -> Result<T, E> {
        if result.is_err() {
            self.note(field);
        }
        result
    }

    /// An error about `field`.
    fn fail<E: de::Error>(&self, field: impl Display, problem: impl Display) -> E {
        self.note(field);
        E::custom(problem)
    }

    /// Notes `field` unless a field was noted already (the innermost is the most precise).
    fn note(&self, field: impl Display) {
        let inner = self.0.take();
        self.0.set(inner.or_else(|| Some(field.to_string())));
    }
}

/// Where in the file a value is.
#[derive(Clone, Copy)]
enum Field {
    /// A top-level key.
    Key(&'static str),
    /// Run `i` of `inputs`.
    Run(usize),
    /// One number of run `i`.
    Number(usize, &'static str),
}

impl Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Field::Key(key) => f.write_str(key),
            Field::Run(i) => write!(f, "inputs[{i}]"),
            Field::Number(i, name) => write!(f, "inputs[{i}].{name}"),
        }
    }
}

/// The top-level values, as read (all `None` but `format` and `version` for a header).
#[derive(Default)]
struct Fields {
    format: Option<()>,
    version: Option<()>,
    scene: Option<String>,
    scene_toml: Option<String>,
    seed: Option<u32>,
    backend: Option<String>,
    steps: Option<u64>,
    state_hash: Option<u64>,
    inputs: Option<Vec<(u64, Input)>>,
}

/// Reads the top-level object; with `header_only`, just `format` and `version` (the rest is
/// skipped, only its syntax checked).
struct Top<'a> {
    blame: &'a Blame,
    header_only: bool,
}

impl<'de> DeserializeSeed<'de> for Top<'_> {
    type Value = Fields;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Fields, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Top<'_> {
    type Value = Fields;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a replay (a JSON object)")
    }

    refuse!(bool, integer, float, str, null, array);

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Fields, A::Error> {
        let blame = self.blame;
        let mut f = Fields::default();
        while let Some(key) = map.next_key::<String>()? {
            let map = &mut map;
            match key.as_str() {
                "format" => {
                    let value = text(blame, "format", |s| match s {
                        FORMAT => Ok(()),
                        _ => Err(format!(
                            "\"{}\" is not a GpuWars replay (allowed {FORMAT:?})",
                            excerpt(s)
                        )),
                    });
                    store(map, blame, &mut f.format, "format", value)?;
                }
                "version" => {
                    let version = Int {
                        blame,
                        field: Field::Key("version"),
                        allowed: VERSION.to_string(),
                        convert: |v| match u64::try_from(v) {
                            Ok(VERSION) => Ok(()),
                            _ => Err(format!(
                                "unsupported version {v} (this build reads version {VERSION})"
                            )),
                        },
                    };
                    store(map, blame, &mut f.version, "version", version)?;
                }
                other if self.header_only => {
                    blame.name(other, map.next_value::<IgnoredAny>())?;
                }
                "scene" => store(map, blame, &mut f.scene, "scene", string(blame, "scene"))?,
                "scene_toml" => {
                    let value = text(blame, "scene_toml", |s| {
                        match s.len() as u64 > MAX_SCENE_BYTES {
                            true => Err(scene_too_large(s.len())),
                            false => Ok(s.to_owned()),
                        }
                    });
                    store(map, blame, &mut f.scene_toml, "scene_toml", value)?;
                }
                "seed" => {
                    let value = ranged(blame, Field::Key("seed"), 0, u32::MAX);
                    store(map, blame, &mut f.seed, "seed", value)?;
                }
                "backend" => {
                    let value = string(blame, "backend");
                    store(map, blame, &mut f.backend, "backend", value)?;
                }
                "steps" => {
                    let value = ranged(blame, Field::Key("steps"), 0, MAX_STEPS);
                    store(map, blame, &mut f.steps, "steps", value)?;
                }
                "state_hash" => {
                    let value = text(blame, "state_hash", parse_hash);
                    store(map, blame, &mut f.state_hash, "state_hash", value)?;
                }
                "inputs" => store(map, blame, &mut f.inputs, "inputs", Runs { blame })?,
                other => {
                    let allowed = KEYS.join(", ");
                    let problem = format!("unknown key (allowed {allowed})");
                    return Err(blame.fail(excerpt(other), problem));
                }
            }
        }
        Ok(f)
    }
}

/// Reads the value of `key` into `slot`; a key may appear once.
fn store<'de, A: MapAccess<'de>, S: DeserializeSeed<'de>>(
    map: &mut A,
    blame: &Blame,
    slot: &mut Option<S::Value>,
    key: &str,
    seed: S,
) -> Result<(), A::Error> {
    if slot.is_some() {
        return Err(blame.fail(key, "appears twice"));
    }
    *slot = Some(map.next_value_seed(seed)?);
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

/// A JSON string, turned into a `T` by `convert` (whose error is the problem).
struct Text<'a, F> {
    blame: &'a Blame,
    field: &'static str,
    convert: F,
}

/// A string checked by `convert`.
fn text<'a, T, F: FnOnce(&str) -> Result<T, String>>(
    blame: &'a Blame,
    field: &'static str,
    convert: F,
) -> Text<'a, F> {
    Text {
        blame,
        field,
        convert,
    }
}

/// Any string.
fn string<'a>(
    blame: &'a Blame,
    field: &'static str,
) -> Text<'a, impl FnOnce(&str) -> Result<String, String>> {
    text(blame, field, |s| Ok(s.to_owned()))
}

impl<'de, T, F: FnOnce(&str) -> Result<T, String>> DeserializeSeed<'de> for Text<'_, F> {
    type Value = T;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<T, D::Error> {
        let (blame, field) = (self.blame, self.field);
        blame.name(field, d.deserialize_any(self))
    }
}

impl<'de, T, F: FnOnce(&str) -> Result<T, String>> Visitor<'de> for Text<'_, F> {
    type Value = T;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a string")
    }

    refuse!(bool, integer, float, null, array, object);

    fn visit_str<E: de::Error>(self, s: &str) -> Result<T, E> {
        (self.convert)(s).map_err(E::custom)
    }
}

/// A JSON integer, turned into a `T` by `convert` (whose error is the problem); `allowed` says
/// what it may be, for the error about a value of another type.
struct Int<'a, F> {
    blame: &'a Blame,
    field: Field,
    allowed: String,
    convert: F,
}

impl<'de, T, F: FnOnce(i128) -> Result<T, String>> DeserializeSeed<'de> for Int<'_, F> {
    type Value = T;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<T, D::Error> {
        let (blame, field) = (self.blame, self.field);
        blame.name(field, d.deserialize_any(self))
    }
}

impl<'de, T, F: FnOnce(i128) -> Result<T, String>> Visitor<'de> for Int<'_, F> {
    type Value = T;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a whole number (allowed {})", self.allowed)
    }

    refuse!(bool, str, null, array, object);

    /// serde_json reads an integer beyond 64 bits as a float.
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<T, E> {
        match v.abs() >= 2f64.powi(63) {
            true => Err(E::custom(format_args!(
                "{v:?} is out of range (allowed {})",
                self.allowed
            ))),
            false => Err(refusal(&self, format_args!("{v:?}"))),
        }
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<T, E> {
        (self.convert)(v.into()).map_err(E::custom)
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<T, E> {
        (self.convert)(v.into()).map_err(E::custom)
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
    blame: &Blame,
    field: Field,
    lo: T,
    hi: T,
) -> Int<'_, impl FnOnce(i128) -> Result<T, String>> {
    Int {
        blame,
        field,
        allowed: span(lo, hi),
        convert: move |v| in_range(v, lo, hi),
    }
}

/// Stores `v` in one field of an [`Input`], saturated to the field's type (a negative value
/// becomes `u32::MAX` in an unsigned one, so that it stays out of range); returns whether `v`
/// fitted unchanged.
type Setter = fn(&mut Input, i128) -> bool;

/// The numbers of a run after the repeat, in file order.
const INPUT_FIELDS: [(&str, Setter); 4] = [
    ("move_x", |input, v| {
        input.move_x = saturate_i32(v);
        i128::from(input.move_x) == v
    }),
    ("move_y", |input, v| {
        input.move_y = saturate_i32(v);
        i128::from(input.move_y) == v
    }),
    ("aim", |input, v| {
        input.aim = u32::try_from(v).unwrap_or(u32::MAX);
        i128::from(input.aim) == v
    }),
    ("fire", |input, v| {
        input.fire = u32::try_from(v).unwrap_or(u32::MAX);
        i128::from(input.fire) == v
    }),
];

/// `v`, clamped to the range of an `i32`.
fn saturate_i32(v: i128) -> i32 {
    i32::try_from(v).unwrap_or(if v < 0 { i32::MIN } else { i32::MAX })
}

/// One number of an input, checked by [`Input::problem`] on an input that is all zeros but
/// for it (so the ranges are the kernels' own).
fn input_number<'a>(
    blame: &'a Blame,
    run: usize,
    (name, set): (&'static str, Setter),
) -> Int<'a, impl FnOnce(i128) -> Result<i128, String>> {
    let allowed = move |v| {
        let mut probe = Input::default();
        let fits = set(&mut probe, v);
        (probe.problem().map(|(_, allowed)| allowed), fits)
    };
    // The largest integer is out of any range the field has, if it has one.
    let any = allowed(i128::MAX).0.unwrap_or("any 32-bit integer");
    Int {
        blame,
        field: Field::Number(run, name),
        allowed: any.to_owned(),
        convert: move |v| match allowed(v) {
            (Some(allowed), _) => Err(format!("{v} is out of range (allowed {allowed})")),
            (None, false) => Err(format!("{v} does not fit in 32 bits")),
            (None, true) => Ok(v),
        },
    }
}

/// The `inputs` array: its runs as `(repeat, input)`.
struct Runs<'a> {
    blame: &'a Blame,
}

impl<'de> DeserializeSeed<'de> for Runs<'_> {
    type Value = Vec<(u64, Input)>;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        let blame = self.blame;
        blame.name("inputs", d.deserialize_any(self))
    }
}

impl<'de> Visitor<'de> for Runs<'_> {
    type Value = Vec<(u64, Input)>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an array of runs [repeat, move_x, move_y, aim, fire]")
    }

    refuse!(bool, integer, float, str, null, object);

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut runs = Vec::new();
        let mut total = 0;
        let run = |index, total| Run {
            blame: self.blame,
            index,
            total,
        };
        while let Some((repeat, input)) = seq.next_element_seed(run(runs.len(), total))? {
            total += repeat;
            runs.push((repeat, input));
        }
        Ok(runs)
    }
}

/// Run `index` of `inputs`; `total` is the steps of the runs before it.
struct Run<'a> {
    blame: &'a Blame,
    index: usize,
    total: u64,
}

impl<'de> DeserializeSeed<'de> for Run<'_> {
    type Value = (u64, Input);

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        let (blame, index) = (self.blame, self.index);
        blame.name(Field::Run(index), d.deserialize_any(self))
    }
}

impl<'de> Visitor<'de> for Run<'_> {
    type Value = (u64, Input);

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a run [repeat, move_x, move_y, aim, fire]")
    }

    refuse!(bool, integer, float, str, null, object);

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let Run {
            blame,
            index,
            total,
        } = self;
        let length = |found: usize| -> A::Error {
            blame.fail(
                Field::Run(index),
                format!("has {found} numbers, expected 5: [repeat, move_x, move_y, aim, fire]"),
            )
        };
        // Checked here, at the number, so the error points at this run's line.
        let repeat = Int {
            blame,
            field: Field::Number(index, "repeat"),
            allowed: span(1, MAX_STEPS),
            convert: |v| {
                let repeat = in_range(v, 1, MAX_STEPS)?;
                match total + repeat {
                    sum if sum > MAX_STEPS => Err(format!(
                        "the runs so far add up to {} steps (allowed at most {})",
                        thousands(sum),
                        thousands(MAX_STEPS)
                    )),
                    _ => Ok(repeat),
                }
            },
        };
        let repeat = seq.next_element_seed(repeat)?.ok_or_else(|| length(0))?;
        let mut input = Input::default();
        for (k, field) in INPUT_FIELDS.into_iter().enumerate() {
            let number = input_number(blame, index, field);
            let v = seq
                .next_element_seed(number)?
                .ok_or_else(|| length(k + 1))?;
            (field.1)(&mut input, v);
        }
        let mut found = 1 + INPUT_FIELDS.len();
        while seq.next_element::<IgnoredAny>()?.is_some() {
            found += 1;
        }
        if found > 1 + INPUT_FIELDS.len() {
            return Err(length(found));
        }
        Ok((repeat, input))
    }
}
