//! The shortest way to put the fluid in a game: the plugins, a camera, a block of water.
//! Drag with the left mouse button to pull the water, the right button to push it.
//!
//! `cargo run --example minimal`

use bevy::prelude::*;
use bevy_sph2d::prelude::*;

fn main() {
    App::new()
        .add_plugins((
            DefaultPlugins,
            ParticlePlugins::default(),
            ParticleUiPlugins,
        ))
        .add_systems(Startup, setup)
        .run();
}

fn setup(mut commands: Commands) {
    // A camera that keeps the tank (2 m × 1.2 m by default) in view.
    commands.spawn(ParticleCamera::default());
    // A 0.6 m × 0.8 m column of water against the left wall.
    commands.queue(FluidBlock::dam_break(0.6, 0.8));
}
