//! The main example: a dam break of about 2,500 water particles in a 1.6 m × 0.9 m tank, with the
//! tweak panel on the left.
//!
//! Left mouse button: the tool picked in the panel (pull by default); right button: push; wheel:
//! tool radius. Space pauses, `.` steps, `R` resets, `L` switches between the liquid and the
//! particles, ←/→ tilt the tank, `Tab` hides the panel.
//!
//! `cargo run --example dam_break [-- PARTICLES]` (the dev profile is optimised)

use bevy::prelude::*;
use bevy_sph2d::demo::SphDemoPlugin;

fn main() {
    let particles = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2500);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    App::new()
        .add_plugins((
            DefaultPlugins
                .set(WindowPlugin {
                    primary_window: Some(Window {
                        title: "bevy_sph2d: dam break".into(),
                        resolution: (1280, 720).into(),
                        ..default()
                    }),
                    ..default()
                })
                .set(bevy_sph2d::task_pool_plugin(threads)),
            SphDemoPlugin::dam_break(particles),
        ))
        .run();
}
