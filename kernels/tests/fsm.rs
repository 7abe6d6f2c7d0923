//! Every transition of the three machines, checked against the paper's prose (section 7)
//! written out as expectations here, not read from the tables under test.

use gpuwars_kernels::game::fsm::{Machine, Percept, State, next_state};

use Machine::{Group, Kamikaze, Tricky};
use State::*;

/// A percept with some facts set: `hit`, `out`, `low`, `full`, `ship`, `similar`, `bullet`.
fn sees(facts: &[&str]) -> Percept {
    let mut p = Percept::default();
    for fact in facts {
        match *fact {
            "hit" => p.hit = true,
            "out" => p.out_of_energy = true,
            "low" => p.low_energy = true,
            "full" => p.full_energy = true,
            "ship" => p.sees_ship = true,
            "similar" => p.sees_similar = true,
            "bullet" => p.sees_bullet = true,
            other => panic!("unknown fact {other}"),
        }
    }
    p
}

fn check(machine: Machine, cases: &[(State, &[&str], State)]) {
    for &(from, facts, to) in cases {
        assert_eq!(
            next_state(machine, from, &sees(facts)),
            to,
            "{machine:?}: from {} seeing {facts:?}",
            from.name()
        );
    }
}

#[test]
fn kamikaze_wanders_until_it_sees_the_ship_then_attacks() {
    check(
        Kamikaze,
        &[
            (Wandering, &[], Wandering),
            (Wandering, &["full"], Wandering),
            (Wandering, &["ship"], Attacking),
            (Attacking, &["ship"], Attacking),
            (Attacking, &[], Wandering),
            // A kamikaze ignores its kind and bullets.
            (Wandering, &["similar", "bullet"], Wandering),
            (Attacking, &["ship", "bullet"], Attacking),
        ],
    );
}

#[test]
fn kamikaze_checks_its_energy_when_hit_and_dies_without_any() {
    check(
        Kamikaze,
        &[
            (Wandering, &["hit"], CheckingEnergy),
            (Attacking, &["hit", "ship"], CheckingEnergy),
            (CheckingEnergy, &["out"], Dead),
            (CheckingEnergy, &["out", "ship", "hit"], Dead),
            (CheckingEnergy, &["ship"], Attacking),
            (CheckingEnergy, &[], Wandering),
            // Still in check when hit again: the check itself decides.
            (CheckingEnergy, &["hit"], Wandering),
            (Dead, &["ship", "hit"], Dead),
            (Dead, &[], Dead),
        ],
    );
}

#[test]
fn group_joins_its_kind_attacks_the_ship_and_dodges_bullets_in_that_order_of_urgency() {
    let live = [Wandering, Grouping, Attacking, AvoidingBullets];
    for from in live {
        check(
            Group,
            &[
                (from, &[], Wandering),
                (from, &["similar"], Grouping),
                (from, &["ship"], Attacking),
                (from, &["ship", "similar"], Attacking),
                (from, &["bullet"], AvoidingBullets),
                (from, &["bullet", "ship", "similar"], AvoidingBullets),
                (from, &["hit", "bullet", "ship"], CheckingEnergy),
                // A group enemy never escapes, however low its energy.
                (from, &["low"], Wandering),
            ],
        );
    }
}

#[test]
fn group_checks_its_energy_when_hit_and_dies_without_any() {
    check(
        Group,
        &[
            (CheckingEnergy, &["out"], Dead),
            (CheckingEnergy, &["out", "bullet"], Dead),
            (CheckingEnergy, &["low"], Wandering),
            (CheckingEnergy, &["bullet"], AvoidingBullets),
            (CheckingEnergy, &["ship"], Attacking),
            (CheckingEnergy, &["similar"], Grouping),
            (CheckingEnergy, &[], Wandering),
            (Dead, &["similar", "ship", "bullet", "hit"], Dead),
        ],
    );
}

#[test]
fn tricky_behaves_like_group_while_its_energy_lasts() {
    let live = [Wandering, Grouping, Attacking, AvoidingBullets];
    for from in live {
        check(
            Tricky,
            &[
                (from, &[], Wandering),
                (from, &["similar"], Grouping),
                (from, &["ship", "similar"], Attacking),
                (from, &["bullet", "ship"], AvoidingBullets),
                (from, &["hit"], CheckingEnergy),
                // Low energy matters only once a hit makes it check.
                (from, &["low"], Wandering),
            ],
        );
    }
}

#[test]
fn tricky_escapes_when_low_and_returns_once_recovered() {
    check(
        Tricky,
        &[
            (CheckingEnergy, &["out", "low"], Dead),
            (CheckingEnergy, &["low", "ship"], Escaping),
            (CheckingEnergy, &["low"], Escaping),
            (CheckingEnergy, &["ship"], Attacking),
            (CheckingEnergy, &["bullet"], AvoidingBullets),
            (CheckingEnergy, &["similar"], Grouping),
            (CheckingEnergy, &[], Wandering),
            // Escaping: it keeps fleeing until its energy is full, even in sight of the ship.
            (Escaping, &["ship"], Escaping),
            (Escaping, &["low", "bullet", "similar"], Escaping),
            (Escaping, &["hit"], CheckingEnergy),
            (Escaping, &["full"], Wandering),
            (Escaping, &["full", "ship"], Attacking),
            (Escaping, &["full", "similar"], Grouping),
            (Escaping, &["full", "bullet"], AvoidingBullets),
            (Dead, &["full"], Dead),
        ],
    );
}

#[test]
fn each_machine_reaches_exactly_its_papers_states() {
    // Closure of the transitions from Wandering over every combination of facts.
    let facts = ["hit", "out", "low", "full", "ship", "similar", "bullet"];
    for (machine, count) in [(Kamikaze, 4), (Group, 6), (Tricky, 7)] {
        let mut seen = vec![Wandering];
        let mut i = 0;
        while i < seen.len() {
            for bits in 0u32..1 << facts.len() {
                let set: Vec<&str> = (0..facts.len())
                    .filter(|b| bits & (1 << b) != 0)
                    .map(|b| facts[b])
                    .collect();
                let next = next_state(machine, seen[i], &sees(&set));
                if !seen.contains(&next) {
                    seen.push(next);
                }
            }
            i += 1;
        }
        let mut expected = machine.states().to_vec();
        seen.sort_by_key(|s| *s as u32);
        expected.sort_by_key(|s| *s as u32);
        assert_eq!(seen, expected, "{machine:?}");
        assert_eq!(seen.len(), count, "{machine:?}");
    }
}

#[test]
fn stored_states_and_machines_read_back() {
    for state in State::ALL {
        assert_eq!(State::from_u32(state as u32), state);
    }
    assert_eq!(State::from_u32(99), Wandering);
    for machine in [Machine::None, Kamikaze, Group, Tricky] {
        assert_eq!(Machine::from_u32(machine as u32), machine);
    }
    assert_eq!(Machine::None.rules().len(), 0);
}
