//! Per-stage times of the step: what `gpuwars demo --profile` reports.

use serde::Serialize;

use super::StagePlan;

/// Time, launches and bytes of one stage, summed over the profiled steps.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// The stage's name.
    pub stage: &'static str,
    /// Kernel launches per step.
    pub launches: usize,
    /// Bytes of device memory moved per profiled step, by our count: every array element
    /// the stage's kernels must read or write, once (neighbour lookups not counted). A
    /// stage that runs only every few steps (the renumbering) moves them in those steps,
    /// spread over all, as its time is.
    pub bytes: u64,
    /// Profiled steps in which the stage ran.
    pub runs: u64,
    /// Bytes of one run.
    #[serde(skip)]
    run_bytes: u64,
    /// Seconds spent in the stage over all profiled steps.
    pub seconds: f64,
}

/// Stage times over some steps.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Profile {
    /// Steps profiled.
    pub steps: u64,
    /// One entry per stage, in step order.
    pub stages: Vec<StageTimes>,
}

impl Profile {
    /// Adds `seconds` of one step to `stage`'s entry, which `ran` in it or not.
    pub(super) fn add(&mut self, stage: &StagePlan, seconds: f64, ran: bool) {
        let entry = match self
            .stages
            .iter_mut()
            .position(|s| s.stage == stage.stage.name())
        {
            Some(i) => &mut self.stages[i],
            None => {
                self.stages.push(StageTimes {
                    stage: stage.stage.name(),
                    launches: stage.launches(),
                    run_bytes: stage.bytes(),
                    ..StageTimes::default()
                });
                self.stages.last_mut().expect("just pushed")
            }
        };
        entry.seconds += seconds;
        entry.runs += u64::from(ran);
    }

    /// Ends a profiled step: counts it, and spreads each stage's bytes over the steps.
    pub(super) fn end_step(&mut self) {
        self.steps += 1;
        for s in &mut self.stages {
            s.bytes = s.run_bytes * s.runs / self.steps;
        }
    }

    /// Bytes of one run of each stage, in step order: what a copy as large moves.
    pub fn run_bytes(&self) -> impl Iterator<Item = u64> + '_ {
        self.stages.iter().map(|s| s.run_bytes)
    }

    /// Mean seconds per step of all stages together.
    pub fn step_seconds(&self) -> f64 {
        self.stages.iter().map(|s| s.seconds).sum::<f64>() / self.steps.max(1) as f64
    }

    /// Each stage's mean time per step on one line, `stage=time` joined by spaces, in units
    /// of `unit` seconds (`1e-6`: µs) with `digits` decimals.
    pub fn stage_line(&self, unit: f64, digits: usize) -> String {
        let steps = self.steps.max(1) as f64;
        self.stages
            .iter()
            .map(|s| format!("{}={:.digits$}", s.stage, s.seconds / steps / unit))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The profile as an aligned table: per stage, microseconds per step, share of the step,
    /// launches, bytes and the bandwidth they make; with `copies` (bytes per second of a
    /// copy as large as each stage's run, in the stages' order, measured in the same run),
    /// the fraction of it each stage achieves; with `launch_s` (seconds a launch of a chain
    /// of launches that do nothing takes, measured in the same run), each stage's floor:
    /// what its launches would take a step doing nothing.
    pub fn to_table(&self, copies: Option<&[f64]>, launch_s: Option<f64>) -> String {
        let steps = self.steps.max(1) as f64;
        let total: f64 = self.stages.iter().map(|s| s.seconds).sum();
        let floor_us =
            |s: &StageTimes| launch_s.map(|l| s.launches as f64 * l * s.runs as f64 / steps * 1e6);
        let shown = |us: Option<f64>| us.map_or("-".to_string(), |us| format!("{us:.2}"));
        let mut out = format!(
            "{:<10} {:>10} {:>7} {:>8} {:>10} {:>12} {:>10} {:>9}\n",
            "stage", "us/step", "share", "launches", "floor us", "bytes/step", "GB/s", "of copy"
        );
        for (i, s) in self.stages.iter().enumerate() {
            let per_step = s.seconds / steps;
            let rate = if per_step > 0.0 {
                s.bytes as f64 / per_step
            } else {
                0.0
            };
            let of_copy = match copies.and_then(|c| c.get(i)) {
                Some(&copy) if s.bytes > 0 => format!("{:.1}%", 100.0 * rate / copy),
                _ => "-".to_string(),
            };
            out += &format!(
                "{:<10} {:>10.2} {:>6.1}% {:>8} {:>10} {:>12} {:>10.1} {:>9}\n",
                s.stage,
                per_step * 1e6,
                100.0 * s.seconds / total.max(f64::MIN_POSITIVE),
                s.launches,
                shown(floor_us(s)),
                s.bytes,
                rate / 1e9,
                of_copy
            );
        }
        let floor = launch_s.map(|_| self.stages.iter().filter_map(floor_us).sum());
        out += &format!(
            "{:<10} {:>10.2} {:>6.1}% {:>8} {:>10} {:>12}\n",
            "step",
            total / steps * 1e6,
            100.0,
            self.stages.iter().map(|s| s.launches).sum::<usize>(),
            shown(floor),
            self.stages.iter().map(|s| s.bytes).sum::<u64>()
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::{Profile, StageTimes};

    /// A stage that runs in one step of four (the renumbering) shows a quarter of its bytes
    /// and of its launches' floor a step; a stage that runs every step, its own.
    #[test]
    fn a_stage_run_every_few_steps_is_spread_over_the_steps() {
        let stage = |name, launches, runs, run_bytes, seconds| StageTimes {
            stage: name,
            launches,
            runs,
            run_bytes,
            seconds,
            ..StageTimes::default()
        };
        // Three steps in, and the fourth ends: "every" ran in all four, "seldom" in one.
        let mut profile = Profile {
            steps: 3,
            stages: vec![
                stage("every", 2, 4, 1000, 3e-6),
                stage("seldom", 4, 1, 8000, 1e-6),
            ],
        };
        profile.end_step();
        let table = profile.to_table(None, Some(2e-6));
        let row = |name: &str| {
            let line = table.lines().find(|l| l.starts_with(name)).expect("a row");
            line.split_whitespace()
                .map(str::to_string)
                .collect::<Vec<_>>()
        };
        // stage, us/step, share, launches, floor us, bytes/step, GB/s, of copy
        assert_eq!(row("every")[4..6], ["4.00", "1000"]);
        assert_eq!(row("seldom")[4..6], ["2.00", "2000"]);
        assert_eq!(row("step")[4..6], ["6.00", "3000"]);
        // Against copies as large as each stage's run: "every" moves 1000 bytes in 0.75 µs
        // a step, 1.33 GB/s, two thirds of its 2 GB/s copy; "seldom" its 8000 in its one
        // run of 1 µs, 8 GB/s, half of its 16; a stage that moves nothing has no fraction.
        profile.stages.push(stage("none", 1, 4, 0, 1e-6));
        let table = profile.to_table(Some(&[2e9, 16e9, 1e9]), None);
        let row = |name: &str| {
            let line = table.lines().find(|l| l.starts_with(name)).expect("a row");
            line.split_whitespace().last().unwrap().to_owned()
        };
        assert_eq!(row("every"), "66.7%");
        assert_eq!(row("seldom"), "50.0%");
        assert_eq!(row("none"), "-");
    }
}
