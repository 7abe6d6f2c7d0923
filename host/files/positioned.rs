//! Documents read with positions: the one layer under the scene (TOML) and replay (JSON)
//! readers. A [`Node`] is one value, where it is written and its path as the file spells it
//! (`kinds[2].mass`, `inputs[17].aim`); its typed accessors check a value's type and range
//! and say what is wrong on the value's line, quoting at most an excerpt of it.
//!
//! TOML comes from the toml crate's spanned tree. serde_json keeps no positions, so a JSON
//! document is read by serde_json once, values skipped, for its first syntax error and how
//! far it got; then walked here one level at a time, as a reader asks, each leaf decoded by
//! serde_json in place. An array's items are walked one at a time, never held.

use std::borrow::Cow;
use std::cell::Cell;
use std::fmt;
use std::ops::Range;

use serde::Deserialize;
use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, Visitor};
use toml::Spanned;
use toml::de::DeValue;

use super::{FileError, excerpt, json_problem, line_of, number, thousands};

/// The text being read and what it is called, for errors.
pub struct Doc<'t> {
    /// The whole text.
    pub text: &'t str,
    /// The file's name, or what the text is.
    pub origin: &'t str,
}

/// One value of a document.
#[derive(Clone)]
pub struct Node<'a> {
    doc: &'a Doc<'a>,
    /// Where the value is written (a JSON document's: up to the end of the text).
    span: Range<usize>,
    /// Whether errors about it have a line (a TOML document as a whole has none).
    placed: bool,
    /// Its path, as the file spells it (empty for the document and an array's items).
    path: String,
    /// The parsed value for TOML; `None` for JSON, read from `span` when asked.
    toml: Option<&'a DeValue<'a>>,
}

/// What a value is, one level deep.
pub enum Value<'a> {
    /// A TOML table or a JSON object, in the order written.
    Table(Vec<Entry<'a>>),
    /// An array (see [`Node::items`]).
    Array,
    /// A string.
    Text(Cow<'a, str>),
    /// A whole number, `None` if beyond 128 bits (JSON's beyond 64 bits are floats, as
    /// serde_json reads them).
    Integer(Option<i128>),
    /// A float, as `written_float` reads a TOML one.
    Float(f64),
    /// `true` or `false`.
    Bool(bool),
    /// JSON's `null`.
    Null,
    /// A TOML date or time.
    Other,
}

/// A key of a table and its value.
pub struct Entry<'a> {
    /// The key.
    pub key: Cow<'a, str>,
    /// Where the key is written.
    pub key_span: Range<usize>,
    /// Its value, whose path is the table's and the key.
    pub node: Node<'a>,
}

/// The first syntax error of a JSON object, as serde_json reads one (keys as strings, values
/// skipped), and how far it got.
pub struct Syntax {
    /// The error.
    pub error: serde_json::Error,
    /// How many keys it read.
    pub keys: usize,
    /// `None` if it broke between entries, else whether it broke in the last key's value
    /// (`false`: at its `:`).
    pub in_value: Option<bool>,
}

/// What serde_json has read of an object (see [`Syntax`]).
#[derive(Default)]
struct Progress {
    keys: Cell<usize>,
    in_value: Cell<Option<bool>>,
}

impl<'de> Visitor<'de> for &Progress {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an object")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        while map.next_key::<String>()?.is_some() {
            self.keys.set(self.keys.get() + 1);
            self.in_value.set(Some(false));
            map.next_value_seed(self)?;
            self.in_value.set(None);
        }
        Ok(())
    }
}

/// A value, skipped once its `:` is read.
impl<'de> DeserializeSeed<'de> for &Progress {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        self.in_value.set(Some(true));
        IgnoredAny::deserialize(d).map(|_| ())
    }
}

impl<'a> Node<'a> {
    /// A TOML document, as the toml crate parsed it.
    pub fn toml(doc: &'a Doc<'a>, root: &'a Spanned<DeValue<'a>>) -> Self {
        Node {
            doc,
            span: root.span(),
            placed: false,
            path: String::new(),
            toml: Some(root.get_ref()),
        }
    }

    /// A JSON document: its top value and, if that is an object, its first syntax error (the
    /// value is then read only as far as serde_json read it).
    pub fn json(doc: &'a Doc<'a>) -> (Self, Option<Syntax>) {
        let bytes = doc.text.as_bytes();
        let start = skip_space(bytes, 0);
        let root = Node {
            doc,
            span: start..bytes.len(),
            placed: true,
            path: String::new(),
            toml: None,
        };
        if bytes.get(start) != Some(&b'{') {
            return (root, None);
        }
        let progress = Progress::default();
        let mut json = serde_json::Deserializer::from_str(doc.text);
        let read = json.deserialize_map(&progress).and_then(|()| json.end());
        let syntax = read.err().map(|error| Syntax {
            error,
            keys: progress.keys.get(),
            in_value: progress.in_value.get(),
        });
        (root, syntax)
    }

    /// Where it is written.
    pub fn span(&self) -> Range<usize> {
        self.span.clone()
    }

    /// The text of the document it is in.
    pub fn text(&self) -> &'a str {
        self.doc.text
    }

    /// The same value under another path.
    pub fn renamed(&self, path: String) -> Self {
        Node {
            path,
            ..self.clone()
        }
    }

    /// The path of key `key` in this table.
    pub fn join(&self, key: &str) -> String {
        match self.path.is_empty() {
            true => key.to_owned(),
            false => format!("{}.{key}", self.path),
        }
    }

    /// The 1-based line it starts on (none for a TOML document as a whole).
    pub fn line(&self) -> Option<usize> {
        self.placed
            .then(|| line_of(self.doc.text.as_bytes(), self.span.start))
    }

    /// An error about this value, on its line.
    pub fn fail(&self, problem: impl fmt::Display) -> FileError {
        FileError::new(self.doc.origin, self.line(), &self.path, problem)
    }

    /// An error about this value on the line of byte `at` (the end of an array, say).
    pub fn fail_at(&self, at: usize, problem: impl fmt::Display) -> FileError {
        let line = line_of(self.doc.text.as_bytes(), at);
        FileError::new(self.doc.origin, Some(line), &self.path, problem)
    }

    /// The JSON value that starts at byte `start`, at `path` (empty if serde_json cannot
    /// read it there).
    fn json_node(&self, start: usize, path: String) -> Node<'a> {
        let end = read_at::<IgnoredAny>(self.doc.text, start).map_or(start, |(_, end)| end);
        let span = start..end;
        Node {
            span,
            path,
            ..self.clone()
        }
    }

    /// The TOML value `value`, inside this one, at `path`.
    fn toml_child(&self, value: &'a Spanned<DeValue<'a>>, path: String) -> Node<'a> {
        let (span, toml) = (value.span(), Some(value.get_ref()));
        let placed = true;
        Node {
            span,
            placed,
            path,
            toml,
            ..self.clone()
        }
    }

    /// What the value is, one level deep. For JSON, a string or number serde_json cannot
    /// read (a lone surrogate, `1e400`) is an error on this value.
    pub fn value(&self) -> Result<Value<'a>, FileError> {
        let integer = |n: serde_json::Number| match (n.as_i64(), n.as_u64()) {
            (Some(v), _) => Value::Integer(Some(v.into())),
            (None, Some(v)) => Value::Integer(Some(v.into())),
            (None, None) => Value::Float(n.as_f64().unwrap_or(f64::NAN)),
        };
        Ok(match self.toml {
            Some(DeValue::Table(table)) => Value::Table(
                table
                    .iter()
                    .map(|(key, value)| Entry {
                        key: key.get_ref().clone(),
                        key_span: key.span(),
                        node: self.toml_child(value, self.join(&excerpt(key.get_ref()))),
                    })
                    .collect(),
            ),
            Some(DeValue::Array(_)) => Value::Array,
            Some(DeValue::String(text)) => Value::Text(Cow::Borrowed(text.as_ref())),
            Some(DeValue::Integer(integer)) => {
                Value::Integer(i128::from_str_radix(integer.as_str(), integer.radix()).ok())
            }
            Some(DeValue::Float(float)) => Value::Float(written_float(float.as_str())),
            Some(DeValue::Boolean(flag)) => Value::Bool(*flag),
            Some(DeValue::Datetime(_)) => Value::Other,
            None => {
                // Read in place, up to the end of the text, so that serde_json meets what
                // follows the value as it would in the whole text; on the line it would say.
                let at = self.span.start;
                let rest = self.doc.text.get(at..).unwrap_or_default();
                let leaf = match rest.as_bytes().first() {
                    Some(b'{') => return Ok(Value::Table(self.entries())),
                    Some(b'[') => return Ok(Value::Array),
                    _ => serde_json::Value::deserialize(&mut serde_json::Deserializer::from_str(
                        rest,
                    )),
                };
                match leaf.map_err(|e| {
                    let line = line_of(self.doc.text.as_bytes(), at) + e.line().saturating_sub(1);
                    FileError::new(self.doc.origin, Some(line), &self.path, json_problem(&e))
                })? {
                    serde_json::Value::String(text) => Value::Text(Cow::Owned(text)),
                    serde_json::Value::Number(n) => integer(n),
                    serde_json::Value::Bool(flag) => Value::Bool(flag),
                    _ => Value::Null,
                }
            }
        })
    }

    /// The entries of this JSON object in the order written, up to where its syntax breaks
    /// (a key without its `:` is listed last, as if it had one).
    fn entries(&self) -> Vec<Entry<'a>> {
        let (text, bytes) = (self.doc.text, self.doc.text.as_bytes());
        let mut entries = Vec::new();
        let mut at = skip_space(bytes, self.span.start + 1);
        while let Some((key, end)) = read_at::<String>(text, at) {
            let colon = skip_space(bytes, end);
            let node = self.json_node(skip_space(bytes, colon + 1), self.join(&excerpt(&key)));
            let next = skip_space(bytes, node.span.end);
            let key = Cow::Owned(key);
            entries.push(Entry {
                key,
                key_span: at..end,
                node,
            });
            if bytes.get(colon) != Some(&b':') || bytes.get(next) != Some(&b',') {
                break;
            }
            at = skip_space(bytes, next + 1);
        }
        entries
    }

    /// The items of the array this value must be (`what` it should hold, for the error), read
    /// one at a time, without paths (see [`Node::array`]).
    pub fn items(&self, what: &str) -> Result<Items<'a>, FileError> {
        match self.value()? {
            Value::Array => Ok(Items {
                next: match self.toml {
                    Some(_) => 0,
                    None => skip_space(self.doc.text.as_bytes(), self.span.start + 1),
                },
                node: self.renamed(String::new()),
            }),
            _ => Err(self.expected(what)),
        }
    }

    /// The items of the array this value must be, each at its path (`kinds[2]`).
    pub fn array(&self, what: &str) -> Result<Vec<Node<'a>>, FileError> {
        let items = self.items(what)?.enumerate();
        Ok(items
            .map(|(i, item)| item.renamed(format!("{}[{i}]", self.path)))
            .collect())
    }

    /// The value as an error quotes it: for TOML an excerpt as written, for JSON the value
    /// as read (`1e30`, `"text"`); what it is for a table or an array.
    pub fn written(&self) -> String {
        let json = self.toml.is_none();
        match self.value() {
            Ok(Value::Table(_)) if json => "an object".to_owned(),
            Ok(Value::Table(_)) => "a table".to_owned(),
            Ok(Value::Array) => "an array".to_owned(),
            Ok(Value::Text(text)) if json => format!("\"{}\"", excerpt(&text)),
            Ok(Value::Integer(Some(v))) if json => v.to_string(),
            Ok(Value::Float(v)) if json => format!("{v:?}"),
            Ok(Value::Bool(flag)) if json => flag.to_string(),
            Ok(Value::Null) => "null".to_owned(),
            _ => excerpt(self.doc.text.get(self.span.clone()).unwrap_or_default()),
        }
    }

    /// The error for a value of the wrong type.
    pub fn expected(&self, what: impl fmt::Display) -> FileError {
        let problem = format!("expected {what}, found {}", self.written());
        let bytes = self.doc.text.as_bytes();
        let at = skip_space(bytes, self.span.start + 1);
        match (self.toml, bytes.get(self.span.start), bytes.get(at)) {
            // serde_json says where it stands after looking past the bracket (and, in an
            // array, a `,`).
            (None, Some(b'['), Some(b',')) => self.fail_at(skip_space(bytes, at + 1), problem),
            (None, Some(b'[' | b'{'), _) => self.fail_at(at, problem),
            _ => self.fail(problem),
        }
    }

    /// The table this value must be, whose keys must be among `keys`.
    pub fn table(&self, keys: &'static [&'static str]) -> Result<Table<'a>, FileError> {
        let Value::Table(entries) = self.value()? else {
            return Err(self.expected("a table"));
        };
        let unknown = entries
            .iter()
            .filter(|entry| !keys.contains(&entry.key.as_ref()))
            .min_by_key(|entry| entry.key_span.start);
        if let Some(entry) = unknown {
            let allowed: Vec<String> = keys.iter().map(|k| format!("`{k}`")).collect();
            return Err(entry.fail(format!("unknown key (allowed {})", allowed.join(", "))));
        }
        Ok(Table {
            node: self.clone(),
            entries,
        })
    }

    /// A string (`what` it should be, for the error).
    pub fn string(&self, what: &str) -> Result<String, FileError> {
        match self.value()? {
            Value::Text(text) => Ok(text.into_owned()),
            _ => Err(self.expected(what)),
        }
    }

    /// A string of one line of printable text (a name, a description): no control
    /// character, which would reach a terminal as a command; `what` the value is, for the
    /// error.
    pub fn line_of_text(&self, what: &str) -> Result<String, FileError> {
        let text = self.string(what)?;
        match text.chars().enumerate().find(|(_, c)| c.is_control()) {
            Some((at, c)) => Err(self.fail(format!(
                "a control character (U+{:04X}, character {}) is not allowed (allowed: one \
                 line of printable text)",
                u32::from(c),
                at + 1
            ))),
            None => Ok(text),
        }
    }

    /// One of `options`, by name; `what` the value is, for the error.
    pub fn choice<T: Copy>(&self, what: &str, options: &[(&str, T)]) -> Result<T, FileError> {
        let names: Vec<String> = options
            .iter()
            .map(|(name, _)| format!("`{name}`"))
            .collect();
        let names = match names.split_last() {
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        };
        let article = match what.starts_with(['a', 'e', 'i', 'o', 'u']) {
            true => "an",
            false => "a",
        };
        let name = self.string(&format!("{article} {what} in quotes ({names})"))?;
        options
            .iter()
            .find(|(option, _)| *option == name)
            .map(|&(_, value)| value)
            .ok_or_else(|| {
                self.fail(format!(
                    "unknown {what} `{}` (allowed {names})",
                    excerpt(&name)
                ))
            })
    }

    /// `true` or `false`.
    pub fn flag(&self) -> Result<bool, FileError> {
        match self.value()? {
            Value::Bool(flag) => Ok(flag),
            _ => Err(self.expected("true or false")),
        }
    }

    /// A whole number as written (not a float, however round), `None` if too large to read
    /// (JSON's beyond 64 bits, which serde_json reads as floats); `what` it should be, for
    /// the error.
    pub fn integer(&self, what: impl fmt::Display) -> Result<Option<i128>, FileError> {
        match self.value()? {
            Value::Integer(v) => Ok(v),
            Value::Float(v) if self.toml.is_none() && v.abs() >= 2f64.powi(63) => Ok(None),
            _ => Err(self.expected(what)),
        }
    }

    /// A whole number from `low` to `high`, as written (not a float, however round).
    pub fn whole<T>(&self, low: T, high: T) -> Result<T, FileError>
    where
        T: Copy + Into<i128> + TryFrom<i128>,
    {
        let allowed = format!(
            "a whole number from {} to {}",
            thousands(low),
            thousands(high)
        );
        self.integer(&allowed)?
            .filter(|v| (low.into()..=high.into()).contains(v))
            .and_then(|v| T::try_from(v).ok())
            .ok_or_else(|| {
                self.fail(format!(
                    "{} is out of range (allowed {allowed})",
                    self.written()
                ))
            })
    }

    /// A number in `range`, checked as written, before it is rounded to an `f32`; a number
    /// the `f32` cannot hold (too large, or so close to 0 that it would lose its precision
    /// or become 0) is an error too. An integer stands for a float.
    pub fn real(&self, range: Interval) -> Result<f32, FileError> {
        let x = match self.value()? {
            Value::Integer(Some(v)) => v as f64,
            // Beyond 128 bits: out of any range, on its side.
            Value::Integer(None) if self.written().starts_with('-') => -f64::MAX,
            Value::Integer(None) => f64::MAX,
            Value::Float(x) => x,
            _ => return Err(self.expected(format_args!("a number in {range}"))),
        };
        let written = self.written();
        if !range.contains(x) {
            return Err(self.fail(format!("{written} is out of range (allowed {range})")));
        }
        let stored = x as f32;
        if x.is_finite() && stored.is_infinite() {
            return Err(self.fail(format!(
                "{written} is too large to store (allowed {range}, finite numbers at most {})",
                number(f32::MAX)
            )));
        }
        // As written, not as rounded: a value just under the bound would round up to it.
        let smallest = f64::from(f32::MIN_POSITIVE);
        if x != 0.0 && x.abs() < smallest {
            return Err(self.fail(format!(
                "{written} is too close to 0 to store (allowed {range}, numbers other than 0 \
                 at least {smallest:e} in size)"
            )));
        }
        Ok(stored)
    }

    /// `[x, y]`: exactly two numbers in `range`; `what` says what they are
    /// (`[width, height]`). An error about either names it by its index (`world.size[1]`).
    pub fn pair(&self, range: Interval, what: &str) -> Result<[f32; 2], FileError> {
        let items = self.array(&format!("an array {what} of two numbers in {range}"))?;
        let [x, y] = &items[..] else {
            let values = match items.len() {
                1 => "1 value".to_owned(),
                n => format!("{n} values"),
            };
            return Err(self.fail(format!(
                "has {values} (allowed exactly 2: {what}, each in {range})"
            )));
        };
        let read =
            |i: usize, item: &Node<'a>| item.renamed(format!("{}[{i}]", self.path)).real(range);
        Ok([read(0, x)?, read(1, y)?])
    }
}

/// The items of an array, read one at a time (see [`Node::items`]).
pub struct Items<'a> {
    /// The array, without its path.
    node: Node<'a>,
    /// The next item's index (TOML) or byte (JSON); `usize::MAX` past the last.
    next: usize,
}

impl<'a> Iterator for Items<'a> {
    type Item = Node<'a>;

    fn next(&mut self) -> Option<Node<'a>> {
        let node = &self.node;
        if let Some(DeValue::Array(items)) = node.toml {
            self.next += 1;
            return Some(node.toml_child(items.get(self.next - 1)?, String::new()));
        }
        let bytes = node.doc.text.as_bytes();
        if matches!(bytes.get(self.next), None | Some(b']')) {
            return None;
        }
        let item = node.json_node(self.next, String::new());
        let after = skip_space(bytes, item.span.end);
        self.next = match bytes.get(after) {
            Some(b',') => skip_space(bytes, after + 1),
            _ => usize::MAX,
        };
        Some(item)
    }
}

impl Entry<'_> {
    /// An error about the key itself (unknown, written twice): on its line in TOML, and in
    /// JSON where serde_json stands after reading it (at what follows).
    pub fn fail(&self, problem: impl fmt::Display) -> FileError {
        let at = match self.node.toml {
            Some(_) => self.key_span.start,
            None => skip_space(self.node.doc.text.as_bytes(), self.key_span.end),
        };
        self.node.fail_at(at, problem)
    }
}

/// The first byte at or after `at` that is not JSON whitespace.
fn skip_space(bytes: &[u8], mut at: usize) -> usize {
    while matches!(bytes.get(at), Some(b' ' | b'\n' | b'\t' | b'\r')) {
        at += 1;
    }
    at
}

/// The JSON value of type `T` that starts at byte `at`, and the byte after it; `None` if
/// serde_json cannot read one there.
fn read_at<'t, T: Deserialize<'t>>(text: &'t str, at: usize) -> Option<(T, usize)> {
    let mut values = serde_json::Deserializer::from_str(text.get(at..)?).into_iter();
    let value = values.next()?.ok()?;
    Some((value, at + values.byte_offset()))
}

/// A float as written in TOML (`1e39`, `-0.5`, `inf`, `nan`) as an `f64`: one that
/// overflows an `f64` becomes its largest finite value, and one that underflows it its
/// smallest normal one, so that neither passes as `inf` or 0.
fn written_float(text: &str) -> f64 {
    let x: f64 = text.parse().unwrap_or(f64::NAN);
    let negative = text.starts_with('-');
    let sign = if negative { -1.0 } else { 1.0 };
    let mantissa = text.split(['e', 'E']).next().unwrap_or_default();
    if x.is_infinite() && !text.contains("inf") {
        sign * f64::MAX
    } else if x == 0.0 && mantissa.bytes().any(|b| (b'1'..=b'9').contains(&b)) {
        sign * f64::MIN_POSITIVE
    } else {
        x
    }
}

/// A table of the document, its keys checked.
pub struct Table<'a> {
    node: Node<'a>,
    entries: Vec<Entry<'a>>,
}

impl<'a> Table<'a> {
    /// The value of `key`, if the table has it.
    pub fn get(&self, key: &str) -> Option<Node<'a>> {
        self.entries
            .iter()
            .find(|entry| entry.key == key)
            .map(|entry| entry.node.renamed(self.node.join(key)))
    }

    /// The value of `key`, which the table must have.
    pub fn need(&self, key: &str) -> Result<Node<'a>, FileError> {
        self.get(key)
            .ok_or_else(|| self.node.fail(format!("missing key `{key}`")))
    }

    /// `read` of the value of `key`, or `default` without one.
    pub fn or<T>(
        &self,
        key: &str,
        default: T,
        read: impl FnOnce(&Node<'a>) -> Result<T, FileError>,
    ) -> Result<T, FileError> {
        self.get(key).map_or(Ok(default), |node| read(&node))
    }
}

/// The range of a number: `(low, high]`, or `[low, high]` when `closed`.
#[derive(Clone, Copy)]
pub struct Interval {
    low: f32,
    closed: bool,
    high: f32,
    /// Where `high` is another value of the file as stored, that value's name (see
    /// [`Interval::up_to_stored`]).
    stored: Option<&'static str>,
}

/// `(low, high]`.
pub fn above(low: f32, high: f32) -> Interval {
    Interval {
        low,
        closed: false,
        high,
        stored: None,
    }
}

/// `[low, high]`.
pub fn within(low: f32, high: f32) -> Interval {
    Interval {
        low,
        closed: true,
        high,
        stored: None,
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let open = if self.closed { '[' } else { '(' };
        write!(f, "{open}{}, {}]", number(self.low), number(self.high))?;
        match self.stored {
            Some(bound) => write!(f, ": at most {bound}"),
            None => Ok(()),
        }
    }
}

impl Interval {
    /// The range whose upper bound is another value of the file, read and stored as an
    /// `f32` (a speed at most its kind's `max_speed`): a number is then compared as it
    /// will be stored, with the same rounding on both sides, so that `70.7` is at most
    /// `70.7` whatever `f32` makes of it, in any spelling. `bound` names that value in
    /// errors (`fps.start`).
    pub fn up_to_stored(self, bound: &'static str) -> Interval {
        Interval {
            stored: Some(bound),
            ..self
        }
    }

    /// Whether `x`, as written (as it will be stored, against a stored bound), is in the
    /// range (NaN never is).
    fn contains(&self, x: f64) -> bool {
        let x = match self.stored {
            Some(_) => f64::from(x as f32),
            None => x,
        };
        let (low, high) = (f64::from(self.low), f64::from(self.high));
        let above = if self.closed { x >= low } else { x > low };
        above && x <= high
    }
}
