//! One MT607 generator per body slot, stored as a structure of arrays in device memory.
//!
//! A body's random numbers come from the generator of its slot, whichever thread runs it,
//! so they do not depend on the launch shape or the backend. The 19 state words are stored
//! word-major (word `k` of slot `s` at `k · slots + s`): when neighbouring threads draw, their
//! loads and stores fall on neighbouring addresses. A draw touches three words, not the
//! whole state.

use super::mt607::{self, Mt607Params};
use crate::access::{Read, Readable, Write};
use crate::data::{Restrict, View};
use crate::{DevSlice, Thread, access, asked, device_data, kernel_args};

device_data! {
    /// The generators of every slot: parameters, state words and positions.
    pub struct RngStreams(slots): RngStreamsAccess {
        /// dcmt parameters, one set per slot.
        params: [Mt607Params; slots],
        /// State words, word-major: `mt607::N · slots` elements.
        words: [u32; mt607::N * slots],
        /// Position of each slot's oldest word (< 19).
        index: [u32; slots],
    }
}

access! {
    /// What a kernel that draws numbers does with the generators: moves their words and
    /// positions on, reading their parameters.
    pub struct Drawing: RngStreamsAccess {
        params: Read, words: Write, index: Write,
    }
}

impl<M: RngStreamsAccess<params: Readable, words = Write, index = Write>> RngStreams<View, M> {
    /// The generator of `slot`. Its position is written back when the handle is dropped, so
    /// at most one handle per slot may be open at a time (one thread owns a slot).
    #[inline(always)]
    pub fn open(&self, slot: u32) -> SlotRng {
        self.open_at(slot, self.position(slot))
    }

    /// The position of `slot`'s generator (the index of its oldest word), which
    /// [`RngStreams::open_at`] takes: a thread that reads it early asks for the words of its
    /// draws with the parameters, not after them.
    #[inline(always)]
    pub fn position(&self, slot: u32) -> u32 {
        self.index.get(slot)
    }

    /// [`RngStreams::open`], given the generator's `position` (read with
    /// [`RngStreams::position`], and not moved since).
    #[inline(always)]
    pub fn open_at(&self, slot: u32, position: u32) -> SlotRng {
        SlotRng {
            streams: self.restrict(),
            slot,
            params: self.params.get(slot),
            index: position,
        }
    }
}

/// A slot's generator, open for drawing.
pub struct SlotRng {
    streams: RngStreams<View, Drawing>,
    slot: u32,
    params: Mt607Params,
    index: u32,
}

impl SlotRng {
    #[inline(always)]
    fn word(&self, k: u32) -> u32 {
        k * self.streams.index.len() + self.slot
    }

    /// Next 32-bit output: the same sequence as [`mt607::Mt607::next_u32`].
    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        let words = &self.streams.words;
        let (next, middle) = mt607::neighbours(self.index);
        let x = mt607::twist(
            words.get(self.word(self.index)),
            words.get(self.word(next)),
            words.get(self.word(middle)),
            self.params.matrix_a,
        );
        words.set(self.word(self.index), x);
        self.index = next;
        mt607::temper(x, &self.params)
    }

    /// Next uniform float in (0, 1] (see [`mt607::to_unit_f32`]).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        mt607::to_unit_f32(self.next_u32())
    }

    /// The next two uniforms, as two calls of [`SlotRng::next_f32`] give them, with the five
    /// words the two draws read asked for at once: the second draw does not read the word
    /// the first replaces, so the thread waits for the state's memory once, not twice.
    #[inline(always)]
    fn next_two_f32(&mut self) -> (f32, f32) {
        // The second draw reads the words 1, 2 and M + 1 after the first's oldest, which
        // the first overwrites: none is it while N does not divide 1, 2 or M + 1.
        const { assert!(mt607::N > 2 && !(mt607::M + 1).is_multiple_of(mt607::N)) };
        let words = &self.streams.words;
        let (next, middle) = mt607::neighbours(self.index);
        let (after, middle_after) = mt607::neighbours(next);
        let [
            oldest,
            next_word,
            middle_word,
            after_word,
            middle_after_word,
        ] = asked([
            words.get(self.word(self.index)),
            words.get(self.word(next)),
            words.get(self.word(middle)),
            words.get(self.word(after)),
            words.get(self.word(middle_after)),
        ]);
        let a = self.params.matrix_a;
        let first = mt607::twist(oldest, next_word, middle_word, a);
        let second = mt607::twist(next_word, after_word, middle_after_word, a);
        words.set(self.word(self.index), first);
        words.set(self.word(next), second);
        self.index = after;
        let unit = |x| mt607::to_unit_f32(mt607::temper(x, &self.params));
        (unit(first), unit(second))
    }

    /// Two standard normals from the next two uniforms (see [`mt607::box_muller`]).
    #[inline(always)]
    pub fn next_normal_pair(&mut self) -> (f32, f32) {
        let (u1, u2) = self.next_two_f32();
        mt607::box_muller(u1, u2)
    }

    /// The first normal of [`SlotRng::next_normal_pair`], bit for bit, from the same two
    /// draws (the generator ends where the pair leaves it), without the second's sine.
    #[inline(always)]
    pub fn next_normal(&mut self) -> f32 {
        let (u1, u2) = self.next_two_f32();
        mt607::box_muller_first(u1, u2)
    }
}

impl Drop for SlotRng {
    #[inline(always)]
    fn drop(&mut self) {
        self.streams.index.set(self.slot, self.index);
    }
}

kernel_args! {
    /// Arguments of [`seed_streams`].
    pub struct SeedArgs {
        /// Output: every slot's generator.
        pub streams: RngStreams,
        /// Each slot's seed.
        pub seeds: DevSlice<u32>,
        /// The parameter sets; slot `i` takes set `i mod len`.
        pub table: DevSlice<Mt607Params>,
    }
}

/// Thread `i` sets up slot `i`'s generator: parameter set `i mod len`, the state
/// [`mt607::seed_state`] makes from its seed, at position 0. Start-up work that grows with
/// the slots is done on the device rather than on the host.
#[inline(always)]
pub fn seed_streams(t: Thread, args: &SeedArgs) {
    let slot = t.global();
    let streams = &args.streams;
    if slot >= args.seeds.len() || args.table.is_empty() {
        return;
    }
    streams
        .params
        .set(slot, args.table.get(slot % args.table.len()));
    let slots = streams.index.len();
    for (k, word) in mt607::seed_state(args.seeds.get(slot))
        .into_iter()
        .enumerate()
    {
        streams.words.set(k as u32 * slots + slot, word);
    }
    streams.index.set(slot, 0);
}
