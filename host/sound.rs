//! Music and sound effects, synthesised in code (no asset files) and driven by the
//! [`Status`] each step reads back.
//!
//! Every sound is rendered once into a mono buffer at [`SAMPLE_RATE`]: the effects
//! ([`synthesize`]) and one loop of music ([`music`]). [`Sound`] plays them through the default
//! output device, or plays nothing when there is none (servers, CI), so a game runs the same
//! with or without a sound card. [`Cues`] decides which effects a step sounds.

use std::f32::consts::TAU;
use std::num::NonZero;
use std::time::{Duration, Instant};

use gpuwars_kernels::game::control::Status;
use rodio::buffer::SamplesBuffer;
use rodio::{DeviceSinkBuilder, DeviceSinkError, MixerDeviceSink, Player, Source};

/// Samples per second of every sound.
pub const SAMPLE_RATE: u32 = 44_100;

/// The shortest time between two starts of one effect, so that a step with thousands of kills
/// (or a kill every step) does not stack voices until the mix saturates.
pub const MIN_GAP: Duration = Duration::from_millis(50);

/// Length of the fade that closes every sound, so none ends on a click.
const FADE_OUT: Duration = Duration::from_millis(5);

/// A sound effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Effect {
    /// The ship fires: a square blip sweeping down (80 ms).
    Shot,
    /// A shot strikes an enemy: a bright bell-like tick sweeping up (60 ms).
    Hit,
    /// An enemy dies: a noise burst closing down over a low thump (400 ms).
    Kill,
    /// Enemies touch the ship: a low, beating, falling buzz (250 ms).
    ShipHurt,
    /// The game ends: a falling minor jingle (1.6 s).
    GameOver,
    /// A wave of enemies arrives: a filtered noise swell rising to a low horn (750 ms).
    Wave,
    /// A new game starts: a rising major arpeggio of soft bells (600 ms).
    Start,
}

impl Effect {
    /// Every effect, in declaration order.
    pub const ALL: [Effect; 7] = [
        Effect::Shot,
        Effect::Hit,
        Effect::Kill,
        Effect::ShipHurt,
        Effect::GameOver,
        Effect::Wave,
        Effect::Start,
    ];

    /// How long the effect lasts.
    pub fn duration(self) -> Duration {
        // Whole multiples of 10 ms, so that the length in samples is exact.
        Duration::from_millis(match self {
            Effect::Shot => 80,
            Effect::Hit => 60,
            Effect::Kill => 400,
            Effect::ShipHurt => 250,
            Effect::GameOver => 1600,
            Effect::Wave => 750,
            Effect::Start => 600,
        })
    }

    /// How many samples [`synthesize`] returns: [`Effect::duration`] at [`SAMPLE_RATE`].
    pub fn samples(self) -> usize {
        samples_in(self.duration())
    }
}

/// Samples in `d` at [`SAMPLE_RATE`], rounded down.
fn samples_in(d: Duration) -> usize {
    (d.as_micros() * u128::from(SAMPLE_RATE) / 1_000_000) as usize
}

/// The samples of `effect`: mono, [`Effect::samples`] long, within `[-1, 1]`, starting and
/// ending at silence. Deterministic: the same samples every call.
pub fn synthesize(effect: Effect) -> Vec<f32> {
    let mut out = vec![0.0; effect.samples()];
    match effect {
        Effect::Shot => shot(&mut out),
        Effect::Hit => hit(&mut out),
        Effect::Kill => kill(&mut out),
        Effect::ShipHurt => ship_hurt(&mut out),
        Effect::GameOver => game_over(&mut out),
        Effect::Wave => wave(&mut out),
        Effect::Start => start(&mut out),
    }
    fade_out(&mut out);
    // Levels under 1 leave room for several effects and the music at once.
    let peak = match effect {
        Effect::Shot => 0.3,
        Effect::Hit => 0.35,
        Effect::Kill => 0.6,
        Effect::ShipHurt => 0.5,
        Effect::GameOver => 0.55,
        Effect::Wave => 0.45,
        Effect::Start => 0.45,
    };
    normalize(&mut out, peak);
    out
}

/// Beats per minute of [`music`].
const TEMPO: u32 = 140;
/// Samples per sixteenth note at [`TEMPO`]: exactly 4725 at 44.1 kHz, so every bar is a whole
/// number of samples and the loop stays in time however often it repeats.
const SIXTEENTH: usize = (SAMPLE_RATE * 60 / TEMPO / 4) as usize;
/// The loop's chords, one bar each (A minor, F, C, G): bass note, and four tones to arpeggiate,
/// as MIDI note numbers.
const CHORDS: [(u8, [u8; 4]); 4] = [
    (45, [69, 72, 76, 81]),
    (41, [65, 69, 72, 77]),
    (48, [67, 72, 76, 79]),
    (43, [67, 71, 74, 79]),
];
/// Which tone of the chord each sixteenth of a bar plays: up and down.
const ARPEGGIO: [usize; 16] = [0, 1, 2, 3, 2, 1, 0, 1, 0, 1, 2, 3, 2, 1, 2, 3];
/// Which eighths of a bar the bass plays an octave up.
const BASS_OCTAVE: [bool; 8] = [false, false, true, false, false, false, true, false];

/// One loop of the music: four bars (about 6.9 s) of a plucked bass and a square arpeggio.
/// Every note ends inside its bar, so played back to back the loop joins without a click.
/// Quiet (peaks at 0.25) so that the effects stand out.
pub fn music() -> Vec<f32> {
    let mut out = vec![0.0; CHORDS.len() * 16 * SIXTEENTH];
    for (bar, &(bass, tones)) in CHORDS.iter().enumerate() {
        let bar_start = bar * 16 * SIXTEENTH;
        for (eighth, &up) in BASS_OCTAVE.iter().enumerate() {
            let start = bar_start + eighth * 2 * SIXTEENTH;
            let note = if up { bass + 12 } else { bass };
            bass_note(&mut out[start..start + 2 * SIXTEENTH], midi(note));
        }
        for (sixteenth, &tone) in ARPEGGIO.iter().enumerate() {
            let start = bar_start + sixteenth * SIXTEENTH;
            arp_note(&mut out[start..start + SIXTEENTH], midi(tones[tone]));
        }
    }
    normalize(&mut out, 0.25);
    out
}

/// Decides which effects each step sounds: [`Effect::Start`] on a game's first step, those of
/// its [`Status::events`] (shots, shots striking enemies, kills, hits on the ship, waves
/// arriving), each at most once per [`MIN_GAP`], and [`Effect::GameOver`] once when the game
/// ends.
#[derive(Clone, Debug, Default)]
pub struct Cues {
    /// When each effect (indexed as [`Effect::ALL`]) last started.
    last: [Option<Instant>; Effect::ALL.len()],
    /// The step of the last status seen.
    step: Option<u32>,
    /// The game-over jingle has started for the game under way.
    over: bool,
}

impl Cues {
    /// No effect played yet.
    pub fn new() -> Self {
        Cues::default()
    }

    /// The effects to start at `now` for one step's `status`. A status of the same step as the
    /// last one plays nothing again (a front end may show one step for several frames), and
    /// once the game is over only [`Effect::GameOver`] plays, once, as the frozen status
    /// repeats its last events. A status of a game under way re-arms the jingle.
    pub fn due(&mut self, status: &Status, now: Instant) -> Vec<Effect> {
        if self.step == Some(status.step) || (self.over && status.is_over()) {
            return Vec::new();
        }
        self.step = Some(status.step);
        let events = &status.events;
        let wanted = [
            (Effect::Start, u32::from(status.step == 1)),
            (Effect::Shot, events.shots_fired),
            (Effect::Hit, events.shot_hits),
            (Effect::Kill, events.kills),
            (Effect::ShipHurt, events.ship_hits),
            (Effect::Wave, events.waves),
        ];
        let mut due: Vec<Effect> = wanted
            .into_iter()
            .filter(|&(effect, count)| count > 0 && self.allow(effect, now))
            .map(|(effect, _)| effect)
            .collect();
        self.over = status.is_over();
        if self.over {
            self.last[Effect::GameOver as usize] = Some(now);
            due.push(Effect::GameOver);
        }
        due
    }

    /// Whether `effect` may start at `now` (it has not started in the last [`MIN_GAP`]); if so,
    /// it counts as started.
    pub fn allow(&mut self, effect: Effect, now: Instant) -> bool {
        let last = &mut self.last[effect as usize];
        // `duration_since` is zero for an earlier `now`, which then waits like a repeat.
        if last.is_some_and(|t| now.duration_since(t) < MIN_GAP) {
            return false;
        }
        *last = Some(now);
        true
    }
}

/// The audio output: effects over looping music on the default output device, or silence
/// where there is no device.
pub struct Sound {
    /// `None`: no device, nothing is played.
    output: Option<Output>,
    cues: Cues,
    muted: bool,
}

/// An open output device and what plays on it.
struct Output {
    /// Playback stops when this is dropped.
    device: MixerDeviceSink,
    /// The music loop, paused while muted.
    music: Player,
    /// Each effect's samples, indexed as [`Effect::ALL`]; cloning one shares its samples.
    effects: [SamplesBuffer; Effect::ALL.len()],
}

impl Sound {
    /// Opens the default output device and starts the music (paused if `muted`). Without a
    /// device, prints one line saying so to stderr and returns a silent `Sound`, on which
    /// every method works and plays nothing.
    pub fn open(muted: bool) -> Sound {
        let output = match open_device() {
            Ok(mut device) => {
                // Dropping the device is how a game ends its sound, not worth a message.
                device.log_on_drop(false);
                let player = Player::connect_new(device.mixer());
                if muted {
                    player.pause();
                }
                player.append(buffer(music()).repeat_infinite());
                Some(Output {
                    effects: Effect::ALL.map(|effect| buffer(synthesize(effect))),
                    device,
                    music: player,
                })
            }
            Err(e) => {
                eprintln!("gpuwars: {}: playing silently", why_silent(&e));
                None
            }
        };
        Sound {
            output,
            cues: Cues::new(),
            muted,
        }
    }

    /// Plays the effects of one step's `status` (see [`Cues::due`]). Muted or silent, nothing
    /// plays but the cues still advance, so that unmuting does not replay a game over.
    pub fn play(&mut self, status: &Status) {
        for effect in self.cues.due(status, Instant::now()) {
            self.start(effect);
        }
    }

    /// Mutes (pausing the music) or unmutes (resuming it where it paused).
    pub fn set_muted(&mut self, muted: bool) {
        self.muted = muted;
        if let Some(output) = &self.output {
            if muted {
                output.music.pause();
            } else {
                output.music.play();
            }
        }
    }

    /// Flips muting; returns whether it is now muted.
    pub fn toggle_muted(&mut self) -> bool {
        self.set_muted(!self.muted);
        self.muted
    }

    /// Whether it is muted.
    pub fn is_muted(&self) -> bool {
        self.muted
    }

    /// Whether there is no output device (nothing ever plays).
    pub fn is_silent(&self) -> bool {
        self.output.is_none()
    }

    /// Starts `effect` on the device, mixed over whatever plays, unless muted or silent.
    fn start(&self, effect: Effect) {
        if let Some(output) = self.output.as_ref().filter(|_| !self.muted) {
            output
                .device
                .mixer()
                .add(output.effects[effect as usize].clone());
        }
    }
}

/// Opens the default output device. Without a sound card alsa-lib prints a dozen lines of
/// configuration errors on the way to saying so; they are turned off for this call, as
/// [`Sound::open`] says it in one line.
/// Why the game plays without sound, in our words rather than the sound library's.
pub fn why_silent(e: &DeviceSinkError) -> &'static str {
    match e {
        DeviceSinkError::NoDevice => "no sound device",
        DeviceSinkError::DefaultSinkConfigError(_) | DeviceSinkError::SupportedConfigsError(_) => {
            "the sound device is busy, gone or refuses a stereo stream"
        }
        DeviceSinkError::UnsupportedSampleFormat => {
            "the sound device wants a sample format we do not make"
        }
        DeviceSinkError::PlayError(_) | DeviceSinkError::BuildError(_) => {
            "the sound device would not start playing"
        }
    }
}

fn open_device() -> Result<MixerDeviceSink, DeviceSinkError> {
    #[cfg(any(
        target_os = "linux",
        target_os = "dragonfly",
        target_os = "freebsd",
        target_os = "netbsd"
    ))]
    let _quiet = alsa::Quiet::new();
    DeviceSinkBuilder::open_default_sink()
}

/// Turning off alsa-lib's error messages on one thread, through `snd_lib_error_set_local`
/// (alsa-lib 1.1.6 and later) looked up at run time in the alsa-lib cpal links: the crate that
/// declares it is not one of ours. On the systems where cpal plays through ALSA.
#[cfg(any(
    target_os = "linux",
    target_os = "dragonfly",
    target_os = "freebsd",
    target_os = "netbsd"
))]
mod alsa {
    use std::ffi::{c_char, c_int, c_void};

    use libloading::os::unix::Library;

    /// alsa-lib's `snd_local_error_handler_t`. The last argument is a `va_list`, which every
    /// ABI of these systems passes as a pointer; it is never read.
    type Handler = unsafe extern "C" fn(
        *const c_char,
        c_int,
        *const c_char,
        c_int,
        *const c_char,
        *mut c_void,
    );
    /// `snd_lib_error_set_local`: sets this thread's handler, returns the one it replaces.
    type SetLocal = unsafe extern "C" fn(Option<Handler>) -> Option<Handler>;

    unsafe extern "C" fn discard(
        _file: *const c_char,
        _line: c_int,
        _function: *const c_char,
        _err: c_int,
        _fmt: *const c_char,
        _args: *mut c_void,
    ) {
    }

    /// alsa-lib's messages are off on this thread while this lives.
    pub(super) struct Quiet {
        set_local: SetLocal,
        previous: Option<Handler>,
    }

    impl Quiet {
        /// `None` where alsa-lib is not loaded or too old: its messages then stay on.
        pub(super) fn new() -> Option<Quiet> {
            // SAFETY: the symbol, where present, is alsa-lib's function of that signature; the
            // library stays loaded (cpal links it), so the pointer outlives the handle.
            unsafe {
                let set_local = *Library::this()
                    .get::<SetLocal>(b"snd_lib_error_set_local")
                    .ok()?;
                let previous = set_local(Some(discard));
                Some(Quiet {
                    set_local,
                    previous,
                })
            }
        }
    }

    impl Drop for Quiet {
        fn drop(&mut self) {
            // SAFETY: as in `new`; puts back the handler this thread had.
            unsafe {
                (self.set_local)(self.previous);
            }
        }
    }
}

/// Mono samples at [`SAMPLE_RATE`] as a rodio source.
fn buffer(samples: Vec<f32>) -> SamplesBuffer {
    const MONO: NonZero<u16> = NonZero::new(1).unwrap();
    const RATE: NonZero<u32> = NonZero::new(SAMPLE_RATE).unwrap();
    SamplesBuffer::new(MONO, RATE, samples)
}

// The effects. Each writes its raw shape into `out`; `synthesize` closes and levels it.

/// Square wave at 25% duty, swept down from 1.4 kHz to 350 Hz, decaying fast.
fn shot(out: &mut [f32]) {
    let mut osc = Osc::default();
    let len = out.len() as f32;
    for (i, s) in out.iter_mut().enumerate() {
        let t = seconds(i);
        let freq = sweep(1400.0, 350.0, i as f32 / len);
        *s = osc.square(freq, 0.25) * envelope(t, 0.001, 0.025);
    }
}

/// Two inharmonic sine partials (a small bell) rising from 2.2 kHz to 3 kHz, with a click of
/// noise at the start for the impact.
fn hit(out: &mut [f32]) {
    let (mut low, mut high) = (Osc::default(), Osc::default());
    let mut noise = Noise(0x1234_5678);
    let len = out.len() as f32;
    for (i, s) in out.iter_mut().enumerate() {
        let t = seconds(i);
        let freq = sweep(2200.0, 3000.0, i as f32 / len);
        let tone = low.sine(freq) + 0.4 * high.sine(freq * 2.76);
        let click = noise.next() * envelope(t, 0.0005, 0.003);
        *s = tone * envelope(t, 0.001, 0.018) + 0.5 * click;
    }
}

/// White noise through a low-pass closing from 5 kHz to 250 Hz, over a sine thump falling
/// from 100 Hz to 40 Hz.
fn kill(out: &mut [f32]) {
    let mut noise = Noise(0x9e37_79b9);
    let mut thump = Osc::default();
    let mut filter = LowPass::default();
    let len = out.len() as f32;
    for (i, s) in out.iter_mut().enumerate() {
        let (t, x) = (seconds(i), i as f32 / len);
        let burst = filter.run(noise.next(), sweep(5000.0, 250.0, x)) * envelope(t, 0.002, 0.11);
        let low = thump.sine(sweep(100.0, 40.0, x)) * envelope(t, 0.002, 0.08);
        *s = burst + 0.6 * low;
    }
}

/// Two saws a little out of tune (they beat), falling by a fifth, low-passed and pulsed at
/// 30 Hz: a rough buzz.
fn ship_hurt(out: &mut [f32]) {
    let (mut a, mut b) = (Osc::default(), Osc::default());
    let mut filter = LowPass::default();
    let len = out.len() as f32;
    for (i, s) in out.iter_mut().enumerate() {
        let (t, x) = (seconds(i), i as f32 / len);
        let freq = sweep(220.0, 147.0, x);
        let raw = a.saw(freq) + b.saw(freq * 1.06);
        let pulse = 0.65 + 0.35 * (TAU * 30.0 * t).sin();
        *s = filter.run(raw, 1800.0) * pulse * envelope(t, 0.003, 0.09);
    }
}

/// C5, G4, E♭4, then a long C4 with vibrato: square tones softened by a low-pass, each over a
/// sine an octave down.
fn game_over(out: &mut [f32]) {
    // (start, length) in milliseconds, and the MIDI note.
    let notes: [(u64, u64, u8); 4] = [
        (0, 200, 72),
        (200, 200, 67),
        (400, 200, 63),
        (600, 1000, 60),
    ];
    for (start, length, note) in notes {
        let start = samples_in(Duration::from_millis(start));
        let end = (start + samples_in(Duration::from_millis(length))).min(out.len());
        let (mut square, mut sub) = (Osc::default(), Osc::default());
        let mut filter = LowPass::default();
        let long = length > 500;
        for (i, s) in out[start..end].iter_mut().enumerate() {
            let t = seconds(i);
            let vibrato = if long {
                1.0 + 0.006 * (TAU * 5.5 * t).sin()
            } else {
                1.0
            };
            let freq = midi(note) * vibrato;
            let tone = filter.run(square.square(freq, 0.5), 2200.0) + 0.6 * sub.sine(freq * 0.5);
            let decay = if long { 0.35 } else { 0.12 };
            // Each note closes inside its slot, so the next starts from silence.
            *s += tone * envelope(t, 0.004, decay) * close(i, end - start);
        }
    }
}

/// Noise through a band-pass (a low-pass minus a lower one) sweeping up from 200 Hz to
/// 2 kHz as it swells, then a low horn (two detuned saws on A2) taking over: something is
/// coming.
fn wave(out: &mut [f32]) {
    let mut noise = Noise(0x2545_f491);
    let (mut high, mut low) = (LowPass::default(), LowPass::default());
    let (mut a, mut b) = (Osc::default(), Osc::default());
    let mut horn_filter = LowPass::default();
    let len = out.len() as f32;
    let horn_at = 0.25;
    for (i, s) in out.iter_mut().enumerate() {
        let (t, x) = (seconds(i), i as f32 / len);
        let centre = sweep(200.0, 2000.0, x);
        let n = noise.next();
        let band = high.run(n, centre * 1.5) - low.run(n, centre * 0.67);
        let swell = (x / 0.4).min(1.0) * (1.0 - x);
        let horn = if t < horn_at {
            0.0
        } else {
            let raw = a.saw(110.0) + b.saw(110.0 * 1.01);
            horn_filter.run(raw, 900.0) * envelope(t - horn_at, 0.04, 0.2)
        };
        *s = 2.0 * band * swell + 0.5 * horn;
    }
}

/// G5, B5, D6 then G6, each a sine with a quieter octave above: ready, go.
fn start(out: &mut [f32]) {
    let notes: [(u64, u64, u8); 4] = [(0, 100, 79), (100, 100, 83), (200, 100, 86), (300, 300, 91)];
    for (start, length, note) in notes {
        let start = samples_in(Duration::from_millis(start));
        let end = (start + samples_in(Duration::from_millis(length))).min(out.len());
        let (mut base, mut octave) = (Osc::default(), Osc::default());
        for (i, s) in out[start..end].iter_mut().enumerate() {
            let t = seconds(i);
            let freq = midi(note);
            let tone = base.sine(freq) + 0.3 * octave.sine(freq * 2.0);
            *s += tone * envelope(t, 0.003, 0.08) * close(i, end - start);
        }
    }
}

// The music's two voices.

/// A plucked saw through a low-pass that closes with the pluck.
fn bass_note(out: &mut [f32], freq: f32) {
    let mut osc = Osc::default();
    let mut filter = LowPass::default();
    let len = out.len();
    for (i, s) in out.iter_mut().enumerate() {
        let t = seconds(i);
        let pluck = envelope(t, 0.003, 0.12);
        *s += 0.5 * filter.run(osc.saw(freq), 300.0 + 1500.0 * pluck) * pluck * close(i, len);
    }
}

/// A short, soft square blip.
fn arp_note(out: &mut [f32], freq: f32) {
    let mut osc = Osc::default();
    let mut filter = LowPass::default();
    let len = out.len();
    for (i, s) in out.iter_mut().enumerate() {
        let t = seconds(i);
        *s += 0.25
            * filter.run(osc.square(freq, 0.5), 2500.0)
            * envelope(t, 0.002, 0.05)
            * close(i, len);
    }
}

// Building blocks.

/// Seconds at sample `i`.
fn seconds(i: usize) -> f32 {
    i as f32 / SAMPLE_RATE as f32
}

/// Frequency of MIDI note `note` (69 is A4, 440 Hz).
fn midi(note: u8) -> f32 {
    440.0 * 2f32.powf((f32::from(note) - 69.0) / 12.0)
}

/// From `from` to `to` geometrically (as pitch is heard) as `x` goes from 0 to 1.
fn sweep(from: f32, to: f32, x: f32) -> f32 {
    from * (to / from).powf(x)
}

/// A linear rise over `attack` seconds, then an exponential decay with time constant `decay`.
fn envelope(t: f32, attack: f32, decay: f32) -> f32 {
    if t < attack {
        t / attack
    } else {
        (-(t - attack) / decay).exp()
    }
}

/// Gain of sample `i` of `len` for a half-cosine fade over the last [`FADE_OUT`]: 1 before
/// it, 0 at the last sample.
fn close(i: usize, len: usize) -> f32 {
    let fade = samples_in(FADE_OUT).min(len);
    let left = len - 1 - i;
    if left >= fade {
        1.0
    } else {
        0.5 - 0.5 * (std::f32::consts::PI * left as f32 / fade as f32).cos()
    }
}

/// Fades the end of `out` (see [`close`]).
fn fade_out(out: &mut [f32]) {
    let len = out.len();
    for (i, s) in out.iter_mut().enumerate() {
        *s *= close(i, len);
    }
}

/// Scales `out` so that its largest magnitude is `peak` (silence stays silence).
fn normalize(out: &mut [f32], peak: f32) {
    let max = out.iter().fold(0.0f32, |m, s| m.max(s.abs()));
    if max > 0.0 {
        let gain = peak / max;
        out.iter_mut().for_each(|s| *s *= gain);
    }
}

/// An oscillator's phase, in turns, with band-limited (PolyBLEP) saw and square waves so that
/// high notes do not alias into harsh tones.
#[derive(Default)]
struct Osc {
    phase: f32,
}

impl Osc {
    /// Advances one sample at `freq`; returns the phase before and the phase step.
    fn advance(&mut self, freq: f32) -> (f32, f32) {
        let (phase, dt) = (self.phase, freq / SAMPLE_RATE as f32);
        self.phase = (phase + dt).fract();
        (phase, dt)
    }

    fn sine(&mut self, freq: f32) -> f32 {
        let (phase, _) = self.advance(freq);
        (TAU * phase).sin()
    }

    fn saw(&mut self, freq: f32) -> f32 {
        let (phase, dt) = self.advance(freq);
        2.0 * phase - 1.0 - blep(phase, dt)
    }

    /// High for the first `duty` of each cycle.
    fn square(&mut self, freq: f32, duty: f32) -> f32 {
        let (phase, dt) = self.advance(freq);
        let naive = if phase < duty { 1.0 } else { -1.0 };
        naive + blep(phase, dt) - blep((phase + 1.0 - duty).fract(), dt)
    }
}

/// The PolyBLEP correction for a unit step at phase 0, `dt` being the phase step.
fn blep(phase: f32, dt: f32) -> f32 {
    if phase < dt {
        let x = phase / dt;
        2.0 * x - x * x - 1.0
    } else if phase > 1.0 - dt {
        let x = (phase - 1.0) / dt;
        x * x + 2.0 * x + 1.0
    } else {
        0.0
    }
}

/// A one-pole low-pass filter.
#[derive(Default)]
struct LowPass {
    y: f32,
}

impl LowPass {
    fn run(&mut self, x: f32, cutoff: f32) -> f32 {
        let a = 1.0 - (-TAU * cutoff / SAMPLE_RATE as f32).exp();
        self.y += a * (x - self.y);
        self.y
    }
}

/// White noise in `[-1, 1)` from a xorshift generator: the same noise every run. The state
/// must not start at 0, where xorshift stays.
struct Noise(u32);

impl Noise {
    fn next(&mut self) -> f32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x >> 8) as f32 / (1u32 << 23) as f32 - 1.0
    }
}
