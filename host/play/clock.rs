//! Game time in the window: it runs while the game is neither paused nor over, as fast as a
//! replay is asked to play, and tells how many steps are due.

use std::time::Instant;

use super::MAX_CATCH_UP;

/// Game time: runs while the game is neither paused nor over, `rate` times as fast as real
/// time, and tells how many steps are due.
pub(super) struct Clock {
    dt: f64,
    /// Game time banked before `since`.
    banked: f64,
    /// When it last started running, if it runs.
    since: Option<Instant>,
    /// Game seconds per real second.
    rate: u32,
    /// Game seconds given up because the steps could not keep up.
    given_up: f64,
}

impl Clock {
    pub(super) fn new(dt: f32) -> Self {
        Clock {
            dt: f64::from(dt),
            banked: 0.0,
            since: None,
            rate: 1,
            given_up: 0.0,
        }
    }

    pub(super) fn run(&mut self, running: bool, now: Instant) {
        match (running, self.since) {
            (true, None) => self.since = Some(now),
            (false, Some(since)) => {
                self.banked += (now - since).as_secs_f64() * f64::from(self.rate);
                self.since = None;
            }
            _ => {}
        }
    }

    /// Runs `rate` times as fast as real time from `now` on.
    pub(super) fn set_rate(&mut self, rate: u32, now: Instant) {
        let running = self.since.is_some();
        self.run(false, now);
        self.rate = rate;
        self.run(running, now);
    }

    /// Counts one step played out of time (a single step while paused), so that the steps
    /// due later do not wait for it.
    pub(super) fn bank_step(&mut self) {
        self.banked += self.dt;
    }

    /// Game seconds given up so far because the steps could not keep up.
    pub(super) fn given_up(&self) -> f64 {
        self.given_up
    }

    /// Steps due at `now` when `played` have been played; the time of the steps beyond
    /// [`MAX_CATCH_UP`] (times the rate) is given up (the game slows down, it does not skip).
    pub(super) fn due(&mut self, played: u64, now: Instant) -> u64 {
        let rate = f64::from(self.rate);
        let elapsed = self.banked + self.since.map_or(0.0, |s| (now - s).as_secs_f64() * rate);
        let due = ((elapsed / self.dt) as u64).saturating_sub(played);
        let most = MAX_CATCH_UP * u64::from(self.rate);
        if due > most {
            let late = (due - most) as f64 * self.dt;
            self.banked -= late;
            self.given_up += late;
        }
        due.min(most)
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    /// A clock of 10 ms steps, started at `t0`.
    fn running(t0: Instant) -> Clock {
        let mut clock = Clock::new(0.01);
        clock.run(true, t0);
        clock
    }

    #[test]
    fn a_faster_clock_makes_steps_due_faster_from_the_change_on() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        let mut clock = running(t0);
        assert_eq!(clock.due(0, t0 + ms(45)), 4);
        // Four times real time from 50 ms on: 50 ms at x1 and 10 ms at x4 make 9 steps of
        // game time, 4 of them played.
        clock.set_rate(4, t0 + ms(50));
        assert_eq!(clock.due(4, t0 + ms(60)), 5);
        // Catching up is capped at MAX_CATCH_UP times the rate, the rest given up.
        assert_eq!(clock.due(9, t0 + ms(1050)), MAX_CATCH_UP * 4);
        assert_eq!(clock.due(9 + MAX_CATCH_UP * 4, t0 + ms(1050)), 0);
        // 4,050 ms of game time were due by then (to a step: whole steps are due), 9 +
        // MAX_CATCH_UP × 4 steps played: the rest was given up.
        let due_ms = 50.0 + 1000.0 * 4.0;
        let played_ms = 10.0 * (9 + MAX_CATCH_UP * 4) as f64;
        let given_up_ms = clock.given_up() * 1000.0;
        assert!(
            (given_up_ms - (due_ms - played_ms)).abs() <= 10.0,
            "{given_up_ms}"
        );
    }

    #[test]
    fn single_steps_while_paused_do_not_delay_the_steps_after() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        let mut clock = running(t0);
        assert_eq!(clock.due(0, t0 + ms(30)), 3);
        clock.run(false, t0 + ms(30));
        // Paused for a second: nothing due; three single steps are banked.
        assert_eq!(clock.due(3, t0 + ms(1030)), 0);
        for _ in 0..3 {
            clock.bank_step();
        }
        clock.run(true, t0 + ms(1030));
        // 10 ms after going on: one step due after the six played.
        assert_eq!(clock.due(6, t0 + ms(1040)), 1);
    }
}
