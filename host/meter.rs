//! The frame counter that the paper's benchmark and `play`'s window share: frames counted
//! second by second, with one profiled frame per second (from its middle on).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::pipeline::Profile;

/// One second of the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Second {
    /// Seconds since the start (the second this row ends).
    pub second: u32,
    /// Frames rendered in this second (one simulation step each).
    pub frames_per_s: f64,
    /// Simulation steps in this second.
    pub steps_per_s: f64,
    /// Enemies alive at its end.
    pub enemies_alive: u32,
    /// The step's time, stage by stage, of one profiled step of this second (µs).
    pub step_us: f64,
    /// The master thread's stages (the master, the autopilot, the tally) of that step (µs).
    pub master_us: f64,
    /// Its physics stages (births, broad, narrow, integrate, free) (µs).
    pub physics_us: f64,
    /// Its AI stage (think) (µs).
    pub ai_us: f64,
    /// The renderer's device work for that frame (kernels, or the vertex kernel with the
    /// map and unmap of the interop buffer) (µs).
    pub render_us: f64,
    /// GL's part of that frame: clear, draw and `glFinish` (µs; 0 for the kernel renderer).
    pub gl_us: f64,
}

/// Frames counted second by second, with one profiled frame per second.
pub struct Seconds {
    rows: Vec<Second>,
    /// Each closed second's profiled step, stage by stage (µs), in step order.
    stages: Vec<Vec<(&'static str, f64)>>,
    frames: u64,
    second_start: Instant,
    in_second: u64,
    /// This second's profiled step, and its frame's device and GL seconds.
    sample: Option<(Profile, f64, f64)>,
}

impl Seconds {
    /// Counting from `now`.
    pub fn new(now: Instant) -> Self {
        Seconds {
            rows: Vec::new(),
            stages: Vec::new(),
            frames: 0,
            second_start: now,
            in_second: 0,
            sample: None,
        }
    }

    /// Whether the frame starting `now` is the current second's profiled one: the first
    /// from its middle on, so that none is the run's first, which sets the device up (its
    /// step and frame took 2.7 and 9.8 times the next seconds' on the CPU emulation).
    pub fn wants_sample(&self, now: Instant) -> bool {
        self.sample.is_none() && (now - self.second_start).as_secs_f64() >= 0.5
    }

    /// The profiled step of this second, and its frame's device and GL seconds.
    pub fn sampled(&mut self, profile: Profile, render: f64, gl: f64) {
        self.sample = Some((profile, render, gl));
    }

    /// One frame finished at `now` with `enemies_alive`; closes the second once a second
    /// has passed and it has its sample.
    pub fn frame(&mut self, now: Instant, enemies_alive: u32) {
        self.frames += 1;
        self.in_second += 1;
        let elapsed = (now - self.second_start).as_secs_f64();
        if elapsed < 1.0 {
            return;
        }
        let Some((profile, render, gl)) = self.sample.take() else {
            return;
        };
        let rate = self.in_second as f64 / elapsed;
        self.rows.push(Second {
            second: self.rows.len() as u32 + 1,
            frames_per_s: rate,
            steps_per_s: rate,
            enemies_alive,
            step_us: profile.step_seconds() * 1e6,
            master_us: stages_us(&profile, &["master", "pilot", "tally"]),
            physics_us: stages_us(
                &profile,
                &["births", "broad", "narrow", "integrate", "free"],
            ),
            ai_us: stages_us(&profile, &["think"]),
            render_us: render * 1e6,
            gl_us: gl * 1e6,
        });
        let mut stages: Vec<(&'static str, f64)> = Vec::new();
        for s in &profile.stages {
            if !stages.iter().any(|(name, _)| *name == s.stage) {
                stages.push((s.stage, stages_us(&profile, &[s.stage])));
            }
        }
        self.stages.push(stages);
        self.second_start = now;
        self.in_second = 0;
    }

    /// The seconds closed so far.
    pub fn rows(&self) -> &[Second] {
        &self.rows
    }

    /// Each closed second's profiled step, stage by stage (µs), in step order.
    pub fn stages(&self) -> &[Vec<(&'static str, f64)>] {
        &self.stages
    }

    /// Frames counted in all.
    pub fn frames(&self) -> u64 {
        self.frames
    }
}

/// Sums the seconds of the named stages of a one-step profile, in µs.
fn stages_us(profile: &Profile, names: &[&str]) -> f64 {
    let seconds: f64 = profile
        .stages
        .iter()
        .filter(|s| names.contains(&s.stage))
        .map(|s| s.seconds)
        .sum();
    seconds * 1e6 / profile.steps.max(1) as f64
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::Seconds;
    use crate::pipeline::Profile;

    /// Each second's profiled frame is the first from its middle on; a second without one
    /// stays open until it has it.
    #[test]
    fn a_second_is_sampled_from_its_middle_on() {
        let start = Instant::now();
        let at = |ms: u64| start + Duration::from_millis(ms);
        let mut seconds = Seconds::new(start);
        assert!(!seconds.wants_sample(at(0)), "the run's first frame");
        assert!(!seconds.wants_sample(at(499)));
        seconds.frame(at(1000), 7);
        assert!(seconds.rows().is_empty(), "closed without its sample");
        assert!(seconds.wants_sample(at(1100)));
        seconds.sampled(Profile::default(), 2e-6, 0.0);
        assert!(!seconds.wants_sample(at(1100)), "sampled already");
        seconds.frame(at(1200), 9);
        assert_eq!(seconds.rows().len(), 1);
        assert_eq!(seconds.rows()[0].enemies_alive, 9);
        assert_eq!(seconds.rows()[0].render_us, 2.0);
        // The next second counts from the frame that closed this one.
        assert!(!seconds.wants_sample(at(1699)));
        assert!(seconds.wants_sample(at(1700)));
        assert_eq!(seconds.frames(), 2);
    }
}
