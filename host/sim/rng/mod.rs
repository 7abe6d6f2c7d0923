//! The slots' generators: parameter sets from the committed dcmt table (slot `i` takes set
//! `i mod` the table's length, on the device: `gpuwars_kernels::rng::streams::seed_streams`),
//! seeds from MT19937. The table itself comes from the Dynamic Creator's search ([`dcmt`]),
//! run once, offline.

pub mod dcmt;

use gpuwars_kernels::rng::Mt19937;
use gpuwars_kernels::rng::mt607::Mt607Params;

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

/// The seed of each of `slots` generators: the first outputs of MT19937 seeded with the
/// world's seed, one per slot.
pub fn slot_seeds(seed: u32, slots: u32) -> Vec<u32> {
    let mut mt = Mt19937::new(seed);
    (0..slots).map(|_| mt.next_u32()).collect()
}
