//! Solids that move through the fluid, as components: [`Solid`] (a shape in the entity's own
//! frame, posed by its `Transform`), what the fluid does to it ([`FluidForce`], [`Submerged`]),
//! and the messages when it enters or leaves the water. The physics is the core's
//! ([`MovingSolid`]): boundary particles that move rigidly through the sub-steps, and the force
//! on them summed pair by pair from what they do to the fluid.

use super::resources::SphSolver;
use crate::sim::solid::{MovingSolid, Pose, SolidMotion, SolidResponse, SolidShape};
use bevy::prelude::*;

/// A rigid solid in the fluid. Its shape is in the entity's own frame; each tick it takes its
/// pose from the entity's `Transform` (translation x, y and the rotation about z; no scale, and
/// no parent) and its velocities from [`SolidVelocity`], or, without one, from how far the pose
/// moved over the last tick. The fluid pushes on it ([`FluidForce`]) and wets it
/// ([`Submerged`]); it never moves it: a game (or the `avian` coupling) does.
///
/// The shape is sampled once into boundary particles, and again only when the component
/// changes or the particle spacing does. A shape that is invalid or would need more than
/// the tank's own limit of boundary particles (4 million) is refused with a warning naming
/// its size.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component, Debug, PartialEq)]
#[require(Transform, FluidForce, Submerged)]
pub struct Solid {
    /// The shape, m, in the entity's frame.
    pub shape: SolidShape,
    /// The centre of mass in the entity's frame, m: the point [`SolidVelocity::linear`] is the
    /// velocity of and [`FluidForce::torque`] is taken about.
    pub center_of_mass: Vec2,
}

impl Solid {
    /// A solid of `shape` with its centre of mass at the shape's centre of area.
    pub fn new(shape: SolidShape) -> Self {
        let center_of_mass = shape.centroid();
        Self {
            shape,
            center_of_mass,
        }
    }
}

/// The liquid's contact angle on a [`Solid`], degrees through the liquid, 0–180: under 90 it
/// wets the solid (clings, spreads into a film), over 90 it beads. Without it the solid takes
/// the tank's, [`SphParams::contact_angle`](crate::fluid::SphParams::contact_angle). It acts
/// only with surface tension ([`SphParams::surface_tension`](crate::fluid::SphParams::surface_tension));
/// an angle out of range is refused with a warning, and the solid keeps the tank's.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component, Debug, PartialEq)]
pub struct ContactAngle(pub f32);

/// A [`Solid`]'s velocities: of its centre of mass (m/s) and about it (rad/s,
/// counter-clockwise). Without this component the fluid takes them from the change of pose.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Debug, Default, PartialEq)]
pub struct SolidVelocity {
    /// Velocity of the centre of mass, m/s.
    pub linear: Vec2,
    /// Angular velocity, rad/s.
    pub angular: f32,
}

/// Makes a [`Solid`] a body that the fluid's force moves within a tick, as the rigid-body step
/// that moves it afterwards will ([`SolidResponse`]: its mass, gravity and the acceleration of
/// its contacts); set it again each tick. Without it the solid keeps its [`SolidVelocity`]
/// through the tick. The `avian` coupling sets it on dynamic bodies.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Debug, Default, PartialEq)]
pub struct SolidDynamics(pub SolidResponse);

/// The fluid's force on a [`Solid`] over the last tick (pressure and viscosity, summed from
/// the pairs of its boundary particles with the fluid, averaged over the sub-steps), and its
/// torque about the centre of mass. SI units per metre of depth (N/m, N).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Debug, Default, PartialEq)]
pub struct FluidForce {
    /// Force, N/m.
    pub force: Vec2,
    /// Torque about the centre of mass, N, counter-clockwise.
    pub torque: f32,
    /// The added mass to step the solid with, kg/m, and its added moment of inertia, kg·m
    /// ([`MovingSolid::added_mass`]; a rigid-body step that moves the solid uses them with
    /// [`coupled_acceleration`](crate::fluid::coupled_acceleration)).
    pub added_mass: f32,
    /// Added moment of inertia, kg·m.
    pub added_inertia: f32,
}

/// How much of a [`Solid`] is under water: the area inside the wetted part of its outline
/// (each convex part's outline points that the fluid covers, closed by the waterline).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Debug, Default, PartialEq)]
pub struct Submerged {
    /// Area under water, m² (a volume per metre of depth).
    pub area: f32,
    /// Fraction of the solid's area under water, 0 to 1.
    pub fraction: f32,
    /// Whether it is in the water, with hysteresis: in from [`SOLID_ENTER_FRACTION`], out
    /// below [`SOLID_LEAVE_FRACTION`].
    pub in_water: bool,
}

/// A solid is in the water once this fraction of it is under ([`SolidEntered`]).
pub const SOLID_ENTER_FRACTION: f32 = 0.05;

/// A solid in the water leaves it when less than this fraction is under ([`SolidLeft`]).
pub const SOLID_LEAVE_FRACTION: f32 = 0.01;

/// A [`Solid`] entered the water (see [`Submerged::in_water`]).
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct SolidEntered {
    /// The solid's entity.
    pub solid: Entity,
    /// Its submerged fraction then.
    pub fraction: f32,
}

/// A [`Solid`] left the water.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct SolidLeft {
    /// The solid's entity.
    pub solid: Entity,
    /// Its submerged fraction then.
    pub fraction: f32,
}

/// The solids the fluid holds, by entity, as last synchronised.
#[derive(Debug, Clone, Default)]
pub(crate) struct SolidIndex {
    entities: Vec<Entity>,
    /// Spacing and layers they were sampled at.
    sampled: (f32, u32),
    /// Poses of the last tick, for solids without a [`SolidVelocity`].
    previous: Vec<Pose>,
}

impl SolidIndex {
    /// The fluid's index of the solid of `entity`.
    pub(crate) fn position(&self, entity: Entity) -> Option<usize> {
        self.entities.iter().position(|&e| e == entity)
    }
}

/// The pose of a solid's `Transform`.
pub(crate) fn pose_of(transform: &Transform) -> Pose {
    Pose {
        position: transform.translation.truncate(),
        angle: transform.rotation.to_euler(EulerRot::ZYX).0,
    }
}

type SolidItem<'a> = (
    Entity,
    Ref<'a, Solid>,
    &'a Transform,
    Option<&'a SolidVelocity>,
    Option<&'a SolidDynamics>,
    Option<&'a ContactAngle>,
);

/// Hands the solids to the fluid: re-samples them when one was added, removed or changed (or
/// the spacing changed), and gives each its pose and velocities.
pub(crate) fn sync_solids(
    mut solver: ResMut<SphSolver>,
    solids: Query<SolidItem>,
    mut removed: RemovedComponents<Solid>,
    time: Res<Time>,
) {
    let solver = &mut *solver;
    let (spacing, layers) = {
        let c = solver.step.constants();
        (c.spacing, c.wall_layers)
    };
    let index = &mut solver.solids;
    let removed_any = removed.read().count() > 0;
    let same = index.sampled == (spacing, layers)
        && index
            .entities
            .iter()
            .copied()
            .eq(solids.iter().map(|s| s.0))
        && !solids.iter().any(|s| s.1.is_changed());
    if !same || removed_any {
        resample(&mut solver.step, index, &solids, (spacing, layers));
    }
    let dt = time.delta_secs();
    let index = &mut solver.solids;
    for (entity, solid, transform, velocity, dynamics, angle) in &solids {
        let Some(k) = index.position(entity) else {
            continue;
        };
        let (pose, previous) = (pose_of(transform), index.previous[k]);
        let (linear, angular) = match velocity {
            Some(v) => (v.linear, v.angular),
            None if dt > 0.0 => {
                let com = |p: Pose| p.apply(solid.center_of_mass);
                let turn = (pose.angle - previous.angle + core::f32::consts::PI)
                    .rem_euclid(core::f32::consts::TAU)
                    - core::f32::consts::PI;
                ((com(pose) - com(previous)) / dt, turn / dt)
            }
            None => (Vec2::ZERO, 0.0),
        };
        index.previous[k] = pose;
        let motion = SolidMotion {
            pose,
            velocity: linear,
            angular_velocity: angular,
        };
        if !solver.step.set_solid_motion(k, motion) {
            warn!("solid {entity}: its pose or velocity is not finite; it stays where it was");
        }
        if !solver.step.set_solid_response(k, dynamics.map(|d| d.0)) {
            warn!("solid {entity}: its dynamics are not finite; it keeps its velocity");
        }
        let angle = angle.map(|a| a.0);
        let valid = angle.filter(|a| (0.0..=180.0).contains(a));
        if valid != angle {
            warn_once!(
                "solid {entity}: contact angle {angle:?}° is outside 0–180; it takes the tank's"
            );
        }
        solver.step.set_solid_contact_angle(k, valid);
    }
}

/// Samples every solid afresh, warning about those it refuses.
fn resample(
    step: &mut crate::sim::step::FluidStep,
    index: &mut SolidIndex,
    solids: &Query<SolidItem>,
    (spacing, layers): (f32, u32),
) {
    index.entities.clear();
    index.previous.clear();
    let moving = step.solids_mut();
    moving.clear();
    for (entity, solid, transform, ..) in solids.iter() {
        match MovingSolid::new(solid.shape.clone(), solid.center_of_mass, spacing, layers) {
            Some(sampled) => {
                moving.push(sampled);
                index.entities.push(entity);
                index.previous.push(pose_of(transform));
            }
            None => warn!(
                "ignoring solid {entity}: its shape is invalid or too big to sample at {spacing} \
                 m spacing (at most {} boundary particles); {:?}",
                crate::sim::boundary::MAX_BOUNDARY_PARTICLES,
                solid.shape
            ),
        }
    }
    index.sampled = (spacing, layers);
}

/// Writes each solid's [`FluidForce`] and [`Submerged`] from the last tick, and sends
/// [`SolidEntered`] and [`SolidLeft`].
pub(crate) fn write_solid_loads(
    solver: Res<SphSolver>,
    mut solids: Query<(&mut FluidForce, &mut Submerged)>,
    mut entered: MessageWriter<SolidEntered>,
    mut left: MessageWriter<SolidLeft>,
) {
    let moving = solver.step.solids();
    let rest_density = solver.step.constants().rest_density;
    for (&entity, solid) in solver.solids.entities.iter().zip(moving) {
        let Ok((mut force, mut submerged)) = solids.get_mut(entity) else {
            continue;
        };
        let load = solid.load();
        let (added_mass, added_inertia) = solid.added_mass(rest_density);
        *force = FluidForce {
            force: load.force,
            torque: load.torque,
            added_mass,
            added_inertia,
        };
        let fraction = load.submerged_fraction;
        let in_water = if submerged.in_water {
            fraction >= SOLID_LEAVE_FRACTION
        } else {
            fraction >= SOLID_ENTER_FRACTION
        };
        if in_water && !submerged.in_water {
            entered.write(SolidEntered {
                solid: entity,
                fraction,
            });
        } else if !in_water && submerged.in_water {
            left.write(SolidLeft {
                solid: entity,
                fraction,
            });
        }
        *submerged = Submerged {
            area: load.submerged_area,
            fraction,
            in_water,
        };
    }
}
