//! The gravity plugin's ECS systems: thin glue that gathers bodies into the
//! [`QuadTree`], evaluates it from `par_iter_mut`, and integrates
//! gravity-only bodies with kick-drift-kick leapfrog. See
//! [`GravityPlugin`](crate::gravity::GravityPlugin).

use super::params::{GravityParams, GravityParamsError};
use super::{GravityAcceleration, GravityPotential, GravitySlot, Mass};
use crate::fluid::{Acceleration, FluidParticle};
use crate::particle::{Position, Velocity};
use crate::sim::gravity::quadtree::{Field, FieldQuery, QuadTree, direct_field_at};
use bevy::platform::time::Instant;
use bevy::prelude::*;

/// The tree and the parameters in use.
#[derive(Resource, Debug, Clone, Default)]
pub struct GravitySolver {
    params: GravityParams,
    tree: QuadTree,
    positions: Vec<Vec2>,
    masses: Vec<f32>,
    /// Field of each gathered body, in gather order (zero for bodies left out of the tree).
    fields: Vec<Field>,
}

impl GravitySolver {
    /// The last valid parameters, which the solver runs on.
    pub fn params(&self) -> &GravityParams {
        &self.params
    }

    /// The tree of the last step.
    pub fn tree(&self) -> &QuadTree {
        &self.tree
    }
}

/// What the last tick measured, for panels and logs.
#[derive(Resource, Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct GravityStats {
    /// Bodies with a [`Mass`].
    pub bodies: usize,
    /// Nodes in the tree.
    pub nodes: usize,
    /// Wall-clock time of the tree build and field evaluation, ms.
    pub field_ms: f32,
    /// Kinetic energy `Σ ½mv²`, J.
    pub kinetic_energy: f64,
    /// Potential energy `½ Σ mφ`, J (from the tree: as accurate as θ allows).
    pub potential_energy: f64,
    /// Total momentum `Σ mv`, kg·m/s.
    pub momentum: Vec2,
}

impl GravityStats {
    /// Kinetic plus potential energy, J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic_energy + self.potential_energy
    }
}

impl crate::params::Params for GravityParams {
    type Solver = GravitySolver;
    const WHAT: &'static str = "gravity";

    fn adopt(&self, solver: &mut GravitySolver) -> Result<(), GravityParamsError> {
        self.validate()?;
        solver.params = self.clone();
        Ok(())
    }
}

/// Run condition: a body appeared since the last tick (its acceleration must be known before
/// the first half kick).
pub(crate) fn bodies_added(added: Query<(), Added<Mass>>) -> bool {
    !added.is_empty()
}

/// What the field pass reads and writes per body.
type FieldData = (
    &'static Position,
    &'static Mass,
    &'static mut GravitySlot,
    &'static mut GravityAcceleration,
    &'static mut GravityPotential,
);

/// Builds the tree over every body, evaluates the field at every body (group walk, in parallel
/// on rayon), and stores each body's acceleration and potential (`par_iter_mut`).
pub(crate) fn compute_gravity_field(
    mut solver: ResMut<GravitySolver>,
    mut stats: ResMut<GravityStats>,
    mut bodies: Query<FieldData>,
) {
    let started = Instant::now();
    let solver = &mut *solver;
    solver.positions.clear();
    solver.masses.clear();
    for (index, (position, mass, mut slot, _, _)) in bodies.iter_mut().enumerate() {
        solver.positions.push(position.0);
        solver.masses.push(mass.0);
        slot.set_if_neq(GravitySlot(index as u32));
    }
    let params = &solver.params;
    let gravity = FieldQuery {
        constant: params.gravitational_constant,
        theta: params.theta,
        softening: params.softening,
    };
    if !params.direct_sum {
        // The tree build and the field on the crate's compute pool (as the fluid's passes).
        let (tree, fields) = (&mut solver.tree, &mut solver.fields);
        let (positions, masses) = (&solver.positions, &solver.masses);
        let leaf_capacity = params.leaf_capacity as usize;
        tree.set_multipole(params.multipole);
        crate::compute::region(|| {
            tree.build(positions, masses, leaf_capacity);
            tree.fields(&gravity, fields);
        });
    }
    let solver = &*solver;
    bodies
        .par_iter_mut()
        .for_each(|(position, _, slot, mut acceleration, mut potential)| {
            let field = if solver.params.direct_sum {
                if position.is_finite() {
                    direct_field_at(position.0, &solver.positions, &solver.masses, &gravity)
                } else {
                    Field::default()
                }
            } else {
                solver
                    .fields
                    .get(slot.0 as usize)
                    .copied()
                    .unwrap_or_default()
            };
            acceleration.0 = field.acceleration;
            potential.0 = field.potential;
        });
    remove_net_force(&mut bodies);
    stats.bodies = solver.positions.len();
    stats.nodes = if solver.params.direct_sum {
        0
    } else {
        solver.tree.nodes().len()
    };
    stats.field_ms = started.elapsed().as_secs_f32() * 1000.0;
}

/// Takes the mass-weighted mean of the bodies' accelerations off every body, so that the field
/// exerts no net force: the bodies' gravity is internal to them, and Newton's third law says
/// its forces sum to zero. Barnes-Hut's forces are not equal and opposite pair by pair (a body
/// feels a far group's centre of mass while the group's bodies feel it one by one), and the
/// remainder pushed a merged fluid planet off at 2.4 kg·m/s in 60 s; it is a small share of
/// the tree's error (about 3·10⁻⁴ of `Σm|a|` there), so the accuracy is unchanged.
fn remove_net_force(bodies: &mut Query<FieldData>) {
    let (mut force, mut mass) = ([0.0f64; 2], 0.0f64);
    for (_, m, _, a, _) in bodies.iter() {
        if m.0.is_finite() && a.0.is_finite() {
            let m = m.0 as f64;
            force[0] += m * a.x as f64;
            force[1] += m * a.y as f64;
            mass += m;
        }
    }
    if mass <= 0.0 {
        return;
    }
    let mean = Vec2::new((force[0] / mass) as f32, (force[1] / mass) as f32);
    bodies
        .par_iter_mut()
        .for_each(|(_, _, _, mut acceleration, _)| acceleration.0 -= mean);
}

/// What the leapfrog moves: bodies that are not fluid particles (the fluid steps itself).
type FreeBody = (
    &'static mut Position,
    &'static mut Velocity,
    &'static GravityAcceleration,
);

/// First half of leapfrog: half a kick, then a whole drift.
pub(crate) fn kick_and_drift(
    time: Res<Time>,
    mut bodies: Query<FreeBody, (With<Mass>, Without<FluidParticle>)>,
) {
    let dt = time.delta_secs();
    bodies
        .par_iter_mut()
        .for_each(|(mut position, mut velocity, acceleration)| {
            let v = velocity.0 + 0.5 * dt * acceleration.0;
            let x = position.0 + dt * v;
            if v.is_finite() && x.is_finite() {
                velocity.0 = v;
                position.0 = x;
            }
        });
}

/// Second half of leapfrog: half a kick with the new field; then the energy and momentum.
pub(crate) fn kick(
    time: Res<Time>,
    mut bodies: Query<FreeBody, (With<Mass>, Without<FluidParticle>)>,
) {
    let dt = time.delta_secs();
    bodies
        .par_iter_mut()
        .for_each(|(_, mut velocity, acceleration)| {
            let v = velocity.0 + 0.5 * dt * acceleration.0;
            if v.is_finite() {
                velocity.0 = v;
            }
        });
}

/// Energy and momentum of every body (fluid included), summed in query order.
pub(crate) fn update_gravity_stats(
    bodies: Query<(&Velocity, &Mass, &GravityPotential)>,
    mut stats: ResMut<GravityStats>,
) {
    let (mut kinetic, mut potential) = (0.0f64, 0.0f64);
    let mut momentum = [0.0f64; 2];
    for (velocity, mass, phi) in &bodies {
        let m = mass.0 as f64;
        kinetic += 0.5 * m * velocity.length_squared() as f64;
        potential += 0.5 * m * phi.0 as f64;
        momentum[0] += m * velocity.x as f64;
        momentum[1] += m * velocity.y as f64;
    }
    stats.kinetic_energy = kinetic;
    stats.potential_energy = potential;
    stats.momentum = Vec2::new(momentum[0] as f32, momentum[1] as f32);
}

/// Run condition: some fluid particle has a [`Mass`]. Its field is then evaluated in every
/// fluid sub-step, at the sub-step's positions: held for a whole tick of sub-steps, a field
/// taken at the tick's start kicks the fluid as if from where it was, which pumps energy into
/// every oscillation (a self-gravitating planet gained 98% of its binding energy in 30 s).
pub(crate) fn fluid_has_mass(particles: Query<(), (With<FluidParticle>, With<Mass>)>) -> bool {
    !particles.is_empty()
}

/// In each fluid sub-step: adds the sub-step's gravitational acceleration of fluid particles with a
/// [`Mass`] to their SPH acceleration.
pub(crate) fn apply_gravity_to_fluid(
    mut particles: Query<(&GravityAcceleration, &mut Acceleration), With<FluidParticle>>,
) {
    particles
        .par_iter_mut()
        .for_each(|(gravity, mut acceleration)| {
            acceleration.0 += gravity.0;
        });
}
