//! Ready-made gravity scenes: a rotating disc of bodies around a heavy centre (the galaxy
//! scenario), generated from a seed, and two self-gravitating discs of water that merge. See
//! [`GravityPlugin`](crate::gravity::GravityPlugin).

use super::{GravityParams, Mass};
use crate::control::ResetSimulation;
use crate::fluid::{FluidParticle, SphParams};
use crate::gameplay::FluidBlock;
use crate::particle::{Position, Velocity};
use bevy::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A disc of bodies spread uniformly over its area around a heavy central body, each on a
/// circular orbit for the mass inside its radius.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, PartialEq)]
pub struct GalaxyDisc {
    /// Bodies in all, the central one included (at least 1).
    pub bodies: usize,
    /// Disc radius, m.
    pub radius: f32,
    /// Mass of the central body, kg.
    pub central_mass: f32,
    /// Mass of the disc, shared equally by its bodies, kg.
    pub disc_mass: f32,
    /// The `G` the orbital speeds are computed for, m³/(kg·s²).
    pub gravitational_constant: f32,
    /// Inner edge of the disc, as a fraction of the radius (bodies closer to the centre orbit
    /// so fast that they need much shorter steps).
    pub inner_radius: f32,
    /// Centre of the disc, m.
    pub center: Vec2,
    /// Seed of the positions.
    pub seed: u64,
}

impl Default for GalaxyDisc {
    fn default() -> Self {
        Self {
            bodies: 20_000,
            radius: 1.0,
            central_mass: 1.0,
            disc_mass: 0.1,
            gravitational_constant: 1.0,
            inner_radius: 0.2,
            center: Vec2::ZERO,
            seed: 0,
        }
    }
}

/// Generated bodies, in spawn order (the central one first).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Bodies {
    /// Positions, m.
    pub positions: Vec<Vec2>,
    /// Velocities, m/s.
    pub velocities: Vec<Vec2>,
    /// Masses, kg.
    pub masses: Vec<f32>,
}

impl GalaxyDisc {
    /// A disc of `bodies` bodies with the default proportions.
    pub fn new(bodies: usize) -> Self {
        Self {
            bodies,
            ..default()
        }
    }

    /// The bodies: positions uniform in area between the inner radius and the radius,
    /// anticlockwise circular speeds `√(G M(<r) / r)`.
    pub(crate) fn generate(&self) -> Bodies {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let n = self.bodies.max(1);
        let disc = n - 1;
        let each = if disc > 0 {
            self.disc_mass / disc as f32
        } else {
            0.0
        };
        let mut bodies = Bodies {
            positions: Vec::with_capacity(n),
            velocities: Vec::with_capacity(n),
            masses: Vec::with_capacity(n),
        };
        bodies.positions.push(self.center);
        bodies.velocities.push(Vec2::ZERO);
        bodies.masses.push(self.central_mass);
        let inner = self.inner_radius.clamp(0.0, 0.99);
        for _ in 0..disc {
            let u: f32 = rng.random_range(inner * inner..1.0);
            let r = self.radius * u.sqrt();
            let angle: f32 = rng.random_range(0.0..core::f32::consts::TAU);
            let direction = Vec2::from_angle(angle);
            // Disc mass inside r (uniform surface density, nothing inside the hole).
            let enclosed = self.central_mass
                + self.disc_mass * ((u - inner * inner) / (1.0 - inner * inner)).max(0.0);
            let speed = (self.gravitational_constant * enclosed / r).sqrt();
            bodies.positions.push(self.center + r * direction);
            bodies.velocities.push(speed * direction.perp());
            bodies.masses.push(each);
        }
        bodies
    }
}

impl GalaxyDisc {
    /// Spawns the disc's bodies into `world` and returns them, the central body first.
    pub fn spawn(&self, world: &mut World) -> Vec<Entity> {
        let bodies = self.generate();
        world
            .spawn_batch(
                bodies
                    .positions
                    .into_iter()
                    .zip(bodies.velocities)
                    .zip(bodies.masses)
                    .map(|((p, v), m)| (Mass(m), Position(p), Velocity(v)))
                    .collect::<Vec<_>>(),
            )
            .collect()
    }
}

impl Command for GalaxyDisc {
    type Out = ();

    fn apply(self, world: &mut World) {
        self.spawn(world);
    }
}

/// The bodies [`ResetSimulation`] respawns: insert it to make reset restart a galaxy.
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Resource, Debug)]
pub struct GravityScenario(pub GalaxyDisc);

/// On [`ResetSimulation`], despawns every body that is not a fluid particle and spawns the
/// [`GravityScenario`] again.
pub(crate) fn reset_bodies(
    mut resets: MessageReader<ResetSimulation>,
    scenario: Option<Res<GravityScenario>>,
    bodies: Query<Entity, (With<Mass>, Without<FluidParticle>)>,
    mut commands: Commands,
) {
    if resets.read().count() == 0 {
        return;
    }
    let Some(scenario) = scenario else {
        return;
    };
    for entity in &bodies {
        commands.entity(entity).despawn();
    }
    commands.queue(scenario.0);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_is_seeded_and_orbits_anticlockwise() {
        let disc = GalaxyDisc::new(1000);
        let a = disc.generate();
        assert_eq!(a, disc.generate());
        assert_ne!(a, GalaxyDisc { seed: 1, ..disc }.generate());
        assert_eq!(a.positions.len(), 1000);
        let total: f32 = a.masses.iter().sum();
        assert!((total - 1.1).abs() < 1e-4);
        for (p, v) in a.positions.iter().zip(&a.velocities).skip(1) {
            assert!(p.length() <= 1.0 && p.length() >= 0.199);
            assert!(p.perp_dot(*v) > 0.0 && p.dot(*v).abs() < 1e-4);
        }
    }
}

/// Two discs of water in empty space, approaching off-centre, that merge under their own
/// gravity into one "planet" (the `planet` example's scene, and the test that holds its energy
/// and momentum).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluidPlanets {
    /// Radius of each disc, m.
    pub radius: f32,
    /// Speed each disc approaches at, m/s.
    pub speed: f32,
}

impl Default for FluidPlanets {
    fn default() -> Self {
        Self {
            radius: 0.15,
            speed: 0.25,
        }
    }
}

impl FluidPlanets {
    /// Water without a tank or uniform gravity; a slow speed of sound suits the discs' small
    /// pressures (10 times their surface speed), and a little more artificial viscosity calms
    /// the merger. The strict DFSPH solve ([`SphParams::reference`]): under the default's grid
    /// start and fixed budget the merged planet's energy rose by a fifth and four particles
    /// were flung a hundred metres out (its pressure is not a column's weight under uniform
    /// gravity, which is what the grid carries).
    pub fn fluid_params(&self) -> SphParams {
        SphParams {
            tank: None,
            gravity: Vec2::ZERO,
            particle_spacing: 0.01,
            support_ratio: 2.5,
            speed_of_sound: 10.0,
            artificial_viscosity: 0.1,
            max_substeps: 40,
            ..SphParams::reference()
        }
    }

    /// Gravity strong enough for a surface gravity `G M / R²` of about 5 m/s².
    pub fn gravity_params(&self) -> GravityParams {
        GravityParams {
            gravitational_constant: 2.0e-3,
            theta: 0.6,
            softening: 0.01,
            ..GravityParams::default()
        }
    }

    /// Each particle's position and velocity (m, m/s) at `spacing` (m): lattice points inside
    /// the two discs, centred 0.8 m apart and 0.06 m off-line.
    pub fn particles(&self, spacing: f32) -> Vec<(Vec2, Vec2)> {
        let mut out = Vec::new();
        for (centre, velocity) in [
            (Vec2::new(-0.4, 0.03), Vec2::new(self.speed, 0.0)),
            (Vec2::new(0.4, -0.03), Vec2::new(-self.speed, 0.0)),
        ] {
            let square = FluidBlock::new(
                centre - Vec2::splat(self.radius),
                Vec2::splat(2.0 * self.radius),
            )
            .with_hydrostatic(false);
            for p in square.positions(spacing) {
                if p.distance(centre) < self.radius {
                    out.push((p, velocity));
                }
            }
        }
        out
    }
}
