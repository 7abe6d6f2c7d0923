//! `Wave::due` is true exactly at the steps of its schedule, listed here by walking it:
//! `first`, then every `every` steps up to `last` (once if `every` is 0).

use gpuwars_kernels::game::rules::Wave;

#[test]
fn a_wave_is_due_exactly_on_its_schedule() {
    for first in 0u32..6 {
        for every in 0u32..5 {
            for last in 0u32..12 {
                let wave = Wave {
                    kind: 0,
                    count: 1,
                    first,
                    every,
                    last,
                    speed: 0.0,
                };
                let mut schedule = Vec::new();
                let mut step = first;
                while step <= last {
                    schedule.push(step);
                    if every == 0 {
                        break;
                    }
                    step += every;
                }
                for step in 0u32..16 {
                    let due = schedule.contains(&step);
                    assert_eq!(wave.due(step), due, "{wave:?} at step {step}");
                }
                // Long after its last spawn, without overflow.
                assert!(!wave.due(u32::MAX), "{wave:?} at the last step");
            }
        }
    }
}
