//! What a game reads from the fluid: [`FluidSensor`] regions that report, every fixed tick, how
//! much fluid is inside and how it moves, with [`FluidEntered`] and [`FluidLeft`] messages when
//! it crosses the sensor's thresholds; and [`FluidQuery`], the fluid's density, velocity and
//! pressure at any point by SPH interpolation, and its particles in a region. See [`SphPlugin`](crate::fluid::SphPlugin).

use crate::fluid::SphParams;
use crate::fluid::SphSolver;
use crate::fluid::{Density, FluidMaterial, FluidParticle, Position, Pressure, Velocity};
use crate::sim::region::FluidRegion;
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;

/// A region that measures the fluid in it every fixed tick (into [`reading`](Self::reading))
/// and sends [`FluidEntered`] when its fill fraction rises to `enter_fill` and [`FluidLeft`]
/// when it falls to `leave_fill` (below `enter_fill`, so a level that wobbles at one threshold
/// does not send a message every tick): once per crossing.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_sph2d::gameplay::{FluidRegion, FluidSensor};
/// fn cup(mut commands: Commands) {
///     // "Fill the cup to 80%".
///     commands.spawn(FluidSensor::new(FluidRegion::rect(Vec2::new(1.2, 0.1), Vec2::splat(0.1)))
///         .with_thresholds(0.8, 0.7));
/// }
/// ```
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component, Debug, PartialEq)]
pub struct FluidSensor {
    /// Where it measures.
    pub region: FluidRegion,
    /// Fill fraction at which fluid counts as arrived (0 to 1).
    pub enter_fill: f32,
    /// Fill fraction at which fluid counts as gone (below `enter_fill`).
    pub leave_fill: f32,
    /// Only this liquid's particles count, if set (every liquid's otherwise).
    pub material: Option<FluidMaterial>,
    /// The last tick's measurement (written by the plugin).
    pub reading: SensorReading,
    /// Whether fluid has arrived and not left since (written by the plugin).
    pub wet: bool,
    #[reflect(ignore)]
    warned: bool,
}

impl FluidSensor {
    /// A sensor over `region` that counts fluid as arrived at 5% fill and gone at 2%.
    pub fn new(region: FluidRegion) -> Self {
        Self {
            region,
            enter_fill: 0.05,
            leave_fill: 0.02,
            material: None,
            reading: SensorReading::default(),
            wet: false,
            warned: false,
        }
    }

    /// The same with other thresholds.
    pub fn with_thresholds(mut self, enter_fill: f32, leave_fill: f32) -> Self {
        self.enter_fill = enter_fill;
        self.leave_fill = leave_fill;
        self
    }

    /// The same, counting only the liquid `material`'s particles.
    pub fn for_material(mut self, material: FluidMaterial) -> Self {
        self.material = Some(material);
        self
    }

    /// Why the sensor cannot measure, if it cannot: a region without area, or thresholds that
    /// are not `0 <= leave_fill < enter_fill`.
    pub fn check(&self) -> Result<(), String> {
        self.region.check()?;
        if !(self.leave_fill >= 0.0 && self.leave_fill < self.enter_fill) {
            return Err(format!(
                "leave_fill {} must be at least 0 and below enter_fill {}",
                self.leave_fill, self.enter_fill
            ));
        }
        Ok(())
    }
}

/// What a [`FluidSensor`] measured in the last fixed tick.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Debug, Default, PartialEq)]
pub struct SensorReading {
    /// Fluid particles inside.
    pub particles: u32,
    /// Their volume, m² (particles times the spacing squared).
    pub volume: f32,
    /// `volume` over the region's area (about 1 when it is full; a little more where the fluid
    /// is compressed).
    pub fill: f32,
    /// Mean density of the particles inside, kg/m³ (0 when empty).
    pub mean_density: f32,
    /// Mean velocity, m/s.
    pub mean_velocity: Vec2,
    /// Mean pressure, Pa.
    pub mean_pressure: f32,
}

/// Fluid reached a [`FluidSensor`]'s `enter_fill`.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct FluidEntered {
    /// The sensor's entity.
    pub sensor: Entity,
    /// Its fill fraction then.
    pub fill: f32,
}

/// Fluid fell to a [`FluidSensor`]'s `leave_fill`.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct FluidLeft {
    /// The sensor's entity.
    pub sensor: Entity,
    /// Its fill fraction then.
    pub fill: f32,
}

/// What a sensor reads of each particle: its state and its liquid.
type SensedData = (
    (
        &'static Position,
        &'static Velocity,
        &'static Density,
        &'static Pressure,
    ),
    Option<&'static FluidMaterial>,
);

/// Measures every [`FluidSensor`] and sends the crossing messages.
pub(crate) fn run_sensors(
    params: Res<SphParams>,
    mut sensors: Query<(Entity, &mut FluidSensor)>,
    particles: Query<SensedData, With<FluidParticle>>,
    mut entered: MessageWriter<FluidEntered>,
    mut left: MessageWriter<FluidLeft>,
) {
    let volume = params.particle_spacing * params.particle_spacing;
    for (entity, mut sensor) in &mut sensors {
        if let Err(problem) = sensor.check() {
            if !sensor.warned {
                warn!("FluidSensor on {entity} measures nothing: {problem}");
                sensor.warned = true;
            }
            continue;
        }
        let (region, only) = (sensor.region, sensor.material);
        let (mut count, mut density, mut velocity, mut pressure) =
            (0u32, 0.0f64, Vec2::ZERO, 0.0f64);
        for ((position, v, rho, p), material) in &particles {
            let material = material.copied().unwrap_or_default();
            if region.contains(position.0) && only.is_none_or(|only| only == material) {
                count += 1;
                density += rho.0 as f64;
                velocity += v.0;
                pressure += p.0 as f64;
            }
        }
        let n = count.max(1) as f64;
        let fill = count as f32 * volume / region.area();
        let reading = SensorReading {
            particles: count,
            volume: count as f32 * volume,
            fill,
            mean_density: (density / n) as f32,
            mean_velocity: velocity / n as f32,
            mean_pressure: (pressure / n) as f32,
        };
        if sensor.reading != reading {
            sensor.reading = reading;
        }
        if !sensor.wet && fill >= sensor.enter_fill {
            sensor.wet = true;
            entered.write(FluidEntered {
                sensor: entity,
                fill,
            });
        } else if sensor.wet && fill <= sensor.leave_fill {
            sensor.wet = false;
            left.write(FluidLeft {
                sensor: entity,
                fill,
            });
        }
    }
}

/// The fluid at a point, from [`FluidQuery::sample`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluidSample {
    /// Density, kg/m³.
    pub density: f32,
    /// Velocity, m/s.
    pub velocity: Vec2,
    /// Pressure, Pa.
    pub pressure: f32,
    /// `Σⱼ Vⱼ W(x − xⱼ)`, the kernel sum of the particles around the point: about 1 inside the
    /// fluid, about ½ on its surface, falling to 0 one support radius out.
    pub coverage: f32,
}

/// The fluid as a system reads it, the way avian's `SpatialQuery` reads colliders: its state at
/// any point, the pressure it puts on a wall, the particles in a region. Read it after
/// [`SphSystems::Simulate`](crate::fluid::SphSystems::Simulate) (in
/// [`SphSystems::Finish`](crate::fluid::SphSystems::Finish) or later) for this tick's fluid.
/// It reads the particles' `particle::Position`: a system that also writes them takes both
/// in a `ParamSet`.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_sph2d::gameplay::FluidQuery;
/// fn bob(fluid: FluidQuery) {
///     if let Some(water) = fluid.sample(Vec2::new(0.5, 0.1)) {
///         info!("{} Pa, flowing at {} m/s", water.pressure, water.velocity.length());
///     }
/// }
/// # bevy::ecs::system::assert_is_system(bob);
/// ```
#[derive(SystemParam)]
pub struct FluidQuery<'w, 's> {
    solver: Res<'w, SphSolver>,
    particles: Query<'w, 's, (Entity, &'static Position), With<FluidParticle>>,
}

impl FluidQuery<'_, '_> {
    /// The fluid's density, velocity and pressure at `x` (m), interpolated from the particles
    /// of the last sub-step within one kernel support by Shepard's normalised SPH sum
    /// `A(x) = Σⱼ Aⱼ W(x − xⱼ) / Σⱼ W(x − xⱼ)` (every particle has the same volume), with the
    /// solver's kernel; `None` where no particle is that close.
    pub fn sample(&self, x: Vec2) -> Option<FluidSample> {
        sample(&self.solver, x, false)
    }

    /// The pressure (Pa) the fluid exerts on a wall at the point `x` (m) of the wall's surface:
    /// [`sample`](Self::sample)'s sum with each particle's pressure carried to the wall by the
    /// hydrostatic head, `p_w = Σⱼ Wⱼ (pⱼ + ρⱼ g·(x − xⱼ)) / Σⱼ Wⱼ`, as the walls' boundary
    /// particles take it (Adami et al. 2012). The particles next to a wall lie half a spacing
    /// to two spacings from it, so the plain sample there reads the pressure of a point inside
    /// the fluid, low by `ρ₀ g` times that distance. `None` where no particle is within one
    /// support of `x`.
    pub fn wall_pressure(&self, x: Vec2) -> Option<f32> {
        sample(&self.solver, x, true).map(|s| s.pressure)
    }

    /// The fluid particles in `region`, with their positions (m), in no particular order (a
    /// pass over the particles).
    pub fn particles_in(&self, region: FluidRegion) -> impl Iterator<Item = (Entity, Vec2)> {
        self.particles
            .iter()
            .map(|(entity, position)| (entity, position.0))
            .filter(move |&(_, x)| region.contains(x))
    }
}

/// The probe's sum at `x`; with `head`, each particle's pressure carried to `x` hydrostatically.
fn sample(solver: &SphSolver, x: Vec2, head: bool) -> Option<FluidSample> {
    let volume = solver.constants().volume;
    let (density, velocity, pressure, weight) = solver.step.sample(x, head)?;
    Some(FluidSample {
        density,
        velocity,
        pressure,
        coverage: volume * weight,
    })
}
