//! A harbour: water in a tank with a wave-maker paddle at the left, and floating crates, a boat,
//! a barrel and a stone of different densities, coupled two ways with avian2d rigid bodies (the
//! water pushes them, they push the water). The app is `demo::HarbourDemoPlugin` (`examples/demo/`).
//!
//! Keys: `Up`/`Down` lengthen or shorten the paddle's stroke, `Space` drops a new crate. The
//! mouse tools and the panel work as in `dam_break` (the drag tool grabs a body); the "Bodies"
//! window lists each body's submerged fraction and the fluid's force on it.
//!
//! `cargo run --example harbour` (a window), or `cargo run --example harbour -- --headless 20`
//! to run 20 simulated seconds without one and print the speed relative to real time.

mod demo;

use bevy::prelude::*;
use bevy_sph2d::prelude::*;
use demo::{
    HarbourDemoPlugin, HarbourScene, harbour_params, headless_plugins, run_headless, window_plugins,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.iter().position(|a| a == "--headless") {
        Some(i) => {
            let seconds = args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(20.0);
            headless(seconds);
        }
        None => {
            App::new()
                .add_plugins((window_plugins("bevy_sph2d: harbour"), HarbourDemoPlugin))
                .run();
        }
    }
}

/// Runs the scene for `seconds` of simulated time at 64 ticks a second, as fast as it goes.
fn headless(seconds: f64) {
    let mut app = App::new();
    app.add_plugins((
        headless_plugins(),
        SphPlugin::default().with_params(harbour_params()),
        avian2d::prelude::PhysicsPlugins::default(),
        FluidCouplingPlugin::with_tank_walls(),
        HarbourScene,
    ));
    run_headless("harbour", app, seconds);
}
