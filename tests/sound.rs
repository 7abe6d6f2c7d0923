//! The synthesised sounds (lengths, levels, clean ends, distinct timbres), the cues a step's
//! events give, and the output on a machine without a sound device.

use std::time::{Duration, Instant};

use gpuwars::kernels::game::control::{DESTROYED, Events, PLAYING, Status};
use gpuwars::sound::{Cues, Effect, MIN_GAP, SAMPLE_RATE, Sound, music, synthesize};

fn rms(samples: &[f32]) -> f32 {
    (samples.iter().map(|s| s * s).sum::<f32>() / samples.len() as f32).sqrt()
}

fn peak(samples: &[f32]) -> f32 {
    samples.iter().fold(0.0, |m, s| m.max(s.abs()))
}

/// Energy at 48 frequencies spaced a quarter-octave apart from 55 Hz, over the first 50 ms
/// (Hann window) as magnitudes scaled to unit length: a coarse spectrum.
fn spectrum(samples: &[f32]) -> Vec<f32> {
    let window = &samples[..ms(50)];
    let n = window.len() as f32;
    let bands: Vec<f32> = (0..48)
        .map(|band| {
            let freq = 55.0 * 2f32.powf(band as f32 / 4.0);
            let step = std::f32::consts::TAU * freq / SAMPLE_RATE as f32;
            let (mut re, mut im) = (0.0, 0.0);
            for (i, &x) in window.iter().enumerate() {
                let hann = 0.5 - 0.5 * (std::f32::consts::TAU * i as f32 / n).cos();
                re += x * hann * (step * i as f32).cos();
                im -= x * hann * (step * i as f32).sin();
            }
            (re * re + im * im).sqrt()
        })
        .collect();
    let norm = bands.iter().map(|e| e * e).sum::<f32>().sqrt();
    bands.iter().map(|e| e / norm).collect()
}

/// Samples in `ms` milliseconds.
fn ms(ms: u32) -> usize {
    (SAMPLE_RATE * ms / 1000) as usize
}

fn status(step: u32, game_over: u32, events: Events) -> Status {
    Status {
        step,
        game_over,
        events,
        ..Status::default()
    }
}

const EVERYTHING: Events = Events {
    shots_fired: 1,
    kills: 5000,
    ship_hits: 3,
    spawned: 100,
    waves: 2,
    shot_hits: 4,
};

/// What [`EVERYTHING`] sounds, in the order cued.
const ALL_EVENTS: [Effect; 5] = [
    Effect::Shot,
    Effect::Hit,
    Effect::Kill,
    Effect::ShipHurt,
    Effect::Wave,
];

#[test]
fn effects_are_audible_in_range_and_end_quietly() {
    for effect in Effect::ALL {
        let samples = synthesize(effect);
        let expected = effect.duration().as_secs_f64() * f64::from(SAMPLE_RATE);
        assert_eq!(samples.len() as f64, expected, "{effect:?} length");
        assert_eq!(samples.len(), effect.samples(), "{effect:?} length");
        assert!(
            samples.iter().all(|s| s.is_finite() && s.abs() <= 1.0),
            "{effect:?} out of [-1, 1]"
        );
        assert!(
            rms(&samples) > 0.02,
            "{effect:?} too quiet: {}",
            rms(&samples)
        );
        // No click at either end: a sound starts and ends at silence.
        assert!(
            samples[0].abs() < 1e-3,
            "{effect:?} starts at {}",
            samples[0]
        );
        let tail = &samples[samples.len() - ms(3)..];
        assert!(
            peak(tail) < 0.02,
            "{effect:?} ends at {} in its last 3 ms",
            peak(tail)
        );
        assert_eq!(*samples.last().unwrap(), 0.0, "{effect:?} last sample");
    }
}

#[test]
fn effects_are_deterministic() {
    for effect in Effect::ALL {
        assert_eq!(synthesize(effect), synthesize(effect), "{effect:?}");
    }
}

#[test]
fn effects_sound_different() {
    let spectra: Vec<(Effect, Vec<f32>)> = Effect::ALL
        .into_iter()
        .map(|effect| (effect, spectrum(&synthesize(effect))))
        .collect();
    for (i, (a, spectrum_a)) in spectra.iter().enumerate() {
        for (b, spectrum_b) in &spectra[i + 1..] {
            let likeness: f32 = spectrum_a.iter().zip(spectrum_b).map(|(x, y)| x * y).sum();
            assert!(likeness < 0.5, "{a:?} and {b:?} are alike ({likeness})");
        }
    }
}

#[test]
fn music_is_a_quiet_loop_of_whole_bars() {
    let samples = music();
    let seconds = samples.len() as f32 / SAMPLE_RATE as f32;
    assert!((3.0..=10.0).contains(&seconds), "loop of {seconds} s");
    // Four bars of 4/4 at 140 beats per minute.
    assert_eq!(samples.len(), 4 * 4 * SAMPLE_RATE as usize * 60 / 140);
    assert!(samples.iter().all(|s| s.is_finite()));
    assert!(rms(&samples) > 0.01, "silent music");
    let loudest_effect = Effect::ALL
        .into_iter()
        .map(|effect| peak(&synthesize(effect)))
        .fold(0.0, f32::max);
    assert!(peak(&samples) <= 0.5 * loudest_effect, "music too loud");
    // The loop joins without a click.
    assert!(samples[0].abs() < 1e-3 && samples.last().unwrap().abs() < 1e-3);
}

#[test]
fn each_event_cues_its_effect() {
    let now = Instant::now();
    let mut cues = Cues::new();
    assert_eq!(cues.due(&status(7, PLAYING, Events::default()), now), []);
    let shot = Events {
        shots_fired: 1,
        ..Events::default()
    };
    assert_eq!(cues.due(&status(2, PLAYING, shot), now), [Effect::Shot]);
    let hurt = Events {
        ship_hits: 2,
        ..Events::default()
    };
    assert_eq!(cues.due(&status(3, PLAYING, hurt), now), [Effect::ShipHurt]);
    // Enemies trickling in are no wave; a wave arriving is.
    let spawned = Events {
        spawned: 7,
        ..Events::default()
    };
    assert_eq!(cues.due(&status(4, PLAYING, spawned), now), []);
    let wave = Events {
        spawned: 7,
        waves: 1,
        ..Events::default()
    };
    assert_eq!(cues.due(&status(5, PLAYING, wave), now), [Effect::Wave]);
    let struck = Events {
        shot_hits: 1,
        ..Events::default()
    };
    assert_eq!(cues.due(&status(6, PLAYING, struck), now), [Effect::Hit]);
    assert_eq!(
        cues.due(&status(8, PLAYING, EVERYTHING), now + MIN_GAP),
        ALL_EVENTS
    );
}

#[test]
fn a_game_starting_sounds_once() {
    let t0 = Instant::now();
    let mut cues = Cues::new();
    let quiet = Events::default();
    // The first step's status: the game has started.
    assert_eq!(cues.due(&status(1, PLAYING, quiet), t0), [Effect::Start]);
    assert_eq!(cues.due(&status(1, PLAYING, quiet), t0 + MIN_GAP), []);
    assert_eq!(cues.due(&status(2, PLAYING, quiet), t0 + MIN_GAP), []);
    assert_eq!(
        cues.due(&status(3, DESTROYED, quiet), t0 + 2 * MIN_GAP),
        [Effect::GameOver]
    );
    // A new game's first step, after the last one ended.
    assert_eq!(
        cues.due(&status(1, PLAYING, quiet), t0 + 3 * MIN_GAP),
        [Effect::Start]
    );
}

#[test]
fn an_effect_starts_at_most_once_per_gap() {
    let t0 = Instant::now();
    let mut cues = Cues::new();
    let all = ALL_EVENTS;
    assert_eq!(cues.due(&status(11, PLAYING, EVERYTHING), t0), all);
    // The same step shown again plays nothing, whenever.
    assert_eq!(cues.due(&status(11, PLAYING, EVERYTHING), t0 + MIN_GAP), []);
    for step in 2..10 {
        let t = t0 + Duration::from_millis(5 * u64::from(step));
        assert_eq!(cues.due(&status(step, PLAYING, EVERYTHING), t), []);
    }
    assert_eq!(
        cues.due(&status(10, PLAYING, EVERYTHING), t0 + MIN_GAP),
        all
    );
    // `allow` shares the gap; other effects are not held up by it.
    assert!(!cues.allow(Effect::Kill, t0 + MIN_GAP));
    assert!(cues.allow(Effect::Start, t0 + MIN_GAP));
    assert!(!cues.allow(Effect::Start, t0 + MIN_GAP + MIN_GAP / 2));
    // A clock read out of order waits like a repeat.
    assert!(!cues.allow(Effect::Kill, t0));
}

#[test]
fn game_over_plays_once_per_game() {
    let t0 = Instant::now();
    let mut cues = Cues::new();
    cues.due(&status(1, PLAYING, EVERYTHING), t0);
    // The last step's events sound with the jingle.
    let later = t0 + 2 * MIN_GAP;
    let mut last = ALL_EVENTS.to_vec();
    last.push(Effect::GameOver);
    assert_eq!(cues.due(&status(2, DESTROYED, EVERYTHING), later), last);
    // The frozen status repeats; nothing more plays.
    for i in 3..6 {
        assert_eq!(
            cues.due(&status(2, DESTROYED, EVERYTHING), t0 + i * MIN_GAP),
            []
        );
    }
    // A new game re-arms the jingle.
    let quiet = Events::default();
    assert_eq!(
        cues.due(&status(1, PLAYING, quiet), t0 + 10 * MIN_GAP),
        [Effect::Start]
    );
    assert_eq!(
        cues.due(&status(40, DESTROYED, quiet), t0 + 11 * MIN_GAP),
        [Effect::GameOver]
    );
}

/// This machine, like CI, may have no sound device: opening must not panic, and everything
/// must work (silently there).
#[test]
fn sound_without_a_device_plays_silently() {
    let mut sound = Sound::open(true);
    assert!(sound.is_muted());
    for step in 1..200 {
        let over = if step < 150 { PLAYING } else { DESTROYED };
        sound.play(&status(step, over, EVERYTHING));
    }
    if sound.is_silent() {
        // Unmuted, a silent output still plays nothing and stays silent.
        sound.set_muted(false);
        sound.play(&status(1, PLAYING, EVERYTHING));
        assert!(sound.is_silent());
    }
}

#[test]
fn muting_toggles() {
    let mut sound = Sound::open(true);
    assert!(sound.is_muted());
    assert!(!sound.toggle_muted());
    assert!(!sound.is_muted());
    assert!(sound.toggle_muted());
    sound.set_muted(true);
    assert!(sound.is_muted());
    sound.set_muted(false);
    assert!(!sound.is_muted());
    assert!(!Sound::open(false).is_muted());
}

#[test]
fn a_silent_game_says_why_in_its_own_words() {
    use gpuwars::sound::why_silent;
    use rodio::DeviceSinkError;
    for (e, said) in [
        (DeviceSinkError::NoDevice, "no sound device"),
        (
            DeviceSinkError::UnsupportedSampleFormat,
            "the sound device wants a sample format we do not make",
        ),
    ] {
        let why = why_silent(&e);
        assert_eq!(why, said);
        // Never the library's own sentence.
        assert_ne!(why, e.to_string());
    }
}
