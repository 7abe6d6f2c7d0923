//! A slot's generator in the device's structure of arrays (`SlotRng`) draws what the host's
//! MT607 draws from the same state, from every position in the 19-word circle: its normals
//! (two draws read together) and its uniforms, and it leaves the same words and position.

use gpuwars_kernels::DevSlice;
use gpuwars_kernels::rng::mt607::{N, seed_state};
use gpuwars_kernels::rng::streams::RngStreams;
use gpuwars_kernels::rng::{Mt607, Mt607Params};

/// Slots in the arrays; the generator under test is the middle one, so that a word read
/// from a neighbouring slot's column would show.
const SLOTS: u32 = 3;
const SLOT: u32 = 1;

/// The device-side arrays of [`SLOTS`] generators: slot [`SLOT`] holds `mt`'s state, the
/// others words that differ from it.
struct Arrays {
    params: Vec<Mt607Params>,
    words: Vec<u32>,
    index: Vec<u32>,
}

impl Arrays {
    fn of(mt: &Mt607) -> Arrays {
        let mut words = vec![0; N * SLOTS as usize];
        for (k, &word) in mt.state.iter().enumerate() {
            for slot in 0..SLOTS {
                // Word-major, as the device keeps them; the other slots' words differ.
                let other = if slot == SLOT { 0 } else { 0x9e37_79b9 };
                words[(k as u32 * SLOTS + slot) as usize] = word ^ other;
            }
        }
        Arrays {
            params: vec![mt.params; SLOTS as usize],
            words,
            index: vec![mt.index; SLOTS as usize],
        }
    }

    /// Views of the arrays for the test's lifetime.
    fn streams(&mut self) -> RngStreams {
        fn view<T: Copy>(data: &mut [T]) -> DevSlice<T> {
            // SAFETY: the vectors outlive the views (they live in the same test), and only
            // the one thread of the test reads and writes them through them.
            unsafe { DevSlice::from_raw_parts(data.as_mut_ptr() as u64, data.len() as u32) }
        }
        RngStreams {
            params: view(&mut self.params),
            words: view(&mut self.words),
            index: view(&mut self.index),
        }
    }

    /// Slot [`SLOT`]'s words in circle order.
    fn state(&self) -> [u32; N] {
        core::array::from_fn(|k| self.words[k * SLOTS as usize + SLOT as usize])
    }
}

/// A generator seeded with `seed` (its parameters made from it too), at position `index`.
fn generator(seed: u32, index: u32) -> Mt607 {
    let params = Mt607Params::new(0x8000_0000 | 0x1234_0000 | seed, 0x9d2c_5680, 0xefc6_0000);
    Mt607 {
        params,
        state: seed_state(seed),
        index,
    }
}

#[test]
fn normals_match_the_host_generator_from_every_position() {
    for seed in [1u32, 2009, 0xdead_beef] {
        for index in 0..N as u32 {
            let mut host = generator(seed, index);
            let mut arrays = Arrays::of(&host);
            let streams = arrays.streams();
            {
                let mut rng = streams.open(SLOT);
                assert_eq!(
                    rng.next_normal_pair(),
                    host.next_normal_pair(),
                    "seed {seed}, index {index}"
                );
                // The pair after, from the position the first left: the two draws wrap.
                assert_eq!(rng.next_normal(), host.next_normal_pair().0);
            }
            assert_eq!(arrays.state(), host.state, "seed {seed}, index {index}");
            assert_eq!(arrays.index[SLOT as usize], host.index);
        }
    }
}

#[test]
fn uniforms_match_the_host_generator_from_every_position() {
    for index in 0..N as u32 {
        let mut host = generator(7, index);
        let mut arrays = Arrays::of(&host);
        let streams = arrays.streams();
        {
            let mut rng = streams.open(SLOT);
            for draw in 0..2 * N {
                assert_eq!(
                    rng.next_u32(),
                    host.next_u32(),
                    "index {index}, draw {draw}"
                );
            }
        }
        assert_eq!(arrays.state(), host.state);
        assert_eq!(arrays.index[SLOT as usize], host.index);
    }
}
