//! The ECS path and the plain-slice solver compute the same numbers, bit for bit.

use crate::common::*;
use bevy::prelude::*;
use bevy_sph2d::fluid::{
    Acceleration, KernelKind, Pose, PressureSolver, Solid, SolidShape, SphParams, SphSubstep,
    SphSubstepSystems, Tank,
};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::slices::{MovingSolid, SliceFluid, SolidMotion};

fn check(kernel: KernelKind, base: SphParams) {
    check_driver(kernel, base, false);
}

/// With `hook`, a game's system sits in `SphSubstep` (it reads the accelerations and changes
/// nothing), so the ECS runs every sub-step through the schedule, copying the components in
/// and out at the stages, instead of once a tick.
fn check_driver(kernel: KernelKind, base: SphParams, hook: bool) {
    let params = SphParams {
        particle_spacing: 0.01,
        kernel,
        tank: Some(Tank::new(0.6, 0.4)),
        speed_of_sound: SphParams::speed_of_sound_for_height(0.2),
        ..base
    };
    let block = FluidBlock::dam_break(0.15, 0.2)
        .with_seed(3)
        .with_jitter(0.1);
    // A still solid (what an obstacle was).
    let (disc, at) = (SolidShape::circle(0.04), Vec2::new(0.35, 0.05));

    let mut app = create_app(params.clone());
    if hook {
        app.add_systems(
            SphSubstep,
            (|_: Query<&Acceleration>| {}).in_set(SphSubstepSystems::ExternalForces),
        );
    }
    app.world_mut().spawn((
        Solid::new(disc.clone()),
        Transform::from_translation(at.extend(0.0)),
    ));
    let ids = spawn(&mut app, block);
    run(&mut app, 20);
    let ecs = states(&mut app);

    let c = params.constants().unwrap();
    let mut fluid = SliceFluid::new(c, block.positions_for(&params));
    let mut still = MovingSolid::new(disc, Vec2::ZERO, c.spacing, c.wall_layers).unwrap();
    still.set_motion(SolidMotion {
        pose: Pose {
            position: at,
            angle: 0.0,
        },
        ..Default::default()
    });
    fluid.solids_mut().push(still);
    for _ in 0..20 {
        fluid.advance(TICK);
    }
    assert_eq!(ecs.len(), ids.len());
    assert!(
        (sim_time(&app) - fluid.clock().time).abs() < 1e-12,
        "ecs time {} slices time {}, substeps {}",
        sim_time(&app),
        fluid.clock().time,
        fluid.clock().total_substeps
    );
    assert!(
        fluid.clock().total_substeps > 20,
        "sub-stepping expected, got {}",
        fluid.clock().total_substeps
    );
    let mut moved = 0.0f32;
    for (i, s) in ecs.iter().enumerate() {
        assert_eq!(s.position, fluid.position[i], "particle {i} position");
        assert_eq!(s.velocity, fluid.velocity[i], "particle {i} velocity");
        assert_eq!(s.density, fluid.density[i], "particle {i} density");
        assert_eq!(s.pressure, fluid.pressure[i], "particle {i} pressure");
        assert_eq!(
            s.acceleration, fluid.acceleration[i],
            "particle {i} acceleration"
        );
        moved = moved.max(s.velocity.length());
    }
    assert!(
        moved > 0.1,
        "the column should be collapsing, max speed {moved}"
    );
}

#[test]
fn ecs_matches_slices_wendland() {
    check(KernelKind::WendlandC2, SphParams::water_wcsph());
}

#[test]
fn ecs_matches_slices_muller() {
    check(KernelKind::Muller, SphParams::water_wcsph());
}

#[test]
fn ecs_matches_slices_dfsph_wendland() {
    check(KernelKind::WendlandC2, dfsph());
}

#[test]
fn ecs_matches_slices_dfsph_cubic() {
    check(KernelKind::CubicSpline, dfsph());
}

#[test]
fn ecs_with_a_hook_matches_slices_wcsph() {
    check_driver(KernelKind::WendlandC2, SphParams::water_wcsph(), true);
}

#[test]
fn ecs_with_a_hook_matches_slices_dfsph() {
    check_driver(KernelKind::WendlandC2, dfsph(), true);
}

fn dfsph() -> SphParams {
    let params = SphParams::water();
    assert_eq!(params.solver, PressureSolver::Dfsph);
    params
}
