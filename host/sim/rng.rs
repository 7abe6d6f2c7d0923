//! The slots' generators: parameter sets from the committed dcmt table, seeds from MT19937.

use gpuwars_kernels::rng::Mt19937;
use gpuwars_kernels::rng::mt607::{self, Mt607Params};

/// dcmt's `init_dc` seed the table was made with.
pub const TABLE_SEED: u32 = 4172;

/// The committed MT607 parameter sets (`data/mt607_params.txt`, made by
/// `cargo run --release --example mt607_table -- --seed 4172 --count 4096 --out …`): entry
/// `id` is dcmt's `get_mt_parameter_id(32, 607, id)` after `init_dc(4172)`. 4096 sets, as
/// many as Podlozhnyuk's sample runs generators (`MT_RNG_COUNT`).
pub const TABLE: &[[u32; 3]] = &include!(concat!(env!("OUT_DIR"), "/mt607_params.rs"));

/// Parameter set `id` of the table.
pub fn table_params(id: usize) -> Mt607Params {
    let [a, b, c] = TABLE[id];
    Mt607Params::new(a, b, c)
}

/// The parameters of each of `slots` generators: slot `i` gets table entry `i`, or entry
/// `i mod TABLE.len()` past the table's end (such slots differ by seed only).
pub fn slot_params(slots: u32) -> Vec<Mt607Params> {
    (0..slots as usize)
        .map(|i| table_params(i % TABLE.len()))
        .collect()
}

/// The seed of each of `slots` generators: the first outputs of MT19937 seeded with the
/// world's seed, one per slot.
pub fn slot_seeds(seed: u32, slots: u32) -> Vec<u32> {
    let mut mt = Mt19937::new(seed);
    (0..slots).map(|_| mt.next_u32()).collect()
}

/// The state words of generators seeded with `seeds`, laid out word-major as
/// `gpuwars_kernels::rng::RngStreams` expects.
pub fn word_major_states(seeds: &[u32]) -> Vec<u32> {
    let mut words = vec![0u32; mt607::N * seeds.len()];
    for (slot, &seed) in seeds.iter().enumerate() {
        for (k, word) in mt607::seed_state(seed).into_iter().enumerate() {
            words[k * seeds.len() + slot] = word;
        }
    }
    words
}
