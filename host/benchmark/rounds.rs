//! Speeds measured as a benchmark tool measures them: each subject warmed up, then timed in
//! interleaved rounds (A B C … A B C …), so that what the machine does meanwhile (other
//! programs, clocks, caches) falls on every subject alike; each reported as its median and
//! its spread over the rounds. Two speeds whose spreads overlap are not told apart, and a
//! Pareto frontier built on them says which points it cannot separate.

use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

/// How a set of subjects is timed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rounds {
    /// Timed rounds, after one untimed round that warms every subject up.
    pub rounds: u32,
    /// Wall seconds each subject runs in a round.
    pub seconds: f64,
}

/// One subject's rate over the rounds (work per wall second).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Rate {
    /// The median round's.
    pub median: f64,
    /// The slowest round's.
    pub low: f64,
    /// The fastest round's.
    pub high: f64,
}

impl Rate {
    /// The rate of `samples` (per round); all zero for none.
    pub fn of(samples: &[f64]) -> Rate {
        let spread = super::Spread::of(samples.iter().copied());
        Rate {
            median: spread.median,
            low: spread.min,
            high: spread.max,
        }
    }

    /// The same rate in other units (steps per second into simulated seconds per second).
    pub fn scaled(self, by: f64) -> Rate {
        Rate {
            median: self.median * by,
            low: self.low * by,
            high: self.high * by,
        }
    }

    /// Whether this is faster than `other` beyond both spreads: its slowest round beat the
    /// other's fastest.
    pub fn beats(&self, other: &Rate) -> bool {
        self.low > other.high
    }
}

/// Times `subjects` in `rounds`: one untimed round, then `rounds.rounds` timed ones, each
/// giving every subject in turn `rounds.seconds` of `run` (which does a batch of work on
/// it, waits for it to be done, and says how much it did). Returns each subject's rate.
pub fn interleaved<S>(
    subjects: &mut [S],
    rounds: Rounds,
    mut run: impl FnMut(&mut S) -> anyhow::Result<u64>,
    mut progress: impl FnMut(),
) -> anyhow::Result<Vec<Rate>> {
    let time = Duration::from_secs_f64(rounds.seconds);
    let mut samples = vec![Vec::new(); subjects.len()];
    for round in 0..=rounds.rounds {
        for (subject, samples) in subjects.iter_mut().zip(&mut samples) {
            let start = Instant::now();
            let mut done = 0u64;
            while done == 0 || start.elapsed() < time {
                done += run(subject)?;
            }
            if round > 0 {
                samples.push(done as f64 / start.elapsed().as_secs_f64());
            }
        }
        progress();
    }
    Ok(samples.iter().map(|s| Rate::of(s)).collect())
}

/// A point of a trade: its error (lower is better) and its speed.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// What it gets wrong.
    pub error: f64,
    /// How fast it runs.
    pub speed: Rate,
}

impl Point {
    /// Whether `self` is better than `other` beyond the speeds' spreads: no worse and
    /// clearly faster, or better and not clearly slower.
    fn dominates(&self, other: &Point) -> bool {
        (self.error <= other.error && self.speed.beats(&other.speed))
            || (self.error < other.error && !other.speed.beats(&self.speed))
    }

    /// Whether `self` is better than `other` by the medians alone.
    fn dominates_by_medians(&self, other: &Point) -> bool {
        let (s, o) = (self.speed.median, other.speed.median);
        self.error <= other.error && s >= o && (self.error < other.error || s > o)
    }
}

/// For each of `points` (`None`: not on the trade), whether it is on the Pareto frontier
/// (nothing is better beyond the spreads), and the indices of the points that beat it by
/// their medians but not beyond the spreads: those the frontier cannot separate it from.
pub fn frontier(points: &[Option<Point>]) -> Vec<(bool, Vec<usize>)> {
    points
        .iter()
        .map(|p| {
            let Some(p) = p else {
                return (false, Vec::new());
            };
            let others = || {
                points
                    .iter()
                    .enumerate()
                    .filter_map(|(i, q)| Some((i, q.as_ref()?)))
            };
            let on = !others().any(|(_, q)| q.dominates(p));
            let unseparated = match on {
                true => others()
                    .filter(|(_, q)| q.dominates_by_medians(p))
                    .map(|(i, _)| i)
                    .collect(),
                false => Vec::new(),
            };
            (on, unseparated)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(error: f64, (low, median, high): (f64, f64, f64)) -> Option<Point> {
        Some(Point {
            error,
            speed: Rate { median, low, high },
        })
    }

    #[test]
    fn speeds_inside_each_others_spreads_are_not_told_apart() {
        let points = [
            // The most accurate.
            point(0.0, (90.0, 100.0, 110.0)),
            // As accurate, slower by its median but within the first's spread: both stay
            // on the frontier, this one unseparated from the first.
            point(0.0, (85.0, 95.0, 105.0)),
            // Less accurate and not clearly faster than the first: off.
            point(1.0, (95.0, 105.0, 115.0)),
            // Less accurate and clearly faster: on.
            point(2.0, (200.0, 210.0, 220.0)),
            // As accurate as the one before and clearly slower: off.
            point(2.0, (120.0, 130.0, 140.0)),
            // Not on the trade.
            None,
        ];
        let f = frontier(&points);
        let on: Vec<bool> = f.iter().map(|(on, _)| *on).collect();
        assert_eq!(on, [true, true, false, true, false, false]);
        assert_eq!(f[1].1, [0]);
        assert!(f[0].1.is_empty() && f[3].1.is_empty());
    }

    #[test]
    fn the_rate_of_rounds_is_their_median_and_range() {
        let r = Rate::of(&[3.0, 1.0, 2.0, 10.0]);
        assert_eq!((r.low, r.median, r.high), (1.0, 2.5, 10.0));
        assert!(Rate::of(&[20.0, 21.0]).beats(&r));
        assert!(!r.beats(&Rate::of(&[9.0])));
        assert_eq!(r.scaled(2.0).high, 20.0);
        let mut ticks = 0;
        let rates = interleaved(
            &mut [1u64, 2],
            Rounds {
                rounds: 3,
                seconds: 0.001,
            },
            |&mut work| {
                std::thread::sleep(Duration::from_micros(100 * work));
                Ok(work)
            },
            || ticks += 1,
        )
        .unwrap();
        assert_eq!(ticks, 4);
        assert!(
            rates
                .iter()
                .all(|r| r.low > 0.0 && r.low <= r.median && r.median <= r.high)
        );
    }
}
