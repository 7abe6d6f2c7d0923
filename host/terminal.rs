//! What the long runs show: a progress bar on stderr where it is a terminal, and, wherever
//! stderr goes, one notice of what the rest will take once the speed is known.

use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

/// The progress of a run of `len` units.
pub(crate) struct Progress {
    bar: ProgressBar,
    what: String,
    unit: &'static str,
    len: u64,
    done: u64,
    start: Instant,
    told: bool,
}

impl Progress {
    /// Seconds a run must be expected to take to be announced.
    const LONG: f64 = 20.0;
    /// Seconds of running after which the speed is taken as known.
    const MEASURED: f64 = 2.0;

    /// `n` more units done; once the speed is known, says on stderr how long the rest
    /// will take if that is long (with or without a bar).
    pub(crate) fn inc(&mut self, n: u64) {
        self.bar.inc(n);
        self.done += n;
        let seconds = self.start.elapsed().as_secs_f64();
        if self.told || self.done == 0 || seconds < Self::MEASURED {
            return;
        }
        let rate = self.done as f64 / seconds;
        let left = self.len.saturating_sub(self.done) as f64 / rate;
        let unit = self.unit;
        self.tell(&format!(" at {rate:.1} {unit}/s"), left, " more");
    }

    /// Says on stderr that the whole run will take about `seconds`, if that is long, before
    /// its speed is known from the units done (which then says nothing more).
    pub(crate) fn announce(&mut self, seconds: f64) {
        self.tell("", seconds, "");
    }

    /// The one notice of a run: `seconds` (`after` them) are left, if that is long; `how`
    /// says how it knows.
    fn tell(&mut self, how: &str, seconds: f64, after: &str) {
        self.told = true;
        if seconds >= Self::LONG {
            let (len, unit) = (crate::files::thousands(self.len), self.unit);
            let left = duration_words(seconds);
            eprintln!(
                "gpuwars: {}: {len} {unit}{how}: about {left}{after}",
                self.what
            );
        }
    }

    /// What the bar says beside it.
    pub(crate) fn set_message(&self, message: impl Into<std::borrow::Cow<'static, str>>) {
        self.bar.set_message(message);
    }

    /// The bar, gone.
    pub(crate) fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

/// The progress of `what`, `len` units of `unit`: a bar on stderr when `show` and stderr is
/// a terminal (hidden otherwise), and the notice of a long run in any case.
pub(crate) fn progress(len: u64, show: bool, what: &str, unit: &'static str) -> Progress {
    use std::io::IsTerminal;
    let bar = match show && std::io::stderr().is_terminal() {
        true => {
            let bar = ProgressBar::new(len);
            let style = ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} {msg}")
                .expect("a valid template")
                .progress_chars("=> ");
            bar.set_style(style);
            bar.set_prefix(what.to_string());
            bar
        }
        false => ProgressBar::hidden(),
    };
    Progress {
        bar,
        what: what.to_string(),
        unit,
        len,
        done: 0,
        start: Instant::now(),
        told: false,
    }
}

/// `seconds` in words: seconds, minutes or hours.
fn duration_words(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.0} s"),
        s if s < 7200.0 => format!("{:.0} minutes", s / 60.0),
        s => format!("{:.1} hours", s / 3600.0),
    }
}
