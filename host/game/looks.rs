//! How a scene's kinds look in a frame: the ship (a chevron) and its shots (streaks) on
//! top, each enemy type in a colour of its machine's family (kamikazes red, groups green,
//! tricky ones violet) and a silhouette of its own, other bodies (obstacles) grey
//! underneath. The radar shows the enemies and the obstacles.

use gpuwars_kernels::render::Look;
use gpuwars_kernels::render::shapes::{
    BOWTIE, CHEVRON, CROSS, DIAMOND, DISC, HEXAGON, RING, SQUARE, STREAK, TRIANGLE,
};

use super::spec::{Machine, Scene};

/// An RGBA8 colour packed little-endian (red in the low byte), opaque.
pub const fn rgb(r: u8, g: u8, b: u8) -> u32 {
    u32::from_le_bytes([r, g, b, 255])
}

/// The colour behind everything.
pub const BACKGROUND: u32 = rgb(10, 12, 26);

/// Colours of each machine's enemy types, taken in order of the scene's kinds.
const KAMIKAZE: [u32; 3] = [rgb(235, 70, 60), rgb(255, 150, 50), rgb(200, 40, 110)];
const GROUP: [u32; 3] = [rgb(80, 220, 110), rgb(40, 180, 170), rgb(175, 230, 60)];
const TRICKY: [u32; 3] = [rgb(150, 110, 255), rgb(230, 90, 230), rgb(90, 140, 255)];
const SHIP: u32 = rgb(235, 245, 255);
const SHOT: u32 = rgb(255, 235, 90);
const OTHER: u32 = rgb(140, 145, 160);

/// Silhouettes of each machine's enemy types, in the order of their colours: the seven
/// types of the paper's three families are seven different shapes.
const KAMIKAZE_SHAPES: [u32; 3] = [TRIANGLE, DIAMOND, DISC];
const GROUP_SHAPES: [u32; 3] = [SQUARE, RING, HEXAGON];
const TRICKY_SHAPES: [u32; 3] = [CROSS, BOWTIE, DISC];

/// The ship while it has lost energy (its FPS meter is down).
const SHIP_HURT: u32 = rgb(255, 110, 100);

/// `colour` halfway to white: the side a body faces.
fn lighter(colour: u32) -> u32 {
    let [r, g, b, a] = colour.to_le_bytes();
    let up = |c: u8| c + (255 - c) / 2;
    u32::from_le_bytes([up(r), up(g), up(b), a])
}

/// `colour` darkened by half: a body that has lost energy.
fn darker(colour: u32) -> u32 {
    let [r, g, b, a] = colour.to_le_bytes();
    u32::from_le_bytes([r / 2, g / 2, b / 2, a])
}

/// One look per kind of `scene`.
pub fn looks(scene: &Scene) -> Vec<Look> {
    let world = &scene.world;
    let ship = world.kind_index(&scene.game.ship.kind);
    let shot = world.kind_index(&scene.game.ship.shot);
    let mut taken = [0usize; 3];
    (0..world.kinds.len())
        .map(|k| {
            let machine = scene.game.behaviours[k].map(|b| b.machine);
            // (colour, layer, silhouette, on the radar)
            let (colour, layer, silhouette, radar) = if Some(k) == ship {
                (SHIP, 250, CHEVRON, false)
            } else if Some(k) == shot {
                (SHOT, 240, STREAK, false)
            } else if let Some(family) = match machine {
                Some(Machine::Kamikaze) => Some((0, &KAMIKAZE, &KAMIKAZE_SHAPES)),
                Some(Machine::Group) => Some((1, &GROUP, &GROUP_SHAPES)),
                Some(Machine::Tricky) => Some((2, &TRICKY, &TRICKY_SHAPES)),
                _ => None,
            } {
                let (i, colours, shapes) = family;
                let n = taken[i] % colours.len();
                taken[i] += 1;
                (colours[n], 100 + k as u32, shapes[n], true)
            } else {
                (OTHER, 10, DISC, true)
            };
            Look {
                colour,
                nose: lighter(colour),
                layer,
                hurt: if Some(k) == ship {
                    SHIP_HURT
                } else {
                    darker(colour)
                },
                silhouette,
                radar: u32::from(radar),
            }
        })
        .collect()
}
