//! Emitters and drains: [`FluidEmitter`] pours particles from a nozzle, [`FluidDrain`] removes
//! the particles that enter its region. Both run once per fixed tick, after the sub-steps (in
//! [`SphSystems::Finish`](crate::fluid::SphSystems::Finish), before the statistics), with either
//! solver. See [`SphPlugin`](crate::fluid::SphPlugin).

use crate::fluid::SphParams;
use crate::fluid::{FluidMaterial, FluidParticle, Position, Velocity};
use crate::fluid::{Pose, Solid, pose_of};
use crate::sim::region::FluidRegion;
use bevy::prelude::*;

/// How fast a [`FluidEmitter`] pours.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, PartialEq)]
pub enum EmitterRate {
    /// Fluid volume per second, m²/s (the 2D fluid's volume is an area: m³/s per metre of
    /// depth).
    Volume(f32),
    /// Particles per second.
    Particles(f32),
}

/// A nozzle that pours fluid: put it on an entity with a [`Transform`] (the nozzle's centre is
/// its translation, in world space: give the emitter no parent) or a [`Position`] (which wins;
/// headless apps without transform propagation work either way). Particles leave the nozzle in rows across its
/// `width`, one particle spacing apart, at `speed` along `direction` (world space); a row is
/// only as full as there is room: no particle is spawned within 0.8 spacings of another, inside
/// a [`Solid`] or outside the tank. Start and stop it with `active`, or remove the component.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_sph2d::gameplay::{EmitterRate, FluidEmitter};
/// fn tap(mut commands: Commands) {
///     commands.spawn((
///         FluidEmitter::new(0.05, Vec2::X, 1.0, EmitterRate::Volume(0.02)),
///         Transform::from_xyz(0.1, 0.6, 0.0),
///     ));
/// }
/// ```
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component, Debug, PartialEq)]
pub struct FluidEmitter {
    /// Nozzle width across the jet, m.
    pub width: f32,
    /// The jet's direction (world space; normalised when used).
    pub direction: Vec2,
    /// Exit speed, m/s.
    pub speed: f32,
    /// How much it pours.
    pub rate: EmitterRate,
    /// Pouring (`false`: paused).
    pub active: bool,
    /// At most this many particles in all, if set.
    pub budget: Option<u32>,
    /// Which liquid it pours (see [`FluidMaterial`]; the base liquid by default).
    pub material: FluidMaterial,
    /// Particles emitted so far (written by the plugin).
    pub emitted: u32,
    /// Rows owed but not yet emitted (fraction carried between ticks).
    #[reflect(ignore)]
    owed: f32,
    /// Whether the last problem was reported (warn once, not every tick).
    #[reflect(ignore)]
    warned: bool,
}

impl FluidEmitter {
    /// An active emitter without a budget.
    pub fn new(width: f32, direction: Vec2, speed: f32, rate: EmitterRate) -> Self {
        Self {
            width,
            direction,
            speed,
            rate,
            active: true,
            budget: None,
            material: FluidMaterial(0),
            emitted: 0,
            owed: 0.0,
            warned: false,
        }
    }

    /// The same, pouring the liquid `material` (see [`SphParams::liquids`]).
    pub fn with_material(mut self, material: FluidMaterial) -> Self {
        self.material = material;
        self
    }

    /// The same, stopping after `particles` particles.
    pub fn with_budget(mut self, particles: u32) -> Self {
        self.budget = Some(particles);
        self
    }

    /// Why the emitter cannot pour (a non-finite or non-positive size, speed or rate, or no
    /// direction), if it cannot.
    pub fn check(&self) -> Result<(), String> {
        let rate = match self.rate {
            EmitterRate::Volume(v) | EmitterRate::Particles(v) => v,
        };
        if !(self.width.is_finite() && self.width > 0.0) {
            return Err(format!("width {} m must be positive", self.width));
        }
        if !(self.speed.is_finite() && self.speed > 0.0) {
            return Err(format!("speed {} m/s must be positive", self.speed));
        }
        if !(rate.is_finite() && rate >= 0.0) {
            return Err(format!("rate {rate} must be finite and not negative"));
        }
        if !self.direction.is_finite() || self.direction.length_squared() < 1e-12 {
            return Err(format!(
                "direction {} must be a non-zero vector",
                self.direction
            ));
        }
        Ok(())
    }

    /// Particles per row across a nozzle of this width at `spacing`.
    pub fn row_len(&self, spacing: f32) -> u32 {
        ((self.width / spacing).round() as u32).max(1)
    }

    /// Particles per second at `spacing`.
    pub fn particles_per_second(&self, spacing: f32) -> f32 {
        match self.rate {
            EmitterRate::Volume(v) => v / (spacing * spacing),
            EmitterRate::Particles(p) => p,
        }
    }
}

/// The positions of one row of `count` particles `spacing` apart across a nozzle centred at
/// `centre` facing `direction` (unit), moved `along` metres down the jet.
pub fn nozzle_row(
    centre: Vec2,
    direction: Vec2,
    count: u32,
    spacing: f32,
    along: f32,
) -> impl Iterator<Item = Vec2> {
    let across = direction.perp();
    let first = -0.5 * (count as f32 - 1.0);
    (0..count).map(move |k| centre + direction * along + across * (spacing * (first + k as f32)))
}

/// A region that removes the fluid particles entering it and counts what it removed.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_sph2d::gameplay::{FluidDrain, FluidRegion};
/// fn sink(mut commands: Commands) {
///     commands.spawn(FluidDrain::new(FluidRegion::circle(Vec2::new(1.5, 0.05), 0.05)));
/// }
/// ```
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component, Debug, PartialEq)]
pub struct FluidDrain {
    /// Where particles are removed.
    pub region: FluidRegion,
    /// Removing (`false`: paused).
    pub active: bool,
    /// Particles removed so far (written by the plugin).
    pub removed: u32,
    /// Fluid volume removed so far, m² (particles times the spacing squared when removed).
    pub removed_volume: f32,
    #[reflect(ignore)]
    warned: bool,
}

impl FluidDrain {
    /// An active drain over `region`.
    pub fn new(region: FluidRegion) -> Self {
        Self {
            region,
            active: true,
            removed: 0,
            removed_volume: 0.0,
            warned: false,
        }
    }
}

/// Where a new particle may go (the emitters' and the pour tool's one rule): a finite point
/// inside the tank (if any) by half a spacing, half a spacing out of every solid (each with its
/// pose), and not within `0.8 Δx` of `taken` (the particles nearby, see [`near`]).
fn free_spot(p: Vec2, params: &SphParams, solids: &[(&Solid, Pose)], taken: &[Vec2]) -> bool {
    let spacing = params.particle_spacing;
    let margin = 0.5 * spacing;
    if !p.is_finite() || params.tank.is_some_and(|tank| !tank.contains(p, -margin)) {
        return false;
    }
    let inside = |(solid, pose): &(&Solid, Pose)| {
        solid.shape.is_valid() && solid.shape.distance(pose.to_local(p)).0 < margin
    };
    if solids.iter().any(inside) {
        return false;
    }
    let min_sq = (0.8 * spacing) * (0.8 * spacing);
    !taken.iter().any(|q| q.distance_squared(p) < min_sq)
}

/// The points of `particles` within `reach` (m) of `centre`: what a new particle near `centre`
/// has to keep clear of.
fn near(particles: impl Iterator<Item = Vec2>, centre: Vec2, reach: f32) -> Vec<Vec2> {
    particles.filter(|p| p.distance(centre) <= reach).collect()
}

/// Pours every active [`FluidEmitter`] for one tick.
pub(crate) fn run_emitters(
    time: Res<Time>,
    params: Res<SphParams>,
    mut emitters: Query<(
        Entity,
        &mut FluidEmitter,
        Option<&Position>,
        Option<&Transform>,
    )>,
    particles: Query<&Position, With<FluidParticle>>,
    solids: Query<(&Solid, &Transform)>,
    mut commands: Commands,
) {
    let dt = time.delta_secs();
    if dt <= 0.0 || emitters.is_empty() {
        return;
    }
    let solids: Vec<_> = solids.iter().map(|(s, t)| (s, pose_of(t))).collect();
    for (entity, mut emitter, position, transform) in &mut emitters {
        if !emitter.active {
            continue;
        }
        let Some(centre) = nozzle_centre(entity, &mut emitter, position, transform) else {
            continue;
        };
        // Nearby particles, the ones spawned now included, keep new ones apart.
        let reach = emitter.width + emitter.speed * dt + 2.0 * params.particle_spacing;
        let taken = near(particles.iter().map(|p| p.0), centre, reach);
        let spot = |p: Vec2, taken: &[Vec2]| free_spot(p, &params, &solids, taken);
        let spawned = pour(
            &mut emitter,
            centre,
            dt,
            params.particle_spacing,
            taken,
            spot,
        );
        let stuck = spawned.is_empty() && emitter.owed >= 1.0;
        let (speed, material) = (
            emitter.direction.normalize() * emitter.speed,
            emitter.material,
        );
        commands.spawn_batch(
            spawned
                .into_iter()
                .map(move |p| (FluidParticle, Position(p), Velocity(speed), material))
                .collect::<Vec<_>>(),
        );
        if stuck && !emitter.warned && !spot(centre, &[]) {
            warn!(
                "FluidEmitter on {entity} at {centre} is inside a wall or outside the tank: \
                 it pours nothing"
            );
            emitter.warned = true;
        }
    }
}

/// Where the emitter's nozzle is (its `Position`, else its `Transform`), if it can pour; warns
/// once why not.
fn nozzle_centre(
    entity: Entity,
    emitter: &mut FluidEmitter,
    position: Option<&Position>,
    transform: Option<&Transform>,
) -> Option<Vec2> {
    let centre = position
        .map(|p| p.0)
        .or_else(|| transform.map(|t| t.translation.truncate()));
    let problem = match (centre, emitter.check()) {
        (Some(centre), Ok(())) => return Some(centre),
        (None, _) => format!("FluidEmitter on {entity} has neither a Position nor a Transform"),
        (Some(_), Err(problem)) => format!("FluidEmitter on {entity} does not pour: {problem}"),
    };
    if !emitter.warned {
        warn!("{problem}");
        emitter.warned = true;
    }
    None
}

/// The rows the emitter owes this tick of `dt` seconds, spread down the jet as if poured
/// continuously, on the spots `free` leaves (given what is `taken`); counts them against the
/// budget and returns their positions.
fn pour(
    emitter: &mut FluidEmitter,
    centre: Vec2,
    dt: f32,
    spacing: f32,
    mut taken: Vec<Vec2>,
    free: impl Fn(Vec2, &[Vec2]) -> bool,
) -> Vec<Vec2> {
    let direction = emitter.direction.normalize();
    let count = emitter.row_len(spacing);
    let rows_per_second = emitter.particles_per_second(spacing) / count as f32;
    // At most two rows in hand: a blocked nozzle does not pile up a burst.
    emitter.owed = (emitter.owed + rows_per_second * dt).min(2.0 + rows_per_second * dt);
    let spent = |emitter: &FluidEmitter| emitter.budget.is_some_and(|b| emitter.emitted >= b);
    let mut spawned = Vec::new();
    while emitter.owed >= 1.0 {
        if spent(emitter) {
            // Spent: it stays off until the game tops the budget up and turns it on.
            emitter.active = false;
            emitter.owed = 0.0;
            break;
        }
        emitter.owed -= 1.0;
        let age = emitter.owed / rows_per_second.max(1e-9);
        let along = (emitter.speed * age).min(emitter.speed * dt);
        for p in nozzle_row(centre, direction, count, spacing, along) {
            if spent(emitter) {
                break;
            }
            if free(p, &taken) {
                taken.push(p);
                spawned.push(p);
                emitter.emitted += 1;
            }
        }
    }
    spawned
}

/// Removes the particles inside every active [`FluidDrain`] and counts them.
pub(crate) fn run_drains(
    params: Res<SphParams>,
    mut drains: Query<(Entity, &mut FluidDrain)>,
    particles: Query<(Entity, &Position), With<FluidParticle>>,
    mut commands: Commands,
) {
    if drains.is_empty() {
        return;
    }
    let volume = params.particle_spacing * params.particle_spacing;
    let mut gone = bevy::platform::collections::HashSet::<Entity>::default();
    for (entity, mut drain) in &mut drains {
        if !drain.active {
            continue;
        }
        if let Err(problem) = drain.region.check() {
            if !drain.warned {
                warn!("FluidDrain on {entity} removes nothing: {problem}");
                drain.warned = true;
            }
            continue;
        }
        let region = drain.region;
        for (particle, position) in &particles {
            if region.contains(position.0) && gone.insert(particle) {
                commands.entity(particle).despawn();
                drain.removed += 1;
                drain.removed_volume += volume;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_spans_the_nozzle_across_the_jet() {
        let row: Vec<Vec2> = nozzle_row(Vec2::new(1.0, 1.0), Vec2::X, 3, 0.01, 0.02).collect();
        assert_eq!(row.len(), 3);
        for (p, y) in row.iter().zip([0.99, 1.0, 1.01]) {
            assert!((p.x - 1.02).abs() < 1e-6 && (p.y - y).abs() < 1e-6, "{p}");
        }
        let emitter = FluidEmitter::new(0.05, Vec2::Y, 1.0, EmitterRate::Volume(0.01));
        assert_eq!(emitter.row_len(0.01), 5);
        assert!((emitter.particles_per_second(0.01) - 100.0).abs() < 1e-3);
    }

    #[test]
    fn bad_emitters_say_why() {
        let good = FluidEmitter::new(0.05, Vec2::X, 1.0, EmitterRate::Particles(10.0));
        assert!(good.check().is_ok());
        for (bad, field) in [
            (
                FluidEmitter {
                    width: f32::NAN,
                    ..good.clone()
                },
                "width",
            ),
            (
                FluidEmitter {
                    speed: -1.0,
                    ..good.clone()
                },
                "speed",
            ),
            (
                FluidEmitter {
                    direction: Vec2::ZERO,
                    ..good.clone()
                },
                "direction",
            ),
            (
                FluidEmitter {
                    rate: EmitterRate::Volume(-0.1),
                    ..good.clone()
                },
                "rate",
            ),
        ] {
            let error = bad.check().unwrap_err();
            assert!(error.contains(field), "{error}");
        }
    }
}
