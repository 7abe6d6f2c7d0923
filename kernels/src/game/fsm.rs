//! The enemies' finite-state machines (paper section 7), as data.
//!
//! Each machine is a table of [`Rule`]s read top to bottom: the first rule whose `from` set
//! holds the current state and whose condition holds in this step's [`Percept`] gives the
//! next state; if none does, the state stays. The paper's figures are not in its text, so the
//! tables follow its prose (7.1–7.3); `docs/ai.md` prints the same tables.
//!
//! A body moves at most one transition per step. A hit sends it to "checking energy", and the
//! next step decides from there: dead when the energy is gone, escaping (tricky only) when
//! little is left, otherwise back to reacting to what it sees.

/// A state of an enemy's machine (stored in `Bodies::state`; 0 at birth).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum State {
    /// Roaming at random, looking for the ship or similar bodies.
    Wandering = 0,
    /// Closing in on visible bodies of its own kind.
    Grouping = 1,
    /// Throwing itself against the ship.
    Attacking = 2,
    /// Stepping out of the path of a shot coming its way.
    AvoidingBullets = 3,
    /// Just hit: the next step decides what its energy allows.
    CheckingEnergy = 4,
    /// Fleeing the ship while it recovers energy (tricky only).
    Escaping = 5,
    /// Out of energy: the slot is freed.
    Dead = 6,
}

impl State {
    /// Every state, in numeric order.
    pub const ALL: [State; 7] = [
        State::Wandering,
        State::Grouping,
        State::Attacking,
        State::AvoidingBullets,
        State::CheckingEnergy,
        State::Escaping,
        State::Dead,
    ];

    /// The state stored as `value`; unknown values read as [`State::Wandering`].
    #[inline(always)]
    pub fn from_u32(value: u32) -> State {
        match value {
            1 => State::Grouping,
            2 => State::Attacking,
            3 => State::AvoidingBullets,
            4 => State::CheckingEnergy,
            5 => State::Escaping,
            6 => State::Dead,
            _ => State::Wandering,
        }
    }

    /// This state's bit in a [`Rule::from`] set.
    #[inline(always)]
    pub const fn bit(self) -> u32 {
        1 << self as u32
    }

    /// Lower-case name, as in the docs.
    pub fn name(self) -> &'static str {
        match self {
            State::Wandering => "wandering",
            State::Grouping => "grouping",
            State::Attacking => "attacking",
            State::AvoidingBullets => "avoiding bullets",
            State::CheckingEnergy => "checking energy",
            State::Escaping => "escaping",
            State::Dead => "dead",
        }
    }
}

/// Which machine drives a kind (`Brain::machine` of [`crate::game::rules::Brain`]).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Machine {
    /// No machine: shots, the ship, obstacles.
    None = 0,
    /// Wanders, attacks the ship on sight (paper 7.1).
    Kamikaze = 1,
    /// Also groups with its own kind and avoids bullets (paper 7.2).
    Group = 2,
    /// Also escapes to recover energy when low (paper 7.3).
    Tricky = 3,
}

impl Machine {
    /// The machine stored as `value`; unknown values read as [`Machine::None`].
    #[inline(always)]
    pub fn from_u32(value: u32) -> Machine {
        match value {
            1 => Machine::Kamikaze,
            2 => Machine::Group,
            3 => Machine::Tricky,
            _ => Machine::None,
        }
    }

    /// The machine's transition table (empty for [`Machine::None`]).
    #[inline(always)]
    pub fn rules(self) -> &'static [Rule] {
        match self {
            Machine::None => &[],
            Machine::Kamikaze => KAMIKAZE,
            Machine::Group => GROUP,
            Machine::Tricky => TRICKY,
        }
    }

    /// The states this machine can be in.
    pub fn states(self) -> &'static [State] {
        use State::*;
        match self {
            Machine::None => &[],
            Machine::Kamikaze => &[Wandering, Attacking, CheckingEnergy, Dead],
            Machine::Group => &[
                Wandering,
                Grouping,
                Attacking,
                CheckingEnergy,
                AvoidingBullets,
                Dead,
            ],
            Machine::Tricky => &[
                Wandering,
                Grouping,
                Attacking,
                AvoidingBullets,
                CheckingEnergy,
                Escaping,
                Dead,
            ],
        }
    }
}

/// What a body knows about itself and its surroundings this step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Percept {
    /// It lost energy to a contact this step.
    pub hit: bool,
    /// Its energy is 0 or less.
    pub out_of_energy: bool,
    /// Its energy is at or below its kind's low mark.
    pub low_energy: bool,
    /// Its energy is back to its kind's birth energy.
    pub full_energy: bool,
    /// The ship is within its vision radius.
    pub sees_ship: bool,
    /// Another body of its kind is within its vision radius.
    pub sees_similar: bool,
    /// A shot within its vision radius is coming its way (and it avoids bullets).
    pub sees_bullet: bool,
}

/// The condition of a [`Rule`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum When {
    /// Always holds.
    Always,
    /// [`Percept::hit`].
    Hit,
    /// [`Percept::out_of_energy`].
    OutOfEnergy,
    /// [`Percept::low_energy`].
    LowEnergy,
    /// Not [`Percept::full_energy`].
    NotFullEnergy,
    /// [`Percept::sees_ship`].
    SeesShip,
    /// [`Percept::sees_similar`].
    SeesSimilar,
    /// [`Percept::sees_bullet`].
    SeesBullet,
}

impl When {
    /// Whether the condition holds for `p`.
    #[inline(always)]
    pub fn holds(self, p: &Percept) -> bool {
        match self {
            When::Always => true,
            When::Hit => p.hit,
            When::OutOfEnergy => p.out_of_energy,
            When::LowEnergy => p.low_energy,
            When::NotFullEnergy => !p.full_energy,
            When::SeesShip => p.sees_ship,
            When::SeesSimilar => p.sees_similar,
            When::SeesBullet => p.sees_bullet,
        }
    }
}

/// One row of a transition table: from any state in `from`, if `when` holds, go to `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rule {
    /// Set of states ([`State::bit`]s) the rule applies in.
    pub from: u32,
    /// Its condition.
    pub when: When,
    /// The next state.
    pub to: State,
}

const fn rule(from: &[State], when: When, to: State) -> Rule {
    let mut bits = 0;
    let mut i = 0;
    while i < from.len() {
        bits |= from[i].bit();
        i += 1;
    }
    Rule {
        from: bits,
        when,
        to,
    }
}

use State::{
    Attacking as A, AvoidingBullets as B, CheckingEnergy as C, Dead as D, Escaping as E,
    Grouping as G, Wandering as W,
};

/// Kamikaze (paper 7.1): wanders until it sees the ship, then throws itself against it.
pub const KAMIKAZE: &[Rule] = &[
    rule(&[W, A], When::Hit, C),
    rule(&[C], When::OutOfEnergy, D),
    rule(&[W, A, C], When::SeesShip, A),
    rule(&[W, A, C], When::Always, W),
];

/// Group (paper 7.2): avoids bullets first, attacks the ship on sight, else joins its kind.
pub const GROUP: &[Rule] = &[
    rule(&[W, G, A, B], When::Hit, C),
    rule(&[C], When::OutOfEnergy, D),
    rule(&[W, G, A, B, C], When::SeesBullet, B),
    rule(&[W, G, A, B, C], When::SeesShip, A),
    rule(&[W, G, A, B, C], When::SeesSimilar, G),
    rule(&[W, G, A, B, C], When::Always, W),
];

/// Tricky (paper 7.3): the group behaviour, plus escaping to recover energy when low.
pub const TRICKY: &[Rule] = &[
    rule(&[W, G, A, B, E], When::Hit, C),
    rule(&[C], When::OutOfEnergy, D),
    rule(&[C], When::LowEnergy, E),
    rule(&[E], When::NotFullEnergy, E),
    rule(&[W, G, A, B, C, E], When::SeesBullet, B),
    rule(&[W, G, A, B, C, E], When::SeesShip, A),
    rule(&[W, G, A, B, C, E], When::SeesSimilar, G),
    rule(&[W, G, A, B, C, E], When::Always, W),
];

/// The state after `state` for a body driven by `machine` that perceives `p`.
#[inline(always)]
pub fn next_state(machine: Machine, state: State, p: &Percept) -> State {
    // The table folded from its last rule to its first, so that the first rule that applies
    // wins: each rule's next state is then a value chosen in registers. Returned from the
    // first match, it was loaded from the table in memory through the matching rule's
    // address, one more wait a body between its state's load and its action on the GPU.
    machine.rules().iter().rev().fold(state, |next, rule| {
        match rule.from & state.bit() != 0 && rule.when.holds(p) {
            true => rule.to,
            false => next,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::{Machine, Percept, State, next_state};

    /// The percept whose seven flags are the low bits of `bits`.
    fn percept(bits: u32) -> Percept {
        let on = |i: u32| bits >> i & 1 != 0;
        Percept {
            hit: on(0),
            out_of_energy: on(1),
            low_energy: on(2),
            full_energy: on(3),
            sees_ship: on(4),
            sees_similar: on(5),
            sees_bullet: on(6),
        }
    }

    /// Every machine, state and percept steps as the tables read top to bottom say: the
    /// first rule whose set holds the state and whose condition holds, else the state stays.
    #[test]
    fn the_first_rule_that_applies_gives_the_next_state() {
        for machine in [
            Machine::None,
            Machine::Kamikaze,
            Machine::Group,
            Machine::Tricky,
        ] {
            for state in State::ALL {
                for bits in 0..1 << 7 {
                    let p = percept(bits);
                    let mut first = None;
                    for rule in machine.rules() {
                        if first.is_none() && rule.from & state.bit() != 0 && rule.when.holds(&p) {
                            first = Some(rule.to);
                        }
                    }
                    assert_eq!(
                        next_state(machine, state, &p),
                        first.unwrap_or(state),
                        "{machine:?} in {state:?} perceiving {p:?}"
                    );
                }
            }
        }
    }
}
