//! `gpuwars bench compare A.json B.json`: every figure two summaries share, and how it
//! changed from A to B.

use std::path::Path;

use anyhow::{Context as _, bail};
use serde_json::Value;
/// One figure of both runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// Where it is in the summary, e.g. `frames_per_s.median` or `rows[enemies=1024].steps_per_s`.
    pub figure: String,
    /// Its value in A.
    pub a: f64,
    /// Its value in B.
    pub b: f64,
}

impl Change {
    /// B relative to A, in percent (`None` when A is 0).
    pub fn percent(&self) -> Option<f64> {
        (self.a != 0.0).then(|| (self.b - self.a) / self.a.abs() * 100.0)
    }
}

/// Reads a summary written by `bench paper` or `bench scale`.
pub fn load(path: &Path) -> anyhow::Result<Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let value: Value = serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}:{}: not a benchmark summary: {e}",
            path.display(),
            e.line()
        )
    })?;
    if value.get("benchmark").and_then(Value::as_str).is_none() {
        bail!(
            "{}: not a benchmark summary (it has no \"benchmark\" field)",
            path.display()
        );
    }
    Ok(value)
}

/// Every number in `value`, with its path; rows that have an `enemies` field are named by it.
fn numbers(value: &Value, path: &str, out: &mut Vec<(String, f64)>) {
    match value {
        Value::Number(n) => {
            if let Some(x) = n.as_f64() {
                out.push((path.to_string(), x));
            }
        }
        Value::Object(map) => {
            for (key, v) in map {
                let path = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                numbers(v, &path, out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                let name = match v.get("enemies").and_then(Value::as_u64) {
                    Some(enemies) => format!("{path}[enemies={enemies}]"),
                    None => format!("{path}[{i}]"),
                };
                numbers(v, &name, out);
            }
        }
        _ => {}
    }
}

/// The figures `a` and `b` share, in `a`'s order. Two different benchmarks are an error.
pub fn compare(a: &Value, b: &Value) -> anyhow::Result<Vec<Change>> {
    let kind = |v: &Value| v["benchmark"].as_str().unwrap_or_default().to_string();
    if kind(a) != kind(b) {
        bail!(
            "a `{}` summary cannot be compared with a `{}` one",
            kind(a),
            kind(b)
        );
    }
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    numbers(a, "", &mut xs);
    numbers(b, "", &mut ys);
    Ok(xs
        .into_iter()
        .filter_map(|(figure, a)| {
            let b = ys.iter().find(|(f, _)| *f == figure)?.1;
            Some(Change { figure, a, b })
        })
        .collect())
}

/// The changes as an aligned table.
pub fn to_text(changes: &[Change], a: &Value, b: &Value) -> String {
    let machine = |v: &Value| {
        format!(
            "{} ({}, {}, commit {})",
            v["machine"]["device"].as_str().unwrap_or("?"),
            v["machine"]["backend"].as_str().unwrap_or("?"),
            v["machine"]["date"].as_str().unwrap_or("?"),
            v["machine"]["commit"].as_str().unwrap_or("?")
        )
    };
    let mut out = format!("A: {}\nB: {}\n", machine(a), machine(b));
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
        let percent = c.percent().map_or("-".to_string(), |p| format!("{p:+.1}%"));
        out += &format!(
            "{:<width$} {:>16.3} {:>16.3} {:>9}\n",
            c.figure, c.a, c.b, percent
        );
    }
    out
}
