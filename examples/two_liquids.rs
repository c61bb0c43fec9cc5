//! Two liquids: a cup of water with a layer of oil on it (920 kg/m³) and brine under it
//! (1,200 kg/m³), each drawn in its own colour. Stir them with the mouse and watch them settle
//! back into layers: the oil floats up, the brine sinks.
//!
//! Left mouse button: drag (stir); right: push; wheel: the tool's radius; `M` picks the liquid
//! the pour tool (`5`) pours. The panel edits each liquid's rest density and adds more; Reset
//! fills the cup again.
//!
//! `cargo run --example two_liquids` (a window), `-- --headless 5` to run 5 simulated seconds
//! without one and print the speed relative to real time, or `-- --screenshot cup.png 4` to
//! save the window after 4 simulated seconds and quit.

mod demo;

use bevy::prelude::*;
use bevy_sph2d::fluid::{FluidMaterial, FluidParticle, Liquid, Position, SphParams, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::interact::{PointerSettings, PointerTool};
use demo::{ScreenshotAt, headless_seconds, liquid_window, run_scene_headless};

/// The cup (the tank), m.
const CUP: Tank = Tank::new(0.3, 0.25);

/// The layers from the floor up: their depth (m) and liquid.
const LAYERS: [(f32, FluidMaterial); 3] = [
    (0.04, FluidMaterial(2)),
    (0.07, FluidMaterial(0)),
    (0.04, FluidMaterial(1)),
];

/// Water at 5 mm spacing with oil and brine, on the default solver at three spacings' support:
/// at two, the particles' arrangement holds the few pascals that lift a stirred-in drop of oil
/// back out of the water (`docs/physics.md`, "Two liquids").
fn cup_params() -> SphParams {
    SphParams {
        tank: Some(CUP),
        particle_spacing: 0.005,
        support_ratio: 3.0,
        liquids: vec![Liquid::oil(), Liquid::brine()],
        max_substeps: 40,
        ..SphParams::water()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match headless_seconds(&args) {
        Some(seconds) => run_scene_headless("two_liquids", cup_params(), CupScene, seconds),
        None => window(ScreenshotAt::from_args(&args, "two_liquids.png", 4.0)),
    }
}

/// The example in a window: the liquid view, the mouse tools (drag to stir) and the panel.
fn window(shot: Option<ScreenshotAt>) {
    liquid_window("bevy_sph2d: two liquids", cup_params(), CupScene, shot)
        .insert_resource(PointerSettings {
            tool: PointerTool::Drag,
            radius: 0.05,
            ..default()
        })
        .run();
}

/// The cup's layers, filled again whenever it is empty (at the start and after Reset, which
/// clears the water).
struct CupScene;

impl Plugin for CupScene {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, fill_cup);
    }
}

/// Pours the layers into an empty cup.
fn fill_cup(fluid: Query<(), With<FluidParticle>>, params: Res<SphParams>, mut commands: Commands) {
    if !fluid.is_empty() {
        return;
    }
    let mut floor = 0.0;
    for (depth, material) in LAYERS {
        let block = FluidBlock::new(Vec2::new(0.0, floor), Vec2::new(CUP.width, depth));
        let positions = block.positions_for(&params);
        commands.spawn_batch(
            positions
                .into_iter()
                .map(move |p| (FluidParticle, Position(p), material))
                .collect::<Vec<_>>(),
        );
        floor += depth;
    }
}
