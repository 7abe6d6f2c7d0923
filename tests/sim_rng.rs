//! The slots' generators: the committed dcmt table against the Dynamic Creator itself, and
//! the device-side streams against the host's MT607.

mod common;

use common::sim::{circle, kind, world};
use glam::Vec2;
use gpuwars::Device;
use gpuwars::kernels::rng::{Mt607, Mt19937};
use gpuwars::pipeline::Simulation;
use gpuwars::sim::Boundary;
use gpuwars::sim::rng::dcmt::{Creator, tempering_parameters};
use gpuwars::sim::rng::{TABLE, TABLE_SEED, table_params};

#[test]
fn the_table_starts_with_what_the_creator_makes_in_sequence() {
    let mut creator = Creator::new(TABLE_SEED);
    for id in 0..24u16 {
        assert_eq!(table_params(id as usize), creator.parameters(id), "id {id}");
    }
}

#[test]
fn every_table_entry_carries_its_id_and_dcmts_tempering() {
    assert_eq!(
        TABLE.len(),
        4096,
        "as many sets as the sample runs generators"
    );
    for (id, &[a, _, _]) in TABLE.iter().enumerate() {
        assert_eq!(a & 0xffff, id as u32 & 0xffff, "id {id}");
        assert_ne!(
            a & 0x8000_0000,
            0,
            "id {id}: the top bit of matrix_a is set by dcmt"
        );
    }
    // The tempering search is deterministic in matrix_a: check a spread of entries.
    for id in (0..TABLE.len())
        .step_by(TABLE.len() / 40)
        .chain([TABLE.len() - 1])
    {
        let p = table_params(id);
        assert_eq!(tempering_parameters(p.matrix_a), p, "id {id}");
    }
}

/// Scattering draws four numbers per body from its slot's generator: two uniforms for the
/// position, two more for the Box–Muller velocity. The device must reproduce the host's
/// MT607 with the slot's table entry and its seed (the slot-th output of MT19937(seed)).
fn device_streams_match_the_host_generator(device: &Device) {
    let spec = world(
        Vec2::new(640.0, 480.0),
        Boundary::Wrap,
        vec![kind("b", circle(1.0), 300, &[])],
    );
    let seed = 2009;
    let mut sim = Simulation::new(device, &spec, seed).unwrap();
    sim.scatter(0, 300, 7.0).unwrap();
    let after = sim.snapshot().unwrap();
    let mut seeds = Mt19937::new(seed);
    for slot in 0..300 {
        let mut mt = Mt607::new(table_params(slot % TABLE.len()), seeds.next_u32());
        let u = Vec2::new(mt.next_f32(), mt.next_f32());
        let (nx, ny) = mt.next_normal_pair();
        let (pos, vel) = sim.space().confine(u * spec.size, Vec2::new(nx, ny) * 7.0);
        assert_eq!(after.bodies.pos[slot], pos, "slot {slot}");
        assert_eq!(after.bodies.vel[slot], vel, "slot {slot}");
        assert_eq!(after.bodies.rng.index[slot], 4);
        for k in 0..19 {
            assert_eq!(after.rng_word(slot, k), mt.state[k], "slot {slot} word {k}");
        }
    }
}

on_both_backends!(device_streams_match_the_host_generator);
