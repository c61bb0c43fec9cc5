//! What the divergence-free solver's walls do to the solids they belong to: minus each pair's
//! push on the fluid, with the same terms as the fluid's (see the module docs of
//! [`dfsph`](super)), so that the solids take exactly the momentum the fluid loses to them.

use super::{Dfsph, WALL_MIRROR, wall_weight};
use crate::sim::config::SphConstants;
use crate::sim::density::with_kernels;
use crate::sim::kernels::RadialKernel;
use crate::sim::layout::{FluidSnapshot, Walls};
use crate::sim::viscosity::Laminar;
use bevy::math::Vec2;

/// One pair's terms: the wall gradient `g_ib` (1/m) and the friction weight (dimensionless).
struct Pair {
    gradient: Vec2,
    friction: f32,
}

impl Dfsph {
    /// Visits every pair of a solid's boundary particle `b` and a fluid particle `i` with
    /// `(solid, x_b, wall slot, fluid slot, pair)`.
    fn for_each_solid_pair(
        c: &SphConstants,
        fluid: &FluidSnapshot,
        walls: &Walls,
        mut visit: impl FnMut(usize, Vec2, usize, usize, Pair),
    ) {
        let eta_sq = 0.01 * c.smoothing_length * c.smoothing_length;
        let scaled_volume = c.gradient_scale * c.volume;
        with_kernels!(c.kernel, c.support, |_w, g| {
            walls.for_each_solid_pair(c, fluid, |k, x, wall, i, r, r2| {
                // r = xᵢ − x_b; the gather's `g_ib = −s V slope (x_b − xᵢ)`.
                let slope = g.push_slope(r2.sqrt());
                let pair = Pair {
                    gradient: scaled_volume * slope * r,
                    friction: c.volume * slope * r2 / (r2 + eta_sq),
                };
                visit(k, x, wall, i, pair);
            });
        });
    }

    /// The force stage's part: minus the wall friction and hydrostatic head the solids' particles
    /// give the fluid (as in [`non_pressure_acceleration`](Dfsph::non_pressure_acceleration)),
    /// pending until the step's length is known.
    pub(crate) fn solid_forces(&self, c: &SphConstants, fluid: &FluidSnapshot, walls: &mut Walls) {
        if walls.solids.is_empty() {
            return;
        }
        let mut sums = vec![(Vec2::ZERO, 0.0f32); walls.solids.len()];
        let centers: Vec<Vec2> = walls.solids.iter().map(|b| b.world_center()).collect();
        Self::for_each_solid_pair(c, fluid, walls, |k, x, wall, i, pair| {
            let s = &self.state[i];
            let rho_i = s.density * c.rest_density / s.inverse_mass;
            let laminar = Laminar::at(fluid, c.kinematic_viscosity, i).own();
            let coefficient = laminar * c.rest_density / (rho_i + c.rest_density);
            let v_b = Vec2::new(walls.data.vx[wall], walls.data.vy[wall]);
            let mut a = coefficient * pair.friction * (self.velocity[i] - v_b);
            if !s.deficient {
                let r = fluid.points.get(i) - x;
                a += c.gravity.dot(r) * pair.gradient;
            }
            // The particle's mass is its liquid's: `mᵢ = ρ₀ V / (1/rᵢ)`.
            let force = -c.mass / s.inverse_mass * a;
            sums[k].0 += force;
            sums[k].1 += (x - centers[k]).perp_dot(force);
        });
        for (solid, (force, torque)) in walls.solids.iter_mut().zip(sums) {
            solid.add_pending(force, torque);
        }
    }

    /// The end of the sub-step of `dt`: minus the mirrored pressure push of both solves
    /// (`Δvᵢ = −2 dt κᵢ g_ib`, the divergence solve's with its own step), plus the pending force.
    pub(crate) fn solid_impulses(
        &self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        walls: &mut Walls,
        dt: f32,
    ) {
        if walls.solids.is_empty() {
            return;
        }
        let mut sums = vec![(Vec2::ZERO, 0.0f32); walls.solids.len()];
        let centers: Vec<Vec2> = walls.solids.iter().map(|b| b.world_center()).collect();
        let divergence_dt = self.divergence_dt;
        Self::for_each_solid_pair(c, fluid, walls, |k, x, _, i, pair| {
            let push = dt * self.kappa[i] + divergence_dt * self.kappa_divergence[i];
            let weight = wall_weight(self.state[i].density);
            let impulse = c.mass * WALL_MIRROR * push * weight * pair.gradient;
            sums[k].0 += impulse;
            sums[k].1 += (x - centers[k]).perp_dot(impulse);
        });
        for (solid, (impulse, angular)) in walls.solids.iter_mut().zip(sums) {
            solid.end_substep(dt, impulse, angular);
        }
    }
}
