//! The main example: a dam break of about 2,500 water particles in a 1.6 m × 0.9 m tank, with the
//! tweak panel on the left.
//!
//! Left mouse button: the tool picked in the panel (pull by default); right button: push; wheel:
//! tool radius. Space pauses, `.` steps, `R` resets, `L` switches between the liquid and the
//! particles, ←/→ tilt the tank, `Tab` hides the panel.
//!
//! `cargo run --example dam_break [-- PARTICLES]` (the dev profile is optimised)

mod demo;

use bevy::prelude::*;
use demo::SphDemoPlugin;

fn main() {
    let particles = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2500);
    App::new()
        .add_plugins((
            demo::window_plugins("bevy_sph2d: dam break"),
            SphDemoPlugin::dam_break(particles),
        ))
        .run();
}
