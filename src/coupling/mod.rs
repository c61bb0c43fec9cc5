//! Feature `avian`: avian2d rigid bodies in the fluid. [`FluidCouplingPlugin`] makes every body
//! marked [`FluidCoupled`] a [`Solid`] of the fluid (its shape from the avian collider, its
//! velocities from avian each tick) and applies the fluid's force and torque back to dynamic
//! bodies through avian's `Forces`. Static and kinematic bodies act as still or moving walls.
//! With feature `render` the mouse tools act on dynamic coupled bodies as on the fluid (the
//! drag tool grabs a crate).
//!
//! Order in a fixed tick: the fluid steps in the crate's schedule (`FixedUpdate` by default)
//! from each body's pose and velocity as avian left them, and writes [`FluidForce`]; avian
//! steps in `FixedPostUpdate` with that force applied (forces last one avian step). A dynamic
//! body is stepped with an added mass (see
//! [`ADDED_MASS_RATIO`](crate::slices::ADDED_MASS_RATIO)): avian is given the acceleration
//! `a − g` with `(m + mₐ) a = F + m g`, which rests where the fluid's force alone would hold it.
//! Within the fluid's tick a dynamic body answers the force of each sub-step the same way, with
//! what its contacts did over the last step ([`SolidDynamics`]), so the fluid moves it as avian
//! will. Measured on a 10 × 6 cm stone of 2,500 kg/m³ landing at 0.54 m/s at 5 mm spacing:
//! carried at its velocity through the tick ([`FluidCouplingPlugin::carried`], the exchange of
//! earlier versions), it squeezed the film under it until the film threw it back (6,400 N/m at
//! 60 ticks a second, 79,000 at 100), and came to rest on its narrow side or on its back;
//! answering, it takes at most 690-890 N/m (under six times its weight), lands flat and rests,
//! and no limit on the force is needed. Where a body touches the floor (or another body) under
//! water, the water that seeps into the contact presses on it (`MovingSolid` in the core): a
//! crate lighter than water that reached the floor of a pool stayed there without it.
//! Gravity is set in one place, `SphParams::gravity`: the plugin keeps avian's `Gravity` equal
//! to it. Tank walls for avian are opt-in ([`FluidCouplingPlugin::with_tank_walls`]).

#[cfg(feature = "render")]
mod pointer;

use crate::fluid::{
    FluidForce, Part, PressureSolver, Solid, SolidDynamics, SolidResponse, SolidShape,
    SolidVelocity, SphParams, SphPlugin, SphSolver, SphSystems, Tank, coupled_acceleration,
};
use crate::schedule::{ParticleSchedule, ParticleSystems};
use avian2d::parry::shape::TypedShape;
use avian2d::prelude as avian;
use avian2d::prelude::WriteRigidBodyForces;
use bevy::prelude::*;

/// Couples avian2d bodies marked [`FluidCoupled`] with the fluid (see the module docs). Add it
/// beside `ParticlePlugins` (or `SphPlugin`) and avian's `PhysicsPlugins`, in any order.
///
/// Gravity is set in one place, [`SphParams::gravity`]: the plugin keeps avian's `Gravity`
/// equal to it.
#[derive(Debug, Clone, Copy, Default)]
pub struct FluidCouplingPlugin {
    /// Put static avian bodies ([`TankWall`]) round the fluid's tank, so that bodies rest on
    /// its floor and stay inside (off by default: a game with its own level geometry has its
    /// own colliders).
    pub tank_walls: bool,
    /// Carry dynamic bodies at their velocity through the fluid's tick, their acceleration held
    /// to [`MAX_FLUID_ACCELERATION`], instead of letting them answer the fluid's force within
    /// it (see the module docs; off by default, and always so under WCSPH).
    pub carried: bool,
}

impl FluidCouplingPlugin {
    /// The coupling with avian walls round the fluid's tank.
    pub fn with_tank_walls() -> Self {
        Self {
            tank_walls: true,
            ..Self::default()
        }
    }
}

/// Marks an avian body (with a `Collider` on the same entity) as a solid of the fluid.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Debug, Default, PartialEq)]
pub struct FluidCoupled;

/// One of the four static avian bodies the coupling puts round the fluid's tank (so bodies
/// rest on its floor and stay inside), re-made when the tank changes; only with
/// [`FluidCouplingPlugin::tank_walls`].
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct TankWall;

/// How thick the tank's avian walls are, m.
const WALL_THICKNESS: f32 = 0.5;

/// The largest acceleration the fluid gives a body in a tick, m/s² (10 g): about what stops a
/// crate that hits the water at 3 m/s within a few centimetres. A body that moves so fast into
/// the tank's floor or wall that fluid is trapped between them takes a pressure spike of
/// millions of g from it for a tick (measured: 9.5·10⁹ N/m on a sinking stone at 1 m/s); held to
/// this, it bounces a centimetre instead of leaving the world. Only for bodies the fluid
/// carries through its tick ([`FluidCouplingPlugin::carried`], and always under WCSPH, which
/// the coupling warns against: without it the soak's WCSPH spikes, 1.9·10⁵ N/m on a crate,
/// threw bodies through the tank's walls at 80 m/s).
pub const MAX_FLUID_ACCELERATION: f32 = 98.1;

impl Plugin for FluidCouplingPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<FluidCoupled>();
    }

    /// The systems go in once every plugin is built, into the schedule the fluid steps in,
    /// whichever order the plugins came in.
    fn finish(&self, app: &mut App) {
        if app.world().contains_resource::<CouplingSystems>() {
            // `App::finish` called again by hand: the systems are in already.
            return;
        }
        app.insert_resource(CouplingSystems {
            carried: self.carried,
        });
        if !app.is_plugin_added::<SphPlugin>() {
            error!(
                "FluidCouplingPlugin: no fluid to couple with; add ParticlePlugins (or SphPlugin)"
            );
            return;
        }
        let schedule = ParticleSchedule::of(app);
        if self.tank_walls {
            app.add_systems(
                schedule,
                tank_walls
                    .in_set(ParticleSystems::Prepare)
                    .before(attach_solids),
            );
        }
        app.add_systems(
            schedule,
            (
                (attach_solids, copy_velocities)
                    .chain()
                    .in_set(ParticleSystems::Prepare)
                    .before(SphSystems::Prepare),
                (share_gravity, apply_fluid_forces)
                    .chain()
                    .in_set(ParticleSystems::Finish)
                    .after(SphSystems::Finish),
            ),
        );
        #[cfg(feature = "render")]
        app.add_systems(
            schedule,
            pointer::pointer_on_bodies
                .in_set(ParticleSystems::Finish)
                .after(apply_fluid_forces),
        );
    }
}

/// The shape of an avian collider as the fluid's parts, in the body's frame; `None` for
/// shapes the fluid does not know (half-spaces, polylines, triangle meshes, height fields).
pub fn shape_of(collider: &avian::Collider) -> Option<SolidShape> {
    let mut parts = Vec::new();
    add_parts(collider.shape_scaled(), Vec2::ZERO, 0.0, &mut parts)?;
    Some(SolidShape::compound(parts))
}

/// Adds the parts of `shape`, placed at `offset` turned by `angle` in the body's frame.
fn add_parts(
    shape: &avian2d::parry::shape::SharedShape,
    offset: Vec2,
    angle: f32,
    parts: &mut Vec<Part>,
) -> Option<()> {
    let place = |p: Vec2| offset + Rot2::radians(angle) * p;
    match shape.as_typed_shape() {
        TypedShape::Ball(ball) => parts.push(Part::Circle {
            center: place(Vec2::ZERO),
            radius: ball.radius,
        }),
        TypedShape::Cuboid(cuboid) => {
            let size = 2.0 * cuboid.half_extents;
            parts.push(Part::rectangle(place(Vec2::ZERO), size.x, size.y, angle));
        }
        TypedShape::Capsule(capsule) => parts.push(Part::Capsule {
            start: place(capsule.segment.a),
            end: place(capsule.segment.b),
            radius: capsule.radius,
        }),
        TypedShape::ConvexPolygon(polygon) => {
            parts.push(Part::polygon(
                polygon.points().iter().map(|&p| place(p)).collect(),
            ));
        }
        TypedShape::Compound(compound) => {
            for (pose, shape) in compound.shapes() {
                let at = place(pose.translation);
                add_parts(shape, at, angle + pose.rotation.angle(), parts)?;
            }
        }
        _ => return None,
    }
    Some(())
}

/// Puts four static avian bodies round the tank of [`SphParams`], again when it changes.
fn tank_walls(
    mut commands: Commands,
    params: Res<SphParams>,
    walls: Query<Entity, With<TankWall>>,
    mut built: Local<Option<Option<Tank>>>,
) {
    if *built == Some(params.tank) {
        return;
    }
    *built = Some(params.tank);
    for wall in &walls {
        commands.entity(wall).despawn();
    }
    let Some(tank) = params.tank else {
        return;
    };
    let (w, h, t) = (tank.width, tank.height, WALL_THICKNESS);
    let sides = [
        (Vec2::new(0.5 * w, -0.5 * t), Vec2::new(w + 2.0 * t, t)),
        (Vec2::new(0.5 * w, h + 0.5 * t), Vec2::new(w + 2.0 * t, t)),
        (Vec2::new(-0.5 * t, 0.5 * h), Vec2::new(t, h)),
        (Vec2::new(w + 0.5 * t, 0.5 * h), Vec2::new(t, h)),
    ];
    for (center, size) in sides {
        commands.spawn((
            TankWall,
            avian::RigidBody::Static,
            avian::Collider::rectangle(size.x, size.y),
            Transform::from_translation(center.extend(0.0)),
        ));
    }
}

/// Marks an app whose coupling systems were added, with its settings.
#[derive(Resource, Default)]
struct CouplingSystems {
    /// [`FluidCouplingPlugin::carried`].
    carried: bool,
}

/// Keeps avian's `Gravity` equal to the gravity the fluid stepped with this tick (from
/// [`SphParams::gravity`], the one place gravity is set; a refused value never reaches the
/// solver, so it never reaches avian), before avian's step.
fn share_gravity(
    mut commands: Commands,
    solver: Res<SphSolver>,
    gravity: Option<ResMut<avian::Gravity>>,
) {
    let fluid = solver.constants().gravity;
    match gravity {
        Some(mut gravity) => {
            if gravity.0 != fluid {
                gravity.0 = fluid;
            }
        }
        None => commands.insert_resource(avian::Gravity(fluid)),
    }
}

/// Coupled bodies new this tick or whose collider changed.
type NewOrReshaped = (
    With<FluidCoupled>,
    Or<(Added<FluidCoupled>, Changed<avian::Collider>)>,
);

/// A body's mass and angular inertia as avian computed them.
type Inertia = (
    &'static avian::ComputedMass,
    &'static avian::ComputedAngularInertia,
);

/// Gives each newly coupled body (or one whose collider changed) its [`Solid`], with the
/// centre of mass avian computed, and keeps it awake (a sleeping body would take the fluid's
/// force a step late).
fn attach_solids(
    mut commands: Commands,
    params: Res<SphParams>,
    bodies: Query<(Entity, &avian::Collider, &avian::ComputedCenterOfMass), NewOrReshaped>,
    mut warned: Local<bool>,
) {
    if params.solver == PressureSolver::Wcsph && !bodies.is_empty() && !*warned {
        *warned = true;
        warn!(
            "FluidCouplingPlugin: the WCSPH solver throws coupled bodies lighter than water out \
             of it (relative density 0.3 and 0.5 measured) and stirs still water round still \
             ones; couple bodies with the DFSPH solver (SphParams::solver, the default)"
        );
    }
    for (entity, collider, center) in &bodies {
        let Some(shape) = shape_of(collider) else {
            warn!("body {entity}: its collider's shape cannot be a solid of the fluid");
            continue;
        };
        commands.entity(entity).insert((
            Solid {
                shape,
                center_of_mass: center.0,
            },
            SolidVelocity::default(),
            Exchange::default(),
            avian::SleepingDisabled,
        ));
    }
}

/// What the coupling gave a body's last step, to tell what else moved it.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
struct Exchange {
    /// Its velocities when the fluid last stepped.
    velocity: (Vec2, f32),
    /// The accelerations the fluid and gravity gave its step then (`None` before the first).
    given: Option<(Vec2, f32)>,
}

/// Dynamic coupled bodies with what the fluid needs to move them within its tick.
type Dynamic<'a> = (
    &'a avian::LinearVelocity,
    &'a avian::AngularVelocity,
    &'a avian::RigidBody,
    Inertia,
    &'a FluidForce,
    &'a mut SolidVelocity,
    &'a mut Exchange,
    Option<&'a mut SolidDynamics>,
);

/// The bodies' velocities as avian left them, for the fluid's sub-steps, and for dynamic
/// bodies their [`SolidDynamics`]: the fluid moves them within its tick as avian will, with
/// what their contacts did over the last step (the change of velocity that neither the
/// fluid nor gravity gave, no more than it takes to hold the body against them: an impact is
/// not carried into the next tick).
fn copy_velocities(
    mut commands: Commands,
    solver: Res<SphSolver>,
    settings: Res<CouplingSystems>,
    time: Res<Time>,
    mut bodies: Query<(Entity, Dynamic), With<FluidCoupled>>,
) {
    let (g, dt) = (solver.constants().gravity, time.delta_secs());
    let answers = answers_within_tick(&settings, &solver);
    for (
        entity,
        (linear, angular, body, (mass, inertia), fluid, mut velocity, mut exchange, dynamics),
    ) in &mut bodies
    {
        velocity.linear = linear.0;
        velocity.angular = angular.0;
        let now = (linear.0, angular.0);
        let held = match exchange.given {
            Some((a, alpha)) if dt > 0.0 => {
                let rest = |change: Vec2, given: Vec2| {
                    (change / dt - given).clamp_length_max(given.length())
                };
                let turn = (now.1 - exchange.velocity.1) / dt - alpha;
                (
                    rest(now.0 - exchange.velocity.0, a),
                    turn.clamp(-alpha.abs(), alpha.abs()),
                )
            }
            _ => (Vec2::ZERO, 0.0),
        };
        exchange.velocity = now;
        if !body.is_dynamic() || !answers {
            if dynamics.is_some() {
                commands.entity(entity).remove::<SolidDynamics>();
            }
            continue;
        }
        let response = SolidDynamics(SolidResponse {
            mass: mass.value(),
            inertia: inertia.value(),
            added: (fluid.added_mass, fluid.added_inertia),
            gravity: g,
            held,
        });
        match dynamics {
            Some(mut dynamics) => *dynamics = response,
            None => {
                commands.entity(entity).insert(response);
            }
        }
    }
}

/// Whether dynamic bodies answer the fluid's force within its tick: unless the plugin carries
/// them, under the divergence-free solver.
fn answers_within_tick(settings: &CouplingSystems, solver: &SphSolver) -> bool {
    !settings.carried && solver.constants().solver == PressureSolver::Dfsph
}

/// Applies the fluid's force and torque to each dynamic coupled body, stepped with its added
/// mass (see the module docs) and, if the fluid carried it, held to [`MAX_FLUID_ACCELERATION`].
fn apply_fluid_forces(
    solver: Res<SphSolver>,
    settings: Res<CouplingSystems>,
    mut bodies: Query<
        (
            &FluidForce,
            &avian::RigidBody,
            Inertia,
            &mut Exchange,
            avian::Forces,
        ),
        With<FluidCoupled>,
    >,
) {
    // The gravity avian steps with (see `share_gravity`).
    let g = solver.constants().gravity;
    let limit = if answers_within_tick(&settings, &solver) {
        f32::INFINITY
    } else {
        MAX_FLUID_ACCELERATION
    };
    for (fluid, body, (mass, inertia), mut exchange, mut forces) in &mut bodies {
        exchange.given = None;
        if !body.is_dynamic() {
            continue;
        }
        let (mass, inertia) = (mass.value(), inertia.value());
        let force = fluid.force + mass * g;
        let a = coupled_acceleration(mass, fluid.added_mass, force);
        let alpha = coupled_acceleration(inertia, fluid.added_inertia, fluid.torque);
        if a.is_finite() && alpha.is_finite() && mass > 0.0 {
            // The same limit for the angular part at the radius of gyration.
            let gyration = (inertia / mass).sqrt().max(f32::MIN_POSITIVE);
            let pushed = (a - g).clamp_length_max(limit);
            let alpha = alpha.clamp(-limit / gyration, limit / gyration);
            forces.apply_linear_acceleration(pushed);
            forces.apply_angular_acceleration(alpha);
            exchange.given = Some((pushed + g, alpha));
        }
    }
}
