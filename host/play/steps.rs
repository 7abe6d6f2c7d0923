//! The game's side of the loop: the due steps submitted with their input, the statuses taken
//! as they come back (sound, the hit flash, the end of the game and its high score), and a
//! replay's end checked against its recording.

use std::time::Instant;

use anyhow::bail;
use gpuwars_kernels::game::control::Status;

use super::App;
use super::draw::FLASH_FRAMES;
use crate::pipeline::Profile;

impl App<'_> {
    /// Whether game time runs: the game has started and is neither paused, nor behind the
    /// help, nor over; a replay has steps left.
    fn running(&self) -> bool {
        self.begun && !self.paused && !self.help && !self.round.record.over && !self.at_end()
    }

    /// Whether a replay has submitted its every step.
    pub(super) fn at_end(&self) -> bool {
        self.watch
            .as_ref()
            .is_some_and(|w| self.round.submitted >= w.replay.inputs.len() as u64)
    }

    /// Plays the due steps (the benchmark's one step, profiled when `profiled`) and takes
    /// the statuses that came back; returns the profile of a profiled step.
    pub(super) fn advance(
        &mut self,
        now: Instant,
        profiled: bool,
    ) -> anyhow::Result<Option<Profile>> {
        let running = self.running();
        self.round.clock.run(running, now);
        let due = match (running, &self.bench) {
            (false, _) => 0,
            (true, Some(_)) => 1,
            (true, None) => self.round.clock.due(self.round.submitted, now),
        };
        let due = match &mut self.watch {
            Some(watch) => {
                let left = watch.replay.inputs.len() as u64 - self.round.submitted;
                (due + std::mem::take(&mut watch.single)).min(left)
            }
            None => due,
        };
        let mut profile = None;
        for _ in 0..due {
            let input = self.input();
            if profiled {
                let mut p = Profile::default();
                self.round.game.submit_profiled(input, &mut p)?;
                profile = Some(p);
            } else {
                self.round.game.submit(input)?;
            }
            self.round.submitted += 1;
            self.rates.1 += 1;
        }
        while let Some(status) = self.round.game.ready_status()? {
            self.take(status);
        }
        if self.at_end() || (self.watch.is_some() && self.round.record.over) {
            self.check_replay()?;
        }
        Ok(profile)
    }

    /// At a replay's end (once): every status taken, the state's hash compared with the
    /// recording's; a mismatch is an error.
    pub(super) fn check_replay(&mut self) -> anyhow::Result<()> {
        let Some(watch) = self.watch.as_mut().filter(|w| !w.checked) else {
            return Ok(());
        };
        watch.checked = true;
        while let Some(status) = self.round.game.next_status()? {
            self.take(status);
        }
        let hash = self.round.game.state_hash()?;
        let watch = self.watch.as_ref().expect("checked above");
        let recorded = watch.replay.state_hash;
        if hash != recorded {
            bail!(
                "{}: the replay ended in state {hash:#018x} but was recorded ending in {recorded:#018x}",
                watch.file
            );
        }
        eprintln!(
            "gpuwars: the replay ended after {} steps in the recorded state {hash:#018x}",
            self.round.submitted
        );
        self.hud_at = None;
        Ok(())
    }

    /// One status back from the device: recorded, heard, and the end of the game noted.
    pub(super) fn take(&mut self, status: Status) {
        if self.round.record.over {
            return;
        }
        self.round.record.take(status);
        self.sound.play(&status);
        if status.events.ship_hits > 0 {
            self.flash = FLASH_FRAMES;
        }
        if self.round.record.over {
            self.keep_score();
        }
    }

    /// Records the game's score as the scene's best if it is, once per game: at game over,
    /// or when the window closes mid-game. A replay's is not the player's.
    pub(super) fn keep_score(&mut self) {
        if std::mem::replace(&mut self.round.scored, true) || self.watch.is_some() {
            return;
        }
        let score = self.round.record.last.score;
        if let Some(scores) = &mut self.scores
            && scores.record(&self.scene.name, score, Some(self.options.seed))
            && let Err(e) = scores.save()
        {
            eprintln!("gpuwars: the high score was not saved: {e}");
        }
    }
}
