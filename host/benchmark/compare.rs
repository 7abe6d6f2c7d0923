//! `gpuwars bench compare A.json B.json`: every figure two summaries share, and how it
//! changed from A to B.

use std::collections::HashMap;
use std::path::Path;

use anyhow::bail;
use serde_json::Value;

use crate::files::{FileError, excerpt, json_problem, read_text, shown};

/// One figure of both runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// Where it is in the summary, e.g. `frames_per_s.median` or `rows[enemies=1024].steps_per_s`.
    pub figure: String,
    /// Its value in A.
    pub a: f64,
    /// Its value in B.
    pub b: f64,
    /// Where the figure is a median of a spread both summaries give (`x.median` beside
    /// `x.min` and `x.max`; `steps_per_s` beside `steps_per_s_low` and `steps_per_s_high`,
    /// or `steps_per_s_range`; `frames_per_s` likewise), its `(least, most)` in A and in B.
    pub spreads: Option<((f64, f64), (f64, f64))>,
}

impl Change {
    /// B relative to A, in percent; `None` where that means nothing: A is 0 or so close to
    /// it (a subnormal number) that the change is out of all proportion.
    pub fn percent(&self) -> Option<f64> {
        // Not `(b - a) / |a|`, whose difference overflows for figures of opposite signs
        // near the largest number.
        let p = (self.b / self.a.abs() - self.a.signum()) * 100.0;
        (self.a.abs() >= f64::MIN_POSITIVE && p.is_finite()).then_some(p)
    }

    /// Whether each run's median lies inside the other's spread: a change the runs cannot
    /// tell from their own variation.
    pub fn inside_spreads(&self) -> bool {
        self.spreads.is_some_and(|((a_lo, a_hi), (b_lo, b_hi))| {
            (a_lo..=a_hi).contains(&self.b) && (b_lo..=b_hi).contains(&self.a)
        })
    }
}

/// The paths of the least and most of the spread whose median is at `figure`, if it is
/// one (see [`Change::spreads`]).
fn spread_of(figure: &str) -> Vec<(String, String)> {
    if let Some(stem) = figure.strip_suffix(".median") {
        return vec![(format!("{stem}.min"), format!("{stem}.max"))];
    }
    let rate = ["steps_per_s", "frames_per_s"].into_iter().any(|name| {
        figure
            .strip_suffix(name)
            .is_some_and(|stem| stem.is_empty() || stem.ends_with('.'))
    });
    match rate {
        true => vec![
            (format!("{figure}_low"), format!("{figure}_high")),
            (format!("{figure}_range[0]"), format!("{figure}_range[1]")),
        ],
        false => Vec::new(),
    }
}

/// Most bytes of a summary (the largest, of `tradeoff`, take tens of kilobytes).
pub const MAX_SUMMARY_BYTES: u64 = 16 << 20;

/// Reads a summary written by a benchmark: a regular file of at most
/// [`MAX_SUMMARY_BYTES`] bytes (see [`read_text`]) holding a JSON object with a
/// `benchmark` field.
pub fn load(path: &Path) -> Result<Value, FileError> {
    parse(&read_text(path, MAX_SUMMARY_BYTES)?, &shown(path))
}

/// Reads the summary `text`; `origin` names it in errors.
pub fn parse(text: &str, origin: &str) -> Result<Value, FileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let value: Value = serde_json::from_str(text).map_err(|e| {
        let problem = format!("not a benchmark summary: {}", json_problem(&e));
        FileError::new(origin, (e.line() > 0).then_some(e.line()), "", problem)
    })?;
    let problem = match value.get("benchmark") {
        Some(Value::String(_)) => return check_figures(value, origin),
        Some(other) => format!(
            "not a benchmark summary: its \"benchmark\" field is {} (expected the benchmark's \
             name, in quotes)",
            excerpt(&other.to_string())
        ),
        None => "not a benchmark summary (it has no \"benchmark\" field)".to_owned(),
    };
    Err(FileError::new(origin, None, "", problem))
}

/// `summary`, if none of its figures is one no run can give: a rate or a time below 0, a
/// spread whose least is above its most, or a median outside its spread.
fn check_figures(summary: Value, origin: &str) -> Result<Value, FileError> {
    let mut figures = Vec::new();
    leaves(&summary, "", &mut figures);
    let paths = by_path(&figures);
    let number = |path: &str| paths.get(path).and_then(|v| v.as_f64());
    for (figure, value) in &figures {
        let Some(x) = value.as_f64() else {
            continue;
        };
        let problem = if x < 0.0 && never_negative(figure) {
            format!(
                "{} is below 0, which no rate or time can be",
                self::figure(x)
            )
        } else if let Some((least, most)) = spread_of(figure)
            .into_iter()
            .find_map(|(low, high)| Some((number(&low)?, number(&high)?)))
            .filter(|(least, most)| !(least <= most && (least..=most).contains(&&x)))
        {
            format!(
                "the median {} is not inside its spread, {} to {}",
                self::figure(x),
                self::figure(least),
                self::figure(most)
            )
        } else {
            continue;
        };
        return Err(FileError::new(origin, None, figure, problem));
    }
    Ok(summary)
}

/// Whether `figure` is a rate or a time (a part of its path named `…_per_s`, `…_us` or
/// `seconds`, or a spread's end of one), which no run makes negative.
fn never_negative(figure: &str) -> bool {
    figure.split('.').any(|part| {
        let name = part.split('[').next().unwrap_or_default();
        let name = ["_low", "_high", "_range"]
            .iter()
            .fold(name, |n, end| n.strip_suffix(end).unwrap_or(n));
        name.ends_with("_per_s") || name.ends_with("_us") || name == "seconds"
    })
}

/// `leaves` by path, the first of each where paths repeat (rows of the same size): looked up
/// in constant time, so that a summary is checked and compared in time linear in its
/// figures (a search of the list for each took minutes for 180,000 of them).
fn by_path<'a, 'v>(leaves: &'a [(String, &'v Value)]) -> HashMap<&'a str, &'v Value> {
    let mut paths = HashMap::with_capacity(leaves.len());
    for (path, value) in leaves {
        paths.entry(path.as_str()).or_insert(*value);
    }
    paths
}

/// Every value in `value` that is not a list or an object, with its path; rows that have
/// an `enemies` field are named by it.
fn leaves<'v>(value: &'v Value, path: &str, out: &mut Vec<(String, &'v Value)>) {
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                let path = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                leaves(v, &path, out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                let name = match v.get("enemies").and_then(Value::as_u64) {
                    Some(enemies) => format!("{path}[enemies={enemies}]"),
                    None => format!("{path}[{i}]"),
                };
                leaves(v, &name, out);
            }
        }
        leaf => out.push((path.to_string(), leaf)),
    }
}

/// The figures `a` and `b` share, in `a`'s order. Two different benchmarks are an error,
/// and so is a figure that is a number in one summary and not in the other (the error names
/// it, and the summary `a_name` or `b_name` where it is not a number).
pub fn compare(a: &Value, a_name: &str, b: &Value, b_name: &str) -> anyhow::Result<Vec<Change>> {
    let kind = |v: &Value| excerpt(v["benchmark"].as_str().unwrap_or_default());
    if kind(a) != kind(b) {
        bail!(
            "a `{}` summary cannot be compared with a `{}` one",
            kind(a),
            kind(b)
        );
    }
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    leaves(a, "", &mut xs);
    leaves(b, "", &mut ys);
    let (a_paths, b_paths) = (by_path(&xs), by_path(&ys));
    let number = |paths: &HashMap<&str, &Value>, path: &str| paths.get(path)?.as_f64();
    let spreads = |figure: &str| {
        spread_of(figure).into_iter().find_map(|(low, high)| {
            let range = |p: &HashMap<&str, &Value>| Some((number(p, &low)?, number(p, &high)?));
            Some((range(&a_paths)?, range(&b_paths)?))
        })
    };
    let mut changes = Vec::new();
    for (figure, x) in &xs {
        let figure = figure.clone();
        let Some(&y) = b_paths.get(figure.as_str()) else {
            continue;
        };
        let not_a_number = |name: &str, v: &Value| {
            let found = excerpt(&v.to_string());
            let problem = format!("not a number (found {found}), where the other summary has one");
            FileError::new(name, None, &figure, problem)
        };
        match (x.as_f64(), y.as_f64()) {
            (Some(a), Some(b)) => {
                let spreads = spreads(&figure);
                changes.push(Change {
                    figure,
                    a,
                    b,
                    spreads,
                });
            }
            (Some(_), None) => return Err(not_a_number(b_name, y).into()),
            (None, Some(_)) => return Err(not_a_number(a_name, x).into()),
            (None, None) => {}
        }
    }
    Ok(changes)
}

/// The figures (numbers) that only one of `a` and `b` has: `(a's, b's)`, each in its
/// summary's order. Rows of other sizes (`rows[enemies=…]`) show here too.
pub fn unshared(a: &Value, b: &Value) -> (Vec<String>, Vec<String>) {
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    leaves(a, "", &mut xs);
    leaves(b, "", &mut ys);
    let only = |these: &[(String, &Value)], other: &[(String, &Value)]| {
        let other = by_path(other);
        (these.iter())
            .filter(|(f, v)| v.is_number() && !other.contains_key(f.as_str()))
            .map(|(f, _)| f.clone())
            .collect()
    };
    (only(&xs, &ys), only(&ys, &xs))
}

/// The changes as an aligned table.
pub fn to_text(changes: &[Change], a: &Value, b: &Value) -> String {
    let machine = |v: &Value| {
        // Quoted shortened and escaped: a summary may come from anywhere.
        let field = |name: &str| excerpt(v["machine"][name].as_str().unwrap_or("?"));
        format!(
            "{} ({}, {}, commit {})",
            field("device"),
            field("backend"),
            field("date"),
            field("commit")
        )
    };
    let mut out = format!("A: {}\nB: {}\n", machine(a), machine(b));
    if changes.iter().any(Change::inside_spreads) {
        out += "≈: each run's median inside the other's spread (no difference they can tell)\n";
    }
    let width = changes
        .iter()
        .map(|c| c.figure.len())
        .max()
        .unwrap_or(6)
        .max(6);
    out += &format!(
        "{:<width$} {:>16} {:>16} {:>9}\n",
        "figure", "A", "B", "change"
    );
    for c in changes {
        let percent = c
            .percent()
            .map_or("n/a".to_string(), |p| match p.abs() < 1e5 {
                true => format!("{p:+.1}%"),
                false => format!("{p:+.1e}%"),
            });
        let same = if c.inside_spreads() { " ≈" } else { "" };
        out += &format!(
            "{:<width$} {:>16} {:>16} {:>9}{same}\n",
            c.figure,
            figure(c.a),
            figure(c.b),
            percent
        );
    }
    out
}

/// A figure in at most 16 characters: three decimals, or in scientific notation when it is
/// too large or too small for them (`-1.000e308`, `5.000e-324`).
fn figure(x: f64) -> String {
    match x == 0.0 || (1e-3..1e12).contains(&x.abs()) {
        true => format!("{x:.3}"),
        false => format!("{x:.3e}"),
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    #[test]
    fn a_median_inside_both_spreads_is_no_difference() {
        let run = |median: f64, (min, max): (f64, f64), rate: f64, range: (f64, f64)| {
            json!({
                "benchmark": "paper",
                "frames_per_s": { "min": min, "median": median, "mean": median, "max": max },
                "game": [ { "choice": "default", "steps_per_s": rate,
                            "steps_per_s_range": [range.0, range.1] } ],
            })
        };
        let a = run(100.0, (90.0, 110.0), 500.0, (480.0, 520.0));
        let b = run(104.0, (95.0, 115.0), 700.0, (690.0, 710.0));
        let changes = compare(&a, "a", &b, "b").unwrap();
        let change = |name: &str| changes.iter().find(|c| c.figure == name).unwrap();
        // 100 and 104, each inside the other's range: no difference.
        assert!(change("frames_per_s.median").inside_spreads());
        // 500 against 690-710: a difference; the minimum has no spread of its own.
        assert!(!change("game[0].steps_per_s").inside_spreads());
        assert_eq!(change("frames_per_s.min").spreads, None);
        let text = to_text(&changes, &a, &b);
        let line = |name: &str| {
            text.lines()
                .find(|l| l.starts_with(name))
                .unwrap()
                .to_owned()
        };
        assert!(line("frames_per_s.median").ends_with(" ≈"), "{text}");
        assert!(!line("game[0].steps_per_s ").ends_with(" ≈"), "{text}");
        // One spread inside the other's but not the reverse: a difference.
        let c = run(112.0, (111.0, 113.0), 500.0, (480.0, 520.0));
        let changes = compare(&a, "a", &c, "c").unwrap();
        assert!(
            !changes
                .iter()
                .any(|c| c.figure == "frames_per_s.median" && c.inside_spreads())
        );
    }

    /// A figure one summary lacks is listed, not dropped unsaid; text is not a figure.
    #[test]
    fn figures_of_one_summary_only_are_named() {
        let a = json!({ "benchmark": "paper", "step_us": 12.5, "frames": 100,
                        "rows": [ { "enemies": 8, "steps_per_s": 1.0 } ], "note": "x" });
        let b = json!({ "benchmark": "paper", "frames": 90,
                        "rows": [ { "enemies": 16, "steps_per_s": 2.0 } ] });
        assert_eq!(
            unshared(&a, &b),
            (
                vec![
                    "rows[enemies=8].enemies".to_owned(),
                    "rows[enemies=8].steps_per_s".to_owned(),
                    "step_us".to_owned()
                ],
                vec![
                    "rows[enemies=16].enemies".to_owned(),
                    "rows[enemies=16].steps_per_s".to_owned()
                ]
            )
        );
        assert_eq!(unshared(&a, &a), (vec![], vec![]));
    }

    /// A figure no run can give is refused, naming it: the edges (0, a spread of one value,
    /// a median on its spread's ends) pass.
    #[test]
    fn impossible_figures_are_refused_by_name() {
        let summary = |fps: (f64, f64, f64), rate: f64, range: (f64, f64), extra: Value| {
            let mut v = json!({
                "benchmark": "scale",
                "frames_per_s": { "min": fps.0, "median": fps.1, "mean": fps.1, "max": fps.2 },
                "stages_us": { "broad": { "min": 0.0, "median": 0.0, "max": 0.0 } },
                "rows": [ { "enemies": 8, "steps_per_s": rate,
                            "steps_per_s_range": [range.0, range.1] } ],
                "penetration_change": -3.5,
            });
            v.as_object_mut()
                .unwrap()
                .extend(extra.as_object().unwrap().clone());
            parse(&v.to_string(), "s.json")
        };
        let fine = json!({});
        assert!(summary((5.0, 5.0, 5.0), 7.0, (7.0, 7.0), fine.clone()).is_ok());
        assert!(summary((1.0, 1.0, 9.0), 9.0, (2.0, 9.0), fine.clone()).is_ok());
        for (fps, rate, range, extra, says) in [
            (
                (1.0, 5.0, 9.0),
                -1.0,
                (-2.0, 0.0),
                fine.clone(),
                "rows[enemies=8].steps_per_s: -1.000 is below 0",
            ),
            (
                (9.0, 5.0, 1.0),
                7.0,
                (7.0, 7.0),
                fine.clone(),
                "frames_per_s.median: the median 5.000 is not inside its spread, 9.000 to 1.000",
            ),
            (
                (1.0, 5.0, 9.0),
                7.0,
                (7.5, 8.0),
                fine.clone(),
                "rows[enemies=8].steps_per_s: the median 7.000 is not inside its spread",
            ),
            (
                (1.0, 5.0, 9.0),
                7.0,
                (7.0, 7.0),
                json!({ "seconds": -0.5 }),
                "seconds: -0.500 is below 0",
            ),
            (
                (1.0, 5.0, 9.0),
                7.0,
                (7.0, 7.0),
                json!({ "stages_us": { "narrow": { "max": -1e-300 } } }),
                "stages_us.narrow.max: -1.000e-300 is below 0",
            ),
        ] {
            let e = summary(fps, rate, range, extra).unwrap_err().to_string();
            assert!(e.contains("s.json") && e.contains(says), "{e}");
        }
    }

    /// A `benchmark` field that is not a name is refused saying what it holds.
    #[test]
    fn a_benchmark_field_not_a_name_is_named() {
        let e = parse(r#"{"benchmark": 5}"#, "b.json").unwrap_err();
        assert!(
            e.to_string().contains("its \"benchmark\" field is 5"),
            "{e}"
        );
        let e = parse(r#"{"bench": "paper"}"#, "b.json").unwrap_err();
        assert!(e.to_string().contains("no \"benchmark\" field"), "{e}");
        assert!(parse(r#"{"benchmark": "paper"}"#, "b.json").is_ok());
    }
}
