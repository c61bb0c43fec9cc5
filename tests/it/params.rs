//! Bad parameters are refused with a clear error, in the resource and at plugin start-up, and
//! the fluid keeps running on the last valid ones without a NaN.

use crate::common::*;
use bevy::prelude::*;
use bevy_sph2d::fluid::{SphParams, SphSolver, Tank};
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::prelude::*;

fn params() -> SphParams {
    SphParams {
        particle_spacing: 0.02,
        tank: Some(Tank::new(0.6, 0.4)),
        speed_of_sound: 20.0,
        ..default()
    }
}

#[test]
fn invalid_changes_are_refused_and_the_last_valid_ones_kept() {
    let mut app = create_app(params());
    spawn(&mut app, FluidBlock::dam_break(0.2, 0.3));
    run(&mut app, 3);
    let good = *app.world().resource::<SphSolver>().constants();

    type Breakage = fn(&mut SphParams);
    let breakages: [(&str, Breakage); 5] = [
        ("particle_spacing", |p| p.particle_spacing = -0.01),
        ("speed_of_sound", |p| p.speed_of_sound = f32::NAN),
        ("support_ratio", |p| p.support_ratio = 0.5),
        ("gravity", |p| p.gravity = Vec2::new(f32::INFINITY, 0.0)),
        ("tank.width", |p| p.tank = Some(Tank::new(0.0, 1.0))),
    ];
    for (field, break_it) in breakages {
        break_it(&mut app.world_mut().resource_mut::<SphParams>());
        run(&mut app, 3);
        let status = app.world().resource::<SphParamsStatus>();
        let error = status.error.as_ref().expect("the change should be refused");
        assert_eq!(error.field, field);
        assert!(error.to_string().contains(field), "{error}");
        assert_eq!(*app.world().resource::<SphSolver>().constants(), good);
        assert!(all_finite(&states(&mut app)), "NaN after refusing {field}");
        *app.world_mut().resource_mut::<SphParams>() = params();
        run(&mut app, 1);
        assert_eq!(app.world().resource::<SphParamsStatus>().error, None);
    }

    // A valid change is taken up.
    app.world_mut().resource_mut::<SphParams>().gravity = Vec2::new(3.0, -9.81);
    run(&mut app, 1);
    assert_eq!(
        app.world().resource::<SphSolver>().constants().gravity,
        Vec2::new(3.0, -9.81)
    );
}

#[test]
fn invalid_plugin_params_start_on_defaults_with_the_error_shown() {
    let mut app = create_app(SphParams {
        rest_density: -1000.0,
        ..params()
    });
    spawn(&mut app, FluidBlock::dam_break(0.2, 0.2));
    run(&mut app, 2);
    let error = app.world().resource::<SphParamsStatus>().error.clone();
    assert_eq!(error.map(|e| e.field), Some("rest_density"));
    assert!(all_finite(&states(&mut app)));
}

#[test]
fn particles_spawned_at_non_finite_positions_are_despawned() {
    let mut app = create_app(params());
    spawn(&mut app, FluidBlock::dam_break(0.1, 0.1));
    let before = states(&mut app).len();
    app.world_mut()
        .spawn((FluidParticle, particle::Position(Vec2::new(f32::NAN, 0.1))));
    app.world_mut().spawn((
        FluidParticle,
        particle::Position(Vec2::new(0.3, 0.1)),
        particle::Velocity(Vec2::new(0.0, f32::INFINITY)),
    ));
    run(&mut app, 2);
    let after = states(&mut app);
    assert_eq!(after.len(), before);
    assert!(all_finite(&after));
}

#[test]
fn particles_spawned_outside_the_tank_are_brought_inside() {
    let mut app = create_app(params());
    spawn(&mut app, FluidBlock::dam_break(0.1, 0.1));
    app.world_mut()
        .spawn((FluidParticle, particle::Position(Vec2::new(5.0, -3.0))));
    run(&mut app, 2);
    for s in states(&mut app) {
        assert!(s.position.x >= 0.0 && s.position.x <= 0.6, "{}", s.position);
        assert!(s.position.y >= 0.0 && s.position.y <= 0.4, "{}", s.position);
    }
}

#[test]
fn gravity_refuses_bad_parameters_through_the_same_pattern() {
    use bevy::time::TimeUpdateStrategy;
    use bevy_sph2d::ParamsStatus;
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, GravityPlugin::default()))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app.update();
    app.world_mut().resource_mut::<GravityParams>().theta = -1.0;
    app.update();
    app.update();
    let error = app
        .world()
        .resource::<ParamsStatus<GravityParams>>()
        .error
        .clone()
        .expect("refused");
    assert_eq!((error.owner, error.field), ("GravityParams", "theta"));
    assert!(
        error
            .to_string()
            .starts_with("invalid GravityParams.theta:"),
        "{error}"
    );
    app.world_mut().resource_mut::<GravityParams>().theta = 0.7;
    app.update();
    app.update();
    assert_eq!(
        app.world().resource::<ParamsStatus<GravityParams>>().error,
        None
    );
}
