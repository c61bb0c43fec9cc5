//! The neighbour pass of [`Dfsph::prepare`]: for each fluid particle, its density by summation,
//! its cached row of fluid neighbours (slot, gradient), its sums over the wall particles, the
//! DFSPH factor, its velocity, and its warm start (the density solve's smoothed over the row as
//! it is written).

use super::rows::RowsMut;
use super::{
    DEFICIENT_NEIGHBORHOOD, Dfsph, PINNED_DIAGONAL, SlotState, WALL_MIRROR, lattice_diagonal,
    lattice_neighbors, wall_weight,
};
use crate::sim::config::SphConstants;
use crate::sim::kernels::RadialKernel;
use crate::sim::layout::{FluidSnapshot, Walls};
use crate::sim::parallel::{CHUNK, Parallel, run_jobs};
use bevy::math::{Vec2, Vec4};

/// The constants of the pass, in the form its loops use.
struct Terms {
    /// `s V`: the gradient's scale times a particle's volume, m².
    scaled_volume: f32,
    /// A particle's volume, m².
    volume: f32,
    /// The squared support, m², in every lane.
    support_sq: Vec4,
    /// The support, m, in every lane.
    support: Vec4,
    /// Below this squared distance (m²) a pair is the particle itself.
    tiny: Vec4,
    /// `η² = 0.01 h²`, m², which keeps the wall friction finite at contact.
    eta_sq: f32,
    /// Gravity, m/s² (the walls' hydrostatic head).
    gravity: Vec2,
}

/// What a particle's fluid neighbours sum to.
struct FluidSums {
    /// Fluid neighbours inside the support (the particle excluded), even past the row's length.
    count: usize,
    /// Kernel values per lane, the particle included (walls are added on top).
    density: Vec4,
    /// `Σⱼ gᵢⱼ`, 1/m.
    gradient: Vec2,
    /// `Σⱼ |gᵢⱼ|²`, 1/m².
    gradient_sq: f32,
    /// The SPH average of the stiffness over the row, when asked for ([`Smoothing`]).
    smoothed: Option<f32>,
}

/// The SPH average `Σⱼ Vⱼ Wᵢⱼ κⱼ / Σⱼ Vⱼ Wᵢⱼ` a row sums as it is written, from the particle's
/// own share.
struct Smoothing<K> {
    /// `Σ V W κ` so far, m²/s².
    sum: f32,
    /// `Σ V W` so far.
    weight: f32,
    /// The stiffness `κⱼ` of the particle at a slot, m²/s².
    kappa: K,
}

/// What a particle's wall neighbours sum to (see [`SlotState`]).
#[derive(Default)]
struct WallSums {
    gradient: Vec2,
    viscosity: f32,
    drag: Vec2,
    flux: f32,
    head: Vec2,
    count: u32,
}

impl Dfsph {
    /// Fills rows of `stride` entries, and each slot's velocity and stiffnesses `[κ, κᵛ]` from
    /// `start(slot)` (with `smooth`, the particle's own kernel weight `V W(0)`, κ replaced by
    /// its SPH average over the row: see [`Dfsph::prepare`]), and returns the most neighbours
    /// any particle has (more than `stride`: the rows were short).
    #[expect(clippy::too_many_arguments, reason = "one pass, spelled out")]
    pub(super) fn gather_neighbors<W: RadialKernel, G: RadialKernel>(
        &mut self,
        w: &W,
        g: &G,
        c: &SphConstants,
        (fluid, walls): (&FluidSnapshot, &Walls),
        (start, smooth): (&(impl Fn(usize) -> (Vec2, Vec2) + Sync), Option<f32>),
        stride: usize,
        parallel: &impl Parallel,
    ) -> usize {
        let n = self.state.len();
        let terms = Terms {
            scaled_volume: c.gradient_scale * c.volume,
            volume: c.volume,
            support_sq: Vec4::splat(c.support_sq),
            support: Vec4::splat(c.support),
            tiny: Vec4::splat(1e-12 * c.support_sq),
            eta_sq: 0.01 * c.smoothing_length * c.smoothing_length,
            gravity: c.gravity,
        };
        let deficient_below = DEFICIENT_NEIGHBORHOOD * lattice_neighbors(c) as f32;
        let pinned_below = PINNED_DIAGONAL * lattice_diagonal(g, c);
        let starts = self
            .velocity
            .chunks_mut(CHUNK)
            .zip(self.kappa.chunks_mut(CHUNK))
            .zip(self.kappa_divergence.chunks_mut(CHUNK));
        let mut jobs: Vec<_> = self
            .state
            .chunks_mut(CHUNK)
            .zip(self.rows.chunks_mut(CHUNK))
            .zip(starts)
            .enumerate()
            .map(|(k, ((state, rows), starts))| (k * CHUNK, state, rows, starts, 0usize))
            .collect();
        run_jobs(
            parallel,
            n,
            &mut jobs,
            |(first, states, rows, ((velocity, kappa), kappa_divergence), most)| {
                for (k, state) in states.iter_mut().enumerate() {
                    let slot = *first + k;
                    let (v, stiffness) = start(slot);
                    (velocity[k], kappa[k], kappa_divergence[k]) = (v, stiffness.x, stiffness.y);
                    let x = fluid.points.get(slot);
                    let smoothing = smooth.map(|own| Smoothing {
                        sum: own * stiffness.x,
                        weight: own,
                        kappa: |j| start(j).1.x,
                    });
                    let mut sums = fluid_row(w, g, &terms, fluid, x, (rows, k, stride), smoothing);
                    let wall = wall_sums(w, g, &terms, walls, x, &mut sums.density);
                    let len = sums.count;
                    *most = (*most).max(len);
                    // The row is padded to whole blocks (see `Rows`) with the particle itself at
                    // zero gradient, which adds nothing to any sum over it.
                    if len <= stride {
                        rows.pad(k, len, slot);
                    }
                    if let Some(smoothed) = sums.smoothed {
                        kappa[k] = smoothed;
                    }
                    // A particle's own stiffness changes its density rate through its own velocity
                    // (pushed by its neighbours and the mirrored wall) and its neighbours'.
                    let density = c.volume * sums.density.element_sum();
                    let mirrored = wall_weight(density);
                    let wall_gradient = mirrored * wall.gradient;
                    // With masses the diagonal is `|…|²/rᵢ + Σⱼ |gᵢⱼ|²/rⱼ`; `1/rᵢ` for both (exact
                    // within one liquid) keeps it a preconditioner's guess at the interface.
                    let inverse_mass = 1.0 / fluid.rest_ratio[slot];
                    let diagonal = inverse_mass
                        * ((sums.gradient + WALL_MIRROR * wall_gradient).length_squared()
                            + sums.gradient_sq);
                    *state = SlotState {
                        count: len.min(stride) as u32,
                        density,
                        inverse_mass,
                        factor: if diagonal > pinned_below {
                            1.0 / diagonal
                        } else {
                            0.0
                        },
                        deficient: ((len as u32 + wall.count) as f32) < deficient_below,
                        wall_gradient,
                        wall_viscosity: wall.viscosity,
                        wall_drag: wall.drag,
                        wall_flux: mirrored * wall.flux,
                        wall_head: wall.head,
                    };
                }
            },
        );
        jobs.iter().map(|job| job.4).max().unwrap_or(0)
    }
}

/// The fluid neighbours of the particle at `x`: writes the `k`-th row of `rows` (up to its
/// `stride` entries, with `smoothing` summed over them) and returns the sums over all of them.
#[inline(always)]
fn fluid_row<W: RadialKernel, G: RadialKernel, K: Fn(usize) -> f32>(
    w: &W,
    g: &G,
    t: &Terms,
    fluid: &FluidSnapshot,
    x: Vec2,
    (rows, k, stride): (&mut RowsMut<'_>, usize, usize),
    mut smoothing: Option<Smoothing<K>>,
) -> FluidSums {
    let mut len = 0usize;
    let mut density = Vec4::ZERO;
    let (mut sum_x, mut sum_y, mut sum_sq) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
    fluid.points.for_each_batch(x, |first, dx, dy, r2| {
        // One square root for the value and the slope (inside the support `√r² ≤ H` exactly,
        // so the slope's clamp changes only lanes the mask drops).
        let r = r2.sqrt();
        let values = w.value_x4(r, r2);
        density += values;
        let inside = r2.cmplt(t.support_sq) & r2.cmpgt(t.tiny);
        let mut mask = inside.bitmask();
        if mask == 0 {
            return;
        }
        let slope = g.push_slope_x4(r.min(t.support));
        // ∇ᵢWᵢⱼ = slope (xᵢ − xⱼ) = −slope (dx, dy); zero on lanes outside.
        let scale = Vec4::select(inside, -t.scaled_volume * slope, Vec4::ZERO);
        let (gx, gy) = (scale * dx, scale * dy);
        sum_x += gx;
        sum_y += gy;
        sum_sq += gx * gx + gy * gy;
        let (gx, gy) = (gx.to_array(), gy.to_array());
        let values = (t.volume * values).to_array();
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if len < stride {
                rows.set(k, len, first + lane, Vec2::new(gx[lane], gy[lane]));
                if let Some(s) = &mut smoothing {
                    s.sum += values[lane] * (s.kappa)(first + lane);
                    s.weight += values[lane];
                }
            }
            len += 1;
        }
    });
    FluidSums {
        count: len,
        density,
        gradient: Vec2::new(sum_x.element_sum(), sum_y.element_sum()),
        gradient_sq: sum_sq.element_sum(),
        smoothed: smoothing.map(|s| s.sum / s.weight),
    }
}

/// The wall particles near `x`: adds their kernel values to `density` and returns their sums.
#[inline(always)]
fn wall_sums<W: RadialKernel, G: RadialKernel>(
    w: &W,
    g: &G,
    t: &Terms,
    walls: &Walls,
    x: Vec2,
    density: &mut Vec4,
) -> WallSums {
    let mut sums = WallSums::default();
    walls.points.for_each_batch(x, |start, dx, dy, r2| {
        let r = r2.sqrt();
        *density += w.value_x4(r, r2);
        let inside = r2.cmplt(t.support_sq) & r2.cmpgt(t.tiny);
        let mask = inside.bitmask();
        if mask == 0 {
            return;
        }
        let r2 = r2.min(t.support_sq);
        let slope = g.push_slope_x4(r.min(t.support));
        let gx = (-t.scaled_volume * slope * dx).to_array();
        let gy = (-t.scaled_volume * slope * dy).to_array();
        let friction = (t.volume * slope * r2 / (r2 + Vec4::splat(t.eta_sq))).to_array();
        let head = (Vec4::splat(t.gravity.x) * dx + Vec4::splat(t.gravity.y) * dy).to_array();
        for lane in 0..4 {
            if mask & (1 << lane) != 0 {
                let gradient = Vec2::new(gx[lane], gy[lane]);
                let velocity = Vec2::new(walls.data.vx[start + lane], walls.data.vy[start + lane]);
                sums.gradient += gradient;
                sums.viscosity += friction[lane];
                sums.drag += friction[lane] * velocity;
                sums.flux += gradient.dot(velocity);
                sums.head -= head[lane] * gradient;
                sums.count += 1;
            }
        }
    });
    sums
}
